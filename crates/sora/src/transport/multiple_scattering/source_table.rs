//! The multiple-scattering source tabulated for images.
//!
//! Synthesising the source J(x, view) from the field's harmonics costs
//! wavelengths x harmonics x streams x species operations per march node,
//! too much for the ~400 000 nodes of a sky-view table. The source varies
//! smoothly with every one of its four local coordinates (it is a
//! scattering integral of a diffuse field), so it is tabulated once per
//! image over
//!
//! - the altitude: the solver's own levels (no interpolation error at them);
//! - the sun's zenith angle: the solver's own sun nodes;
//! - the view's zenith angle, 0..180 degrees, uniform;
//! - the view's azimuth from the sun's, 0..180 degrees (the field is
//!   symmetric about the solar meridian), at [`TABLE_AZIMUTHS_DEG`]:
//!   4-7 degrees apart from 10 to 30 degrees from the sun, where the
//!   source of a forward-peaked aerosol bends most in azimuth (its
//!   multiply scattered aureole), 10-12 degrees beyond; another node
//!   count spreads its nodes the same way ([`table_azimuths_rad`]),
//!
//! and read by quadrilinear interpolation, linear in the azimuth's angle
//! but in its cosine within the first and the last azimuth cell, where ln R
//! is even in the azimuth ([`azimuth_cell`]). Uniform nodes 10 degrees
//! apart read linearly in the angle put mars-dust's multiply scattered
//! light, through an image's tables, up to 2-3 % off the exact synthesis
//! within 30 degrees of the sun (a wave along the almucantar that the
//! engine tables' layers inherited); `docs/engine-tables.md` has the
//! numbers. What is stored is
//! R = J / beta*_sca(x) (radiance units: the phase-weighted mean diffuse
//! radiance, averaged over species by their scattering), which is smooth in
//! altitude where J itself falls off exponentially; the march multiplies it
//! back by the scaled scattering coefficient at each node.

use std::f64::consts::PI;
use std::sync::Arc;

use super::phase_fourier::normalized_associated_legendre;
use super::view_march::{Alongside, NodeCells};
use super::{
    LOG_FLOOR, MultipleScatteringField, MultipleScatteringScratch, NodeGeometry, SourceCells,
    floored_log,
};
use crate::geometry::Vector3;
use crate::transport::SunColumns;

/// The per-image source table (see the module docs).
#[derive(Debug, Clone)]
pub struct MultipleScatteringTable {
    /// Shared with the sky that made it, not copied (the field's solution
    /// is tens of megabytes at twilight).
    field: Arc<MultipleScatteringField>,
    view_zenith_nodes: usize,
    /// The azimuths from the sun of the nodes, rad, ascending from 0 to pi
    /// ([`table_azimuths_rad`]).
    azimuths_rad: Arc<Vec<f64>>,
    /// ln R (R in W m^-2 sr^-1 nm^-1), [(((k * suns + s) * azimuth_nodes + f)
    /// * view_zenith_nodes + v) * wavelengths + i]
    ///
    /// Shared by the tables that `aimed` makes.
    values: Arc<Vec<f32>>,
}

impl MultipleScatteringTable {
    /// Tabulates the source of `field` (which it keeps, for the march's
    /// optics and for exact comparisons), at the table size of its settings.
    pub(crate) fn compute(field: Arc<MultipleScatteringField>) -> MultipleScatteringTable {
        let settings = field.settings;
        let nodes = (
            settings.table_view_zenith_nodes,
            settings.table_azimuth_nodes,
        );
        MultipleScatteringTable::compute_with_nodes(field, nodes)
    }

    /// [`MultipleScatteringTable::compute`] at half the steps of the
    /// settings' nodes on both view axes (2 n - 1 nodes for n).
    pub(crate) fn compute_at_half_steps(
        field: Arc<MultipleScatteringField>,
    ) -> MultipleScatteringTable {
        let settings = field.settings;
        let nodes = (
            2 * settings.table_view_zenith_nodes.max(2) - 1,
            2 * settings.table_azimuth_nodes.max(2) - 1,
        );
        MultipleScatteringTable::compute_with_nodes(field, nodes)
    }

    /// [`MultipleScatteringTable::compute`] with `(view zenith, azimuth)`
    /// nodes of its own instead of the settings'.
    fn compute_with_nodes(
        field: Arc<MultipleScatteringField>,
        (views, azimuths): (usize, usize),
    ) -> MultipleScatteringTable {
        let views = views.max(2);
        let angles = table_azimuths_rad(azimuths);
        let values = source_values(&field, views, &angles);
        MultipleScatteringTable {
            field,
            view_zenith_nodes: views,
            azimuths_rad: Arc::new(angles),
            values: Arc::new(values),
        }
    }
}

/// The source table's azimuths from the sun, degrees, for its default 19
/// nodes: 0 and 10, then 4-7 degrees apart to 30 (where a forward-peaked
/// aerosol's source bends most in azimuth), then 10-12 degrees apart to
/// 180. Chosen for the engine tables' aerial-perspective march (which
/// reads this table; `engine_tables/march.rs`): mars-dust, suns 2 and -4,
/// views 1-30 degrees up, largest error 1.20 / 1.43 % against 3.04 /
/// 4.15 % with 19 uniform nodes read linearly and 2.1 % with 37.
pub(crate) const TABLE_AZIMUTHS_DEG: [f64; 19] = [
    0.0, 10.0, 14.0, 18.0, 23.0, 30.0, 41.0, 53.0, 65.0, 77.0, 89.0, 101.0, 113.0, 125.0, 137.0,
    149.0, 160.0, 170.0, 180.0,
];

/// The azimuths from the sun of a source table of `nodes` (at least 2)
/// azimuth nodes, rad, ascending from 0 to pi: [`TABLE_AZIMUTHS_DEG`]
/// for 19, and otherwise as many nodes spread the same way (node f at
/// the place f (19 - 1) / (nodes - 1) among those 19, linear between them:
/// 37 halves every cell).
pub(crate) fn table_azimuths_rad(nodes: usize) -> Vec<f64> {
    let nodes = nodes.max(2);
    let last = TABLE_AZIMUTHS_DEG.len() - 1;
    (0..nodes)
        .map(|f| {
            let x = (f * last) as f64 / (nodes - 1) as f64;
            let k = (x as usize).min(last - 1);
            let (a, b) = (TABLE_AZIMUTHS_DEG[k], TABLE_AZIMUTHS_DEG[k + 1]);
            (a + (x - k as f64) * (b - a)).to_radians()
        })
        .collect()
}

/// The cell (node, fraction) of the azimuth from the sun whose cosine is
/// `cos_azimuth` among the ascending azimuths `azimuths_rad` (0 and pi
/// the first and the last): linear in the angle, but in the cosine within
/// the first and the last cell (ln R is even in the azimuth about 0 and
/// pi, so a read linear in the angle cuts its bend there: 3-4 % too dark
/// 5 degrees from a low sun on mars-dust with cells of 10 degrees). The
/// library's march and the engine tables' read a source table by it.
pub(crate) fn azimuth_cell(azimuths_rad: &[f64], cos_azimuth: f64) -> (usize, f64) {
    let c = cos_azimuth.clamp(-1.0, 1.0);
    let angle = c.acos();
    let upper = azimuths_rad.partition_point(|a| *a <= angle);
    let f = upper.clamp(1, azimuths_rad.len() - 1) - 1;
    if f == 0 || f + 2 == azimuths_rad.len() {
        let (a, b) = (azimuths_rad[f].cos(), azimuths_rad[f + 1].cos());
        (f, ((a - c) / (a - b)).clamp(0.0, 1.0))
    } else {
        let (a, b) = (azimuths_rad[f], azimuths_rad[f + 1]);
        (f, ((angle - a) / (b - a)).clamp(0.0, 1.0))
    }
}

/// ln R of `field` over its levels and sun nodes, `views` view zenith
/// angles uniform over 0..pi and the azimuths from the sun `azimuths_rad`
/// (ascending), [(((k * suns + s) * azimuths + f) * views + v) *
/// wavelengths + i] (see [`MultipleScatteringTable`]).
fn source_values(field: &MultipleScatteringField, views: usize, azimuths_rad: &[f64]) -> Vec<f32> {
    let azimuths = azimuths_rad.len();
    let degrees = field.optics.geometry.streams.count();
    let levels = field.optics.geometry.grid.levels();
    let suns = field.optics.sun_axis.count();
    let (w, species) = (field.optics.wavelengths, field.optics.species);
    let per_level = suns * azimuths * views * w;
    let view_legendre: Vec<Vec<f64>> = (0..views)
        .map(|v| {
            let mut table = vec![0.0; degrees * degrees];
            let zenith = PI * v as f64 / (views - 1) as f64;
            normalized_associated_legendre(zenith.cos(), degrees, &mut table);
            table
        })
        .collect();
    let azimuth_cosines: Vec<f64> = azimuths_rad
        .iter()
        .flat_map(|phi| (0..degrees).map(move |m| (m as f64 * phi).cos()))
        .collect();
    let active: Vec<usize> = (0..degrees).filter(|m| field.harmonics[*m]).collect();
    // 2 pi w_b p*_jm(mu_v, mu_b) by wavelength, species, harmonic and
    // stream, a row over view nodes:
    // [(((i * species + j) * degrees + m) * degrees + b) * views + v].
    let block = degrees * degrees * views;
    let mut kernel = vec![0.0; w * species * block];
    crate::parallel::for_each_chunk_mut(&mut kernel, species * block, |i, out| {
        for j in 0..species {
            // A species that does not scatter here (an absorber: the
            // banded gases, ozone) has no share of the source below: its
            // rows are never read, and left zero.
            if field.optics.scaled.scaled_scattering[i * species + j] == 0.0 {
                continue;
            }
            let phase = &field.optics.scaled.phases[i * species + j];
            for &m in &active {
                for b in 0..degrees {
                    let row = &mut out[j * block + (m * degrees + b) * views..][..views];
                    for (value, legendre) in row.iter_mut().zip(&view_legendre) {
                        *value = 2.0
                            * PI
                            * field.optics.geometry.streams.weights()[b]
                            * phase.harmonic(
                                m,
                                legendre,
                                field.optics.geometry.streams.legendre(b),
                            );
                    }
                }
            }
        }
    });
    let sun_nodes = field.reachable_sun_nodes();
    // Every value is written by its level's transpose below: zeros (pages
    // the system maps on first write) rather than a fill of their own.
    let mut values = vec![0.0f32; levels * per_level];
    // One level per task; within it one wavelength at a time into a
    // wavelength-major buffer, transposed at the end (in cache). Only
    // the sun nodes that view rays reach at the level are filled, the
    // others left at the floor. The buffer is one per thread's run of
    // levels, refilled at each (a fresh one per level had its pages
    // mapped and cleared by the system each time: with the k-distribution's
    // five term skies, a tenth of a gas image's CPU).
    let new_buffer = || vec![0.0f32; per_level];
    crate::parallel::for_each_chunk_mut_with(
        &mut values,
        per_level,
        new_buffer,
        |by_wavelength, k, out| {
            by_wavelength.fill(LOG_FLOOR.ln() as f32);
            let densities = field.optics.geometry.grid.densities_at_level(k);
            let mut combined = vec![0.0; block];
            let mut harmonics = vec![0.0; degrees * views];
            let mut sum = vec![0.0; views];
            let cells = suns * azimuths * views;
            let (first_sun, last_sun) = sun_nodes[k];
            for i in 0..w {
                let plane = &mut by_wavelength[i * cells..(i + 1) * cells];
                let total: f64 = (0..species)
                    .map(|j| densities[j] * field.optics.scaled.scaled_scattering[i * species + j])
                    .sum();
                if total <= 0.0 {
                    plane.fill(LOG_FLOOR.ln() as f32);
                    continue;
                }
                combined.fill(0.0);
                for j in 0..species {
                    let fraction = densities[j]
                        * field.optics.scaled.scaled_scattering[i * species + j]
                        / total;
                    if fraction != 0.0 {
                        let q = &kernel[(i * species + j) * block..][..block];
                        for (c, q) in combined.iter_mut().zip(q) {
                            *c += fraction * q;
                        }
                    }
                }
                for s in first_sun..=last_sun {
                    let solution = field.solution(s, i);
                    for &m in &active {
                        let row = &mut harmonics[m * views..(m + 1) * views];
                        row.fill(0.0);
                        let radiance = &solution[(m * levels + k) * degrees..][..degrees];
                        let columns = &combined[m * degrees * views..(m + 1) * degrees * views];
                        for (l, column) in radiance.iter().zip(columns.chunks_exact(views)) {
                            for (r, q) in row.iter_mut().zip(column) {
                                *r += l * q;
                            }
                        }
                    }
                    let cell = &mut plane[s * azimuths * views..(s + 1) * azimuths * views];
                    for (f, row) in cell.chunks_exact_mut(views).enumerate() {
                        let cosines = &azimuth_cosines[f * degrees..(f + 1) * degrees];
                        sum.fill(0.0);
                        for &m in &active {
                            let c = cosines[m];
                            for (acc, r) in sum.iter_mut().zip(&harmonics[m * views..][..views]) {
                                *acc += c * r;
                            }
                        }
                        for (o, v) in row.iter_mut().zip(&sum) {
                            *o = floored_log(*v) as f32;
                        }
                    }
                }
            }
            for i in 0..w {
                for (cell, value) in by_wavelength[i * cells..(i + 1) * cells].iter().enumerate() {
                    out[cell * w + i] = *value;
                }
            }
        },
    );
    values
}

impl MultipleScatteringTable {
    /// This table (of a field solved for every sun) for `field`, the same
    /// field aimed at another eye and sun
    /// ([`MultipleScatteringField::aimed`]): the values are shared.
    pub(crate) fn aimed(&self, field: Arc<MultipleScatteringField>) -> MultipleScatteringTable {
        debug_assert!(self.field.every_sun && Arc::ptr_eq(&self.field.solutions, &field.solutions));
        MultipleScatteringTable {
            field,
            ..self.clone()
        }
    }

    /// The field the table was made from.
    pub(crate) fn field(&self) -> &MultipleScatteringField {
        &self.field
    }

    /// Work space for [`MultipleScatteringTable::compute_radiance`].
    pub(crate) fn scratch(&self) -> MultipleScatteringScratch {
        self.field.scratch()
    }

    /// Multiply scattered radiance along `view` (as
    /// [`MultipleScatteringField::compute_radiance`], with the source read
    /// from the table), W m^-2 sr^-1 nm^-1.
    #[cfg(test)]
    pub(crate) fn compute_radiance(
        &self,
        view: Vector3,
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        radiance: &mut [f64],
    ) {
        let mut ground = vec![0.0; radiance.len()];
        self.compute_radiance_parts(
            (view, f64::INFINITY),
            sun_columns,
            scratch,
            (&mut *radiance, &mut ground),
        );
        for (r, g) in radiance.iter_mut().zip(&ground) {
            *r += g;
        }
        self.field.add_forward_peak(view, scratch, radiance);
    }

    /// As [`MultipleScatteringField::compute_field_radiance`] (the air's
    /// light into `terms.0`, the ground's skylight into `terms.1`, along
    /// the view to a distance), with the source read from the table; the
    /// forward-peak term is left in the scratch
    /// ([`MultipleScatteringScratch::forward_integrals`]) as integrals that
    /// take the phase functions exactly as single scattering's do (the
    /// sky-view table adds them to its single-scattering integrals).
    pub(crate) fn compute_radiance_parts(
        &self,
        segment: (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        terms: (&mut [f64], &mut [f64]),
    ) {
        self.field
            .optics
            .march(segment, sun_columns, scratch, terms, |node, _, scratch| {
                self.lookup_log_source(node, &mut scratch.source_cells, &mut scratch.log_source);
            });
    }

    /// The table's nodes (prototype measurements, `engine_tables` tests):
    /// (altitude levels, sun nodes, view zenith nodes, azimuth nodes,
    /// wavelengths).
    #[cfg(test)]
    pub(crate) fn nodes(&self) -> (usize, usize, usize, usize, usize) {
        let optics = &self.field.optics;
        (
            optics.geometry.grid.levels(),
            optics.sun_axis.count(),
            self.view_zenith_nodes,
            self.azimuths_rad.len(),
            optics.wavelengths,
        )
    }

    /// Prototype measurements (`engine_tables` tests): the scaled field's
    /// light along the segment by a midpoint march of `steps` even steps
    /// from this table's source, per wavelength, and per group of
    /// wavelengths in `groups` with every quantity (the species' scaled
    /// extinction and scattering, the source R) the group's mean.
    #[cfg(test)]
    pub(crate) fn march_segment_coarse(
        &self,
        (view, distance_m): (Vector3, f64),
        steps: usize,
        groups: &[Vec<usize>],
    ) -> (Vec<f64>, Vec<f64>) {
        let optics = &self.field.optics;
        let (w, s) = (optics.wavelengths, optics.species);
        let (ground, top) = (
            optics.geometry.ground_radius_m,
            optics.geometry.top_radius_m,
        );
        let (scaled_extinction, scaled_scattering) = (
            &optics.scaled.scaled_extinction,
            &optics.scaled.scaled_scattering,
        );
        let (mut spectral, mut grouped) = (vec![0.0; w], vec![0.0; groups.len()]);
        let Some((enter, exit)) =
            crate::geometry::segment_in_atmosphere(optics.observer, view, ground, top)
        else {
            return (spectral, grouped);
        };
        let length = exit.min(distance_m) - enter;
        let mean = |g: &[usize], f: &dyn Fn(usize) -> f64| {
            g.iter().map(|i| f(*i)).sum::<f64>() / g.len() as f64
        };
        let mut columns = vec![0.0; s];
        let mut log_source = vec![0.0; w];
        let density = |s: f64| -> Vec<f64> {
            let h = ((optics.observer + view * (enter + s)).length() - ground).max(0.0);
            optics
                .geometry
                .profiles
                .iter()
                .map(|p| p.relative_density(h))
                .collect()
        };
        let (mut previous, mut previous_rho) = (0.0, density(0.0));
        for k in 0..steps {
            let (at, ds) = crate::engine_tables::tests::march_node(length, k, steps);
            let point = optics.observer + view * (enter + at);
            let r = point.length();
            let zenith = point * (1.0 / r);
            let view_cosine = view.dot(zenith).clamp(-1.0, 1.0);
            let sun_cosine = optics.sun.dot(zenith).clamp(-1.0, 1.0);
            let sines =
                ((1.0 - view_cosine * view_cosine) * (1.0 - sun_cosine * sun_cosine)).sqrt();
            let cos_azimuth = if sines > 1e-12 {
                ((view.dot(optics.sun) - view_cosine * sun_cosine) / sines).clamp(-1.0, 1.0)
            } else {
                1.0
            };
            let altitude_m = (r - ground).max(0.0);
            let node = |altitude_m: f64| NodeGeometry {
                altitude_m,
                sun_cosine,
                view_cosine,
                cos_azimuth,
                march_node: None,
            };
            // SORA_LEVEL_STRIDE=q: the source read at every q-th level
            // only (and the top), linear in ln R between them.
            match std::env::var("SORA_LEVEL_STRIDE").map(|q| q.parse::<usize>().unwrap()) {
                Ok(q) if q > 1 => {
                    let all = optics.geometry.grid.altitudes_m();
                    let mut kept: Vec<f64> = all.iter().step_by(q).copied().collect();
                    if kept.last() != all.last() {
                        kept.push(*all.last().unwrap());
                    }
                    let (k, t) = super::vertical_grid::locate_among(&kept, altitude_m);
                    let mut upper = vec![0.0; w];
                    self.lookup_log_source(node(kept[k]), &mut Vec::new(), &mut log_source);
                    self.lookup_log_source(node(kept[k + 1]), &mut Vec::new(), &mut upper);
                    for (l, u) in log_source.iter_mut().zip(&upper) {
                        *l += t * (u - *l);
                    }
                }
                _ => {
                    self.lookup_log_source(node(altitude_m), &mut Vec::new(), &mut log_source);
                }
            }
            let rho = density(at);
            for j in 0..s {
                columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (at - previous);
            }
            (previous, previous_rho) = (at, rho.clone());
            let here = columns.clone();
            let source = |i: usize| {
                if log_source[i] > super::view_march::DARK_LOG_SOURCE {
                    log_source[i].exp()
                } else {
                    0.0
                }
            };
            for (i, out) in spectral.iter_mut().enumerate() {
                let (mut tau, mut scattering) = (0.0, 0.0);
                for j in 0..s {
                    tau += scaled_extinction[i * s + j] * here[j];
                    scattering += scaled_scattering[i * s + j] * rho[j];
                }
                *out += ds * scattering * source(i) * (-tau).exp();
            }
            for (out, g) in grouped.iter_mut().zip(groups) {
                let (mut tau, mut scattering) = (0.0, 0.0);
                for j in 0..s {
                    tau += mean(g, &|i| scaled_extinction[i * s + j]) * here[j];
                    scattering += mean(g, &|i| scaled_scattering[i * s + j]) * rho[j];
                }
                *out += ds * scattering * mean(g, &source) * (-tau).exp();
            }
        }
        (spectral, grouped)
    }

    /// Prototype measurements (`engine_tables` tests): what a shader's
    /// march of the segment to `distance_m` gathers, per wavelength, to
    /// rebuild the library's light of the air
    /// ([`crate::sky::Sky::compute_segment_light`]'s terms): `steps.0`
    /// nodes along the segment crowded toward the eye and `steps.1` nodes
    /// from the segment's end to the ray's end crowded toward the point;
    /// the columns toward the sun from `sun_columns` (None: the planet's
    /// shadow). At each node the source R from this table (scaled field),
    /// and the forward-peak integrals as the library's march takes them
    /// (the tilted peak beam near a low sun included).
    #[cfg(test)]
    pub(crate) fn march_segment_parts(
        &self,
        (view, distance_m): (Vector3, f64),
        steps: (usize, usize),
        sun_columns: &dyn Fn(Vector3) -> Option<Vec<f64>>,
    ) -> SegmentMarch {
        let optics = &self.field.optics;
        let (w, s) = (optics.wavelengths, optics.species);
        let (ground, top) = (
            optics.geometry.ground_radius_m,
            optics.geometry.top_radius_m,
        );
        let scaled = &optics.scaled;
        let mut out = SegmentMarch {
            field: vec![0.0; w],
            field_behind: vec![0.0; w],
            forward: vec![0.0; (s + super::forward_peak::EXTRA_ROWS) * w],
            forward_sky: vec![0.0; (s + super::forward_peak::EXTRA_ROWS) * w],
            scaled: vec![0.0; s * w],
            scaled_sky: vec![0.0; s * w],
            columns: vec![0.0; s],
        };
        let Some((enter, exit)) =
            crate::geometry::segment_in_atmosphere(optics.observer, view, ground, top)
        else {
            return out;
        };
        let length = exit.min(distance_m) - enter;
        let beyond = exit - enter - length;
        let mut scratch = self.scratch();
        scratch.forward_integrals.fill(0.0);
        scratch.scaled_forward_integrals.fill(0.0);
        let density = |at: f64| -> Vec<f64> {
            let h = ((optics.observer + view * (enter + at)).length() - ground).max(0.0);
            optics
                .geometry
                .profiles
                .iter()
                .map(|p| p.relative_density(h))
                .collect()
        };
        let mut columns = vec![0.0; s];
        let (mut previous, mut previous_rho) = (0.0, density(0.0));
        let nodes = (0..steps.0)
            .map(|k| {
                (
                    crate::engine_tables::tests::march_node(length, k, steps.0),
                    true,
                )
            })
            .chain((0..steps.1).map(|k| {
                let (at, ds) = crate::engine_tables::tests::march_node(beyond, k, steps.1);
                ((length + at, ds), false)
            }));
        let mut segment_done = false;
        for ((at, ds), in_segment) in nodes {
            if !in_segment && !segment_done {
                // The segment's end: its columns and integrals.
                let rho = density(length);
                for j in 0..s {
                    columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (length - previous);
                }
                (previous, previous_rho) = (length, rho);
                out.columns.copy_from_slice(&columns);
                out.forward.copy_from_slice(&scratch.forward_integrals);
                out.scaled
                    .copy_from_slice(&scratch.scaled_forward_integrals);
                segment_done = true;
            }
            if ds <= 0.0 {
                continue;
            }
            let point = optics.observer + view * (enter + at);
            let r = point.length();
            let zenith = point * (1.0 / r);
            let view_cosine = view.dot(zenith).clamp(-1.0, 1.0);
            let sun_cosine = optics.sun.dot(zenith).clamp(-1.0, 1.0);
            let sines =
                ((1.0 - view_cosine * view_cosine) * (1.0 - sun_cosine * sun_cosine)).sqrt();
            let cos_azimuth = if sines > 1e-12 {
                ((view.dot(optics.sun) - view_cosine * sun_cosine) / sines).clamp(-1.0, 1.0)
            } else {
                1.0
            };
            let node = NodeGeometry {
                altitude_m: (r - ground).max(0.0),
                sun_cosine,
                view_cosine,
                cos_azimuth,
                march_node: None,
            };
            let mut log_source = vec![0.0; w];
            self.lookup_log_source(node, &mut Vec::new(), &mut log_source);
            let rho = density(at);
            for j in 0..s {
                columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (at - previous);
            }
            (previous, previous_rho) = (at, rho.clone());
            let target = if in_segment {
                &mut out.field
            } else {
                &mut out.field_behind
            };
            for (i, o) in target.iter_mut().enumerate() {
                let (mut tau, mut scattering) = (0.0, 0.0);
                for j in 0..s {
                    tau += scaled.scaled_extinction[i * s + j] * columns[j];
                    scattering += scaled.scaled_scattering[i * s + j] * rho[j];
                }
                if log_source[i] > super::view_march::DARK_LOG_SOURCE {
                    *o += ds * scattering * log_source[i].exp() * (-tau).exp();
                }
            }
            if !optics.has_forward_peaks {
                continue;
            }
            scratch.node_columns.copy_from_slice(&columns);
            scratch.densities.copy_from_slice(&rho);
            let to_sun = sun_columns(point);
            let lit = to_sun.is_some();
            match to_sun {
                Some(c) => scratch.sun_columns.copy_from_slice(&c),
                None => scratch.sun_columns.fill(0.0),
            }
            let share = match &optics.peak_beam {
                Some(beam) => beam.lookup_beam(r, sun_cosine, &mut scratch.beam),
                None => 0.0,
            };
            let view_terms = optics.view_terms(&columns, &rho);
            optics.add_tilted_forward_peak(ds, lit, share, &view_terms, &mut scratch);
        }
        if !segment_done {
            out.columns.copy_from_slice(&columns);
            out.forward.copy_from_slice(&scratch.forward_integrals);
            out.scaled
                .copy_from_slice(&scratch.scaled_forward_integrals);
        }
        out.forward_sky.copy_from_slice(&scratch.forward_integrals);
        out.scaled_sky
            .copy_from_slice(&scratch.scaled_forward_integrals);
        out
    }

    /// The light of the air of a marched segment
    /// ([`MultipleScatteringTable::march_segment_parts`]), per wavelength,
    /// without single scattering and the ground: the library's
    /// `L_air - S_seg` (`sky/aerial_perspective.rs`), F_seg + (1 - T / T*)
    /// (F_sky - F_seg) + P_sky - T P_behind.
    #[cfg(test)]
    pub(crate) fn segment_light_from_parts(&self, view: Vector3, parts: &SegmentMarch) -> Vec<f64> {
        let optics = &self.field.optics;
        let (w, s) = (optics.wavelengths, optics.species);
        let scaled = &optics.scaled;
        let mut light = vec![0.0; w];
        let mut forward = vec![0.0; parts.forward.len()];
        let mut behind = vec![0.0; parts.forward.len()];
        for (i, l) in light.iter_mut().enumerate() {
            let (mut tau, mut tau_scaled) = (0.0, 0.0);
            for (j, column) in parts.columns.iter().enumerate() {
                tau += scaled.extinction[i * s + j] * column;
                tau_scaled += scaled.scaled_extinction[i * s + j] * column;
            }
            let (share, depth) = (1.0 - (tau_scaled - tau).exp(), tau - tau_scaled);
            *l = parts.field[i] + share * parts.field_behind[i];
            for j in 0..s {
                let k = j * w + i;
                forward[k] = parts.forward[k] + share * (parts.scaled_sky[k] - parts.scaled[k]);
            }
            let (q, qx) = (s * w + i, (s + 1) * w + i);
            forward[q] = parts.forward_sky[q];
            forward[qx] = parts.forward_sky[qx];
            behind[q] = parts.forward_sky[q] - parts.forward[q];
            behind[qx] = (parts.forward_sky[qx] - parts.forward[qx]) - depth * behind[q];
        }
        let cos_theta = view.dot(optics.sun);
        let (mut phase, mut peak, mut hidden) = (vec![0.0; w], vec![0.0; w], vec![0.0; w]);
        self.field
            .compute_forward_peak_radiance(cos_theta, &forward, &mut phase, &mut peak);
        self.field
            .compute_forward_peak_radiance(cos_theta, &behind, &mut phase, &mut hidden);
        for ((l, p), h) in light.iter_mut().zip(&peak).zip(&hidden) {
            *l += p - h;
        }
        light
    }

    /// What the engine tables' aerial-perspective march reads from this
    /// table and its field (`engine_tables/march.rs`; a field solved for
    /// every sun): the source ln R with its axes, the optics, the ground's
    /// light, the peak beam and the forward-peak term's tables. The source
    /// is at the azimuths from the sun `azimuths_rad` (ascending, 0 and pi
    /// among them; None: the table's own): computed anew from the field,
    /// exactly, or the table's own values where the azimuths are the
    /// table's. Its `log_source` is left empty and returned beside it,
    /// borrowed where it is the table's own: the march keeps a part of it,
    /// and a copy of the whole (written on one thread) was a serial
    /// stretch of the engine tables' bake.
    pub(crate) fn exported_parts(
        &self,
        azimuths_rad: Option<&[f64]>,
    ) -> (ExportedSource, std::borrow::Cow<'_, [f32]>) {
        match azimuths_rad.filter(|a| *a != self.azimuths_rad.as_slice()) {
            None => (
                self.exported_with(Vec::new(), self.azimuths_rad.as_ref().clone()),
                std::borrow::Cow::Borrowed(&self.values[..]),
            ),
            Some(azimuths_rad) => {
                let values = source_values(&self.field, self.view_zenith_nodes, azimuths_rad);
                (
                    self.exported_with(Vec::new(), azimuths_rad.to_vec()),
                    std::borrow::Cow::Owned(values),
                )
            }
        }
    }

    /// What [`Self::exported_parts`] gives, with the source `log_source` at the
    /// azimuths `azimuths_rad`.
    fn exported_with(&self, log_source: Vec<f32>, azimuths_rad: Vec<f64>) -> ExportedSource {
        let optics = &self.field.optics;
        let atmosphere = &self.field.atmosphere;
        let (w, s) = (optics.wavelengths, optics.species);
        let mut scattering = vec![0.0; w * s];
        for (j, species) in atmosphere.species.iter().enumerate() {
            for i in 0..w {
                scattering[i * s + j] = species.scattering_per_m[i];
            }
        }
        ExportedSource {
            wavelengths: w,
            species: s,
            view_zenith_nodes: self.view_zenith_nodes,
            azimuth_nodes: azimuths_rad.len(),
            azimuths_rad,
            levels_m: optics.geometry.grid.altitudes_m().to_vec(),
            sun_zenith_rad: optics.sun_axis.angles_rad.clone(),
            log_source,
            extinction: optics.scaled.extinction.clone(),
            scaled_extinction: optics.scaled.scaled_extinction.clone(),
            scaled_scattering: optics.scaled.scaled_scattering.clone(),
            scattering,
            solar: atmosphere.solar_irradiance_w_m2_nm.values().to_vec(),
            profiles: optics.geometry.profiles.clone(),
            ground_diffuse: optics.ground_diffuse.clone(),
            ground_direct: optics.ground_direct.clone(),
            has_forward_peaks: optics.has_forward_peaks,
            beam: optics
                .peak_beam
                .as_ref()
                .filter(|_| optics.has_forward_peaks)
                .map(|beam| beam.exported()),
            kernel: optics.forward_peak.exported_kernel(),
        }
    }

    /// The phase functions the march's single scattering (`exact`, p_j)
    /// and its forward-peak term's first line (`smooth`, (1 - f) p*_j near
    /// the sun, see `forward_peak.rs`) take at cos(theta) = `cos_theta`,
    /// [j * wavelengths + i], sr^-1.
    pub(crate) fn march_phases(&self, cos_theta: f64, exact: &mut [f64], smooth: &mut [f64]) {
        let optics = &self.field.optics;
        let w = optics.wavelengths;
        for (j, species) in self.field.atmosphere.species.iter().enumerate() {
            species
                .phase_function
                .eval_into(cos_theta, &mut exact[j * w..(j + 1) * w]);
            optics.forward_peak.smooth_phase_into(
                j,
                &species.phase_function,
                cos_theta,
                &mut smooth[j * w..(j + 1) * w],
            );
        }
    }

    /// ln R(x, view) at one march node, into `log_source`: quadrilinear
    /// in ln R. A view ray's replayed node (`NodeGeometry::march_node`)
    /// takes its altitude's and view's cells from `cells` (per node
    /// index), the others keep theirs there. Returns the node's cells
    /// (what [`Self::read_log_source`] reads at).
    fn lookup_log_source(
        &self,
        node: NodeGeometry,
        cells: &mut Vec<SourceCells>,
        log_source: &mut [f64],
    ) -> NodeCells {
        let at = self.node_cells(node, cells);
        self.read_log_source(at, log_source);
        at
    }

    /// ln R at one march node whose cells in this table are `at`
    /// ([`Self::node_cells`]), into `log_source`.
    fn read_log_source(&self, at: NodeCells, log_source: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if crate::transport::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.read_log_source_avx2(at, log_source) };
            return;
        }
        self.read_log_source_portable(at, log_source);
    }

    /// [`Self::read_log_source`] compiled for AVX2 (8 lanes of f32 across
    /// the wavelengths; the same operations per lane, so the same bits as
    /// the portable form).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn read_log_source_avx2(&self, at: NodeCells, log_source: &mut [f64]) {
        self.read_log_source_portable(at, log_source);
    }

    /// [`Self::read_log_source`] in the target's baseline instructions.
    #[inline(always)]
    fn read_log_source_portable(
        &self,
        (altitude, sun, azimuth, view): NodeCells,
        log_source: &mut [f64],
    ) {
        interpolate_log_source_in_cells(
            &self.values,
            (
                self.field.optics.sun_axis.count(),
                self.azimuths_rad.len(),
                self.view_zenith_nodes,
            ),
            (altitude, sun, azimuth),
            view,
            log_source,
        );
    }

    /// The cells of one march node in this table: its altitude's, its
    /// sun's, its azimuth's from the sun and its view's zenith (node,
    /// fraction). A view ray's replayed node (`NodeGeometry::march_node`)
    /// takes its altitude's and view's cells from `cells` (per node
    /// index), the others keep theirs there.
    fn node_cells(&self, node: NodeGeometry, cells: &mut Vec<SourceCells>) -> NodeCells {
        let optics = &self.field.optics;
        let (altitude, view) = self.altitude_and_view_cells(node, cells);
        (
            altitude,
            optics.sun_axis.locate(node.sun_cosine),
            azimuth_cell(&self.azimuths_rad, node.cos_azimuth),
            view,
        )
    }

    /// The altitude's and the view's zenith cells of one march node
    /// (as [`Self::node_cells`] finds them).
    fn altitude_and_view_cells(
        &self,
        node: NodeGeometry,
        cells: &mut Vec<SourceCells>,
    ) -> SourceCells {
        let locate = || {
            (
                self.field.optics.geometry.grid.locate(node.altitude_m),
                view_cell(node.view_cosine, self.view_zenith_nodes),
            )
        };
        match node.march_node {
            Some((index, true)) if index < cells.len() => cells[index],
            Some((index, false)) => {
                if cells.len() <= index {
                    cells.resize(index + 1, ((0, 0.0), (0, 0.0)));
                }
                cells[index] = locate();
                cells[index]
            }
            _ => locate(),
        }
    }

    /// Which of a node's cells in `other` are its cells in this table:
    /// all of them (the same altitude levels, sun nodes, azimuths and
    /// view zenith nodes), the sun's and the azimuth's alone (the same
    /// sun nodes and azimuths: the k-distribution's term skies, whose
    /// levels follow their absorption), or none.
    fn cells_shared_with(&self, other: &MultipleScatteringTable) -> SharedCells {
        let (a, b) = (&self.field.optics, &other.field.optics);
        let angles = a.sun_axis.angles_rad == b.sun_axis.angles_rad
            && self.azimuths_rad == other.azimuths_rad;
        let levels = a.geometry.grid.altitudes_m() == b.geometry.grid.altitudes_m()
            && self.view_zenith_nodes == other.view_zenith_nodes;
        match (angles, levels) {
            (true, true) => SharedCells::All,
            (true, false) => SharedCells::SunAndAzimuth,
            _ => SharedCells::None,
        }
    }

    /// Whether a march of this table can take `other`'s with it
    /// ([`Self::compute_radiance_parts_together`]): the same view rays
    /// (the same species' profiles, radii, eye, sun and panels;
    /// their optics may differ).
    pub(crate) fn marches_with(&self, other: &MultipleScatteringTable) -> bool {
        self.field.optics.has_view_geometry_of(&other.field.optics)
    }

    /// `other`'s march taken with this table's
    /// ([`Self::compute_radiance_parts_together`]; [`Self::marches_with`]
    /// holds): its scratch and its outputs, the air's light and the
    /// ground's skylight.
    pub(crate) fn alongside<'a>(
        &'a self,
        other: &'a MultipleScatteringTable,
        scratch: &'a mut MultipleScatteringScratch,
        (air, skylit): (&'a mut [f64], &'a mut [f64]),
    ) -> (Alongside<'a>, AlongsideSource<'a>) {
        assert!(self.marches_with(other));
        (
            Alongside {
                optics: &other.field.optics,
                scratch,
                field: air,
                ground: skylit,
            },
            AlongsideSource {
                table: other,
                shared: self.cells_shared_with(other),
            },
        )
    }

    /// [`Self::compute_radiance_parts`], and with it each of `others`'
    /// (their tables in `sources`, in order; made by [`Self::alongside`],
    /// their columns toward the sun `sun_columns`' too): one march of the
    /// view ray ([`ViewRayOptics::march_alongside`]), each node's cells
    /// in the tables located once where their axes are the same (the
    /// sun's and the azimuth's of the term skies, whose altitude levels
    /// differ; each table keeps its altitude's and view's cells per node
    /// index, as its own march does). Each
    /// one's outputs and forward-peak integrals (in its scratch) are bit
    /// for bit what its own `compute_radiance_parts` gives.
    pub(crate) fn compute_radiance_parts_together(
        &self,
        segment: (Vector3, f64),
        sun_columns: SunColumns,
        scratch: &mut MultipleScatteringScratch,
        terms: (&mut [f64], &mut [f64]),
        (others, sources): (&mut [Alongside], &[AlongsideSource]),
    ) {
        assert_eq!(others.len(), sources.len());
        self.field.optics.march_alongside(
            0.0,
            segment,
            sun_columns,
            (scratch, terms),
            |node, _, scratch| {
                scratch.node_cells = self.lookup_log_source(
                    node,
                    &mut scratch.source_cells,
                    &mut scratch.log_source,
                );
            },
            others,
            |t, node, first, own| {
                let source = &sources[t];
                let at = match source.shared {
                    SharedCells::All => first.node_cells,
                    SharedCells::SunAndAzimuth => {
                        let (_, sun, azimuth, _) = first.node_cells;
                        let (altitude, view) = source
                            .table
                            .altitude_and_view_cells(node, &mut own.source_cells);
                        (altitude, sun, azimuth, view)
                    }
                    SharedCells::None => source.table.node_cells(node, &mut own.source_cells),
                };
                source.table.read_log_source(at, &mut own.log_source);
            },
        );
    }
}

/// The source table of a march taken with another's
/// ([`MultipleScatteringTable::alongside`]), and which of a node's cells
/// in it are the other's.
pub(crate) struct AlongsideSource<'a> {
    table: &'a MultipleScatteringTable,
    shared: SharedCells,
}

/// Which of a march node's cells in a source table are its cells in
/// another ([`MultipleScatteringTable::cells_shared_with`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SharedCells {
    All,
    SunAndAzimuth,
    None,
}

/// What [`MultipleScatteringTable::march_segment_parts`] gathers (prototype
/// measurements), per wavelength: the scaled field's light of the segment
/// and of the ray beyond it (both seen from the eye, W m^-2 sr^-1 nm^-1),
/// the forward-peak integrals of the segment and of the whole ray, their
/// scaled parts, and the segment's columns (m).
#[cfg(test)]
pub(crate) struct SegmentMarch {
    pub(crate) field: Vec<f64>,
    pub(crate) field_behind: Vec<f64>,
    pub(crate) forward: Vec<f64>,
    pub(crate) forward_sky: Vec<f64>,
    pub(crate) scaled: Vec<f64>,
    pub(crate) scaled_sky: Vec<f64>,
    pub(crate) columns: Vec<f64>,
}

/// ln R at one node from a source table's values `values` (ln R,
/// [(((k * suns + s) * azimuths + f) * views + v) * wavelengths + i],
/// views uniform over 0..pi), quadrilinear in ln R: the altitude, sun and
/// azimuth cells (node, fraction) given, the view's zenith cosine located
/// here; into `out` (one value per wavelength). The library's march and
/// the engine tables' (`engine_tables/lookup.rs`) read the table by it.
pub(crate) fn interpolate_log_source(
    values: &[f32],
    (suns, azimuths, views): (usize, usize, usize),
    ((k, tz), (s, ts), (f, tf)): ((usize, f64), (usize, f64), (usize, f64)),
    view_cosine: f64,
    out: &mut [f64],
) {
    interpolate_log_source_in_cells(
        values,
        (suns, azimuths, views),
        ((k, tz), (s, ts), (f, tf)),
        view_cell(view_cosine, views),
        out,
    );
}

/// The view zenith cell (node, fraction) of a view of zenith cosine
/// `view_cosine` among `views` nodes uniform over 0..pi.
fn view_cell(view_cosine: f64, views: usize) -> (usize, f64) {
    let y = view_cosine.clamp(-1.0, 1.0).acos() / PI * (views - 1) as f64;
    let v = (y as usize).min(views - 2);
    (v, y - v as f64)
}

/// [`interpolate_log_source`] with the view's zenith cell located
/// ([`view_cell`]). Inlined, so that the march's AVX2 form
/// ([`MultipleScatteringTable::lookup_log_source`]) compiles its loops
/// for AVX2 (as a function of its own they took two lanes, SSE2's).
#[inline(always)]
fn interpolate_log_source_in_cells(
    values: &[f32],
    (suns, azimuths, views): (usize, usize, usize),
    ((k, tz), (s, ts), (f, tf)): ((usize, f64), (usize, f64), (usize, f64)),
    (v, tv): (usize, f64),
    out: &mut [f64],
) {
    let w = out.len();
    out.fill(0.0);
    for (kk, wk) in [(k, 1.0 - tz), (k + 1, tz)] {
        for (ss, ws) in [(s, 1.0 - ts), (s + 1, ts)] {
            for (ff, wf) in [(f, 1.0 - tf), (f + 1, tf)] {
                let node = ((kk * suns + ss) * azimuths + ff) * views + v;
                let (low, high) = values[node * w..(node + 2) * w].split_at(w);
                let (a, b) = (
                    (wk * ws * wf * (1.0 - tv)) as f32,
                    (wk * ws * wf * tv) as f32,
                );
                for ((o, l), h) in out.iter_mut().zip(low).zip(high) {
                    *o += (a * l + b * h) as f64;
                }
            }
        }
    }
}

/// What the engine tables' march reads from a source table and its field
/// ([`MultipleScatteringTable::exported`]), per wavelength i of the
/// field's grid and species j.
#[derive(Debug, Clone)]
pub(crate) struct ExportedSource {
    pub(crate) wavelengths: usize,
    pub(crate) species: usize,
    pub(crate) view_zenith_nodes: usize,
    pub(crate) azimuth_nodes: usize,
    /// The source's azimuths from the sun, rad, ascending from 0 to pi.
    pub(crate) azimuths_rad: Vec<f64>,
    /// The source's altitude levels, m, and sun zenith nodes, rad.
    pub(crate) levels_m: Vec<f64>,
    pub(crate) sun_zenith_rad: Vec<f64>,
    /// ln R, [(((k * suns + s) * azimuth_nodes + f) * view_zenith_nodes +
    /// v) * wavelengths + i] (views uniform over 0..pi, azimuths at
    /// `azimuths_rad`).
    pub(crate) log_source: Vec<f32>,
    /// Per unit relative density, m^-1, [i * species + j]: extinction,
    /// delta-M scaled extinction and scattering, scattering.
    pub(crate) extinction: Vec<f64>,
    pub(crate) scaled_extinction: Vec<f64>,
    pub(crate) scaled_scattering: Vec<f64>,
    pub(crate) scattering: Vec<f64>,
    /// Top-of-atmosphere solar irradiance, W m^-2 nm^-1.
    pub(crate) solar: Vec<f64>,
    pub(crate) profiles: Vec<crate::atmosphere::DensityProfile>,
    /// The ground's light per sun node, [s * wavelengths + i], W m^-2
    /// sr^-1 nm^-1 (`view_march.rs`).
    pub(crate) ground_diffuse: Vec<f64>,
    pub(crate) ground_direct: Vec<f64>,
    pub(crate) has_forward_peaks: bool,
    pub(crate) beam: Option<ExportedBeam>,
    /// X nodes, angle nodes, (blend start, radius) rad, e^(-X) G.
    pub(crate) kernel: (Vec<f64>, usize, (f64, f64), Vec<f64>),
}

/// The peak beam's table ([`super::peak_beam::PeakBeam::exported`]).
#[derive(Debug, Clone)]
pub(crate) struct ExportedBeam {
    pub(crate) altitudes_m: Vec<f64>,
    pub(crate) first_elevation_deg: f64,
    pub(crate) step_deg: f64,
    pub(crate) elevations: usize,
    pub(crate) ln_beam: Vec<f64>,
    pub(crate) range_deg: (f64, f64, f64),
}
