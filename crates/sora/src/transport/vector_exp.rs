//! exp(-x) for the hot loops' Beer-Lambert transmittances, written so
//! that the compiler vectorises a loop of them (the spherical first
//! order's, `multiple_scattering/spherical_first_order.rs`: one per
//! wavelength, sample, path and sun node, half of its time with the
//! standard library's scalar `exp`; the fast method's view marches', one
//! or three per wavelength and node), and e^y of either sign
//! ([`exp_in_place`]: the view march's source term, ln R - tau).
//!
//! Method (Tang's table-driven exponential, as libm's: Cody & Waite
//! range reduction against a table of 2^(j/32)): with n the integer
//! nearest 32 y / ln 2 (by the 1.5 2^52 shift, no rounding call),
//! r = y - n ln 2 / 32 in [-ln 2 / 64, ln 2 / 64] with ln 2 / 32 split in
//! a high part exact in 32 bits and a low part, e^r by its Taylor series
//! to degree 4 (truncation below 1.3e-12 relative: the transmittances'
//! other errors, of the quadratures, are 1e-3), and e^y = 2^(n div 32)
//! 2^((n mod 32) / 32) e^r, the first factor built from its exponent
//! bits, the second read from a table of 32 correctly rounded values.
//! Branch-free: y is clamped to [-708, 708] first, so every step is a
//! plain arithmetic, bit or load operation on f64 and u64 lanes (SSE2 has
//! them all). Relative error below 2e-12 over 0 <= x <= 700 (tested
//! against `f64::exp`); exp(-x) for x beyond 708 is returned as exp(-708) ~ 3e-308,
//! indistinguishable from zero in every sum it enters. Negative x (not
//! an optical depth) is clamped to 0.
//!
//! Why by hand: no crate offers a vectorisable f64 exp without pulling a
//! SIMD framework; the function is 30 lines.

/// exp(-x) (see the module docs).
#[inline(always)]
pub(crate) fn exp_neg(x: f64) -> f64 {
    exp_clamped(-x.clamp(0.0, 708.0))
}

/// e^y for y clamped to [-708, 708], one value (see the module docs): the
/// sun-column lookup's one per species, inlined where libm's is a call.
#[inline(always)]
pub(crate) fn exp(y: f64) -> f64 {
    exp_clamped(y)
}

/// e^y for y clamped to [-708, 708] (the same steps as [`exp_neg`], which
/// is e^-x with x clamped to [0, 708]; e^708 ~ 3e307 is finite).
#[inline(always)]
fn exp_clamped(y: f64) -> f64 {
    // 32 / ln 2.
    const STEPS_PER_LN2: f64 = TABLE_STEPS as f64 * std::f64::consts::LOG2_E;
    // ln 2 / 32 = STEP_HI + STEP_LO, STEP_HI with its low 32 mantissa
    // bits zero (so n * STEP_HI is exact for |n| < 2^20; |n| <= 32 * 708 /
    // ln 2 < 2^15): ln 2's split scaled by 1/32, exactly.
    const STEP_HI: f64 = 6.931_471_803_691_238e-1 / TABLE_STEPS as f64;
    const STEP_LO: f64 = 1.908_214_929_270_587_7e-10 / TABLE_STEPS as f64;
    // 1.5 * 2^52: adding it rounds to an integer held in the low bits.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    // Added to n's bits so that it is positive before the shift that
    // divides it by 32 (AVX2 shifts 64-bit lanes logically only).
    const BIAS: u64 = 1 << 20;
    let y = y.clamp(-708.0, 708.0);
    let shifted = y * STEPS_PER_LN2 + SHIFT;
    let n = shifted - SHIFT;
    let r = (y - n * STEP_HI) - n * STEP_LO;
    // e^r, Horner on 1/k!, k = 4 down to 1.
    let p = (((r * (1.0 / 24.0) + 1.0 / 6.0) * r + 0.5) * r + 1.0) * r + 1.0;
    // n + BIAS as an unsigned integer: its low 5 bits are n mod 32, the
    // rest floor(n / 32) + BIAS / 32.
    let biased = shifted
        .to_bits()
        .wrapping_sub(SHIFT.to_bits())
        .wrapping_add(BIAS);
    let fraction = TWO_TO_STEP[(biased % TABLE_STEPS) as usize];
    let exponent = (biased / TABLE_STEPS).wrapping_sub(BIAS / TABLE_STEPS);
    let scale = f64::from_bits(exponent.wrapping_add(1023) << 52);
    (fraction * p) * scale
}

/// The table's steps per factor 2 (a power of two).
const TABLE_STEPS: u64 = 32;

/// 2^(j / 32), j = 0..32, correctly rounded.
const TWO_TO_STEP: [f64; TABLE_STEPS as usize] = [
    1.0,
    1.0218971486541166,
    1.0442737824274138,
    1.0671404006768237,
    1.0905077326652577,
    1.1143867425958924,
    1.1387886347566916,
    1.1637248587775775,
    1.189207115002721,
    1.215247359980469,
    1.241857812073484,
    1.2690509571917332,
    1.2968395546510096,
    1.3252366431597413,
    1.3542555469368927,
    1.383909881963832,
    std::f64::consts::SQRT_2,
    1.4451808069770467,
    1.4768261459394993,
    1.5091644275934228,
    1.5422108254079407,
    1.5759808451078865,
    1.6104903319492543,
    1.645755478153965,
    1.681792830507429,
    1.718619298122478,
    1.7562521603732995,
    1.7947090750031072,
    1.8340080864093424,
    1.8741676341103,
    1.9152065613971474,
    1.9571441241754002,
];

/// Replaces each optical depth by its transmittance exp(-x), in place:
/// in AVX2's 4-lane registers where the CPU has them ([`wide`]), the same
/// bits as [`exp_neg_in_place_portable`].
pub(crate) fn exp_neg_in_place(values: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if wide::available() {
        wide::exp_neg_in_place(values);
        return;
    }
    exp_neg_in_place_portable(values);
}

/// Replaces each exponent y by e^y, in place (y clamped to [-708, 708]:
/// a logarithm of a radiance minus an optical depth, of either sign); in
/// AVX2's registers where the CPU has them, the same bits as
/// [`exp_in_place_portable`].
pub(crate) fn exp_in_place(values: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if wide::available() {
        wide::exp_in_place(values);
        return;
    }
    exp_in_place_portable(values);
}

/// Whether the hot loops may run in AVX2's registers (x86-64 with AVX2;
/// see [`wide`]): the view march's forward-peak integrals and the source
/// table's reads take their AVX2 twins then, the same bits.
#[inline(always)]
#[cfg_attr(not(any(target_arch = "x86_64", test)), allow(dead_code))]
pub(crate) fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        wide::available()
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Tests only: every loop that has an AVX2 twin takes its portable form
/// (the slow path; the numbers are the same bits, so tests running
/// meanwhile are not disturbed).
#[cfg(test)]
pub(crate) static PORTABLE_ONLY: std::sync::atomic::AtomicBool =
    std::sync::atomic::AtomicBool::new(false);

/// [`exp_neg_in_place`] in the target's baseline instructions (SSE2's
/// 2-lane registers on x86-64): the slow path the wide one is held to.
#[inline(always)]
pub(crate) fn exp_neg_in_place_portable(values: &mut [f64]) {
    for v in values {
        *v = exp_neg(*v);
    }
}

/// [`exp_in_place`] in the target's baseline instructions.
#[inline(always)]
pub(crate) fn exp_in_place_portable(values: &mut [f64]) {
    for v in values {
        *v = exp_clamped(*v);
    }
}

/// The same loops compiled for AVX2 (4 lanes of f64 instead of SSE2's 2),
/// chosen at run time: the default x86-64 target has SSE2 only, and the
/// engine tables' bake spends about a fifth of its time in these
/// exponentials (`docs/engine-tables.md`). AVX2 alone, not FMA: every lane
/// does the same IEEE operations in the same order as the portable loop
/// (Rust never fuses a multiply and an add on its own), so the results are
/// the same bits (tested).
#[cfg(target_arch = "x86_64")]
mod wide {
    /// Whether the CPU has AVX2 (the standard library caches the answer)
    /// and, in tests, [`super::PORTABLE_ONLY`] is not set.
    #[inline(always)]
    pub(crate) fn available() -> bool {
        #[cfg(test)]
        if super::PORTABLE_ONLY.load(std::sync::atomic::Ordering::Relaxed) {
            return false;
        }
        std::arch::is_x86_feature_detected!("avx2")
    }

    /// [`super::exp_neg_in_place_portable`] with AVX2; only where
    /// [`available`].
    pub(super) fn exp_neg_in_place(values: &mut [f64]) {
        debug_assert!(available());
        // SAFETY: the callers checked that the CPU has AVX2.
        unsafe { exp_neg_in_place_avx2(values) }
    }

    /// [`super::exp_in_place_portable`] with AVX2; only where [`available`].
    pub(super) fn exp_in_place(values: &mut [f64]) {
        debug_assert!(available());
        // SAFETY: the callers checked that the CPU has AVX2.
        unsafe { exp_in_place_avx2(values) }
    }

    #[target_feature(enable = "avx2")]
    fn exp_neg_in_place_avx2(values: &mut [f64]) {
        in_lanes(values, exp_neg_lanes);
    }

    #[target_feature(enable = "avx2")]
    fn exp_in_place_avx2(values: &mut [f64]) {
        in_lanes(values, exp_lanes);
    }

    /// `each` (one function applied to each of four values) over `values`
    /// four at a time, the last one to three values padded with zeros to
    /// a whole register: a loop over a slice of unknown length takes its
    /// tail one value at a time, and a tail (one of the wavelength grid's
    /// 21 values, two of 42) costs as much as a register of four. Every
    /// lane does the same operations whatever its neighbours, so the
    /// values are the same bits as the portable loop's.
    #[inline(always)]
    fn in_lanes(values: &mut [f64], each: fn(&mut [f64; 4])) {
        let mut chunks = values.chunks_exact_mut(4);
        for chunk in &mut chunks {
            let lanes: &mut [f64; 4] = chunk.try_into().expect("four values");
            each(lanes);
        }
        let tail = chunks.into_remainder();
        let n = tail.len();
        if n > 0 {
            let at = |k: usize| if k < n { tail[k] } else { 0.0 };
            let mut lanes = [at(0), at(1), at(2), 0.0];
            each(&mut lanes);
            // Lane by lane (a copy of unknown length is a call).
            for (k, lane) in lanes.into_iter().enumerate().take(3) {
                if k < n {
                    tail[k] = lane;
                }
            }
        }
    }

    #[inline(always)]
    fn exp_neg_lanes(lanes: &mut [f64; 4]) {
        for v in lanes {
            *v = super::exp_neg(*v);
        }
    }

    #[inline(always)]
    fn exp_lanes(lanes: &mut [f64; 4]) {
        for v in lanes {
            *v = super::exp_clamped(*v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Within 2e-12 of the standard library's exp over optical depths 0
    /// to 700 (dense near 0, where transmittances matter, and across the
    /// range reduction's half-integer boundaries), exactly 1 at 0, and
    /// the slice form equals the scalar one bit for bit.
    #[test]
    fn exp_neg_matches_the_standard_library() {
        let mut worst = 0.0f64;
        let mut depths: Vec<f64> = (0..200_000).map(|i| i as f64 * 3.5e-3).collect();
        depths.extend((1..2000).map(|i| i as f64 * 0.5 * std::f64::consts::LN_2));
        depths.extend([1e-300, 1e-17, 1e-9, 0.1, 1.0, 699.9]);
        for x in &depths {
            let want = (-x).exp();
            let got = exp_neg(*x);
            worst = worst.max(((got - want) / want).abs());
        }
        assert!(worst < 2e-12, "worst relative error {worst:e}");
        assert_eq!(exp_neg(0.0), 1.0);
        assert!(exp_neg(1e4) < 1e-307 && exp_neg(1e4) >= 0.0);
        assert_eq!(exp_neg(-3.0), 1.0);
        let mut slice = depths.clone();
        exp_neg_in_place(&mut slice);
        for (x, v) in depths.iter().zip(&slice) {
            assert_eq!(v.to_bits(), exp_neg(*x).to_bits());
        }
    }

    /// The table holds 2^(j / 32) (within one rounding of the standard
    /// library's exp2, which is not always correctly rounded), and 2^0
    /// and 2^(1/2) exactly.
    #[test]
    fn the_table_holds_the_powers_of_two() {
        for (j, value) in TWO_TO_STEP.iter().enumerate() {
            let want = (j as f64 / TABLE_STEPS as f64).exp2();
            assert!(
                ((value - want) / want).abs() <= 2.3e-16,
                "{j}: {value} vs {want}"
            );
        }
        assert_eq!(TWO_TO_STEP[0], 1.0);
        assert_eq!(TWO_TO_STEP[16], std::f64::consts::SQRT_2);
    }

    /// The signed form: within 2e-12 of the standard library's exp over
    /// -700..700, the same bits as exp_neg for y = -x <= 0, and e^y of a
    /// y beyond the range is e^(+-708).
    #[test]
    fn exp_in_place_matches_the_standard_library() {
        let ys: Vec<f64> = (-200_000..=200_000).map(|i| i as f64 * 3.5e-3).collect();
        let mut values = ys.clone();
        exp_in_place(&mut values);
        let mut worst = 0.0f64;
        for (y, v) in ys.iter().zip(&values) {
            worst = worst.max(((v - y.exp()) / y.exp()).abs());
            if *y <= 0.0 {
                assert_eq!(v.to_bits(), exp_neg(-y).to_bits(), "{y}");
            }
        }
        assert!(worst < 2e-12, "worst relative error {worst:e}");
        let mut far = [1e4, -1e4];
        exp_in_place(&mut far);
        assert!(far[0].is_finite() && far[0] > 1e307 && far[1] < 1e-307);
    }

    /// The AVX2 loops (where the CPU has AVX2) give the portable loops'
    /// bits, for every slice length's remainder and across the whole
    /// range, beyond it, and for the clamped negative depths.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_wide_loops_are_the_portable_loops_bit_for_bit() {
        if !wide::available() {
            eprintln!("no AVX2 here: nothing to compare");
            return;
        }
        let mut xs: Vec<f64> = (-300_000..=300_000).map(|i| i as f64 * 2.4e-3).collect();
        xs.extend([
            1e-300,
            -1e-300,
            1e4,
            -1e4,
            707.9,
            708.1,
            -708.1,
            f64::MIN_POSITIVE,
        ]);
        // Whole slices and short ones, and (the wide loops take a slice's
        // last one to three values in one register padded with zeros)
        // slices of every remainder from across the range.
        let mut slices: Vec<(usize, usize)> = [xs.len(), 1, 2, 3, 5, 7, 21, 22, 23]
            .into_iter()
            .map(|length| (0, length))
            .collect();
        for start in (0..xs.len() - 64).step_by(997) {
            slices.extend((1..=9).chain([21, 42]).map(|length| (start, length)));
        }
        slices.push((xs.len() - 3, 3));
        for (start, length) in slices {
            let xs = &xs[start..start + length];
            for (wide_loop, portable) in [
                (
                    wide::exp_neg_in_place as fn(&mut [f64]),
                    exp_neg_in_place_portable as fn(&mut [f64]),
                ),
                (wide::exp_in_place, exp_in_place_portable),
            ] {
                let (mut a, mut b) = (xs.to_vec(), xs.to_vec());
                wide_loop(&mut a);
                portable(&mut b);
                for ((x, a), b) in xs.iter().zip(&a).zip(&b) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{x}");
                }
            }
        }
    }
}
