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
//!
//! The one refinement for the sphere inside a column: the near-horizontal
//! streams are carried along their paths through the spherical shells
//! (`spherical_paths.rs`) instead of the slab's recursion. What the
//! columns of neighbouring sun nodes do to one another (the twilight
//! shift) is `twilight_shift.rs`.

use std::f64::consts::PI;

use super::phase_fourier::{
    TruncatedPhase, gauss_legendre_unit_interval, normalized_associated_legendre,
};
use super::spherical_paths::{StreamPaths, linear_source_weights, nonzero_rows};
use super::vertical_grid::VerticalGrid;

/// Relative size of the remaining orders at which the iteration stops.
pub(super) const CONVERGENCE_TOLERANCE: f64 = 1e-4;
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

    /// The downward flux (W m^-2 nm^-1 for a radiance in W m^-2 sr^-1
    /// nm^-1) of the azimuth-mean radiance `field` at one level, its
    /// upward-looking streams first: 2 pi sum_{mu_b > 0} w_b mu_b L_0(mu_b).
    pub(crate) fn downward_flux(&self, field: &[f64]) -> f64 {
        let n = self.per_hemisphere;
        2.0 * PI
            * (0..n)
                .map(|a| self.weights[a] * self.cosines[a] * field[a])
                .sum::<f64>()
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
    pub(super) active_harmonics: Vec<bool>,
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
    pub(super) paths: Option<&'a StreamPaths>,
    spherical_transport: Vec<f64>,
    spherical_rows: Vec<(usize, usize)>,
    /// Per spherical stream and level, the mean angle at the planet's
    /// centre to where its light is gathered and that angle's spread, rad
    /// (`StreamPaths::compute_transport_matrices`).
    pub(super) spherical_mean_angles: Vec<(f64, f64)>,
    /// With the every-order shift in pieces
    /// ([`ColumnSystem::with_shift_pieces`]).
    pub(super) shift_pieces: Option<ShiftPieces>,
    /// Per harmonic and level the matrix 2 pi w_b sum_j omega_j p*_jm(mu_a, mu_b),
    /// stored by columns, [((m * levels + k) * streams + b) * streams + a],
    /// so that scattering is a sum of whole columns (vectorisable) rather
    /// than of dot products (one long dependency chain each).
    scattering_matrices: Vec<f64>,
    /// The most sweeps (orders of scattering) of a solve:
    /// `MAX_ITERATIONS`, fewer for the tests that look at one order.
    pub(super) sweeps: usize,
}

impl<'a> ColumnSystem<'a> {
    /// This system stopping after `sweeps` sweeps: with one, a solve
    /// returns the first order only (the tests that compare orders).
    pub(crate) fn with_sweeps(mut self, sweeps: usize) -> ColumnSystem<'a> {
        self.sweeps = sweeps.clamp(1, MAX_ITERATIONS);
        self
    }

    /// This system shifting each spherical stream's orders after sunset
    /// in pieces of its path, each read at its own mean angle +- spread,
    /// instead of the whole path at the path's (`twilight_shift.rs`): at
    /// most `pieces`, one per `spread_step_deg` of the path's angle's
    /// spread (0: every path in `pieces`; `StreamPaths::compute_piece_matrices`).
    /// Without it (or with one piece) each path is shifted whole.
    pub(crate) fn with_shift_pieces(
        mut self,
        (pieces, spread_step_deg): (usize, f64),
    ) -> ColumnSystem<'a> {
        self.shift_pieces = match (self.paths, pieces) {
            (Some(paths), 2..) => {
                let depths = layer_optical_depths(self.grid, &self.species);
                let (matrices, mean_angles) =
                    paths.compute_piece_matrices(&depths, pieces, spread_step_deg.to_radians());
                let levels = self.grid.levels();
                let block = levels * (levels + 1);
                let mut rows = vec![(0, 0); matrices.len() / block * levels];
                for (matrix, rows) in matrices
                    .chunks_exact(block)
                    .zip(rows.chunks_exact_mut(levels))
                {
                    nonzero_rows(&matrix[..levels * levels], levels, rows);
                }
                Some(ShiftPieces {
                    count: pieces,
                    matrices,
                    rows,
                    mean_angles,
                })
            }
            _ => None,
        };
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
        let layer_optical_depth = layer_optical_depths(grid, &species);
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
            // A species that does not scatter has omega = 0 at every level
            // (its harmonic is never added).
            for (j, sp) in species.iter().enumerate() {
                if sp.scattering_per_m == 0.0 {
                    continue;
                }
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
            shift_pieces: None,
            scattering_matrices,
            sweeps: MAX_ITERATIONS,
        }
    }

    /// Solves for the sun at zenith cosine `sun_cosine` with scaled
    /// transmittances `sun_transmittance[k]` at each level (0 in the
    /// planet's shadow) into `radiance` (harmonics x levels x streams
    /// values, [(m * levels + k) * streams + b]), with `work` space.
    /// Returns the diffuse downward irradiance at the ground. (With the
    /// spherical first order, from `FIRST_ORDER_SUN_ZENITH_DEG` on, the
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
            // p*_jm(mu_a, mu_s), the same at every level; none for a
            // species that does not scatter (its omega is 0 at every level
            // below, so its row is never read).
            for j in 0..s {
                if self.species[j].scattering_per_m == 0.0 {
                    continue;
                }
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

    /// Adds to `source` the scattering of the harmonic `m` of a field
    /// (levels x streams), column by column: the next order's source.
    pub(super) fn add_scattering(&self, m: usize, field: &[f64], source: &mut [f64]) {
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
        self.streams.downward_flux(field)
    }

    /// The spherical streams of `field` carried from `source` along piece
    /// `piece` of their paths only ([`ColumnSystem::with_shift_pieces`]);
    /// the other streams are left as they are (`columns`: work space of 2
    /// levels).
    pub(super) fn transport_piece(
        &self,
        piece: usize,
        source: &[f64],
        ground_radiance: f64,
        field: &mut [f64],
        columns: &mut [f64],
    ) {
        let (Some(paths), Some(pieces)) = (self.paths, &self.shift_pieces) else {
            return;
        };
        let levels = self.grid.levels();
        let count = paths.spherical_streams().len();
        let block = levels * (levels + 1);
        let at = piece * count;
        spherical_transport(
            self,
            &pieces.matrices[at * block..(at + count) * block],
            &pieces.rows[at * levels..(at + count) * levels],
            (source, ground_radiance),
            field,
            columns,
        );
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
        self.transport_slab_paths(source, ground_radiance, field);
        // The near-horizontal streams along their spherical paths
        // (overwriting the slab's values).
        spherical_transport(
            self,
            &self.spherical_transport,
            &self.spherical_rows,
            (source, ground_radiance),
            field,
            columns,
        );
    }

    /// [`ColumnSystem::transport`] of every stream along its slab path
    /// (the spherical streams' values to be overwritten).
    pub(super) fn transport_slab_paths(
        &self,
        source: &[f64],
        ground_radiance: f64,
        field: &mut [f64],
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
    }
}

/// The spherical streams of `field` carried from `source` (and the ground's
/// radiance) by the transport matrices `matrices` (per spherical stream,
/// the layout of `StreamPaths::compute_transport_matrices`, with their
/// non-zero `rows`), column by column; nothing in a slab.
fn spherical_transport(
    system: &ColumnSystem,
    matrices: &[f64],
    rows: &[(usize, usize)],
    (source, ground_radiance): (&[f64], f64),
    field: &mut [f64],
    columns: &mut [f64],
) {
    let Some(paths) = system.paths else {
        return;
    };
    let total = system.streams.count();
    let levels = system.grid.levels();
    let block = levels * (levels + 1);
    let (column, result) = columns[..2 * levels].split_at_mut(levels);
    for (s, &a) in paths.spherical_streams().iter().enumerate() {
        let (matrix, ground) = matrices[s * block..(s + 1) * block].split_at(levels * levels);
        for (k, value) in column.iter_mut().enumerate() {
            *value = source[k * total + a];
        }
        result.fill(0.0);
        let rows = &rows[s * levels..(s + 1) * levels];
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

/// The every-order shift's pieces of the spherical streams' paths
/// (`StreamPaths::compute_piece_matrices`).
#[derive(Debug, Clone)]
pub(super) struct ShiftPieces {
    pub(super) count: usize,
    /// Per piece and spherical stream, the transport matrix and ground
    /// weights (the layout of the whole path's).
    matrices: Vec<f64>,
    /// Per piece, spherical stream and source level, the rows where the
    /// matrix is non-zero (half-open).
    rows: Vec<(usize, usize)>,
    /// Per piece, spherical stream and level, the mean angle at the
    /// planet's centre and its spread, rad.
    pub(super) mean_angles: Vec<(f64, f64)>,
}

/// Each layer's optical depth (scaled extinction) of the column `grid`
/// with `species`.
fn layer_optical_depths(grid: &VerticalGrid, species: &[ScaledSpecies]) -> Vec<f64> {
    (0..grid.levels() - 1)
        .map(|k| {
            species
                .iter()
                .zip(grid.layer_columns_m(k))
                .map(|(sp, c)| sp.extinction_per_m * c)
                .sum()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;

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
