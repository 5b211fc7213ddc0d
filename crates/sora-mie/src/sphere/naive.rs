//! Test oracle: Bohren & Huffman's BHMIE (B&H Appendix A), transcribed
//! plainly in f64, beside the optimised solver.
//!
//! Every step is the textbook one: D_n(mx) by the downward recurrence of
//! B&H eq. 4.89 from D = 0 at a start index far beyond both the series
//! length and |mx| (twice the larger, plus 50: the start error is then
//! crushed by many Airy units of decay), psi_n and chi_n by their upward
//! recurrences, a_n and b_n by eq. 4.88 with plain complex division, and the
//! sums of eqs. 4.61, 4.62, 4.74, 4.82. No ratios, no scaling, no shared
//! divisions: slower, and less accurate for x << 1 (the upward psi_n and the
//! eq. 4.88 numerators lose ~1e-16/x^2 there), but obviously the textbook.
//! It sums more terms than the fast path (x + 12 x^(1/3) + 10) so that the
//! two do not share a truncation choice either.

use crate::Complex64;

pub(super) struct NaiveSolution {
    pub a: Vec<Complex64>,
    pub b: Vec<Complex64>,
    pub qext: f64,
    pub qsca: f64,
    pub qback: f64,
    pub g: f64,
}

// Kept in BHMIE's index form, loop variables indexing the arrays.
#[allow(clippy::needless_range_loop)]
pub(super) fn bhmie(m: Complex64, x: f64) -> NaiveSolution {
    let n_terms = (x + 12.0 * x.cbrt() + 10.0) as usize;
    let mx = m * x;
    let start = 2 * n_terms.max(mx.norm() as usize) + 50;

    // Logarithmic derivative D_n(mx), n = 0..=start, downward from D = 0.
    let mut d = vec![Complex64::new(0.0, 0.0); start + 1];
    for n in (1..=start).rev() {
        let n_over_mx = n as f64 / mx;
        d[n - 1] = n_over_mx - 1.0 / (d[n] + n_over_mx);
    }

    // psi_{n-1}, psi_n and chi_{n-1}, chi_n, starting at n = 0 from n = -1.
    let mut psi_previous = x.cos();
    let mut psi = x.sin();
    let mut chi_previous = -x.sin();
    let mut chi = x.cos();
    let mut a = Vec::with_capacity(n_terms);
    let mut b = Vec::with_capacity(n_terms);
    for n in 1..=n_terms {
        let nf = n as f64;
        let psi_next = (2.0 * nf - 1.0) / x * psi - psi_previous;
        let chi_next = (2.0 * nf - 1.0) / x * chi - chi_previous;
        psi_previous = psi;
        psi = psi_next;
        chi_previous = chi;
        chi = chi_next;
        let xi = Complex64::new(psi, -chi);
        let xi_previous = Complex64::new(psi_previous, -chi_previous);
        let da = d[n] / m + nf / x;
        let db = m * d[n] + nf / x;
        a.push((da * psi - psi_previous) / (da * xi - xi_previous));
        b.push((db * psi - psi_previous) / (db * xi - xi_previous));
    }

    let mut qext = 0.0;
    let mut qsca = 0.0;
    let mut back = Complex64::new(0.0, 0.0);
    let mut g_sum = 0.0;
    for n in 1..=n_terms {
        let nf = n as f64;
        let (an, bn) = (a[n - 1], b[n - 1]);
        qext += (2.0 * nf + 1.0) * (an.re + bn.re);
        qsca += (2.0 * nf + 1.0) * (an.norm_sqr() + bn.norm_sqr());
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        back += (2.0 * nf + 1.0) * sign * (an - bn);
        g_sum += (2.0 * nf + 1.0) / (nf * (nf + 1.0)) * (an * bn.conj()).re;
        if n < n_terms {
            let (an1, bn1) = (a[n], b[n]);
            g_sum += nf * (nf + 2.0) / (nf + 1.0) * (an * an1.conj() + bn * bn1.conj()).re;
        }
    }
    let qext = 2.0 / (x * x) * qext;
    let qsca = 2.0 / (x * x) * qsca;
    NaiveSolution {
        a,
        b,
        qext,
        qsca,
        qback: back.norm_sqr() / (x * x),
        g: 4.0 / (x * x * qsca) * g_sum,
    }
}

/// S1, S2 by B&H eq. 4.74 with the pi_n, tau_n recurrences of eq. 4.47.
pub(super) fn naive_amplitudes(
    a: &[Complex64],
    b: &[Complex64],
    mu: f64,
) -> (Complex64, Complex64) {
    let mut pi_previous = 0.0;
    let mut pi = 1.0;
    let mut s1 = Complex64::new(0.0, 0.0);
    let mut s2 = Complex64::new(0.0, 0.0);
    for n in 1..=a.len() {
        let nf = n as f64;
        let tau = nf * mu * pi - (nf + 1.0) * pi_previous;
        let weight = (2.0 * nf + 1.0) / (nf * (nf + 1.0));
        s1 += weight * (a[n - 1] * pi + b[n - 1] * tau);
        s2 += weight * (a[n - 1] * tau + b[n - 1] * pi);
        let pi_next = ((2.0 * nf + 1.0) * mu * pi - (nf + 1.0) * pi_previous) / nf;
        pi_previous = pi;
        pi = pi_next;
    }
    (s1, s2)
}

#[cfg(test)]
mod tests {
    use super::super::{MieSolution, compute_efficiencies};
    use super::*;

    fn relative(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn oracle_reproduces_the_bohren_huffman_example() {
        // B&H Appendix A printout (single precision): m = 1.55, x = 5.213:
        // Qsca = 3.10543, Qback = 2.92534, g = 0.63314.
        let s = bhmie(Complex64::new(1.55, 0.0), 5.212_819_668_567_135);
        assert!((s.qsca - 3.10543).abs() < 1e-5);
        assert!((s.qback - 2.92534).abs() < 1e-5);
        assert!((s.g - 0.63314).abs() < 1e-5);
    }

    /// The fast path against the oracle over x in 0.1 ..= 1000 and seven
    /// refractive indices spanning bubbles, near matching, water, glass, soot
    /// and metal-like absorption.
    #[test]
    fn fast_path_agrees_with_the_oracle_across_the_grid() {
        let indices = [
            Complex64::new(0.75, 0.0),
            Complex64::new(1.0001, 0.0),
            Complex64::new(1.33, 1e-8),
            Complex64::new(1.5, 0.01),
            Complex64::new(1.75, 0.44),
            Complex64::new(2.5, 1.5),
            Complex64::new(10.0, 10.0),
        ];
        let mut worst = [0.0f64; 4];
        for &m in &indices {
            for step in 0..=48 {
                let x = 0.1 * 10f64.powf(step as f64 / 12.0);
                let oracle = bhmie(m, x);
                let fast = compute_efficiencies(m, x).unwrap();
                // The oracle's own error, which sets the tolerance (ours is
                // smaller: see the 100-digit reference tests). With
                // e = f64::EPSILON:
                // - eq. 4.88 numerators cancel to (1 - m^2) and, for x < 1,
                //   to x^2 of their terms: ~ e / (x^2 |m^2 - 1|) on a_n, b_n;
                //   sin x / x - cos x loses ~3 e / x^2 on psi_1;
                // - g also needs a_2, whose upward psi_2 loses ~45 e / x^4,
                //   and b_1, whose numerator cancels psi_1's ~3 e / x^2 error
                //   down by another 15 / (x^2 |m^2 - 1|);
                // - sums of ~x terms accumulate ~x e (times the matching
                //   factor's leftover for m -> 1);
                // - Q_back is a cancelling sum: its rounding is
                //   e sum (2n+1)(|a_n| + |b_n|) / |sum (2n+1)(-1)^n (a_n - b_n)|,
                //   again with the matching leftover for m -> 1.
                let e = f64::EPSILON;
                let matching = 1.0 / (m * m - 1.0).norm();
                let x_small = x.min(1.0);
                let magnitude: f64 = oracle
                    .a
                    .iter()
                    .zip(&oracle.b)
                    .enumerate()
                    .map(|(i, (a, b))| (2 * i + 3) as f64 * (a.norm() + b.norm()))
                    .sum();
                let back_cancellation = magnitude / (oracle.qback.sqrt() * x);
                let q_error = e * (3.0 + 3.0 * matching) / (x_small * x_small)
                    + e * x * (1.0 + 0.01 * matching);
                let g_error = q_error + e * 45.0 * (1.0 + matching) / x_small.powi(4);
                let back_error = q_error + e * back_cancellation * (1.0 + 0.01 * matching);
                // Neither code can beat the conditioning of the quantity:
                // its change when x or m moves by one ulp (estimated by a
                // finite difference over 1e-8; a resonance, e.g. a_55 at
                // m = 1.33, x = 46.4, has d ln a / d ln x ~ 1e5).
                let conditioning = {
                    let h = 1e-8;
                    let dx = compute_efficiencies(m, x * (1.0 + h)).unwrap();
                    let dm = compute_efficiencies(m * (1.0 + h), x).unwrap();
                    let c = |f: fn(&super::super::Efficiencies) -> f64| {
                        let change = (f(&dx) - f(&fast)).abs().max((f(&dm) - f(&fast)).abs());
                        change / f(&fast).abs() / h * e
                    };
                    [c(|q| q.qext), c(|q| q.qsca), c(|q| q.qback), c(|q| q.g)]
                };
                let models = [q_error, q_error, back_error, g_error];
                let tolerances: [f64; 4] =
                    std::array::from_fn(|k| 10.0 * models[k] + 30.0 * conditioning[k] + 1e-14);
                let errors = [
                    relative(fast.qext, oracle.qext),
                    relative(fast.qsca, oracle.qsca),
                    relative(fast.qback, oracle.qback),
                    relative(fast.g, oracle.g),
                ];
                for (k, &e) in errors.iter().enumerate() {
                    if matching < 10.0 {
                        worst[k] = worst[k].max(e);
                    }
                    assert!(
                        e <= tolerances[k],
                        "m = {m}, x = {x}: quantity {k} differs by {e:e} (tolerance {:e}); fast {fast:?}",
                        tolerances[k]
                    );
                }
                // Amplitudes at a few angles, relative to the forward value.
                if x <= 200.0 {
                    let solution = MieSolution::compute(m, x).unwrap();
                    let (a, b) = solution.coefficients();
                    let forward = naive_amplitudes(&oracle.a, &oracle.b, 1.0).0.norm();
                    for &mu in &[1.0, 0.5, 0.0, -0.3, -1.0] {
                        let (s1, s2) = solution.amplitudes(mu);
                        let (o1, o2) = naive_amplitudes(&oracle.a, &oracle.b, mu);
                        let error = ((s1 - o1).norm() + (s2 - o2).norm()) / forward;
                        // Beyond n ~ x the oracle's upward psi_n is rounding
                        // noise of size e chi_n, which leaves every a_n, b_n
                        // there with an absolute error ~e: summed with the
                        // weights (2n+1)/2 of S(0), ~e n_terms^2.
                        let terms = oracle.a.len() as f64;
                        let tail = 10.0 * e * terms * terms / forward;
                        assert!(
                            error < tolerances[3] + tail,
                            "m = {m}, x = {x}, mu = {mu}: amplitude error {error:e}"
                        );
                        // Same coefficients through the naive angular sums.
                        let (n1, _) = naive_amplitudes(a, b, mu);
                        assert!((n1 - s1).norm() <= 1e-12 * forward);
                    }
                }
            }
        }
        eprintln!(
            "worst fast-vs-oracle relative differences, m away from 1 (qext, qsca, qback, g): {worst:?}"
        );
    }
}
