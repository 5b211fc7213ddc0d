// sora engine tables: reference reader, WGSL (WebGPU).
//
// The same formulas as sora_sky.glsl (and crates/sora/src/engine_tables/
// lookup.rs); table reads by textureLoad only. Bind (docs/engine-tables.md):
//   group(0) binding(0) sky: texture_2d_array<f32>, sky.exr, layer = s * A + a
//   group(0) binding(1) transmittance: texture_2d<f32>, transmittance.exr
//   group(0) binding(2) irradiance: texture_2d<f32>, irradiance.exr (its height
//   the irradiance table's own altitude nodes)
//   group(0) binding(3) params: SoraTables (values from manifest.json)
//   group(0) binding(4) aerial: texture_2d_array<f32>, aerial.exr, layer = s * A + a,
//                       its distance slices one above another in each layer
// Textures rgba32float (unfilterable is fine), holding X, Y, Z.

struct SoraTables {
  // sun_nodes, altitude_nodes, zenith_nodes_per_half, azimuth_nodes
  sky_nodes: vec4<i32>,
  // transmittance altitude nodes, mu nodes, the sky's
  // zenith_fine_cells_per_half and zenith_wide_cells_per_half (each 0
  // where the manifest has none)
  transmittance_nodes: vec4<i32>,
  // ground_radius_m, top_radius_m, sun angular radius (rad), limb darkening
  planet_sun: vec4<f32>,
  // sun.irradiance_xyz_w_m2_nm, sun.axis_width_deg
  sun_irradiance_xyz_width: vec4<f32>,
  // aerial: zenith_nodes_per_half, azimuth_nodes, distance_nodes, unused
  aerial_nodes: vec4<i32>,
};

@group(0) @binding(0) var sora_sky: texture_2d_array<f32>;
@group(0) @binding(1) var sora_transmittance: texture_2d<f32>;
@group(0) @binding(2) var sora_irradiance: texture_2d<f32>;
@group(0) @binding(3) var<uniform> sora: SoraTables;
@group(0) @binding(4) var sora_aerial: texture_2d_array<f32>;

const SORA_PI: f32 = 3.14159265358979;
const SORA_FLOOR: f32 = 1e-30;

fn sora_asinh(x: f32) -> f32 { return sign(x) * log(abs(x) + sqrt(x * x + 1.0)); }

fn sora_sun_coordinate(e_deg: f32) -> f32 {
  let w = sora.sun_irradiance_xyz_width.w;
  let t0 = sora_asinh(-12.0 / w);
  let t1 = sora_asinh(90.0 / w);
  let t = sora_asinh(clamp(e_deg, -12.0, 90.0) / w);
  return clamp((t - t0) / (t1 - t0), 0.0, 1.0) * f32(sora.sky_nodes.x - 1);
}

fn sora_thickness() -> f32 { return sora.planet_sun.y - sora.planet_sun.x; }

// The altitude axis: ln(1 + h / h0) / ln(1 + 50), h0 = thickness / 50.
fn sora_altitude_coordinate(h: f32, nodes: i32) -> f32 {
  let x = clamp(h, 0.0, sora_thickness()) / (sora_thickness() / 50.0);
  return clamp(log(1.0 + x) / log(51.0), 0.0, 1.0) * f32(nodes - 1);
}

// Altitude (m) of node a of an axis of `nodes` nodes (axes::altitude_of_node).
fn sora_altitude_of_node(a: i32, nodes: i32) -> f32 {
  let h0 = sora_thickness() / 50.0;
  return min(h0 * (pow(51.0, f32(a) / f32(nodes - 1)) - 1.0), sora_thickness());
}

// Share (0..1) of altitude h between nodes a and a + 1, linear in h.
fn sora_altitude_share(h: f32, a: i32, nodes: i32) -> f32 {
  let h0 = sora_altitude_of_node(a, nodes);
  let h1 = sora_altitude_of_node(a + 1, nodes);
  return clamp((h - h0) / (h1 - h0), 0.0, 1.0);
}

// Cell index and the upper node's weight of fractional index x.
struct SoraCell { i: i32, f: f32 };

fn sora_cell(x: f32, lowest: i32, highest: i32) -> SoraCell {
  let i = clamp(i32(floor(max(x, 0.0))), lowest, highest);
  return SoraCell(i, clamp(x - f32(i), 0.0, 1.0));
}

// Zenith node coordinate (0..half_nodes - 1, from the zenith or the
// nadir) of v = 1 - sqrt(1 - u) on an axis of half_nodes nodes per half
// with cells.x fine and cells.y wide cells next to the horizon
// (axes::zenith_coordinate): 2, 3 and 1 grid cells a coarse, wide and fine
// cell.
fn sora_zenith_node(v: f32, half_nodes: i32, cells: vec2<i32>) -> f32 {
  let fine = min(cells.x, half_nodes - 1);
  let wide = min(cells.y, half_nodes - 1 - fine);
  let c = f32(half_nodes - 1 - fine - wide);
  let w = f32(wide);
  let j = v * f32(2 * (half_nodes - 1) - fine + wide);
  let outer = select(j - c - 2.0 * w, c + (j - 2.0 * c) / 3.0, j <= 2.0 * c + 3.0 * w);
  return select(outer, 0.5 * j, j <= 2.0 * c);
}

// The zenith axis's cell for an eye at radius r on an axis of half_nodes
// nodes per half with cells.x fine and cells.y wide cells (never across
// the horizon).
fn sora_zenith_cell(zenith: f32, r: f32, half_nodes: i32, cells: vec2<i32>) -> SoraCell {
  let zh = SORA_PI - asin(min(sora.planet_sun.x / r, 1.0));
  if (zenith < zh) {
    let u = clamp(zenith / (zh - 1e-6), 0.0, 1.0);
    return sora_cell(sora_zenith_node(1.0 - sqrt(1.0 - u), half_nodes, cells), 0, half_nodes - 2);
  }
  let u = clamp((SORA_PI - zenith) / (SORA_PI - zh - 1e-6), 0.0, 1.0);
  return sora_cell(f32(2 * half_nodes - 1) - sora_zenith_node(1.0 - sqrt(1.0 - u), half_nodes, cells), half_nodes, 2 * half_nodes - 2);
}

// Zenith cells of the sky table, from the zenith, read by the cubic in
// ln L (lookup.rs ZENITH_CAP_CELLS).
const SORA_ZENITH_CAP_CELLS: i32 = 16;

// The uniform Catmull-Rom cubic in ln L (each value floored at SORA_FLOOR)
// between p0 (t = 0) and p1 (t = 1), m and n the nodes before and after
// (as soraCatmullRomLog in sora_sky.glsl; lookup.rs catmull_rom_log).
fn sora_catmull_rom_log(m: vec3<f32>, p0: vec3<f32>, p1: vec3<f32>, n: vec3<f32>, t: f32) -> vec3<f32> {
  let lm = log(max(m, vec3<f32>(SORA_FLOOR)));
  let a = log(max(p0, vec3<f32>(SORA_FLOOR)));
  let b = log(max(p1, vec3<f32>(SORA_FLOOR)));
  let ln = log(max(n, vec3<f32>(SORA_FLOOR)));
  let cubic = -lm + 3.0 * a - 3.0 * b + ln;
  let square = 2.0 * lm - 5.0 * a + 4.0 * b - ln;
  return exp(a + 0.5 * t * ((b - lm) + t * (square + t * cubic)));
}

// Row `row` of a layer of `table`, linear between azimuth nodes k.i and k.i + 1.
fn sora_row(table: texture_2d_array<f32>, layer: i32, row: i32, k: SoraCell) -> vec3<f32> {
  return mix(textureLoad(table, vec2<i32>(k.i, row), layer, 0).xyz,
             textureLoad(table, vec2<i32>(k.i + 1, row), layer, 0).xyz, k.f);
}

// Read of the slice whose first row is row0 of a layer of `table` in zenith
// cell z and azimuth cell k: bilinear, but in the cells of the zenith cap
// (z.i < cap, of the upper half's zn nodes, and z.i + 2 < zn) the cubic in
// ln L through rows z.i - 1 .. z.i + 2, row -1 being row 1 at the opposite
// azimuth (its cell km) (as soraLayer in sora_sky.glsl).
fn sora_layer(table: texture_2d_array<f32>, layer: i32, row0: i32, z: SoraCell, k: SoraCell, km: SoraCell,
              cap: i32, zn: i32) -> vec3<f32> {
  let a = sora_row(table, layer, row0 + z.i, k);
  let b = sora_row(table, layer, row0 + z.i + 1, k);
  if (z.i < cap && z.i + 2 < zn) {
    var before = sora_row(table, layer, row0 + z.i - 1, k);
    if (z.i == 0) { before = sora_row(table, layer, row0 + 1, km); }
    return sora_catmull_rom_log(before, a, b, sora_row(table, layer, row0 + z.i + 2, k), z.f);
  }
  return mix(a, b, z.f);
}

fn sora_mix_log(a: vec3<f32>, b: vec3<f32>, f: f32) -> vec3<f32> {
  return exp(mix(log(max(a, vec3<f32>(SORA_FLOOR))), log(max(b, vec3<f32>(SORA_FLOOR))), f));
}

// Elevation (degrees) of sun node s: the inverse of sora_sun_coordinate.
fn sora_sun_elevation_of_node(s: i32) -> f32 {
  let w = sora.sun_irradiance_xyz_width.w;
  let t0 = sora_asinh(-12.0 / w);
  let t1 = sora_asinh(90.0 / w);
  let t = t0 + (t1 - t0) * f32(s) / f32(sora.sky_nodes.x - 1);
  return clamp(w * 0.5 * (exp(t) - exp(-t)), -12.0, 90.0);
}

// The view (zenith, phi) turned by delta (rad) about the horizontal axis
// across the sun's azimuth, as the sun is turned to a sun node's
// elevation (keeping the scattering angle), on its side of the horizon zh.
fn sora_turned_view(zenith: f32, phi: f32, delta: f32, zh: f32) -> vec2<f32> {
  if (delta == 0.0) { return vec2<f32>(zenith, phi); }
  let sz = sin(zenith);
  let v = vec3<f32>(sz * cos(phi), sz * sin(phi), cos(zenith));
  let c = cos(delta);
  let s = sin(delta);
  let x = v.x * c - v.z * s;
  var turned = acos(clamp(v.x * s + v.z * c, -1.0, 1.0));
  if (zenith < zh) { turned = min(turned, zh - 2e-6); } else { turned = max(turned, zh); }
  return vec2<f32>(turned, atan2(abs(v.y), x));
}

// Share of the sun's step the view is turned by: 1 within 10 degrees of
// the sun, 0 beyond 40 (1 everywhere for suns above 68 degrees, ramping
// from 55); 0 within 5 degrees of the horizon, 1 from 20 up; or, for
// suns below 2 degrees (0 above 6), 1 within 40 degrees of the antisolar
// point, 0 beyond 80, horizon included (the planet's shadow turns with
// it; smoothstep ramps).
fn sora_turn_share(zenith: f32, phi: f32, e_deg: f32, zh: f32) -> f32 {
  let e = radians(e_deg);
  let cos_theta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  // For a high sun the whole sky (lookup.rs's HIGH_SUN_DEG, 55 to 68).
  let sun_side = max(smoothstep(cos(radians(40.0)), cos(radians(10.0)), cos_theta), smoothstep(55.0, 68.0, e_deg))
    * (1.0 - smoothstep(zh - radians(20.0), zh - radians(5.0), zenith));
  let shadow = smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cos_theta)
    * (1.0 - smoothstep(2.0, 6.0, e_deg));
  return max(sun_side, shadow);
}

// The share of the read near the antisolar point with the sun below the
// horizon that takes the sun layers below the horizon only (as
// soraShadowReadShare in sora_sky.glsl; lookup.rs shadow_read_share).
const SORA_SHADOW_RAMP: f32 = 2.5;
fn sora_shadow_read_share(zenith: f32, phi: f32, e_deg: f32, zh: f32) -> f32 {
  if (e_deg >= 0.0) { return 0.0; }
  let e = radians(e_deg);
  let cos_theta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  return smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cos_theta)
    * (1.0 - smoothstep(-e, -SORA_SHADOW_RAMP * e, zh - zenith));
}

// ln L of layer `low` (and low + 1, the altitude node above: above the
// eye's horizon ln L blended by a_h, the share linear in the altitude;
// below it L by a_f, the altitude coordinate's) of a
// layer table toward `view` (zenith, phi), slices row0 and row1 by fj; its
// first `cap` zenith cells read by the cubic (sora_layer).
fn sora_layer_log(table: texture_2d_array<f32>, zn: i32, zf: vec2<i32>, kn: i32, cap: i32, low: i32, a_f: f32, a_h: f32,
                  row0: i32, row1: i32, fj: f32, view: vec2<f32>, r: f32) -> vec3<f32> {
  let z = sora_zenith_cell(view.x, r, zn, zf);
  let k = sora_cell(sqrt(clamp(view.y / SORA_PI, 0.0, 1.0)) * f32(kn - 1), 0, kn - 2);
  let km = sora_cell(sqrt(clamp(1.0 - view.y / SORA_PI, 0.0, 1.0)) * f32(kn - 1), 0, kn - 2);
  let ground = mix(sora_layer(table, low, row0, z, k, km, cap, zn), sora_layer(table, low, row1, z, k, km, cap, zn), fj);
  let above = mix(sora_layer(table, low + 1, row0, z, k, km, cap, zn), sora_layer(table, low + 1, row1, z, k, km, cap, zn), fj);
  let zh = SORA_PI - asin(min(sora.planet_sun.x / r, 1.0));
  if (view.x < zh) {
    return mix(log(max(ground, vec3<f32>(SORA_FLOOR))), log(max(above, vec3<f32>(SORA_FLOOR))), a_h);
  }
  return log(max(mix(ground, above, a_f), vec3<f32>(SORA_FLOOR)));
}

// A layer table (the sky, or the aerial-perspective table with zn zenith
// nodes per half, kn azimuth nodes, its distance slices j and j + 1
// blended by fj) at altitude h (m) toward zenith angle `zenith` and
// azimuth `phi` from the sun's (rad), sun at e_deg: bilinear in a layer,
// between the altitude layers as sora_layer_log, in ln L between the sun layers (the chord less the
// curvature of the four nearest), each read at the view turned with the
// sun to its node.
fn sora_layers_xyz(table: texture_2d_array<f32>, zn: i32, zf: vec2<i32>, kn: i32, cap: i32, j: i32, fj: f32,
                   h_in: f32, zenith: f32, phi: f32, e_in: f32) -> vec3<f32> {
  let h = clamp(h_in, 0.0, sora_thickness());
  let r = sora.planet_sun.x + h;
  let zh = SORA_PI - asin(min(sora.planet_sun.x / r, 1.0));
  let e_deg = clamp(e_in, -12.0, 90.0);
  let an = sora.sky_nodes.y;
  let a = sora_cell(sora_altitude_coordinate(h, an), 0, an - 2);
  let a_h = sora_altitude_share(h, a.i, an);
  let s = sora_cell(sora_sun_coordinate(e_deg), 0, sora.sky_nodes.x - 2);
  let share = sora_turn_share(zenith, phi, e_deg, zh);
  let row0 = 2 * zn * j;
  var row1 = row0;
  if (fj > 0.0) { row1 = row0 + 2 * zn; }
  // ln L of sun layers s - 1 .. s + 2 (clamped to the axis).
  var layers: array<vec3<f32>, 4>;
  for (var m = 0; m < 4; m++) {
    let n = clamp(s.i + m - 1, 0, sora.sky_nodes.x - 1) - s.i;
    let view = sora_turned_view(zenith, phi, radians(sora_sun_elevation_of_node(s.i + n) - e_deg) * share, zh);
    let low = (s.i + n) * an + a.i;
    layers[m] = sora_layer_log(table, zn, zf, kn, cap, low, a.f, a_h, row0, row1, fj, view, r);
  }
  // The chord in ln L less its curvature: the second differences at nodes
  // s and s + 1 (zero at the axis's ends, each within +-1), blended.
  var d0 = vec3<f32>(0.0);
  var d1 = vec3<f32>(0.0);
  if (s.i > 0) { d0 = clamp(layers[0] - 2.0 * layers[1] + layers[2], vec3<f32>(-1.0), vec3<f32>(1.0)); }
  if (s.i + 2 < sora.sky_nodes.x) { d1 = clamp(layers[1] - 2.0 * layers[2] + layers[3], vec3<f32>(-1.0), vec3<f32>(1.0)); }
  var whole = mix(layers[1], layers[2], s.f) - 0.5 * s.f * (1.0 - s.f) * mix(d0, d1, s.f);
  // Below the planet's shadow's edge, the layers with the sun below the
  // horizon alone (the axis cut at the last of them, `top`; beyond it the
  // chord of the last two extended), blended in by sora_shadow_read_share.
  let top = i32(ceil(sora_sun_coordinate(0.0))) - 1;
  let below = sora_shadow_read_share(zenith, phi, e_deg, zh);
  if (below > 0.0 && top >= 1 && top + 1 < sora.sky_nodes.x && s.i + 2 > top && s.i <= top) {
    var shadow = mix(layers[1], layers[2], s.f) - 0.5 * s.f * (1.0 - s.f) * (1.0 - s.f) * d0;
    if (s.i == top) { shadow = mix(layers[0], layers[1], 1.0 + s.f); }
    whole = mix(whole, shadow, below);
  }
  return exp(whole);
}

// Sky radiance (XYZ, W m^-2 sr^-1 nm^-1) at altitude h (m) toward zenith
// angle `zenith` and azimuth `phi` from the sun's (rad), sun at e_deg. The
// sky table's read (lookup.rs's table_sky_xyz): the Rust lookup's sky_xyz
// for an eye on the ground or tables without the march's. For an eye above
// the ground with march tables sky_xyz is sora_raised_sky_xyz (below), a
// separate entry, so that a pipeline drawing an eye on the ground compiles
// no march (as in sora_sky.glsl).
fn sora_sky_xyz(h_in: f32, zenith: f32, phi: f32, e_in: f32) -> vec3<f32> {
  return sora_layers_xyz(sora_sky, sora.sky_nodes.z, sora.transmittance_nodes.zw, sora.sky_nodes.w, SORA_ZENITH_CAP_CELLS, 0, 0.0, h_in, zenith, phi, e_in);
}

fn sora_horizon_cosine(r: f32) -> f32 {
  let q = min(sora.planet_sun.x / r, 1.0);
  return -sqrt(max(1.0 - q * q, 0.0));
}

fn sora_transmittance_texel(m: i32, a: i32) -> vec3<f32> {
  return textureLoad(sora_transmittance, vec2<i32>(m, a), 0).xyz;
}

// Transmittance from altitude h to the top along view cosine mu.
fn sora_transmittance_xyz(h_in: f32, mu: f32) -> vec3<f32> {
  let h = clamp(h_in, 0.0, sora_thickness());
  let r = sora.planet_sun.x + h;
  let mu_h = sora_horizon_cosine(r);
  if (mu < mu_h) { return vec3<f32>(0.0); }
  let an = sora.transmittance_nodes.x;
  let mn = sora.transmittance_nodes.y;
  let a = sora_cell(sora_altitude_coordinate(h, an), 0, an - 2);
  // Each row at the view cosine's coordinate for its own altitude's horizon.
  let h0 = sora_thickness() / 50.0;
  let mu_a = sora_horizon_cosine(sora.planet_sun.x + h0 * (exp(f32(a.i) / f32(an - 1) * log(51.0)) - 1.0));
  let mu_b = sora_horizon_cosine(sora.planet_sun.x + h0 * (exp(f32(a.i + 1) / f32(an - 1) * log(51.0)) - 1.0));
  let m = sora_cell(sqrt(clamp((mu - mu_a) / (1.0 - mu_a), 0.0, 1.0)) * f32(mn - 1), 0, mn - 2);
  let n = sora_cell(sqrt(clamp((mu - mu_b) / (1.0 - mu_b), 0.0, 1.0)) * f32(mn - 1), 0, mn - 2);
  let t0 = mix(sora_transmittance_texel(m.i, a.i), sora_transmittance_texel(m.i + 1, a.i), m.f);
  let t1 = mix(sora_transmittance_texel(n.i, a.i + 1), sora_transmittance_texel(n.i + 1, a.i + 1), n.f);
  return mix(t0, t1, a.f);
}

fn sora_irradiance_texel(s: i32, a: i32) -> vec3<f32> {
  return textureLoad(sora_irradiance, vec2<i32>(s, a), 0).xyz;
}

// Global horizontal irradiance (XYZ, W m^-2 nm^-1) at altitude h, sun at e_deg.
// The irradiance table has its own altitude axis (the same mapping, its
// height's nodes: manifest tables.irradiance.altitude_nodes).
fn sora_ground_irradiance_xyz(h_in: f32, e_deg: f32) -> vec3<f32> {
  let h = clamp(h_in, 0.0, sora_thickness());
  let an = i32(textureDimensions(sora_irradiance, 0).y);
  let a = sora_cell(sora_altitude_coordinate(h, an), 0, an - 2);
  let s = sora_cell(sora_sun_coordinate(e_deg), 0, sora.sky_nodes.x - 2);
  let low = mix(sora_irradiance_texel(s.i, a.i), sora_irradiance_texel(s.i, a.i + 1), a.f);
  let high = mix(sora_irradiance_texel(s.i + 1, a.i), sora_irradiance_texel(s.i + 1, a.i + 1), a.f);
  let mu_sun = sin(radians(e_deg));
  return sora_mix_log(low, high, s.f)
    + sora.sun_irradiance_xyz_width.xyz * sora_transmittance_xyz(h, mu_sun) * max(mu_sun, 0.0);
}

// The sun disc's radiance at angle gamma (rad) from its centre.
fn sora_sun_disc_xyz(h: f32, e_deg: f32, gamma: f32) -> vec3<f32> {
  let alpha = sora.planet_sun.z;
  if (gamma >= alpha) { return vec3<f32>(0.0); }
  let u = sora.planet_sun.w;
  let cos_a = sqrt(max(1.0 - (gamma / alpha) * (gamma / alpha), 0.0));
  let shape = (1.0 - u * (1.0 - cos_a)) / (SORA_PI * alpha * alpha * (1.0 - u / 3.0));
  return sora.sun_irradiance_xyz_width.xyz * sora_transmittance_xyz(h, sin(radians(e_deg))) * shape;
}

// Zenith angle and azimuth from the sun's of v seen where `up` is vertical.
fn sora_local_view(v: vec3<f32>, up: vec3<f32>, sun: vec3<f32>) -> vec2<f32> {
  let mu = clamp(dot(v, up), -1.0, 1.0);
  let vh = v - up * mu;
  let sh = sun - up * dot(sun, up);
  let nv = length(vh);
  let ns = length(sh);
  var cos_phi = 1.0;
  if (nv > 1e-6 && ns > 1e-6) { cos_phi = clamp(dot(vh, sh) / (nv * ns), -1.0, 1.0); }
  return vec2<f32>(acos(mu), acos(cos_phi));
}

// The sun's elevation (degrees) from its direction in the eye's
// east-north-up frame: atan2(z, |xy|), not asin(z), which loses
// precision near the zenith (as soraSunElevationDeg in sora_sky.glsl).
fn sora_sun_elevation_deg(sun: vec3<f32>) -> f32 {
  return degrees(atan2(sun.z, length(sun.xy)));
}

// Sky radiance for an eye at altitude h along unit v, sun toward unit sun
// (east-north-up, z up). The table's read (sora_sky_xyz): the entry for an
// eye on the ground; for an eye above it sora_raised_sky_view (at the end
// of this file).
fn sora_sky_view(h: f32, v: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
  let zp = sora_local_view(v, vec3<f32>(0.0, 0.0, 1.0), sun);
  return sora_sky_xyz(h, zp.x, zp.y, sora_sun_elevation_deg(sun));
}

// Transmittance of the segment from the eye at altitude h to the point at
// distance d along v (a ratio of two transmittance reads; of the reversed
// rays when v meets the ground), each channel at most 1.
fn sora_segment_transmittance(h_in: f32, v: vec3<f32>, d: f32) -> vec3<f32> {
  let ground = sora.planet_sun.x;
  let h = clamp(h_in, 0.0, sora_thickness());
  let r = ground + h;
  let p = vec3<f32>(v.xy * d, r + v.z * d);
  let rp = length(p);
  let up_p = p / rp;
  let hp = clamp(rp - ground, 0.0, sora_thickness());
  let mu = v.z;
  let mu_p = dot(v, up_p);
  var near: vec3<f32>;
  var far: vec3<f32>;
  if (mu < sora_horizon_cosine(r)) {
    near = sora_transmittance_xyz(hp, -mu_p);
    far = sora_transmittance_xyz(h, -mu);
  } else {
    near = sora_transmittance_xyz(h, mu);
    far = sora_transmittance_xyz(hp, mu_p);
  }
  return min(near / max(far, vec3<f32>(SORA_FLOOR)), vec3<f32>(1.0));
}

// Length (m) of the ray from altitude h along view cosine mu to the ground
// (below the horizon) or the top of the atmosphere.
fn sora_ray_length(h: f32, mu: f32) -> f32 {
  let r = sora.planet_sun.x + clamp(h, 0.0, sora_thickness());
  let b = r * mu;
  let c = r * r;
  if (mu < sora_horizon_cosine(r)) {
    return max(-b - sqrt(max(b * b - c + sora.planet_sun.x * sora.planet_sun.x, 0.0)), 0.0);
  }
  return max(-b + sqrt(max(b * b - c + sora.planet_sun.y * sora.planet_sun.y, 0.0)), 0.0);
}

struct SoraAerial { inscattered: vec3<f32>, transmittance: vec3<f32> };

// Aerial perspective between the eye at altitude h and the point at
// distance d (m) along v: L = L_point * transmittance + inscattered, the
// light S(x, v) R(x, v, d) w per channel (S the sky, R the aerial table
// linear between its distance slices, spaced in ln d from thickness / 1000
// to the ray's end, w = (1 - T) / (1 - T_end)).
fn sora_aerial_perspective(h_in: f32, v: vec3<f32>, sun: vec3<f32>, d: f32) -> SoraAerial {
  // Tables without an aerial table (aerial_nodes zero): the sky's difference.
  if (sora.aerial_nodes.z < 2) { return sora_aerial_perspective_from_sky(h_in, v, sun, d); }
  let h = clamp(h_in, 0.0, sora_thickness());
  let t = sora_segment_transmittance(h, v, d);
  let length_ = sora_ray_length(h, v.z);
  let all_ = vec3<f32>(1.0) - sora_segment_transmittance(h, v, length_);
  let share = select(vec3<f32>(1.0), clamp((vec3<f32>(1.0) - t) / max(all_, vec3<f32>(1e-9)), vec3<f32>(0.0), vec3<f32>(1.0)), all_ > vec3<f32>(1e-9));
  let nearest = sora_thickness() / 1000.0;
  let last = max(length_, 2.0 * nearest);
  let dn = sora.aerial_nodes.z;
  let x = clamp(log(max(d, nearest) / nearest) / log(last / nearest), 0.0, 1.0) * f32(dn - 1);
  let j = sora_cell(x, 0, dn - 2);
  let zp = sora_local_view(v, vec3<f32>(0.0, 0.0, 1.0), sun);
  let e_deg = sora_sun_elevation_deg(sun);
  let sky = sora_sky_xyz(h, zp.x, zp.y, e_deg);
  let ratio = sora_layers_xyz(sora_aerial, sora.aerial_nodes.x, vec2<i32>(0, 0), sora.aerial_nodes.y, 0, j.i, j.f, h, zp.x, zp.y, e_deg);
  return SoraAerial(sky * ratio * share, t);
}

// The former aerial perspective from the sky table alone, S(x, v) - T S(p,
// v): no aerial table needed, but not within 2 % of the library for short
// segments (docs/engine-tables.md).
fn sora_aerial_perspective_from_sky(h_in: f32, v: vec3<f32>, sun: vec3<f32>, d: f32) -> SoraAerial {
  let ground = sora.planet_sun.x;
  let h = clamp(h_in, 0.0, sora_thickness());
  let p = vec3<f32>(v.xy * d, ground + h + v.z * d);
  let up_p = normalize(p);
  let hp = clamp(length(p) - ground, 0.0, sora_thickness());
  let t = sora_segment_transmittance(h, v, d);
  let at_eye = sora_sky_view(h, v, sun);
  let zp = sora_local_view(v, up_p, sun);
  let at_point = sora_sky_xyz(hp, zp.x, zp.y, degrees(asin(clamp(dot(sun, up_p), -1.0, 1.0))));
  return SoraAerial(max(at_eye - t * at_point, vec3<f32>(0.0)), t);
}

// Linear sRGB (Rec. 709, D65) of XYZ (manifest colour.linear_srgb_from_xyz).
fn sora_xyz_to_linear_srgb(xyz: vec3<f32>) -> vec3<f32> {
  return mat3x3<f32>(
    vec3<f32>(3.2406, -0.9689, 0.0557),
    vec3<f32>(-1.5372, 1.8758, -0.2040),
    vec3<f32>(-0.4986, 0.0415, 1.0570)) * xyz;
}

// ---------------------------------------------------------------------------
// The aerial-perspective march (march.bin; `sora tables --march`): the
// GLSL twin's soraAerialPerspectiveMarch and its helpers, which are
// crates/sora/src/engine_tables/lookup.rs's MarchTables::
// aerial_perspective_xyz step by step (same names). Bind
// (docs/engine-tables.md, "Binding the tables"):
//   group(0) binding(5) march: SoraMarch (values from tables.march)
//   group(0) binding(6) march_source: texture_2d_array<f32>, rgba16float:
//                       log_source, its channels four to a texel (the last
//                       padded), texel (v * T + c / 4, s * azimuth_nodes + f),
//                       layer k; T = ceil(channels / 4)
//   group(0) binding(7) march_tables: texture_2d<f32>, r32float,
//                       SORA_MARCH_WIDTH wide: every other (32-bit) array of
//                       march.bin in file order, value n at (n % width, n / width)

struct SoraMarch {
  // offsets[a / 4][a % 4], lengths[a / 4][a % 4]: the start (in values,
  // within march_tables) and length of array a (SORA_MARCH_* below)
  offsets: array<vec4<i32>, 5>,
  lengths: array<vec4<i32>, 5>,
  // wavelengths, species, sun_nodes, density_nodes (zero: no march tables)
  counts: vec4<i32>,
  // azimuth_nodes, view_zenith_nodes (of the source), phase_nodes, kernel_angles
  nodes: vec4<i32>,
  // sun_column_nodes (altitude A, view cosine M), beam_elevations, has_forward_peaks (0 or 1)
  columns_beam: vec4<i32>,
  // march_steps (along the segment, beyond the point), unused, unused
  steps: vec4<i32>,
  // kernel_blend_start_rad, kernel_radius_rad, beam_first_elevation_deg, beam_step_deg
  kernel_beam: vec4<f32>,
  // beam_range_deg (lowest, blend, highest), dark_log_source
  beam_range_dark: vec4<f32>,
};

@group(0) @binding(5) var<uniform> sora_march: SoraMarch;
@group(0) @binding(6) var sora_march_source: texture_2d_array<f32>;
@group(0) @binding(7) var sora_march_tables: texture_2d<f32>;

const SORA_MARCH_LEVELS: i32 = 0;            // source_levels_m
const SORA_MARCH_SUN_ZENITH: i32 = 1;        // source_sun_zenith_rad
const SORA_MARCH_CHANNELS: i32 = 2;          // source_wavelength_indices
const SORA_MARCH_EXTINCTION: i32 = 3;
const SORA_MARCH_SCALED_EXTINCTION: i32 = 4;
const SORA_MARCH_SCALED_SCATTERING: i32 = 5;
const SORA_MARCH_SCATTERING: i32 = 6;
const SORA_MARCH_SOLAR: i32 = 7;
const SORA_MARCH_XYZ: i32 = 8;
const SORA_MARCH_DENSITY: i32 = 9;
const SORA_MARCH_SUN_COLUMNS: i32 = 10;
const SORA_MARCH_PHASE: i32 = 11;
const SORA_MARCH_SMOOTH_PHASE: i32 = 12;
const SORA_MARCH_KERNEL_X: i32 = 13;
const SORA_MARCH_KERNEL: i32 = 14;
const SORA_MARCH_BEAM_ALTITUDES: i32 = 15;   // beam_altitudes_m
const SORA_MARCH_LN_BEAM: i32 = 16;
const SORA_MARCH_GROUND_DIFFUSE: i32 = 17;
const SORA_MARCH_GROUND_DIRECT: i32 = 18;
const SORA_MARCH_AZIMUTHS: i32 = 19;         // source_azimuth_rad
const SORA_MARCH_WIDTH: i32 = 2048;
// Capacities of the per-pixel arrays (the counts come from SoraMarch).
const SORA_MARCH_MAX_WAVELENGTHS: i32 = 32;
const SORA_MARCH_MAX_SPECIES: i32 = 4;
const SORA_MARCH_MAX_ROWS: i32 = 128;

alias SoraMarchSpecies = array<f32, 4>;
alias SoraMarchWavelengths = array<f32, 32>;
alias SoraMarchRows = array<f32, 128>;

// acos(c) as atan2, as the GLSL twin (SwiftShader's acos is coarse).
fn sora_march_acos(c: f32) -> f32 { return atan2(sqrt(max((1.0 - c) * (1.0 + c), 0.0)), c); }

fn sora_march_length(array_: i32) -> i32 { return sora_march.lengths[array_ / 4][array_ % 4]; }

// Value n of march.bin's array `array_`.
fn sora_march_value(array_: i32, n: i32) -> f32 {
  let at = sora_march.offsets[array_ / 4][array_ % 4] + n;
  return textureLoad(sora_march_tables, vec2<i32>(at % SORA_MARCH_WIDTH, at / SORA_MARCH_WIDTH), 0).x;
}

// The cell of the ascending array `array_` holding x (locate: a binary
// search for partition_point), clamped to the nodes.
fn sora_march_locate(array_: i32, x: f32) -> SoraCell {
  let count = sora_march_length(array_);
  var low = 0;
  var high = count;
  while (low < high) {
    let middle = (low + high) / 2;
    if (sora_march_value(array_, middle) <= x) { low = middle + 1; } else { high = middle; }
  }
  let k = clamp(low, 1, count - 1) - 1;
  let a = sora_march_value(array_, k);
  let b = sora_march_value(array_, k + 1);
  return SoraCell(k, clamp((x - a) / (b - a), 0.0, 1.0));
}

// Cosine of the horizon's zenith angle at altitude h (axes::horizon_cosine
// in float precision: 1 - (R / r)^2 = h (2 R + h) / r^2).
fn sora_march_horizon_cosine(h_in: f32) -> f32 {
  let ground = sora.planet_sun.x;
  let h = max(h_in, 0.0);
  return -sqrt(h * (2.0 * ground + h)) / (ground + h);
}

// Altitude (m) of node `index` of `nodes` (axes::altitude_of_node).
fn sora_march_altitude_of_node(index: i32, nodes: i32) -> f32 {
  let h0 = sora_thickness() / 50.0;
  return min(h0 * (exp(f32(index) / f32(nodes - 1) * log(51.0)) - 1.0), sora_thickness());
}

// The k-th of `steps` nodes along a stretch of length_ m: (distance from
// its start, weight), m (march_node).
fn sora_march_node(length_: f32, k: i32, steps: i32) -> vec2<f32> {
  let u = (f32(k) + 0.5) / f32(steps);
  return vec2<f32>(u * u * length_, 2.0 * u * length_ / f32(steps));
}

// The species' relative densities at altitude h (densities).
fn sora_march_densities(h: f32) -> SoraMarchSpecies {
  let s = sora_march.counts.y;
  let nodes = sora_march.counts.w;
  let c = sora_cell(clamp(h / sora_thickness(), 0.0, 1.0) * f32(nodes - 1), 0, nodes - 2);
  var rho: SoraMarchSpecies;
  for (var j = 0; j < s; j++) {
    let a = sora_march_value(SORA_MARCH_DENSITY, c.i * s + j);
    let b = sora_march_value(SORA_MARCH_DENSITY, (c.i + 1) * s + j);
    rho[j] = a + (b - a) * c.f;
  }
  return rho;
}

// p_j (table SORA_MARCH_PHASE) or the smooth phase (SORA_MARCH_SMOOTH_PHASE)
// at the scattering angle theta, [j * w + i] (phases: linear in u =
// sqrt(theta / pi)).
fn sora_march_phase(table: i32, theta: f32) -> SoraMarchRows {
  let w = sora_march.counts.x;
  let s = sora_march.counts.y;
  let p = sora_march.nodes.z;
  let c = sora_cell(sqrt(clamp(theta / SORA_PI, 0.0, 1.0)) * f32(p - 1), 0, p - 2);
  var out_: SoraMarchRows;
  for (var j = 0; j < s; j++) {
    for (var i = 0; i < w; i++) {
      let a = sora_march_value(table, (j * p + c.i) * w + i);
      let b = sora_march_value(table, (j * p + c.i + 1) * w + i);
      out_[j * w + i] = a + (b - a) * c.f;
    }
  }
  return out_;
}

// The sun zenith cell of a sun cosine (locate_sun: linear in the angle).
fn sora_march_locate_sun(sun_cosine: f32) -> SoraCell {
  return sora_march_locate(SORA_MARCH_SUN_ZENITH, sora_march_acos(clamp(sun_cosine, -1.0, 1.0)));
}

// The azimuth cell of the cosine of an azimuth from the sun
// (locate_azimuth): located by the angle among source_azimuth_rad, linear
// in the angle, but in the cosine within the first and the last cell (ln
// R is even in the azimuth about 0 and pi).
fn sora_march_locate_azimuth(cos_azimuth: f32) -> SoraCell {
  let c = clamp(cos_azimuth, -1.0, 1.0);
  var cell = sora_march_locate(SORA_MARCH_AZIMUTHS, sora_march_acos(c));
  if (cell.i == 0 || cell.i + 2 == sora_march_length(SORA_MARCH_AZIMUTHS)) {
    let a = cos(sora_march_value(SORA_MARCH_AZIMUTHS, cell.i));
    let b = cos(sora_march_value(SORA_MARCH_AZIMUTHS, cell.i + 1));
    cell.f = clamp((a - c) / (a - b), 0.0, 1.0);
  }
  return cell;
}

// ln R at a node at every wavelength, quadrilinear in ln R over altitude
// level, sun zenith node, view zenith and azimuth (source_azimuth_rad's
// nodes; log_source and
// interpolate_log_source), linear in the wavelength's index between the
// source's channels.
fn sora_march_log_source(altitude: f32, sun_cosine: f32, view_cosine: f32, cos_azimuth: f32) -> SoraMarchWavelengths {
  let w = sora_march.counts.x;
  let channel_count = sora_march_length(SORA_MARCH_CHANNELS);
  let texels = (channel_count + 3) / 4;
  let azimuths = sora_march.nodes.x;
  let views = sora_march.nodes.y;
  let k = sora_march_locate(SORA_MARCH_LEVELS, altitude);
  let s = sora_march_locate_sun(sun_cosine);
  let y = sora_march_acos(clamp(view_cosine, -1.0, 1.0)) / SORA_PI * f32(views - 1);
  let v = min(i32(y), views - 2);
  let tv = y - f32(v);
  let f = sora_march_locate_azimuth(cos_azimuth);
  var channels: SoraMarchWavelengths;
  for (var c4 = 0; c4 < texels; c4++) {
    var sum = vec4<f32>(0.0);
    for (var n = 0; n < 8; n++) {
      let kk = k.i + (n & 1);
      let ss = s.i + ((n >> 1u) & 1);
      let ff = f.i + (n >> 2u);
      let weight = select(1.0 - k.f, k.f, (n & 1) == 1) * select(1.0 - s.f, s.f, ((n >> 1u) & 1) == 1)
        * select(1.0 - f.f, f.f, (n >> 2u) == 1);
      let low = textureLoad(sora_march_source, vec2<i32>(v * texels + c4, ss * azimuths + ff), kk, 0);
      let high = textureLoad(sora_march_source, vec2<i32>((v + 1) * texels + c4, ss * azimuths + ff), kk, 0);
      sum += weight * (1.0 - tv) * low + weight * tv * high;
    }
    for (var n = 0; n < 4; n++) {
      if (4 * c4 + n < channel_count) { channels[4 * c4 + n] = sum[n]; }
    }
  }
  var log_source: SoraMarchWavelengths;
  if (channel_count == 1) {
    for (var i = 0; i < w; i++) { log_source[i] = channels[0]; }
    return log_source;
  }
  // Linear in the wavelength's index between the kept ones.
  for (var pair = 0; pair + 1 < channel_count; pair++) {
    let a = i32(sora_march_value(SORA_MARCH_CHANNELS, pair) + 0.5);
    let b = i32(sora_march_value(SORA_MARCH_CHANNELS, pair + 1) + 0.5);
    for (var i = a; i <= b; i++) {
      let t = f32(i - a) / f32(b - a);
      log_source[i] = channels[pair] + t * (channels[pair + 1] - channels[pair]);
    }
  }
  return log_source;
}

// The species' columns toward the sun from altitude h with the sun's
// zenith cosine mu there (sun_columns: bilinear over the transmittance
// table's axes); lit false below the point's horizon (the planet's shadow).
struct SoraMarchSunColumns { lit: bool, columns: SoraMarchSpecies };

fn sora_march_sun_columns(h_in: f32, mu: f32) -> SoraMarchSunColumns {
  let s = sora_march.counts.y;
  let a_count = sora_march.columns_beam.x;
  let m_count = sora_march.columns_beam.y;
  let h = clamp(h_in, 0.0, sora_thickness());
  var to_sun: SoraMarchSpecies;
  if (mu < sora_march_horizon_cosine(h)) { return SoraMarchSunColumns(false, to_sun); }
  let a = sora_cell(sora_altitude_coordinate(h, a_count), 0, a_count - 2);
  for (var row = 0; row < 2; row++) {
    let mu_h = sora_march_horizon_cosine(sora_march_altitude_of_node(a.i + row, a_count));
    let m = sora_cell(sqrt(clamp((mu - mu_h) / (1.0 - mu_h), 0.0, 1.0)) * f32(m_count - 1), 0, m_count - 2);
    let weight = select(a.f, 1.0 - a.f, row == 0);
    for (var j = 0; j < s; j++) {
      let p = sora_march_value(SORA_MARCH_SUN_COLUMNS, ((a.i + row) * m_count + m.i) * s + j);
      let q = sora_march_value(SORA_MARCH_SUN_COLUMNS, ((a.i + row) * m_count + m.i + 1) * s + j);
      to_sun[j] += weight * (p + (q - p) * m.f);
    }
  }
  return SoraMarchSunColumns(true, to_sun);
}

// The peak beam B at altitude h with the sun's zenith cosine mu, and the
// share the scaled beam takes (peak_beam: 0 beyond the table's elevations).
struct SoraMarchBeam { share: f32, beam: SoraMarchWavelengths };

fn sora_march_peak_beam(h: f32, mu: f32) -> SoraMarchBeam {
  var beam: SoraMarchWavelengths;
  let elevations = sora_march.columns_beam.z;
  if (elevations < 2) { return SoraMarchBeam(0.0, beam); }
  let elevation = degrees(atan2(clamp(mu, -1.0, 1.0), sqrt(max((1.0 - mu) * (1.0 + mu), 0.0))));
  let lowest = sora_march.beam_range_dark.x;
  let blend = sora_march.beam_range_dark.y;
  let highest = sora_march.beam_range_dark.z;
  if (!(elevation >= lowest && elevation < highest)) { return SoraMarchBeam(0.0, beam); }
  let share = min((highest - elevation) / (highest - blend), 1.0);
  let last = sora_march_length(SORA_MARCH_BEAM_ALTITUDES) - 1;
  let z = clamp(h, 0.0, sora_march_value(SORA_MARCH_BEAM_ALTITUDES, last));
  let a = sora_march_locate(SORA_MARCH_BEAM_ALTITUDES, z);
  let xe = clamp((elevation - sora_march.kernel_beam.z) / sora_march.kernel_beam.w, 0.0, f32(elevations - 1));
  let e = min(i32(xe), elevations - 2);
  let te = xe - f32(e);
  let w = sora_march.counts.x;
  for (var i = 0; i < w; i++) {
    let c00 = sora_march_value(SORA_MARCH_LN_BEAM, (a.i * elevations + e) * w + i);
    let c01 = sora_march_value(SORA_MARCH_LN_BEAM, (a.i * elevations + e + 1) * w + i);
    let c10 = sora_march_value(SORA_MARCH_LN_BEAM, ((a.i + 1) * elevations + e) * w + i);
    let c11 = sora_march_value(SORA_MARCH_LN_BEAM, ((a.i + 1) * elevations + e + 1) * w + i);
    beam[i] = exp((1.0 - a.f) * ((1.0 - te) * c00 + te * c01) + a.f * ((1.0 - te) * c10 + te * c11));
  }
  return SoraMarchBeam(share, beam);
}

// The forward-peak term at wavelength i and the scattering angle theta
// (peak_radiance): `rows` the species rows already summed with their
// weights beta_sca,j q_j, q and qx the peak-only rows Q and Q X.
fn sora_march_peak_radiance(theta: f32, i: i32, rows: f32, q: f32, qx: f32) -> f32 {
  let w = sora_march.counts.x;
  let solar = sora_march_value(SORA_MARCH_SOLAR, i);
  let out_ = solar * rows;
  let start = sora_march.kernel_beam.x;
  let radius = sora_march.kernel_beam.y;
  let angles = sora_march.nodes.w;
  let x_count = sora_march_length(SORA_MARCH_KERNEL_X);
  if (sora_march_length(SORA_MARCH_KERNEL) == 0 || theta >= radius || q <= 0.0) { return out_; }
  let wide = clamp((theta - start) / (radius - start), 0.0, 1.0);
  let position = sqrt(theta / radius) * f32(angles - 1);
  let t = min(i32(position), angles - 2);
  let ft = position - f32(t);
  let last = sora_march_value(SORA_MARCH_KERNEL_X, x_count - 1);
  let x_mean = clamp(qx / q, 0.0, last);
  let x = sora_march_locate(SORA_MARCH_KERNEL_X, x_mean);
  let k00 = sora_march_value(SORA_MARCH_KERNEL, (x.i * angles + t) * w + i);
  let k01 = sora_march_value(SORA_MARCH_KERNEL, (x.i * angles + t + 1) * w + i);
  let k10 = sora_march_value(SORA_MARCH_KERNEL, ((x.i + 1) * angles + t) * w + i);
  let k11 = sora_march_value(SORA_MARCH_KERNEL, ((x.i + 1) * angles + t + 1) * w + i);
  let value = (1.0 - x.f) * ((1.0 - ft) * k00 + ft * k01) + x.f * ((1.0 - ft) * k10 + ft * k11);
  return out_ + (1.0 - wide) * solar * q * value * exp(x_mean);
}

// The ground's light at wavelength i with the sun's zenith cosine at the
// ground point (ground_light's lerp: in ln where both nodes are positive).
fn sora_march_ground_light(i: i32, sun_cosine: f32) -> f32 {
  let w = sora_march.counts.x;
  let c = sora_march_locate_sun(sun_cosine);
  var light = 0.0;
  for (var table = SORA_MARCH_GROUND_DIFFUSE; table <= SORA_MARCH_GROUND_DIRECT; table++) {
    let a = sora_march_value(table, c.i * w + i);
    let b = sora_march_value(table, (c.i + 1) * w + i);
    light += select((1.0 - c.f) * a + c.f * b, exp((1.0 - c.f) * log(max(a, SORA_FLOOR)) + c.f * log(max(b, SORA_FLOOR))), a > 0.0 && b > 0.0);
  }
  return light;
}

// (altitude, radius) m of the point at distance t along unit v from the
// eye at altitude h, in float precision (|p|^2 - R^2 = t^2 + 2 r0 v.z t
// + h (2 R + h)).
fn sora_march_altitude_along(h: f32, v: vec3<f32>, t: f32) -> vec2<f32> {
  let ground = sora.planet_sun.x;
  let r0 = ground + h;
  let r = length(vec3<f32>(v.xy * t, r0 + v.z * t));
  return vec2<f32>(max((t * t + 2.0 * r0 * v.z * t + h * (2.0 * ground + h)) / (r + ground), 0.0), r);
}

// Aerial perspective by the march (soraAerialPerspectiveMarch; lookup.rs's
// MarchTables::aerial_perspective_xyz): an eye at altitude h, the unit view
// v and sun (east-north-up), a point at distance d (m); L = L_point *
// transmittance + inscattered, L_air = S_seg + F_seg + (1 - T / T*)
// (F_beyond + G_sky) + P(forward) - P(behind). As the GLSL twin, the
// forward-peak species rows are kept summed with their weights beta_sca,j
// q_j, and each row only where it is read.
//
// sora_march_xyz is lookup.rs's MarchTables::march_xyz: with `whole` false
// the above; with `whole` true (MarchTables::whole_ray_xyz, d the split)
// the nodes beyond d are counted as the segment's too, so that the light
// and the transmittance are the whole ray's, its nodes crowded toward the
// eye and toward d.
fn sora_aerial_perspective_march(h_in: f32, v: vec3<f32>, sun: vec3<f32>, d: f32) -> SoraAerial {
  return sora_march_xyz(h_in, v, sun, d, false);
}

// The march's light of the whole ray from the eye at altitude h along v to
// its end (the top or the ground) and the whole ray's transmittance, its
// two stretches of nodes split at split_m (MarchTables::whole_ray_xyz).
fn sora_whole_ray_march(h_in: f32, v: vec3<f32>, sun: vec3<f32>, split_m: f32) -> SoraAerial {
  return sora_march_xyz(h_in, v, sun, split_m, true);
}

fn sora_march_xyz(h_in: f32, v: vec3<f32>, sun: vec3<f32>, d: f32, whole: bool) -> SoraAerial {
  let w = sora_march.counts.x;
  let s = sora_march.counts.y;
  let ground = sora.planet_sun.x;
  let thickness = sora_thickness();
  let h = clamp(h_in, 0.0, thickness);
  let r0 = ground + h;
  // segment_in_atmosphere from inside the atmosphere (enter = 0), its
  // roots in the forms without cancellation.
  let b = r0 * v.z;
  let c_top = (h - thickness) * (r0 + sora.planet_sun.y);
  let root_top = sqrt(max(b * b - c_top, 0.0));
  let top_far = select(-b + root_top, -c_top / (b + root_top), b > 0.0);
  if (top_far <= 0.0) { return SoraAerial(vec3<f32>(0.0), vec3<f32>(1.0)); }
  let enter = 0.0;
  var exit_ = top_far;
  let c_ground = h * (2.0 * ground + h);
  let disc_ground = b * b - c_ground;
  var on_ground = false;
  if (b < 0.0 && disc_ground >= 0.0) {
    let ground_near = c_ground / (-b + sqrt(disc_ground));
    if (ground_near >= enter && ground_near < top_far) {
      exit_ = ground_near;
      on_ground = true;
    }
  }
  let length_ = max(min(exit_, d) - enter, 0.0);
  let beyond = exit_ - enter - length_;
  // The phase functions at the view's one scattering angle.
  let cos_theta = clamp(dot(v, sun), -1.0, 1.0);
  // theta from the chord, not the cosine (as sora_sky.glsl: near the sun
  // 1 - cos(theta) is lost to 32-bit rounding).
  let theta = 2.0 * atan2(length(v - sun), length(v + sun));
  let exact_phase = sora_march_phase(SORA_MARCH_PHASE, theta);
  let smooth_phase = sora_march_phase(SORA_MARCH_SMOOTH_PHASE, theta);
  var extinction: SoraMarchRows;
  var scaled_extinction: SoraMarchRows;
  var scaled_scattering: SoraMarchRows;
  var scattering: SoraMarchRows;
  for (var n = 0; n < w * s; n++) {
    extinction[n] = sora_march_value(SORA_MARCH_EXTINCTION, n);
    scaled_extinction[n] = sora_march_value(SORA_MARCH_SCALED_EXTINCTION, n);
    scaled_scattering[n] = sora_march_value(SORA_MARCH_SCALED_SCATTERING, n);
    scattering[n] = sora_march_value(SORA_MARCH_SCATTERING, n);
  }
  var single: SoraMarchWavelengths;
  var field: SoraMarchWavelengths;
  var field_beyond: SoraMarchWavelengths;
  // The species rows (summed) and Q, Q X, over the segment and beyond it.
  var forward_segment: SoraMarchWavelengths;
  var scaled_beyond: SoraMarchWavelengths;
  var q_segment: SoraMarchWavelengths;
  var qx_segment: SoraMarchWavelengths;
  var q_beyond: SoraMarchWavelengths;
  var qx_beyond: SoraMarchWavelengths;
  var columns: SoraMarchSpecies;
  var columns_segment: SoraMarchSpecies;
  var previous_rho = sora_march_densities(sora_march_altitude_along(h, v, enter).x);
  var previous = 0.0;
  let steps = sora_march.steps.x;
  let steps_beyond = sora_march.steps.y;
  let peaks = sora_march.columns_beam.w == 1;
  var segment_done = false;
  for (var node = 0; node < steps + steps_beyond; node++) {
    // Beyond the first stretch, the whole ray's nodes are the segment's.
    let in_segment = node < steps || whole;
    var at_ds: vec2<f32>;
    if (node < steps) {
      at_ds = sora_march_node(length_, node, steps);
    } else {
      at_ds = sora_march_node(beyond, node - steps, steps_beyond) + vec2<f32>(length_, 0.0);
    }
    let at = at_ds.x;
    let ds = at_ds.y;
    if (!in_segment && !segment_done) {
      let rho_end = sora_march_densities(sora_march_altitude_along(h, v, enter + length_).x);
      for (var j = 0; j < s; j++) {
        columns[j] += 0.5 * (previous_rho[j] + rho_end[j]) * (length_ - previous);
      }
      previous_rho = rho_end;
      columns_segment = columns;
      previous = length_;
      segment_done = true;
    }
    if (ds <= 0.0) { continue; }
    let point = sora_march_altitude_along(h, v, enter + at);
    let altitude = point.x;
    let r = point.y;
    // The cosines at the point: v.p / r and sun.p / r.
    let view_cosine = clamp((enter + at + r0 * v.z) / r, -1.0, 1.0);
    let sun_cosine = clamp(((enter + at) * cos_theta + r0 * sun.z) / r, -1.0, 1.0);
    let sines = sqrt(max((1.0 - view_cosine * view_cosine) * (1.0 - sun_cosine * sun_cosine), 0.0));
    let cos_azimuth = select(1.0, clamp((cos_theta - view_cosine * sun_cosine) / sines, -1.0, 1.0), sines > 1e-6);
    let log_source = sora_march_log_source(altitude, sun_cosine, view_cosine, cos_azimuth);
    let rho = sora_march_densities(altitude);
    for (var j = 0; j < s; j++) { columns[j] += 0.5 * (previous_rho[j] + rho[j]) * (at - previous); }
    previous = at;
    for (var i = 0; i < w; i++) {
      var tau = 0.0;
      var scattering_sum = 0.0;
      for (var j = 0; j < s; j++) {
        tau += scaled_extinction[i * s + j] * columns[j];
        scattering_sum += scaled_scattering[i * s + j] * rho[j];
      }
      if (log_source[i] > sora_march.beam_range_dark.w) {
        let add = ds * scattering_sum * exp(log_source[i] - tau);
        if (in_segment) { field[i] += add; } else { field_beyond[i] += add; }
      }
    }
    let to_sun = sora_march_sun_columns(altitude, sun_cosine);
    let lit = to_sun.lit;
    var peak_beam: SoraMarchBeam;
    if (peaks) { peak_beam = sora_march_peak_beam(altitude, sun_cosine); }
    let share = peak_beam.share;
    for (var i = 0; i < w; i++) {
      var depths = vec4<f32>(0.0);
      var peak = 0.0;
      var source = 0.0;
      var row_weight = 0.0;
      for (var j = 0; j < s; j++) {
        let scaled_ext = scaled_extinction[i * s + j];
        let ext = extinction[i * s + j];
        let sun_column = select(0.0, to_sun.columns[j], lit);
        depths += vec4<f32>(scaled_ext * columns[j], ext * columns[j], scaled_ext * sun_column, ext * sun_column);
        peak += (ext - scaled_ext) * rho[j];
        source += scattering[i * s + j] * exact_phase[j * w + i] * rho[j];
        row_weight += scattering[i * s + j] * smooth_phase[j * w + i] * rho[j];
      }
      let transmitted = exp(-depths);
      let view_beam = transmitted.x;
      let view_direct = transmitted.y;
      let sun_beam = select(0.0, transmitted.z, lit);
      let sun_direct = select(0.0, transmitted.w, lit);
      if (in_segment && lit) {
        single[i] += ds * sora_march_value(SORA_MARCH_SOLAR, i) * source * view_direct * sun_direct;
      }
      if (!peaks) { continue; }
      // As the library's march (add_tilted_forward_peak).
      let through = sun_beam - sun_direct;
      let scattered = through + share * (peak_beam.beam[i] - through);
      let excess = ds * (view_beam * scattered + sun_direct * (view_beam - view_direct));
      let beam_weight = ds * view_beam * (scattered + sun_direct);
      if (in_segment) { forward_segment[i] += excess * row_weight; } else { scaled_beyond[i] += beam_weight * row_weight; }
      if (lit && sun_beam > 0.0) {
        let only = ds * view_direct * sun_direct * peak * ((sun_direct + scattered) / sun_beam);
        let x = (depths.y + depths.w) - (depths.x + depths.z);
        if (in_segment) {
          q_segment[i] += only;
          qx_segment[i] += only * x;
        } else {
          q_beyond[i] += only;
          qx_beyond[i] += only * x;
        }
      }
    }
    previous_rho = rho;
  }
  if (!segment_done) { columns_segment = columns; }
  // The ground's light where the ray ends on it, through the whole ray's
  // scaled transmittance.
  let end = sora_march_altitude_along(h, v, exit_);
  let ground_sun_cosine = clamp((exit_ * cos_theta + r0 * sun.z) / end.y, -1.0, 1.0);
  var light = vec3<f32>(0.0);
  var through_xyz = vec3<f32>(0.0);
  var solar_xyz = vec3<f32>(0.0);
  for (var i = 0; i < w; i++) {
    var tau = 0.0;
    var tau_scaled = 0.0;
    var tau_scaled_whole = 0.0;
    for (var j = 0; j < s; j++) {
      tau += extinction[i * s + j] * columns_segment[j];
      tau_scaled += scaled_extinction[i * s + j] * columns_segment[j];
      tau_scaled_whole += scaled_extinction[i * s + j] * columns[j];
    }
    let solar = sora_march_value(SORA_MARCH_SOLAR, i);
    let share = 1.0 - exp(tau_scaled - tau);
    let depth = tau - tau_scaled;
    var ground_light = 0.0;
    if (on_ground) { ground_light = exp(-tau_scaled_whole) * sora_march_ground_light(i, ground_sun_cosine); }
    var value = single[i] + field[i] + share * (field_beyond[i] + ground_light);
    if (peaks) {
      let peak_forward = sora_march_peak_radiance(theta, i, forward_segment[i] + share * scaled_beyond[i],
                                                  q_segment[i] + q_beyond[i], qx_segment[i] + qx_beyond[i]);
      let hidden = sora_march_peak_radiance(theta, i, 0.0, q_beyond[i], qx_beyond[i] - depth * q_beyond[i]);
      value += peak_forward - hidden;
    }
    let spike = vec3<f32>(sora_march_value(SORA_MARCH_XYZ, 3 * i), sora_march_value(SORA_MARCH_XYZ, 3 * i + 1),
                          sora_march_value(SORA_MARCH_XYZ, 3 * i + 2));
    light += value * spike;
    through_xyz += solar * exp(-tau) * spike;
    solar_xyz += solar * spike;
  }
  return SoraAerial(light, clamp(through_xyz / max(solar_xyz, vec3<f32>(1e-30)), vec3<f32>(0.0), vec3<f32>(1.0)));
}

// ---------------------------------------------------------------------------
// The sky for an eye above the ground from the march's tables (lookup.rs's
// EngineTables::raised_sky_xyz, whole_ray_sky_xyz, composed_below_xyz; the
// GLSL twin's soraRaisedSkyXyz and its helpers; docs/engine-tables.md, "An
// eye between the altitude nodes").

// The eye's height above a view's perigee (a share of the thickness) from
// which the whole ray's march splits at the perigee (PERIGEE_SPLIT_RAMP).
const SORA_PERIGEE_SPLIT_RAMP: f32 = 0.05;

// Zenith angle of the horizon (rad) at altitude h (axes::horizon_zenith,
// pi - asin(R / r), written for float precision as pi / 2 + atan2(sqrt(h
// (2 R + h)), R)).
fn sora_horizon_zenith(h_in: f32) -> f32 {
  let ground = sora.planet_sun.x;
  let h = max(h_in, 0.0);
  return 0.5 * SORA_PI + atan2(sqrt(h * (2.0 * ground + h)), ground);
}

// The split of the whole ray's march from an eye at h toward the unit v,
// a view above the eye's horizon (whole_ray_sky_xyz; as soraWholeRaySplit
// in sora_sky.glsl): for a view going down, between the perigee (the eye
// at least SORA_PERIGEE_SPLIT_RAMP times the thickness above it) and the
// ray's end (the eye at the perigee's altitude), smoothstep in the eye's
// height above the perigee; the ray's end otherwise.
fn sora_whole_ray_split(h: f32, v: vec3<f32>) -> f32 {
  let r = sora.planet_sun.x + h;
  let length_ = sora_ray_length(h, v.z);
  if (v.z >= 0.0) { return length_; }
  let perigee = -r * v.z;
  // r - sqrt(r^2 - perigee^2) = r v.z^2 / (1 + sin z), without cancellation.
  let above = r * v.z * v.z / (1.0 + sqrt(max((1.0 - v.z) * (1.0 + v.z), 0.0)));
  let w = smoothstep(0.0, SORA_PERIGEE_SPLIT_RAMP * sora_thickness(), above);
  return length_ + (min(perigee, length_) - length_) * w;
}

// Where the ray from an eye at h toward the unit v first meets the sphere
// of altitude h_node (composed_below_xyz's t, 0 where the eye is on it; the
// near root as c / (-b + sqrt(b^2 - c))) and the table's read there
// (altitude, zenith angle, azimuth from the sun, sun elevation in the
// point's own frame).
struct SoraComposed { t: f32, read: vec4<f32> };

fn sora_composed_below_geometry(h: f32, v: vec3<f32>, sun: vec3<f32>, h_node: f32) -> SoraComposed {
  let ground = sora.planet_sun.x;
  let r = ground + h;
  let b = r * v.z;
  let c = (h - h_node) * (2.0 * ground + h + h_node);
  let disc = max(b * b - c, 0.0);
  var t = 0.0;
  if (h > h_node) {
    let q = -b + sqrt(disc);
    if (q > 0.0) { t = max(c / q, 0.0); }
  }
  let p = vec3<f32>(v.xy * t, r + v.z * t);
  let up = p / length(p);
  let zp = sora_local_view(v, up, sun);
  return SoraComposed(t, vec4<f32>(h_node, zp.x, zp.y, degrees(asin(clamp(dot(sun, up), -1.0, 1.0)))));
}

// value times (want / got)^share per channel, each floored at SORA_FLOOR
// (raised_sky_xyz's `scaled`).
fn sora_scaled_xyz(value: vec3<f32>, want: vec3<f32>, got: vec3<f32>, share: f32) -> vec3<f32> {
  let k = log(max(want, vec3<f32>(SORA_FLOOR))) - log(max(got, vec3<f32>(SORA_FLOOR)));
  return value * exp(k * share);
}

// The sky for an eye above the ground, from the march's tables
// (raised_sky_xyz; soraRaisedSkyXyz in sora_sky.glsl, in the same form:
// at most three table reads and two marches, each from one call in a
// loop): above the eye's horizon the whole ray's march, in the first
// altitude cell times the table's ratio to the march on the ground fading
// linearly in h to none at the first node; below it the composition at
// the lower altitude node's sphere times the table's ratio to the same
// composition at the upper node, that ratio's logarithm linear in h.
// Without march tables or on the ground, the table's read. A separate
// entry (sora_raised_sky_view), not sora_sky_xyz's read (see the GLSL
// twin, which is checked against the Rust lookup; this one is validated
// only).
fn sora_raised_sky_xyz(h_in: f32, zenith: f32, phi: f32, e_deg: f32) -> vec3<f32> {
  var reads: array<vec4<f32>, 3>;   // the table's reads: altitude, zenith, azimuth, sun elevation
  var marches: array<vec4<f32>, 2>; // the marches: the eye's altitude, the distance (split), whole (1) or segment (0)
  var views: array<vec3<f32>, 2>;
  var read_count = 1;
  var march_count = 0;
  reads[0] = vec4<f32>(h_in, zenith, phi, e_deg);
  let raised = sora_march.counts.w > 0 && h_in > 0.0;
  var above = true;
  var scaled = false;
  var share = 0.0;
  var sun = vec3<f32>(1.0, 0.0, 0.0);
  if (raised) {
    let h = clamp(h_in, 0.0, sora_thickness());
    let z = zenith;
    let e = radians(e_deg);
    sun = vec3<f32>(cos(e), 0.0, sin(e));
    let an = sora.sky_nodes.y;
    let a = sora_cell(sora_altitude_coordinate(h, an), 0, an - 2).i;
    let fh = sora_altitude_share(h, a, an);
    let horizon = sora_horizon_zenith(h);
    let v = vec3<f32>(sin(z) * cos(phi), sin(z) * sin(phi), cos(z));
    above = z < horizon;
    if (above) {
      read_count = 0;
      march_count = 1;
      views[0] = v;
      marches[0] = vec4<f32>(h, sora_whole_ray_split(h, v), 1.0, 0.0);
      if (!(a > 0 || fh >= 1.0)) {
        let z0 = z * sora_horizon_zenith(0.0) / horizon;
        let v0 = vec3<f32>(sin(z0) * cos(phi), sin(z0) * sin(phi), cos(z0));
        views[1] = v0;
        marches[1] = vec4<f32>(0.0, sora_whole_ray_split(0.0, v0), 1.0, 0.0);
        march_count = 2;
        reads[0] = vec4<f32>(0.0, z0, phi, e_deg);
        read_count = 1;
        scaled = true;
        share = 1.0 - fh;
      }
    } else {
      let h_a = sora_altitude_of_node(a, an);
      views[0] = v;
      let c0 = sora_composed_below_geometry(h, v, sun, h_a);
      reads[0] = c0.read;
      marches[0] = vec4<f32>(h, c0.t, 0.0, 0.0);
      march_count = 1;
      if (fh > 0.0) {
        let h_b = sora_altitude_of_node(a + 1, an);
        let z_b = SORA_PI - (SORA_PI - z) * (SORA_PI - sora_horizon_zenith(h_b)) / (SORA_PI - horizon);
        let v_b = vec3<f32>(sin(z_b) * cos(phi), sin(z_b) * sin(phi), cos(z_b));
        views[1] = v_b;
        let c1 = sora_composed_below_geometry(h_b, v_b, sun, h_a);
        reads[1] = c1.read;
        marches[1] = vec4<f32>(h_b, c1.t, 0.0, 0.0);
        march_count = 2;
        reads[2] = vec4<f32>(h_b, z_b, phi, e_deg);
        read_count = 3;
        scaled = true;
        share = fh;
      }
    }
  }
  var tables: array<vec3<f32>, 3>;
  for (var k = 0; k < read_count; k++) {
    tables[k] = sora_sky_xyz(reads[k].x, reads[k].y, reads[k].z, reads[k].w);
  }
  if (!raised) { return tables[0]; }
  // Each march's light: the whole ray's, or the composition (the table's
  // read itself where the segment has no length).
  var lights: array<vec3<f32>, 2>;
  for (var k = 0; k < march_count; k++) {
    let whole = marches[k].z > 0.5;
    if (!whole && marches[k].y <= 0.0) {
      lights[k] = tables[k];
      continue;
    }
    let m = sora_march_xyz(marches[k].x, views[k], sun, marches[k].y, whole);
    lights[k] = select(m.inscattered + m.transmittance * tables[k], m.inscattered, whole);
  }
  if (!scaled) { return lights[0]; }
  return sora_scaled_xyz(lights[0], tables[select(2, 0, above)], lights[1], share);
}

// Sky radiance for an eye at altitude h along unit v, sun toward unit sun
// (east-north-up, z up), as the Rust lookup's sky_xyz reads it
// (sora_raised_sky_xyz): the entry for an eye above the ground
// (soraRaisedSkyView in sora_sky.glsl). A pipeline that calls it compiles
// the march, so a host draws an eye on the ground with one calling
// sora_sky_view instead (the same read there).
fn sora_raised_sky_view(h: f32, v: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
  let zp = sora_local_view(v, vec3<f32>(0.0, 0.0, 1.0), sun);
  return sora_raised_sky_xyz(h, zp.x, zp.y, sora_sun_elevation_deg(sun));
}
