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
//! transform over `AZIMUTHS` midpoint azimuths on 0..180 degrees (the
//! field is symmetric about the solar meridian):
//! L1_m = (2 - delta_m0) / N sum_a L1(phi_a) cos(m phi_a), exact for a
//! field of harmonics below N. Along each path: `PANELS` Gauss panels
//! ([`ProfileCorners::fill_panel_ends`]) and columns toward the sun from a
//! [`SunColumnTable`]. Units: W m^-2 sr^-1 nm^-1.

use std::f64::consts::PI;

use super::phase_fourier::TruncatedPhase;
use crate::atmosphere::DensityProfile;
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::transport::optical_column::{ProfileCorners, SunColumnTable};
use crate::transport::quadrature::{GAUSS_NODES, GAUSS_WEIGHTS, running_integral_matrix};

/// Azimuths of the cosine transform (the solver has 2n = 16 harmonics at
/// the default 8 streams per hemisphere).
const AZIMUTHS: usize = 16;
/// Gauss panels along each stream's path.
const PANELS: usize = 8;

/// What the first-order march needs (all per wavelength i and species j
/// at [i * species + j]).
pub(crate) struct FirstOrderInputs<'a> {
    pub profiles: &'a [DensityProfile],
    pub corners: &'a ProfileCorners,
    pub sun_columns: &'a SunColumnTable,
    pub level_altitudes_m: &'a [f64],
    pub stream_cosines: &'a [f64],
    pub sun_zenith_rad: &'a [f64],
    pub scaled_extinction: &'a [f64],
    pub scaled_scattering: &'a [f64],
    pub phases: &'a [TruncatedPhase],
    pub solar_irradiance_w_m2_nm: &'a [f64],
}

/// L1 for every sun node, wavelength, harmonic, level and stream, laid out
/// as the solver's solutions: [(s * wavelengths + i) * solution + (m *
/// levels + k) * streams + b], solution = streams * levels * streams
/// (harmonics = streams).
pub(crate) fn compute_spherical_first_order(inputs: &FirstOrderInputs) -> Vec<f64> {
    let wavelengths = inputs.solar_irradiance_w_m2_nm.len();
    let species = inputs.profiles.len();
    let levels = inputs.level_altitudes_m.len();
    let streams = inputs.stream_cosines.len();
    let solution = streams * levels * streams;
    let suns = inputs.sun_zenith_rad.len();
    let (ground, _) = inputs.corners.radii_m();
    let mut out = vec![0.0; suns * wavelengths * solution];
    let running = running_integral_matrix();
    crate::parallel::for_each_chunk_mut(&mut out, wavelengths * solution, |s, block| {
        let theta = inputs.sun_zenith_rad[s];
        let sun = Vector3::new(theta.sin(), 0.0, theta.cos());
        let mut work = MarchWork {
            radiance: vec![0.0; wavelengths],
            phase: vec![0.0; wavelengths * species],
            densities: vec![[0.0; 4]; species],
            view_columns: vec![0.0; species],
            node_columns: vec![0.0; species],
            sun_columns: vec![0.0; species],
            ends: Vec::with_capacity(inputs.corners.most_panel_ends(PANELS)),
        };
        for (k, z) in inputs.level_altitudes_m.iter().enumerate() {
            let x = Vector3::new(0.0, 0.0, ground + z);
            for (b, mu) in inputs.stream_cosines.iter().enumerate() {
                let sine = (1.0 - mu * mu).max(0.0).sqrt();
                for a in 0..AZIMUTHS {
                    let phi = PI * (a as f64 + 0.5) / AZIMUTHS as f64;
                    let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), *mu);
                    if !compute_first_order_along_ray(
                        inputs, &running, x, direction, sun, &mut work,
                    ) {
                        continue;
                    }
                    for m in 0..streams {
                        let factor = if m == 0 { 1.0 } else { 2.0 } / AZIMUTHS as f64
                            * (m as f64 * phi).cos();
                        let at = (m * levels + k) * streams + b;
                        for (i, l) in work.radiance.iter().enumerate() {
                            block[i * solution + at] += factor * l;
                        }
                    }
                }
            }
        }
    });
    out
}

struct MarchWork {
    radiance: Vec<f64>,
    phase: Vec<f64>,
    densities: Vec<[f64; 4]>,
    view_columns: Vec<f64>,
    node_columns: Vec<f64>,
    sun_columns: Vec<f64>,
    ends: Vec<f64>,
}

/// L1(x, w) per wavelength into `work.radiance` (see the module docs);
/// false when the path has no length in the atmosphere (nothing written).
fn compute_first_order_along_ray(
    inputs: &FirstOrderInputs,
    running: &[[f64; 4]; 4],
    x: Vector3,
    direction: Vector3,
    sun: Vector3,
    work: &mut MarchWork,
) -> bool {
    let (ground, top) = inputs.corners.radii_m();
    let Some((enter, exit)) = segment_in_atmosphere(x, direction, ground, top) else {
        return false;
    };
    let length = exit - enter;
    if length <= 0.0 {
        return false;
    }
    let species = inputs.profiles.len();
    let cos_theta = direction.dot(sun);
    for (p, phase) in work.phase.iter_mut().zip(inputs.phases) {
        *p = phase.eval(cos_theta);
    }
    let start = x + direction * enter;
    inputs
        .corners
        .fill_panel_ends(start, direction, length, PANELS, &mut work.ends);
    work.radiance.fill(0.0);
    work.view_columns.fill(0.0);
    for e in 0..work.ends.len() - 1 {
        let (a, b) = (work.ends[e], work.ends[e + 1]);
        let (centre, half) = (0.5 * (a + b), 0.5 * (b - a));
        let mut points = [Vector3::default(); 4];
        for (n, g) in GAUSS_NODES.iter().enumerate() {
            points[n] = start + direction * (centre + half * g);
            let altitude = points[n].length() - ground;
            for j in 0..species {
                work.densities[j][n] = inputs.profiles[j].relative_density(altitude);
            }
        }
        for n in 0..4 {
            for j in 0..species {
                let inside: f64 = (0..4).map(|q| running[n][q] * work.densities[j][q]).sum();
                work.node_columns[j] = work.view_columns[j] + half * inside;
            }
            let r = points[n].length();
            if !inputs.sun_columns.lookup_columns_to_sun(
                r,
                points[n].dot(sun) / r,
                &mut work.sun_columns,
            ) {
                continue;
            }
            let weight = half * GAUSS_WEIGHTS[n];
            for (i, out) in work.radiance.iter_mut().enumerate() {
                let (mut tau, mut source) = (0.0, 0.0);
                for j in 0..species {
                    let at = i * species + j;
                    tau +=
                        inputs.scaled_extinction[at] * (work.node_columns[j] + work.sun_columns[j]);
                    source += inputs.scaled_scattering[at] * work.densities[j][n] * work.phase[at];
                }
                if source > 0.0 {
                    *out += weight * inputs.solar_irradiance_w_m2_nm[i] * source * (-tau).exp();
                }
            }
        }
        for j in 0..species {
            let panel: f64 = (0..4)
                .map(|q| GAUSS_WEIGHTS[q] * work.densities[j][q])
                .sum();
            work.view_columns[j] += half * panel;
        }
    }
    true
}
