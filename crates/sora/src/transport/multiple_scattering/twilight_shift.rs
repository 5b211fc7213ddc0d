//! The twilight shift: the near-horizontal streams' light moved toward the
//! sun angle of the columns where it was gathered.
//!
//! A near-horizontal path gathers its light hundreds of kilometres away,
//! where the sun stands higher (toward the sun's azimuth) or lower (away
//! from it) by the angle gamma that the path subtends at the planet's
//! centre: a low sun's sunward horizon is lit by brighter air than the
//! column's own. The paths' mean angles gamma (weighted by what a uniform
//! source along them would contribute) and their spreads are
//! [`super::spherical_paths`]'.
//!
//! - **First-order shift** ([`ColumnSystem::shift_toward_sources`]), sun
//!   nodes below `FIRST_ORDER_SUN_ZENITH_DEG` (`regimes.rs`): once the
//!   field is solved at every sun zenith angle, each spherical stream's
//!   radiance is shifted to first order, L(theta_s - gamma cos phi) = L -
//!   gamma cos(phi) dL/dtheta_s, with dL/dtheta_s the difference between
//!   neighbouring sun nodes; cos(phi) couples each azimuthal harmonic to
//!   its neighbours. Measured against the path tracer for a sun 5 degrees
//!   high, it halves the error of the sunward horizon (-2.3 % to -1.3 % of
//!   the total at 380 nm).
//! - **Every-order shift** ([`ColumnSystem::solve_shifted_orders`]), sun
//!   nodes from `FIRST_ORDER_SUN_ZENITH_DEG` on, where the first order is
//!   spherical and the first-order shift is not enough: the columns of all
//!   those nodes are solved together, order by order, and every order >= 2
//!   of the spherical streams is shifted exactly, per azimuth, with the
//!   mean angle and its spread, before it is scattered into the next
//!   ([`ColumnSystem::shift_order_toward_sources`]).
//! - **The every-order shift in pieces**
//!   ([`ColumnSystem::with_shift_pieces`], the settings'
//!   `twilight_shift_pieces`, default 1 = whole paths): each path cut
//!   into consecutive pieces, each piece's light carried by its part of
//!   the transport matrix and shifted by its own mean angle and spread,
//!   the pieces summed over the azimuths (`ColumnSystem::shift_sums`).
//!   A path takes one piece per `SHIFT_PIECE_SPREAD_DEG` of its angle's
//!   spread, at most the settings' number; the pieces gather equal shares
//!   of w^(1/3) d^(2/3) (`StreamPaths::compute_piece_matrices`). Whole
//!   paths move the light gathered near the point (in the planet's shadow
//!   after sunset) to the path's mean angle, where the column's air at
//!   that altitude may already be sunlit: measured for earth-hazy, an eye
//!   3 km up, a 1 km segment 10 degrees down toward the sun, suns from
//!   -1 to -4 degrees, 2-3 % too bright at 560 and 680 nm; at most 3
//!   pieces take 86-91 % of that away (32 pieces of every path the rest),
//!   at 1.19 times the CPU of an almucantar (`docs/aerial_perspective.md`).
//!
//! The plane-parallel solver ([`super::successive_orders`]) carries the
//! spherical streams along their paths within one column; this file adds
//! what the columns of neighbouring sun nodes do to one another.

use std::f64::consts::PI;

use super::successive_orders::{CONVERGENCE_TOLERANCE, ColumnSystem, StoppingRule};

/// With the shift in pieces (`MultipleScatteringSettings::twilight_shift_pieces`
/// above 1): a path takes one piece per this many degrees of its angle's
/// spread (at most that many; [`ColumnSystem::with_shift_pieces`]). With
/// at most 3 pieces, measured for earth-hazy (eye 3 km up, a 1 km segment
/// 10 degrees down toward the sun, suns -1 to -4 degrees, 560 and 680 nm),
/// it moves the segment by 86-91 % of what 32 pieces of every path move
/// it, at 1.19 times the CPU of the whole-path shift for an almucantar
/// (docs/aerial_perspective.md).
pub(crate) const SHIFT_PIECE_SPREAD_DEG: f64 = 0.2;
use crate::transport::vector_exp::exp_neg;

/// The interpolation brackets of a twilight shift ([`ColumnSystem::shift_plan`]).
pub(crate) struct ShiftPlan {
    nodes: usize,
    /// [(((s * levels + k) * nodes + node) * streams + q) * 2 + i]: the
    /// node below and the fraction of its segment.
    brackets: Vec<(u32, f64)>,
    /// [s * levels + k]: whether the path gathers light away from its
    /// start (a mean angle above zero), so that it is shifted.
    shifted: Vec<bool>,
    /// The harmonics that are not zero.
    active: Vec<usize>,
    /// cos(m phi_q) of the active harmonics at the midpoint azimuths,
    /// [q * active + i], and the same by harmonics, [i * streams + q].
    cosines: Vec<f64>,
    synthesis: Vec<f64>,
}

impl ColumnSystem<'_> {
    /// Shifts the solutions `fields` (one per sun zenith angle of
    /// `sun_zenith_rad`, each harmonics x levels x streams) of the
    /// spherical streams toward where their light comes from, to first
    /// order (see the module docs).
    pub(crate) fn shift_toward_sources(&self, sun_zenith_rad: &[f64], fields: &mut [&mut [f64]]) {
        let Some(paths) = self.paths else {
            return;
        };
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let nodes = sun_zenith_rad.len();
        if nodes < 2 {
            return;
        }
        let mut derivative = vec![0.0; total];
        let mut shifted = vec![0.0; nodes * total];
        for (s, &a) in paths.spherical_streams().iter().enumerate() {
            for k in 0..levels {
                let angle = self.spherical_mean_angles[s * levels + k].0;
                if angle == 0.0 {
                    continue;
                }
                for node in 0..nodes {
                    let (lo, hi) = (node.saturating_sub(1), (node + 1).min(nodes - 1));
                    let span = sun_zenith_rad[hi] - sun_zenith_rad[lo];
                    for (m, d) in derivative.iter_mut().enumerate() {
                        let at = m * size + k * total + a;
                        *d = (fields[hi][at] - fields[lo][at]) / span;
                    }
                    // L(theta - angle cos phi) ~ L - angle cos(phi) dL/dtheta,
                    // and cos(phi) couples harmonic m to m - 1 and m + 1.
                    for m in 0..total {
                        let neighbours = match m {
                            0 => 0.5 * derivative.get(1).copied().unwrap_or(0.0),
                            1 => derivative[0] + 0.5 * derivative.get(2).copied().unwrap_or(0.0),
                            _ => {
                                0.5 * (derivative[m - 1]
                                    + derivative.get(m + 1).copied().unwrap_or(0.0))
                            }
                        };
                        shifted[node * total + m] =
                            fields[node][m * size + k * total + a] - angle * neighbours;
                    }
                }
                for node in 0..nodes {
                    for m in 0..total {
                        fields[node][m * size + k * total + a] = shifted[node * total + m];
                    }
                }
            }
        }
    }

    /// Where [`ColumnSystem::shift_order_toward_sources`] reads each
    /// shifted value on the sun axis `sun_zenith_rad`: per spherical
    /// stream, level, node, azimuth and each of the two angles, the node
    /// below and the fraction of its segment, the same at every order.
    pub(crate) fn shift_plan(&self, sun_zenith_rad: &[f64]) -> ShiftPlan {
        self.shift_plan_at(sun_zenith_rad, &self.spherical_mean_angles)
    }

    /// [`ColumnSystem::shift_plan`] for the mean angles and spreads
    /// `mean_angles` ([s * levels + k], rad): those of the whole paths or
    /// of one of their pieces.
    fn shift_plan_at(&self, sun_zenith_rad: &[f64], mean_angles: &[(f64, f64)]) -> ShiftPlan {
        let nodes = sun_zenith_rad.len();
        let azimuths = self.streams.count();
        let mut brackets = Vec::new();
        if let (Some(paths), true) = (self.paths, nodes >= 2) {
            let levels = self.grid.levels();
            brackets.reserve(paths.spherical_streams().len() * levels * nodes * azimuths * 2);
            for s in 0..paths.spherical_streams().len() {
                for k in 0..levels {
                    // Two angles with the mean and spread of the path's: the
                    // source changes exponentially along the path, and its
                    // mean is brighter than its value at the mean angle.
                    let (mean, spread) = mean_angles[s * levels + k];
                    if mean == 0.0 {
                        // Not shifted.
                        let len = brackets.len();
                        brackets.resize(len + nodes * azimuths * 2, (0, 0.0));
                        continue;
                    }
                    let angles = [mean + spread, (mean - spread).max(0.0)];
                    for &sun in sun_zenith_rad {
                        for q in 0..azimuths {
                            let phi_cosine = (PI * (q as f64 + 0.5) / azimuths as f64).cos();
                            for angle in angles {
                                let theta = sun - angle * phi_cosine;
                                let upper = sun_zenith_rad.partition_point(|t| *t <= theta);
                                let lo = upper.clamp(1, nodes - 1) - 1;
                                let t = ((theta - sun_zenith_rad[lo])
                                    / (sun_zenith_rad[lo + 1] - sun_zenith_rad[lo]))
                                    .clamp(-0.5, 1.5);
                                brackets.push((lo as u32, t));
                            }
                        }
                    }
                }
            }
        }
        let active: Vec<usize> = (0..azimuths)
            .filter(|m| self.active_harmonics[*m])
            .collect();
        let h = active.len();
        let cosines: Vec<f64> = (0..azimuths)
            .flat_map(|q| {
                let phi = PI * (q as f64 + 0.5) / azimuths as f64;
                active.iter().map(move |&m| (m as f64 * phi).cos())
            })
            .collect();
        let synthesis: Vec<f64> = (0..h)
            .flat_map(|i| (0..azimuths).map(move |q| (i, q)))
            .map(|(i, q)| cosines[q * h + i])
            .collect();
        ShiftPlan {
            nodes,
            brackets,
            shifted: mean_angles.iter().map(|(mean, _)| *mean != 0.0).collect(),
            active,
            cosines,
            synthesis,
        }
    }

    /// After sunset: shifts one order of scattering of each spherical
    /// stream (`orders`, one per sun node of `sun_zenith_rad`) to the sun
    /// zenith angle where its light was gathered, in each direction
    /// separately, by interpolation across the sun nodes linear in the
    /// logarithm:
    ///
    /// ```text
    /// H'(theta_s, phi) = H(theta_s - gamma cos phi, phi),
    /// ```
    ///
    /// averaged over two angles gamma = gamma_mean +- gamma_spread, the
    /// mean and spread at the planet's centre of where the path gathers
    /// its light (as [`ColumnSystem::shift_toward_sources`], which takes
    /// the first order of the Taylor series at the mean: in twilight H
    /// changes by orders of magnitude over a few degrees, a linear shift
    /// runs negative, and the mean of an exponential is brighter than its
    /// value at the mean angle).
    /// H is synthesised at `streams` midpoint azimuths on 0..180
    /// degrees from its harmonics and transformed back (exact for an
    /// unshifted field). An angle beyond the axis reads its end node's
    /// segment, extrapolated by at most half a segment; where H is not
    /// positive at both nodes, H is kept.
    pub(crate) fn shift_order_toward_sources(&self, plan: &ShiftPlan, orders: &mut [&mut [f64]]) {
        if self.paths.is_none() || plan.nodes < 2 {
            return;
        }
        let total = self.streams.count();
        let carried = vec![true; orders.len() * total];
        let pieces: Vec<&[f64]> = orders.iter().map(|o| &o[..]).collect();
        let mut shifted = vec![0.0; self.shift_sums_len(orders.len())];
        self.shift_sums(
            std::slice::from_ref(plan),
            &[pieces],
            &carried,
            &mut shifted,
        );
        self.put_spherical(&shifted, &carried, orders);
    }

    /// The shift in pieces: each piece's light of one order
    /// (`piece_orders`, per piece and node) shifted by its own plan, and
    /// their sum put in place of the spherical streams' light in `orders`
    /// (per node); the harmonics not `carried` (per node and harmonic)
    /// are zero.
    fn shift_pieces_toward_sources(
        &self,
        plans: &[ShiftPlan],
        piece_orders: &[Vec<Vec<f64>>],
        carried: &[bool],
        orders: &mut [Vec<f64>],
    ) {
        let pieces: Vec<Vec<&[f64]>> = piece_orders
            .iter()
            .map(|nodes| nodes.iter().map(|o| &o[..]).collect())
            .collect();
        let mut shifted = vec![0.0; self.shift_sums_len(orders.len())];
        self.shift_sums(plans, &pieces, carried, &mut shifted);
        let mut views: Vec<&mut [f64]> = orders.iter_mut().map(|o| &mut o[..]).collect();
        self.put_spherical(&shifted, carried, &mut views);
    }

    /// The length of [`ColumnSystem::shift_sums`]'s `out` for `nodes` sun
    /// nodes.
    fn shift_sums_len(&self, nodes: usize) -> usize {
        let count = self.paths.map_or(0, |p| p.spherical_streams().len());
        nodes * self.grid.levels() * count * self.streams.count()
    }

    /// Writes the spherical streams' shifted active harmonics `shifted`
    /// (the layout of [`ColumnSystem::shift_sums`]'s `out`) into `orders`
    /// (per node), zero where a harmonic is not `carried` (per node and
    /// harmonic); the other harmonics are left as they are.
    fn put_spherical(&self, shifted: &[f64], carried: &[bool], orders: &mut [&mut [f64]]) {
        let Some(paths) = self.paths else {
            return;
        };
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let count = paths.spherical_streams().len();
        for (node, order) in orders.iter_mut().enumerate() {
            for k in 0..levels {
                for (s, &a) in paths.spherical_streams().iter().enumerate() {
                    let values = &shifted[((node * levels + k) * count + s) * total..][..total];
                    for m in (0..total).filter(|m| self.active_harmonics[*m]) {
                        order[m * size + k * total + a] = if carried[node * total + m] {
                            values[m]
                        } else {
                            0.0
                        };
                    }
                }
            }
        }
    }

    /// The heart of the shift: per node, level and spherical stream, the
    /// harmonics of the sum over `pieces` (per piece and node, the layout
    /// of [`ColumnSystem::solve`]'s radiance) of each piece's light read
    /// at its plan's angles, into `out` ([((node * levels + k) * spherical
    /// streams + s) * streams + m], the harmonics the phase functions lack
    /// zero; a
    /// piece's path that is not shifted adds its light as it is). The
    /// pieces are summed over the azimuths, so the harmonics are taken
    /// once.
    fn shift_sums(
        &self,
        plans: &[ShiftPlan],
        pieces: &[Vec<&[f64]>],
        carried: &[bool],
        out: &mut [f64],
    ) {
        let Some(paths) = self.paths else {
            return;
        };
        let nodes = plans[0].nodes;
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let count = paths.spherical_streams().len();
        let azimuths = total;
        let (active, cosines, synthesis) =
            (&plans[0].active, &plans[0].cosines, &plans[0].synthesis);
        let h = active.len();
        let mut harmonics = vec![0.0; nodes * h];
        let mut higher = vec![0.0; nodes * azimuths];
        let mut logs = vec![0.0; nodes * azimuths];
        let (mut exponents, mut powers) = (vec![0.0; 2 * azimuths], vec![0.0; 2 * azimuths]);
        let mut summed = vec![0.0; nodes * azimuths];
        let mut kept = vec![0.0; nodes * h];
        let mut transformed = vec![0.0; h];
        out.fill(0.0);
        // Level by level: a level's streams share the nodes' cache lines.
        for k in 0..levels {
            for (s, &a) in paths.spherical_streams().iter().enumerate() {
                summed.fill(0.0);
                kept.fill(0.0);
                let (mut any_shifted, mut any_kept) = (false, false);
                for (plan, orders) in plans.iter().zip(pieces) {
                    if !plan.shifted[s * levels + k] {
                        any_kept = true;
                        for (node, order) in orders.iter().enumerate() {
                            for (i, &m) in active.iter().enumerate() {
                                if carried[node * total + m] {
                                    kept[node * h + i] += order[m * size + k * total + a];
                                }
                            }
                        }
                        continue;
                    }
                    any_shifted = true;
                    let brackets = &plan.brackets[(s * levels + k) * nodes * azimuths * 2..]
                        [..nodes * azimuths * 2];
                    for (node, order) in orders.iter().enumerate() {
                        for (i, &m) in active.iter().enumerate() {
                            harmonics[node * h + i] = order[m * size + k * total + a];
                        }
                    }
                    // The azimuths' values, harmonic by harmonic (the loops
                    // over azimuths vectorise).
                    for (row, values) in higher
                        .chunks_exact_mut(azimuths)
                        .zip(harmonics.chunks_exact(h))
                    {
                        row.fill(0.0);
                        for (v, c) in values.iter().zip(synthesis.chunks_exact(azimuths)) {
                            for (r, c) in row.iter_mut().zip(c) {
                                *r += v * c;
                            }
                        }
                    }
                    for (l, v) in logs.iter_mut().zip(&higher) {
                        *l = if *v > 0.0 { v.ln() } else { f64::NEG_INFINITY };
                    }
                    for node in 0..nodes {
                        let brackets = &brackets[node * azimuths * 2..(node + 1) * azimuths * 2];
                        for (j, (&(lo, t), y)) in brackets.iter().zip(&mut exponents).enumerate() {
                            let (lo, q) = (lo as usize, j / 2);
                            // Not finite where either node's value is not
                            // positive.
                            *y = (1.0 - t) * logs[lo * azimuths + q]
                                + t * logs[(lo + 1) * azimuths + q];
                        }
                        // e^y by the vectorisable e^-|y|, then inverted where
                        // y is positive (only in a rare extrapolation: a
                        // predictable branch, no division in the vector loop).
                        for (e, y) in powers.iter_mut().zip(&exponents) {
                            *e = exp_neg(y.abs());
                        }
                        for (e, y) in powers.iter_mut().zip(&exponents) {
                            if *y > 0.0 {
                                *e = 1.0 / *e;
                            }
                        }
                        let row = &mut summed[node * azimuths..(node + 1) * azimuths];
                        for (q, out) in row.iter_mut().enumerate() {
                            let kept = higher[node * azimuths + q];
                            *out += (2 * q..2 * q + 2)
                                .map(|j| {
                                    if exponents[j].is_finite() {
                                        powers[j]
                                    } else {
                                        kept
                                    }
                                })
                                .sum::<f64>()
                                * 0.5;
                        }
                    }
                }
                for node in 0..nodes {
                    let at = ((node * levels + k) * count + s) * total;
                    let out = &mut out[at..at + total];
                    if any_shifted {
                        transformed.fill(0.0);
                        let row = &summed[node * azimuths..(node + 1) * azimuths];
                        for (v, c) in row.iter().zip(cosines.chunks_exact(h)) {
                            for (t, c) in transformed.iter_mut().zip(c) {
                                *t += v * c;
                            }
                        }
                        for (&m, t) in active.iter().zip(&transformed) {
                            let factor = if m == 0 { 1.0 } else { 2.0 } / azimuths as f64;
                            out[m] = factor * t;
                        }
                    }
                    if any_kept {
                        for (&m, v) in active.iter().zip(&kept[node * h..(node + 1) * h]) {
                            out[m] += v;
                        }
                    }
                }
            }
        }
    }

    /// After sunset: solves the columns of every sun node of
    /// `sun_zenith_rad` together, order by order, shifting each order of
    /// the spherical streams toward the columns where its light was
    /// gathered ([`ColumnSystem::shift_order_toward_sources`])
    /// before it is scattered into the next. `first_orders` are the
    /// spherical first orders (the layout of [`ColumnSystem::solve`]'s
    /// `radiance`), `ground_direct` the radiance of the directly sunlit
    /// ground (W m^-2 sr^-1 nm^-1) under each node's sun; the solutions go
    /// to `fields`, and each node's diffuse downward irradiance at the
    /// ground is returned.
    ///
    /// Why order by order: the field of a column is horizontally uniform,
    /// the twilight sky is not. Light that has travelled a stream's path
    /// was scattered where the sun stood higher (toward it) or lower, and
    /// the mean of that exponential is brighter than the column's own
    /// value. Shifting only the finished field corrects the last leg of
    /// every path and leaves each earlier leg in its own column, so the
    /// n-th order misses the shift n - 2 times: measured on mars-dust with
    /// Henyey-Greenstein dust, sun -6 degrees, 5 degrees up 90 degrees
    /// from the sun, the orders up to 2, 3 and 4 and all of them were
    /// -1.0, -3.7, -7.3 and -13.5 % from the path tracer (+-1.6-1.8 %) when
    /// only the field was shifted, -4.7 % in all with every order shifted
    /// (`docs/twilight_survey.md`).
    pub(crate) fn solve_shifted_orders(
        &self,
        sun_zenith_rad: &[f64],
        ground_direct: &[f64],
        first_orders: &[&[f64]],
        fields: &mut [&mut [f64]],
    ) -> Vec<f64> {
        let levels = self.grid.levels();
        let total = self.streams.count();
        let size = levels * total;
        let nodes = sun_zenith_rad.len();
        let mut current: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        let mut next: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        let (mut source, mut columns) = (vec![0.0; size], vec![0.0; 2 * levels]);
        // The first order: the spherical one, and the sunlit ground seen
        // through the column.
        for node in 0..nodes {
            fields[node].copy_from_slice(first_orders[node]);
            if ground_direct[node] > 0.0 {
                source.fill(0.0);
                self.transport(
                    &source,
                    ground_direct[node],
                    &mut next[node][..size],
                    &mut columns,
                );
                for (f, g) in fields[node][..size].iter_mut().zip(&next[node][..size]) {
                    *f += g;
                }
            }
            current[node].copy_from_slice(fields[node]);
        }
        // The whole paths' plan, or with the shift in pieces each piece's
        // plan and per piece and node the spherical streams' light of the
        // order from that piece.
        let (plans, mut piece_orders) = match &self.shift_pieces {
            Some(pieces) => {
                let per_piece = pieces.mean_angles.len() / pieces.count;
                let plans: Vec<ShiftPlan> = pieces
                    .mean_angles
                    .chunks_exact(per_piece)
                    .map(|angles| self.shift_plan_at(sun_zenith_rad, angles))
                    .collect();
                (
                    plans,
                    vec![vec![vec![0.0; total * size]; nodes]; pieces.count],
                )
            }
            None => (vec![self.shift_plan(sun_zenith_rad)], Vec::new()),
        };
        // Each node stops by the rule of `solve` on its whole field; a
        // harmonic is no longer carried once its order is negligible there
        // (the high harmonics within a few orders: the light of the higher
        // orders turns isotropic). Every node stays on the axis while one
        // goes on: the shift reads its neighbours' orders.
        let mut rules: Vec<StoppingRule> = (0..nodes).map(|_| StoppingRule::new()).collect();
        let mut done = vec![false; nodes];
        let mut carried: Vec<bool> = (0..nodes * total)
            .map(|i| self.active_harmonics[i % total])
            .collect();
        let (mut previous, mut increment) = (vec![0.0; total * size], vec![0.0; total * size]);
        for _order in 2..=self.sweeps {
            // Harmonic by harmonic, so that its scattering matrices stay in
            // the cache across the nodes.
            for m in 0..total {
                for (node, (l, out)) in current.iter().zip(next.iter_mut()).enumerate() {
                    let out = &mut out[m * size..(m + 1) * size];
                    if !carried[node * total + m] {
                        out.fill(0.0);
                        for orders in piece_orders.iter_mut() {
                            orders[node][m * size..(m + 1) * size].fill(0.0);
                        }
                        continue;
                    }
                    source.fill(0.0);
                    self.add_scattering(m, &l[m * size..(m + 1) * size], &mut source);
                    let ground = match m {
                        0 => self.ground_albedo / PI * self.downward_flux(&l[..size]),
                        _ => 0.0,
                    };
                    if piece_orders.is_empty() {
                        self.transport(&source, ground, out, &mut columns);
                    } else {
                        // The spherical streams' light is the pieces' sum.
                        self.transport_slab_paths(&source, ground, out);
                    }
                    for (piece, orders) in piece_orders.iter_mut().enumerate() {
                        let out = &mut orders[node][m * size..(m + 1) * size];
                        self.transport_piece(piece, &source, ground, out, &mut columns);
                    }
                }
            }
            if piece_orders.is_empty() {
                let mut orders: Vec<&mut [f64]> = next.iter_mut().map(|v| &mut v[..]).collect();
                self.shift_order_toward_sources(&plans[0], &mut orders);
            } else {
                self.shift_pieces_toward_sources(&plans, &piece_orders, &carried, &mut next);
            }
            for node in 0..nodes {
                if done[node] {
                    continue;
                }
                previous.copy_from_slice(fields[node]);
                for (f, o) in fields[node].iter_mut().zip(&next[node]) {
                    *f += o;
                }
                let whole: f64 = fields[node].iter().map(|v| v.abs()).sum();
                for m in 1..total {
                    let order = &next[node][m * size..(m + 1) * size];
                    let part: f64 = order.iter().map(|v| v.abs()).sum();
                    if part <= 1e-2 * CONVERGENCE_TOLERANCE * whole {
                        carried[node * total + m] = false;
                    }
                }
                done[node] = rules[node].finish_sweep(fields[node], &previous, &mut increment);
            }
            std::mem::swap(&mut current, &mut next);
            if done.iter().all(|d| *d) {
                break;
            }
        }
        fields.iter().map(|f| self.downward_flux(f)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atmosphere::DensityProfile;
    use crate::transport::multiple_scattering::phase_fourier::TruncatedPhase;
    use crate::transport::multiple_scattering::regimes::FIRST_ORDER_SUN_ZENITH_DEG;
    use crate::transport::multiple_scattering::spherical_paths::StreamPaths;
    use crate::transport::multiple_scattering::successive_orders::{ScaledSpecies, Streams};
    use crate::transport::multiple_scattering::vertical_grid::VerticalGrid;

    /// I_m(x), the modified Bessel function of the first kind, by its
    /// series.
    fn bessel_i(m: usize, x: f64) -> f64 {
        let mut term = (0.5 * x).powi(m as i32) / (1..=m).map(|i| i as f64).product::<f64>();
        let mut sum = 0.0;
        for k in 0..60 {
            sum += term;
            term *= 0.25 * x * x / ((k + 1) as f64 * (k + 1 + m) as f64);
        }
        sum
    }

    /// The tests' column: 20 layers of exponential air, 8 streams per
    /// hemisphere, a phase function of Legendre moments 0.6^l.
    fn column() -> (VerticalGrid, Streams, TruncatedPhase) {
        let air = DensityProfile::Exponential {
            scale_height_m: 8000.0,
        };
        let grid = VerticalGrid::compute(&[&air], &[1.2e-5], 100e3, 20);
        let streams = Streams::new(8);
        let total = streams.count();
        let moments: Vec<f64> = (0..=total).map(|l| 0.6f64.powi(l as i32)).collect();
        let phase = TruncatedPhase::from_moments(&moments, total);
        (grid, streams, phase)
    }

    /// The twilight shift of the orders >= 2 against its definition,
    /// evaluated directly: for orders >= 2 of ln H linear in the sun
    /// zenith angle and uniform in azimuth, H = A_k,a e^(-kappa theta) (the
    /// interpolation is then exact), the shifted field's active harmonics
    /// are those of (1/2) sum over gamma = mean +- spread of
    /// A e^(-kappa (theta - gamma cos phi)) (Bessel functions I_m), the
    /// first order is kept as it was, and the streams that are not
    /// spherical and the harmonics the phase functions lack are untouched.
    #[test]
    fn twilight_shift_matches_its_definition() {
        let (grid, streams, phase) = column();
        let total = streams.count();
        let species = vec![ScaledSpecies {
            extinction_per_m: 1.2e-5,
            scattering_per_m: 1.2e-5,
            phase: &phase,
        }];
        let radii: Vec<f64> = grid.altitudes_m().iter().map(|z| 6.36e6 + z).collect();
        let paths = StreamPaths::compute(&radii, streams.cosines());
        let system = ColumnSystem::new(&streams, &grid, Some(&paths), species, 1.7, 0.0);
        let levels = grid.levels();
        let size = levels * total;
        let nodes = 24;
        let suns: Vec<f64> = (0..nodes)
            .map(|n| (FIRST_ORDER_SUN_ZENITH_DEG + 0.75 * n as f64).to_radians())
            .collect();
        let kappa = 50.0; // e-fold per 1.1 degree, a twilight sky's rate
        let amplitude = |k: usize, a: usize| 1.0 + 0.1 * k as f64 + 0.01 * a as f64;
        // Harmonic 0 only: the order is uniform in azimuth.
        let mut fields: Vec<Vec<f64>> = vec![vec![0.0; total * size]; nodes];
        for n in 0..nodes {
            for k in 0..levels {
                for a in 0..total {
                    fields[n][k * total + a] = amplitude(k, a) * (-kappa * suns[n]).exp();
                }
            }
        }
        let before = fields.clone();
        {
            let mut views: Vec<&mut [f64]> = fields.iter_mut().map(|f| f.as_mut_slice()).collect();
            system.shift_order_toward_sources(&system.shift_plan(&suns), &mut views);
        }
        let spherical = paths.spherical_streams();
        let (mut worst, mut checked) = (0.0f64, 0);
        // Nodes whose shifted angles stay on the axis.
        for n in 6..nodes - 6 {
            for k in 0..levels {
                for a in 0..total {
                    let at = |m: usize| m * size + k * total + a;
                    let Some(s) = spherical.iter().position(|b| *b == a) else {
                        for m in 0..total {
                            assert_eq!(fields[n][at(m)], before[n][at(m)]);
                        }
                        continue;
                    };
                    let (mean, spread) = system.spherical_mean_angles[s * levels + k];
                    if mean + spread > 4f64.to_radians() {
                        continue; // beyond the axis's 6 nodes either side
                    }
                    checked += 1;
                    // The harmonics of e^(x cos phi) are I_0(x) and 2 I_m(x).
                    let unshifted = amplitude(k, a) * (-kappa * suns[n]).exp();
                    for m in 0..total {
                        let got = fields[n][at(m)];
                        if !system.active_harmonics[m] {
                            assert_eq!(got, before[n][at(m)]);
                            continue;
                        }
                        let expected: f64 = [mean + spread, (mean - spread).max(0.0)]
                            .iter()
                            .map(|gamma| {
                                let c = if m == 0 { 0.5 } else { 1.0 };
                                c * unshifted * bessel_i(m, kappa * gamma)
                            })
                            .sum();
                        let error = (got - expected).abs() / unshifted;
                        worst = worst.max(error);
                    }
                }
            }
        }
        eprintln!("{checked} (node, level, stream) checked, worst {worst:e}");
        assert!(checked > 100, "{checked}");
        // Measured 6e-14.
        assert!(worst < 1e-9, "{worst}");
    }

    /// The shift in pieces against the one-piece shift where both are the
    /// identity: with the same first order and sunlit ground at every sun
    /// node nothing changes across the sun axis, so shifting moves no
    /// light and the pieces' transports must add up to the whole path's,
    /// order by order, every harmonic.
    #[test]
    fn pieces_add_up_to_the_whole_path_where_the_shift_moves_nothing() {
        let (grid, streams, phase) = column();
        let total = streams.count();
        let species = || {
            vec![ScaledSpecies {
                extinction_per_m: 1.2e-5,
                scattering_per_m: 1.1e-5,
                phase: &phase,
            }]
        };
        let radii: Vec<f64> = grid.altitudes_m().iter().map(|z| 6.36e6 + z).collect();
        let paths = StreamPaths::compute(&radii, streams.cosines());
        let levels = grid.levels();
        let size = levels * total;
        let nodes = 6;
        let suns: Vec<f64> = (0..nodes)
            .map(|n| (FIRST_ORDER_SUN_ZENITH_DEG + 0.75 * n as f64).to_radians())
            .collect();
        // A first order with harmonics 0 and 1, the same at every node.
        let mut first = vec![0.0; total * size];
        for k in 0..levels {
            for a in 0..total {
                first[k * total + a] = 1.0 + 0.1 * k as f64 + 0.02 * a as f64;
                first[size + k * total + a] = 0.3 + 0.01 * a as f64;
            }
        }
        let firsts: Vec<&[f64]> = (0..nodes).map(|_| first.as_slice()).collect();
        let ground = vec![0.05; nodes];
        let solve = |pieces: usize| {
            let system = ColumnSystem::new(&streams, &grid, Some(&paths), species(), 1.7, 0.2)
                .with_sweeps(6)
                .with_shift_pieces((pieces, 0.0));
            let mut fields = vec![vec![0.0; total * size]; nodes];
            let mut views: Vec<&mut [f64]> = fields.iter_mut().map(|f| f.as_mut_slice()).collect();
            let down = system.solve_shifted_orders(&suns, &ground, &firsts, &mut views);
            (fields, down)
        };
        let (whole, whole_down) = solve(1);
        let (pieced, pieced_down) = solve(4);
        // Against the field's largest value: the small harmonics are
        // differences of the azimuths' values.
        let largest = whole.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for (a, b) in whole.iter().flatten().zip(pieced.iter().flatten()) {
            worst = worst.max((a - b).abs() / largest);
        }
        for (a, b) in whole_down.iter().zip(&pieced_down) {
            worst = worst.max((a / b - 1.0).abs());
        }
        // Rounding only (the logarithm and the vectorised exponential of
        // the shift, 1e-11 relative).
        eprintln!("worst {worst:e} of the largest value {largest:e}");
        assert!(worst < 1e-10, "{worst}");
        // And the pieces do carry light (the test is not of zeros).
        assert!(whole[0].iter().map(|v| v.abs()).sum::<f64>() > 1.0);
    }
}
