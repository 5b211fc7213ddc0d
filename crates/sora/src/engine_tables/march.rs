//! The tables of the aerial-perspective march: what a shader needs to
//! march the segment from the eye to a point, per pixel, and get the
//! library's light of the air (`Sky::compute_segment_light`), on the sky's
//! wavelength grid (i) for each species (j). All of it comes from the
//! multiple-scattering field solved once for every sun and eye
//! (`sky::shared_field`), which the sky table's layers are drawn from too:
//!
//! - **source**: ln R, R = J* / beta*_sca the scaled field's source toward
//!   the eye (W m^-2 sr^-1 nm^-1), over the field's altitude levels, its
//!   sun zenith nodes, the view's zenith angle and its azimuth from the
//!   sun (uniform over 0..pi); quadrilinear in ln R (a value at or below
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

use super::axes;
use crate::colour::{Observer, SpectrumToXyz};
use crate::error::{Error, Result};
use crate::geometry::Vector3;
use crate::sky::{SharedField, Sky};
use crate::spectrum::SampledSpectrum;
use crate::transport::multiple_scattering::{ExportedBeam, ExportedSource};

/// Nodes of the density table over 0..the atmosphere's thickness.
pub const DENSITY_NODES: usize = 1024;

/// Nodes of the sun-column table: altitude, view cosine (the
/// transmittance table's axes). At 32 x 128 the march was 2.3 % off at
/// -4 degrees (earth-clear, 50 km); at 64 x 512 it matches exact
/// columns (`docs/engine-tables.md`).
pub const SUN_COLUMN_NODES: (usize, usize) = (64, 512);

/// Nodes of the phase tables in u = sqrt(theta / pi).
pub const PHASE_NODES: usize = 1024;

/// ln R at or below this is no light (as the library's march).
pub const DARK_LOG_SOURCE: f64 = -46.0;

/// Steps of the march along the segment (crowded toward the eye) and
/// from the point to the ray's end (crowded toward the point).
pub const MARCH_STEPS: (usize, usize) = (32, 16);

/// The tables of the aerial-perspective march (see the module docs).
#[derive(Debug, Clone)]
pub struct MarchTables {
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
        let source = shared.table().exported();
        let n = sky.wavelengths().len();
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
        let (a_count, m_count) = SUN_COLUMN_NODES;
        let mut sun_columns = vec![0.0f32; a_count * m_count * species];
        for a in 0..a_count {
            let r = ground + axes::altitude_of_node(a, a_count, thickness);
            for m in 0..m_count {
                let mu = axes::transmittance_mu_of_node(m, m_count, r, ground)
                    .max(axes::horizon_cosine(r, ground) + 1e-9);
                let direction = Vector3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
                let columns = columns_to_top(&source, (ground, top), r, direction);
                for (j, c) in columns.iter().enumerate() {
                    sun_columns[(a * m_count + m) * species + j] = *c as f32;
                }
            }
        }
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

    /// Bytes of the march's tables as 32-bit floats.
    pub fn size_bytes(&self) -> usize {
        let s = &self.source;
        let beam = s.beam.as_ref().map_or(0, |b| b.ln_beam.len());
        4 * (s.log_source.len()
            + self.density.len()
            + self.sun_columns.len()
            + self.phase.len()
            + self.smooth_phase.len()
            + s.kernel.3.len()
            + beam
            + s.ground_diffuse.len()
            + s.ground_direct.len()
            + 4 * s.extinction.len()
            + 4 * s.wavelengths)
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
fn columns_to_top(
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
