//! The sun's light that reaches a point after scatterings in the phase
//! functions' forward peaks, with the last of them at its real angle in
//! the spherical shell: what the forward-peak term (`forward_peak.rs`)
//! takes as delta-M's T*_sun - T_sun. A fraction of the sun's irradiance
//! (1).
//!
//! # Why
//! Delta-M takes each peak as exactly forward: the light scattered k >= 1
//! times in the peaks reaches a point x along the sun's line through x,
//!
//! ```text
//! S(x) = T*_sun(x) - T_sun(x) = T_sun(x) (e^(X_sun(x)) - 1),
//! ```
//!
//! X_sun the peaks' optical depth of that line. Near and below the
//! horizon that line is the worst of all a point has: it grazes the
//! ground, while light scattered a few degrees (the width of an aerosol's
//! diffraction peak) comes down to x from higher, far less attenuated air.
//! With the sun on the horizon at the ground, `mars-dust` at 440 nm:
//! B / S = 2.5; with the sun 4 and 6 degrees up, 0.97 and 0.96; 12
//! degrees up, 0.99 (the lines tilted down then pass through denser air).
//! Against the path tracer (400 000 paths), `mars-dust` 1 degree above a
//! sun on the horizon and within 5 degrees of it was -4.3 to -7.5 % (7
//! of 9 values outside the issue's 3 % + 3 standard errors), with this
//! -1.0 to -3.4 %; 2 degrees below the horizon -4.5 to -9.0 %, now -2.6
//! to -6.2 % (+-1.0 to 1.6 %; with 1 600 000 paths -0.6 to -3.6 %,
//! +-0.35 to 0.8 %; docs/twilight_survey.md, its last section).
//!
//! # The model
//! The last peak scattering before x is taken at its angle, the earlier
//! ones exactly forward (the scaled beam T*_sun of the point where the
//! last one happens):
//!
//! ```text
//! B(x) = integral P(delta) M(x, delta) d delta,
//! M(x, delta) = integral_0^S [sum_j f_j beta_sca,j rho_j](y) T*_sun(y) T(x, y) dt,
//! y = x + t d(delta),
//! ```
//!
//! d(delta) the sun's direction turned by delta in the vertical plane
//! through the sun (up for delta > 0), T(x, y) the exact transmittance
//! (no further peak scattering after the last), T*_sun(y) zero in the
//! planet's shadow, P the peaks' mixture r / f = (p - (1 - f) p*) / f
//! (`forward_peak.rs`), weighted by f_j beta_sca,j times each species'
//! vertical column, projected on that plane (a turn by a small angle
//! alpha about any axis moves the elevation by the axis' share of it:
//! P(delta) = integral r(sqrt(delta^2 + eta^2)) d eta, the peak's
//! negative residues clipped, over +-144 / N degrees for N terms). The
//! azimuthal part of the turn changes the point's altitude only at
//! second order and is left out. With P a delta function B = S exactly (tested): the
//! exactly forward beam is this model's limit.
//!
//! The forward-peak term then takes T_sun + B for the scaled beam
//! T*_sun: its first line ([`crate::transport::multiple_scattering`], the
//! view march) becomes T*(eye, x) B(x) + T_sun(x) (T*(eye, x) - T(eye, x))
//! (which is T* T*_sun - T T_sun when B = S), also where x itself is in
//! the shadow and B is not zero; its peak-only light (k >= 2, G) is
//! scaled by (T_sun + B) / T*_sun where x is lit. The field's own first
//! order (`spherical_first_order.rs`) keeps T*_sun: with B there it
//! moved `mars-dust`'s views near a sun on the horizon by less than
//! 0.1 %, others near a low sun by up to 0.4 % (measured, not kept): the
//! first order reaching a low point was scattered high up, where B and
//! delta-M's beam hardly differ.
//!
//! Left out, measured: the peak scatterings on the view's side at their
//! angles (light scattered once by p* off the view ray, then into it by
//! a peak): per view node a fan of tilted lines with the sun's columns at
//! each sample, far too costly per pixel. For `mars-dust` 1 degree up
//! 2 degrees from a sun at 0 and -2 degrees it adds another +1.7 to
//! +3.2 % (toward the path tracer); 2 degrees up +0.1 to +1.8 %, 5
//! degrees up -0.1 to -0.6 % (`earth-hazy` at 680 nm up to +2 %).
//!
//! # Numerics
//! Tabulated per wavelength over the field's levels (dense where the
//! extinction is: the haze, the lowest air) and the sun's elevation at
//! the point, every [`ELEVATION_STEP_DEG`] from -20 to +12 degrees but
//! only where the sky's view rays can go
//! ([`PeakBeam::needed_elevations_deg`]), and at each altitude only
//! those its points on the rays can have ([`NeededElevations`]: a point
//! 1 km up is within 1 degree of the eye's sun, 10 km up 3.2 degrees,
//! where the sky reaches 10; the same table where they read it, bit for
//! bit, at 0.9 times the explorer's preview time at suns 2 to -4);
//! ln B read bilinearly. The
//! tilts are bins of [`TILT_STEP_DEG`] over +-[`TILT_REACH_DEG`] / N
//! degrees (9 for the default N = 16; see there),
//! each tilted line marched on [`PANELS`] Gauss panels cut at the
//! profiles' corners until x sees through it no more, the sun's columns
//! read from a [`SunColumnTable`]. Against an oracle of the same tilts
//! (fine midpoint steps, exact columns; tested): `mars-dust` within
//! 0.1 %, `earth-hazy` within 2 % where B is 1e-3 of the sun or more.
//! Half-degree tilts and quarter-degree sun steps change the views near
//! a low sun by less than 0.2 %. Toward a higher sun the beam passes
//! linearly back to delta-M's between [`PEAK_BEAM_BLEND_START_DEG`] and the
//! table's top, 12 degrees (where B / S is 0.99); below -20 degrees a
//! point's tilted lines no longer reach lit air (the top's horizon dip
//! is 10-14 degrees) and delta-M's beam, zero there, is kept. Cost: 16
//! to 34 ms per sky of 21 wavelengths on 2 cores. A row does not depend
//! on the eye's sun, so the skies of one atmosphere and eye keep the rows
//! computed so far ([`PeakBeamCache`]): a sky moved to another sun computes
//! only the rows its sun needs and no sun before it did.

use std::ops::ControlFlow;
use std::sync::{Arc, Mutex, PoisonError};

use super::column_optics::{ColumnGeometry, ScaledOptics};
use super::phase_fourier::TruncatedPhase;
use super::regimes::{
    PEAK_BEAM_BLEND_START_DEG, PEAK_BEAM_HIGHEST_ELEVATION_DEG, PEAK_BEAM_LOWEST_ELEVATION_DEG,
};
use crate::atmosphere::{AtmosphereOptics, DensityProfile};
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::transport::optical_column::{PanelMarch, SunColumnRadius, SunColumnTable};
use crate::transport::vector_exp::exp_neg_in_place;

/// The table's lowest node is this high, m: a horizontal line from it
/// clears the ground (from the ground itself it would graze it).
const LOWEST_NODE_M: f64 = 0.1;
/// Step of the table's sun elevations at the point (from
/// [`PEAK_BEAM_LOWEST_ELEVATION_DEG`] to [`PEAK_BEAM_HIGHEST_ELEVATION_DEG`]), degrees.
const ELEVATION_STEP_DEG: f64 = 1.0;
/// The tilts' bins are TILT_STEP_DEG wide, out to +-TILT_REACH_DEG / N
/// degrees for phases truncated to N terms: the projected peak of N = 16
/// terms' truncation has nothing beyond 9 degrees (measured, mars-dust
/// and earth-hazy, 440-680 nm, in half-degree bins), and it is as much
/// narrower as N is larger.
const TILT_STEP_DEG: f64 = 1.0;
const TILT_REACH_DEG: f64 = 144.0;
/// Bins lighter than this for every wavelength are skipped (under 1e-3
/// of the peak together for up to 50 bins).
const LIGHTEST_TILT: f64 = 2e-5;
/// Gauss panels along each tilted line (cut at the profiles' corners too).
const PANELS: usize = 4;
/// The transmittance from a node along a line below which, at every
/// wavelength, the line's march stops (what it would add is below this
/// times the peaks' optical depth ahead, against beams of 1e-3 or more
/// wherever the forward-peak term carries light).
const OPAQUE: f64 = 1e-10;
/// Step of the peak's projection onto the vertical plane, degrees.
const PROJECTION_STEP_DEG: f64 = 0.1;

/// What [`PeakBeam::compute`] needs; per wavelength i and species j at
/// [i * species + j].
pub(crate) struct PeakBeamInputs<'a> {
    pub optics: &'a AtmosphereOptics,
    pub scaled: &'a ScaledOptics,
    /// The columns' geometry; the table's altitudes are its levels (m,
    /// increasing from 0: dense where the extinction is).
    pub geometry: &'a ColumnGeometry,
    pub sun_columns: &'a SunColumnTable,
}

/// A line from a table node marched once: per sample its radius located
/// in the sun-column table, its central angle from the node, rad, and per
/// wavelength its quadrature weight times f beta_sca rho T(x, y),
/// [sample * wavelengths + i].
#[derive(Default)]
struct MarchedLine {
    located: Vec<SunColumnRadius>,
    central_rad: Vec<f64>,
    sources: Vec<f64>,
}

/// B tabulated (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PeakBeam {
    wavelengths: usize,
    ground_m: f64,
    altitudes_m: Vec<f64>,
    /// The sun elevation nodes computed: first..first + elevations (of
    /// the table's grid, [`elevation_rad`]).
    first: usize,
    elevations: usize,
    /// ln B, [(a * elevations + e) * wavelengths + i].
    ln_beam: Vec<f64>,
}

impl PeakBeam {
    /// The table for a sky whose species have forward peaks (None when
    /// none has), at the table's sun elevations within `elevations_deg`
    /// (those its view rays meet, [`PeakBeam::needed_elevations_deg`]),
    /// per altitude of the table (its field's levels) those within
    /// `needed` there (None: none; see [`NeededElevations`]). Every row
    /// computed anew: the tests' table (a sky's field takes its rows from
    /// a [`PeakBeamCache`], the same numbers).
    #[cfg(test)]
    pub(crate) fn compute(
        inputs: &PeakBeamInputs,
        elevations_deg: (f64, f64),
        needed: &NeededElevations,
    ) -> Option<PeakBeam> {
        let weights = tilt_weights(inputs)?;
        let mut known = KnownRows::new(inputs);
        Some(PeakBeam::compute_with_tilts(
            inputs,
            &weights,
            elevations_deg,
            needed,
            &mut known,
        ))
    }

    /// The table with the tilts' weights given, [i * tilts + k] (bin k
    /// centred on [`tilt_deg`]), taking the rows that `known` holds and
    /// adding to it those it computes.
    ///
    /// A line from a node depends on its own elevation only, not on the
    /// sun's: the lines are on one grid of elevations, the tilts being a
    /// whole number of the sun's elevation steps, so each is marched once
    /// per altitude (its samples' radii, central angles from x and
    /// f beta_sca rho T(x, y) kept) and read by every sun elevation and tilt
    /// that meet on it. At each altitude only the elevations `needed`
    /// there (and a node beyond each end, for the interpolation) are
    /// computed, those `known` does not hold yet, and only the lines they
    /// read are marched; the others hold ln of the smallest positive
    /// number, what no light gives. A row is the same numbers whichever
    /// sun asked for it first (its sums do not depend on the eye's sun):
    /// the table is the same bit for bit with `known` empty or not.
    fn compute_with_tilts(
        inputs: &PeakBeamInputs,
        weights: &[f64],
        (lowest_deg, highest_deg): (f64, f64),
        needed: &NeededElevations,
        known: &mut KnownRows,
    ) -> PeakBeam {
        let (corners, profiles) = (&inputs.geometry.corners, &inputs.geometry.profiles);
        let altitudes_m = inputs.geometry.grid.altitudes_m();
        let (ground, top) = corners.radii_m();
        let w = inputs.optics.grid.len();
        let s = profiles.len();
        let tilts = weights.len() / w;
        let used: Vec<usize> = (0..tilts)
            .filter(|k| (0..w).any(|i| weights[i * tilts + k] > LIGHTEST_TILT))
            .collect();
        // f_j beta_sca,j, [j * w + i]; the coefficients species-major too.
        let by_species = |values: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..s * w).map(|at| values(at % w, at / w)).collect()
        };
        let peak = by_species(&|i, j| {
            inputs.scaled.phases[i * s + j].forward_fraction
                * inputs.optics.species[j].scattering_per_m[i]
        });
        let extinction = by_species(&|i, j| inputs.scaled.extinction[i * s + j]);
        let scaled_extinction = by_species(&|i, j| inputs.scaled.scaled_extinction[i * s + j]);
        let node = |deg: f64| (deg - PEAK_BEAM_LOWEST_ELEVATION_DEG) / ELEVATION_STEP_DEG;
        let all = elevation_count();
        let last_node = all - 1;
        let first = (node(lowest_deg).floor().max(0.0) as usize).min(last_node - 1);
        let last = (node(highest_deg).ceil().max(0.0) as usize).clamp(first + 1, last_node);
        let elevations = last - first + 1;
        let steps_per_tilt = (TILT_STEP_DEG / ELEVATION_STEP_DEG).round() as usize;
        let half_tilts = (tilts / 2) * steps_per_tilt;
        // Line n has the elevation of the table's node n plus the lowest
        // tilt; elevation node g reads lines g + k * steps_per_tilt.
        let lines = all + 2 * half_tilts;
        let line_rad = |n: usize| elevation_rad(n) + tilt_deg(0, tilts).to_radians();
        let altitudes = altitudes_m.len();
        // Per altitude, the elevation nodes it needs (from..=to of the
        // table's grid, within first..=last), None when none.
        let windows: Vec<Option<(usize, usize)>> = (0..altitudes)
            .map(|a| {
                let (low, high) = needed.at_altitude(a)?;
                let from = (node(low).floor() - 1.0).max(first as f64) as usize;
                let to = ((node(high).ceil() + 1.0).max(0.0) as usize).min(last);
                (from <= to).then_some((from, to))
            })
            .collect();
        let KnownRows { computed, ln_beam } = known;
        let computed_before: &[bool] = computed;
        crate::parallel::for_each_chunk_mut(ln_beam, all * w, |a, block| {
            let Some((from, to)) = windows[a] else {
                return;
            };
            let missing: Vec<usize> = (from..=to)
                .filter(|g| !computed_before[a * all + g])
                .collect();
            if missing.is_empty() {
                return;
            }
            let mut read = vec![false; lines];
            for g in &missing {
                for k in &used {
                    read[g + k * steps_per_tilt] = true;
                }
            }
            let x = Vector3::new(0.0, 0.0, ground + altitudes_m[a].max(LOWEST_NODE_M));
            let mut ends = Vec::with_capacity(corners.most_panel_ends(PANELS));
            let mut march = PanelMarch::new(s);
            let mut sun = vec![0.0; s];
            let mut depth = vec![0.0; w];
            let mut source = vec![0.0; w];
            let mut marched: Vec<MarchedLine> = Vec::with_capacity(lines);
            for (n, read) in read.iter().enumerate() {
                let mut line = MarchedLine::default();
                if !read {
                    marched.push(line);
                    continue;
                }
                let d = Vector3::new(line_rad(n).cos(), 0.0, line_rad(n).sin());
                if let Some((enter, exit)) = segment_in_atmosphere(x, d, ground, top)
                    && exit > enter
                {
                    let start = x + d * enter;
                    corners.fill_panel_ends(start, d, exit - enter, PANELS, &mut ends);
                    march.march(
                        profiles,
                        ground,
                        (start, d),
                        &ends,
                        |node, columns, densities| {
                            let r = node.point.length();
                            // f beta_sca rho T(x, y) times the weight.
                            depth.fill(0.0);
                            source.fill(0.0);
                            for j in 0..s {
                                let rows = j * w..(j + 1) * w;
                                for (((tau, src), ext), f_sca) in depth
                                    .iter_mut()
                                    .zip(source.iter_mut())
                                    .zip(&extinction[rows.clone()])
                                    .zip(&peak[rows])
                                {
                                    *tau += ext * columns[j];
                                    *src += f_sca * densities[j];
                                }
                            }
                            exp_neg_in_place(&mut depth);
                            // Beyond where x sees no wavelength through the
                            // line the samples add nothing: T(x, y) only falls.
                            if depth.iter().all(|t| *t < OPAQUE) {
                                return ControlFlow::Break(());
                            }
                            for (src, t) in source.iter_mut().zip(&depth) {
                                *src *= node.weight * t;
                            }
                            line.located.push(inputs.sun_columns.locate_radius(r));
                            // The sun's elevation at y is the node's plus the
                            // central angle between them (the line lies in
                            // the sun's vertical plane, toward it).
                            line.central_rad
                                .push((node.point.z / r).clamp(-1.0, 1.0).acos());
                            line.sources.extend_from_slice(&source);
                            ControlFlow::Continue(())
                        },
                    );
                }
                marched.push(line);
            }
            let mut line_sum = vec![0.0; w];
            for g in missing {
                let elevation = elevation_rad(g);
                let beam = &mut block[g * w..(g + 1) * w];
                beam.fill(0.0);
                for &k in &used {
                    let line = &marched[g + k * steps_per_tilt];
                    line_sum.fill(0.0);
                    for (y, located) in line.located.iter().enumerate() {
                        let mu_sun = (elevation + line.central_rad[y]).sin();
                        if !inputs
                            .sun_columns
                            .lookup_columns_at_radius(located, mu_sun, &mut sun)
                        {
                            continue;
                        }
                        depth.fill(0.0);
                        for j in 0..s {
                            for (tau, scaled) in
                                depth.iter_mut().zip(&scaled_extinction[j * w..(j + 1) * w])
                            {
                                *tau += scaled * sun[j];
                            }
                        }
                        exp_neg_in_place(&mut depth);
                        for ((out, t), src) in line_sum
                            .iter_mut()
                            .zip(&depth)
                            .zip(&line.sources[y * w..(y + 1) * w])
                        {
                            *out += src * t;
                        }
                    }
                    for (i, (b, m)) in beam.iter_mut().zip(&line_sum).enumerate() {
                        *b += weights[i * tilts + k] * m;
                    }
                }
                for b in beam.iter_mut() {
                    *b = b.max(f64::MIN_POSITIVE).ln();
                }
            }
        });
        // The table: the rows each altitude needs, no light elsewhere.
        let mut table = vec![f64::MIN_POSITIVE.ln(); altitudes * elevations * w];
        for (a, window) in windows.iter().enumerate() {
            let Some((from, to)) = *window else {
                continue;
            };
            for g in from..=to {
                computed[a * all + g] = true;
            }
            table[(a * elevations + from - first) * w..(a * elevations + to + 1 - first) * w]
                .copy_from_slice(&ln_beam[(a * all + from) * w..(a * all + to + 1) * w]);
        }
        PeakBeam {
            wavelengths: w,
            ground_m: ground,
            altitudes_m: altitudes_m.to_vec(),
            first,
            elevations,
            ln_beam: table,
        }
    }

    /// The sun elevations, degrees, that the view rays of a sky whose eye
    /// sees the sun at `eye_sun_elevation_rad` meet within the table's
    /// (None: none): the sun's elevation at a point differs from the eye's
    /// by at most the central angle between them, at most `reach_rad` (the
    /// field's reach: to the ground's horizon from the eye, then to the
    /// top's, or less for a field solved for views above some elevation,
    /// `FieldRequest::lowest_view_elevation_rad`).
    pub(crate) fn needed_elevations_deg(
        eye_sun_elevation_rad: f64,
        reach_rad: f64,
    ) -> Option<(f64, f64)> {
        let lowest = (eye_sun_elevation_rad - reach_rad)
            .to_degrees()
            .max(PEAK_BEAM_LOWEST_ELEVATION_DEG);
        let highest = (eye_sun_elevation_rad + reach_rad)
            .to_degrees()
            .min(PEAK_BEAM_HIGHEST_ELEVATION_DEG);
        (lowest < highest).then_some((lowest, highest))
    }

    /// Every sun elevation the table can cover, degrees (a field for every
    /// sun, `FieldRequest::every_sun`).
    pub(crate) fn every_elevation_deg() -> (f64, f64) {
        (
            PEAK_BEAM_LOWEST_ELEVATION_DEG,
            PEAK_BEAM_HIGHEST_ELEVATION_DEG,
        )
    }

    /// The table as the engine tables' march reads it
    /// (`engine_tables/march.rs`): its altitudes (m), the elevation of its
    /// first node and the nodes' step (degrees), its elevation count, ln B
    /// [(a * elevations + e) * wavelengths + i], and the elevations
    /// (degrees) where it starts, where its share starts falling and where
    /// it ends (see [`PeakBeam::lookup_beam`]).
    pub(crate) fn exported(&self) -> super::source_table::ExportedBeam {
        super::source_table::ExportedBeam {
            altitudes_m: self.altitudes_m.clone(),
            first_elevation_deg: elevation_rad(self.first).to_degrees(),
            step_deg: ELEVATION_STEP_DEG,
            elevations: self.elevations,
            ln_beam: self.ln_beam.clone(),
            range_deg: (
                PEAK_BEAM_LOWEST_ELEVATION_DEG,
                PEAK_BEAM_BLEND_START_DEG,
                PEAK_BEAM_HIGHEST_ELEVATION_DEG,
            ),
        }
    }

    /// B per wavelength into `out` at radius `r_m` with the sun's zenith
    /// cosine `mu_sun` there, and the share of it the scaled beam takes:
    /// 1 up to [`PEAK_BEAM_BLEND_START_DEG`], falling to 0 at the table's top, 0
    /// (and `out` untouched) beyond the table's elevations.
    pub(crate) fn lookup_beam(&self, r_m: f64, mu_sun: f64, out: &mut [f64]) -> f64 {
        let elevation = mu_sun.clamp(-1.0, 1.0).asin().to_degrees();
        if !(PEAK_BEAM_LOWEST_ELEVATION_DEG..PEAK_BEAM_HIGHEST_ELEVATION_DEG).contains(&elevation) {
            return 0.0;
        }
        let share = ((PEAK_BEAM_HIGHEST_ELEVATION_DEG - elevation)
            / (PEAK_BEAM_HIGHEST_ELEVATION_DEG - PEAK_BEAM_BLEND_START_DEG))
            .min(1.0);
        let altitudes = &self.altitudes_m;
        let z = (r_m - self.ground_m).clamp(0.0, altitudes[altitudes.len() - 1]);
        let a = altitudes
            .partition_point(|node| *node <= z)
            .clamp(1, altitudes.len() - 1)
            - 1;
        let ta = ((z - altitudes[a]) / (altitudes[a + 1] - altitudes[a])).clamp(0.0, 1.0);
        // Within the nodes computed (a view ray's points cannot leave them).
        let elevations = self.elevations;
        let xe = ((elevation - PEAK_BEAM_LOWEST_ELEVATION_DEG) / ELEVATION_STEP_DEG
            - self.first as f64)
            .clamp(0.0, (elevations - 1) as f64);
        let e = (xe as usize).min(elevations - 2);
        let te = xe - e as f64;
        let w = self.wavelengths;
        let at = |a: usize, e: usize| &self.ln_beam[(a * elevations + e) * w..][..w];
        let (c00, c01, c10, c11) = (at(a, e), at(a, e + 1), at(a + 1, e), at(a + 1, e + 1));
        let out = &mut out[..w];
        for (i, out) in out.iter_mut().enumerate() {
            *out = -((1.0 - ta) * ((1.0 - te) * c00[i] + te * c01[i])
                + ta * ((1.0 - te) * c10[i] + te * c11[i]));
        }
        exp_neg_in_place(out);
        share
    }
}

/// The tilts' weights of [`compute_tilt_weights`] for these inputs.
fn tilt_weights(inputs: &PeakBeamInputs) -> Option<Vec<f64>> {
    let (ground, top) = inputs.geometry.corners.radii_m();
    compute_tilt_weights(
        inputs.optics,
        &inputs.scaled.phases,
        &inputs.geometry.profiles,
        top - ground,
    )
}

/// Rows of ln B on the table's whole grid of sun elevations, per altitude
/// of the field's levels: those computed so far
/// ([`PeakBeam::compute_with_tilts`] adds to them).
#[derive(Debug, Clone)]
struct KnownRows {
    /// [a * elevation_count() + g].
    computed: Vec<bool>,
    /// [(a * elevation_count() + g) * wavelengths + i].
    ln_beam: Vec<f64>,
}

impl KnownRows {
    /// None computed yet.
    fn new(inputs: &PeakBeamInputs) -> KnownRows {
        let rows = inputs.geometry.grid.altitudes_m().len() * elevation_count();
        KnownRows {
            computed: vec![false; rows],
            ln_beam: vec![0.0; rows * inputs.optics.grid.len()],
        }
    }

    /// Adds the rows `other` has computed and this has not.
    fn merge(&mut self, other: &KnownRows) {
        let w = self.ln_beam.len() / self.computed.len().max(1);
        for (n, (mine, theirs)) in self.computed.iter_mut().zip(&other.computed).enumerate() {
            if *theirs && !*mine {
                *mine = true;
                self.ln_beam[n * w..(n + 1) * w]
                    .copy_from_slice(&other.ln_beam[n * w..(n + 1) * w]);
            }
        }
    }
}

/// The tilted beams' rows computed so far for the skies of one atmosphere
/// and eye, whatever their sun (a row does not depend on it): shared by
/// every sky moved to another sun (`SingleScatteringScene::with_sun`), so
/// that a slider moving the sun computes only the rows its new sun needs
/// and no sky computed before it did. Keyed by what the rows depend on
/// besides the optics: the streams (the delta-M truncation), the field's
/// levels (bit for bit) and the sun-column table's nodes.
#[derive(Debug, Default)]
pub(crate) struct PeakBeamCache(Mutex<Vec<PeakBeamRows>>);

/// One entry of [`PeakBeamCache`].
#[derive(Debug)]
struct PeakBeamRows {
    streams: usize,
    altitudes_m: Vec<u64>,
    sun_column_nodes: (usize, usize),
    /// The tilts' weights (None: no species has a peak).
    weights: Option<Arc<Vec<f64>>>,
    known: KnownRows,
}

impl PeakBeamCache {
    /// [`PeakBeam::compute`] for these inputs, the same table bit for bit,
    /// from the rows kept and those it adds. The rows are copied out and
    /// merged back under the lock, not computed under it (the computation
    /// runs on the thread pool, whose tasks may be other skies' fields); two
    /// threads that race compute the same rows.
    pub(crate) fn compute(
        &self,
        inputs: &PeakBeamInputs,
        elevations_deg: (f64, f64),
        needed: &NeededElevations,
    ) -> Option<PeakBeam> {
        let streams = inputs.geometry.streams.count();
        let altitudes_m: Vec<u64> = inputs
            .geometry
            .grid
            .altitudes_m()
            .iter()
            .map(|z| z.to_bits())
            .collect();
        let sun_column_nodes = inputs.sun_columns.node_counts();
        let matches = |entry: &PeakBeamRows| {
            entry.streams == streams
                && entry.altitudes_m == altitudes_m
                && entry.sun_column_nodes == sun_column_nodes
        };
        // A poisoned lock only means that another thread panicked: the
        // entries in it are whole (each row is merged when complete).
        let lock = || self.0.lock().unwrap_or_else(PoisonError::into_inner);
        let kept = lock()
            .iter()
            .find(|e| matches(e))
            .map(|e| (e.weights.clone(), e.known.clone()));
        let (weights, mut known) = match kept {
            Some(kept) => kept,
            None => (tilt_weights(inputs).map(Arc::new), KnownRows::new(inputs)),
        };
        let beam = weights.as_ref().map(|weights| {
            PeakBeam::compute_with_tilts(inputs, weights, elevations_deg, needed, &mut known)
        });
        let mut entries = lock();
        match entries.iter_mut().find(|e| matches(e)) {
            Some(entry) => entry.known.merge(&known),
            None => entries.push(PeakBeamRows {
                streams,
                altitudes_m,
                sun_column_nodes,
                weights,
                known,
            }),
        }
        beam
    }
}

/// The peaks' mixture projected on the vertical plane (see the module
/// docs), per wavelength and tilt bin, [i * tilts + k], each wavelength's
/// row summing to 1 (zero where no species has a peak); None when no
/// species has one.
fn compute_tilt_weights(
    optics: &AtmosphereOptics,
    phases: &[TruncatedPhase],
    profiles: &[DensityProfile],
    atmosphere_height_m: f64,
) -> Option<Vec<f64>> {
    let w = optics.grid.len();
    let s = optics.species.len();
    let peaked: Vec<usize> = (0..s)
        .filter(|j| (0..w).any(|i| phases[i * s + j].forward_fraction > 0.0))
        .collect();
    if peaked.is_empty() {
        return None;
    }
    // r(alpha) of the mixture, unnormalised, on nodes PROJECTION_STEP_DEG
    // apart out to the corner of the projection's square.
    let step = PROJECTION_STEP_DEG.to_radians();
    let tilts = tilt_count(phases[0].terms());
    let half = tilt_deg(tilts - 1, tilts).to_radians();
    let nodes = (half * 2f64.sqrt() / step).ceil() as usize + 2;
    let mut mixture = vec![0.0; nodes * w];
    // Whether any species has a peak at the wavelength (where none has,
    // the mixture is only p's truncation residue, not a peak).
    let mut has_peak = vec![false; w];
    let mut exact = vec![0.0; w];
    for &j in &peaked {
        let species = &optics.species[j];
        let column = super::forward_peak::vertical_column_m(&profiles[j], atmosphere_height_m);
        let mut legendre = vec![0.0; phases[j].terms()];
        for (i, peaked) in has_peak.iter_mut().enumerate() {
            *peaked |= phases[i * s + j].forward_fraction > 0.0;
        }
        for a in 0..nodes {
            let cos_alpha = (a as f64 * step).cos();
            species.phase_function.eval_into(cos_alpha, &mut exact);
            super::forward_peak::legendre_into(cos_alpha, &mut legendre);
            for i in 0..w {
                let phase = &phases[i * s + j];
                let smooth = (1.0 - phase.forward_fraction) * phase.eval_with_legendre(&legendre);
                mixture[a * w + i] += species.scattering_per_m[i] * column * (exact[i] - smooth);
            }
        }
    }
    let cells = (2.0 * half / step).round() as usize;
    let mut weights = vec![0.0; w * tilts];
    for i in (0..w).filter(|i| has_peak[*i]) {
        let peak = |alpha: f64| {
            let x = alpha / step;
            let a = (x as usize).min(nodes - 2);
            let t = x - a as f64;
            ((1.0 - t) * mixture[a * w + i] + t * mixture[(a + 1) * w + i]).max(0.0)
        };
        // The marginal is even in delta and its integrand even in eta:
        // the cells of the positive quadrant, counted for all four.
        let row = &mut weights[i * tilts..(i + 1) * tilts];
        for u in cells / 2..cells {
            let delta = -half + (u as f64 + 0.5) * step;
            let marginal: f64 = (cells / 2..cells)
                .map(|v| {
                    let eta = -half + (v as f64 + 0.5) * step;
                    peak((delta * delta + eta * eta).sqrt())
                })
                .sum();
            let k = (((delta + half) / TILT_STEP_DEG.to_radians()).round() as usize).min(tilts - 1);
            row[k] += 2.0 * marginal;
            row[tilts - 1 - k] += 2.0 * marginal;
        }
        let total: f64 = row.iter().sum();
        if total > 0.0 {
            row.iter_mut().for_each(|v| *v /= total);
        }
    }
    Some(weights)
}

/// Tilt bins for phases truncated to `terms` terms.
fn tilt_count(terms: usize) -> usize {
    2 * (TILT_REACH_DEG / (terms.max(1) as f64 * TILT_STEP_DEG)).ceil() as usize + 1
}

/// The sun elevations that a sky's view rays meet at each altitude of
/// the table: a point at radius r on a ray from an eye at radius r_e is at
/// most acos(R / r_e) + acos(R / r) from the eye's zenith (as an angle at
/// the planet's centre; to the ground's horizon, then out to r), and its
/// sun's elevation differs from the eye's by at most that angle. A point
/// between the table's altitudes z_a and z_a+1 reads both rows, so row a
/// takes the angle of z_a+1 (the top of the atmosphere for the last row,
/// which serves every point above it).
#[derive(Debug, Clone)]
pub(crate) enum NeededElevations {
    /// Every altitude the whole range (a field for every sun and eye).
    Everywhere,
    /// The eye's sun elevation (rad) and per altitude the largest central
    /// angle (rad) of the points that read its row.
    AroundEye {
        eye_elevation_rad: f64,
        reach_rad: Vec<f64>,
    },
}

impl NeededElevations {
    /// Around an eye at radius `eye_radius_m` whose sun is
    /// `eye_elevation_rad` up, for the table's `altitudes_m` above a
    /// ground of radius `ground_m` under a top of radius `top_m`, each
    /// reach at most `reach_rad` (the field's).
    pub(crate) fn around_eye(
        eye_elevation_rad: f64,
        eye_radius_m: f64,
        (ground_m, top_m): (f64, f64),
        altitudes_m: &[f64],
        reach_rad: f64,
    ) -> NeededElevations {
        let eye = (ground_m / eye_radius_m.max(ground_m)).min(1.0).acos();
        let reach_rad = (0..altitudes_m.len())
            .map(|a| {
                let r = altitudes_m
                    .get(a + 1)
                    .map_or(top_m, |z| ground_m + z)
                    .max(ground_m);
                (eye + (ground_m / r).min(1.0).acos()).min(reach_rad)
            })
            .collect();
        NeededElevations::AroundEye {
            eye_elevation_rad,
            reach_rad,
        }
    }

    /// The elevations (degrees) needed at altitude `a` within the table's
    /// range, None when none.
    fn at_altitude(&self, a: usize) -> Option<(f64, f64)> {
        match self {
            NeededElevations::Everywhere => Some(PeakBeam::every_elevation_deg()),
            NeededElevations::AroundEye {
                eye_elevation_rad,
                reach_rad,
            } => PeakBeam::needed_elevations_deg(*eye_elevation_rad, reach_rad[a]),
        }
    }
}

/// The tilt of bin k of `tilts`, degrees.
fn tilt_deg(k: usize, tilts: usize) -> f64 {
    (k as f64 - (tilts / 2) as f64) * TILT_STEP_DEG
}

fn elevation_count() -> usize {
    ((PEAK_BEAM_HIGHEST_ELEVATION_DEG - PEAK_BEAM_LOWEST_ELEVATION_DEG) / ELEVATION_STEP_DEG)
        .round() as usize
        + 1
}

/// The sun's elevation at node e, rad.
fn elevation_rad(e: usize) -> f64 {
    (PEAK_BEAM_LOWEST_ELEVATION_DEG + e as f64 * ELEVATION_STEP_DEG).to_radians()
}

#[cfg(test)]
mod tests {
    use super::super::vertical_grid::VerticalGrid;
    use super::*;
    use crate::atmosphere::Atmosphere;
    use crate::spectrum::WavelengthGrid;
    use crate::transport::optical_column::compute_columns_along_ray;

    /// What the table needs, for `preset` at 440, 560 and 680 nm with 8
    /// streams a hemisphere's delta-M (the sky's default).
    struct Inputs {
        optics: AtmosphereOptics,
        scaled: ScaledOptics,
        geometry: ColumnGeometry,
        sun_columns: SunColumnTable,
    }

    impl Inputs {
        fn new(preset: &str) -> Inputs {
            let atmosphere = Atmosphere::preset(preset).unwrap();
            let grid = WavelengthGrid::new(440.0, 680.0, 120.0).unwrap();
            let optics = atmosphere.compute_optics(&grid).unwrap();
            let ground = atmosphere.planet.radius_m();
            let top = ground + atmosphere.planet.atmosphere_height_m();
            let scaled = ScaledOptics::delta_m(&optics, 16);
            let profiles: Vec<DensityProfile> =
                optics.species.iter().map(|s| s.profile.clone()).collect();
            let sun_columns = SunColumnTable::compute(&profiles, ground, top, 128, 256);
            // The field's levels, as the sky's default makes them.
            let altitudes_m = VerticalGrid::for_optics(&optics, top - ground, 40)
                .altitudes_m()
                .to_vec();
            let geometry = ColumnGeometry::with_levels(profiles, (ground, top), 8, &altitudes_m);
            assert_eq!(scaled.phases.len(), grid.len() * optics.species.len());
            Inputs {
                optics,
                scaled,
                geometry,
                sun_columns,
            }
        }

        fn beam_inputs(&self) -> PeakBeamInputs<'_> {
            PeakBeamInputs {
                optics: &self.optics,
                scaled: &self.scaled,
                geometry: &self.geometry,
                sun_columns: &self.sun_columns,
            }
        }

        /// f_j beta_sca,j at [i * species + j], m^-1.
        fn peak_scattering(&self) -> Vec<f64> {
            self.scaled
                .extinction
                .iter()
                .zip(&self.scaled.scaled_extinction)
                .map(|(e, s)| e - s)
                .collect()
        }

        /// Columns of every species from `point` to the top along
        /// `direction` (None through the ground), on 64 panels.
        fn columns(&self, point: Vector3, direction: Vector3) -> Option<Vec<f64>> {
            let (ground, top) = self.geometry.corners.radii_m();
            let r = point.length();
            if crate::geometry::ray_intersects_ground(r, point.dot(direction) / r, ground) {
                return None;
            }
            let length = crate::geometry::distance_to_top_of_atmosphere(point, direction, top);
            let mut ends = Vec::new();
            self.geometry
                .corners
                .fill_panel_ends(point, direction, length, 64, &mut ends);
            let mut columns = vec![0.0; self.geometry.profiles.len()];
            compute_columns_along_ray(
                &self.geometry.profiles,
                ground,
                point,
                direction,
                &ends,
                &mut columns,
            );
            Some(columns)
        }

        /// The oracle of B at altitude `altitude_m` with the sun
        /// `elevation_deg` high there: each tilt's line marched on midpoint
        /// steps growing from 20 m by 3 % a step to at most 2 km, the
        /// columns toward the sun integrated exactly (64 panels) at every
        /// step.
        fn reference_beam(&self, weights: &[f64], altitude_m: f64, elevation_deg: f64) -> Vec<f64> {
            let (ground, top) = self.geometry.corners.radii_m();
            let (w, s) = (self.optics.grid.len(), self.geometry.profiles.len());
            let tilts = weights.len() / w;
            // From the ground a horizontal line would graze it (the table's
            // lowest node is LOWEST_NODE_M up for that reason).
            let x = Vector3::new(0.0, 0.0, ground + altitude_m.max(LOWEST_NODE_M));
            let elevation = elevation_deg.to_radians();
            let sun = Vector3::new(elevation.cos(), 0.0, elevation.sin());
            let mut beam = vec![0.0; w];
            for k in 0..tilts {
                let turned = elevation + tilt_deg(k, tilts).to_radians();
                let d = Vector3::new(turned.cos(), 0.0, turned.sin());
                let Some((_, exit)) = segment_in_atmosphere(x, d, ground, top) else {
                    continue;
                };
                let mut view = vec![0.0; s];
                let mut line = vec![0.0; w];
                let mut t: f64 = 0.0;
                let mut step: f64 = 20.0;
                while t < exit {
                    let h = step.min(exit - t);
                    let y = x + d * (t + 0.5 * h);
                    let altitude = y.length() - ground;
                    let densities: Vec<f64> = self
                        .geometry
                        .profiles
                        .iter()
                        .map(|p| p.relative_density(altitude))
                        .collect();
                    if let Some(sun_columns) = self.columns(y, sun) {
                        let columns: Vec<f64> = view
                            .iter()
                            .zip(&densities)
                            .map(|(v, d)| v + 0.5 * h * d)
                            .collect();
                        let exact = depths(&self.scaled.extinction, &columns);
                        let scaled = depths(&self.scaled.scaled_extinction, &sun_columns);
                        let peak = depths(&self.peak_scattering(), &densities);
                        for (((out, e), t), p) in line.iter_mut().zip(exact).zip(scaled).zip(peak) {
                            *out += h * p * (-(e + t)).exp();
                        }
                    }
                    for j in 0..s {
                        view[j] += h * densities[j];
                    }
                    t += h;
                    step = (step * 1.03).min(2000.0);
                }
                for i in 0..w {
                    beam[i] += weights[i * tilts + k] * line[i];
                }
            }
            beam
        }
    }

    /// Per wavelength, sum_j coefficients[i * species + j] values[j].
    fn depths(coefficients: &[f64], values: &[f64]) -> Vec<f64> {
        coefficients
            .chunks_exact(values.len())
            .map(|row| row.iter().zip(values).map(|(c, v)| c * v).sum())
            .collect()
    }

    /// With every weight but the untilted bin's zero, the last peak scattering is
    /// exactly forward and B is delta-M's T*_sun - T_sun = T_sun (e^X - 1)
    /// (the model's limit, a closed form of the line's integral): the
    /// table at its nodes against the exact columns' value, lit points at
    /// five of the field's levels from the ground up with the sun from
    /// -2 to 10 degrees there. Measured within 0.46 % (the ground with the
    /// sun on its horizon, where the sun-column table's interpolation is
    /// least exact); mars-dust.
    #[test]
    fn an_untilted_peak_gives_delta_ms_beam() {
        let inputs = Inputs::new("mars-dust");
        let w = inputs.optics.grid.len();
        let tilts = tilt_count(inputs.scaled.phases[0].terms());
        let mut weights = vec![0.0; w * tilts];
        for i in 0..w {
            weights[i * tilts + tilts / 2] = 1.0;
        }
        let table = PeakBeam::compute_with_tilts(
            &inputs.beam_inputs(),
            &weights,
            (
                PEAK_BEAM_LOWEST_ELEVATION_DEG,
                PEAK_BEAM_HIGHEST_ELEVATION_DEG,
            ),
            &NeededElevations::Everywhere,
            &mut KnownRows::new(&inputs.beam_inputs()),
        );
        let (ground, _) = inputs.geometry.corners.radii_m();
        let mut worst = 0.0f64;
        let mut looked_up = vec![0.0; w];
        for a in [0, 3, 6, 10, 15] {
            let z = inputs.geometry.grid.altitudes_m()[a];
            for e in (18..=30).step_by(2) {
                let elevation = elevation_rad(e);
                let x = Vector3::new(0.0, 0.0, ground + z);
                let sun = Vector3::new(elevation.cos(), 0.0, elevation.sin());
                let Some(columns) = inputs.columns(x, sun) else {
                    continue;
                };
                table.lookup_beam(x.length(), elevation.sin(), &mut looked_up);
                let exact = depths(&inputs.scaled.extinction, &columns);
                let scaled = depths(&inputs.scaled.scaled_extinction, &columns);
                for (i, ((b, tau), scaled)) in looked_up.iter().zip(exact).zip(scaled).enumerate() {
                    let expected = (-scaled).exp() - (-tau).exp();
                    let error = b / expected - 1.0;
                    worst = worst.max(error.abs());
                    assert!(
                        error.abs() < 1e-2,
                        "altitude {z} m, sun {} deg, index {i}: {b} against {expected}",
                        elevation.to_degrees()
                    );
                }
            }
        }
        eprintln!("worst relative error: {worst:.2e}");
    }

    /// A table restricted to the elevations an eye's view rays meet at
    /// each altitude reads, everywhere they can read it (every altitude
    /// from the ground to the top, every sun elevation within the central
    /// angle a point there can have from the eye), the same bits as the
    /// whole table; eyes on the ground and 3 km up, suns from 10 degrees
    /// up to 6 below. And it computes fewer of them.
    #[test]
    fn a_table_for_an_eyes_rays_reads_as_the_whole_table_where_they_go() {
        let inputs = Inputs::new("earth-hazy");
        let (ground, top) = inputs.geometry.corners.radii_m();
        let altitudes = inputs.geometry.grid.altitudes_m();
        let whole = PeakBeam::compute(
            &inputs.beam_inputs(),
            PeakBeam::every_elevation_deg(),
            &NeededElevations::Everywhere,
        )
        .unwrap();
        let w = inputs.optics.grid.len();
        let (mut a_out, mut b_out) = (vec![0.0; w], vec![0.0; w]);
        for eye_altitude in [0.0, 3_000.0] {
            let eye = ground + eye_altitude;
            let reach = (ground / eye).acos() + (ground / top).acos();
            for eye_sun_deg in [10.0, 5.0, 2.0, 0.0, -3.0, -6.0] {
                let eye_sun = f64::to_radians(eye_sun_deg);
                let needed =
                    NeededElevations::around_eye(eye_sun, eye, (ground, top), altitudes, reach);
                let Some(range) = PeakBeam::needed_elevations_deg(eye_sun, reach) else {
                    continue;
                };
                let restricted = PeakBeam::compute(&inputs.beam_inputs(), range, &needed).unwrap();
                // Entries the whole table has light at and the restricted
                // one left out (no light: ln of the smallest number).
                let floor = f64::MIN_POSITIVE.ln();
                let at = |table: &PeakBeam, a: usize, e: usize| {
                    table.ln_beam[(a * table.elevations + e) * w]
                };
                let left_out = (0..altitudes.len())
                    .flat_map(|a| (0..restricted.elevations).map(move |e| (a, e)))
                    .filter(|&(a, e)| {
                        at(&restricted, a, e) == floor
                            && at(&whole, a, e + restricted.first - whole.first) != floor
                    })
                    .count();
                assert!(
                    left_out > 0,
                    "eye {eye_altitude} m, sun {eye_sun_deg}: nothing left out"
                );
                let mut compared = 0;
                for step in 0..=400 {
                    let z = (top - ground) * (step as f64 / 400.0).powi(3);
                    let r = ground + z;
                    let angle = (ground / eye).acos() + (ground / r).min(1.0).acos();
                    for t in -20..=20 {
                        let elevation = eye_sun + angle * t as f64 / 20.0;
                        let a_share = whole.lookup_beam(r, elevation.sin(), &mut a_out);
                        let b_share = restricted.lookup_beam(r, elevation.sin(), &mut b_out);
                        assert_eq!(a_share.to_bits(), b_share.to_bits());
                        if a_share > 0.0 {
                            compared += 1;
                            for (x, y) in a_out.iter().zip(&b_out) {
                                assert_eq!(
                                    x.to_bits(),
                                    y.to_bits(),
                                    "eye {eye_altitude} m, sun {eye_sun_deg}, {z} m, {} deg",
                                    elevation.to_degrees()
                                );
                            }
                        }
                    }
                }
                assert!(compared > 1000, "{compared}");
            }
        }
    }

    /// The cache's tables are the ones computed anew, bit for bit, for a
    /// sun moving down as a slider moves it (and back up), eyes on the
    /// ground and 3 km up; a sun a degree below the last computes one row
    /// a level, and a sun met again none.
    #[test]
    fn the_kept_rows_give_the_table_computed_anew() {
        let inputs = Inputs::new("earth-hazy");
        let (ground, top) = inputs.geometry.corners.radii_m();
        let altitudes = inputs.geometry.grid.altitudes_m();
        for eye_altitude in [0.0, 3_000.0] {
            let cache = PeakBeamCache::default();
            let eye = ground + eye_altitude;
            let reach = (ground / eye).acos() + (ground / top).acos();
            let computed = |cache: &PeakBeamCache| {
                let entries = cache.0.lock().unwrap();
                entries[0].known.computed.iter().filter(|c| **c).count()
            };
            let mut before = 0;
            for (n, eye_sun_deg) in [20.0, 10.0, 5.0, 2.0, -4.0, -5.0, 2.0]
                .into_iter()
                .enumerate()
            {
                let eye_sun = f64::to_radians(eye_sun_deg);
                let needed =
                    NeededElevations::around_eye(eye_sun, eye, (ground, top), altitudes, reach);
                let range = PeakBeam::needed_elevations_deg(eye_sun, reach).unwrap();
                let anew = PeakBeam::compute(&inputs.beam_inputs(), range, &needed).unwrap();
                let kept = cache
                    .compute(&inputs.beam_inputs(), range, &needed)
                    .unwrap();
                assert_eq!((kept.first, kept.elevations), (anew.first, anew.elevations));
                assert_eq!(kept.altitudes_m, anew.altitudes_m);
                assert!(
                    kept.ln_beam
                        .iter()
                        .zip(&anew.ln_beam)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "eye {eye_altitude} m, sun {eye_sun_deg}"
                );
                // The rows this sun added: after a sun 1 degree above it,
                // one a level (under half of those with light in a table
                // anew); at a sun met before, none.
                let added = computed(&cache) - before;
                let lit_rows = anew
                    .ln_beam
                    .chunks_exact(anew.wavelengths)
                    .filter(|row| row[0] != f64::MIN_POSITIVE.ln())
                    .count();
                match n {
                    0 => assert!(added >= lit_rows, "{added} of {lit_rows}"),
                    5 => assert!(
                        added == altitudes.len() && added < lit_rows / 2,
                        "{added} of {lit_rows}"
                    ),
                    6 => assert_eq!(added, 0),
                    _ => {}
                }
                before += added;
            }
        }
    }

    /// The table at the field's levels and between them against the oracle
    /// with the same tilts (its Gauss panels, line sharing, sun-column
    /// table and interpolation in altitude; the sun at the table's
    /// elevations), for mars-dust (its dust well mixed) and earth-hazy
    /// (its haze 1.2 km high), from the ground to 6 km, with the sun from
    /// 3 degrees below to 6 above. Measured: mars-dust within 0.1 %;
    /// earth-hazy within 2 % where the beam is 1e-3 of the sun or more
    /// (where the forward-peak term carries light), and up to 13 % where
    /// it is 1e-4 to 1e-8 (6 km, the sun below the horizon: lines tilted
    /// down through the haze's top, between levels 1.5 km apart).
    #[test]
    fn the_table_matches_a_direct_integral() {
        for (preset, bright, dark) in [("mars-dust", 0.005, 0.005), ("earth-hazy", 0.03, 0.2)] {
            let inputs = Inputs::new(preset);
            let (ground, top) = inputs.geometry.corners.radii_m();
            let weights = compute_tilt_weights(
                &inputs.optics,
                &inputs.scaled.phases,
                &inputs.geometry.profiles,
                top - ground,
            )
            .unwrap();
            let table = PeakBeam::compute_with_tilts(
                &inputs.beam_inputs(),
                &weights,
                (
                    PEAK_BEAM_LOWEST_ELEVATION_DEG,
                    PEAK_BEAM_HIGHEST_ELEVATION_DEG,
                ),
                &NeededElevations::Everywhere,
                &mut KnownRows::new(&inputs.beam_inputs()),
            );
            let mut looked_up = vec![0.0; inputs.optics.grid.len()];
            for altitude in [0.0, 150.0, 1_300.0, 6_000.0] {
                for elevation in [-3.0, -1.0, 0.0, 3.0, 6.0] {
                    let expected = inputs.reference_beam(&weights, altitude, elevation);
                    table.lookup_beam(
                        ground + altitude,
                        f64::to_radians(elevation).sin(),
                        &mut looked_up,
                    );
                    for (i, (b, e)) in looked_up.iter().zip(&expected).enumerate() {
                        let error = b / e - 1.0;
                        let bound = if *e >= 1e-3 { bright } else { dark };
                        assert!(
                            error.abs() < bound,
                            "{preset}, {altitude} m, sun {elevation} deg, index {i}: {b:e} against {e:e}"
                        );
                    }
                }
            }
        }
    }
}
