//! # The ensemble's phase matrix relative to its phase function
//!
//! Spheres (and randomly oriented particles with a plane of symmetry) turn
//! the Stokes vector of light with a matrix of four independent elements
//! per angle, in the scattering plane's frame (Bohren & Huffman 1983,
//! eq. 4.77):
//!
//! ```text
//! S11 = (|S2|^2 + |S1|^2) / 2,   S12 = (|S2|^2 - |S1|^2) / 2,
//! S33 = Re(S2 S1*),              S34 = Im(S2 S1*),
//! ```
//!
//! with S22 = S11 and S44 = S33. For an ensemble at one wavelength each
//! element is the number-weighted radius integral of the particles' (the
//! per-particle factor 1/k^2 is the same for all), so the ratios
//! F12/F11, F33/F11 and F34/F11 need no normalisation: they multiply the
//! tabulated phase function (F11) to give the rest of the matrix. For small
//! spheres they tend to Rayleigh's, -(1 - mu^2)/(1 + mu^2), 2 mu/(1 + mu^2)
//! and 0; for one sphere F12^2 + F33^2 + F34^2 = F11^2 exactly, and an
//! ensemble, a mixture, depolarises: the sum is at most F11^2.
//!
//! This is the straightforward path (the amplitudes of every node at every
//! angle, by the sphere's blocked amplitude recurrences, not the phase
//! tables' vector kernels), for polarised computations only: the scalar
//! phase tables keep their fast angular sums (`angular_sums.rs`).
//!
//! Two entry points, one wavelength and several:
//! - [`compute_ensemble_phase_matrix_ratios`]: one wavelength, the radius
//!   integral by its own Gauss-Legendre rule (the reference path);
//! - [`compute_shared_ensemble_phase_matrix_ratios`]: several wavelengths
//!   at which the particles have one refractive index. The amplitudes
//!   depend on the size parameter x = k r and the index only, so one
//!   solution per node of a quadrature in x shared by the wavelengths
//!   ([`SharedSizeParameterQuadrature`], as the cross-sections use) serves
//!   every wavelength, each with its own weights: n wavelengths cost about
//!   as much as one over the union of their ranges in x. Its ratios equal
//!   the reference path's up to the two quadratures' difference (tested).

use super::{EnsembleError, validate_wavelength};
use crate::Complex64;
use crate::distribution::{
    RadiusQuadrature, RadiusQuadratureSettings, SharedSizeParameterQuadrature, SizeDistribution,
};
use crate::sphere::{MieError, MieSolution};

/// F12/F11, F33/F11 and F34/F11 of an ensemble at the scattering-angle
/// cosines it was computed at (dimensionless; 0 where F11 is 0).
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseMatrixRatios {
    /// The cosines of the scattering angles, as given.
    pub cos_theta: Vec<f64>,
    /// F12 / F11 (minus the degree of linear polarisation of scattered
    /// unpolarised light).
    pub f12_over_f11: Vec<f64>,
    /// F33 / F11.
    pub f33_over_f11: Vec<f64>,
    /// F34 / F11.
    pub f34_over_f11: Vec<f64>,
}

/// The phase-matrix ratios of `distribution` at `wavelength_nm` (nm) for
/// particles of index `refractive_index`, at each of `cos_theta`, the
/// radius integral by the Gauss-Legendre rule of `settings`
/// ([`RadiusQuadratureSettings::phase_function`] is the validated choice
/// for phase functions).
pub fn compute_ensemble_phase_matrix_ratios(
    wavelength_nm: f64,
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
    cos_theta: &[f64],
) -> Result<PhaseMatrixRatios, EnsembleError> {
    let wavenumber_per_m = validate_wavelength(wavelength_nm)?;
    let quadrature = RadiusQuadrature::gauss_legendre(
        distribution,
        wavenumber_per_m,
        &settings.for_refractive_index(refractive_index),
    )?;
    let (sums, _) = phase_matrix_sums(
        wavelength_nm,
        wavenumber_per_m,
        refractive_index,
        &quadrature,
        cos_theta,
    )?;
    Ok(ratios_of_sums(&sums, cos_theta))
}

/// [`compute_ensemble_phase_matrix_ratios`] at each of `wavelengths_nm`
/// (nm, at least one), in the order given, for particles whose index is
/// `refractive_index` at every one of them: the radius integrals over one
/// [`SharedSizeParameterQuadrature`] (see the module docs).
pub fn compute_shared_ensemble_phase_matrix_ratios(
    wavelengths_nm: &[f64],
    refractive_index: Complex64,
    distribution: &SizeDistribution,
    settings: &RadiusQuadratureSettings,
    cos_theta: &[f64],
) -> Result<Vec<PhaseMatrixRatios>, EnsembleError> {
    let wavenumbers_per_m = wavelengths_nm
        .iter()
        .map(|&lambda| validate_wavelength(lambda))
        .collect::<Result<Vec<f64>, EnsembleError>>()?;
    let quadrature = SharedSizeParameterQuadrature::gauss_legendre(
        distribution,
        &wavenumbers_per_m,
        &settings.for_refractive_index(refractive_index),
    )?;
    // [S11, S12, S33, S34] summed over the nodes, per wavelength and angle.
    let mut sums = vec![vec![[0.0f64; 4]; cos_theta.len()]; wavelengths_nm.len()];
    let mut solution: Option<MieSolution> = None;
    let zero = Complex64::new(0.0, 0.0);
    let (mut s1, mut s2) = (vec![zero; cos_theta.len()], vec![zero; cos_theta.len()]);
    for (node, &x) in quadrature.size_parameters().iter().enumerate() {
        let weights = quadrature.weights_at_node(node);
        if weights.iter().all(|&w| w == 0.0) {
            continue;
        }
        let solution = solve_in_place(&mut solution, refractive_index, x).map_err(|error| {
            EnsembleError::Mie {
                wavelength_nm: wavelengths_nm[0],
                radius_m: x / wavenumbers_per_m[0],
                error,
            }
        })?;
        solution.amplitudes_table(cos_theta, &mut s1, &mut s2);
        for (sums, &weight) in sums.iter_mut().zip(weights) {
            if weight != 0.0 {
                add_node(sums, weight, &s1, &s2);
            }
        }
    }
    Ok(sums
        .iter()
        .map(|sums| ratios_of_sums(sums, cos_theta))
        .collect())
}

/// The sphere of size parameter `x` and index `refractive_index` in
/// `solution`: its buffers recomputed in place, or made on the first node.
fn solve_in_place(
    solution: &mut Option<MieSolution>,
    refractive_index: Complex64,
    x: f64,
) -> Result<&MieSolution, MieError> {
    match solution {
        Some(solution) => {
            solution.recompute(refractive_index, x)?;
            Ok(solution)
        }
        None => Ok(solution.insert(MieSolution::compute(refractive_index, x)?)),
    }
}

/// Adds one node's [S11, S12, S33, S34] at each angle, times `weight`, to
/// `sums`.
fn add_node(sums: &mut [[f64; 4]], weight: f64, s1: &[Complex64], s2: &[Complex64]) {
    for ((sum, s1), s2) in sums.iter_mut().zip(s1).zip(s2) {
        let (n1, n2) = (s1.norm_sqr(), s2.norm_sqr());
        let product = s2 * s1.conj();
        sum[0] += weight * 0.5 * (n2 + n1);
        sum[1] += weight * 0.5 * (n2 - n1);
        sum[2] += weight * product.re;
        sum[3] += weight * product.im;
    }
}

/// The ratios of the radius sums [S11, S12, S33, S34] at `cos_theta` (0
/// where S11's sum is 0).
fn ratios_of_sums(sums: &[[f64; 4]], cos_theta: &[f64]) -> PhaseMatrixRatios {
    let ratio = |k: usize| -> Vec<f64> {
        sums.iter()
            .map(|s| if s[0] > 0.0 { s[k] / s[0] } else { 0.0 })
            .collect()
    };
    PhaseMatrixRatios {
        cos_theta: cos_theta.to_vec(),
        f12_over_f11: ratio(1),
        f33_over_f11: ratio(2),
        f34_over_f11: ratio(3),
    }
}

/// The radius sums of [S11, S12, S33, S34] at each of `cos_theta` over the
/// nodes of `quadrature`, and the sum of `w x^2 Q_sca` (so that
/// `P11 = S11 sum / (pi x^2 Q_sca sum)` per sr).
pub(super) fn phase_matrix_sums(
    wavelength_nm: f64,
    wavenumber_per_m: f64,
    refractive_index: Complex64,
    quadrature: &RadiusQuadrature,
    cos_theta: &[f64],
) -> Result<(Vec<[f64; 4]>, f64), EnsembleError> {
    // [S11, S12, S33, S34] summed over the nodes, per angle.
    let mut sums = vec![[0.0f64; 4]; cos_theta.len()];
    let mut scattering_x_squared = 0.0;
    // One solution's buffers serve every node (recomputed in place), and
    // the amplitudes of every angle one node's.
    let mut solution: Option<MieSolution> = None;
    let zero = Complex64::new(0.0, 0.0);
    let (mut s1, mut s2) = (vec![zero; cos_theta.len()], vec![zero; cos_theta.len()]);
    for (&radius_m, &weight) in quadrature.radii_m().iter().zip(quadrature.weights()) {
        let x = wavenumber_per_m * radius_m;
        let solution = solve_in_place(&mut solution, refractive_index, x).map_err(|error| {
            EnsembleError::Mie {
                wavelength_nm,
                radius_m,
                error,
            }
        })?;
        scattering_x_squared += weight * x * x * solution.efficiencies().qsca;
        solution.amplitudes_table(cos_theta, &mut s1, &mut s2);
        add_node(&mut sums, weight, &s1, &s2);
    }
    Ok((sums, scattering_x_squared))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lognormal(median_m: f64, sigma_g: f64) -> SizeDistribution {
        SizeDistribution::log_normal(median_m, sigma_g).unwrap()
    }

    fn cosines() -> Vec<f64> {
        (0..=36)
            .map(|k| (5.0 * k as f64).to_radians().cos())
            .collect()
    }

    #[test]
    fn small_spheres_have_the_rayleigh_matrix() {
        // 2 nm spheres at 550 nm (x ~ 0.02): Rayleigh to O(x^2).
        let ratios = compute_ensemble_phase_matrix_ratios(
            550.0,
            Complex64::new(1.5, 0.01),
            &lognormal(2e-9, 1.2),
            &RadiusQuadratureSettings::phase_function(),
            &cosines(),
        )
        .unwrap();
        for (k, &mu) in ratios.cos_theta.iter().enumerate() {
            let f12 = -(1.0 - mu * mu) / (1.0 + mu * mu);
            let f33 = 2.0 * mu / (1.0 + mu * mu);
            assert!((ratios.f12_over_f11[k] - f12).abs() < 1e-3, "mu {mu}");
            assert!((ratios.f33_over_f11[k] - f33).abs() < 1e-3, "mu {mu}");
            assert!(ratios.f34_over_f11[k].abs() < 1e-3, "mu {mu}");
        }
    }

    #[test]
    fn one_sphere_keeps_light_polarised_and_an_ensemble_depolarises() {
        let m = Complex64::new(1.33, 0.0);
        let settings = RadiusQuadratureSettings::phase_function();
        // sigma_g = 1.0001: the optics of one sphere to ~1e-7 (x = 10).
        let narrow = lognormal(10.0 * 550e-9 / (2.0 * std::f64::consts::PI), 1.0001);
        let broad = lognormal(10.0 * 550e-9 / (2.0 * std::f64::consts::PI), 1.6);
        let norm = |r: &PhaseMatrixRatios, k: usize| {
            (r.f12_over_f11[k].powi(2) + r.f33_over_f11[k].powi(2) + r.f34_over_f11[k].powi(2))
                .sqrt()
        };
        let one =
            compute_ensemble_phase_matrix_ratios(550.0, m, &narrow, &settings, &cosines()).unwrap();
        let many =
            compute_ensemble_phase_matrix_ratios(550.0, m, &broad, &settings, &cosines()).unwrap();
        let mut depolarised = 0.0f64;
        for k in 0..one.cos_theta.len() {
            assert!(
                (norm(&one, k) - 1.0).abs() < 1e-4,
                "angle {k}: {}",
                norm(&one, k)
            );
            assert!(
                norm(&many, k) <= 1.0 + 1e-12,
                "angle {k}: {}",
                norm(&many, k)
            );
            depolarised = depolarised.max(1.0 - norm(&many, k));
        }
        // The broad ensemble depolarises noticeably somewhere.
        assert!(depolarised > 0.05, "{depolarised}");
        // Forward and backward scattering keep unpolarised light
        // unpolarised (S1 = S2 there for a sphere).
        for k in [0, one.cos_theta.len() - 1] {
            assert!(one.f12_over_f11[k].abs() < 1e-9 && many.f12_over_f11[k].abs() < 1e-9);
        }
    }

    /// The shared quadrature's ratios against each wavelength's own
    /// (the reference path), at the polarised sky's anchors on the
    /// default grid and for the presets' kinds of particle (Earth's fine
    /// aerosol, Mars dust and a water cloud's droplets): against a denser
    /// rule, the shared one errs no more than the reference path does.
    #[test]
    fn shared_wavelengths_give_each_wavelengths_own_ratios() {
        let settings = RadiusQuadratureSettings::phase_function();
        let wavelengths_nm = [380.0, 440.0, 500.0, 560.0, 620.0, 680.0, 740.0, 780.0];
        let cosines: Vec<f64> = (0..=72)
            .map(|k| (2.5 * k as f64).to_radians().cos())
            .collect();
        let cases = [
            (
                "fine",
                lognormal(0.0212e-6, 2.24),
                Complex64::new(1.53, 0.006),
            ),
            (
                "dust",
                SizeDistribution::log_normal_from_effective_radius_and_variance(1.5e-6, 0.3)
                    .unwrap(),
                Complex64::new(1.52, 0.003),
            ),
            (
                "cloud",
                SizeDistribution::log_normal_from_effective_radius_and_variance(10e-6, 0.1)
                    .unwrap(),
                Complex64::new(1.33, 1e-8),
            ),
        ];
        for (name, distribution, m) in cases {
            let shared = compute_shared_ensemble_phase_matrix_ratios(
                &wavelengths_nm,
                m,
                &distribution,
                &settings,
                &cosines,
            )
            .unwrap();
            let dense_settings = RadiusQuadratureSettings {
                resonance_nodes_per_unit_ln_radius: 600.0,
                ripple_nodes_per_unit_size_parameter: 384.0,
                max_panel_width_ln_radius: 0.125,
                tail_depth: 16.0,
                ..settings
            };
            let largest = |a: &PhaseMatrixRatios, b: &PhaseMatrixRatios| -> f64 {
                let mut largest = 0.0f64;
                for (a, b) in [
                    (&a.f12_over_f11, &b.f12_over_f11),
                    (&a.f33_over_f11, &b.f33_over_f11),
                    (&a.f34_over_f11, &b.f34_over_f11),
                ] {
                    for (a, b) in a.iter().zip(b) {
                        largest = largest.max((a - b).abs());
                    }
                }
                largest
            };
            let (mut shared_vs_own, mut shared_err, mut own_err) = (0.0f64, 0.0f64, 0.0f64);
            for (&wavelength_nm, shared) in wavelengths_nm.iter().zip(&shared) {
                let own = |settings: &RadiusQuadratureSettings| {
                    compute_ensemble_phase_matrix_ratios(
                        wavelength_nm,
                        m,
                        &distribution,
                        settings,
                        &cosines,
                    )
                    .unwrap()
                };
                let (own, dense) = (own(&settings), own(&dense_settings));
                assert_eq!(shared.cos_theta, own.cos_theta);
                shared_vs_own = shared_vs_own.max(largest(shared, &own));
                shared_err = shared_err.max(largest(shared, &dense));
                own_err = own_err.max(largest(&own, &dense));
            }
            // Measured: fine 1.7e-3 apart, 8.2e-4 and 1.7e-3 from the
            // denser rule; dust 1.4e-2, 1.2e-2 and 1.5e-2; cloud 2.4e-3,
            // 1.5e-3 and 2.5e-3. The shared rule's panels are the
            // narrowest any wavelength needs, so it is the closer one.
            eprintln!(
                "{name}: shared vs own {shared_vs_own:.3e}; against a denser rule: shared {shared_err:.3e}, own {own_err:.3e}"
            );
            assert!(shared_err <= own_err, "{name}: {shared_err} vs {own_err}");
            assert!(shared_vs_own <= shared_err + own_err, "{name}");
        }
    }

    #[test]
    fn it_matches_the_single_sphere_reference() {
        // ../shared/reference/mie/phase.csv, case 0 (m = 1.33, x = 10):
        // the degree of linear polarisation -S12/S11 at 30, 90 and 150
        // degrees, against the narrowest ensemble (one sphere to ~1e-7 in
        // x, so to ~1e-5 in a ratio that varies on the scale of a degree).
        let text = include_str!("../../tests/data/phase.csv");
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let (case, theta, dolp) = (column("case_id"), column("theta_deg"), column("dolp"));
        let narrow = lognormal(10.0 * 550e-9 / (2.0 * std::f64::consts::PI), 1.0001);
        let mut checked = 0;
        for line in lines {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            if v[case] != 0.0 || ![30.0, 90.0, 150.0].contains(&v[theta]) {
                continue;
            }
            let mu = v[theta].to_radians().cos();
            let ratios = compute_ensemble_phase_matrix_ratios(
                550.0,
                Complex64::new(1.33, 0.0),
                &narrow,
                &RadiusQuadratureSettings::phase_function(),
                &[mu],
            )
            .unwrap();
            assert!(
                (-ratios.f12_over_f11[0] - v[dolp]).abs() < 1e-4,
                "theta {}: {} vs {}",
                v[theta],
                -ratios.f12_over_f11[0],
                v[dolp]
            );
            checked += 1;
        }
        assert_eq!(checked, 3);
    }
}
