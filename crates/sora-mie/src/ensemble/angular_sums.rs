//! # The angular sums S11(theta) of the phase tables
//!
//! For each node of a radius rule, S11 = (|S1|^2 + |S2|^2) / 2
//! (dimensionless; B&H eq. 4.74, with pi_n, tau_n by the upward recurrences
//! of B&H eq. 4.47) at the 406 table angles, for several spheres of the same
//! size parameter at once (the reference indices of the index-interpolated
//! tables share their rule's nodes, so pi_n and tau_n are computed once per
//! node for all of them), and the weighted sums w S11 of a group of eight
//! nodes added into the per-wavelength tables. Both kernels are compiled
//! for AVX-512F with FMA, for AVX and portably ([`crate::simd`]); the
//! module docs ("Cost") say where the time goes.

use crate::simd::{self, MultiplyAdd};
use crate::sphere::SPHERE_LANES;

/// Constants of term n of the angular sums, for n = 1, 2, ...: the term
/// factor (2n+1)/(n(n+1)) of B&H eq. 4.74 and the ratios (2n+1)/n and
/// (n+1)/n of the pi_n recurrence (B&H eq. 4.47), tabulated once rather than
/// divided out in every angle block.
#[derive(Debug, Clone, Copy)]
pub(super) struct AngularTermConstants {
    n: f64,
    pub(super) term_factor: f64,
    pi_ratio_current: f64,
    pi_ratio_previous: f64,
}

impl AngularTermConstants {
    pub(super) fn new(index: usize) -> Self {
        let n = (index + 1) as f64;
        AngularTermConstants {
            n,
            term_factor: (2.0 * n + 1.0) / (n * (n + 1.0)),
            pi_ratio_current: (2.0 * n + 1.0) / n,
            pi_ratio_previous: (n + 1.0) / n,
        }
    }
}

/// The most spheres (reference indices at one size parameter) whose angular
/// sums [`accumulate_s11`] evaluates in one pass.
const MAX_SPHERES_PER_PASS: usize = 5;

/// S11 at each `cos_theta` of several spheres of the same size parameter
/// (their series have the same length `constants.len()`), added to
/// `s11[sphere * angles + angle]`. S11 = (|S1|^2 + |S2|^2) / 2 with
/// S1 = sum (2n+1)/(n(n+1)) (a_n pi_n + b_n tau_n), S2 likewise with pi and
/// tau exchanged (B&H eq. 4.74), pi_n and tau_n by the upward recurrences
/// (B&H eq. 4.47). `terms[n * spheres + sphere]` holds the sphere's term
/// factor times (a_n + b_n) and (a_n - b_n), [re, im, re, im]: S11 is
/// accumulated as U = S1 + S2 = sum (A + B)(pi + tau) and V = S1 - S2 =
/// sum (A - B)(pi - tau), two complex products per term instead of four, and
/// |S1|^2 + |S2|^2 = (|U|^2 + |V|^2) / 2.
///
/// Layout for speed: term-outer, angle-inner in blocks of angles whose
/// recurrences run side by side (independent chains, vector lanes), and
/// the angular functions pi_n, tau_n, which do not depend on the sphere, are
/// computed once for all the spheres (the reference indices of the
/// index-interpolated phase tables share the nodes of their rule). Compiled
/// for AVX-512F with FMA (fused multiply-adds: a different rounding, within
/// 2e-14 of the largest value) and for AVX (the portable build's operations:
/// bit-identical), selected at run time; in every build each sphere's sums
/// are those it would get alone (tested).
pub(super) fn accumulate_s11(
    cos_theta: &[f64],
    constants: &[AngularTermConstants],
    terms: &[[f64; 4]],
    spheres: usize,
    s11: &mut [f64],
) {
    assert!(
        terms.len() == constants.len() * spheres && s11.len() == cos_theta.len() * spheres,
        "accumulate_s11: table lengths"
    );
    simd::dispatch(AccumulateS11 {
        cos_theta,
        constants,
        terms,
        spheres,
        s11,
    })
}

/// The arguments of [`accumulate_s11`], as a kernel compiled for each
/// [`simd::Build`]: for AVX-512F and FMA, 8-wide vectors and 32 registers,
/// so that a block's recurrence state and sums stay in registers, and fused
/// multiply-adds (half the instructions of the sums; a different rounding,
/// within 2e-14 of the largest value of the other builds, tested); for AVX,
/// 4-wide vectors and three-operand instructions, the portable build's
/// operations (bit-identical, tested).
pub(super) struct AccumulateS11<'a> {
    pub(super) cos_theta: &'a [f64],
    pub(super) constants: &'a [AngularTermConstants],
    pub(super) terms: &'a [[f64; 4]],
    pub(super) spheres: usize,
    pub(super) s11: &'a mut [f64],
}

impl simd::Kernel for AccumulateS11<'_> {
    type Output = ();

    #[inline(always)]
    fn run<A: MultiplyAdd>(self) {
        accumulate_s11_with::<A>(
            self.cos_theta,
            self.constants,
            self.terms,
            self.spheres,
            self.s11,
        )
    }
}

/// Dispatch on the number of spheres (a compile-time count, so that the
/// per-sphere sums are unrolled into registers): one or two spheres in
/// blocks of 16 angles (two vectors per sum keep the pi recurrence, a chain
/// of three dependent operations per term, from setting the pace), more in
/// blocks of 8 (the sums of five spheres fill 20 of the 32 registers).
#[inline(always)]
fn accumulate_s11_with<A: MultiplyAdd>(
    cos_theta: &[f64],
    constants: &[AngularTermConstants],
    terms: &[[f64; 4]],
    spheres: usize,
    s11: &mut [f64],
) {
    let angles = cos_theta.len();
    let mut first = 0;
    while first < spheres {
        let count = (spheres - first).min(MAX_SPHERES_PER_PASS);
        let out = &mut s11[first * angles..(first + count) * angles];
        match count {
            1 => {
                accumulate_s11_spheres::<A, 1, 16>(cos_theta, constants, terms, spheres, first, out)
            }
            2 => {
                accumulate_s11_spheres::<A, 2, 16>(cos_theta, constants, terms, spheres, first, out)
            }
            3 => {
                accumulate_s11_spheres::<A, 3, 8>(cos_theta, constants, terms, spheres, first, out)
            }
            4 => {
                accumulate_s11_spheres::<A, 4, 8>(cos_theta, constants, terms, spheres, first, out)
            }
            _ => {
                accumulate_s11_spheres::<A, 5, 8>(cos_theta, constants, terms, spheres, first, out)
            }
        }
        first += count;
    }
}

/// [`accumulate_s11`] for spheres `first..first + S` of `spheres`, in blocks
/// of `B` angles.
#[inline(always)]
fn accumulate_s11_spheres<A: MultiplyAdd, const S: usize, const B: usize>(
    cos_theta: &[f64],
    constants: &[AngularTermConstants],
    terms: &[[f64; 4]],
    spheres: usize,
    first: usize,
    s11: &mut [f64],
) {
    let angles = cos_theta.len();
    for block_start in (0..angles).step_by(B) {
        let block_len = B.min(angles - block_start);
        let mut mu = [0.0; B];
        mu[..block_len].copy_from_slice(&cos_theta[block_start..block_start + block_len]);
        // pi_0 = 0, pi_1 = 1.
        let mut pi_previous = [0.0; B];
        let mut pi_current = [1.0; B];
        let mut u_re = [[0.0; B]; S];
        let mut u_im = [[0.0; B]; S];
        let mut v_re = [[0.0; B]; S];
        let mut v_im = [[0.0; B]; S];
        let fma = A::mul_add;
        for (term, sphere_terms) in constants.iter().zip(terms.chunks_exact(spheres)) {
            let n = term.n;
            let mut pi_plus_tau = [0.0; B];
            let mut pi_minus_tau = [0.0; B];
            for i in 0..B {
                let pi = pi_current[i];
                let mu_pi = mu[i] * pi;
                let tau = fma(n, mu_pi, -((n + 1.0) * pi_previous[i]));
                pi_plus_tau[i] = pi + tau;
                pi_minus_tau[i] = pi - tau;
                let pi_next = fma(
                    term.pi_ratio_current,
                    mu_pi,
                    -(term.pi_ratio_previous * pi_previous[i]),
                );
                pi_previous[i] = pi;
                pi_current[i] = pi_next;
            }
            for s in 0..S {
                let [sum_re, sum_im, difference_re, difference_im] = sphere_terms[first + s];
                for i in 0..B {
                    u_re[s][i] = fma(sum_re, pi_plus_tau[i], u_re[s][i]);
                    u_im[s][i] = fma(sum_im, pi_plus_tau[i], u_im[s][i]);
                    v_re[s][i] = fma(difference_re, pi_minus_tau[i], v_re[s][i]);
                    v_im[s][i] = fma(difference_im, pi_minus_tau[i], v_im[s][i]);
                }
            }
        }
        for s in 0..S {
            let out = &mut s11[s * angles + block_start..s * angles + block_start + block_len];
            for (i, value) in out.iter_mut().enumerate() {
                let sum = fma(
                    u_re[s][i],
                    u_re[s][i],
                    fma(
                        u_im[s][i],
                        u_im[s][i],
                        fma(v_re[s][i], v_re[s][i], v_im[s][i] * v_im[s][i]),
                    ),
                );
                *value = fma(0.25, sum, *value);
            }
        }
    }
}

/// For each wavelength w: `tables[w][i] += weights[w][0] S_0[i] +
/// weights[w][1] S_1[i] + ...`, added in that order, where node l's S11 row
/// is `s11[first + l * stride..]` (l < `nodes`) and a table has
/// `tables.len() / weights.len()` angles. Angle-chunk outer, wavelength
/// inner, so that the nodes' rows are read once per chunk (not once per
/// wavelength) and each table entry is loaded and stored once. Compiled for
/// AVX-512F and AVX as well ([`AddWeightedGroup`]; bit-identical: no FMA).
pub(super) fn add_weighted_group(
    tables: &mut [f64],
    s11: &[f64],
    first: usize,
    stride: usize,
    nodes: usize,
    weights: &[[f64; SPHERE_LANES]],
) {
    simd::dispatch(AddWeightedGroup {
        tables,
        s11,
        first,
        stride,
        nodes,
        weights,
    })
}

/// The arguments of [`add_weighted_group`], as a kernel compiled for each
/// [`simd::Build`] (no multiply-add is fused: every build performs the same
/// operations).
pub(super) struct AddWeightedGroup<'a> {
    pub(super) tables: &'a mut [f64],
    pub(super) s11: &'a [f64],
    pub(super) first: usize,
    pub(super) stride: usize,
    pub(super) nodes: usize,
    pub(super) weights: &'a [[f64; SPHERE_LANES]],
}

impl simd::Kernel for AddWeightedGroup<'_> {
    type Output = ();

    #[inline(always)]
    fn run<A: MultiplyAdd>(self) {
        let AddWeightedGroup {
            tables,
            s11,
            first,
            stride,
            nodes,
            weights,
        } = self;
        const CHUNK: usize = 16;
        let angles = tables.len() / weights.len();
        for chunk_start in (0..angles).step_by(CHUNK) {
            let chunk_length = CHUNK.min(angles - chunk_start);
            // The nodes' values on this chunk (zero beyond `nodes` and the end,
            // where the weights are zero too: they add exactly +0).
            let mut rows = [[0.0; CHUNK]; SPHERE_LANES];
            for (node, row) in rows.iter_mut().enumerate().take(nodes) {
                let start = first + node * stride + chunk_start;
                copy_prefix(row, &s11[start..start + chunk_length]);
            }
            for (table, node_weights) in tables.chunks_exact_mut(angles).zip(weights) {
                let entries = &mut table[chunk_start..chunk_start + chunk_length];
                let mut sums = [0.0; CHUNK];
                copy_prefix(&mut sums, entries);
                for (row, &weight) in rows.iter().zip(node_weights) {
                    for (sum, &value) in sums.iter_mut().zip(row) {
                        *sum += weight * value;
                    }
                }
                if let Ok(entries) = <&mut [f64; CHUNK]>::try_from(&mut *entries) {
                    *entries = sums;
                } else {
                    entries.copy_from_slice(&sums[..chunk_length]);
                }
            }
        }
    }
}

/// `destination[..source.len()] = source`, as a fixed-size copy when the
/// lengths match (a variable-length copy is a call to memmove).
#[inline(always)]
fn copy_prefix<const N: usize>(destination: &mut [f64; N], source: &[f64]) {
    if let Ok(full) = <&[f64; N]>::try_from(source) {
        *destination = *full;
    } else {
        destination[..source.len()].copy_from_slice(source);
    }
}
