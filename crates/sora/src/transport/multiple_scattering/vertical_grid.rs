//! The vertical grid of the discrete-ordinate solver: levels from the
//! ground to the top of the atmosphere, the species' relative densities at
//! each level and their exact columns through each layer.
//!
//! The solver assumes the source function varies linearly in optical depth
//! across a layer, so layers should be thin in optical depth where the
//! optical depth is, and still resolve the thin upper atmosphere where a
//! twilight sun lights only the top. Levels are placed at equal steps of
//! u(z) = 0.7 tau(z) / tau(top) + 0.3 z / top, where tau(z) is the column
//! below z weighted by each species' largest extinction on the grid: dense
//! in the aerosol layer and the lowest air, never coarser than 1 / (0.3 K)
//! of the height.

use crate::atmosphere::DensityProfile;

/// Share of the level placement that follows the optical depth (the rest
/// follows altitude).
const OPTICAL_DEPTH_SHARE: f64 = 0.7;
/// Resolution of the placement function (uniform altitude steps).
const PLACEMENT_STEPS: usize = 4000;

/// Levels, densities and layer columns (see the module docs).
#[derive(Debug, Clone)]
pub struct VerticalGrid {
    species: usize,
    /// Level altitudes, m, increasing from 0 to the top.
    altitudes_m: Vec<f64>,
    /// Relative density of each species at each level, [level * species + j].
    densities: Vec<f64>,
    /// Column of each species through each layer (level k to k + 1), m,
    /// [layer * species + j].
    layer_columns_m: Vec<f64>,
}

impl VerticalGrid {
    /// `layers` layers from the ground to `top_altitude_m` for the species
    /// of `optics`, each weighted by its largest extinction coefficient on
    /// the grid.
    pub(crate) fn for_optics(
        optics: &crate::atmosphere::AtmosphereOptics,
        top_altitude_m: f64,
        layers: usize,
    ) -> VerticalGrid {
        let profiles: Vec<&DensityProfile> = optics.species.iter().map(|s| &s.profile).collect();
        let weights: Vec<f64> = optics
            .species
            .iter()
            .map(|s| {
                s.extinction_per_m
                    .values()
                    .iter()
                    .copied()
                    .fold(0.0, f64::max)
            })
            .collect();
        VerticalGrid::compute(&profiles, &weights, top_altitude_m, layers)
    }

    /// `layers` layers from the ground to `top_altitude_m` for these
    /// profiles; `extinction_weights[j]` is species j's largest extinction
    /// coefficient at relative density 1 (m^-1), its weight in the
    /// placement.
    pub(crate) fn compute(
        profiles: &[&DensityProfile],
        extinction_weights: &[f64],
        top_altitude_m: f64,
        layers: usize,
    ) -> VerticalGrid {
        assert!(layers >= 2 && top_altitude_m > 0.0);
        // u(z) at uniform altitude steps.
        let step = top_altitude_m / PLACEMENT_STEPS as f64;
        let mut optical_depth = vec![0.0; PLACEMENT_STEPS + 1];
        for i in 0..PLACEMENT_STEPS {
            let (a, b) = (i as f64 * step, (i + 1) as f64 * step);
            let slab: f64 = profiles
                .iter()
                .zip(extinction_weights)
                .map(|(p, w)| w * p.column_between_m(a, b))
                .sum();
            optical_depth[i + 1] = optical_depth[i] + slab.max(0.0);
        }
        let total = optical_depth[PLACEMENT_STEPS];
        let share = if total > 0.0 {
            OPTICAL_DEPTH_SHARE
        } else {
            0.0
        };
        let u: Vec<f64> = (0..=PLACEMENT_STEPS)
            .map(|i| {
                let tau = if total > 0.0 {
                    optical_depth[i] / total
                } else {
                    0.0
                };
                share * tau + (1.0 - share) * i as f64 / PLACEMENT_STEPS as f64
            })
            .collect();
        let mut altitudes_m = Vec::with_capacity(layers + 1);
        altitudes_m.push(0.0);
        let mut i = 0;
        for k in 1..layers {
            let target = k as f64 / layers as f64;
            while u[i + 1] < target {
                i += 1;
            }
            let t = (target - u[i]) / (u[i + 1] - u[i]);
            altitudes_m.push((i as f64 + t) * step);
        }
        altitudes_m.push(top_altitude_m);
        VerticalGrid::with_altitudes(profiles, altitudes_m)
    }

    /// The grid of these level altitudes (m, increasing from 0) for these
    /// profiles.
    pub(crate) fn with_altitudes(
        profiles: &[&DensityProfile],
        altitudes_m: Vec<f64>,
    ) -> VerticalGrid {
        let species = profiles.len();
        let densities = altitudes_m
            .iter()
            .flat_map(|z| profiles.iter().map(move |p| p.relative_density(*z)))
            .collect();
        let layer_columns_m = altitudes_m
            .windows(2)
            .flat_map(|w| profiles.iter().map(move |p| p.column_between_m(w[0], w[1])))
            .collect();
        VerticalGrid {
            species,
            altitudes_m,
            densities,
            layer_columns_m,
        }
    }

    /// Number of levels (layers + 1).
    pub(crate) fn levels(&self) -> usize {
        self.altitudes_m.len()
    }

    /// Level altitudes, m.
    pub(crate) fn altitudes_m(&self) -> &[f64] {
        &self.altitudes_m
    }

    /// Relative densities of every species at level `k`.
    pub(crate) fn densities_at_level(&self, k: usize) -> &[f64] {
        &self.densities[k * self.species..(k + 1) * self.species]
    }

    /// Columns of every species through layer `k` (level k to k + 1), m.
    pub(crate) fn layer_columns_m(&self, k: usize) -> &[f64] {
        &self.layer_columns_m[k * self.species..(k + 1) * self.species]
    }

    /// The layer containing `altitude_m` and the fraction of the way up it
    /// (clamped to the grid).
    pub(crate) fn locate(&self, altitude_m: f64) -> (usize, f64) {
        locate_among(&self.altitudes_m, altitude_m)
    }
}

/// The layer of the level altitudes `altitudes_m` (ascending, m) holding
/// `altitude_m` and the fraction of the way up it (clamped to the grid).
pub(crate) fn locate_among(altitudes_m: &[f64], altitude_m: f64) -> (usize, f64) {
    let levels = altitudes_m.len();
    let upper = altitudes_m.partition_point(|z| *z <= altitude_m);
    let k = upper.clamp(1, levels - 1) - 1;
    let (z0, z1) = (altitudes_m[k], altitudes_m[k + 1]);
    (k, ((altitude_m - z0) / (z1 - z0)).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_crowd_where_the_optical_depth_is() {
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let aerosol = DensityProfile::Exponential {
            scale_height_m: 1200.0,
        };
        let grid = VerticalGrid::compute(&[&air, &aerosol], &[4e-5, 8e-5], 100e3, 40);
        let z = grid.altitudes_m();
        assert_eq!(z.len(), 41);
        assert_eq!((z[0], z[40]), (0.0, 100e3));
        assert!(z.windows(2).all(|w| w[1] > w[0]));
        // Thin layers at the bottom, none thicker than the altitude share allows.
        assert!(z[1] < 300.0, "{}", z[1]);
        let thickest = z.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        assert!(thickest <= 100e3 / (0.3 * 40.0) + 1.0, "{thickest}");
        // Layer columns add up to the vertical column.
        let total: f64 = (0..40).map(|k| grid.layer_columns_m(k)[1]).sum();
        assert!((total / aerosol.vertical_column_m(100e3) - 1.0).abs() < 1e-12);
        assert_eq!(grid.locate(0.0), (0, 0.0));
        let (k, t) = grid.locate(z[7] + 0.25 * (z[8] - z[7]));
        assert_eq!(k, 7);
        assert!((t - 0.25).abs() < 1e-9);
        assert_eq!(grid.locate(2e5), (39, 1.0));
    }
}
