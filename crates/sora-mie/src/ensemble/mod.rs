//! # Ensemble optics: Mie theory averaged over a size distribution
//!
//! A volume of aerosol with number density `rho` (m^-3) of a population with
//! per-particle mean cross-sections `<C>` (m^2) scatters and extinguishes with
//! coefficients `beta = rho <C>` (m^-1, the paper's eq. 1). This module
//! computes those per-particle means for one wavelength and one population,
//! replacing the paper's per-sample random radius by the integral whose
//! expectation it estimates (same mean, no noise):
//!
//! ```text
//!     <C_ext> = integral pi r^2 Q_ext(m, x) dN / N       x = 2 pi r / lambda
//!     <C_sca> = integral pi r^2 Q_sca(m, x) dN / N
//!     <C_abs> = integral pi r^2 Q_abs(m, x) dN / N       (Q_abs direct, not Q_ext - Q_sca)
//!     omega   = <C_sca> / <C_ext>                        single-scattering albedo
//!     g       = integral g(x) C_sca dN / integral C_sca dN
//!     P(mu)   = integral S11(mu; x) dN / (k^2 integral C_sca dN)        [sr^-1]
//! ```
//!
//! (Bohren & Huffman 1983, §4.4-4.5; Hansen & Travis 1974, §2-3). `N` is the
//! number of particles of the population, i.e. inside the radius window of a
//! truncated distribution. `k = 2 pi / lambda`, so `k^2 C_sca = pi x^2 Q_sca`
//! and `P` is the scattering-weighted mean of the single-sphere phase
//! functions `S11 / (pi x^2 Q_sca)`, normalised to 1 over 4 pi sr. The medium
//! has index 1: `lambda` is the vacuum wavelength in nm, `m` the particle's
//! index at that wavelength ([`RefractiveIndexModel`]).
//!
//! ## Quadrature and its measured error
//!
//! The integrals are composite Gauss-Legendre rules in `ln x` whose node
//! density resolves the absorption-limited Mie resonances and relaxes in the
//! tails ([`crate::distribution::quadrature`]). All wavelengths at
//! which the particles have the same index share one rule and one Mie
//! solution per node ([`SharedSizeParameterQuadrature`](crate::distribution::SharedSizeParameterQuadrature)); a wavelength alone
//! is the one-wavelength case of the same code. Cross-sections, `g` and the
//! paper's HG `g` come from [`compute_efficiencies_many_with`](crate::sphere::compute_efficiencies_many_with) over the
//! nodes (eight neighbouring nodes solved side by side in vector lanes,
//! equal to [`compute_efficiencies`](crate::sphere::compute_efficiencies) to rounding) with
//! [`RadiusQuadratureSettings::cross_sections`]; the phase
//! function needs the series coefficients and an angular sum per node, so it has
//! its own sparser rule, [`RadiusQuadratureSettings::phase_function`].
//!
//! Measured error of the cross-section rule (relative, worst case):
//!
//! | against | C_ext | C_sca | C_abs | g |
//! |---|---|---|---|---|
//! | `tests/data/lognormal.csv` (520 rows, m = 1.5 + 0.01i) | 2.7e-7 | 3.0e-7 | 1.4e-7 | 4.5e-8 |
//! | a rule 4x denser, 16 nodes/panel, depth 25: k = 0.01 | 1.6e-8 | 3.1e-9 | 6.0e-8 | 2.4e-9 |
//! | same, k = 0.005 | 1.8e-6 | 4.1e-7 | 1.2e-5 | 4.0e-7 |
//! | same, k = 0.001 | 1.8e-4 | 8.1e-5 | 3.1e-3 | 8.4e-5 |
//! | same, Mars dust with the Wolff (2009) index (k 0.0009-0.011) | 1.2e-4 | 6.8e-5 | 2.1e-3 | 6.7e-5 |
//!
//! (The denser-rule rows: r_m 0.05-1.5 um, sigma_g 1.5-2.0, untruncated and
//! both windows, 21 wavelengths.) The table's worst row (r_m 0.5 um, sigma_g
//! 2.0, 480 nm, 0.1-2.5 um) is the table's: a 200 001-node trapezoid, a rule
//! 4 times denser and ours agree to 1e-11 there. The error grows as `k`
//! falls because the resonances narrow like `k`: for weakly absorbing
//! particles (k < 0.005) raise `resonance_nodes_per_unit_ln_radius` in
//! proportion to 0.005 / k if C_abs matters to better than 1e-3; C_ext,
//! C_sca and g stay within 2e-4 at k = 0.001.
//!
//! ## The phase-function table
//!
//! `P` is tabulated at 406 scattering angles, dense where the forward
//! diffraction peak is (its width is about `1/x` rad) and where it falls
//! steeply: `theta` = 0-1 deg by 0.02 deg, 1-5 by 0.05, 5-20 by 0.2, 20-60
//! by 0.5, 60-180 by 1 ([`ensemble_phase_table_angles_deg`]). Between
//! nodes, `P` is linear in `mu = cos theta`. That makes the forward peak
//! exact to second order (a diffraction peak `[2 J_1(x theta) / (x theta)]^2`
//! is `1 - (x theta)^2 / 4 ~ 1 - x^2 (1 - mu) / 2` near 0, linear in `mu`), and
//! makes the interpolant the exact density of [`TabulatedPhaseFunction`]:
//! its integral (`2 pi` times the trapezoid rule in `mu`) is exact, so the
//! table is rescaled to integrate to 1 exactly; the cumulative distribution
//! over the nodes is piecewise quadratic in `mu` and is inverted in closed
//! form for sampling, so `eval`, `pdf` and `sample` agree exactly. The scale
//! factor applied (the raw table's integral) is kept as a diagnostic of the
//! angular resolution, and so is the table's mean cosine against the
//! cross-section `g`.
//!
//! Measured accuracy of the Mie phase tables (21 wavelengths; Mars dust
//! r_m 0.78 um sigma_g 1.67 at k 0.005, Table 1 aerosol, the 0.45-0.56 um
//! window, r_m 0.1 and 1.5 um): against a phase rule 4 times denser and
//! deeper, within 2.3e-3 relative at every angle below 90 deg and 5.3e-3
//! beyond (backscatter is the most sensitive to the radius sampling); the raw
//! table integrates to 1 within 4e-4 before rescaling (angular
//! interpolation); its mean cosine matches the cross-section `g` within
//! 8.5e-5 (1e-5 for the denser rule: the rest is the table's interpolation).
//!
//! The radius rule's noise grows as `k` falls (the resonances narrow like
//! `k`, as for the cross-sections): for Mars dust with the Wolff (2009)
//! index, against a rule 16 times denser and deeper (itself converged to
//! 8e-4), the exact tables are within 1.3e-3 to 2.7e-3 forward and 2e-3 to
//! 5e-3 backward for k 0.0099-0.0055 (380-500 nm), but 4e-3 to 8.3e-3
//! forward and 7e-3 to 2.4e-2 backward for k 0.0034-0.00094 (540-780 nm).
//!
//! For nearly non-absorbing spheres (water, k ~ 1e-7) the resonances are
//! not limited by absorption and the phase rule adds a density per unit
//! size parameter (see "The ripple of weakly absorbing spheres" in
//! [`crate::distribution::quadrature`]): a water cloud of r_eff 10 um at
//! 800 nm (modified gamma or log-normal, v_eff 0.1) is within 2.0e-3 (P11)
//! and 1.7e-3 (F12/F11) of 100 times the nodes at 120-180 deg; the rules of
//! absorbing aerosols (k / n >= 5e-4), and with them the figures above, are
//! unchanged. Between (k ~ 1e-4 to 5e-4) the backscatter errs by 1e-2 to
//! 4e-2, like Mars dust's at 540-780 nm.
//!
//! ## A tabulated index: phase tables interpolated in the index
//!
//! With m(lambda) tabulated, every wavelength has its own index, so no Mie
//! solution is shared and the exact phase tables cost one full radius rule
//! (Mie solution and 406-angle sums per node) per wavelength: 21 times the
//! work of a constant index. [`SpectralPhaseMethod::IndexInterpolated`] (the
//! default) instead computes, for all the wavelengths at once with the
//! shared size-parameter rule, the tables at five reference indices, and
//! interpolates each wavelength's table from them:
//!
//! ```text
//!     P(lambda; n + ik) = sum_j L_j(ln k) P(lambda; n_mid + i k_j)
//!                         + t [P(lambda; n_max + i k_2) - P(lambda; n_mid + i k_2)]
//! ```
//!
//! with `k_j` the four Chebyshev-Lobatto points of `[ln k_min, ln k_max]`,
//! `L_j` their Lagrange basis (cubic in ln k), `n_mid` the middle of the n
//! range and `t = (n - n_mid) / (n_max - n_mid)` (linear in n); the result is
//! renormalised like any table. Why in the index and not in wavelength: the
//! table's strong wavelength dependence is the size parameter's scaling
//! (the forward peak's width goes like lambda), which each reference gets
//! exactly because it is computed at every wavelength; what is interpolated
//! is only the smooth dependence of the ensemble on m at a fixed
//! wavelength (absorption damps the refracted light like exp(-c k x), smooth
//! in ln k once averaged over a broad distribution). Interpolating the
//! tables in wavelength instead (every 4th or 5th wavelength, in ln P, or
//! along the index path) errs by 1-2e-2 near 400-500 nm, because the Wolff
//! m(lambda) has kinks at its rows (440, 460, 500, 600, 700 nm). A cubic in
//! ln k without the n term errs by up to 2.7e-2 backward: n varies by only
//! 0.0044, but that moves the resonances and the rainbow.
//!
//! It applies where it saves work and has been validated: more distinct
//! indices than references, all absorbing, n spread at most
//! [`MAX_INTERPOLATED_REAL_INDEX_SPREAD`] and k_max / k_min at most
//! [`MAX_INTERPOLATED_ABSORPTION_RATIO`] ([`index_interpolation_applies`]);
//! otherwise each index is computed exactly. Cross-sections, albedo, g and
//! the paper's g are always computed exactly per index (bit-identical in
//! both methods). [`SpectralPhaseMethod::Exact`] keeps the exact path, and
//! the tests check one against the other at every wavelength.
//!
//! Measured (Mars dust, Wolff index, 21 wavelengths; against the converged
//! rule above): the interpolated tables are within 8.8e-4 to 5e-3 forward
//! and 2.7e-3 to 1e-2 backward at every wavelength, against 1.3e-3 to 8.3e-3
//! and 2e-3 to 2.4e-2 for the exact path: more accurate in both hemispheres
//! at 12 of the 21 wavelengths (all of 480-660 nm), worse backward at
//! 380-460 nm (up to 6.7e-3 against 4.2e-3: there k is large and the exact
//! tables' noise smallest) and by at most 1.5e-3 in one hemisphere at
//! 680-740 nm. The reason they are
//! generally better: the shared size-parameter rule spans the union of the
//! wavelengths' ranges, so each wavelength gets more nodes than its own
//! rule. Fast against exact: within 1.2e-2 forward and 2.3e-2 backward,
//! which is the two paths' radius-rule noise; the tables' mean cosine stays
//! within 4e-4 of the cross-section g.
//!
//! ## Cost
//!
//! Where the time goes, and how it is kept down:
//! - Mie solutions: the nodes of a rule are solved eight at a time, side by
//!   side in vector lanes ([`compute_efficiencies_many_with`](crate::sphere::compute_efficiencies_many_with) for the
//!   cross-sections, the same solver recording a_n, b_n for the phase
//!   tables): the nodes are sorted and neighbouring, so the eight series
//!   have nearly the same length, and every recurrence step and the
//!   per-sphere set-up (continued fractions, trigonometry) are shared by
//!   eight spheres. About 3 times the one-sphere solver's rate on these
//!   nodes (x 0.6-470, Mars dust, 21 wavelengths).
//! - Angular sums (`accumulate_s11`): term-outer, angle-inner in blocks
//!   of angles; the reference indices of the index-interpolated tables
//!   share their rule's nodes, so pi_n and tau_n are computed once per node
//!   for all of them, and the per-term constants are tabulated once.
//! - Accumulating w S11 into the per-wavelength tables: a group of eight
//!   nodes at a time, each table entry loaded and stored once per group.
//! - All three are compiled for AVX-512F with FMA and for AVX as well as the
//!   portable target, selected at run time (`crate::simd`; the AVX build is
//!   bit-identical to the portable one; the fused build rounds differently,
//!   within 1e-15 of the others, tested).
//!
//! The radius rules themselves are unchanged by this: the same nodes and
//! weights, so the measured quadrature errors above still hold (the
//! cross-sections changed by rounding only, ~1e-15, and the reference tests
//! pass at the same tolerances).
//!
//! Criterion (`benches/ensemble.rs`), 21 paper wavelengths, one thread,
//! load average (`uptime`, this 2-core machine is shared with other builds)
//! given for each set, so +-30%:
//!
//! | case | one-sphere solver (load 4.2-5.0) | batched (load 1.0-1.8) |
//! |---|---|---|
//! | Mars dust, m = 1.5 + 0.005i, Mie phase | 30.3 ms | 13.0 ms |
//! | Mars dust, paper HG (cross-sections only) | 10.2 ms | 4.9 ms |
//! | Table 1 aerosol 0.1-2.5 um, Mie phase | 24.8 ms | 10.3 ms |
//! | Mars dust, Wolff index, Mie phase (default: interpolated) | 155 ms | 46 ms |
//! | same, exact per-index tables | 388 ms | 104 ms |
//! | same, paper HG (cross-sections only) | 103 ms | 22 ms |
//!
//! (At load 2.4 the one-sphere figures for the three Wolff cases were 132,
//! 230 and 71 ms.) With the Wolff index the default build is about 22 ms of
//! cross-sections (one rule of about 1800 nodes per wavelength, 37 800
//! sphere solutions, 2.0 million series terms) and about 24 ms of phase
//! tables (five reference indices on a 520-node rule: 2 600 solutions and
//! 46 million angle-terms).
//!
//! ## Files
//!
//! This file holds the API (settings, errors, [`compute_ensemble_optics`] and
//! its spectrum form, which group the wavelengths by index and pick the phase
//! path); the work is split by job:
//! - `cross_sections.rs`: `<C_ext>`, `<C_sca>`, `<C_abs>` (m^2), albedo, g
//!   and the paper's g ([`compute_ensemble_cross_sections`]);
//! - `phase_table.rs`: the 406-angle table [`TabulatedPhaseFunction`]
//!   (sr^-1) and the radius integration that fills it;
//! - `angular_sums.rs`: S11(theta) of the nodes and its weighted
//!   accumulation into the tables (the hot loops);
//! - `index_interpolation.rs`: the tables of a tabulated m(lambda) from five
//!   reference indices ([`index_interpolation_applies`]);
//! - `phase_matrix.rs`: F12, F33 and F34 relative to F11, for polarised
//!   computations ([`compute_ensemble_phase_matrix_ratios`]);
//! - `tests.rs`: the tests of all of them.

mod angular_sums;
mod cross_sections;
mod index_interpolation;
mod phase_matrix;
mod phase_table;
#[cfg(test)]
mod tests;

pub use cross_sections::{
    EnsembleCrossSections, compute_ensemble_cross_sections, integrate_ensemble_cross_sections,
};
pub use index_interpolation::{
    MAX_INTERPOLATED_ABSORPTION_RATIO, MAX_INTERPOLATED_REAL_INDEX_SPREAD,
    index_interpolation_applies,
};
pub use phase_matrix::{
    PhaseMatrixRatios, compute_ensemble_phase_matrix_ratios,
    compute_shared_ensemble_phase_matrix_ratios,
};
pub use phase_table::{
    InvalidPhaseTable, TabulatedPhaseFunction, compute_ensemble_phase_function,
    ensemble_phase_table_angles_deg,
};

use crate::Complex64;
use crate::distribution::{RadiusQuadratureSettings, SizeDistribution, SizeDistributionError};
use crate::paper_phase::{AerosolPhaseMode, HenyeyGreensteinPhaseFunction};
use crate::refractive_index::{RefractiveIndexError, RefractiveIndexModel};
use crate::sphere::MieError;
use cross_sections::compute_shared_cross_sections;
use phase_table::PhaseTableWorkspace;
use std::f64::consts::PI;

/// The paper's spectral samples: 380 to 780 nm every 20 nm (21 wavelengths, nm).
pub const PAPER_WAVELENGTHS_NM: [f64; 21] = [
    380.0, 400.0, 420.0, 440.0, 460.0, 480.0, 500.0, 520.0, 540.0, 560.0, 580.0, 600.0, 620.0,
    640.0, 660.0, 680.0, 700.0, 720.0, 740.0, 760.0, 780.0,
];

/// Why ensemble optics could not be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum EnsembleError {
    /// The wavelength must be finite and > 0 (nm).
    InvalidWavelength { wavelength_nm: f64 },
    /// The refractive-index model has no valid index at this wavelength.
    RefractiveIndex(RefractiveIndexError),
    /// The distribution or quadrature settings are unusable.
    Distribution(SizeDistributionError),
    /// The Mie solver rejected a quadrature node.
    Mie {
        wavelength_nm: f64,
        radius_m: f64,
        error: MieError,
    },
}

impl std::fmt::Display for EnsembleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EnsembleError::InvalidWavelength { wavelength_nm } => write!(
                f,
                "wavelength {wavelength_nm} nm is invalid: it must be finite and greater than 0"
            ),
            EnsembleError::RefractiveIndex(error) => write!(f, "{error}"),
            EnsembleError::Distribution(error) => write!(f, "{error}"),
            EnsembleError::Mie {
                wavelength_nm,
                radius_m,
                error,
            } => write!(
                f,
                "Mie solution failed at wavelength {wavelength_nm} nm, radius {radius_m} m: {error}"
            ),
        }
    }
}

impl std::error::Error for EnsembleError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            EnsembleError::InvalidWavelength { .. } => None,
            EnsembleError::RefractiveIndex(error) => Some(error),
            EnsembleError::Distribution(error) => Some(error),
            EnsembleError::Mie { error, .. } => Some(error),
        }
    }
}

impl From<RefractiveIndexError> for EnsembleError {
    fn from(error: RefractiveIndexError) -> Self {
        EnsembleError::RefractiveIndex(error)
    }
}

impl From<SizeDistributionError> for EnsembleError {
    fn from(error: SizeDistributionError) -> Self {
        EnsembleError::Distribution(error)
    }
}

fn validate_wavelength(wavelength_nm: f64) -> Result<f64, EnsembleError> {
    if wavelength_nm.is_finite() && wavelength_nm > 0.0 {
        Ok(2.0 * PI / (wavelength_nm * 1e-9))
    } else {
        Err(EnsembleError::InvalidWavelength { wavelength_nm })
    }
}

/// The phase function carried by ensemble optics: the tabulated Mie one or
/// the paper's Henyey-Greenstein. All densities per steradian, normalised to
/// 1 over 4 pi sr; sampling returns cos theta (azimuth uniform, the caller's).
#[derive(Debug, Clone, PartialEq)]
pub enum AerosolPhaseFunction {
    Tabulated(TabulatedPhaseFunction),
    HenyeyGreenstein(HenyeyGreensteinPhaseFunction),
}

impl AerosolPhaseFunction {
    /// Phase function at `cos_theta` (sr^-1).
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        match self {
            AerosolPhaseFunction::Tabulated(table) => table.phase_function_per_sr(cos_theta),
            AerosolPhaseFunction::HenyeyGreenstein(hg) => hg.phase_function_per_sr(cos_theta),
        }
    }

    /// Sampling density at `cos_theta` (sr^-1), equal to the phase function.
    pub fn pdf_per_sr(&self, cos_theta: f64) -> f64 {
        self.phase_function_per_sr(cos_theta)
    }

    /// cos theta for a uniform random number in [0, 1].
    pub fn sample_cos_theta(&self, uniform_sample: f64) -> f64 {
        match self {
            AerosolPhaseFunction::Tabulated(table) => table.sample_cos_theta(uniform_sample),
            AerosolPhaseFunction::HenyeyGreenstein(hg) => hg.sample_cos_theta(uniform_sample),
        }
    }

    /// Mean cosine of the phase function as represented.
    pub fn asymmetry_parameter(&self) -> f64 {
        match self {
            AerosolPhaseFunction::Tabulated(table) => table.asymmetry_parameter(),
            AerosolPhaseFunction::HenyeyGreenstein(hg) => hg.asymmetry_parameter(),
        }
    }
}

/// How ensemble optics are computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleSettings {
    /// Exact Mie phase function (default) or the paper's HG.
    pub phase_mode: AerosolPhaseMode,
    /// Quadrature of the cross-sections, g and the paper's g.
    pub cross_section_quadrature: RadiusQuadratureSettings,
    /// Quadrature of the phase-function table (Mie mode only).
    pub phase_function_quadrature: RadiusQuadratureSettings,
    /// How the phase tables of a spectrum are computed when the particles'
    /// index differs between wavelengths (Mie mode only; see
    /// [`SpectralPhaseMethod`]).
    pub spectral_phase_method: SpectralPhaseMethod,
}

impl Default for EnsembleSettings {
    fn default() -> Self {
        Self {
            phase_mode: AerosolPhaseMode::Mie,
            cross_section_quadrature: RadiusQuadratureSettings::cross_sections(),
            phase_function_quadrature: RadiusQuadratureSettings::phase_function(),
            spectral_phase_method: SpectralPhaseMethod::IndexInterpolated,
        }
    }
}

/// How [`compute_ensemble_optics_spectrum`] computes the phase tables of
/// wavelengths at which the particles have different indices (a tabulated
/// m(lambda)). Cross-sections are always computed exactly, per index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpectralPhaseMethod {
    /// One phase computation (Mie solutions and angular sums at every radius
    /// node) per distinct index: the reference path, and the test oracle of
    /// the interpolated one.
    Exact,
    /// Phase tables at a few reference indices, each one computation shared
    /// by every wavelength, interpolated per wavelength to its own index
    /// (see the module docs). Falls back to [`Self::Exact`] where it would
    /// not save work or lies outside its validated range
    /// ([`index_interpolation_applies`]).
    IndexInterpolated,
}

/// Everything a renderer needs of one aerosol species at one wavelength.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleOptics {
    pub cross_sections: EnsembleCrossSections,
    pub phase_function: AerosolPhaseFunction,
}

/// The ensemble optics (per-particle cross-sections, albedo, g, phase
/// function) of `distribution` at vacuum wavelength `wavelength_nm` (nm),
/// with the particle index from `refractive_index_model`.
pub fn compute_ensemble_optics(
    wavelength_nm: f64,
    refractive_index_model: &RefractiveIndexModel,
    distribution: &SizeDistribution,
    settings: &EnsembleSettings,
) -> Result<EnsembleOptics, EnsembleError> {
    let mut optics = compute_ensemble_optics_spectrum(
        &[wavelength_nm],
        refractive_index_model,
        distribution,
        settings,
    )?;
    Ok(optics.remove(0))
}

/// [`compute_ensemble_optics`] at each of `wavelengths_nm` (nm), e.g.
/// [`PAPER_WAVELENGTHS_NM`], in the order given. Wavelengths at which the
/// particles have the same refractive index (all of them, for a constant
/// index) share their Mie solutions: the quadratures are laid out in size
/// parameter x = 2 pi r / lambda, where a solution at x serves every
/// wavelength (see the module docs), so 21 wavelengths cost little more than
/// one. Results are the same as wavelength by wavelength, up to the
/// quadrature error. Single-threaded and deterministic.
pub fn compute_ensemble_optics_spectrum(
    wavelengths_nm: &[f64],
    refractive_index_model: &RefractiveIndexModel,
    distribution: &SizeDistribution,
    settings: &EnsembleSettings,
) -> Result<Vec<EnsembleOptics>, EnsembleError> {
    // Group the wavelengths by refractive index, keeping first-seen order.
    let mut groups: Vec<(Complex64, Vec<usize>)> = Vec::new();
    for (index, &wavelength_nm) in wavelengths_nm.iter().enumerate() {
        validate_wavelength(wavelength_nm)?;
        let refractive_index = refractive_index_model.refractive_index_at(wavelength_nm)?;
        match groups.iter_mut().find(|(m, _)| *m == refractive_index) {
            Some((_, members)) => members.push(index),
            None => groups.push((refractive_index, vec![index])),
        }
    }
    let mut results: Vec<Option<EnsembleOptics>> = vec![None; wavelengths_nm.len()];
    let mut workspace = PhaseTableWorkspace::new();
    let group_indices: Vec<Complex64> = groups.iter().map(|(m, _)| *m).collect();
    let mut interpolated_tables = match settings.phase_mode {
        AerosolPhaseMode::Mie
            if settings.spectral_phase_method == SpectralPhaseMethod::IndexInterpolated
                && index_interpolation_applies(&group_indices) =>
        {
            let indices: Vec<Complex64> = groups
                .iter()
                .flat_map(|(m, members)| members.iter().map(move |_| *m))
                .collect();
            let order: Vec<usize> = groups
                .iter()
                .flat_map(|(_, members)| members.iter().copied())
                .collect();
            let ordered_wavelengths_nm: Vec<f64> =
                order.iter().map(|&i| wavelengths_nm[i]).collect();
            let tables = workspace.compute_index_interpolated(
                &ordered_wavelengths_nm,
                &indices,
                distribution,
                &settings.phase_function_quadrature,
            )?;
            Some(tables.into_iter().rev().collect::<Vec<_>>())
        }
        _ => None,
    };
    for (refractive_index, members) in groups {
        let group_wavelengths_nm: Vec<f64> = members.iter().map(|&i| wavelengths_nm[i]).collect();
        let cross_sections = compute_shared_cross_sections(
            &group_wavelengths_nm,
            refractive_index,
            distribution,
            &settings.cross_section_quadrature,
        )?;
        let phase_functions: Vec<AerosolPhaseFunction> = match settings.phase_mode {
            AerosolPhaseMode::Mie if interpolated_tables.is_some() => {
                // The tables come in group order; popped from the reversed list.
                let tables = interpolated_tables.as_mut().expect("checked");
                members
                    .iter()
                    .map(|_| {
                        AerosolPhaseFunction::Tabulated(
                            tables.pop().expect("one table per wavelength"),
                        )
                    })
                    .collect()
            }
            AerosolPhaseMode::Mie => workspace
                .compute(
                    &group_wavelengths_nm,
                    refractive_index,
                    distribution,
                    &settings.phase_function_quadrature,
                )?
                .into_iter()
                .map(AerosolPhaseFunction::Tabulated)
                .collect(),
            AerosolPhaseMode::PaperHenyeyGreenstein => cross_sections
                .iter()
                .map(|c| {
                    // The paper's g lies in [0.5, 0.9], or is 0 for a
                    // non-scattering population (see `EnsembleCrossSections`),
                    // so this cannot fail.
                    let hg = HenyeyGreensteinPhaseFunction::new(c.paper_asymmetry_parameter)
                        .expect("the paper's g(r) lies in [0.5, 0.9] or is 0");
                    AerosolPhaseFunction::HenyeyGreenstein(hg)
                })
                .collect(),
        };
        for ((index, cross_sections), phase_function) in
            members.into_iter().zip(cross_sections).zip(phase_functions)
        {
            results[index] = Some(EnsembleOptics {
                cross_sections,
                phase_function,
            });
        }
    }
    Ok(results
        .into_iter()
        .map(|optics| optics.expect("every wavelength belongs to one group"))
        .collect())
}
