//! Reading the engine tables: the formulas the reference shaders
//! (`web/shaders/`) run, here in f64 so that tests can hold the tables to
//! the library and the shaders to these.
//!
//! - Sky: at the eye's altitude h, the view's zenith coordinate is taken
//!   with the eye's own horizon (`axes::zenith_coordinate`) and used on
//!   every altitude layer; bilinear in (zenith, azimuth) within a layer,
//!   but in the sky table's zenith cap (its first [`ZENITH_CAP_CELLS`]
//!   zenith cells, to about 40 degrees from the zenith by default) a
//!   Catmull-Rom cubic in ln L along the zenith axis through the rows on
//!   both sides of the cell, the row before the zenith being row 1 at the
//!   opposite azimuth: a high sun's aureole, tens of times brighter within
//!   a few degrees of the sun than the rows 2.8 degrees apart resolve, is
//!   read with a continuous slope across the rows and through the zenith
//!   (a read linear between them bent the zenith's brightness against the
//!   sun's elevation where a turned view crossed a row),
//!   between the two altitude layers in ln L linear in the altitude h
//!   itself above the eye's horizon (the sky falls about exponentially
//!   with the air above the eye), and linear in L and in the altitude
//!   coordinate below it (the ground's views); neither is within the 2 %
//!   asked between the nodes (docs/engine-tables.md, "An eye between the
//!   altitude nodes": the nodes are too far apart in the haze and a
//!   raised eye's limb needs its own zenith axis), and in the logarithm (each
//!   value floored at [`FLOOR`]) between the two sun layers s and s + 1:
//!   the chord of ln L less `f (1 - f) / 2` times the second difference of
//!   ln L over the sun nodes (that at s - 1, s, s + 1 and that at s, s + 1,
//!   s + 2 blended by f, the fraction of the step; zero at the axis's ends;
//!   each within [`CURVATURE_LIMIT`]), exact where ln L is quadratic in the
//!   node coordinate: the twilight sky's ln L bends between nodes (2.3 %
//!   below the chord at -4 degrees for paper-earth). Each sun layer is
//!   read at the view turned with the sun
//!   (about the horizontal axis across the sun's azimuth) from the sun's
//!   elevation e to the layer's e_j, by the share w of the step
//!   ([`turn_share`]): at w = 1 the view keeps its angle to the sun, so
//!   the aureole, which the sun axis's steps (8 degrees apart at e = 60)
//!   would otherwise interpolate between two places, stays where it is;
//!   at w = 0 the view keeps its zenith angle, which the horizon's band
//!   needs. w = 1 within 10 degrees of the sun and 0 beyond 40, 0 within
//!   5 degrees of the horizon (1 from 20 up); or, for suns below 2
//!   degrees (none above 6), w = 1 within 40 degrees of the antisolar
//!   point and 0 beyond 80, the horizon included: the planet's shadow,
//!   which rises at the antisolar horizon as the sun sets, turns with the
//!   antisolar point, and a view along its edge read unturned from the
//!   layer below the sunset is several times too dark (smoothstep ramps
//!   between; the larger of the two shares). For suns above 68 degrees
//!   (ramping from 55, [`HIGH_SUN_DEG`]) w = 1 far from the sun too, the
//!   horizon's band excepted: the aureole reaches the zenith, and the
//!   zenith read unturned in the layer at 90 degrees would be that
//!   layer's sun (earth-hazy's zenith 3.8 times too bright at 86).
//!   At a sun node the read is the layer's own. With the sun
//!   below the horizon, near the antisolar point and below the shadow's
//!   edge ([`shadow_read_share`]), the read is blended toward that of the sun
//!   axis cut at its last node below the horizon (the chord of the last
//!   two such layers, extended beyond the last; the curvature at the cut
//!   dropped): a layer with the sun up has no shadow to give.
//! - Sky for an eye above the ground, tables with the march's
//!   (`EngineTables::raised_sky_xyz`; the manifest's
//!   `lookup.sky_raised_eye`; the shaders have it as `soraRaisedSkyView` /
//!   `sora_raised_sky_view`, the entry for a raised eye beside the
//!   table's read for an eye on the ground, the GLSL within 0.071 % of
//!   this and the explorer's real-time view drawing it within 0.32 %):
//!   above the eye's horizon the march's light
//!   of the whole ray (`MarchTables::whole_ray_xyz`, split at the
//!   perigee for a view going down from well above it), in the first
//!   altitude cell times the table's ratio to the march on the ground
//!   (fading to none at the first node); below it the march to the lower
//!   altitude node's sphere plus the segment's transmittance times the
//!   table's read there, times the table's ratio to that composition at
//!   the upper node (ln linear in h). The table's own read on the
//!   ground, continuous in the altitude; within 0.2-3.4 % of the library
//!   between the nodes where the table's read was 6-65 % off
//!   (docs/engine-tables.md, "An eye between the altitude nodes").
//! - Transmittance: linear in altitude between two rows, each read
//!   linearly at the mu coordinate of its own altitude's horizon; zero
//!   for a view below the eye's horizon.
//! - Irradiance: linear in altitude, geometric in sun elevation, plus the
//!   direct beam `E_sun T(h, sin e) sin e` (zero below the horizon).
//! - Sun disc: `E_sun T(h, mu_sun) (1 - u (1 - cos a)) / (pi alpha^2 (1 - u / 3))`
//!   within the sun's angular radius alpha, with cos a = sqrt(1 - (gamma
//!   / alpha)^2) (limb darkening u = 0.6, as `sky/sun_disc.rs`).
//! - Aerial perspective, tables with the march's (`march.rs`): the
//!   segment marched per wavelength from the field's source and the
//!   optics, as the library composes a segment's light
//!   (`MarchTables::aerial_perspective_xyz`; not in the shaders yet).
//!   Otherwise (the shaders' lookup): `S(x, v) R(x, v, d) w` per channel, S the sky
//!   read at the eye, R the aerial table read as the sky table (its own
//!   view nodes) and linear in ln d between its two distance slices (d
//!   from the thickness / 1000 to the ray's end), w = (1 - T) / (1 -
//!   T_end) from the transmittance table (see the module docs of
//!   `engine_tables`).

use super::EngineTables;
use super::axes;
use super::march::{DARK_LOG_SOURCE, DENSITY_NODES, MARCH_STEPS, MarchTables, PHASE_NODES};
use crate::geometry::{Vector3, segment_in_atmosphere};
use crate::transport::multiple_scattering::{azimuth_cell, interpolate_log_source};

/// Smallest value the sun axis's geometric interpolation takes the
/// logarithm of (XYZ in W m^-2 sr^-1 nm^-1 units).
pub const FLOOR: f64 = 1e-30;

/// Largest |second difference of ln L| between sun layers that the sun
/// axis's curvature term takes (a layer at [`FLOOR`] would otherwise
/// blow it up).
pub const CURVATURE_LIMIT: f64 = 1.0;

/// Linear limb-darkening coefficient of the sun's disc (as `sky/sun_disc.rs`).
pub const LIMB_DARKENING: f64 = crate::sky::SUN_LIMB_DARKENING;

/// A view in a point's local frame: its zenith angle and its azimuth from
/// the sun's.
#[derive(Debug, Clone, Copy)]
pub struct LocalView {
    /// Zenith angle, rad.
    pub zenith_rad: f64,
    /// Azimuth from the sun's, rad, 0..pi.
    pub relative_azimuth_rad: f64,
}

impl LocalView {
    /// The view `v` (unit) seen from a point whose local vertical is the
    /// unit `up`, with the sun toward the unit `sun`.
    pub fn from_vectors(v: [f64; 3], up: [f64; 3], sun: [f64; 3]) -> LocalView {
        let mu = dot(v, up).clamp(-1.0, 1.0);
        let vh = sub(v, scale(up, mu));
        let sh = sub(sun, scale(up, dot(sun, up)));
        let (nv, ns) = (dot(vh, vh).sqrt(), dot(sh, sh).sqrt());
        let cos_phi = if nv > 1e-12 && ns > 1e-12 {
            (dot(vh, sh) / (nv * ns)).clamp(-1.0, 1.0)
        } else {
            1.0
        };
        LocalView {
            zenith_rad: mu.acos(),
            relative_azimuth_rad: cos_phi.acos(),
        }
    }
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}

fn mix(a: [f64; 3], b: [f64; 3], f: f64) -> [f64; 3] {
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * f)
}

/// The share (0..1) of altitude `h` (m) between altitude nodes `a` and
/// `a + 1` of `nodes` over `thickness_m`, linear in the altitude itself.
fn altitude_share(h: f64, a: usize, nodes: usize, thickness_m: f64) -> f64 {
    let (h0, h1) = (
        axes::altitude_of_node(a, nodes, thickness_m),
        axes::altitude_of_node(a + 1, nodes, thickness_m),
    );
    ((h - h0) / (h1 - h0)).clamp(0.0, 1.0)
}

fn mix_log(a: [f64; 3], b: [f64; 3], f: f64) -> [f64; 3] {
    std::array::from_fn(|i| {
        let (la, lb) = (a[i].max(FLOOR).ln(), b[i].max(FLOOR).ln());
        (la + (lb - la) * f).exp()
    })
}

/// The share of the step from the sun's elevation `e_deg` to a sun node's
/// that `view` is turned by before a sun layer is read (see the module
/// docs), for an eye whose horizon is at zenith angle `horizon` (rad).
pub(crate) fn turn_share(view: LocalView, e_deg: f64, horizon: f64) -> f64 {
    let e = e_deg.to_radians();
    let (z, phi) = (view.zenith_rad, view.relative_azimuth_rad);
    let cos_theta = z.cos() * e.sin() + z.sin() * phi.cos() * e.cos();
    // Near the sun, and for a high sun the whole sky (its aureole reaches
    // the zenith, where the zenith angle alone would read the layer's sun).
    let sun_side = smoothstep(
        40f64.to_radians().cos(),
        10f64.to_radians().cos(),
        cos_theta,
    )
    .max(smoothstep(HIGH_SUN_DEG.0, HIGH_SUN_DEG.1, e_deg))
        * (1.0 - smoothstep(horizon - 20f64.to_radians(), horizon - 5f64.to_radians(), z));
    // The planet's shadow, which rises at the antisolar horizon as the sun
    // sets, turns with the antisolar point (horizon included).
    let shadow = smoothstep(
        80f64.to_radians().cos(),
        40f64.to_radians().cos(),
        -cos_theta,
    ) * (1.0 - smoothstep(2.0, 6.0, e_deg));
    sun_side.max(shadow)
}

/// The eye's height above a view's perigee (a share of the atmosphere's
/// thickness) from which the march of a raised eye's sky splits the ray
/// at the perigee (`EngineTables::whole_ray_sky_xyz`; a smoothstep from
/// none at the perigee's altitude).
pub(crate) const PERIGEE_SPLIT_RAMP: f64 = 0.05;

/// Sun elevations (degrees) over which the whole sky above the horizon's
/// band comes to be read turned (`turn_share`): none below the first, all
/// above the second (below the sun node at 69.15 degrees of the default
/// 48 nodes, so that no cell or curvature term about the layers at 78.89
/// and 90 degrees reads a view turned part of the way).
pub(crate) const HIGH_SUN_DEG: (f64, f64) = (55.0, 68.0);

/// Where the read below the planet's shadow's edge ([`shadow_read_share`])
/// ends: at this many times the sun's depression in view elevation. At 2
/// paper-mars's horizon band (p99) at suns -0.1 and -0.19 degrees was
/// 2.61 % and 2.00 %, at 3 1.47 % and 2.27 %, ending at the edge itself
/// (1.1) 2.74 % and 2.71 %, at 2.5 1.47 % and 1.70 % (`docs/engine-tables.md`).
pub(crate) const SHADOW_READ_RAMP: f64 = 2.5;

/// The share of the read of a view near the antisolar point with the sun
/// below the horizon that takes the sun layers below the horizon only
/// (`layers_xyz`): the planet's shadow's share of `turn_share`, where the
/// view is below the shadow's edge (its elevation within the sun's
/// depression |e|), ramping to none at [`SHADOW_READ_RAMP`] |e|; none with
/// the sun up.
pub(crate) fn shadow_read_share(view: LocalView, e_deg: f64, horizon: f64) -> f64 {
    if e_deg >= 0.0 {
        return 0.0;
    }
    let e = e_deg.to_radians();
    let (z, phi) = (view.zenith_rad, view.relative_azimuth_rad);
    let cos_theta = z.cos() * e.sin() + z.sin() * phi.cos() * e.cos();
    let shadow = smoothstep(
        80f64.to_radians().cos(),
        40f64.to_radians().cos(),
        -cos_theta,
    );
    let elevation = horizon - z;
    shadow * (1.0 - smoothstep(-e, -SHADOW_READ_RAMP * e, elevation))
}

/// `view` turned by `delta` (rad) about the horizontal axis across the
/// sun's azimuth, as the sun is turned from its elevation to a node's
/// (keeping its angle to the sun), on the same side of the eye's horizon
/// (at zenith angle `horizon`) as before; unturned (`delta` 0) exactly.
pub(crate) fn turned_view(view: LocalView, delta: f64, horizon: f64) -> LocalView {
    if delta == 0.0 {
        return view;
    }
    let (z, phi) = (view.zenith_rad, view.relative_azimuth_rad);
    let v = [z.sin() * phi.cos(), z.sin() * phi.sin(), z.cos()];
    let (s, c) = delta.sin_cos();
    let x = v[0] * c - v[2] * s;
    let turned = (v[0] * s + v[2] * c).clamp(-1.0, 1.0).acos();
    let turned = if z < horizon {
        turned.min(horizon - 2e-6)
    } else {
        turned.max(horizon)
    };
    LocalView {
        zenith_rad: turned,
        relative_azimuth_rad: v[1].abs().atan2(x),
    }
}

/// Slice `slice` (of all layers' slices) of `table` at zenith coordinate
/// `(y, lowest, highest)` and relative azimuth `phi`: bilinear, but within
/// the table's zenith cap (its first `cap` cells from the zenith,
/// [`LayerTable::cap`]) a cubic in ln L along the zenith axis
/// ([`catmull_rom_log`]) through the rows on both sides of the cell, the
/// row before the zenith being row 1 at the opposite azimuth (pi - phi):
/// the read is smooth in the zenith across the rows and through the
/// zenith itself.
fn layer_value_at(
    table: LayerTable<'_>,
    slice: usize,
    (y, lowest, highest): (f64, usize, usize),
    phi: f64,
) -> [f64; 3] {
    let k_count = table.azimuth;
    let (i, fy) = axes::cell(y, lowest, highest);
    // The cap's cells: the upper half's first `cap` (a cell of the lower
    // half is at least `half`), rows i + 2 still above the horizon.
    let column = |phi: f64| axes::cell(axes::azimuth_coordinate(phi, k_count), 0, k_count - 2);
    let texel = |row: usize, column: usize| {
        let t = table.texels[(slice * 2 * table.half + row) * k_count + column];
        [t[0] as f64, t[1] as f64, t[2] as f64]
    };
    let row = |row: usize, (k, fx): (usize, f64)| mix(texel(row, k), texel(row, k + 1), fx);
    let at = column(phi);
    if i < table.cap && i + 2 < table.half {
        let before = if i == 0 {
            row(1, column(std::f64::consts::PI - phi))
        } else {
            row(i - 1, at)
        };
        return catmull_rom_log(before, row(i, at), row(i + 1, at), row(i + 2, at), fy);
    }
    mix(row(i, at), row(i + 1, at), fy)
}

/// The uniform Catmull-Rom cubic in ln L (each value floored at
/// [`FLOOR`]) between `p0` (t = 0) and `p1` (t = 1), with `before` and
/// `after` the nodes on either side: it passes through the nodes, and its
/// slope at each is the centred difference of the nodes about it, so that
/// consecutive cells join with a continuous slope.
fn catmull_rom_log(
    before: [f64; 3],
    p0: [f64; 3],
    p1: [f64; 3],
    after: [f64; 3],
    t: f64,
) -> [f64; 3] {
    std::array::from_fn(|c| {
        let [m, a, b, n] = [before[c], p0[c], p1[c], after[c]].map(|v| v.max(FLOOR).ln());
        let cubic = -m + 3.0 * a - 3.0 * b + n;
        let square = 2.0 * m - 5.0 * a + 4.0 * b - n;
        (a + 0.5 * t * ((b - m) + t * (square + t * cubic))).exp()
    })
}

/// Zenith cells of the sky table, from the zenith, read by the cubic in
/// ln L (`layer_value_at`).
pub(crate) const ZENITH_CAP_CELLS: usize = 16;

/// A test's override of [`ZENITH_CAP_CELLS`] (`usize::MAX`: none), so
/// that one bake can be read with caps of several sizes
/// (`tests::probe_zenith_cap`).
#[cfg(test)]
pub(crate) static CAP_OVERRIDE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(usize::MAX);

/// A test's choice of the sky's read for a raised eye (0: the lookup's;
/// 1-3 [`EngineTables::probe_altitude_read`]'s blends of the table's
/// layers; 4 the table's read, ln L linear in h, as without march
/// tables; 5-7 [`EngineTables::probe_march_read`]'s marches), so
/// that one bake can be read several ways
/// (`tests::the_sky_between_the_altitude_nodes_matches_the_library`).
#[cfg(test)]
pub(crate) static ALTITUDE_READ_OVERRIDE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

/// Probe (`tests::probe_the_march_s_parts`): which parts of the march's light come back (0: all; 1:
/// single scattering alone; 2: all but single scattering) and the march's
/// steps (0: [`MARCH_STEPS`]).
#[cfg(test)]
pub(crate) static MARCH_PART: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);
#[cfg(test)]
pub(crate) static MARCH_STEPS_OVERRIDE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

/// Probe (`tests::probe_the_march_s_parts`): the march's columns toward the sun (0: the table's,
/// bilinear; 1: exact; 2: the table's, bilinear in ln column).
#[cfg(test)]
pub(crate) static SUN_COLUMNS_MODE: std::sync::atomic::AtomicUsize =
    std::sync::atomic::AtomicUsize::new(0);

fn march_steps() -> (usize, usize) {
    #[cfg(test)]
    if let n @ 1.. = MARCH_STEPS_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) {
        return (n / 1000, n % 1000);
    }
    MARCH_STEPS
}

fn zenith_cap_cells() -> usize {
    #[cfg(test)]
    if let n @ 0..usize::MAX = CAP_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) {
        return n;
    }
    ZENITH_CAP_CELLS
}

/// GLSL's smoothstep: 0 at `a`, 1 at `b`, 3 t^2 - 2 t^3 between.
fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A table of layers (sun node s, altitude node a; layer s * A + a), each
/// `slices` images of `2 half` zenith rows by `azimuth` nodes: the sky
/// table (one slice) and the aerial-perspective table (one per distance
/// node), texel (k, row) of slice j of layer L at index
/// `((L * slices + j) * 2 half + row) * azimuth + k`.
#[derive(Clone, Copy)]
pub(crate) struct LayerTable<'a> {
    pub texels: &'a [[f32; 3]],
    pub half: usize,
    /// Fine and wide zenith cells next to the horizon per half
    /// (`axes::zenith_of_node`).
    pub cells: (usize, usize),
    pub azimuth: usize,
    pub slices: usize,
    /// Zenith cells (from the zenith) read by the cubic in ln L
    /// (`layer_value_at`): [`ZENITH_CAP_CELLS`] for the sky table, none for
    /// the aerial-perspective table.
    pub cap: usize,
}

impl EngineTables {
    pub(crate) fn sky_layers_table(&self) -> LayerTable<'_> {
        LayerTable {
            texels: &self.sky,
            half: self.settings.zenith_nodes_per_half,
            cells: self.settings.zenith_cells(),
            azimuth: self.settings.azimuth_nodes,
            slices: 1,
            cap: zenith_cap_cells(),
        }
    }

    pub(crate) fn aerial_layers_table(&self) -> LayerTable<'_> {
        let (half, azimuth, slices) = self.settings.aerial_nodes;
        LayerTable {
            texels: &self.aerial,
            half,
            cells: (0, 0),
            azimuth,
            slices,
            cap: 0,
        }
    }

    /// The sky table's value in `layer` toward zenith angle `zenith` (the
    /// horizon at `horizon`, rad) and relative azimuth `phi`: bilinear.
    pub(crate) fn layer_value(
        &self,
        layer: usize,
        zenith: f64,
        horizon: f64,
        phi: f64,
    ) -> [f64; 3] {
        let table = self.sky_layers_table();
        let coordinate = axes::zenith_coordinate(zenith, table.half, table.cells, horizon);
        layer_value_at(table, layer, coordinate, phi)
    }

    /// The cells (lower node, upper node's weight) of altitude `h` (m,
    /// within the atmosphere) and sun elevation `sun_elevation_deg` on the
    /// sky and irradiance tables' axes.
    fn altitude_and_sun_cells(
        &self,
        h: f64,
        sun_elevation_deg: f64,
    ) -> ((usize, f64), (usize, f64)) {
        let (a_count, s_count) = (self.settings.altitude_nodes, self.settings.sun_nodes);
        (
            axes::cell(
                axes::altitude_coordinate(h, self.thickness_m(), a_count),
                0,
                a_count - 2,
            ),
            axes::cell(
                axes::sun_coordinate(sun_elevation_deg, s_count),
                0,
                s_count - 2,
            ),
        )
    }

    /// Sky radiance (XYZ, W m^-2 sr^-1 nm^-1 units) seen at `altitude_m`
    /// toward `view` with the sun at `sun_elevation_deg` (no sun disc).
    pub fn sky_xyz(&self, altitude_m: f64, view: LocalView, sun_elevation_deg: f64) -> [f64; 3] {
        #[cfg(test)]
        match ALTITUDE_READ_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed) {
            1..=4 => return self.table_sky_xyz(altitude_m, view, sun_elevation_deg),
            mode @ 5.. => {
                if let Some(value) =
                    self.probe_march_read(mode, altitude_m, view, sun_elevation_deg)
                {
                    return value;
                }
            }
            _ => {}
        }
        match &self.march {
            Some(march) if altitude_m > 0.0 => {
                self.raised_sky_xyz(march, altitude_m, view, sun_elevation_deg)
            }
            _ => self.table_sky_xyz(altitude_m, view, sun_elevation_deg),
        }
    }

    /// The sky table's read (see the module docs) at `altitude_m` toward
    /// `view` with the sun at `sun_elevation_deg`: [`Self::sky_xyz`]
    /// without march tables and on the ground.
    pub(crate) fn table_sky_xyz(
        &self,
        altitude_m: f64,
        view: LocalView,
        sun_elevation_deg: f64,
    ) -> [f64; 3] {
        self.layers_xyz(
            self.sky_layers_table(),
            altitude_m,
            view,
            sun_elevation_deg,
            (0, 0.0),
        )
    }

    /// A layer table's value at `altitude_m` toward `view` with the sun at
    /// `sun_elevation_deg`, linear between slices `slice.0` and
    /// `slice.0 + 1` by `slice.1` (see the module docs: bilinear in the
    /// layer, in ln L linear in altitude, in ln L with its curvature between the
    /// sun layers, each sun layer read at the view turned with the sun).
    pub(crate) fn layers_xyz(
        &self,
        table: LayerTable<'_>,
        altitude_m: f64,
        view: LocalView,
        sun_elevation_deg: f64,
        (j, fj): (usize, f64),
    ) -> [f64; 3] {
        let h = altitude_m.clamp(0.0, self.thickness_m());
        let horizon = axes::horizon_zenith(self.ground_radius_m + h, self.ground_radius_m);
        let e_deg =
            sun_elevation_deg.clamp(axes::SUN_ELEVATION_MIN_DEG, axes::SUN_ELEVATION_MAX_DEG);
        let a_count = self.settings.altitude_nodes;
        let ((a, fa), (s, fs)) = self.altitude_and_sun_cells(h, e_deg);
        // Between the two altitude layers: above the eye's horizon ln L
        // linear in the altitude itself (the sky falls with the air above
        // the eye, about exponentially in h); below it, toward the ground,
        // L linear in the altitude coordinate (the air's light there grows
        // with the path, not exponentially).
        let fh = altitude_share(h, a, a_count, self.thickness_m());
        let share = turn_share(view, e_deg, horizon);
        // ln L of sun layer `s` read at `view` turned by `share` of the
        // step to its node.
        let read_at = |s: usize, share: f64| {
            let node_deg = axes::sun_elevation_of_node(s, self.settings.sun_nodes);
            let turned = turned_view(view, (node_deg - e_deg).to_radians() * share, horizon);
            let coordinate =
                axes::zenith_coordinate(turned.zenith_rad, table.half, table.cells, horizon);
            let at = |a: usize| {
                let first = (s * a_count + a) * table.slices + j;
                let value = |slice: usize| {
                    layer_value_at(table, slice, coordinate, turned.relative_azimuth_rad)
                };
                if fj > 0.0 {
                    mix(value(first), value(first + 1), fj)
                } else {
                    value(first)
                }
            };
            #[cfg(test)]
            if let mode @ 1..=3 = ALTITUDE_READ_OVERRIDE.load(std::sync::atomic::Ordering::Relaxed)
            {
                return self.probe_altitude_read(mode, (a, fa), h, turned, horizon, at);
            }
            let (lower, upper) = (at(a), at(a + 1));
            if turned.zenith_rad < horizon {
                std::array::from_fn(|i| {
                    let (l0, l1) = (lower[i].max(FLOOR).ln(), upper[i].max(FLOOR).ln());
                    l0 + (l1 - l0) * fh
                })
            } else {
                mix(lower, upper, fa).map(|v| v.max(FLOOR).ln())
            }
        };
        let layer = |s: usize| read_at(s, share);
        let s_count = self.settings.sun_nodes;
        // ln L on the sun axis cut at node `top`: the chord between the
        // two layers about the sun less its curvature (the second
        // differences at nodes s and s + 1, zero at the axis's ends, each
        // within +-CURVATURE_LIMIT); beyond `top`, the chord of the last
        // two layers extended.
        let read = |top: usize| -> [f64; 3] {
            let (s, fs) = if s + 1 > top {
                (top - 1, fs + (s + 1 - top) as f64)
            } else {
                (s, fs)
            };
            let (l0, l1) = (layer(s), layer(s + 1));
            let second = |lower: [f64; 3], middle: [f64; 3], upper: [f64; 3]| -> [f64; 3] {
                std::array::from_fn(|i| {
                    (lower[i] - 2.0 * middle[i] + upper[i]).clamp(-CURVATURE_LIMIT, CURVATURE_LIMIT)
                })
            };
            let inside = fs <= 1.0;
            let d0 = if s > 0 && inside {
                second(layer(s - 1), l0, l1)
            } else {
                [0.0; 3]
            };
            let d1 = if s + 2 <= top && inside {
                second(l0, l1, layer(s + 2))
            } else {
                [0.0; 3]
            };
            std::array::from_fn(|i| {
                let chord = l0[i] + (l1[i] - l0[i]) * fs;
                let curvature = d0[i] + (d1[i] - d0[i]) * fs;
                chord - 0.5 * fs * (1.0 - fs) * curvature
            })
        };
        let whole = read(s_count - 1);
        let below = shadow_read_share(view, e_deg, horizon);
        // The last sun node below the horizon.
        let top = (axes::sun_coordinate(0.0, s_count).ceil() as usize).saturating_sub(1);
        if below == 0.0 || top < 1 || top + 1 >= s_count || s + 2 <= top || s > top {
            return whole.map(f64::exp);
        }
        let shadow = read(top);
        std::array::from_fn(|i| (whole[i] + (shadow[i] - whole[i]) * below).exp())
    }

    /// Probe ([`ALTITUDE_READ_OVERRIDE`], measured and set aside,
    /// docs/engine-tables.md "An eye between the altitude nodes"): ln L of the two altitude layers
    /// `a`, `a + 1` (values `at(a)`) blended for an eye at `h` toward
    /// `view` (the eye's horizon at `horizon`) by mode 1: ln L linear in
    /// the altitude coordinate; 2: L linear in the altitude coordinate (the
    /// read before ln L linear in h); 3:
    /// L / (1 - T) linear in the coordinate, T the transmittance to the top
    /// along the view at each layer's own zenith angle for the view's
    /// coordinate, times the eye's 1 - T.
    #[cfg(test)]
    fn probe_altitude_read(
        &self,
        mode: usize,
        (a, fa): (usize, f64),
        h: f64,
        view: LocalView,
        horizon: f64,
        at: impl Fn(usize) -> [f64; 3],
    ) -> [f64; 3] {
        let a_count = self.settings.altitude_nodes;
        let node = |a: usize| axes::altitude_of_node(a, a_count, self.thickness_m());
        let (l0, l1) = (at(a), at(a + 1));
        match mode {
            1 => mix_log(l0, l1, fa),
            2 => mix(l0, l1, fa),
            _ => {
                let pi = std::f64::consts::PI;
                let z = view.zenith_rad;
                let depth = |h_a: f64| {
                    let horizon_a =
                        axes::horizon_zenith(self.ground_radius_m + h_a, self.ground_radius_m);
                    let z_a = if z < horizon {
                        z * horizon_a / horizon
                    } else {
                        pi - (pi - z) * (pi - horizon_a) / (pi - horizon)
                    };
                    self.transmittance_xyz(h_a, z_a.cos()).map(|t| 1.0 - t)
                };
                let (d0, d1, d) = (depth(node(a)), depth(node(a + 1)), depth(h));
                std::array::from_fn(|i| {
                    let r0 = if d0[i] > 1e-9 {
                        l0[i] / d0[i]
                    } else {
                        f64::NAN
                    };
                    let r1 = if d1[i] > 1e-9 {
                        l1[i] / d1[i]
                    } else {
                        f64::NAN
                    };
                    let (r0, r1) = match (r0.is_nan(), r1.is_nan()) {
                        (false, false) => (r0, r1),
                        (true, false) => (r1, r1),
                        (false, true) => (r0, r0),
                        (true, true) => (0.0, 0.0),
                    };
                    d[i] * (r0 + (r1 - r0) * fa)
                })
            }
        }
        .map(|v| v.max(FLOOR).ln())
    }

    /// The sky for an eye above the ground, from the march's tables
    /// (`sky_xyz` with march tables; see the module docs): above the
    /// eye's horizon the march's light of the whole ray
    /// ([`Self::whole_ray_sky_xyz`]), in the first altitude cell times the
    /// ratio of the table's read on the ground to the march's there (the
    /// view at the same place relative to the ground's horizon), that
    /// ratio's logarithm fading linearly in h to none at the first node;
    /// below it the march to where the ray crosses the lower altitude
    /// node's sphere plus the segment's transmittance times the table's
    /// read there ([`Self::composed_below_xyz`]), times the ratio of the
    /// table's read at the upper node to the same composition from there
    /// (the view at the same place relative to that node's horizon), that
    /// ratio's logarithm linear in h. The table's own read on the ground
    /// and, below the horizon, at every node; continuous in the altitude.
    pub(crate) fn raised_sky_xyz(
        &self,
        march: &MarchTables,
        altitude_m: f64,
        view: LocalView,
        sun_elevation_deg: f64,
    ) -> [f64; 3] {
        let pi = std::f64::consts::PI;
        let h = altitude_m.clamp(0.0, self.thickness_m());
        let (z, phi) = (view.zenith_rad, view.relative_azimuth_rad);
        let towards = |z: f64| [z.sin() * phi.cos(), z.sin() * phi.sin(), z.cos()];
        let e = sun_elevation_deg.to_radians();
        let sun = [e.cos(), 0.0, e.sin()];
        let a_count = self.settings.altitude_nodes;
        let node = |a: usize| axes::altitude_of_node(a, a_count, self.thickness_m());
        let ((a, _), _) = self.altitude_and_sun_cells(h, sun_elevation_deg);
        let fh = altitude_share(h, a, a_count, self.thickness_m());
        let horizon_at =
            |h: f64| axes::horizon_zenith(self.ground_radius_m + h, self.ground_radius_m);
        let horizon = horizon_at(h);
        let table = |h: f64, z: f64| {
            let local = LocalView {
                zenith_rad: z,
                relative_azimuth_rad: phi,
            };
            self.table_sky_xyz(h, local, sun_elevation_deg)
        };
        let scaled = |value: [f64; 3], want: [f64; 3], got: [f64; 3], share: f64| {
            std::array::from_fn(|i| {
                let k = want[i].max(FLOOR).ln() - got[i].max(FLOOR).ln();
                value[i] * (k * share).exp()
            })
        };
        if z < horizon {
            let whole = self.whole_ray_sky_xyz(march, h, towards(z), sun);
            if a > 0 || fh >= 1.0 {
                return whole;
            }
            let z_0 = z * horizon_at(0.0) / horizon;
            let on_ground = self.whole_ray_sky_xyz(march, 0.0, towards(z_0), sun);
            return scaled(whole, table(0.0, z_0), on_ground, 1.0 - fh);
        }
        let below = self.composed_below_xyz(march, h, towards(z), sun, node(a));
        if fh <= 0.0 {
            return below;
        }
        let h_b = node(a + 1);
        let z_b = pi - (pi - z) * (pi - horizon_at(h_b)) / (pi - horizon);
        let from_b = self.composed_below_xyz(march, h_b, towards(z_b), sun, node(a));
        scaled(below, table(h_b, z_b), from_b, fh)
    }

    /// The march's light of the whole ray from an eye at altitude `h` (m) toward the
    /// unit `v` (the sun toward the unit `sun`, eye-local), a view above
    /// the eye's horizon: [`MarchTables::whole_ray_xyz`] split, for a view
    /// going down, between the perigee (where the eye is at least
    /// [`PERIGEE_SPLIT_RAMP`] times the thickness above it) and the ray's
    /// end (no split, where the eye is at the perigee's altitude),
    /// smoothstep in the eye's height above the perigee.
    pub(crate) fn whole_ray_sky_xyz(
        &self,
        march: &MarchTables,
        h: f64,
        v: [f64; 3],
        sun: [f64; 3],
    ) -> [f64; 3] {
        let r = self.ground_radius_m + h;
        let length = axes::ray_length(r, v[2], self.ground_radius_m, self.top_radius_m);
        let split = if v[2] < 0.0 {
            let perigee = -r * v[2];
            let above = r - (r * r - perigee * perigee).max(0.0).sqrt();
            let w = smoothstep(0.0, PERIGEE_SPLIT_RAMP * self.thickness_m(), above);
            length + (perigee.min(length) - length) * w
        } else {
            length
        };
        march.whole_ray_xyz(h, v, sun, split).0
    }

    /// The sky below the horizon of an eye at altitude `h` (m) toward the unit `v` (the
    /// sun toward the unit `sun`, eye-local) composed at the sphere of
    /// altitude `h_node` (m; at or below the eye; the ray meets it, as it
    /// meets the ground): the march's light of the segment to the
    /// crossing plus the segment's transmittance times the sky table's
    /// read there (`table_sky_xyz` at `h_node`, in the point's own frame),
    /// the table's read itself where the eye is on the sphere.
    pub(crate) fn composed_below_xyz(
        &self,
        march: &MarchTables,
        h: f64,
        v: [f64; 3],
        sun: [f64; 3],
        h_node: f64,
    ) -> [f64; 3] {
        let r = self.ground_radius_m + h;
        let r_node = self.ground_radius_m + h_node;
        let mu = v[2];
        let disc = (r * r * mu * mu - (r - r_node) * (r + r_node)).max(0.0);
        let t = if h > h_node {
            (-r * mu - disc.sqrt()).max(0.0)
        } else {
            0.0
        };
        let p = [v[0] * t, v[1] * t, r + v[2] * t];
        let up = scale(p, 1.0 / dot(p, p).sqrt());
        let local = LocalView::from_vectors(v, up, sun);
        let e = dot(sun, up).clamp(-1.0, 1.0).asin().to_degrees();
        let far = self.table_sky_xyz(h_node, local, e);
        if t <= 0.0 {
            return far;
        }
        let (light, segment) = march.aerial_perspective_xyz(h, v, sun, t);
        std::array::from_fn(|i| light[i] + segment[i] * far[i])
    }

    /// Probe ([`ALTITUDE_READ_OVERRIDE`] 5 to 7, measured and set aside,
    /// docs/engine-tables.md "An eye between the altitude nodes"): the
    /// sky for a raised eye from the march (None without march tables,
    /// or on the ground). 5: the march's light of the whole ray (no
    /// split, no ratio to the table); 6: the march to where the ray first
    /// crosses the sphere of the nearer altitude node (the lower node's
    /// going down, if it reaches it, else the upper's) plus the segment's
    /// transmittance times the table's read there; 7: the whole ray's
    /// march (no split) times the table's ratio to the march at the two
    /// nodes about the eye (the view at the same place relative to each
    /// node's horizon), that ratio's logarithm linear in h.
    #[cfg(test)]
    fn probe_march_read(
        &self,
        mode: usize,
        altitude_m: f64,
        view: LocalView,
        e_deg: f64,
    ) -> Option<[f64; 3]> {
        let march = self.march.as_ref()?;
        let h = altitude_m.clamp(0.0, self.thickness_m());
        if h <= 0.0 {
            return None;
        }
        let (z, phi) = (view.zenith_rad, view.relative_azimuth_rad);
        let v = [z.sin() * phi.cos(), z.sin() * phi.sin(), z.cos()];
        let e = e_deg.to_radians();
        let sun = [e.cos(), 0.0, e.sin()];
        let a_count = self.settings.altitude_nodes;
        let node = |a: usize| axes::altitude_of_node(a, a_count, self.thickness_m());
        let ((a, fa), _) = self.altitude_and_sun_cells(h, e_deg);
        let whole = |h: f64, v: [f64; 3]| march.aerial_perspective_xyz(h, v, sun, f64::MAX).0;
        match mode {
            5 => Some(whole(h, v)),
            6 => {
                let r = self.ground_radius_m + h;
                let mu = v[2];
                let r_a = self.ground_radius_m + node(a);
                let lower = r * r * mu * mu - r * r + r_a * r_a;
                if mu < 0.0 && (fa <= 0.0 || lower >= 0.0) {
                    return Some(self.composed_below_xyz(march, h, v, sun, node(a)));
                }
                let h_b = node(a + 1);
                let r_b = self.ground_radius_m + h_b;
                let t = (-r * mu + (r * r * mu * mu - r * r + r_b * r_b).max(0.0).sqrt()).max(0.0);
                let p = [v[0] * t, v[1] * t, r + v[2] * t];
                let up = scale(p, 1.0 / dot(p, p).sqrt());
                let local = LocalView::from_vectors(v, up, sun);
                let e_p = dot(sun, up).clamp(-1.0, 1.0).asin().to_degrees();
                let far = self.table_sky_xyz(h_b, local, e_p);
                let (light, segment) = march.aerial_perspective_xyz(h, v, sun, t);
                Some(std::array::from_fn(|i| light[i] + segment[i] * far[i]))
            }
            _ => {
                let pi = std::f64::consts::PI;
                let horizon_at =
                    |h: f64| axes::horizon_zenith(self.ground_radius_m + h, self.ground_radius_m);
                let horizon = horizon_at(h);
                let ratio = |h_n: f64| {
                    let z_n = if z < horizon {
                        z * horizon_at(h_n) / horizon
                    } else {
                        pi - (pi - z) * (pi - horizon_at(h_n)) / (pi - horizon)
                    };
                    let local = LocalView {
                        zenith_rad: z_n,
                        relative_azimuth_rad: phi,
                    };
                    let v_n = [z_n.sin() * phi.cos(), z_n.sin() * phi.sin(), z_n.cos()];
                    let table = self.table_sky_xyz(h_n, local, e_deg);
                    let marched = whole(h_n, v_n);
                    std::array::from_fn::<f64, 3, _>(|i| {
                        table[i].max(FLOOR).ln() - marched[i].max(FLOOR).ln()
                    })
                };
                let fh = altitude_share(h, a, a_count, self.thickness_m());
                let (k_a, k_b) = (ratio(node(a)), ratio(node(a + 1)));
                let whole = whole(h, v);
                Some(std::array::from_fn(|i| {
                    whole[i] * (k_a[i] + (k_b[i] - k_a[i]) * fh).exp()
                }))
            }
        }
    }
    /// Transmittance (XYZ of the transmitted sunlight over XYZ of the
    /// sunlight) from `altitude_m` to the top of the atmosphere along view
    /// cosine `mu`; zero below the horizon.
    pub fn transmittance_xyz(&self, altitude_m: f64, mu: f64) -> [f64; 3] {
        let h = altitude_m.clamp(0.0, self.thickness_m());
        let r = self.ground_radius_m + h;
        if mu < axes::horizon_cosine(r, self.ground_radius_m) {
            return [0.0; 3];
        }
        let (a_count, m_count) = self.settings.transmittance_nodes;
        let (a, fa) = axes::cell(
            axes::altitude_coordinate(h, self.thickness_m(), a_count),
            0,
            a_count - 2,
        );
        // Each altitude row is read at the view cosine's coordinate for
        // that row's own horizon: the horizon's cosine changes as
        // sqrt(h) near the ground, and a coordinate taken for the eye's
        // horizon would move a row's value with it (0.3 % at 9 cm).
        let row = |a: usize| {
            let r_a = self.ground_radius_m + axes::altitude_of_node(a, a_count, self.thickness_m());
            let (m, fm) = axes::cell(
                axes::transmittance_mu_coordinate(mu, m_count, r_a, self.ground_radius_m),
                0,
                m_count - 2,
            );
            let texel = |m: usize| {
                let t = self.transmittance[a * m_count + m];
                [t[0] as f64, t[1] as f64, t[2] as f64]
            };
            mix(texel(m), texel(m + 1), fm)
        };
        mix(row(a), row(a + 1), fa)
    }

    /// Global horizontal irradiance (XYZ, W m^-2 nm^-1 units) at
    /// `altitude_m` with the sun at `sun_elevation_deg`: the diffuse part
    /// from the irradiance table (linear in its own altitude axis's
    /// coordinate, geometric between the sun nodes) and the direct beam.
    pub fn ground_irradiance_xyz(&self, altitude_m: f64, sun_elevation_deg: f64) -> [f64; 3] {
        let h = altitude_m.clamp(0.0, self.thickness_m());
        let s_count = self.settings.sun_nodes;
        let (_, (s, fs)) = self.altitude_and_sun_cells(h, sun_elevation_deg);
        // The irradiance table's own altitude axis (the sky table's
        // mapping, more nodes).
        let n_count = self.settings.irradiance_altitude_nodes();
        let (a, fa) = axes::cell(
            axes::altitude_coordinate(h, self.thickness_m(), n_count),
            0,
            n_count - 2,
        );
        let texel = |a: usize, s: usize| {
            let t = self.irradiance[a * s_count + s];
            [t[0] as f64, t[1] as f64, t[2] as f64]
        };
        let diffuse = mix_log(
            mix(texel(a, s), texel(a + 1, s), fa),
            mix(texel(a, s + 1), texel(a + 1, s + 1), fa),
            fs,
        );
        let mu_sun = sun_elevation_deg.to_radians().sin();
        let t = self.transmittance_xyz(h, mu_sun);
        std::array::from_fn(|i| diffuse[i] + self.solar_xyz[i] * t[i] * mu_sun.max(0.0))
    }

    /// The sun disc's radiance (XYZ) at angle `gamma_rad` from the sun's
    /// centre, for an eye at `altitude_m` with the sun at
    /// `sun_elevation_deg`; zero outside the disc.
    pub fn sun_disc_xyz(
        &self,
        altitude_m: f64,
        sun_elevation_deg: f64,
        gamma_rad: f64,
    ) -> [f64; 3] {
        let alpha = self.sun_angular_radius_rad;
        if gamma_rad >= alpha {
            return [0.0; 3];
        }
        let cos_a = (1.0 - (gamma_rad / alpha).powi(2)).max(0.0).sqrt();
        let u = LIMB_DARKENING;
        let shape =
            (1.0 - u * (1.0 - cos_a)) / (std::f64::consts::PI * alpha * alpha * (1.0 - u / 3.0));
        let t = self.transmittance_xyz(altitude_m, sun_elevation_deg.to_radians().sin());
        std::array::from_fn(|i| self.solar_xyz[i] * t[i] * shape)
    }

    /// The transmittance (XYZ of the sun's spectrum, per channel) of the
    /// segment from an eye at `altitude_m` to the point `distance_m` along
    /// the unit `view` (eye-local east-north-up): a ratio of two
    /// transmittances to the top, along the reversed rays when the view
    /// meets the ground; and the point's radius and unit vertical.
    pub(crate) fn segment_transmittance_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], f64, [f64; 3]) {
        let r = self.ground_radius_m + altitude_m.clamp(0.0, self.thickness_m());
        let p = [
            view[0] * distance_m,
            view[1] * distance_m,
            r + view[2] * distance_m,
        ];
        let r_p = dot(p, p).sqrt();
        let up_p = scale(p, 1.0 / r_p);
        let h_p = (r_p - self.ground_radius_m).clamp(0.0, self.thickness_m());
        let mu = view[2];
        let mu_p = dot(view, up_p);
        let hits_ground = mu < axes::horizon_cosine(r, self.ground_radius_m);
        let (near, far) = if hits_ground {
            (
                self.transmittance_xyz(h_p, -mu_p),
                self.transmittance_xyz(r - self.ground_radius_m, -mu),
            )
        } else {
            (
                self.transmittance_xyz(r - self.ground_radius_m, mu),
                self.transmittance_xyz(h_p, mu_p),
            )
        };
        (
            std::array::from_fn(|i| (near[i] / far[i].max(FLOOR)).min(1.0)),
            r_p,
            up_p,
        )
    }

    /// The aerial-perspective table's value (the ratio R of the segment's
    /// light to `S (1 - T)`) for an eye at `altitude_m` toward `view`, the
    /// sun at `sun_elevation_deg`, at distance `distance_m`: as the sky
    /// table, and linear in ln d between the two distance slices.
    pub(crate) fn aerial_ratio_xyz(
        &self,
        altitude_m: f64,
        view: LocalView,
        sun_elevation_deg: f64,
        distance_m: f64,
    ) -> [f64; 3] {
        let table = self.aerial_layers_table();
        let slice = axes::cell(
            axes::distance_coordinate(
                distance_m,
                table.slices,
                self.aerial_distance_range(altitude_m, view.zenith_rad.cos()),
            ),
            0,
            table.slices - 2,
        );
        self.layers_xyz(table, altitude_m, view, sun_elevation_deg, slice)
    }

    /// The aerial-perspective table's distance axis (m) for an eye at
    /// `altitude_m` along view cosine `mu`: from the nearest node to the
    /// ray's end.
    pub(crate) fn aerial_distance_range(&self, altitude_m: f64, mu: f64) -> (f64, f64) {
        let r = self.ground_radius_m + altitude_m.clamp(0.0, self.thickness_m());
        axes::distance_range(
            self.thickness_m(),
            axes::ray_length(r, mu, self.ground_radius_m, self.top_radius_m),
        )
    }

    /// Aerial perspective between an eye at `altitude_m` and the point at
    /// `distance_m` along the unit `view` (eye-local east-north-up), the
    /// sun toward the unit `sun`: (the light scattered into the segment,
    /// XYZ radiance; the segment's transmittance, XYZ of the transmitted
    /// solar spectrum over XYZ of the solar spectrum per channel). Tables
    /// of a multiply scattering sky march the segment
    /// (`march.rs`, `MarchTables::aerial_perspective_xyz`: within 2 % of
    /// the library at 1-50 km); others take
    /// [`Self::aerial_perspective_by_ratio_xyz`].
    pub fn aerial_perspective_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        match &self.march {
            Some(tables) => tables.aerial_perspective_xyz(altitude_m, view, sun, distance_m),
            None => self.aerial_perspective_by_ratio_xyz(altitude_m, view, sun, distance_m),
        }
    }

    /// Aerial perspective from the aerial-perspective ratio table (the
    /// reference shaders' `soraAerialPerspective` reads it when the tables
    /// have no march): (the light scattered into the segment, XYZ
    /// radiance; the segment's transmittance, XYZ of the sun's spectrum)
    /// as [`Self::aerial_perspective_xyz`] takes them. The light is `S(x, v) R(x, v, d) w` per channel, S the
    /// sky table's read at the eye, R the aerial-perspective table's and w
    /// the segment's share of the whole ray's extinction
    /// ((1 - T) / (1 - T_end), T_end to the ray's end; see the module docs of
    /// `engine_tables`); tables baked without an aerial-perspective table
    /// take [`Self::aerial_perspective_by_difference_xyz`].
    pub fn aerial_perspective_by_ratio_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        if self.aerial.is_empty() {
            return self.aerial_perspective_by_difference_xyz(altitude_m, view, sun, distance_m);
        }
        let (segment, share) = self.aerial_share_xyz(altitude_m, view, distance_m);
        let up = [0.0, 0.0, 1.0];
        let local = LocalView::from_vectors(view, up, sun);
        let e = dot(sun, up).clamp(-1.0, 1.0).asin().to_degrees();
        let sky = self.table_sky_xyz(altitude_m, local, e);
        let ratio = self.aerial_ratio_xyz(altitude_m, local, e, distance_m);
        let inscattered = std::array::from_fn(|i| sky[i] * ratio[i] * share[i]);
        (inscattered, segment)
    }

    /// The segment's transmittance T (as [`Self::segment_transmittance_xyz`])
    /// and the share of the whole ray's extinction it holds, (1 - T) / (1 -
    /// T_end) per channel, T_end the transmittance to the ray's end (the
    /// top of the atmosphere or the ground); 1 where the whole ray has no
    /// extinction.
    pub(crate) fn aerial_share_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        let (segment, _, _) = self.segment_transmittance_xyz(altitude_m, view, distance_m);
        let r = self.ground_radius_m + altitude_m.clamp(0.0, self.thickness_m());
        let length = axes::ray_length(r, view[2], self.ground_radius_m, self.top_radius_m);
        let (whole, _, _) = self.segment_transmittance_xyz(altitude_m, view, length);
        let share = std::array::from_fn(|i| {
            let (part, all) = (1.0 - segment[i], 1.0 - whole[i]);
            if all > 1e-9 {
                (part / all).clamp(0.0, 1.0)
            } else {
                1.0
            }
        });
        (segment, share)
    }

    /// Aerial perspective from the sky table alone (tables without an
    /// aerial-perspective table): `S(x, v) - T(x, p) S(p, v)`, S read at
    /// each end's own altitude, zenith angle and sun elevation. A
    /// difference of two nearly equal reads for short segments, so not
    /// within 2 % of the library there (`docs/engine-tables.md`).
    pub fn aerial_perspective_by_difference_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        let up = [0.0, 0.0, 1.0];
        let (segment, r_p, up_p) = self.segment_transmittance_xyz(altitude_m, view, distance_m);
        let h_p = (r_p - self.ground_radius_m).clamp(0.0, self.thickness_m());
        let sun_elevation = |up: [f64; 3]| dot(sun, up).clamp(-1.0, 1.0).asin().to_degrees();
        let at_eye = self.sky_xyz(
            altitude_m.clamp(0.0, self.thickness_m()),
            LocalView::from_vectors(view, up, sun),
            sun_elevation(up),
        );
        let at_point = self.sky_xyz(
            h_p,
            LocalView::from_vectors(view, up_p, sun),
            sun_elevation(up_p),
        );
        let inscattered = std::array::from_fn(|i| (at_eye[i] - segment[i] * at_point[i]).max(0.0));
        (inscattered, segment)
    }
}

/// The aerial-perspective march (the Rust lookup, the oracle of the
/// reference shaders' `soraAerialPerspectiveMarch`, which follows it step
/// by step): the tables of [`super::march`], read at the nodes of one view
/// ray.
impl MarchTables {
    /// Aerial perspective by the march (see the module docs of
    /// [`super::march`]): an eye at `altitude_m`, the unit `view` and `sun`
    /// (eye-local east-north-up), a point at `distance_m`: (the light
    /// scattered into the segment, XYZ W m^-2 sr^-1 nm^-1; the segment's
    /// transmittance, XYZ of the transmitted solar spectrum over XYZ of
    /// the solar spectrum per channel).
    ///
    /// [`MARCH_STEPS`] nodes along the segment (u = sqrt(s / length)
    /// uniform, the midpoint rule) and as many more from the point to the
    /// ray's end; at each node the species' densities and columns from the
    /// eye (trapezoids), the columns toward the sun, the source ln R and
    /// the peak beam. Gathered per wavelength: single scattering S =
    /// sum ds E sum_j beta_sca,j p_j rho_j T T_sun, the scaled field
    /// F = sum ds beta*_sca R T* over the segment and the ray beyond it,
    /// and the forward-peak integrals (per species rho_j (T* T*_sun -
    /// T T_sun) and rho_j T* T*_sun, the peak-only Q = f beta_sca rho T T_sun
    /// and Q X; near a low sun with the peak beam). Then, as
    /// `sky/aerial_perspective.rs` composes a segment,
    ///
    /// ```text
    /// L_air = S_seg + F_seg + (1 - T / T*) (F_beyond + G_sky) + P(forward) - P(behind)
    /// ```
    ///
    /// with G_sky the ground's light where the ray meets the ground, P the
    /// forward-peak term of the rows (species rows: the segment's plus
    /// (1 - T / T*) times the scaled rows beyond it; the peak-only rows:
    /// the whole ray's) and of the light behind the point (Q beyond it,
    /// Q X beyond it less ln(T* / T) Q).
    pub(crate) fn aerial_perspective_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        distance_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        self.march_xyz(altitude_m, view, sun, distance_m, false)
    }

    /// The march's light of the whole ray from an eye at `altitude_m`
    /// along the unit `view` (the sun toward the unit `sun`, eye-local
    /// east-north-up) to its end (the top of the atmosphere or the
    /// ground), and the whole ray's transmittance: the march of
    /// [`Self::aerial_perspective_xyz`] with its two stretches of nodes
    /// (crowded toward each stretch's start) split at `split_m` and both
    /// counted as the segment, so that a view going down, split at its
    /// perigee, has nodes crowded at the eye and where the ray runs
    /// lowest.
    pub(crate) fn whole_ray_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        split_m: f64,
    ) -> ([f64; 3], [f64; 3]) {
        self.march_xyz(altitude_m, view, sun, split_m, true)
    }

    fn march_xyz(
        &self,
        altitude_m: f64,
        view: [f64; 3],
        sun: [f64; 3],
        distance_m: f64,
        whole: bool,
    ) -> ([f64; 3], [f64; 3]) {
        let tables = self;
        let src = &tables.source;
        let (w, s) = (src.wavelengths, src.species);
        let (ground, thickness) = (self.ground_radius_m, self.thickness_m);
        let top = ground + thickness;
        let eye = Vector3::new(0.0, 0.0, ground + altitude_m.clamp(0.0, thickness));
        let v = Vector3::new(view[0], view[1], view[2]);
        let sun = Vector3::new(sun[0], sun[1], sun[2]);
        let to_xyz = |values: &[f64]| -> [f64; 3] {
            std::array::from_fn(|c| values.iter().zip(&tables.xyz).map(|(x, k)| x * k[c]).sum())
        };
        let Some((enter, exit)) = segment_in_atmosphere(eye, v, ground, top) else {
            return ([0.0; 3], [1.0; 3]);
        };
        let length = (exit.min(distance_m) - enter).max(0.0);
        let beyond = exit - enter - length;
        // The phase functions at the view's one scattering angle.
        let cos_theta = v.dot(sun).clamp(-1.0, 1.0);
        let theta = cos_theta.acos();
        let (exact_phase, smooth_phase) = tables.phases(theta);
        let rows = s + 2;
        let mut single = vec![0.0; w];
        let (mut field, mut field_beyond) = (vec![0.0; w], vec![0.0; w]);
        let (mut forward, mut scaled) = (vec![0.0; rows * w], vec![0.0; s * w]);
        let (mut forward_segment, mut scaled_segment) = (vec![0.0; rows * w], vec![0.0; s * w]);
        let mut columns = vec![0.0; s];
        let mut columns_segment = vec![0.0; s];
        let (mut log_source, mut beam) = (vec![0.0; w], vec![0.0; w]);
        let density =
            |at: f64| tables.densities(((eye + v * (enter + at)).length() - ground).max(0.0));
        let (mut previous, mut previous_rho) = (0.0, density(0.0));
        let (steps, steps_beyond) = march_steps();
        let nodes = (0..steps)
            .map(|k| (march_node(length, k, steps), true))
            .chain((0..steps_beyond).map(|k| {
                let (at, ds) = march_node(beyond, k, steps_beyond);
                ((length + at, ds), whole)
            }));
        let mut segment_done = false;
        for ((at, ds), in_segment) in nodes {
            if !in_segment && !segment_done {
                let rho = density(length);
                for j in 0..s {
                    columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (length - previous);
                }
                (previous, previous_rho) = (length, rho);
                columns_segment.copy_from_slice(&columns);
                forward_segment.copy_from_slice(&forward);
                scaled_segment.copy_from_slice(&scaled);
                segment_done = true;
            }
            if ds <= 0.0 {
                continue;
            }
            let point = eye + v * (enter + at);
            let r = point.length();
            let zenith = point * (1.0 / r);
            let view_cosine = v.dot(zenith).clamp(-1.0, 1.0);
            let sun_cosine = sun.dot(zenith).clamp(-1.0, 1.0);
            let sines =
                ((1.0 - view_cosine * view_cosine) * (1.0 - sun_cosine * sun_cosine)).sqrt();
            let cos_azimuth = if sines > 1e-12 {
                ((cos_theta - view_cosine * sun_cosine) / sines).clamp(-1.0, 1.0)
            } else {
                1.0
            };
            let altitude = (r - ground).max(0.0);
            tables.log_source(
                altitude,
                sun_cosine,
                view_cosine,
                cos_azimuth,
                &mut log_source,
            );
            let rho = density(at);
            for j in 0..s {
                columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (at - previous);
            }
            previous = at;
            let target = if in_segment {
                &mut field
            } else {
                &mut field_beyond
            };
            for (i, o) in target.iter_mut().enumerate() {
                let (mut tau, mut scattering) = (0.0, 0.0);
                for j in 0..s {
                    tau += src.scaled_extinction[i * s + j] * columns[j];
                    scattering += src.scaled_scattering[i * s + j] * rho[j];
                }
                if log_source[i] > DARK_LOG_SOURCE {
                    *o += ds * scattering * log_source[i].exp() * (-tau).exp();
                }
            }
            let to_sun = tables.sun_columns(r, sun_cosine);
            let share = if src.has_forward_peaks {
                tables.peak_beam(ground, r, sun_cosine, &mut beam)
            } else {
                0.0
            };
            for i in 0..w {
                let mut depths = [0.0; 4];
                let (mut peak, mut source) = (0.0, 0.0);
                for j in 0..s {
                    let (scaled_ext, ext) =
                        (src.scaled_extinction[i * s + j], src.extinction[i * s + j]);
                    let to_sun = to_sun.as_ref().map_or(0.0, |c| c[j]);
                    depths[0] += scaled_ext * columns[j];
                    depths[1] += ext * columns[j];
                    depths[2] += scaled_ext * to_sun;
                    depths[3] += ext * to_sun;
                    peak += (ext - scaled_ext) * rho[j];
                    source += src.scattering[i * s + j] * exact_phase[j * w + i] * rho[j];
                }
                let lit = to_sun.is_some();
                let [view_beam, view_direct, sun_beam, sun_direct] = if lit {
                    depths.map(|d| (-d).exp())
                } else {
                    [(-depths[0]).exp(), (-depths[1]).exp(), 0.0, 0.0]
                };
                if in_segment && lit {
                    single[i] += ds * src.solar[i] * source * view_direct * sun_direct;
                }
                if !src.has_forward_peaks {
                    continue;
                }
                // As the library's march (`add_tilted_forward_peak`).
                let through = sun_beam - sun_direct;
                let scattered = through + share * (beam[i] - through);
                let excess = ds * (view_beam * scattered + sun_direct * (view_beam - view_direct));
                let beam_weight = ds * view_beam * (scattered + sun_direct);
                for j in 0..s {
                    forward[j * w + i] += excess * rho[j];
                    scaled[j * w + i] += beam_weight * rho[j];
                }
                if lit && sun_beam > 0.0 {
                    let only = ds
                        * view_direct
                        * sun_direct
                        * peak
                        * ((sun_direct + scattered) / sun_beam);
                    let x = (depths[1] + depths[3]) - (depths[0] + depths[2]);
                    forward[s * w + i] += only;
                    forward[(s + 1) * w + i] += only * x;
                }
            }
            previous_rho = rho;
        }
        if !segment_done {
            columns_segment.copy_from_slice(&columns);
            forward_segment.copy_from_slice(&forward);
            scaled_segment.copy_from_slice(&scaled);
        }
        // The ground's light where the ray ends on it, through the whole
        // ray's scaled transmittance.
        let end = eye + v * exit;
        let on_ground = end.length() <= ground * (1.0 + 1e-9);
        let ground_light = |i: usize| -> f64 {
            if !on_ground {
                return 0.0;
            }
            let tau_scaled: f64 = (0..s)
                .map(|j| src.scaled_extinction[i * s + j] * columns[j])
                .sum();
            let (node, t) = tables.locate_sun(sun.dot(end.normalized()));
            let lerp = |table: &[f64]| {
                let (a, b) = (table[node * w + i], table[(node + 1) * w + i]);
                if a > 0.0 && b > 0.0 {
                    ((1.0 - t) * a.ln() + t * b.ln()).exp()
                } else {
                    (1.0 - t) * a + t * b
                }
            };
            (-tau_scaled).exp() * (lerp(&src.ground_diffuse) + lerp(&src.ground_direct))
        };
        let mut light = vec![0.0; w];
        let mut transmitted = vec![0.0; w];
        let (mut rows_forward, mut rows_behind) = (vec![0.0; rows * w], vec![0.0; rows * w]);
        for i in 0..w {
            let (mut tau, mut tau_scaled) = (0.0, 0.0);
            for (j, column) in columns_segment.iter().enumerate() {
                tau += src.extinction[i * s + j] * column;
                tau_scaled += src.scaled_extinction[i * s + j] * column;
            }
            transmitted[i] = src.solar[i] * (-tau).exp();
            let (share, depth) = (1.0 - (tau_scaled - tau).exp(), tau - tau_scaled);
            light[i] = single[i] + field[i] + share * (field_beyond[i] + ground_light(i));
            #[cfg(test)]
            match MARCH_PART.load(std::sync::atomic::Ordering::Relaxed) {
                1 => light[i] = single[i],
                2 => light[i] -= single[i],
                _ => {}
            }
            for j in 0..s {
                let k = j * w + i;
                rows_forward[k] = forward_segment[k] + share * (scaled[k] - scaled_segment[k]);
            }
            let (q, qx) = (s * w + i, (s + 1) * w + i);
            rows_forward[q] = forward[q];
            rows_forward[qx] = forward[qx];
            rows_behind[q] = forward[q] - forward_segment[q];
            rows_behind[qx] = (forward[qx] - forward_segment[qx]) - depth * rows_behind[q];
        }
        #[cfg(test)]
        let skip_peak = MARCH_PART.load(std::sync::atomic::Ordering::Relaxed) == 1;
        #[cfg(not(test))]
        let skip_peak = false;
        if src.has_forward_peaks && !skip_peak {
            let peak = tables.peak_radiance(theta, &smooth_phase, &rows_forward);
            let hidden = tables.peak_radiance(theta, &smooth_phase, &rows_behind);
            for i in 0..w {
                light[i] += peak[i] - hidden[i];
            }
        }
        let (through, solar) = (to_xyz(&transmitted), to_xyz(&src.solar));
        (
            to_xyz(&light),
            std::array::from_fn(|c| (through[c] / solar[c].max(1e-300)).clamp(0.0, 1.0)),
        )
    }
}

/// The march's k-th of `steps` nodes along a stretch of `length` m: its
/// distance from the stretch's start and its weight, m (the midpoint rule
/// in u = sqrt(s / length): crowded toward the start).
pub(crate) fn march_node(length: f64, k: usize, steps: usize) -> (f64, f64) {
    let u = (k as f64 + 0.5) / steps as f64;
    (u * u * length, 2.0 * u * length / steps as f64)
}

impl MarchTables {
    /// The species' relative densities at `altitude_m` (linear).
    fn densities(&self, altitude_m: f64) -> Vec<f64> {
        let s = self.source.species;
        let x = (altitude_m / self.thickness_m).clamp(0.0, 1.0) * (DENSITY_NODES - 1) as f64;
        let (n, f) = axes::cell(x, 0, DENSITY_NODES - 2);
        (0..s)
            .map(|j| {
                let (a, b) = (
                    self.density[n * s + j] as f64,
                    self.density[(n + 1) * s + j] as f64,
                );
                a + (b - a) * f
            })
            .collect()
    }

    /// p_j and the smooth phase at the scattering angle `theta` (rad),
    /// [j * wavelengths + i] (linear in u = sqrt(theta / pi)).
    fn phases(&self, theta: f64) -> (Vec<f64>, Vec<f64>) {
        let (w, s) = (self.source.wavelengths, self.source.species);
        let x = (theta / std::f64::consts::PI).clamp(0.0, 1.0).sqrt() * (PHASE_NODES - 1) as f64;
        let (t, f) = axes::cell(x, 0, PHASE_NODES - 2);
        let read = |table: &[f32]| -> Vec<f64> {
            let mut out = vec![0.0; s * w];
            for j in 0..s {
                for i in 0..w {
                    let a = table[(j * PHASE_NODES + t) * w + i] as f64;
                    let b = table[(j * PHASE_NODES + t + 1) * w + i] as f64;
                    out[j * w + i] = a + (b - a) * f;
                }
            }
            out
        };
        (read(&self.phase), read(&self.smooth_phase))
    }

    /// ln R at a node (quadrilinear in ln R over altitude level, sun
    /// zenith node, view zenith and azimuth; the levels, sun nodes and
    /// azimuths located in their arrays), into `out`.
    fn log_source(
        &self,
        altitude_m: f64,
        sun_cosine: f64,
        view_cosine: f64,
        cos_azimuth: f64,
        out: &mut [f64],
    ) {
        let src = &self.source;
        let kept = &self.source_wavelengths;
        let mut channels = vec![0.0; kept.len()];
        interpolate_log_source(
            &src.log_source,
            (
                src.sun_zenith_rad.len(),
                src.azimuth_nodes,
                src.view_zenith_nodes,
            ),
            (
                locate(&src.levels_m, altitude_m),
                self.locate_sun(sun_cosine),
                self.locate_azimuth(cos_azimuth),
            ),
            view_cosine,
            &mut channels,
        );
        // Linear in the wavelength's index between the kept ones.
        for pair in 0..kept.len().saturating_sub(1) {
            let (a, b) = (kept[pair], kept[pair + 1]);
            for (i, o) in out.iter_mut().enumerate().take(b + 1).skip(a) {
                let t = (i - a) as f64 / (b - a) as f64;
                *o = channels[pair] + t * (channels[pair + 1] - channels[pair]);
            }
        }
        if kept.len() == 1 {
            out.fill(channels[0]);
        }
    }

    /// The azimuth cell of the cosine of an azimuth from the sun: (node,
    /// fraction) among the source's azimuths, as the library's march reads
    /// its table ([`azimuth_cell`]).
    fn locate_azimuth(&self, cos_azimuth: f64) -> (usize, f64) {
        azimuth_cell(&self.source.azimuths_rad, cos_azimuth)
    }

    /// The sun zenith cell of a sun cosine: (node, fraction), linear in
    /// the angle.
    fn locate_sun(&self, sun_cosine: f64) -> (usize, f64) {
        locate(
            &self.source.sun_zenith_rad,
            sun_cosine.clamp(-1.0, 1.0).acos(),
        )
    }

    /// The species' columns toward the sun from radius `r` with the sun's
    /// zenith cosine `mu` there (bilinear over the transmittance table's
    /// axes), None below the point's horizon (the planet's shadow).
    fn sun_columns(&self, r: f64, mu: f64) -> Option<Vec<f64>> {
        let (ground, thickness) = (self.ground_radius_m, self.thickness_m);
        let s = self.source.species;
        let (a_count, m_count) = super::march::sun_column_nodes();
        let h = (r - ground).clamp(0.0, thickness);
        if mu < axes::horizon_cosine(ground + h, ground) {
            return None;
        }
        #[cfg(test)]
        let mode = SUN_COLUMNS_MODE.load(std::sync::atomic::Ordering::Relaxed);
        #[cfg(test)]
        if mode == 1 {
            let mu = mu.max(axes::horizon_cosine(ground + h, ground) + 1e-9);
            let direction = Vector3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            return Some(super::march::columns_to_top(
                &self.source,
                (ground, ground + thickness),
                ground + h,
                direction,
            ));
        }
        #[cfg(not(test))]
        let mode = 0;
        let lerp = |p: f64, q: f64, f: f64| {
            if mode == 2 && p > 0.0 && q > 0.0 {
                (p.ln() + (q.ln() - p.ln()) * f).exp()
            } else {
                p + (q - p) * f
            }
        };
        let (a, fa) = axes::cell(
            axes::altitude_coordinate(h, thickness, a_count),
            0,
            a_count - 2,
        );
        let row = |a: usize| -> Vec<f64> {
            let r_a = ground + axes::altitude_of_node(a, a_count, thickness);
            let (m, fm) = axes::cell(
                axes::transmittance_mu_coordinate(mu, m_count, r_a, ground),
                0,
                m_count - 2,
            );
            (0..s)
                .map(|j| {
                    let (p, q) = (
                        self.sun_columns[(a * m_count + m) * s + j] as f64,
                        self.sun_columns[(a * m_count + m + 1) * s + j] as f64,
                    );
                    lerp(p, q, fm)
                })
                .collect()
        };
        let (low, high) = (row(a), row(a + 1));
        Some((0..s).map(|j| lerp(low[j], high[j], fa)).collect())
    }

    /// The peak beam B at radius `r` with the sun's zenith cosine `mu`
    /// into `out`, and the share the scaled beam takes (0 beyond the
    /// table's elevations; `peak_beam.rs`).
    fn peak_beam(&self, ground: f64, r: f64, mu: f64, out: &mut [f64]) -> f64 {
        let Some(beam) = self.beam() else {
            return 0.0;
        };
        let elevation = mu.clamp(-1.0, 1.0).asin().to_degrees();
        let (lowest, blend, highest) = beam.range_deg;
        if !(lowest..highest).contains(&elevation) {
            return 0.0;
        }
        let share = ((highest - elevation) / (highest - blend)).min(1.0);
        let altitudes = &beam.altitudes_m;
        let z = (r - ground).clamp(0.0, altitudes[altitudes.len() - 1]);
        let (a, ta) = locate(altitudes, z);
        let xe = ((elevation - beam.first_elevation_deg) / beam.step_deg)
            .clamp(0.0, (beam.elevations - 1) as f64);
        let e = (xe as usize).min(beam.elevations - 2);
        let te = xe - e as f64;
        let w = self.source.wavelengths;
        let at = |a: usize, e: usize| &beam.ln_beam[(a * beam.elevations + e) * w..][..w];
        let (c00, c01, c10, c11) = (at(a, e), at(a, e + 1), at(a + 1, e), at(a + 1, e + 1));
        for (i, o) in out.iter_mut().enumerate() {
            *o = ((1.0 - ta) * ((1.0 - te) * c00[i] + te * c01[i])
                + ta * ((1.0 - te) * c10[i] + te * c11[i]))
                .exp();
        }
        share
    }

    /// The forward-peak term (W m^-2 sr^-1 nm^-1) at the scattering angle
    /// `theta` from its integrals `rows` (species rows, then Q and Q X),
    /// as `forward_peak.rs` evaluates it: E beta_sca,j q_j row_j summed
    /// over species (q_j the smooth phase `smooth`), plus within the
    /// kernel's radius (1 - wide) E Q e^(-X) G(theta; X) e^X at X = Q X /
    /// Q (bilinear in sqrt(theta / R) and X).
    fn peak_radiance(&self, theta: f64, smooth: &[f64], rows: &[f64]) -> Vec<f64> {
        let src = &self.source;
        let (w, s) = (src.wavelengths, src.species);
        let mut out = vec![0.0; w];
        for j in 0..s {
            for i in 0..w {
                out[i] +=
                    src.solar[i] * src.scattering[i * s + j] * smooth[j * w + i] * rows[j * w + i];
            }
        }
        let (x_nodes, angles, (start, radius), kernel) = &src.kernel;
        if kernel.is_empty() || theta >= *radius {
            return out;
        }
        let wide = ((theta - start) / (radius - start)).clamp(0.0, 1.0);
        let position = (theta / radius).sqrt() * (angles - 1) as f64;
        let t = (position as usize).min(angles - 2);
        let ft = position - t as f64;
        let last = x_nodes[x_nodes.len() - 1];
        for i in 0..w {
            let (q, qx) = (rows[s * w + i], rows[(s + 1) * w + i]);
            if q <= 0.0 {
                continue;
            }
            let x_mean = (qx / q).clamp(0.0, last);
            let upper = x_nodes
                .partition_point(|x| *x <= x_mean)
                .clamp(1, x_nodes.len() - 1);
            let fx = (x_mean - x_nodes[upper - 1]) / (x_nodes[upper] - x_nodes[upper - 1]);
            let at = |x: usize, t: usize| kernel[(x * angles + t) * w + i];
            let value = (1.0 - fx) * ((1.0 - ft) * at(upper - 1, t) + ft * at(upper - 1, t + 1))
                + fx * ((1.0 - ft) * at(upper, t) + ft * at(upper, t + 1));
            out[i] += (1.0 - wide) * src.solar[i] * q * value * x_mean.exp();
        }
        out
    }
}

/// The cell of ascending `nodes` holding `x` and the fraction of the way
/// across it (clamped to the nodes).
fn locate(nodes: &[f64], x: f64) -> (usize, f64) {
    let upper = nodes.partition_point(|z| *z <= x);
    let k = upper.clamp(1, nodes.len() - 1) - 1;
    (
        k,
        ((x - nodes[k]) / (nodes[k + 1] - nodes[k])).clamp(0.0, 1.0),
    )
}
