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
//! solution per node ([`SharedSizeParameterQuadrature`]); a wavelength alone
//! is the one-wavelength case of the same code. Cross-sections, `g` and the
//! paper's HG `g` come from [`compute_efficiencies_many_with`] over the
//! nodes (eight neighbouring nodes solved side by side in vector lanes,
//! equal to [`compute_efficiencies`] to rounding) with
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
//!   side in vector lanes ([`compute_efficiencies_many_with`] for the
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

use crate::Complex64;
use crate::distribution::{
    RadiusQuadrature, RadiusQuadratureSettings, SharedSizeParameterQuadrature, SizeDistribution,
    SizeDistributionError,
};
use crate::paper_phase::{
    AerosolPhaseMode, HenyeyGreensteinPhaseFunction, paper_asymmetry_parameter_for_radius,
};
use crate::refractive_index::{RefractiveIndexError, RefractiveIndexModel};
use crate::simd::{self, MultiplyAdd};
use crate::sphere::{
    Efficiencies, GroupCoefficients, MieError, SPHERE_LANES, SphereWorkspace, compute_efficiencies,
    compute_efficiencies_many_with, compute_group_coefficients,
};
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

/// Per-particle mean cross-sections and related quantities of a population
/// at one wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleCrossSections {
    /// Vacuum wavelength (nm).
    pub wavelength_nm: f64,
    /// The particles' refractive index at this wavelength.
    pub refractive_index: Complex64,
    /// <C_ext> per particle (m^2).
    pub extinction_cross_section_m2: f64,
    /// <C_sca> per particle (m^2).
    pub scattering_cross_section_m2: f64,
    /// <C_abs> per particle (m^2), integrated from Q_abs directly.
    pub absorption_cross_section_m2: f64,
    /// <C_sca> / <C_ext> (dimensionless).
    pub single_scattering_albedo: f64,
    /// Scattering-weighted mean of the Mie asymmetry parameters (dimensionless).
    pub asymmetry_parameter: f64,
    /// Scattering-weighted mean of the paper's g(r) (the HG mode's g).
    pub paper_asymmetry_parameter: f64,
    /// Fraction of the untruncated population inside the radius window (1 if untruncated).
    pub number_fraction_in_window: f64,
    /// Radius nodes used (each one Mie solution).
    pub radius_node_count: usize,
}

fn validate_wavelength(wavelength_nm: f64) -> Result<f64, EnsembleError> {
    if wavelength_nm.is_finite() && wavelength_nm > 0.0 {
        Ok(2.0 * PI / (wavelength_nm * 1e-9))
    } else {
        Err(EnsembleError::InvalidWavelength { wavelength_nm })
    }
}

/// Per-particle mean cross-sections (m^2), single-scattering albedo, g and
/// the paper's HG g of `distribution` at vacuum wavelength `wavelength_nm`
/// (nm) for refractive index `refractive_index`, integrated with the
/// composite Gauss-Legendre rule laid out by `settings`
/// ([`RadiusQuadratureSettings::cross_sections`] is the validated choice).
pub fn compute_ensemble_cross_sections(
    wavelength_nm: f64,
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
) -> Result<EnsembleCrossSections, EnsembleError> {
    let mut per_wavelength =
        compute_shared_cross_sections(&[wavelength_nm], refractive_index, distribution, settings)?;
    Ok(per_wavelength.remove(0))
}

/// Cross-sections at several wavelengths at which the particles have the
/// same refractive index, from one Mie solution per node of a
/// [`SharedSizeParameterQuadrature`].
fn compute_shared_cross_sections(
    wavelengths_nm: &[f64],
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
) -> Result<Vec<EnsembleCrossSections>, EnsembleError> {
    let wavenumbers_per_m = wavelengths_nm
        .iter()
        .map(|&lambda| validate_wavelength(lambda))
        .collect::<Result<Vec<f64>, EnsembleError>>()?;
    let quadrature =
        SharedSizeParameterQuadrature::gauss_legendre(distribution, &wavenumbers_per_m, settings)?;
    // Per wavelength: sums of w x^2 Q_ext, w x^2 Q_sca, w x^2 Q_abs,
    // w x^2 Q_sca g and w x^2 Q_sca g_paper(r); pi / k^2 is applied at the end.
    let mut sums = vec![[0.0f64; 5]; wavelengths_nm.len()];
    // All nodes at once: the solver runs SPHERE_LANES neighbouring nodes
    // side by side (see `sphere::compute_efficiencies_many_with`).
    let size_parameters = quadrature.size_parameters();
    let mut node_efficiencies = vec![
        Efficiencies {
            qext: 0.0,
            qsca: 0.0,
            qabs: 0.0,
            qback: 0.0,
            g: 0.0,
        };
        size_parameters.len()
    ];
    compute_efficiencies_many_with(
        &mut SphereWorkspace::new(),
        refractive_index,
        size_parameters,
        &mut node_efficiencies,
    )
    .map_err(|error| {
        // Name the first node the solver rejects.
        let node = size_parameters
            .iter()
            .position(|&x| compute_efficiencies(refractive_index, x).is_err())
            .unwrap_or(0);
        EnsembleError::Mie {
            wavelength_nm: wavelengths_nm[0],
            radius_m: size_parameters.get(node).copied().unwrap_or(f64::NAN) / wavenumbers_per_m[0],
            error,
        }
    })?;
    for (node, (&size_parameter, efficiencies)) in
        size_parameters.iter().zip(&node_efficiencies).enumerate()
    {
        let x_squared = size_parameter * size_parameter;
        for ((sum, &weight), &wavenumber) in sums
            .iter_mut()
            .zip(quadrature.weights_at_node(node))
            .zip(&wavenumbers_per_m)
        {
            if weight == 0.0 {
                continue;
            }
            let weighted_area = weight * x_squared;
            let weighted_scattering = weighted_area * efficiencies.qsca;
            let radius_m = size_parameter / wavenumber;
            sum[0] += weighted_area * efficiencies.qext;
            sum[1] += weighted_scattering;
            sum[2] += weighted_area * efficiencies.qabs;
            sum[3] += weighted_scattering * efficiencies.g;
            sum[4] += weighted_scattering * paper_asymmetry_parameter_for_radius(radius_m);
        }
    }
    Ok(sums
        .iter()
        .zip(wavelengths_nm)
        .zip(&wavenumbers_per_m)
        .map(|((sum, &wavelength_nm), &wavenumber)| {
            let area_per_x_squared_m2 = PI / (wavenumber * wavenumber);
            EnsembleCrossSections {
                wavelength_nm,
                refractive_index,
                extinction_cross_section_m2: sum[0] * area_per_x_squared_m2,
                scattering_cross_section_m2: sum[1] * area_per_x_squared_m2,
                absorption_cross_section_m2: sum[2] * area_per_x_squared_m2,
                single_scattering_albedo: sum[1] / sum[0],
                asymmetry_parameter: sum[3] / sum[1],
                paper_asymmetry_parameter: sum[4] / sum[1],
                number_fraction_in_window: distribution.number_fraction_in_window(),
                radius_node_count: quadrature.len(),
            }
        })
        .collect())
}

/// As [`compute_ensemble_cross_sections`] with any quadrature, e.g. the slow
/// [`RadiusQuadrature::trapezoid`] oracle built for the same distribution.
pub fn integrate_ensemble_cross_sections(
    wavelength_nm: f64,
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    quadrature: &RadiusQuadrature,
) -> Result<EnsembleCrossSections, EnsembleError> {
    let wavenumber_per_m = validate_wavelength(wavelength_nm)?;
    let mut extinction_m2 = 0.0;
    let mut scattering_m2 = 0.0;
    let mut absorption_m2 = 0.0;
    let mut scattering_times_g_m2 = 0.0;
    let mut scattering_times_paper_g_m2 = 0.0;
    for (&radius_m, &weight) in quadrature.radii_m().iter().zip(quadrature.weights()) {
        let efficiencies = compute_efficiencies(refractive_index, wavenumber_per_m * radius_m)
            .map_err(|error| EnsembleError::Mie {
                wavelength_nm,
                radius_m,
                error,
            })?;
        let weighted_area_m2 = weight * PI * radius_m * radius_m;
        let weighted_scattering_m2 = weighted_area_m2 * efficiencies.qsca;
        extinction_m2 += weighted_area_m2 * efficiencies.qext;
        scattering_m2 += weighted_scattering_m2;
        absorption_m2 += weighted_area_m2 * efficiencies.qabs;
        scattering_times_g_m2 += weighted_scattering_m2 * efficiencies.g;
        scattering_times_paper_g_m2 +=
            weighted_scattering_m2 * paper_asymmetry_parameter_for_radius(radius_m);
    }
    Ok(EnsembleCrossSections {
        wavelength_nm,
        refractive_index,
        extinction_cross_section_m2: extinction_m2,
        scattering_cross_section_m2: scattering_m2,
        absorption_cross_section_m2: absorption_m2,
        single_scattering_albedo: scattering_m2 / extinction_m2,
        asymmetry_parameter: scattering_times_g_m2 / scattering_m2,
        paper_asymmetry_parameter: scattering_times_paper_g_m2 / scattering_m2,
        number_fraction_in_window: distribution.number_fraction_in_window(),
        radius_node_count: quadrature.len(),
    })
}

/// (start, end, step) in degrees of the phase table's uniform segments.
const PHASE_TABLE_SEGMENTS_DEG: [(f64, f64, f64); 5] = [
    (0.0, 1.0, 0.02),
    (1.0, 5.0, 0.05),
    (5.0, 20.0, 0.2),
    (20.0, 60.0, 0.5),
    (60.0, 180.0, 1.0),
];

/// The scattering angles of the ensemble phase table (degrees, increasing
/// from 0 to 180): 0-1 by 0.02, 1-5 by 0.05, 5-20 by 0.2, 20-60 by 0.5,
/// 60-180 by 1 (406 angles).
pub fn ensemble_phase_table_angles_deg() -> Vec<f64> {
    let mut angles_deg = Vec::new();
    for (start_deg, end_deg, step_deg) in PHASE_TABLE_SEGMENTS_DEG {
        let steps = ((end_deg - start_deg) / step_deg).round() as usize;
        // Each node from its index, so no rounding accumulates.
        angles_deg.extend((0..steps).map(|i| start_deg + i as f64 * step_deg));
    }
    angles_deg.push(180.0);
    angles_deg
}

/// Why a tabulated phase function could not be built.
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidPhaseTable {
    pub message: String,
}

impl std::fmt::Display for InvalidPhaseTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "invalid phase-function table: {}", self.message)
    }
}

impl std::error::Error for InvalidPhaseTable {}

/// A phase function tabulated against mu = cos theta, linear in mu between
/// nodes, normalised to 1 over 4 pi sr, with its cumulative distribution for
/// sampling (see the module docs). All densities are per steradian.
#[derive(Debug, Clone, PartialEq)]
pub struct TabulatedPhaseFunction {
    /// Node cosines, increasing from -1 to 1.
    cos_theta: Vec<f64>,
    /// Phase function at the nodes (sr^-1), normalised.
    phase_per_sr: Vec<f64>,
    /// F_i = 2 pi integral_{-1}^{mu_i} P dmu: 0 at mu = -1, 1 at mu = 1.
    cumulative: Vec<f64>,
    /// 2 pi integral of the table before rescaling.
    normalisation_before_rescaling: f64,
}

impl TabulatedPhaseFunction {
    /// A table from node cosines (strictly increasing, from exactly -1 to
    /// exactly 1) and phase-function values at them (finite, >= 0, not all
    /// 0; any normalisation: they are rescaled so that the linear-in-mu
    /// interpolant integrates to 1 over 4 pi sr).
    pub fn from_nodes(
        cos_theta: Vec<f64>,
        mut phase_per_sr: Vec<f64>,
    ) -> Result<Self, InvalidPhaseTable> {
        let invalid = |message: String| Err(InvalidPhaseTable { message });
        if cos_theta.len() != phase_per_sr.len() || cos_theta.len() < 2 {
            return invalid(format!(
                "{} cosines and {} values: need equal lengths of at least 2",
                cos_theta.len(),
                phase_per_sr.len()
            ));
        }
        if cos_theta[0] != -1.0 || cos_theta[cos_theta.len() - 1] != 1.0 {
            return invalid("cosines must run from exactly -1 to exactly 1".to_string());
        }
        if cos_theta
            .windows(2)
            .any(|pair| pair[1].partial_cmp(&pair[0]) != Some(std::cmp::Ordering::Greater))
        {
            return invalid("cosines must increase strictly".to_string());
        }
        if phase_per_sr.iter().any(|p| !(p.is_finite() && *p >= 0.0)) {
            return invalid("phase-function values must be finite and >= 0".to_string());
        }
        let mut cumulative = Vec::with_capacity(cos_theta.len());
        let mut running = 0.0;
        cumulative.push(0.0);
        for i in 1..cos_theta.len() {
            running += 2.0
                * PI
                * (cos_theta[i] - cos_theta[i - 1])
                * 0.5
                * (phase_per_sr[i] + phase_per_sr[i - 1]);
            cumulative.push(running);
        }
        let normalisation_before_rescaling = running;
        if normalisation_before_rescaling.is_nan() || normalisation_before_rescaling <= 0.0 {
            return invalid("the phase function integrates to 0".to_string());
        }
        for value in &mut phase_per_sr {
            *value /= normalisation_before_rescaling;
        }
        for value in &mut cumulative {
            *value /= normalisation_before_rescaling;
        }
        let last = cumulative.len() - 1;
        cumulative[last] = 1.0;
        Ok(Self {
            cos_theta,
            phase_per_sr,
            cumulative,
            normalisation_before_rescaling,
        })
    }

    /// Node cosines, increasing from -1 to 1.
    pub fn cos_theta_nodes(&self) -> &[f64] {
        &self.cos_theta
    }

    /// Normalised phase function at the nodes (sr^-1).
    pub fn phase_per_sr_nodes(&self) -> &[f64] {
        &self.phase_per_sr
    }

    /// Cumulative distribution at the nodes: 2 pi integral_{-1}^{mu_i} P dmu.
    pub fn cumulative_distribution(&self) -> &[f64] {
        &self.cumulative
    }

    /// The integral over 4 pi sr of the values as given (before rescaling to
    /// 1): for a table of exact phase-function values, 1 minus this is the
    /// interpolation error of the table.
    pub fn normalisation_before_rescaling(&self) -> f64 {
        self.normalisation_before_rescaling
    }

    /// Index i of the interval [mu_i, mu_{i+1}] holding `cos_theta` (clamped).
    fn interval_index(&self, cos_theta: f64) -> usize {
        let upper = self.cos_theta.partition_point(|&mu| mu <= cos_theta);
        upper.clamp(1, self.cos_theta.len() - 1) - 1
    }

    /// Phase function at `cos_theta` (sr^-1), linear in cos theta between
    /// nodes; `cos_theta` is clamped to [-1, 1].
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        let mu = cos_theta.clamp(-1.0, 1.0);
        let i = self.interval_index(mu);
        let t = (mu - self.cos_theta[i]) / (self.cos_theta[i + 1] - self.cos_theta[i]);
        self.phase_per_sr[i] + t * (self.phase_per_sr[i + 1] - self.phase_per_sr[i])
    }

    /// Probability density per steradian of scattering into `cos_theta`:
    /// identical to [`Self::phase_function_per_sr`].
    pub fn pdf_per_sr(&self, cos_theta: f64) -> f64 {
        self.phase_function_per_sr(cos_theta)
    }

    /// cos theta for a uniform random number `uniform_sample` in [0, 1],
    /// distributed with density [`Self::pdf_per_sr`] (0 maps to mu = -1, 1 to
    /// mu = 1): exact inversion of the piecewise-quadratic cumulative
    /// distribution.
    pub fn sample_cos_theta(&self, uniform_sample: f64) -> f64 {
        let u = uniform_sample.clamp(0.0, 1.0);
        let upper = self.cumulative.partition_point(|&f| f <= u);
        let i = upper.clamp(1, self.cumulative.len() - 1) - 1;
        let width = self.cos_theta[i + 1] - self.cos_theta[i];
        // On the interval, 2 pi width (P_i t + (P_{i+1} - P_i) t^2 / 2) = u - F_i:
        // the root in [0, 1] of a t^2 + b t - c = 0, written without cancellation.
        let a = 0.5 * (self.phase_per_sr[i + 1] - self.phase_per_sr[i]);
        let b = self.phase_per_sr[i];
        let c = (u - self.cumulative[i]).max(0.0) / (2.0 * PI * width);
        let discriminant = (b * b + 4.0 * a * c).max(0.0);
        let denominator = b + discriminant.sqrt();
        let t = if denominator > 0.0 {
            2.0 * c / denominator
        } else {
            0.0
        };
        self.cos_theta[i] + t.clamp(0.0, 1.0) * width
    }

    /// Mean cosine 2 pi integral mu P(mu) dmu of the interpolant (exact for
    /// piecewise-linear P).
    pub fn asymmetry_parameter(&self) -> f64 {
        let mut sum = 0.0;
        for i in 0..self.cos_theta.len() - 1 {
            let (mu0, mu1) = (self.cos_theta[i], self.cos_theta[i + 1]);
            let (p0, p1) = (self.phase_per_sr[i], self.phase_per_sr[i + 1]);
            sum += (mu1 - mu0) / 6.0 * (p0 * (2.0 * mu0 + mu1) + p1 * (mu0 + 2.0 * mu1));
        }
        2.0 * PI * sum
    }
}

/// Constants of term n of the angular sums, for n = 1, 2, ...: the term
/// factor (2n+1)/(n(n+1)) of B&H eq. 4.74 and the ratios (2n+1)/n and
/// (n+1)/n of the pi_n recurrence (B&H eq. 4.47), tabulated once rather than
/// divided out in every angle block.
#[derive(Debug, Clone, Copy)]
struct AngularTermConstants {
    n: f64,
    term_factor: f64,
    pi_ratio_current: f64,
    pi_ratio_previous: f64,
}

impl AngularTermConstants {
    fn new(index: usize) -> Self {
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
fn accumulate_s11(
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
struct AccumulateS11<'a> {
    cos_theta: &'a [f64],
    constants: &'a [AngularTermConstants],
    terms: &'a [[f64; 4]],
    spheres: usize,
    s11: &'a mut [f64],
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
fn add_weighted_group(
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
struct AddWeightedGroup<'a> {
    tables: &'a mut [f64],
    s11: &'a [f64],
    first: usize,
    stride: usize,
    nodes: usize,
    weights: &'a [[f64; SPHERE_LANES]],
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

/// Scratch tables of the phase-table integration, allocated once per
/// spectrum rather than per wavelength or node.
struct PhaseTableWorkspace {
    /// cos theta of the table angles, increasing (theta decreasing).
    cos_theta: Vec<f64>,
    /// Constants of the angular sums' terms n = 1, 2, ... (grown as needed).
    term_constants: Vec<AngularTermConstants>,
    /// The Mie solver's tables.
    sphere: SphereWorkspace,
    /// Coefficients of one group of nodes, per reference index.
    groups: Vec<GroupCoefficients>,
    /// Term factors times (a_n +- b_n) of one node, [n][reference].
    terms: Vec<[f64; 4]>,
    /// S11 of each node of a group, [node][reference][angle].
    node_s11: Vec<f64>,
    /// sum of w S11, row-major [reference][wavelength][angle].
    accumulated_s11: Vec<f64>,
}

impl PhaseTableWorkspace {
    fn new() -> Self {
        let mut cos_theta: Vec<f64> = ensemble_phase_table_angles_deg()
            .iter()
            .map(|theta_deg| theta_deg.to_radians().cos())
            .collect();
        cos_theta.reverse();
        // cos(0) and cos(pi) are exact in floating point; set them anyway,
        // as the table requires exactly -1 and 1 at its ends.
        let last = cos_theta.len() - 1;
        cos_theta[0] = -1.0;
        cos_theta[last] = 1.0;
        Self {
            cos_theta,
            term_constants: Vec::new(),
            sphere: SphereWorkspace::new(),
            groups: Vec::new(),
            terms: Vec::new(),
            node_s11: Vec::new(),
            accumulated_s11: Vec::new(),
        }
    }

    /// Phase tables at `wavelengths_nm`, at all of which the particles have
    /// index `refractive_index`, from one Mie solution per node.
    fn compute(
        &mut self,
        wavelengths_nm: &[f64],
        refractive_index: Complex64,
        distribution: &SizeDistribution,
        settings: &RadiusQuadratureSettings,
    ) -> Result<Vec<TabulatedPhaseFunction>, EnsembleError> {
        let mut tables =
            self.compute_for_indices(wavelengths_nm, &[refractive_index], distribution, settings)?;
        Ok(tables.remove(0))
    }

    /// Phase tables at `wavelengths_nm` for each of `refractive_indices`
    /// (`result[index][wavelength]`), each index as if the particles had it
    /// at every wavelength. The indices share the quadrature (it depends on
    /// the distribution and the wavelengths only) and with it the angular
    /// functions of each node; the Mie solutions are computed for groups of
    /// [`SPHERE_LANES`] neighbouring nodes side by side.
    fn compute_for_indices(
        &mut self,
        wavelengths_nm: &[f64],
        refractive_indices: &[Complex64],
        distribution: &SizeDistribution,
        settings: &RadiusQuadratureSettings,
    ) -> Result<Vec<Vec<TabulatedPhaseFunction>>, EnsembleError> {
        let wavenumbers_per_m = wavelengths_nm
            .iter()
            .map(|&lambda| validate_wavelength(lambda))
            .collect::<Result<Vec<f64>, EnsembleError>>()?;
        let quadrature = SharedSizeParameterQuadrature::gauss_legendre(
            distribution,
            &wavenumbers_per_m,
            settings,
        )?;
        let angle_count = self.cos_theta.len();
        let index_count = refractive_indices.len();
        let wavelength_count = wavelengths_nm.len();
        self.accumulated_s11.clear();
        self.accumulated_s11
            .resize(index_count * wavelength_count * angle_count, 0.0);
        while self.groups.len() < index_count {
            self.groups.push(GroupCoefficients::new());
        }
        // sum of w x^2 Q_sca, [index][wavelength].
        let mut scattering_x_squared = vec![0.0; index_count * wavelength_count];
        let size_parameters = quadrature.size_parameters();
        // The group's node weights, [wavelength][node].
        let mut group_weights: Vec<[f64; SPHERE_LANES]> = Vec::with_capacity(wavelength_count);
        for (group_index, group_x) in size_parameters.chunks(SPHERE_LANES).enumerate() {
            let first_node = group_index * SPHERE_LANES;
            for (&m, group) in refractive_indices.iter().zip(&mut self.groups) {
                compute_group_coefficients(&mut self.sphere, m, group_x, group).map_err(
                    |error| {
                        let node = group_x
                            .iter()
                            .position(|&x| compute_efficiencies(m, x).is_err())
                            .unwrap_or(0);
                        EnsembleError::Mie {
                            wavelength_nm: wavelengths_nm[0],
                            radius_m: group_x[node] / wavenumbers_per_m[0],
                            error,
                        }
                    },
                )?;
            }
            // S11 of each node of the group, all indices at once.
            self.node_s11.clear();
            self.node_s11
                .resize(group_x.len() * index_count * angle_count, 0.0);
            for (lane, node_s11) in self
                .node_s11
                .chunks_exact_mut(index_count * angle_count)
                .enumerate()
            {
                let n_terms = self.groups[0].a[lane].len();
                while self.term_constants.len() < n_terms {
                    let index = self.term_constants.len();
                    self.term_constants.push(AngularTermConstants::new(index));
                }
                self.terms.clear();
                for (index, constants) in self.term_constants[..n_terms].iter().enumerate() {
                    for group in &self.groups[..index_count] {
                        let (a_n, b_n) = (group.a[lane][index], group.b[lane][index]);
                        let sum = constants.term_factor * (a_n + b_n);
                        let difference = constants.term_factor * (a_n - b_n);
                        self.terms
                            .push([sum.re, sum.im, difference.re, difference.im]);
                    }
                }
                accumulate_s11(
                    &self.cos_theta,
                    &self.term_constants[..n_terms],
                    &self.terms,
                    index_count,
                    node_s11,
                );
            }
            // Add w S11 to every (index, wavelength) table, the group's
            // nodes in order (a node outside a wavelength's window has
            // weight 0 and adds exactly 0).
            group_weights.clear();
            for wavelength in 0..wavelength_count {
                let mut weights = [0.0; SPHERE_LANES];
                for (lane, weight) in weights.iter_mut().enumerate().take(group_x.len()) {
                    *weight = quadrature.weights_at_node(first_node + lane)[wavelength];
                }
                group_weights.push(weights);
            }
            for index in 0..index_count {
                for (wavelength, weights) in group_weights.iter().enumerate() {
                    for (lane, &x) in group_x.iter().enumerate() {
                        let qsca = self.groups[index].efficiencies[lane].qsca;
                        scattering_x_squared[index * wavelength_count + wavelength] +=
                            weights[lane] * x * x * qsca;
                    }
                }
                let tables_start = index * wavelength_count * angle_count;
                add_weighted_group(
                    &mut self.accumulated_s11
                        [tables_start..tables_start + wavelength_count * angle_count],
                    &self.node_s11,
                    index * angle_count,
                    index_count * angle_count,
                    group_x.len(),
                    &group_weights,
                );
            }
        }
        // P = integral S11 dN / (k^2 integral C_sca dN) = sum w S11 / (pi sum w x^2 Q_sca),
        // with the same nodes in both sums so that their quadrature errors cancel.
        let mut tables = Vec::with_capacity(index_count);
        for index in 0..index_count {
            let mut per_wavelength = Vec::with_capacity(wavelength_count);
            for (wavelength, &wavelength_nm) in wavelengths_nm.iter().enumerate() {
                let table_start = (index * wavelength_count + wavelength) * angle_count;
                let table_sums = &self.accumulated_s11[table_start..table_start + angle_count];
                let scale =
                    1.0 / (PI * scattering_x_squared[index * wavelength_count + wavelength]);
                let phase_per_sr: Vec<f64> = table_sums.iter().map(|s| s * scale).collect();
                per_wavelength.push(
                    TabulatedPhaseFunction::from_nodes(self.cos_theta.clone(), phase_per_sr)
                        .map_err(|error| {
                            EnsembleError::Distribution(
                                SizeDistributionError::InvalidQuadratureSettings {
                                    message: format!("phase table at {wavelength_nm} nm: {error}"),
                                },
                            )
                        })?,
                );
            }
            tables.push(per_wavelength);
        }
        Ok(tables)
    }
}

/// Number of reference values of ln k of the index interpolation (Chebyshev-Lobatto points).
const INTERPOLATION_ABSORPTION_NODES: usize = 4;

/// Widest spread of the real part n over a spectrum that the index
/// interpolation (linear in n) accepts; validated on the Wolff et al.
/// (2009) Mars dust, whose n spans 0.0044 over 380-780 nm.
pub const MAX_INTERPOLATED_REAL_INDEX_SPREAD: f64 = 0.01;

/// Largest ratio k_max / k_min that the index interpolation (cubic in ln k)
/// accepts; validated on the Wolff et al. (2009) Mars dust (ratio 10.5).
pub const MAX_INTERPOLATED_ABSORPTION_RATIO: f64 = 20.0;

/// Whether [`SpectralPhaseMethod::IndexInterpolated`] interpolates for
/// these distinct indices, rather than computing each exactly: more distinct
/// indices than the interpolation's reference computations, all absorbing
/// (k > 0, as ln k is the interpolation variable), n spread at most
/// [`MAX_INTERPOLATED_REAL_INDEX_SPREAD`] and k_max / k_min at most
/// [`MAX_INTERPOLATED_ABSORPTION_RATIO`].
pub fn index_interpolation_applies(distinct_indices: &[Complex64]) -> bool {
    let Some(plan) = IndexInterpolationPlan::new(distinct_indices) else {
        return false;
    };
    distinct_indices.len() > plan.reference_indices().len()
}

/// The reference indices of the index interpolation and the weights that
/// combine their tables for one index (see the module docs).
#[derive(Debug, Clone, PartialEq)]
struct IndexInterpolationPlan {
    /// ln k of the reference indices at n_mid (Chebyshev-Lobatto in [ln k_min, ln k_max]).
    ln_absorption_nodes: [f64; INTERPOLATION_ABSORPTION_NODES],
    /// n_mid = (n_min + n_max) / 2.
    real_mid: f64,
    /// n_max - n_mid: the step of the n reference (0: n is constant, no n reference).
    real_half_spread: f64,
}

impl IndexInterpolationPlan {
    /// The plan for these indices, or `None` outside the validated range.
    fn new(indices: &[Complex64]) -> Option<Self> {
        let first = indices.first()?;
        let (mut k_min, mut k_max, mut n_min, mut n_max) = (first.im, first.im, first.re, first.re);
        for m in indices {
            k_min = k_min.min(m.im);
            k_max = k_max.max(m.im);
            n_min = n_min.min(m.re);
            n_max = n_max.max(m.re);
        }
        let valid = k_min > 0.0
            && k_max.is_finite()
            && k_max <= MAX_INTERPOLATED_ABSORPTION_RATIO * k_min
            && n_max - n_min <= MAX_INTERPOLATED_REAL_INDEX_SPREAD
            // Distinct values of ln k, or the Lagrange basis is singular.
            && k_max > k_min * (1.0 + 1e-6);
        if !valid {
            return None;
        }
        let (lower, upper) = (k_min.ln(), k_max.ln());
        let (centre, half_width) = (0.5 * (lower + upper), 0.5 * (upper - lower));
        let mut ln_absorption_nodes = [0.0; INTERPOLATION_ABSORPTION_NODES];
        for (j, node) in ln_absorption_nodes.iter_mut().enumerate() {
            let angle = PI * j as f64 / (INTERPOLATION_ABSORPTION_NODES - 1) as f64;
            *node = centre - half_width * angle.cos();
        }
        // The end nodes exactly at the ends (cos rounding), so that no weight extrapolates.
        ln_absorption_nodes[0] = lower;
        ln_absorption_nodes[INTERPOLATION_ABSORPTION_NODES - 1] = upper;
        let real_mid = 0.5 * (n_min + n_max);
        Some(Self {
            ln_absorption_nodes,
            real_mid,
            real_half_spread: n_max - real_mid,
        })
    }

    /// Index of the reference that sits beside the n reference (same k, n_mid).
    const REAL_PARTNER: usize = INTERPOLATION_ABSORPTION_NODES / 2;

    /// The reference indices: n_mid + i k_j for each ln k node, then (if n
    /// varies) n_max + i k_{REAL_PARTNER}.
    fn reference_indices(&self) -> Vec<Complex64> {
        let mut references: Vec<Complex64> = self
            .ln_absorption_nodes
            .iter()
            .map(|&ln_k| Complex64::new(self.real_mid, ln_k.exp()))
            .collect();
        if self.real_half_spread > 0.0 {
            references.push(Complex64::new(
                self.real_mid + self.real_half_spread,
                self.ln_absorption_nodes[Self::REAL_PARTNER].exp(),
            ));
        }
        references
    }

    /// Weight of each reference table for index `m`: the Lagrange basis in
    /// ln k at n_mid, plus t (P(n_max) - P(n_mid)) at the partner k, t =
    /// (n - n_mid) / (n_max - n_mid).
    fn weights(&self, m: Complex64) -> Vec<f64> {
        let ln_k = m.im.ln();
        let nodes = &self.ln_absorption_nodes;
        let mut weights: Vec<f64> = (0..nodes.len())
            .map(|j| {
                nodes
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != j)
                    .map(|(_, &node)| (ln_k - node) / (nodes[j] - node))
                    .product()
            })
            .collect();
        if self.real_half_spread > 0.0 {
            let t = (m.re - self.real_mid) / self.real_half_spread;
            weights[Self::REAL_PARTNER] -= t;
            weights.push(t);
        }
        weights
    }
}

impl PhaseTableWorkspace {
    /// Phase tables at `wavelengths_nm`, where the particles have index
    /// `indices[i]` at `wavelengths_nm[i]`, by interpolation in the index
    /// between tables computed for all the wavelengths at a few reference
    /// indices (see the module docs). `indices` must satisfy
    /// [`index_interpolation_applies`].
    fn compute_index_interpolated(
        &mut self,
        wavelengths_nm: &[f64],
        indices: &[Complex64],
        distribution: &SizeDistribution,
        settings: &RadiusQuadratureSettings,
    ) -> Result<Vec<TabulatedPhaseFunction>, EnsembleError> {
        let plan = IndexInterpolationPlan::new(indices)
            .expect("the caller checked index_interpolation_applies");
        let reference_tables = self.compute_for_indices(
            wavelengths_nm,
            &plan.reference_indices(),
            distribution,
            settings,
        )?;
        let angle_count = self.cos_theta.len();
        let mut tables = Vec::with_capacity(wavelengths_nm.len());
        for (wavelength, (&wavelength_nm, &m)) in wavelengths_nm.iter().zip(indices).enumerate() {
            let weights = plan.weights(m);
            let mut phase_per_sr = vec![0.0; angle_count];
            for (weight, reference) in weights.iter().zip(&reference_tables) {
                for (value, &reference_value) in phase_per_sr
                    .iter_mut()
                    .zip(reference[wavelength].phase_per_sr_nodes())
                {
                    *value += weight * reference_value;
                }
            }
            // The weights sum to 1 and each reference is positive; an
            // interpolant below 0 (never seen) would be clipped.
            phase_per_sr.iter_mut().for_each(|p| *p = p.max(0.0));
            tables.push(
                TabulatedPhaseFunction::from_nodes(self.cos_theta.clone(), phase_per_sr).map_err(
                    |error| {
                        EnsembleError::Distribution(
                            SizeDistributionError::InvalidQuadratureSettings {
                                message: format!(
                                    "interpolated phase table at {wavelength_nm} nm: {error}"
                                ),
                            },
                        )
                    },
                )?,
            );
        }
        Ok(tables)
    }
}

/// The ensemble Mie phase function of `distribution` at `wavelength_nm`
/// (nm) for `refractive_index`, tabulated on [`ensemble_phase_table_angles_deg`]
/// and integrated over radius with `settings`
/// ([`RadiusQuadratureSettings::phase_function`] is the validated choice).
pub fn compute_ensemble_phase_function(
    wavelength_nm: f64,
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
) -> Result<TabulatedPhaseFunction, EnsembleError> {
    let mut tables = PhaseTableWorkspace::new().compute(
        &[wavelength_nm],
        refractive_index,
        distribution,
        settings,
    )?;
    Ok(tables.remove(0))
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
                    // The paper's g lies in [0.5, 0.9], so this cannot fail.
                    let hg = HenyeyGreensteinPhaseFunction::new(c.paper_asymmetry_parameter)
                        .expect("the paper's g(r) lies in [0.5, 0.9]");
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distribution::RadiusWindow;
    use crate::paper_phase::henyey_greenstein_phase_function_per_sr;
    use crate::simd::Build;
    use crate::sphere::MieSolution;

    const MICROMETRE: f64 = 1e-6;

    /// [`accumulate_s11`] in `build` (which the CPU must support).
    fn accumulate_s11_as(
        build: Build,
        cos_theta: &[f64],
        constants: &[AngularTermConstants],
        terms: &[[f64; 4]],
        spheres: usize,
        s11: &mut [f64],
    ) {
        simd::run_as(
            build,
            AccumulateS11 {
                cos_theta,
                constants,
                terms,
                spheres,
                s11,
            },
        )
    }

    fn table_cosines() -> Vec<f64> {
        PhaseTableWorkspace::new().cos_theta
    }

    #[test]
    fn angle_table_is_as_documented() {
        let angles = ensemble_phase_table_angles_deg();
        assert_eq!(angles.len(), 406);
        assert_eq!(angles[0], 0.0);
        assert_eq!(angles[1], 0.02);
        assert_eq!(angles[50], 1.0);
        assert_eq!(angles[angles.len() - 1], 180.0);
        assert!(angles.windows(2).all(|w| w[1] > w[0]));
        let cosines = table_cosines();
        assert_eq!((cosines[0], cosines[cosines.len() - 1]), (-1.0, 1.0));
        assert!(cosines.windows(2).all(|w| w[1] > w[0]));
    }

    /// A Henyey-Greenstein function tabulated on the ensemble angles: the
    /// table's interpolation error is measurable against the exact function.
    #[test]
    fn tabulated_henyey_greenstein_keeps_normalisation_and_mean_cosine() {
        let cosines = table_cosines();
        for g in [0.0, 0.5, 0.8, 0.95] {
            let values: Vec<f64> = cosines
                .iter()
                .map(|&mu| henyey_greenstein_phase_function_per_sr(g, mu))
                .collect();
            let table = TabulatedPhaseFunction::from_nodes(cosines.clone(), values).unwrap();
            // The exact values integrate to 1; the interpolant's excess is the table error.
            let excess = (table.normalisation_before_rescaling() - 1.0).abs();
            // Measured: 4e-5 (g 0.5), 1.2e-4 (0.8), 2.8e-4 (0.95); mean cosine
            // after rescaling within 5.3e-6 of g.
            assert!(
                excess < 4e-4,
                "g {g}: raw normalisation {}",
                table.normalisation_before_rescaling()
            );
            assert!(
                (table.asymmetry_parameter() - g).abs() < 1e-5,
                "g {g}: <mu> {}",
                table.asymmetry_parameter()
            );
            // Interpolated between nodes, within 1% of the exact function.
            for theta_deg in [0.013f64, 0.5, 3.33, 17.1, 45.5, 120.7, 179.5] {
                let mu = theta_deg.to_radians().cos();
                let exact = henyey_greenstein_phase_function_per_sr(g, mu);
                let value = table.phase_function_per_sr(mu);
                assert!(
                    (value / exact - 1.0).abs() < 1e-2,
                    "g {g} theta {theta_deg}: {value} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn tabulated_sampling_inverts_the_cumulative_distribution() {
        let cosines = table_cosines();
        let values: Vec<f64> = cosines
            .iter()
            .map(|&mu| henyey_greenstein_phase_function_per_sr(0.85, mu))
            .collect();
        let table = TabulatedPhaseFunction::from_nodes(cosines, values).unwrap();
        assert_eq!(table.sample_cos_theta(0.0), -1.0);
        assert_eq!(table.sample_cos_theta(1.0), 1.0);
        let mut previous = -1.0;
        for i in 1..1000 {
            let u = i as f64 / 1000.0;
            let mu = table.sample_cos_theta(u);
            assert!(mu >= previous, "sampling must be monotone");
            previous = mu;
            // F(mu) by integrating the linear pieces up to mu exactly.
            let k = table.interval_index(mu);
            let nodes = table.cos_theta_nodes();
            let (mu0, p0) = (nodes[k], table.phase_per_sr_nodes()[k]);
            let p_mu = table.pdf_per_sr(mu);
            let cumulative =
                table.cumulative_distribution()[k] + 2.0 * PI * (mu - mu0) * 0.5 * (p0 + p_mu);
            assert!(
                (cumulative - u).abs() < 1e-12,
                "u {u}: F(mu) = {cumulative}"
            );
        }
    }

    #[test]
    fn invalid_tables_are_rejected() {
        assert!(TabulatedPhaseFunction::from_nodes(vec![-1.0, 1.0], vec![1.0]).is_err());
        assert!(TabulatedPhaseFunction::from_nodes(vec![-0.9, 1.0], vec![1.0, 1.0]).is_err());
        assert!(
            TabulatedPhaseFunction::from_nodes(vec![-1.0, 0.5, 0.5, 1.0], vec![1.0; 4]).is_err()
        );
        assert!(TabulatedPhaseFunction::from_nodes(vec![-1.0, 1.0], vec![1.0, -1.0]).is_err());
        assert!(TabulatedPhaseFunction::from_nodes(vec![-1.0, 1.0], vec![0.0, 0.0]).is_err());
        let isotropic =
            TabulatedPhaseFunction::from_nodes(vec![-1.0, 1.0], vec![3.0, 3.0]).unwrap();
        assert!((isotropic.phase_function_per_sr(0.2) - 1.0 / (4.0 * PI)).abs() < 1e-16);
    }

    #[test]
    fn invalid_inputs_are_errors_not_panics() {
        let distribution = SizeDistribution::log_normal(0.5 * MICROMETRE, 1.5).unwrap();
        let model = RefractiveIndexModel::constant(Complex64::new(1.5, 0.01)).unwrap();
        let settings = EnsembleSettings::default();
        assert!(matches!(
            compute_ensemble_optics(f64::NAN, &model, &distribution, &settings),
            Err(EnsembleError::InvalidWavelength { .. })
        ));
        assert!(compute_ensemble_optics(-500.0, &model, &distribution, &settings).is_err());
        let table = crate::refractive_index::TabulatedRefractiveIndex::from_columns(
            vec![500.0, 600.0],
            vec![1.5, 1.5],
            vec![0.01, 0.01],
        )
        .unwrap();
        let error = compute_ensemble_optics(
            450.0,
            &RefractiveIndexModel::Tabulated(table),
            &distribution,
            &settings,
        )
        .unwrap_err();
        assert!(error.to_string().contains("450 nm"), "{error}");
        let bad_settings = EnsembleSettings {
            cross_section_quadrature: RadiusQuadratureSettings {
                nodes_per_panel: 0,
                ..RadiusQuadratureSettings::cross_sections()
            },
            ..settings
        };
        assert!(matches!(
            compute_ensemble_optics(500.0, &model, &distribution, &bad_settings),
            Err(EnsembleError::Distribution(_))
        ));
        let _ = RadiusWindow::from_micrometres(0.1, 2.5).unwrap();
    }

    fn mars_dust() -> SizeDistribution {
        SizeDistribution::log_normal(0.78 * MICROMETRE, 1.67).unwrap()
    }

    fn paper_table1_aerosol() -> SizeDistribution {
        SizeDistribution::log_normal(0.5 * MICROMETRE, 2.0)
            .unwrap()
            .truncated_to(RadiusWindow::from_micrometres(0.1, 2.5).unwrap())
            .unwrap()
    }

    /// 2 pi integral_{-1}^{1} f(mu) dmu by composite Simpson, independent of
    /// the table's own (trapezoid-in-mu) integral.
    fn integrate_over_sphere(f: impl Fn(f64) -> f64, intervals: usize) -> f64 {
        let h = 2.0 / intervals as f64;
        let mut sum = f(-1.0) + f(1.0);
        for i in 1..intervals {
            sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(-1.0 + i as f64 * h);
        }
        2.0 * PI * sum * h / 3.0
    }

    /// The angular-sum inputs of spheres that share a size parameter:
    /// constants and [n][sphere] terms.
    fn angular_terms(solutions: &[MieSolution]) -> (Vec<AngularTermConstants>, Vec<[f64; 4]>) {
        let n_terms = solutions[0].n_terms();
        let constants: Vec<AngularTermConstants> =
            (0..n_terms).map(AngularTermConstants::new).collect();
        let mut terms = Vec::new();
        for (index, c) in constants.iter().enumerate() {
            for solution in solutions {
                let (a, b) = solution.coefficients();
                let sum = c.term_factor * (a[index] + b[index]);
                let difference = c.term_factor * (a[index] - b[index]);
                terms.push([sum.re, sum.im, difference.re, difference.im]);
            }
        }
        (constants, terms)
    }

    /// The blocked angular sums against the sphere module's own S11 table.
    #[test]
    fn blocked_angular_sums_match_the_sphere_module() {
        let cosines = table_cosines();
        let m = Complex64::new(1.5, 0.005);
        for x in [0.3, 7.0, 95.0, 400.0] {
            let solution = MieSolution::compute(m, x).unwrap();
            let (constants, terms) = angular_terms(std::slice::from_ref(&solution));
            let mut blocked = vec![0.0; cosines.len()];
            accumulate_s11(&cosines, &constants, &terms, 1, &mut blocked);
            let mut s11 = vec![0.0; cosines.len()];
            let mut s12 = vec![0.0; cosines.len()];
            solution.s11_s12_table(&cosines, &mut s11, &mut s12);
            let scale = s11.iter().fold(0.0f64, |acc, &v| acc.max(v));
            // The two orders of summation round differently: about 1e-16 per
            // term relative to the largest (forward) value.
            let tolerance = 1e-14 * solution.n_terms() as f64 * scale;
            for (i, (&mine, &theirs)) in blocked.iter().zip(&s11).enumerate() {
                assert!(
                    (mine - theirs).abs() <= tolerance,
                    "x {x} mu {}: {mine} vs {theirs}",
                    cosines[i]
                );
            }
        }
    }

    /// The AVX build of the angular sums performs the portable build's
    /// operations in the same order (bit-identical results); the AVX-512
    /// build fuses the multiply-adds, which changes the rounding only
    /// (measured: within 2e-14 of the largest value); and in every build a
    /// sphere's sums are the same alone or beside others (one to seven
    /// spheres, the passes of five, two and one included).
    #[test]
    fn angular_sum_builds_agree() {
        let cosines = table_cosines();
        let angles = cosines.len();
        let solutions: Vec<MieSolution> = [0.002, 0.004, 0.008, 0.001, 0.003, 0.02, 0.0005]
            .iter()
            .map(|&k| MieSolution::compute(Complex64::new(1.5, k), 80.0).unwrap())
            .collect();
        let mut alone = Vec::new();
        for solution in &solutions {
            let (constants, terms) = angular_terms(std::slice::from_ref(solution));
            let mut s11 = vec![0.0; angles];
            accumulate_s11(&cosines, &constants, &terms, 1, &mut s11);
            alone.push(s11);
        }
        for count in 1..=solutions.len() {
            let (constants, terms) = angular_terms(&solutions[..count]);
            let mut portable = vec![0.0; count * angles];
            accumulate_s11_as(
                Build::Portable,
                &cosines,
                &constants,
                &terms,
                count,
                &mut portable,
            );
            let mut dispatched = vec![0.0; count * angles];
            accumulate_s11(&cosines, &constants, &terms, count, &mut dispatched);
            for (sphere, s11) in dispatched.chunks(angles).enumerate() {
                assert_eq!(s11, &alone[sphere][..], "{count} spheres, sphere {sphere}");
            }
            let largest = portable.iter().fold(0.0f64, |m, &v| m.max(v));
            for (&d, &p) in dispatched.iter().zip(&portable) {
                assert!((d - p).abs() <= 1e-13 * largest, "{d} vs {p}");
            }
            if Build::Avx.is_supported() {
                let mut avx = vec![0.0; count * angles];
                accumulate_s11_as(Build::Avx, &cosines, &constants, &terms, count, &mut avx);
                assert_eq!(avx, portable);
            }
        }
    }

    /// The grouped accumulation adds node by node, in order: the same sums
    /// as one node at a time, in every build.
    #[test]
    fn grouped_accumulation_is_the_node_by_node_sum() {
        let (angles, wavelengths, nodes, stride) = (37, 3, 5, 41);
        let value = |i: usize| ((i * 7919) % 1000) as f64 / 997.0 + 1e-3 * i as f64;
        let s11: Vec<f64> = (0..nodes * stride + 2).map(value).collect();
        let mut weights = vec![[0.0; SPHERE_LANES]; wavelengths];
        for (w, row) in weights.iter_mut().enumerate() {
            for (node, weight) in row.iter_mut().enumerate().take(nodes) {
                // Some nodes outside a wavelength's window: weight 0.
                *weight = if (w + node) % 4 == 3 {
                    0.0
                } else {
                    value(w * 31 + node)
                };
            }
        }
        let start: Vec<f64> = (0..wavelengths * angles).map(|i| value(i + 500)).collect();
        let mut expected = start.clone();
        for (w, row) in weights.iter().enumerate() {
            for (node, &weight) in row.iter().enumerate().take(nodes) {
                if weight == 0.0 {
                    continue;
                }
                for i in 0..angles {
                    expected[w * angles + i] += weight * s11[2 + node * stride + i];
                }
            }
        }
        let mut dispatched = start.clone();
        add_weighted_group(&mut dispatched, &s11, 2, stride, nodes, &weights);
        let mut portable = start;
        simd::run_as(
            Build::Portable,
            AddWeightedGroup {
                tables: &mut portable,
                s11: &s11,
                first: 2,
                stride,
                nodes,
                weights: &weights,
            },
        );
        assert_eq!(dispatched, expected);
        assert_eq!(portable, expected);
    }

    /// The interpolation weights reproduce each reference index exactly,
    /// sum to 1 and stay bounded inside the range.
    #[test]
    fn index_interpolation_weights() {
        let indices = [
            Complex64::new(1.4956, 0.00094),
            Complex64::new(1.5, 0.0099),
            Complex64::new(1.498, 0.003),
        ];
        let plan = IndexInterpolationPlan::new(&indices).unwrap();
        let references = plan.reference_indices();
        assert_eq!(references.len(), 5);
        assert!((references[0].im / 0.00094 - 1.0).abs() < 1e-14);
        assert!((references[3].im / 0.0099 - 1.0).abs() < 1e-14);
        for (j, &reference) in references.iter().enumerate() {
            let weights = plan.weights(reference);
            for (i, &w) in weights.iter().enumerate() {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((w - expected).abs() < 1e-12, "reference {j}: {weights:?}");
            }
        }
        for m in indices {
            let weights = plan.weights(m);
            assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(weights.iter().all(|w| w.abs() <= 2.0), "{weights:?}");
        }
        // Constant n: no n reference.
        let plan =
            IndexInterpolationPlan::new(&[Complex64::new(1.5, 0.001), Complex64::new(1.5, 0.01)])
                .unwrap();
        assert_eq!(plan.reference_indices().len(), 4);
    }

    /// The Mie ensemble phase function integrates to 1 over 4 pi sr, its raw
    /// table (exact ensemble values at the nodes) did so to within the
    /// angular interpolation error, and its mean cosine is the ensemble g
    /// computed from the cross-sections, to the accuracy of the table.
    #[test]
    fn ensemble_phase_function_is_normalised_and_its_mean_cosine_is_g() {
        let model = RefractiveIndexModel::constant(Complex64::new(1.5, 0.005)).unwrap();
        for distribution in [
            mars_dust(),
            paper_table1_aerosol(),
            SizeDistribution::log_normal(0.1 * MICROMETRE, 1.5).unwrap(),
        ] {
            let spectrum = compute_ensemble_optics_spectrum(
                &[380.0, 550.0, 780.0],
                &model,
                &distribution,
                &EnsembleSettings::default(),
            )
            .unwrap();
            for optics in &spectrum {
                let AerosolPhaseFunction::Tabulated(table) = &optics.phase_function else {
                    panic!("Mie mode gives a table");
                };
                let lambda = optics.cross_sections.wavelength_nm;
                let norm = integrate_over_sphere(
                    |mu| optics.phase_function.phase_function_per_sr(mu),
                    400_000,
                );
                assert!((norm - 1.0).abs() < 1e-6, "{lambda} nm: integral {norm}");
                // Measured: 4.7e-5 to 2.3e-4 (the trapezoid in mu over-counts the convex forward peak).
                let raw = table.normalisation_before_rescaling();
                assert!(
                    (raw - 1.0).abs() < 5e-4,
                    "{lambda} nm: raw table integral {raw}"
                );
                let mean_cosine = optics.phase_function.asymmetry_parameter();
                let g = optics.cross_sections.asymmetry_parameter;
                // Measured: within 8.5e-5 (radius quadrature of the table and interpolation).
                assert!(
                    (mean_cosine - g).abs() < 2e-4,
                    "{lambda} nm: <mu> {mean_cosine} vs g {g}"
                );
                let independent_mean_cosine = integrate_over_sphere(
                    |mu| mu * optics.phase_function.phase_function_per_sr(mu),
                    400_000,
                );
                assert!((independent_mean_cosine - mean_cosine).abs() < 1e-6);
            }
        }
    }

    /// A very narrow distribution is one sphere: the ensemble reduces to the
    /// single-sphere efficiencies and phase function at the median radius.
    #[test]
    fn a_narrow_distribution_is_a_single_sphere() {
        let radius_m = 0.6 * MICROMETRE;
        let distribution = SizeDistribution::log_normal(radius_m, 1.0001).unwrap();
        let m = Complex64::new(1.5, 0.01);
        let wavelength_nm = 550.0;
        let x = 2.0 * PI * radius_m / (wavelength_nm * 1e-9);
        let sphere = MieSolution::compute(m, x).unwrap();
        let q = sphere.efficiencies();
        let area_m2 = PI * radius_m * radius_m;
        let c = compute_ensemble_cross_sections(
            wavelength_nm,
            m,
            &distribution,
            &RadiusQuadratureSettings::cross_sections(),
        )
        .unwrap();
        // sigma_g = 1.0001 spreads the radius by 1e-4: second-order effects ~1e-7 on smooth Q(x).
        assert!((c.extinction_cross_section_m2 / (area_m2 * q.qext) - 1.0).abs() < 1e-5);
        assert!((c.scattering_cross_section_m2 / (area_m2 * q.qsca) - 1.0).abs() < 1e-5);
        assert!((c.absorption_cross_section_m2 / (area_m2 * q.qabs) - 1.0).abs() < 1e-5);
        assert!((c.asymmetry_parameter - q.g).abs() < 1e-5);
        let table = compute_ensemble_phase_function(
            wavelength_nm,
            m,
            &distribution,
            &RadiusQuadratureSettings::phase_function(),
        )
        .unwrap();
        for theta_deg in [0.0f64, 10.0, 45.0, 90.0, 150.0, 180.0] {
            let mu = theta_deg.to_radians().cos();
            let node = table
                .cos_theta_nodes()
                .iter()
                .position(|&c| (c - mu).abs() < 1e-15)
                .unwrap();
            let exact = sphere.phase_function_per_sr(mu);
            let tabulated =
                table.phase_per_sr_nodes()[node] * table.normalisation_before_rescaling();
            assert!(
                (tabulated / exact - 1.0).abs() < 1e-4,
                "{theta_deg} deg: {tabulated} vs {exact}"
            );
        }
    }

    /// Sharing Mie solutions across wavelengths gives the same per-wavelength
    /// optics as computing each wavelength alone (two different quadratures
    /// of the same integrals).
    #[test]
    fn shared_spectrum_matches_wavelength_by_wavelength() {
        // At k = 0.01 both quadratures are converged to ~1e-7 (module docs),
        // so any difference beyond that would be a bug in the sharing.
        let m = Complex64::new(1.5, 0.01);
        let model = RefractiveIndexModel::Constant(m);
        for distribution in [mars_dust(), paper_table1_aerosol()] {
            let spectrum = compute_ensemble_optics_spectrum(
                &PAPER_WAVELENGTHS_NM,
                &model,
                &distribution,
                &EnsembleSettings::default(),
            )
            .unwrap();
            for optics in spectrum.iter().step_by(5) {
                let shared = &optics.cross_sections;
                let alone = compute_ensemble_cross_sections(
                    shared.wavelength_nm,
                    m,
                    &distribution,
                    &RadiusQuadratureSettings::cross_sections(),
                )
                .unwrap();
                for (a, b) in [
                    (
                        shared.extinction_cross_section_m2,
                        alone.extinction_cross_section_m2,
                    ),
                    (
                        shared.scattering_cross_section_m2,
                        alone.scattering_cross_section_m2,
                    ),
                    (
                        shared.absorption_cross_section_m2,
                        alone.absorption_cross_section_m2,
                    ),
                    (shared.asymmetry_parameter, alone.asymmetry_parameter),
                ] {
                    assert!(
                        (a / b - 1.0).abs() < 1e-6,
                        "{} nm: {a} vs {b}",
                        shared.wavelength_nm
                    );
                }
            }
        }
    }

    /// The paper's mode: an HG function whose g is the scattering-weighted
    /// paper g(r), between the end values, larger for larger particles.
    #[test]
    fn paper_mode_carries_the_weighted_paper_g() {
        let model = RefractiveIndexModel::constant(Complex64::new(1.5, 0.01)).unwrap();
        let settings = EnsembleSettings {
            phase_mode: AerosolPhaseMode::PaperHenyeyGreenstein,
            ..EnsembleSettings::default()
        };
        let small = compute_ensemble_optics(
            550.0,
            &model,
            &SizeDistribution::log_normal(0.01 * MICROMETRE, 1.2).unwrap(),
            &settings,
        )
        .unwrap();
        let dust = compute_ensemble_optics(550.0, &model, &mars_dust(), &settings).unwrap();
        for optics in [&small, &dust] {
            let AerosolPhaseFunction::HenyeyGreenstein(hg) = &optics.phase_function else {
                panic!("paper mode gives HG");
            };
            assert_eq!(
                hg.asymmetry_parameter(),
                optics.cross_sections.paper_asymmetry_parameter
            );
            assert!((0.5..=0.9).contains(&hg.asymmetry_parameter()));
        }
        // Small particles scatter like r^6: their weighted radius is ~0.02 um, g ~ 0.5.
        assert!(small.cross_sections.paper_asymmetry_parameter < 0.502);
        let dust_g = dust.cross_sections.paper_asymmetry_parameter;
        assert!(dust_g > 0.6 && dust_g < 0.9, "{dust_g}");
        // The same weights by brute force: sum of g_paper(r) C_sca over a fine trapezoid.
        let distribution = mars_dust();
        let wavenumber = 2.0 * PI / 550e-9;
        let quadrature =
            RadiusQuadrature::trapezoid(&distribution, wavenumber, 20_001, 18.0).unwrap();
        let m = Complex64::new(1.5, 0.01);
        let mut weighted = 0.0;
        let mut total = 0.0;
        for (&r, &w) in quadrature.radii_m().iter().zip(quadrature.weights()) {
            let c_sca = w * PI * r * r * compute_efficiencies(m, wavenumber * r).unwrap().qsca;
            weighted += c_sca * paper_asymmetry_parameter_for_radius(r);
            total += c_sca;
        }
        assert!((weighted / total - dust_g).abs() < 1e-6);
    }

    /// A tabulated index gives each wavelength its own index, and the
    /// results match the constant-index computation at that index.
    #[test]
    fn tabulated_index_is_used_per_wavelength() {
        let table = crate::refractive_index::TabulatedRefractiveIndex::parse_csv(include_str!(
            "../tests/data/mars_dust_refractive_index_wolff2009.csv"
        ))
        .unwrap();
        let model = RefractiveIndexModel::Tabulated(table);
        let settings = EnsembleSettings {
            phase_mode: AerosolPhaseMode::PaperHenyeyGreenstein,
            ..EnsembleSettings::default()
        };
        let spectrum =
            compute_ensemble_optics_spectrum(&[440.0, 700.0], &model, &mars_dust(), &settings)
                .unwrap();
        for optics in &spectrum {
            let c = &optics.cross_sections;
            let m = model.refractive_index_at(c.wavelength_nm).unwrap();
            assert_eq!(c.refractive_index, m);
            let alone = compute_ensemble_cross_sections(
                c.wavelength_nm,
                m,
                &mars_dust(),
                &settings.cross_section_quadrature,
            )
            .unwrap();
            assert_eq!(
                c.extinction_cross_section_m2,
                alone.extinction_cross_section_m2
            );
        }
        // Less absorbing at 700 nm (k 0.00094 against 0.0077 at 440 nm).
        assert!(
            spectrum[1].cross_sections.single_scattering_albedo
                > spectrum[0].cross_sections.single_scattering_albedo
        );
    }
}
