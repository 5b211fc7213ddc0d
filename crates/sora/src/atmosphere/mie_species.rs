//! Aerosol from Mie theory: the paper's central idea (§2-3). Particles of a
//! given material (complex refractive index m(lambda), constant or
//! tabulated) and size distribution (log-normal, optionally truncated to
//! a radius window as in the paper's Tables 1-2, gamma, or a volume
//! distribution dV/d ln r tabulated as measured) have, per
//! particle, ensemble-averaged cross-sections `<C_ext>(lambda)`,
//! `<C_sca>(lambda)` and a phase function, computed by the `sora-mie`
//! engine (eq. 2 with its misprint corrected, integrated over the
//! distribution instead of the paper's random radius draw). Then
//!
//! ```text
//!     beta_ext(lambda) = N_ref <C_ext>(lambda),   beta_sca = N_ref <C_sca>      [m^-1]
//! ```
//!
//! at relative density 1, with N_ref either given (`number_density_m3`,
//! particles per m^3 of the population the distribution describes: for a
//! truncated distribution, the particles inside the window, as the paper's
//! tables count them) or set by a column optical depth tau at a reference
//! wavelength: `N_ref = tau / (<C_ext>(lambda_ref) column_m)`, the way
//! aerosol amounts are measured (sun photometers) and the way the Earth
//! presets are set, or, for a measured (tabulated) volume distribution
//! dV/d ln r, by the table itself: `N_ref = N_column / column_m`, with
//! `N_column = integral dV/d ln r / (4/3 pi r^3) d ln r` the column number.
//!
//! Phase function, two modes (see `sora_mie::paper_phase`):
//! - `"mie"`: the exact phase function of the distribution (scattering-
//!   weighted mean of the single-sphere functions), tabulated per
//!   wavelength on a grid of scattering angles dense in the forward peak;
//! - `"paper-hg"`: the paper's eq. 3, Henyey-Greenstein with its g(radius)
//!   rule averaged over the distribution.

use super::phase::{PhaseFunction, TabulatedPhase};
use crate::error::{Error, Result};
use crate::mie::Complex64;
use crate::mie::distribution::SizeDistribution;
use crate::mie::ensemble::{
    AerosolPhaseFunction, EnsembleError, EnsembleOptics, EnsembleSettings, PhaseMatrixRatios,
    compute_ensemble_cross_sections, compute_ensemble_optics_spectrum,
    compute_shared_ensemble_phase_matrix_ratios,
};
use crate::mie::paper_phase::AerosolPhaseMode;
use crate::mie::refractive_index::{RefractiveIndexError, RefractiveIndexModel};
use crate::spectrum::{SampledSpectrum, WavelengthAnchors, WavelengthGrid};

/// How much aerosol there is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParticleAmount {
    /// Particles per m^3 at relative density 1.
    NumberDensityM3(f64),
    /// Vertical column extinction optical depth at a reference wavelength.
    OpticalDepth {
        /// The column extinction optical depth.
        optical_depth: f64,
        /// The wavelength it is given at, nm.
        reference_wavelength_nm: f64,
    },
    /// Particles per m^2 of the whole column (ground to top): a measured
    /// size distribution's absolute amount, `N_ref = N_column / column_m`.
    ColumnNumberPerM2(f64),
}

/// A Mie aerosol, validated by the file loader.
#[derive(Debug, Clone, PartialEq)]
pub struct MieAerosol {
    /// The particles' complex refractive index against wavelength.
    pub refractive_index: RefractiveIndexModel,
    /// Their radii (log-normal, gamma, ...), with its integration window.
    pub size_distribution: SizeDistribution,
    /// Which phase function: full Mie, or the paper's HG of g(r).
    pub phase_mode: AerosolPhaseMode,
    /// How many particles there are.
    pub amount: ParticleAmount,
}

/// The optics of a Mie aerosol on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct MieOptics {
    /// beta_ext at relative density 1, m^-1, per wavelength.
    pub extinction_per_m: SampledSpectrum,
    /// beta_sca at relative density 1, m^-1, per wavelength.
    pub scattering_per_m: SampledSpectrum,
    /// The ensemble's phase function per wavelength.
    pub phase_function: PhaseFunction,
    /// Particles per m^3 at relative density 1.
    pub reference_number_density_m3: f64,
}

impl MieAerosol {
    /// Ensemble cross-sections on `grid` and the phase function, scaled to
    /// the amount (the expensive step: one Mie ensemble per wavelength,
    /// with `sora-mie`'s validated quadrature settings). `name` prefixes
    /// errors (`species[1] (dust)`).
    pub(crate) fn compute_optics(
        &self,
        grid: &WavelengthGrid,
        column_m: f64,
        name: &str,
    ) -> Result<MieOptics> {
        let settings = EnsembleSettings {
            phase_mode: self.phase_mode,
            ..EnsembleSettings::default()
        };
        let wavelengths_nm: Vec<f64> = grid.wavelengths_nm().collect();
        let per_wavelength = compute_ensemble_optics_spectrum(
            &wavelengths_nm,
            &self.refractive_index,
            &self.size_distribution,
            &settings,
        )
        .map_err(|e| ensemble_error(name, e))?;

        let reference_number_density_m3 = match self.amount {
            ParticleAmount::NumberDensityM3(n) => n,
            ParticleAmount::ColumnNumberPerM2(column_number) => column_number / column_m,
            ParticleAmount::OpticalDepth {
                optical_depth,
                reference_wavelength_nm,
            } => {
                let m = self
                    .refractive_index
                    .refractive_index_at(reference_wavelength_nm)
                    .map_err(|e| ensemble_error(name, e.into()))?;
                let reference = compute_ensemble_cross_sections(
                    reference_wavelength_nm,
                    m,
                    &self.size_distribution,
                    &settings.cross_section_quadrature,
                )
                .map_err(|e| ensemble_error(name, e))?;
                // Particles that do not extinguish light at the reference
                // wavelength (e.g. m = 1 + 0i) cannot reach any optical
                // depth there: refused, naming the index (issue 17).
                if reference.extinction_cross_section_m2.is_nan()
                    || reference.extinction_cross_section_m2 <= 0.0
                {
                    return Err(Error::parse(
                        "atmosphere",
                        0,
                        format!(
                            "{name}: optical_depth = {optical_depth} at reference_wavelength_nm = {reference_wavelength_nm} cannot be reached: particles of refractive index {} + {}i neither scatter nor absorb there (zero extinction cross-section); give a refractive index other than 1 + 0i, or give number_density_m3 for a non-scattering species",
                            m.re, m.im
                        ),
                    ));
                }
                optical_depth / (reference.extinction_cross_section_m2 * column_m)
            }
        };

        let n = reference_number_density_m3;
        let extinction_per_m = per_wavelength
            .iter()
            .map(|o| n * o.cross_sections.extinction_cross_section_m2)
            .collect();
        let scattering_per_m = per_wavelength
            .iter()
            .map(|o| n * o.cross_sections.scattering_cross_section_m2)
            .collect();
        let phase_function = phase_on_grid(&per_wavelength).ok_or_else(|| {
            Error::InvalidSpectrum(format!(
                "{name}: the Mie phase tables of the wavelengths do not share their angles"
            ))
        })?;
        Ok(MieOptics {
            extinction_per_m: SampledSpectrum::from_values(extinction_per_m),
            scattering_per_m: SampledSpectrum::from_values(scattering_per_m),
            phase_function,
            reference_number_density_m3,
        })
    }
}

impl MieAerosol {
    /// The phase-matrix ratios of the ensemble at every wavelength of
    /// `grid`, on the nodes of its phase table `table`, kept in the table
    /// (`phase_matrix.rs`; the radius rule of the phase tables): computed
    /// at the wavelengths `anchors` and, between them, interpolated in
    /// wavelength node by node ([`WavelengthAnchors::blend`]). `name` prefixes errors.
    pub(crate) fn compute_phase_matrix(
        &self,
        grid: &WavelengthGrid,
        anchors: &WavelengthAnchors,
        table: &mut TabulatedPhase,
        name: &str,
    ) -> Result<()> {
        let settings = EnsembleSettings::default().phase_function_quadrature;
        let nodes = table.cos_theta_nodes().to_vec();
        // The anchors grouped by the particles' index, in first-seen
        // order: one group (one Mie solution per node of a quadrature in
        // size parameter shared by its wavelengths,
        // `compute_shared_ensemble_phase_matrix_ratios`) a task.
        let mut groups: Vec<(Complex64, Vec<usize>)> = Vec::new();
        for (n, &i) in anchors.anchors().iter().enumerate() {
            let m = self
                .refractive_index
                .refractive_index_at(grid.wavelength_nm(i))
                .map_err(|e| ensemble_error(name, e.into()))?;
            match groups.iter_mut().find(|(index, _)| *index == m) {
                Some((_, members)) => members.push(n),
                None => groups.push((m, vec![n])),
            }
        }
        let mut per_group: Vec<Option<Result<Vec<PhaseMatrixRatios>>>> =
            groups.iter().map(|_| None).collect();
        crate::parallel::for_each_chunk_mut(&mut per_group, 1, |g, slot| {
            let (m, members) = &groups[g];
            let wavelengths_nm: Vec<f64> = members
                .iter()
                .map(|&n| grid.wavelength_nm(anchors.anchors()[n]))
                .collect();
            slot[0] = Some(
                compute_shared_ensemble_phase_matrix_ratios(
                    &wavelengths_nm,
                    *m,
                    &self.size_distribution,
                    &settings,
                    &nodes,
                )
                .map_err(|e| ensemble_error(name, e)),
            );
        });
        // Back in anchor order; the first error in group order.
        let mut at_anchors: Vec<Option<PhaseMatrixRatios>> =
            anchors.anchors().iter().map(|_| None).collect();
        for ((_, members), ratios) in groups.iter().zip(per_group.into_iter().flatten()) {
            for (&n, ratios) in members.iter().zip(ratios?) {
                at_anchors[n] = Some(ratios);
            }
        }
        let at_anchors: Vec<PhaseMatrixRatios> = at_anchors
            .into_iter()
            .map(|r| r.expect("every anchor is in one group"))
            .collect();
        let ratios = (0..grid.len())
            .map(|i| {
                let blend = anchors.blend(i);
                let mix = |of: fn(&PhaseMatrixRatios) -> &Vec<f64>| -> Vec<f64> {
                    (0..nodes.len())
                        .map(|node| {
                            blend
                                .iter()
                                .map(|(n, w)| w * of(&at_anchors[*n])[node])
                                .sum()
                        })
                        .collect()
                };
                match blend {
                    [(n, _)] => at_anchors[*n].clone(),
                    _ => PhaseMatrixRatios {
                        cos_theta: nodes.clone(),
                        f12_over_f11: mix(|r| &r.f12_over_f11),
                        f33_over_f11: mix(|r| &r.f33_over_f11),
                        f34_over_f11: mix(|r| &r.f34_over_f11),
                    },
                }
            })
            .collect();
        if !table.set_matrix_ratios(ratios) {
            return Err(Error::InvalidSpectrum(format!(
                "{name}: the phase matrix does not match the phase table's nodes"
            )));
        }
        Ok(())
    }
}

/// The per-wavelength phase functions of the ensembles as one
/// [`PhaseFunction`]: Henyey-Greenstein with the paper's g per wavelength,
/// or one table with a row per wavelength (the engine tabulates every
/// wavelength on the same angles).
fn phase_on_grid(per_wavelength: &[EnsembleOptics]) -> Option<PhaseFunction> {
    let mut asymmetry_g = Vec::with_capacity(per_wavelength.len());
    let mut tables = Vec::with_capacity(per_wavelength.len());
    for optics in per_wavelength {
        match &optics.phase_function {
            AerosolPhaseFunction::HenyeyGreenstein(hg) => {
                asymmetry_g.push(hg.asymmetry_parameter());
            }
            AerosolPhaseFunction::Tabulated(table) => tables.push(table.clone()),
        }
    }
    match (tables.is_empty(), asymmetry_g.is_empty()) {
        (true, _) => Some(PhaseFunction::HenyeyGreenstein { asymmetry_g }),
        (false, false) => None,
        // The engine's tables as they are: `from_tables` checks that they
        // share their angles.
        (false, true) => TabulatedPhase::from_tables(tables).map(PhaseFunction::Tabulated),
    }
}

/// An engine error as a one-line library error: a refractive-index table
/// that does not cover a wavelength is a spectrum problem (like any table
/// that does not cover the grid); the rest are Mie-domain problems.
fn ensemble_error(name: &str, e: EnsembleError) -> Error {
    match e {
        EnsembleError::RefractiveIndex(RefractiveIndexError::WavelengthOutsideTable { .. }) => {
            Error::InvalidSpectrum(format!("{name}: scattering.mie.refractive_index: {e}"))
        }
        other => Error::parse(
            "atmosphere",
            0,
            format!("{name}: Mie aerosol optics: {other}"),
        ),
    }
}
