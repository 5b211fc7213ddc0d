//! # Particle size distributions
//!
//! An aerosol is not one sphere but a population with a spread of radii. Its
//! optics per particle are averages over the number distribution of radius,
//! `<C> = integral C(r) dN / integral dN` (see [`crate::ensemble`]). The paper
//! (Nakai & Sakai §2) uses a log-normal distribution truncated to a radius
//! window; this module provides that, the gamma distribution common in the
//! remote-sensing literature, and a volume distribution dV/d ln r tabulated
//! as sun-photometer inversions publish it ([`tabulated`]), all with the
//! Hansen & Travis (1974, §2.3)
//! effective radius and variance, and the quadrature over radius
//! ([`RadiusQuadrature`]) that replaces the paper's random radius draw by the
//! integral it estimates (same expectation, no noise).
//!
//! Units: radii in metres in every `_m` name (micrometres only where a name
//! says `_um`); densities are per unit `ln r` and per particle (dimensionless).
//!
//! ## Log-normal in radius
//!
//! ```text
//!     dN/d ln r = N / (sqrt(2 pi) ln sigma_g) exp(-(ln r - ln r_m)^2 / (2 ln^2 sigma_g))
//! ```
//!
//! with number median radius `r_m` and geometric standard deviation
//! `sigma_g > 1`; `s = ln sigma_g` is the standard deviation of `ln r`. Its
//! moments are `<r^p> = r_m^p exp(p^2 s^2 / 2)`, so the Hansen & Travis
//! effective radius and variance,
//!
//! ```text
//!     r_eff = <r^3> / <r^2>,     v_eff = <(r - r_eff)^2 r^2> / (r_eff^2 <r^2>)
//! ```
//!
//! are `r_eff = r_m exp(5 s^2 / 2)` and `v_eff = exp(s^2) - 1`; conversely
//! `s^2 = ln(1 + v_eff)` and `r_m = r_eff exp(-5 s^2 / 2)` (any `v_eff > 0`).
//! The number fraction in `[r_1, r_2]` is `Phi(z_2) - Phi(z_1)`,
//! `z = (ln r - ln r_m) / s`, with `Phi` the standard normal distribution
//! function, computed from erfc in the tail nearest to the window.
//!
//! ## Gamma ("modified gamma") distribution
//!
//! [`ModifiedGammaDistribution`] is the Hansen & Travis (1974, eq. 2.56)
//! "standard gamma distribution"
//!
//! ```text
//!     n(r) = dN/dr = C r^((1 - 3b)/b) exp(-r / (a b)),      0 < b < 1/2,
//! ```
//!
//! whose effective radius and variance are exactly `a` and `b`. It is
//! Deirmendjian's (1969) modified gamma `r^alpha exp(-B r^gamma)` with
//! `gamma = 1`, `alpha = (1 - 3b)/b`, `B = 1/(a b)`; in statistical terms a
//! gamma distribution of `r` with shape `k = (1 - 2b)/b` and scale
//! `theta = a b`, so `C = 1 / (Gamma(k) theta^k)` and the number fraction below
//! `r` is the regularised incomplete gamma function `P(k, r/theta)`.
//! `b >= 1/2` has no normalisable `n(r)` and is rejected.
//!
//! ## The narrowest populations
//!
//! A population narrower than [`MIN_GEOMETRIC_STANDARD_DEVIATION`] 1.0001
//! (log-normal; a spread of 1e-4 in `ln r`) or with an effective variance
//! below [`MIN_EFFECTIVE_VARIANCE`] 1e-8 (both shapes; the gamma's spread
//! `1/sqrt(k + 2)` is then 1e-4) is refused. Nothing physical is lost:
//! aerosols are never that narrow (laboratory latex spheres have
//! `sigma_g ~ 1.01-1.05`). Numerically the limit matters: the radius
//! quadrature's panels are a fixed number of spreads wide, so a vanishing
//! spread makes them narrower than the spacing of doubles in `ln r` (the
//! rule stops advancing and allocates without end, as `v_eff = 1e-30` did),
//! and the gamma density `k ln u - u - ln Gamma(k)` would lose
//! `~ k ln k 1e-16` of its logarithm to cancellation unless written with
//! Stirling's series, as it is here (below, `number_density_per_ln_radius`). At the
//! limit a population is a single sphere to ~1e-7 in its cross-sections
//! (second order in the spread).
//!
//! ## Truncation
//!
//! The paper keeps only radii in a window (Table 1: 0.1-2.5 um; Table 2:
//! 0.45-0.56 um). A truncated distribution here is the population of the
//! particles inside the window: its per-particle quantities divide by the
//! number inside, `dN/d ln r / N_window`, and
//! [`SizeDistribution::number_fraction_in_window`] reports `N_window / N`
//! (closed form, erf or incomplete gamma), so a caller who knows the total
//! number density of the untruncated population can convert.
//!
//! ## Where the quadrature goes
//!
//! Cross-sections weight the number distribution by about `r^2` (area) for
//! particles larger than the wavelength, and by `r^3` (absorption) to `r^6`
//! (scattering) below it, so the radii that matter lie around the peak of the
//! importance density `r^2 min(1, x/4) dN/d ln r` (see [`quadrature`]); for
//! large particles, a log-normal's is a Gaussian in `ln r` of the same `s`,
//! centred on the area-weighted median `r_m exp(2 s^2)`. The integration range
//! is where the importance density is within `exp(-tail_depth)` of its peak
//! (clipped to the window; the peak of a truncated population is the clipped
//! peak): [`RadiusQuadratureSettings::tail_depth`] 18 keeps +-6 `s` for the
//! log-normal and drops about 1e-9 of the area. The quadrature itself is
//! described in [`quadrature`].

pub mod quadrature;
mod special_functions;
pub mod tabulated;

pub use tabulated::{
    MAX_TABULATED_POINTS, TabulatedDistributionError, TabulatedVolumeDistribution,
};

pub use quadrature::{
    MAX_RADIUS_QUADRATURE_NODES, MAX_SHARED_QUADRATURE_WEIGHTS, RadiusQuadrature,
    RadiusQuadratureSettings, SharedSizeParameterQuadrature,
};

use special_functions::{
    ln_gamma, regularized_incomplete_gamma, standard_normal_probability_between,
};
use std::f64::consts::PI;

/// Size parameter above which the importance model of the quadrature takes
/// Mie efficiencies as roughly constant (the geometric regime): near the
/// first extinction maximum, 2 x (n - 1) ~ 4 for n ~ 1.5, where Q_sca ~ 3-4
/// after rising from the Rayleigh regime. Below it the model falls like x
/// (absorption's law there, the slowest of the efficiencies).
const GEOMETRIC_REGIME_SIZE_PARAMETER: f64 = 4.0;

/// Smallest geometric standard deviation of a log-normal (see the module
/// docs, "The narrowest populations"): a spread of ln 1.0001 ~ 1e-4 in ln r.
pub const MIN_GEOMETRIC_STANDARD_DEVIATION: f64 = 1.0001;

/// Smallest effective variance of either shape (see the module docs): a
/// spread of about 1e-4 in ln r.
pub const MIN_EFFECTIVE_VARIANCE: f64 = 1e-8;

/// Why a size distribution could not be built.
#[derive(Debug, Clone, PartialEq)]
pub enum SizeDistributionError {
    /// A radius that must be finite and > 0 is not.
    InvalidRadius {
        quantity: &'static str,
        radius_m: f64,
    },
    /// The geometric standard deviation must be finite and at least
    /// [`MIN_GEOMETRIC_STANDARD_DEVIATION`].
    InvalidGeometricStandardDeviation { geometric_standard_deviation: f64 },
    /// The effective variance must be finite, at least
    /// [`MIN_EFFECTIVE_VARIANCE`] and below the distribution's upper limit
    /// (infinite for the log-normal, 1/2 for the gamma).
    InvalidEffectiveVariance {
        effective_variance: f64,
        upper_limit_exclusive: f64,
    },
    /// A radius window must satisfy 0 < min < max, both finite.
    InvalidRadiusWindow {
        min_radius_m: f64,
        max_radius_m: f64,
    },
    /// The window holds no particles to double precision (number fraction
    /// underflows to 0), so per-particle quantities are undefined.
    NoParticlesInWindow {
        min_radius_m: f64,
        max_radius_m: f64,
    },
    /// The quadrature settings are not usable.
    InvalidQuadratureSettings { message: String },
    /// The radius quadrature would need more than
    /// [`quadrature::MAX_RADIUS_QUADRATURE_NODES`] nodes, or more than
    /// [`quadrature::MAX_SHARED_QUADRATURE_WEIGHTS`] weights over its
    /// wavelengths (refused before allocating; `node_count` is where the
    /// count stopped).
    TooManyQuadratureNodes {
        node_count: usize,
        wavelength_count: usize,
        max_nodes: usize,
        max_weights: usize,
    },
}

impl std::fmt::Display for SizeDistributionError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SizeDistributionError::InvalidRadius { quantity, radius_m } => write!(
                f,
                "{quantity} = {} m is invalid: it must be finite and greater than 0",
                Number(*radius_m)
            ),
            SizeDistributionError::InvalidGeometricStandardDeviation {
                geometric_standard_deviation,
            } => write!(
                f,
                "geometric standard deviation sigma_g = {} is invalid: it must be finite and at least {MIN_GEOMETRIC_STANDARD_DEVIATION} (narrower populations are not resolved)",
                Number(*geometric_standard_deviation)
            ),
            SizeDistributionError::InvalidEffectiveVariance {
                effective_variance,
                upper_limit_exclusive,
            } => write!(
                f,
                "effective variance v_eff = {} is invalid: it must be finite, at least {MIN_EFFECTIVE_VARIANCE:e} (narrower populations are not resolved) and less than {upper_limit_exclusive}",
                Number(*effective_variance)
            ),
            SizeDistributionError::InvalidRadiusWindow {
                min_radius_m,
                max_radius_m,
            } => write!(
                f,
                "radius window [{} m, {} m] is invalid: it needs 0 < min < max, both finite",
                Number(*min_radius_m),
                Number(*max_radius_m)
            ),
            SizeDistributionError::NoParticlesInWindow {
                min_radius_m,
                max_radius_m,
            } => write!(
                f,
                "radius window [{} m, {} m] holds no particles of the distribution (number fraction underflows to 0)",
                Number(*min_radius_m),
                Number(*max_radius_m)
            ),
            SizeDistributionError::InvalidQuadratureSettings { message } => {
                write!(f, "invalid radius quadrature settings: {message}")
            }
            SizeDistributionError::TooManyQuadratureNodes {
                node_count,
                wavelength_count,
                max_nodes,
                max_weights,
            } => write!(
                f,
                "the radius quadrature needs at least {node_count} nodes at {wavelength_count} wavelength(s), more than its limits of {max_nodes} nodes and {max_weights} nodes x wavelengths: use fewer wavelengths or a wider size distribution"
            ),
        }
    }
}

impl std::error::Error for SizeDistributionError {}

/// A number in a message, in the fewest digits that read back as it: plain
/// between 1e-4 and 1e6, in exponent form outside (`1e-30`, not 31 digits).
struct Number(f64);

impl std::fmt::Display for Number {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let magnitude = self.0.abs();
        if self.0.is_finite() && magnitude != 0.0 && !(1e-4..1e6).contains(&magnitude) {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

fn validate_radius(quantity: &'static str, radius_m: f64) -> Result<(), SizeDistributionError> {
    if radius_m.is_finite() && radius_m > 0.0 {
        Ok(())
    } else {
        Err(SizeDistributionError::InvalidRadius { quantity, radius_m })
    }
}

/// Log-normal distribution of radius (see the module docs), untruncated,
/// normalised to one particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogNormalDistribution {
    number_median_radius_m: f64,
    geometric_standard_deviation: f64,
}

impl LogNormalDistribution {
    /// From the number median radius `r_m` (m, > 0) and the geometric
    /// standard deviation `sigma_g` (>= [`MIN_GEOMETRIC_STANDARD_DEVIATION`],
    /// dimensionless).
    pub fn new(
        number_median_radius_m: f64,
        geometric_standard_deviation: f64,
    ) -> Result<Self, SizeDistributionError> {
        validate_radius("number median radius", number_median_radius_m)?;
        if !(geometric_standard_deviation.is_finite()
            && geometric_standard_deviation >= MIN_GEOMETRIC_STANDARD_DEVIATION)
        {
            return Err(SizeDistributionError::InvalidGeometricStandardDeviation {
                geometric_standard_deviation,
            });
        }
        Ok(Self {
            number_median_radius_m,
            geometric_standard_deviation,
        })
    }

    /// From the Hansen & Travis effective radius (m, > 0) and effective
    /// variance (>= [`MIN_EFFECTIVE_VARIANCE`], dimensionless): `s^2 = ln(1 + v_eff)`,
    /// `r_m = r_eff exp(-5 s^2 / 2)`.
    pub fn from_effective_radius_and_variance(
        effective_radius_m: f64,
        effective_variance: f64,
    ) -> Result<Self, SizeDistributionError> {
        validate_radius("effective radius", effective_radius_m)?;
        if !(effective_variance.is_finite() && effective_variance >= MIN_EFFECTIVE_VARIANCE) {
            return Err(SizeDistributionError::InvalidEffectiveVariance {
                effective_variance,
                upper_limit_exclusive: f64::INFINITY,
            });
        }
        let ln_sigma_squared = effective_variance.ln_1p();
        // v_eff = 1e-8 gives sigma_g = 1.000100005, above the log-normal's own
        // minimum, so this cannot fail on the width.
        Self::new(
            effective_radius_m * (-2.5 * ln_sigma_squared).exp(),
            ln_sigma_squared.sqrt().exp(),
        )
    }

    /// Number median radius r_m (m).
    pub fn number_median_radius_m(&self) -> f64 {
        self.number_median_radius_m
    }

    /// Geometric standard deviation sigma_g (dimensionless, > 1).
    pub fn geometric_standard_deviation(&self) -> f64 {
        self.geometric_standard_deviation
    }

    /// s = ln sigma_g, the standard deviation of ln r.
    pub fn ln_geometric_standard_deviation(&self) -> f64 {
        self.geometric_standard_deviation.ln()
    }

    /// Effective radius r_eff = r_m exp(5 s^2 / 2) (m).
    pub fn effective_radius_m(&self) -> f64 {
        let s = self.ln_geometric_standard_deviation();
        self.number_median_radius_m * (2.5 * s * s).exp()
    }

    /// Effective variance v_eff = exp(s^2) - 1 (dimensionless).
    pub fn effective_variance(&self) -> f64 {
        let s = self.ln_geometric_standard_deviation();
        (s * s).exp_m1()
    }

    /// Median of the area-weighted distribution r^2 dN/d ln r: r_m exp(2 s^2) (m).
    pub fn area_weighted_median_radius_m(&self) -> f64 {
        let s = self.ln_geometric_standard_deviation();
        self.number_median_radius_m * (2.0 * s * s).exp()
    }

    /// dN/d ln r per particle at `radius_m` (dimensionless).
    pub fn number_density_per_ln_radius(&self, radius_m: f64) -> f64 {
        let s = self.ln_geometric_standard_deviation();
        let z = (radius_m / self.number_median_radius_m).ln() / s;
        (-0.5 * z * z).exp() / ((2.0 * PI).sqrt() * s)
    }

    /// Fraction of the particles with radius in [min_radius_m, max_radius_m].
    pub fn number_fraction_between(&self, min_radius_m: f64, max_radius_m: f64) -> f64 {
        let s = self.ln_geometric_standard_deviation();
        let z = |r: f64| (r / self.number_median_radius_m).ln() / s;
        standard_normal_probability_between(z(min_radius_m), z(max_radius_m))
    }
}

/// Hansen & Travis (1974) standard gamma distribution of radius, i.e.
/// Deirmendjian's modified gamma with gamma = 1 (see the module docs),
/// untruncated, normalised to one particle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModifiedGammaDistribution {
    effective_radius_m: f64,
    effective_variance: f64,
}

impl ModifiedGammaDistribution {
    /// From the effective radius a (m, > 0) and effective variance b
    /// ([`MIN_EFFECTIVE_VARIANCE`] <= b < 1/2, dimensionless); these are exactly the distribution's
    /// r_eff and v_eff.
    pub fn new(
        effective_radius_m: f64,
        effective_variance: f64,
    ) -> Result<Self, SizeDistributionError> {
        validate_radius("effective radius", effective_radius_m)?;
        if !(MIN_EFFECTIVE_VARIANCE..0.5).contains(&effective_variance) {
            return Err(SizeDistributionError::InvalidEffectiveVariance {
                effective_variance,
                upper_limit_exclusive: 0.5,
            });
        }
        Ok(Self {
            effective_radius_m,
            effective_variance,
        })
    }

    /// Effective radius a = r_eff (m).
    pub fn effective_radius_m(&self) -> f64 {
        self.effective_radius_m
    }

    /// Effective variance b = v_eff (dimensionless).
    pub fn effective_variance(&self) -> f64 {
        self.effective_variance
    }

    /// Gamma shape of n(r): k = (1 - 2b)/b (the exponent of r is k - 1).
    pub fn gamma_shape(&self) -> f64 {
        (1.0 - 2.0 * self.effective_variance) / self.effective_variance
    }

    /// Gamma scale of n(r): theta = a b (m).
    pub fn gamma_scale_m(&self) -> f64 {
        self.effective_radius_m * self.effective_variance
    }

    /// dN/d ln r = r n(r) per particle at `radius_m` (dimensionless):
    /// `exp(k ln u - u - ln Gamma(k))`, `u = r / theta`. For a narrow
    /// distribution (large k) the three terms are ~k ln k and cancel to
    /// O(1), losing `k ln k` ulps; there (k >= 10) Stirling's series
    /// `ln Gamma(k) = (k - 1/2) ln k - k + ln(2 pi)/2 + R(k)` turns it into
    /// `k (ln(1 + w) - w) + ln(k / (2 pi))/2 - R(k)`, `w = u/k - 1`, whose
    /// terms are O(1) near the peak.
    pub fn number_density_per_ln_radius(&self, radius_m: f64) -> f64 {
        let k = self.gamma_shape();
        let u = radius_m / self.gamma_scale_m();
        if k < 10.0 {
            return (k * u.ln() - u - ln_gamma(k)).exp();
        }
        let w = (u - k) / k;
        let inverse_k_squared = 1.0 / (k * k);
        // R(k) to 4 terms: the next, 1/(1188 k^9), is below 1e-12 of R at k = 10.
        let stirling_remainder = (1.0 / 12.0
            - inverse_k_squared
                * (1.0 / 360.0 - inverse_k_squared * (1.0 / 1260.0 - inverse_k_squared / 1680.0)))
            / k;
        (k * (w.ln_1p() - w) + 0.5 * (k / (2.0 * PI)).ln() - stirling_remainder).exp()
    }

    /// Fraction of the particles with radius in [min_radius_m, max_radius_m].
    pub fn number_fraction_between(&self, min_radius_m: f64, max_radius_m: f64) -> f64 {
        let k = self.gamma_shape();
        let theta = self.gamma_scale_m();
        let (p_low, q_low) = regularized_incomplete_gamma(k, min_radius_m / theta);
        let (p_high, q_high) = regularized_incomplete_gamma(k, max_radius_m / theta);
        // Difference of whichever tail is smaller, so tail windows keep their digits.
        if min_radius_m / theta >= k {
            q_low - q_high
        } else if max_radius_m / theta <= k {
            p_high - p_low
        } else {
            1.0 - p_low - q_high
        }
    }
}

/// The untruncated shape of a size distribution.
#[derive(Debug, Clone, PartialEq)]
pub enum SizeDistributionShape {
    LogNormal(LogNormalDistribution),
    ModifiedGamma(ModifiedGammaDistribution),
    /// A measured volume distribution dV/d ln r at given radii (see [`tabulated`]).
    TabulatedVolume(TabulatedVolumeDistribution),
}

impl SizeDistributionShape {
    /// dN/d ln r per particle of the untruncated distribution.
    pub fn number_density_per_ln_radius(&self, radius_m: f64) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => d.number_density_per_ln_radius(radius_m),
            SizeDistributionShape::ModifiedGamma(d) => d.number_density_per_ln_radius(radius_m),
            SizeDistributionShape::TabulatedVolume(d) => d.number_density_per_ln_radius(radius_m),
        }
    }

    /// Fraction of the untruncated population in [min_radius_m, max_radius_m].
    pub fn number_fraction_between(&self, min_radius_m: f64, max_radius_m: f64) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => {
                d.number_fraction_between(min_radius_m, max_radius_m)
            }
            SizeDistributionShape::ModifiedGamma(d) => {
                d.number_fraction_between(min_radius_m, max_radius_m)
            }
            SizeDistributionShape::TabulatedVolume(d) => {
                d.number_fraction_between(min_radius_m, max_radius_m)
            }
        }
    }

    /// Effective radius of the untruncated distribution (m).
    pub fn effective_radius_m(&self) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => d.effective_radius_m(),
            SizeDistributionShape::ModifiedGamma(d) => d.effective_radius_m(),
            SizeDistributionShape::TabulatedVolume(d) => d.effective_radius_m(),
        }
    }

    /// Effective variance of the untruncated distribution (dimensionless).
    pub fn effective_variance(&self) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => d.effective_variance(),
            SizeDistributionShape::ModifiedGamma(d) => d.effective_variance(),
            SizeDistributionShape::TabulatedVolume(d) => d.effective_variance(),
        }
    }

    /// ln of the moment-weighted density r^p dN/d ln r at t = ln r, up to an
    /// additive constant; concave in t for both analytic shapes (a table
    /// need not be: the quadrature takes its range and depth from the table).
    fn ln_moment_weighted_density_unnormalised(&self, ln_radius: f64, power: f64) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => {
                let s = d.ln_geometric_standard_deviation();
                let z = (ln_radius - d.number_median_radius_m.ln()) / s;
                power * ln_radius - 0.5 * z * z
            }
            SizeDistributionShape::ModifiedGamma(d) => {
                // r^(k+p) exp(-r/theta), with r in units of theta.
                let t = ln_radius - d.gamma_scale_m().ln();
                (d.gamma_shape() + power) * t - t.exp()
            }
            SizeDistributionShape::TabulatedVolume(d) => {
                d.value_at(ln_radius).ln() + (power - 3.0) * ln_radius
            }
        }
    }

    /// ln r at the peak of the moment-weighted density r^p dN/d ln r:
    /// ln r_m + p s^2 for the log-normal, ln((k + p) theta) for the gamma.
    fn ln_radius_of_moment_weighted_peak(&self, power: f64) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => {
                let s = d.ln_geometric_standard_deviation();
                d.number_median_radius_m.ln() + power * s * s
            }
            SizeDistributionShape::ModifiedGamma(d) => {
                ((d.gamma_shape() + power) * d.gamma_scale_m()).ln()
            }
            // The table point where it is largest.
            SizeDistributionShape::TabulatedVolume(d) => d
                .ln_radii()
                .iter()
                .copied()
                .max_by(|&a, &b| {
                    self.ln_moment_weighted_density_unnormalised(a, power)
                        .total_cmp(&self.ln_moment_weighted_density_unnormalised(b, power))
                })
                .expect("a table has at least 2 points"),
        }
    }

    /// The spread of the area-weighted density in ln r (its standard
    /// deviation, s for the log-normal; about 1/sqrt(k + 2) for the gamma),
    /// the natural unit of panel widths.
    fn ln_radius_spread(&self) -> f64 {
        match self {
            SizeDistributionShape::LogNormal(d) => d.ln_geometric_standard_deviation(),
            SizeDistributionShape::ModifiedGamma(d) => 1.0 / (d.gamma_shape() + 2.0).sqrt(),
            SizeDistributionShape::TabulatedVolume(d) => d.ln_radius_spread(),
        }
    }
}

/// A radius window [min, max] (m) to which a distribution is truncated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadiusWindow {
    min_radius_m: f64,
    max_radius_m: f64,
}

impl RadiusWindow {
    /// The window [min_radius_m, max_radius_m] (m), 0 < min < max.
    pub fn new(min_radius_m: f64, max_radius_m: f64) -> Result<Self, SizeDistributionError> {
        let valid = min_radius_m.is_finite()
            && max_radius_m.is_finite()
            && min_radius_m > 0.0
            && min_radius_m < max_radius_m;
        if valid {
            Ok(Self {
                min_radius_m,
                max_radius_m,
            })
        } else {
            Err(SizeDistributionError::InvalidRadiusWindow {
                min_radius_m,
                max_radius_m,
            })
        }
    }

    /// The window [min_radius_um, max_radius_um] given in micrometres.
    pub fn from_micrometres(
        min_radius_um: f64,
        max_radius_um: f64,
    ) -> Result<Self, SizeDistributionError> {
        Self::new(min_radius_um * 1e-6, max_radius_um * 1e-6)
    }

    /// Lower edge (m).
    pub fn min_radius_m(&self) -> f64 {
        self.min_radius_m
    }

    /// Upper edge (m).
    pub fn max_radius_m(&self) -> f64 {
        self.max_radius_m
    }
}

/// A particle population: a distribution shape, optionally truncated to a
/// radius window, normalised per particle of the population (of the window's
/// particles when truncated).
#[derive(Debug, Clone, PartialEq)]
pub struct SizeDistribution {
    shape: SizeDistributionShape,
    radius_window: Option<RadiusWindow>,
    number_fraction_in_window: f64,
}

impl SizeDistribution {
    /// The untruncated population of `shape`.
    pub fn untruncated(shape: SizeDistributionShape) -> Self {
        Self {
            shape,
            radius_window: None,
            number_fraction_in_window: 1.0,
        }
    }

    /// Untruncated log-normal: number median radius (m), sigma_g (> 1).
    pub fn log_normal(
        number_median_radius_m: f64,
        geometric_standard_deviation: f64,
    ) -> Result<Self, SizeDistributionError> {
        let shape =
            LogNormalDistribution::new(number_median_radius_m, geometric_standard_deviation)?;
        Ok(Self::untruncated(SizeDistributionShape::LogNormal(shape)))
    }

    /// Untruncated log-normal from effective radius (m) and variance.
    pub fn log_normal_from_effective_radius_and_variance(
        effective_radius_m: f64,
        effective_variance: f64,
    ) -> Result<Self, SizeDistributionError> {
        let shape = LogNormalDistribution::from_effective_radius_and_variance(
            effective_radius_m,
            effective_variance,
        )?;
        Ok(Self::untruncated(SizeDistributionShape::LogNormal(shape)))
    }

    /// Untruncated Hansen & Travis gamma: effective radius (m), effective
    /// variance (0 < v_eff < 1/2).
    pub fn modified_gamma(
        effective_radius_m: f64,
        effective_variance: f64,
    ) -> Result<Self, SizeDistributionError> {
        let shape = ModifiedGammaDistribution::new(effective_radius_m, effective_variance)?;
        Ok(Self::untruncated(SizeDistributionShape::ModifiedGamma(
            shape,
        )))
    }

    /// A measured volume distribution dV/d ln r (see [`tabulated`]),
    /// normalised to one particle.
    pub fn tabulated_volume(table: TabulatedVolumeDistribution) -> Self {
        Self::untruncated(SizeDistributionShape::TabulatedVolume(table))
    }

    /// The population of the particles of `self`'s shape whose radius lies
    /// in `window` (replaces any earlier window). An error if the window
    /// holds no particles to double precision.
    pub fn truncated_to(self, window: RadiusWindow) -> Result<Self, SizeDistributionError> {
        let number_fraction_in_window = self
            .shape
            .number_fraction_between(window.min_radius_m, window.max_radius_m);
        // NaN counts as no particles.
        if number_fraction_in_window.is_nan() || number_fraction_in_window <= 0.0 {
            return Err(SizeDistributionError::NoParticlesInWindow {
                min_radius_m: window.min_radius_m,
                max_radius_m: window.max_radius_m,
            });
        }
        Ok(Self {
            shape: self.shape,
            radius_window: Some(window),
            number_fraction_in_window,
        })
    }

    /// The untruncated shape.
    pub fn shape(&self) -> &SizeDistributionShape {
        &self.shape
    }

    /// The truncation window, if any.
    pub fn radius_window(&self) -> Option<RadiusWindow> {
        self.radius_window
    }

    /// N_window / N: the fraction of the untruncated population inside the
    /// window (exactly 1 when untruncated). Closed form.
    pub fn number_fraction_in_window(&self) -> f64 {
        self.number_fraction_in_window
    }

    /// dN/d ln r per particle of this population at `radius_m`: the shape's
    /// density divided by the number fraction in the window, 0 outside it.
    pub fn number_density_per_ln_radius(&self, radius_m: f64) -> f64 {
        if let Some(window) = self.radius_window {
            if !(window.min_radius_m..=window.max_radius_m).contains(&radius_m) {
                return 0.0;
            }
        }
        self.number_density_per_ln_radius_inside_window(radius_m)
    }

    /// As [`Self::number_density_per_ln_radius`] without the window test: for
    /// quadrature nodes, which lie inside the window by construction but may
    /// round a hair outside it through exp(ln r).
    fn number_density_per_ln_radius_inside_window(&self, radius_m: f64) -> f64 {
        self.shape.number_density_per_ln_radius(radius_m) / self.number_fraction_in_window
    }

    /// Effective radius (m) and variance of this population (truncated or
    /// not) from its numerically integrated moments <r^2>, <r^3>, <r^4>
    /// (Gauss-Legendre in ln r over the range of [`RadiusQuadratureSettings::smooth`]).
    pub fn effective_radius_and_variance_by_quadrature(&self) -> (f64, f64) {
        let quadrature =
            RadiusQuadrature::gauss_legendre(self, 0.0, &RadiusQuadratureSettings::smooth())
                .expect("the built-in smooth quadrature settings are valid");
        let moment = |power: i32| quadrature.integrate(|r| r.powi(power));
        let (m2, m3, m4) = (moment(2), moment(3), moment(4));
        let effective_radius_m = m3 / m2;
        (effective_radius_m, m4 * m2 / (m3 * m3) - 1.0)
    }

    /// ln of the importance density at t = ln r, up to a constant: the
    /// integrand of a cross-section modelled as
    /// `r^2 min(1, x / x_g) dN/d ln r`, `x = k r`, i.e. an efficiency
    /// constant above [`GEOMETRIC_REGIME_SIZE_PARAMETER`] `x_g` and falling
    /// like x below it: the slowest fall-off of any efficiency (absorption,
    /// Q_abs ~ x in the Rayleigh regime, against Q_sca ~ x^4), so that no
    /// cross-section has mass where the model says there is none. Or the
    /// area-weighted density `r^2 dN/d ln r` when `wavenumber_per_m` is 0.
    /// A sum of concave functions of t, hence concave.
    fn ln_importance_density(&self, ln_radius: f64, wavenumber_per_m: f64) -> f64 {
        let rayleigh_suppression = if wavenumber_per_m > 0.0 {
            (ln_radius + (wavenumber_per_m / GEOMETRIC_REGIME_SIZE_PARAMETER).ln()).min(0.0)
        } else {
            0.0
        };
        self.shape
            .ln_moment_weighted_density_unnormalised(ln_radius, 2.0)
            + rayleigh_suppression
    }

    /// ln r at the peak of the importance density, clipped to the window (the
    /// maximum of a concave function over an interval).
    fn ln_radius_of_importance_peak(&self, wavenumber_per_m: f64) -> f64 {
        let area_peak = self.shape.ln_radius_of_moment_weighted_peak(2.0);
        let peak = if wavenumber_per_m > 0.0 {
            // Where x = x_g; below it the importance is r^3 dN/d ln r.
            let geometric_regime_start = (GEOMETRIC_REGIME_SIZE_PARAMETER / wavenumber_per_m).ln();
            let rayleigh_peak = self.shape.ln_radius_of_moment_weighted_peak(3.0);
            if area_peak >= geometric_regime_start {
                area_peak
            } else if rayleigh_peak <= geometric_regime_start {
                rayleigh_peak
            } else {
                geometric_regime_start
            }
        } else {
            area_peak
        };
        match self.radius_window {
            Some(w) => peak.clamp(w.min_radius_m.ln(), w.max_radius_m.ln()),
            None => peak,
        }
    }

    /// How many e-folds the importance density at t = ln r lies below its
    /// (clipped) peak: >= 0 inside the window.
    fn importance_depth_below_peak(&self, ln_radius: f64, wavenumber_per_m: f64) -> f64 {
        // A table need not be log-concave and vanishes at its ends: the whole
        // support is resolved as the peak is (see [`tabulated`]).
        if let SizeDistributionShape::TabulatedVolume(_) = self.shape {
            return 0.0;
        }
        let peak = self.ln_radius_of_importance_peak(wavenumber_per_m);
        self.ln_importance_density(peak, wavenumber_per_m)
            - self.ln_importance_density(ln_radius, wavenumber_per_m)
    }

    /// The ln-radius interval where the importance density is within
    /// exp(-tail_depth) of its peak, clipped to the window. The depth is
    /// convex in t with its minimum at the peak, so each end is found by
    /// bracketing outwards in steps of the spread and bisecting.
    fn ln_radius_integration_range(&self, tail_depth: f64, wavenumber_per_m: f64) -> (f64, f64) {
        if let SizeDistributionShape::TabulatedVolume(table) = &self.shape {
            let (mut lower, mut upper) = table.ln_radius_support();
            if let Some(w) = self.radius_window {
                lower = lower.max(w.min_radius_m.ln());
                upper = upper.min(w.max_radius_m.ln());
            }
            return (lower, upper);
        }
        let peak = self.ln_radius_of_importance_peak(wavenumber_per_m);
        let spread = self.shape.ln_radius_spread();
        let depth = |t: f64| self.importance_depth_below_peak(t, wavenumber_per_m);
        let find_end = |direction: f64| {
            let mut inside = peak;
            let mut step = spread;
            let mut outside = peak + direction * step;
            while depth(outside) < tail_depth {
                inside = outside;
                step *= 2.0;
                outside = peak + direction * step;
            }
            for _ in 0..200 {
                let middle = 0.5 * (inside + outside);
                if middle == inside || middle == outside {
                    break;
                }
                if depth(middle) < tail_depth {
                    inside = middle;
                } else {
                    outside = middle;
                }
            }
            0.5 * (inside + outside)
        };
        let (mut lower, mut upper) = (find_end(-1.0), find_end(1.0));
        if let Some(w) = self.radius_window {
            lower = lower.max(w.min_radius_m.ln());
            upper = upper.min(w.max_radius_m.ln());
        }
        (lower, upper)
    }

    /// Spread of the area-weighted density in ln r.
    fn ln_radius_spread(&self) -> f64 {
        self.shape.ln_radius_spread()
    }

    /// The ln r (m) where the density is not smooth, increasing: the window's
    /// edges and a table's points inside the window. Quadrature panels end there.
    fn ln_radius_breakpoints(&self) -> Vec<f64> {
        let mut points = Vec::new();
        if let Some(w) = self.radius_window {
            points.push(w.min_radius_m.ln());
            points.push(w.max_radius_m.ln());
        }
        if let SizeDistributionShape::TabulatedVolume(table) = &self.shape {
            let inside = |t: f64| {
                self.radius_window
                    .is_none_or(|w| t > w.min_radius_m.ln() && t < w.max_radius_m.ln())
            };
            points.extend(table.ln_radii().iter().copied().filter(|&t| inside(t)));
        }
        points.sort_by(f64::total_cmp);
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MICROMETRE: f64 = 1e-6;

    #[test]
    fn constructors_reject_invalid_parameters() {
        assert!(matches!(
            LogNormalDistribution::new(0.0, 1.5),
            Err(SizeDistributionError::InvalidRadius { .. })
        ));
        assert!(LogNormalDistribution::new(-1e-6, 1.5).is_err());
        assert!(LogNormalDistribution::new(f64::NAN, 1.5).is_err());
        assert!(matches!(
            LogNormalDistribution::new(1e-6, 1.0),
            Err(SizeDistributionError::InvalidGeometricStandardDeviation { .. })
        ));
        assert!(LogNormalDistribution::new(1e-6, 0.5).is_err());
        assert!(LogNormalDistribution::new(1e-6, f64::INFINITY).is_err());
        assert!(LogNormalDistribution::from_effective_radius_and_variance(1e-6, 0.0).is_err());
        assert!(LogNormalDistribution::from_effective_radius_and_variance(1e-6, -0.1).is_err());
        assert!(LogNormalDistribution::from_effective_radius_and_variance(0.0, 0.1).is_err());
        assert!(matches!(
            ModifiedGammaDistribution::new(1e-6, 0.5),
            Err(SizeDistributionError::InvalidEffectiveVariance { upper_limit_exclusive, .. }) if upper_limit_exclusive == 0.5
        ));
        assert!(ModifiedGammaDistribution::new(1e-6, 0.0).is_err());
        assert!(ModifiedGammaDistribution::new(-1e-6, 0.2).is_err());
        assert!(matches!(
            RadiusWindow::new(2e-6, 1e-6),
            Err(SizeDistributionError::InvalidRadiusWindow { .. })
        ));
        assert!(RadiusWindow::new(1e-6, 1e-6).is_err());
        assert!(RadiusWindow::new(0.0, 1e-6).is_err());
        // A window 60 s above the median holds nothing in double precision.
        let far = SizeDistribution::log_normal(1e-8, 1.1)
            .unwrap()
            .truncated_to(RadiusWindow::new(1e-4, 2e-4).unwrap());
        assert!(matches!(
            far,
            Err(SizeDistributionError::NoParticlesInWindow { .. })
        ));
        let message = LogNormalDistribution::new(1e-6, 0.9)
            .unwrap_err()
            .to_string();
        assert!(message.contains("sigma_g = 0.9"), "{message}");
    }

    /// Issue 17: a vanishing width (v_eff = 1e-30 made the radius quadrature
    /// allocate without end) is refused at the stated limits, and the
    /// narrowest accepted populations still integrate to one particle with
    /// their own effective radius and variance.
    #[test]
    fn the_narrowest_populations_are_refused_at_the_stated_limits() {
        for (v_eff, shown) in [(1e-30, "1e-30"), (5e-324, "5e-324"), (0.99e-8, "9.9e-9")] {
            let message = LogNormalDistribution::from_effective_radius_and_variance(1e-6, v_eff)
                .unwrap_err()
                .to_string();
            assert!(
                message.contains(&format!("v_eff = {shown} is invalid"))
                    && message.contains("at least 1e-8"),
                "{message}"
            );
            assert!(ModifiedGammaDistribution::new(1e-6, v_eff).is_err());
        }
        for sigma_g in [1.0 + f64::EPSILON, 1.000_099] {
            let message = LogNormalDistribution::new(1e-6, sigma_g)
                .unwrap_err()
                .to_string();
            assert!(message.contains("at least 1.0001"), "{message}");
        }
        let narrowest = [
            SizeDistribution::log_normal(MICROMETRE, MIN_GEOMETRIC_STANDARD_DEVIATION).unwrap(),
            SizeDistribution::log_normal_from_effective_radius_and_variance(
                MICROMETRE,
                MIN_EFFECTIVE_VARIANCE,
            )
            .unwrap(),
            SizeDistribution::modified_gamma(MICROMETRE, MIN_EFFECTIVE_VARIANCE).unwrap(),
        ];
        for distribution in narrowest {
            let quadrature = RadiusQuadrature::gauss_legendre(
                &distribution,
                2.0 * PI / 360e-9,
                &RadiusQuadratureSettings::cross_sections(),
            )
            .unwrap();
            assert!(quadrature.len() < 1000, "{}", quadrature.len());
            let total = quadrature.integrate(|_| 1.0);
            assert!((total - 1.0).abs() < 1e-8, "{distribution:?}: {total}");
            let (r_eff, v_eff) = distribution.effective_radius_and_variance_by_quadrature();
            let shape = distribution.shape();
            assert!((r_eff / shape.effective_radius_m() - 1.0).abs() < 1e-12);
            assert!(
                (v_eff / shape.effective_variance() - 1.0).abs() < 1e-4,
                "{v_eff}"
            );
        }
    }

    #[test]
    fn effective_radius_and_variance_round_trip_for_the_log_normal() {
        // The Mars dust of Wolff et al.: r_eff 1.5 um, v_eff 0.3 -> r_m ~0.78 um, sigma_g ~1.67.
        let dust = LogNormalDistribution::from_effective_radius_and_variance(1.5 * MICROMETRE, 0.3)
            .unwrap();
        assert!((dust.number_median_radius_m() / MICROMETRE - 0.78).abs() < 0.01);
        assert!((dust.geometric_standard_deviation() - 1.67).abs() < 0.01);
        assert!((dust.effective_radius_m() / (1.5 * MICROMETRE) - 1.0).abs() < 1e-14);
        assert!((dust.effective_variance() - 0.3).abs() < 1e-14);
    }

    /// The number fraction of a truncated log-normal against the
    /// closed form 0.5 (erf(z2/sqrt2) - erf(z1/sqrt2)), values from mpmath
    /// (30 digits) for the paper's windows.
    #[test]
    // The expected values are mpmath's, written as printed.
    #[allow(clippy::excessive_precision)]
    fn truncated_log_normal_number_fraction_matches_erf() {
        // (r_m um, sigma_g, window um, mpmath ncdf(z2) - ncdf(z1))
        let cases = [
            (0.5, 1.5, (0.1, 2.5), 0.999_927_934_760_716_2),
            (0.05, 1.5, (0.45, 0.56), 2.868_909_413_319_212e-8),
            (1.5, 2.0, (0.45, 0.56), 0.036_394_367_692_287_454),
            (0.1, 2.0, (0.1, 2.5), 0.499_998_290_171_814_06),
        ];
        for (r_m_um, sigma_g, (lo_um, hi_um), expected) in cases {
            let distribution = SizeDistribution::log_normal(r_m_um * MICROMETRE, sigma_g)
                .unwrap()
                .truncated_to(RadiusWindow::from_micrometres(lo_um, hi_um).unwrap())
                .unwrap();
            let fraction = distribution.number_fraction_in_window();
            assert!(
                (fraction / expected - 1.0).abs() < 1e-13,
                "r_m {r_m_um} sigma {sigma_g} window {lo_um}-{hi_um}: {fraction:e} vs {expected:e}"
            );
        }
    }

    /// The closed-form fraction against a brute-force trapezoid of the density
    /// (the slow path), for both shapes, and per-particle normalisation of
    /// the truncated population.
    #[test]
    fn number_fraction_matches_a_brute_force_integral() {
        let shapes = [
            SizeDistributionShape::LogNormal(
                LogNormalDistribution::new(0.78 * MICROMETRE, 1.67).unwrap(),
            ),
            SizeDistributionShape::ModifiedGamma(
                ModifiedGammaDistribution::new(1.5 * MICROMETRE, 0.3).unwrap(),
            ),
            SizeDistributionShape::ModifiedGamma(
                ModifiedGammaDistribution::new(0.2 * MICROMETRE, 0.05).unwrap(),
            ),
        ];
        for shape in shapes {
            let (lo, hi) = (0.45 * MICROMETRE, 2.5 * MICROMETRE);
            let n = 200_000;
            let (a, b) = (lo.ln(), hi.ln());
            let h = (b - a) / n as f64;
            // Composite Simpson in ln r (the trapezoid's h^2 error on this
            // steep, non-periodic integrand would be ~5e-9).
            let mut sum =
                shape.number_density_per_ln_radius(lo) + shape.number_density_per_ln_radius(hi);
            for i in 1..n {
                let simpson_weight = if i % 2 == 1 { 4.0 } else { 2.0 };
                sum +=
                    simpson_weight * shape.number_density_per_ln_radius((a + i as f64 * h).exp());
            }
            let brute_force = sum * h / 3.0;
            let closed_form = shape.number_fraction_between(lo, hi);
            assert!(
                (closed_form / brute_force - 1.0).abs() < 1e-10,
                "{shape:?}: {closed_form} vs {brute_force}"
            );
            // The whole line holds every particle (the gamma with k = 4/3 still
            // has 2e-8 of its particles below 1e-12 m, hence 1e-20).
            assert!((shape.number_fraction_between(1e-20, 1.0) - 1.0).abs() < 1e-14);
            // The truncated population integrates to one particle.
            let truncated = SizeDistribution::untruncated(shape.clone())
                .truncated_to(RadiusWindow::new(lo, hi).unwrap())
                .unwrap();
            let total = RadiusQuadrature::gauss_legendre(
                &truncated,
                0.0,
                &RadiusQuadratureSettings::smooth(),
            )
            .unwrap()
            .integrate(|_| 1.0);
            assert!((total - 1.0).abs() < 1e-13, "{shape:?}: {total}");
        }
    }

    /// r_eff and v_eff recovered from numerically integrated moments.
    #[test]
    fn effective_radius_and_variance_recovered_by_numerical_moments() {
        let cases = [
            SizeDistribution::log_normal(0.78 * MICROMETRE, 1.67).unwrap(),
            SizeDistribution::log_normal(0.05 * MICROMETRE, 2.0).unwrap(),
            SizeDistribution::log_normal(1.5 * MICROMETRE, 1.05).unwrap(),
            SizeDistribution::log_normal_from_effective_radius_and_variance(10.0 * MICROMETRE, 0.1)
                .unwrap(),
            SizeDistribution::modified_gamma(1.5 * MICROMETRE, 0.3).unwrap(),
            SizeDistribution::modified_gamma(0.3 * MICROMETRE, 0.01).unwrap(),
            SizeDistribution::modified_gamma(5.0 * MICROMETRE, 0.45).unwrap(),
        ];
        for distribution in cases {
            let (r_eff, v_eff) = distribution.effective_radius_and_variance_by_quadrature();
            let shape = distribution.shape();
            assert!(
                (r_eff / shape.effective_radius_m() - 1.0).abs() < 1e-11,
                "{shape:?}: r_eff {r_eff}"
            );
            assert!(
                (v_eff / shape.effective_variance() - 1.0).abs() < 1e-9,
                "{shape:?}: v_eff {v_eff}"
            );
        }
    }

    #[test]
    fn gamma_density_is_the_hansen_travis_form() {
        // n(r) = C r^((1-3b)/b) exp(-r/(ab)): ratio of densities at two radii
        // is independent of C.
        let d = ModifiedGammaDistribution::new(1.5 * MICROMETRE, 0.3).unwrap();
        let (a, b) = (1.5 * MICROMETRE, 0.3);
        let n = |r: f64| d.number_density_per_ln_radius(r) / r;
        let (r1, r2) = (0.7 * MICROMETRE, 2.9 * MICROMETRE);
        let expected = (r1 / r2).powf((1.0 - 3.0 * b) / b) * (-(r1 - r2) / (a * b)).exp();
        assert!((n(r1) / n(r2) / expected - 1.0).abs() < 1e-13);
    }

    #[test]
    fn integration_range_covers_the_area_weighted_log_normal() {
        let d = SizeDistribution::log_normal(0.78 * MICROMETRE, 1.67).unwrap();
        let (lower, upper) = d.ln_radius_integration_range(25.0, 0.0);
        let s = 1.67f64.ln();
        let centre = (0.78 * MICROMETRE).ln() + 2.0 * s * s;
        let half_width = (2.0 * 25.0f64).sqrt() * s;
        assert!((lower - (centre - half_width)).abs() < 1e-12);
        assert!((upper - (centre + half_width)).abs() < 1e-12);
        // Truncated far below the peak: the range is the window.
        let t = d
            .truncated_to(RadiusWindow::from_micrometres(0.45, 0.56).unwrap())
            .unwrap();
        let (lower, upper) = t.ln_radius_integration_range(25.0, 0.0);
        assert_eq!(
            (lower, upper),
            ((0.45 * MICROMETRE).ln(), (0.56 * MICROMETRE).ln())
        );
    }
}
