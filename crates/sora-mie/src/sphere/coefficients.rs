//! The Mie coefficients a_n, b_n and the efficiency sums, in one upward pass.
//!
//! B&H eq. 4.88 writes, with D_n = D_n(mx) the logarithmic derivative,
//!
//! ```text
//! a_n = [(D_n/m + n/x) psi_n - psi_{n-1}] / [(D_n/m + n/x) xi_n - xi_{n-1}]
//! b_n = [(m D_n + n/x) psi_n - psi_{n-1}] / [(m D_n + n/x) xi_n - xi_{n-1}]
//! ```
//!
//! with psi_n = psi_n(x), xi_n = psi_n - i chi_n (B&H eq. 4.89-4.90, chi_n =
//! -x y_n(x)). Using psi_n' = (n+1)/x psi_n - psi_{n+1} instead of
//! psi_n' = psi_{n-1} - n/x psi_n, and D_n(z) = (n+1)/z - rho_{n+1}(z) with
//! rho_n(z) = psi_n(z)/psi_{n-1}(z) (see `bessel_ratio.rs`), the same
//! coefficients read
//!
//! ```text
//! a_n = (A_n psi_n + psi_{n+1}) / (A_n xi_n + xi_{n+1}),   A_n = (n+1)/x (1/m^2 - 1) - rho_{n+1}(mx)/m
//! b_n = (B_n psi_n + psi_{n+1}) / (B_n xi_n + xi_{n+1}),   B_n = -m rho_{n+1}(mx)
//! ```
//!
//! The (n+1)/x of m D_n and of psi_n'/psi_n have cancelled *analytically* in
//! B_n. In eq. 4.88 they cancel numerically: for x << 1 the numerator of b_n
//! is (2n+1)/x psi_n minus almost the same number, leaving (1 - m^2) x/(2n+3)
//! psi_n and a relative error ~1e-16 / x^2 (1e-8 at x = 1e-4). That error
//! reaches the asymmetry parameter at leading order (g ~ Re(a_1 conj(b_1))
//! + Re(a_1 conj(a_2)), both ~x^8), which is why reference codes lose g for
//! small spheres. 1/m^2 - 1 is formed as -(m-1)(m+1)/m^2 so that m -> 1 keeps
//! its relative accuracy.
//!
//! Absorption without cancellation. For any complex A, the Wronskian
//! psi_n chi_{n+1} - psi_{n+1} chi_n = 1 gives
//! Re(a_n) - |a_n|^2 = -Im(A_n) / |A_n xi_n + xi_{n+1}|^2 (and likewise for b_n
//! with B_n), so Q_abs = Q_ext - Q_sca is summed term by term from quantities
//! that are proportional to Im(m): exactly zero for a real m, and accurate to
//! the last digits for Im(m) = 1e-8 where Q_ext - Q_sca would keep none.
//!
//! Two paths:
//! - x >= 1: psi_n by the upward recurrence while it is oscillatory (n <= x,
//!   where the upward recurrence is neutrally stable), then by
//!   psi_{n+1} = psi_n rho_{n+1}(x) from a downward ratio recurrence beyond
//!   the turning point, where the upward recurrence would amplify rounding by
//!   chi_n/psi_n. chi_n always upward (it is the dominant solution).
//! - x < 1: every quantity is scaled by its power of x so that nothing
//!   underflows, overflows or cancels for x down to 1e-300: rhot_n = rho_n/z,
//!   psit_n = psi_n/x^(n+1), Ut_n = 1/(x^n xi_n) by Ut_n = Ut_{n-1}/sigt_n
//!   with sigt_n = x xi_n/xi_{n-1} = (2n-1) - x^2/sigt_{n-1} (upward, the
//!   dominant direction), and the coefficients come out as a_n/x^3, b_n/x^3.
//!   psi_n(x) has no zero for x < pi, so the ratio products are safe there.
//!
//! The efficiency sums (B&H eqs. 4.61-4.62, 4.82 and the g formula of
//! B&H p. 120) are accumulated in the same loop, so `compute_efficiencies`
//! never stores a_n, b_n.

use super::Efficiencies;
use super::bessel_ratio::{
    fill_ratios_downward, fill_scaled_ratios_downward, reciprocal, scaled_ratio_continued_fraction,
};
use super::series_length::series_length_converged;
use crate::Complex64;

/// Below this size parameter the scaled small-x path is used.
pub(super) const SMALL_SIZE_PARAMETER: f64 = 1.0;

/// The factor s with which [`solve_series`] scales the coefficients it
/// records: a_n = s * recorded.
pub(super) fn coefficient_scale(x: f64) -> f64 {
    if x < SMALL_SIZE_PARAMETER {
        x * x * x
    } else {
        1.0
    }
}

/// Lengths of the two scratch arrays the solver needs for size parameter x:
/// (complex ratios of mx, real ratios of x).
pub(super) fn scratch_lengths(x: f64) -> (usize, usize) {
    let n_cap = series_length_converged(x);
    if x < SMALL_SIZE_PARAMETER {
        (n_cap + 2, n_cap + 2)
    } else {
        (n_cap + 2, n_cap + 2 - (x as usize))
    }
}

/// Running sums over n of the series for the efficiencies, in units of the
/// coefficients as passed (which may be scaled by 1/x^3, see `finish`).
struct SeriesSums {
    /// sum (2n+1) (|a_n|^2 + |b_n|^2)
    scattering: f64,
    /// sum (2n+1) (Re a_n - |a_n|^2 + Re b_n - |b_n|^2), without cancellation
    absorption: f64,
    /// sum (2n+1) (-1)^n (a_n - b_n)
    backscattering: Complex64,
    /// sum_{n>=1} n(n+2)/(n+1) Re(a_n conj(a_{n+1}) + b_n conj(b_{n+1}))
    asymmetry_adjacent: f64,
    /// sum (2n+1)/(n(n+1)) Re(a_n conj(b_n))
    asymmetry_cross: f64,
    previous_a: Complex64,
    previous_b: Complex64,
}

impl SeriesSums {
    fn new() -> Self {
        let zero = Complex64::new(0.0, 0.0);
        SeriesSums {
            scattering: 0.0,
            absorption: 0.0,
            backscattering: zero,
            asymmetry_adjacent: 0.0,
            asymmetry_cross: 0.0,
            previous_a: zero,
            previous_b: zero,
        }
    }

    /// Add term n. `absorption` is Re a_n - |a_n|^2 + Re b_n - |b_n|^2.
    /// `inverse_n` = 1/n and `inverse_n_plus_1` = 1/(n+1) (divisions shared).
    #[inline(always)]
    fn add(
        &mut self,
        n: usize,
        inverse_n: f64,
        inverse_n_plus_1: f64,
        a: Complex64,
        b: Complex64,
        absorption: f64,
    ) {
        let weight = (2 * n + 1) as f64;
        self.scattering += weight * (a.re * a.re + a.im * a.im + b.re * b.re + b.im * b.im);
        self.absorption += weight * absorption;
        let difference = (a - b) * weight;
        if n % 2 == 0 {
            self.backscattering += difference;
        } else {
            self.backscattering -= difference;
        }
        // Term n-1 of the adjacent sum: (n-1)(n+1)/n = n - 1/n.
        let adjacent = self.previous_a.re * a.re
            + self.previous_a.im * a.im
            + self.previous_b.re * b.re
            + self.previous_b.im * b.im;
        self.asymmetry_adjacent += (n as f64 - inverse_n) * adjacent;
        // (2n+1)/(n(n+1)) = 1/n + 1/(n+1).
        self.asymmetry_cross += (inverse_n + inverse_n_plus_1) * (a.re * b.re + a.im * b.im);
        self.previous_a = a;
        self.previous_b = b;
    }

    /// Efficiencies from sums of coefficients that were divided by `scale`
    /// (a_n = scale * ahat_n): Q_ext = 2/x^2 sum..., Q_back = |sum|^2/x^2, with
    /// the scale folded into the prefactors so that nothing underflows first.
    fn finish(&self, x: f64, scale_over_x: f64, scale_squared_over_x_squared: f64) -> Efficiencies {
        let qsca = 2.0 * scale_squared_over_x_squared * self.scattering;
        let qabs = 2.0 * scale_over_x / x * self.absorption;
        // Q_ext = (2/x^2) sum (2n+1) Re(a_n + b_n) (B&H 4.62), summed as
        // Q_sca + Q_abs: per term Re a_n = |a_n|^2 + (Re a_n - |a_n|^2), and
        // both parts are sums of non-negative, accurately computed terms.
        // The direct sum is ill-conditioned for small lossless spheres, where
        // Re a_1 = |a_1|^2 ~ x^6 is the residue of products of O(x^3)
        // numbers (relative error ~1e-16/x^3).
        let qext = qsca + qabs;
        let qback = scale_squared_over_x_squared * self.backscattering.norm_sqr();
        // g = (4 / (x^2 Q_sca)) (adjacent + cross): the scale cancels.
        let g = if self.scattering > 0.0 {
            2.0 * (self.asymmetry_adjacent + self.asymmetry_cross) / self.scattering
        } else {
            0.0
        };
        Efficiencies {
            qext,
            qsca,
            qabs,
            qback,
            g,
        }
    }
}

/// Solve the series for a validated (m, x): returns the efficiencies and
/// calls `record(a_n / s, b_n / s)` for n = 1, 2, ... in order, with the
/// scale s = [`coefficient_scale`]`(x)` (x^3 below x = 1, so that the
/// recorded values never underflow). `complex_scratch` and `real_scratch`
/// must have at least the lengths of [`scratch_lengths`].
pub(super) fn solve_series<F: FnMut(Complex64, Complex64)>(
    m: Complex64,
    x: f64,
    complex_scratch: &mut [Complex64],
    real_scratch: &mut [f64],
    record: F,
) -> Efficiencies {
    let mut efficiencies = if x < SMALL_SIZE_PARAMETER {
        solve_small(m, x, complex_scratch, real_scratch, record)
    } else {
        solve_large(m, x, complex_scratch, real_scratch, record)
    };
    if m.im == 0.0 {
        // Every absorption term is Im(...) of a real number: exactly zero,
        // but possibly -0.0. The efficiency of a lossless sphere is +0.
        efficiencies.qabs = 0.0;
    }
    efficiencies
}

/// The x >= 1 path: unscaled psi, chi; ratios rho_n(mx) stored downward.
fn solve_large<F: FnMut(Complex64, Complex64)>(
    m: Complex64,
    x: f64,
    rho_mx: &mut [Complex64],
    rho_x: &mut [f64],
    mut record: F,
) -> Efficiencies {
    let n_cap = series_length_converged(x);
    // psi_n(x) > 0 and decreasing for n >= x (its last zero in n is below
    // x - 1.8 x^(1/3)), so from there on the ratio form is well conditioned.
    let n_switch = (x as usize).min(n_cap);
    fill_ratios_downward(m * x, n_cap + 1, rho_mx);

    // rho_x[k] = psi_{n_switch+k}(x) / psi_{n_switch+k-1}(x), k >= 1.
    let rho_x = &mut rho_x[..n_cap + 2 - n_switch];
    let mut ratio = x * scaled_ratio_continued_fraction(Complex64::new(x * x, 0.0), n_cap + 1).re;
    rho_x[n_cap + 1 - n_switch] = ratio;
    for n in (n_switch + 1..=n_cap).rev() {
        ratio = x / ((2 * n + 1) as f64 - x * ratio);
        rho_x[n - n_switch] = ratio;
    }

    let inverse_x = 1.0 / x;
    let (sin_x, cos_x) = x.sin_cos();
    // B&H eq. 4.89 starting values (psi_0, psi_1, chi_0, chi_1); for x >= 1
    // psi_1 = sin x / x - cos x loses at most two bits.
    let mut psi_previous = sin_x;
    let mut psi = sin_x * inverse_x - cos_x;
    let mut chi_previous = cos_x;
    let mut chi = cos_x * inverse_x + sin_x;

    let inverse_m = reciprocal(m);
    // (1/m^2 - 1)/x, formed without cancelling for m near 1.
    let a_slope = -((m - 1.0) * (m + 1.0)) * (inverse_m * inverse_m) * inverse_x;
    let mut sums = SeriesSums::new();
    let mut inverse_n = 1.0;
    for n in 1..=n_cap {
        let step = (2 * n + 1) as f64 * inverse_x;
        let psi_next = if n < n_switch {
            step * psi - psi_previous
        } else {
            psi * rho_x[n + 1 - n_switch]
        };
        let chi_next = step * chi - chi_previous;

        let rho = rho_mx[n + 1];
        let a_factor = a_slope * (n + 1) as f64 - rho * inverse_m;
        let b_factor = -(m * rho);
        // numerator = F psi_n + psi_{n+1}; denominator = F xi_n + xi_{n+1}
        // = numerator - i (F chi_n + chi_{n+1}).
        let a_numerator = a_factor * psi + psi_next;
        let a_chi = a_factor * chi + chi_next;
        let a_denominator = Complex64::new(a_numerator.re + a_chi.im, a_numerator.im - a_chi.re);
        let b_numerator = b_factor * psi + psi_next;
        let b_chi = b_factor * chi + chi_next;
        let b_denominator = Complex64::new(b_numerator.re + b_chi.im, b_numerator.im - b_chi.re);
        // One division for both quotients: 1/(|Da|^2 |Db|^2).
        let a_norm = a_denominator.norm_sqr();
        let b_norm = b_denominator.norm_sqr();
        let inverse_both = 1.0 / (a_norm * b_norm);
        let inverse_a_norm = b_norm * inverse_both;
        let inverse_b_norm = a_norm * inverse_both;
        let a = a_numerator * a_denominator.conj() * inverse_a_norm;
        let b = b_numerator * b_denominator.conj() * inverse_b_norm;
        let absorption = -a_factor.im * inverse_a_norm - b_factor.im * inverse_b_norm;

        let inverse_n_plus_1 = 1.0 / (n + 1) as f64;
        sums.add(n, inverse_n, inverse_n_plus_1, a, b, absorption);
        record(a, b);
        inverse_n = inverse_n_plus_1;
        psi_previous = psi;
        psi = psi_next;
        chi_previous = chi;
        chi = chi_next;
    }
    sums.finish(x, inverse_x, inverse_x * inverse_x)
}

/// The x < 1 path: all quantities scaled by powers of x, coefficients
/// accumulated as ahat_n = a_n / x^3, bhat_n = b_n / x^3.
fn solve_small<F: FnMut(Complex64, Complex64)>(
    m: Complex64,
    x: f64,
    rhot_mx: &mut [Complex64],
    rhot_x: &mut [f64],
    mut record: F,
) -> Efficiencies {
    let n_cap = series_length_converged(x);
    let x_squared = x * x;
    fill_scaled_ratios_downward(m * x, n_cap + 1, rhot_mx);
    let rhot_x = &mut rhot_x[..n_cap + 2];
    let mut ratio = scaled_ratio_continued_fraction(Complex64::new(x_squared, 0.0), n_cap + 1).re;
    rhot_x[n_cap + 1] = ratio;
    for n in (1..=n_cap).rev() {
        ratio = 1.0 / ((2 * n + 1) as f64 - x_squared * ratio);
        rhot_x[n] = ratio;
    }

    let (sin_x, cos_x) = x.sin_cos();
    // psit_0 = psi_0/x = sin x / x; Ut_0 = 1/xi_0 = i e^{-ix}; sigt_1 = 1 - i x.
    let mut psi_scaled = if x > 0.0 { sin_x / x } else { 1.0 };
    let mut inverse_xi_scaled = Complex64::new(sin_x, cos_x);
    let mut sigma_scaled = Complex64::new(1.0, -x);

    let m_squared = m * m;
    let a_slope = -((m - 1.0) * (m + 1.0)) / m_squared;
    let mut power = 1.0; // x^(2n-2)
    let mut sums = SeriesSums::new();
    let mut inverse_n = 1.0;
    for n in 1..=n_cap {
        psi_scaled *= rhot_x[n];
        let inverse_sigma = reciprocal(sigma_scaled);
        inverse_xi_scaled *= inverse_sigma;
        sigma_scaled = Complex64::new((2 * n + 1) as f64, 0.0) - inverse_sigma * x_squared;
        let transmission = inverse_xi_scaled * psi_scaled; // psi_n/xi_n / x^(2n+1)
        let rhot = rhot_mx[n + 1];
        let rhot_real = rhot_x[n + 1];

        // x A_n and x B_n of the module documentation.
        let a_factor = a_slope * (n + 1) as f64 - rhot * x_squared;
        let b_internal = m_squared * rhot;
        let a_denominator = a_factor + sigma_scaled;
        let b_denominator = sigma_scaled - b_internal * x_squared;
        let inverse_a_denominator = reciprocal(a_denominator);
        let inverse_b_denominator = reciprocal(b_denominator);
        let a = transmission * (a_factor + rhot_real * x_squared) * inverse_a_denominator * power;
        let b = transmission
            * (Complex64::new(rhot_real, 0.0) - b_internal)
            * inverse_b_denominator
            * (power * x_squared);
        let u_norm = inverse_xi_scaled.norm_sqr();
        let absorption = power
            * u_norm
            * (-a_factor.im * inverse_a_denominator.norm_sqr()
                + x_squared * b_internal.im * inverse_b_denominator.norm_sqr());

        let inverse_n_plus_1 = 1.0 / (n + 1) as f64;
        sums.add(n, inverse_n, inverse_n_plus_1, a, b, absorption);
        record(a, b);
        inverse_n = inverse_n_plus_1;
        power *= x_squared;
    }
    sums.finish(x, x_squared, x_squared * x_squared)
}
