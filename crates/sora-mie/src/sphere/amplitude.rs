//! Amplitude functions S1, S2 and the phase matrix elements S11, S12.
//!
//! B&H eq. 4.74: S1 = sum_n (2n+1)/(n(n+1)) (a_n pi_n + b_n tau_n),
//! S2 = sum_n (2n+1)/(n(n+1)) (a_n tau_n + b_n pi_n), with the angular
//! functions of mu = cos(theta) (B&H eq. 4.47)
//!
//! ```text
//! pi_0 = 0, pi_1 = 1,  pi_{n+1} = ((2n+1) mu pi_n - (n+1) pi_{n-1}) / n
//! tau_n = n mu pi_n - (n+1) pi_{n-1}
//! ```
//!
//! The upward recurrence is stable at every angle (pi_n and tau_n are bounded
//! by n(n+1)/2, reached in the forward and backward directions). It is
//! evaluated in Wiscombe's (1979, MIEV0) arrangement s = mu pi_n,
//! t = s - pi_{n-1}, tau_n = n t - pi_{n-1}, pi_{n+1} = s + t + t/n, where
//! the rounded 1/n only touches the small correction t/n: multiplying the
//! whole right-hand side by a rounded 1/n instead accumulates a relative
//! error of 2e-11 in pi_n(1) by n = 1e4, while this form is exact at
//! mu = +-1 and as good elsewhere (checked against 40-digit arithmetic).
//! Evaluating
//! many angles, the loops run over blocks of [`LANES`] angles inside the loop
//! over n, so that the per-n work (weights, divisions, the coefficient loads)
//! is shared and the per-angle work is a straight line the compiler can
//! vectorise, all on the stack.

use crate::Complex64;

/// Angles processed together by the table functions.
const LANES: usize = 8;

/// (S1, S2) at `mu` from coefficient slices (index 0 is n = 1).
pub(super) fn amplitudes(a: &[Complex64], b: &[Complex64], mu: f64) -> (Complex64, Complex64) {
    let mut s1 = [Complex64::new(0.0, 0.0); 1];
    let mut s2 = [Complex64::new(0.0, 0.0); 1];
    amplitudes_block::<1>(a, b, &[mu], &mut s1, &mut s2);
    (s1[0], s2[0])
}

/// (S11, S12) = ((|S1|^2 + |S2|^2)/2, (|S2|^2 - |S1|^2)/2), B&H eq. 4.77.
pub(super) fn s11_s12_from_amplitudes(s1: Complex64, s2: Complex64) -> (f64, f64) {
    let (n1, n2) = (s1.norm_sqr(), s2.norm_sqr());
    (0.5 * (n1 + n2), 0.5 * (n2 - n1))
}

/// S11 and S12 at every mu of `mu` (equal lengths checked by the caller).
pub(super) fn s11_s12_table(
    a: &[Complex64],
    b: &[Complex64],
    mu: &[f64],
    s11: &mut [f64],
    s12: &mut [f64],
) {
    for_each_block(a, b, mu, |start, s1, s2| {
        for lane in 0..s1.len() {
            let (v11, v12) = s11_s12_from_amplitudes(s1[lane], s2[lane]);
            s11[start + lane] = v11;
            s12[start + lane] = v12;
        }
    });
}

/// (S1, S2) at every mu of `mu` (equal lengths checked by the caller):
/// each angle's the same numbers [`amplitudes`] gives it alone (the lanes
/// of a block do the same operations in the same order).
pub(super) fn amplitudes_table(
    a: &[Complex64],
    b: &[Complex64],
    mu: &[f64],
    s1: &mut [Complex64],
    s2: &mut [Complex64],
) {
    crate::simd::dispatch(AmplitudesTable { a, b, mu, s1, s2 });
}

/// [`amplitudes_table`] as a kernel of [`crate::simd`]: compiled for the
/// widest vectors the processor has, with the plain multiplications and
/// additions of [`amplitudes_block`] in every build (it takes no fused
/// multiply-adds), so the numbers do not depend on the build.
struct AmplitudesTable<'a> {
    a: &'a [Complex64],
    b: &'a [Complex64],
    mu: &'a [f64],
    s1: &'a mut [Complex64],
    s2: &'a mut [Complex64],
}

impl crate::simd::Kernel for AmplitudesTable<'_> {
    type Output = ();

    #[inline(always)]
    fn run<A: crate::simd::MultiplyAdd>(self) {
        let AmplitudesTable { a, b, mu, s1, s2 } = self;
        for_each_block(a, b, mu, |start, b1, b2| {
            s1[start..start + b1.len()].copy_from_slice(b1);
            s2[start..start + b2.len()].copy_from_slice(b2);
        });
    }
}

/// S11 alone at every mu of `mu`.
pub(super) fn s11_table(a: &[Complex64], b: &[Complex64], mu: &[f64], s11: &mut [f64]) {
    for_each_block(a, b, mu, |start, s1, s2| {
        for lane in 0..s1.len() {
            s11[start + lane] = s11_s12_from_amplitudes(s1[lane], s2[lane]).0;
        }
    });
}

/// Run the amplitude sums over `mu` in blocks of LANES angles and hand each
/// block's (first index, S1, S2) to `consume`.
#[inline(always)]
fn for_each_block<F: FnMut(usize, &[Complex64], &[Complex64])>(
    a: &[Complex64],
    b: &[Complex64],
    mu: &[f64],
    mut consume: F,
) {
    let mut chunks = mu.chunks_exact(LANES);
    let mut start = 0;
    let mut s1 = [Complex64::new(0.0, 0.0); LANES];
    let mut s2 = [Complex64::new(0.0, 0.0); LANES];
    for chunk in &mut chunks {
        let block: &[f64; LANES] = chunk.try_into().expect("chunks_exact yields LANES");
        amplitudes_block::<LANES>(a, b, block, &mut s1, &mut s2);
        consume(start, &s1, &s2);
        start += LANES;
    }
    for (offset, &m) in chunks.remainder().iter().enumerate() {
        let (v1, v2) = amplitudes(a, b, m);
        s1[offset] = v1;
        s2[offset] = v2;
    }
    let rest = chunks.remainder().len();
    consume(start, &s1[..rest], &s2[..rest]);
}

/// The sums of B&H eq. 4.74 for L angles at once.
#[inline(always)]
fn amplitudes_block<const L: usize>(
    a: &[Complex64],
    b: &[Complex64],
    mu: &[f64; L],
    s1: &mut [Complex64; L],
    s2: &mut [Complex64; L],
) {
    let mut pi_previous = [0.0; L]; // pi_{n-1}
    let mut pi = [1.0; L]; // pi_n
    let mut s1_re = [0.0; L];
    let mut s1_im = [0.0; L];
    let mut s2_re = [0.0; L];
    let mut s2_im = [0.0; L];
    for (index, (a_n, b_n)) in a.iter().zip(b).enumerate() {
        let n = (index + 1) as f64;
        let inverse_n = 1.0 / n;
        let inverse_n_plus_1 = 1.0 / (n + 1.0);
        // (2n+1)/(n(n+1)) = 1/n + 1/(n+1)
        let weight = inverse_n + inverse_n_plus_1;
        let (wa, wb) = (*a_n * weight, *b_n * weight);
        for lane in 0..L {
            let s = mu[lane] * pi[lane];
            let t = s - pi_previous[lane];
            let tau = n * t - pi_previous[lane];
            s1_re[lane] += wa.re * pi[lane] + wb.re * tau;
            s1_im[lane] += wa.im * pi[lane] + wb.im * tau;
            s2_re[lane] += wa.re * tau + wb.re * pi[lane];
            s2_im[lane] += wa.im * tau + wb.im * pi[lane];
            pi_previous[lane] = pi[lane];
            pi[lane] = s + t + t * inverse_n;
        }
    }
    for lane in 0..L {
        s1[lane] = Complex64::new(s1_re[lane], s1_im[lane]);
        s2[lane] = Complex64::new(s2_re[lane], s2_im[lane]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_amplitude_table_gives_each_angle_its_own_amplitudes_to_the_last_bit() {
        // 19 angles: two blocks of 8 and a remainder of 3.
        let terms = 40;
        let a: Vec<Complex64> = (0..terms)
            .map(|n| Complex64::new((0.3 * n as f64).sin() / (n + 1) as f64, 0.01 * n as f64))
            .collect();
        let b: Vec<Complex64> = (0..terms)
            .map(|n| Complex64::new((0.7 * n as f64).cos() / (n + 2) as f64, -0.02))
            .collect();
        let mu: Vec<f64> = (0..19).map(|k| -1.0 + 2.0 * k as f64 / 18.0).collect();
        let zero = Complex64::new(0.0, 0.0);
        let (mut s1, mut s2) = (vec![zero; mu.len()], vec![zero; mu.len()]);
        amplitudes_table(&a, &b, &mu, &mut s1, &mut s2);
        for (k, &m) in mu.iter().enumerate() {
            let (one, two) = amplitudes(&a, &b, m);
            assert_eq!((s1[k], s2[k]), (one, two), "mu {m}");
        }
        assert!(s1.iter().any(|s| s.norm() > 1.0));
    }

    #[test]
    fn angular_functions_have_their_forward_and_backward_values() {
        // With a single a_n = 1 (n = N) the sums isolate w_N pi_N and w_N tau_N;
        // pi_n(1) = tau_n(1) = n(n+1)/2, pi_n(-1) = (-1)^(n+1) n(n+1)/2,
        // tau_n(-1) = (-1)^n n(n+1)/2.
        for big_n in 1..=12usize {
            let mut a = vec![Complex64::new(0.0, 0.0); big_n];
            let b = vec![Complex64::new(0.0, 0.0); big_n];
            a[big_n - 1] = Complex64::new(1.0, 0.0);
            let n = big_n as f64;
            let weight = (2.0 * n + 1.0) / (n * (n + 1.0));
            let half = n * (n + 1.0) / 2.0;
            let (s1, s2) = amplitudes(&a, &b, 1.0);
            assert!(
                (s1.re - weight * half).abs() < 1e-12 * half,
                "pi_{big_n}(1)"
            );
            assert!(
                (s2.re - weight * half).abs() < 1e-12 * half,
                "tau_{big_n}(1)"
            );
            let sign = if big_n % 2 == 1 { 1.0 } else { -1.0 };
            let (s1, s2) = amplitudes(&a, &b, -1.0);
            assert!(
                (s1.re - sign * weight * half).abs() < 1e-12 * half,
                "pi_{big_n}(-1)"
            );
            assert!(
                (s2.re + sign * weight * half).abs() < 1e-12 * half,
                "tau_{big_n}(-1)"
            );
        }
    }

    #[test]
    fn table_agrees_with_single_angle_evaluation_including_the_remainder_block() {
        let a: Vec<Complex64> = (1..=20)
            .map(|n| Complex64::new(1.0 / n as f64, 0.3 / (n * n) as f64))
            .collect();
        let b: Vec<Complex64> = (1..=20)
            .map(|n| Complex64::new(-0.5 / n as f64, 0.1))
            .collect();
        let mu: Vec<f64> = (0..19).map(|i| (i as f64 * 0.17).cos()).collect();
        let (mut s11, mut s12) = (vec![0.0; mu.len()], vec![0.0; mu.len()]);
        s11_s12_table(&a, &b, &mu, &mut s11, &mut s12);
        let mut only_s11 = vec![0.0; mu.len()];
        s11_table(&a, &b, &mu, &mut only_s11);
        for (i, &m) in mu.iter().enumerate() {
            let (s1, s2) = amplitudes(&a, &b, m);
            let (v11, v12) = s11_s12_from_amplitudes(s1, s2);
            assert_eq!(s11[i], v11);
            assert_eq!(s12[i], v12);
            assert_eq!(only_s11[i], v11);
        }
    }
}
