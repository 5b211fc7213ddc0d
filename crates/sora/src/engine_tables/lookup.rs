//! Reading the engine tables: the formulas the reference shaders
//! (`web/shaders/`) run, here in f64 so that tests can hold the tables to
//! the library and the shaders to these.
//!
//! - Sky: at the eye's altitude h, the view's zenith coordinate is taken
//!   with the eye's own horizon (`axes::zenith_coordinate`) and used on
//!   every altitude layer; bilinear in (zenith, azimuth) within a layer,
//!   linear between the two altitude layers, and geometric (linear in the
//!   logarithm, each value floored at [`FLOOR`]) between the two sun
//!   layers. Each sun layer is read at the view turned with the sun
//!   (about the horizontal axis across the sun's azimuth) from the sun's
//!   elevation e to the layer's e_j, by the share w of the step
//!   ([`turn_share`]): at w = 1 the view keeps its angle to the sun, so
//!   the aureole, which the sun axis's steps (8 degrees apart at e = 60)
//!   would otherwise interpolate between two places, stays where it is;
//!   at w = 0 the view keeps its zenith angle, which the horizon's band
//!   needs. w = 1 within 10 degrees of the sun and 0 beyond 40, 0 within
//!   5 degrees of the horizon (1 from 20 up), and 0 for suns above 85
//!   degrees (1 below 70), where the aureole reaches the zenith and the
//!   zenith axis's nodes (3 degrees apart there) are coarser than it
//!   (smoothstep ramps between). At a sun node the read is the layer's
//!   own.
//! - Transmittance: linear in altitude between two rows, each read
//!   linearly at the mu coordinate of its own altitude's horizon; zero
//!   for a view below the eye's horizon.
//! - Irradiance: linear in altitude, geometric in sun elevation, plus the
//!   direct beam `E_sun T(h, sin e) sin e` (zero below the horizon).
//! - Sun disc: `E_sun T(h, mu_sun) (1 - u (1 - cos a)) / (pi alpha^2 (1 - u / 3))`
//!   within the sun's angular radius alpha, with cos a = sqrt(1 - (gamma
//!   / alpha)^2) (limb darkening u = 0.6, as `sky/sun_disc.rs`).
//! - Aerial perspective: `S(x, v) R(x, v, d) w` per channel, S the sky
//!   read at the eye, R the aerial table read as the sky table (its own
//!   view nodes) and linear in ln d between its two distance slices (d
//!   from the thickness / 1000 to the ray's end), w = (1 - T) / (1 -
//!   T_end) from the transmittance table (see the module docs of
//!   `engine_tables`).

use super::EngineTables;
use super::axes;

/// Smallest value the sun axis's geometric interpolation takes the
/// logarithm of (XYZ in W m^-2 sr^-1 nm^-1 units).
pub const FLOOR: f64 = 1e-30;

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
    smoothstep(
        40f64.to_radians().cos(),
        10f64.to_radians().cos(),
        cos_theta,
    ) * (1.0 - smoothstep(horizon - 20f64.to_radians(), horizon - 5f64.to_radians(), z))
        * (1.0 - smoothstep(70.0, 85.0, e_deg))
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
/// `(y, lowest, highest)` and relative azimuth `phi`: bilinear.
fn layer_value_at(
    table: LayerTable<'_>,
    slice: usize,
    (y, lowest, highest): (f64, usize, usize),
    phi: f64,
) -> [f64; 3] {
    let k_count = table.azimuth;
    let (i, fy) = axes::cell(y, lowest, highest);
    let (k, fx) = axes::cell(axes::azimuth_coordinate(phi, k_count), 0, k_count - 2);
    let texel = |row: usize, column: usize| {
        let t = table.texels[(slice * 2 * table.half + row) * k_count + column];
        [t[0] as f64, t[1] as f64, t[2] as f64]
    };
    mix(
        mix(texel(i, k), texel(i, k + 1), fx),
        mix(texel(i + 1, k), texel(i + 1, k + 1), fx),
        fy,
    )
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
    pub azimuth: usize,
    pub slices: usize,
}

impl EngineTables {
    pub(crate) fn sky_layers_table(&self) -> LayerTable<'_> {
        LayerTable {
            texels: &self.sky,
            half: self.settings.zenith_nodes_per_half,
            azimuth: self.settings.azimuth_nodes,
            slices: 1,
        }
    }

    pub(crate) fn aerial_layers_table(&self) -> LayerTable<'_> {
        let (half, azimuth, slices) = self.settings.aerial_nodes;
        LayerTable {
            texels: &self.aerial,
            half,
            azimuth,
            slices,
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
        let coordinate = axes::zenith_coordinate(zenith, table.half, horizon);
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
    /// layer, linear in altitude, geometric in the sun's elevation, each
    /// sun layer read at the view turned with the sun).
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
        let share = turn_share(view, e_deg, horizon);
        let layer = |s: usize| {
            let node_deg = axes::sun_elevation_of_node(s, self.settings.sun_nodes);
            let turned = turned_view(view, (node_deg - e_deg).to_radians() * share, horizon);
            let coordinate = axes::zenith_coordinate(turned.zenith_rad, table.half, horizon);
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
            mix(at(a), at(a + 1), fa)
        };
        mix_log(layer(s), layer(s + 1), fs)
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
    /// from the irradiance table and the direct beam.
    pub fn ground_irradiance_xyz(&self, altitude_m: f64, sun_elevation_deg: f64) -> [f64; 3] {
        let h = altitude_m.clamp(0.0, self.thickness_m());
        let s_count = self.settings.sun_nodes;
        let ((a, fa), (s, fs)) = self.altitude_and_sun_cells(h, sun_elevation_deg);
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
    /// XYZ radiance; the segment's transmittance, XYZ of the sun's
    /// spectrum). The light is `S(x, v) R(x, v, d) w` per channel, S the
    /// sky table's read at the eye, R the aerial-perspective table's and w
    /// the segment's share of the whole ray's extinction
    /// ((1 - T) / (1 - T_end), T_end to the ray's end; see the module docs of
    /// `engine_tables`); tables baked without an aerial-perspective table
    /// take [`Self::aerial_perspective_by_difference_xyz`].
    pub fn aerial_perspective_xyz(
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
        let sky = self.sky_xyz(altitude_m, local, e);
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
