//! The view ray's march of the fast method: the scaled field's source,
//! the forward-peak integrals and the ground's diffuse light along one
//! view ray ([`ViewRayOptics::march`]), shared by the field's exact
//! synthesis and its source table.
//!
//! At each node the march takes per wavelength: the scaled field's light
//! T* beta*_sca R (one exponential of ln R - tau*), and where the node is
//! sunlit the forward-peak integrals (`forward_peak.rs`: two
//! exponentials, T_sun and T*_sun, or through the view and the sun
//! together where the peaks are not tilted toward a low sun's beam).
//! What depends on the view ray alone is kept per node index for the
//! replayed nodes of a row ([`VIEW_TERMS`]). The node's sums run species
//! by species over the wavelengths (the coefficients species-major,
//! [`SpeciesMajorOptics`]), so that their loops take whole registers (and
//! AVX2's four lanes where the CPU has it, chosen at run time); each
//! value is the same operations in the same order as the sums wavelength
//! by wavelength with the species inside, which are kept as the slow
//! path (`MultipleScatteringScratch::sum_by_wavelength`, held to the fast
//! one bit for bit by the test
//! `the_species_major_sums_are_the_wavelength_major_sums`). Where a
//! wavelength adds nothing (a dark source, a sun beam of zero) the fast
//! sums add +0 instead of skipping it: the sums start at +0, which adding
//! +0 leaves as they are.
//!
//! Skies whose view rays are the same (the same species' profiles, radii,
//! eye, sun and panels: the k-distribution's term skies, which differ in
//! what absorbs only) march a ray once ([`ViewRayOptics::march_alongside`]):
//! the nodes, their densities and columns, their geometry and their
//! columns toward the sun are found by the first sky's march, and every
//! sky's light is taken at each node with its own optics and source, the
//! same operations on the same values as its own march (which stays, the
//! slow path; the sky-view table's test
//! `the_terms_image_tables_built_together_are_each_terms_own` holds them
//! together bit for bit).

use std::ops::ControlFlow;
use std::sync::Arc;

use super::column_optics::{ColumnGeometry, SUN_RAY_PANELS, ScaledOptics};
use super::field::SunZenithAxis;
use super::forward_peak::{self, ForwardPeak};
use super::peak_beam::PeakBeam;
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::transport::optical_column::{LocatedNode, MarchNode, PanelMarch};
use crate::transport::single_scattering::SunColumns;
use crate::transport::vector_exp::{exp_in_place, exp_neg_in_place};

/// Values below this are treated as zero by the logarithmic
/// interpolations (radiances are ~1e-6..1 W m^-2 sr^-1 nm^-1).
pub(super) const LOG_FLOOR: f64 = 1e-30;

/// ln R below which the march takes the source as zero: e^-46 = 1e-20
/// W m^-2 sr^-1 nm^-1 (the logarithms' floor is ln 1e-30 = -69), far below
/// the night floor ([`crate::colour::NIGHT_FLOOR_CD_M2`], ~1e-11 in these
/// units).
pub(super) const DARK_LOG_SOURCE: f64 = -46.0;

/// ln of a non-negative value, floored.
pub(super) fn floored_log(value: f64) -> f64 {
    value.max(LOG_FLOOR).ln()
}

/// a^(1 - t) b^t for positive a, b: exact for quantities that change
/// exponentially between nodes, as everything does across sunset; linear
/// when an end is zero (a ground that reflects nothing, or has no sun).
pub(super) fn interpolate_geometrically(a: f64, b: f64, t: f64) -> f64 {
    if a > 0.0 && b > 0.0 {
        ((1.0 - t) * a.ln() + t * b.ln()).exp()
    } else {
        (1.0 - t) * a + t * b
    }
}

/// What the view-ray march needs, shared by the field and its table.
#[derive(Debug, Clone)]
pub(super) struct ViewRayOptics {
    pub(super) wavelengths: usize,
    pub(super) species: usize,
    pub(super) panels: usize,
    pub(super) observer: Vector3,
    pub(super) sun: Vector3,
    /// The delta-M scaled optics.
    pub(super) scaled: ScaledOptics,
    /// The same coefficients species-major, for the march's loops over
    /// the wavelengths ([`SpeciesMajorOptics`]).
    pub(super) by_species: SpeciesMajorOptics,
    /// The columns' geometry (the profiles' corners cut the rays).
    pub(super) geometry: ColumnGeometry,
    pub(super) sun_axis: SunZenithAxis,
    /// Whether any phase function lost a forward peak to delta-M.
    pub(super) has_forward_peaks: bool,
    /// The forward-peak term's tables (`forward_peak.rs`).
    pub(super) forward_peak: Arc<ForwardPeak>,
    /// Near a low sun, the beam of the peaks' light with the last
    /// scattering at its angle (`peak_beam.rs`), for that term.
    pub(super) peak_beam: Option<PeakBeam>,
    /// [s * wavelengths + i]: (A / pi)(F*_diffuse + E mu_s (T*_sun - T_sun))
    /// at the ground, W m^-2 sr^-1 nm^-1.
    pub(super) ground_diffuse: Vec<f64>,
    /// [s * wavelengths + i]: (A / pi) E mu_s T_sun at the ground.
    pub(super) ground_direct: Vec<f64>,
}

/// Per-ray work space of the march.
#[derive(Debug, Clone)]
pub struct MultipleScatteringScratch {
    /// The view ray's march, and at its current node the species'
    /// relative densities and columns from the eye; the whole ray's
    /// columns after it.
    pub(super) march: PanelMarch,
    pub(super) densities: Vec<f64>,
    pub(super) view_columns: Vec<f64>,
    pub(super) node_columns: Vec<f64>,
    /// ln R(x, view) per wavelength at the current node (R = J / beta*_sca,
    /// radiance units).
    pub(super) log_source: Vec<f64>,
    /// Lambda table of the view direction times cos(m phi) (exact
    /// synthesis), [m * streams + l].
    pub(super) view_legendre: Vec<f64>,
    /// Per march node index, the Lambda table of the view cosine last
    /// synthesised there (before the cos(m phi) weights) and that cosine's
    /// bits: a replayed node (the same view cosine) reads it instead of
    /// computing it again, bit for bit the same table.
    pub(super) node_legendre: Vec<(u64, Vec<f64>)>,
    /// Columns from the current node toward the sun, m.
    pub(super) sun_columns: Vec<f64>,
    /// Ends of the Gauss panels of the view ray and of a path toward the
    /// sun, m along each.
    pub(super) view_panel_ends: Vec<f64>,
    pub(super) sun_panel_ends: Vec<f64>,
    /// The forward-peak integrals of the last ray, species-major
    /// [j * wavelengths + i], m, then the peak-only rows Q and Q X-bar
    /// (`forward_peak.rs`; see [`MultipleScatteringTable::compute_radiance_parts`]).
    pub(super) forward_integrals: Vec<f64>,
    /// The scaled part of the forward-peak integrals' first line,
    /// integral rho_j T* (T*_sun or, near a low sun, T_sun + S~) ds,
    /// species-major, m: what an aerial perspective needs to move the
    /// light from behind a point to the point
    /// ([`MultipleScatteringScratch::scaled_forward_integrals`]).
    pub(super) scaled_forward_integrals: Vec<f64>,
    /// The tilted peak beam B at the current node (`peak_beam.rs`), and
    /// the node's optical depths / transmittances and peak scattering
    /// coefficients and X there ([`ViewRayOptics::add_tilted_forward_peak`]).
    pub(super) beam: Vec<f64>,
    pub(super) tilted_depths: Vec<f64>,
    /// Per wavelength at the current node, 4 blocks of work space for the
    /// march's exponentials (`ViewRayOptics::march`).
    pub(super) node_terms: Vec<f64>,
    pub(super) tilted_peak: Vec<f64>,
    /// Per wavelength at the current node, the forward-peak integrands'
    /// two species factors (the first line's, T* T*_sun - T T_sun or its
    /// tilted form, and its scaled part), each times the node's weight,
    /// and the tilted peak's light reaching the node.
    pub(super) peak_factors: Vec<f64>,
    /// Tests: the node's sums wavelength by wavelength (species inside,
    /// the slow path) instead of species by species over the wavelengths.
    pub(super) by_wavelength: bool,
    /// The view ray's nodes located in the sun-column table, per node
    /// (`SunColumns::compute_columns_to_sun_at_node`).
    pub(super) located: Vec<LocatedNode>,
    /// Per node of the view ray: its radius (m) and view cosine, kept for
    /// the replayed nodes (`PanelMarch::reuse_nodes`).
    pub(super) view_nodes: Vec<(f64, f64)>,
    /// Per node of the view ray, what depends on the view alone
    /// ([`ViewTerms`]), [node * VIEW_TERMS * wavelengths ..]: kept for the
    /// replayed nodes, whose columns and densities are the same bits.
    pub(super) view_terms: Vec<f64>,
    /// Per node: whether its view terms hold their transmittances.
    pub(super) view_exps_filled: Vec<bool>,
    /// Per node of the view ray: its altitude's and view's cells in a
    /// source table, kept for the replayed nodes
    /// (`MultipleScatteringTable::compute_radiance_parts`).
    pub(super) source_cells: Vec<SourceCells>,
    /// The current node's cells in the source table that the march reads
    /// (`MultipleScatteringTable::compute_radiance_parts_together`).
    pub(super) node_cells: NodeCells,
}

/// The blocks of a view node's terms that depend on the view alone, one
/// value per wavelength i each: the scaled and exact optical depths from
/// the eye, sum_j beta*_ext,ij c_j and sum_j beta_ext,ij c_j (c_j the
/// columns from the eye, m; the depths without unit), the scaled
/// scattering sum_j beta*_sca,ij rho_j (m^-1), the peaks' scattering
/// sum_j (beta_ext,ij - beta*_ext,ij) rho_j (m^-1), and
/// (filled where a tilted peak needs them, [`ViewRayOptics::add_tilted_forward_peak`])
/// the transmittances e^-tau* and e^-tau from the eye.
pub(super) const VIEW_TERMS: usize = 6;

/// Another optics marched with a view ray's march
/// ([`ViewRayOptics::march_alongside`]): its scratch, and its outputs (the
/// air's light and the ground's skylight, as `march_from` takes them).
pub(crate) struct Alongside<'a> {
    pub(super) optics: &'a ViewRayOptics,
    pub(super) scratch: &'a mut MultipleScatteringScratch,
    pub(super) field: &'a mut [f64],
    pub(super) ground: &'a mut [f64],
}

/// A march node's altitude cell (level, fraction) and view zenith cell
/// (node, fraction) in a source table.
pub(super) type SourceCells = ((usize, f64), (usize, f64));

/// A march node's cells in a source table: its altitude's, its sun's, its
/// azimuth's from the sun and its view's zenith (node, fraction).
pub(super) type NodeCells = ((usize, f64), (usize, f64), (usize, f64), (usize, f64));

impl MultipleScatteringScratch {
    /// As [`crate::transport::single_scattering::SingleScatteringScratch::reuse_view_nodes`]:
    /// the view rays' densities and columns marched once for the rays of
    /// the same altitudes after them, with the nodes' located cells in
    /// the sun-column and source tables: a scratch that reuses nodes
    /// serves the marches of one source table and one sun-column table
    /// (`MultipleScatteringTable::compute_radiance_parts`).
    pub(crate) fn reuse_view_nodes(&mut self) {
        self.march.reuse_nodes();
    }

    /// Tests: each node's sums wavelength by wavelength with the species
    /// inside (the slow path, the sums as written in the module's
    /// formulas), or species by species over the wavelengths (the
    /// default: the same operations on each value, so the same bits).
    #[cfg(test)]
    pub(crate) fn sum_by_wavelength(&mut self, by_wavelength: bool) {
        self.by_wavelength = by_wavelength;
    }

    /// The forward-peak integrals of the last ray: integral rho_j
    /// (T* T*_sun - T T_sun) ds, species-major [j * wavelengths + i], m,
    /// then the peak-only rows Q = integral (sum_j f_j beta_sca,j rho_j)
    /// T T_sun ds and Q X-bar (dimensionless), as
    /// [`MultipleScatteringField::compute_forward_peak_radiance`] takes them.
    pub(crate) fn forward_integrals(&self) -> &[f64] {
        &self.forward_integrals
    }

    /// The scaled part of the last ray's forward-peak integrals (the
    /// first line's integral rho_j T* T*_sun ds, species-major
    /// [j * wavelengths + i], m; near a low sun with T*_sun replaced by
    /// T_sun + S~ of the tilted beam): the forward integrals' species rows
    /// are these minus integral rho_j T T_sun ds. Seen from a point at s =
    /// d on the ray (T and T* counted from there), the rows of the ray
    /// beyond it are these over T*(d) minus the rest over T(d).
    pub(crate) fn scaled_forward_integrals(&self) -> &[f64] {
        &self.scaled_forward_integrals
    }
}

/// Local geometry of a march node.
#[derive(Debug, Clone, Copy)]
pub(super) struct NodeGeometry {
    pub(super) altitude_m: f64,
    pub(super) sun_cosine: f64,
    pub(super) view_cosine: f64,
    pub(super) cos_azimuth: f64,
    /// Of a view ray's march: the node's index along the ray and whether
    /// it is replayed (`MarchNode::repeated`: its altitude and view cosine
    /// are those of that node of the ray marched last).
    pub(super) march_node: Option<(usize, bool)>,
}

impl ViewRayOptics {
    pub(super) fn scratch(&self, streams: usize) -> MultipleScatteringScratch {
        let (s, w) = (self.species, self.wavelengths);
        MultipleScatteringScratch {
            march: PanelMarch::new(s),
            densities: vec![0.0; s],
            view_columns: vec![0.0; s],
            node_columns: vec![0.0; s],
            log_source: vec![0.0; w],
            view_legendre: vec![0.0; streams * streams],
            node_legendre: Vec::new(),
            sun_columns: vec![0.0; s],
            view_panel_ends: Vec::with_capacity(self.geometry.corners.most_panel_ends(self.panels)),
            sun_panel_ends: Vec::with_capacity(
                self.geometry.corners.most_panel_ends(SUN_RAY_PANELS),
            ),
            forward_integrals: vec![0.0; (s + forward_peak::EXTRA_ROWS) * w],
            scaled_forward_integrals: vec![0.0; s * w],
            beam: vec![0.0; w],
            tilted_depths: vec![0.0; 4 * w],
            node_terms: vec![0.0; 4 * w],
            tilted_peak: vec![0.0; 2 * w],
            peak_factors: vec![0.0; 3 * w],
            by_wavelength: false,
            located: Vec::new(),
            view_nodes: Vec::new(),
            view_terms: Vec::new(),
            view_exps_filled: Vec::new(),
            source_cells: Vec::new(),
            node_cells: ((0, 0.0), (0, 0.0), (0, 0.0), (0, 0.0)),
        }
    }

    /// Integrates T*(eye, x) beta*_sca(x) R(x) along the view ray from the
    /// eye to `distance_m` m (or the ray's end in the atmosphere, if
    /// nearer; `f64::INFINITY` for the whole ray), with `source` writing
    /// ln R at each node into `scratch.log_source`, into `field`; the
    /// ground's skylight (its diffuse term) seen where the ray ends on the
    /// ground, through the scaled transmittance, into `ground` (zero where
    /// the segment does not reach the ground). W m^-2 sr^-1 nm^-1.
    pub(super) fn march<F>(
        &self,
        segment: (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        out: (&mut [f64], &mut [f64]),
        source: F,
    ) where
        F: FnMut(NodeGeometry, &[f64], &mut MultipleScatteringScratch),
    {
        self.march_from(0.0, segment, sun_columns, scratch, out, source);
    }

    /// [`ViewRayOptics::march`] of the part of the view ray from `from_m`
    /// m on (the start where the ray enters the atmosphere, if later): its
    /// columns, transmittances and peak optical depths counted from there,
    /// as if the eye were at that point.
    pub(super) fn march_from<F>(
        &self,
        from_m: f64,
        segment: (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        out: (&mut [f64], &mut [f64]),
        source: F,
    ) where
        F: FnMut(NodeGeometry, &[f64], &mut MultipleScatteringScratch),
    {
        self.march_alongside(
            from_m,
            segment,
            sun_columns,
            (scratch, out),
            source,
            &mut [],
            |_, _, _, _| {},
        );
    }

    /// [`ViewRayOptics::march_from`], and with it the same march of every
    /// optics of `others` (each with its scratch and its two outputs, as
    /// `march_from` takes them) whose view rays are this one's
    /// ([`ViewRayOptics::has_view_geometry_of`]) and whose columns toward
    /// the sun are `sun_columns`' (the k-distribution's term skies, which
    /// differ in what absorbs only): the ray's nodes, their densities and
    /// columns, their geometry and their columns toward the sun are found
    /// once, and each of the others' light is taken at each node with this
    /// one's, `other_source(index in others, node, this one's scratch, its
    /// scratch)`
    /// writing its ln R into its scratch's `log_source` (this one's
    /// `source` has run at the node). Each of the others' outputs are bit
    /// for bit what its own `march_from` gives: the same operations on the
    /// same values, its view terms kept per node index in its own scratch
    /// as its own march keeps them.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn march_alongside<F, G>(
        &self,
        from_m: f64,
        (view, distance_m): (Vector3, f64),
        sun_columns: SunColumns,
        (scratch, (field, ground_out)): (&mut MultipleScatteringScratch, (&mut [f64], &mut [f64])),
        mut source: F,
        others: &mut [Alongside],
        mut other_source: G,
    ) where
        F: FnMut(NodeGeometry, &[f64], &mut MultipleScatteringScratch),
        G: FnMut(usize, NodeGeometry, &MultipleScatteringScratch, &mut MultipleScatteringScratch),
    {
        debug_assert!(others.iter().all(|o| o.optics.has_view_geometry_of(self)));
        let radiance = field;
        radiance.fill(0.0);
        ground_out.fill(0.0);
        scratch.forward_integrals.fill(0.0);
        scratch.scaled_forward_integrals.fill(0.0);
        for other in others.iter_mut() {
            other.field.fill(0.0);
            other.ground.fill(0.0);
            other.scratch.forward_integrals.fill(0.0);
            other.scratch.scaled_forward_integrals.fill(0.0);
            other.scratch.view_columns.fill(0.0);
        }
        // Whether a node's columns toward the sun are asked for.
        let needs_sun_columns =
            self.has_forward_peaks || others.iter().any(|o| o.optics.has_forward_peaks);
        let (ground, top) = (self.geometry.ground_radius_m, self.geometry.top_radius_m);
        let (profiles, corners) = (&self.geometry.profiles, &self.geometry.corners);
        let Some((enter, exit)) = segment_in_atmosphere(self.observer, view, ground, top) else {
            return;
        };
        let enter = enter.max(from_m);
        let start = self.observer + view * enter;
        let length = exit.min(distance_m) - enter;
        scratch.view_columns.fill(0.0);
        if length > 0.0 {
            let mut view_ends = std::mem::take(&mut scratch.view_panel_ends);
            // Per node, the terms of the view alone: a replayed node's are
            // the node's it repeats (the same columns and densities, bit
            // for bit), so they are computed once per row of rays.
            let mut view_terms = std::mem::take(&mut scratch.view_terms);
            let mut view_exps_filled = std::mem::take(&mut scratch.view_exps_filled);
            corners.fill_panel_ends(start, view, length, self.panels, &mut view_ends);
            let mut march = std::mem::take(&mut scratch.march);
            march.march(
                profiles,
                ground,
                (start, view),
                &view_ends,
                |node, node_columns, densities| {
                    scratch.node_columns.copy_from_slice(node_columns);
                    scratch.densities.copy_from_slice(densities);
                    // A replayed node's radius and view cosine are those
                    // of the node it repeats (the same to rounding).
                    let cached = scratch.view_nodes.get(node.index).filter(|_| node.repeated);
                    let (r, view_cosine) = match cached {
                        Some(kept) => *kept,
                        None => {
                            let r = node.point.length();
                            let view_cosine = view.dot(node.point * (1.0 / r)).clamp(-1.0, 1.0);
                            if scratch.view_nodes.len() <= node.index {
                                scratch.view_nodes.resize(node.index + 1, (0.0, 0.0));
                            }
                            scratch.view_nodes[node.index] = (r, view_cosine);
                            (r, view_cosine)
                        }
                    };
                    let zenith = node.point * (1.0 / r);
                    let sun_cosine = self.sun.dot(zenith).clamp(-1.0, 1.0);
                    let sines = ((1.0 - view_cosine * view_cosine)
                        * (1.0 - sun_cosine * sun_cosine))
                        .sqrt();
                    let cos_azimuth = if sines > 1e-12 {
                        ((view.dot(self.sun) - view_cosine * sun_cosine) / sines).clamp(-1.0, 1.0)
                    } else {
                        1.0
                    };
                    let geometry = NodeGeometry {
                        altitude_m: r - ground,
                        sun_cosine,
                        view_cosine,
                        cos_azimuth,
                        march_node: Some((node.index, node.repeated)),
                    };
                    let densities = std::mem::take(&mut scratch.densities);
                    source(geometry, &densities, scratch);
                    scratch.densities = densities;
                    // What delta-M moved from single scattering into the
                    // sun's beam and the view's transmittance (see the
                    // module docs, TMS) needs the node's columns toward
                    // the sun: found once for every optics.
                    let sunlit = needs_sun_columns
                        && sun_columns.compute_columns_to_sun_at_node(
                            profiles,
                            corners,
                            &node,
                            self.sun,
                            &mut scratch.located,
                            &mut scratch.sun_panel_ends,
                            &mut scratch.sun_columns,
                        );
                    // Every sky's source first (the reads of tables
                    // apart, independent of each other, can overlap),
                    // then every sky's light.
                    for (t, other) in others.iter_mut().enumerate() {
                        let own = &mut *other.scratch;
                        own.node_columns.copy_from_slice(node_columns);
                        own.densities.copy_from_slice(&scratch.densities);
                        other_source(t, geometry, scratch, own);
                        if sunlit && other.optics.has_forward_peaks {
                            own.sun_columns.copy_from_slice(&scratch.sun_columns);
                        }
                    }
                    self.add_node_light(
                        (&node, r, sun_cosine, sunlit),
                        scratch,
                        (&mut view_terms, &mut view_exps_filled),
                        radiance,
                    );
                    for other in others.iter_mut() {
                        let own = &mut *other.scratch;
                        let mut terms = std::mem::take(&mut own.view_terms);
                        let mut filled = std::mem::take(&mut own.view_exps_filled);
                        other.optics.add_node_light(
                            (&node, r, sun_cosine, sunlit),
                            own,
                            (&mut terms, &mut filled),
                            other.field,
                        );
                        own.view_terms = terms;
                        own.view_exps_filled = filled;
                    }
                    ControlFlow::Continue(())
                },
            );
            scratch.view_columns.copy_from_slice(march.columns());
            for other in others.iter_mut() {
                other.scratch.view_columns.copy_from_slice(march.columns());
            }
            scratch.march = march;
            scratch.view_panel_ends = view_ends;
            scratch.view_terms = view_terms;
            scratch.view_exps_filled = view_exps_filled;
        }
        let end = start + view * length;
        if distance_m >= exit && end.length() <= ground * (1.0 + 1e-12) {
            let sun_cosine = self.sun.dot(end.normalized());
            self.add_ground_skylight(sun_cosine, &scratch.view_columns, ground_out);
            for other in others.iter_mut() {
                other.optics.add_ground_skylight(
                    sun_cosine,
                    &other.scratch.view_columns,
                    other.ground,
                );
            }
        }
    }

    /// The ground's skylight (its diffuse term) seen through the view's
    /// columns `view_columns` from the eye to the ground, where the sun's
    /// zenith cosine is `sun_cosine`, into `ground_out`.
    fn add_ground_skylight(&self, sun_cosine: f64, view_columns: &[f64], ground_out: &mut [f64]) {
        let (w, s) = (self.wavelengths, self.species);
        let (extinction, scaled_extinction) =
            (&self.scaled.extinction, &self.scaled.scaled_extinction);
        let (node, t) = self.sun_axis.locate(sun_cosine);
        let next = node + 1;
        for i in 0..w {
            let (mut tau_scaled, mut tau) = (0.0, 0.0);
            for j in 0..s {
                tau_scaled += scaled_extinction[i * s + j] * view_columns[j];
                tau += extinction[i * s + j] * view_columns[j];
            }
            let lerp = |table: &[f64]| {
                interpolate_geometrically(table[node * w + i], table[next * w + i], t)
            };
            let (scaled, exact) = ((-tau_scaled).exp(), (-tau).exp());
            ground_out[i] =
                scaled * lerp(&self.ground_diffuse) + (scaled - exact) * lerp(&self.ground_direct);
        }
    }

    /// One node's light of the march ([`ViewRayOptics::march_alongside`]):
    /// the node `node` at radius `r` (m) with the sun at zenith cosine
    /// `sun_cosine`, its columns toward the sun in `scratch.sun_columns`
    /// where `sunlit`, its densities, columns from the eye and ln R in
    /// `scratch`; the scaled field's light added to `radiance`, the
    /// forward-peak integrals to the scratch's. `view_terms` holds the
    /// view terms per node index (and whether their transmittances are
    /// filled), computed here where the node is not a replayed one.
    fn add_node_light(
        &self,
        (node, r, sun_cosine, sunlit): (&MarchNode, f64, f64, bool),
        scratch: &mut MultipleScatteringScratch,
        (view_terms, view_exps_filled): (&mut Vec<f64>, &mut Vec<bool>),
        radiance: &mut [f64],
    ) {
        let w = self.wavelengths;
        let terms_length = VIEW_TERMS * w;
        let terms_end = (node.index + 1) * terms_length;
        if !(node.repeated && view_terms.len() >= terms_end) {
            if view_terms.len() < terms_end {
                view_terms.resize(terms_end, 0.0);
                view_exps_filled.resize(node.index + 1, false);
            }
            let node_terms = &mut view_terms[terms_end - terms_length..terms_end];
            if scratch.by_wavelength {
                self.fill_view_terms_by_wavelength(
                    &scratch.node_columns,
                    &scratch.densities,
                    node_terms,
                );
            } else {
                self.fill_view_terms(&scratch.node_columns, &scratch.densities, node_terms);
            }
            view_exps_filled[node.index] = false;
        }
        let terms = &mut view_terms[terms_end - terms_length..terms_end];
        // T*(eye, x) beta*_sca(x) R(x): one exponential per
        // wavelength for the transmittance and the source.
        let weight = node.weight;
        if scratch.by_wavelength {
            self.add_source_light_by_wavelength(weight, terms, scratch, radiance);
        } else {
            self.add_source_light(weight, terms, scratch, radiance);
        }
        // What delta-M moved from single scattering into the sun's beam
        // and the view's transmittance (see the module docs, TMS).
        let lit = self.has_forward_peaks && sunlit;
        let share = match &self.peak_beam {
            Some(beam) if self.has_forward_peaks => {
                beam.lookup_beam(r, sun_cosine, &mut scratch.beam)
            }
            _ => 0.0,
        };
        if share > 0.0 {
            if !view_exps_filled[node.index] {
                let (depths, transmittances) = terms.split_at_mut(4 * w);
                transmittances.copy_from_slice(&depths[..2 * w]);
                exp_neg_in_place(transmittances);
                view_exps_filled[node.index] = true;
            }
            if scratch.by_wavelength {
                self.add_tilted_forward_peak_by_wavelength(weight, lit, share, terms, scratch);
            } else {
                self.add_tilted_forward_peak(weight, lit, share, terms, scratch);
            }
        } else if lit {
            if scratch.by_wavelength {
                self.add_forward_peak_by_wavelength(weight, terms, scratch);
            } else {
                self.add_forward_peak(weight, terms, scratch);
            }
        }
    }

    /// Whether `other`'s view rays march the same nodes as this one's
    /// and their paths toward the sun are the same: the same species'
    /// profiles (in order), radii, eye, sun and panels (what
    /// [`ViewRayOptics::march_alongside`] shares); their optics may differ.
    pub(super) fn has_view_geometry_of(&self, other: &ViewRayOptics) -> bool {
        self.geometry.profiles == other.geometry.profiles
            && (self.geometry.ground_radius_m, self.geometry.top_radius_m)
                == (other.geometry.ground_radius_m, other.geometry.top_radius_m)
            && self.observer == other.observer
            && self.sun == other.sun
            && self.panels == other.panels
            && self.species == other.species
    }

    /// The view terms of a node ([`VIEW_TERMS`] blocks) from its columns
    /// from the eye and its relative densities, into `terms` (all but the
    /// transmittances): species by species over the wavelengths, each
    /// value the sum over the species in their order, as
    /// [`Self::fill_view_terms_by_wavelength`] (the slow path) takes it.
    fn fill_view_terms(&self, columns: &[f64], densities: &[f64], terms: &mut [f64]) {
        let (w, s) = (self.wavelengths, self.species);
        let by = &self.by_species;
        let (scaled, rest) = terms.split_at_mut(w);
        let (exact, rest) = rest.split_at_mut(w);
        let (scattering, rest) = rest.split_at_mut(w);
        let peak = &mut rest[..w];
        for row in [&mut *scaled, &mut *exact, &mut *scattering, &mut *peak] {
            row.fill(0.0);
        }
        for j in 0..s {
            let (column, density) = (columns[j], densities[j]);
            let (beta_scaled, beta) = (by.scaled_extinction(j), by.extinction(j));
            let (scaled_scattering, peaks) = (by.scaled_scattering(j), by.peak_scattering(j));
            for i in 0..w {
                scaled[i] += beta_scaled[i] * column;
                exact[i] += beta[i] * column;
                scattering[i] += scaled_scattering[i] * density;
                // f_j beta_sca,j rho_j: what the peaks scatter here.
                peak[i] += peaks[i] * density;
            }
        }
    }

    /// [`Self::fill_view_terms`] wavelength by wavelength, the species
    /// inside (the slow path, `sum_by_wavelength`).
    fn fill_view_terms_by_wavelength(&self, columns: &[f64], densities: &[f64], terms: &mut [f64]) {
        let (w, s) = (self.wavelengths, self.species);
        let (extinction, scaled_extinction) =
            (&self.scaled.extinction, &self.scaled.scaled_extinction);
        let scaled_scattering = &self.scaled.scaled_scattering;
        for i in 0..w {
            let (mut scaled, mut exact, mut scattering, mut peak) = (0.0, 0.0, 0.0, 0.0);
            for j in 0..s {
                let (beta_scaled, beta) = (scaled_extinction[i * s + j], extinction[i * s + j]);
                scaled += beta_scaled * columns[j];
                exact += beta * columns[j];
                scattering += scaled_scattering[i * s + j] * densities[j];
                // f_j beta_sca,j rho_j: what the peaks scatter here.
                peak += (beta - beta_scaled) * densities[j];
            }
            terms[i] = scaled;
            terms[w + i] = exact;
            terms[2 * w + i] = scattering;
            terms[3 * w + i] = peak;
        }
    }

    /// A node's view terms whole ([`VIEW_TERMS`] blocks, the
    /// transmittances from the eye included), for a march of its own
    /// (prototype measurements).
    #[cfg(test)]
    pub(super) fn view_terms(&self, columns: &[f64], densities: &[f64]) -> Vec<f64> {
        let w = self.wavelengths;
        let mut terms = vec![0.0; VIEW_TERMS * w];
        self.fill_view_terms(columns, densities, &mut terms);
        let (depths, transmittances) = terms.split_at_mut(4 * w);
        transmittances.copy_from_slice(&depths[..2 * w]);
        exp_neg_in_place(transmittances);
        terms
    }

    /// The forward-peak integrals of one view node (the march's weight
    /// `weight`, m; its view terms, transmittances included, in
    /// `view_terms`; its densities and, where `lit`, its columns toward
    /// the sun in `scratch`) with the peaks' light reaching the
    /// node S = T*_sun - T_sun moved toward the tilted beam B of
    /// `scratch.beam` by `share` (`peak_beam.rs`): the first line's
    /// T* T*_sun - T T_sun becomes T* S~ + T_sun (T* - T), the peak-only
    /// light's weight T T_sun is scaled by (T_sun + S~) / T*_sun.
    pub(super) fn add_tilted_forward_peak(
        &self,
        weight: f64,
        lit: bool,
        share: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::transport::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.add_tilted_forward_peak_avx2(weight, lit, share, view_terms, scratch) };
            return;
        }
        self.add_tilted_forward_peak_portable(weight, lit, share, view_terms, scratch);
    }

    /// [`Self::add_tilted_forward_peak`] compiled for AVX2 (4 lanes of
    /// f64 across the wavelengths; the same operations per lane, so the
    /// same bits as the portable form: `vector_exp.rs`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_tilted_forward_peak_avx2(
        &self,
        weight: f64,
        lit: bool,
        share: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        self.add_tilted_forward_peak_portable(weight, lit, share, view_terms, scratch);
    }

    /// [`Self::add_tilted_forward_peak`] wavelength by wavelength, the
    /// species inside (the slow path, `sum_by_wavelength`): the sums as
    /// the module's formulas write them.
    fn add_tilted_forward_peak_by_wavelength(
        &self,
        weight: f64,
        lit: bool,
        share: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        let (w, s) = (self.wavelengths, self.species);
        // T* and T from the eye, and the view's parts of the optical depths.
        let (view_scaled_depths, view_depths) = (&view_terms[..w], &view_terms[w..2 * w]);
        let peaks = &view_terms[3 * w..4 * w];
        let (view_beam, view_direct) = (&view_terms[4 * w..5 * w], &view_terms[5 * w..6 * w]);
        // Optical depths toward the sun, then (in place) T*_sun and
        // T_sun, per wavelength; the sun's columns are there where lit.
        let (sun_beam, rest) = scratch.tilted_depths.split_at_mut(w);
        let sun_direct = &mut rest[..w];
        if lit {
            for i in 0..w {
                let (mut scaled_depth, mut depth) = (0.0, 0.0);
                for j in 0..s {
                    scaled_depth +=
                        self.scaled.scaled_extinction[i * s + j] * scratch.sun_columns[j];
                    depth += self.scaled.extinction[i * s + j] * scratch.sun_columns[j];
                }
                sun_beam[i] = scaled_depth;
                sun_direct[i] = depth;
                // X, the peaks' optical depth of both legs.
                scratch.tilted_peak[w + i] =
                    (view_depths[i] + depth) - (view_scaled_depths[i] + scaled_depth);
            }
            exp_neg_in_place(&mut scratch.tilted_depths[..2 * w]);
        }
        let (sun_beam, rest) = scratch.tilted_depths.split_at(w);
        let sun_direct = &rest[..w];
        for i in 0..w {
            let (sun_beam, sun_direct) = if lit {
                (sun_beam[i], sun_direct[i])
            } else {
                (0.0, 0.0)
            };
            let forward = sun_beam - sun_direct;
            let scattered = forward + share * (scratch.beam[i] - forward);
            let excess =
                weight * (view_beam[i] * scattered + sun_direct * (view_beam[i] - view_direct[i]));
            let beam = weight * view_beam[i] * (scattered + sun_direct);
            for j in 0..s {
                scratch.forward_integrals[j * w + i] += excess * scratch.densities[j];
                scratch.scaled_forward_integrals[j * w + i] += beam * scratch.densities[j];
            }
            if lit && sun_beam > 0.0 {
                let only = weight
                    * view_direct[i]
                    * sun_direct
                    * peaks[i]
                    * ((sun_direct + scattered) / sun_beam);
                let x = scratch.tilted_peak[w + i];
                scratch.forward_integrals[s * w + i] += only;
                scratch.forward_integrals[(s + 1) * w + i] += only * x;
            }
        }
    }

    /// [`Self::add_tilted_forward_peak`] in the target's baseline
    /// instructions: species by species over the wavelengths (each value
    /// the same operations in the same order as
    /// [`Self::add_tilted_forward_peak_by_wavelength`], so the same bits;
    /// the loops run across the wavelengths, in whole registers).
    #[inline(always)]
    fn add_tilted_forward_peak_portable(
        &self,
        weight: f64,
        lit: bool,
        share: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        let (w, s) = (self.wavelengths, self.species);
        let by = &self.by_species;
        let MultipleScatteringScratch {
            tilted_depths,
            tilted_peak,
            sun_columns,
            beam,
            densities,
            forward_integrals,
            scaled_forward_integrals,
            peak_factors,
            ..
        } = scratch;
        // T* and T from the eye, and the view's parts of the optical depths.
        let (view_scaled_depths, view_depths) = (&view_terms[..w], &view_terms[w..2 * w]);
        let peaks = &view_terms[3 * w..4 * w];
        let (view_beam, view_direct) = (&view_terms[4 * w..5 * w], &view_terms[5 * w..6 * w]);
        if lit {
            // Optical depths toward the sun, then (in place) T*_sun and
            // T_sun, per wavelength.
            let (sun_beam, rest) = tilted_depths.split_at_mut(w);
            by.optical_depths(|j| sun_columns[j], sun_beam, &mut rest[..w]);
            let sun_direct = &rest[..w];
            // X, the peaks' optical depth of both legs.
            for i in 0..w {
                tilted_peak[w + i] =
                    (view_depths[i] + sun_direct[i]) - (view_scaled_depths[i] + sun_beam[i]);
            }
            exp_neg_in_place(&mut tilted_depths[..2 * w]);
        }
        let (sun_beam, rest) = tilted_depths.split_at(w);
        let sun_direct = &rest[..w];
        let (excess, rest) = peak_factors.split_at_mut(w);
        let (beam_factor, scattered) = rest.split_at_mut(w);
        for i in 0..w {
            let (sun_beam, sun_direct) = if lit {
                (sun_beam[i], sun_direct[i])
            } else {
                (0.0, 0.0)
            };
            let forward = sun_beam - sun_direct;
            scattered[i] = forward + share * (beam[i] - forward);
            excess[i] = weight
                * (view_beam[i] * scattered[i] + sun_direct * (view_beam[i] - view_direct[i]));
            beam_factor[i] = weight * view_beam[i] * (scattered[i] + sun_direct);
        }
        add_species_rows(
            densities,
            (&*excess, &*beam_factor),
            (
                &mut forward_integrals[..],
                &mut scaled_forward_integrals[..],
            ),
        );
        if lit {
            let (only_row, rest) = forward_integrals[s * w..].split_at_mut(w);
            let x_row = &mut rest[..w];
            for i in 0..w {
                let (sun_beam, sun_direct) = (sun_beam[i], sun_direct[i]);
                let only = weight
                    * view_direct[i]
                    * sun_direct
                    * peaks[i]
                    * ((sun_direct + scattered[i]) / sun_beam);
                let x = tilted_peak[w + i];
                // Adding zero leaves a sum that starts at +0 as it is.
                let kept = sun_beam > 0.0;
                only_row[i] += if kept { only } else { 0.0 };
                x_row[i] += if kept { only * x } else { 0.0 };
            }
        }
    }

    /// The node's light from the scaled field's source, T*(eye, x)
    /// beta*_sca(x) R(x) times the march's weight `weight`, added to
    /// `radiance` (ln R in `scratch.log_source`, the node's view terms in
    /// `view_terms`): one exponential per wavelength.
    fn add_source_light(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::transport::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.add_source_light_avx2(weight, view_terms, scratch, radiance) };
            return;
        }
        self.add_source_light_portable(weight, view_terms, scratch, radiance);
    }

    /// [`Self::add_source_light`] compiled for AVX2 (the same operations
    /// per lane, so the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_source_light_avx2(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        self.add_source_light_portable(weight, view_terms, scratch, radiance);
    }

    /// [`Self::add_source_light`] in the target's baseline instructions:
    /// the dark or non-scattering wavelengths add zero instead of being
    /// skipped (the sums start at +0, which adding +0 leaves as they
    /// are), so the loop runs in whole registers.
    #[inline(always)]
    fn add_source_light_portable(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        let w = self.wavelengths;
        let exponents = &mut scratch.node_terms[..w];
        let log_source = &scratch.log_source[..w];
        for ((exponent, log), depth) in exponents.iter_mut().zip(log_source).zip(view_terms) {
            *exponent = log - depth;
        }
        exp_in_place(exponents);
        let scatterings = &view_terms[2 * w..3 * w];
        for (((out, scattering), light), log) in radiance[..w]
            .iter_mut()
            .zip(scatterings)
            .zip(exponents.iter())
            .zip(log_source)
        {
            // A source at the logarithms' floor is no light (the
            // interpolation between a dark node, 1e-30, and a lit one
            // would otherwise leave numerical noise in the night sky).
            let lit = *scattering > 0.0 && *log > DARK_LOG_SOURCE;
            let term = weight * scattering * light;
            *out += if lit { term } else { 0.0 };
        }
    }

    /// [`Self::add_source_light`] wavelength by wavelength, skipping the
    /// dark ones (the slow path, `sum_by_wavelength`).
    fn add_source_light_by_wavelength(
        &self,
        weight: f64,
        terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        let w = self.wavelengths;
        let exponents = &mut scratch.node_terms[..w];
        for i in 0..w {
            exponents[i] = scratch.log_source[i] - terms[i];
        }
        exp_in_place(exponents);
        let scatterings = &terms[2 * w..3 * w];
        for (i, out) in radiance.iter_mut().enumerate() {
            if scatterings[i] > 0.0 && scratch.log_source[i] > DARK_LOG_SOURCE {
                *out += weight * scatterings[i] * exponents[i];
            }
        }
    }

    /// The forward-peak integrals of one sunlit view node away from a
    /// low sun (no tilted beam: the march's weight `weight`, m; its view
    /// terms in `view_terms`; its densities and its columns from the eye
    /// and toward the sun in `scratch`): the first line's T* T*_sun - T
    /// T_sun and its scaled part T* T*_sun per species, the peak-only
    /// light's weight T T_sun and X.
    fn add_forward_peak(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        #[cfg(target_arch = "x86_64")]
        if crate::transport::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.add_forward_peak_avx2(weight, view_terms, scratch) };
            return;
        }
        self.add_forward_peak_portable(weight, view_terms, scratch);
    }

    /// [`Self::add_forward_peak`] compiled for AVX2 (the same operations
    /// per lane, so the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn add_forward_peak_avx2(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        self.add_forward_peak_portable(weight, view_terms, scratch);
    }

    /// [`Self::add_forward_peak`] in the target's baseline instructions,
    /// species by species over the wavelengths (the same operations on
    /// each value as [`Self::add_forward_peak_by_wavelength`]).
    #[inline(always)]
    fn add_forward_peak_portable(
        &self,
        weight: f64,
        view_terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        let (w, s) = (self.wavelengths, self.species);
        let by = &self.by_species;
        let MultipleScatteringScratch {
            node_terms,
            node_columns,
            sun_columns,
            densities,
            forward_integrals,
            scaled_forward_integrals,
            peak_factors,
            ..
        } = scratch;
        // Optical depths (exact, scaled), then in place their
        // transmittances, all together: [exact depths, scaled depths,
        // direct, through].
        let (exact_depths, rest) = node_terms.split_at_mut(w);
        by.optical_depths(
            |j| node_columns[j] + sun_columns[j],
            &mut rest[..w],
            exact_depths,
        );
        let (depths, transmittances) = node_terms.split_at_mut(2 * w);
        transmittances.copy_from_slice(depths);
        exp_neg_in_place(transmittances);
        let (excess, rest) = peak_factors.split_at_mut(w);
        let beam = &mut rest[..w];
        for i in 0..w {
            let (direct, through) = (transmittances[i], transmittances[w + i]);
            excess[i] = weight * (through - direct);
            beam[i] = weight * through;
        }
        add_species_rows(
            densities,
            (&*excess, &*beam),
            (
                &mut forward_integrals[..],
                &mut scaled_forward_integrals[..],
            ),
        );
        // The peak-only light: its weight and the peak optical depth X
        // of its two legs.
        let peaks = &view_terms[3 * w..4 * w];
        let (only_row, rest) = forward_integrals[s * w..].split_at_mut(w);
        let x_row = &mut rest[..w];
        for i in 0..w {
            let only = weight * transmittances[i] * peaks[i];
            only_row[i] += only;
            x_row[i] += only * (depths[i] - depths[w + i]);
        }
    }

    /// [`Self::add_forward_peak`] wavelength by wavelength, the species
    /// inside (the slow path, `sum_by_wavelength`).
    fn add_forward_peak_by_wavelength(
        &self,
        weight: f64,
        terms: &[f64],
        scratch: &mut MultipleScatteringScratch,
    ) {
        let (w, s) = (self.wavelengths, self.species);
        let (extinction, scaled_extinction) =
            (&self.scaled.extinction, &self.scaled.scaled_extinction);
        let (exact_depths, rest) = scratch.node_terms.split_at_mut(w);
        let scaled_depths = &mut rest[..w];
        for i in 0..w {
            let (mut scaled, mut exact) = (0.0, 0.0);
            for j in 0..s {
                let column = scratch.node_columns[j] + scratch.sun_columns[j];
                scaled += scaled_extinction[i * s + j] * column;
                exact += extinction[i * s + j] * column;
            }
            exact_depths[i] = exact;
            scaled_depths[i] = scaled;
        }
        let (depths, transmittances) = scratch.node_terms.split_at_mut(2 * w);
        transmittances.copy_from_slice(depths);
        exp_neg_in_place(transmittances);
        for i in 0..w {
            let peak = terms[3 * w + i];
            let (exact, scaled) = (depths[i], depths[w + i]);
            let (direct, through) = (transmittances[i], transmittances[w + i]);
            let excess = weight * (through - direct);
            let beam = weight * through;
            for j in 0..s {
                scratch.forward_integrals[j * w + i] += excess * scratch.densities[j];
                scratch.scaled_forward_integrals[j * w + i] += beam * scratch.densities[j];
            }
            let only = weight * direct * peak;
            scratch.forward_integrals[s * w + i] += only;
            scratch.forward_integrals[(s + 1) * w + i] += only * (exact - scaled);
        }
    }
}

/// Adds to the forward-peak integrals' species rows (`rows.0`, and the
/// scaled part's, `rows.1`, [j * wavelengths + i]) a node's factors
/// (`factors`, per wavelength) times each species' relative density.
#[inline(always)]
fn add_species_rows(
    densities: &[f64],
    (excess, beam): (&[f64], &[f64]),
    (forward, scaled): (&mut [f64], &mut [f64]),
) {
    let w = excess.len();
    for (j, density) in densities.iter().enumerate() {
        let (forward, scaled) = (&mut forward[j * w..][..w], &mut scaled[j * w..][..w]);
        for i in 0..w {
            forward[i] += excess[i] * density;
            scaled[i] += beam[i] * density;
        }
    }
}

/// The view march's coefficients per unit relative density, m^-1,
/// species-major ([j * wavelengths + i], where [`ScaledOptics`] holds
/// them [i * species + j]), so that the march's loops run across the
/// wavelengths: the extinction, the delta-M scaled extinction and
/// scattering, and the peaks' scattering beta_ext - beta*_ext = f
/// beta_sca (the same subtraction the sums took per node).
#[derive(Debug, Clone)]
pub(super) struct SpeciesMajorOptics {
    wavelengths: usize,
    extinction: Vec<f64>,
    scaled_extinction: Vec<f64>,
    scaled_scattering: Vec<f64>,
    peak_scattering: Vec<f64>,
}

impl SpeciesMajorOptics {
    /// The optical depths (1) of columns `column(j)` (m) of every species
    /// j, delta-M scaled into `scaled` and exact into `exact`, per
    /// wavelength: each the sum over the species in their order.
    #[inline(always)]
    fn optical_depths(&self, column: impl Fn(usize) -> f64, scaled: &mut [f64], exact: &mut [f64]) {
        scaled.fill(0.0);
        exact.fill(0.0);
        for j in 0..self.extinction.len() / self.wavelengths {
            let column = column(j);
            let (beta_scaled, beta) = (self.scaled_extinction(j), self.extinction(j));
            for i in 0..scaled.len() {
                scaled[i] += beta_scaled[i] * column;
                exact[i] += beta[i] * column;
            }
        }
    }

    /// `scaled`'s coefficients for `wavelengths` wavelengths and `species`
    /// species, species-major.
    pub(super) fn new(scaled: &ScaledOptics, wavelengths: usize, species: usize) -> Self {
        let transposed = |values: &[f64]| -> Vec<f64> {
            (0..species)
                .flat_map(|j| (0..wavelengths).map(move |i| values[i * species + j]))
                .collect()
        };
        let extinction = transposed(&scaled.extinction);
        let scaled_extinction = transposed(&scaled.scaled_extinction);
        let peak_scattering = extinction
            .iter()
            .zip(&scaled_extinction)
            .map(|(beta, beta_scaled)| beta - beta_scaled)
            .collect();
        SpeciesMajorOptics {
            wavelengths,
            scaled_scattering: transposed(&scaled.scaled_scattering),
            extinction,
            scaled_extinction,
            peak_scattering,
        }
    }

    fn row<'a>(&self, values: &'a [f64], j: usize) -> &'a [f64] {
        &values[j * self.wavelengths..(j + 1) * self.wavelengths]
    }

    fn extinction(&self, j: usize) -> &[f64] {
        self.row(&self.extinction, j)
    }

    fn scaled_extinction(&self, j: usize) -> &[f64] {
        self.row(&self.scaled_extinction, j)
    }

    fn scaled_scattering(&self, j: usize) -> &[f64] {
        self.row(&self.scaled_scattering, j)
    }

    fn peak_scattering(&self, j: usize) -> &[f64] {
        self.row(&self.peak_scattering, j)
    }
}
