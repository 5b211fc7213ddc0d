//! Phase sampling at a scattering vertex (step 4): the new direction drawn
//! from one wavelength's phase function or toward the sunlit air, and the
//! cosine-weighted reflection off the ground.

use std::f64::consts::PI;

use super::tracer::{PathScratch, PathTracer};
use crate::atmosphere::PhaseFunction;
use crate::atmosphere::phase::henyey_greenstein_phase;
use crate::geometry::{Vector3, direction_about};
use crate::transport::random::RandomStream;
use crate::transport::sunlit_directions::SunlitDirections;

/// The share of the scattered directions drawn toward the sunlit air at a
/// vertex in the planet's shadow (module docs, step 4;
/// [`SunlitDirections`]).
pub(super) const SUNLIT_DIRECTION_SHARE: f64 = 0.5;

/// A cosine-weighted direction about the unit `normal` (pdf n.w / pi).
pub(super) fn cosine_weighted_direction(normal: Vector3, u: [f64; 2]) -> Vector3 {
    direction_about(normal, (1.0 - u[0]).sqrt(), 2.0 * PI * u[1])
}

impl<'a> PathTracer<'a> {
    /// Samples the direction after a scattering at the current vertex
    /// (module docs, step 4) and weights the throughput; None when nothing
    /// scatters here.
    pub(super) fn sample_scattering(
        &self,
        direction: Vector3,
        toward_sunlit_air: Option<&SunlitDirections>,
        random: &mut RandomStream,
        scratch: &mut PathScratch,
    ) -> Option<Vector3> {
        let n = self.wavelengths;
        let members = scratch
            .scattering_coefficient
            .iter()
            .filter(|s| **s > 0.0)
            .count();
        if members == 0 {
            return None;
        }
        let pick = random.next_index(members);
        let hero = scratch
            .scattering_coefficient
            .iter()
            .enumerate()
            .filter(|(_, s)| **s > 0.0)
            .nth(pick)
            .map_or(0, |(i, _)| i);
        // The species, with probability sigma_s,j / sigma_s at the hero.
        let threshold = random.next_f64() * scratch.scattering_coefficient[hero];
        let mut chosen = None;
        let mut running = 0.0;
        for j in 0..self.profiles.len() {
            let share = scratch.densities[j] * self.scattering_per_m[j * n + hero];
            if share > 0.0 {
                running += share;
                chosen = Some(j);
                if threshold < running {
                    break;
                }
            }
        }
        let chosen = chosen?;
        // In the planet's shadow a share of the directions is drawn toward
        // the sunlit air instead (step 4); the choice uses one more random
        // number only there, so lit paths keep their random numbers.
        let share = toward_sunlit_air.map_or(0.0, |_| self.sunlit_direction_share);
        let next = match toward_sunlit_air {
            Some(q) if random.next_f64() < share => {
                q.sample([random.next_f64(), random.next_f64()])
            }
            _ => {
                let sample = self.optics.species[chosen]
                    .phase_function
                    .sample(hero, [random.next_f64(), random.next_f64()]);
                direction_about(direction, sample.cos_theta, sample.phi)
            }
        };
        let cos_theta = direction.dot(next).clamp(-1.0, 1.0);
        // The mixture density of `next` over wavelengths and species, and
        // the phase term of every wavelength there.
        scratch.phase_term.fill(0.0);
        let mut density_sum = 0.0;
        for (j, species) in self.optics.species.iter().enumerate() {
            let density = scratch.densities[j];
            if !(density > 0.0 && self.scatters[j]) {
                continue;
            }
            let phase = &species.phase_function;
            phase.eval_into(cos_theta, &mut scratch.phase_values);
            for i in 0..n {
                let coefficient = density * self.scattering_per_m[j * n + i];
                let value = scratch.phase_values[i];
                scratch.phase_term[i] += coefficient * value;
                let sigma = scratch.scattering_coefficient[i];
                if sigma > 0.0 && coefficient > 0.0 {
                    density_sum +=
                        coefficient / sigma * sampling_density(phase, i, cos_theta, value);
                }
            }
        }
        let mut density = density_sum / members as f64;
        if let Some(q) = toward_sunlit_air {
            density = (1.0 - share) * density + share * q.pdf(next);
        }
        if density.is_nan() || density <= 0.0 {
            return None;
        }
        for (b, term) in scratch.throughput.iter_mut().zip(&scratch.phase_term) {
            *b *= term / density;
        }
        if self.polarised {
            self.scatter_stokes(direction, next, cos_theta, scratch);
        }
        Some(next)
    }
}

/// The density (sr^-1) with which [`PhaseFunction::sample`] draws a
/// direction at `cos_theta` at wavelength `i`, given the function's value
/// there (equal to it for every exactly sampled function). The match is
/// exhaustive on purpose: a new kind of phase function must say how it is
/// sampled.
pub(super) fn sampling_density(phase: &PhaseFunction, i: usize, cos_theta: f64, value: f64) -> f64 {
    match phase {
        PhaseFunction::Isotropic
        | PhaseFunction::Rayleigh { .. }
        | PhaseFunction::HenyeyGreenstein { .. }
        | PhaseFunction::Tabulated(_) => value,
        PhaseFunction::CornetteShanks { g } => henyey_greenstein_phase(g[i], cos_theta),
    }
}
