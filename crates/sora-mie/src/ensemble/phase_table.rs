//! # The ensemble phase-function table
//!
//! The phase function `P(mu)` (sr^-1, normalised to 1 over 4 pi sr) of one
//! population at one or several vacuum wavelengths (nm), tabulated at the
//! 406 scattering angles of [`ensemble_phase_table_angles_deg`] (degrees):
//! [`TabulatedPhaseFunction`], linear in `mu = cos theta` between nodes, with
//! the exact cumulative distribution for sampling, and the integration that
//! fills it, `P = sum w S11 / (pi sum w x^2 Q_sca)` over the nodes of
//! [`RadiusQuadratureSettings::phase_function`] (S11 from
//! `angular_sums.rs`). The module docs ("The phase-function table") give
//! the angle grid's reasons and the measured accuracy.

use super::angular_sums::{AngularTermConstants, accumulate_s11, add_weighted_group};
use super::{EnsembleError, validate_wavelength};
use crate::Complex64;
use crate::distribution::{
    RadiusQuadratureSettings, SharedSizeParameterQuadrature, SizeDistribution,
    SizeDistributionError,
};
use crate::sphere::{
    GroupCoefficients, SPHERE_LANES, SphereWorkspace, compute_efficiencies,
    compute_group_coefficients,
};
use std::f64::consts::PI;

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
    /// Where [`Self::interval_index`] starts its search: for each of
    /// [`LOCATE_BINS`] + 1 cosines -1 + 2 b / [`LOCATE_BINS`], the number of
    /// nodes at or below it.
    bin_starts: Vec<usize>,
}

/// Bins of equal width in mu that [`TabulatedPhaseFunction::interval_index`]
/// narrows its search to (a renderer locates every pixel's angle several
/// times; the whole table's binary search was 6 % of a polarised image).
const LOCATE_BINS: usize = 512;

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
        let bin_starts = (0..=LOCATE_BINS)
            .map(|b| {
                let edge = -1.0 + 2.0 * b as f64 / LOCATE_BINS as f64;
                cos_theta.partition_point(|&mu| mu <= edge)
            })
            .collect();
        Ok(Self {
            cos_theta,
            phase_per_sr,
            cumulative,
            normalisation_before_rescaling,
            bin_starts,
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
    pub(super) fn interval_index(&self, cos_theta: f64) -> usize {
        let nodes = &self.cos_theta;
        // The nodes at or below cos_theta, searched for among those of its
        // bin only; the whole table if rounding put it in a neighbouring
        // bin (the same count either way).
        let bin = ((cos_theta + 1.0) * (0.5 * LOCATE_BINS as f64)).clamp(0.0, LOCATE_BINS as f64);
        let bin = (bin as usize).min(LOCATE_BINS - 1);
        let (start, end) = (self.bin_starts[bin], self.bin_starts[bin + 1]);
        let inside = (start == 0 || nodes[start - 1] <= cos_theta)
            && (end == nodes.len() || nodes[end] > cos_theta);
        let upper = if inside {
            start + nodes[start..end].partition_point(|&mu| mu <= cos_theta)
        } else {
            nodes.partition_point(|&mu| mu <= cos_theta)
        };
        upper.clamp(1, nodes.len() - 1) - 1
    }

    /// Phase function at `cos_theta` (sr^-1), linear in cos theta between
    /// nodes; `cos_theta` is clamped to [-1, 1].
    pub fn phase_function_per_sr(&self, cos_theta: f64) -> f64 {
        self.phase_function_at(self.locate(cos_theta))
    }

    /// Where `cos_theta` (clamped to [-1, 1]) lies among the nodes: the
    /// index i of the interval [mu_i, mu_{i+1}] holding it and the fraction
    /// t = (mu - mu_i) / (mu_{i+1} - mu_i) across it. Tables on the same
    /// nodes (one per wavelength) share it: a caller searches once and
    /// evaluates each with [`Self::phase_function_at`].
    pub fn locate(&self, cos_theta: f64) -> (usize, f64) {
        let mu = cos_theta.clamp(-1.0, 1.0);
        let i = self.interval_index(mu);
        let t = (mu - self.cos_theta[i]) / (self.cos_theta[i + 1] - self.cos_theta[i]);
        (i, t)
    }

    /// Phase function (sr^-1) at a location from [`Self::locate`] on a table
    /// with the same nodes: P_i + t (P_{i+1} - P_i).
    pub fn phase_function_at(&self, (i, t): (usize, f64)) -> f64 {
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

/// Scratch tables of the phase-table integration, allocated once per
/// spectrum rather than per wavelength or node.
pub(super) struct PhaseTableWorkspace {
    /// cos theta of the table angles, increasing (theta decreasing).
    pub(super) cos_theta: Vec<f64>,
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
    pub(super) fn new() -> Self {
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
    pub(super) fn compute(
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
    pub(super) fn compute_for_indices(
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
        // The ripple density of the least absorbing index serves them all.
        let settings = match refractive_indices
            .iter()
            .min_by(|a, b| (a.im / a.re).total_cmp(&(b.im / b.re)))
        {
            Some(&m) => settings.for_refractive_index(m),
            None => *settings,
        };
        let quadrature = SharedSizeParameterQuadrature::gauss_legendre(
            distribution,
            &wavenumbers_per_m,
            &settings,
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
                let phase_per_sr: Vec<f64> = if scale.is_finite() && scale > 0.0 {
                    table_sums.iter().map(|s| s * scale).collect()
                } else {
                    // No scattering at this wavelength (sum w x^2 Q_sca = 0,
                    // e.g. m = 1): the population is non-scattering (albedo
                    // 0, see `cross_sections::ratio_or_zero`) and its phase
                    // function, never used, is isotropic rather than 0/0.
                    vec![1.0 / (4.0 * PI); angle_count]
                };
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
