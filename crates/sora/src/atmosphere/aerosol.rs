//! The parametric aerosol: optics given directly, as radiative-transfer
//! studies and aerosol climatologies publish them, rather than derived from
//! particles (for that, see [`super::mie_species`]).
//!
//! Parameters:
//! - the column (extinction) optical depth tau_ref at a reference
//!   wavelength lambda_ref;
//! - the Angstrom exponent alpha: tau(lambda) = tau_ref (lambda /
//!   lambda_ref)^-alpha (Angstrom 1929; ~1-2 for fine continental and urban
//!   aerosol, ~0 for coarse dust and sea salt);
//! - the single-scattering albedo omega (scattering / extinction), constant
//!   over wavelength;
//! - the phase function: Henyey-Greenstein (the paper's eq. 3) or
//!   Cornette-Shanks, with a constant g.
//!
//! With the species' profile of vertical column `column_m` (see
//! [`super::profile`]), the coefficients at the reference density are
//!
//! ```text
//!     beta_ext(lambda) = tau_ref / column_m * (lambda / lambda_ref)^-alpha      [m^-1]
//!     beta_sca(lambda) = omega * beta_ext(lambda)
//! ```
//!
//! so that beta_ext(h, lambda) = relative_density(h) beta_ext(lambda)
//! integrates over the column to tau(lambda) exactly. The clear-sky
//! reference atmosphere is of this form (tau 0.1 at 550 nm, alpha 1.3,
//! omega 0.9, HG g = 0.7, scale height 1200 m: beta_ext = 8.333e-5 m^-1 at
//! sea level).

use super::phase::{PhaseFunction, TabulatedPhase};
use crate::mie::ensemble::{PhaseMatrixRatios, TabulatedPhaseFunction};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// The shape of a parametric aerosol's phase function.
#[derive(Debug, Clone, PartialEq)]
pub enum AerosolPhase {
    /// Henyey-Greenstein with asymmetry parameter g, |g| < 1.
    HenyeyGreenstein {
        /// The asymmetry parameter (mean scattering cosine).
        g: f64,
    },
    /// Cornette-Shanks with parameter g, |g| < 1 (its mean cosine differs).
    CornetteShanks {
        /// The Cornette-Shanks parameter g.
        g: f64,
    },
    /// A measured or computed phase function given as a table (the same at
    /// every wavelength): linear in cos theta between its angles, rescaled
    /// to integrate to 1 over the sphere, with its phase matrix as the
    /// ratios F12/F11, F33/F11, F34/F11 on the same nodes (a sphere's
    /// matrix: F22 = F11, F44 = F33); the ratios 0, 1, 0 of a
    /// non-polarising scatterer when none were given.
    Tabulated {
        /// The phase function.
        table: TabulatedPhaseFunction,
        /// Its phase matrix, on the table's nodes.
        ratios: PhaseMatrixRatios,
    },
}

impl AerosolPhase {
    /// The phase function on a grid of `len` wavelengths (the same at
    /// every one).
    pub(crate) fn on_grid(&self, len: usize) -> PhaseFunction {
        match self {
            AerosolPhase::HenyeyGreenstein { g } => PhaseFunction::HenyeyGreenstein {
                asymmetry_g: vec![*g; len],
            },
            AerosolPhase::CornetteShanks { g } => {
                PhaseFunction::CornetteShanks { g: vec![*g; len] }
            }
            AerosolPhase::Tabulated { table, ratios } => {
                let mut phase = TabulatedPhase::from_tables(vec![table.clone(); len])
                    .expect("one valid table per wavelength");
                let kept = phase.set_matrix_ratios(vec![ratios.clone(); len]);
                debug_assert!(kept, "the ratios are on the table's nodes");
                PhaseFunction::Tabulated(phase)
            }
        }
    }
}

/// An aerosol described by its column optical depth, Angstrom exponent,
/// single-scattering albedo and phase function (validated by the file
/// loader: tau >= 0, lambda_ref > 0, 0 <= omega <= 1, |g| < 1).
#[derive(Debug, Clone, PartialEq)]
pub struct ParametricAerosol {
    /// Column extinction optical depth at `reference_wavelength_nm`.
    pub optical_depth: f64,
    /// The wavelength of `optical_depth`, nm.
    pub reference_wavelength_nm: f64,
    /// tau(lambda) = tau_ref (lambda / lambda_ref)^-angstrom_exponent.
    pub angstrom_exponent: f64,
    /// Scattering over extinction, the same at every wavelength.
    pub single_scattering_albedo: f64,
    /// The phase function's shape.
    pub phase: AerosolPhase,
}

impl ParametricAerosol {
    /// Extinction coefficient at the reference density, m^-1, for a profile
    /// of vertical column `column_m` (> 0).
    pub(crate) fn extinction_per_m(&self, wavelength_nm: f64, column_m: f64) -> f64 {
        self.optical_depth / column_m
            * (wavelength_nm / self.reference_wavelength_nm).powf(-self.angstrom_exponent)
    }

    /// (extinction, scattering) coefficients at the reference density on
    /// `grid`, m^-1, and the phase function.
    pub(crate) fn compute_optics(
        &self,
        grid: &WavelengthGrid,
        column_m: f64,
    ) -> (SampledSpectrum, SampledSpectrum, PhaseFunction) {
        let extinction: Vec<f64> = grid
            .wavelengths_nm()
            .map(|w| self.extinction_per_m(w, column_m))
            .collect();
        let scattering = extinction
            .iter()
            .map(|e| e * self.single_scattering_albedo)
            .collect();
        (
            SampledSpectrum::from_values(extinction),
            SampledSpectrum::from_values(scattering),
            self.phase.on_grid(grid.len()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_optical_depth_follows_angstrom_law() {
        let aerosol = ParametricAerosol {
            optical_depth: 0.1,
            reference_wavelength_nm: 550.0,
            angstrom_exponent: 1.3,
            single_scattering_albedo: 0.9,
            phase: AerosolPhase::HenyeyGreenstein { g: 0.7 },
        };
        let grid = WavelengthGrid::paper();
        let (ext, sca, phase) = aerosol.compute_optics(&grid, 1200.0);
        // At 550 nm (not on the grid) the coefficient is tau / column.
        assert!((aerosol.extinction_per_m(550.0, 1200.0) * 1200.0 - 0.1).abs() < 1e-15);
        // Angstrom exponent recovered from two wavelengths.
        let alpha = -(ext[20] / ext[0]).ln() / (780.0f64 / 380.0).ln();
        assert!((alpha - 1.3).abs() < 1e-12);
        assert!((sca[5] / ext[5] - 0.9).abs() < 1e-15);
        assert_eq!(phase.asymmetry_g(3), 0.7);
    }
}
