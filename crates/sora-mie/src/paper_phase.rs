//! # The paper's aerosol phase mode: Henyey-Greenstein with g growing with radius
//!
//! Nakai & Sakai do not use the Mie phase function of their particles. They
//! use the Henyey-Greenstein (1941) function, their eq. 3,
//!
//! ```text
//!     P_HG(theta) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2))      [sr^-1]
//! ```
//!
//! normalised to 1 over the 4 pi sr of the sphere, with an asymmetry parameter
//! `g` that depends on the particle radius only: `g = 0.5` at `r = 0.01 um`,
//! `g = 0.9` at `r = 5.0 um`, linear in `r` in between (the paper draws one
//! radius per sample and uses its `g`). Outside that range the project clamps
//! `g` to the end values: the paper is silent there, and clamping keeps
//! `|g| < 1`, where eq. 3 is a valid probability density.
//!
//! For a size distribution the project replaces the paper's random radius by
//! the expectation it samples: the light scattered by the ensemble is the sum
//! of what each particle scatters, so each particle's phase function enters
//! weighted by its scattering cross-section. The ensemble of HG functions is
//! not itself an HG function; the paper's mode keeps the HG shape and gives it
//! the scattering-weighted mean asymmetry parameter
//!
//! ```text
//!     g_HG = integral g_paper(r) C_sca(r) dN / integral C_sca(r) dN,
//! ```
//!
//! which is the mean cosine of the true mixture (the mean cosine is linear in
//! the mixture). The integral is done in [`crate::ensemble`] with the same
//! radius quadrature as the cross-sections.
//!
//! This module also holds [`AerosolPhaseMode`], the switch between this mode
//! and the exact Mie phase function of the distribution (the accurate mode,
//! and the default).

use std::f64::consts::PI;

/// Radius at which the paper's asymmetry parameter is 0.5 (metres; 0.01 um).
pub const PAPER_SMALL_PARTICLE_RADIUS_M: f64 = 0.01e-6;
/// The paper's asymmetry parameter for particles of radius
/// [`PAPER_SMALL_PARTICLE_RADIUS_M`] and smaller (dimensionless).
pub const PAPER_SMALL_PARTICLE_ASYMMETRY_PARAMETER: f64 = 0.5;
/// Radius at which the paper's asymmetry parameter is 0.9 (metres; 5.0 um).
pub const PAPER_LARGE_PARTICLE_RADIUS_M: f64 = 5.0e-6;
/// The paper's asymmetry parameter for particles of radius
/// [`PAPER_LARGE_PARTICLE_RADIUS_M`] and larger (dimensionless).
pub const PAPER_LARGE_PARTICLE_ASYMMETRY_PARAMETER: f64 = 0.9;

/// Which aerosol phase function the ensemble optics carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AerosolPhaseMode {
    /// The exact phase function of the size distribution: the
    /// scattering-weighted mean of the single-sphere Mie phase functions,
    /// tabulated (see [`crate::ensemble`]). The accurate mode.
    #[default]
    Mie,
    /// The paper's eq. 3: Henyey-Greenstein with the paper's `g(r)` averaged
    /// over the distribution, weighted by the scattering cross-section.
    PaperHenyeyGreenstein,
}

/// The paper's asymmetry parameter of one particle of radius `radius_m`
/// (metres): 0.5 at 0.01 um rising linearly in radius to 0.9 at 5.0 um,
/// clamped outside that range. Dimensionless. A NaN radius gives NaN.
pub fn paper_asymmetry_parameter_for_radius(radius_m: f64) -> f64 {
    let fraction_of_the_way = (radius_m - PAPER_SMALL_PARTICLE_RADIUS_M)
        / (PAPER_LARGE_PARTICLE_RADIUS_M - PAPER_SMALL_PARTICLE_RADIUS_M);
    let clamped_fraction = fraction_of_the_way.clamp(0.0, 1.0);
    PAPER_SMALL_PARTICLE_ASYMMETRY_PARAMETER
        + clamped_fraction
            * (PAPER_LARGE_PARTICLE_ASYMMETRY_PARAMETER - PAPER_SMALL_PARTICLE_ASYMMETRY_PARAMETER)
}

/// Henyey-Greenstein phase function (paper eq. 3) with asymmetry parameter
/// `asymmetry_parameter` at scattering angle theta, `cos_theta = cos(theta)`;
/// normalised to 1 over 4 pi sr, unit sr^-1. Valid for |g| < 1.
pub fn henyey_greenstein_phase_function_per_sr(asymmetry_parameter: f64, cos_theta: f64) -> f64 {
    let g = asymmetry_parameter;
    let denominator_base = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denominator_base * denominator_base.sqrt())
}

/// The cosine of the scattering angle of a Henyey-Greenstein function with
/// asymmetry parameter `asymmetry_parameter` (|g| < 1) for a uniform random
/// number `uniform_sample` in [0, 1] (clamped): the closed-form inverse of
/// the cumulative distribution F(mu) = 2 pi integral_{-1}^{mu} P dmu', so 0
/// maps to backscattering (mu = -1) and 1 to the forward direction (mu = 1).
pub fn sample_henyey_greenstein_cos_theta(asymmetry_parameter: f64, uniform_sample: f64) -> f64 {
    let g = asymmetry_parameter;
    let u = uniform_sample.clamp(0.0, 1.0);
    // The closed-form inverse divides by g: below 1e-8 its round-off
    // (~1e-16 / g) would exceed the error of using the isotropic inverse (~g).
    if g.abs() < 1e-8 {
        return 2.0 * u - 1.0;
    }
    let ratio = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
    ((1.0 + g * g - ratio * ratio) / (2.0 * g)).clamp(-1.0, 1.0)
}

/// The asymmetry parameter given to a Henyey-Greenstein function was not in
/// the open interval (-1, 1), where eq. 3 is a probability density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvalidAsymmetryParameter(pub f64);

impl std::fmt::Display for InvalidAsymmetryParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "asymmetry parameter g = {} is invalid for a Henyey-Greenstein phase function: it must be finite with |g| < 1",
            self.0
        )
    }
}

impl std::error::Error for InvalidAsymmetryParameter {}

/// A Henyey-Greenstein phase function as a distribution of scattering
/// directions: evaluation, probability density and sampling agree exactly
/// (density with respect to solid angle, sr^-1; azimuth is uniform and left
/// to the caller).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HenyeyGreensteinPhaseFunction {
    asymmetry_parameter: f64,
}

impl HenyeyGreensteinPhaseFunction {
    /// A Henyey-Greenstein function with mean cosine `asymmetry_parameter`
    /// (|g| < 1, finite).
    pub fn new(asymmetry_parameter: f64) -> Result<Self, InvalidAsymmetryParameter> {
        if asymmetry_parameter.is_finite() && asymmetry_parameter.abs() < 1.0 {
            Ok(Self {
                asymmetry_parameter,
            })
        } else {
            Err(InvalidAsymmetryParameter(asymmetry_parameter))
        }
    }

    /// The asymmetry parameter g = `<cos theta>` (dimensionless).
    pub fn asymmetry_parameter(&self) -> f64 {
        self.asymmetry_parameter
    }

    /// Phase function at `cos_theta` (sr^-1, normalised to 1 over 4 pi sr).
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        henyey_greenstein_phase_function_per_sr(self.asymmetry_parameter, cos_theta)
    }

    /// Probability density of scattering into a direction at `cos_theta`, per
    /// steradian: identical to [`Self::phase_function_per_sr`].
    pub fn pdf_per_sr(&self, cos_theta: f64) -> f64 {
        self.phase_function_per_sr(cos_theta)
    }

    /// The cosine of the scattering angle for a uniform random number
    /// `uniform_sample` in [0, 1]: the inverse of the cumulative distribution
    /// F(mu) = 2 pi integral_{-1}^{mu} P dmu', so 0 maps to backscattering
    /// (mu = -1) and 1 to the forward direction (mu = 1).
    pub fn sample_cos_theta(&self, uniform_sample: f64) -> f64 {
        sample_henyey_greenstein_cos_theta(self.asymmetry_parameter, uniform_sample)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2 pi integral_{-1}^{1} f(mu) dmu by composite Simpson on `intervals` intervals.
    fn integrate_over_sphere(f: impl Fn(f64) -> f64, intervals: usize) -> f64 {
        let h = 2.0 / intervals as f64;
        let mut sum = f(-1.0) + f(1.0);
        for i in 1..intervals {
            let mu = -1.0 + i as f64 * h;
            sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(mu);
        }
        2.0 * PI * sum * h / 3.0
    }

    #[test]
    fn paper_g_is_linear_in_radius_and_clamped() {
        assert_eq!(paper_asymmetry_parameter_for_radius(0.01e-6), 0.5);
        assert!((paper_asymmetry_parameter_for_radius(5.0e-6) - 0.9).abs() < 1e-15);
        assert_eq!(paper_asymmetry_parameter_for_radius(1e-9), 0.5);
        assert_eq!(paper_asymmetry_parameter_for_radius(20e-6), 0.9);
        // Half-way in radius is half-way in g.
        let midpoint_m = 0.5 * (0.01e-6 + 5.0e-6);
        assert!((paper_asymmetry_parameter_for_radius(midpoint_m) - 0.7).abs() < 1e-14);
        // 1 um: 0.5 + 0.4 * 0.99 / 4.99.
        let expected = 0.5 + 0.4 * (0.99 / 4.99);
        assert!((paper_asymmetry_parameter_for_radius(1e-6) - expected).abs() < 1e-14);
    }

    #[test]
    fn henyey_greenstein_is_normalised_and_has_mean_cosine_g() {
        for g in [-0.6, 0.0, 0.3, 0.7, 0.9] {
            let hg = HenyeyGreensteinPhaseFunction::new(g).unwrap();
            let norm = integrate_over_sphere(|mu| hg.phase_function_per_sr(mu), 200_000);
            let mean_cosine =
                integrate_over_sphere(|mu| mu * hg.phase_function_per_sr(mu), 200_000);
            assert!((norm - 1.0).abs() < 1e-9, "g = {g}: norm {norm}");
            assert!(
                (mean_cosine - g).abs() < 1e-9,
                "g = {g}: <mu> {mean_cosine}"
            );
        }
    }

    #[test]
    fn henyey_greenstein_isotropic_limit_is_one_over_four_pi() {
        let value = henyey_greenstein_phase_function_per_sr(0.0, 0.3);
        assert!((value - 1.0 / (4.0 * PI)).abs() < 1e-16);
    }

    #[test]
    fn sampling_inverts_the_cumulative_distribution() {
        for g in [-0.5, 1e-10, 0.2, 0.85] {
            let hg = HenyeyGreensteinPhaseFunction::new(g).unwrap();
            for u in [0.0, 0.1, 0.37, 0.5, 0.93, 1.0] {
                let mu = hg.sample_cos_theta(u);
                // F(mu) = 2 pi integral_{-1}^{mu} P by Simpson on [-1, mu].
                let intervals = 20_000;
                let h = (mu + 1.0) / intervals as f64;
                let mut sum = hg.pdf_per_sr(-1.0) + hg.pdf_per_sr(mu);
                for i in 1..intervals {
                    let w = if i % 2 == 1 { 4.0 } else { 2.0 };
                    sum += w * hg.pdf_per_sr(-1.0 + i as f64 * h);
                }
                let cumulative = 2.0 * PI * sum * h / 3.0;
                assert!(
                    (cumulative - u).abs() < 1e-9,
                    "g {g} u {u}: F = {cumulative}"
                );
            }
        }
    }

    #[test]
    fn invalid_asymmetry_parameters_are_rejected() {
        assert!(HenyeyGreensteinPhaseFunction::new(1.0).is_err());
        assert!(HenyeyGreensteinPhaseFunction::new(-1.2).is_err());
        assert!(HenyeyGreensteinPhaseFunction::new(f64::NAN).is_err());
        let message = HenyeyGreensteinPhaseFunction::new(1.0)
            .unwrap_err()
            .to_string();
        assert!(message.contains("|g| < 1"), "{message}");
    }
}
