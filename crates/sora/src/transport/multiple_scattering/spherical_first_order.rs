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
//! field of harmonics below N. Along each path: `PANELS` Gauss panels
//! ([`ProfileCorners::fill_panel_ends`]) and columns toward the sun from a
//! [`SunColumnTable`]. Units: W m^-2 sr^-1 nm^-1.

use std::f64::consts::PI;

use super::phase_fourier::TruncatedPhase;
use crate::atmosphere::DensityProfile;
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::transport::optical_column::{ProfileCorners, SunColumnRadius, SunColumnTable};
use crate::transport::quadrature::{GAUSS_NODES, GAUSS_WEIGHTS, running_integral_matrix};

/// Gauss panels along each stream's path (measured: 8 panels change the
/// zenith at sun -6 degrees by 4e-5 and at sun 5 by 2.5e-4, at 1.6 times
/// the cost).
const PANELS: usize = 4;
/// Nodes of the phase functions' tables over cos theta in [-1, 1].
const PHASE_NODES: usize = 2049;

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
///
/// A stream's path from a level does not depend on the sun (the sun turns
/// in the x-z plane, the azimuths are taken from it), so each path is
/// marched once, its samples' points, densities and columns from the
/// level kept, and every sun node then reads them: the same sums in the
/// same order as marching it per sun node
/// (`compute_spherical_first_order_reference`, the test's oracle), so the
/// result is the same bit for bit. One task per level.
pub(crate) fn compute_spherical_first_order(inputs: &FirstOrderInputs) -> Vec<f64> {
    let wavelengths = inputs.solar_irradiance_w_m2_nm.len();
    let species = inputs.profiles.len();
    let levels = inputs.level_altitudes_m.len();
    let streams = inputs.stream_cosines.len();
    let solution = streams * levels * streams;
    let suns = inputs.sun_zenith_rad.len();
    let (ground, _) = inputs.corners.radii_m();
    let azimuths = azimuth_count(streams);
    let running = running_integral_matrix();
    let cosines = harmonic_cosines(azimuths, streams);
    let phase_table = tabulate_phases(inputs.phases);
    let tables = &Tables {
        inputs,
        phase_table: &phase_table,
    };
    let by_species = &BySpecies::new(inputs);
    let suns_vectors: Vec<Vector3> = inputs
        .sun_zenith_rad
        .iter()
        .map(|theta| Vector3::new(theta.sin(), 0.0, theta.cos()))
        .collect();
    // Per level: [(s * streams + b) * streams + m) * wavelengths + i].
    let per_level = suns * streams * streams * wavelengths;
    let mut by_level = vec![0.0; levels * per_level];
    crate::parallel::for_each_chunk_mut(&mut by_level, per_level, |k, block| {
        let x = Vector3::new(0.0, 0.0, ground + inputs.level_altitudes_m[k]);
        let mut work = MarchWork {
            radiance: vec![0.0; wavelengths],
            phase: vec![0.0; wavelengths * species],
            densities: vec![[0.0; 4]; species],
            view_columns: vec![0.0; species],
            #[cfg(test)]
            node_columns: vec![0.0; species],
            #[cfg(test)]
            sun_columns: vec![0.0; species],
            ends: Vec::with_capacity(inputs.corners.most_panel_ends(PANELS)),
        };
        let mut sun_work = SunWork {
            phase: vec![0.0; species * wavelengths],
            columns: vec![0.0; species],
            optical_depths: vec![0.0; wavelengths],
            sources: vec![0.0; wavelengths],
        };
        let mut path = MarchedPath::default();
        for (b, mu) in inputs.stream_cosines.iter().enumerate() {
            let sine = (1.0 - mu * mu).max(0.0).sqrt();
            for a in 0..azimuths {
                let phi = PI * (a as f64 + 0.5) / azimuths as f64;
                let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), *mu);
                if !march_path(tables, &running, x, direction, &mut work, &mut path) {
                    continue;
                }
                for (s, sun) in suns_vectors.iter().enumerate() {
                    compute_first_order_on_path(
                        tables,
                        by_species,
                        direction,
                        *sun,
                        &path,
                        &mut work,
                        &mut sun_work,
                    );
                    let harmonics = &mut block[(s * streams + b) * streams * wavelengths..]
                        [..streams * wavelengths];
                    for (m, row) in harmonics.chunks_exact_mut(wavelengths).enumerate() {
                        let factor = cosines[a * streams + m];
                        for (h, l) in row.iter_mut().zip(&work.radiance) {
                            *h += factor * l;
                        }
                    }
                }
            }
        }
    });
    let mut out = vec![0.0; suns * wavelengths * solution];
    for k in 0..levels {
        for s in 0..suns {
            for b in 0..streams {
                for m in 0..streams {
                    let row = &by_level
                        [k * per_level + ((s * streams + b) * streams + m) * wavelengths..]
                        [..wavelengths];
                    let at = (m * levels + k) * streams + b;
                    for (i, h) in row.iter().enumerate() {
                        out[(s * wavelengths + i) * solution + at] = *h;
                    }
                }
            }
        }
    }
    out
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

/// p*_ij tabulated over cos theta on `PHASE_NODES` nodes in [-1, 1],
/// [(i * species + j) * PHASE_NODES + n], sr^-1.
fn tabulate_phases(phases: &[TruncatedPhase]) -> Vec<f64> {
    phases
        .iter()
        .flat_map(|phase| {
            (0..PHASE_NODES)
                .map(move |n| phase.eval(2.0 * n as f64 / (PHASE_NODES - 1) as f64 - 1.0))
        })
        .collect()
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
    running: &[[f64; 4]; 4],
    x: Vector3,
    direction: Vector3,
    work: &mut MarchWork,
    path: &mut MarchedPath,
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
    let start = x + direction * enter;
    inputs
        .corners
        .fill_panel_ends(start, direction, length, PANELS, &mut work.ends);
    path.points.clear();
    path.radii.clear();
    path.located.clear();
    path.weights.clear();
    path.densities.clear();
    path.node_columns.clear();
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
            let r = points[n].length();
            path.points.push(points[n]);
            path.radii.push(r);
            path.located.push(inputs.sun_columns.locate_radius(r));
            path.weights.push(half * GAUSS_WEIGHTS[n]);
            for j in 0..species {
                let inside: f64 = (0..4).map(|q| running[n][q] * work.densities[j][q]).sum();
                path.node_columns.push(work.view_columns[j] + half * inside);
                path.densities.push(work.densities[j][n]);
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
/// march, once for every sun.
fn compute_first_order_on_path(
    inputs: &Tables,
    by_species: &BySpecies,
    direction: Vector3,
    sun: Vector3,
    path: &MarchedPath,
    work: &mut MarchWork,
    sun_work: &mut SunWork,
) {
    let species = inputs.profiles.len();
    let wavelengths = work.radiance.len();
    interpolate_phases(inputs.phase_table, direction.dot(sun), &mut work.phase);
    for (i, row) in work.phase.chunks_exact(species).enumerate() {
        for (j, p) in row.iter().enumerate() {
            sun_work.phase[j * wavelengths + i] = *p;
        }
    }
    work.radiance.fill(0.0);
    for (n, point) in path.points.iter().enumerate() {
        let r = path.radii[n];
        if !inputs.sun_columns.lookup_columns_at_radius(
            &path.located[n],
            point.dot(sun) / r,
            &mut sun_work.columns,
        ) {
            continue;
        }
        let weight = path.weights[n];
        let node_columns = &path.node_columns[n * species..(n + 1) * species];
        let densities = &path.densities[n * species..(n + 1) * species];
        sun_work.optical_depths.fill(0.0);
        sun_work.sources.fill(0.0);
        for j in 0..species {
            let column = node_columns[j] + sun_work.columns[j];
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
        for (((out, tau), source), solar) in work
            .radiance
            .iter_mut()
            .zip(&sun_work.optical_depths)
            .zip(&sun_work.sources)
            .zip(inputs.solar_irradiance_w_m2_nm)
        {
            if *source > 0.0 {
                *out += weight * solar * source * (-tau).exp();
            }
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
        let species = inputs.profiles.len();
        let transpose = |by_wavelength: &[f64]| -> Vec<f64> {
            (0..species * wavelengths)
                .map(|at| by_wavelength[(at % wavelengths) * species + at / wavelengths])
                .collect()
        };
        BySpecies {
            scaled_extinction: transpose(inputs.scaled_extinction),
            scaled_scattering: transpose(inputs.scaled_scattering),
        }
    }
}

/// Work space of [`compute_first_order_on_path`], species-major: the
/// phase functions [j * wavelengths + i], the columns toward the sun per
/// species, and per wavelength the optical depth and the source of a
/// sample.
struct SunWork {
    phase: Vec<f64>,
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
    let species = inputs.profiles.len();
    let levels = inputs.level_altitudes_m.len();
    let streams = inputs.stream_cosines.len();
    let solution = streams * levels * streams;
    let suns = inputs.sun_zenith_rad.len();
    let (ground, _) = inputs.corners.radii_m();
    let mut out = vec![0.0; suns * wavelengths * solution];
    let running = running_integral_matrix();
    let azimuths = azimuth_count(streams);
    let cosines = harmonic_cosines(azimuths, streams);
    let phase_table = tabulate_phases(inputs.phases);
    let inputs = &Tables {
        inputs,
        phase_table: &phase_table,
    };
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
        // Harmonics of one (level, stream), [m * wavelengths + i], summed
        // over the azimuths before they go to their strided places.
        let mut harmonics = vec![0.0; streams * wavelengths];
        for (k, z) in inputs.level_altitudes_m.iter().enumerate() {
            let x = Vector3::new(0.0, 0.0, ground + z);
            for (b, mu) in inputs.stream_cosines.iter().enumerate() {
                let sine = (1.0 - mu * mu).max(0.0).sqrt();
                harmonics.fill(0.0);
                for a in 0..azimuths {
                    let phi = PI * (a as f64 + 0.5) / azimuths as f64;
                    let direction = Vector3::new(sine * phi.cos(), sine * phi.sin(), *mu);
                    if !compute_first_order_along_ray(
                        inputs, &running, x, direction, sun, &mut work,
                    ) {
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

/// The inputs and the phase functions' tables.
struct Tables<'a> {
    inputs: &'a FirstOrderInputs<'a>,
    phase_table: &'a [f64],
}

impl<'a> std::ops::Deref for Tables<'a> {
    type Target = FirstOrderInputs<'a>;
    fn deref(&self) -> &FirstOrderInputs<'a> {
        self.inputs
    }
}

struct MarchWork {
    radiance: Vec<f64>,
    phase: Vec<f64>,
    densities: Vec<[f64; 4]>,
    view_columns: Vec<f64>,
    /// The oracle's columns from the level to the current node.
    #[cfg(test)]
    node_columns: Vec<f64>,
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
    interpolate_phases(inputs.phase_table, direction.dot(sun), &mut work.phase);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast first order (each path marched once for every sun node)
    /// equals the oracle (marched per sun node) bit for bit: two species,
    /// three wavelengths, 2 streams per hemisphere, five levels, suns from
    /// 84 to 100 degrees of zenith (lit, grazing and deep in the shadow).
    #[test]
    fn marching_once_for_every_sun_is_the_oracle_bit_for_bit() {
        let (ground, top) = (6_360e3, 6_460e3);
        let profiles = vec![
            DensityProfile::Exponential {
                scale_height_m: 8_000.0,
            },
            DensityProfile::Exponential {
                scale_height_m: 1_200.0,
            },
        ];
        let corners = ProfileCorners::new(&profiles, ground, top);
        let sun_columns = SunColumnTable::compute(&profiles, ground, top, 32, 64);
        let streams = crate::transport::multiple_scattering::successive_orders::Streams::new(2);
        let degrees = streams.count();
        let phases: Vec<TruncatedPhase> = (0..3 * 2)
            .map(|n| {
                // Rayleigh-like and forward-peaked moments.
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
            .collect();
        let inputs = FirstOrderInputs {
            profiles: &profiles,
            corners: &corners,
            sun_columns: &sun_columns,
            level_altitudes_m: &[0.0, 1e3, 5e3, 20e3, 60e3],
            stream_cosines: streams.cosines(),
            sun_zenith_rad: &[
                84f64.to_radians(),
                89f64.to_radians(),
                93f64.to_radians(),
                100f64.to_radians(),
            ],
            scaled_extinction: &[2.4e-5, 8e-5, 1.2e-5, 7e-5, 0.6e-5, 6e-5],
            scaled_scattering: &[2.4e-5, 7e-5, 1.2e-5, 6e-5, 0.6e-5, 5e-5],
            phases: &phases,
            solar_irradiance_w_m2_nm: &[1.7, 1.9, 1.5],
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
}
