//! A perfectly conducting sphere: the limit |m| -> infinity of a metal.
//!
//! The tangential electric field vanishes on the surface, and the
//! coefficients become (B&H problem 4.x; Wiscombe 1980's MIEV0 "perfectly
//! conducting" case)
//!
//! ```text
//! a_n = psi_n'(x) / xi_n'(x),   b_n = psi_n(x) / xi_n(x).
//! ```
//!
//! With psi_n' = (n+1)/x psi_n - psi_{n+1} (as in `coefficients.rs`),
//! a_n = (psi_{n+1} - (n+1)/x psi_n) / (xi_{n+1} - (n+1)/x xi_n), which is the
//! dielectric formula with A_n = -(n+1)/x: for x << 1 the numerator is
//! psi_n ((n+1)/x - x/(2n+3)) and the denominator ~ n/x chi_n, neither of
//! which cancels. There is no absorption: Q_abs = 0 and Q_ext = Q_sca.
//!
//! This path is not tuned for speed (a scalar loop, one allocation for the
//! ratio table): perfect conductors are a reference case, not an aerosol.

use super::bessel_ratio::scaled_ratio_continued_fraction_real;
use super::series_length::series_length_converged;
use super::{Efficiencies, MAX_SIZE_PARAMETER, MieError};
use crate::Complex64;

/// Smallest size parameter of the perfect-conductor path: below it chi_n(x)
/// ~ (2n-1)!!/x^n of the unscaled recurrence would approach overflow.
pub const MIN_PERFECT_CONDUCTOR_SIZE_PARAMETER: f64 = 1e-6;

/// Efficiencies and asymmetry parameter (dimensionless) of a perfectly
/// conducting sphere of size parameter `x` (MIEV0's "perfectly conducting"
/// case, |m| -> infinity). `x` must be finite and within
/// [`MIN_PERFECT_CONDUCTOR_SIZE_PARAMETER`] ..= [`MAX_SIZE_PARAMETER`].
pub fn compute_efficiencies_perfect_conductor(x: f64) -> Result<Efficiencies, MieError> {
    if !(MIN_PERFECT_CONDUCTOR_SIZE_PARAMETER..=MAX_SIZE_PARAMETER).contains(&x) {
        return Err(MieError::InvalidSizeParameter(x));
    }
    let n_terms = series_length_converged(x);
    // psi_n(x) upward while oscillatory (n < x), by ratios beyond (see
    // coefficients.rs): ratio[k] = psi_k / psi_{k-1} for k > n_switch.
    let n_switch = (x as usize).min(n_terms);
    let mut ratio = vec![0.0; n_terms + 2];
    let mut current = x * scaled_ratio_continued_fraction_real(x * x, n_terms + 1);
    ratio[n_terms + 1] = current;
    for n in (n_switch.max(1)..=n_terms).rev() {
        current = x / ((2 * n + 1) as f64 - x * current);
        ratio[n] = current;
    }
    let inverse_x = 1.0 / x;
    let (sin_x, cos_x) = x.sin_cos();
    let mut psi_previous = sin_x;
    let mut psi = if n_switch == 0 {
        sin_x * ratio[1]
    } else {
        sin_x * inverse_x - cos_x
    };
    let mut chi_previous = cos_x;
    let mut chi = cos_x * inverse_x + sin_x;

    let mut scattering = 0.0;
    let mut backscattering = Complex64::new(0.0, 0.0);
    let mut adjacent = 0.0;
    let mut cross = 0.0;
    let (mut previous_a, mut previous_b) = (Complex64::new(0.0, 0.0), Complex64::new(0.0, 0.0));
    for n in 1..=n_terms {
        let nf = n as f64;
        let step = (2.0 * nf + 1.0) * inverse_x;
        let psi_next = if n < n_switch {
            step * psi - psi_previous
        } else {
            psi * ratio[n + 1]
        };
        let chi_next = step * chi - chi_previous;
        let xi = Complex64::new(psi, -chi);
        let xi_next = Complex64::new(psi_next, -chi_next);
        let slope = (nf + 1.0) * inverse_x;
        let a = (psi_next - slope * psi) / (xi_next - xi * slope);
        let b = psi / xi;
        let weight = 2.0 * nf + 1.0;
        scattering += weight * (a.norm_sqr() + b.norm_sqr());
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        backscattering += (a - b) * (sign * weight);
        adjacent +=
            (nf - 1.0) * (nf + 1.0) / nf * (previous_a * a.conj() + previous_b * b.conj()).re;
        cross += weight / (nf * (nf + 1.0)) * (a * b.conj()).re;
        previous_a = a;
        previous_b = b;
        psi_previous = psi;
        psi = psi_next;
        chi_previous = chi;
        chi = chi_next;
    }
    let qsca = 2.0 * inverse_x * inverse_x * scattering;
    Ok(Efficiencies {
        qext: qsca,
        qsca,
        qabs: 0.0,
        qback: inverse_x * inverse_x * backscattering.norm_sqr(),
        g: if scattering > 0.0 {
            2.0 * (adjacent + cross) / scattering
        } else {
            0.0
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small perfect conductors: Q_sca -> (10/3) x^4 and g -> -2/5 (the
    /// electric and magnetic dipoles of a conductor, B&H sec. 5.x / Jackson
    /// 10.1), with O(x^2) corrections.
    #[test]
    fn small_conductor_has_its_dipole_limit() {
        for x in [1e-6, 1e-4, 1e-2] {
            let q = compute_efficiencies_perfect_conductor(x).unwrap();
            assert!(
                (q.qsca / (10.0 / 3.0 * x.powi(4)) - 1.0).abs() < 2.0 * x * x,
                "x = {x}: {q:?}"
            );
            assert!((q.g + 0.4).abs() < x * x, "x = {x}: g = {}", q.g);
            assert_eq!(q.qabs, 0.0);
        }
    }

    #[test]
    fn large_conductor_reaches_the_extinction_paradox() {
        let q = compute_efficiencies_perfect_conductor(2e4).unwrap();
        assert!((q.qext - 2.0).abs() < 1e-3 && q.qext > 2.0, "{q:?}");
        // Geometric optics: a perfect mirror backscatters like a sphere of
        // reflectance 1.
        assert!((q.qback - 1.0).abs() < 1e-3, "{q:?}");
    }

    #[test]
    fn invalid_size_parameters_are_rejected() {
        for x in [0.0, -1.0, 1e-7, f64::NAN, f64::INFINITY, 2e6] {
            assert!(
                compute_efficiencies_perfect_conductor(x).is_err(),
                "x = {x}"
            );
        }
    }
}
