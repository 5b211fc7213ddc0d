//! The polarisation of the multiply scattered light, first form: the
//! column at the eye solved twice, with Stokes vectors
//! ([`super::vector_successive_orders`]) and scalar
//! ([`super::successive_orders`]), and the ratio of the two columns'
//! multiply scattered light applied to the sky's own (spherical) multiply
//! scattered radiance:
//!
//! ```text
//! (I, Q, U, V)_ms(eye, w) = L_ms(eye, w) (I, Q, U, V)_col(w) / I_col,scalar(w)
//! ```
//!
//! L_ms the scalar field's radiance (every refinement of the sphere:
//! spherical paths, the spherical first order, the view ray through the
//! shell), the column's Stokes vector and scalar intensity those of the
//! light scattered two or more times that reaches the eye's level from
//! w in the plane-parallel column with the eye's sun zenith angle (the
//! sun's beam attenuated along its real path through the shell, as the
//! scalar field's), by source-function integration along w from the
//! top (looking up) or the ground (looking down) to the eye's level.
//!
//! **What it is exact for**: the plane-parallel limit, where the scalar
//! field is the column's and the ratio turns its intensity into the
//! polarised one. **What it assumes on the sphere**: that the sphere
//! changes the polarised and the scalar multiply scattered light in the
//! same proportion (the ratio is a smooth function of direction, a degree
//! of polarisation and a few per cent of intensity); with the sun near or
//! below the horizon the column's first order is its own (not the
//! spherical one), so the ratio is the one of a column whose lower air is
//! in the shadow. The measured accuracy against the vector path tracer is
//! in `docs/polarisation.md`.
//!
//! **The truncated phase matrix**: delta-M truncates the phase function
//! (`phase_fourier.rs`); the matrix's other elements are taken in the
//! same proportion to it as in the exact matrix, F*_xy = (F_xy / F_11)
//! F*_11 (exact for Rayleigh, which is not truncated, and for
//! non-polarising species, whose ratios are 0 and 1).

use std::f64::consts::PI;

use super::phase_fourier::TruncatedPhase;
use super::phase_matrix_fourier::{COMPONENTS, PhaseMatrixHarmonics, is_even_component};
use super::spherical_paths::{StreamPaths, linear_source_weights};
use super::successive_orders::{ColumnSystem, ScaledSpecies, Streams};
use super::vector_successive_orders::VectorColumnSystem;
use super::vertical_grid::VerticalGrid;
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{AtmosphereOptics, PhaseFunction};

/// The smallest |cosine| of a view's zenith angle the column integrates
/// along (a horizontal view sees the eye level's own source).
const SMALLEST_VIEW_COSINE: f64 = 1e-6;

/// Everything the correction's columns need from the scalar field.
pub(crate) struct CorrectionInputs<'a> {
    pub(crate) optics: &'a AtmosphereOptics,
    pub(crate) streams: &'a Streams,
    pub(crate) grid: &'a VerticalGrid,
    pub(crate) paths: &'a StreamPaths,
    /// Delta-M truncated phase functions, [i * species + j].
    pub(crate) phases: &'a [TruncatedPhase],
    /// [i * species + j], m^-1 at relative density 1.
    pub(crate) scaled_extinction: &'a [f64],
    pub(crate) scaled_scattering: &'a [f64],
    /// The eye's sun zenith cosine.
    pub(crate) sun_cosine: f64,
    /// The scaled and exact optical depths toward the sun from each level,
    /// [i * levels + k], None for a level in the planet's shadow (the
    /// eye's sun zenith angle).
    pub(crate) sun_optical_depths: &'a [Option<(f64, f64)>],
    pub(crate) eye_altitude_m: f64,
}

/// The two columns' fields at the eye's sun zenith angle (see the module
/// docs).
#[derive(Debug, Clone)]
pub struct PolarisationCorrection {
    wavelengths: usize,
    species: usize,
    streams: Streams,
    levels: usize,
    eye_level: usize,
    /// Per wavelength the polarised field, the scalar field, and the two
    /// ground radiances (polarised, scalar), W m^-2 sr^-1 nm^-1.
    solutions: Vec<f64>,
    solution_len: usize,
    /// [i * layers + k].
    layer_optical_depths: Vec<f64>,
    /// omega_j per wavelength and level, [(i * levels + k) * species + j].
    level_albedos: Vec<f64>,
}

/// F*(cos theta) of species `j` at every wavelength into `out`: the exact
/// matrix scaled to the truncated phase function (see the module docs).
fn truncated_phase_matrix_into(
    function: &PhaseFunction,
    phases: &[TruncatedPhase],
    (j, species): (usize, usize),
    cos_theta: f64,
    out: &mut [PhaseMatrix],
) {
    function.phase_matrix_into(cos_theta, out);
    for (i, m) in out.iter_mut().enumerate() {
        let truncated = phases[i * species + j].eval(cos_theta);
        let scale = if m.a1 > 0.0 { truncated / m.a1 } else { 0.0 };
        for value in [
            &mut m.a1, &mut m.a2, &mut m.a3, &mut m.a4, &mut m.b1, &mut m.b2,
        ] {
            *value *= scale;
        }
    }
}

/// Each species' harmonics of its truncated phase matrix from the streams
/// (and the sun, if given) into the look directions of zenith cosines
/// `outputs`, at every wavelength: [j][i].
fn compute_species_harmonics(
    optics: &AtmosphereOptics,
    phases: &[TruncatedPhase],
    streams: &Streams,
    outputs: &[f64],
    sun_cosine: Option<f64>,
) -> Vec<Vec<PhaseMatrixHarmonics>> {
    let species = optics.species.len();
    optics
        .species
        .iter()
        .enumerate()
        .map(|(j, s)| {
            PhaseMatrixHarmonics::compute(
                &|c, out| {
                    truncated_phase_matrix_into(&s.phase_function, phases, (j, species), c, out)
                },
                optics.grid.len(),
                outputs,
                (streams.cosines(), streams.weights()),
                sun_cosine,
                streams.count(),
            )
        })
        .collect()
}

impl PolarisationCorrection {
    /// Solves both columns at every wavelength.
    pub(crate) fn compute(inputs: &CorrectionInputs) -> PolarisationCorrection {
        let optics = inputs.optics;
        let wavelengths = optics.grid.len();
        let species = optics.species.len();
        let streams = inputs.streams;
        let total = streams.count();
        let grid = inputs.grid;
        let levels = grid.levels();
        let cosines = streams.cosines();
        // Each species' harmonics between the streams and from the sun, at
        // every wavelength: [j][i].
        let harmonics = compute_species_harmonics(
            optics,
            inputs.phases,
            streams,
            cosines,
            Some(inputs.sun_cosine),
        );
        let vector_len = total * COMPONENTS * levels * total;
        let scalar_len = total * levels * total;
        let solution_len = vector_len + scalar_len + 2;
        let mut solutions = vec![0.0; wavelengths * solution_len];
        let mut level_albedos = vec![0.0; wavelengths * levels * species];
        let mut layer_optical_depths = vec![0.0; wavelengths * (levels - 1)];
        for i in 0..wavelengths {
            for k in 0..levels - 1 {
                layer_optical_depths[i * (levels - 1) + k] = (0..species)
                    .map(|j| inputs.scaled_extinction[i * species + j] * grid.layer_columns_m(k)[j])
                    .sum();
            }
        }
        let lit = inputs.sun_cosine.max(0.0);
        crate::parallel::for_each_chunk_mut(&mut solutions, solution_len, |i, out| {
            let scaled: Vec<ScaledSpecies> = (0..species)
                .map(|j| ScaledSpecies {
                    extinction_per_m: inputs.scaled_extinction[i * species + j],
                    scattering_per_m: inputs.scaled_scattering[i * species + j],
                    phase: &inputs.phases[i * species + j],
                })
                .collect();
            let solar = optics.solar_irradiance_w_m2_nm[i];
            let albedo = optics.ground_albedo[i];
            let scalar =
                ColumnSystem::new(streams, grid, Some(inputs.paths), scaled, solar, albedo);
            let per_species: Vec<&PhaseMatrixHarmonics> = harmonics.iter().map(|h| &h[i]).collect();
            let vector = VectorColumnSystem::new(scalar.clone(), &per_species);
            debug_assert_eq!(vector.field_len(), vector_len);
            let optical_depths = &inputs.sun_optical_depths[i * levels..(i + 1) * levels];
            let transmittance: Vec<f64> = optical_depths
                .iter()
                .map(|t| t.map_or(0.0, |(scaled, _)| (-scaled).exp()))
                .collect();
            let exact_ground = optical_depths[0].map_or(0.0, |(_, exact)| (-exact).exp());
            let (vector_field, rest) = out.split_at_mut(vector_len);
            let (scalar_field, ground) = rest.split_at_mut(scalar_len);
            let mut work = Vec::new();
            let sun_cosine = inputs.sun_cosine;
            let down_vector = vector.solve(sun_cosine, &transmittance, vector_field, &mut work);
            let down_scalar =
                scalar.solve(sun_cosine, &transmittance, None, scalar_field, &mut work);
            // The ground's diffuse light as the scalar field's ground
            // term takes it (the sunlit ground's single reflection is
            // exact elsewhere; delta-M's share of the beam stays here).
            let beam = solar * lit * (transmittance[0] - exact_ground);
            ground[0] = albedo / PI * (down_vector + beam);
            ground[1] = albedo / PI * (down_scalar + beam);
        });
        // The level albedos are the scalar system's (the same for both).
        for i in 0..wavelengths {
            for k in 0..levels {
                let densities = grid.densities_at_level(k);
                let extinction: f64 = (0..species)
                    .map(|j| inputs.scaled_extinction[i * species + j] * densities[j])
                    .sum();
                if extinction > 0.0 {
                    for j in 0..species {
                        level_albedos[(i * levels + k) * species + j] =
                            densities[j] * inputs.scaled_scattering[i * species + j] / extinction;
                    }
                }
            }
        }
        let (k, t) = grid.locate(inputs.eye_altitude_m);
        PolarisationCorrection {
            wavelengths,
            species,
            streams: streams.clone(),
            levels,
            eye_level: if t < 0.5 { k } else { (k + 1).min(levels - 1) },
            solutions,
            solution_len,
            layer_optical_depths,
            level_albedos,
        }
    }

    /// The ratios (I, Q, U, V)_col / I_col,scalar toward the view of zenith
    /// cosine `view_cosine` at azimuth `view_azimuth_rad` from the sun's
    /// (clockwise, the sky's convention) at every wavelength, into `out`
    /// ([component * wavelengths + i]); (1, 0, 0, 0) where the column has
    /// no multiply scattered light.
    pub(crate) fn compute_ratios(
        &self,
        optics: &AtmosphereOptics,
        phases: &[TruncatedPhase],
        (view_cosine, view_azimuth_rad): (f64, f64),
        out: &mut [f64],
    ) {
        let (w, species, levels) = (self.wavelengths, self.species, self.levels);
        let total = self.streams.count();
        let block = levels * total;
        let mu = if view_cosine.abs() < SMALLEST_VIEW_COSINE {
            SMALLEST_VIEW_COSINE
        } else {
            view_cosine
        };
        let rows = compute_species_harmonics(optics, phases, &self.streams, &[mu], None);
        let mut sources = vec![[0.0; COMPONENTS + 1]; levels];
        for i in 0..w {
            let solution = &self.solutions[i * self.solution_len..][..self.solution_len];
            let vector_len = total * COMPONENTS * block;
            let (vector_field, rest) = solution.split_at(vector_len);
            let (scalar_field, ground) = rest.split_at(total * block);
            let dtau = &self.layer_optical_depths[i * (levels - 1)..(i + 1) * (levels - 1)];
            // Polarised (I, Q, U, V), then the scalar I, at the eye.
            let mut stokes = [0.0; COMPONENTS + 1];
            for m in 0..total {
                for (k, source) in sources.iter_mut().enumerate() {
                    *source = [0.0; COMPONENTS + 1];
                    for (j, species_rows) in rows.iter().enumerate() {
                        let omega = self.level_albedos[(i * levels + k) * species + j];
                        if omega == 0.0 {
                            continue;
                        }
                        let matrix = species_rows[i].scattering(m);
                        for c in 0..COMPONENTS {
                            for b in 0..total {
                                let radiance =
                                    vector_field[(m * COMPONENTS + c) * block + k * total + b];
                                let column = &matrix[(c * total + b) * COMPONENTS..][..COMPONENTS];
                                for (s, z) in source.iter_mut().zip(column) {
                                    *s += omega * z * radiance;
                                }
                            }
                        }
                        for b in 0..total {
                            source[COMPONENTS] += omega
                                * matrix[b * COMPONENTS]
                                * scalar_field[m * block + k * total + b];
                        }
                    }
                }
                let mut radiance = [0.0; COMPONENTS + 1];
                let carry =
                    |radiance: &mut [f64; COMPONENTS + 1], k: usize, near: usize, far: usize| {
                        let (one_minus_e, c) = linear_source_weights(dtau[k] / mu.abs());
                        for (n, r) in radiance.iter_mut().enumerate() {
                            *r = (1.0 - one_minus_e) * *r
                                + (one_minus_e - c) * sources[near][n]
                                + c * sources[far][n];
                        }
                    };
                if mu > 0.0 {
                    for k in (self.eye_level..levels - 1).rev() {
                        carry(&mut radiance, k, k, k + 1);
                    }
                } else {
                    if m == 0 {
                        radiance[0] = ground[0];
                        radiance[COMPONENTS] = ground[1];
                    }
                    for k in 0..self.eye_level {
                        carry(&mut radiance, k, k + 1, k);
                    }
                }
                let (sin_m, cos_m) = (m as f64 * view_azimuth_rad).sin_cos();
                for (n, (s, r)) in stokes.iter_mut().zip(radiance).enumerate() {
                    let even = n == COMPONENTS || is_even_component(n);
                    *s += r * if even { cos_m } else { sin_m };
                }
            }
            let scalar = stokes[COMPONENTS];
            for c in 0..COMPONENTS {
                out[c * w + i] = if scalar > 0.0 {
                    stokes[c] / scalar
                } else if c == 0 {
                    1.0
                } else {
                    0.0
                };
            }
        }
    }
}
