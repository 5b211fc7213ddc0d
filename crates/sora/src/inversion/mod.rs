//! # Inversion: from measured sky radiances back to the aerosol
//!
//! The paper's future work, as sun-sky photometer networks do it (AERONET,
//! Dubovik & King 2000): from sky radiances in known directions at a few
//! wavelengths (an almucantar or a principal plane, 440/675/870/1020 nm),
//! with the aerosol optical depths measured from the direct sun if there
//! are any, estimate the aerosol: its optical depth, its size
//! distribution and its complex refractive index, and from them its
//! single-scattering albedo, asymmetry parameter, Angstrom exponent and
//! effective radii, each with an uncertainty.
//!
//! - `measurements.rs`: what is measured ([`Measurements`]), and its
//!   checks ([`Measurements::validate`]); `input/`: its readers from
//!   text (sora's CSV, AERONET version 3 almucantar, principal-plane and
//!   optical-depth files (and version 2 optical depths), a normalised
//!   spectrum in one direction), and of the network's own version 2
//!   inversion products, to compare with ([`parse_aeronet_inversion`]);
//! - `state.rs`: what is fitted ([`AerosolState`]: the optical depth at a
//!   reference wavelength, two log-normal volume modes, a refractive
//!   index per wavelength with a smoothness prior on n's slope and on the
//!   curvature of n and ln k in ln lambda, or one for every wavelength,
//!   [`IndexSpectrum`]),
//!   its bounds and its a priori;
//! - `kernels.rs`: Mie kernels per radius node, so that a new size
//!   distribution costs no Mie solution;
//! - `forward.rs`: the forward model, the library's fast multiple-
//!   scattering method on the user's atmosphere with the state's aerosol;
//! - `fit.rs`: Levenberg-Marquardt with the a priori, and the posterior
//!   covariance.
//!
//! Measurements enter the fit as ln L (sky radiances, sigma = the relative
//! uncertainty) and as tau (optical depths, sigma = their uncertainty), so
//! the fit is in log space for radiances, which span decades along an
//! almucantar, and linear for optical depths, which may be near 0.
//!
//! Assumptions, stated: spheres (Mie theory; AERONET adds spheroids for
//! dust); one refractive index per wavelength for both modes; the
//! aerosol in one exponential layer (scale height
//! [`RetrievalSettings::aerosol_scale_height_m`]; an almucantar depends on
//! it very little, since every view sees the same air mass); scalar light
//! (the polarised intensity differs by up to a few per cent,
//! `docs/polarisation.md`); the ground albedo of the atmosphere given.
//! What a single normalised spectrum in one direction (the paper's Fig. 2,
//! [`RadianceScale::Relative`]) can tell: with one free scale factor only
//! the spectral shape of one radiance is left, which the optical depth,
//! the fine fraction and the fine radius all change alike, so the
//! retrieval returns the a priori for most of the state with wide
//! uncertainties, and says so in its warnings; an almucantar's angular
//! shape is what carries the size distribution.
//!
//! No I/O: text formats are read in `input/` from strings; the CLI
//! (`sora retrieve`) reads the files and writes the outputs.

mod fit;
mod forward;
pub mod input;
mod kernels;
pub mod measurements;
pub mod state;

pub use input::{
    AeronetInversion, AeronetInversionChannel, AeronetOpticalDepths, AeronetScan, AeronetSky,
    AeronetSkyScan, AeronetTime, SkyGeometry, attach_nearest_optical_depths, parse_aeronet_aod,
    parse_aeronet_inversion, parse_aeronet_sky, parse_normalised_spectrum_csv,
    parse_optical_depth_csv, parse_sky_radiance_csv,
};
pub use kernels::{MAX_RADIUS_UM, MIN_RADIUS_UM, RADIUS_NODES};
pub use measurements::{
    MIN_SCATTERING_ANGLE_DEG, Measurements, OpticalDepthMeasurement, RadianceScale,
    SkyRadianceMeasurement,
};
pub use state::{AerosolState, BOUNDS, Bounds, LogNormalMode, PARAMETER_NAMES, PARAMETERS};

use crate::atmosphere::Atmosphere;
use crate::error::{Error, Result};
use crate::mie::Complex64;
use crate::spectrum::Filter;
use fit::{Problem, Start};
use forward::{AerosolOptics, ForwardModel};
use std::sync::atomic::Ordering;

/// The most distinct wavelengths one retrieval takes (checked before any
/// work): the forward model computes one sky per wavelength (and sun
/// position) at every evaluation, so a spectroradiometer's 1-nm spectrum
/// (hundreds of wavelengths) would take minutes for a result that a few
/// tens of wavelengths determine as well (a photometer has 4-7).
pub const MAX_RETRIEVAL_WAVELENGTHS: usize = 41;

/// How a retrieval runs.
#[derive(Debug, Clone, PartialEq)]
pub struct RetrievalSettings {
    /// The wavelength of the state's optical depth, nm; one of the measured
    /// wavelengths. None: 440 nm if it was measured, else the shortest.
    pub reference_wavelength_nm: Option<f64>,
    /// Scale height of the aerosol's exponential profile, m.
    pub aerosol_scale_height_m: f64,
    /// The most Levenberg-Marquardt iterations in all: the starting
    /// points' scouting (three iterations each), then the best one's.
    pub max_iterations: usize,
    /// Starting points, each fitted to its own minimum; the lowest chi^2
    /// wins (see [`RetrievalSettings::starting_states`]).
    pub starting_points: usize,
    /// Width of each measured wavelength's band, nm: the sun's spectrum and
    /// the gases' cross-sections are averaged over [lambda - band/2,
    /// lambda + band/2] (a one-point grid of this step), as the channel of
    /// an instrument that wide sees them (10 nm: the Cimel channels at
    /// 440-1020 nm, `spectrum::CIMEL_CHANNELS`); 0.01..=50.
    pub band_nm: f64,
    /// The refractive index: one n + ik per measured wavelength, smooth in
    /// wavelength (the default: a smoothness prior across the channels, as
    /// AERONET's inversion has, Dubovik & King 2000; see
    /// [`IndexSpectrum`]), or one for every wavelength.
    pub index: IndexSpectrum,
    /// Instrument channels (docs/filters.md): each measured wavelength
    /// inside a filter's support (the nearest to its weighted centre) is
    /// computed as that channel sees it, the sun and the air's and gases'
    /// optics weighted by the response (`forward::band_optics`) instead of
    /// the box of `band_nm`. Empty: every wavelength takes the box.
    pub filters: Vec<Filter>,
}

/// How the refractive index may vary with wavelength.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IndexSpectrum {
    /// One n and one k at each measured wavelength, both modes alike, with
    /// the smoothness prior of Dubovik & King (2000, section 2.3): the
    /// second derivatives of n and of ln k with respect to ln lambda,
    /// estimated by the second divided differences of consecutive channels,
    /// have a priori standard deviations [`SMOOTHNESS_SIGMA_N`] and
    /// [`SMOOTHNESS_SIGMA_LN_K`] (a straight line in ln lambda costs
    /// nothing; a power law k ~ lambda^p is such a line in ln k), and n's
    /// first derivative, estimated by the first divided difference of each
    /// two consecutive channels, [`SMOOTHNESS_SIGMA_SLOPE_N`]: n may vary a
    /// little with wavelength, k freely along a smooth curve. The default.
    PerWavelength,
    /// One n and one k for every wavelength.
    One,
}

/// A priori standard deviation of d^2 n / d(ln lambda)^2 between
/// consecutive channels (the smoothness prior of [`IndexSpectrum::PerWavelength`]).
/// Aerosols' n varies by a few hundredths over 440-1020 nm: a curvature of
/// 0.5 over that span (0.84 in ln lambda) bends n by about 0.04.
pub const SMOOTHNESS_SIGMA_N: f64 = 0.5;

/// A priori standard deviation of dn / d(ln lambda) between consecutive
/// channels. Aerosols' n changes by a few hundredths at most over
/// 440-1020 nm (water 1.337 to 1.327), below the retrieval's bar for n
/// (0.04), and an almucantar cannot tell n's slope from the fine mode's
/// size (docs/retrieval.md: without this prior, the validation set's
/// case 1 missed the fine effective radius by 18.6 %), so n is held
/// nearly flat: at 440/675/870/1020 nm a slope s costs 3 (s / 0.01)^2, so
/// 1 sigma is a change of n of about 0.005 over the span.
pub const SMOOTHNESS_SIGMA_SLOPE_N: f64 = 0.01;

/// A priori standard deviation of d^2 ln k / d(ln lambda)^2 between
/// consecutive channels. Dust's k (falling steeply from 440 to 675 nm,
/// flat beyond) has a curvature of about 4-5, within its 1 sigma.
pub const SMOOTHNESS_SIGMA_LN_K: f64 = 5.0;

impl Default for RetrievalSettings {
    fn default() -> Self {
        RetrievalSettings {
            reference_wavelength_nm: None,
            aerosol_scale_height_m: 1200.0,
            max_iterations: 30,
            starting_points: 2,
            band_nm: 1.0,
            index: IndexSpectrum::PerWavelength,
            filters: Vec::new(),
        }
    }
}

impl RetrievalSettings {
    /// The starting states, in order (the first `starting_points` are
    /// used): a fine-dominated aerosol (urban, smoke), a coarse-dominated
    /// one (dust), and the a priori; each with the measured optical depth
    /// at the reference wavelength where there is one.
    pub fn starting_states(optical_depth: f64) -> Vec<AerosolState> {
        let mode = |r, s| LogNormalMode {
            volume_median_radius_um: r,
            width: s,
        };
        vec![
            AerosolState {
                optical_depth,
                fine: mode(0.15, 0.45),
                coarse: mode(2.5, 0.65),
                fine_volume_fraction: 0.6,
                refractive_index_real: 1.45,
                refractive_index_imaginary: 0.008,
            },
            AerosolState {
                optical_depth,
                fine: mode(0.12, 0.45),
                coarse: mode(2.0, 0.6),
                fine_volume_fraction: 0.1,
                refractive_index_real: 1.52,
                refractive_index_imaginary: 0.003,
            },
            AerosolState {
                optical_depth,
                ..AerosolState::a_priori()
            },
        ]
    }
}

/// A retrieved number and its 1-sigma uncertainty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// Its 1-sigma uncertainty (from the linearised posterior covariance).
    pub sigma: f64,
}

/// The aerosol's optics at one measured wavelength.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralOptics {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Aerosol extinction optical depth.
    pub optical_depth: Estimate,
    /// Single-scattering albedo.
    pub single_scattering_albedo: Estimate,
    /// Asymmetry parameter.
    pub asymmetry: Estimate,
    /// Real part of the refractive index at this wavelength.
    pub refractive_index_real: Estimate,
    /// Imaginary part of the refractive index at this wavelength.
    pub refractive_index_imaginary: Estimate,
}

/// One measured sky radiance and its fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedRadiance {
    /// The measurement.
    pub measured: SkyRadianceMeasurement,
    /// The forward model at the retrieved state, W m^-2 sr^-1 nm^-1 (in the
    /// measurement's units when the scale is relative).
    pub fitted_w_m2_sr_nm: f64,
    /// (measured - fitted) / uncertainty.
    pub normalised_residual: f64,
}

/// One measured optical depth and its fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedOpticalDepth {
    /// The measurement.
    pub measured: OpticalDepthMeasurement,
    /// The retrieved aerosol's optical depth there.
    pub fitted: f64,
    /// (measured - fitted) / uncertainty.
    pub normalised_residual: f64,
}

/// What a retrieval found.
#[derive(Debug, Clone, PartialEq)]
pub struct Retrieval {
    /// The measurements' label.
    pub label: String,
    /// The reference wavelength of the optical depth, nm.
    pub reference_wavelength_nm: f64,
    /// The retrieved state (its refractive index: the reference
    /// wavelength's; every wavelength's is in `spectral`).
    pub state: AerosolState,
    /// Each parameter with its 1-sigma uncertainty, in
    /// [`PARAMETER_NAMES`]' order (the refractive index at the reference
    /// wavelength).
    pub parameters: Vec<Estimate>,
    /// Correlations between the parameters (row-major, PARAMETERS^2).
    pub correlations: Vec<f64>,
    /// Optical depth, albedo and asymmetry per measured wavelength.
    pub spectral: Vec<SpectralOptics>,
    /// Angstrom exponent: minus the slope of ln tau against ln lambda,
    /// least squares over the measured wavelengths.
    pub angstrom_exponent: Estimate,
    /// Effective radius of the fine and the coarse mode, um.
    pub fine_effective_radius_um: Estimate,
    /// See above.
    pub coarse_effective_radius_um: Estimate,
    /// The fitted radiance scale factor (relative radiances only).
    pub radiance_scale: Option<Estimate>,
    /// Every sky radiance and its fit.
    pub radiances: Vec<FittedRadiance>,
    /// Every optical depth and its fit.
    pub optical_depths: Vec<FittedOpticalDepth>,
    /// chi^2 of the measurements at the retrieved state.
    pub chi_square: f64,
    /// How many measurements (radiances and optical depths).
    pub measurement_count: usize,
    /// Levenberg-Marquardt iterations of the winning start.
    pub iterations: usize,
    /// Whether the fit met its convergence criterion.
    pub converged: bool,
    /// Forward-model evaluations (radiances at every measurement) and
    /// Mie kernel computations (one per wavelength and refractive index met) it took.
    pub forward_evaluations: usize,
    /// See above.
    pub kernel_computations: usize,
    /// What the user should know about this result (no convergence, a poor
    /// fit, parameters the measurements did not constrain), one line each.
    pub warnings: Vec<String>,
}

/// A posterior uncertainty above this fraction of its a priori one means
/// the measurements did not constrain the parameter (warned about).
const UNCONSTRAINED_FRACTION: f64 = 0.7;

/// Iterations each starting point gets before the best is continued.
const SCOUT_ITERATIONS: usize = 3;

/// Forward difference step of the Jacobian, in the fit's coordinates
/// (logit units: a relative change of about 1 % of a log-bounded
/// parameter); small enough for the model's curvature, large enough
/// against its interpolation noise.
const JACOBIAN_STEP: f64 = 0.02;

/// Retrieves the aerosol from `measurements` in `atmosphere` (its air,
/// gases, ground and sun; its own aerosol species are set aside).
pub fn retrieve(
    atmosphere: &Atmosphere,
    measurements: &Measurements,
    settings: &RetrievalSettings,
) -> Result<Retrieval> {
    measurements.validate()?;
    if !(1..=3).contains(&settings.starting_points) {
        return Err(Error::out_of_range(
            "starting points",
            settings.starting_points as f64,
            "1",
            "1..=3",
        ));
    }
    if settings.max_iterations == 0 {
        return Err(Error::out_of_range("max iterations", 0.0, "1", ">= 1"));
    }
    let wavelengths = measurements.wavelengths_nm();
    if wavelengths.len() > MAX_RETRIEVAL_WAVELENGTHS {
        return Err(Error::Unsupported(format!(
            "{}: {} wavelengths, more than the {MAX_RETRIEVAL_WAVELENGTHS} one retrieval fits (the model computes a sky per wavelength at every step); keep fewer, e.g. one every 10-20 nm",
            measurements.label,
            wavelengths.len()
        )));
    }
    let reference_wavelength_nm = settings.reference_wavelength_nm.unwrap_or(
        if forward::wavelength_index(&wavelengths, 440.0).is_some() {
            440.0
        } else {
            wavelengths[0]
        },
    );
    if !(0.01..=50.0).contains(&settings.band_nm) {
        return Err(Error::out_of_range(
            "band",
            settings.band_nm,
            "nm",
            "0.01..=50",
        ));
    }
    let filters = assign_filters(&settings.filters, &wavelengths)?;
    let forward = ForwardModel::new(
        atmosphere,
        measurements,
        settings.aerosol_scale_height_m,
        reference_wavelength_nm,
        settings.band_nm,
        &filters,
    )?;
    let relative = measurements.scale == RadianceScale::Relative;
    let layout = Layout {
        wavelengths: forward.wavelengths_nm.len(),
        reference: forward.reference,
        per_wavelength: settings.index == IndexSpectrum::PerWavelength,
        relative,
    };
    let parameters = layout.count();
    let smoothness = layout.smoothness_rows(&forward.wavelengths_nm);

    // y: ln L for radiances, tau for optical depths, then the smoothness
    // prior's second differences (0, sigma 1: the rows are scaled).
    let mut measured: Vec<f64> = measurements
        .sky
        .iter()
        .map(|m| m.radiance_w_m2_sr_nm.ln())
        .collect();
    let mut sigma: Vec<f64> = measurements
        .sky
        .iter()
        .map(|m| m.uncertainty_w_m2_sr_nm / m.radiance_w_m2_sr_nm)
        .collect();
    measured.extend(
        measurements
            .optical_depths
            .iter()
            .map(|d| d.aerosol_optical_depth),
    );
    sigma.extend(measurements.optical_depths.iter().map(|d| d.uncertainty));
    measured.extend(smoothness.iter().map(|_| 0.0));
    sigma.extend(smoothness.iter().map(|_| 1.0));
    let depth_wavelengths: Vec<usize> = measurements
        .optical_depths
        .iter()
        .map(|d| {
            forward::wavelength_index(&forward.wavelengths_nm, d.wavelength_nm).ok_or_else(|| {
                Error::Unsupported(format!(
                    "{}: an optical depth at {} nm, where no sky radiance was measured",
                    measurements.label, d.wavelength_nm
                ))
            })
        })
        .collect::<Result<_>>()?;

    let model = |t: &[f64]| -> Option<Vec<f64>> {
        let (state, indices) = layout.unpack(t);
        let (radiances, optics) = forward.radiances(&state, &indices).ok()?;
        let shift = if relative { t[layout.physical()] } else { 0.0 };
        let mut values: Vec<f64> = radiances.iter().map(|l| l.ln() + shift).collect();
        values.extend(depth_wavelengths.iter().map(|&w| optics[w].optical_depth));
        values.extend(smoothness.iter().map(|row| row.evaluate(&indices)));
        values.iter().all(|v| v.is_finite()).then_some(values)
    };
    let evaluate_many = |points: &[Vec<f64>]| -> Vec<Option<Vec<f64>>> {
        let mut results: Vec<Option<Vec<f64>>> = vec![None; points.len()];
        crate::parallel::for_each_chunk_mut(&mut results, 1, |i, chunk| {
            chunk[0] = model(&points[i]);
        });
        results
    };

    let measured_depth = measurements
        .optical_depths
        .iter()
        .find(|d| {
            (d.wavelength_nm - reference_wavelength_nm).abs() < measurements::SAME_WAVELENGTH_NM
        })
        .map(|d| d.aerosol_optical_depth.clamp(0.01, 3.0));
    let prior_mean = vec![0.0; parameters];
    let mut prior_sigma = vec![state::PRIOR_SIGMA; parameters];
    if relative {
        // The scale factor: free (a flat a priori).
        prior_sigma[layout.physical()] = 1e3;
    }
    let problem = Problem {
        measured: &measured,
        sigma: &sigma,
        prior_mean: &prior_mean,
        prior_sigma: &prior_sigma,
        step: JACOBIAN_STEP,
        max_iterations: settings.max_iterations,
        finish: true,
    };
    // Several starts against local minima, each scouted for a few
    // iterations; the best goes on to convergence.
    let mut scouted: Option<fit::Solution> = None;
    let total = |s: &fit::Solution| s.chi_square_measurements + s.chi_square_prior;
    for start in RetrievalSettings::starting_states(measured_depth.unwrap_or(0.2))
        .into_iter()
        .take(settings.starting_points)
    {
        let mut t = layout.start(&start);
        if relative {
            // Start the scale at the mean ratio of measured to modelled.
            let modelled = model(&[t.clone(), vec![0.0]].concat());
            let shift = modelled.map_or(0.0, |f| {
                measured[..measurements.sky.len()]
                    .iter()
                    .zip(&f)
                    .map(|(y, f)| y - f)
                    .sum::<f64>()
                    / measurements.sky.len() as f64
            });
            t.push(shift);
        }
        let scout = Problem {
            max_iterations: SCOUT_ITERATIONS.min(settings.max_iterations),
            finish: false,
            ..problem
        };
        if let Some(solution) = scout.solve(Start::At(t), &evaluate_many) {
            if scouted.as_ref().is_none_or(|b| total(&solution) < total(b)) {
                scouted = Some(solution);
            }
        }
    }
    let best = match scouted {
        Some(s) => {
            // The scouting counts against the iterations allowed; with
            // none left, the continuation only finishes (the Jacobian and
            // the covariance at the scout's end point).
            let (scouting, scout_converged) = (s.iterations, s.converged);
            let remaining = settings.max_iterations.saturating_sub(scouting);
            let rest = Problem {
                max_iterations: remaining,
                ..problem
            };
            rest.solve(Start::From(s), &evaluate_many).map(|mut rest| {
                rest.iterations += scouting;
                rest.converged |= remaining == 0 && scout_converged;
                rest
            })
        }
        None => None,
    };
    let Some(solution) = best else {
        return Err(Error::Unsupported(format!(
            "{}: the fit failed: the forward model could not be evaluated at any starting point",
            measurements.label
        )));
    };
    summarise(
        &forward,
        measurements,
        &solution,
        &prior_sigma,
        &layout,
        reference_wavelength_nm,
    )
}

/// Each measured wavelength's filter, if any: a filter goes to the measured
/// wavelength inside its support nearest its weighted centre; an error when
/// a filter covers none, or two filters the same wavelength.
pub fn assign_filters(filters: &[Filter], wavelengths_nm: &[f64]) -> Result<Vec<Option<Filter>>> {
    let mut assigned: Vec<Option<Filter>> = vec![None; wavelengths_nm.len()];
    for filter in filters {
        let centre = filter.centre_nm()?;
        let nearest = wavelengths_nm
            .iter()
            .enumerate()
            .filter(|(_, w)| filter.response_at(**w) > 0.0)
            .min_by(|a, b| (a.1 - centre).abs().total_cmp(&(b.1 - centre).abs()))
            .map(|(i, _)| i);
        let Some(i) = nearest else {
            return Err(Error::Unsupported(format!(
                "filter {} (centre {centre:.1} nm) covers none of the measured wavelengths ({})",
                filter.name(),
                wavelengths_nm
                    .iter()
                    .map(|w| format!("{w} nm"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        };
        if let Some(other) = &assigned[i] {
            return Err(Error::Unsupported(format!(
                "filters {} and {} both cover the measured wavelength {} nm: give one filter per channel",
                other.name(),
                filter.name(),
                wavelengths_nm[i]
            )));
        }
        assigned[i] = Some(filter.clone());
    }
    Ok(assigned)
}

/// Where each parameter sits in the fit's vector: the state's first six
/// (optical depth, size distribution), then n and k (one each, or one per
/// wavelength: all n, then all k), then the radiance scale's ln if the
/// radiances are relative.
#[derive(Debug, Clone, Copy)]
struct Layout {
    wavelengths: usize,
    reference: usize,
    per_wavelength: bool,
    relative: bool,
}

/// The state's parameters before the refractive index.
const SHARED_PARAMETERS: usize = 6;

/// The refractive index's real and imaginary parts in the state's
/// [`PARAMETER_NAMES`] order, after the shared parameters.
const REAL: usize = SHARED_PARAMETERS;
/// See [`REAL`].
const IMAGINARY: usize = SHARED_PARAMETERS + 1;

/// One row of the smoothness prior: c . (n or ln k at consecutive
/// wavelengths) / sigma, the estimate of a derivative with respect to
/// ln lambda in units of its a priori standard deviation.
#[derive(Debug, Clone)]
struct SmoothnessRow {
    first: usize,
    coefficients: Vec<f64>,
    imaginary: bool,
}

impl SmoothnessRow {
    fn evaluate(&self, indices: &[Complex64]) -> f64 {
        self.coefficients
            .iter()
            .zip(&indices[self.first..])
            .map(|(c, m)| c * if self.imaginary { m.im.ln() } else { m.re })
            .sum()
    }
}

impl Layout {
    /// How many refractive indices are fitted.
    fn indices(&self) -> usize {
        if self.per_wavelength {
            self.wavelengths
        } else {
            1
        }
    }

    /// The position of n at wavelength index `w`.
    fn real(&self, w: usize) -> usize {
        SHARED_PARAMETERS + if self.per_wavelength { w } else { 0 }
    }

    /// The position of k at wavelength index `w`.
    fn imaginary(&self, w: usize) -> usize {
        self.real(w) + self.indices()
    }

    /// How many parameters the aerosol has (the scale follows them).
    fn physical(&self) -> usize {
        SHARED_PARAMETERS + 2 * self.indices()
    }

    /// How many parameters are fitted.
    fn count(&self) -> usize {
        self.physical() + usize::from(self.relative)
    }

    /// Its name.
    fn name(&self, position: usize, wavelengths_nm: &[f64]) -> String {
        if position < SHARED_PARAMETERS || !self.per_wavelength {
            let k = if position < SHARED_PARAMETERS {
                position
            } else if position < SHARED_PARAMETERS + self.indices() {
                REAL
            } else {
                IMAGINARY
            };
            return PARAMETER_NAMES[k].to_string();
        }
        let offset = position - SHARED_PARAMETERS;
        let (k, w) = if offset < self.wavelengths {
            (REAL, offset)
        } else {
            (IMAGINARY, offset - self.wavelengths)
        };
        format!("{} at {} nm", PARAMETER_NAMES[k], wavelengths_nm[w])
    }

    /// The fit's coordinates of `state` (its index at every wavelength).
    fn start(&self, state: &AerosolState) -> Vec<f64> {
        let t = state.to_fit();
        let mut v = t[..SHARED_PARAMETERS].to_vec();
        v.extend(std::iter::repeat_n(t[REAL], self.indices()));
        v.extend(std::iter::repeat_n(t[IMAGINARY], self.indices()));
        v
    }

    /// The state (its index the reference wavelength's) and the index at
    /// every wavelength, at fit coordinates `t`.
    fn unpack(&self, t: &[f64]) -> (AerosolState, Vec<Complex64>) {
        let mut t8 = [0.0; PARAMETERS];
        t8[..SHARED_PARAMETERS].copy_from_slice(&t[..SHARED_PARAMETERS]);
        t8[REAL] = t[self.real(self.reference)];
        t8[IMAGINARY] = t[self.imaginary(self.reference)];
        let indices = (0..self.wavelengths)
            .map(|w| {
                Complex64::new(
                    BOUNDS[REAL].from_fit(t[self.real(w)]),
                    BOUNDS[IMAGINARY].from_fit(t[self.imaginary(w)]),
                )
            })
            .collect();
        (AerosolState::from_fit(&t8), indices)
    }

    /// The smoothness prior's rows (none for one index or one wavelength):
    /// for each three consecutive wavelengths, the second divided
    /// difference in x = ln lambda,
    /// 2 [(f2 - f1)/(x2 - x1) - (f1 - f0)/(x1 - x0)] / (x2 - x0),
    /// of n and of ln k, and for each two, n's first divided difference
    /// (n1 - n0)/(x1 - x0), each over its a priori standard deviation.
    fn smoothness_rows(&self, wavelengths_nm: &[f64]) -> Vec<SmoothnessRow> {
        if !self.per_wavelength || wavelengths_nm.len() < 2 {
            return Vec::new();
        }
        let x: Vec<f64> = wavelengths_nm.iter().map(|w| w.ln()).collect();
        let mut rows = Vec::new();
        for (imaginary, sigma) in [(false, SMOOTHNESS_SIGMA_N), (true, SMOOTHNESS_SIGMA_LN_K)] {
            for first in 0..x.len().saturating_sub(2) {
                let (x0, x1, x2) = (x[first], x[first + 1], x[first + 2]);
                let a = 2.0 / ((x1 - x0) * (x2 - x0));
                let c = 2.0 / ((x2 - x1) * (x2 - x0));
                rows.push(SmoothnessRow {
                    first,
                    coefficients: vec![a / sigma, -(a + c) / sigma, c / sigma],
                    imaginary,
                });
            }
        }
        for first in 0..x.len() - 1 {
            let d = 1.0 / ((x[first + 1] - x[first]) * SMOOTHNESS_SIGMA_SLOPE_N);
            rows.push(SmoothnessRow {
                first,
                coefficients: vec![-d, d],
                imaginary: false,
            });
        }
        rows
    }
}

/// The retrieval's report from the fit's solution.
fn summarise(
    forward: &ForwardModel,
    measurements: &Measurements,
    solution: &fit::Solution,
    prior_sigma: &[f64],
    layout: &Layout,
    reference_wavelength_nm: f64,
) -> Result<Retrieval> {
    let n = solution.t.len();
    let t = &solution.t;
    let (state, _) = layout.unpack(t);
    let covariance = &solution.covariance;
    let sigma_t: Vec<f64> = (0..n).map(|k| covariance[k * n + k].sqrt()).collect();
    // The state's eight parameters' positions in t.
    let positions: Vec<usize> = (0..SHARED_PARAMETERS)
        .chain([
            layout.real(layout.reference),
            layout.imaginary(layout.reference),
        ])
        .collect();
    let parameters: Vec<Estimate> = positions
        .iter()
        .enumerate()
        .map(|(k, &p)| Estimate {
            value: state.to_array()[k],
            sigma: BOUNDS[k].derivative(t[p]).abs() * sigma_t[p],
        })
        .collect();
    let correlations: Vec<f64> = (0..PARAMETERS * PARAMETERS)
        .map(|ij| {
            let (i, j) = (positions[ij / PARAMETERS], positions[ij % PARAMETERS]);
            covariance[i * n + j] / (sigma_t[i] * sigma_t[j])
        })
        .collect();

    // Derived quantities and their gradients in t (forward differences,
    // the Jacobian's step: its index columns' kernels are cached).
    let derived = |t: &[f64]| -> Result<Vec<f64>> {
        let (state, indices) = layout.unpack(t);
        let optics = forward.aerosol_optics(&state, &indices)?;
        Ok(derived_quantities(
            &forward.wavelengths_nm,
            &optics,
            &state,
            &indices,
        ))
    };
    let centre = derived(t)?;
    let mut gradients = vec![vec![0.0; n]; centre.len()];
    for k in 0..layout.physical() {
        let mut moved = t.clone();
        moved[k] += JACOBIAN_STEP;
        for (q, value) in derived(&moved)?.iter().enumerate() {
            gradients[q][k] = (value - centre[q]) / JACOBIAN_STEP;
        }
    }
    let estimate = |q: usize| {
        let g = &gradients[q];
        let variance: f64 = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| g[i] * covariance[i * n + j] * g[j])
            .sum();
        Estimate {
            value: centre[q],
            sigma: variance.max(0.0).sqrt(),
        }
    };
    let w = forward.wavelengths_nm.len();
    let spectral = (0..w)
        .map(|i| SpectralOptics {
            wavelength_nm: forward.wavelengths_nm[i],
            optical_depth: estimate(i),
            single_scattering_albedo: estimate(w + i),
            asymmetry: estimate(2 * w + i),
            refractive_index_real: estimate(3 * w + 3 + i),
            refractive_index_imaginary: estimate(4 * w + 3 + i),
        })
        .collect();

    let sky = measurements.sky.len();
    let measurement_count = sky + measurements.optical_depths.len();
    let radiances = measurements
        .sky
        .iter()
        .zip(&solution.modelled)
        .map(|(m, f)| {
            let fitted = f.exp();
            FittedRadiance {
                measured: *m,
                fitted_w_m2_sr_nm: fitted,
                normalised_residual: (m.radiance_w_m2_sr_nm - fitted) / m.uncertainty_w_m2_sr_nm,
            }
        })
        .collect();
    let optical_depths: Vec<FittedOpticalDepth> = measurements
        .optical_depths
        .iter()
        .zip(&solution.modelled[sky..measurement_count])
        .map(|(m, f)| FittedOpticalDepth {
            measured: *m,
            fitted: *f,
            normalised_residual: (m.aerosol_optical_depth - f) / m.uncertainty,
        })
        .collect();
    // chi^2 of the measurements alone (the fit's also holds the smoothness
    // prior's rows).
    let chi_square: f64 = measurements
        .sky
        .iter()
        .zip(&solution.modelled)
        .map(|(m, f)| {
            ((m.radiance_w_m2_sr_nm.ln() - f) * m.radiance_w_m2_sr_nm / m.uncertainty_w_m2_sr_nm)
                .powi(2)
        })
        .sum::<f64>()
        + optical_depths
            .iter()
            .map(|d| d.normalised_residual.powi(2))
            .sum::<f64>();

    let mut warnings = Vec::new();
    if !solution.converged {
        warnings.push(format!(
            "the fit did not converge in {} iterations: the result is the best point reached, not a minimum",
            solution.iterations
        ));
    }
    let reduced = chi_square / measurement_count as f64;
    if reduced > 4.0 {
        warnings.push(format!(
            "poor fit: chi^2 per measurement is {reduced:.2} (about 1 expected): the measurements' uncertainties are too small, or the model (spheres, one index per wavelength, two modes) does not describe this aerosol"
        ));
    }
    for k in 0..layout.physical() {
        if sigma_t[k] > UNCONSTRAINED_FRACTION * prior_sigma[k] {
            warnings.push(format!(
                "{} is barely constrained by these measurements (posterior uncertainty {:.0} % of the a priori's): its value mostly reflects the a priori",
                layout.name(k, &forward.wavelengths_nm),
                100.0 * sigma_t[k] / prior_sigma[k]
            ));
        }
    }
    let scale = layout.physical();
    Ok(Retrieval {
        label: measurements.label.clone(),
        reference_wavelength_nm,
        state,
        parameters,
        correlations,
        spectral,
        angstrom_exponent: estimate(3 * w),
        fine_effective_radius_um: estimate(3 * w + 1),
        coarse_effective_radius_um: estimate(3 * w + 2),
        radiance_scale: layout.relative.then(|| Estimate {
            value: t[scale].exp(),
            sigma: t[scale].exp() * sigma_t[scale],
        }),
        radiances,
        optical_depths,
        chi_square,
        measurement_count,
        iterations: solution.iterations,
        converged: solution.converged,
        forward_evaluations: forward.evaluations.load(Ordering::Relaxed),
        kernel_computations: forward.kernel_computations.load(Ordering::Relaxed),
        warnings,
    })
}

/// tau, omega and g per wavelength, then the Angstrom exponent and the
/// two modes' effective radii, then n and k per wavelength.
fn derived_quantities(
    wavelengths_nm: &[f64],
    optics: &[AerosolOptics],
    state: &AerosolState,
    indices: &[Complex64],
) -> Vec<f64> {
    let mut values: Vec<f64> = optics.iter().map(|o| o.optical_depth).collect();
    values.extend(optics.iter().map(|o| o.single_scattering_albedo));
    values.extend(
        optics
            .iter()
            .map(|o| o.phase_function.asymmetry_parameter()),
    );
    values.push(angstrom_exponent(wavelengths_nm, optics));
    values.push(state.fine.effective_radius_um());
    values.push(state.coarse.effective_radius_um());
    values.extend(indices.iter().map(|m| m.re));
    values.extend(indices.iter().map(|m| m.im));
    values
}

/// Minus the least-squares slope of ln tau against ln lambda (0 for one
/// wavelength).
fn angstrom_exponent(wavelengths_nm: &[f64], optics: &[AerosolOptics]) -> f64 {
    let n = wavelengths_nm.len() as f64;
    if wavelengths_nm.len() < 2 {
        return 0.0;
    }
    let x: Vec<f64> = wavelengths_nm.iter().map(|w| w.ln()).collect();
    let y: Vec<f64> = optics.iter().map(|o| o.optical_depth.ln()).collect();
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = x.iter().map(|x| (x - mx) * (x - mx)).sum();
    -sxy / sxx
}

/// The refractive index of `state` (for a forward model with the same
/// index at every wavelength).
#[cfg(test)]
pub(crate) fn index_of(state: &AerosolState) -> Complex64 {
    Complex64::new(
        state.refractive_index_real,
        state.refractive_index_imaginary,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// AERONET's almucantar azimuths from the sun, degrees (one side).
    pub(crate) const ALMUCANTAR_AZIMUTHS_DEG: [f64; 26] = [
        3.5, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 25.0, 30.0, 35.0, 40.0,
        45.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 120.0, 140.0, 160.0,
    ];

    /// An almucantar at 440-1020 nm made by the forward model from
    /// `truth`'s size distribution with index `indices[i]` at each channel
    /// (3 % uncertainties, no noise), with its optical depths (0.01); and
    /// the truth's albedo per channel.
    pub(crate) fn self_made_almucantar(
        truth: &AerosolState,
        indices: &[Complex64],
    ) -> (Measurements, Vec<f64>) {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let (sun_elevation_deg, sun_azimuth_deg) = (30.0, 180.0);
        let mut measurements = Measurements {
            label: "self".into(),
            ..Measurements::default()
        };
        for wavelength_nm in [440.0, 675.0, 870.0, 1020.0] {
            for a in ALMUCANTAR_AZIMUTHS_DEG {
                measurements.sky.push(SkyRadianceMeasurement {
                    wavelength_nm,
                    sun_elevation_deg,
                    sun_azimuth_deg,
                    view_elevation_deg: sun_elevation_deg,
                    view_azimuth_deg: sun_azimuth_deg + a,
                    radiance_w_m2_sr_nm: 1.0,
                    uncertainty_w_m2_sr_nm: 0.03,
                });
            }
        }
        let forward =
            ForwardModel::new(&atmosphere, &measurements, 1200.0, 440.0, 1.0, &[]).unwrap();
        let (radiances, optics) = forward.radiances(truth, indices).unwrap();
        for (m, l) in measurements.sky.iter_mut().zip(&radiances) {
            m.radiance_w_m2_sr_nm = *l;
            m.uncertainty_w_m2_sr_nm = 0.03 * l;
        }
        for (w, o) in forward.wavelengths_nm.iter().zip(&optics) {
            measurements.optical_depths.push(OpticalDepthMeasurement {
                wavelength_nm: *w,
                aerosol_optical_depth: o.optical_depth,
                uncertainty: 0.01,
            });
        }
        let albedos = optics.iter().map(|o| o.single_scattering_albedo).collect();
        (measurements, albedos)
    }

    /// A channel's band averages the sun over it: at 870 nm (no gas
    /// absorption to speak of: ozone's optical depth there is below 2e-4)
    /// the radiances with a 10-nm band are those with a 1-nm band times
    /// the ratio of the sun's band means.
    #[test]
    fn the_band_averages_the_sun_over_the_channel() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let state = AerosolState {
            optical_depth: 0.2,
            ..RetrievalSettings::starting_states(0.2)[0]
        };
        let mut measurements = Measurements {
            label: "band".into(),
            ..Measurements::default()
        };
        for a in [5.0, 30.0, 90.0] {
            measurements.sky.push(SkyRadianceMeasurement {
                wavelength_nm: 870.0,
                sun_elevation_deg: 40.0,
                sun_azimuth_deg: 180.0,
                view_elevation_deg: 40.0,
                view_azimuth_deg: 180.0 + a,
                radiance_w_m2_sr_nm: 1.0,
                uncertainty_w_m2_sr_nm: 0.03,
            });
        }
        let radiances = |band| {
            ForwardModel::new(&atmosphere, &measurements, 1200.0, 870.0, band, &[])
                .unwrap()
                .radiances(&state, &[index_of(&state)])
                .unwrap()
                .0
        };
        let sun = |band| {
            atmosphere
                .sun
                .sample_irradiance_w_m2_nm(
                    &crate::spectrum::WavelengthGrid::new(870.0, 870.0, band).unwrap(),
                )
                .unwrap()[0]
        };
        let ratio = sun(10.0) / sun(1.0);
        // The two bands' suns differ by more than the tolerance below.
        assert!((ratio - 1.0).abs() > 3e-3, "{ratio}");
        for (wide, narrow) in radiances(10.0).iter().zip(radiances(1.0)) {
            assert!(
                (wide / narrow / ratio - 1.0).abs() < 3e-4,
                "{wide} {narrow} {ratio}"
            );
        }
    }

    /// A filter's channel is computed as the response-weighted mean of the
    /// skies at the filter's wavelengths would be: the forward model with
    /// `cimel-440` (a 10-nm Gaussian) against the weighted mean of 21 skies,
    /// one per wavelength of the filter's grid (each with the sun and gases
    /// of its 2-nm grid step, the aerosol the same), within 1e-3; the
    /// channel differs from the 1-nm box at 440 nm by more than that.
    #[test]
    fn a_filter_weights_the_sky_as_its_mean_over_the_filter() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let state = AerosolState {
            optical_depth: 0.3,
            ..RetrievalSettings::starting_states(0.3)[0]
        };
        let filter = Filter::named("cimel-440").unwrap();
        let views = |wavelength_nm: f64| {
            let mut measurements = Measurements {
                label: "filter".into(),
                ..Measurements::default()
            };
            for a in [4.0, 30.0, 120.0] {
                measurements.sky.push(SkyRadianceMeasurement {
                    wavelength_nm,
                    sun_elevation_deg: 30.0,
                    sun_azimuth_deg: 180.0,
                    view_elevation_deg: 30.0,
                    view_azimuth_deg: 180.0 + a,
                    radiance_w_m2_sr_nm: 1.0,
                    uncertainty_w_m2_sr_nm: 0.03,
                });
            }
            measurements
        };
        let m = [index_of(&state)];
        let at_440 = views(440.0);
        let model = |filters: &[Option<Filter>], band: f64| {
            ForwardModel::new(&atmosphere, &at_440, 1200.0, 440.0, band, filters)
                .unwrap()
                .radiances(&state, &m)
                .unwrap()
                .0
        };
        let filtered = model(&[Some(filter.clone())], 1.0);
        let boxed = model(&[], 1.0);
        let grid = filter.grid().unwrap();
        let (mut sum, mut weight) = (vec![0.0; 3], 0.0);
        for wavelength_nm in grid.wavelengths_nm() {
            let r = filter.response_at(wavelength_nm);
            let here = views(wavelength_nm);
            let radiances = ForwardModel::new(
                &atmosphere,
                &here,
                1200.0,
                wavelength_nm,
                grid.step_nm(),
                &[],
            )
            .unwrap()
            .radiances(&state, &m)
            .unwrap()
            .0;
            for (s, l) in sum.iter_mut().zip(radiances) {
                *s += r * l;
            }
            weight += r;
        }
        for ((f, s), b) in filtered.iter().zip(&sum).zip(&boxed) {
            let mean = s / weight;
            println!(
                "filtered {f:.6e}, mean of the skies {mean:.6e} ({:+.2e}), 1-nm box {b:.6e} ({:+.2e})",
                f / mean - 1.0,
                b / mean - 1.0
            );
            assert!((f / mean - 1.0).abs() < 1e-3);
            assert!((b / mean - 1.0).abs() > 1e-3);
        }
    }

    /// Without noise, the fit returns the state that made its own
    /// measurements, a spectrally flat index as flat (the forward model is the same: this checks the fit,
    /// not the physics; `tests/retrieval.rs` checks against the path
    /// tracer).
    #[test]
    fn retrieval_recovers_the_state_of_its_own_forward_model() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let truth = AerosolState {
            optical_depth: 0.45,
            fine: LogNormalMode {
                volume_median_radius_um: 0.17,
                width: 0.45,
            },
            coarse: LogNormalMode {
                volume_median_radius_um: 2.8,
                width: 0.62,
            },
            fine_volume_fraction: 0.45,
            refractive_index_real: 1.47,
            refractive_index_imaginary: 0.012,
        };
        let (measurements, albedos) = self_made_almucantar(&truth, &[index_of(&truth); 4]);
        let started = std::time::Instant::now();
        // The index per wavelength (the one-index fit of a flat truth is
        // the same problem with fewer parameters).
        let settings = RetrievalSettings {
            index: IndexSpectrum::PerWavelength,
            ..RetrievalSettings::default()
        };
        let retrieval = retrieve(&atmosphere, &measurements, &settings).unwrap();
        println!(
            "retrieval in {:?}, {} iterations, chi2 {:.3e}",
            started.elapsed(),
            retrieval.iterations,
            retrieval.chi_square
        );
        for (k, e) in retrieval.parameters.iter().enumerate() {
            println!(
                "{}: {:.4} +- {:.4} (truth {:.4})",
                PARAMETER_NAMES[k],
                e.value,
                e.sigma,
                truth.to_array()[k]
            );
        }
        println!("warnings {:?}", retrieval.warnings);
        assert!(retrieval.converged);
        for (k, e) in retrieval.parameters.iter().enumerate() {
            assert!(
                (e.value - truth.to_array()[k]).abs() < 0.3 * e.sigma,
                "{}",
                PARAMETER_NAMES[k]
            );
        }
        // The index is spectrally flat: the per-wavelength fit finds it
        // flat, every channel's albedo within 0.01, k
        // within 15 % and n within 0.02.
        let worst = super::index_spectrum_tests::worst_albedo_error("flat", &retrieval, &albedos);
        assert!(worst < 0.01, "{worst}");
        for s in &retrieval.spectral {
            assert!((s.refractive_index_imaginary.value / 0.012 - 1.0).abs() < 0.15);
            assert!((s.refractive_index_real.value - 1.47).abs() < 0.02);
        }
    }
}

#[cfg(test)]
mod index_spectrum_tests {
    use super::tests::self_made_almucantar;
    use super::*;

    /// The largest albedo error over the channels, printing each.
    pub(crate) fn worst_albedo_error(name: &str, retrieval: &Retrieval, truth: &[f64]) -> f64 {
        let mut worst = 0.0f64;
        for (s, t) in retrieval.spectral.iter().zip(truth) {
            let error = s.single_scattering_albedo.value - t;
            println!(
                "{name}: {} nm omega {:.4} +- {:.4} (truth {t:.4}, error {error:+.4}), n {:.4} +- {:.4}, k {:.5} +- {:.5}",
                s.wavelength_nm,
                s.single_scattering_albedo.value,
                s.single_scattering_albedo.sigma,
                s.refractive_index_real.value,
                s.refractive_index_real.sigma,
                s.refractive_index_imaginary.value,
                s.refractive_index_imaginary.sigma,
            );
            worst = worst.max(error.abs());
        }
        println!(
            "{name}: chi^2 {:.3} over {}, {} iterations, converged {}, worst albedo error {worst:.4}",
            retrieval.chi_square,
            retrieval.measurement_count,
            retrieval.iterations,
            retrieval.converged
        );
        worst
    }

    /// k rising with wavelength (k = 0.004 (lambda / 440 nm)^1.5, n 1.45):
    /// the per-wavelength index recovers every channel's single-scattering
    /// albedo within 0.01; one index for all wavelengths cannot follow the
    /// albedo's spectrum and misses it by more.
    #[test]
    fn per_wavelength_index_recovers_an_albedo_spectrum_one_index_misses() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let truth = AerosolState {
            optical_depth: 0.6,
            ..RetrievalSettings::starting_states(0.6)[0]
        };
        let indices: Vec<Complex64> = [440.0, 675.0, 870.0, 1020.0]
            .iter()
            .map(|w: &f64| Complex64::new(1.45, 0.004 * (w / 440.0).powf(1.5)))
            .collect();
        let (measurements, albedos) = self_made_almucantar(&truth, &indices);
        let per_wavelength = retrieve(
            &atmosphere,
            &measurements,
            &RetrievalSettings {
                index: IndexSpectrum::PerWavelength,
                ..RetrievalSettings::default()
            },
        )
        .unwrap();
        let one = retrieve(
            &atmosphere,
            &measurements,
            &RetrievalSettings {
                index: IndexSpectrum::One,
                ..RetrievalSettings::default()
            },
        )
        .unwrap();
        let worst_per_wavelength = worst_albedo_error("per wavelength", &per_wavelength, &albedos);
        let worst_one = worst_albedo_error("one index", &one, &albedos);
        assert!(per_wavelength.converged);
        assert!(worst_per_wavelength < 0.01, "{worst_per_wavelength}");
        assert!(worst_one > 0.01, "{worst_one}");
        for (s, m) in per_wavelength.spectral.iter().zip(&indices) {
            assert!((s.refractive_index_imaginary.value / m.im - 1.0).abs() < 0.15);
        }
    }
}

#[cfg(test)]
mod normalised_spectrum_tests {
    use super::*;

    /// The paper's Fig. 2 case: one direction, a spectrum known only up to
    /// a factor. The fit finds a state that reproduces the shape, and says
    /// which parameters the shape does not constrain (the size
    /// distribution's widths and the coarse mode, the refractive index).
    #[test]
    fn a_normalised_spectrum_constrains_little_and_says_so() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let truth = AerosolState {
            optical_depth: 0.3,
            ..AerosolState::a_priori()
        };
        let mut measurements = Measurements {
            label: "one direction".into(),
            scale: RadianceScale::Relative,
            ..Measurements::default()
        };
        for wavelength_nm in [400.0, 440.0, 500.0, 560.0, 620.0, 675.0, 740.0, 870.0] {
            measurements.sky.push(SkyRadianceMeasurement {
                wavelength_nm,
                sun_elevation_deg: 36.0,
                sun_azimuth_deg: 207.0,
                view_elevation_deg: 17.0,
                view_azimuth_deg: 347.0,
                radiance_w_m2_sr_nm: 1.0,
                uncertainty_w_m2_sr_nm: 0.02,
            });
        }
        let forward =
            ForwardModel::new(&atmosphere, &measurements, 1200.0, 440.0, 1.0, &[]).unwrap();
        let (radiances, _) = forward.radiances(&truth, &[index_of(&truth); 8]).unwrap();
        // Normalised to 1 at 560 nm, as the paper's figure is.
        for (m, l) in measurements.sky.iter_mut().zip(&radiances) {
            m.radiance_w_m2_sr_nm = l / radiances[3];
            m.uncertainty_w_m2_sr_nm = 0.02 * m.radiance_w_m2_sr_nm;
        }
        let settings = RetrievalSettings {
            starting_points: 1,
            ..RetrievalSettings::default()
        };
        let retrieval = retrieve(&atmosphere, &measurements, &settings).unwrap();
        // The shape is reproduced (noise-free data: far below 1 per point).
        assert!(retrieval.chi_square / (retrieval.measurement_count as f64) < 0.1);
        let scale = retrieval.radiance_scale.unwrap();
        assert!((scale.value * radiances[3] - 1.0).abs() < 3.0 * scale.sigma * radiances[3] + 0.02);
        // And most of the state is reported as the a priori's.
        let unconstrained = retrieval
            .warnings
            .iter()
            .filter(|w| w.contains("barely constrained"))
            .count();
        println!("{:#?}", retrieval.warnings);
        assert!(unconstrained >= 4, "{:?}", retrieval.warnings);
    }
}
