// sora engine tables: reference reader, WGSL (WebGPU).
//
// The same formulas as sora_sky.glsl (and crates/sora/src/engine_tables/
// lookup.rs); table reads by textureLoad only. Bind (docs/engine-tables.md):
//   group(0) binding(0) sky: texture_2d_array<f32>, sky.exr, layer = s * A + a
//   group(0) binding(1) transmittance: texture_2d<f32>, transmittance.exr
//   group(0) binding(2) irradiance: texture_2d<f32>, irradiance.exr
//   group(0) binding(3) params: SoraTables (values from manifest.json)
//   group(0) binding(4) aerial: texture_2d_array<f32>, aerial.exr, layer = s * A + a,
//                       its distance slices one above another in each layer
// Textures rgba32float (unfilterable is fine), holding X, Y, Z.

struct SoraTables {
  // sun_nodes, altitude_nodes, zenith_nodes_per_half, azimuth_nodes
  sky_nodes: vec4<i32>,
  // transmittance altitude nodes, mu nodes, unused, unused
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

// Cell index and the upper node's weight of fractional index x.
struct SoraCell { i: i32, f: f32 };

fn sora_cell(x: f32, lowest: i32, highest: i32) -> SoraCell {
  let i = clamp(i32(floor(max(x, 0.0))), lowest, highest);
  return SoraCell(i, clamp(x - f32(i), 0.0, 1.0));
}

// The zenith axis's cell for an eye at radius r on an axis of half_nodes
// nodes per half (never across the horizon).
fn sora_zenith_cell(zenith: f32, r: f32, half_nodes: i32) -> SoraCell {
  let zh = SORA_PI - asin(min(sora.planet_sun.x / r, 1.0));
  let last = f32(half_nodes - 1);
  if (zenith < zh) {
    let u = clamp(zenith / (zh - 1e-6), 0.0, 1.0);
    return sora_cell((1.0 - sqrt(1.0 - u)) * last, 0, half_nodes - 2);
  }
  let u = clamp((SORA_PI - zenith) / (SORA_PI - zh - 1e-6), 0.0, 1.0);
  return sora_cell(f32(2 * half_nodes - 1) - (1.0 - sqrt(1.0 - u)) * last, half_nodes, 2 * half_nodes - 2);
}

// Bilinear read of the slice whose first row is row0 of a layer of `table`.
fn sora_layer(table: texture_2d_array<f32>, layer: i32, row0: i32, z: SoraCell, k: SoraCell) -> vec3<f32> {
  let a = mix(textureLoad(table, vec2<i32>(k.i, row0 + z.i), layer, 0).xyz,
              textureLoad(table, vec2<i32>(k.i + 1, row0 + z.i), layer, 0).xyz, k.f);
  let b = mix(textureLoad(table, vec2<i32>(k.i, row0 + z.i + 1), layer, 0).xyz,
              textureLoad(table, vec2<i32>(k.i + 1, row0 + z.i + 1), layer, 0).xyz, k.f);
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
// the sun, 0 beyond 40; 0 within 5 degrees of the horizon, 1 from 20 up;
// 0 for suns above 85 degrees, 1 below 70; or, for suns below 2 degrees
// (0 above 6), 1 within 40 degrees of the antisolar point, 0 beyond 80,
// horizon included (the planet's shadow turns with it; smoothstep ramps).
fn sora_turn_share(zenith: f32, phi: f32, e_deg: f32, zh: f32) -> f32 {
  let e = radians(e_deg);
  let cos_theta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  let sun_side = smoothstep(cos(radians(40.0)), cos(radians(10.0)), cos_theta)
    * (1.0 - smoothstep(zh - radians(20.0), zh - radians(5.0), zenith))
    * (1.0 - smoothstep(70.0, 85.0, e_deg));
  let shadow = smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cos_theta)
    * (1.0 - smoothstep(2.0, 6.0, e_deg));
  return max(sun_side, shadow);
}

// A layer table (the sky, or the aerial-perspective table with zn zenith
// nodes per half, kn azimuth nodes, its distance slices j and j + 1
// blended by fj) at altitude h (m) toward zenith angle `zenith` and
// azimuth `phi` from the sun's (rad), sun at e_deg: bilinear in a layer,
// linear in altitude, in ln L between the sun layers (the chord less the
// curvature of the four nearest), each read at the view turned with the
// sun to its node.
fn sora_layers_xyz(table: texture_2d_array<f32>, zn: i32, kn: i32, j: i32, fj: f32,
                   h_in: f32, zenith: f32, phi: f32, e_in: f32) -> vec3<f32> {
  let h = clamp(h_in, 0.0, sora_thickness());
  let r = sora.planet_sun.x + h;
  let zh = SORA_PI - asin(min(sora.planet_sun.x / r, 1.0));
  let e_deg = clamp(e_in, -12.0, 90.0);
  let an = sora.sky_nodes.y;
  let a = sora_cell(sora_altitude_coordinate(h, an), 0, an - 2);
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
    let z = sora_zenith_cell(view.x, r, zn);
    let k = sora_cell(sqrt(clamp(view.y / SORA_PI, 0.0, 1.0)) * f32(kn - 1), 0, kn - 2);
    let low = (s.i + n) * an + a.i;
    let ground = mix(sora_layer(table, low, row0, z, k), sora_layer(table, low, row1, z, k), fj);
    let above = mix(sora_layer(table, low + 1, row0, z, k), sora_layer(table, low + 1, row1, z, k), fj);
    layers[m] = log(max(mix(ground, above, a.f), vec3<f32>(SORA_FLOOR)));
  }
  // The chord in ln L less its curvature: the second differences at nodes
  // s and s + 1 (zero at the axis's ends, each within +-1), blended.
  var d0 = vec3<f32>(0.0);
  var d1 = vec3<f32>(0.0);
  if (s.i > 0) { d0 = clamp(layers[0] - 2.0 * layers[1] + layers[2], vec3<f32>(-1.0), vec3<f32>(1.0)); }
  if (s.i + 2 < sora.sky_nodes.x) { d1 = clamp(layers[1] - 2.0 * layers[2] + layers[3], vec3<f32>(-1.0), vec3<f32>(1.0)); }
  return exp(mix(layers[1], layers[2], s.f) - 0.5 * s.f * (1.0 - s.f) * mix(d0, d1, s.f));
}

// Sky radiance (XYZ, W m^-2 sr^-1 nm^-1) at altitude h (m) toward zenith
// angle `zenith` and azimuth `phi` from the sun's (rad), sun at e_deg.
fn sora_sky_xyz(h_in: f32, zenith: f32, phi: f32, e_in: f32) -> vec3<f32> {
  return sora_layers_xyz(sora_sky, sora.sky_nodes.z, sora.sky_nodes.w, 0, 0.0, h_in, zenith, phi, e_in);
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
fn sora_ground_irradiance_xyz(h_in: f32, e_deg: f32) -> vec3<f32> {
  let h = clamp(h_in, 0.0, sora_thickness());
  let an = sora.sky_nodes.y;
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

// Sky radiance for an eye at altitude h along unit v, sun toward unit sun
// (east-north-up, z up).
fn sora_sky_view(h: f32, v: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
  let zp = sora_local_view(v, vec3<f32>(0.0, 0.0, 1.0), sun);
  return sora_sky_xyz(h, zp.x, zp.y, degrees(asin(clamp(sun.z, -1.0, 1.0))));
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
  let e_deg = degrees(asin(clamp(sun.z, -1.0, 1.0)));
  let sky = sora_sky_xyz(h, zp.x, zp.y, e_deg);
  let ratio = sora_layers_xyz(sora_aerial, sora.aerial_nodes.x, sora.aerial_nodes.y, j.i, j.f, h, zp.x, zp.y, e_deg);
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
