//! # Per-particle mean cross-sections of a size distribution
//!
//! `<C_ext>`, `<C_sca>`, `<C_abs>` (m^2 per particle), the single-scattering
//! albedo `<C_sca> / <C_ext>`, the scattering-weighted asymmetry parameter
//! `g` and the paper's HG `g` (all dimensionless) of one population at one
//! or several vacuum wavelengths (nm): the integrals of the module docs'
//! first block, done with the composite Gauss-Legendre rule in `ln x` of
//! [`RadiusQuadratureSettings::cross_sections`] (its measured error is in
//! the module docs, "Quadrature and its measured error"). Wavelengths at
//! which the particles have the same index share one rule in size
//! parameter and one Mie solution per node, eight nodes solved side by side
//! ([`compute_efficiencies_many_with`]). [`integrate_ensemble_cross_sections`]
//! is the same sum over any quadrature, one sphere at a time: the oracle of
//! the tests.

use super::{EnsembleError, validate_wavelength};
use crate::Complex64;
use crate::distribution::{
    RadiusQuadrature, RadiusQuadratureSettings, SharedSizeParameterQuadrature, SizeDistribution,
};
use crate::paper_phase::paper_asymmetry_parameter_for_radius;
use crate::sphere::{
    Efficiencies, SphereWorkspace, compute_efficiencies, compute_efficiencies_many_with,
};
use std::f64::consts::PI;

/// `numerator / denominator`, or 0 where the denominator is 0 (or the
/// quotient is not finite). A population whose mean scattering
/// cross-section is 0 at a wavelength (e.g. m = 1, where every Mie
/// coefficient vanishes) is non-scattering there: its single-scattering
/// albedo is 0 and its asymmetry parameters (Mie and the paper's HG g) are
/// reported as 0, i.e. an isotropic phase function that is never used,
/// instead of 0/0 = NaN (issue 17). The phase table of such a population is
/// isotropic too (`phase_table.rs`).
pub(super) fn ratio_or_zero(numerator: f64, denominator: f64) -> f64 {
    let ratio = numerator / denominator;
    if denominator > 0.0 && ratio.is_finite() {
        ratio
    } else {
        0.0
    }
}

/// Per-particle mean cross-sections and related quantities of a population
/// at one wavelength. Where `scattering_cross_section_m2` is 0 the
/// population is non-scattering: albedo and both g are 0 (see
/// `ratio_or_zero`).
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
pub(super) fn compute_shared_cross_sections(
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
                single_scattering_albedo: ratio_or_zero(sum[1], sum[0]),
                asymmetry_parameter: ratio_or_zero(sum[3], sum[1]),
                paper_asymmetry_parameter: ratio_or_zero(sum[4], sum[1]),
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
        single_scattering_albedo: ratio_or_zero(scattering_m2, extinction_m2),
        asymmetry_parameter: ratio_or_zero(scattering_times_g_m2, scattering_m2),
        paper_asymmetry_parameter: ratio_or_zero(scattering_times_paper_g_m2, scattering_m2),
        number_fraction_in_window: distribution.number_fraction_in_window(),
        radius_node_count: quadrature.len(),
    })
}
