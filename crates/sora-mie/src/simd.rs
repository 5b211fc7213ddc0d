//! # One source, three builds: run-time selection of the instruction set
//!
//! The crate's four hot kernels (the one-sphere series in
//! `sphere/coefficients.rs`, the eight-sphere series in `sphere/batch.rs`,
//! the angular sums S11(theta) and their weighted accumulation into the
//! phase tables in `ensemble/angular_sums.rs`) are plain Rust loops over
//! fixed-size arrays, written so that the compiler vectorises them. How fast
//! they run depends on the vector instructions the compiler may use, and the
//! widest ones are not on every CPU, so each kernel is compiled three times
//! from the same source and the build is chosen once per process from what
//! the CPU reports:
//!
//! | [`Build`] | instructions | a * b + c | results |
//! |---|---|---|---|
//! | [`Build::Avx512Fma`] | AVX-512F and FMA: 8 f64 a vector, 32 registers | fused, one rounding ([`Fused`]) | within ~1e-15 relative of the others (2e-14 of the largest S11; tested per kernel) |
//! | [`Build::Avx`] | AVX: 4 f64 a vector, three-operand instructions | two roundings ([`Unfused`]) | bit-identical to the portable build (tested) |
//! | [`Build::Portable`] | whatever the target is compiled for (SSE2 on x86-64, wasm32, aarch64, ...) | two roundings ([`Unfused`]) | the reference build |
//!
//! Why the AVX build is bit-identical to the portable one: Rust never
//! contracts `a * b + c` into a fused multiply-add by itself, and FMA is not
//! enabled in that build, so both perform the same IEEE operations in the
//! same order; only the register width and the instruction encoding differ.
//! The AVX-512 build enables FMA and the kernels' explicit multiply-adds
//! ([`MultiplyAdd::mul_add`]) become one instruction with one rounding:
//! the algorithm is the same, the rounding is not.
//!
//! How a kernel is written: its body is a generic function over
//! `A: MultiplyAdd`, marked `#[inline(always)]`; a small struct holding its
//! arguments implements [`Kernel`] by calling that body; [`dispatch`] (or
//! `run_as`, for the tests that compare builds) runs it. The three entry
//! points below carry the `#[target_feature]` attributes, and because the
//! body is inlined into them it is compiled with their instruction set.
//! On targets other than x86-64 only the portable build exists (the others
//! are compiled out, and [`Build::is_supported`] says so).

use std::sync::OnceLock;

/// How a kernel evaluates a * b + c.
pub(crate) trait MultiplyAdd {
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// Two roundings, a * b then + c: what every target computes at full speed.
pub(crate) struct Unfused;

impl MultiplyAdd for Unfused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}

/// One rounding (fused multiply-add): only for builds with the FMA
/// instruction set, where it is one instruction (elsewhere it is a slow
/// library call); compiled on x86-64 only.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Fused;

#[cfg(target_arch = "x86_64")]
impl MultiplyAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

/// The builds of a kernel (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Build {
    /// AVX-512F and FMA, fused multiply-adds (x86-64 only).
    Avx512Fma,
    /// AVX, unfused: the portable build's operations (x86-64 only).
    Avx,
    /// Any target, unfused.
    Portable,
}

impl Build {
    /// Every build, fastest first.
    #[cfg(test)]
    pub(crate) const ALL: [Build; 3] = [Build::Avx512Fma, Build::Avx, Build::Portable];

    /// Whether this CPU can run the build.
    pub(crate) fn is_supported(self) -> bool {
        match self {
            Build::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Build::Avx512Fma => {
                std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Build::Avx => std::arch::is_x86_feature_detected!("avx"),
            #[cfg(not(target_arch = "x86_64"))]
            Build::Avx512Fma | Build::Avx => false,
        }
    }

    /// The fastest build this CPU supports, detected on the first call.
    pub(crate) fn detected() -> Build {
        static DETECTED: OnceLock<Build> = OnceLock::new();
        *DETECTED.get_or_init(|| {
            [Build::Avx512Fma, Build::Avx]
                .into_iter()
                .find(|build| build.is_supported())
                .unwrap_or(Build::Portable)
        })
    }
}

/// A kernel compiled once per [`Build`]: `run` is the kernel's body for
/// multiply-add flavour `A`, and must be `#[inline(always)]` (and so must
/// what it calls on the hot path) so that it is compiled into each build's
/// entry point with that build's instruction set.
pub(crate) trait Kernel {
    type Output;
    fn run<A: MultiplyAdd>(self) -> Self::Output;
}

/// Runs `kernel` in the fastest build this CPU supports ([`Build::detected`]).
#[inline]
pub(crate) fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    run_supported(Build::detected(), kernel)
}

/// Runs `kernel` in `build`, which must be supported by this CPU
/// ([`Build::is_supported`]; panics otherwise): for comparing the builds.
#[cfg(test)]
pub(crate) fn run_as<K: Kernel>(build: Build, kernel: K) -> K::Output {
    assert!(
        build.is_supported(),
        "{build:?} is not supported by this CPU"
    );
    run_supported(build, kernel)
}

/// Runs `kernel` in `build`, which the caller has checked is supported.
#[inline(always)]
fn run_supported<K: Kernel>(build: Build, kernel: K) -> K::Output {
    match build {
        // SAFETY: the caller checked that the CPU supports AVX-512F and FMA,
        // the only requirements of `run_avx512_fma`.
        #[cfg(target_arch = "x86_64")]
        Build::Avx512Fma => unsafe { run_avx512_fma(kernel) },
        // SAFETY: the caller checked that the CPU supports AVX, the only
        // requirement of `run_avx`.
        #[cfg(target_arch = "x86_64")]
        Build::Avx => unsafe { run_avx(kernel) },
        _ => kernel.run::<Unfused>(),
    }
}

/// [`Build::Avx512Fma`]: the kernel compiled for AVX-512F and FMA, fused.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn run_avx512_fma<K: Kernel>(kernel: K) -> K::Output {
    kernel.run::<Fused>()
}

/// [`Build::Avx`]: the kernel compiled for AVX, unfused.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn run_avx<K: Kernel>(kernel: K) -> K::Output {
    kernel.run::<Unfused>()
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sum<'a>(&'a [f64]);

    impl Kernel for Sum<'_> {
        type Output = f64;
        #[inline(always)]
        fn run<A: MultiplyAdd>(self) -> f64 {
            self.0.iter().fold(0.0, |sum, &v| A::mul_add(v, v, sum))
        }
    }

    #[test]
    fn the_detected_build_is_supported_and_the_portable_one_always() {
        assert!(Build::detected().is_supported());
        assert!(Build::Portable.is_supported());
        let values: Vec<f64> = (0..100).map(|i| 1.0 / (i as f64 + 3.0)).collect();
        let portable = run_as(Build::Portable, Sum(&values));
        for build in Build::ALL.into_iter().filter(|b| b.is_supported()) {
            let sum = run_as(build, Sum(&values));
            if build == Build::Avx512Fma {
                assert!((sum - portable).abs() <= 1e-15 * portable, "{build:?}");
            } else {
                assert_eq!(sum, portable, "{build:?}");
            }
        }
        assert_eq!(
            dispatch(Sum(&values)),
            run_as(Build::detected(), Sum(&values))
        );
    }
}
