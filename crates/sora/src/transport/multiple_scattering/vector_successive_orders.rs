//! The polarised diffuse field of one column at one wavelength: the
//! successive orders of [`super::successive_orders`] carried for the
//! Stokes vector (I, Q, U, V) instead of the radiance alone.
//!
//! The equations are the scalar solver's with every quantity a Stokes
//! vector referred to its direction's meridian plane and every phase
//! function p_m a 4 x 4 block Z^m (`phase_matrix_fourier.rs`): at each
//! level the source function of harmonic m, component i, stream a is
//!
//! ```text
//! S_m,i(z, mu_a) = E T*_sun(z) sum_j omega_j(z) B^m_j,i(mu_a)
//!                + sum_b sum_c sum_j omega_j(z) w_b Z^m_j,ic(mu_a, mu_b) L_m,c(z, mu_b)
//! ```
//!
//! with I and Q carried as cosine series in the azimuth from the sun, U
//! and V as sine series. Extinction is a scalar for randomly oriented
//! particles, so every component is carried from level to level by the
//! scalar solver's own transport (the same layer weights, and along the
//! same spherical paths for the near-horizontal streams). The Lambertian
//! ground reflects unpolarised light: only I of harmonic 0 gets the
//! ground's radiance. The stopping rule is the scalar solver's, on the
//! whole Stokes field.
//!
//! It is a column solver: the sky's fast method polarises its multiply
//! scattered light with the ratio of this column's Stokes vector to the
//! scalar column's (`polarisation_correction.rs`). What it leaves out of
//! the scalar field's refinements for the spherical planet: the spherical
//! first order of a sun near or below the horizon (its first order is the
//! column's own at every sun) and the twilight shift of the spherical
//! streams (`twilight_shift.rs`).

use std::f64::consts::PI;

use super::phase_matrix_fourier::{COMPONENTS, PhaseMatrixHarmonics};
use super::successive_orders::{ColumnSystem, MAX_ITERATIONS, StoppingRule};

/// A column system (`scalar`: the streams, layers, transport and level
/// albedos) with the species' phase-matrix harmonics between its streams.
#[derive(Debug, Clone)]
pub struct VectorColumnSystem<'a> {
    scalar: ColumnSystem<'a>,
    harmonics: Vec<&'a PhaseMatrixHarmonics>,
    /// Per harmonic m, the species whose harmonic m does not vanish
    /// (Rayleigh's end at m = 2; none: the harmonic is not solved).
    active_species: Vec<Vec<usize>>,
}

impl<'a> VectorColumnSystem<'a> {
    /// `harmonics[j]`: species j's phase-matrix harmonics between the
    /// streams of `scalar` and from the sun of the solve (as many as the
    /// streams).
    pub(crate) fn new(
        scalar: ColumnSystem<'a>,
        harmonics: &[&'a PhaseMatrixHarmonics],
    ) -> VectorColumnSystem<'a> {
        let total = scalar.streams.count();
        debug_assert!(harmonics.iter().all(|h| h.harmonics() == total));
        let active_species = (0..total)
            .map(|m| {
                (0..harmonics.len())
                    .filter(|j| !harmonics[*j].harmonic_vanishes(m))
                    .collect()
            })
            .collect();
        VectorColumnSystem {
            scalar,
            harmonics: harmonics.to_vec(),
            active_species,
        }
    }

    /// Harmonic m's sun source at every level, E sum_j omega_j B^m_j,
    /// [k * size + i * streams + a] (size = 4 streams), the species'
    /// terms added in their order.
    fn sun_sources(&self, m: usize, sun_sources: &mut [f64]) {
        let scalar = &self.scalar;
        let species = self.harmonics.len();
        sun_sources.fill(0.0);
        let size = COMPONENTS * scalar.streams.count();
        for (k, sun) in sun_sources.chunks_exact_mut(size).enumerate() {
            for &j in &self.active_species[m] {
                let omega = scalar.level_albedo[k * species + j];
                if omega == 0.0 {
                    continue;
                }
                for (out, value) in sun.iter_mut().zip(self.harmonics[j].sun(m)) {
                    *out += scalar.solar_irradiance * omega * value;
                }
            }
        }
    }

    /// The values of a field: harmonics x components x levels x streams,
    /// [((m * 4 + i) * levels + k) * streams + a].
    pub(crate) fn field_len(&self) -> usize {
        let total = self.scalar.streams.count();
        total * COMPONENTS * self.scalar.grid.levels() * total
    }

    /// Solves for the sun at zenith cosine `sun_cosine` (the one the
    /// harmonics were computed for) with scaled transmittances
    /// `sun_transmittance[k]` at each level (0 in the planet's shadow) into
    /// `radiance` ([`VectorColumnSystem::field_len`] values, each
    /// component's block laid out as the scalar solver's field), with
    /// `work` space. Returns the diffuse downward irradiance at the ground.
    pub(crate) fn solve(
        &self,
        sun_cosine: f64,
        sun_transmittance: &[f64],
        radiance: &mut [f64],
        work: &mut Vec<f64>,
    ) -> f64 {
        let scalar = &self.scalar;
        let levels = scalar.grid.levels();
        let total = scalar.streams.count();
        let size = COMPONENTS * total;
        let block = levels * total;
        let field_size = COMPONENTS * block;
        let species = self.harmonics.len();
        work.resize(4 * field_size + levels * size + 2 * size + 2 * levels, 0.0);
        let (sun_sources, rest) = work.split_at_mut(levels * size);
        let (direct_source, rest) = rest.split_at_mut(field_size);
        let (source, rest) = rest.split_at_mut(field_size);
        let (previous, rest) = rest.split_at_mut(field_size);
        let (increment, rest) = rest.split_at_mut(field_size);
        let (gathered, rest) = rest.split_at_mut(size);
        let (scattered, columns) = rest.split_at_mut(size);
        radiance.fill(0.0);
        let ground_direct = if sun_cosine > 0.0 {
            scalar.ground_albedo / PI * scalar.solar_irradiance * sun_cosine * sun_transmittance[0]
        } else {
            0.0
        };
        let mut ground_diffuse_irradiance = 0.0;
        for m in (0..total).filter(|m| !self.active_species[*m].is_empty()) {
            self.sun_sources(m, sun_sources);
            // Single scattering of the sun's beam into every stream and
            // component.
            for k in 0..levels {
                let sun = &sun_sources[k * size..][..size];
                for i in 0..COMPONENTS {
                    for a in 0..total {
                        direct_source[i * block + k * total + a] =
                            sun_transmittance[k] * sun[i * total + a];
                    }
                }
            }
            let field = &mut radiance[m * field_size..(m + 1) * field_size];
            source.copy_from_slice(direct_source);
            let mut stopping = StoppingRule::new();
            for _ in 0..MAX_ITERATIONS {
                previous.copy_from_slice(field);
                let ground_radiance = match m {
                    0 => scalar.ground_albedo / PI * scalar.downward_flux(previous) + ground_direct,
                    _ => 0.0,
                };
                for i in 0..COMPONENTS {
                    let ground = if i == 0 { ground_radiance } else { 0.0 };
                    let range = i * block..(i + 1) * block;
                    scalar.transport(&source[range.clone()], ground, &mut field[range], columns);
                }
                if stopping.finish_sweep(field, previous, increment) {
                    break;
                }
                // Scattering of the new field: the next order's source,
                // level by level (gathered into one Stokes-and-streams
                // vector), species by species: omega_j(z) times the
                // species' matrix (the same at every level, so it stays
                // in cache) times the field, by whole columns.
                source.copy_from_slice(direct_source);
                for k in 0..levels {
                    for i in 0..COMPONENTS {
                        gathered[i * total..(i + 1) * total]
                            .copy_from_slice(&field[i * block + k * total..][..total]);
                    }
                    for &j in &self.active_species[m] {
                        let omega = scalar.level_albedo[k * species + j];
                        if omega == 0.0 {
                            continue;
                        }
                        let matrix = self.harmonics[j].scattering(m);
                        scattered.fill(0.0);
                        for (value, column) in gathered.iter().zip(matrix.chunks_exact(size)) {
                            if *value != 0.0 {
                                for (o, p) in scattered.iter_mut().zip(column) {
                                    *o += value * p;
                                }
                            }
                        }
                        for i in 0..COMPONENTS {
                            for (s, v) in source[i * block + k * total..][..total]
                                .iter_mut()
                                .zip(&scattered[i * total..(i + 1) * total])
                            {
                                *s += omega * v;
                            }
                        }
                    }
                }
            }
            if m == 0 {
                ground_diffuse_irradiance = scalar.downward_flux(field);
            }
        }
        ground_diffuse_irradiance
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;
    use crate::atmosphere::phase_matrix::{PhaseMatrix, rayleigh_phase_matrix};
    use crate::transport::multiple_scattering::phase_fourier::TruncatedPhase;
    use crate::transport::multiple_scattering::spherical_paths::linear_source_weights;
    use crate::transport::multiple_scattering::successive_orders::{ScaledSpecies, Streams};
    use crate::transport::multiple_scattering::vertical_grid::VerticalGrid;
    use crate::transport::reference_tests::reference_data::coulson_table;

    /// A slab of `species` (profile, scattering = extinction at density 1
    /// per m, scalar phase, phase matrix) on `layers` layers up to 100 km.
    struct Slab {
        grid: VerticalGrid,
        streams: Streams,
    }

    impl Slab {
        fn new(profiles: &[&DensityProfile], betas: &[f64], layers: usize, streams: usize) -> Slab {
            Slab {
                grid: VerticalGrid::compute(profiles, betas, 100e3, layers),
                streams: Streams::new(streams),
            }
        }

        /// Optical depth of each layer.
        fn layer_optical_depths(&self, betas: &[f64]) -> Vec<f64> {
            (0..self.grid.levels() - 1)
                .map(|k| {
                    betas
                        .iter()
                        .zip(self.grid.layer_columns_m(k))
                        .map(|(b, c)| b * c)
                        .sum()
                })
                .collect()
        }

        /// The plane-parallel beam transmittance at each level.
        fn sun_transmittance(&self, betas: &[f64], sun_cosine: f64) -> Vec<f64> {
            let dtau = self.layer_optical_depths(betas);
            let mut t = vec![1.0; self.grid.levels()];
            for k in (0..dtau.len()).rev() {
                t[k] = t[k + 1] * (-dtau[k] / sun_cosine).exp();
            }
            t
        }
    }

    #[test]
    fn non_polarising_species_give_the_scalar_field() {
        // Rayleigh-like and HG scattering whose matrices are p times the
        // identity: no Q, U, V is ever made, and I is the scalar solver's
        // (every harmonic, level and stream).
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let aerosol = DensityProfile::Exponential {
            scale_height_m: 1200.0,
        };
        let betas = [4e-5, 1.5e-4];
        let slab = Slab::new(&[&air, &aerosol], &betas, 30, 4);
        let total = slab.streams.count();
        let rayleigh_moments: Vec<f64> = (0..=total)
            .map(|l| match l {
                0 => 1.0,
                2 => 0.1,
                _ => 0.0,
            })
            .collect();
        let hg_moments: Vec<f64> = (0..=total).map(|l| 0.7f64.powi(l as i32)).collect();
        let rayleigh = TruncatedPhase::from_moments(&rayleigh_moments, total);
        let hg = TruncatedPhase::from_moments(&hg_moments, total);
        let f = hg.forward_fraction;
        let scaled = [betas[0], betas[1] * (1.0 - f)];
        let species = vec![
            ScaledSpecies {
                extinction_per_m: scaled[0],
                scattering_per_m: scaled[0],
                phase: &rayleigh,
            },
            ScaledSpecies {
                extinction_per_m: scaled[1],
                scattering_per_m: scaled[1] * 0.9,
                phase: &hg,
            },
        ];
        let (solar, albedo, sun_cosine) = (1.7, 0.3, 0.4);
        let scalar = ColumnSystem::new(&slab.streams, &slab.grid, None, species, solar, albedo);
        let harmonics: Vec<PhaseMatrixHarmonics> = [&rayleigh, &hg]
            .iter()
            .map(|p| {
                PhaseMatrixHarmonics::compute(
                    &|c, out| out[0] = PhaseMatrix::non_polarising(p.eval(c)),
                    1,
                    slab.streams.cosines(),
                    (slab.streams.cosines(), slab.streams.weights()),
                    Some(sun_cosine),
                    total,
                )
                .remove(0)
            })
            .collect();
        let vector = VectorColumnSystem::new(scalar.clone(), &harmonics.iter().collect::<Vec<_>>());
        let transmittance = slab.sun_transmittance(&scaled, sun_cosine);
        let levels = slab.grid.levels();
        let mut scalar_field = vec![0.0; total * levels * total];
        let mut vector_field = vec![0.0; vector.field_len()];
        let mut work = Vec::new();
        let scalar_down = scalar.solve(sun_cosine, &transmittance, &mut scalar_field, &mut work);
        let vector_down = vector.solve(sun_cosine, &transmittance, &mut vector_field, &mut work);
        assert!((vector_down - scalar_down).abs() < 1e-12 * scalar_down);
        let block = levels * total;
        let largest = scalar_field.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for m in 0..total {
            for at in 0..block {
                let s = scalar_field[m * block + at];
                let v = &vector_field[m * COMPONENTS * block..];
                assert!(
                    (v[at] - s).abs() <= 1e-12 * largest,
                    "m {m} at {at}: {} vs {s}",
                    v[at]
                );
                for i in 1..COMPONENTS {
                    assert!(v[i * block + at].abs() <= 1e-14 * largest);
                }
            }
        }
    }

    /// (I, Q, U) reflected to the top of a Rayleigh slab (no depolarisation,
    /// vertical optical depth `tau`, ground albedo `albedo`) with the sun at
    /// zenith cosine `sun_cosine` and incident flux pi, looking down at
    /// zenith cosine `-mu` at azimuth `phi_deg` from the sun's, in sora's
    /// convention; by source-function integration of the converged field
    /// along the view from the ground up.
    fn reflected_stokes(
        tau: f64,
        albedo: f64,
        sun_cosine: f64,
        views: &[(f64, f64)],
        (streams, layers): (usize, usize),
    ) -> Vec<[f64; 3]> {
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let slab = Slab::new(&[&air], &[1.0], layers, streams);
        // The scattering coefficient (m^-1) that gives the slab optical depth tau.
        let column_m: f64 = (0..slab.grid.levels() - 1)
            .map(|k| slab.grid.layer_columns_m(k)[0])
            .sum();
        let betas = [tau / column_m];
        let total = slab.streams.count();
        let moments: Vec<f64> = (0..=total)
            .map(|l| match l {
                0 => 1.0,
                2 => 0.1,
                _ => 0.0,
            })
            .collect();
        let rayleigh = TruncatedPhase::from_moments(&moments, total);
        let species = vec![ScaledSpecies {
            extinction_per_m: betas[0],
            scattering_per_m: betas[0],
            phase: &rayleigh,
        }];
        let solar = PI;
        let scalar = ColumnSystem::new(&slab.streams, &slab.grid, None, species, solar, albedo);
        let phase = |c: f64, out: &mut [PhaseMatrix]| out[0] = rayleigh_phase_matrix(0.0, c);
        let (cosines, weights) = (slab.streams.cosines(), slab.streams.weights());
        let harmonics = PhaseMatrixHarmonics::compute(
            &phase,
            1,
            cosines,
            (cosines, weights),
            Some(sun_cosine),
            total,
        )
        .remove(0);
        let vector = VectorColumnSystem::new(scalar, &[&harmonics]);
        let transmittance = slab.sun_transmittance(&betas, sun_cosine);
        let mut field = vec![0.0; vector.field_len()];
        let mut work = Vec::new();
        let diffuse_down = vector.solve(sun_cosine, &transmittance, &mut field, &mut work);
        let levels = slab.grid.levels();
        let block = levels * total;
        let dtau = slab.layer_optical_depths(&betas);
        views
            .iter()
            .map(|&(mu, phi_deg)| {
                let rows = PhaseMatrixHarmonics::compute(
                    &phase,
                    1,
                    &[-mu],
                    (cosines, weights),
                    Some(sun_cosine),
                    total,
                )
                .remove(0);
                let mut stokes = [0.0; 3];
                for m in 0..total {
                    let matrix = rows.scattering(m);
                    let sun = rows.sun(m);
                    // The source at every level for this view.
                    let source: Vec<[f64; COMPONENTS]> = (0..levels)
                        .map(|k| {
                            let mut s = [0.0; COMPONENTS];
                            for (i, value) in s.iter_mut().enumerate() {
                                *value = solar * transmittance[k] * sun[i];
                                for c in 0..COMPONENTS {
                                    for b in 0..total {
                                        *value += matrix[(c * total + b) * COMPONENTS + i]
                                            * field[(m * COMPONENTS + c) * block + k * total + b];
                                    }
                                }
                            }
                            s
                        })
                        .collect();
                    let mut radiance = [0.0; COMPONENTS];
                    if m == 0 {
                        radiance[0] =
                            albedo / PI * (diffuse_down + solar * sun_cosine * transmittance[0]);
                    }
                    for k in 0..levels - 1 {
                        let (one_minus_e, c) = linear_source_weights(dtau[k] / mu);
                        for (i, r) in radiance.iter_mut().enumerate() {
                            *r = (1.0 - one_minus_e) * *r
                                + (one_minus_e - c) * source[k + 1][i]
                                + c * source[k][i];
                        }
                    }
                    let (sin_m, cos_m) = (m as f64 * phi_deg.to_radians()).sin_cos();
                    stokes[0] += radiance[0] * cos_m;
                    stokes[1] += radiance[1] * cos_m;
                    stokes[2] += radiance[2] * sin_m;
                }
                stokes
            })
            .collect()
    }

    #[test]
    fn stokes_vectors_match_the_coulson_tables() {
        // The corrected Coulson, Dave & Sekera tables (Natraj, Li & Yung
        // 2009): tau 0.5, mu0 0.2, no depolarisation. Their Q and U are both
        // of the opposite sign to sora's (see the path tracer's test in
        // `reference_tests/polarisation_reference.rs`: they refer Stokes
        // vectors to the plane perpendicular to the meridian plane); phi is
        // the view's azimuth from the sun's, as in sora.
        let table = coulson_table();
        let mut worst = 0.0f64;
        for albedo in [0.0, 0.8] {
            let rows: Vec<&Vec<f64>> = table.rows.iter().filter(|r| r[0] == albedo).collect();
            let views: Vec<(f64, f64)> = rows.iter().map(|r| (r[1], r[2])).collect();
            let ours = reflected_stokes(0.5, albedo, 0.2, &views, (12, 60));
            for (row, s) in rows.iter().zip(&ours) {
                let mapped = [s[0], -s[1], -s[2]];
                for c in 0..3 {
                    let error = (mapped[c] - row[3 + c]).abs();
                    worst = worst.max(error);
                    assert!(
                        error <= 1e-4,
                        "albedo {albedo} mu {} phi {}: component {c} {} vs table {} ({error:.2e})",
                        row[1],
                        row[2],
                        mapped[c],
                        row[3 + c]
                    );
                }
            }
        }
        println!("worst absolute difference {worst:.2e}");
    }
}
