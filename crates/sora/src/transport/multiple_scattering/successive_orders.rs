//! The plane-parallel diffuse field of one column at one wavelength, by
//! discrete ordinates in the cosine of the zenith angle, a Fourier series
//! in azimuth, and successive orders of scattering (source iteration)
//! accelerated by geometric extrapolation.
//!
//! Conventions: a direction is where one *looks* (as everywhere in
//! `transport`): mu > 0 looks up and sees downwelling light; azimuth phi is
//! measured from the sun's. The radiance of harmonic m is L_m(z, mu), with
//! L(z, mu, phi) = sum_m L_m(z, mu) cos(m phi). At each level the source
//! function (radiance units) of harmonic m in stream a is
//!
//! ```text
//! S_m(z, mu_a) = (2 - delta_m0) E T*_sun(z) sum_j omega_j(z) p*_jm(mu_a, mu_s)
//!              + 2 pi sum_b w_b sum_j omega_j(z) p*_jm(mu_a, mu_b) L_m(z, mu_b)
//! ```
//!
//! with omega_j(z) = beta*_sca,j(z) / beta*_ext(z) (delta-M scaled, see
//! [`super::phase_fourier`]) and T*_sun the scaled transmittance toward
//! the sun, computed in the spherical shell (the pseudo-spherical
//! approximation: the sun's beam is attenuated along its real curved-Earth
//! path, the diffuse light between levels as in a plane-parallel slab).
//! Radiance is carried from level to level exactly for a source function
//! linear in optical depth within each layer:
//!
//! ```text
//! L(near) = e^{-x} L(far) + S_near [(1 - e^{-x}) - c] + S_far c,
//! c = (1 - e^{-x} - x e^{-x}) / x,     x = dtau / |mu|
//! ```
//!
//! Looking up, nothing diffuse comes in at the top; looking down, the
//! Lambertian ground sends (A / pi)(F_diffuse + E mu_s T*_sun(0)) into
//! harmonic 0, F_diffuse = 2 pi sum_{mu_b > 0} w_b mu_b L_0(0, mu_b).
//!
//! Each sweep (transport, then scattering) adds one order of scattering.
//! Once successive increments shrink by a steady ratio r (the dominant
//! eigenvalue of the sweep), the remaining orders sum to r / (1 - r) times
//! the last increment, and the iteration stops with that added.

use std::f64::consts::PI;

use super::phase_fourier::{
    TruncatedPhase, gauss_legendre_unit_interval, normalized_associated_legendre,
};
use super::spherical_paths::{StreamPaths, linear_source_weights};
use super::vertical_grid::VerticalGrid;
use crate::transport::vector_exp::exp_neg;

/// Relative size of the remaining orders at which the iteration stops.
const CONVERGENCE_TOLERANCE: f64 = 1e-4;
/// A safety net (an optically thick conservative atmosphere converges
/// slowly, but the extrapolation still ends it long before this).
pub(super) const MAX_ITERATIONS: usize = 200;

/// What the successive orders do after a sweep (see [`StoppingRule`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Sweep {
    Continue,
    /// The last increment is negligible.
    Converged,
    /// The remaining orders sum to this multiple of the last increment:
    /// add it and stop.
    Extrapolate(f64),
}

/// The stopping rule of the successive orders (see the module docs): the
/// increments of successive sweeps, once their ratio r is steady, sum to
/// r / (1 - r) times the last one.
#[derive(Debug, Clone)]
pub(super) struct StoppingRule {
    sweeps: usize,
    last_norm: f64,
    last_ratio: f64,
}

impl StoppingRule {
    pub(super) fn new() -> StoppingRule {
        StoppingRule {
            sweeps: 0,
            last_norm: 0.0,
            last_ratio: f64::NAN,
        }
    }

    /// After a sweep from `previous` to `field`: the increment into
    /// `increment` and the rule's decision, the extrapolated orders added
    /// to `field` if it extrapolates. True when the iteration stops.
    pub(super) fn finish_sweep(
        &mut self,
        field: &mut [f64],
        previous: &[f64],
        increment: &mut [f64],
    ) -> bool {
        let (mut norm, mut size_of_field) = (0.0, 0.0);
        for ((d, new), old) in increment.iter_mut().zip(field.iter()).zip(previous) {
            *d = new - old;
            norm += d.abs();
            size_of_field += new.abs();
        }
        match self.after_sweep(norm, size_of_field) {
            Sweep::Continue => false,
            Sweep::Converged => true,
            Sweep::Extrapolate(remaining) => {
                for (value, d) in field.iter_mut().zip(increment.iter()) {
                    *value += remaining * d;
                }
                true
            }
        }
    }

    /// After a sweep whose increment has L1 norm `norm`, the new field
    /// having L1 norm `size_of_field`.
    fn after_sweep(&mut self, norm: f64, size_of_field: f64) -> Sweep {
        let first = self.sweeps == 0;
        self.sweeps += 1;
        if size_of_field == 0.0 || norm <= 1e-3 * CONVERGENCE_TOLERANCE * size_of_field {
            return Sweep::Converged;
        }
        if !first {
            let ratio = norm / self.last_norm;
            let steady = (ratio - self.last_ratio).abs() < 0.05 * ratio;
            if ratio < 1.0 && steady {
                let remaining = ratio / (1.0 - ratio);
                if norm * remaining <= CONVERGENCE_TOLERANCE * size_of_field {
                    return Sweep::Extrapolate(remaining);
                }
            }
            self.last_ratio = ratio;
        }
        self.last_norm = norm;
        Sweep::Continue
    }
}

/// The interpolation brackets of a twilight shift ([`ColumnSystem::shift_plan`]).
pub(crate) struct ShiftPlan {
    nodes: usize,
    /// [(((s * levels + k) * nodes + node) * streams + q) * 2 + i]: the
    /// node below and the fraction of its segment.
    brackets: Vec<(u32, f64)>,
    /// The harmonics that are not zero.
    active: Vec<usize>,
    /// cos(m phi_q) of the active harmonics at the midpoint azimuths,
    /// [q * active + i], and the same by harmonics, [i * streams + q].
    cosines: Vec<f64>,
    synthesis: Vec<f64>,
}

/// The discrete ordinates: Gauss-Legendre cosines on each hemisphere
/// ("double Gauss", Sykes 1951), exact for the polynomial fields of each
/// hemisphere separately, so the upward and downward fluxes are exact.
#[derive(Debug, Clone)]
pub struct Streams {
    per_hemisphere: usize,
    /// Looking up (+x_i) then looking down (-x_i).
    cosines: Vec<f64>,
    /// Quadrature weights on each hemisphere (each half sums to 1).
    weights: Vec<f64>,
    /// Lambda_l^m of each stream, [(a * degrees + m) * degrees + l].
    legendre: Vec<f64>,
}

impl Streams {
    pub(crate) fn new(per_hemisphere: usize) -> Streams {
        let (x, w) = gauss_legendre_unit_interval(per_hemisphere);
        let cosines: Vec<f64> = x.iter().copied().chain(x.iter().map(|v| -v)).collect();
        let weights: Vec<f64> = w.iter().chain(w.iter()).copied().collect();
        let degrees = 2 * per_hemisphere;
        let mut legendre = vec![0.0; 2 * per_hemisphere * degrees * degrees];
        for (a, mu) in cosines.iter().enumerate() {
            normalized_associated_legendre(
                *mu,
                degrees,
                &mut legendre[a * degrees * degrees..(a + 1) * degrees * degrees],
            );
        }
        Streams {
            per_hemisphere,
            cosines,
            weights,
            legendre,
        }
    }

    /// Streams in total (both hemispheres): also the number of Legendre
    /// terms and harmonics the solver represents.
    pub(crate) fn count(&self) -> usize {
        2 * self.per_hemisphere
    }

    pub(crate) fn per_hemisphere(&self) -> usize {
        self.per_hemisphere
    }

    pub(crate) fn cosines(&self) -> &[f64] {
        &self.cosines
    }

    pub(crate) fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The Lambda table of stream `a` ([m * degrees + l]).
    pub(crate) fn legendre(&self, a: usize) -> &[f64] {
        let d = self.count();
        &self.legendre[a * d * d..(a + 1) * d * d]
    }
}

/// One species at one wavelength, delta-M scaled.
#[derive(Debug, Clone, Copy)]
pub struct ScaledSpecies<'a> {
    /// beta*_ext at relative density 1, m^-1.
    pub extinction_per_m: f64,
    /// beta*_sca at relative density 1, m^-1.
    pub scattering_per_m: f64,
    pub phase: &'a TruncatedPhase,
}

/// Everything about one wavelength that does not depend on the sun.
#[derive(Debug, Clone)]
pub struct ColumnSystem<'a> {
    pub(super) streams: &'a Streams,
    pub(super) grid: &'a VerticalGrid,
    species: Vec<ScaledSpecies<'a>>,
    pub(super) solar_irradiance: f64,
    pub(super) ground_albedo: f64,
    /// Harmonics with any scattering.
    active_harmonics: Vec<bool>,
    /// omega_j at each level, [k * species + j].
    pub(super) level_albedo: Vec<f64>,
    /// Per layer and stream magnitude, [k * n + a]: e^{-x}, the near
    /// level's weight and the far level's weight.
    transmission: Vec<f64>,
    near_weight: Vec<f64>,
    far_weight: Vec<f64>,
    /// The near-horizontal streams' paths through the spherical shells and
    /// their transport matrices at this wavelength (see
    /// [`super::spherical_paths`]); none in a slab.
    paths: Option<&'a StreamPaths>,
    spherical_transport: Vec<f64>,
    spherical_rows: Vec<(usize, usize)>,
    /// Per spherical stream and level, the mean angle at the planet's
    /// centre to where its light is gathered and that angle's spread, rad
    /// (`StreamPaths::compute_transport_matrices`).
    spherical_mean_angles: Vec<(f64, f64)>,
    /// Per harmonic and level the matrix 2 pi w_b sum_j omega_j p*_jm(mu_a, mu_b),
    /// stored by columns, [((m * levels + k) * streams + b) * streams + a],
    /// so that scattering is a sum of whole columns (vectorisable) rather
    /// than of dot products (one long dependency chain each).
    scattering_matrices: Vec<f64>,
    /// The most sweeps (orders of scattering) of a solve:
    /// `MAX_ITERATIONS`, fewer for the tests that look at one order.
    sweeps: usize,
}

impl<'a> ColumnSystem<'a> {
    /// This system stopping after `sweeps` sweeps: with one, a solve
    /// returns the first order only (the tests that compare orders).
    pub(crate) fn with_sweeps(mut self, sweeps: usize) -> ColumnSystem<'a> {
        self.sweeps = sweeps.clamp(1, MAX_ITERATIONS);
        self
    }

    pub(crate) fn new(
        streams: &'a Streams,
        grid: &'a VerticalGrid,
        paths: Option<&'a StreamPaths>,
        species: Vec<ScaledSpecies<'a>>,
        solar_irradiance: f64,
        ground_albedo: f64,
    ) -> ColumnSystem<'a> {
        let levels = grid.levels();
        let n = streams.per_hemisphere();
        let total = streams.count();
        let s = species.len();
        let mut level_albedo = vec![0.0; levels * s];
        for k in 0..levels {
            let densities = grid.densities_at_level(k);
            let extinction: f64 = species
                .iter()
                .zip(densities)
                .map(|(sp, rho)| sp.extinction_per_m * rho)
                .sum();
            if extinction > 0.0 {
                for j in 0..s {
                    level_albedo[k * s + j] =
                        densities[j] * species[j].scattering_per_m / extinction;
                }
            }
        }
        let layers = levels - 1;
        let mut transmission = vec![0.0; layers * n];
        let mut near_weight = vec![0.0; layers * n];
        let mut far_weight = vec![0.0; layers * n];
        let layer_optical_depth: Vec<f64> = (0..layers)
            .map(|k| {
                species
                    .iter()
                    .zip(grid.layer_columns_m(k))
                    .map(|(sp, c)| sp.extinction_per_m * c)
                    .sum()
            })
            .collect();
        for (k, dtau) in layer_optical_depth.iter().enumerate() {
            for a in 0..n {
                let (one_minus_e, c) = linear_source_weights(dtau / streams.cosines()[a]);
                transmission[k * n + a] = 1.0 - one_minus_e;
                near_weight[k * n + a] = one_minus_e - c;
                far_weight[k * n + a] = c;
            }
        }
        let (spherical_transport, spherical_rows, spherical_mean_angles) = match paths {
            Some(paths) => {
                let count = paths.spherical_streams().len();
                let mut matrices = vec![0.0; count * levels * (levels + 1)];
                let mut rows = vec![(0, 0); count * levels];
                let mut angles = vec![(0.0, 0.0); count * levels];
                paths.compute_transport_matrices(
                    &layer_optical_depth,
                    &mut matrices,
                    &mut rows,
                    &mut angles,
                );
                (matrices, rows, angles)
            }
            None => (Vec::new(), Vec::new(), Vec::new()),
        };
        let active_harmonics: Vec<bool> = (0..total)
            .map(|m| {
                species
                    .iter()
                    .any(|sp| sp.scattering_per_m > 0.0 && !sp.phase.harmonic_vanishes(m))
            })
            .collect();
        let mut scattering_matrices = vec![0.0; total * levels * total * total];
        let mut harmonic = vec![0.0; s * total * total];
        for m in (0..total).filter(|m| active_harmonics[*m]) {
            for (j, sp) in species.iter().enumerate() {
                for b in 0..total {
                    for a in 0..total {
                        harmonic[(j * total + b) * total + a] = 2.0
                            * PI
                            * streams.weights()[b]
                            * sp.phase
                                .harmonic(m, streams.legendre(a), streams.legendre(b));
                    }
                }
            }
            for k in 0..levels {
                let matrix = &mut scattering_matrices
                    [(m * levels + k) * total * total..(m * levels + k + 1) * total * total];
                for j in 0..s {
                    let omega = level_albedo[k * s + j];
                    if omega == 0.0 {
                        continue;
                    }
                    let h = &harmonic[j * total * total..(j + 1) * total * total];
                    for (out, value) in matrix.iter_mut().zip(h) {
                        *out += omega * value;
                    }
                }
            }
        }
        ColumnSystem {
            streams,
            grid,
            species,
            solar_irradiance,
            ground_albedo,
            active_harmonics,
            level_albedo,
            transmission,
            near_weight,
            far_weight,
            paths,
            spherical_transport,
            spherical_rows,
            spherical_mean_angles,
            scattering_matrices,
            sweeps: MAX_ITERATIONS,
        }
    }

    /// Solves for the sun at zenith cosine `sun_cosine` with scaled
    /// transmittances `sun_transmittance[k]` at each level (0 in the
    /// planet's shadow) into `radiance` (harmonics x levels x streams
    /// values, [(m * levels + k) * streams + b]), with `work` space.
    /// Returns the diffuse downward irradiance at the ground. (With the
    /// spherical first order, from a sun zenith angle of 84 degrees on, the
    /// columns are solved together: [`ColumnSystem::solve_shifted_orders`].)
    pub(crate) fn solve(
        &self,
        sun_cosine: f64,
        sun_transmittance: &[f64],
        radiance: &mut [f64],
        work: &mut Vec<f64>,
    ) -> f64 {
        let levels = self.grid.levels();
        let total = self.streams.count();
        let s = self.species.len();
        let size = levels * total;
        work.resize(4 * size + total * total + s * total + 2 * levels, 0.0);
        let (direct_source, rest) = work.split_at_mut(size);
        let (source, rest) = rest.split_at_mut(size);
        let (previous, rest) = rest.split_at_mut(size);
        let (increment, rest) = rest.split_at_mut(size);
        let (sun_legendre, rest) = rest.split_at_mut(total * total);
        let (sun_phase, columns) = rest.split_at_mut(s * total);
        radiance.fill(0.0);
        normalized_associated_legendre(sun_cosine, total, sun_legendre);
        let ground_direct = if sun_cosine > 0.0 {
            self.ground_albedo / PI * self.solar_irradiance * sun_cosine * sun_transmittance[0]
        } else {
            0.0
        };
        let mut ground_diffuse_irradiance = 0.0;
        for m in (0..total).filter(|m| self.active_harmonics[*m]) {
            let factor = if m == 0 { 1.0 } else { 2.0 };
            // p*_jm(mu_a, mu_s), the same at every level.
            for j in 0..s {
                for a in 0..total {
                    sun_phase[j * total + a] =
                        self.species[j]
                            .phase
                            .harmonic(m, self.streams.legendre(a), sun_legendre);
                }
            }
            // Single scattering of the sun's beam into every stream.
            for k in 0..levels {
                let beam = factor * self.solar_irradiance * sun_transmittance[k];
                let out = &mut direct_source[k * total..(k + 1) * total];
                out.fill(0.0);
                if beam <= 0.0 {
                    continue;
                }
                for j in 0..s {
                    let omega = beam * self.level_albedo[k * s + j];
                    if omega != 0.0 {
                        for (o, p) in out.iter_mut().zip(&sun_phase[j * total..(j + 1) * total]) {
                            *o += omega * p;
                        }
                    }
                }
            }
            let field = &mut radiance[m * size..(m + 1) * size];
            source.copy_from_slice(direct_source);
            let mut stopping = StoppingRule::new();
            for sweep in 1..=self.sweeps {
                previous.copy_from_slice(field);
                let ground_radiance = match m {
                    0 => self.ground_albedo / PI * self.downward_flux(previous) + ground_direct,
                    _ => 0.0,
                };
                self.transport(source, ground_radiance, field, columns);
                if stopping.finish_sweep(field, previous, increment) || sweep == self.sweeps {
                    break;
                }
                source.copy_from_slice(direct_source);
                self.add_scattering(m, field, source);
            }
            if m == 0 {
                ground_diffuse_irradiance = self.downward_flux(field);
            }
        }
        ground_diffuse_irradiance
    }

    /// Shifts the solutions `fields` (one per sun zenith angle of
    /// `sun_zenith_rad`, each harmonics x levels x streams) of the
    /// spherical streams toward where their light comes from: see
    /// [`super::spherical_paths`] on horizontal displacement.
    pub(crate) fn shift_toward_sources(&self, sun_zenith_rad: &[f64], fields: &mut [&mut [f64]]) {
        let Some(paths) = self.paths else {
            return;
        };
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let nodes = sun_zenith_rad.len();
        if nodes < 2 {
            return;
        }
        let mut derivative = vec![0.0; total];
        let mut shifted = vec![0.0; nodes * total];
        for (s, &a) in paths.spherical_streams().iter().enumerate() {
            for k in 0..levels {
                let angle = self.spherical_mean_angles[s * levels + k].0;
                if angle == 0.0 {
                    continue;
                }
                for node in 0..nodes {
                    let (lo, hi) = (node.saturating_sub(1), (node + 1).min(nodes - 1));
                    let span = sun_zenith_rad[hi] - sun_zenith_rad[lo];
                    for (m, d) in derivative.iter_mut().enumerate() {
                        let at = m * size + k * total + a;
                        *d = (fields[hi][at] - fields[lo][at]) / span;
                    }
                    // L(theta - angle cos phi) ~ L - angle cos(phi) dL/dtheta,
                    // and cos(phi) couples harmonic m to m - 1 and m + 1.
                    for m in 0..total {
                        let neighbours = match m {
                            0 => 0.5 * derivative.get(1).copied().unwrap_or(0.0),
                            1 => derivative[0] + 0.5 * derivative.get(2).copied().unwrap_or(0.0),
                            _ => {
                                0.5 * (derivative[m - 1]
                                    + derivative.get(m + 1).copied().unwrap_or(0.0))
                            }
                        };
                        shifted[node * total + m] =
                            fields[node][m * size + k * total + a] - angle * neighbours;
                    }
                }
                for node in 0..nodes {
                    for m in 0..total {
                        fields[node][m * size + k * total + a] = shifted[node * total + m];
                    }
                }
            }
        }
    }

    /// Where [`ColumnSystem::shift_order_toward_sources`] reads each
    /// shifted value on the sun axis `sun_zenith_rad`: per spherical
    /// stream, level, node, azimuth and each of the two angles, the node
    /// below and the fraction of its segment, the same at every order.
    pub(crate) fn shift_plan(&self, sun_zenith_rad: &[f64]) -> ShiftPlan {
        let nodes = sun_zenith_rad.len();
        let azimuths = self.streams.count();
        let mut brackets = Vec::new();
        if let (Some(paths), true) = (self.paths, nodes >= 2) {
            let levels = self.grid.levels();
            brackets.reserve(paths.spherical_streams().len() * levels * nodes * azimuths * 2);
            for s in 0..paths.spherical_streams().len() {
                for k in 0..levels {
                    // Two angles with the mean and spread of the path's: the
                    // source changes exponentially along the path, and its
                    // mean is brighter than its value at the mean angle.
                    let (mean, spread) = self.spherical_mean_angles[s * levels + k];
                    let angles = [mean + spread, (mean - spread).max(0.0)];
                    for &sun in sun_zenith_rad {
                        for q in 0..azimuths {
                            let phi_cosine = (PI * (q as f64 + 0.5) / azimuths as f64).cos();
                            for angle in angles {
                                let theta = sun - angle * phi_cosine;
                                let upper = sun_zenith_rad.partition_point(|t| *t <= theta);
                                let lo = upper.clamp(1, nodes - 1) - 1;
                                let t = ((theta - sun_zenith_rad[lo])
                                    / (sun_zenith_rad[lo + 1] - sun_zenith_rad[lo]))
                                    .clamp(-0.5, 1.5);
                                brackets.push((lo as u32, t));
                            }
                        }
                    }
                }
            }
        }
        let active: Vec<usize> = (0..azimuths)
            .filter(|m| self.active_harmonics[*m])
            .collect();
        let h = active.len();
        let cosines: Vec<f64> = (0..azimuths)
            .flat_map(|q| {
                let phi = PI * (q as f64 + 0.5) / azimuths as f64;
                active.iter().map(move |&m| (m as f64 * phi).cos())
            })
            .collect();
        let synthesis: Vec<f64> = (0..h)
            .flat_map(|i| (0..azimuths).map(move |q| (i, q)))
            .map(|(i, q)| cosines[q * h + i])
            .collect();
        ShiftPlan {
            nodes,
            brackets,
            active,
            cosines,
            synthesis,
        }
    }

    /// After sunset: shifts one order of scattering of each spherical
    /// stream (`orders`, one per sun node of `sun_zenith_rad`) to the sun
    /// zenith angle where its light was gathered, in each direction
    /// separately, by interpolation across the sun nodes linear in the
    /// logarithm:
    ///
    /// ```text
    /// H'(theta_s, phi) = H(theta_s - gamma cos phi, phi),
    /// ```
    ///
    /// averaged over two angles gamma = gamma_mean +- gamma_spread, the
    /// mean and spread at the planet's centre of where the path gathers
    /// its light (as [`ColumnSystem::shift_toward_sources`], which takes
    /// the first order of the Taylor series at the mean: in twilight H
    /// changes by orders of magnitude over a few degrees, a linear shift
    /// runs negative, and the mean of an exponential is brighter than its
    /// value at the mean angle).
    /// H is synthesised at `streams` midpoint azimuths on 0..180
    /// degrees from its harmonics and transformed back (exact for an
    /// unshifted field). An angle beyond the axis reads its end node's
    /// segment, extrapolated by at most half a segment; where H is not
    /// positive at both nodes, H is kept.
    pub(crate) fn shift_order_toward_sources(&self, plan: &ShiftPlan, orders: &mut [&mut [f64]]) {
        let Some(paths) = self.paths else {
            return;
        };
        let nodes = plan.nodes;
        if nodes < 2 {
            return;
        }
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let azimuths = total;
        let (active, cosines, synthesis) = (&plan.active, &plan.cosines, &plan.synthesis);
        let h = active.len();
        let mut harmonics = vec![0.0; nodes * h];
        let mut higher = vec![0.0; nodes * azimuths];
        let mut logs = vec![0.0; nodes * azimuths];
        let (mut exponents, mut powers) = (vec![0.0; 2 * azimuths], vec![0.0; 2 * azimuths]);
        let mut shifted = vec![0.0; azimuths];
        let mut transformed = vec![0.0; h];
        // Level by level: a level's streams share the nodes' cache lines.
        for k in 0..levels {
            for (s, &a) in paths.spherical_streams().iter().enumerate() {
                if self.spherical_mean_angles[s * levels + k].0 == 0.0 {
                    continue;
                }
                let brackets = &plan.brackets[(s * levels + k) * nodes * azimuths * 2..]
                    [..nodes * azimuths * 2];
                for (node, order) in orders.iter().enumerate() {
                    for (i, &m) in active.iter().enumerate() {
                        harmonics[node * h + i] = order[m * size + k * total + a];
                    }
                }
                // The azimuths' values, harmonic by harmonic (the loops
                // over azimuths vectorise).
                for (row, values) in higher
                    .chunks_exact_mut(azimuths)
                    .zip(harmonics.chunks_exact(h))
                {
                    row.fill(0.0);
                    for (v, c) in values.iter().zip(synthesis.chunks_exact(azimuths)) {
                        for (r, c) in row.iter_mut().zip(c) {
                            *r += v * c;
                        }
                    }
                }
                for (l, v) in logs.iter_mut().zip(&higher) {
                    *l = if *v > 0.0 { v.ln() } else { f64::NEG_INFINITY };
                }
                for (node, order) in orders.iter_mut().enumerate() {
                    let brackets = &brackets[node * azimuths * 2..(node + 1) * azimuths * 2];
                    for (j, (&(lo, t), y)) in brackets.iter().zip(&mut exponents).enumerate() {
                        let (lo, q) = (lo as usize, j / 2);
                        // Not finite where either node's value is not
                        // positive.
                        *y =
                            (1.0 - t) * logs[lo * azimuths + q] + t * logs[(lo + 1) * azimuths + q];
                    }
                    // e^y by the vectorisable e^-|y|, then inverted where y
                    // is positive (only in a rare extrapolation: a
                    // predictable branch, no division in the vector loop).
                    for (e, y) in powers.iter_mut().zip(&exponents) {
                        *e = exp_neg(y.abs());
                    }
                    for (e, y) in powers.iter_mut().zip(&exponents) {
                        if *y > 0.0 {
                            *e = 1.0 / *e;
                        }
                    }
                    for (q, out) in shifted.iter_mut().enumerate() {
                        let kept = higher[node * azimuths + q];
                        *out = (2 * q..2 * q + 2)
                            .map(|j| {
                                if exponents[j].is_finite() {
                                    powers[j]
                                } else {
                                    kept
                                }
                            })
                            .sum::<f64>()
                            * 0.5;
                    }
                    transformed.fill(0.0);
                    for (v, c) in shifted.iter().zip(cosines.chunks_exact(h)) {
                        for (t, c) in transformed.iter_mut().zip(c) {
                            *t += v * c;
                        }
                    }
                    for (&m, t) in active.iter().zip(&transformed) {
                        let factor = if m == 0 { 1.0 } else { 2.0 } / azimuths as f64;
                        order[m * size + k * total + a] = factor * t;
                    }
                }
            }
        }
    }

    /// After sunset: solves the columns of every sun node of
    /// `sun_zenith_rad` together, order by order, shifting each order of
    /// the spherical streams toward the columns where its light was
    /// gathered ([`ColumnSystem::shift_order_toward_sources`])
    /// before it is scattered into the next. `first_orders` are the
    /// spherical first orders (the layout of [`ColumnSystem::solve`]'s
    /// `radiance`), `ground_direct` the radiance of the directly sunlit
    /// ground (W m^-2 sr^-1 nm^-1) under each node's sun; the solutions go
    /// to `fields`, and each node's diffuse downward irradiance at the
    /// ground is returned.
    ///
    /// Why order by order: the field of a column is horizontally uniform,
    /// the twilight sky is not. Light that has travelled a stream's path
    /// was scattered where the sun stood higher (toward it) or lower, and
    /// the mean of that exponential is brighter than the column's own
    /// value. Shifting only the finished field corrects the last leg of
    /// every path and leaves each earlier leg in its own column, so the
    /// n-th order misses the shift n - 2 times: measured on mars-dust with
    /// Henyey-Greenstein dust, sun -6 degrees, 5 degrees up 90 degrees
    /// from the sun, the orders up to 2, 3 and 4 and all of them were
    /// -1.0, -3.7, -7.3 and -13.5 % from the path tracer (+-1.6-1.8 %) when
    /// only the field was shifted, -4.7 % in all with every order shifted
    /// (`docs/twilight_survey.md`).
    pub(crate) fn solve_shifted_orders(
        &self,
        sun_zenith_rad: &[f64],
        ground_direct: &[f64],
        first_orders: &[&[f64]],
        fields: &mut [&mut [f64]],
    ) -> Vec<f64> {
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let nodes = sun_zenith_rad.len();
        let mut current: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        let mut next: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        let (mut source, mut columns) = (vec![0.0; size], vec![0.0; 2 * levels]);
        // The first order: the spherical one, and the sunlit ground seen
        // through the column.
        for node in 0..nodes {
            fields[node].copy_from_slice(first_orders[node]);
            if ground_direct[node] > 0.0 {
                source.fill(0.0);
                self.transport(
                    &source,
                    ground_direct[node],
                    &mut next[node][..size],
                    &mut columns,
                );
                for (f, g) in fields[node][..size].iter_mut().zip(&next[node][..size]) {
                    *f += g;
                }
            }
            current[node].copy_from_slice(fields[node]);
        }
        let plan = self.shift_plan(sun_zenith_rad);
        // Each node stops by the rule of `solve` on its whole field; a
        // harmonic is no longer carried once its order is negligible there
        // (the high harmonics within a few orders: the light of the higher
        // orders turns isotropic). Every node stays on the axis while one
        // goes on: the shift reads its neighbours' orders.
        let mut rules: Vec<StoppingRule> = (0..nodes).map(|_| StoppingRule::new()).collect();
        let mut done = vec![false; nodes];
        let mut carried: Vec<bool> = (0..nodes * total)
            .map(|i| self.active_harmonics[i % total])
            .collect();
        let (mut previous, mut increment) = (vec![0.0; total * size], vec![0.0; total * size]);
        for _order in 2..=self.sweeps {
            // Harmonic by harmonic, so that its scattering matrices stay in
            // the cache across the nodes.
            for m in 0..total {
                for (node, (l, out)) in current.iter().zip(next.iter_mut()).enumerate() {
                    let out = &mut out[m * size..(m + 1) * size];
                    if !carried[node * total + m] {
                        out.fill(0.0);
                        continue;
                    }
                    source.fill(0.0);
                    self.add_scattering(m, &l[m * size..(m + 1) * size], &mut source);
                    let ground = match m {
                        0 => self.ground_albedo / PI * self.downward_flux(&l[..size]),
                        _ => 0.0,
                    };
                    self.transport(&source, ground, out, &mut columns);
                }
            }
            {
                let mut orders: Vec<&mut [f64]> = next.iter_mut().map(|v| &mut v[..]).collect();
                self.shift_order_toward_sources(&plan, &mut orders);
            }
            for node in 0..nodes {
                if done[node] {
                    continue;
                }
                previous.copy_from_slice(fields[node]);
                for (f, o) in fields[node].iter_mut().zip(&next[node]) {
                    *f += o;
                }
                let whole: f64 = fields[node].iter().map(|v| v.abs()).sum();
                for m in 1..total {
                    let order = &next[node][m * size..(m + 1) * size];
                    let part: f64 = order.iter().map(|v| v.abs()).sum();
                    if part <= 1e-2 * CONVERGENCE_TOLERANCE * whole {
                        carried[node * total + m] = false;
                    }
                }
                done[node] = rules[node].finish_sweep(fields[node], &previous, &mut increment);
            }
            std::mem::swap(&mut current, &mut next);
            if done.iter().all(|d| *d) {
                break;
            }
        }
        fields.iter().map(|f| self.downward_flux(f)).collect()
    }

    /// Adds to `source` the scattering of the harmonic `m` of a field
    /// (levels x streams), column by column: the next order's source.
    fn add_scattering(&self, m: usize, field: &[f64], source: &mut [f64]) {
        let total = self.streams.count();
        let levels = self.grid.levels();
        let matrices =
            &self.scattering_matrices[m * levels * total * total..][..levels * total * total];
        for ((out, l), matrix) in source
            .chunks_exact_mut(total)
            .zip(field.chunks_exact(total))
            .zip(matrices.chunks_exact(total * total))
        {
            for (value, column) in l.iter().zip(matrix.chunks_exact(total)) {
                for (o, p) in out.iter_mut().zip(column) {
                    *o += value * p;
                }
            }
        }
    }

    /// 2 pi sum_{mu_b > 0} w_b mu_b L_0(ground, mu_b).
    pub(super) fn downward_flux(&self, field: &[f64]) -> f64 {
        let n = self.streams.per_hemisphere();
        2.0 * PI
            * (0..n)
                .map(|a| self.streams.weights()[a] * self.streams.cosines()[a] * field[a])
                .sum::<f64>()
    }

    /// Carries the source function `source` (levels x streams) into the
    /// radiance `field`: up-looking streams from the top down, down-looking
    /// streams from the ground (radiance `ground_radiance`) up; the
    /// spherical streams along their paths (`columns`: work space of 2
    /// levels).
    pub(super) fn transport(
        &self,
        source: &[f64],
        ground_radiance: f64,
        field: &mut [f64],
        columns: &mut [f64],
    ) {
        let n = self.streams.per_hemisphere();
        let total = self.streams.count();
        let levels = self.grid.levels();
        let top = levels - 1;
        field[top * total..top * total + n].fill(0.0);
        for k in (0..top).rev() {
            let (below, above) = field.split_at_mut((k + 1) * total);
            let here = &mut below[k * total..k * total + n];
            let above = &above[..n];
            let near = &source[k * total..k * total + n];
            let far = &source[(k + 1) * total..(k + 1) * total + n];
            let coefficients = k * n..(k + 1) * n;
            let t = &self.transmission[coefficients.clone()];
            let wn = &self.near_weight[coefficients.clone()];
            let wf = &self.far_weight[coefficients];
            for a in 0..n {
                here[a] = t[a] * above[a] + wn[a] * near[a] + wf[a] * far[a];
            }
        }
        field[n..total].fill(ground_radiance);
        for k in 0..top {
            let (below, above) = field.split_at_mut((k + 1) * total);
            let here = &below[k * total + n..(k + 1) * total];
            let next = &mut above[n..total];
            let near = &source[(k + 1) * total + n..(k + 2) * total];
            let far = &source[k * total + n..(k + 1) * total];
            let coefficients = k * n..(k + 1) * n;
            let t = &self.transmission[coefficients.clone()];
            let wn = &self.near_weight[coefficients.clone()];
            let wf = &self.far_weight[coefficients];
            for a in 0..n {
                next[a] = t[a] * here[a] + wn[a] * near[a] + wf[a] * far[a];
            }
        }
        if let Some(paths) = self.paths {
            // The near-horizontal streams along their spherical paths
            // (overwriting the slab's values), column by column.
            let block = levels * (levels + 1);
            let (column, result) = columns[..2 * levels].split_at_mut(levels);
            for (s, &a) in paths.spherical_streams().iter().enumerate() {
                let (matrix, ground) =
                    self.spherical_transport[s * block..(s + 1) * block].split_at(levels * levels);
                for (k, value) in column.iter_mut().enumerate() {
                    *value = source[k * total + a];
                }
                result.fill(0.0);
                let rows = &self.spherical_rows[s * levels..(s + 1) * levels];
                for ((value, weights), &(first, last)) in
                    column.iter().zip(matrix.chunks_exact(levels)).zip(rows)
                {
                    for (r, w) in result[first..last].iter_mut().zip(&weights[first..last]) {
                        *r += value * w;
                    }
                }
                for (k, r) in result.iter().enumerate() {
                    field[k * total + a] = r + ground[k] * ground_radiance;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;
    use crate::transport::multiple_scattering::regimes::FIRST_ORDER_SUN_ZENITH_DEG;

    /// A conservative (non-absorbing) column: HG aerosol and Rayleigh air.
    /// Returns the upward flux at the top, the diffuse and direct downward
    /// fluxes at the ground, and the incident flux E mu_s.
    fn fluxes(ground_albedo: f64, sun_cosine: f64) -> (f64, f64, f64, f64) {
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let aerosol = DensityProfile::Exponential {
            scale_height_m: 1200.0,
        };
        let (beta_air, beta_aerosol) = (4e-5, 1.5e-4);
        let grid = VerticalGrid::compute(&[&air, &aerosol], &[beta_air, beta_aerosol], 100e3, 40);
        let streams = Streams::new(8);
        let total = streams.count();
        let rayleigh_moments: Vec<f64> = (0..=total)
            .map(|l| match l {
                0 => 1.0,
                2 => 0.1,
                _ => 0.0,
            })
            .collect();
        let hg_moments: Vec<f64> = (0..=total).map(|l| 0.7f64.powi(l as i32)).collect();
        let rayleigh = TruncatedPhase::from_moments(&rayleigh_moments, total);
        let hg = TruncatedPhase::from_moments(&hg_moments, total);
        let f = hg.forward_fraction;
        let species = vec![
            ScaledSpecies {
                extinction_per_m: beta_air,
                scattering_per_m: beta_air,
                phase: &rayleigh,
            },
            ScaledSpecies {
                extinction_per_m: beta_aerosol * (1.0 - f),
                scattering_per_m: beta_aerosol * (1.0 - f),
                phase: &hg,
            },
        ];
        let solar = 1.7;
        let system =
            ColumnSystem::new(&streams, &grid, None, species.clone(), solar, ground_albedo);
        let levels = grid.levels();
        // Plane-parallel beam: optical depth above each level over mu_s.
        let mut transmittance = vec![1.0; levels];
        for k in (0..levels - 1).rev() {
            let dtau: f64 = species
                .iter()
                .zip(grid.layer_columns_m(k))
                .map(|(s, c)| s.extinction_per_m * c)
                .sum();
            transmittance[k] = transmittance[k + 1] * (-dtau / sun_cosine).exp();
        }
        let mut radiance = vec![0.0; total * levels * total];
        let mut work = Vec::new();
        let diffuse_down = system.solve(sun_cosine, &transmittance, &mut radiance, &mut work);
        let top = levels - 1;
        let n = streams.per_hemisphere();
        let up: f64 = 2.0
            * PI
            * (n..total)
                .map(|a| streams.weights()[a] * -streams.cosines()[a] * radiance[top * total + a])
                .sum::<f64>();
        let direct = solar * sun_cosine * transmittance[0];
        (up, diffuse_down, direct, solar * sun_cosine)
    }

    /// I_m(x), the modified Bessel function of the first kind, by its
    /// series.
    fn bessel_i(m: usize, x: f64) -> f64 {
        let mut term = (0.5 * x).powi(m as i32) / (1..=m).map(|i| i as f64).product::<f64>();
        let mut sum = 0.0;
        for k in 0..60 {
            sum += term;
            term *= 0.25 * x * x / ((k + 1) as f64 * (k + 1 + m) as f64);
        }
        sum
    }

    /// The twilight shift of the orders >= 2 against its definition,
    /// evaluated directly: for orders >= 2 of ln H linear in the sun
    /// zenith angle and uniform in azimuth, H = A_k,a e^(-kappa theta) (the
    /// interpolation is then exact), the shifted field's active harmonics
    /// are those of (1/2) sum over gamma = mean +- spread of
    /// A e^(-kappa (theta - gamma cos phi)) (Bessel functions I_m), the
    /// first order is kept as it was, and the streams that are not
    /// spherical and the harmonics the phase functions lack are untouched.
    #[test]
    fn twilight_shift_matches_its_definition() {
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let grid = VerticalGrid::compute(&[&air], &[1.2e-5], 100e3, 20);
        let streams = Streams::new(8);
        let total = streams.count();
        let moments: Vec<f64> = (0..=total).map(|l| 0.6f64.powi(l as i32)).collect();
        let phase = TruncatedPhase::from_moments(&moments, total);
        let species = vec![ScaledSpecies {
            extinction_per_m: 1.2e-5,
            scattering_per_m: 1.2e-5,
            phase: &phase,
        }];
        let radii: Vec<f64> = grid.altitudes_m().iter().map(|z| 6.36e6 + z).collect();
        let paths = StreamPaths::compute(&radii, streams.cosines());
        let system = ColumnSystem::new(&streams, &grid, Some(&paths), species, 1.7, 0.0);
        let levels = grid.levels();
        let size = levels * total;
        let nodes = 24;
        let suns: Vec<f64> = (0..nodes)
            .map(|n| (FIRST_ORDER_SUN_ZENITH_DEG + 0.75 * n as f64).to_radians())
            .collect();
        let kappa = 50.0; // e-fold per 1.1 degree, a twilight sky's rate
        let amplitude = |k: usize, a: usize| 1.0 + 0.1 * k as f64 + 0.01 * a as f64;
        // Harmonic 0 only: the order is uniform in azimuth.
        let mut fields: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        for n in 0..nodes {
            for k in 0..levels {
                for a in 0..total {
                    fields[n][k * total + a] = amplitude(k, a) * (-kappa * suns[n]).exp();
                }
            }
        }
        let before = fields.clone();
        {
            let mut views: Vec<&mut [f64]> = fields.iter_mut().map(|f| f.as_mut_slice()).collect();
            system.shift_order_toward_sources(&system.shift_plan(&suns), &mut views);
        }
        let spherical = paths.spherical_streams();
        let (mut worst, mut checked) = (0.0f64, 0);
        // Nodes whose shifted angles stay on the axis.
        for n in 6..nodes - 6 {
            for k in 0..levels {
                for a in 0..total {
                    let at = |m: usize| m * size + k * total + a;
                    let Some(s) = spherical.iter().position(|b| *b == a) else {
                        for m in 0..total {
                            assert_eq!(fields[n][at(m)], before[n][at(m)]);
                        }
                        continue;
                    };
                    let (mean, spread) = system.spherical_mean_angles[s * levels + k];
                    if mean + spread > 4f64.to_radians() {
                        continue; // beyond the axis's 6 nodes either side
                    }
                    checked += 1;
                    // The harmonics of e^(x cos phi) are I_0(x) and 2 I_m(x).
                    let unshifted = amplitude(k, a) * (-kappa * suns[n]).exp();
                    for m in 0..total {
                        let got = fields[n][at(m)];
                        if !system.active_harmonics[m] {
                            assert_eq!(got, before[n][at(m)]);
                            continue;
                        }
                        let expected: f64 = [mean + spread, (mean - spread).max(0.0)]
                            .iter()
                            .map(|gamma| {
                                let c = if m == 0 { 0.5 } else { 1.0 };
                                c * unshifted * bessel_i(m, kappa * gamma)
                            })
                            .sum();
                        let error = (got - expected).abs() / unshifted;
                        worst = worst.max(error);
                    }
                }
            }
        }
        eprintln!("{checked} (node, level, stream) checked, worst {worst:e}");
        assert!(checked > 100, "{checked}");
        // Measured 6e-14.
        assert!(worst < 1e-9, "{worst}");
    }

    #[test]
    fn a_white_ground_under_a_conservative_sky_returns_all_light() {
        for sun_cosine in [1.0, 0.5, 0.15] {
            let (up, _, _, incident) = fluxes(1.0, sun_cosine);
            assert!(
                (up / incident - 1.0).abs() < 2e-3,
                "mu_s {sun_cosine}: {up} of {incident}"
            );
        }
    }

    #[test]
    fn a_black_ground_absorbs_what_the_sky_does_not_reflect() {
        let mut last_reflectance = 0.0;
        for sun_cosine in [1.0, 0.5, 0.15] {
            let (up, diffuse, direct, incident) = fluxes(0.0, sun_cosine);
            let total = up + diffuse + direct;
            assert!(
                (total / incident - 1.0).abs() < 2e-3,
                "mu_s {sun_cosine}: {up} + {diffuse} + {direct} of {incident}"
            );
            // A lower sun's light meets more air on the way in: the sky
            // reflects a larger share of it.
            assert!(up / incident > last_reflectance);
            last_reflectance = up / incident;
        }
    }
}
