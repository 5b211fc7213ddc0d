//! Single scattering: sunlight scattered once toward the eye (the paper's
//! §4, eq. 4-5, as corrected in `NOTES.md`).
//!
//! For a view ray from the eye x0 in direction w, with sun direction s
//! (unit vector toward the sun) and scattering angle theta, cos theta = w.s:
//!
//! ```text
//! L(lambda) = integral_0^S T(x0, x) sum_j beta_sca,j(x, lambda) p_j(theta, lambda)
//!                          E_sun(lambda) T_sun(x, lambda) ds        (eq. 5)
//!           + [ray ends on the ground] T(x0, x_g) albedo(lambda)/pi E_sun(lambda)
//!                          mu_s(x_g) T_sun(x_g, lambda)
//! ```
//!
//! T is the extinction transmittance (Beer-Lambert, exp of minus the
//! optical depth; absorption included, unlike the paper), T_sun is the
//! transmittance from x to the top of the atmosphere toward the sun, and 0
//! when that path hits the ground (the planet's shadow). Radiance is in
//! W m^-2 sr^-1 nm^-1 when E_sun is in W m^-2 nm^-1. The second line is the
//! Lambertian ground lit directly by the sun (zero for a black ground); it
//! keeps the ground below the horizon from being black in images. The sun
//! is a point (parallel rays) for the sky; its disc is drawn separately.
//!
//! Two ways to compute it, kept side by side (the RustFFT habit):
//! - the **reference path**, [`SingleScatteringScene::compute_radiance_reference`]:
//!   the paper's method: a uniform midpoint march along the view ray, and at
//!   every sample a second uniform march toward the sun. Obviously right,
//!   second-order in the step, slow.
//! - the **fast path**, [`SingleScatteringScene::compute_radiance`]: with
//!   parallel sun rays theta is the same along the whole view ray, so the
//!   phase functions come out of the integral:
//!   L = E sum_j beta_sca,j p_j(theta) I_j with
//!   I_j(lambda) = integral rho_j(x) T(x0, x) T_sun(x) ds (m). Every optical
//!   depth is sum_j beta_ext,j(lambda) column_j, so the march integrates
//!   one geometric column per species, not one per wavelength. The view ray
//!   is cut into Gauss-Legendre panels that crowd toward its start and its
//!   lowest point (`super::optical_column::ray_panel`), at the
//!   corners of piecewise-linear profiles ([`ProfileCorners`]) and where it
//!   enters or leaves the planet's shadow (`add_shadow_crossings`); the column back to
//!   the eye at each node comes from the same density samples
//!   (`super::quadrature::running_integral_matrix`). Columns toward the
//!   sun are exact integrals ([`SunColumns::Exact`]) or a table
//!   ([`SunColumns::Table`]) for images; from the table, a ray's sunlit
//!   nodes are looked up together after the march
//!   (`SunColumnTable::lookup_lit_columns`, the same bits as one by one).

use std::borrow::Borrow;
use std::ops::ControlFlow;
use std::sync::{Arc, Mutex};

use super::multiple_scattering::{SunFreeParts, ViewHarmonicsCache};
use super::optical_column::{
    LocatedNode, MarchNode, PanelMarch, ProfileCorners, SunColumnRadius, SunColumnTable,
    compute_columns_along_ray,
};
use super::vector_exp::exp_neg_in_place;
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::atmosphere::{Atmosphere, AtmosphereOptics, DensityProfile};
use crate::error::{Error, Result};
use crate::geometry::{Vector3, direction_from_elevation_azimuth, segment_in_atmosphere};
use crate::spectrum::{SampledSpectrum, WavelengthGrid};

/// Gauss panels along a view ray in the fast path.
pub(crate) const VIEW_RAY_PANELS: usize = 16;
/// Gauss panels along each exact path toward the sun.
pub(crate) const SUN_RAY_PANELS: usize = 12;

/// Adds to the panel ends `ends` (increasing, over [0, `length_m`]) of the
/// ray from `origin` along the unit `direction` the distances where it
/// enters or leaves the planet's shadow for the sun in the unit direction
/// `sun`: the cylinder of radius `ground_radius_m` behind the planet,
/// |x|^2 - (x.s)^2 = R^2 with x.s < 0 (a quadratic in the distance). Why:
/// the in-scattered light jumps there (from the sunlight grazing the
/// ground to none), and a Gauss panel across a jump converges slowly.
/// Measured in deep twilight (us-standard-1976-rayleigh, sun -10, 680 nm,
/// against the path tracer's single scattering, 1 000 000 paths): the
/// zenith -1.6 % (+-0.2) and 20 degrees up toward the sun +2.1 % (+-0.2)
/// without the cuts.
fn add_shadow_crossings(
    origin: Vector3,
    direction: Vector3,
    length_m: f64,
    sun: Vector3,
    ground_radius_m: f64,
    ends: &mut Vec<f64>,
) {
    let (vs, os) = (direction.dot(sun), origin.dot(sun));
    let a = 1.0 - vs * vs;
    let b = 2.0 * (origin.dot(direction) - os * vs);
    let c = origin.dot(origin) - os * os - ground_radius_m * ground_radius_m;
    let discriminant = b * b - 4.0 * a * c;
    if a <= 1e-12 || discriminant <= 0.0 {
        return;
    }
    let root = discriminant.sqrt();
    let before = ends.len();
    for t in [(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)] {
        if t > 0.0 && t < length_m && (origin + direction * t).dot(sun) < 0.0 {
            ends.push(t);
        }
    }
    if ends.len() > before {
        ends.sort_unstable_by(f64::total_cmp);
        ends.dedup();
    }
}

/// Where the eye is and where the sun is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Height of the eye above the ground, m (may be above the atmosphere).
    pub observer_altitude_m: f64,
    /// Sun elevation above the horizon, degrees (-90..=90).
    pub sun_elevation_deg: f64,
    /// Sun azimuth clockwise from north, degrees.
    pub sun_azimuth_deg: f64,
}

/// How the fast path gets the columns from a point toward the sun.
#[derive(Debug, Clone, Copy)]
pub enum SunColumns<'a> {
    /// An exact Gauss-Legendre integral at every sample (for one direction).
    Exact,
    /// Interpolated in a precomputed table (for images).
    Table(&'a SunColumnTable),
}

impl SunColumns<'_> {
    /// Columns (m) of `profiles` from `point` (planet-centred, m) to the
    /// top of the atmosphere toward the unit `sun`, into `columns`: exact
    /// on [`SUN_RAY_PANELS`] Gauss panels cut at `corners`, or from the
    /// table. False, with `columns` untouched, when the point is in the
    /// planet's shadow. `ends` is scratch for the exact path's panel ends.
    pub(crate) fn compute_columns_to_sun<P: Borrow<DensityProfile>>(
        self,
        profiles: &[P],
        corners: &ProfileCorners,
        point: Vector3,
        sun: Vector3,
        ends: &mut Vec<f64>,
        columns: &mut [f64],
    ) -> bool {
        let (ground_radius_m, top_radius_m) = corners.radii_m();
        let r = point.length();
        let mu = point.dot(sun) / r;
        match self {
            SunColumns::Table(table) => table.lookup_columns_to_sun(r, mu, columns),
            SunColumns::Exact => {
                if crate::geometry::ray_intersects_ground(r, mu, ground_radius_m) {
                    return false;
                }
                let length =
                    crate::geometry::distance_to_top_of_atmosphere(point, sun, top_radius_m);
                corners.fill_panel_ends(point, sun, length, SUN_RAY_PANELS, ends);
                compute_columns_along_ray(profiles, ground_radius_m, point, sun, ends, columns);
                true
            }
        }
    }
}

impl SunColumns<'_> {
    /// [`SunColumns::compute_columns_to_sun`] from the march node `node`:
    /// with a table, its radius located once for the replayed nodes of
    /// every ray that repeats it (`SunColumnTable::locate_node`, `located`
    /// per node index; the same columns on the ray that is marched).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn compute_columns_to_sun_at_node<P: Borrow<DensityProfile>>(
        self,
        profiles: &[P],
        corners: &ProfileCorners,
        node: &MarchNode,
        sun: Vector3,
        located: &mut Vec<LocatedNode>,
        ends: &mut Vec<f64>,
        columns: &mut [f64],
    ) -> bool {
        match self {
            SunColumns::Table(table) => {
                let at = table.locate_node(node, located);
                let mu = node.point.dot(sun) / at.radius_m;
                table.lookup_columns_at_radius(&at.located, mu, columns)
            }
            SunColumns::Exact => {
                self.compute_columns_to_sun(profiles, corners, node.point, sun, ends, columns)
            }
        }
    }
}

/// The most view rays an [`ExactSunColumns`] keeps per scene geometry:
/// beyond them a ray's columns are computed, not kept (a bound on the
/// memory, some 3 kB a ray, for skies asked for many exact views).
const MOST_KEPT_RAYS: usize = 4096;

/// The exact columns toward the sun from the march nodes of the view rays
/// marched so far ([`SunColumns::Exact`]), kept for skies whose march and
/// sun paths are the same: the same species' profiles (in order), radii,
/// eye and sun. The k-distribution's term skies (`sky/k_terms.rs`) are
/// such skies: their atmospheres differ in the banded gases' amounts only,
/// so each view's columns, the costliest part of its single scattering
/// (the profiles' densities on every sun path), are computed by the first
/// term's sky and read by the others, bit for bit the same.
#[derive(Debug, Default)]
pub(crate) struct ExactSunColumns {
    /// Per scene geometry ([`ExactSunColumns::slot_for`]), the rays by
    /// (view direction, segment length) bits.
    slots: Mutex<Vec<(SceneGeometry, KeptRays)>>,
}

type KeptRays = std::collections::HashMap<[u64; 4], Arc<RayColumns>>;

/// What a view ray's nodes and their paths to the sun depend on.
#[derive(Debug, Clone, PartialEq)]
struct SceneGeometry {
    profiles: Vec<DensityProfile>,
    radii_m: (f64, f64),
    observer: Vector3,
    sun: Vector3,
}

/// One view ray's columns toward the sun, per march node in march order:
/// whether the node is sunlit and its columns, [node * species + j], m.
#[derive(Debug, Default)]
pub(crate) struct RayColumns {
    lit: Vec<bool>,
    columns: Vec<f64>,
}

/// Scenes whose in-scattering integrals one march computes together with
/// its own ([`SingleScatteringScene::compute_inscattering_integrals_together`]):
/// scenes of the march's view geometry ([`SingleScatteringScene::has_view_geometry_of`]:
/// the same nodes, weights, columns and densities, and the same columns
/// toward the sun) whose optics differ (the k-distribution's terms, which
/// differ in what absorbs), their scratches, and their extinction
/// coefficients one scene after another, per species: at each node the
/// optical depths and transmittances of every scene are one loop and one
/// run of exponentials, bit for bit each scene's own (the same sums in
/// the same order; the exponentials' lanes do not depend on their
/// neighbours).
pub(crate) struct Together<'a> {
    skies: Vec<(&'a SingleScatteringScene, &'a mut SingleScatteringScratch)>,
    /// [species][offset of the scene + i], m^-1.
    extinction: Vec<Vec<f64>>,
    /// Where each scene's wavelengths start in a row of `extinction`.
    offsets: Vec<usize>,
    /// The optical depths, then the transmittances, of one node.
    depths: Vec<f64>,
}

impl<'a> Together<'a> {
    /// `skies`, each with its scratch, to march with a scene of their view
    /// geometry (checked by the march).
    pub(crate) fn new(
        skies: Vec<(&'a SingleScatteringScene, &'a mut SingleScatteringScratch)>,
    ) -> Together<'a> {
        let species = skies.first().map_or(0, |(sky, _)| sky.optics.species.len());
        let mut offsets = Vec::with_capacity(skies.len());
        let mut extinction = vec![Vec::new(); species];
        for (sky, _) in &skies {
            offsets.push(extinction.first().map_or(0, Vec::len));
            for (row, s) in extinction.iter_mut().zip(&sky.optics.species) {
                row.extend_from_slice(s.extinction_per_m.values());
            }
        }
        let channels = extinction.first().map_or(0, Vec::len);
        Together {
            skies,
            extinction,
            offsets,
            depths: vec![0.0; channels],
        }
    }

    /// The scenes' scratches, in the order given.
    pub(crate) fn scratches(&self) -> impl Iterator<Item = &SingleScatteringScratch> {
        self.skies.iter().map(|(_, scratch)| &**scratch)
    }

    /// A sunlit node's share of every scene's integrals (as
    /// [`SingleScatteringScene::compute_segment_integrals`] adds it).
    fn add_node(
        &mut self,
        weight: f64,
        node_columns: &[f64],
        sun_columns: &[f64],
        densities: &[f64],
    ) {
        self.depths.fill(0.0);
        for (j, betas) in self.extinction.iter().enumerate() {
            let column = node_columns[j] + sun_columns[j];
            for (tau, beta) in self.depths.iter_mut().zip(betas) {
                *tau += beta * column;
            }
        }
        exp_neg_in_place(&mut self.depths);
        for ((sky, scratch), offset) in self.skies.iter_mut().zip(&self.offsets) {
            let wavelengths = sky.optics.grid.len();
            add_to_integrals(
                (
                    weight,
                    densities,
                    &self.depths[*offset..*offset + wavelengths],
                ),
                &scratch.scattering_species,
                &mut scratch.inscattering_integrals,
            );
        }
    }
}

impl ExactSunColumns {
    /// The slot of `scene`'s geometry, added if new.
    fn slot_for(&self, scene: &SingleScatteringScene) -> usize {
        let geometry = SceneGeometry {
            profiles: scene.profiles.clone(),
            radii_m: (scene.ground_radius_m, scene.top_radius_m),
            observer: scene.observer,
            sun: scene.sun_direction,
        };
        let mut slots = self.lock();
        match slots.iter().position(|(g, _)| *g == geometry) {
            Some(slot) => slot,
            None => {
                slots.push((geometry, KeptRays::default()));
                slots.len() - 1
            }
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(SceneGeometry, KeptRays)>> {
        // A poisoned lock only means that another thread panicked: every
        // ray in it is whole (each is inserted when complete).
        self.slots
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    fn get(&self, slot: usize, ray: &[u64; 4]) -> Option<Arc<RayColumns>> {
        self.lock()[slot].1.get(ray).cloned()
    }

    fn keep(&self, slot: usize, ray: [u64; 4], columns: RayColumns) {
        let mut slots = self.lock();
        let rays = &mut slots[slot].1;
        if rays.len() < MOST_KEPT_RAYS {
            rays.entry(ray).or_insert_with(|| Arc::new(columns));
        }
    }
}

/// An atmosphere on a wavelength grid, seen from one place with the sun in
/// one place: everything single scattering needs, precomputed.
#[derive(Debug, Clone)]
pub struct SingleScatteringScene {
    optics: AtmosphereOptics,
    ground_radius_m: f64,
    top_radius_m: f64,
    /// The eye, planet-centred (its local zenith is +z), m.
    observer: Vector3,
    /// Unit vector toward the sun in the eye's east-north-up frame, which
    /// is also the planet-centred frame's orientation.
    sun_direction: Vector3,
    sun_angular_radius_rad: f64,
    /// The species' density profiles (a copy, so rays need no list of
    /// references).
    profiles: Vec<DensityProfile>,
    /// Where the profiles have corners: rays are cut there.
    corners: ProfileCorners,
    /// The sun-column tables built so far, by size: they depend on the
    /// profiles and radii only, so every sky moved to another sun
    /// ([`SingleScatteringScene::with_sun`]) shares them.
    sun_column_tables: Arc<Mutex<Vec<Arc<SunColumnTable>>>>,
    /// The polarisation correction's harmonics from the streams computed
    /// so far (`ViewHarmonicsCache`): they depend on the scattering
    /// species and not on the sun, the eye or what absorbs, so every sky
    /// moved to another sun shares them, and so do the k-distribution's
    /// term skies ([`SingleScatteringScene::sharing_view_harmonics`]).
    view_harmonics: Arc<ViewHarmonicsCache>,
    /// What the multiple-scattering field computes that depends on the
    /// optics and the eye but not on the sun (`SunFreeParts`): every sky
    /// moved to another sun shares it.
    sun_free_field_parts: Arc<SunFreeParts>,
    /// The exact sun columns of view rays shared with skies of the same
    /// geometry, and this scene's slot in them
    /// ([`SingleScatteringScene::sharing_exact_sun_columns`]); none by
    /// default.
    exact_sun_columns: Option<(Arc<ExactSunColumns>, usize)>,
}

/// Per-thread work space of the fast path (no allocation per ray).
#[derive(Debug, Clone)]
pub struct SingleScatteringScratch {
    /// The view ray's march.
    march: PanelMarch,
    /// Columns of the whole view ray, m.
    view_columns: Vec<f64>,
    sun_columns: Vec<f64>,
    /// One view node's optical depth eye-node-sun per wavelength, then
    /// its transmittance.
    optical_depth: Vec<f64>,
    /// I_j(lambda), species-major: [j * wavelengths + i], m.
    inscattering_integrals: Vec<f64>,
    /// The Lambertian ground's radiance times the view transmittance.
    ground_radiance: Vec<f64>,
    /// Transmittance of the whole view ray (for the sun's disc).
    view_transmittance: Vec<f64>,
    /// Ends of the Gauss panels of the view ray and of a path toward the
    /// sun, m along each.
    view_panel_ends: Vec<f64>,
    sun_panel_ends: Vec<f64>,
    /// The view ray's nodes located in the sun-column table, per node
    /// (`SunColumns::compute_columns_to_sun_at_node`).
    located: Vec<LocatedNode>,
    /// Per species: whether it scatters at any wavelength (an absorbing
    /// gas adds nothing to the integrals).
    scattering_species: Vec<bool>,
    /// The sunlit nodes of the ray being marched, for the sums after the
    /// march ([`SingleScatteringScratch::add_lit_nodes_to_integrals`]).
    lit_nodes: LitNodes,
    /// Whether each node's exponentials and sums are taken at the node
    /// (the slow path the sums after the march are held to, bit for bit)
    /// instead of after the march.
    node_by_node: bool,
}

/// The sunlit nodes of one view ray in march order: per node its weight
/// (m), and per node and species [node * species + j] its relative
/// density and its columns (m) from the eye and toward the sun; then, per
/// node and wavelength, the optical depths eye-node-sun and in place their
/// transmittances. With a sun-column table the columns toward the sun are
/// looked up after the march, all the ray's together
/// (`SunColumnTable::lookup_lit_columns`), from each node's located radius
/// and sun cosine kept in `sun_points`.
#[derive(Debug, Clone, Default)]
struct LitNodes {
    weights: Vec<f64>,
    densities: Vec<f64>,
    view_columns: Vec<f64>,
    sun_points: Vec<(SunColumnRadius, f64)>,
    sun_columns: Vec<f64>,
    transmittances: Vec<f64>,
}

impl LitNodes {
    fn clear(&mut self) {
        self.weights.clear();
        self.densities.clear();
        self.view_columns.clear();
        self.sun_points.clear();
        self.sun_columns.clear();
    }
}

/// Adds to `depths` (per wavelength) the optical depths of the path eye
/// -> node -> sun of columns `view_columns` and `sun_columns` (m, per
/// species), species by species: the sum of each species' two columns
/// times its extinction.
#[inline(always)]
fn add_optical_depths(
    species: &[crate::atmosphere::SpeciesOptics],
    view_columns: &[f64],
    sun_columns: &[f64],
    depths: &mut [f64],
) {
    for (j, s) in species.iter().enumerate() {
        let column = view_columns[j] + sun_columns[j];
        for (tau, beta) in depths.iter_mut().zip(s.extinction_per_m.values()) {
            *tau += beta * column;
        }
    }
}

/// Adds one node's light to the integrals I_j(lambda) ([j * wavelengths +
/// i], m): its weight (m) times each scattering species' relative density
/// times the transmittance eye-node-sun (per wavelength).
#[inline(always)]
fn add_to_integrals(
    (weight, densities, transmittances): (f64, &[f64], &[f64]),
    scattering_species: &[bool],
    integrals: &mut [f64],
) {
    let wavelengths = transmittances.len();
    for (j, density) in densities.iter().enumerate() {
        let density = *density;
        if density <= 0.0 || !scattering_species[j] {
            continue;
        }
        let row = &mut integrals[j * wavelengths..(j + 1) * wavelengths];
        for (acc, transmittance) in row.iter_mut().zip(transmittances) {
            *acc += weight * density * transmittance;
        }
    }
}

impl SingleScatteringScratch {
    /// Marches each view ray's densities and columns once for the rays
    /// after it whose nodes lie at the same altitudes (the same zenith
    /// angle from the same eye, e.g. a sky-view table's row:
    /// [`PanelMarch`]'s `reuse_nodes`); the integrals differ from a march
    /// of every ray by rounding (1e-16 relative). The nodes' located
    /// sun-column cells are kept with them: a scratch that reuses nodes
    /// serves one scene and one sun-column table.
    pub(crate) fn reuse_view_nodes(&mut self) {
        self.march.reuse_nodes();
    }

    /// The sunlit nodes kept by the march ([`LitNodes`]) added to the
    /// integrals: every node's optical depths, then their exponentials
    /// all together (whole registers, one call per ray), then the sums in
    /// march order. The same operations on each value as node by node
    /// (`node_by_node`), so the same bits. With a sun-column table the
    /// march keeps each sunlit node's located radius and sun cosine, and
    /// their columns are looked up after it, before these sums, all
    /// together, four at a time (`SunColumnTable::lookup_lit_columns`;
    /// the scenes marched together then take their nodes in march
    /// order).
    fn add_lit_nodes_to_integrals(&mut self, species: &[crate::atmosphere::SpeciesOptics]) {
        let lit = &mut self.lit_nodes;
        let (count, s) = (lit.weights.len(), species.len());
        let wavelengths = self.optical_depth.len();
        lit.transmittances.clear();
        lit.transmittances.resize(count * wavelengths, 0.0);
        for (n, depths) in lit.transmittances.chunks_exact_mut(wavelengths).enumerate() {
            let (view, sun) = (
                &lit.view_columns[n * s..][..s],
                &lit.sun_columns[n * s..][..s],
            );
            add_optical_depths(species, view, sun, depths);
        }
        exp_neg_in_place(&mut lit.transmittances);
        for (n, transmittances) in lit.transmittances.chunks_exact(wavelengths).enumerate() {
            add_to_integrals(
                (lit.weights[n], &lit.densities[n * s..][..s], transmittances),
                &self.scattering_species,
                &mut self.inscattering_integrals,
            );
        }
    }

    /// Tests: each node's exponentials and sums taken at the node (the
    /// slow path), or after the march (the default).
    #[cfg(test)]
    pub(crate) fn sum_node_by_node(&mut self, node_by_node: bool) {
        self.node_by_node = node_by_node;
    }

    /// The integrals I_j(lambda) of the last ray, species-major, m.
    pub(crate) fn inscattering_integrals(&self) -> &[f64] {
        &self.inscattering_integrals
    }

    /// The sunlit ground's radiance seen along the last ray (zero when it
    /// does not end on the ground), W m^-2 sr^-1 nm^-1.
    pub(crate) fn ground_radiance(&self) -> &[f64] {
        &self.ground_radiance
    }

    /// The transmittance of the whole last ray.
    pub(crate) fn view_transmittance(&self) -> &[f64] {
        &self.view_transmittance
    }
}

impl SingleScatteringScene {
    /// Puts `atmosphere` on `grid` and places the eye and the sun.
    #[cfg(test)]
    pub(crate) fn new(
        atmosphere: &Atmosphere,
        grid: &WavelengthGrid,
        observation: Observation,
    ) -> Result<SingleScatteringScene> {
        SingleScatteringScene::new_with_phase_matrices(atmosphere, grid, observation, None)
    }

    /// [`SingleScatteringScene::new`], with the Mie species' phase matrices
    /// (for polarised skies) when `phase_matrices` gives their wavelength
    /// stride (`Atmosphere::add_phase_matrices`; 1: at every wavelength).
    pub(crate) fn new_with_phase_matrices(
        atmosphere: &Atmosphere,
        grid: &WavelengthGrid,
        observation: Observation,
        phase_matrices: Option<usize>,
    ) -> Result<SingleScatteringScene> {
        let mut optics = atmosphere.compute_optics(grid)?;
        if let Some(stride) = phase_matrices {
            atmosphere.add_phase_matrices(&mut optics, stride)?;
        }
        SingleScatteringScene::from_optics(
            optics,
            atmosphere.planet.radius_m(),
            atmosphere.planet.top_radius_m(),
            atmosphere.sun.angular_radius_rad(),
            observation,
        )
    }

    /// From optics already on a grid (e.g. with a ground albedo replaced).
    pub(crate) fn from_optics(
        optics: AtmosphereOptics,
        ground_radius_m: f64,
        top_radius_m: f64,
        sun_angular_radius_rad: f64,
        observation: Observation,
    ) -> Result<SingleScatteringScene> {
        let Observation {
            observer_altitude_m,
            sun_elevation_deg,
            sun_azimuth_deg,
        } = observation;
        if !(observer_altitude_m.is_finite() && observer_altitude_m >= 0.0) {
            return Err(Error::out_of_range(
                "observer altitude",
                observer_altitude_m,
                "m",
                ">= 0 (on or above the ground)",
            ));
        }
        crate::geometry::direction::check_elevation_azimuth(
            "sun",
            sun_elevation_deg,
            sun_azimuth_deg,
        )?;
        let profiles: Vec<DensityProfile> =
            optics.species.iter().map(|s| s.profile.clone()).collect();
        let corners = ProfileCorners::new(&profiles, ground_radius_m, top_radius_m);
        Ok(SingleScatteringScene {
            optics,
            profiles,
            corners,
            ground_radius_m,
            top_radius_m,
            observer: Vector3::new(0.0, 0.0, ground_radius_m + observer_altitude_m),
            sun_direction: direction_from_elevation_azimuth(sun_elevation_deg, sun_azimuth_deg),
            sun_angular_radius_rad,
            sun_column_tables: Arc::default(),
            view_harmonics: Arc::default(),
            sun_free_field_parts: Arc::default(),
            exact_sun_columns: None,
        })
    }

    /// The same atmosphere on the same grid, seen by the same eye, with the
    /// sun moved to `sun_elevation_deg`, `sun_azimuth_deg` (the optics are
    /// copied, not recomputed).
    pub(crate) fn with_sun(
        &self,
        sun_elevation_deg: f64,
        sun_azimuth_deg: f64,
    ) -> Result<SingleScatteringScene> {
        let moved = SingleScatteringScene::from_optics(
            self.optics.clone(),
            self.ground_radius_m,
            self.top_radius_m,
            self.sun_angular_radius_rad,
            Observation {
                observer_altitude_m: self.observer.z - self.ground_radius_m,
                sun_elevation_deg,
                sun_azimuth_deg,
            },
        )?;
        Ok(SingleScatteringScene {
            sun_column_tables: Arc::clone(&self.sun_column_tables),
            view_harmonics: Arc::clone(&self.view_harmonics),
            sun_free_field_parts: Arc::clone(&self.sun_free_field_parts),
            ..moved
        })
    }

    /// The same atmosphere on the same grid with the eye moved to
    /// `altitude_m` above the ground and the sun to `sun_elevation_deg`,
    /// `sun_azimuth_deg` (optics copied, sun-column tables shared).
    pub(crate) fn with_observer_and_sun(
        &self,
        altitude_m: f64,
        sun_elevation_deg: f64,
        sun_azimuth_deg: f64,
    ) -> Result<SingleScatteringScene> {
        let mut moved = self.with_sun(sun_elevation_deg, sun_azimuth_deg)?;
        if !(altitude_m.is_finite() && altitude_m >= 0.0) {
            return Err(Error::out_of_range(
                "observer altitude",
                altitude_m,
                "m",
                ">= 0 (on or above the ground)",
            ));
        }
        moved.observer = Vector3::new(0.0, 0.0, self.ground_radius_m + altitude_m);
        // The sun-column tables are per eye (see `sun_column_table`).
        moved.sun_column_tables = Arc::default();
        moved.sun_free_field_parts = Arc::default();
        Ok(moved)
    }

    /// The spectral transmittance from `point` (planet-centred, m) to the
    /// top of the atmosphere along the unit `direction`, into
    /// `transmittance`: exp(-sum_j k_j(lambda) C_j) with the columns C_j
    /// integrated exactly (Gauss panels cut at the profiles' corners).
    /// False, with `transmittance` zeroed, when the ray meets the ground.
    pub(crate) fn compute_transmittance_to_top(
        &self,
        point: Vector3,
        direction: Vector3,
        transmittance: &mut [f64],
    ) -> bool {
        let mut ends = Vec::new();
        let mut columns = vec![0.0; self.profiles.len()];
        transmittance.fill(0.0);
        if !SunColumns::Exact.compute_columns_to_sun(
            &self.profiles,
            &self.corners,
            point,
            direction,
            &mut ends,
            &mut columns,
        ) {
            return false;
        }
        for (i, t) in transmittance.iter_mut().enumerate() {
            let tau: f64 = self
                .optics
                .species
                .iter()
                .zip(&columns)
                .map(|(species, column)| species.extinction_per_m.values()[i] * column)
                .sum();
            *t = (-tau).exp();
        }
        true
    }

    /// The optics on the grid.
    pub(crate) fn optics(&self) -> &AtmosphereOptics {
        &self.optics
    }

    /// Unit vector toward the sun (east-north-up).
    pub(crate) fn sun_direction(&self) -> Vector3 {
        self.sun_direction
    }

    /// Distance of the eye from the planet's centre, m.
    pub(crate) fn observer_radius_m(&self) -> f64 {
        self.observer.z
    }

    /// Planet radius and top-of-atmosphere radius, m.
    pub(crate) fn radii_m(&self) -> (f64, f64) {
        (self.ground_radius_m, self.top_radius_m)
    }

    /// The sun-column table of this sky's atmosphere (altitude x mu nodes):
    /// built on first use, then shared by every sky of this atmosphere and
    /// eye, whatever its sun (the table does not depend on it), so that a
    /// sequence of frames or a moving slider builds it once.
    pub(crate) fn sun_column_table(
        &self,
        altitude_nodes: usize,
        mu_nodes: usize,
    ) -> Arc<SunColumnTable> {
        let find = |tables: &[Arc<SunColumnTable>]| {
            tables
                .iter()
                .find(|t| t.node_counts() == (altitude_nodes, mu_nodes))
                .cloned()
        };
        // A poisoned lock only means that another thread panicked: the
        // tables in it are whole (each is pushed when complete).
        let lock = || {
            self.sun_column_tables
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
        };
        if let Some(table) = find(&lock()) {
            return table;
        }
        // Computed without the lock (the computation runs on the thread
        // pool, whose workers may ask for a table too); two threads that
        // race compute the same table, and the first one is kept.
        // The absorbing gases on exponential profiles (the [gases] table's
        // water vapour, mixed gases and O2-O2; none of the presets' own
        // species) take the vector exponential: their columns enter only
        // optical depths, where its 2e-12 is nothing; every other
        // species' entries are the same bits as before.
        let fast: Vec<bool> = self
            .optics
            .species
            .iter()
            .map(|s| s.kind == crate::atmosphere::ABSORBING_GAS_KIND)
            .collect();
        let table = Arc::new(SunColumnTable::compute_with_fast_exponentials(
            &self.profiles,
            &fast,
            (self.ground_radius_m, self.top_radius_m),
            altitude_nodes,
            mu_nodes,
        ));
        let mut tables = lock();
        if let Some(first) = find(&tables) {
            return first;
        }
        tables.push(Arc::clone(&table));
        table
    }

    /// The store of the polarisation correction's image-table harmonics
    /// this sky shares with the skies moved from it to other suns.
    pub(crate) fn view_harmonics_cache(&self) -> Arc<ViewHarmonicsCache> {
        Arc::clone(&self.view_harmonics)
    }

    /// The field's sun-independent parts kept for this sky's optics and
    /// eye (`SunFreeParts`), shared with every sky moved to another sun.
    pub(crate) fn sun_free_field_parts(&self) -> Arc<SunFreeParts> {
        Arc::clone(&self.sun_free_field_parts)
    }

    /// This sky sharing `other`'s sun-column tables (those built so far
    /// and those to come), when the two have what the tables depend on in
    /// common: the species' profiles (in order), the planet's radii and the
    /// eye; else this sky unchanged. For skies of one atmosphere whose
    /// amounts (optical depths, albedos, phase functions) change, not its
    /// profiles: a retrieval's forward model builds one such sky per
    /// wavelength at every evaluation, and at a low sun each would build
    /// the same table again.
    pub(crate) fn sharing_sun_column_tables_of(
        mut self,
        other: &SingleScatteringScene,
    ) -> SingleScatteringScene {
        if self.profiles == other.profiles
            && self.ground_radius_m == other.ground_radius_m
            && self.top_radius_m == other.top_radius_m
            && self.observer.z == other.observer.z
        {
            self.sun_column_tables = Arc::clone(&other.sun_column_tables);
        }
        self
    }

    /// This sky keeping its view rays' exact columns toward the sun in
    /// `shared`, and reading those that a sky of the same geometry (the
    /// species' profiles, radii, eye and sun) kept there
    /// ([`ExactSunColumns`]): the same columns bit for bit, computed once.
    pub(crate) fn sharing_exact_sun_columns(
        mut self,
        shared: &Arc<ExactSunColumns>,
    ) -> SingleScatteringScene {
        let slot = shared.slot_for(&self);
        self.exact_sun_columns = Some((Arc::clone(shared), slot));
        self
    }

    /// This sky keeping the polarisation correction's harmonics from the
    /// streams in `shared` and reading those that a sky of the same
    /// scattering species kept there ([`ViewHarmonicsCache`]: the term
    /// skies of `sky/k_terms.rs`, whose atmospheres differ in what absorbs
    /// only): the same harmonics bit for bit, computed once.
    pub(crate) fn sharing_view_harmonics(
        mut self,
        shared: &Arc<ViewHarmonicsCache>,
    ) -> SingleScatteringScene {
        self.view_harmonics = Arc::clone(shared);
        self
    }

    /// Work space for [`SingleScatteringScene::compute_radiance`].
    pub(crate) fn scratch(&self) -> SingleScatteringScratch {
        let (species, wavelengths) = (self.optics.species.len(), self.optics.grid.len());
        SingleScatteringScratch {
            march: PanelMarch::new(species),
            view_columns: vec![0.0; species],
            sun_columns: vec![0.0; species],
            optical_depth: vec![0.0; wavelengths],
            inscattering_integrals: vec![0.0; species * wavelengths],
            ground_radiance: vec![0.0; wavelengths],
            view_transmittance: vec![0.0; wavelengths],
            view_panel_ends: Vec::with_capacity(self.corners.most_panel_ends(VIEW_RAY_PANELS) + 2),
            sun_panel_ends: Vec::with_capacity(self.corners.most_panel_ends(SUN_RAY_PANELS)),
            located: Vec::new(),
            scattering_species: self
                .optics
                .species
                .iter()
                .map(|s| s.scattering_per_m.values().iter().any(|b| *b != 0.0))
                .collect(),
            lit_nodes: LitNodes::default(),
            node_by_node: false,
        }
    }

    /// Fast path, first half: fills the scratch's in-scattering integrals
    /// I_j(lambda) (m), the ground term and the view transmittance for the
    /// view direction `view` (unit, east-north-up).
    pub(crate) fn compute_inscattering_integrals(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
    ) {
        self.compute_segment_integrals((view, f64::INFINITY), sun_columns, scratch);
    }

    /// As [`Self::compute_inscattering_integrals`] along the segment of
    /// the view ray from the eye to `distance_m` m (or where the ray
    /// leaves the atmosphere or meets the ground, if nearer): the
    /// integrals, the transmittance and columns are the segment's, and the
    /// ground term is there only if the segment reaches the ground
    /// (aerial perspective, [`crate::Sky::aerial_perspective`]).
    pub(crate) fn compute_segment_integrals(
        &self,
        (view, distance_m): (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
    ) {
        self.compute_segment_integrals_sharing((view, distance_m), sun_columns, scratch, None);
    }

    /// [`Self::compute_inscattering_integrals`], and those of the scenes of
    /// `together` along the same ray, from this march (each scene's
    /// integrals, transmittance, columns and ground term in its scratch,
    /// bit for bit what it computes alone). Every scene of `together` must
    /// have this scene's view geometry ([`Self::has_view_geometry_of`]) and
    /// read the same `sun_columns` (the same sun-column table).
    pub(crate) fn compute_inscattering_integrals_together(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
        together: &mut Together,
    ) {
        debug_assert!(
            together
                .skies
                .iter()
                .all(|(sky, _)| sky.has_view_geometry_of(self))
        );
        self.compute_segment_integrals_sharing(
            (view, f64::INFINITY),
            sun_columns,
            scratch,
            Some(together),
        );
    }

    /// Whether `other`'s view rays march the same nodes as this scene's
    /// and their paths toward the sun are the same: the same species'
    /// profiles (in order), radii, eye and sun (what [`ExactSunColumns`]
    /// keys its rays by); their optics may differ.
    pub(crate) fn has_view_geometry_of(&self, other: &SingleScatteringScene) -> bool {
        self.profiles == other.profiles
            && (self.ground_radius_m, self.top_radius_m)
                == (other.ground_radius_m, other.top_radius_m)
            && self.observer == other.observer
            && self.sun_direction == other.sun_direction
    }

    fn compute_segment_integrals_sharing(
        &self,
        (view, distance_m): (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
        mut together: Option<&mut Together>,
    ) {
        let species = &self.optics.species;
        let reset = |scratch: &mut SingleScatteringScratch| {
            scratch.inscattering_integrals.fill(0.0);
            scratch.ground_radiance.fill(0.0);
            scratch.view_transmittance.fill(1.0);
            scratch.view_columns.fill(0.0);
        };
        reset(scratch);
        for (_, other) in together.iter_mut().flat_map(|t| t.skies.iter_mut()) {
            reset(other);
        }
        let Some((enter, exit)) =
            segment_in_atmosphere(self.observer, view, self.ground_radius_m, self.top_radius_m)
        else {
            return;
        };
        let start = self.observer + view * enter;
        let length = exit.min(distance_m) - enter;
        if length <= 0.0 {
            if distance_m >= exit {
                self.add_ground_term(start, view, sun_columns, scratch);
                for (sky, other) in together.iter_mut().flat_map(|t| t.skies.iter_mut()) {
                    sky.add_ground_term(start, view, sun_columns, other);
                }
            }
            return;
        }
        let mut view_ends = std::mem::take(&mut scratch.view_panel_ends);
        self.corners
            .fill_panel_ends(start, view, length, VIEW_RAY_PANELS, &mut view_ends);
        add_shadow_crossings(
            start,
            view,
            length,
            self.sun_direction,
            self.ground_radius_m,
            &mut view_ends,
        );
        let mut march = std::mem::take(&mut scratch.march);
        // The exact sun columns kept by a sky of the same geometry, or
        // kept now for those that follow (`ExactSunColumns`).
        // (Not for a ray shared by the caller: it says where its columns
        // come from.)
        let kept = match (sun_columns, &self.exact_sun_columns) {
            (SunColumns::Exact, Some((shared, slot))) => {
                let ray = [
                    view.x.to_bits(),
                    view.y.to_bits(),
                    view.z.to_bits(),
                    distance_m.to_bits(),
                ];
                Some((shared, *slot, ray, shared.get(*slot, &ray)))
            }
            _ => None,
        };
        let kept_replay = kept.as_ref().and_then(|(.., ray)| ray.clone());
        let mut kept_record = match kept {
            Some((.., None)) => Some(RayColumns::default()),
            _ => None,
        };
        let (replay, mut record) = (kept_replay.as_deref(), kept_record.as_mut());
        // With a table and the sums after the march, the columns toward
        // the sun are looked up after it too, all the ray's lit nodes
        // together (`LitNodes`); the same columns as node by node.
        let after_march = match sun_columns {
            SunColumns::Table(table) if !scratch.node_by_node => Some(table),
            _ => None,
        };
        let mut node_index = 0;
        scratch.lit_nodes.clear();
        march.march(
            &self.profiles,
            self.ground_radius_m,
            (start, view),
            &view_ends,
            |node, node_columns, densities| {
                let kept_node = replay
                    .as_ref()
                    .and_then(|ray| Some((ray, *ray.lit.get(node_index)?)));
                let lit = match kept_node {
                    Some((ray, lit)) => {
                        if lit {
                            let n = scratch.sun_columns.len();
                            scratch
                                .sun_columns
                                .copy_from_slice(&ray.columns[node_index * n..][..n]);
                        }
                        lit
                    }
                    None if after_march.is_some() => {
                        let table = after_march.expect("a table");
                        // `compute_columns_to_sun_at_node`'s located radius
                        // and sun cosine, and its shadow test.
                        let at = table.locate_node(&node, &mut scratch.located);
                        let mu = node.point.dot(self.sun_direction) / at.radius_m;
                        let lit = !table.is_shadowed(&at.located, mu);
                        if lit {
                            scratch.lit_nodes.sun_points.push((at.located, mu));
                        }
                        lit
                    }
                    None => sun_columns.compute_columns_to_sun_at_node(
                        &self.profiles,
                        &self.corners,
                        &node,
                        self.sun_direction,
                        &mut scratch.located,
                        &mut scratch.sun_panel_ends,
                        &mut scratch.sun_columns,
                    ),
                };
                node_index += 1;
                if let Some(record) = record.as_mut() {
                    record.lit.push(lit);
                    if lit {
                        record.columns.extend_from_slice(&scratch.sun_columns);
                    } else {
                        let n = scratch.sun_columns.len();
                        record.columns.resize(record.columns.len() + n, 0.0);
                    }
                }
                if !lit {
                    return ControlFlow::Continue(());
                }
                if scratch.node_by_node {
                    let (depths, columns) = (&mut scratch.optical_depth, &scratch.sun_columns);
                    depths.fill(0.0);
                    add_optical_depths(species, node_columns, columns, depths);
                    // The transmittance eye-node-sun, one exponential per
                    // wavelength for every species, all together (a loop
                    // the compiler vectorises, `vector_exp.rs`).
                    exp_neg_in_place(depths);
                    add_to_integrals(
                        (node.weight, densities, depths),
                        &scratch.scattering_species,
                        &mut scratch.inscattering_integrals,
                    );
                } else {
                    // Kept for after the march (`lit_nodes`).
                    let lit_nodes = &mut scratch.lit_nodes;
                    lit_nodes.weights.push(node.weight);
                    lit_nodes.densities.extend_from_slice(densities);
                    lit_nodes.view_columns.extend_from_slice(node_columns);
                    if after_march.is_none() {
                        lit_nodes
                            .sun_columns
                            .extend_from_slice(&scratch.sun_columns);
                    }
                }
                if let (Some(together), None) = (together.as_deref_mut(), after_march) {
                    together.add_node(node.weight, node_columns, &scratch.sun_columns, densities);
                }
                ControlFlow::Continue(())
            },
        );
        if let Some(table) = after_march {
            let lit = &mut scratch.lit_nodes;
            let s = species.len();
            lit.sun_columns.resize(lit.sun_points.len() * s, 0.0);
            table.lookup_lit_columns(&lit.sun_points, &mut lit.sun_columns);
            // The scenes marched together, node by node in march order
            // (what each adds at a node is its own).
            if let Some(together) = together.as_deref_mut() {
                for (n, weight) in lit.weights.iter().enumerate() {
                    let range = n * s..(n + 1) * s;
                    together.add_node(
                        *weight,
                        &lit.view_columns[range.clone()],
                        &lit.sun_columns[range.clone()],
                        &lit.densities[range],
                    );
                }
            }
        }
        if !scratch.node_by_node {
            scratch.add_lit_nodes_to_integrals(species);
        }
        scratch.view_columns.copy_from_slice(march.columns());
        for (sky, other) in together.iter_mut().flat_map(|t| t.skies.iter_mut()) {
            other.view_columns.copy_from_slice(march.columns());
            sky.finish_segment(
                (start, view, length),
                (distance_m, exit),
                sun_columns,
                other,
            );
        }
        scratch.march = march;
        scratch.view_panel_ends = view_ends;
        if let (Some((shared, slot, ray, _)), Some(record)) = (kept, kept_record) {
            shared.keep(slot, ray, record);
        }
        self.finish_segment(
            (start, view, length),
            (distance_m, exit),
            sun_columns,
            scratch,
        );
    }

    /// The end of a segment's integrals, its columns from the eye in
    /// `scratch.view_columns`: the transmittance of the whole segment and,
    /// where it reaches the ground, the sunlit ground's term.
    fn finish_segment(
        &self,
        (start, view, length): (Vector3, Vector3, f64),
        (distance_m, exit): (f64, f64),
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
    ) {
        let species = &self.optics.species;
        // Transmittance of the whole view ray: the optical depths, then
        // their exponentials together.
        for (i, t) in scratch.view_transmittance.iter_mut().enumerate() {
            *t = species
                .iter()
                .zip(&scratch.view_columns)
                .map(|(s, c)| s.extinction_per_m[i] * c)
                .sum();
        }
        exp_neg_in_place(&mut scratch.view_transmittance);
        let end = start + view * length;
        if distance_m >= exit && end.length() <= self.ground_radius_m * (1.0 + 1e-12) {
            self.add_ground_term(end, view, sun_columns, scratch);
        }
    }

    /// The transmittance of the sun's beam (toward its centre) from the top
    /// of the atmosphere to `point` (planet-centred, m), with columns from
    /// `sun_columns`, into `out`: zero where the planet is in the way.
    pub(crate) fn compute_sun_transmittance_at(
        &self,
        point: Vector3,
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
        out: &mut [f64],
    ) {
        out.fill(0.0);
        if !sun_columns.compute_columns_to_sun(
            &self.profiles,
            &self.corners,
            point,
            self.sun_direction,
            &mut scratch.sun_panel_ends,
            &mut scratch.sun_columns,
        ) {
            return;
        }
        for (i, t) in out.iter_mut().enumerate() {
            let tau: f64 = self
                .optics
                .species
                .iter()
                .zip(&scratch.sun_columns)
                .map(|(s, c)| s.extinction_per_m[i] * c)
                .sum();
            *t = (-tau).exp();
        }
    }

    /// The eye, planet-centred, m.
    pub(crate) fn observer(&self) -> Vector3 {
        self.observer
    }

    /// The sunlit Lambertian ground at `ground_point`, seen through the view
    /// transmittance already in the scratch.
    fn add_ground_term(
        &self,
        ground_point: Vector3,
        _view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
    ) {
        let normal = ground_point.normalized();
        let mu_sun = normal.dot(self.sun_direction);
        if mu_sun <= 0.0 || self.optics.ground_albedo.values().iter().all(|a| *a == 0.0) {
            return;
        }
        let point = normal * self.ground_radius_m;
        let mut ground = std::mem::take(&mut scratch.ground_radiance);
        self.compute_sun_transmittance_at(point, sun_columns, scratch, &mut ground);
        for (i, out) in ground.iter_mut().enumerate() {
            *out = self.optics.ground_albedo[i] / std::f64::consts::PI
                * self.optics.solar_irradiance_w_m2_nm[i]
                * mu_sun
                * *out
                * scratch.view_transmittance[i];
        }
        scratch.ground_radiance = ground;
    }

    /// Fast path, second half: the singly scattered radiance of the air
    /// from the integrals in `scratch` for a view at scattering-angle
    /// cosine `cos_theta` with the sun, W m^-2 sr^-1 nm^-1, into `radiance`
    /// (the sunlit ground, [`SingleScatteringScratch::ground_radiance`], is
    /// a term of its own).
    pub(crate) fn radiance_from_integrals(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        phase: &mut [f64],
        radiance: &mut [f64],
    ) {
        let wavelengths = self.optics.grid.len();
        radiance.fill(0.0);
        for (j, s) in self.optics.species.iter().enumerate() {
            let row = &integrals[j * wavelengths..(j + 1) * wavelengths];
            if row.iter().all(|v| *v == 0.0) {
                continue;
            }
            s.phase_function.eval_into(cos_theta, phase);
            for i in 0..wavelengths {
                radiance[i] += self.optics.solar_irradiance_w_m2_nm[i]
                    * s.scattering_per_m[i]
                    * phase[i]
                    * row[i];
            }
        }
    }

    /// The polarised part of single scattering from the same integrals:
    /// per wavelength sum_j E sigma_s,j b1_j(theta) I_j, W m^-2 sr^-1 nm^-1,
    /// into `polarised`: the Q of the singly scattered light referred to the
    /// scattering plane (its I is [`Self::radiance_from_integrals`]'s; the
    /// sunlit ground is unpolarised, and sunlight scattered once has U = V
    /// = 0 there). The scattering angle is the same along the whole view
    /// ray (a parallel sun), so the phase matrix comes out of the integral
    /// as the phase function does.
    pub(crate) fn polarised_radiance_from_integrals(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        matrices: &mut [PhaseMatrix],
        polarised: &mut [f64],
    ) {
        let wavelengths = self.optics.grid.len();
        polarised.fill(0.0);
        for (j, s) in self.optics.species.iter().enumerate() {
            let row = &integrals[j * wavelengths..(j + 1) * wavelengths];
            if row.iter().all(|v| *v == 0.0) {
                continue;
            }
            s.phase_function.phase_matrix_into(cos_theta, matrices);
            for i in 0..wavelengths {
                polarised[i] += self.optics.solar_irradiance_w_m2_nm[i]
                    * s.scattering_per_m[i]
                    * matrices[i].b1
                    * row[i];
            }
        }
    }

    /// Fast path: single-scattered sky radiance (plus the sunlit ground) in
    /// the direction `view` (unit, east-north-up), W m^-2 sr^-1 nm^-1.
    #[cfg(test)]
    pub(crate) fn compute_radiance(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut SingleScatteringScratch,
        radiance: &mut SampledSpectrum,
    ) {
        self.compute_inscattering_integrals(view, sun_columns, scratch);
        let cos_theta = view.dot(self.sun_direction);
        let mut phase = vec![0.0; radiance.len()];
        self.radiance_from_integrals(
            cos_theta,
            &scratch.inscattering_integrals,
            &mut phase,
            radiance.values_mut(),
        );
        for (r, g) in radiance
            .values_mut()
            .iter_mut()
            .zip(&scratch.ground_radiance)
        {
            *r += g;
        }
    }

    /// Reference path (the paper's method): uniform midpoint march of
    /// `view_steps` along the view ray and, from every sample,
    /// `sun_steps` toward the sun. W m^-2 sr^-1 nm^-1.
    pub(crate) fn compute_radiance_reference(
        &self,
        view: Vector3,
        view_steps: usize,
        sun_steps: usize,
    ) -> SampledSpectrum {
        let optics = &self.optics;
        let wavelengths = optics.grid.len();
        let mut radiance = SampledSpectrum::zeros(wavelengths);
        let Some((enter, exit)) =
            segment_in_atmosphere(self.observer, view, self.ground_radius_m, self.top_radius_m)
        else {
            return radiance;
        };
        let cos_theta = view.dot(self.sun_direction);
        let step = (exit - enter) / view_steps as f64;
        let mut tau_view = SampledSpectrum::zeros(wavelengths);
        let mut extinction = SampledSpectrum::zeros(wavelengths);
        let mut scattering = SampledSpectrum::zeros(wavelengths);
        let mut tau_sun = SampledSpectrum::zeros(wavelengths);
        let mut phase_buffer = vec![0.0; wavelengths];
        for i in 0..view_steps {
            let point = self.observer + view * (enter + (i as f64 + 0.5) * step);
            let altitude_m = point.length() - self.ground_radius_m;
            extinction.fill(0.0);
            optics.add_extinction_at_altitude(altitude_m, &mut extinction);
            if self.reference_optical_depth_to_sun(point, sun_steps, &mut tau_sun) {
                scattering.fill(0.0);
                optics.add_scattering_at_altitude(
                    altitude_m,
                    cos_theta,
                    &mut phase_buffer,
                    &mut scattering,
                );
                for w in 0..wavelengths {
                    let tau = tau_view[w] + 0.5 * step * extinction[w] + tau_sun[w];
                    radiance[w] +=
                        optics.solar_irradiance_w_m2_nm[w] * scattering[w] * (-tau).exp() * step;
                }
            }
            tau_view.add_scaled(&extinction, step);
        }
        // The sunlit ground, when the ray ends there.
        let end = self.observer + view * exit;
        let normal = end.normalized();
        let mu_sun = normal.dot(self.sun_direction);
        if end.length() <= self.ground_radius_m * (1.0 + 1e-12)
            && mu_sun > 0.0
            && self.reference_optical_depth_to_sun(
                normal * self.ground_radius_m,
                sun_steps,
                &mut tau_sun,
            )
        {
            for w in 0..wavelengths {
                radiance[w] += optics.ground_albedo[w] / std::f64::consts::PI
                    * optics.solar_irradiance_w_m2_nm[w]
                    * mu_sun
                    * (-(tau_sun[w] + tau_view[w])).exp();
            }
        }
        radiance
    }

    /// Uniform midpoint march toward the sun; false in the planet's shadow.
    fn reference_optical_depth_to_sun(
        &self,
        point: Vector3,
        steps: usize,
        tau: &mut SampledSpectrum,
    ) -> bool {
        let r = point.length();
        let mu = point.dot(self.sun_direction) / r;
        if crate::geometry::ray_intersects_ground(r, mu, self.ground_radius_m) {
            return false;
        }
        let length = crate::geometry::distance_to_top_of_atmosphere(
            point,
            self.sun_direction,
            self.top_radius_m,
        );
        let step = length / steps as f64;
        tau.fill(0.0);
        for k in 0..steps {
            let altitude_m = (point + self.sun_direction * ((k as f64 + 0.5) * step)).length()
                - self.ground_radius_m;
            self.optics.add_extinction_at_altitude(altitude_m, tau);
        }
        *tau *= step;
        true
    }

    /// True when `view` points inside the sun's disc and reaches space: a
    /// ray that ends on the ground never sees the sun, however close to it.
    #[cfg(test)]
    pub(crate) fn is_in_sun_disc(&self, view: Vector3) -> bool {
        self.sun_angular_radius_rad > 0.0
            && self.sees_sky(view)
            && view
                .cross(self.sun_direction)
                .length()
                .atan2(view.dot(self.sun_direction))
                < self.sun_angular_radius_rad
    }

    /// Angular radius of the sun's disc, rad (0: a point).
    pub(crate) fn sun_angular_radius_rad(&self) -> f64 {
        self.sun_angular_radius_rad
    }

    /// True when the ray from the eye toward `direction` (unit) reaches
    /// space rather than the ground.
    pub(crate) fn sees_sky(&self, direction: Vector3) -> bool {
        !crate::geometry::ray_intersects_ground(self.observer.z, direction.z, self.ground_radius_m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;

    /// The integrals summed after the march (every sunlit node's
    /// exponentials together) are those summed node by node, bit for bit:
    /// earth-hazy's and paper-mars's air, aerosols and absorbing gases, on
    /// the ground and at 30 km, the sun high, low, and below the horizon
    /// (rays cut where they enter the planet's shadow), views up, grazing
    /// and down to the ground, each row marched once for its azimuths
    /// (replayed nodes) and with the sun-column table and the exact columns.
    #[test]
    fn the_sums_after_the_march_are_the_sums_node_by_node() {
        let grid = WavelengthGrid::new(380.0, 780.0, 20.0).unwrap();
        let (mut compared, mut lit) = (0, 0);
        for preset in ["earth-hazy", "paper-mars"] {
            let atmosphere = Atmosphere::preset(preset).unwrap();
            for (altitude_m, sun_elevation_deg) in [(0.0, 40.0), (0.0, 2.0), (30e3, -5.0)] {
                let sky = SingleScatteringScene::new(
                    &atmosphere,
                    &grid,
                    Observation {
                        observer_altitude_m: altitude_m,
                        sun_elevation_deg,
                        sun_azimuth_deg: 0.0,
                    },
                )
                .unwrap();
                let table = sky.sun_column_table(32, 64);
                for columns in [SunColumns::Table(&table), SunColumns::Exact] {
                    let (mut after, mut by_node) = (sky.scratch(), sky.scratch());
                    after.reuse_view_nodes();
                    by_node.reuse_view_nodes();
                    by_node.sum_node_by_node(true);
                    for zenith_deg in [10.0, 70.0, 89.5, 92.0, 120.0] {
                        for azimuth_deg in [0.0, 45.0, 90.0, 170.0] {
                            let view =
                                direction_from_elevation_azimuth(90.0 - zenith_deg, azimuth_deg);
                            sky.compute_inscattering_integrals(view, columns, &mut after);
                            sky.compute_inscattering_integrals(view, columns, &mut by_node);
                            let bits = |s: &SingleScatteringScratch| {
                                s.inscattering_integrals()
                                    .iter()
                                    .chain(s.ground_radiance())
                                    .chain(s.view_transmittance())
                                    .map(|v| v.to_bits())
                                    .collect::<Vec<_>>()
                            };
                            assert_eq!(bits(&after), bits(&by_node), "{preset} {zenith_deg}");
                            compared += 1;
                            // (From the ground a view down meets it at
                            // once: no air, the ground's light only.)
                            if after.inscattering_integrals().iter().any(|v| *v > 0.0) {
                                lit += 1;
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(compared, 2 * 3 * 2 * 5 * 4);
        // Every view but those down from the ground (2 zenith angles at 4
        // azimuths, 2 suns, 2 column sources, 2 presets) sees lit air.
        assert_eq!(lit, compared - 2 * 4 * 2 * 2 * 2);
    }

    /// Skies of one atmosphere's profiles, radii and eye share one
    /// sun-column table whatever their amounts and sun; a sky of other
    /// profiles or another eye keeps its own.
    #[test]
    fn skies_of_the_same_profiles_and_eye_share_their_sun_column_tables() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let observation = |altitude_m, sun_elevation_deg| Observation {
            observer_altitude_m: altitude_m,
            sun_elevation_deg,
            sun_azimuth_deg: 180.0,
        };
        let grid = |w| WavelengthGrid::new(w, w, 1.0).unwrap();
        let first =
            SingleScatteringScene::new(&atmosphere, &grid(440.0), observation(0.0, 10.0)).unwrap();
        let optics = atmosphere.compute_optics(&grid(870.0)).unwrap();
        let sky = |optics: &AtmosphereOptics, altitude_m| {
            SingleScatteringScene::from_optics(
                optics.clone(),
                atmosphere.planet.radius_m(),
                atmosphere.planet.top_radius_m(),
                atmosphere.sun.angular_radius_rad(),
                observation(altitude_m, 20.0),
            )
            .unwrap()
            .sharing_sun_column_tables_of(&first)
        };
        let nodes = (8, 16);
        // Another wavelength and sun, the same profiles and eye: the table
        // the second sky builds is the first's.
        let table = sky(&optics, 0.0).sun_column_table(nodes.0, nodes.1);
        assert!(Arc::ptr_eq(
            &table,
            &first.sun_column_table(nodes.0, nodes.1)
        ));
        // Another eye: its own.
        let raised = sky(&optics, 1000.0).sun_column_table(nodes.0, nodes.1);
        assert!(!Arc::ptr_eq(&raised, &table));
        // Another profile: its own.
        let mut other = optics.clone();
        other.species[0].profile = DensityProfile::exponential(5000.0, "test").unwrap();
        let own = sky(&other, 0.0).sun_column_table(nodes.0, nodes.1);
        assert!(!Arc::ptr_eq(&own, &table));
    }
}
