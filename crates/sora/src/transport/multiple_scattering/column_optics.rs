//! The values the field's steps share: the delta-M scaled optics
//! ([`ScaledOptics`], per wavelength and species) and the columns'
//! geometry ([`ColumnGeometry`]: the vertical grid, the streams and their
//! spherical paths, the profiles and their corners).

use super::MultipleScatteringSettings;
use super::phase_fourier::{TruncatedPhase, compute_truncated_phases};
use super::spherical_paths::StreamPaths;
use super::successive_orders::Streams;
use super::vertical_grid::VerticalGrid;
use crate::atmosphere::AtmosphereOptics;
use crate::atmosphere::DensityProfile;
use crate::geometry::Vector3;
use crate::transport::optical_column::{ProfileCorners, compute_columns_along_ray};
use crate::transport::single_scattering::SingleScatteringScene;

/// Panels of the exact column integrals toward the sun from each level.
pub(super) const SUN_RAY_PANELS: usize = 12;

/// Delta-M truncated phase functions and the scaled coefficients, per
/// wavelength i and species j at [i * species + j], m^-1 at relative
/// density 1.
#[derive(Debug, Clone)]
pub(super) struct ScaledOptics {
    pub(super) phases: Vec<TruncatedPhase>,
    pub(super) extinction: Vec<f64>,
    pub(super) scaled_extinction: Vec<f64>,
    pub(super) scaled_scattering: Vec<f64>,
}

impl ScaledOptics {
    /// The delta-M scaling of `optics` to `degrees` Legendre terms.
    pub(super) fn delta_m(optics: &AtmosphereOptics, degrees: usize) -> ScaledOptics {
        let (wavelengths, species) = (optics.grid.len(), optics.species.len());
        let phases = compute_truncated_phases(optics, degrees);
        let mut extinction = vec![0.0; wavelengths * species];
        let mut scaled_extinction = vec![0.0; wavelengths * species];
        let mut scaled_scattering = vec![0.0; wavelengths * species];
        for i in 0..wavelengths {
            for (j, s) in optics.species.iter().enumerate() {
                let f = phases[i * species + j].forward_fraction;
                let (ext, sca) = (s.extinction_per_m[i], s.scattering_per_m[i]);
                extinction[i * species + j] = ext;
                scaled_extinction[i * species + j] = ext - f * sca;
                scaled_scattering[i * species + j] = (1.0 - f) * sca;
            }
        }
        ScaledOptics {
            phases,
            extinction,
            scaled_extinction,
            scaled_scattering,
        }
    }

    /// The scaled and exact optical depths at wavelength `i` of `columns`
    /// (m, one per species).
    pub(super) fn optical_depths(&self, i: usize, columns: &[f64]) -> (f64, f64) {
        let species = columns.len();
        let (mut scaled, mut exact) = (0.0, 0.0);
        for (j, column) in columns.iter().enumerate() {
            scaled += self.scaled_extinction[i * species + j] * column;
            exact += self.extinction[i * species + j] * column;
        }
        (scaled, exact)
    }
}

/// The columns' geometry: the vertical grid, the spherical streams'
/// paths, the profiles and their corners, and the geometric columns
/// toward the sun from every level.
#[derive(Debug, Clone)]
pub(super) struct ColumnGeometry {
    pub(super) ground_radius_m: f64,
    pub(super) top_radius_m: f64,
    pub(super) streams: Streams,
    pub(super) grid: VerticalGrid,
    pub(super) paths: StreamPaths,
    pub(super) profiles: Vec<DensityProfile>,
    pub(super) corners: ProfileCorners,
}

impl ColumnGeometry {
    pub(super) fn new(
        sky: &SingleScatteringScene,
        settings: &MultipleScatteringSettings,
    ) -> ColumnGeometry {
        let optics = sky.optics();
        let (ground_radius_m, top_radius_m) = sky.radii_m();
        let profiles: Vec<DensityProfile> =
            optics.species.iter().map(|s| s.profile.clone()).collect();
        let grid =
            VerticalGrid::for_optics(optics, top_radius_m - ground_radius_m, settings.layers);
        ColumnGeometry::on_grid(
            profiles,
            (ground_radius_m, top_radius_m),
            Streams::new(settings.streams_per_hemisphere),
            grid,
        )
    }

    /// The geometry of a shell from `ground_radius_m` to `top_radius_m`
    /// with levels at `altitudes_m` (m, increasing from 0), for the tests
    /// that choose their own levels.
    #[cfg(test)]
    pub(super) fn with_levels(
        profiles: Vec<DensityProfile>,
        radii_m: (f64, f64),
        streams_per_hemisphere: usize,
        altitudes_m: &[f64],
    ) -> ColumnGeometry {
        let grid = VerticalGrid::with_altitudes(
            &profiles.iter().collect::<Vec<_>>(),
            altitudes_m.to_vec(),
        );
        ColumnGeometry::on_grid(
            profiles,
            radii_m,
            Streams::new(streams_per_hemisphere),
            grid,
        )
    }

    /// The streams' paths and the profiles' corners of a shell from
    /// `ground_radius_m` to `top_radius_m` on `grid`.
    fn on_grid(
        profiles: Vec<DensityProfile>,
        (ground_radius_m, top_radius_m): (f64, f64),
        streams: Streams,
        grid: VerticalGrid,
    ) -> ColumnGeometry {
        let radii: Vec<f64> = grid
            .altitudes_m()
            .iter()
            .map(|z| ground_radius_m + z)
            .collect();
        let paths = StreamPaths::compute(&radii, streams.cosines());
        let corners = ProfileCorners::new(&profiles, ground_radius_m, top_radius_m);
        ColumnGeometry {
            ground_radius_m,
            top_radius_m,
            streams,
            grid,
            paths,
            profiles,
            corners,
        }
    }

    /// Appends to `sun_columns` the geometric columns (m, per species)
    /// toward a sun at zenith angle `theta` (rad) from every level, None in
    /// the planet's shadow.
    pub(super) fn add_columns_toward_sun(
        &self,
        theta: f64,
        sun_columns: &mut Vec<Option<Vec<f64>>>,
    ) {
        let (ground_radius_m, top_radius_m) = (self.ground_radius_m, self.top_radius_m);
        let mut ends = Vec::with_capacity(self.corners.most_panel_ends(SUN_RAY_PANELS));
        let direction = Vector3::new(theta.sin(), 0.0, theta.cos());
        for &z in self.grid.altitudes_m() {
            let r = ground_radius_m + z;
            if crate::geometry::ray_intersects_ground(r, theta.cos(), ground_radius_m) {
                sun_columns.push(None);
                continue;
            }
            let origin = Vector3::new(0.0, 0.0, r);
            let length =
                crate::geometry::distance_to_top_of_atmosphere(origin, direction, top_radius_m);
            let mut columns = vec![0.0; self.profiles.len()];
            self.corners
                .fill_panel_ends(origin, direction, length, SUN_RAY_PANELS, &mut ends);
            compute_columns_along_ray(
                &self.profiles,
                ground_radius_m,
                origin,
                direction,
                &ends,
                &mut columns,
            );
            sun_columns.push(Some(columns));
        }
    }
}
