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
//! - the view's azimuth from the sun's, 0..180 degrees, uniform (the
//!   field is symmetric about the solar meridian),
//!
//! and read by quadrilinear interpolation. What is stored is
//! R = J / beta*_sca(x) (radiance units: the phase-weighted mean diffuse
//! radiance, averaged over species by their scattering), which is smooth in
//! altitude where J itself falls off exponentially; the march multiplies it
//! back by the scaled scattering coefficient at each node.

use std::f64::consts::PI;
use std::sync::Arc;

use super::phase_fourier::normalized_associated_legendre;
use super::{
    LOG_FLOOR, MultipleScatteringField, MultipleScatteringScratch, NodeGeometry, floored_log,
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
    azimuth_nodes: usize,
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
        let (views, azimuths) = (views.max(2), azimuths.max(2));
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
        let azimuth_cosines: Vec<f64> = (0..azimuths)
            .flat_map(|f| {
                let phi = PI * f as f64 / (azimuths - 1) as f64;
                (0..degrees).map(move |m| (m as f64 * phi).cos())
            })
            .collect();
        let active: Vec<usize> = (0..degrees).filter(|m| field.harmonics[*m]).collect();
        // 2 pi w_b p*_jm(mu_v, mu_b) by wavelength, species, harmonic and
        // stream, a row over view nodes:
        // [(((i * species + j) * degrees + m) * degrees + b) * views + v].
        let block = degrees * degrees * views;
        let mut kernel = vec![0.0; w * species * block];
        crate::parallel::for_each_chunk_mut(&mut kernel, species * block, |i, out| {
            for j in 0..species {
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
        let mut values = vec![LOG_FLOOR.ln() as f32; levels * per_level];
        // One level per task; within it one wavelength at a time into a
        // wavelength-major buffer, transposed at the end (in cache). Only
        // the sun nodes that view rays reach at the level are filled.
        crate::parallel::for_each_chunk_mut(&mut values, per_level, |k, out| {
            let densities = field.optics.geometry.grid.densities_at_level(k);
            let mut combined = vec![0.0; block];
            let mut harmonics = vec![0.0; degrees * views];
            let mut sum = vec![0.0; views];
            let cells = suns * azimuths * views;
            let mut by_wavelength = vec![LOG_FLOOR.ln() as f32; per_level];
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
        });
        MultipleScatteringTable {
            field,
            view_zenith_nodes: views,
            azimuth_nodes: azimuths,
            values: Arc::new(values),
        }
    }

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
                self.lookup_log_source(node, &mut scratch.log_source)
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
            self.azimuth_nodes,
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
                    self.lookup_log_source(node(kept[k]), &mut log_source);
                    self.lookup_log_source(node(kept[k + 1]), &mut upper);
                    for (l, u) in log_source.iter_mut().zip(&upper) {
                        *l += t * (u - *l);
                    }
                }
                _ => self.lookup_log_source(node(altitude_m), &mut log_source),
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

    /// ln R(x, view) at one march node, into `log_source`: quadrilinear
    /// in ln R.
    fn lookup_log_source(&self, node: NodeGeometry, log_source: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if crate::transport::vector_exp::avx2_available() {
            // SAFETY: the CPU has AVX2 (checked just above).
            unsafe { self.lookup_log_source_avx2(node, log_source) };
            return;
        }
        self.lookup_log_source_portable(node, log_source);
    }

    /// [`Self::lookup_log_source`] compiled for AVX2 (8 lanes of f32
    /// across the wavelengths; the same operations per lane, so the same
    /// bits as the portable form).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn lookup_log_source_avx2(&self, node: NodeGeometry, log_source: &mut [f64]) {
        self.lookup_log_source_portable(node, log_source);
    }

    /// [`Self::lookup_log_source`] in the target's baseline instructions.
    #[inline(always)]
    fn lookup_log_source_portable(&self, node: NodeGeometry, log_source: &mut [f64]) {
        let optics = &self.field.optics;
        let w = optics.wavelengths;
        let suns = optics.sun_axis.count();
        let (views, azimuths) = (self.view_zenith_nodes, self.azimuth_nodes);
        let (k, tz) = self.field.optics.geometry.grid.locate(node.altitude_m);
        let (s, ts) = optics.sun_axis.locate(node.sun_cosine);
        let y = node.view_cosine.acos() / PI * (views - 1) as f64;
        let v = (y as usize).min(views - 2);
        let tv = y - v as f64;
        let x = node.cos_azimuth.acos() / PI * (azimuths - 1) as f64;
        let f = (x as usize).min(azimuths - 2);
        let tf = x - f as f64;
        log_source.fill(0.0);
        for (kk, wk) in [(k, 1.0 - tz), (k + 1, tz)] {
            for (ss, ws) in [(s, 1.0 - ts), (s + 1, ts)] {
                for (ff, wf) in [(f, 1.0 - tf), (f + 1, tf)] {
                    let node = ((kk * suns + ss) * azimuths + ff) * views + v;
                    let (low, high) = self.values[node * w..(node + 2) * w].split_at(w);
                    let (a, b) = (
                        (wk * ws * wf * (1.0 - tv)) as f32,
                        (wk * ws * wf * tv) as f32,
                    );
                    for ((out, l), h) in log_source.iter_mut().zip(low).zip(high) {
                        *out += (a * l + b * h) as f64;
                    }
                }
            }
        }
    }
}
