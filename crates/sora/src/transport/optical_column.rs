//! Optical columns: integral of each species' relative density along a
//! ray, in metres (the "equivalent path" of the species at relative
//! density 1).
//!
//! Every species has beta(h, lambda) = relative_density(h) beta(lambda)
//! (the paper's eq. 1), so the optical depth of a path at every wavelength
//! is tau(lambda) = sum_s beta_ext,s(lambda) column_s: one geometric
//! integral per species serves all wavelengths. Transmittance is
//! exp(-tau) (Beer-Lambert, the paper's A(x0, xi)).
//!
//! - `compute_columns_along_ray`: the integral by composite 4-point
//!   Gauss-Legendre on panels that crowd toward the ray's lowest point
//!   (where the density peaks) and its start, cut where the ray crosses a
//!   corner of a piecewise-linear profile ([`ProfileCorners`]).
//! - [`PanelMarch`]: the same panels with the columns from the ray's start
//!   to every node (a running integral inside each panel), the one march
//!   of every integral along a path of the fast method.
//! - [`SunColumnTable`]: the columns from any point to the top of the
//!   atmosphere toward the sun, tabulated over (altitude, cos of the sun's
//!   zenith angle) and read by `SunColumnTable::lookup_columns_to_sun`.
//!   Its rays' absorbing gases on exponential profiles (the `[gases]`
//!   table's water, mixed gases and O2-O2) take the vector exponential,
//!   a ray's nodes at once (`compute_with_fast_exponentials`, within
//!   1e-11 of the scalar entries); every other profile's entries are
//!   `compute_columns_along_ray`'s bits.
//!   Both axes are Bruneton's (2017) transmittance-texture
//!   parametrisation: altitude through rho = sqrt(r^2 - R^2) (dense near
//!   the ground, where thin aerosol layers live), and mu through the
//!   distance d to the top boundary (which resolves the steep growth of
//!   the column near the horizon). The table holds the mean relative
//!   density along the path, column / d, which stays finite and smooth up
//!   to the top boundary where both go to zero; it is interpolated
//!   bilinearly in its logarithm (an exponential profile's mean density is
//!   close to exponential in both coordinates), or linearly for a layer
//!   (piecewise-linear) profile, whose column falls to zero quadratically
//!   where paths leave the layer (measured: a 2-4 km tent aerosol layer's
//!   image 2.3e-3 from the reference march in the logarithm, 8.2e-4
//!   linearly). `SunColumnTable::lookup_columns_at_radius` looks up one
//!   point (the slow path); `SunColumnTable::lookup_lit_columns` looks up
//!   a ray's sunlit points together, four at a time (compiled for AVX2
//!   where the CPU has it; the compiler keeps most steps scalar, so the
//!   gain is four independent chains overlapping, not vector
//!   instructions), each lane the single lookup's operations,
//!   so the same bits: single scattering's march and the spherical first
//!   order's paths take their columns so, after the march, where the
//!   lookups of one node after another each waited on its own chain (a
//!   square root, two divisions, the corners' loads, an exponential per
//!   smooth profile).

use std::borrow::Borrow;
use std::ops::ControlFlow;

use super::quadrature::{GAUSS_NODES, GAUSS_WEIGHTS, running_integral_matrix};
use crate::atmosphere::DensityProfile;
use crate::geometry::{Vector3, ray_sphere_roots};

/// How a ray of `length` m with its closest approach to the planet's
/// centre at `tangent_distance` m along it is cut into `panels` Gauss
/// panels: the (start, end) of panel `k`, in m along the ray.
///
/// Each part of the ray gets panels crowded toward where the integrand is
/// largest: toward the start (the eye, or the point the sun's light
/// reaches) when the ray only climbs; toward the tangent point from both
/// sides when it first descends and then climbs; toward both ends when it
/// only descends (to the ground or the far side). One panel is the whole
/// ray (the explorer's preview marches its twilight first order so, cut
/// only at the shells and the profiles' corners).
pub(crate) fn ray_panel(tangent_distance: f64, length: f64, panels: usize, k: usize) -> (f64, f64) {
    let crowded_toward_start = |a: f64, b: f64, n: usize, i: usize| {
        let (u0, u1) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
        (a + (b - a) * u0 * u0, a + (b - a) * u1 * u1)
    };
    let crowded_toward_end = |a: f64, b: f64, n: usize, i: usize| {
        let (u0, u1) = ((n - i) as f64 / n as f64, (n - i - 1) as f64 / n as f64);
        (b - (b - a) * u0 * u0, b - (b - a) * u1 * u1)
    };
    debug_assert!(panels >= 1 && k < panels);
    if panels == 1 {
        return (0.0, length);
    }
    let half = panels / 2;
    if tangent_distance <= 0.0 {
        // Climbs all the way.
        crowded_toward_start(0.0, length, panels, k)
    } else if tangent_distance < length {
        // Descends to the tangent point, then climbs.
        if k < half {
            crowded_toward_end(0.0, tangent_distance, half, k)
        } else {
            crowded_toward_start(tangent_distance, length, panels - half, k - half)
        }
    } else {
        // Descends all the way (ends at the ground).
        let middle = 0.5 * length;
        if k < half {
            crowded_toward_start(0.0, middle, half, k)
        } else {
            crowded_toward_end(middle, length, panels - half, k - half)
        }
    }
}

/// The altitudes where a density profile has a corner, at which rays are
/// cut into separate Gauss panels: 4-point Gauss-Legendre converges slowly
/// across a corner and fast on either side (measured: a 2-4 km tent layer
/// seen from the ground at 10 degrees elevation was 0.9 % too bright in
/// single scattering without the cuts, 1e-4 with them).
/// Piecewise-linear profiles (tent, layers) have corners at their rows;
/// exponential and log-linear table profiles are smooth enough (measured:
/// the 50-row US Standard 1976 table gives the same sky as the paper's
/// uniform march to 1e-4).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProfileCorners {
    ground_radius_m: f64,
    top_radius_m: f64,
    /// Corner altitudes strictly inside the atmosphere, m, increasing.
    altitudes_m: Vec<f64>,
}

impl ProfileCorners {
    /// The corners of `profiles` between the ground (radius
    /// `ground_radius_m`) and the top of the atmosphere (`top_radius_m`).
    pub(crate) fn new<P: Borrow<DensityProfile>>(
        profiles: &[P],
        ground_radius_m: f64,
        top_radius_m: f64,
    ) -> ProfileCorners {
        let altitudes_m = profiles
            .iter()
            .filter_map(|profile| match profile.borrow() {
                DensityProfile::PiecewiseLinear(table) => Some(table.altitudes_m()),
                _ => None,
            })
            .flatten()
            .copied();
        ProfileCorners::from_altitudes(ground_radius_m, top_radius_m, altitudes_m)
    }

    /// These corners and `extra_m` (altitudes, m) as well.
    pub(crate) fn with_altitudes(&self, extra_m: &[f64]) -> ProfileCorners {
        let altitudes_m = self.altitudes_m.iter().chain(extra_m).copied();
        ProfileCorners::from_altitudes(self.ground_radius_m, self.top_radius_m, altitudes_m)
    }

    /// Corners at `altitudes_m` (m, in any order, repeats allowed): those
    /// strictly inside the atmosphere, increasing.
    fn from_altitudes(
        ground_radius_m: f64,
        top_radius_m: f64,
        altitudes_m: impl Iterator<Item = f64>,
    ) -> ProfileCorners {
        let height = top_radius_m - ground_radius_m;
        let mut altitudes_m: Vec<f64> = altitudes_m.filter(|h| *h > 0.0 && *h < height).collect();
        altitudes_m.sort_by(f64::total_cmp);
        altitudes_m.dedup();
        ProfileCorners {
            ground_radius_m,
            top_radius_m,
            altitudes_m,
        }
    }

    /// The radii of the ground and of the top of the atmosphere, m.
    pub(crate) fn radii_m(&self) -> (f64, f64) {
        (self.ground_radius_m, self.top_radius_m)
    }

    /// The most panel ends [`ProfileCorners::fill_panel_ends`] writes for
    /// `panels` panels: a ray crosses each corner altitude at most twice.
    pub(crate) fn most_panel_ends(&self, panels: usize) -> usize {
        panels + 1 + 2 * self.altitudes_m.len()
    }

    /// The ends of the Gauss panels of a ray from `origin` along the unit
    /// `direction` over [0, `length_m`] into `ends` (increasing, from 0 to
    /// `length_m`): `panels` panels crowded toward the ray's start and its
    /// lowest point ([`ray_panel`]), cut where the ray crosses a corner
    /// altitude. Allocation-free when `ends` has the capacity of
    /// [`ProfileCorners::most_panel_ends`].
    pub(crate) fn fill_panel_ends(
        &self,
        origin: Vector3,
        direction: Vector3,
        length_m: f64,
        panels: usize,
        ends: &mut Vec<f64>,
    ) {
        ends.clear();
        ends.push(0.0);
        let tangent_distance = -origin.dot(direction);
        for k in 0..panels {
            ends.push(ray_panel(tangent_distance, length_m, panels, k).1);
        }
        let uncut = ends.len();
        for h in &self.altitudes_m {
            if let Some((near, far)) = ray_sphere_roots(origin, direction, self.ground_radius_m + h)
            {
                for t in [near, far] {
                    if t > 0.0 && t < length_m {
                        ends.push(t);
                    }
                }
            }
        }
        if ends.len() > uncut {
            ends.sort_unstable_by(f64::total_cmp);
            ends.dedup();
        }
    }
}

/// Columns (m) of every species along a ray from `origin` (planet-centred,
/// m) in the unit `direction`, integrated by 4-point Gauss-Legendre on the
/// panels between consecutive `panel_ends` (m along the ray, increasing;
/// see [`ProfileCorners::fill_panel_ends`]), into `columns_m`.
pub(crate) fn compute_columns_along_ray<P: Borrow<DensityProfile>>(
    profiles: &[P],
    ground_radius_m: f64,
    origin: Vector3,
    direction: Vector3,
    panel_ends: &[f64],
    columns_m: &mut [f64],
) {
    columns_m.fill(0.0);
    for ends in panel_ends.windows(2) {
        let (centre, half) = (0.5 * (ends[0] + ends[1]), 0.5 * (ends[1] - ends[0]));
        for (x, w) in GAUSS_NODES.iter().zip(GAUSS_WEIGHTS) {
            let point = origin + direction * (centre + half * x);
            let altitude_m = point.length() - ground_radius_m;
            for (column, profile) in columns_m.iter_mut().zip(profiles) {
                *column += half * w * profile.borrow().relative_density(altitude_m);
            }
        }
    }
}

/// [`compute_columns_along_ray`] where the profiles marked in
/// `fast_scale_heights` (Some(the scale height, m) of an exponential
/// profile) take their relative densities from the vector exponential
/// (`vector_exp::exp_neg_in_place`, within 2e-12 relative of `f64::exp`),
/// every node of the ray and every such profile in one call (the two
/// buffers hold the nodes' altitudes and those densities); the other
/// profiles take the same operations in the same order as
/// [`compute_columns_along_ray`], so their columns are the same bits.
fn compute_columns_along_ray_fast<P: Borrow<DensityProfile>>(
    profiles: &[P],
    fast_scale_heights: &[Option<f64>],
    (ground_radius_m, origin, direction): (f64, Vector3, Vector3),
    panel_ends: &[f64],
    columns_m: &mut [f64],
    (altitudes_m, fast): (&mut Vec<f64>, &mut Vec<f64>),
) {
    columns_m.fill(0.0);
    // Every node's altitude, panel by panel, as compute_columns_along_ray
    // finds it.
    altitudes_m.clear();
    for ends in panel_ends.windows(2) {
        let (centre, half) = (0.5 * (ends[0] + ends[1]), 0.5 * (ends[1] - ends[0]));
        altitudes_m.extend(GAUSS_NODES.iter().map(|x| {
            let point = origin + direction * (centre + half * x);
            point.length() - ground_radius_m
        }));
    }
    fast.clear();
    for h in fast_scale_heights.iter().flatten() {
        fast.extend(altitudes_m.iter().map(|a| a / h));
    }
    crate::transport::vector_exp::exp_neg_in_place(fast);
    let mut fast = fast.chunks_exact(altitudes_m.len().max(1));
    for ((column, profile), scale_height) in
        columns_m.iter_mut().zip(profiles).zip(fast_scale_heights)
    {
        let densities = scale_height.and_then(|_| fast.next());
        for (p, ends) in panel_ends.windows(2).enumerate() {
            let half = 0.5 * (ends[1] - ends[0]);
            for (n, w) in GAUSS_WEIGHTS.iter().enumerate() {
                let density = match densities {
                    Some(densities) => densities[4 * p + n],
                    None => profile.borrow().relative_density(altitudes_m[4 * p + n]),
                };
                *column += half * w * density;
            }
        }
    }
}

/// One node of a [`PanelMarch`]: where it is and what it weighs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct MarchNode {
    /// The node, planet-centred, m.
    pub(crate) point: Vector3,
    /// The Gauss quadrature weight of the node, m (half the panel's length
    /// times the 4-point weight).
    pub(crate) weight: f64,
    /// Which node of the ray it is (0 first).
    pub(crate) index: usize,
    /// Whether the node is replayed ([`PanelMarch::reuse_nodes`]): at the
    /// altitude of node `index` of the ray that was marched last, so what
    /// depends on its altitude alone (its radius located in a table) is
    /// what it was there.
    pub(crate) repeated: bool,
}

/// A march node's radius (m) and that radius located in a
/// [`SunColumnTable`], kept per node index for the replayed nodes of
/// [`PanelMarch::reuse_nodes`] ([`SunColumnTable::locate_node`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct LocatedNode {
    pub(crate) radius_m: f64,
    pub(crate) located: SunColumnRadius,
}

/// The Gauss-panel march along a ray that every integral along a path of
/// the fast method shares (single scattering's view ray, the multiple
/// scattering's view ray, the spherical first order's stream paths, the
/// tilted peak beam's lines): 4-point Gauss-Legendre nodes on the panels
/// between consecutive panel ends ([`ProfileCorners::fill_panel_ends`]),
/// at each node the species' relative densities and the columns from the
/// ray's start to the node (the columns of the panels before it plus the
/// running integral inside its own, [`running_integral_matrix`], exact for
/// a density cubic across the panel). The march keeps its buffers between
/// rays (allocation-free after the first).
///
/// With [`PanelMarch::reuse_nodes`] it keeps the last ray's nodes too
/// (their distances, weights, columns and densities) and replays them for
/// a ray whose nodes lie at the same altitudes: the same planet, profiles
/// and panel ends, and the same |start|^2, start . direction and
/// direction . direction (the altitude at s along the ray is
/// sqrt(|start|^2 + 2 s start . d + s^2 d . d) - R), each within
/// [`REUSE_TOLERANCE`] relative. The rays of one zenith angle from one eye
/// (a row of a sky-view table, at every azimuth) are such rays: their
/// densities and columns are marched once, not once per azimuth. Only the
/// nodes' points are the new ray's own (start + s direction, as the march
/// computes them); the rest differs from a march of the new ray by the
/// rounding of its |point| (1e-16 relative; the test
/// `replayed_nodes_are_the_march_s`).
#[derive(Debug, Clone, Default)]
pub(crate) struct PanelMarch {
    running_integral: [[f64; 4]; 4],
    /// Per species, the relative densities at the current panel's nodes.
    panel_densities: Vec<[f64; 4]>,
    /// Per species, the columns from the start to the current panel's
    /// start, m (after a march: the whole ray's).
    columns: Vec<f64>,
    /// Per species, at the current node: the column from the start, m,
    /// and the relative density.
    node_columns: Vec<f64>,
    densities: Vec<f64>,
    /// The last whole ray's nodes, when reused ([`PanelMarch::reuse_nodes`]).
    recorded: Option<Box<RecordedNodes>>,
    reuse: bool,
}

/// Relative tolerance within which a ray's altitudes are taken as a
/// recorded ray's ([`PanelMarch::reuse_nodes`]): rays of one zenith angle
/// computed at different azimuths differ by a few units of rounding
/// (1e-16); 1e-12 is a micrometre in a thousand kilometres.
const REUSE_TOLERANCE: f64 = 1e-12;

/// A whole march's nodes, for [`PanelMarch::reuse_nodes`].
#[derive(Debug, Clone, Default)]
struct RecordedNodes {
    /// |start|^2, start . direction, direction . direction, the ground's
    /// radius: what, with the panel ends and the profiles, fixes every
    /// node's altitude.
    key: [f64; 4],
    ends: Vec<f64>,
    profiles: Vec<DensityProfile>,
    /// Per node: the distance along the ray (m), the weight (m), the
    /// panel it is in.
    distances: Vec<f64>,
    weights: Vec<f64>,
    panels: Vec<usize>,
    /// Per node, per species: the column from the start (m), the relative
    /// density.
    node_columns: Vec<f64>,
    densities: Vec<f64>,
    /// Per panel, per species: the columns from the start to the panel's
    /// start, m; then the whole ray's.
    panel_columns: Vec<f64>,
}

impl RecordedNodes {
    fn key(start: Vector3, direction: Vector3, ground_radius_m: f64) -> [f64; 4] {
        [
            start.dot(start),
            start.dot(direction),
            direction.dot(direction),
            ground_radius_m,
        ]
    }

    /// Whether a ray with this key, these profiles and these panel ends
    /// has the recorded nodes' altitudes.
    fn matches<P: Borrow<DensityProfile>>(
        &self,
        key: &[f64; 4],
        profiles: &[P],
        ends: &[f64],
    ) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= REUSE_TOLERANCE * a.abs().max(b.abs());
        self.key.iter().zip(key).all(|(a, b)| close(*a, *b))
            && self.ends.len() == ends.len()
            && self.ends.iter().zip(ends).all(|(a, b)| close(*a, *b))
            && self.profiles.len() == profiles.len()
            && self
                .profiles
                .iter()
                .zip(profiles)
                .all(|(a, b)| a == b.borrow())
    }
}

impl PanelMarch {
    /// A march for `species` species.
    pub(crate) fn new(species: usize) -> PanelMarch {
        PanelMarch {
            running_integral: running_integral_matrix(),
            panel_densities: vec![[0.0; 4]; species],
            columns: vec![0.0; species],
            node_columns: vec![0.0; species],
            densities: vec![0.0; species],
            recorded: None,
            reuse: false,
        }
    }

    /// Keeps each whole ray's nodes and replays them for the next rays
    /// whose nodes lie at the same altitudes (see [`PanelMarch`]): for a
    /// march of many rays of one zenith angle from one eye.
    pub(crate) fn reuse_nodes(&mut self) {
        self.reuse = true;
    }

    /// Marches the ray from `start` (planet-centred, m) along the unit
    /// `direction` over the panels between consecutive `panel_ends` (m
    /// along the ray, increasing), calling `visit` at every node in order
    /// with the node, the columns from `start` to it (m, per species) and
    /// the relative densities there; `visit` stops the march by returning
    /// [`ControlFlow::Break`]. Afterwards [`PanelMarch::columns`] holds the
    /// columns of the panels marched whole.
    pub(crate) fn march<P: Borrow<DensityProfile>>(
        &mut self,
        profiles: &[P],
        ground_radius_m: f64,
        (start, direction): (Vector3, Vector3),
        panel_ends: &[f64],
        mut visit: impl FnMut(MarchNode, &[f64], &[f64]) -> ControlFlow<()>,
    ) {
        let species = profiles.len();
        let mut recording = None;
        if self.reuse {
            let key = RecordedNodes::key(start, direction, ground_radius_m);
            match self.recorded.take() {
                Some(recorded) if recorded.matches(&key, profiles, panel_ends) => {
                    self.replay(&recorded, (start, direction), species, visit);
                    self.recorded = Some(recorded);
                    return;
                }
                old => {
                    // Record this ray (in the old record's buffers).
                    let mut record = old.unwrap_or_default();
                    record.key = key;
                    record.ends.clear();
                    record.ends.extend_from_slice(panel_ends);
                    record.profiles.clear();
                    record
                        .profiles
                        .extend(profiles.iter().map(|p| p.borrow().clone()));
                    for buffer in [
                        &mut record.distances,
                        &mut record.weights,
                        &mut record.node_columns,
                        &mut record.densities,
                        &mut record.panel_columns,
                    ] {
                        buffer.clear();
                    }
                    record.panels.clear();
                    recording = Some(record);
                }
            }
        }
        self.columns.fill(0.0);
        for (panel, ends) in panel_ends.windows(2).enumerate() {
            let (centre, half) = (0.5 * (ends[0] + ends[1]), 0.5 * (ends[1] - ends[0]));
            let mut points = [Vector3::default(); 4];
            let mut distances = [0.0; 4];
            for (n, x) in GAUSS_NODES.iter().enumerate() {
                distances[n] = centre + half * x;
                points[n] = start + direction * distances[n];
                let altitude_m = points[n].length() - ground_radius_m;
                for (j, profile) in profiles.iter().enumerate() {
                    self.panel_densities[j][n] = profile.borrow().relative_density(altitude_m);
                }
            }
            if let Some(record) = recording.as_mut() {
                record.panel_columns.extend_from_slice(&self.columns);
            }
            for (n, point) in points.into_iter().enumerate() {
                for j in 0..species {
                    let inside: f64 = (0..4)
                        .map(|m| self.running_integral[n][m] * self.panel_densities[j][m])
                        .sum();
                    self.node_columns[j] = self.columns[j] + half * inside;
                    self.densities[j] = self.panel_densities[j][n];
                }
                let node = MarchNode {
                    point,
                    weight: half * GAUSS_WEIGHTS[n],
                    index: 4 * panel + n,
                    repeated: false,
                };
                if let Some(record) = recording.as_mut() {
                    record.distances.push(distances[n]);
                    record.weights.push(node.weight);
                    record.panels.push(panel);
                    record.node_columns.extend_from_slice(&self.node_columns);
                    record.densities.extend_from_slice(&self.densities);
                }
                if visit(node, &self.node_columns, &self.densities).is_break() {
                    // An unfinished record is not kept.
                    self.recorded = None;
                    return;
                }
            }
            for j in 0..species {
                let panel: f64 = (0..4)
                    .map(|m| GAUSS_WEIGHTS[m] * self.panel_densities[j][m])
                    .sum();
                self.columns[j] += half * panel;
            }
        }
        if let Some(mut record) = recording {
            record.panel_columns.extend_from_slice(&self.columns);
            self.recorded = Some(record);
        }
    }

    /// [`PanelMarch::march`] of a ray from `start` along `direction` from
    /// the nodes of `recorded` (which has the ray's altitudes).
    fn replay(
        &mut self,
        recorded: &RecordedNodes,
        (start, direction): (Vector3, Vector3),
        species: usize,
        mut visit: impl FnMut(MarchNode, &[f64], &[f64]) -> ControlFlow<()>,
    ) {
        for (n, (distance, weight)) in recorded.distances.iter().zip(&recorded.weights).enumerate()
        {
            let node = MarchNode {
                point: start + direction * *distance,
                weight: *weight,
                index: n,
                repeated: true,
            };
            let columns = &recorded.node_columns[n * species..][..species];
            let densities = &recorded.densities[n * species..][..species];
            if visit(node, columns, densities).is_break() {
                // The columns of the panels before this node's.
                let panel = recorded.panels[n];
                self.columns
                    .copy_from_slice(&recorded.panel_columns[panel * species..][..species]);
                return;
            }
        }
        let panels = recorded.panel_columns.len() / species.max(1);
        if species > 0 {
            self.columns
                .copy_from_slice(&recorded.panel_columns[(panels - 1) * species..][..species]);
        }
    }

    /// The columns of the last march, m per species: the whole ray's
    /// unless `visit` stopped it.
    pub(crate) fn columns(&self) -> &[f64] {
        &self.columns
    }
}

/// Number of panels of the exact column integrals that fill the table.
const TABLE_RAY_PANELS: usize = 16;

/// Columns from any point in the atmosphere to its top toward the sun,
/// tabulated (see the module docs). Points whose path to the sun hits the
/// ground are in the planet's shadow: `SunColumnTable::lookup_columns_to_sun`
/// reports them and leaves the columns alone.
#[derive(Debug, Clone)]
pub struct SunColumnTable {
    ground_radius_m: f64,
    top_radius_m: f64,
    altitude_nodes: usize,
    mu_nodes: usize,
    species: usize,
    /// Per species: interpolate ln(mean density) (smooth profiles), or
    /// the mean density itself (piecewise-linear layers: along paths that
    /// leave a layer near its top the column falls to zero quadratically,
    /// and its logarithm to -inf, which no linear blend follows).
    logarithmic: Vec<bool>,
    /// The mean relative density along the path to the top (column_m /
    /// d), index [(altitude * mu_nodes + mu) * species + s]: exp() of the
    /// logarithms the table is computed as, what the layers' lookups
    /// blend (four per lookup that would each take an exp) and what a
    /// smooth profile's lookup blends where a corner's is zero.
    mean_densities: Vec<f64>,
    /// What a lookup blends, laid out so that a cell's four corners lie
    /// together (one or two cache lines, where a table by node puts them
    /// in two places): per species ln(mean density), -inf where it is
    /// zero (`logarithmic`), or the mean density (the same bits as
    /// `mean_densities`), index [((altitude * mu_nodes + mu) * 2 + a) *
    /// species + s] for the altitude node `altitude` + a, a in {0, 1},
    /// `altitude` below `altitude_nodes` - 1.
    cell_corners: Vec<f64>,
    /// H = sqrt(R_top^2 - R^2), m ([`SunColumnTable::horizon_distance_m`]),
    /// and the altitude nodes' radii, m
    /// ([`SunColumnTable::radius_from_unit`] at each node): what every
    /// [`SunColumnTable::locate_radius`] would compute again, the same
    /// bits.
    horizon_distance_m: f64,
    node_radii_m: Vec<f64>,
}

impl SunColumnTable {
    /// Fills the table for these species' profiles: `altitude_nodes` x
    /// `mu_nodes` exact column integrals.
    #[cfg(test)]
    pub(crate) fn compute<P: Borrow<DensityProfile> + Sync>(
        profiles: &[P],
        ground_radius_m: f64,
        top_radius_m: f64,
        altitude_nodes: usize,
        mu_nodes: usize,
    ) -> SunColumnTable {
        let exact = vec![false; profiles.len()];
        SunColumnTable::compute_with_fast_exponentials(
            profiles,
            &exact,
            (ground_radius_m, top_radius_m),
            altitude_nodes,
            mu_nodes,
        )
    }

    /// `SunColumnTable::compute`, the exponential profiles marked in
    /// `fast` taking their densities along the table's rays from the
    /// vector exponential (within 2e-12 relative of `f64::exp`, far inside
    /// the table's interpolation error; `compute_columns_along_ray_fast`):
    /// with the banded gases and O2-O2, three of the four exponentials at
    /// each node, and the exponentials three quarters of the table's time.
    /// The other profiles' entries are the same bits as
    /// `SunColumnTable::compute`'s.
    pub(crate) fn compute_with_fast_exponentials<P: Borrow<DensityProfile> + Sync>(
        profiles: &[P],
        fast: &[bool],
        (ground_radius_m, top_radius_m): (f64, f64),
        altitude_nodes: usize,
        mu_nodes: usize,
    ) -> SunColumnTable {
        assert!(altitude_nodes >= 2 && mu_nodes >= 2);
        assert_eq!(fast.len(), profiles.len());
        let fast_scale_heights: Vec<Option<f64>> = profiles
            .iter()
            .zip(fast)
            .map(|(p, fast)| match p.borrow() {
                DensityProfile::Exponential { scale_height_m } if *fast => Some(*scale_height_m),
                _ => None,
            })
            .collect();
        let species = profiles.len();
        let corners = ProfileCorners::new(profiles, ground_radius_m, top_radius_m);
        let table = SunColumnTable {
            ground_radius_m,
            top_radius_m,
            altitude_nodes,
            mu_nodes,
            species,
            logarithmic: profiles
                .iter()
                .map(|p| !matches!(p.borrow(), DensityProfile::PiecewiseLinear(_)))
                .collect(),
            mean_densities: Vec::new(),
            cell_corners: Vec::new(),
            horizon_distance_m: ((top_radius_m - ground_radius_m)
                * (top_radius_m + ground_radius_m))
                .sqrt(),
            node_radii_m: Vec::new(),
        };
        let mut log_mean_densities = vec![0.0; altitude_nodes * mu_nodes * species];
        // One altitude row per task; each row is the same computation
        // whatever the thread count.
        crate::parallel::for_each_chunk_mut(
            &mut log_mean_densities,
            mu_nodes * species,
            |i, row| {
                let mut columns = vec![0.0; species];
                let (mut altitudes, mut scratch) = (Vec::new(), Vec::new());
                let mut ends = Vec::with_capacity(corners.most_panel_ends(TABLE_RAY_PANELS));
                let r = table.radius_from_unit(i as f64 / (altitude_nodes - 1) as f64);
                for j in 0..mu_nodes {
                    let mu = table.mu_from_unit(r, j as f64 / (mu_nodes - 1) as f64);
                    let origin = Vector3::new(0.0, 0.0, r);
                    let direction = Vector3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                    let length = crate::geometry::distance_to_top_of_atmosphere(
                        origin,
                        direction,
                        top_radius_m,
                    );
                    corners.fill_panel_ends(origin, direction, length, TABLE_RAY_PANELS, &mut ends);
                    compute_columns_along_ray_fast(
                        profiles,
                        &fast_scale_heights,
                        (ground_radius_m, origin, direction),
                        &ends,
                        &mut columns,
                        (&mut altitudes, &mut scratch),
                    );
                    for (k, profile) in profiles.iter().enumerate() {
                        // At the top looking up the path is empty: its mean
                        // density is the density there, the limit of column / d.
                        let mean_density = if length > 0.0 {
                            columns[k] / length
                        } else {
                            profile
                                .borrow()
                                .relative_density(top_radius_m - ground_radius_m)
                        };
                        row[j * species + k] = mean_density.ln();
                    }
                }
            },
        );
        let mean_densities: Vec<f64> = log_mean_densities.iter().map(|v| v.exp()).collect();
        let mut cell_corners = Vec::with_capacity(2 * log_mean_densities.len());
        for altitude in 0..altitude_nodes - 1 {
            for mu in 0..mu_nodes {
                for a in 0..2 {
                    let node = ((altitude + a) * mu_nodes + mu) * species;
                    cell_corners.extend((0..species).map(|k| {
                        if table.logarithmic[k] {
                            log_mean_densities[node + k]
                        } else {
                            mean_densities[node + k]
                        }
                    }));
                }
            }
        }
        let node_radii_m = (0..altitude_nodes)
            .map(|i| table.radius_from_unit(i as f64 / (altitude_nodes - 1) as f64))
            .collect();
        SunColumnTable {
            mean_densities,
            cell_corners,
            node_radii_m,
            ..table
        }
    }

    /// The table's (altitude, mu) node counts.
    pub(crate) fn node_counts(&self) -> (usize, usize) {
        (self.altitude_nodes, self.mu_nodes)
    }

    /// Bruneton's altitude coordinate: rho / H in [0, 1], rho = sqrt(r^2 - R^2),
    /// H = sqrt(R_top^2 - R^2).
    #[cfg(test)]
    fn unit_from_radius(&self, r: f64) -> f64 {
        let (ground, top) = (self.ground_radius_m, self.top_radius_m);
        let h = ((top - ground) * (top + ground)).sqrt();
        (((r - ground) * (r + ground)).max(0.0).sqrt() / h).clamp(0.0, 1.0)
    }

    fn radius_from_unit(&self, unit: f64) -> f64 {
        let (ground, top) = (self.ground_radius_m, self.top_radius_m);
        let rho = unit * ((top - ground) * (top + ground)).sqrt();
        (rho * rho + ground * ground).sqrt().min(top)
    }

    /// The zenith cosine at radius r of the mu coordinate `unit` (see
    /// [`SunColumnTable::lookup_columns_at_radius`]).
    fn mu_from_unit(&self, r: f64, unit: f64) -> f64 {
        let (ground, top) = (self.ground_radius_m, self.top_radius_m);
        let h = ((top - ground) * (top + ground)).sqrt();
        let rho = ((r - ground) * (r + ground)).max(0.0).sqrt();
        let (d_min, d_max) = (top - r, rho + h);
        let d = d_min + unit * (d_max - d_min);
        if d <= 0.0 {
            return 1.0;
        }
        ((h * h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
    }

    /// The columns (m) from a point at radius `r_m` to the top of the
    /// atmosphere along a direction with zenith cosine `mu`, interpolated.
    /// Returns false, and leaves `columns_m` alone, when that path hits the
    /// ground (the point is in the planet's shadow).
    pub(crate) fn lookup_columns_to_sun(&self, r_m: f64, mu: f64, columns_m: &mut [f64]) -> bool {
        self.lookup_columns_at_radius(&self.locate_radius(r_m), mu, columns_m)
    }

    /// The part of a lookup that depends on the radius alone: a point
    /// that is looked up toward many suns (the spherical first order's
    /// samples) locates its radius once.
    ///
    /// The node radii and H are kept in the table, and rho = sqrt(r^2 -
    /// R^2) taken once: the same values as computed here each time
    /// ([`SunColumnTable::unit_from_radius`], `radius_from_unit`; the
    /// test `the_located_radius_is_the_one_computed_anew`).
    pub(crate) fn locate_radius(&self, r_m: f64) -> SunColumnRadius {
        let ground = self.ground_radius_m;
        let r = r_m.clamp(ground, self.top_radius_m);
        let (top, h) = (self.top_radius_m, self.horizon_distance_m);
        let rho = ((r - ground) * (r + ground)).max(0.0).sqrt();
        let x = (rho / h).clamp(0.0, 1.0) * (self.altitude_nodes - 1) as f64;
        let i = (x as usize).min(self.altitude_nodes - 2);
        // Nodes are spaced in rho, but the weight between two altitude nodes
        // is linear in altitude: ln(mean density) of an exponential profile
        // is linear in altitude, and quadratic in rho.
        let (r0, r1) = (self.node_radii_m[i], self.node_radii_m[i + 1]);
        SunColumnRadius::new(r, (i, r0, r1), (top, rho, h))
    }

    /// The radius of the march node `node` and where it lies in the table:
    /// for a replayed node ([`MarchNode::repeated`]) what `cache` holds
    /// for its index, else computed and kept there.
    pub(crate) fn locate_node(
        &self,
        node: &MarchNode,
        cache: &mut Vec<LocatedNode>,
    ) -> LocatedNode {
        if node.repeated && node.index < cache.len() {
            return cache[node.index];
        }
        let radius_m = node.point.length();
        let located = LocatedNode {
            radius_m,
            located: self.locate_radius(radius_m),
        };
        if cache.len() <= node.index {
            cache.resize(node.index + 1, LocatedNode::default());
        }
        cache[node.index] = located;
        located
    }

    /// Whether the path from a located radius with zenith cosine `mu`
    /// hits the ground (the point is in the planet's shadow): the test
    /// that opens [`SunColumnTable::lookup_columns_at_radius`]
    /// (`ray_intersects_ground`, with r^2 from the located radius).
    #[inline(always)]
    pub(crate) fn is_shadowed(&self, at_radius: &SunColumnRadius, mu: f64) -> bool {
        let ground = self.ground_radius_m;
        mu < 0.0 && at_radius.r_squared * (1.0 - mu * mu) <= ground * ground
    }

    /// [`SunColumnTable::lookup_columns_to_sun`] at a located radius: the
    /// same operations in the same order, so the same columns bit for bit.
    /// The obviously correct form, one point at a time, that
    /// [`SunColumnTable::lookup_lit_columns`] is held to.
    pub(crate) fn lookup_columns_at_radius(
        &self,
        at_radius: &SunColumnRadius,
        mu: f64,
        columns_m: &mut [f64],
    ) -> bool {
        if self.is_shadowed(at_radius, mu) {
            return false;
        }
        let r = at_radius.r;
        // Bruneton's horizon-adapted coordinate: the distance d to the top
        // along mu (the path's length), mapped to [0, 1] between its
        // smallest (straight up) and largest (the ground's horizon) values.
        let length = crate::geometry::distance_to_top_boundary(r, mu, self.top_radius_m);
        let (d_min, d_max) = (at_radius.d_min, at_radius.d_max);
        let unit = if d_max > d_min {
            ((length - d_min) / (d_max - d_min)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let y = unit * (self.mu_nodes - 1) as f64;
        let (i, j) = (at_radius.altitude_node, (y as usize).min(self.mu_nodes - 2));
        let fx = at_radius.altitude_weight;
        let fy = y - j as f64;
        let s = self.species;
        let nodes = self.corner_nodes(i, j);
        // The same corners in `cell_corners`, in the same order.
        let cell = (i * self.mu_nodes + j) * 2 * s;
        let cell_nodes = [cell, cell + 2 * s, cell + s, cell + 3 * s];
        let weights = corner_weights(fx, fy);
        for (k, column) in columns_m.iter_mut().enumerate().take(s) {
            let corners = cell_nodes.map(|n| self.cell_corners[n + k]);
            let mean_density = if !self.logarithmic[k] {
                // A layer profile: interpolate the density itself (the
                // corners' exp() kept in the table).
                blend(corners, weights)
            } else if corners.iter().all(|v| v.is_finite()) {
                // (Below e^-708 ~ 3e-308 the table's own exponential
                // clamps: a column of zero either way.)
                super::vector_exp::exp(blend(corners, weights))
            } else {
                // A path with no density at a corner: the densities.
                blend(nodes.map(|n| self.mean_densities[n + k]), weights)
            };
            *column = mean_density * length;
        }
        true
    }

    /// The four corners of the cell (altitude node `i`, mu node `j`) in
    /// `mean_densities`, their first species, in the blend's order:
    /// (i, j), (i, j + 1), (i + 1, j), (i + 1, j + 1).
    #[inline(always)]
    fn corner_nodes(&self, i: usize, j: usize) -> [usize; 4] {
        let corner = |ii: usize, jj: usize| (ii * self.mu_nodes + jj) * self.species;
        [
            corner(i, j),
            corner(i, j + 1),
            corner(i + 1, j),
            corner(i + 1, j + 1),
        ]
    }

    /// [`SunColumnTable::lookup_columns_at_radius`] of many sunlit points
    /// (none [`SunColumnTable::is_shadowed`]) at once: point `n`'s located
    /// radius and zenith cosine in `points[n]`, its columns (m) into
    /// `columns_m[n * species..][..species]`. The lookups of a ray's nodes
    /// are independent of one another; taken four at a time, each step
    /// of the four (the path's length, its cell and weights, each
    /// species' blend and exponential) is written on four lanes, compiled
    /// for AVX2 where the CPU has it (perf annotate shows most of it
    /// scalar: the four lanes' independent chains overlap). Every lane does the
    /// single lookup's operations in its order, so the columns are the
    /// same bits (the test `the_lookups_four_at_a_time_are_the_single_lookups`).
    pub(crate) fn lookup_lit_columns(
        &self,
        points: &[(SunColumnRadius, f64)],
        columns_m: &mut [f64],
    ) {
        assert_eq!(columns_m.len(), points.len() * self.species);
        #[cfg(target_arch = "x86_64")]
        if super::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.lookup_lit_columns_avx2(points, columns_m) };
            return;
        }
        self.lookup_lit_columns_portable(points, columns_m);
    }

    /// [`SunColumnTable::lookup_lit_columns`] compiled for AVX2 (4 lanes
    /// of f64; the same operations per lane, so the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn lookup_lit_columns_avx2(&self, points: &[(SunColumnRadius, f64)], columns_m: &mut [f64]) {
        self.lookup_lit_columns_portable(points, columns_m);
    }

    /// [`SunColumnTable::lookup_lit_columns`] in the target's baseline
    /// instructions: four points at a time, the last one to three one by
    /// one ([`SunColumnTable::lookup_columns_at_radius`]).
    #[inline(always)]
    fn lookup_lit_columns_portable(
        &self,
        points: &[(SunColumnRadius, f64)],
        columns_m: &mut [f64],
    ) {
        let s = self.species;
        if s == 0 {
            return;
        }
        let mut groups = points.chunks_exact(4);
        let mut outs = columns_m.chunks_exact_mut(4 * s);
        for (group, out) in (&mut groups).zip(&mut outs) {
            self.lookup_four(group.try_into().expect("four points"), out);
        }
        let tail = groups.remainder().iter();
        for ((at_radius, mu), out) in tail.zip(outs.into_remainder().chunks_exact_mut(s)) {
            let lit = self.lookup_columns_at_radius(at_radius, *mu, out);
            debug_assert!(lit, "a shadowed point among the lit ones");
        }
    }

    /// Four lit points' columns into `columns_m` ([lane * species + k]):
    /// [`SunColumnTable::lookup_columns_at_radius`] lane by lane, step by
    /// step.
    #[inline(always)]
    fn lookup_four(&self, points: &[(SunColumnRadius, f64); 4], columns_m: &mut [f64]) {
        let s = self.species;
        let last_cell = self.mu_nodes - 2;
        let scale = (self.mu_nodes - 1) as f64;
        let mut length = [0.0; 4];
        let mut weights = [[0.0; 4]; 4];
        let mut cells = [0usize; 4];
        let mut cell_indices = [(0usize, 0usize); 4];
        for l in 0..4 {
            let (at_radius, mu) = (&points[l].0, points[l].1);
            length[l] =
                crate::geometry::distance_to_top_boundary(at_radius.r, mu, self.top_radius_m);
            let (d_min, d_max) = (at_radius.d_min, at_radius.d_max);
            let unit = if d_max > d_min {
                ((length[l] - d_min) / (d_max - d_min)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let y = unit * scale;
            let j = (y as usize).min(last_cell);
            let i = at_radius.altitude_node;
            weights[l] = corner_weights(at_radius.altitude_weight, y - j as f64);
            cells[l] = (i * self.mu_nodes + j) * 2 * s;
            cell_indices[l] = (i, j);
        }
        for k in 0..s {
            let mut blended = [0.0; 4];
            let mut finite = [true; 4];
            for l in 0..4 {
                let cell = cells[l];
                let corners =
                    [cell, cell + 2 * s, cell + s, cell + 3 * s].map(|n| self.cell_corners[n + k]);
                blended[l] = blend(corners, weights[l]);
                finite[l] = corners.iter().all(|v| v.is_finite());
            }
            if self.logarithmic[k] {
                let mut exps = blended;
                for v in &mut exps {
                    *v = super::vector_exp::exp(*v);
                }
                for l in 0..4 {
                    let mean_density = if finite[l] {
                        exps[l]
                    } else {
                        let (i, j) = cell_indices[l];
                        let nodes = self.corner_nodes(i, j);
                        blend(nodes.map(|n| self.mean_densities[n + k]), weights[l])
                    };
                    columns_m[l * s + k] = mean_density * length[l];
                }
            } else {
                for l in 0..4 {
                    columns_m[l * s + k] = blended[l] * length[l];
                }
            }
        }
    }

    /// [`SunColumnTable::locate_radius`] computed from the table's axes
    /// alone, nothing kept (the slow path it is held to).
    #[cfg(test)]
    fn locate_radius_anew(&self, r_m: f64) -> SunColumnRadius {
        let ground = self.ground_radius_m;
        let r = r_m.clamp(ground, self.top_radius_m);
        let x = self.unit_from_radius(r) * (self.altitude_nodes - 1) as f64;
        let i = (x as usize).min(self.altitude_nodes - 2);
        let denominator = (self.altitude_nodes - 1) as f64;
        let (r0, r1) = (
            self.radius_from_unit(i as f64 / denominator),
            self.radius_from_unit((i + 1) as f64 / denominator),
        );
        let top = self.top_radius_m;
        let h = ((top - ground) * (top + ground)).sqrt();
        let rho = ((r - ground) * (r + ground)).max(0.0).sqrt();
        SunColumnRadius::new(r, (i, r0, r1), (top, rho, h))
    }
}

impl SunColumnRadius {
    /// The radius `r` (m) in the cell above altitude node `i`, between the
    /// node radii `r0` and `r1`, in an atmosphere of top radius `top` (m),
    /// with rho = sqrt(r^2 - R^2) and H (m).
    fn new(r: f64, (i, r0, r1): (usize, f64, f64), (top, rho, h): (f64, f64, f64)) -> Self {
        SunColumnRadius {
            r,
            r_squared: r * r,
            altitude_node: i,
            altitude_weight: ((r - r0) / (r1 - r0)).clamp(0.0, 1.0),
            d_min: top - r,
            d_max: rho + h,
        }
    }
}

/// The bilinear weights of a cell's corners (i, j), (i, j + 1), (i + 1,
/// j), (i + 1, j + 1) at (fx, fy) in it.
#[inline(always)]
fn corner_weights(fx: f64, fy: f64) -> [f64; 4] {
    [
        (1.0 - fx) * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * (1.0 - fy),
        fx * fy,
    ]
}

/// The corners' values blended with their weights (the sum in corner
/// order).
#[inline(always)]
fn blend(corners: [f64; 4], weights: [f64; 4]) -> f64 {
    corners.iter().zip(weights).map(|(c, w)| c * w).sum::<f64>()
}

/// A radius located in a [`SunColumnTable`]
/// ([`SunColumnTable::locate_radius`]): the radius clamped to the
/// atmosphere and its square, the lower altitude node and the weight
/// toward the next, and the shortest (straight up) and longest (the
/// ground's horizon) distances to the top from it, m.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SunColumnRadius {
    r: f64,
    r_squared: f64,
    altitude_node: usize,
    altitude_weight: f64,
    d_min: f64,
    d_max: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f64 = 6_360e3;
    const TOP: f64 = 6_460e3;

    fn exponential(h: f64) -> DensityProfile {
        DensityProfile::Exponential { scale_height_m: h }
    }

    /// Columns along a ray through the test atmosphere (ground R, top
    /// TOP), cut at the profiles' corners.
    fn columns_along_ray(
        profiles: &[&DensityProfile],
        origin: Vector3,
        direction: Vector3,
        length: f64,
        panels: usize,
        columns: &mut [f64],
    ) {
        let mut ends = Vec::new();
        ProfileCorners::new(profiles, R, TOP)
            .fill_panel_ends(origin, direction, length, panels, &mut ends);
        compute_columns_along_ray(profiles, R, origin, direction, &ends, columns);
    }

    #[test]
    fn vertical_column_of_an_exponential_is_closed_form() {
        let air = exponential(8000.0);
        let mut c = [0.0];
        let up = Vector3::new(0.0, 0.0, 1.0);
        columns_along_ray(&[&air], Vector3::new(0.0, 0.0, R), up, 100e3, 32, &mut c);
        let exact = 8000.0 * (1.0 - (-100e3f64 / 8000.0).exp());
        assert!((c[0] / exact - 1.0).abs() < 1e-12, "{} vs {exact}", c[0]);
    }

    /// The march up a vertical ray through an exponential atmosphere: at
    /// every node the column from the start is the closed form H (1 -
    /// e^(-s / H)) (the running integral of each panel's cubic), the nodes'
    /// weights sum to the ray's length, the whole ray's columns are the
    /// Gauss columns of `compute_columns_along_ray`, and a break stops it.
    #[test]
    fn the_panel_march_carries_the_columns_to_every_node() {
        let air = exponential(8000.0);
        let up = Vector3::new(0.0, 0.0, 1.0);
        let start = Vector3::new(0.0, 0.0, R);
        let mut ends = Vec::new();
        ProfileCorners::default().fill_panel_ends(start, up, 100e3, 32, &mut ends);
        let mut march = PanelMarch::new(1);
        let (mut nodes, mut length, mut worst) = (0, 0.0, 0.0f64);
        march.march(
            &[&air],
            R,
            (start, up),
            &ends,
            |node, columns, densities| {
                let s = node.point.length() - R;
                let exact = 8000.0 * (1.0 - (-s / 8000.0).exp());
                worst = worst.max((columns[0] / exact - 1.0).abs());
                assert_eq!(densities[0], air.relative_density(s));
                nodes += 1;
                length += node.weight;
                ControlFlow::Continue(())
            },
        );
        assert_eq!(nodes, 4 * 32);
        assert!((length / 100e3 - 1.0).abs() < 1e-12, "{length}");
        assert!(worst < 1e-6, "{worst}");
        let mut whole = [0.0];
        compute_columns_along_ray(&[&air], R, start, up, &ends, &mut whole);
        assert!((march.columns()[0] / whole[0] - 1.0).abs() < 1e-12);
        let mut visited = 0;
        march.march(&[&air], R, (start, up), &ends, |_, _, _| {
            visited += 1;
            if visited == 5 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        assert_eq!(visited, 5);
    }

    /// Nodes replayed for a ray of the same zenith angle from the same eye
    /// ([`PanelMarch::reuse_nodes`]) against a march of that ray: the
    /// points and weights within 1e-13, the columns, densities and
    /// whole-ray columns within 1e-11 (rounding: the two rays' panel ends
    /// and radii differ in their last bits, a nanometre, and the haze's
    /// density changes by 1e-12 in a nanometre); a ray of another zenith
    /// angle is marched anew, and so is one with other panel ends.
    #[test]
    fn replayed_nodes_are_the_march_s() {
        let air = exponential(8000.0);
        let haze = exponential(1200.0);
        let profiles = [&air, &haze];
        let eye = Vector3::new(0.0, 0.0, R + 2000.0);
        let corners = ProfileCorners::new(&profiles, R, TOP);
        let ray = |zenith_deg: f64, azimuth_deg: f64| {
            let (z, a) = (zenith_deg.to_radians(), azimuth_deg.to_radians());
            let d = Vector3::new(z.sin() * a.cos(), z.sin() * a.sin(), z.cos());
            let length = crate::geometry::distance_to_top_of_atmosphere(eye, d, TOP);
            let mut ends = Vec::new();
            corners.fill_panel_ends(eye, d, length, 16, &mut ends);
            (d, ends)
        };
        type Nodes = Vec<(MarchNode, Vec<f64>, Vec<f64>)>;
        let run = |march: &mut PanelMarch, (d, ends): &(Vector3, Vec<f64>)| -> (Nodes, Vec<f64>) {
            let mut nodes = Vec::new();
            march.march(&profiles, R, (eye, *d), ends, |node, columns, densities| {
                nodes.push((node, columns.to_vec(), densities.to_vec()));
                ControlFlow::Continue(())
            });
            (nodes, march.columns().to_vec())
        };
        let mut reusing = PanelMarch::new(2);
        reusing.reuse_nodes();
        let (first, _) = run(&mut reusing, &ray(87.0, 0.0));
        assert!(first.iter().all(|(node, _, _)| !node.repeated));
        for azimuth_deg in [30.0, 97.0, 180.0] {
            let other = ray(87.0, azimuth_deg);
            let (replayed, replayed_columns) = run(&mut reusing, &other);
            let (marched, marched_columns) = run(&mut PanelMarch::new(2), &other);
            assert_eq!(replayed.len(), marched.len());
            let close = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .all(|(a, b)| (a - b).abs() <= 1e-11 * a.abs().max(b.abs()))
            };
            for ((a, a_columns, a_densities), (b, b_columns, b_densities)) in
                replayed.iter().zip(&marched)
            {
                assert!(a.repeated && !b.repeated);
                assert_eq!(a.index, b.index);
                assert!(close(&[a.weight], &[b.weight]));
                assert!((a.point - b.point).length() <= 1e-13 * b.point.length());
                assert!(close(a_columns, b_columns), "{a_columns:?} {b_columns:?}");
                assert!(close(a_densities, b_densities));
            }
            assert!(close(&replayed_columns, &marched_columns));
        }
        // Another zenith angle, and the same one with a cut added.
        let (other_zenith, _) = run(&mut reusing, &ray(60.0, 0.0));
        assert!(other_zenith.iter().all(|(node, _, _)| !node.repeated));
        let (d, mut ends) = ray(60.0, 45.0);
        ends.insert(3, 0.5 * (ends[2] + ends[3]));
        let (cut, _) = run(&mut reusing, &(d, ends));
        assert!(cut.iter().all(|(node, _, _)| !node.repeated));
    }

    /// The lookup's cells hold their corners' values: for every cell and
    /// species, the node table's mean density (a layer profile) or its
    /// logarithm (a smooth profile, whose exp() is the node table's bits).
    #[test]
    fn the_cells_hold_their_corners() {
        use crate::atmosphere::ProfileTable;
        let tent =
            ProfileTable::new(vec![10e3, 25e3, 40e3], vec![0.0, 1.0, 0.0], false, "tent").unwrap();
        let profiles = [exponential(8000.0), DensityProfile::PiecewiseLinear(tent)];
        let (altitudes, mus) = (7, 11);
        let table = SunColumnTable::compute(&profiles, R, TOP, altitudes, mus);
        assert_eq!(table.logarithmic, [true, false]);
        assert_eq!(table.cell_corners.len(), (altitudes - 1) * mus * 2 * 2);
        for i in 0..altitudes - 1 {
            for j in 0..mus {
                for a in 0..2 {
                    for k in 0..2 {
                        let cell = table.cell_corners[((i * mus + j) * 2 + a) * 2 + k];
                        let node = table.mean_densities[((i + a) * mus + j) * 2 + k];
                        let value = if k == 0 { cell.exp() } else { cell };
                        assert_eq!(value.to_bits(), node.to_bits(), "{i} {j} {a} {k}");
                    }
                }
            }
        }
    }

    /// The lookups of many lit points four at a time
    /// ([`SunColumnTable::lookup_lit_columns`], in AVX2's registers where
    /// the CPU has them, and in the baseline instructions) are the single
    /// lookups bit for bit: for an exponential profile (the logarithms'
    /// blend and its exponential), a tent layer (the densities' blend), and
    /// cells with a corner of no density (the densities' fallback, a
    /// corner's logarithm set to -inf), at points across the atmosphere
    /// and every sun cosine that is lit, on the nodes, the ground and the
    /// top, in counts that leave one to three points after the fours.
    #[test]
    fn the_lookups_four_at_a_time_are_the_single_lookups() {
        use crate::atmosphere::ProfileTable;
        let tent =
            ProfileTable::new(vec![10e3, 25e3, 40e3], vec![0.0, 1.0, 0.0], false, "tent").unwrap();
        let profiles = [
            exponential(8000.0),
            DensityProfile::PiecewiseLinear(tent),
            exponential(1200.0),
        ];
        let (altitudes, mus) = (16, 32);
        let mut table = SunColumnTable::compute(&profiles, R, TOP, altitudes, mus);
        let unmodified = table.clone();
        // Cells with a corner of no density (species 2).
        for (i, j) in [(0, 0), (3, 7), (9, 31)] {
            let node = (i * mus + j) * 3 + 2;
            table.mean_densities[node] = 0.0;
            if i < altitudes - 1 {
                table.cell_corners[((i * mus + j) * 2) * 3 + 2] = f64::NEG_INFINITY;
            }
            if i > 0 {
                table.cell_corners[(((i - 1) * mus + j) * 2 + 1) * 3 + 2] = f64::NEG_INFINITY;
            }
        }
        let mut points = Vec::new();
        let mut radii: Vec<f64> = (0..=60)
            .map(|i| R + (TOP - R) * (i as f64 / 60.0).powi(2))
            .collect();
        radii.extend(table.node_radii_m.iter().copied());
        radii.extend([R - 1.0, TOP + 1.0, R + 1e-9]);
        for r in radii {
            let located = table.locate_radius(r);
            for k in 0..=80 {
                let mu = -1.0 + 2.0 * (k as f64 / 80.0).powf(0.7);
                if !table.is_shadowed(&located, mu) {
                    points.push((located, mu));
                }
            }
            let horizon = -((r - R).max(0.0) * (r + R)).sqrt() / r;
            for mu in [horizon, horizon + 1e-9, 0.0, 1.0] {
                if !table.is_shadowed(&located, mu) {
                    points.push((located, mu));
                }
            }
        }
        let first_fallback = points.len();
        for (i, j) in [(0, 0), (3, 7)] {
            let r = table.node_radii_m[i] + 1.0;
            let located = table.locate_radius(r);
            let (d_min, d_max) = (located.d_min, located.d_max);
            let d = d_min + (d_max - d_min) * (j as f64 + 0.5) / (mus - 1) as f64;
            let h = table.horizon_distance_m;
            let rho = ((r - R) * (r + R)).sqrt();
            let mu = (h * h - rho * rho - d * d) / (2.0 * r * d);
            points.push((located, mu));
        }
        assert!(points.len() > 4000, "{}", points.len());
        let s = profiles.len();
        let mut single = vec![0.0; points.len() * s];
        for ((located, mu), out) in points.iter().zip(single.chunks_exact_mut(s)) {
            assert!(table.lookup_columns_at_radius(located, *mu, out));
        }
        assert!(single.iter().all(|c| c.is_finite() && *c >= 0.0));
        // The points put in the cells with a corner of no density take
        // the densities' blend: a column a fraction of the unmodified
        // table's (not the exponential of -inf, 1e-308 m).
        for (n, (located, mu)) in points.iter().enumerate().skip(first_fallback) {
            let mut columns = [0.0; 3];
            assert!(unmodified.lookup_columns_at_radius(located, *mu, &mut columns));
            let fallback = single[n * s + 2];
            assert!(
                fallback != columns[2] && fallback > 0.1 * columns[2],
                "{fallback} {}",
                columns[2]
            );
        }
        for count in [points.len(), points.len() - 1, points.len() - 2, 3, 1, 0] {
            let bits = |v: &[f64]| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
            let mut wide = vec![0.0; count * s];
            table.lookup_lit_columns(&points[..count], &mut wide);
            assert_eq!(bits(&wide), bits(&single[..count * s]), "{count}");
            let mut portable = vec![0.0; count * s];
            table.lookup_lit_columns_portable(&points[..count], &mut portable);
            assert_eq!(bits(&portable), bits(&single[..count * s]), "{count}");
        }
    }

    /// The radius located with the table's kept node radii and H is the
    /// one located from the axes anew, field for field and bit for bit, at
    /// radii across the atmosphere, on its nodes, and beyond its bounds.
    #[test]
    fn the_located_radius_is_the_one_computed_anew() {
        let profiles = [exponential(8000.0), exponential(1200.0)];
        let table = SunColumnTable::compute(&profiles, R, TOP, 64, 32);
        let mut radii: Vec<f64> = (0..=20_000)
            .map(|i| R + (TOP - R) * (i as f64 / 20_000.0).powi(2))
            .collect();
        radii.extend(table.node_radii_m.iter().copied());
        radii.extend([R - 1.0, R, TOP, TOP + 1e3, R + 1e-9, TOP - 1e-9]);
        for r in radii {
            let (kept, anew) = (table.locate_radius(r), table.locate_radius_anew(r));
            let bits = |a: &SunColumnRadius| {
                [
                    a.r,
                    a.r_squared,
                    a.altitude_weight,
                    a.d_min,
                    a.d_max,
                    a.altitude_node as f64,
                ]
                .map(f64::to_bits)
            };
            assert_eq!(bits(&kept), bits(&anew), "{r}");
        }
    }

    /// A tent layer 10-40 km peaking at 25 km: vertically its column is
    /// exactly its half width, which 4-point Gauss panels reproduce only
    /// when cut at the corners; along slant rays the cut integral matches
    /// a fine midpoint sum.
    #[test]
    fn columns_of_a_tent_layer_are_exact_when_cut_at_its_corners() {
        use crate::atmosphere::ProfileTable;
        let table =
            ProfileTable::new(vec![10e3, 25e3, 40e3], vec![0.0, 1.0, 0.0], false, "tent").unwrap();
        let tent = DensityProfile::PiecewiseLinear(table);
        let origin = Vector3::new(0.0, 0.0, R);
        let up = Vector3::new(0.0, 0.0, 1.0);
        let mut cut = [0.0];
        columns_along_ray(&[&tent], origin, up, TOP - R, 16, &mut cut);
        assert!((cut[0] / 15e3 - 1.0).abs() < 1e-12, "{}", cut[0]);
        let mut ends = Vec::new();
        ProfileCorners::default().fill_panel_ends(origin, up, TOP - R, 16, &mut ends);
        let mut uncut = [0.0];
        compute_columns_along_ray(&[&tent], R, origin, up, &ends, &mut uncut);
        // Without the cuts: 2.6e-4 off.
        assert!((uncut[0] / 15e3 - 1.0).abs() > 1e-4, "uncut {}", uncut[0]);
        for elevation_deg in [2.0f64, 10.0, 45.0] {
            let el = elevation_deg.to_radians();
            let d = Vector3::new(el.cos(), 0.0, el.sin());
            let length = crate::geometry::distance_to_top_of_atmosphere(origin, d, TOP);
            let mut fast = [0.0];
            columns_along_ray(&[&tent], origin, d, length, 16, &mut fast);
            let n = 400_000;
            let step = length / n as f64;
            let slow: f64 = (0..n)
                .map(|i| {
                    let p = origin + d * ((i as f64 + 0.5) * step);
                    step * tent.relative_density(p.length() - R)
                })
                .sum();
            assert!(
                (fast[0] / slow - 1.0).abs() < 1e-8,
                "{elevation_deg} deg: {} vs {slow}",
                fast[0]
            );
        }
    }

    #[test]
    fn panels_tile_the_ray_in_every_case() {
        for (tangent, length) in [
            (-5.0, 100.0),
            (0.0, 100.0),
            (30.0, 100.0),
            (150.0, 100.0),
            (100.0, 100.0),
        ] {
            for panels in [1, 2, 3, 16] {
                let mut end = 0.0;
                for k in 0..panels {
                    let (a, b) = ray_panel(tangent, length, panels, k);
                    assert!(
                        (a - end).abs() < 1e-9 && b >= a,
                        "{tangent} {length} {panels} {k}: {a} {b} after {end}"
                    );
                    end = b;
                }
                assert!((end - length).abs() < 1e-9);
            }
        }
    }

    /// The slant column through the limb, against a brute-force trapezoid.
    #[test]
    fn grazing_columns_match_brute_force() {
        let profiles = [exponential(8000.0), exponential(1200.0)];
        let refs: Vec<&DensityProfile> = profiles.iter().collect();
        for (altitude, elevation_deg) in [
            (0.0, 0.0),
            (0.0, 2.0),
            (5e3, -1.5),
            (20e3, -3.0),
            (1e3, 30.0),
        ] {
            let origin = Vector3::new(0.0, 0.0, R + altitude);
            let el: f64 = f64::to_radians(elevation_deg);
            let d = Vector3::new(el.cos(), 0.0, el.sin());
            let length = crate::geometry::distance_to_top_of_atmosphere(origin, d, TOP);
            if crate::geometry::planet_sphere::distance_to_ground(origin, d, R).is_some() {
                continue;
            }
            let mut fast = [0.0; 2];
            columns_along_ray(&refs, origin, d, length, 32, &mut fast);
            let n = 400_000;
            let step = length / n as f64;
            let mut slow = [0.0; 2];
            for i in 0..n {
                let p = origin + d * ((i as f64 + 0.5) * step);
                for (s, prof) in slow.iter_mut().zip(&profiles) {
                    *s += prof.relative_density(p.length() - R) * step;
                }
            }
            for k in 0..2 {
                assert!(
                    (fast[k] / slow[k] - 1.0).abs() < 2e-6,
                    "h {altitude} el {elevation_deg} species {k}: {} vs {}",
                    fast[k],
                    slow[k]
                );
            }
        }
    }

    /// A table whose exponential absorbers take the vector exponential
    /// (`compute_with_fast_exponentials`) keeps the other profiles' entries
    /// bit for bit and the fast ones within 1e-11 relative of the exact
    /// table's (the exponential's 2e-12 through a 4-point sum).
    #[test]
    fn fast_exponentials_move_only_their_own_entries_and_by_rounding() {
        let profiles = [
            exponential(8435.0),
            DensityProfile::tent(25e3, 15e3, "ozone").unwrap(),
            exponential(2000.0),
            exponential(8000.0),
            exponential(4217.5),
        ];
        let exact = SunColumnTable::compute(&profiles, R, TOP, 24, 48);
        let fast = [false, false, true, true, true];
        let table =
            SunColumnTable::compute_with_fast_exponentials(&profiles, &fast, (R, TOP), 24, 48);
        let s = profiles.len();
        let mut worst: f64 = 0.0;
        for (n, (a, b)) in exact
            .mean_densities
            .iter()
            .zip(&table.mean_densities)
            .enumerate()
        {
            if fast[n % s] {
                worst = worst.max(((a - b) / a).abs());
            } else {
                assert_eq!(a.to_bits(), b.to_bits(), "entry {n}");
            }
        }
        assert!(worst > 0.0 && worst < 1e-11, "{worst:e}");
    }

    /// The table against exact integrals at points between its nodes, for
    /// Earth-like air (8 km) and aerosol (1.2 km). Columns below 1 m are
    /// skipped: their optical depth is below 1e-3 for any coefficient
    /// under 1e-3 m^-1, so their relative error does not matter.
    #[test]
    fn table_matches_exact_columns() {
        let profiles = [exponential(8000.0), exponential(1200.0)];
        let refs: Vec<&DensityProfile> = profiles.iter().collect();
        let table = SunColumnTable::compute(&refs, R, TOP, 128, 256);
        let (mut worst_grazing, mut worst_above_3_deg): (f64, f64) = (0.0, 0.0);
        for i in 0..40 {
            for j in 0..40 {
                let altitude = 100e3 * ((i as f64 + 0.37) / 40.0).powi(2);
                let r = R + altitude;
                let horizon_mu = -((r - R) * (r + R)).sqrt() / r;
                let mu = horizon_mu + (1.0 - horizon_mu) * ((j as f64 + 0.5) / 40.0).powi(2) + 1e-6;
                let mut exact = [0.0; 2];
                let origin = Vector3::new(0.0, 0.0, r);
                let d = Vector3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let length = crate::geometry::distance_to_top_of_atmosphere(origin, d, TOP);
                columns_along_ray(&refs, origin, d, length, 64, &mut exact);
                let mut looked_up = [0.0; 2];
                assert!(table.lookup_columns_to_sun(r, mu, &mut looked_up));
                for k in 0..2 {
                    if exact[k] < 1.0 {
                        continue;
                    }
                    let error = (looked_up[k] / exact[k] - 1.0).abs();
                    if mu >= 3f64.to_radians().sin() {
                        worst_above_3_deg = worst_above_3_deg.max(error);
                    } else {
                        worst_grazing = worst_grazing.max(error);
                    }
                }
            }
        }
        // Measured: 7.1e-4 and 3.4e-3 (the grazing worst case is a sun on
        // the horizon seen from 9 m above the ground, through 1e5 m of aerosol).
        assert!(
            worst_above_3_deg < 1e-3,
            "sun above 3 deg: worst relative column error {worst_above_3_deg}"
        );
        assert!(
            worst_grazing < 4e-3,
            "grazing sun: worst relative column error {worst_grazing}"
        );
    }

    #[test]
    fn shadowed_points_are_reported() {
        let air = exponential(8000.0);
        let table = SunColumnTable::compute(&[&air], R, TOP, 16, 16);
        let mut c = [7.0];
        assert!(!table.lookup_columns_to_sun(R + 1e3, -0.2, &mut c));
        assert_eq!(c[0], 7.0);
        assert!(table.lookup_columns_to_sun(R + 50e3, -0.1, &mut c));
    }
}
