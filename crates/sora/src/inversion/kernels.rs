//! Mie kernels per size bin: the optics of one unit of particle volume at
//! each radius node, so that a change of the size distribution re-weights
//! them instead of re-solving Mie theory.
//!
//! The aerosol of a retrieval is a volume size distribution v(ln r) =
//! dV/d ln r (um^3 um^-2 or any unit: only its shape matters, the amount
//! is set by the optical depth) over the radius range AERONET's inversion
//! uses, 0.05-15 um (Dubovik & King 2000). On `RADIUS_NODES` nodes equally
//! spaced in ln r (spacing h), each node j carries, per wavelength, the
//! cross-sections and the differential scattering cross-section of one
//! sphere of radius r_j divided by its volume v_j = 4/3 pi r_j^3:
//!
//! ```text
//!     e_j(lambda) = C_ext(r_j) / v_j,   s_j(lambda) = C_sca(r_j) / v_j      [m^-1]
//!     f_j(lambda, theta) = S11(theta; r_j) / (k^2 v_j)                      [m^-1 sr^-1]
//! ```
//!
//! (Bohren & Huffman 1983, eqs. 3.16 and 4.77: dC_sca/dOmega = S11 / k^2.)
//! The ensemble is the trapezoid rule in ln r, with the end nodes at half
//! weight:
//!
//! ```text
//!     E(lambda) = sum_j w_j v(ln r_j) e_j,   S = sum_j w_j v(ln r_j) s_j,
//!     P(theta)  = sum_j w_j v(ln r_j) f_j(theta) / S                        [sr^-1]
//! ```
//!
//! so E and S are extinction and scattering per unit volume of particles,
//! and P the ensemble's phase function. The kernels depend on the
//! wavelength and the refractive index only: [`MieKernels`] holds them for
//! one index, and the retrieval keeps a small cache of them per wavelength
//! keyed by the index (`forward.rs`), so the Jacobian's columns in radius, width and
//! volume fraction, and every step that moves only the size distribution,
//! cost no Mie solution.
//!
//! Why the trapezoid rule on fixed nodes, and not `sora-mie`'s adaptive
//! ensemble rule: the nodes must not depend on the distribution, or they
//! could not be cached. The log-normal modes a retrieval fits are smooth and
//! at least 0.3 wide in ln r, so the trapezoid rule is exact for them far
//! beyond double precision; what it does not resolve are the sharp
//! Mie resonances of weakly absorbing large spheres, which the equal
//! spacing samples at random: the test
//! `kernels_match_the_adaptive_ensemble` measures the result against
//! `sora-mie`'s validated adaptive quadrature.

use crate::error::{Error, Result};
use crate::mie::Complex64;
use crate::mie::ensemble::ensemble_phase_table_angles_deg;
use crate::mie::sphere::MieSolution;

/// Smallest radius of the retrieval's size distribution, um (AERONET's).
pub const MIN_RADIUS_UM: f64 = 0.05;
/// Largest radius, um (AERONET's).
pub const MAX_RADIUS_UM: f64 = 15.0;
/// Radius nodes, equally spaced in ln r from [`MIN_RADIUS_UM`] to
/// [`MAX_RADIUS_UM`] (spacing 0.0475 in ln r). Against `sora-mie`'s adaptive
/// rule (test): with 121 nodes the optics of a bimodal ensemble are within
/// the errors stated in the test; half as many double them.
pub const RADIUS_NODES: usize = 121;

/// The Mie kernels of one refractive index at a few wavelengths.
#[derive(Debug, Clone)]
pub(crate) struct MieKernels {
    /// The index they were computed for.
    pub refractive_index: Complex64,
    /// cos(theta) of the phase-table nodes, increasing from -1 to 1.
    pub cos_theta: Vec<f64>,
    /// The radius nodes, um, and their trapezoid weights in ln r.
    pub radii_um: Vec<f64>,
    weights: Vec<f64>,
    /// Per wavelength, per radius node: e_j and s_j (m^-1 per unit volume
    /// fraction, i.e. m^2 per m^3 of particle).
    pub extinction: Vec<Vec<f64>>,
    pub scattering: Vec<Vec<f64>>,
    /// Per wavelength, per radius node, per angle (in `cos_theta`'s order):
    /// f_j(theta), m^-1 sr^-1.
    pub differential: Vec<Vec<f64>>,
}

/// The radius nodes, um, and their trapezoid weights in ln r.
pub(crate) fn radius_nodes_um() -> (Vec<f64>, Vec<f64>) {
    let (a, b) = (MIN_RADIUS_UM.ln(), MAX_RADIUS_UM.ln());
    let h = (b - a) / (RADIUS_NODES - 1) as f64;
    let radii = (0..RADIUS_NODES)
        .map(|j| (a + j as f64 * h).exp())
        .collect();
    let weights = (0..RADIUS_NODES)
        .map(|j| {
            if j == 0 || j == RADIUS_NODES - 1 {
                h / 2.0
            } else {
                h
            }
        })
        .collect();
    (radii, weights)
}

impl MieKernels {
    /// Solves one sphere per radius node and wavelength (`wavelengths_nm`,
    /// vacuum, nm) for `refractive_index` and tabulates its optics per unit
    /// volume (the expensive step: 121 spheres per wavelength, size
    /// parameters up to 2 pi 15 um / lambda).
    pub(crate) fn compute(
        wavelengths_nm: &[f64],
        refractive_index: Complex64,
    ) -> Result<MieKernels> {
        // The phase-table angles of `sora-mie`'s ensembles, dense in the
        // forward peak, as cosines from -1 to 1.
        let mut cos_theta: Vec<f64> = ensemble_phase_table_angles_deg()
            .iter()
            .rev()
            .map(|deg| deg.to_radians().cos())
            .collect();
        cos_theta[0] = -1.0;
        *cos_theta.last_mut().expect("angles") = 1.0;
        let (radii_um, weights) = radius_nodes_um();
        let mut kernels = MieKernels {
            refractive_index,
            radii_um,
            weights,
            extinction: Vec::with_capacity(wavelengths_nm.len()),
            scattering: Vec::with_capacity(wavelengths_nm.len()),
            differential: Vec::with_capacity(wavelengths_nm.len()),
            cos_theta,
        };
        let angles = kernels.cos_theta.len();
        let mut s11 = vec![0.0; angles];
        let mut s12 = vec![0.0; angles];
        let mut solution: Option<MieSolution> = None;
        for &wavelength_nm in wavelengths_nm {
            let wavenumber_per_m = 2.0 * std::f64::consts::PI / (wavelength_nm * 1e-9);
            let mut extinction = Vec::with_capacity(RADIUS_NODES);
            let mut scattering = Vec::with_capacity(RADIUS_NODES);
            let mut differential = Vec::with_capacity(RADIUS_NODES * angles);
            for &radius_um in &kernels.radii_um {
                let radius_m = radius_um * 1e-6;
                let x = wavenumber_per_m * radius_m;
                let solved = match solution.as_mut() {
                    Some(s) => s.recompute(refractive_index, x).map(|_| ()),
                    None => MieSolution::compute(refractive_index, x).map(|s| {
                        solution = Some(s);
                    }),
                };
                solved.map_err(Error::Mie)?;
                let sphere = solution.as_ref().expect("solved above");
                let area_m2 = std::f64::consts::PI * radius_m * radius_m;
                let volume_m3 = 4.0 / 3.0 * std::f64::consts::PI * radius_m.powi(3);
                let q = sphere.efficiencies();
                extinction.push(q.qext * area_m2 / volume_m3);
                scattering.push(q.qsca * area_m2 / volume_m3);
                sphere.s11_s12_table(&kernels.cos_theta, &mut s11, &mut s12);
                let scale = 1.0 / (wavenumber_per_m * wavenumber_per_m * volume_m3);
                differential.extend(s11.iter().map(|v| v * scale));
            }
            kernels.extinction.push(extinction);
            kernels.scattering.push(scattering);
            kernels.differential.push(differential);
        }
        Ok(kernels)
    }

    /// The ensemble of the volume distribution whose values at the radius
    /// nodes are `volume_per_ln_radius` (any unit) at wavelength index
    /// `wavelength`: (E, S) per unit of the distribution's volume and the
    /// unnormalised phase function sum_j w_j v_j f_j(theta) into `phase`
    /// (its integral over 4 pi sr is S, to the table's resolution).
    pub(crate) fn ensemble(
        &self,
        wavelength: usize,
        volume_per_ln_radius: &[f64],
        phase: &mut Vec<f64>,
    ) -> (f64, f64) {
        let angles = self.cos_theta.len();
        phase.clear();
        phase.resize(angles, 0.0);
        let (mut extinction, mut scattering) = (0.0, 0.0);
        for (j, (v, w)) in volume_per_ln_radius.iter().zip(&self.weights).enumerate() {
            let weight = v * w;
            if weight == 0.0 {
                continue;
            }
            extinction += weight * self.extinction[wavelength][j];
            scattering += weight * self.scattering[wavelength][j];
            let row = &self.differential[wavelength][j * angles..][..angles];
            for (p, f) in phase.iter_mut().zip(row) {
                *p += weight * f;
            }
        }
        (extinction, scattering)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inversion::state::{AerosolState, LogNormalMode};
    use crate::mie::distribution::SizeDistribution;
    use crate::mie::ensemble::{
        EnsembleSettings, TabulatedPhaseFunction, compute_ensemble_optics_spectrum,
    };
    use crate::mie::refractive_index::RefractiveIndexModel;

    /// The kernels' bimodal ensemble against `sora-mie`'s adaptive
    /// quadrature of the same two modes (untruncated, 1e-7 to 1e-4 by its
    /// own measured errors): the ratios the forward model uses (the
    /// spectral shape of the extinction, the albedo, the phase function).
    #[test]
    fn kernels_match_the_adaptive_ensemble() {
        let wavelengths_nm = [440.0, 675.0, 870.0, 1020.0];
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for (m, fine, coarse, fraction) in [
            (Complex64::new(1.45, 0.005), (0.15, 0.45), (2.5, 0.65), 0.5),
            (Complex64::new(1.55, 0.02), (0.12, 0.4), (1.8, 0.6), 0.2),
            (Complex64::new(1.40, 0.001), (0.2, 0.5), (3.5, 0.7), 0.8),
        ] {
            let state = AerosolState {
                optical_depth: 0.5,
                fine: LogNormalMode {
                    volume_median_radius_um: fine.0,
                    width: fine.1,
                },
                coarse: LogNormalMode {
                    volume_median_radius_um: coarse.0,
                    width: coarse.1,
                },
                fine_volume_fraction: fraction,
                refractive_index_real: m.re,
                refractive_index_imaginary: m.im,
            };
            let kernels = MieKernels::compute(&wavelengths_nm, m).unwrap();
            let (radii_um, _) = radius_nodes_um();
            let volume: Vec<f64> = radii_um
                .iter()
                .map(|r| state.volume_per_ln_radius(*r))
                .collect();

            // The exact modes, per unit volume.
            let settings = EnsembleSettings::default();
            let model = RefractiveIndexModel::constant(m).unwrap();
            let modes: Vec<_> = [(state.fine, fraction), (state.coarse, 1.0 - fraction)]
                .iter()
                .map(|(mode, weight)| {
                    let s = mode.width;
                    let number_median_m =
                        mode.volume_median_radius_um * 1e-6 * (-3.0 * s * s).exp();
                    let mean_volume_m3 = 4.0 / 3.0
                        * std::f64::consts::PI
                        * number_median_m.powi(3)
                        * (4.5 * s * s).exp();
                    let d = SizeDistribution::log_normal(number_median_m, s.exp()).unwrap();
                    let optics =
                        compute_ensemble_optics_spectrum(&wavelengths_nm, &model, &d, &settings)
                            .unwrap();
                    (optics, weight / mean_volume_m3)
                })
                .collect();
            let exact: Vec<(f64, f64)> = (0..4)
                .map(|i| {
                    modes.iter().fold((0.0, 0.0), |(e, s), (optics, w)| {
                        let c = &optics[i].cross_sections;
                        (
                            e + w * c.extinction_cross_section_m2,
                            s + w * c.scattering_cross_section_m2,
                        )
                    })
                })
                .collect();
            let mut phase = Vec::new();
            let (e_ref, _) = kernels.ensemble(0, &volume, &mut phase);
            for i in 0..4 {
                let (e, s) = kernels.ensemble(i, &volume, &mut phase);
                let table =
                    TabulatedPhaseFunction::from_nodes(kernels.cos_theta.clone(), phase.clone())
                        .unwrap();
                let shape = (e / e_ref) / (exact[i].0 / exact[0].0) - 1.0;
                let albedo = s / e - exact[i].1 / exact[i].0;
                let mut phase_error = 0.0f64;
                for mu in &kernels.cos_theta {
                    let exact_phase: f64 = modes
                        .iter()
                        .map(|(optics, w)| {
                            w * optics[i].cross_sections.scattering_cross_section_m2
                                * optics[i].phase_function.phase_function_per_sr(*mu)
                        })
                        .sum::<f64>()
                        / exact[i].1;
                    let err = (table.phase_function_per_sr(*mu) / exact_phase - 1.0).abs();
                    // Within 2 degrees the kernels lack the diffraction
                    // peaks of spheres beyond 15 um (up to 6 % at 0 deg
                    // for a coarse mode of 3.5 um, width 0.7): the
                    // retrieval's size range, not its quadrature.
                    if mu.acos().to_degrees() >= 2.0 {
                        phase_error = phase_error.max(err);
                    }
                }
                worst = (
                    worst.0.max(shape.abs()),
                    worst.1.max(albedo.abs()),
                    worst.2.max(phase_error),
                );
            }
        }
        // Measured: 1.5e-3, 4.3e-4 and 2.8e-2 (the last at 170-180 deg for
        // k = 0.001, where sharp resonances dominate the backscatter and
        // `sora-mie`'s own rule is good to 2.4e-2); 241 nodes halve the
        // phase error at twice the cost.
        println!("worst: extinction shape, albedo, phase beyond 2 deg: {worst:?}");
        assert!(
            worst.0 < 2e-3 && worst.1 < 6e-4 && worst.2 < 3.5e-2,
            "{worst:?}"
        );
    }
}
