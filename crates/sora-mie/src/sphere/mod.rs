//! # One homogeneous sphere: Lorenz-Mie theory
//!
//! ## The model
//! A plane wave of wavelength lambda (in the medium) falls on a homogeneous,
//! isotropic sphere of radius r. Everything depends on two numbers:
//! - the refractive index m = n + i k *relative to the medium*, k >= 0 meaning
//!   absorption, with the time dependence exp(-i w t) of Bohren & Huffman
//!   (1983, "Absorption and Scattering of Light by Small Particles", hereafter
//!   B&H);
//! - the size parameter x = 2 pi r / lambda (dimensionless).
//!
//! The scattered field is a series of vector spherical harmonics whose
//! coefficients are (B&H eq. 4.53, 4.88)
//!
//! ```text
//! a_n = [m psi_n(mx) psi_n'(x) - psi_n(x) psi_n'(mx)] / [m psi_n(mx) xi_n'(x) - xi_n(x) psi_n'(mx)]
//! b_n = [psi_n(mx) psi_n'(x) - m psi_n(x) psi_n'(mx)] / [psi_n(mx) xi_n'(x) - m xi_n(x) psi_n'(mx)]
//! ```
//!
//! with the Riccati-Bessel functions psi_n(z) = z j_n(z), xi_n(z) = z h_n^(1)(z)
//! = psi_n(z) - i chi_n(z). From them (all dimensionless; an efficiency is a
//! cross-section divided by the geometric cross-section pi r^2):
//!
//! ```text
//! Q_ext  = (2/x^2) sum (2n+1) Re(a_n + b_n)                          (B&H 4.62)
//! Q_sca  = (2/x^2) sum (2n+1) (|a_n|^2 + |b_n|^2)                    (B&H 4.61)
//! Q_abs  = Q_ext - Q_sca, summed as (2/x^2) sum (2n+1) (Re a_n - |a_n|^2 + Re b_n - |b_n|^2)
//! Q_back = |sum (2n+1) (-1)^n (a_n - b_n)|^2 / x^2                   (B&H 4.82)
//! g      = (4/(x^2 Q_sca)) [sum n(n+2)/(n+1) Re(a_n a*_{n+1} + b_n b*_{n+1})
//!                           + sum (2n+1)/(n(n+1)) Re(a_n b*_n)]      (B&H sec. 4.5)
//! S1(theta) = sum (2n+1)/(n(n+1)) (a_n pi_n + b_n tau_n)              (B&H 4.74)
//! S2(theta) = sum (2n+1)/(n(n+1)) (a_n tau_n + b_n pi_n)
//! ```
//!
//! In cross-sections, C_sca = lambda^2/(2 pi) sum (2n+1)(|a_n|^2 + |b_n|^2) =
//! pi r^2 Q_sca (the paper's eq. 2 is misprinted, see `shared/paper/NOTES.md`).
//! The unpolarised phase function is S11 / (pi x^2 Q_sca) per steradian,
//! S11 = (|S1|^2 + |S2|^2)/2, and integrates to 1 over the sphere;
//! S12 = (|S2|^2 - |S1|^2)/2 (B&H eq. 4.77).
//!
//! ## The algorithms, and why
//! The aim is double-precision results (1e-12 typical, 1e-9 guaranteed against
//! 100-digit references) for x from 1e-6 to 2e4, m from 1.0001 (nearly index
//! matched) through 0.75 (bubbles) to 10 + 10i, with no allocation in the
//! efficiency path, and faster than the reference codes.
//!
//! - **Series length** ([`series_length_converged`]): Wiscombe's n_stop =
//!   x + 4 x^(1/3) + 2 (Wiscombe 1980, "Improved Mie scattering algorithms",
//!   Appl. Opt. 19, 1505) leaves terms of ~1e-7 out, visible in Q_back at the
//!   1e-6 level for x ~ 1000 and in g at 1e-6 for x ~ 0.1; we sum to
//!   x + 7.6 x^(1/3) + 3, where the terms are below 1e-18 (Airy argument
//!   ~9.6 past the turning point n ~ x).
//! - **Interior functions** (`bessel_ratio.rs`): not the logarithmic
//!   derivative D_n(mx) of B&H eq. 4.89 but the ratio
//!   rho_n(mx) = psi_n(mx)/psi_{n-1}(mx), with D_n = (n+1)/(mx) - rho_{n+1}.
//!   It is computed downward (stable: Kattawar & Plass 1967, Wiscombe 1980),
//!   started at the top of the series from Lentz's continued fraction (Lentz
//!   1976, Appl. Opt. 15, 668), which converges to full precision wherever it
//!   is started and costs only as many terms as the argument needs. BHMIE's
//!   start index max(n_stop, |mx|) + 15 from D = 0 is not converged for real
//!   |mx| >~ 1000 (the start error shrinks by only ~0.3 at |mx| = 1.5e4), and
//!   is needlessly far for strongly absorbing spheres (|mx| = 2.8e5 at
//!   m = 10 + 10i, x = 2e4, where the fraction stops after a few hundred
//!   terms). Because rho_n(mx) tends to a constant (i) instead of growing
//!   like psi_n(mx) ~ exp(Im(mx)), nothing overflows for large Im(m) x.
//! - **Exterior functions**: chi_n(x) by the upward three-term recurrence of
//!   the spherical Bessel functions (A&S 10.1.19; the dominant solution,
//!   stable); psi_n(x) upward while n < x (oscillatory, neutral), and from
//!   n = x on as products of ratios from the downward recurrence, since there
//!   the upward recurrence amplifies rounding by chi_n/psi_n (1e19 at x = 1,
//!   n = 11). For x < 1 also psi_1 comes from a ratio: sin x / x - cos x
//!   cancels to 1e-16/x^2.
//! - **Cancellation-free coefficients** (`coefficients.rs`): a_n, b_n written
//!   with psi_{n+1} instead of psi_{n-1}, so that the (n+1)/x terms of m D_n
//!   and psi_n'/psi_n cancel algebraically in b_n (B&H eq. 4.88 loses
//!   1e-16/x^2 there, which reaches g at leading order). Below x = 0.01
//!   every quantity is carried scaled by its power of x (a_n / x^3,
//!   psi_n / x^(n+1), ...), so that the solver stays exact to rounding and
//!   finite down to x = 1e-300.
//! - **Absorption directly**: Re a_n - |a_n|^2 = -Im(A_n)/|denominator|^2 by the
//!   Wronskian psi_n chi_{n+1} - psi_{n+1} chi_n = 1, so Q_abs is exactly 0 for
//!   real m and keeps its relative accuracy when Im(m) = 1e-8; Q_ext is then
//!   Q_sca + Q_abs, two sums of non-negative terms (the direct sum of
//!   Re(a_n + b_n) loses 1e-16/x^3 for small lossless spheres).
//! - **Speed** (`coefficients.rs`, `bessel_ratio.rs`): every recurrence of
//!   the x >= 0.01 path is arranged so that no division sits on a
//!   dependency chain. The fraction is evaluated by the forward (Wallis)
//!   recurrence of its convergents; the interior recurrence runs on
//!   unnormalised psi_n(mx) two steps at a time (a leapfrog form), forming
//!   the ratios in batches of eight; the exterior ratios run on an
//!   unnormalised linear recurrence too; the upward exterior recurrences run
//!   in the same loop as the interior one; and the coefficients and all five
//!   sums are computed in blocks of eight terms from structure-of-arrays
//!   tables, with one real division per term, in code the compiler
//!   vectorises. On x86-64 the solver is also compiled for AVX (the same
//!   operations: bit-identical results) and for AVX-512F with the blocks'
//!   multiply-adds fused (FMA: a different rounding, within ~1e-15 of the
//!   others), selected at run time.
//!   The tables
//!   (about 40 bytes a term) live on the stack up to x ~ 950 and in a
//!   reusable [`SphereWorkspace`] beyond.
//! - **Many spheres** (`batch.rs`, [`compute_efficiencies_many_with`]): the
//!   same algorithms vectorised across eight spheres instead of across
//!   terms, for quadrature nodes (same m, neighbouring x): every recurrence
//!   step and the per-sphere set-up are then shared by eight spheres.
//! - **Angular functions** (`amplitude.rs`): pi_n, tau_n by the upward
//!   recurrences of B&H eq. 4.47 in Wiscombe's arrangement (exact at
//!   mu = +-1), for blocks of angles at once.
//! - **Perfect conductors** (`perfect_conductor.rs`): the limit
//!   |m| -> infinity, a_n = psi_n'/xi_n', b_n = psi_n/xi_n, as a separate,
//!   simple path ([`compute_efficiencies_perfect_conductor`]).
//!
//! Measured (tests in `tests/sphere_reference.rs`): against the 100-digit
//! reference table the worst relative errors are 2e-14 (Q_ext, Q_sca, g),
//! 7e-13 (Q_abs) and 5e-12 (Q_back, x = 1e4); against the phase-matrix table
//! 6e-13. A plain BHMIE transcription is kept beside the fast path as a test
//! oracle (`naive.rs`, test builds only).

mod amplitude;
mod batch;
mod bessel_ratio;
mod coefficients;
#[cfg(test)]
mod naive;
mod perfect_conductor;
mod series_length;

pub(crate) use batch::{GroupCoefficients, compute_group_coefficients};
pub use batch::{SPHERE_LANES, compute_efficiencies_many, compute_efficiencies_many_with};
pub use perfect_conductor::{
    MIN_PERFECT_CONDUCTOR_SIZE_PARAMETER, compute_efficiencies_perfect_conductor,
};
pub use series_length::{series_length_converged, series_length_wiscombe};

use crate::Complex64;
use coefficients::{coefficient_scale, scratch_length, solve_series};

/// Why a sphere could not be solved: the input is outside the supported domain.
#[derive(Debug, Clone, PartialEq)]
pub enum MieError {
    /// `x` must be finite and > 0, at most [`MAX_SIZE_PARAMETER`], and with
    /// |m| x at most [`MAX_INTERIOR_SIZE_PARAMETER`]
    /// (supported 1e-6 ..= 2e4 guaranteed; larger allowed but slow).
    InvalidSizeParameter(f64),
    /// `m` must be finite, Re(m) > 0, Im(m) >= 0, and |m| within
    /// [`REFRACTIVE_INDEX_MODULUS_RANGE`] (beyond it m^2 and the interior
    /// recurrences leave double precision; the limit |m| -> infinity is
    /// [`compute_efficiencies_perfect_conductor`]).
    InvalidRefractiveIndex(Complex64),
}

impl std::fmt::Display for MieError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MieError::InvalidSizeParameter(x) => {
                write!(
                    f,
                    "size parameter x = {x} is invalid: it must be finite, greater than 0 and at most {MAX_SIZE_PARAMETER:e}, with |m| x at most {MAX_INTERIOR_SIZE_PARAMETER:e}"
                )
            }
            MieError::InvalidRefractiveIndex(m) => write!(
                f,
                "refractive index m = {}{:+}i is invalid: the real part must be > 0 and the imaginary part >= 0 (absorption), both finite, with |m| between {:e} and {:e}",
                m.re,
                m.im,
                REFRACTIVE_INDEX_MODULUS_RANGE.start(),
                REFRACTIVE_INDEX_MODULUS_RANGE.end()
            ),
        }
    }
}

impl std::error::Error for MieError {}

/// Largest accepted size parameter. The series has ~x terms, so time and the
/// tables (40 bytes a term) grow linearly; at x = 1e6 (a 100 um droplet in
/// visible light) that is 40 MB and ~0.1 s. Larger spheres belong to
/// geometric optics.
pub const MAX_SIZE_PARAMETER: f64 = 1e6;

/// Largest accepted |m| x. For a weakly absorbing interior the continued
/// fraction that starts the interior recurrence runs past n = |m x| (see
/// `bessel_ratio.rs`), ~1e8 steps or about a second at this limit.
pub const MAX_INTERIOR_SIZE_PARAMETER: f64 = 1e8;

/// Accepted moduli of the relative refractive index. Real materials in the
/// optical range have 0.01 < |m| < 100.
pub const REFRACTIVE_INDEX_MODULUS_RANGE: std::ops::RangeInclusive<f64> = 1e-6..=1e6;

/// Efficiencies (dimensionless, cross-section / (pi r^2)) and asymmetry parameter of one sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Efficiencies {
    pub qext: f64,
    pub qsca: f64,
    /// Computed directly (not as qext - qsca) so it keeps its relative accuracy when tiny.
    pub qabs: f64,
    /// Backscattering efficiency, B&H eq. 4.82 convention: |sum (2n+1)(-1)^n (a_n - b_n)|^2 / x^2.
    pub qback: f64,
    /// Asymmetry parameter `<cos theta>`, weighted by scattered intensity.
    pub g: f64,
}

fn validate(m: Complex64, x: f64) -> Result<(), MieError> {
    // |m| without hypot: |m|^2 over- or underflows only far outside the range.
    let modulus = m.norm_sqr().sqrt();
    if !(m.re > 0.0
        && m.re.is_finite()
        && m.im >= 0.0
        && m.im.is_finite()
        && REFRACTIVE_INDEX_MODULUS_RANGE.contains(&modulus))
    {
        return Err(MieError::InvalidRefractiveIndex(m));
    }
    if !(x > 0.0 && x <= MAX_SIZE_PARAMETER && modulus * x <= MAX_INTERIOR_SIZE_PARAMETER) {
        return Err(MieError::InvalidSizeParameter(x));
    }
    Ok(())
}

/// Scratch capacities (f64 values) of the stack tiers of
/// [`compute_efficiencies`]. The scratch is zeroed on every call, so its size
/// is time: a small tier for small spheres (x up to ~7), a middle one to
/// x ~ 100 and a large one (40 KB) to x ~ 950. The solver needs about
/// 5 (x + 7.6 x^(1/3)) values.
const STACK_SCRATCH_SMALL: usize = 128;
const STACK_SCRATCH_MIDDLE: usize = 640;
const STACK_SCRATCH_LARGE: usize = 5120;

/// Largest table (f64 values) that [`compute_efficiencies`] keeps per thread
/// between calls: 1 MB, spheres up to x ~ 26 000. Larger ones allocate their
/// own, so that a one-off huge sphere does not pin its memory to the thread.
const THREAD_SCRATCH_MAX: usize = 1 << 17;

thread_local! {
    /// The tables of [`compute_efficiencies`] beyond the stack tiers.
    static THREAD_WORKSPACE: std::cell::RefCell<SphereWorkspace> =
        std::cell::RefCell::new(SphereWorkspace::new());
}

/// Fast path: efficiencies and g of a sphere of relative refractive index `m`
/// and size parameter `x`, without allocation for x up to ~950 (the tables
/// live on the stack, at most 40 KB); larger spheres, up to x ~ 26 000,
/// reuse a table kept per thread (allocated once, the first time it is
/// needed), and larger ones still allocate one per call (use
/// [`compute_efficiencies_with`] to reuse it).
pub fn compute_efficiencies(m: Complex64, x: f64) -> Result<Efficiencies, MieError> {
    validate(m, x)?;
    let n_terms = series_length_converged(x);
    let needed = scratch_length(x, n_terms);
    Ok(if needed == 0 {
        solve_series(m, x, n_terms, &mut [], |_, _| {})
    } else if needed <= STACK_SCRATCH_SMALL {
        with_stack_scratch::<STACK_SCRATCH_SMALL>(m, x, n_terms)
    } else if needed <= STACK_SCRATCH_MIDDLE {
        with_stack_scratch::<STACK_SCRATCH_MIDDLE>(m, x, n_terms)
    } else if needed <= STACK_SCRATCH_LARGE {
        with_stack_scratch::<STACK_SCRATCH_LARGE>(m, x, n_terms)
    } else if needed <= THREAD_SCRATCH_MAX {
        THREAD_WORKSPACE
            .try_with(|workspace| match workspace.try_borrow_mut() {
                Ok(mut workspace) => solve_in_workspace(&mut workspace, m, x),
                Err(_) => solve_in_workspace(&mut SphereWorkspace::new(), m, x),
            })
            .unwrap_or_else(|_| solve_in_workspace(&mut SphereWorkspace::new(), m, x))
    } else {
        solve_in_workspace(&mut SphereWorkspace::new(), m, x)
    })
}

fn with_stack_scratch<const N: usize>(m: Complex64, x: f64, n_terms: usize) -> Efficiencies {
    let mut scratch = [0.0; N];
    solve_series(m, x, n_terms, &mut scratch, |_, _| {})
}

/// Scratch memory for [`compute_efficiencies_with`]: the tables the solver
/// fills (Bessel ratios of mx downward, psi and chi of x upward) and then
/// reads. Create it once per thread and reuse it; it grows to the largest
/// sphere it has seen (about 40 bytes per series term).
#[derive(Debug, Clone, Default)]
pub struct SphereWorkspace {
    tables: Vec<f64>,
    /// The tables of [`compute_efficiencies_many_with`], one row per n.
    batch_rows: Vec<batch::BatchRow>,
}

impl SphereWorkspace {
    /// An empty workspace (allocates nothing until first used).
    pub fn new() -> SphereWorkspace {
        SphereWorkspace::default()
    }

    /// Grow the tables for size parameter x; returns the series length.
    fn reserve_for(&mut self, x: f64) -> usize {
        let n_terms = series_length_converged(x);
        let needed = scratch_length(x, n_terms);
        if self.tables.len() < needed {
            self.tables.resize(needed, 0.0);
        }
        n_terms
    }
}

/// Same as [`compute_efficiencies`], with the tables in `workspace`:
/// allocation-free once the workspace has grown to the largest x used.
pub fn compute_efficiencies_with(
    workspace: &mut SphereWorkspace,
    m: Complex64,
    x: f64,
) -> Result<Efficiencies, MieError> {
    validate(m, x)?;
    Ok(solve_in_workspace(workspace, m, x))
}

fn solve_in_workspace(workspace: &mut SphereWorkspace, m: Complex64, x: f64) -> Efficiencies {
    let n_terms = workspace.reserve_for(x);
    solve_series(m, x, n_terms, &mut workspace.tables, |_, _| {})
}

/// The full solution of one sphere: series coefficients kept, so that amplitude
/// functions can be evaluated at any angle.
#[derive(Debug, Clone)]
pub struct MieSolution {
    /// a_n / scale, b_n / scale for n = 1..=n_terms (never underflow).
    a_scaled: Vec<Complex64>,
    b_scaled: Vec<Complex64>,
    /// a_n, b_n themselves (scale * the above).
    a: Vec<Complex64>,
    b: Vec<Complex64>,
    /// x^3 below x = 0.01 (the scaled path), else 1.
    scale: f64,
    /// sum (2n+1)(|a_n|^2 + |b_n|^2) / scale^2 = x^2 Q_sca / (2 scale^2).
    scattering_sum_scaled: f64,
    x: f64,
    efficiencies: Efficiencies,
    workspace: SphereWorkspace,
}

impl MieSolution {
    /// Solve the sphere (allocates the coefficient vectors once).
    pub fn compute(m: Complex64, x: f64) -> Result<MieSolution, MieError> {
        let mut solution = MieSolution {
            a_scaled: Vec::new(),
            b_scaled: Vec::new(),
            a: Vec::new(),
            b: Vec::new(),
            scale: 1.0,
            scattering_sum_scaled: 0.0,
            x,
            efficiencies: Efficiencies {
                qext: 0.0,
                qsca: 0.0,
                qabs: 0.0,
                qback: 0.0,
                g: 0.0,
            },
            workspace: SphereWorkspace::new(),
        };
        solution.recompute(m, x)?;
        Ok(solution)
    }

    /// Solve another sphere in place, reusing this solution's memory (no
    /// allocation once it has held a sphere at least as large). On error the
    /// previous solution is left unchanged.
    pub fn recompute(&mut self, m: Complex64, x: f64) -> Result<(), MieError> {
        validate(m, x)?;
        let n_terms = self.workspace.reserve_for(x);
        self.a_scaled.clear();
        self.b_scaled.clear();
        let (a_scaled, b_scaled) = (&mut self.a_scaled, &mut self.b_scaled);
        self.efficiencies = solve_series(m, x, n_terms, &mut self.workspace.tables, |a, b| {
            a_scaled.push(a);
            b_scaled.push(b);
        });
        self.x = x;
        self.scale = coefficient_scale(x);
        let scale = self.scale;
        self.a.clear();
        self.a.extend(self.a_scaled.iter().map(|&a| a * scale));
        self.b.clear();
        self.b.extend(self.b_scaled.iter().map(|&b| b * scale));
        self.scattering_sum_scaled = self
            .a_scaled
            .iter()
            .zip(&self.b_scaled)
            .enumerate()
            .map(|(index, (a, b))| (2 * index + 3) as f64 * (a.norm_sqr() + b.norm_sqr()))
            .sum();
        Ok(())
    }

    /// Efficiencies and asymmetry parameter (dimensionless), as
    /// [`compute_efficiencies`] returns them.
    pub fn efficiencies(&self) -> Efficiencies {
        self.efficiencies
    }

    /// The size parameter x = 2 pi r / lambda this solution is for.
    pub fn size_parameter(&self) -> f64 {
        self.x
    }

    /// Number of series terms kept.
    pub fn n_terms(&self) -> usize {
        self.a.len()
    }

    /// a_n, b_n for n = 1..=n_terms (index 0 is n = 1).
    pub fn coefficients(&self) -> (&[Complex64], &[Complex64]) {
        (&self.a, &self.b)
    }

    /// Amplitude functions (S1, S2) at scattering angle theta with mu = cos(theta), B&H eq. 4.74.
    /// Dimensionless; the far field is E_s = e^{ikr}/(-ikr) S E_i (B&H eq. 3.12).
    pub fn amplitudes(&self, cos_theta: f64) -> (Complex64, Complex64) {
        let (s1, s2) = amplitude::amplitudes(&self.a_scaled, &self.b_scaled, cos_theta);
        (s1 * self.scale, s2 * self.scale)
    }

    /// [`MieSolution::amplitudes`] at each mu of `cos_theta`, into `s1` and
    /// `s2` (the same numbers, to the last bit, in blocks of angles whose
    /// recurrences run side by side). The slices must have equal lengths.
    pub fn amplitudes_table(&self, cos_theta: &[f64], s1: &mut [Complex64], s2: &mut [Complex64]) {
        assert!(
            cos_theta.len() == s1.len() && cos_theta.len() == s2.len(),
            "amplitudes_table: cos_theta, s1 and s2 must have equal lengths"
        );
        amplitude::amplitudes_table(&self.a_scaled, &self.b_scaled, cos_theta, s1, s2);
        for (s1, s2) in s1.iter_mut().zip(s2.iter_mut()) {
            *s1 *= self.scale;
            *s2 *= self.scale;
        }
    }

    /// (S11, S12) at mu = cos(theta): S11 = (|S1|^2 + |S2|^2)/2, S12 = (|S2|^2 - |S1|^2)/2.
    pub fn s11_s12(&self, cos_theta: f64) -> (f64, f64) {
        let (s1, s2) = self.amplitudes(cos_theta);
        amplitude::s11_s12_from_amplitudes(s1, s2)
    }

    /// Unpolarised phase function, normalised to 1 over 4 pi sr (unit: sr^-1):
    /// S11 / (pi x^2 Qsca). For a sphere that does not scatter at all
    /// (m = 1) it is the isotropic 1/(4 pi).
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        // pi x^2 Q_sca = 2 pi sum (2n+1)(|a_n|^2 + |b_n|^2): with the scaled
        // coefficients both sides carry scale^2, which then cancels, so the
        // phase function of a 1e-300 sphere is still the Rayleigh one.
        if self.scattering_sum_scaled <= 0.0 {
            return 1.0 / (4.0 * std::f64::consts::PI);
        }
        let (s1, s2) = amplitude::amplitudes(&self.a_scaled, &self.b_scaled, cos_theta);
        let (s11_scaled, _) = amplitude::s11_s12_from_amplitudes(s1, s2);
        s11_scaled / (2.0 * std::f64::consts::PI * self.scattering_sum_scaled)
    }

    /// Fill `s11` and `s12` at each mu of `cos_theta` (one pass of the angular
    /// recurrences per angle, no allocation). Slices must have equal lengths.
    pub fn s11_s12_table(&self, cos_theta: &[f64], s11: &mut [f64], s12: &mut [f64]) {
        assert!(
            cos_theta.len() == s11.len() && cos_theta.len() == s12.len(),
            "s11_s12_table: cos_theta, s11 and s12 must have equal lengths"
        );
        amplitude::s11_s12_table(&self.a_scaled, &self.b_scaled, cos_theta, s11, s12);
        let scale_squared = self.scale * self.scale;
        if scale_squared != 1.0 {
            s11.iter_mut().for_each(|v| *v *= scale_squared);
            s12.iter_mut().for_each(|v| *v *= scale_squared);
        }
    }

    /// Fill `phase` with the unpolarised phase function (sr^-1, normalised to
    /// 1 over 4 pi sr) at each mu of `cos_theta`, without allocation. The
    /// slices must have equal lengths.
    pub fn phase_function_table(&self, cos_theta: &[f64], phase: &mut [f64]) {
        assert_eq!(
            cos_theta.len(),
            phase.len(),
            "phase_function_table: lengths differ"
        );
        if self.scattering_sum_scaled <= 0.0 {
            phase
                .iter_mut()
                .for_each(|p| *p = 1.0 / (4.0 * std::f64::consts::PI));
            return;
        }
        let normalisation = 1.0 / (2.0 * std::f64::consts::PI * self.scattering_sum_scaled);
        amplitude::s11_table(&self.a_scaled, &self.b_scaled, cos_theta, phase);
        phase.iter_mut().for_each(|p| *p *= normalisation);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_inputs_are_errors_that_name_the_value() {
        let good = Complex64::new(1.5, 0.01);
        for x in [0.0, -1.0, f64::NAN, f64::INFINITY, 2e6] {
            let error = compute_efficiencies(good, x).unwrap_err();
            // The offending value is carried bit for bit (NaN included).
            assert!(
                matches!(error, MieError::InvalidSizeParameter(v) if v.to_bits() == x.to_bits())
            );
            assert!(error.to_string().contains("size parameter"));
        }
        for m in [
            Complex64::new(0.0, 1.0),
            Complex64::new(-1.5, 0.0),
            Complex64::new(1.5, -0.01),
            Complex64::new(f64::NAN, 0.0),
            Complex64::new(1.5, f64::INFINITY),
            Complex64::new(1e7, 0.0),
            Complex64::new(1e-7, 0.0),
        ] {
            let error = compute_efficiencies(m, 1.0).unwrap_err();
            assert!(matches!(error, MieError::InvalidRefractiveIndex(_)), "{m}");
            assert!(error.to_string().contains("refractive index"));
        }
        // |m| x beyond the interior limit.
        assert!(matches!(
            compute_efficiencies(Complex64::new(1e3, 0.0), 2e5),
            Err(MieError::InvalidSizeParameter(_))
        ));
        assert!(MieSolution::compute(good, 0.0).is_err());
    }

    #[test]
    fn recompute_reuses_and_equals_a_fresh_solution() {
        let mut solution = MieSolution::compute(Complex64::new(1.33, 0.0), 500.0).unwrap();
        for &(m, x) in &[
            (Complex64::new(1.5, 0.01), 30.0),
            (Complex64::new(0.75, 0.0), 0.004),
        ] {
            solution.recompute(m, x).unwrap();
            let fresh = MieSolution::compute(m, x).unwrap();
            assert_eq!(solution.efficiencies(), fresh.efficiencies());
            assert_eq!(solution.coefficients(), fresh.coefficients());
            assert_eq!(solution.n_terms(), series_length_converged(x));
            assert_eq!(solution.size_parameter(), x);
            assert_eq!(solution.efficiencies(), compute_efficiencies(m, x).unwrap());
        }
        // An invalid sphere leaves the previous solution in place.
        let before = solution.efficiencies();
        assert!(solution.recompute(Complex64::new(1.5, 0.0), -1.0).is_err());
        assert_eq!(solution.efficiencies(), before);
    }

    #[test]
    fn tiny_spheres_keep_the_rayleigh_phase_function() {
        // At x = 1e-200 every a_n underflows, but the phase function is formed
        // from the scaled coefficients: 3/(16 pi) (1 + mu^2).
        let solution = MieSolution::compute(Complex64::new(1.5, 0.01), 1e-200).unwrap();
        assert!(solution.coefficients().0.iter().all(|a| a.norm() == 0.0));
        for mu in [1.0, 0.5, 0.0, -0.7, -1.0] {
            let rayleigh = 3.0 / (16.0 * std::f64::consts::PI) * (1.0 + mu * mu);
            let p = solution.phase_function_per_sr(mu);
            assert!(
                (p / rayleigh - 1.0).abs() < 1e-12,
                "mu = {mu}: {p} vs {rayleigh}"
            );
        }
        // And the amplitudes of a small sphere scale as x^3: S(0) = (3/2) a_1.
        let x = 1e-3;
        let solution = MieSolution::compute(Complex64::new(1.5, 0.01), x).unwrap();
        let (s1, s2) = solution.amplitudes(1.0);
        let a1 = solution.coefficients().0[0];
        assert!((s1 - a1 * 1.5).norm() < 1e-5 * s1.norm());
        assert_eq!(s1, s2);
    }
}
