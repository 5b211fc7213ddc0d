//! The tables of the aerial-perspective march: what a shader needs to
//! march the segment from the eye to a point, per pixel, and get the
//! library's light of the air (`Sky::compute_segment_light`), on the sky's
//! wavelength grid (i) for each species (j). All of it comes from the
//! multiple-scattering field solved once for every sun and eye
//! (`sky::shared_field`), which the sky table's layers are drawn from too:
//!
//! - **source**: ln R, R = J* / beta*_sca the scaled field's source toward
//!   the eye (W m^-2 sr^-1 nm^-1), over the field's altitude levels, its
//!   sun zenith nodes, the view's zenith angle (uniform over 0..pi) and
//!   its azimuth from the sun (at [`AZIMUTHS_DEG`], closer near the sun
//!   and the antisolar point); quadrilinear in ln R (a value at or below
//!   [`DARK_LOG_SOURCE`] is no light);
//! - **optics**: per species and wavelength the extinction, the delta-M
//!   scaled extinction and scattering and the scattering per unit
//!   relative density (m^-1), the solar irradiance, the XYZ of a unit
//!   spike at each wavelength; the species' relative densities over
//!   altitude ([`DENSITY_NODES`] uniform nodes, linear);
//! - **sun columns**: the species' columns (m) from a point toward the
//!   sun to the top of the atmosphere over the transmittance table's axes
//!   ([`SUN_COLUMN_NODES`]: altitude, view cosine with each row's own
//!   horizon; linear in both), none below a point's horizon;
//! - **phases**: per species, the exact phase function p_j (single
//!   scattering) and the forward-peak term's smooth one ((1 - f) p*_j near
//!   the sun) over the scattering angle theta = pi u^2 ([`PHASE_NODES`]
//!   nodes in u, linear);
//! - **peak-only kernel** e^(-X) G(theta; X) and the **peak beam** ln B
//!   near a low sun (`transport/multiple_scattering/forward_peak.rs`,
//!   `peak_beam.rs`), with their axes;
//! - **ground**: the ground's diffuse and direct light per sun node.
//!
//! The march itself (`lookup.rs`, `EngineTables::aerial_perspective_xyz`)
//! is the library's composition of a segment's light (`sky/
//! aerial_perspective.rs`): single scattering with the exact phase
//! functions, the segment's own scaled field, the field beyond the point
//! that the segment's forward peaks scatter toward the eye, and the
//! forward-peak term, all from integrals along the one view ray.

use std::borrow::Cow;

use super::axes;
use crate::colour::{Observer, SpectrumToXyz};
use crate::error::{Error, Result};
use crate::geometry::Vector3;
use crate::sky::{SharedField, Sky};
use crate::spectrum::SampledSpectrum;
use crate::transport::multiple_scattering::{ExportedBeam, ExportedSource, TABLE_AZIMUTHS_DEG};

/// Nodes of the density table over 0..the atmosphere's thickness.
pub const DENSITY_NODES: usize = 1024;

/// Nodes of the sun-column table: altitude, view cosine (the
/// transmittance table's axes). At 32 x 128 the march was 2.3 % off at
/// -4 degrees (earth-clear, 50 km); at 64 x 512 it matched exact
/// columns for an eye on the ground, but not for a raised eye in
/// twilight, whose sun rays graze the ground a few km down: the column
/// linear between altitude rows is too large there (it falls about
/// exponentially), and the raised eye's sky at 19.2 km with the sun at
/// -4 degrees was 7.7 % dark (earth-clear, single scattering; 0.84 %
/// with exact columns); 128 rows 2.4 %, 256 rows 1.17 %
/// (`docs/engine-tables.md`).
pub const SUN_COLUMN_NODES: (usize, usize) = (256, 512);

/// Probe (`tests::probe_the_march_s_parts`): a test's sun-column nodes (a * 10000 + m; 0: none).
#[cfg(test)]
pub(crate) static SUN_COLUMN_NODES_OVERRIDE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

/// [`SUN_COLUMN_NODES`] (or a test's override).
pub(crate) fn sun_column_nodes() -> (usize, usize) {
    #[cfg(test)]
    if let n @ 1.. = SUN_COLUMN_NODES_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) {
        return (n / 10000, n % 10000);
    }
    SUN_COLUMN_NODES
}

/// Nodes of the phase tables in u = sqrt(theta / pi).
pub const PHASE_NODES: usize = 1024;

/// How the source is kept: every altitude level up to `dense_below_m`,
/// every `level_stride`-th above (and the top), every `sun_stride`-th of
/// the field's sun zenith nodes below `sun_stride_below_zenith_deg` and
/// every one from there on (and the last), every `wavelength_stride`-th
/// wavelength, every `azimuth_stride`-th azimuth, ln R rounded to 16-bit
/// floats where `half` (what `march.bin` holds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SourceThinning {
    pub level_stride: usize,
    /// Levels are thinned only in a field of at least this many (a
    /// coarser field keeps every one).
    pub thin_from_levels: usize,
    pub dense_below_m: f64,
    pub sun_stride: usize,
    /// The sun stride applies to the sun zenith nodes below this angle
    /// (degrees; where the light changes slowly with the sun); every node
    /// from it on is kept.
    pub sun_stride_below_zenith_deg: f64,
    /// Every `wavelength_stride`-th wavelength (and the last) kept, ln R
    /// read linearly in the wavelength's index between them.
    pub wavelength_stride: usize,
    /// The stride is lowered (to 1 at the least) so that the kept
    /// wavelengths are at most this far apart, nm: a sky on a coarser grid
    /// than the paper's 20 nm keeps more of its wavelengths.
    pub max_wavelength_gap_nm: f64,
    /// The azimuths from the sun the source is computed at, degrees
    /// (ascending from 0 to 180; empty: the field's table's own, uniform
    /// over 0..pi).
    pub azimuths_deg: &'static [f64],
    /// Every `azimuth_stride`-th of those azimuths (and the last).
    pub azimuth_stride: usize,
    pub half: bool,
}

impl SourceThinning {
    /// The wavelength stride on a grid of `step_nm`: `wavelength_stride`,
    /// lowered so that the kept wavelengths are at most
    /// `max_wavelength_gap_nm` apart (1 at the least).
    pub fn wavelength_stride_for(&self, step_nm: f64) -> usize {
        let widest = (self.max_wavelength_gap_nm / step_nm + 1e-9).floor();
        self.wavelength_stride.min(widest as usize).max(1)
    }
}

/// The default [`SourceThinning`]: every level up to 6 km, every third
/// above (in a field of 30 levels or more), every other sun node (6 degrees apart) for suns more than 15
/// degrees up and every one below (0.75-3 degrees apart), every other
/// wavelength (11 of the default 21, ln R linear between them; at most
/// 40 nm apart, so a 40 nm grid keeps every one), the 19
/// azimuths of [`AZIMUTHS_DEG`], 16-bit floats: 29-34 MB. The field for every sun has 41
/// levels (22-25 of them below 6 km on Earth) and 82 sun nodes; the
/// source at all of them is 200 MB as 32-bit floats. Measured against the
/// library (`docs/engine-tables.md`): every other level and sun node
/// (27 MB) was 3.0 % off on earth-hazy at -4 degrees (the sun axis: 32-bit
/// floats gave the same), every third level with every sun node 2.45 %
/// (the levels near the ground: with all of them below 6 km the errors
/// are those of every level), 16-bit floats changed no error by more than
/// 0.02 points; every other wavelength kept the march within 1.70 %
/// (mars-dust at -4 degrees; earth-hazy 1.57 %, earth-clear 0.93 %);
/// every other sun node above 15 degrees moved the largest errors at
/// suns between the kept nodes (58.5, 40.5 and 22.5 degrees) from
/// 0.27-0.29 to 0.35-0.58 % on mars-dust and from 1.30-1.46 to
/// 0.83-1.44 % on earth-hazy, where every other sun node at twilight
/// moved earth-hazy at -4 degrees from 1.37 to 2.03 %; every other
/// azimuth (10 of the field's 19 uniform ones) put mars-dust's aureole
/// 9.2 % off. On the explorer's real-time grid (11 wavelengths 40 nm
/// apart) every other wavelength put its march 2.3-2.9 % off at sun -4
/// (earth-clear, 1-50 km; ln R read linearly over 80 nm),
/// every one 0.3-1.2 % (with every third level above 6 km of its field's
/// 17, 1.2-1.3 % at 50 km, where the view leaves the Earth's shadow; every
/// level, below 30 levels: 0.3 %).
pub const SOURCE_THINNING: SourceThinning = SourceThinning {
    level_stride: 3,
    thin_from_levels: 30,
    dense_below_m: 6000.0,
    sun_stride: 2,
    sun_stride_below_zenith_deg: 75.0,
    wavelength_stride: 2,
    max_wavelength_gap_nm: 40.0,
    azimuths_deg: &AZIMUTHS_DEG,
    azimuth_stride: 1,
    half: true,
};

/// The source's azimuths from the sun, degrees: the field's source
/// table's own (`TABLE_AZIMUTHS_DEG`, 19 nodes 4-7 degrees apart from 10
/// to 30 degrees from the sun, where a low sun's ln R bends most in
/// azimuth, and 10-12 beyond; read linearly in the cosine of the azimuth
/// within the first and the last cell, as the library does), so the march
/// takes the table as it is. Measured with the probe (mars-dust, suns 2
/// and -4, views 1-30 degrees up, 0-175 degrees from the sun): 19
/// uniform nodes read linearly put the march 2.9-4.2 % below the
/// library 2.5-7.5 degrees from the sun; these within 1.43 %
/// (`docs/engine-tables.md`).
pub const AZIMUTHS_DEG: [f64; 19] = TABLE_AZIMUTHS_DEG;

/// ln R at or below this is no light (as the library's march).
pub const DARK_LOG_SOURCE: f64 = -46.0;

/// Steps of the march along the segment (crowded toward the eye) and
/// from the point to the ray's end (crowded toward the point).
pub const MARCH_STEPS: (usize, usize) = (32, 16);

/// The tables of the aerial-perspective march (see the module docs).
#[derive(Debug, Clone)]
pub struct MarchTables {
    /// The wavelengths (indices) the source is kept at, ascending, the
    /// first and the last among them.
    pub(crate) source_wavelengths: Vec<usize>,
    pub(crate) ground_radius_m: f64,
    pub(crate) thickness_m: f64,
    pub(crate) source: ExportedSource,
    /// XYZ of a unit spike at each wavelength.
    pub(crate) xyz: Vec<[f64; 3]>,
    /// Relative densities, [n * species + j], node n at altitude n H /
    /// (DENSITY_NODES - 1).
    pub(crate) density: Vec<f32>,
    /// Columns toward the sun, [(a * M + m) * species + j], m.
    pub(crate) sun_columns: Vec<f32>,
    /// p_j and the smooth phase, [(j * PHASE_NODES + t) * wavelengths + i].
    pub(crate) phase: Vec<f32>,
    pub(crate) smooth_phase: Vec<f32>,
}

impl MarchTables {
    /// The march's tables of `sky`'s atmosphere from its field solved for
    /// every sun (`shared`). An error when the field's wavelengths are not
    /// the sky's.
    pub(crate) fn bake(sky: &Sky, shared: &SharedField) -> Result<MarchTables> {
        // Probe (`tests::probe_the_march_s_parts`): the source kept at
        // level stride, dense below (km), wavelength stride, half (0 / 1)
        // as SORA_PROBE_FULL_SOURCE says ("1,0,1,0": the whole source, every
        // level, sun node and wavelength in 32-bit floats).
        #[cfg(test)]
        if let Ok(v) = std::env::var("SORA_PROBE_FULL_SOURCE") {
            let n: Vec<f64> = v.split(',').map(|n| n.parse().unwrap()).collect();
            let full = SourceThinning {
                level_stride: n[0] as usize,
                dense_below_m: n[1] * 1e3,
                wavelength_stride: n[2] as usize,
                half: n[3] != 0.0,
                ..SOURCE_THINNING
            };
            return MarchTables::bake_with(sky, shared, full);
        }
        MarchTables::bake_with(sky, shared, SOURCE_THINNING)
    }

    /// [`MarchTables::bake`] with the source kept as `thinning` says (the
    /// tests measure others than the default).
    pub(crate) fn bake_with(
        sky: &Sky,
        shared: &SharedField,
        thinning: SourceThinning,
    ) -> Result<MarchTables> {
        let azimuths: Vec<f64> = thinning
            .azimuths_deg
            .iter()
            .map(|a| a.to_radians())
            .collect();
        // The source beside the rest, not copied where it is the table's.
        let (exported, log_source) = shared
            .table()
            .exported_parts(Some(&azimuths[..]).filter(|a| !a.is_empty()));
        let grid = sky.wavelengths();
        let thinning = SourceThinning {
            wavelength_stride: thinning.wavelength_stride_for(grid.step_nm()),
            ..thinning
        };
        let (source, source_wavelengths) = thinned_source(exported, &log_source, thinning);
        let n = grid.len();
        if source.wavelengths != n {
            return Err(Error::Unsupported(
                "the aerial-perspective march: the field's wavelengths are not the sky's".into(),
            ));
        }
        let to_xyz = SpectrumToXyz::new(sky.wavelengths(), Observer::default());
        let mut xyz = Vec::with_capacity(n);
        for i in 0..n {
            let mut spike = vec![0.0; n];
            spike[i] = 1.0;
            let c = to_xyz.to_xyz(&SampledSpectrum::from_values(spike))?;
            xyz.push([c.x, c.y, c.z]);
        }
        let (ground, top) = sky.scene().radii_m();
        let thickness = top - ground;
        let species = source.species;
        let mut density = vec![0.0f32; DENSITY_NODES * species];
        for node in 0..DENSITY_NODES {
            let h = node as f64 * thickness / (DENSITY_NODES - 1) as f64;
            for (j, profile) in source.profiles.iter().enumerate() {
                density[node * species + j] = profile.relative_density(h) as f32;
            }
        }
        let (a_count, m_count) = sun_column_nodes();
        // Altitude rows in parallel.
        let mut sun_columns = vec![0.0f32; a_count * m_count * species];
        crate::parallel::for_each_chunk_mut(&mut sun_columns, m_count * species, |a, row| {
            let r = ground + axes::altitude_of_node(a, a_count, thickness);
            for m in 0..m_count {
                let mu = axes::transmittance_mu_of_node(m, m_count, r, ground)
                    .max(axes::horizon_cosine(r, ground) + 1e-9);
                let direction = Vector3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                let columns = columns_to_top(&source, (ground, top), r, direction);
                for (j, c) in columns.iter().enumerate() {
                    row[m * species + j] = *c as f32;
                }
            }
        });
        let mut phase = vec![0.0f32; species * PHASE_NODES * n];
        let mut smooth_phase = vec![0.0f32; species * PHASE_NODES * n];
        let (mut exact, mut smooth) = (vec![0.0; species * n], vec![0.0; species * n]);
        for t in 0..PHASE_NODES {
            let theta = phase_angle(t);
            shared
                .table()
                .march_phases(theta.cos(), &mut exact, &mut smooth);
            for j in 0..species {
                for i in 0..n {
                    phase[(j * PHASE_NODES + t) * n + i] = exact[j * n + i] as f32;
                    smooth_phase[(j * PHASE_NODES + t) * n + i] = smooth[j * n + i] as f32;
                }
            }
        }
        Ok(MarchTables {
            source_wavelengths,
            ground_radius_m: ground,
            thickness_m: thickness,
            source,
            xyz,
            density,
            sun_columns,
            phase,
            smooth_phase,
        })
    }

    /// Bytes of the march's tables (`march.bin`'s size).
    pub fn size_bytes(&self) -> usize {
        self.arrays()
            .iter()
            .map(|a| a.values.len() * if a.half { 2 } else { 4 })
            .sum()
    }

    /// The peak beam's table, if any.
    pub(crate) fn beam(&self) -> Option<&ExportedBeam> {
        self.source.beam.as_ref()
    }
}

/// The scattering angle of phase node `t`, rad: pi u^2, u = t /
/// (PHASE_NODES - 1).
pub(crate) fn phase_angle(t: usize) -> f64 {
    let u = t as f64 / (PHASE_NODES - 1) as f64;
    std::f64::consts::PI * u * u
}

/// Columns (m) of every species from radius `r` on the z axis to the top
/// of the atmosphere along `direction` (midpoint rule in u = sqrt(s /
/// length), 400 steps crowded toward the point, where the air is
/// densest).
pub(crate) fn columns_to_top(
    source: &ExportedSource,
    (ground, top): (f64, f64),
    r: f64,
    direction: Vector3,
) -> Vec<f64> {
    const STEPS: usize = 400;
    let p = Vector3::new(0.0, 0.0, r);
    let b = p.dot(direction);
    let length = -b + (b * b - r * r + top * top).max(0.0).sqrt();
    let mut columns = vec![0.0; source.species];
    for k in 0..STEPS {
        let u = (k as f64 + 0.5) / STEPS as f64;
        let (at, ds) = (u * u * length, 2.0 * u * length / STEPS as f64);
        let h = ((p + direction * at).length() - ground).max(0.0);
        for (c, profile) in columns.iter_mut().zip(&source.profiles) {
            *c += profile.relative_density(h) * ds;
        }
    }
    columns
}

/// One array of `march.bin`: its name, its values, its layout and unit.
pub(crate) struct MarchArray<'a> {
    pub(crate) name: &'static str,
    /// Borrowed where the tables hold the array as stored (the source's
    /// tens of megabytes are not copied for the file, its size and the
    /// manifest).
    pub(crate) values: Cow<'a, [f32]>,
    /// Stored as 16-bit floats (otherwise 32-bit).
    pub(crate) half: bool,
    pub(crate) layout: &'static str,
    pub(crate) unit: &'static str,
}

impl MarchTables {
    /// The arrays of `march.bin`, in file order (little-endian 32-bit
    /// floats, one after another; the manifest gives each one's offset).
    pub(crate) fn arrays(&self) -> Vec<MarchArray<'_>> {
        let s = &self.source;
        let f = |v: &[f64]| Cow::Owned(v.iter().map(|x| *x as f32).collect::<Vec<f32>>());
        let beam = s.beam.as_ref();
        let array = |name, values, layout, unit| MarchArray {
            name,
            values,
            half: name == "log_source",
            layout,
            unit,
        };
        vec![
            array("source_levels_m", f(&s.levels_m), "[k]", "m (altitude)"),
            array("source_sun_zenith_rad", f(&s.sun_zenith_rad), "[s]", "rad"),
            array(
                "source_wavelength_indices",
                Cow::Owned(self.source_wavelengths.iter().map(|i| *i as f32).collect()),
                "[c]: the wavelength index of the source's channel c (ascending, the first and last wavelengths among them); ln R at the wavelengths between two channels is linear in the index",
                "1",
            ),
            array(
                "log_source",
                Cow::Borrowed(&s.log_source[..]),
                "[(((k * sun_nodes + s) * azimuth_nodes + f) * view_zenith_nodes + v) * channels + c], channels = source_wavelength_indices' length; view zenith v uniform over 0..pi, azimuth from the sun f at source_azimuth_rad[f]",
                "ln(W m^-2 sr^-1 nm^-1)",
            ),
            array(
                "extinction",
                f(&s.extinction),
                "[i * species + j]",
                "m^-1 per unit relative density",
            ),
            array(
                "scaled_extinction",
                f(&s.scaled_extinction),
                "[i * species + j]",
                "m^-1 per unit relative density (delta-M)",
            ),
            array(
                "scaled_scattering",
                f(&s.scaled_scattering),
                "[i * species + j]",
                "m^-1 per unit relative density (delta-M)",
            ),
            array(
                "scattering",
                f(&s.scattering),
                "[i * species + j]",
                "m^-1 per unit relative density",
            ),
            array("solar", f(&s.solar), "[i]", "W m^-2 nm^-1"),
            array(
                "xyz",
                Cow::Owned(self.xyz.iter().flatten().map(|x| *x as f32).collect()),
                "[i * 3 + c]",
                "XYZ of a unit spike at wavelength i",
            ),
            array(
                "density",
                Cow::Borrowed(&self.density[..]),
                "[n * species + j], altitude n H / (density_nodes - 1)",
                "1 (relative density)",
            ),
            array(
                "sun_columns",
                Cow::Borrowed(&self.sun_columns[..]),
                "[(a * M + m) * species + j] over the transmittance table's axes (a: axes.altitude with A nodes, m: axes.transmittance_mu with M nodes)",
                "m",
            ),
            array(
                "phase",
                Cow::Borrowed(&self.phase[..]),
                "[(j * phase_nodes + t) * wavelengths + i], theta = pi (t / (phase_nodes - 1))^2",
                "sr^-1",
            ),
            array(
                "smooth_phase",
                Cow::Borrowed(&self.smooth_phase[..]),
                "[(j * phase_nodes + t) * wavelengths + i], as phase",
                "sr^-1",
            ),
            array("kernel_x", f(&s.kernel.0), "[x]", "1"),
            array(
                "kernel",
                f(&s.kernel.3),
                "[(x * kernel_angles + t) * wavelengths + i], theta = kernel_radius_rad (t / (kernel_angles - 1))^2 (empty: no peak)",
                "sr^-1 (e^(-X) G)",
            ),
            array(
                "beam_altitudes_m",
                beam.map_or(Cow::Borrowed(&[][..]), |b| f(&b.altitudes_m)),
                "[a]",
                "m",
            ),
            array(
                "ln_beam",
                beam.map_or(Cow::Borrowed(&[][..]), |b| f(&b.ln_beam)),
                "[(a * beam_elevations + e) * wavelengths + i], elevation beam_first_elevation_deg + e beam_step_deg",
                "ln(1)",
            ),
            array(
                "ground_diffuse",
                f(&s.ground_diffuse),
                "[s * wavelengths + i] on the source's sun nodes",
                "W m^-2 sr^-1 nm^-1",
            ),
            array(
                "ground_direct",
                f(&s.ground_direct),
                "[s * wavelengths + i] on the source's sun nodes",
                "W m^-2 sr^-1 nm^-1",
            ),
            array(
                "source_azimuth_rad",
                f(&s.azimuths_rad),
                "[f]: the source's azimuth from the sun of node f (ascending from 0 to pi); ln R is linear in the azimuth between two nodes",
                "rad",
            ),
        ]
    }

    /// The manifest's entry of `march.bin`: its counts, constants, arrays
    /// (offset and length in floats, layout, unit).
    pub(crate) fn manifest(&self) -> serde_json::Value {
        let s = &self.source;
        let mut offset = 0usize;
        let mut arrays = serde_json::Map::new();
        for a in self.arrays() {
            arrays.insert(
                a.name.into(),
                serde_json::json!({
                    "offset_bytes": offset,
                    "length": a.values.len(),
                    "type": if a.half { "f16" } else { "f32" },
                    "layout": a.layout,
                    "unit": a.unit,
                }),
            );
            offset += a.values.len() * if a.half { 2 } else { 4 };
        }
        let beam = s.beam.as_ref();
        serde_json::json!({
            "file": "march.bin",
            "format": "little-endian IEEE floats of each array's type (f16 or f32), the arrays one after another (offset in bytes, length in values)",
            "wavelengths": s.wavelengths,
            "species": s.species,
            "sun_nodes": s.sun_zenith_rad.len(),
            "view_zenith_nodes": s.view_zenith_nodes,
            "azimuth_nodes": s.azimuth_nodes,
            "density_nodes": DENSITY_NODES,
            "sun_column_nodes": [sun_column_nodes().0, sun_column_nodes().1],
            "phase_nodes": PHASE_NODES,
            "kernel_angles": s.kernel.1,
            "kernel_blend_start_rad": s.kernel.2.0,
            "kernel_radius_rad": s.kernel.2.1,
            "has_forward_peaks": s.has_forward_peaks,
            "beam_first_elevation_deg": beam.map(|b| b.first_elevation_deg),
            "beam_step_deg": beam.map(|b| b.step_deg),
            "beam_elevations": beam.map(|b| b.elevations),
            "beam_range_deg": beam.map(|b| [b.range_deg.0, b.range_deg.1, b.range_deg.2]),
            "dark_log_source": DARK_LOG_SOURCE,
            "march_steps": [MARCH_STEPS.0, MARCH_STEPS.1],
            "arrays": arrays,
        })
    }
}

/// `source` kept as `thinning` says.
fn thinned_source(
    source: ExportedSource,
    log_source: &[f32],
    thinning: SourceThinning,
) -> (ExportedSource, Vec<usize>) {
    let SourceThinning {
        level_stride,
        thin_from_levels,
        dense_below_m,
        sun_stride,
        sun_stride_below_zenith_deg,
        wavelength_stride,
        max_wavelength_gap_nm: _,
        azimuths_deg: _,
        azimuth_stride,
        half,
    } = thinning;
    let kept = |count: usize, stride: usize| -> Vec<usize> {
        let mut nodes: Vec<usize> = (0..count).step_by(stride.max(1)).collect();
        if nodes.last() != Some(&(count - 1)) {
            nodes.push(count - 1);
        }
        nodes
    };
    // Every level up to the dense altitude, every level_stride-th above.
    let count = source.levels_m.len();
    let level_stride = if count < thin_from_levels {
        1
    } else {
        level_stride
    };
    let mut levels: Vec<usize> = Vec::new();
    let mut since = level_stride;
    for k in 0..count {
        if source.levels_m[k] <= dense_below_m || since >= level_stride || k + 1 == count {
            levels.push(k);
            since = 1;
        } else {
            since += 1;
        }
    }
    let suns_all = source.sun_zenith_rad.len();
    let sparse_below = sun_stride_below_zenith_deg.to_radians();
    let suns: Vec<usize> = (0..suns_all)
        .filter(|s| {
            source.sun_zenith_rad[*s] >= sparse_below
                || s % sun_stride.max(1) == 0
                || s + 1 == suns_all
        })
        .collect();
    let w = source.wavelengths;
    let channels = kept(w, wavelength_stride);
    let views = source.view_zenith_nodes;
    let azimuths = kept(source.azimuth_nodes, azimuth_stride);
    let block = source.azimuth_nodes * views * w;
    // One kept level per task.
    let per_level = suns.len() * azimuths.len() * views * channels.len();
    let mut kept_source = vec![0.0f32; levels.len() * per_level];
    crate::parallel::for_each_chunk_mut(&mut kept_source, per_level, |level, out| {
        let k = levels[level];
        let mut out = out.iter_mut();
        for s in &suns {
            let at = (k * suns_all + s) * block;
            for f in &azimuths {
                let values = &log_source[at + f * views * w..][..views * w];
                for node in values.chunks_exact(w) {
                    for (i, o) in channels.iter().zip(out.by_ref()) {
                        *o = if half {
                            exr::prelude::f16::from_f32(node[*i]).to_f32()
                        } else {
                            node[*i]
                        };
                    }
                }
            }
        }
    });
    let log_source = kept_source;
    let thinned = ExportedSource {
        levels_m: levels.iter().map(|k| source.levels_m[*k]).collect(),
        sun_zenith_rad: suns.iter().map(|s| source.sun_zenith_rad[*s]).collect(),
        ground_diffuse: suns
            .iter()
            .flat_map(|s| {
                source.ground_diffuse[s * source.wavelengths..][..source.wavelengths].to_vec()
            })
            .collect(),
        ground_direct: suns
            .iter()
            .flat_map(|s| {
                source.ground_direct[s * source.wavelengths..][..source.wavelengths].to_vec()
            })
            .collect(),
        azimuth_nodes: azimuths.len(),
        azimuths_rad: azimuths.iter().map(|f| source.azimuths_rad[*f]).collect(),
        log_source,
        ..source
    };
    (thinned, channels)
}
