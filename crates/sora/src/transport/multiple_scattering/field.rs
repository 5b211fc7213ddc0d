//! The multiple-scattering field: the steps that solve it for the sun
//! zenith angles a sky's view rays meet, and its exact synthesis along a
//! view ray (see the module docs of [`super`]).

use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::{Arc, Mutex, PoisonError};

use super::MultipleScatteringSettings;
use super::column_optics::{ColumnGeometry, ScaledOptics};
use super::forward_peak::{self, ForwardPeak};
use super::peak_beam::{NeededElevations, PeakBeam, PeakBeamCache, PeakBeamInputs};
use super::phase_fourier::normalized_associated_legendre;
use super::polarisation_correction::{
    AnchorSolves, CorrectionInputs, PolarisationCorrection, PolarisationRows, PolarisationTable,
};
use super::regimes::{
    self, FIRST_ORDER_SUN_ZENITH_DEG, SUNSET_STEP_END_DEG, SUNSET_STEP_START_DEG,
};
use super::spherical_first_order::{
    FirstOrderInputs, MomentQuadrature, compute_spherical_first_order_with_phases, tabulate_phases,
};
use super::successive_orders::{self, ColumnSystem, ScaledSpecies};
use super::twilight_shift::SHIFT_PIECE_SPREAD_DEG;
use super::view_march::{
    MultipleScatteringScratch, NodeGeometry, SpeciesMajorOptics, ViewRayOptics, floored_log,
};
use crate::atmosphere::AtmosphereOptics;
use crate::atmosphere::phase_matrix::PhaseMatrix;
use crate::error::Result;
use crate::geometry::Vector3;
use crate::spectrum::WavelengthAnchors;
use crate::transport::single_scattering::{SingleScatteringScene, SunColumns};

/// Altitude and mu nodes of the sun-column table of the spherical first
/// order in the tests' fields: the default image tables' size
/// ([`crate::FastTableSize`]; a sky's field takes its own image tables'
/// size, see [`MultipleScatteringField::compute_with_sun_column_nodes`]).
#[cfg(test)]
const FIRST_ORDER_SUN_COLUMN_NODES: (usize, usize) = (128, 256);

/// Sun zenith angles at which the field is solved, increasing.
#[derive(Debug, Clone)]
pub(super) struct SunZenithAxis {
    pub(super) angles_rad: Vec<f64>,
}

impl SunZenithAxis {
    /// Nodes covering `lowest..=highest` (rad), one of them at `centre`
    /// (the eye's own sun zenith angle, where the nearest and so brightest
    /// part of every view ray is), spaced by `coarse` for a high sun and
    /// narrowing to `fine` from `SUNSET_STEP_START_DEG` (70 degrees) to
    /// `SUNSET_STEP_END_DEG` (85) and beyond, where the
    /// lower atmosphere's sun sets and the field changes fastest; but never
    /// closer than a quarter of the distance from `centre`: far from the
    /// eye's own sun angle lie only the far ends of grazing view rays, high
    /// in thin air. Without a centre (a field for every sun and eye, see
    /// [`FieldRequest::every_sun`]) the nodes start at `lowest` and keep
    /// the local step throughout.
    pub(super) fn new(
        lowest: f64,
        highest: f64,
        centre: Option<f64>,
        coarse: f64,
        fine: f64,
    ) -> SunZenithAxis {
        let (start, end) = (
            SUNSET_STEP_START_DEG.to_radians(),
            SUNSET_STEP_END_DEG.to_radians(),
        );
        let widening = centre.is_some();
        let centre = centre.unwrap_or(lowest).clamp(lowest, highest);
        let step = |theta: f64| {
            let t = ((theta - start) / (end - start)).clamp(0.0, 1.0);
            let local = coarse + t * (fine - coarse);
            let far = if widening {
                0.25 * (theta - centre).abs()
            } else {
                0.0
            };
            local.max(far).min(coarse.max(fine))
        };
        let mut below = vec![centre];
        while *below.last().unwrap() > lowest {
            let theta = *below.last().unwrap();
            below.push((theta - step(theta - 0.5 * step(theta))).max(0.0));
            if theta == 0.0 {
                break;
            }
        }
        below.dedup();
        let mut angles_rad: Vec<f64> = below.into_iter().rev().collect();
        while *angles_rad.last().unwrap() < highest {
            let theta = *angles_rad.last().unwrap();
            angles_rad.push(theta + step(theta + 0.5 * step(theta)));
        }
        if angles_rad.len() < 2 {
            angles_rad.push(angles_rad[0] + fine);
        }
        SunZenithAxis { angles_rad }
    }

    /// The nodes for the sun zenith angles within `reach` (rad) of the
    /// eye's, at `settings`' steps; `None`: every sun zenith angle, with no
    /// node placed at the eye's.
    fn for_reach(
        sky: &SingleScatteringScene,
        settings: &MultipleScatteringSettings,
        reach: Option<f64>,
    ) -> SunZenithAxis {
        let (ground_radius_m, top_radius_m) = sky.radii_m();
        let sun_zenith = sky.sun_direction().z.clamp(-1.0, 1.0).acos();
        let (lowest_rad, highest_rad) = match reach {
            Some(reach) => ((sun_zenith - reach).max(0.0), sun_zenith + reach),
            None => (0.0, PI),
        };
        // The sun sets for the top of a column at 90 degrees +
        // acos(R / R_top), and a straight path from a point of the column
        // reaches at most 2 acos(R / R_top) farther (to the top, grazing
        // the ground): beyond 90 degrees + 3 acos(R / R_top) nothing a
        // column's streams reach is sunlit (`spherical_first_order`), and
        // its field is zero. The axis ends a degree past that, so that a
        // sun angle beyond its end (read at its last node) reads darkness,
        // not the last lit column (measured: a zenith of 1e-6 cd/m^2 with
        // the sun 30 degrees below the horizon when it ended at 111 deg).
        let darkest = 0.5 * PI + 3.0 * (ground_radius_m / top_radius_m).acos() + 1f64.to_radians();
        let lowest = lowest_rad.clamp(0.0, darkest);
        let highest = highest_rad.clamp(lowest, darkest);
        SunZenithAxis::new(
            lowest,
            highest,
            reach.map(|_| sun_zenith),
            settings.sun_zenith_step_deg.to_radians(),
            settings.sunset_sun_zenith_step_deg.to_radians(),
        )
    }

    pub(super) fn count(&self) -> usize {
        self.angles_rad.len()
    }

    pub(super) fn angle(&self, s: usize) -> f64 {
        self.angles_rad[s]
    }

    /// Lower node and fraction for a sun zenith cosine (clamped to the axis).
    pub(super) fn locate(&self, sun_cosine: f64) -> (usize, f64) {
        let theta = sun_cosine.clamp(-1.0, 1.0).acos();
        let angles = &self.angles_rad;
        let upper = angles.partition_point(|a| *a <= theta);
        let s = upper.clamp(1, angles.len() - 1) - 1;
        let t = (theta - angles[s]) / (angles[s + 1] - angles[s]);
        (s, t.clamp(0.0, 1.0))
    }
}

/// The diffuse (multiply scattered) light field of a sky, solved at the
/// sun zenith angles its view rays meet, or at every sun zenith angle
/// ([`FieldRequest::every_sun`]: one field aimed at many skies).
#[derive(Debug, Clone)]
pub struct MultipleScatteringField {
    pub(super) settings: MultipleScatteringSettings,
    /// The sky's optics (exact phase functions for the forward-peak term).
    pub(super) atmosphere: AtmosphereOptics,
    /// The view march's optics, with the scaled optics and the columns'
    /// geometry the field was solved on.
    pub(super) optics: ViewRayOptics,
    pub(super) harmonics: Vec<bool>,
    /// The solver's output as it wrote it: per wavelength i and sun node s
    /// a block of `solution_len + 2` values, L_m(z_k, mu_b) at [(m *
    /// levels + k) * streams + b] and then the ground's two values, blocks
    /// [i * sun nodes + s] (read with [`MultipleScatteringField::solution`];
    /// kept as solved, not transposed: tens of megabytes at twilight).
    pub(super) solutions: Arc<Vec<f64>>,
    pub(super) solution_len: usize,
    /// The source's Legendre moments for the exact synthesis, made on
    /// first use ([`MultipleScatteringField::source_moments`]).
    /// Shared by the fields [`MultipleScatteringField::aimed`] makes.
    pub(super) moments: Arc<std::sync::OnceLock<Vec<f64>>>,
    /// Solved for every sun zenith angle ([`FieldRequest::every_sun`]).
    pub(super) every_sun: bool,
    /// With Stokes vectors, the columns of the polarisation correction.
    pub(super) polarisation: Option<PolarisationCorrection>,
}

/// What a field is solved for: one request instead of a chain of
/// constructors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FieldRequest {
    pub(crate) settings: MultipleScatteringSettings,
    /// (altitude, mu) nodes of the sun-column table that the spherical
    /// first order and the peak beam read the columns toward the sun from:
    /// a sky passes its image tables' size ([`crate::FastTableSize`], 128
    /// x 256 by default), so that the two share one table. The explorer's
    /// preview (32 x 64) then builds no second table of 128 x 256 nodes for
    /// its first low sun (measured on one thread: its 128-pixel frame at
    /// sun 10 0.10 -> 0.075 s), and its first order on the coarse table
    /// moves its images by at most 0.1 % of their 99th-percentile error
    /// against the default resolution at suns 10 to -12 degrees (the
    /// `quality_accuracy` example of `crates/sora-web`). So a view's
    /// radiance at a sun low enough for either (the sun nodes from
    /// `FIRST_ORDER_SUN_ZENITH_DEG`, or a point's sun below
    /// `PEAK_BEAM_HIGHEST_ELEVATION_DEG`) depends on this size, as the
    /// images' do: a documented setting of the sky
    /// (`FastTableSize::sun_column_nodes`). Measured (the zenith and six
    /// views 1 to 20 degrees up toward, across and away from the sun,
    /// 440/560/680 nm, earth-clear, earth-hazy and mars-dust): 32 x 64
    /// nodes move a view by at most 0.11 % from 128 x 256 at suns 5 to -8
    /// degrees (earth-hazy at 2 degrees the worst), by under 1e-5 at 10.
    pub(crate) sun_column_nodes: (usize, usize),
    /// Whether the field also solves the columns of its polarisation
    /// correction.
    pub(crate) polarised: bool,
    /// The solver stops after this many orders of the field (the field's
    /// own first order, or the spherical one, is order 1): with one, the
    /// field is the first order and a view's multiply scattered radiance
    /// is the second order alone (the twilight survey compares it with the
    /// path tracer's).
    pub(crate) sweeps: usize,
    /// After sunset, each order of the near-horizontal streams is shifted
    /// in pieces of its path, each at its own mean angle +- spread: at
    /// most the first, one per the second (degrees) of the path's angle's
    /// spread, 0: every path in the most (`ColumnSystem::with_shift_pieces`;
    /// by default the settings' `twilight_shift_pieces` and
    /// `SHIFT_PIECE_SPREAD_DEG`). (1, _) shifts each whole path at its
    /// mean angle; (32, 0) is the slow reference (docs/aerial_perspective.md
    /// measures what they move).
    pub(crate) shift_pieces: (usize, f64),
    /// For views no lower than this elevation (rad, >= 0) only: the sun
    /// zenith angles the field is solved for are those at the points of
    /// such views' rays, within acos(r cos e / R_top) - e of the eye's
    /// (the angle at the planet's centre between the eye and where a ray
    /// of elevation e leaves the atmosphere), instead of every point the
    /// eye sees (acos(R / R_top) + acos(R / r), 10 degrees on Earth). For an
    /// almucantar 15 degrees up that is 3 degrees, which spares the field
    /// the sunset's fine sun steps and spherical first order when the sun
    /// is 15 degrees high (a retrieval's forward model: 12 times faster
    /// there). None: every view.
    pub(crate) lowest_view_elevation_rad: Option<f64>,
    /// For every sun and eye: the sun zenith angles from 0 to where the
    /// field is dark, at the settings' steps, and the peak beam for every
    /// sun elevation it covers, so that one solve serves the skies of
    /// every sun and eye altitude ([`MultipleScatteringField::aimed`], the
    /// engine tables' bake). The nodes are not placed around the eye's
    /// sun, so a view differs from its own sky's by the interpolation
    /// between nodes (the engine tables' tests measure it).
    pub(crate) every_sun: bool,
}

impl FieldRequest {
    /// The converged, scalar field for every view, at these settings with
    /// this sun-column table.
    pub(crate) fn new(
        settings: MultipleScatteringSettings,
        sun_column_nodes: (usize, usize),
    ) -> FieldRequest {
        FieldRequest {
            settings,
            sun_column_nodes,
            polarised: false,
            sweeps: successive_orders::MAX_ITERATIONS,
            shift_pieces: (settings.twilight_shift_pieces, SHIFT_PIECE_SPREAD_DEG),
            lowest_view_elevation_rad: None,
            every_sun: false,
        }
    }

    /// The angle at the planet's centre (rad) within which the sun zenith
    /// angles the field needs lie around the eye's.
    fn reach(&self, sky: &SingleScatteringScene) -> Option<f64> {
        if self.every_sun {
            return None;
        }
        let (ground, top) = sky.radii_m();
        Some(match self.lowest_view_elevation_rad {
            // A point of the atmosphere that the eye sees is at most this
            // far (as an angle at the planet's centre) from the eye's zenith.
            None => {
                let r = sky.observer_radius_m();
                (ground / r.max(ground)).min(1.0).acos() + (ground / top).acos()
            }
            Some(lowest) => {
                let r = sky.observer_radius_m().max(ground);
                let e = lowest.clamp(0.0, 0.5 * PI);
                if r < top {
                    (r * e.cos() / top).min(1.0).acos() - e
                } else {
                    (ground / r).min(1.0).acos() + (ground / top).acos()
                }
            }
        })
    }
}

/// The solved columns: per wavelength i and sun node s a block of
/// `solution_len + 2` values (the field, then the ground's diffuse and
/// direct radiances), blocks [i * sun nodes + s].
struct SolvedColumns {
    solved: Vec<f64>,
    solution_len: usize,
}

impl MultipleScatteringField {
    /// The field for `request` with the default image tables' sun-column
    /// table.
    #[cfg(test)]
    pub(crate) fn compute(
        sky: &SingleScatteringScene,
        settings: MultipleScatteringSettings,
        polarised: bool,
    ) -> Result<MultipleScatteringField> {
        MultipleScatteringField::solve(
            sky,
            &FieldRequest {
                polarised,
                ..FieldRequest::new(settings, FIRST_ORDER_SUN_COLUMN_NODES)
            },
        )
    }

    /// Solves the field of `sky` for `request`; an error for settings that
    /// `MultipleScatteringSettings::validate` rejects. The steps: the sun
    /// axis, the delta-M scaled optics, the columns' geometry and their
    /// columns toward the sun, the polarisation correction's column, the
    /// spherical first order, the successive orders with the twilight
    /// shift, the ground's tables, the forward-peak term and its tilted
    /// beam, and the view march's optics.
    pub(crate) fn solve(
        sky: &SingleScatteringScene,
        request: &FieldRequest,
    ) -> Result<MultipleScatteringField> {
        let settings = request.settings;
        settings.validate()?;
        let optics = sky.optics();
        let reach = request.reach(sky);
        let sun_axis = SunZenithAxis::for_reach(sky, &settings, reach);
        let geometry = ColumnGeometry::new(sky, &settings);
        let scaled = ScaledOptics::delta_m(optics, geometry.streams.count());
        let mut sun_columns: Vec<Option<Vec<f64>>> =
            Vec::with_capacity(sun_axis.count() * geometry.grid.levels());
        for s in 0..sun_axis.count() {
            geometry.add_columns_toward_sun(sun_axis.angle(s), &mut sun_columns);
        }
        // The polarisation correction's column (`polarisation_correction.rs`),
        // prepared; its anchors solved with the field where the two share
        // their scalar column (see `solve_columns`), the others after it.
        let anchors = request.polarised.then(|| {
            WavelengthAnchors::following_optics(
                sky.optics(),
                settings.polarisation_wavelength_stride,
            )
        });
        let column = anchors
            .as_ref()
            .map(|anchors| PolarisationColumn::new(sky, (&geometry, &scaled), anchors));
        let inputs = column.as_ref().map(PolarisationColumn::inputs);
        let solves = inputs.as_ref().map(AnchorSolves::new);
        let sun_free = sky.sun_free_field_parts();
        let (forward_peak, first_order_phases) =
            sun_free.for_streams(geometry.streams.count(), || StreamParts {
                forward_peak: Arc::new(ForwardPeak::new(
                    optics,
                    &scaled.phases,
                    geometry.streams.count(),
                    &geometry.profiles,
                    geometry.top_radius_m - geometry.ground_radius_m,
                )),
                first_order_phases: Arc::new(tabulate_phases(&scaled.phases)),
            });
        let first_spherical = sun_axis
            .angles_rad
            .partition_point(|a| *a < FIRST_ORDER_SUN_ZENITH_DEG.to_radians());
        let first_order = solve_spherical_first_order(
            sky,
            (request.sun_column_nodes, &settings),
            (&geometry, &scaled, &first_order_phases),
            &sun_axis.angles_rad[first_spherical..],
        );
        // The field's sun node at the correction column's sun, where the
        // field's scalar solve is the correction's (the same system, sun
        // and transmittances, all its sweeps).
        let shared_node = column.as_ref().and_then(|column| {
            (request.sweeps == successive_orders::MAX_ITERATIONS)
                .then(|| (0..first_spherical).find(|&s| sun_axis.angle(s) == column.sun_zenith))
                .flatten()
        });
        let anchor_solutions = Mutex::new(Vec::new());
        let columns = solve_columns(
            optics,
            (&geometry, &scaled),
            (&sun_axis, &sun_columns),
            (first_spherical, &first_order),
            (request.sweeps, request.shift_pieces),
            solves
                .as_ref()
                .zip(shared_node)
                .map(|(solves, node)| (solves, node, &anchor_solutions)),
        );
        let polarisation = solves.map(|solves| {
            solves.finish(
                anchor_solutions
                    .into_inner()
                    .unwrap_or_else(PoisonError::into_inner),
            )
        });
        let (ground_diffuse, ground_direct) = ground_tables(&columns, optics.grid.len(), &sun_axis);
        let peak_beam = compute_peak_beam(
            sky,
            (request.sun_column_nodes, reach),
            (&geometry, &scaled),
            (&forward_peak, &sun_free.peak_beams),
        );
        let harmonics = (0..geometry.streams.count())
            .map(|m| {
                scaled
                    .phases
                    .iter()
                    .zip(&scaled.scaled_scattering)
                    .any(|(p, b)| *b > 0.0 && !p.harmonic_vanishes(m))
            })
            .collect();
        Ok(MultipleScatteringField {
            settings,
            atmosphere: optics.clone(),
            optics: ViewRayOptics {
                wavelengths: optics.grid.len(),
                species: optics.species.len(),
                panels: settings.view_ray_panels,
                observer: Vector3::new(0.0, 0.0, sky.observer_radius_m()),
                sun: sky.sun_direction(),
                by_species: SpeciesMajorOptics::new(
                    &scaled,
                    optics.grid.len(),
                    optics.species.len(),
                ),
                scaled,
                geometry,
                has_forward_peaks: forward_peak.any(),
                forward_peak,
                peak_beam,
                sun_axis,
                ground_diffuse,
                ground_direct,
            },
            harmonics,
            solutions: Arc::new(columns.solved),
            solution_len: columns.solution_len,
            moments: Arc::default(),
            every_sun: request.every_sun,
            polarisation,
        })
    }

    /// This field (solved with [`FieldRequest::every_sun`]) for an eye at
    /// `observer_radius_m` from the planet's centre under the sun toward
    /// `sun` (unit, east-north-up): the columns and their moments are
    /// shared (`Arc`), not copied; the rest of the optics (the peak beam,
    /// the forward-peak tables) is cloned; only the view march's eye and
    /// sun change.
    pub(crate) fn aimed(&self, observer_radius_m: f64, sun: Vector3) -> MultipleScatteringField {
        debug_assert!(self.every_sun, "a field solved for its own eye's suns only");
        let mut aimed = self.clone();
        aimed.optics.observer = Vector3::new(0.0, 0.0, observer_radius_m);
        aimed.optics.sun = sun;
        aimed
    }

    /// This field with its view rays marched in `panels` Gauss panels
    /// instead of the settings' `view_ray_panels` (the engine tables'
    /// layers, `engine_tables/mod.rs`).
    pub(crate) fn with_view_ray_panels(mut self, panels: usize) -> MultipleScatteringField {
        self.optics.panels = panels.max(1);
        self
    }

    /// The field L_m(z_k, mu_b) of sun node `s` at wavelength `i`, W m^-2
    /// sr^-1 nm^-1, [(m * levels + k) * streams + b].
    pub(super) fn solution(&self, s: usize, i: usize) -> &[f64] {
        let block = self.solution_len + 2;
        let at = (i * self.optics.sun_axis.count() + s) * block;
        &self.solutions[at..at + self.solution_len]
    }

    /// The diffuse (sky) irradiance on a horizontal plane at every level
    /// of the columns and every sun node, W m^-2 nm^-1: the field's own
    /// downward flux 2 pi sum_{mu_b > 0} w_b mu_b L_0(z_k, mu_b) plus the
    /// sunlight that delta-M moved into the scaled beam, E mu_s (T*_sun -
    /// T_sun) (the forward peaks' light, as the ground's table counts it).
    /// Returns the levels' altitudes (m, increasing from 0), the sun
    /// nodes' zenith angles (rad, increasing) and the flux and (in it) the
    /// moved sunlight, each at [(s * levels + k) * wavelengths + i]. What
    /// the engine tables' irradiance takes its altitude shape from between
    /// their altitude nodes.
    pub(crate) fn downward_diffuse_flux(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let geometry = &self.optics.geometry;
        let levels = geometry.grid.levels();
        let streams = &geometry.streams;
        let (n, degrees) = (streams.per_hemisphere(), streams.count());
        let wavelengths = self.atmosphere.grid.len();
        let suns = self.optics.sun_axis.count();
        let mut flux = vec![0.0; suns * levels * wavelengths];
        let mut moved = vec![0.0; suns * levels * wavelengths];
        let mut columns = Vec::with_capacity(levels);
        for s in 0..suns {
            let theta = self.optics.sun_axis.angle(s);
            columns.clear();
            geometry.add_columns_toward_sun(theta, &mut columns);
            let lit = theta.cos().max(0.0);
            for i in 0..wavelengths {
                let solution = self.solution(s, i);
                let solar = self.atmosphere.solar_irradiance_w_m2_nm[i];
                for k in 0..levels {
                    let mut down = streams.downward_flux(&solution[k * degrees..][..n]);
                    if let Some(column) = columns.get(k).and_then(|c| c.as_ref()) {
                        let (tau_scaled, tau) = self.optics.scaled.optical_depths(i, column);
                        let sunlight = solar * lit * ((-tau_scaled).exp() - (-tau).exp());
                        moved[(s * levels + k) * wavelengths + i] = sunlight;
                        down += sunlight;
                    }
                    flux[(s * levels + k) * wavelengths + i] = down;
                }
            }
        }
        (
            geometry.grid.altitudes_m().to_vec(),
            self.optics.sun_axis.angles_rad.clone(),
            flux,
            moved,
        )
    }

    /// The scattering source's moments per sun node s, wavelength i, level
    /// k, harmonic m and degree l >= m (the view direction factored out):
    ///
    /// ```text
    /// S[s, i, k, m, l] = c_l(k) sum_b 2 pi w_b Lambda_l^m(mu_b) L_m(z_k, mu_b; s)
    /// c_l(k) = sum_j (beta*_sca,j(z_k) / beta*_sca(z_k)) c_jl
    /// ```
    ///
    /// so that J / beta*_sca at (k, s) toward a view of zenith cosine mu_v
    /// and azimuth phi from the sun is sum_m cos(m phi) sum_l
    /// Lambda_l^m(mu_v) S[s, i, k, m, l]: the same sums as the harmonic
    /// kernels p*_jm(mu_v, mu_b) of [`MultipleScatteringTable`], reordered so
    /// that a view costs degrees^2 / 2 products per node and wavelength
    /// instead of species x degrees^3. Laid out
    /// [((s * wavelengths + i) * levels + k) * degrees^2 + m * degrees + l];
    /// zero where the level does not scatter. Made once, on one thread (it
    /// is called from inside parallel loops).
    pub(super) fn source_moments(&self) -> &[f64] {
        self.moments.get_or_init(|| {
            let degrees = self.optics.geometry.streams.count();
            let levels = self.optics.geometry.grid.levels();
            let (w, species) = (self.optics.wavelengths, self.optics.species);
            let square = degrees * degrees;
            let suns = self.optics.sun_axis.count();
            let mut moments = vec![0.0; suns * w * levels * square];
            let mut mixed = vec![0.0; degrees];
            // 2 pi w_b Lambda_l^m(mu_b), [(m * degrees + b) * degrees + l]
            // for l >= m: the sums over b below run over l together (a
            // loop the compiler vectorises), each in the order of b and
            // with the same products as sum_b (2 pi w_b Lambda) L_b.
            let streams = &self.optics.geometry.streams;
            let mut kernel = vec![0.0; degrees * square];
            for m in 0..degrees {
                for b in 0..degrees {
                    let legendre = &streams.legendre(b)[m * degrees..(m + 1) * degrees];
                    let row = &mut kernel[(m * degrees + b) * degrees..][..degrees];
                    for l in m..degrees {
                        row[l] = 2.0 * PI * streams.weights()[b] * legendre[l];
                    }
                }
            }
            let mut sums = vec![0.0; degrees];
            for s in 0..suns {
                for i in 0..w {
                    let solution = self.solution(s, i);
                    for k in 0..levels {
                        let densities = self.optics.geometry.grid.densities_at_level(k);
                        let scattering = |j: usize| {
                            densities[j] * self.optics.scaled.scaled_scattering[i * species + j]
                        };
                        let total: f64 = (0..species).map(scattering).sum();
                        if total <= 0.0 {
                            continue;
                        }
                        mixed.fill(0.0);
                        for j in 0..species {
                            let fraction = scattering(j) / total;
                            let phase = &self.optics.scaled.phases[i * species + j];
                            for (c, p) in mixed.iter_mut().zip(&phase.coefficients) {
                                *c += fraction * p;
                            }
                        }
                        let out = &mut moments[((s * w + i) * levels + k) * square..][..square];
                        for m in (0..degrees).filter(|m| self.harmonics[*m]) {
                            let radiance = &solution[(m * levels + k) * degrees..][..degrees];
                            // From -0.0, as a float iterator's sum starts.
                            let sums = &mut sums[m..];
                            sums.fill(-0.0);
                            for (b, r) in radiance.iter().enumerate() {
                                let row = &kernel[(m * degrees + b) * degrees + m..][..degrees - m];
                                for (sum, c) in sums.iter_mut().zip(row) {
                                    *sum += c * r;
                                }
                            }
                            for (l, sum) in (m..degrees).zip(sums.iter()) {
                                out[m * degrees + l] = mixed[l] * sum;
                            }
                        }
                    }
                }
            }
            moments
        })
    }

    /// For each level, the first and last sun node that a view ray from the
    /// eye can need there: a point at altitude h that the eye sees is at
    /// most acos(R / r_eye) + acos(R / (R + h)) from the eye (seen from the
    /// planet's centre), and so is its sun zenith angle from the eye's. A
    /// level takes the reach of the level above it (points between the two
    /// read both), and one node more on each side for the interpolation.
    pub(super) fn reachable_sun_nodes(&self) -> Vec<(usize, usize)> {
        let optics = &self.optics;
        let levels = self.optics.geometry.grid.levels();
        if self.every_sun {
            return vec![(0, optics.sun_axis.count() - 1); levels];
        }
        let ground = optics.geometry.ground_radius_m;
        let eye = optics.observer.length().max(ground);
        let centre = optics
            .sun
            .dot(optics.observer * (1.0 / eye))
            .clamp(-1.0, 1.0)
            .acos();
        let altitudes = self.optics.geometry.grid.altitudes_m();
        let axis = &optics.sun_axis;
        (0..altitudes.len())
            .map(|k| {
                let above = altitudes[(k + 1).min(altitudes.len() - 1)];
                let reach = (ground / eye).min(1.0).acos() + (ground / (ground + above)).acos();
                let (low, _) = axis.locate((centre - reach).max(0.0).cos());
                let (high, t) = axis.locate((centre + reach).min(PI).cos());
                let high = if t > 0.0 { high + 1 } else { high };
                (low.saturating_sub(1), (high + 1).min(axis.count() - 1))
            })
            .collect()
    }

    /// The forward-peak term toward a view at cos(theta) = `cos_theta` from
    /// the sun, into `out`, from its integrals along the view ray
    /// ([`MultipleScatteringScratch::forward_integrals`], or the sky-view
    /// table's interpolation of them); `phase` is work space, one value per
    /// wavelength.
    pub(crate) fn compute_forward_peak_radiance(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        phase: &mut [f64],
        out: &mut [f64],
    ) {
        if !self.optics.has_forward_peaks {
            out.fill(0.0);
            return;
        }
        self.optics
            .forward_peak
            .radiance(&self.atmosphere, cos_theta, integrals, phase, out);
    }

    /// The delta-M scaled transmittance T* = exp(-sum_j beta*_ext,j c_j) of
    /// the last ray or segment the march of `scratch` went along, into
    /// `out`: what the scaled field lets through, counting light
    /// scattered into the forward peaks as unscattered.
    pub(crate) fn scaled_transmittance_of_last_ray(
        &self,
        scratch: &MultipleScatteringScratch,
        out: &mut [f64],
    ) {
        let s = self.optics.species;
        for (i, t) in out.iter_mut().enumerate() {
            let tau: f64 = (0..s)
                .map(|j| self.optics.scaled.scaled_extinction[i * s + j] * scratch.view_columns[j])
                .sum();
            *t = (-tau).exp();
        }
    }

    /// The peaks' optical depth of the last ray or segment the march of
    /// `scratch` went along, X = sum_j f_j beta_sca,j c_j = tau - tau*
    /// (the view leg's part of the forward-peak term's X), into `out`.
    pub(crate) fn peak_depth_of_last_ray(
        &self,
        scratch: &MultipleScatteringScratch,
        out: &mut [f64],
    ) {
        let s = self.optics.species;
        let scaled = &self.optics.scaled;
        for (i, x) in out.iter_mut().enumerate() {
            *x = (0..s)
                .map(|j| {
                    (scaled.extinction[i * s + j] - scaled.scaled_extinction[i * s + j])
                        * scratch.view_columns[j]
                })
                .sum();
        }
    }

    /// Rows of the forward-peak integrals per wavelength.
    pub(crate) fn forward_integral_rows(&self) -> usize {
        self.optics.species + forward_peak::EXTRA_ROWS
    }

    /// The scattering-plane Q of the forward-peak term toward a view at
    /// cos(theta) = `cos_theta` from the sun, into `out` (see
    /// `ForwardPeak::polarised_radiance`), from the same integrals as
    /// [`MultipleScatteringField::compute_forward_peak_radiance`];
    /// `work` is work space of one value per wavelength.
    pub(crate) fn compute_forward_peak_polarised_radiance(
        &self,
        cos_theta: f64,
        integrals: &[f64],
        work: (&mut [f64], &mut [PhaseMatrix]),
        out: &mut [f64],
    ) {
        if !self.optics.has_forward_peaks {
            out.fill(0.0);
            return;
        }
        self.optics.forward_peak.polarised_radiance(
            &self.atmosphere,
            cos_theta,
            integrals,
            work,
            out,
        );
    }

    /// The polarisation correction's harmonic rows toward every distinct
    /// view of `views` (its zenith cosine and the altitude its segment ends
    /// at, infinity for the whole ray), from which each view's ratios (I, Q, U, V)
    /// / I_scalar of the light the scaled field scatters two or more times
    /// are summed at its azimuth (see `polarisation_correction.rs`). None
    /// for a scalar field.
    pub(crate) fn compute_polarisation_rows(
        &self,
        views: &[(f64, f64)],
    ) -> Option<PolarisationRows> {
        let correction = self.polarisation.as_ref()?;
        Some(correction.compute_rows(&self.atmosphere, &self.optics.scaled.phases, views))
    }

    /// The polarisation correction's ratios tabulated over view directions
    /// on `nodes` (per half of the zenith-cosine axis, azimuths), for
    /// images (see `polarisation_correction.rs`). None for a scalar field.
    pub(crate) fn compute_polarisation_table(
        &self,
        nodes: (usize, usize),
    ) -> Option<PolarisationTable> {
        let correction = self.polarisation.as_ref()?;
        Some(correction.tabulate(&self.atmosphere, &self.optics.scaled.phases, nodes))
    }

    /// Work space for [`MultipleScatteringField::compute_radiance`].
    pub(crate) fn scratch(&self) -> MultipleScatteringScratch {
        self.optics.scratch(self.optics.geometry.streams.count())
    }

    /// Multiply scattered radiance (orders >= 2 and skylight reflected by
    /// the ground) seen along `view`, W m^-2 sr^-1 nm^-1, into `radiance`:
    /// the scaled field's light ([`MultipleScatteringField::compute_field_radiance`])
    /// plus the forward-peak term of its integrals along the view (the
    /// sky adds its terms itself, `ViewTerms` in `sky/composition.rs`).
    #[cfg(test)]
    pub(crate) fn compute_radiance(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        let mut ground = vec![0.0; radiance.len()];
        self.compute_field_radiance(
            (view, f64::INFINITY),
            sun_columns,
            scratch,
            (&mut *radiance, &mut ground),
        );
        for (r, g) in radiance.iter_mut().zip(&ground) {
            *r += g;
        }
        self.add_forward_peak(view, scratch, radiance);
    }

    /// Adds to `radiance` the forward-peak term of the integrals the last
    /// march along `view` left in `scratch`.
    #[cfg(test)]
    pub(crate) fn add_forward_peak(
        &self,
        view: Vector3,
        scratch: &MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        let w = radiance.len();
        let (mut phase, mut forward) = (vec![0.0; w], vec![0.0; w]);
        self.compute_forward_peak_radiance(
            view.dot(self.optics.sun),
            scratch.forward_integrals(),
            &mut phase,
            &mut forward,
        );
        for (r, f) in radiance.iter_mut().zip(&forward) {
            *r += f;
        }
    }

    /// The scaled field's light seen along `view` from the eye to
    /// `distance_m` m (`f64::INFINITY`: the whole ray), W m^-2 sr^-1 nm^-1:
    /// orders >= 2 of the scaled problem scattered by the air into `field`
    /// (the field's exact angular synthesis at every march node), the
    /// skylight the ground reflects into `ground` (zero unless the segment
    /// ends on the ground). The forward-peak term's integrals along the
    /// segment are left in the scratch
    /// ([`MultipleScatteringScratch::forward_integrals`], with columns
    /// toward the sun from `sun_columns`), for
    /// [`MultipleScatteringField::compute_forward_peak_radiance`].
    pub(crate) fn compute_field_radiance(
        &self,
        segment: (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        terms: (&mut [f64], &mut [f64]),
    ) {
        self.optics
            .march(segment, sun_columns, scratch, terms, |node, _, scratch| {
                self.compute_log_source(node, scratch)
            });
    }

    /// The forward-peak integrals of the view ray beyond `from_m` m (to
    /// its end in the atmosphere) into `scratch` (read them with
    /// [`MultipleScatteringScratch::forward_integrals`]), with the
    /// transmittances and the peak optical depth X of the view leg counted
    /// from that point, as an eye there sees the ray: the light from behind
    /// a point of an aerial perspective, summed over the ray beyond it
    /// itself (not the whole ray's less the segment's, two quadratures
    /// whose difference is their error where little light comes from
    /// behind). The field's light is not synthesised (zero).
    pub(crate) fn compute_forward_integrals_beyond(
        &self,
        view: Vector3,
        from_m: f64,
        scratch: &mut MultipleScatteringScratch,
    ) {
        let w = self.optics.wavelengths;
        let (mut field, mut ground) = (vec![0.0; w], vec![0.0; w]);
        self.optics.march_from(
            from_m,
            (view, f64::INFINITY),
            SunColumns::Exact,
            scratch,
            (&mut field, &mut ground),
            |_, _, scratch| scratch.log_source.fill(super::view_march::DARK_LOG_SOURCE),
        );
    }

    /// ln R(x, view) at one march node into `scratch.log_source`: R synthesised
    /// exactly from the harmonics at the four surrounding (level, sun node)
    /// corners ([`MultipleScatteringField::source_moments`]), interpolated
    /// linearly in ln R (as the table does).
    pub(super) fn compute_log_source(
        &self,
        node: NodeGeometry,
        scratch: &mut MultipleScatteringScratch,
    ) {
        let degrees = self.optics.geometry.streams.count();
        let square = degrees * degrees;
        let levels = self.optics.geometry.grid.levels();
        let w = self.optics.wavelengths;
        let moments = self.source_moments();
        let (k, tz) = self.optics.geometry.grid.locate(node.altitude_m);
        let (sun_node, ts) = self.optics.sun_axis.locate(node.sun_cosine);
        // Lambda_l^m(mu_v), kept per march node: the replayed nodes of an
        // almucantar's rays have the view cosine of the ray marched first
        // (a pure function of the cosine: the kept table where the cosine's
        // bits are the same).
        let cosine_bits = node.view_cosine.to_bits();
        match node.march_node {
            Some((index, _)) => {
                if scratch.node_legendre.len() <= index {
                    scratch.node_legendre.resize(index + 1, (0, Vec::new()));
                }
                let (bits, kept) = &mut scratch.node_legendre[index];
                if *bits == cosine_bits && kept.len() == square {
                    scratch.view_legendre[..square].copy_from_slice(kept);
                } else {
                    normalized_associated_legendre(
                        node.view_cosine,
                        degrees,
                        &mut scratch.view_legendre,
                    );
                    *bits = cosine_bits;
                    kept.clear();
                    kept.extend_from_slice(&scratch.view_legendre[..square]);
                }
            }
            None => normalized_associated_legendre(
                node.view_cosine,
                degrees,
                &mut scratch.view_legendre,
            ),
        }
        // cos(m phi) Lambda_l^m(mu_v) by the Chebyshev recurrence for cos(m phi).
        let mut cosine = 0.0;
        let mut previous = 0.0;
        for m in 0..degrees {
            let next = match m {
                0 => 1.0,
                1 => node.cos_azimuth,
                _ => 2.0 * node.cos_azimuth * cosine - previous,
            };
            (previous, cosine) = (cosine, next);
            let weight = if self.harmonics[m] { cosine } else { 0.0 };
            for value in &mut scratch.view_legendre[m * degrees + m..(m + 1) * degrees] {
                *value *= weight;
            }
        }
        let view = &scratch.view_legendre[..square];
        let corners = [
            (k, 1.0 - tz, sun_node, 1.0 - ts),
            (k, 1.0 - tz, sun_node + 1, ts),
            (k + 1, tz, sun_node, 1.0 - ts),
            (k + 1, tz, sun_node + 1, ts),
        ];
        for i in 0..w {
            // The four corners' sums side by side (four independent
            // chains of additions, each in the order of l and m as one
            // corner's alone; the same values).
            let source = corners
                .map(|(kk, _, ss, _)| &moments[((ss * w + i) * levels + kk) * square..][..square]);
            let mut values = [0.0; 4];
            for m in 0..degrees {
                let range = m * degrees + m..(m + 1) * degrees;
                // From -0.0, as a float iterator's sum starts.
                let mut sums = [-0.0; 4];
                let products = view[range.clone()]
                    .iter()
                    .zip(&source[0][range.clone()])
                    .zip(&source[1][range.clone()])
                    .zip(&source[2][range.clone()])
                    .zip(&source[3][range]);
                for ((((a, b0), b1), b2), b3) in products {
                    sums[0] += a * b0;
                    sums[1] += a * b1;
                    sums[2] += a * b2;
                    sums[3] += a * b3;
                }
                for (value, sum) in values.iter_mut().zip(sums) {
                    *value += sum;
                }
            }
            let mut log_value = 0.0;
            for ((_, wk, _, ws), value) in corners.iter().zip(values) {
                log_value += wk * ws * floored_log(value);
            }
            scratch.log_source[i] = log_value;
        }
    }
}

/// The sun zenith angle (rad) of the polarisation correction's column and
/// the share of its polarisation kept (`polarisation_correction.rs`), for
/// the eye's sun zenith angle `eye_sun_zenith` (rad) in a shell of radii
/// `(ground, top)` (m): the eye's own sun down to
/// `POLARISATION_COLUMN_MARGIN_DEG` above the column's last lit sun
/// (-acos(R_ground / R_top) in elevation), that sun below it; the whole
/// polarisation down to `POLARISATION_FADE_START_DEG` below the last lit
/// sun, then a share falling as exp(-d / `POLARISATION_FADE_SCALE_DEG`).
fn polarisation_column_sun(eye_sun_zenith: f64, (ground, top): (f64, f64)) -> (f64, f64) {
    let last_lit = 0.5 * PI + (ground / top).min(1.0).acos();
    let lowest = last_lit - regimes::POLARISATION_COLUMN_MARGIN_DEG.to_radians();
    let past_fade = (eye_sun_zenith - last_lit).to_degrees() - regimes::POLARISATION_FADE_START_DEG;
    let share = (-past_fade.max(0.0) / regimes::POLARISATION_FADE_SCALE_DEG).exp();
    (eye_sun_zenith.min(lowest), share)
}

/// The polarisation correction's column (`polarisation_correction.rs`):
/// the eye's own sun, or the lowest that still lights the column
/// ([`polarisation_column_sun`]), and its optical depths toward that sun,
/// for the correction's inputs ([`PolarisationColumn::inputs`]), solved
/// at the wavelengths `anchors` and interpolated between them.
struct PolarisationColumn<'a> {
    sky: &'a SingleScatteringScene,
    geometry: &'a ColumnGeometry,
    scaled: &'a ScaledOptics,
    anchors: &'a WavelengthAnchors,
    /// The column's sun zenith angle, rad.
    sun_zenith: f64,
    polarised_share: f64,
    /// [i * levels + k] (`CorrectionInputs::sun_optical_depths`).
    sun_optical_depths: Vec<Option<(f64, f64)>>,
}

impl<'a> PolarisationColumn<'a> {
    fn new(
        sky: &'a SingleScatteringScene,
        (geometry, scaled): (&'a ColumnGeometry, &'a ScaledOptics),
        anchors: &'a WavelengthAnchors,
    ) -> PolarisationColumn<'a> {
        let optics = sky.optics();
        let (sun_zenith, polarised_share) = polarisation_column_sun(
            sky.sun_direction().z.clamp(-1.0, 1.0).acos(),
            (geometry.ground_radius_m, geometry.top_radius_m),
        );
        let mut eye_columns = Vec::with_capacity(geometry.grid.levels());
        geometry.add_columns_toward_sun(sun_zenith, &mut eye_columns);
        let sun_optical_depths: Vec<Option<(f64, f64)>> = (0..optics.grid.len())
            .flat_map(|i| {
                eye_columns.iter().map(move |columns| {
                    columns
                        .as_ref()
                        .map(|columns| scaled.optical_depths(i, columns))
                })
            })
            .collect();
        PolarisationColumn {
            sky,
            geometry,
            scaled,
            anchors,
            sun_zenith,
            polarised_share,
            sun_optical_depths,
        }
    }

    fn inputs(&self) -> CorrectionInputs<'_> {
        CorrectionInputs {
            optics: self.sky.optics(),
            scaled: self.scaled,
            geometry: self.geometry,
            sun_cosine: self.sun_zenith.cos(),
            polarised_share: self.polarised_share,
            sun_optical_depths: &self.sun_optical_depths,
            eye_altitude_m: self.sky.observer_radius_m() - self.geometry.ground_radius_m,
            view_harmonics: self.sky.view_harmonics_cache(),
            anchors: self.anchors,
        }
    }
}

/// The first order in the spherical shell, with the planet's shadow, at
/// the sun nodes `suns` (rad; those from `FIRST_ORDER_SUN_ZENITH_DEG` on),
/// the columns toward the sun from a table of `sun_column_nodes`, the
/// quadrature's panels and nodes from `settings`; empty
/// when there are none (a high sun's nodes all stop short of them).
fn solve_spherical_first_order(
    sky: &SingleScatteringScene,
    (sun_column_nodes, settings): ((usize, usize), &MultipleScatteringSettings),
    (geometry, scaled, phase_table): (&ColumnGeometry, &ScaledOptics, &[f64]),
    suns: &[f64],
) -> Vec<f64> {
    if suns.is_empty() {
        return Vec::new();
    }
    let solar_irradiance: Vec<f64> = sky.optics().solar_irradiance_w_m2_nm.values().to_vec();
    let (altitude_nodes, mu_nodes) = sun_column_nodes;
    let table_columns = sky.sun_column_table(altitude_nodes, mu_nodes);
    compute_spherical_first_order_with_phases(
        &FirstOrderInputs {
            scaled,
            geometry,
            sun_columns: &table_columns,
            moments: MomentQuadrature::Fine,
            sun_zenith_rad: suns,
            solar_irradiance_w_m2_nm: &solar_irradiance,
            panels: settings.first_order_panels,
            fine_nodes: settings.first_order_fine_nodes,
        },
        phase_table,
    )
}

/// The polarisation correction's anchors that the field's solve solves
/// (`polarisation_correction.rs`): the prepared solves, the field's sun
/// node at the correction column's sun, and the solutions per anchor.
type SharedAnchors<'s, 'a> = (
    &'s AnchorSolves<'a>,
    usize,
    &'s Mutex<Vec<Option<Vec<f64>>>>,
);

/// The successive orders of every wavelength's columns at every sun node
/// (in parallel over wavelengths), with the twilight shift; with
/// `polarisation`, each of its anchors' columns with the scalar system and
/// the field's scalar solve at its sun node
/// (`AnchorSolves::solve_anchor`: the same solve the correction would make
/// on its own, made once).
fn solve_columns(
    optics: &AtmosphereOptics,
    (geometry, scaled): (&ColumnGeometry, &ScaledOptics),
    (sun_axis, sun_columns): (&SunZenithAxis, &[Option<Vec<f64>>]),
    (first_spherical, first_order): (usize, &[f64]),
    (sweeps, shift_pieces): (usize, (usize, f64)),
    polarisation: Option<SharedAnchors>,
) -> SolvedColumns {
    let levels = geometry.grid.levels();
    let degrees = geometry.streams.count();
    let solution_len = degrees * levels * degrees;
    // Per wavelength: every sun node's solution, then its two ground values.
    let chunk = sun_axis.count() * (solution_len + 2);
    let mut solved = vec![0.0; optics.grid.len() * chunk];
    crate::parallel::for_each_chunk_mut(&mut solved, chunk, |i, out| {
        solve_wavelength(
            i,
            out,
            optics,
            (geometry, scaled),
            (sun_axis, sun_columns),
            (first_spherical, first_order),
            (sweeps, shift_pieces, polarisation),
        )
    });
    SolvedColumns {
        solved,
        solution_len,
    }
}

/// The columns of wavelength `i` at every sun node into `out` (see
/// [`SolvedColumns`]): each node below `first_spherical` solved on its
/// own with the column's first order and then shifted to first order,
/// the nodes from there on with the spherical first order `first_order`
/// and solved together, every order shifted (`twilight_shift.rs`).
fn solve_wavelength(
    i: usize,
    out: &mut [f64],
    optics: &AtmosphereOptics,
    (geometry, scaled_optics): (&ColumnGeometry, &ScaledOptics),
    (sun_axis, sun_columns): (&SunZenithAxis, &[Option<Vec<f64>>]),
    (first_spherical, first_order): (usize, &[f64]),
    (sweeps, shift_pieces, polarisation): (usize, (usize, f64), Option<SharedAnchors>),
) {
    let (wavelengths, species) = (optics.grid.len(), optics.species.len());
    let (streams, grid, paths) = (&geometry.streams, &geometry.grid, &geometry.paths);
    let levels = grid.levels();
    let degrees = streams.count();
    let solution_len = degrees * levels * degrees;
    let count = sun_axis.count();
    let ScaledOptics {
        phases,
        scaled_extinction,
        scaled_scattering,
        ..
    } = scaled_optics;
    // The spherical first order of node s >= first_spherical.
    let first_of = |s: usize| {
        &first_order[((s - first_spherical) * wavelengths + i) * solution_len..][..solution_len]
    };
    let scaled: Vec<ScaledSpecies> = (0..species)
        .map(|j| ScaledSpecies {
            extinction_per_m: scaled_extinction[i * species + j],
            scattering_per_m: scaled_scattering[i * species + j],
            phase: &phases[i * species + j],
        })
        .collect();
    let solar = optics.solar_irradiance_w_m2_nm[i];
    let albedo = optics.ground_albedo[i];
    let system = ColumnSystem::new(streams, grid, Some(paths), scaled, solar, albedo)
        .with_sweeps(sweeps)
        .with_shift_pieces(shift_pieces);
    let mut work = Vec::new();
    let mut transmittance = vec![0.0; levels];
    // Per spherical node: the sunlit ground's radiance under the
    // scaled beam, and the sunlight delta-M moved into that beam
    // (W m^-2 nm^-1), for the ground values after the joint solve.
    // The polarisation correction's anchor at this wavelength, if it
    // shares the field's sun node, and the field's scalar solve there.
    let anchor = polarisation.and_then(|(solves, node, _)| Some((solves.anchor_of(i)?, node)));
    let mut anchor_field = None;
    let spherical_nodes = count - first_spherical.min(count);
    let mut ground_direct = vec![0.0; spherical_nodes];
    let mut moved_sunlight = vec![0.0; spherical_nodes];
    for s in 0..count {
        let sun_cosine = sun_axis.angle(s).cos();
        let mut exact_ground = 0.0;
        for k in 0..levels {
            transmittance[k] = match &sun_columns[s * levels + k] {
                None => 0.0,
                Some(columns) => {
                    let (tau_scaled, tau) = scaled_optics.optical_depths(i, columns);
                    if k == 0 {
                        exact_ground = (-tau).exp();
                    }
                    (-tau_scaled).exp()
                }
            };
        }
        let block = &mut out[s * (solution_len + 2)..(s + 1) * (solution_len + 2)];
        let (field, ground) = block.split_at_mut(solution_len);
        let lit = sun_cosine.max(0.0);
        // The ground's sunlight that delta-M moved into the beam
        // (reflected as if diffuse), and the exact direct beam.
        let moved = solar * lit * (transmittance[0] - exact_ground);
        ground[1] = albedo / PI * solar * lit * exact_ground;
        if s >= first_spherical {
            // Solved below with the other spherical nodes.
            moved_sunlight[s - first_spherical] = moved;
            ground_direct[s - first_spherical] = albedo / PI * solar * lit * transmittance[0];
            continue;
        }
        let diffuse = system.solve(sun_cosine, &transmittance, field, &mut work);
        ground[0] = albedo / PI * (diffuse + moved);
        if anchor.is_some_and(|(_, node)| node == s) {
            // Before the twilight shift moves it.
            anchor_field = Some((field.to_vec(), diffuse));
        }
    }
    // The near-horizontal light comes from columns where the sun
    // stands higher or lower (see `twilight_shift.rs`).
    // Only the sun nodes with the column's own first order: with the
    // spherical first order the light from lit columns is in the
    // field already, and the shift's finite difference across the
    // sun axis would carry light into columns that are dark
    // (measured: a zenith of 1e-6 cd/m^2 with the sun 30 degrees
    // below the horizon).
    let mut fields: Vec<&mut [f64]> = out
        .chunks_exact_mut(solution_len + 2)
        .map(|block| &mut block[..solution_len])
        .take(first_spherical)
        .collect();
    system.shift_toward_sources(&sun_axis.angles_rad[..fields.len()], &mut fields);
    // From FIRST_ORDER_SUN_ZENITH_DEG on, the nodes with the spherical first order,
    // all together: each order of the spherical streams shifted in
    // the logarithm before it is scattered again.
    if first_spherical < count {
        let first_orders: Vec<&[f64]> = (first_spherical..count).map(first_of).collect();
        let (mut fields, mut grounds): (Vec<&mut [f64]>, Vec<&mut [f64]>) = out
            .chunks_exact_mut(solution_len + 2)
            .skip(first_spherical)
            .map(|block| block.split_at_mut(solution_len))
            .unzip();
        let diffuse = system.solve_shifted_orders(
            &sun_axis.angles_rad[first_spherical..],
            &ground_direct,
            &first_orders,
            &mut fields,
        );
        for ((ground, diffuse), moved) in grounds.iter_mut().zip(diffuse).zip(&moved_sunlight) {
            ground[0] = albedo / PI * (diffuse + moved);
        }
    }
    if let (Some((solves, _, solutions)), Some((n, _)), Some((field, down))) =
        (polarisation, anchor, anchor_field)
    {
        let mut solution = vec![0.0; solves.solution_len()];
        solves.solve_anchor(n, system, Some((&field, down)), &mut work, &mut solution);
        let mut solutions = solutions.lock().unwrap_or_else(PoisonError::into_inner);
        if solutions.len() <= n {
            solutions.resize(n + 1, None);
        }
        solutions[n] = Some(solution);
    }
}

/// The ground's tables per sun node s and wavelength i at
/// [s * wavelengths + i]: (A / pi)(F*_diffuse + E mu_s (T*_sun - T_sun))
/// and (A / pi) E mu_s T_sun, W m^-2 sr^-1 nm^-1.
fn ground_tables(
    columns: &SolvedColumns,
    wavelengths: usize,
    sun_axis: &SunZenithAxis,
) -> (Vec<f64>, Vec<f64>) {
    let (solved, solution_len) = (&columns.solved, columns.solution_len);
    let count = sun_axis.count();
    let chunk = count * (solution_len + 2);
    let mut ground_diffuse = vec![0.0; count * wavelengths];
    let mut ground_direct = vec![0.0; count * wavelengths];
    for i in 0..wavelengths {
        for s in 0..count {
            let block = &solved[i * chunk + s * (solution_len + 2)..][..solution_len + 2];
            ground_diffuse[s * wavelengths + i] = block[solution_len];
            ground_direct[s * wavelengths + i] = block[solution_len + 1];
        }
    }
    (ground_diffuse, ground_direct)
}

/// The tilted peak beam (`peak_beam.rs`) where the sky's view rays meet a
/// sun low enough for it and some species has a peak, from the rows
/// `kept` holds and with those it adds (the same table as computed anew,
/// bit for bit).
fn compute_peak_beam(
    sky: &SingleScatteringScene,
    (sun_column_nodes, reach_rad): ((usize, usize), Option<f64>),
    (geometry, scaled): (&ColumnGeometry, &ScaledOptics),
    (forward_peak, kept): (&ForwardPeak, &PeakBeamCache),
) -> Option<PeakBeam> {
    let eye_sun_elevation = FRAC_PI_2 - sky.sun_direction().z.clamp(-1.0, 1.0).acos();
    // No reach: the field serves every sun (engine tables).
    let (needed, per_altitude) = match reach_rad {
        None => (
            Some(PeakBeam::every_elevation_deg()),
            NeededElevations::Everywhere,
        ),
        Some(reach) => (
            PeakBeam::needed_elevations_deg(eye_sun_elevation, reach),
            NeededElevations::around_eye(
                eye_sun_elevation,
                sky.observer_radius_m(),
                sky.radii_m(),
                geometry.grid.altitudes_m(),
                reach,
            ),
        ),
    };
    match needed {
        Some(elevations_deg) if forward_peak.any() => {
            let (altitude_nodes, mu_nodes) = sun_column_nodes;
            kept.compute(
                &PeakBeamInputs {
                    optics: sky.optics(),
                    scaled,
                    geometry,
                    sun_columns: &sky.sun_column_table(altitude_nodes, mu_nodes),
                },
                elevations_deg,
                &per_altitude,
            )
        }
        _ => None,
    }
}

/// The parts of a field that depend on the optics and the eye but not on
/// the sun: per number of streams the forward-peak tables and the first
/// order's phase-function table, and the tilted beam's rows. A sky moved
/// to another sun (`SingleScatteringScene::with_sun`) shares them, so that
/// a slider moving the sun computes the tables once and at each new sun
/// only the beam's rows it needs that no sun before it did (they were 7 %,
/// 3 % and 23 % of the explorer's preview at suns 5 to -4 degrees,
/// measured by `perf`). Each field reads the same numbers as it would
/// compute (tested: the peak beam's `the_kept_rows_give_the_table_computed_anew`
/// and the sky's images, `tests/sky_front_door.rs`).
#[derive(Debug, Default)]
pub(crate) struct SunFreeParts {
    by_streams: Mutex<Vec<(usize, StreamParts)>>,
    peak_beams: PeakBeamCache,
}

/// The parts of [`SunFreeParts`] kept per number of streams (the delta-M
/// truncation).
#[derive(Debug, Clone)]
struct StreamParts {
    forward_peak: Arc<ForwardPeak>,
    /// The first order's phase functions ([`tabulate_phases`]).
    first_order_phases: Arc<Vec<f64>>,
}

impl SunFreeParts {
    /// The parts for `streams` streams: a copy of the kept ones, or
    /// `compute()`'s, kept (computed without the lock, which the thread
    /// pool's other tasks may want; of two threads that race, the first
    /// one's are kept: the same numbers).
    fn for_streams(
        &self,
        streams: usize,
        compute: impl FnOnce() -> StreamParts,
    ) -> (Arc<ForwardPeak>, Arc<Vec<f64>>) {
        // A poisoned lock only means that another thread panicked: the
        // entries in it are whole (each is pushed when complete).
        let lock = || {
            self.by_streams
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
        };
        let find = |entries: &[(usize, StreamParts)]| {
            entries
                .iter()
                .find(|(n, _)| *n == streams)
                .map(|(_, parts)| parts.clone())
        };
        // The guard dropped before `compute()` (the lock is not held while
        // computing, nor taken twice).
        let kept = find(&lock());
        let parts = match kept {
            Some(parts) => parts,
            None => {
                let parts = compute();
                let mut entries = lock();
                match find(&entries) {
                    Some(first) => first,
                    None => {
                        entries.push((streams, parts.clone()));
                        parts
                    }
                }
            }
        };
        (parts.forward_peak, parts.first_order_phases)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::Atmosphere;
    use crate::spectrum::WavelengthGrid;
    use crate::transport::Observation;

    /// A polarised field solves its correction's anchors with the scalar
    /// system and solve of its own sun node at the correction column's sun
    /// (`solve_columns`): the correction is the one solved on its own, bit
    /// for bit, for a sun high enough for that node (30 degrees) and one
    /// below the column's lowest sun (-5 degrees, every anchor solved on
    /// its own).
    #[test]
    fn anchors_solved_with_the_field_are_the_correction_solved_alone() {
        let atmosphere = Atmosphere::preset("earth-clear").unwrap();
        let grid = WavelengthGrid::new(440.0, 680.0, 60.0).unwrap();
        for (sun_elevation_deg, shared) in [(30.0, true), (-5.0, false)] {
            let observation = Observation {
                observer_altitude_m: 0.0,
                sun_elevation_deg,
                sun_azimuth_deg: 180.0,
            };
            let sky = SingleScatteringScene::new_with_phase_matrices(
                &atmosphere,
                &grid,
                observation,
                Some(3),
            )
            .unwrap();
            let settings = MultipleScatteringSettings::default();
            let field = MultipleScatteringField::compute(&sky, settings, true).unwrap();
            let geometry = ColumnGeometry::new(&sky, &settings);
            let scaled = ScaledOptics::delta_m(sky.optics(), geometry.streams.count());
            let anchors = WavelengthAnchors::following_optics(
                sky.optics(),
                settings.polarisation_wavelength_stride,
            );
            let column = PolarisationColumn::new(&sky, (&geometry, &scaled), &anchors);
            let axis = &field.optics.sun_axis.angles_rad;
            // Shared where the axis has a node at the column's sun before
            // the spherical first order's.
            let node = axis.iter().position(|a| *a == column.sun_zenith);
            let before_spherical =
                |s: usize| axis[s] < regimes::FIRST_ORDER_SUN_ZENITH_DEG.to_radians();
            assert_eq!(node.is_some_and(before_spherical), shared, "{axis:?}");
            let alone = PolarisationCorrection::compute(&column.inputs());
            let with_field = field.polarisation.as_ref().unwrap().solutions();
            assert_eq!(with_field.len(), alone.solutions().len());
            for (a, b) in with_field.iter().zip(alone.solutions()) {
                assert_eq!(a.to_bits(), b.to_bits(), "{a} {b}");
            }
        }
    }
}
