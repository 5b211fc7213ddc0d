//! The paths of the near-horizontal streams through the spherical shells,
//! and the angles at the planet's centre over which they gather their
//! light.
//!
//! In a plane-parallel slab a stream of zenith cosine mu crosses every
//! layer with the path dz / |mu|, and the radiance at a level follows from
//! the next level's by one recursion step. In the planet's spherical shell
//! the same straight ray turns steeper as it climbs (its impact parameter
//! b = r sqrt(1 - mu^2) is fixed), and a ray looking slightly down passes
//! its lowest point above the ground and climbs back out to space instead
//! of reaching the ground: near the horizon the slab's paths are far too
//! long (infinite at mu = 0), and the diffuse light it computes there is
//! too bright. In a thin atmosphere (the red end of the spectrum) that
//! horizontal excess is a visible share of the multiply scattered light:
//! measured against the path tracer, 2-7 % of it at 780 nm.
//!
//! **Spherical paths.** For the streams whose paths differ from the slab's
//! (|mu| below [`SPHERICAL_STREAM_COSINE`]), the radiance at each level is
//! integrated along the real straight path through the shells, from the
//! level to the top or to the ground: step by step between the spheres it
//! crosses, with the source function linear in optical depth on each step
//! (as in the slab), each layer's optical depth stretched by the step's
//! length over the layer's thickness, and the source at the lowest point of
//! a ray that misses the ground interpolated between the two levels around
//! it. The source along the path is the column's own at the same stream
//! (the pseudo-spherical column is horizontally uniform; the small change
//! of the local zenith angle along the path is neglected). The result is a
//! transport matrix per stream and wavelength, L(k) = sum_j M_kj S(j) +
//! g_k L_ground, applied at every order.
//!
//! **Where the light comes from**: each path's mean angle at the planet's
//! centre and its spread ([`StreamPaths::compute_transport_matrices`]),
//! with which `twilight_shift.rs` moves the light of these streams toward
//! the columns where it was gathered.

use super::regimes::SPHERICAL_STREAM_COSINE;

/// One straight step of a path inside one layer.
#[derive(Debug, Clone, Copy)]
struct PathStep {
    layer: usize,
    /// Length of the step over the layer's thickness (1 / |mu| in a slab).
    stretch: f64,
    /// The source at the step's near and far ends: a level and the
    /// weight of the level above it ((1 - w) S(level) + w S(level + 1)).
    near: (usize, f64),
    far: (usize, f64),
    /// Angle at the planet's centre between the path's start and the
    /// step's middle, rad.
    centre_angle: f64,
}

impl PathStep {
    /// Adds this step's share of path k's light to `matrix` (levels x
    /// levels, row = source level, column = k): the linear source's
    /// weights at its near and far ends (`linear_source_weights`: the
    /// step's 1 - e^-x and c) times the transmittance to the step, each
    /// split between the two levels about it.
    #[inline]
    fn add_source_weights(
        &self,
        matrix: &mut [f64],
        levels: usize,
        k: usize,
        transmittance: f64,
        one_minus_e: f64,
        c: f64,
    ) {
        let near = transmittance * (one_minus_e - c);
        let far = transmittance * c;
        for ((level, w), weight) in [(self.near, near), (self.far, far)] {
            matrix[level * levels + k] += (1.0 - w) * weight;
            if w > 0.0 {
                matrix[(level + 1) * levels + k] += w * weight;
            }
        }
    }
}

/// The paths of every (level, stream) whose stream is spherical.
#[derive(Debug, Clone)]
pub struct StreamPaths {
    levels: usize,
    /// Streams (of the solver's 2n) with spherical paths.
    spherical_streams: Vec<usize>,
    /// [(index into spherical_streams) * levels + k]: range of steps, and
    /// whether the path ends on the ground.
    paths: Vec<(usize, usize, bool)>,
    steps: Vec<PathStep>,
}

impl StreamPaths {
    /// Paths from the levels at `radii_m` (increasing, the first the
    /// ground) along each stream cosine of `cosines` with
    /// |mu| < [`SPHERICAL_STREAM_COSINE`].
    pub(crate) fn compute(radii_m: &[f64], cosines: &[f64]) -> StreamPaths {
        let levels = radii_m.len();
        let spherical_streams: Vec<usize> = (0..cosines.len())
            .filter(|a| cosines[*a].abs() < SPHERICAL_STREAM_COSINE)
            .collect();
        let mut paths = Vec::with_capacity(spherical_streams.len() * levels);
        let mut steps = Vec::new();
        for &a in &spherical_streams {
            for k in 0..levels {
                let first = steps.len();
                let ends_on_ground = trace(radii_m, k, cosines[a], &mut steps);
                paths.push((first, steps.len(), ends_on_ground));
            }
        }
        StreamPaths {
            levels,
            spherical_streams,
            paths,
            steps,
        }
    }

    /// The streams that take spherical paths.
    pub(crate) fn spherical_streams(&self) -> &[usize] {
        &self.spherical_streams
    }

    /// Transport matrices for layer optical depths `layer_optical_depth`:
    /// for each spherical stream, M by columns ([j * levels + k], the
    /// weight of S(j) in L(k)) then the ground weights g_k, into `out`
    /// (`spherical_streams().len() * levels * (levels + 1)` values), and
    /// the rows where each column is non-zero into `rows`
    /// ([s * levels + j], half-open; paths that only climb make M
    /// triangular), and the mean angle at the planet's centre between each
    /// level and the light its path gathers (weighted by what a uniform
    /// source would contribute) and the spread of that angle (its standard
    /// deviation with the same weights) into `mean_angles` ([s * levels +
    /// k], rad).
    pub(crate) fn compute_transport_matrices(
        &self,
        layer_optical_depth: &[f64],
        out: &mut [f64],
        rows: &mut [(usize, usize)],
        mean_angles: &mut [(f64, f64)],
    ) {
        let levels = self.levels;
        let block = levels * (levels + 1);
        out.fill(0.0);
        for (s, _) in self.spherical_streams.iter().enumerate() {
            let (matrix, ground) = out[s * block..(s + 1) * block].split_at_mut(levels * levels);
            for k in 0..levels {
                let (first, last, ends_on_ground) = self.paths[s * levels + k];
                let mut transmittance = 1.0;
                let (mut angle_sum, mut square_sum, mut weight_sum) = (0.0, 0.0, 0.0);
                for step in &self.steps[first..last] {
                    let x = layer_optical_depth[step.layer] * step.stretch;
                    let (one_minus_e, c) = linear_source_weights(x);
                    angle_sum += transmittance * one_minus_e * step.centre_angle;
                    square_sum += transmittance * one_minus_e * step.centre_angle.powi(2);
                    weight_sum += transmittance * one_minus_e;
                    step.add_source_weights(matrix, levels, k, transmittance, one_minus_e, c);
                    transmittance *= 1.0 - one_minus_e;
                }
                if ends_on_ground {
                    ground[k] = transmittance;
                }
                mean_angles[s * levels + k] = if weight_sum > 0.0 {
                    let mean = angle_sum / weight_sum;
                    (
                        mean,
                        (square_sum / weight_sum - mean * mean).max(0.0).sqrt(),
                    )
                } else {
                    (0.0, 0.0)
                };
            }
            nonzero_rows(matrix, levels, &mut rows[s * levels..(s + 1) * levels]);
        }
    }

    /// Per step of `steps` (one path's) under the layer optical depths
    /// `layer_optical_depth`: its weight w (what a uniform source along it
    /// contributes: the transmittance to it times 1 - e^-x, as the mean
    /// angles') and its measure w^(1/3) d^(2/3), d the angle it spans at
    /// the planet's centre (half the distance between its neighbours'
    /// centres), into `out`.
    fn step_measures(
        &self,
        steps: &[PathStep],
        layer_optical_depth: &[f64],
        out: &mut Vec<(f64, f64)>,
    ) {
        out.clear();
        let mut transmittance = 1.0;
        for (i, step) in steps.iter().enumerate() {
            let (one_minus_e, _) =
                linear_source_weights(layer_optical_depth[step.layer] * step.stretch);
            let w = transmittance * one_minus_e;
            let before = i.checked_sub(1).map_or(0.0, |i| steps[i].centre_angle);
            let after = steps
                .get(i + 1)
                .map_or(step.centre_angle, |s| s.centre_angle);
            let span = 0.5 * (after - before).abs();
            out.push((w, w.cbrt() * span.powf(2.0 / 3.0)));
            transmittance *= 1.0 - one_minus_e;
        }
    }

    /// The transport matrices of [`StreamPaths::compute_transport_matrices`]
    /// with each path cut into consecutive pieces: per piece b and
    /// spherical stream s the matrix and ground weights at
    /// [(b * count + s) * levels * (levels + 1)] (same layout; the pieces' matrices sum to
    /// the whole path's), and each piece's mean angle at the planet's
    /// centre and its spread at [(b * count + s) * levels + k] (rad; (0, 0)
    /// for a piece that gathers nothing). A path whose angle's spread is
    /// sigma (the whole path's, as the mean angles') takes ceil(sigma /
    /// `spread_step_rad`) pieces, at least 1 and at most `pieces` (all
    /// `pieces` where the step is 0), the first ones; they gather equal
    /// shares of the measure w^(1/3) d^(2/3) summed over the path's steps
    /// ([`StreamPaths::step_measures`]): the spacing that minimises the
    /// sum over pieces of their light times their angle's variance, for
    /// a piece's error grows as the square of the angle it spans (the
    /// density of light per angle to the power 1/3, as for a piecewise
    /// constant approximation's optimal mesh). The ground's weight goes to
    /// the path's last piece.
    pub(crate) fn compute_piece_matrices(
        &self,
        layer_optical_depth: &[f64],
        pieces: usize,
        spread_step_rad: f64,
    ) -> (Vec<f64>, Vec<(f64, f64)>) {
        let levels = self.levels;
        let block = levels * (levels + 1);
        let count = self.spherical_streams.len();
        let pieces = pieces.max(1);
        let mut out = vec![0.0; pieces * count * block];
        let mut angles = vec![(0.0, 0.0); pieces * count * levels];
        let mut sums = vec![(0.0, 0.0, 0.0); pieces];
        let mut measures = Vec::new();
        for s in 0..count {
            for k in 0..levels {
                let (first, last, ends_on_ground) = self.paths[s * levels + k];
                let steps = &self.steps[first..last];
                self.step_measures(steps, layer_optical_depth, &mut measures);
                let (mut angle_sum, mut square_sum, mut weight_sum) = (0.0, 0.0, 0.0);
                for (step, (w, _)) in steps.iter().zip(&measures) {
                    angle_sum += w * step.centre_angle;
                    square_sum += w * step.centre_angle.powi(2);
                    weight_sum += w;
                }
                let total: f64 = measures.iter().map(|(_, m)| m).sum();
                // As many pieces as the whole path's spread asks for.
                let here = if weight_sum > 0.0 && spread_step_rad > 0.0 {
                    let mean = angle_sum / weight_sum;
                    let spread = (square_sum / weight_sum - mean * mean).max(0.0).sqrt();
                    ((spread / spread_step_rad).ceil() as usize).clamp(1, pieces)
                } else {
                    pieces
                };
                sums.fill((0.0, 0.0, 0.0));
                let (mut transmittance, mut gathered) = (1.0, 0.0);
                for (step, (_, measure)) in steps.iter().zip(&measures) {
                    let (one_minus_e, c) =
                        linear_source_weights(layer_optical_depth[step.layer] * step.stretch);
                    let weight = transmittance * one_minus_e;
                    let b = if total > 0.0 {
                        ((gathered + 0.5 * measure) / total * here as f64) as usize
                    } else {
                        0
                    }
                    .min(here - 1);
                    gathered += measure;
                    let sum = &mut sums[b];
                    sum.0 += weight * step.centre_angle;
                    sum.1 += weight * step.centre_angle.powi(2);
                    sum.2 += weight;
                    let matrix = &mut out[(b * count + s) * block..][..levels * levels];
                    step.add_source_weights(matrix, levels, k, transmittance, one_minus_e, c);
                    transmittance *= 1.0 - one_minus_e;
                }
                if ends_on_ground {
                    out[((here - 1) * count + s) * block + levels * levels + k] = transmittance;
                }
                for (b, &(angle_sum, square_sum, weight_sum)) in sums.iter().enumerate() {
                    angles[(b * count + s) * levels + k] = if weight_sum > 0.0 {
                        let mean = angle_sum / weight_sum;
                        (
                            mean,
                            (square_sum / weight_sum - mean * mean).max(0.0).sqrt(),
                        )
                    } else {
                        (0.0, 0.0)
                    };
                }
            }
        }
        (out, angles)
    }
}

/// The rows where each column of the transport matrix `matrix` (levels x
/// levels, [j * levels + k]) is non-zero, half-open, into `rows` ([j]).
pub(crate) fn nonzero_rows(matrix: &[f64], levels: usize, rows: &mut [(usize, usize)]) {
    for (column, row) in matrix.chunks_exact(levels).zip(rows) {
        let first = column.iter().position(|w| *w != 0.0).unwrap_or(0);
        let last = column.iter().rposition(|w| *w != 0.0).map_or(0, |k| k + 1);
        *row = (first, last.max(first));
    }
}

/// (1 - e^{-x}, c) with c = (1 - e^{-x} - x e^{-x}) / x: the weights of a
/// source linear in optical depth across a step of optical thickness x
/// (near end: 1 - e^{-x} - c, far end: c), by series for thin steps.
pub(crate) fn linear_source_weights(x: f64) -> (f64, f64) {
    if x < 1e-4 {
        (x - 0.5 * x * x, 0.5 * x - x * x / 3.0)
    } else {
        let one_minus_e = -(-x).exp_m1();
        (one_minus_e, (one_minus_e - x * (1.0 - one_minus_e)) / x)
    }
}

/// Appends the steps of the ray from level `k` with zenith cosine
/// `cosine`; returns whether it ends on the ground (level 0 from above).
fn trace(radii: &[f64], k: usize, cosine: f64, steps: &mut Vec<PathStep>) -> bool {
    let levels = radii.len();
    let r = radii[k];
    let r_mu = r * cosine.abs();
    // Squared distance term r^2 mu^2 + (r_j^2 - r^2), without cancellation.
    let discriminant = |j: usize| r_mu * r_mu + (radii[j] - r) * (radii[j] + r);
    let thickness = |layer: usize| radii[layer + 1] - radii[layer];
    // Points along the ray: (distance, source (level, weight)), and the
    // layer of the step that ends at each point.
    let mut points: Vec<(f64, (usize, f64), usize)> = vec![(0.0, (k, 0.0), usize::MAX)];
    let mut on_ground = false;
    if cosine > 0.0 {
        for (j, radius) in radii.iter().enumerate().skip(k + 1) {
            let t = (radius - r) * (radius + r) / (discriminant(j).sqrt() + r_mu);
            points.push((t, (j, 0.0), j - 1));
        }
    } else {
        let mut lowest = k;
        let mut tangent_layer = None;
        for j in (0..k).rev() {
            let d = discriminant(j);
            if d < 0.0 {
                tangent_layer = Some(j);
                break;
            }
            let t = (r - radii[j]) * (r + radii[j]) / (r_mu + d.sqrt());
            points.push((t, (j, 0.0), j));
            lowest = j;
            if j == 0 {
                on_ground = true;
                break;
            }
        }
        if k == 0 {
            // Looking down from the ground itself.
            on_ground = true;
        }
        if !on_ground {
            // The lowest point, inside the layer below `lowest` (or in the
            // top level's own layer when k is the top and the ray grazes it).
            let layer = tangent_layer.unwrap_or(lowest.saturating_sub(1));
            let b = (r * r - r_mu * r_mu).max(0.0).sqrt();
            let w = ((b - radii[layer]) / thickness(layer)).clamp(0.0, 1.0);
            points.push((r_mu, (layer, w), layer));
            for j in layer + 1..levels {
                let t = r_mu + discriminant(j).max(0.0).sqrt();
                points.push((t, (j, 0.0), j - 1));
            }
        }
    }
    let sine = (1.0 - cosine * cosine).max(0.0).sqrt();
    for pair in points.windows(2) {
        let ((t0, near, _), (t1, far, layer)) = (pair[0], pair[1]);
        let middle = 0.5 * (t0 + t1);
        steps.push(PathStep {
            layer,
            stretch: (t1 - t0) / thickness(layer),
            near,
            far,
            centre_angle: (middle * sine).atan2(r + middle * cosine),
        });
    }
    on_ground
}

#[cfg(test)]
mod tests {
    use super::*;

    fn radii(ground: f64) -> Vec<f64> {
        (0..=20).map(|k| ground + 5e3 * k as f64).collect()
    }

    #[test]
    fn a_huge_planet_gives_the_slab_paths() {
        let r = radii(6.36e12);
        for cosine in [0.3, -0.3, 0.02, -0.02] {
            let mut steps = Vec::new();
            let ground = trace(&r, 10, cosine, &mut steps);
            assert_eq!(ground, cosine < 0.0);
            assert_eq!(steps.len(), 10);
            for step in &steps {
                assert!(
                    (step.stretch * cosine.abs() - 1.0).abs() < 1e-4,
                    "{cosine}: {}",
                    step.stretch
                );
            }
        }
    }

    #[test]
    fn a_grazing_ray_passes_above_the_ground_and_climbs_out() {
        let r = radii(6.36e6);
        // From 50 km at 2 degrees below the horizon: the lowest point is
        // 50e3 + 6.41e6 (cos 2 deg - 1) ~ 46.1 km, in layer 9.
        let mut steps = Vec::new();
        let ground = trace(&r, 10, -(2f64.to_radians().sin()), &mut steps);
        assert!(!ground);
        let tangent = steps.iter().find(|s| s.far.1 > 0.0).unwrap();
        assert_eq!(tangent.layer, 9);
        assert!((tangent.far.1 - 0.22).abs() < 0.02, "{}", tangent.far.1);
        // Down through layer 9 to the lowest point, back up through 9..19.
        assert_eq!(steps.len(), 2 + 10);
        assert_eq!(steps.last().unwrap().far, (20, 0.0));
        // The whole path equals the chord through the top sphere.
        let length: f64 = steps.iter().map(|s| s.stretch * 5e3).sum();
        let r0 = r[10];
        let mu = 2f64.to_radians().sin();
        let chord = r0 * mu + ((r0 * mu).powi(2) + (r[20] - r0) * (r[20] + r0)).sqrt();
        assert!((length / chord - 1.0).abs() < 1e-9, "{length} vs {chord}");
    }

    #[test]
    fn matrices_reproduce_a_constant_source() {
        // With the same source S everywhere and no ground, L = S (1 - T).
        let r = radii(6.36e6);
        let cosines = [0.05, -0.05, 0.3, -0.3];
        let paths = StreamPaths::compute(&r, &cosines);
        let depths = vec![0.02; 20];
        let levels = r.len();
        let mut out = vec![0.0; paths.spherical_streams().len() * levels * (levels + 1)];
        let mut rows = vec![(0, 0); paths.spherical_streams().len() * levels];
        let mut angles = vec![(0.0, 0.0); paths.spherical_streams().len() * levels];
        paths.compute_transport_matrices(&depths, &mut out, &mut rows, &mut angles);
        for (s, &a) in paths.spherical_streams().iter().enumerate() {
            let block = &out[s * levels * (levels + 1)..];
            for k in 0..levels {
                let row_sum: f64 = (0..levels).map(|j| block[j * levels + k]).sum();
                let ground = block[levels * levels + k];
                let (first, last, _) = paths.paths[s * levels + k];
                let tau: f64 = paths.steps[first..last]
                    .iter()
                    .map(|st| depths[st.layer] * st.stretch)
                    .sum();
                assert!(
                    (row_sum - (1.0 - (-tau).exp())).abs() < 1e-12,
                    "stream {a} level {k}: {row_sum} vs tau {tau}"
                );
                if cosines[a] < 0.0 && k > 0 {
                    assert!(ground == 0.0 || (ground - (-tau).exp()).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn pieces_split_the_paths_measure_in_equal_shares() {
        let r = radii(6.36e6);
        let cosines = [0.05, -0.05, 0.2, -0.2];
        let paths = StreamPaths::compute(&r, &cosines);
        let depths: Vec<f64> = (0..20).map(|k| 0.05 * (-(k as f64) / 4.0).exp()).collect();
        let levels = r.len();
        let count = paths.spherical_streams().len();
        let block = levels * (levels + 1);
        let mut whole = vec![0.0; count * block];
        let mut rows = vec![(0, 0); count * levels];
        let mut angles = vec![(0.0, 0.0); count * levels];
        paths.compute_transport_matrices(&depths, &mut whole, &mut rows, &mut angles);
        // One piece is the whole path.
        let (one, one_angles) = paths.compute_piece_matrices(&depths, 1, 0.0);
        assert_eq!(one, whole);
        assert_eq!(one_angles, angles);
        let pieces = 4;
        // Every path in 4 pieces, then one piece per 0.2 degree of spread.
        let step = 0.2f64.to_radians();
        let (mut split_paths, mut fewer) = (0, 0);
        for spread_step in [0.0, step] {
            let (split, split_angles) = paths.compute_piece_matrices(&depths, pieces, spread_step);
            for s in 0..count {
                for k in 0..levels {
                    // The pieces' weights add up to the whole's.
                    for j in 0..=levels {
                        let sum: f64 = (0..pieces)
                            .map(|b| split[(b * count + s) * block + j * levels + k])
                            .sum();
                        let w = whole[s * block + j * levels + k];
                        assert!(
                            (sum - w).abs() <= 1e-12 * w.abs().max(1e-300),
                            "{s} {k} {j}"
                        );
                    }
                    let (first, last, _) = paths.paths[s * levels + k];
                    let mut measures = Vec::new();
                    paths.step_measures(&paths.steps[first..last], &depths, &mut measures);
                    let weight: f64 = measures.iter().map(|(w, _)| w).sum();
                    if weight == 0.0 {
                        continue;
                    }
                    // The path's share of pieces: all of them, or one per
                    // step of its angle's spread.
                    let (mean, spread) = angles[s * levels + k];
                    let expected = if spread_step > 0.0 {
                        ((spread / spread_step).ceil() as usize).clamp(1, pieces)
                    } else {
                        pieces
                    };
                    if spread_step > 0.0 {
                        fewer += usize::from(expected < pieces);
                        split_paths += usize::from(expected > 1);
                    }
                    // Each piece's light, and its measure: the pieces in
                    // order along the path, each step in the piece its
                    // middle falls in.
                    let shares: Vec<f64> = (0..pieces)
                        .map(|b| {
                            (0..levels)
                                .map(|j| split[(b * count + s) * block + j * levels + k])
                                .sum()
                        })
                        .collect();
                    let total: f64 = measures.iter().map(|(_, m)| m).sum();
                    let largest = measures.iter().fold(0.0f64, |l, (_, m)| l.max(*m));
                    let (mut next_step, mut piece_measures) = (0usize, vec![0.0; pieces]);
                    for (b, &share) in shares.iter().enumerate() {
                        // Steps are taken whole: a piece's light is the
                        // weight of the next steps of the path.
                        let mut light = 0.0;
                        while next_step < measures.len() && light < share * (1.0 - 1e-9) {
                            light += measures[next_step].0;
                            piece_measures[b] += measures[next_step].1;
                            next_step += 1;
                        }
                        assert!((light - share).abs() <= 1e-9 * weight, "{s} {k} {b}");
                    }
                    for (b, m) in piece_measures.iter().enumerate() {
                        let target = if b < expected {
                            total / expected as f64
                        } else {
                            0.0
                        };
                        assert!(
                            (m - target).abs() <= largest * (1.0 + 1e-9),
                            "{s} {k} {b}: {piece_measures:?} of {total}, {expected} pieces"
                        );
                    }
                    // Farther pieces at larger angles, and their mean is
                    // the whole path's.
                    let piece_mean: f64 = (0..pieces)
                        .map(|b| shares[b] * split_angles[(b * count + s) * levels + k].0)
                        .sum::<f64>()
                        / shares.iter().sum::<f64>();
                    assert!(
                        (piece_mean / mean - 1.0).abs() < 1e-9,
                        "{piece_mean} vs {mean}"
                    );
                    for b in 1..pieces {
                        if shares[b] > 0.0 && shares[b - 1] > 0.0 {
                            let (this, before) = (
                                split_angles[(b * count + s) * levels + k].0,
                                split_angles[((b - 1) * count + s) * levels + k].0,
                            );
                            assert!(this > before, "{s} {k}: {this} <= {before}");
                        }
                    }
                }
            }
        }
        // Paths cut in fewer pieces than the most, and paths cut.
        eprintln!("{split_paths} paths cut, {fewer} in fewer than {pieces} pieces");
        assert!(split_paths > 0 && fewer > 0, "{split_paths} {fewer}");
    }
}
