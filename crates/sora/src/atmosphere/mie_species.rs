//! Aerosol from Mie theory: the paper's central idea (§2-3). Particles of a
//! given material (complex refractive index m(lambda), constant or
//! tabulated) and size distribution (log-normal, optionally truncated to
//! a radius window as in the paper's Tables 1-2, or gamma) have, per
//! particle, ensemble-averaged cross-sections <C_ext>(lambda),
//! <C_sca>(lambda) and a phase function, computed by the `sora-mie`
//! engine (eq. 2 with its misprint corrected, integrated over the
//! distribution instead of the paper's random radius draw). Then
//!
//! ```text
//!     beta_ext(lambda) = N_ref <C_ext>(lambda),   beta_sca = N_ref <C_sca>      [m^-1]
//! ```
//!
//! at relative density 1, with N_ref either given (`number_density_m3`,
//! particles per m^3 of the population the distribution describes: for a
//! truncated distribution, the particles inside the window, as the paper's
//! tables count them) or set by a column optical depth tau at a reference
//! wavelength: N_ref = tau / (<C_ext>(lambda_ref) column_m), the way
//! aerosol amounts are measured (sun photometers) and the way the Earth
//! presets are set.
//!
//! Phase function, two modes (see `sora_mie::paper_phase`):
//! - `"mie"`: the exact phase function of the distribution (scattering-
//!   weighted mean of the single-sphere functions), tabulated per
//!   wavelength on a grid of scattering angles dense in the forward peak;
//! - `"paper-hg"`: the paper's eq. 3, Henyey-Greenstein with its g(radius)
//!   rule averaged over the distribution.

use super::phase::PhaseFunction;
use crate::error::{Error, Result};
use crate::mie::distribution::SizeDistribution;
use crate::mie::paper_phase::AerosolPhaseMode;
use crate::mie::refractive_index::RefractiveIndexModel;
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// How much aerosol there is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParticleAmount {
    /// Particles per m^3 at relative density 1.
    NumberDensityM3(f64),
    /// Vertical column extinction optical depth at a reference wavelength.
    OpticalDepth {
        optical_depth: f64,
        reference_wavelength_nm: f64,
    },
}

/// A Mie aerosol, validated by the file loader.
#[derive(Debug, Clone, PartialEq)]
pub struct MieAerosol {
    pub refractive_index: RefractiveIndexModel,
    pub size_distribution: SizeDistribution,
    pub phase_mode: AerosolPhaseMode,
    pub amount: ParticleAmount,
}

/// The optics of a Mie aerosol on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct MieOptics {
    pub extinction_per_m: SampledSpectrum,
    pub scattering_per_m: SampledSpectrum,
    pub phase_function: PhaseFunction,
    pub reference_number_density_m3: f64,
}

impl MieAerosol {
    /// Ensemble cross-sections on `grid` and the phase function, scaled to
    /// the amount (the expensive step: one Mie ensemble per wavelength).
    /// `name` prefixes errors (`species[1]`).
    pub fn compute_optics(
        &self,
        grid: &WavelengthGrid,
        column_m: f64,
        name: &str,
    ) -> Result<MieOptics> {
        let _ = (grid, column_m);
        Err(Error::parse(
            "atmosphere",
            0,
            format!(
                "{name}: Mie aerosol optics are not yet available (the sora-mie ensemble is still being written); use scattering.parametric meanwhile"
            ),
        ))
    }
}
