//! The first order of the diffuse field in the real spherical geometry:
//! the sunlight scattered once that arrives at each level of the field's
//! column in each of its streams, marched along the stream's straight
//! path through the spherical shell with the planet's shadow tested at
//! every sample (each sample with its own sun zenith angle).
//!
//! Why: the local-column picture (`super` item 3) takes the field at a
//! point from a plane-parallel column with the point's own sun zenith
//! angle. After sunset that column's air is in the Earth's shadow, so its
//! field is zero, while the real point is lit by light scattered once in
//! the sunlit layer toward the sun, tens to hundreds of kilometres away:
//! the twilight sky is that light scattered a second time. With the sun
//! 10 degrees below the horizon the column picture gave a zenith 3e5 times
//! too dark (earth-clear, against the path tracer). Here the first order
//! is exact (up to the quadrature below), and the solver carries it into
//! the higher orders through the column's kernel
//! (`super::successive_orders`, `ColumnSystem::solve` with a first order
//! given): orders >= 2 of the sources are still the column's, but they are
//! fed by the true first-order light.
//!
//! For each sun node s, level k (altitude z_k, point x = (0, 0, R + z_k))
//! and stream b (zenith cosine mu_b), with the sun at zenith angle theta_s
//! in the x-z plane and the stream looking at azimuth phi from the sun's,
//!
//! ```text
//! L1(x, w) = integral_0^S E sum_j beta*_sca,j(y) p*_j(w.s) T*(x, y) T*_sun(y) dt,
//! y = x + t w,
//! ```
//!
//! delta-M scaled (beta*, p*, T*) as the solver's problem is, T*_sun zero
//! where the path from y toward the sun hits the ground, no ground
//! reflection (the solver adds that). Its harmonics are the cosine
//! transform over N midpoint azimuths (as many as the solver has
//! harmonics, [`azimuth_count`]) on 0..180 degrees (the
//! field is symmetric about the solar meridian):
//! L1_m = (2 - delta_m0) / N sum_a L1(phi_a) cos(m phi_a), exact for a
//! field of harmonics below N. Along each path:
//! [`FirstOrderInputs::panels`] Gauss panels
//! ([`ProfileCorners::fill_panel_ends`]), cut at the profiles' corners and
//! at shells every `SHELL_SPACING_M`, and columns toward the sun from a
//! [`SunColumnTable`]. Units: W m^-2 sr^-1 nm^-1.
//!
//! What the solver takes from L1 is its Legendre moments (the scattering
//! integrals of the next order, the views' sources; [`StreamFit`]). After
//! sunset L1 is a narrow peak just above the sunward horizon, which the
//! streams' quadrature (2 of 8 nodes within 6 degrees of the horizon)
//! integrates badly: nautical twilight came out 8-17 % too dark. So from
//! a sun zenith angle of 90 degrees on ([`MomentQuadrature::Fine`]) the
//! moments are integrated over 40 zenith cosines graded toward each
//! level's horizon ([`fine_cosines`]; within 0.15 % of a brute-force
//! integral where the streams' quadrature is 10-77 % off, tested) and the
//! streams' values are the ones whose quadrature gives them.

use std::f64::consts::PI;
use std::ops::ControlFlow;

use super::column_optics::{ColumnGeometry, ScaledOptics};
use super::phase_fourier::{
    TruncatedPhase, gauss_legendre_unit_interval, legendre_polynomials,
    normalized_associated_legendre,
};
use super::regimes::FINE_MOMENTS_SUN_ZENITH_RAD;
use super::successive_orders::Streams;
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::linear_algebra::inverse;
use crate::transport::optical_column::{
    PanelMarch, ProfileCorners, SunColumnRadius, SunColumnTable,
};
#[cfg(test)]
use crate::transport::vector_exp::exp_neg;
use crate::transport::vector_exp::exp_neg_in_place;

/// Gauss panels along each stream's path by default
/// ([`crate::MultipleScatteringSettings::first_order_panels`]; measured: 8
/// panels change the zenith at sun -6 degrees by 4e-5 and at sun 5 by
/// 2.5e-4, at 1.6 times the cost).
pub(crate) const PANELS: usize = 4;
/// Nodes of the phase functions' tables over cos theta in [-1, 1].
const PHASE_NODES: usize = 2049;

/// What the first-order march needs (all per wavelength i and species j
/// at [i * species + j]).
pub(crate) struct FirstOrderInputs<'a> {
    /// The delta-M scaled coefficients and phase functions.
    pub scaled: &'a ScaledOptics,
    /// The levels, the streams (their zenith cosines, quadrature weights
    /// and Legendre functions), the profiles and their corners.
    pub geometry: &'a ColumnGeometry,
    pub sun_columns: &'a SunColumnTable,
    /// How the first order's Legendre moments are integrated.
    pub moments: MomentQuadrature,
    pub sun_zenith_rad: &'a [f64],
    pub solar_irradiance_w_m2_nm: &'a [f64],
    /// Gauss panels along each path besides its cuts ([`PANELS`] by
    /// default).
    pub panels: usize,
    /// Gauss nodes per panel of the fine moments' quadrature
    /// ([`fine_cosines`]; [`FINE_PANEL_NODES`] by default).
    pub fine_nodes: usize,
}

/// How the first order's Legendre moments (what the solver and the views
/// take from it, see [`StreamFit`]) are integrated over the zenith cosine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum MomentQuadrature {
    /// By the streams' own quadrature: L1 at the streams as marched (the
    /// tests' comparison, and the oracle's).
    #[cfg(test)]
    Streams,
    /// For the sun nodes from a zenith angle of 90 degrees on
    /// (`FINE_MOMENTS_SUN_ZENITH_RAD`), on a finer grid graded toward the
    /// horizon ([`fine_cosines`]): the streams are not marched for those,
    /// their values are the ones whose quadrature gives those moments
    /// ([`StreamFit`], from zero). The streams' own quadrature for the
    /// others, and for all where the fit cannot be made (12 streams per
    /// hemisphere and more).
    Fine,
}

/// L1 for every sun node, wavelength, harmonic, level and stream, laid out
/// as the solver's solutions: [(s * wavelengths + i) * solution + (m *
/// levels + k) * streams + b], solution = streams * levels * streams
/// (harmonics = streams). With [`MomentQuadrature::Fine`] the values are
/// the streams' radiances fitted to the fine moments, not L1 itself: the
/// same moments, so the same source everywhere (for harmonic 0, which
/// alone makes the ground's irradiance, the same values too).
///
/// A stream's path from a level does not depend on the sun (the sun turns
/// in the x-z plane, the azimuths are taken from it), so each path is
/// marched once, its samples' points, densities and columns from the
/// level kept, and every sun node then reads them: the same sums in the
/// same order as marching it per sun node
/// (`compute_spherical_first_order_reference`, the test's oracle), so the
/// result is the same bit for bit. One task per level.
#[cfg(test)]
pub(crate) fn compute_spherical_first_order(inputs: &FirstOrderInputs) -> Vec<f64> {
    compute_spherical_first_order_with_phases(inputs, &tabulate_phases(&inputs.scaled.phases))
}

/// [`compute_spherical_first_order`] with the phase functions' table of
/// [`tabulate_phases`] given (it does not depend on the sun: a sky moved
/// to another sun keeps it).
pub(crate) fn compute_spherical_first_order_with_phases(
    inputs: &FirstOrderInputs,
    phase_table: &[f64],
) -> Vec<f64> {
    let wavelengths = inputs.solar_irradiance_w_m2_nm.len();
    let species = inputs.geometry.profiles.len();
    let levels = inputs.geometry.grid.altitudes_m().len();
    let streams = inputs.geometry.streams.count();
    let solution = streams * levels * streams;
    let suns = inputs.sun_zenith_rad.len();
    let (ground, _) = inputs.geometry.corners.radii_m();
    let azimuths = azimuth_count(streams);
    let cosines = harmonic_cosines(azimuths, streams);
    let tables = &Tables::new(inputs, phase_table);
    let by_species = &BySpecies::new(inputs);
    let fit = match inputs.moments {
        #[cfg(test)]
        MomentQuadrature::Streams => None,
        MomentQuadrature::Fine => StreamFit::new(&inputs.geometry.streams, wavelengths),
    };
    // The sun nodes from a zenith angle of 90 degrees on (after sunset on
    // the ground) take the fine moments (with `MomentQuadrature::Fine`).
    let first_fine = match fit {
        None => suns,
        Some(_) => inputs
            .sun_zenith_rad
            .partition_point(|theta| *theta < FINE_MOMENTS_SUN_ZENITH_RAD),
    };
    let suns_vectors: Vec<Vector3> = inputs
        .sun_zenith_rad
        .iter()
        .map(|theta| Vector3::new(theta.sin(), 0.0, theta.cos()))
        .collect();
    // Per level: [(s * streams + b) * streams + m) * wavelengths + i].
    let per_level = suns * streams * streams * wavelengths;
    let mut by_level = vec![0.0; levels * per_level];
    crate::parallel::for_each_chunk_mut(&mut by_level, per_level, |k, block| {
        let x = Vector3::new(0.0, 0.0, ground + inputs.geometry.grid.altitudes_m()[k]);
        let mut work = MarchWork {
            radiance: vec![0.0; wavelengths],
            phase: vec![0.0; wavelengths * species],
            march: PanelMarch::new(species),
            #[cfg(test)]
            sun_columns: vec![0.0; species],
            ends: Vec::with_capacity(tables.march_corners.most_panel_ends(inputs.panels)),
        };
        let mut sun_work = SunWork {
            phase: vec![0.0; species * wavelengths],
            lit: Vec::new(),
            lit_points: Vec::new(),
            columns: Vec::new(),
            optical_depths: vec![0.0; wavelengths],
            sources: vec![0.0; wavelengths],
        };
        let mut path = MarchedPath::default();
        let fine_suns = suns - first_fine;
        let mut moments = vec![0.0; fine_suns * streams * streams * wavelengths];
        let mut fine_harmonics = vec![0.0; fine_suns * streams * wavelengths];
        let mut legendre = vec![0.0; streams * streams];
        let mut residual = vec![0.0; streams * wavelengths];
        // The sun nodes before `first_fine` from the streams marched
        // themselves; the others' stream values the fit makes from the
        // moments alone.
        let marched_streams = if first_fine > 0 { streams } else { 0 };
        let level = LevelPaths {
            tables,
            by_species,
            cosines: &cosines,
            azimuths,
            x,
        };
        let per_stream = streams * wavelengths;
        for (b, mu) in inputs.geometry.streams.cosines()[..marched_streams]
            .iter()
            .enumerate()
        {
            level.add_harmonics(
                *mu,
                &suns_vectors[..first_fine],
                (&mut work, &mut sun_work, &mut path),
                &mut block[b * per_stream..],
                streams * per_stream,
            );
        }
        let Some(fit) = &fit else {
            return;
        };
        if fine_suns == 0 {
            return;
        }
        // The moments on the fine grid, [((s * streams + m) * streams + l) *
        // wavelengths + i] for the fine sun nodes s (from `first_fine`),
        // from the harmonics of each fine cosine, [(s * streams + m) *
        // wavelengths + i].
        for (mu, weight) in fine_cosines(
            ground,
            ground + inputs.geometry.grid.altitudes_m()[k],
            inputs.fine_nodes,
        ) {
            normalized_associated_legendre(mu, streams, &mut legendre);
            fine_harmonics.fill(0.0);
            level.add_harmonics(
                mu,
                &suns_vectors[first_fine..],
                (&mut work, &mut sun_work, &mut path),
                &mut fine_harmonics,
                per_stream,
            );
            for s in 0..fine_suns {
                for m in 0..streams {
                    let harmonic =
                        &fine_harmonics[(s * streams + m) * wavelengths..][..wavelengths];
                    for l in m..streams {
                        let factor = weight * legendre[m * streams + l];
                        let out = &mut moments[((s * streams + m) * streams + l) * wavelengths..]
                            [..wavelengths];
                        for (o, h) in out.iter_mut().zip(harmonic) {
                            *o += factor * h;
                        }
                    }
                }
            }
        }
        for s in 0..fine_suns {
            let size = streams * streams * wavelengths;
            fit.correct(
                &moments[s * size..][..size],
                &mut block[(first_fine + s) * size..][..size],
                &mut residual,
            );
        }
    });
    // Transposed to [(s * wavelengths + i) * solution + (m * levels + k) *
    // streams + b], one (sun, wavelength) block per task.
    let mut out = vec![0.0; suns * wavelengths * solution];
    crate::parallel::for_each_chunk_mut(&mut out, solution, |block, out| {
        let (s, i) = (block / wavelengths, block % wavelengths);
        for k in 0..levels {
            for b in 0..streams {
                for m in 0..streams {
                    out[(m * levels + k) * streams + b] = by_level
                        [k * per_level + ((s * streams + b) * streams + m) * wavelengths + i];
                }
            }
        }
    });
    out
}

/// What the paths from one level share: the inputs' tables, the azimuths'
/// transform factors
/// ([`harmonic_cosines`]) and the level's point `x`.
struct LevelPaths<'a> {
    tables: &'a Tables<'a>,
    by_species: &'a BySpecies,
    cosines: &'a [f64],
    azimuths: usize,
    x: Vector3,
}

impl LevelPaths<'_> {
    /// Marches the paths at zenith cosine `mu` and every azimuth once, and
    /// adds for each sun of `suns` the harmonics of L1 ([m * wavelengths +
    /// i]) into `harmonics` from `s * stride` on.
    fn add_harmonics(
        &self,
        mu: f64,
        suns: &[Vector3],
        (work, sun_work, path): (&mut MarchWork, &mut SunWork, &mut MarchedPath),
        harmonics: &mut [f64],
        stride: usize,
    ) {
        let harmonic_count = self.cosines.len() / self.azimuths;
        let size = harmonic_count * work.radiance.len();
        let sine = (1.0 - mu * mu).max(0.0).sqrt();
        for a in 0..self.azimuths {
            let phi = PI * (a as f64 + 0.5) / self.azimuths as f64;
            let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), mu);
            if !march_path(self.tables, self.x, direction, work, path) {
                continue;
            }
            for (s, sun) in suns.iter().enumerate() {
                compute_first_order_on_path(
                    self.tables,
                    self.by_species,
                    direction,
                    *sun,
                    path,
                    work,
                    sun_work,
                );
                add_azimuth_to_harmonics(
                    &self.cosines[a * harmonic_count..][..harmonic_count],
                    &work.radiance,
                    &mut harmonics[s * stride..][..size],
                );
            }
        }
    }
}

/// Azimuths of the cosine transform for `streams` harmonics: as many as
/// harmonics (the delta-M phase functions have no more terms than that),
/// which the transform needs to be exact. Fewer alias: harmonic m >= N
/// of N midpoint azimuths reads as -(harmonic 2N - m). (Until the sky
/// had more than 8 streams per hemisphere, 16 azimuths were the most;
/// at 16 streams the first order's harmonics 17-31 were minus copies of
/// 15-1, which cost mars-dust 13-30 % of its multiply scattered light
/// 5 degrees above the horizon with the sun below it. At 4 streams per
/// hemisphere 8 azimuths change the explorer's preview by 0.1 % of its
/// 99th-percentile error at suns 5 to -6 degrees, the `quality_accuracy`
/// example of `crates/sora-web`, and halve its cost.)
fn azimuth_count(streams: usize) -> usize {
    streams.max(1)
}

/// (2 - delta_m0) / N cos(m phi_a) of the cosine transform over N =
/// `azimuths` midpoint azimuths, [a * streams + m].
fn harmonic_cosines(azimuths: usize, streams: usize) -> Vec<f64> {
    (0..azimuths)
        .flat_map(|a| {
            let phi = PI * (a as f64 + 0.5) / azimuths as f64;
            (0..streams).map(move |m| {
                (if m == 0 { 1.0 } else { 2.0 }) / azimuths as f64 * (m as f64 * phi).cos()
            })
        })
        .collect()
}

/// Adds one azimuth's radiance per wavelength `radiance`, times that
/// azimuth's transform factors `cosines` (one per harmonic), to
/// `harmonics` ([m * wavelengths + i]).
fn add_azimuth_to_harmonics(cosines: &[f64], radiance: &[f64], harmonics: &mut [f64]) {
    for (factor, row) in cosines
        .iter()
        .zip(harmonics.chunks_exact_mut(radiance.len()))
    {
        for (h, l) in row.iter_mut().zip(radiance) {
            *h += factor * l;
        }
    }
}

/// Zenith cosines and weights (summing to 2) of the fine quadrature of the
/// first order's moments at a level of radius `radius_m` above a ground
/// of radius `ground_m`: Gauss-Legendre panels on [-1, 1], narrowest
/// around the cosine mu_h = -sqrt(1 - (R / r)^2) of the level's horizon.
///
/// Why: after sunset the first order at a shadowed point comes from the
/// sunlit air seen a few degrees above the horizon toward the sun, and
/// from a high level from the sunlit air seen just above and below its
/// horizon: a peak a few hundredths wide in mu, with a kink at mu_h where
/// the path begins to end on the ground. The 8 Gauss streams of a
/// hemisphere put 2 nodes within 6 degrees of the horizon (mu 0.020 and
/// 0.10), and their quadrature of that peak into the next order left
/// earth-clear's deep twilight 8-17 % too dark (`docs/twilight_survey.md`).
/// Here `nodes` Gauss nodes (by default `FINE_PANEL_NODES`, 4) on each of
/// the panels between the breakpoints -1, mu_h +- `FINE_PANEL_OFFSETS` (0,
/// 0.01, 0.03, 0.08, 0.25) and 1: 40 cosines; the first and last panels
/// (the wide ones reaching mu = -1 and 1) take at least
/// `OUTER_PANEL_LEAST_NODES`.
fn fine_cosines(ground_m: f64, radius_m: f64, nodes: usize) -> Vec<(f64, f64)> {
    let ratio = (ground_m / radius_m).min(1.0);
    let horizon = -(1.0 - ratio * ratio).max(0.0).sqrt();
    let mut breaks: Vec<f64> = [-1.0, 1.0]
        .into_iter()
        .chain(
            FINE_PANEL_OFFSETS
                .iter()
                .flat_map(|d| [horizon - d, horizon + d]),
        )
        .map(|b: f64| b.clamp(-1.0, 1.0))
        .collect();
    breaks.sort_by(f64::total_cmp);
    breaks.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let last = breaks.len() - 2;
    breaks
        .windows(2)
        .enumerate()
        .flat_map(|(p, edge)| {
            let outer = p == 0 || p == last;
            let count = if outer {
                nodes.max(OUTER_PANEL_LEAST_NODES)
            } else {
                nodes
            };
            let (nodes, weights) = gauss_legendre_unit_interval(count);
            let width = edge[1] - edge[0];
            nodes
                .iter()
                .zip(&weights)
                .map(|(t, w)| (edge[0] + width * t, width * w))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Offsets of the fine quadrature's breakpoints from the level's horizon
/// cosine ([`fine_cosines`]).
const FINE_PANEL_OFFSETS: [f64; 5] = [0.0, 0.01, 0.03, 0.08, 0.25];
/// Gauss nodes per panel of the fine quadrature by default
/// ([`crate::MultipleScatteringSettings::first_order_fine_nodes`]).
pub(crate) const FINE_PANEL_NODES: usize = 4;
/// The fewest Gauss nodes on the fine quadrature's two outer panels, 0.6-0.8
/// wide in mu, whatever `nodes` the narrow ones near the horizon take: there
/// the moments' Legendre functions (up to degree 2n - 1) vary most across a
/// panel. Measured (the explorer's preview, 4 streams per hemisphere,
/// earth-clear, sun -4 degrees, 99th percentile of its luminance error
/// against the default resolution): 2 nodes on every panel 2.9 %, 3 on
/// every panel 2.3 %, 2 near the horizon and 4 on the outer ones 2.25 %
/// (4 everywhere: 2.24 %).
const OUTER_PANEL_LEAST_NODES: usize = 4;

/// The streams' radiances fitted to given Legendre moments: everything the
/// solver and the views take from the field at the streams is its
/// moments by the streams' quadrature,
///
/// ```text
/// Lambda_m,l = sum_b w_b Lambda_l^m(mu_b) L_m(mu_b),   l = m .. 2n - 1
/// ```
///
/// (the scattering matrices' p*_m(mu_a, mu_b) = sum_l c_l Lambda_l^m(mu_a)
/// Lambda_l^m(mu_b), the views' source moments, the image table's
/// kernels; the delta-M phase functions have no terms beyond 2n - 1). So
/// the first order enters them exactly when its stream values are
/// replaced by values whose quadrature gives the finely integrated
/// moments. Per harmonic m, with A = B W the (2n - m) x 2n matrix of w_b
/// Lambda_l^m(mu_b) (B of Lambda_l^m(mu_b), W the weights), that is the
/// correction dL with A (L + dL) = Lambda_fine that is smallest in the
/// quadrature's norm sum_b w_b dL_b^2,
///
/// ```text
/// dL = B^T (B W B^T)^-1 (Lambda_fine - A L)
/// ```
///
/// (B has full row rank: polynomials of degrees below 2n - m at 2n
/// distinct nodes). For m = 0 it is the one solution, whatever the
/// values were before. The fitted values are not radiances in their own
/// directions (they may be negative); the diffuse flux onto the ground is
/// a half-range moment, not one of these, and the solver takes it from
/// them by the streams' quadrature.
struct StreamFit {
    streams: usize,
    wavelengths: usize,
    /// Per harmonic m, A ([l * streams + b], rows l < m zero).
    moments_of_streams: Vec<Vec<f64>>,
    /// Per harmonic m, B^T (B W B^T)^-1 ([b * streams + l], columns l < m
    /// zero).
    correction: Vec<Vec<f64>>,
}

impl StreamFit {
    /// The fit for these streams, or None where the streams' Legendre
    /// functions are too ill-conditioned to fit every harmonic (from 12
    /// streams per hemisphere on; those streams' own quadrature then
    /// serves, and resolves the first order's peak better anyway).
    fn new(streams: &Streams, wavelengths: usize) -> Option<StreamFit> {
        let weights = streams.weights();
        let n = streams.count();
        let mut moments_of_streams = Vec::with_capacity(n);
        let mut correction = Vec::with_capacity(n);
        for m in 0..n {
            let mut a = vec![0.0; n * n];
            for l in m..n {
                for b in 0..n {
                    a[l * n + b] = weights[b] * streams.legendre(b)[m * n + l];
                }
            }
            // The correction in the span of Lambda_l^m at the streams, dL_b =
            // sum_l Lambda_l^m(mu_b) y_l: the one that least changes sum_b w_b
            // dL_b^2. Its Gram matrix sum_b w_b Lambda_l^m Lambda_q^m is the
            // streams' discrete orthogonality, near the identity (better
            // conditioned than A A^T).
            let rows = n - m;
            let lambda = |l: usize, b: usize| streams.legendre(b)[m * n + l];
            let mut gram = vec![0.0; rows * rows];
            for p in 0..rows {
                for q in 0..rows {
                    gram[p * rows + q] = (0..n)
                        .map(|b| weights[b] * lambda(m + p, b) * lambda(m + q, b))
                        .sum();
                }
            }
            let mut p = vec![0.0; n * n];
            if let Some(inverse) = inverse(&gram, rows) {
                for b in 0..n {
                    for q in 0..rows {
                        p[b * n + m + q] = (0..rows)
                            .map(|r| lambda(m + r, b) * inverse[r * rows + q])
                            .sum();
                    }
                }
            }
            // Independent in exact arithmetic (distinct cosines), but the
            // full-range Lambda_l^m at the double-Gauss cosines grow
            // ill-conditioned with the streams: where A P is not the
            // identity to 1e-6 (none at 4 and 8 streams per hemisphere;
            // harmonic 0 at 12, 0-1 at 16, 0-3 at 24) there is no fit.
            let exact = (m..n).all(|l| {
                (m..n).all(|q| {
                    let product: f64 = (0..n).map(|b| a[l * n + b] * p[b * n + q]).sum();
                    (product - if l == q { 1.0 } else { 0.0 }).abs() < 1e-6
                })
            });
            if !exact {
                return None;
            }
            moments_of_streams.push(a);
            correction.push(p);
        }
        Some(StreamFit {
            streams: n,
            wavelengths,
            moments_of_streams,
            correction,
        })
    }

    /// Corrects one sun node's stream harmonics `values` ([(b * streams +
    /// m) * wavelengths + i]) so that their quadrature gives `moments`
    /// ([(m * streams + l) * wavelengths + i]); `residual` is work space of
    /// streams x wavelengths.
    fn correct(&self, moments: &[f64], values: &mut [f64], residual: &mut [f64]) {
        let (n, w) = (self.streams, self.wavelengths);
        for m in 0..n {
            let a = &self.moments_of_streams[m];
            for l in m..n {
                let row = &mut residual[l * w..(l + 1) * w];
                row.copy_from_slice(&moments[(m * n + l) * w..][..w]);
                for b in 0..n {
                    let factor = a[l * n + b];
                    for (r, v) in row.iter_mut().zip(&values[(b * n + m) * w..][..w]) {
                        *r -= factor * v;
                    }
                }
            }
            let p = &self.correction[m];
            for b in 0..n {
                let out = &mut values[(b * n + m) * w..][..w];
                for l in m..n {
                    let factor = p[b * n + l];
                    for (o, r) in out.iter_mut().zip(&residual[l * w..(l + 1) * w]) {
                        *o += factor * r;
                    }
                }
            }
        }
    }
}

/// p*_ij tabulated over cos theta on `PHASE_NODES` nodes in [-1, 1],
/// [(i * species + j) * PHASE_NODES + n], sr^-1.
pub(crate) fn tabulate_phases(phases: &[TruncatedPhase]) -> Vec<f64> {
    // The Legendre polynomials of each node once for every phase function
    // (`TruncatedPhase::eval` of each, the same sums).
    let terms = phases.iter().map(TruncatedPhase::terms).max().unwrap_or(0);
    let mut legendre = vec![0.0; terms];
    let mut table = vec![0.0; phases.len() * PHASE_NODES];
    for n in 0..PHASE_NODES {
        legendre_polynomials(
            2.0 * n as f64 / (PHASE_NODES - 1) as f64 - 1.0,
            &mut legendre,
        );
        for (phase, row) in phases.iter().zip(table.chunks_exact_mut(PHASE_NODES)) {
            row[n] = phase.eval_with_legendre(&legendre);
        }
    }
    table
}

/// Every p*_ij at `cos_theta` into `phase`, linear between the table's
/// nodes (p* is a 16-term Legendre series: its second derivative is at
/// most ~ l^4 / 4 p* ~ 1.6e4 p*, so the error is below
/// 1.6e4 (2 / 2048)^2 / 8 = 2e-3 of the largest p*, and far less where it
/// is flat).
fn interpolate_phases(phase_table: &[f64], cos_theta: f64, phase: &mut [f64]) {
    let position = (cos_theta + 1.0) * 0.5 * (PHASE_NODES - 1) as f64;
    let node = (position.max(0.0) as usize).min(PHASE_NODES - 2);
    let t = position - node as f64;
    for (p, row) in phase.iter_mut().zip(phase_table.chunks_exact(PHASE_NODES)) {
        *p = row[node] + t * (row[node + 1] - row[node]);
    }
}

/// A stream's path marched once for every sun node: per Gauss sample, its
/// point (planet-centred, m), its distance from the planet's centre (m)
/// and that radius located in the sun-column table, its quadrature weight
/// (half the panel times the Gauss weight, m) and, per species, its
/// relative density and the column from the level to it (relative density
/// times length, m).
#[derive(Default)]
struct MarchedPath {
    points: Vec<Vector3>,
    radii: Vec<f64>,
    located: Vec<SunColumnRadius>,
    weights: Vec<f64>,
    /// [sample * species + j].
    densities: Vec<f64>,
    node_columns: Vec<f64>,
}

/// Marches the path from `x` along `direction` (the sun-independent part
/// of `compute_first_order_along_ray`) into `path`; false when it has no
/// length in the atmosphere.
fn march_path(
    inputs: &Tables,
    x: Vector3,
    direction: Vector3,
    work: &mut MarchWork,
    path: &mut MarchedPath,
) -> bool {
    let (ground, top) = inputs.geometry.corners.radii_m();
    let Some((enter, exit)) = segment_in_atmosphere(x, direction, ground, top) else {
        return false;
    };
    let length = exit - enter;
    if length <= 0.0 {
        return false;
    }
    let start = x + direction * enter;
    inputs
        .march_corners
        .fill_panel_ends(start, direction, length, inputs.panels, &mut work.ends);
    path.points.clear();
    path.radii.clear();
    path.located.clear();
    path.weights.clear();
    path.densities.clear();
    path.node_columns.clear();
    work.march.march(
        &inputs.geometry.profiles,
        ground,
        (start, direction),
        &work.ends,
        |node, node_columns, densities| {
            let r = node.point.length();
            path.points.push(node.point);
            path.radii.push(r);
            path.located.push(inputs.sun_columns.locate_radius(r));
            path.weights.push(node.weight);
            path.node_columns.extend_from_slice(node_columns);
            path.densities.extend_from_slice(densities);
            ControlFlow::Continue(())
        },
    );
    true
}

/// L1 per wavelength into `work.radiance` along a marched `path` for the
/// sun `sun` (the sun-dependent part of `compute_first_order_along_ray`:
/// the phase functions at direction . sun, the columns toward the sun,
/// the shadow).
///
/// The oracle's sums per wavelength, tau = sum_j beta*_ext,ij (C_j + C_sun,j)
/// and source = sum_j beta*_sca,ij rho_j p*_ij, are taken here species by
/// species over all wavelengths at once (`by_species`, contiguous rows that
/// the compiler vectorises), each wavelength's sum still starting from zero
/// and adding the species in the same order: the same numbers bit for bit.
/// The radius of each sample was located in the sun-column table by the
/// march, once for every sun; the sunlit samples' columns toward the sun
/// are looked up all together before the sums (the same columns as one
/// by one, `SunColumnTable::lookup_lit_columns`).
fn compute_first_order_on_path(
    inputs: &Tables,
    by_species: &BySpecies,
    direction: Vector3,
    sun: Vector3,
    path: &MarchedPath,
    work: &mut MarchWork,
    sun_work: &mut SunWork,
) {
    let species = inputs.geometry.profiles.len();
    let wavelengths = work.radiance.len();
    interpolate_phases(inputs.phase_table, direction.dot(sun), &mut work.phase);
    // No species (an empty atmosphere): no rows, and no zero-sized chunks.
    for (i, row) in work.phase.chunks_exact(species.max(1)).enumerate() {
        for (j, p) in row.iter().enumerate() {
            sun_work.phase[j * wavelengths + i] = *p;
        }
    }
    work.radiance.fill(0.0);
    sun_work.lit.clear();
    sun_work.lit_points.clear();
    for (n, point) in path.points.iter().enumerate() {
        let (located, mu) = (path.located[n], point.dot(sun) / path.radii[n]);
        if !inputs.sun_columns.is_shadowed(&located, mu) {
            sun_work.lit.push(n);
            sun_work.lit_points.push((located, mu));
        }
    }
    sun_work.columns.clear();
    sun_work.columns.resize(sun_work.lit.len() * species, 0.0);
    inputs
        .sun_columns
        .lookup_lit_columns(&sun_work.lit_points, &mut sun_work.columns);
    for (lit, &n) in sun_work.lit.iter().enumerate() {
        let sun_columns = &sun_work.columns[lit * species..(lit + 1) * species];
        let weight = path.weights[n];
        let node_columns = &path.node_columns[n * species..(n + 1) * species];
        let densities = &path.densities[n * species..(n + 1) * species];
        sun_work.optical_depths.fill(0.0);
        sun_work.sources.fill(0.0);
        for j in 0..species {
            let column = node_columns[j] + sun_columns[j];
            let density = densities[j];
            let rows = (j * wavelengths)..((j + 1) * wavelengths);
            for (((tau, source), (extinction, scattering)), phase) in sun_work
                .optical_depths
                .iter_mut()
                .zip(sun_work.sources.iter_mut())
                .zip(
                    by_species.scaled_extinction[rows.clone()]
                        .iter()
                        .zip(&by_species.scaled_scattering[rows.clone()]),
                )
                .zip(&sun_work.phase[rows])
            {
                *tau += extinction * column;
                *source += scattering * density * phase;
            }
        }
        // The optical depths become transmittances.
        exp_neg_in_place(&mut sun_work.optical_depths);
        for (((out, transmittance), source), solar) in work
            .radiance
            .iter_mut()
            .zip(&sun_work.optical_depths)
            .zip(&sun_work.sources)
            .zip(inputs.solar_irradiance_w_m2_nm)
        {
            *out += weight * solar * source * transmittance;
        }
    }
}

/// The scaled coefficients species-major, [j * wavelengths + i] (the
/// inputs have them [i * species + j]).
struct BySpecies {
    scaled_extinction: Vec<f64>,
    scaled_scattering: Vec<f64>,
}

impl BySpecies {
    fn new(inputs: &FirstOrderInputs) -> BySpecies {
        let wavelengths = inputs.solar_irradiance_w_m2_nm.len();
        let species = inputs.geometry.profiles.len();
        let transpose = |by_wavelength: &[f64]| -> Vec<f64> {
            (0..species * wavelengths)
                .map(|at| by_wavelength[(at % wavelengths) * species + at / wavelengths])
                .collect()
        };
        BySpecies {
            scaled_extinction: transpose(&inputs.scaled.scaled_extinction),
            scaled_scattering: transpose(&inputs.scaled.scaled_scattering),
        }
    }
}

/// Work space of [`compute_first_order_on_path`], species-major: the
/// phase functions [j * wavelengths + i], the columns toward the sun per
/// species, and per wavelength the optical depth and the source of a
/// sample.
struct SunWork {
    phase: Vec<f64>,
    /// The path's sunlit samples: their indices, located radii and sun
    /// cosines, and their columns toward the sun [lit * species + j]
    /// (looked up together, `SunColumnTable::lookup_lit_columns`).
    lit: Vec<usize>,
    lit_points: Vec<(SunColumnRadius, f64)>,
    columns: Vec<f64>,
    optical_depths: Vec<f64>,
    sources: Vec<f64>,
}

/// The first order marched per sun node: the oracle of
/// [`compute_spherical_first_order`].
/// L1 for every sun node, wavelength, harmonic, level and stream, laid out
/// as the solver's solutions: [(s * wavelengths + i) * solution + (m *
/// levels + k) * streams + b], solution = streams * levels * streams
/// (harmonics = streams).
#[cfg(test)]
fn compute_spherical_first_order_reference(inputs: &FirstOrderInputs) -> Vec<f64> {
    let wavelengths = inputs.solar_irradiance_w_m2_nm.len();
    let species = inputs.geometry.profiles.len();
    let levels = inputs.geometry.grid.altitudes_m().len();
    let streams = inputs.geometry.streams.count();
    let solution = streams * levels * streams;
    let suns = inputs.sun_zenith_rad.len();
    let (ground, _) = inputs.geometry.corners.radii_m();
    let mut out = vec![0.0; suns * wavelengths * solution];
    let azimuths = azimuth_count(streams);
    let cosines = harmonic_cosines(azimuths, streams);
    let phase_table = tabulate_phases(&inputs.scaled.phases);
    let inputs = &Tables::new(inputs, &phase_table);
    crate::parallel::for_each_chunk_mut(&mut out, wavelengths * solution, |s, block| {
        let theta = inputs.sun_zenith_rad[s];
        let sun = Vector3::new(theta.sin(), 0.0, theta.cos());
        let mut work = MarchWork {
            radiance: vec![0.0; wavelengths],
            phase: vec![0.0; wavelengths * species],
            march: PanelMarch::new(species),
            sun_columns: vec![0.0; species],
            ends: Vec::with_capacity(inputs.march_corners.most_panel_ends(inputs.panels)),
        };
        // Harmonics of one (level, stream), [m * wavelengths + i], summed
        // over the azimuths before they go to their strided places.
        let mut harmonics = vec![0.0; streams * wavelengths];
        for (k, z) in inputs.geometry.grid.altitudes_m().iter().enumerate() {
            let x = Vector3::new(0.0, 0.0, ground + z);
            for (b, mu) in inputs.geometry.streams.cosines().iter().enumerate() {
                let sine = (1.0 - mu * mu).max(0.0).sqrt();
                harmonics.fill(0.0);
                for a in 0..azimuths {
                    let phi = PI * (a as f64 + 0.5) / azimuths as f64;
                    let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), *mu);
                    if !compute_first_order_along_ray(inputs, x, direction, sun, &mut work) {
                        continue;
                    }
                    for (m, row) in harmonics.chunks_exact_mut(wavelengths).enumerate() {
                        let factor = cosines[a * streams + m];
                        for (h, l) in row.iter_mut().zip(&work.radiance) {
                            *h += factor * l;
                        }
                    }
                }
                for (m, row) in harmonics.chunks_exact(wavelengths).enumerate() {
                    let at = (m * levels + k) * streams + b;
                    for (i, h) in row.iter().enumerate() {
                        block[i * solution + at] = *h;
                    }
                }
            }
        }
    });
    out
}

/// The inputs, the phase functions' tables and where the paths are cut.
struct Tables<'a> {
    inputs: &'a FirstOrderInputs<'a>,
    phase_table: &'a [f64],
    /// The profiles' corners and the shells every `SHELL_SPACING_M`.
    march_corners: ProfileCorners,
}

impl<'a> Tables<'a> {
    fn new(inputs: &'a FirstOrderInputs<'a>, phase_table: &'a [f64]) -> Tables<'a> {
        let (ground, top) = inputs.geometry.corners.radii_m();
        let shells: Vec<f64> = (1..)
            .map(|n| n as f64 * SHELL_SPACING_M)
            .take_while(|h| *h < top - ground)
            .collect();
        Tables {
            inputs,
            phase_table,
            march_corners: inputs.geometry.corners.with_altitudes(&shells),
        }
    }
}

/// Altitude step of the shells at which the first order's paths are cut
/// into separate Gauss panels besides the profiles' corners, m. Why: after
/// sunset the light of a near-horizontal stream comes from the sunlit air
/// hundreds of kilometres along its path and tens of kilometres up, where
/// [`PANELS`] panels crowded toward the path's start and lowest point are
/// hundreds of kilometres long and the density changes by orders of
/// magnitude within one. Measured against 64 panels: with 4 panels alone
/// `us-standard-1976-rayleigh` (its top at 120 km) was off by up to 23 %
/// at sun -10 and -12 degrees and earth-clear by up to 1 %; with the
/// shells every 20 km, by at most 0.2 % (8 panels alone: 1.1 %).
const SHELL_SPACING_M: f64 = 20e3;

impl<'a> std::ops::Deref for Tables<'a> {
    type Target = FirstOrderInputs<'a>;
    fn deref(&self) -> &FirstOrderInputs<'a> {
        self.inputs
    }
}

struct MarchWork {
    radiance: Vec<f64>,
    phase: Vec<f64>,
    /// The paths' march.
    march: PanelMarch,
    /// The oracle's columns toward the sun.
    #[cfg(test)]
    sun_columns: Vec<f64>,
    ends: Vec<f64>,
}

/// L1(x, w) per wavelength into `work.radiance` (see the module docs);
/// false when the path has no length in the atmosphere (nothing written).
#[cfg(test)]
fn compute_first_order_along_ray(
    inputs: &Tables,
    x: Vector3,
    direction: Vector3,
    sun: Vector3,
    work: &mut MarchWork,
) -> bool {
    let (ground, top) = inputs.geometry.corners.radii_m();
    let Some((enter, exit)) = segment_in_atmosphere(x, direction, ground, top) else {
        return false;
    };
    let length = exit - enter;
    if length <= 0.0 {
        return false;
    }
    let species = inputs.geometry.profiles.len();
    interpolate_phases(inputs.phase_table, direction.dot(sun), &mut work.phase);
    let start = x + direction * enter;
    inputs
        .march_corners
        .fill_panel_ends(start, direction, length, inputs.panels, &mut work.ends);
    work.radiance.fill(0.0);
    let (phase, radiance, sun_columns) = (&work.phase, &mut work.radiance, &mut work.sun_columns);
    work.march.march(
        &inputs.geometry.profiles,
        ground,
        (start, direction),
        &work.ends,
        |node, node_columns, densities| {
            let r = node.point.length();
            if !inputs
                .sun_columns
                .lookup_columns_to_sun(r, node.point.dot(sun) / r, sun_columns)
            {
                return ControlFlow::Continue(());
            }
            for (i, out) in radiance.iter_mut().enumerate() {
                let (mut tau, mut source) = (0.0, 0.0);
                for j in 0..species {
                    let at = i * species + j;
                    tau += inputs.scaled.scaled_extinction[at] * (node_columns[j] + sun_columns[j]);
                    source += inputs.scaled.scaled_scattering[at] * densities[j] * phase[at];
                }
                *out += node.weight * inputs.solar_irradiance_w_m2_nm[i] * source * exp_neg(tau);
            }
            ControlFlow::Continue(())
        },
    );
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;
    use crate::transport::multiple_scattering::regimes::FIRST_ORDER_SUN_ZENITH_DEG;

    /// An Earth-like shell (6 360 to 6 460 km, air and a 1.2-km aerosol
    /// layer) with levels at `levels_m` and `streams_per_hemisphere`, and
    /// its sun-column table on `nodes` (altitude, mu) nodes: the ground
    /// radius, the geometry and the table.
    fn earth_like_shell(
        nodes: (usize, usize),
        streams_per_hemisphere: usize,
        levels_m: &[f64],
    ) -> (f64, ColumnGeometry, SunColumnTable) {
        let (ground, top) = (6_360e3, 6_460e3);
        let profiles = vec![
            DensityProfile::Exponential {
                scale_height_m: 8_000.0,
            },
            DensityProfile::Exponential {
                scale_height_m: 1_200.0,
            },
        ];
        let sun_columns = SunColumnTable::compute(&profiles, ground, top, nodes.0, nodes.1);
        let geometry =
            ColumnGeometry::with_levels(profiles, (ground, top), streams_per_hemisphere, levels_m);
        (ground, geometry, sun_columns)
    }

    /// Scaled optics of `phases` with these coefficients (the exact
    /// extinction is not read by the first order).
    fn scaled_optics(
        phases: Vec<TruncatedPhase>,
        scaled_extinction: &[f64],
        scaled_scattering: &[f64],
    ) -> ScaledOptics {
        ScaledOptics {
            phases,
            extinction: scaled_extinction.to_vec(),
            scaled_extinction: scaled_extinction.to_vec(),
            scaled_scattering: scaled_scattering.to_vec(),
        }
    }

    /// `count` truncated phase functions of `degrees` terms, alternately
    /// Rayleigh-like (chi_2 = 0.1, the rest 0) and forward-peaked (HG moments,
    /// g = 0.7): [i * 2 + j] for wavelength i and the two species j.
    fn test_phases(count: usize, degrees: usize) -> Vec<TruncatedPhase> {
        (0..count)
            .map(|n| {
                let g: f64 = if n % 2 == 0 { 0.0 } else { 0.7 };
                let moments: Vec<f64> = (0..=degrees)
                    .map(|l| {
                        if l == 2 && n % 2 == 0 {
                            0.1
                        } else {
                            g.powi(l as i32)
                        }
                    })
                    .collect();
                TruncatedPhase::from_moments(&moments, degrees)
            })
            .collect()
    }

    /// The fast first order (each path marched once for every sun node)
    /// equals the oracle (marched per sun node) bit for bit: two species,
    /// three wavelengths, 2 streams per hemisphere, five levels, suns from
    /// 84 to 100 degrees of zenith (lit, grazing and deep in the shadow).
    #[test]
    fn marching_once_for_every_sun_is_the_oracle_bit_for_bit() {
        let (_, geometry, sun_columns) =
            earth_like_shell((32, 64), 2, &[0.0, 1e3, 5e3, 20e3, 60e3]);
        let degrees = geometry.streams.count();
        let scaled = scaled_optics(
            test_phases(3 * 2, degrees),
            &[2.4e-5, 8e-5, 1.2e-5, 7e-5, 0.6e-5, 6e-5],
            &[2.4e-5, 7e-5, 1.2e-5, 6e-5, 0.6e-5, 5e-5],
        );
        let inputs = FirstOrderInputs {
            scaled: &scaled,
            geometry: &geometry,
            sun_columns: &sun_columns,
            moments: MomentQuadrature::Streams,
            sun_zenith_rad: &[
                FIRST_ORDER_SUN_ZENITH_DEG.to_radians(),
                89f64.to_radians(),
                93f64.to_radians(),
                100f64.to_radians(),
            ],
            solar_irradiance_w_m2_nm: &[1.7, 1.9, 1.5],
            panels: PANELS,
            fine_nodes: FINE_PANEL_NODES,
        };
        let fast = compute_spherical_first_order(&inputs);
        let oracle = compute_spherical_first_order_reference(&inputs);
        assert_eq!(fast.len(), oracle.len());
        assert!(oracle.iter().any(|v| *v > 0.0), "some light");
        assert!(fast == oracle, "bit for bit");
    }

    /// The cosine transform gives back every harmonic of a field that has
    /// as many as the solver (2n for n streams per hemisphere), for the
    /// explorer's 4, the default 8 and more: with at most 16 azimuths, as
    /// before, 16 streams per hemisphere read harmonic 17 as minus
    /// harmonic 15.
    #[test]
    fn the_azimuth_transform_is_exact_for_every_harmonic() {
        for harmonics in [8, 16, 24, 32] {
            let azimuths = azimuth_count(harmonics);
            let cosines = harmonic_cosines(azimuths, harmonics);
            let truth: Vec<f64> = (0..harmonics)
                .map(|m| 1.0 / (1.0 + m as f64) * if m % 3 == 1 { -1.0 } else { 1.0 })
                .collect();
            let mut recovered = vec![0.0; harmonics];
            for a in 0..azimuths {
                let phi = PI * (a as f64 + 0.5) / azimuths as f64;
                let field: f64 = truth
                    .iter()
                    .enumerate()
                    .map(|(m, c)| c * (m as f64 * phi).cos())
                    .sum();
                for (m, r) in recovered.iter_mut().enumerate() {
                    *r += field * cosines[a * harmonics + m];
                }
            }
            for (m, (r, t)) in recovered.iter().zip(&truth).enumerate() {
                assert!(
                    (r - t).abs() < 1e-12,
                    "{harmonics} harmonics: harmonic {m} {r} against {t}"
                );
            }
        }
    }

    /// The fit gives the streams' radiances the asked moments to 1e-10 at
    /// the explorer's 4 streams per hemisphere and the default 8, and
    /// leaves values that already have them unchanged; from 12 on it is
    /// not made (ill-conditioned).
    #[test]
    fn the_stream_fit_gives_the_asked_moments() {
        for n in [12, 16, 24] {
            let streams = crate::transport::multiple_scattering::successive_orders::Streams::new(n);
            assert!(StreamFit::new(&streams, 1).is_none());
        }
        for n in [4, 8] {
            let tolerance = 1e-10;
            let streams = crate::transport::multiple_scattering::successive_orders::Streams::new(n);
            let d = streams.count();
            let w = 2;
            let fit = StreamFit::new(&streams, w).expect("every harmonic fits");
            let quadrature = |values: &[f64], m: usize, l: usize, i: usize| -> f64 {
                (0..d)
                    .map(|b| {
                        streams.weights()[b]
                            * streams.legendre(b)[m * d + l]
                            * values[(b * d + m) * w + i]
                    })
                    .sum()
            };
            // Made-up stream values, and targets 0-40 % away from their
            // moments.
            let mut values: Vec<f64> = (0..d * d * w)
                .map(|at| 1.0 + 0.5 * ((at * 7919) % 13) as f64 / 13.0)
                .collect();
            let target: Vec<f64> = (0..d * d * w)
                .map(|at| {
                    let (m, l, i) = (at / w / d, at / w % d, at % w);
                    if l < m {
                        0.0
                    } else {
                        quadrature(&values, m, l, i) * (1.0 + 0.4 * ((at * 31) % 7) as f64 / 7.0)
                    }
                })
                .collect();
            let mut residual = vec![0.0; d * w];
            fit.correct(&target, &mut values, &mut residual);
            let scale = target.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for m in 0..d {
                for l in m..d {
                    for i in 0..w {
                        let got = quadrature(&values, m, l, i);
                        let want = target[(m * d + l) * w + i];
                        assert!(
                            (got - want).abs() < tolerance * scale,
                            "{n} streams: moment ({m}, {l}) {got} against {want}"
                        );
                    }
                }
            }
            let before = values.clone();
            let largest = before.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            fit.correct(&target, &mut values, &mut residual);
            for (a, b) in values.iter().zip(&before) {
                assert!(
                    (a - b).abs() < 100.0 * tolerance * largest,
                    "{n} streams: a second fit moves {b} to {a}"
                );
            }
        }
    }

    /// After sunset (sun 12 degrees below the horizon, an Earth-like shell
    /// of air and aerosol) the first order's moments that the solver takes
    /// (harmonics 0-2, degrees up to 4) are integrated by the fine
    /// quadrature (with the streams' 16 azimuths) to within 0.3 % of the
    /// largest, against a brute-force oracle: 1 340 midpoint cosines
    /// (0.0005 apart within 0.3 of the level's horizon cosine) times 48
    /// azimuths, marched one by one. Measured: 0.14 % on the ground and
    /// 0.13 % at 30 km; the default 8 streams' own quadrature is off by 10
    /// and 77 % (asserted above 5 %), which is what the fine quadrature is
    /// for. With 4 streams per hemisphere and so 8 azimuths the fine
    /// quadrature was within 0.7 % (48 cosines then, 40 now).
    #[test]
    fn fine_moments_match_a_brute_force_integral_after_sunset() {
        for (k, (fine, streams)) in fine_moment_errors(8, PANELS, FINE_PANEL_NODES)
            .into_iter()
            .enumerate()
        {
            assert!(
                fine < 3e-3,
                "level {k}: the fine quadrature is off by {:.3} %",
                100.0 * fine
            );
            assert!(
                streams > 0.05,
                "level {k}: the streams' own quadrature is off by only {:.2} %",
                100.0 * streams
            );
        }
    }

    /// The explorer's coarse first orders (`quality_settings` in
    /// `crates/sora-web`) against the same oracle, marched at the default 4
    /// panels: the preview's 4 streams per hemisphere, one panel along each
    /// path besides its cuts and 2 nodes on each panel near the horizon (24
    /// cosines), and the refinement's 7 streams, 1 panel and 2 nodes.
    /// Measured, on the ground and at 30 km: the preview 1.2 % and 0.44 %
    /// (its quadrature with 4 panels 0.21 % and 1.1 %; 4 streams with the
    /// default panels and quadrature 0.05 % and 0.27 %), the refinement
    /// 1.17 % and 0.090 % (8 streams: 1.15 % and 0.095 %, with 2 panels
    /// 0.78 % and 0.14 %). One node near the horizon (16 cosines) is 12 % and
    /// 9 % off with 4 streams, which is why it is not used.
    #[test]
    fn the_explorers_coarser_quadratures_stay_near_the_brute_force_integral() {
        for (k, (fine, _)) in fine_moment_errors(4, 1, 2)
            .into_iter()
            .chain(fine_moment_errors(7, 1, 2))
            .enumerate()
        {
            assert!(
                fine < 2e-2,
                "level {k}: the fine quadrature is off by {:.3} %",
                100.0 * fine
            );
        }
    }

    /// Per level (the ground and 30 km), the largest error of the fine
    /// quadrature's moments and of the streams' own quadrature, relative to
    /// the largest moment, with `streams_per_hemisphere`, `panels` along
    /// each path and `fine_nodes` per panel of the fine quadrature.
    fn fine_moment_errors(
        streams_per_hemisphere: usize,
        panels: usize,
        fine_nodes: usize,
    ) -> Vec<(f64, f64)> {
        let levels_m = [0.0, 30e3];
        let (ground, geometry, sun_columns) =
            earth_like_shell((128, 256), streams_per_hemisphere, &levels_m);
        let streams = &geometry.streams;
        let d = streams.count();
        let scaled = scaled_optics(test_phases(2, d), &[1.2e-5, 5e-5], &[1.2e-5, 4.5e-5]);
        let sun_zenith = 102f64.to_radians();
        let mut inputs = FirstOrderInputs {
            scaled: &scaled,
            geometry: &geometry,
            sun_columns: &sun_columns,
            moments: MomentQuadrature::Fine,
            sun_zenith_rad: &[sun_zenith],
            solar_irradiance_w_m2_nm: &[1.8],
            panels,
            fine_nodes,
        };
        let fine = compute_spherical_first_order(&inputs);
        inputs.moments = MomentQuadrature::Streams;
        let by_streams = compute_spherical_first_order(&inputs);
        let levels = levels_m.len();
        let moment_of = |field: &[f64], k: usize, m: usize, l: usize| -> f64 {
            (0..d)
                .map(|b| {
                    streams.weights()[b]
                        * streams.legendre(b)[m * d + l]
                        * field[(m * levels + k) * d + b]
                })
                .sum()
        };
        // The oracle, marched at the default panels.
        inputs.panels = PANELS;
        let phase_table = tabulate_phases(&scaled.phases);
        let tables = Tables::new(&inputs, &phase_table);
        let mut errors = Vec::new();
        let mut work = MarchWork {
            radiance: vec![0.0; 1],
            phase: vec![0.0; 2],
            march: PanelMarch::new(2),
            sun_columns: vec![0.0; 2],
            ends: Vec::new(),
        };
        let sun = Vector3::new(sun_zenith.sin(), 0.0, sun_zenith.cos());
        let azimuths = 48;
        let mut legendre = vec![0.0; d * d];
        for (k, z) in levels_m.iter().enumerate() {
            let x = Vector3::new(0.0, 0.0, ground + z);
            let ratio = ground / (ground + z);
            let horizon = -(1.0f64 - ratio * ratio).sqrt();
            let (low, high) = (horizon - 0.3, horizon + 0.3);
            let mut cosines = Vec::new();
            let mut push_midpoints = |from: f64, to: f64, step: f64| {
                let count = ((to - from) / step).round() as usize;
                let width = (to - from) / count as f64;
                for c in 0..count {
                    cosines.push((from + (c as f64 + 0.5) * width, width));
                }
            };
            push_midpoints(-1.0, low, 0.01);
            push_midpoints(low, high, 0.0005);
            push_midpoints(high, 1.0, 0.01);
            let mut oracle = [0.0; 3 * 5];
            for (mu, weight) in cosines {
                let sine = (1.0 - mu * mu).sqrt();
                let mut harmonics = [0.0; 3];
                for a in 0..azimuths {
                    let phi = PI * (a as f64 + 0.5) / azimuths as f64;
                    let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), mu);
                    if compute_first_order_along_ray(&tables, x, direction, sun, &mut work) {
                        for (m, h) in harmonics.iter_mut().enumerate() {
                            let factor = if m == 0 { 1.0 } else { 2.0 };
                            *h += factor / azimuths as f64
                                * (m as f64 * phi).cos()
                                * work.radiance[0];
                        }
                    }
                }
                normalized_associated_legendre(mu, d, &mut legendre);
                for m in 0..3 {
                    for l in m..5 {
                        oracle[m * 5 + l] += weight * legendre[m * d + l] * harmonics[m];
                    }
                }
            }
            let largest = oracle.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(largest > 0.0, "level {k}: some light");
            let mut worst_streams = 0.0f64;
            let mut worst_fine = 0.0f64;
            for m in 0..3 {
                for l in m..5 {
                    let want = oracle[m * 5 + l];
                    let got = moment_of(&fine, k, m, l);
                    worst_streams =
                        worst_streams.max((moment_of(&by_streams, k, m, l) - want).abs());
                    worst_fine = worst_fine.max((got - want).abs());
                }
            }
            errors.push((worst_fine / largest, worst_streams / largest));
        }
        errors
    }
}
