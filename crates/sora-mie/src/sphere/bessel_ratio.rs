//! Ratios of Riccati-Bessel functions, the stable replacement for psi_n itself.
//!
//! psi_n(z) = z j_n(z) is the *minimal* solution of the three-term recurrence
//! psi_{n+1} = (2n+1)/z psi_n - psi_{n-1} (B&H eq. 4.89): once n + 1/2 > |z|
//! it decays much faster than the other solution chi_n, so any rounding error
//! in an upward recurrence is amplified by chi_n / psi_n. The ratio
//!
//! ```text
//! rho_n(z) = psi_n(z) / psi_{n-1}(z) = z / (2n + 1 - z rho_{n+1}(z))
//! ```
//!
//! obeys a *downward* recurrence that contracts errors instead: a perturbation
//! of rho_N is multiplied by (psi_N / psi_n)^2 on its way down to n (the
//! derivative of the map is rho_n^2). It is also the continued fraction of
//! Lentz (1976, "Generating Bessel functions in Mie scattering calculations
//! using continued fractions", Appl. Opt. 15, 668):
//!
//! ```text
//! 1 / rhot_N = (2N+1) - z^2 / ((2N+3) - z^2 / ((2N+5) - ...)),   rhot = rho / z,
//! ```
//!
//! which we evaluate top-down with the modified Lentz algorithm (Thompson &
//! Barnett 1986), stopping when a convergent changes by less than 1e-16. The
//! scaled ratio rhot_n(z) = rho_n(z) / z -> 1/(2n+1) as z -> 0 is O(1) for any
//! small z, which is what the small-x path needs; the large-x path uses rho_n.
//!
//! The logarithmic derivative of B&H eq. 4.88 follows from the ratio:
//! D_n(z) = psi_n'(z)/psi_n(z) = (n+1)/z - rho_{n+1}(z) (from
//! psi_n' = (n+1)/z psi_n - psi_{n+1}, A&S 10.1.22). Working with rho instead
//! of D lets the (n+1)/z terms cancel analytically in b_n, which is what keeps
//! small spheres accurate (see `coefficients.rs`).
//!
//! Why a continued fraction to start the recurrence rather than Wiscombe's
//! start index max(n_stop, |mz|) + 15 from D = 0: the error of that start
//! shrinks by (psi_N / psi_n)^2, and for real |mz| >> 1 fifteen steps past the
//! turning point are only ~15 / (|mz|/2)^(1/3) Airy units: at |mz| = 1.5e4 the
//! error at the turning point is still ~1e-2. The continued fraction knows
//! when it has converged: for weakly absorbing spheres it runs past the turning
//! point by ~10 Airy units, for strongly absorbing ones (where psi_n(z) decays
//! like exp(-n^2 Im(z) / 2|z|^2) long before the turning point) it stops after
//! a few hundred terms even at |mz| = 3e5, where a start beyond |mz| would
//! cost 3e5 steps.

use crate::Complex64;

/// 1/q with a single real division (conj(q) / |q|^2).
///
/// |q|^2 cannot overflow here (|q| stays far below 1e150 in every recurrence
/// of this module); an exact zero, which would need an exact cancellation in a
/// recurrence denominator, is replaced by the smallest normal number so that
/// nothing downstream becomes infinite or NaN.
#[inline(always)]
pub(super) fn reciprocal(q: Complex64) -> Complex64 {
    let mut norm = q.re * q.re + q.im * q.im;
    if norm < f64::MIN_POSITIVE {
        norm = f64::MIN_POSITIVE;
    }
    let s = 1.0 / norm;
    Complex64::new(q.re * s, -q.im * s)
}

/// Convergence threshold of the continued fraction: |Delta_j - 1| below it
/// means the next convergents agree to about one ulp.
const CONTINUED_FRACTION_TOLERANCE: f64 = 1e-16;

/// The scaled ratio rhot_n(z) = psi_n(z) / (z psi_{n-1}(z)) by Lentz's
/// continued fraction, for n >= 1 and any complex z (given as z^2), evaluated
/// with the modified Lentz algorithm (Numerical Recipes 3rd ed. sec. 5.2).
///
/// The number of terms adapts to z: a handful for |z| << n, about
/// |z| - n + 10 (|z|/2)^(1/3) for real z > n, fewer when Im(z) is large.
pub(super) fn scaled_ratio_continued_fraction(z_squared: Complex64, n: usize) -> Complex64 {
    // f = b_0 + a/(b_1 + a/(b_2 + ...)) with b_j = 2(n+j)+1, a = -z^2.
    const TINY: f64 = 1e-300;
    let a = -z_squared;
    let b0 = (2 * n + 1) as f64;
    let mut f = Complex64::new(b0, 0.0);
    let mut c = f;
    let mut d = Complex64::new(0.0, 0.0);
    // Convergence needs at most ~ |z| + 10 |z|^(1/3) + 50 terms (real z); the
    // cap only guards against an infinite loop on non-finite input.
    let size = z_squared.norm().sqrt();
    let max_terms = (2.0 * size + 20.0 * size.cbrt() + 1000.0).min(1e9) as usize;
    for j in 1..=max_terms {
        let b = (2 * (n + j) + 1) as f64;
        d = a * d + b;
        if d.re == 0.0 && d.im == 0.0 {
            d = Complex64::new(TINY, 0.0);
        }
        c = a / c + b;
        if c.re == 0.0 && c.im == 0.0 {
            c = Complex64::new(TINY, 0.0);
        }
        d = reciprocal(d);
        let delta = c * d;
        f *= delta;
        if (delta.re - 1.0).abs() + delta.im.abs() < CONTINUED_FRACTION_TOLERANCE {
            break;
        }
    }
    reciprocal(f)
}

/// Fill `rho[n] = psi_n(z) / psi_{n-1}(z)` for n = 2..=top by the downward
/// recurrence, started from the continued fraction at n = top.
/// `rho[0]` and `rho[1]` are not touched. `rho.len()` must exceed `top`.
pub(super) fn fill_ratios_downward(z: Complex64, top: usize, rho: &mut [Complex64]) {
    let rho = &mut rho[..=top];
    let w = reciprocal(z);
    let mut current = z * scaled_ratio_continued_fraction(z * z, top);
    rho[top] = current;
    // The loop is one dependent chain of complex reciprocals: its latency
    // (~30 cycles a step) is what bounds the whole solver for large x.
    for n in (2..top).rev() {
        current = reciprocal(w * (2 * n + 1) as f64 - current);
        rho[n] = current;
    }
}

/// Fill `rhot[n] = psi_n(z) / (z psi_{n-1}(z))` for n = 1..=top, the scaled
/// ratio that stays O(1) as z -> 0 (for the small-x path).
/// `rhot.len()` must exceed `top`.
pub(super) fn fill_scaled_ratios_downward(z: Complex64, top: usize, rhot: &mut [Complex64]) {
    let rhot = &mut rhot[..=top];
    let z_squared = z * z;
    let mut current = scaled_ratio_continued_fraction(z_squared, top);
    rhot[top] = current;
    for n in (1..top).rev() {
        current = reciprocal(Complex64::new((2 * n + 1) as f64, 0.0) - z_squared * current);
        rhot[n] = current;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    fn relative(value: Complex64, reference: Complex64) -> f64 {
        (value - reference).norm() / reference.norm()
    }

    /// psi_n(z)/psi_{n-1}(z) from mpmath (50 digits, J_{n+1/2} ratios).
    #[test]
    fn ratios_match_mpmath_at_moderate_arguments() {
        let cases = [
            (
                c(0.75, 0.0),
                [
                    c(0.15247265737868964656, 0.0),
                    c(0.10811369597668981663, 0.0),
                ],
            ),
            (
                c(2.0, 0.0),
                [
                    c(0.45578540006610301813, 0.0),
                    c(0.30598500993017988876, 0.0),
                ],
            ),
            (
                c(7.5, 0.3),
                [
                    c(1.7950929679393874468, 2.2176909001322125861),
                    c(0.44508817409837049523, 0.24580240624832298205),
                ],
            ),
            (
                c(15.0, 15.0),
                [
                    c(0.064370546318094731257, 0.93325415676955180087),
                    c(0.093109313645871851485, 0.8997792374645688506),
                ],
            ),
        ];
        for (z, expected) in cases {
            let mut rho = vec![c(0.0, 0.0); 60];
            fill_ratios_downward(z, 59, &mut rho);
            for (k, &e) in expected.iter().enumerate() {
                let n = k + 2;
                let err = relative(rho[n], e);
                assert!(err < 4e-16, "z = {z}, n = {n}: {} vs {e} ({err:e})", rho[n]);
            }
        }
    }

    #[test]
    fn scaled_ratio_has_its_small_argument_limit() {
        // rhot_n(z) = 1/(2n+1) + z^2/((2n+1)^2 (2n+3)) + O(z^4).
        let z = c(1e-5, 2e-6);
        let mut rhot = vec![c(0.0, 0.0); 8];
        fill_scaled_ratios_downward(z, 7, &mut rhot);
        for n in 1..=7 {
            let k = (2 * n + 1) as f64;
            let expected = 1.0 / k + z * z / (k * k * (k + 2.0));
            let err = relative(rhot[n], expected);
            assert!(err < 3e-16, "n = {n}: {} vs {expected} ({err:e})", rhot[n]);
        }
    }

    /// Large arguments, against mpmath's downward recurrence in 50 digits
    /// started at n = 25000. For real z = 15000 the fraction at n = 10000
    /// must run past the turning point (~6000 terms). The tolerance is the
    /// conditioning of the value, not the algorithm: psi_9999(15000) is near
    /// a zero (rho = 29.75), where d ln(rho)/d ln(z) = z (D_n - D_{n-1}) ~ 4e5,
    /// so the 1-ulp uncertainty of z alone moves rho by ~5e-11; what the
    /// solver reaches (7e-13) is well inside that.
    #[test]
    fn continued_fraction_and_recurrence_are_accurate_for_large_arguments() {
        let cases = [
            (
                c(15000.0, 0.0),
                [
                    c(29.753036940234739906, 0.0),
                    c(3.0795818683773081767, 0.0),
                    c(-1.9884465783866105326, 0.0),
                ],
            ),
            (
                c(15000.0, 100.0),
                [
                    c(0.66268962806167346012, 0.74099108400545421914),
                    c(0.33253725297679777521, 0.9406067950209447444),
                    c(0.00013332734871299588534, 0.99999910670675772715),
                ],
            ),
        ];
        for (z, expected) in cases {
            let mut rho = vec![c(0.0, 0.0); 10_001];
            fill_ratios_downward(z, 10_000, &mut rho);
            for (n, e) in [10_000, 5_000, 2].into_iter().zip(expected) {
                let err = relative(rho[n], e);
                eprintln!("z = {z}, n = {n}: relative error {err:e}");
                assert!(err < 1e-11, "z = {z}, n = {n}: {} vs {e} ({err:e})", rho[n]);
            }
        }
    }

    #[test]
    fn strongly_absorbing_large_argument_stays_finite_and_tends_to_the_limit() {
        // D_n(z) -> -i as Im(z) -> infinity (B&H convention, Im m > 0), so
        // rho_{n+1} = (n+1)/z - D_n -> i for n << |z|.
        let z = c(2e5, 2e5);
        let mut rho = vec![c(0.0, 0.0); 21_001];
        fill_ratios_downward(z, 21_000, &mut rho);
        for n in [2, 100, 10_000, 21_000] {
            assert!(rho[n].re.is_finite() && rho[n].im.is_finite());
        }
        assert!((rho[2] - c(0.0, 1.0)).norm() < 1e-4);
    }

    #[test]
    fn reciprocal_of_zero_is_finite() {
        let r = reciprocal(c(0.0, 0.0));
        assert!(r.re.is_finite() && r.im.is_finite());
    }
}
