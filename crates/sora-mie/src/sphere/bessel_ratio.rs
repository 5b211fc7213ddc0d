//! Ratios of Riccati-Bessel functions, the stable replacement for psi_n itself.
//!
//! psi_n(z) = z j_n(z) is the *minimal* solution of the three-term recurrence
//! psi_{n+1} = (2n+1)/z psi_n - psi_{n-1} (A&S 10.1.19): once n + 1/2 > |z|
//! it decays much faster than the other solution chi_n, so any rounding error
//! in an upward recurrence is amplified by chi_n / psi_n. The ratio
//!
//! ```text
//! rho_n(z) = psi_n(z) / psi_{n-1}(z) = z / (2n + 1 - z rho_{n+1}(z))
//! ```
//!
//! is computed *downward* instead, where errors contract: a perturbation of
//! rho_N is multiplied by (psi_N / psi_n)^2 on its way down to n. Its value at
//! the top of the table is Lentz's continued fraction (Lentz 1976,
//! "Generating Bessel functions in Mie scattering calculations using
//! continued fractions", Appl. Opt. 15, 668), here for the scaled ratio
//! rhot = rho / z, which tends to 1/(2n+1) as z -> 0:
//!
//! ```text
//! 1 / rhot_N = (2N+1) - z^2 / ((2N+3) - z^2 / ((2N+5) - ...))
//! ```
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
//!
//! Speed: both the fraction and the table are thousands of steps long for
//! large spheres, and the obvious forms (Lentz's algorithm, the ratio
//! recurrence above) put a complex division on the dependency chain of every
//! step (~30 cycles). Here neither does:
//! - the fraction is evaluated by the forward (Wallis) recurrence of its
//!   convergents A_j / B_j (Numerical Recipes 3rd ed. sec. 5.2), rescaled and
//!   tested for convergence (last two convergents agreeing to 1e-16) every 8
//!   terms; A_j and B_j are two solutions of the same linear recurrence, so
//!   the chain is a complex multiply-add;
//! - the table runs the *linear* recurrence u_{n-1} = (2n+1)/z u_n - u_{n+1}
//!   downward (the same minimal solution, Miller's algorithm, started from the
//!   fraction's ratio) and forms rho_n = u_n / u_{n-1} off the chain,
//!   rescaling u when it grows large.
//!
//! The rounding behaviour is that of the ratio recurrence (the two are the
//! same recurrence in exact arithmetic): the tests below compare with
//! 50-digit values.

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

/// Convergence threshold of the continued fraction: the last two
/// convergents of a block agreeing to this relative difference.
pub(super) const CONTINUED_FRACTION_TOLERANCE: f64 = 1e-16;

/// Terms of the continued fraction evaluated between convergence tests.
pub(super) const CONTINUED_FRACTION_BLOCK: usize = 8;

/// Most blocks of the continued fraction for an argument of modulus `size`:
/// convergence needs about |z| + 10 |z|^(1/3) + 50 terms at most (real z);
/// this cap (3 |z| + 2000 terms) only guards against an endless loop.
#[inline(always)]
pub(super) fn max_continued_fraction_blocks(size: f64) -> usize {
    ((3.0 * size + 2000.0).min(1e9) as usize) / CONTINUED_FRACTION_BLOCK + 1
}

/// The scaled ratio rhot_n(z) = psi_n(z) / (z psi_{n-1}(z)) by Lentz's
/// continued fraction, for n >= 1 and any complex z (given as z^2).
///
/// The number of terms adapts to z: a handful for |z| << n, about
/// |z| - n + 10 (|z|/2)^(1/3) for real z > n, fewer when Im(z) is large.
#[inline(always)]
pub(super) fn scaled_ratio_continued_fraction(z_squared: Complex64, n: usize) -> Complex64 {
    // 1/rhot = b_0 + a/(b_1 + a/(b_2 + ...)) with b_j = 2(n+j)+1, a = -z^2.
    // Convergents f_j = A_j / B_j with A_j = b_j A_{j-1} + a A_{j-2}, same for
    // B, from A_{-1} = 1, A_0 = b_0, B_{-1} = 0, B_0 = 1; we return B_j / A_j.
    // A and B share the coefficients, so they are carried as one lane array
    // [Re A, Im A, Re B, Im B] that the compiler keeps in one vector.
    let a = -z_squared;
    // a * p for a complex pair p = [re, im]: re = a.re p.re - a.im p.im,
    // im = a.re p.im + a.im p.re, i.e. a.re p[i] + sign[i] a.im p[i ^ 1].
    let signed_a_im = [-a.im, a.im, -a.im, a.im];
    let mut previous = [1.0, 0.0, 0.0, 0.0];
    let mut current = [(2 * n + 1) as f64, 0.0, 1.0, 0.0];
    let quotient =
        |v: &[f64; 4]| Complex64::new(v[2], v[3]) * reciprocal(Complex64::new(v[0], v[1]));
    let mut estimate = quotient(&current);
    let max_blocks = max_continued_fraction_blocks(z_squared.norm_sqr().sqrt().sqrt());
    let mut b_j = (2 * n + 1) as f64;
    for _ in 0..max_blocks {
        for _ in 0..CONTINUED_FRACTION_BLOCK {
            b_j += 2.0;
            let mut next = [0.0; 4];
            // The previous convergent's terms first: the chain through the
            // current one is then one multiply and one add.
            for i in 0..4 {
                next[i] =
                    current[i] * b_j + (a.re * previous[i] + signed_a_im[i] * previous[i ^ 1]);
            }
            previous = current;
            current = next;
        }
        // Rescale so that A_j stays near 1 (the convergents are ratios and
        // do not change; the scaling's own rounding is one ulp of a ratio).
        let magnitude = current[0].abs().max(current[1].abs());
        if !(1e-100..=1e100).contains(&magnitude) && magnitude > 0.0 && magnitude.is_finite() {
            let scale = 1.0 / magnitude;
            for i in 0..4 {
                previous[i] *= scale;
                current[i] *= scale;
            }
        }
        // Converged when the last two convergents agree to the tolerance:
        // past the turning region the fraction converges geometrically, and
        // in the oscillatory region consecutive convergents differ by O(1).
        estimate = quotient(&current);
        let change = (estimate - quotient(&previous)).norm_sqr();
        if change
            <= CONTINUED_FRACTION_TOLERANCE * CONTINUED_FRACTION_TOLERANCE * estimate.norm_sqr()
        {
            break;
        }
    }
    estimate
}

/// [`scaled_ratio_continued_fraction`] for a real argument (z^2 = x^2 > 0),
/// in real arithmetic: the same algorithm at half the cost, for the
/// exterior ratios psi_n(x)/psi_{n-1}(x).
#[inline(always)]
pub(super) fn scaled_ratio_continued_fraction_real(x_squared: f64, n: usize) -> f64 {
    let a = -x_squared;
    let mut a_previous = 1.0;
    let mut a_current = (2 * n + 1) as f64;
    let mut b_previous = 0.0;
    let mut b_current = 1.0;
    let mut estimate = b_current / a_current;
    let max_blocks = max_continued_fraction_blocks(x_squared.sqrt());
    let mut b_j = (2 * n + 1) as f64;
    for _ in 0..max_blocks {
        for _ in 0..CONTINUED_FRACTION_BLOCK {
            b_j += 2.0;
            let a_next = a_current * b_j + a * a_previous;
            let b_next = b_current * b_j + a * b_previous;
            a_previous = a_current;
            a_current = a_next;
            b_previous = b_current;
            b_current = b_next;
        }
        let magnitude = a_current.abs();
        if !(1e-100..=1e100).contains(&magnitude) && magnitude > 0.0 && magnitude.is_finite() {
            let scale = 1.0 / magnitude;
            a_previous *= scale;
            a_current *= scale;
            b_previous *= scale;
            b_current *= scale;
        }
        estimate = b_current / a_current;
        let change = (estimate - b_previous / a_previous).abs();
        if change <= CONTINUED_FRACTION_TOLERANCE * estimate.abs() {
            break;
        }
    }
    estimate
}

/// Growth of the unnormalised downward solutions beyond which
/// [`DownwardRatios::step`] and the batched solver (`batch.rs`) rescale them.
pub(super) const RESCALE_ABOVE: f64 = 1e100;

/// The downward recurrence of rho_n(z), n = top, top-1, ..., as a state
/// machine (so that the solver can interleave it with its upward
/// recurrences).
///
/// It runs the *linear* recurrence u_{n-1} = (2n+1)/z u_n - u_{n+1} for an
/// unnormalised psi_n(z), started from (u_{top-1}, u_top) = (1, rho_top), and
/// forms rho_n = u_n / u_{n-1} off the dependency chain; u is rescaled when it
/// grows past 1e100 (only ratios of neighbours are used).
pub(super) struct DownwardRatios {
    inverse_z: Complex64,
    inverse_z_squared: Complex64,
    /// u_{n+1}, u_n for the n of the next step.
    upper: Complex64,
    current: Complex64,
    /// 2n + 1 for the n of the next step, kept as a float (an integer
    /// conversion per step costs more than the recurrence's additions).
    two_n_plus_1: f64,
}

impl DownwardRatios {
    /// Start at `top` (>= 1): returns the state and rho_top(z) from the
    /// continued fraction.
    #[inline(always)]
    pub(super) fn start(z: Complex64, top: usize) -> (DownwardRatios, Complex64) {
        let first = z * scaled_ratio_continued_fraction(z * z, top);
        let inverse_z = reciprocal(z);
        let state = DownwardRatios {
            inverse_z,
            inverse_z_squared: inverse_z * inverse_z,
            upper: first,
            current: Complex64::new(1.0, 0.0),
            two_n_plus_1: (2 * top - 1) as f64,
        };
        (state, first)
    }

    /// rho_n(z) for the next n (top-1, top-2, ...), one step at a time: the
    /// plain form of the recurrence that [`Self::batch`] reorganises (kept
    /// as the tests' reference).
    #[cfg(test)]
    pub(super) fn step(&mut self) -> Complex64 {
        let lower = self.inverse_z * self.two_n_plus_1 * self.current - self.upper;
        let ratio = self.current * reciprocal(lower);
        self.upper = self.current;
        self.current = lower;
        if self.current.re.abs() > RESCALE_ABOVE || self.current.im.abs() > RESCALE_ABOVE {
            self.current *= 1.0 / RESCALE_ABOVE;
            self.upper *= 1.0 / RESCALE_ABOVE;
        }
        self.two_n_plus_1 -= 2.0;
        ratio
    }

    /// Eight steps at once: writes rho_n, ..., rho_{n-7} for the next n to
    /// `re[7], im[7]` down to `re[0], im[0]` (the recurrence is defined for
    /// any n, negative included, so a batch may run past n = 1).
    ///
    /// The chain runs as four leapfrog double steps,
    /// u_{n-1} = t_n u_n - u_{n+1} and, straight from the same pair,
    /// u_{n-2} = (t_{n-1} t_n - 1) u_n - t_{n-1} u_{n+1} with t_k = (2k+1)/z
    /// (so the dependency chain is one complex multiply-add per two steps;
    /// the coefficient t_{n-1} t_n - 1 = (4n^2 - 1)/z^2 - 1 is a real factor
    /// on 1/z^2, formed off the chain, and its rounding, one ulp of
    /// |t_{n-1} t_n| on u_n, is that of two single steps). They only record
    /// the unnormalised u; the eight ratios are then formed in
    /// one straight-line pass (vectorised), and the state is rescaled, if
    /// needed, only afterwards, so that every ratio is taken within one
    /// scale. Growth within a batch stays below ~1e60 for |z| >= 0.01 (and
    /// below the overflow of |u|^2 for any |z| the solver accepts), which the
    /// 1e20 threshold leaves room for.
    #[inline(always)]
    pub(super) fn batch(&mut self, re: &mut [f64; 8], im: &mut [f64; 8]) {
        // u[0] = u_n+1 (current), u[1..=8] = u_n, ..., u_{n-7}.
        let mut u_re = [0.0; 9];
        let mut u_im = [0.0; 9];
        u_re[0] = self.current.re;
        u_im[0] = self.current.im;
        for pair in 0..4 {
            let t_upper = self.inverse_z * self.two_n_plus_1;
            let t_lower = self.inverse_z * (self.two_n_plus_1 - 2.0);
            let coupling =
                self.inverse_z_squared * (self.two_n_plus_1 * (self.two_n_plus_1 - 2.0)) - 1.0;
            let lower = t_upper * self.current - self.upper;
            let lowest = coupling * self.current - t_lower * self.upper;
            u_re[2 * pair + 1] = lower.re;
            u_im[2 * pair + 1] = lower.im;
            u_re[2 * pair + 2] = lowest.re;
            u_im[2 * pair + 2] = lowest.im;
            self.upper = lower;
            self.current = lowest;
            self.two_n_plus_1 -= 4.0;
        }
        // rho = u_k / u_{k+1} = u_k conj(u_{k+1}) / |u_{k+1}|^2; slot 7 is
        // the highest n.
        for j in 0..8 {
            let (a_re, a_im) = (u_re[j], u_im[j]);
            let (b_re, b_im) = (u_re[j + 1], u_im[j + 1]);
            let norm = (b_re * b_re + b_im * b_im).max(f64::MIN_POSITIVE);
            let inverse = 1.0 / norm;
            re[7 - j] = (a_re * b_re + a_im * b_im) * inverse;
            im[7 - j] = (a_im * b_re - a_re * b_im) * inverse;
        }
        if self.current.re.abs() > BATCH_RESCALE_ABOVE
            || self.current.im.abs() > BATCH_RESCALE_ABOVE
            || self.upper.re.abs() > BATCH_RESCALE_ABOVE
            || self.upper.im.abs() > BATCH_RESCALE_ABOVE
        {
            let scale = 1.0 / self.current.norm_sqr().max(self.upper.norm_sqr()).sqrt();
            self.current *= scale;
            self.upper *= scale;
        }
    }
}

/// Rescaling threshold of [`DownwardRatios::batch`].
const BATCH_RESCALE_ABOVE: f64 = 1e20;

/// Fill `rho[n] = psi_n(z) / psi_{n-1}(z)` for n = 2..=top (test helper; the
/// solver interleaves [`DownwardRatios`] with its own loop).
#[cfg(test)]
pub(super) fn fill_ratios_downward(z: Complex64, top: usize, rho: &mut [Complex64]) {
    let (mut state, first) = DownwardRatios::start(z, top);
    rho[top] = first;
    for slot in rho[2..top].iter_mut().rev() {
        *slot = state.step();
    }
}

/// Fill `rhot[n] = psi_n(z) / (z psi_{n-1}(z))` for n = 1..=top, the scaled
/// ratio that stays O(1) as z -> 0 (for the small-x path, where top is at
/// most a handful: the plain ratio recurrence is used).
/// `rhot.len()` must exceed `top`.
#[inline(always)]
pub(super) fn fill_scaled_ratios_downward(z: Complex64, top: usize, rhot: &mut [Complex64]) {
    let rhot = &mut rhot[..=top];
    let z_squared = z * z;
    let mut current = scaled_ratio_continued_fraction(z_squared, top);
    rhot[top] = current;
    for (n, slot) in rhot.iter_mut().enumerate().take(top).skip(1).rev() {
        current = reciprocal(Complex64::new((2 * n + 1) as f64, 0.0) - z_squared * current);
        *slot = current;
    }
}

#[cfg(test)]
// The reference values are written as mpmath printed them (20 digits).
#[allow(clippy::excessive_precision)]
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
                // A few ulps: rho_2(7.5 + 0.3i) = 2.9 sits where psi_1 is
                // small, which multiplies the rounding of each step by ~3.
                let err = relative(rho[n], e);
                assert!(err < 2e-15, "z = {z}, n = {n}: {} vs {e} ({err:e})", rho[n]);
            }
        }
    }

    #[test]
    fn scaled_ratio_has_its_small_argument_limit() {
        // rhot_n(z) = 1/(2n+1) + z^2/((2n+1)^2 (2n+3)) + O(z^4).
        let z = c(1e-5, 2e-6);
        let mut rhot = vec![c(0.0, 0.0); 8];
        fill_scaled_ratios_downward(z, 7, &mut rhot);
        for (n, &value) in rhot.iter().enumerate().skip(1) {
            let k = (2 * n + 1) as f64;
            let expected = 1.0 / k + z * z / (k * k * (k + 2.0));
            let err = relative(value, expected);
            assert!(err < 3e-16, "n = {n}: {value} vs {expected} ({err:e})");
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

    /// The batched leapfrog chain and the single-step chain are the same
    /// recurrence: their ratios agree to rounding, across regimes (small,
    /// oscillatory, strongly absorbing, and tiny |z| where u grows by 1e7 a
    /// step and the batch must rescale).
    #[test]
    fn batched_steps_agree_with_single_steps() {
        for z in [
            c(7.5, 0.3),
            c(150.0, 1.0),
            c(2e5, 2e5),
            c(0.01, 0.0),
            c(1e-6, 1e-6),
        ] {
            let top = 97;
            let (mut single, _) = DownwardRatios::start(z, top);
            let (mut batched, _) = DownwardRatios::start(z, top);
            for _ in 0..11 {
                let (mut re, mut im) = ([0.0; 8], [0.0; 8]);
                batched.batch(&mut re, &mut im);
                for slot in (0..8).rev() {
                    let expected = single.step();
                    let err = relative(c(re[slot], im[slot]), expected);
                    assert!(err < 1e-13, "z = {z}: slot {slot}: {err:e}");
                }
            }
        }
    }

    #[test]
    fn real_continued_fraction_is_the_complex_one() {
        for (x, n) in [(0.3, 5), (12.0, 30), (12.0, 5), (1500.0, 1200)] {
            let real = scaled_ratio_continued_fraction_real(x * x, n);
            let complex = scaled_ratio_continued_fraction(c(x * x, 0.0), n);
            assert!(
                (real - complex.re).abs() <= 1e-14 * real.abs() && complex.im == 0.0,
                "x = {x}, n = {n}"
            );
        }
    }

    #[test]
    fn reciprocal_of_zero_is_finite() {
        let r = reciprocal(c(0.0, 0.0));
        assert!(r.re.is_finite() && r.im.is_finite());
    }
}
