// sora engine tables: reference reader, GLSL ES 3.0 (WebGL2).
//
// Include this after `#version 300 es` and `precision highp float;`.
// Everything per frame is table reads (texelFetch) and arithmetic; the
// formulas are those of crates/sora/src/engine_tables/lookup.rs and of the
// tables' manifest.json ("axes", "lookup"). Bind (docs/engine-tables.md):
//   uSky           sampler2DArray, sky.exr as azimuth_nodes x 2*zenith_nodes_per_half
//                  texels per layer, sun_nodes*altitude_nodes layers (layer = s*A + a)
//   uAerial        sampler2DArray, aerial.exr as azimuth nodes x 2*zenith_nodes_per_half*
//                  distance_nodes texels per layer (the distance slices one above
//                  another), the sky's sun_nodes*altitude_nodes layers
//   uTransmittance sampler2D, transmittance.exr (x = mu node, y = altitude node)
//   uIrradiance    sampler2D, irradiance.exr (x = sun node, y = altitude node of
//                  its own axis, tables.irradiance.altitude_nodes = its height)
// as RGBA32F (or RGB32F) textures holding X, Y, Z; no filtering is needed
// (texelFetch only). Values are CIE XYZ in the units of manifest.json;
// soraXyzToLinearSrgb converts to linear sRGB (Rec. 709 primaries, D65).

uniform highp sampler2DArray uSky;
uniform highp sampler2D uTransmittance;
uniform highp sampler2D uIrradiance;
uniform highp sampler2DArray uAerial;
// aerial: zenith_nodes_per_half, azimuth_nodes, distance_nodes
uniform ivec3 uAerialNodes;
// sun_nodes, altitude_nodes, zenith_nodes_per_half, azimuth_nodes
uniform ivec4 uSkyNodes;
// sky zenith_fine_cells_per_half, zenith_wide_cells_per_half (each 0
// where the manifest has none)
uniform int uSkyZenithFineCells;
uniform int uSkyZenithWideCells;
// transmittance altitude nodes, mu nodes
uniform ivec2 uTransmittanceNodes;
// ground_radius_m, top_radius_m, sun angular radius (rad), limb darkening
uniform vec4 uPlanetSun;
// sun.irradiance_xyz_w_m2_nm
uniform vec3 uSunIrradianceXyz;
// sun.axis_width_deg
uniform float uSunAxisWidthDeg;

const float SORA_PI = 3.14159265358979;
const float SORA_FLOOR = 1e-30;

float soraAsinh(float x) { return sign(x) * log(abs(x) + sqrt(x * x + 1.0)); }

// Fractional sun node of elevation eDeg.
float soraSunCoordinate(float eDeg) {
  float t0 = soraAsinh(-12.0 / uSunAxisWidthDeg);
  float t1 = soraAsinh(90.0 / uSunAxisWidthDeg);
  float t = soraAsinh(clamp(eDeg, -12.0, 90.0) / uSunAxisWidthDeg);
  return clamp((t - t0) / (t1 - t0), 0.0, 1.0) * float(uSkyNodes.x - 1);
}

float soraThickness() { return uPlanetSun.y - uPlanetSun.x; }

// The altitude axis: ln(1 + h / h0) / ln(1 + 50), h0 = thickness / 50.
float soraAltitudeCoordinate(float h, int nodes) {
  float x = clamp(h, 0.0, soraThickness()) / (soraThickness() / 50.0);
  return clamp(log(1.0 + x) / log(51.0), 0.0, 1.0) * float(nodes - 1);
}

// Altitude (m) of node a of an axis of `nodes` nodes (axes::altitude_of_node).
float soraAltitudeOfNode(int a, int nodes) {
  float h0 = soraThickness() / 50.0;
  return min(h0 * (pow(51.0, float(a) / float(nodes - 1)) - 1.0), soraThickness());
}

// Share (0..1) of altitude h between nodes a and a + 1, linear in h.
float soraAltitudeShare(float h, int a, int nodes) {
  float h0 = soraAltitudeOfNode(a, nodes), h1 = soraAltitudeOfNode(a + 1, nodes);
  return clamp((h - h0) / (h1 - h0), 0.0, 1.0);
}

// Cell index and weight of fractional index x within lowest..highest.
void soraCell(float x, int lowest, int highest, out int i, out float f) {
  i = clamp(int(floor(max(x, 0.0))), lowest, highest);
  f = clamp(x - float(i), 0.0, 1.0);
}

// Zenith node coordinate (0..half_ - 1, from the zenith or the nadir) of
// v = 1 - sqrt(1 - u) on an axis of half_ nodes per half with cells.x fine
// and cells.y wide cells next to the horizon (axes::zenith_coordinate): v
// on a grid of 2 (half_ - 1) - fine + wide cells, from the zenith every
// other grid node a node, then every third over the wide cells, every one
// in the last `fine` cells.
float soraZenithNode(float v, int half_, ivec2 cells) {
  int fine = min(cells.x, half_ - 1);
  int wide = min(cells.y, half_ - 1 - fine);
  float c = float(half_ - 1 - fine - wide);
  float w = float(wide);
  float j = v * float(2 * (half_ - 1) - fine + wide);
  return j <= 2.0 * c ? 0.5 * j : (j <= 2.0 * c + 3.0 * w ? c + (j - 2.0 * c) / 3.0 : j - c - 2.0 * w);
}

// Zenith coordinate (y, lowest cell, highest cell) for an eye at radius r
// on an axis of half_ nodes per half with cells.x fine and cells.y wide
// cells.
void soraZenithCoordinate(float zenith, float r, int half_, ivec2 cells, out float y, out int lowest, out int highest) {
  float zh = SORA_PI - asin(min(uPlanetSun.x / r, 1.0));
  if (zenith < zh) {
    float u = clamp(zenith / (zh - 1e-6), 0.0, 1.0);
    y = soraZenithNode(1.0 - sqrt(1.0 - u), half_, cells);
    lowest = 0;
    highest = half_ - 2;
  } else {
    float u = clamp((SORA_PI - zenith) / (SORA_PI - zh - 1e-6), 0.0, 1.0);
    y = float(2 * half_ - 1) - soraZenithNode(1.0 - sqrt(1.0 - u), half_, cells);
    lowest = half_;
    highest = 2 * half_ - 2;
  }
}

vec3 soraMixLog(vec3 a, vec3 b, float f) {
  return exp(mix(log(max(a, vec3(SORA_FLOOR))), log(max(b, vec3(SORA_FLOOR))), f));
}

// Zenith cells of the sky table, from the zenith, read by the cubic in
// ln L (lookup.rs ZENITH_CAP_CELLS).
const int SORA_ZENITH_CAP_CELLS = 16;

// The uniform Catmull-Rom cubic in ln L (each value floored at SORA_FLOOR)
// between p0 (t = 0) and p1 (t = 1), m and n the nodes before and after
// (lookup.rs catmull_rom_log): through the nodes, its slope at each the
// centred difference of the nodes about it.
vec3 soraCatmullRomLog(vec3 m, vec3 p0, vec3 p1, vec3 n, float t) {
  vec3 lm = log(max(m, vec3(SORA_FLOOR)));
  vec3 a = log(max(p0, vec3(SORA_FLOOR)));
  vec3 b = log(max(p1, vec3(SORA_FLOOR)));
  vec3 ln = log(max(n, vec3(SORA_FLOOR)));
  vec3 cubic = -lm + 3.0 * a - 3.0 * b + ln;
  vec3 square = 2.0 * lm - 5.0 * a + 4.0 * b - ln;
  return exp(a + 0.5 * t * ((b - lm) + t * (square + t * cubic)));
}

// Row `row` of a layer of `table`, linear between azimuth nodes k and k + 1.
vec3 soraRow(highp sampler2DArray table, int layer, int row, int k, float fx) {
  return mix(texelFetch(table, ivec3(k, row, layer), 0).xyz, texelFetch(table, ivec3(k + 1, row, layer), 0).xyz, fx);
}

// Read of slice row0 (its first row) of a layer of `table` in zenith cell i
// (fy) and azimuth cell k (fx): bilinear, but in the cells of the zenith
// cap (i < cap, of the upper half's Z nodes, and i + 2 < Z) the cubic in
// ln L through rows i - 1 .. i + 2, row -1 being row 1 at the opposite
// azimuth (its cell km, fxm): smooth across the rows and through the
// zenith (lookup.rs layer_value_at).
vec3 soraLayer(highp sampler2DArray table, int layer, int row0, int i, float fy, int k, float fx, int km, float fxm, int cap, int Z) {
  vec3 a = soraRow(table, layer, row0 + i, k, fx);
  vec3 b = soraRow(table, layer, row0 + i + 1, k, fx);
  if (i < cap && i + 2 < Z) {
    vec3 before = i == 0 ? soraRow(table, layer, row0 + 1, km, fxm) : soraRow(table, layer, row0 + i - 1, k, fx);
    return soraCatmullRomLog(before, a, b, soraRow(table, layer, row0 + i + 2, k, fx), fy);
  }
  return mix(a, b, fy);
}

// Elevation (degrees) of sun node s: the inverse of soraSunCoordinate.
float soraSunElevationOfNode(int s) {
  float t0 = soraAsinh(-12.0 / uSunAxisWidthDeg);
  float t1 = soraAsinh(90.0 / uSunAxisWidthDeg);
  float t = t0 + (t1 - t0) * float(s) / float(uSkyNodes.x - 1);
  return clamp(uSunAxisWidthDeg * 0.5 * (exp(t) - exp(-t)), -12.0, 90.0);
}

// The view (zenith, phi) turned by delta (rad) about the horizontal axis
// across the sun's azimuth, as the sun is turned from its elevation to a
// sun node's: the scattering angle is kept. The zenith stays on its side
// of the eye's horizon zh (the ground is never read for the sky).
vec2 soraTurnedView(float zenith, float phi, float delta, float zh) {
  // Unturned views keep their coordinates exactly (the horizon's band is
  // steep in the zenith axis).
  if (delta == 0.0) return vec2(zenith, phi);
  float sz = sin(zenith);
  vec3 v = vec3(sz * cos(phi), sz * sin(phi), cos(zenith));
  float c = cos(delta), s = sin(delta);
  float x = v.x * c - v.z * s;
  float z = clamp(v.x * s + v.z * c, -1.0, 1.0);
  float turned = acos(z);
  turned = zenith < zh ? min(turned, zh - 2e-6) : max(turned, zh);
  return vec2(turned, atan(abs(v.y), x));
}

// Share of the sun's step that the view is turned by (lookup.rs's
// turn_share): 1 within 10 degrees of the sun (the aureole keeps its angle
// to the sun between sun nodes), 0 beyond 40; 0 within 5 degrees of the
// horizon (its band keeps its zenith angle), 1 from 20 up (for suns above
// 68 degrees 1 away from the sun too, none below 55); or, for suns
// below 2 degrees (0 above 6), 1 within 40 degrees of the antisolar
// point, 0 beyond 80, horizon included (smoothstep ramps).
float soraTurnShare(float zenith, float phi, float eDeg, float zh) {
  float e = radians(eDeg);
  float cosTheta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  // For a high sun the whole sky (lookup.rs's HIGH_SUN_DEG, 55 to 68):
  // its aureole reaches the zenith, which read unturned in the layer at 90
  // degrees would be the sun's own place.
  float sunSide = max(smoothstep(cos(radians(40.0)), cos(radians(10.0)), cosTheta), smoothstep(55.0, 68.0, eDeg))
    * (1.0 - smoothstep(zh - radians(20.0), zh - radians(5.0), zenith));
  // The planet's shadow, rising at the antisolar horizon as the sun sets,
  // turns with the antisolar point (horizon included).
  float shadow = smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cosTheta)
    * (1.0 - smoothstep(2.0, 6.0, eDeg));
  return max(sunSide, shadow);
}

// The share of the read near the antisolar point with the sun below the
// horizon that takes the sun layers below the horizon only: the planet's
// shadow's share of soraTurnShare where the view's elevation is within
// the sun's depression |e| (below the shadow's edge), ramping to none at
// SORA_SHADOW_RAMP |e|; none with the sun up (lookup.rs shadow_read_share).
const float SORA_SHADOW_RAMP = 2.5;
float soraShadowReadShare(float zenith, float phi, float eDeg, float zh) {
  if (eDeg >= 0.0) return 0.0;
  float e = radians(eDeg);
  float cosTheta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  return smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cosTheta)
    * (1.0 - smoothstep(-e, -SORA_SHADOW_RAMP * e, zh - zenith));
}

// ln L of layer `low` (and low + 1, the altitude node above: above the
// eye's horizon ln L blended by fh, the share linear in the altitude;
// below it L by fa, the altitude coordinate's) of a
// layer table toward `view` (zenith, phi), slices row0 and row1 by fj;
// its first `cap` zenith cells read by the cubic (soraLayer).
vec3 soraLayerLog(highp sampler2DArray table, int Z, ivec2 F, int K, int cap, int low, float fa, float fh, int row0, int row1, float fj, vec2 view, float r) {
  float y; int lowest; int highest;
  soraZenithCoordinate(view.x, r, Z, F, y, lowest, highest);
  int i; float fy; soraCell(y, lowest, highest, i, fy);
  int k; float fx; soraCell(sqrt(clamp(view.y / SORA_PI, 0.0, 1.0)) * float(K - 1), 0, K - 2, k, fx);
  int km; float fxm; soraCell(sqrt(clamp(1.0 - view.y / SORA_PI, 0.0, 1.0)) * float(K - 1), 0, K - 2, km, fxm);
  vec3 ground = mix(soraLayer(table, low, row0, i, fy, k, fx, km, fxm, cap, Z), soraLayer(table, low, row1, i, fy, k, fx, km, fxm, cap, Z), fj);
  vec3 above = mix(soraLayer(table, low + 1, row0, i, fy, k, fx, km, fxm, cap, Z), soraLayer(table, low + 1, row1, i, fy, k, fx, km, fxm, cap, Z), fj);
  float zh = SORA_PI - asin(min(uPlanetSun.x / r, 1.0));
  return view.x < zh
    ? mix(log(max(ground, vec3(SORA_FLOOR))), log(max(above, vec3(SORA_FLOOR))), fh)
    : log(max(mix(ground, above, fa), vec3(SORA_FLOOR)));
}

// A layer table (the sky, or the aerial-perspective table with Z zenith
// nodes per half, K azimuth nodes, and its distance slices j and j + 1
// blended by fj) at altitude h (m), toward zenith angle `zenith` (rad) and
// azimuth `phi` (rad, 0..pi) from the sun's, with the sun at elevation
// eDeg (degrees): bilinear in a layer (its first `cap` zenith cells by the
// cubic in ln L, soraLayer), between the altitude layers as soraLayerLog, in ln L between the two
// sun layers (the chord less the curvature of the four nearest), each read
// at the view turned with the sun to its node (soraTurnedView, by
// soraTurnShare of the step).
vec3 soraLayersXyz(highp sampler2DArray table, int Z, ivec2 F, int K, int cap, int j, float fj, float h, float zenith, float phi, float eDeg) {
  h = clamp(h, 0.0, soraThickness());
  float r = uPlanetSun.x + h;
  float zh = SORA_PI - asin(min(uPlanetSun.x / r, 1.0));
  int A = uSkyNodes.y;
  int a; float fa; soraCell(soraAltitudeCoordinate(h, A), 0, A - 2, a, fa);
  float fh = soraAltitudeShare(h, a, A);
  eDeg = clamp(eDeg, -12.0, 90.0);
  int s; float fs; soraCell(soraSunCoordinate(eDeg), 0, uSkyNodes.x - 2, s, fs);
  float share = soraTurnShare(zenith, phi, eDeg, zh);
  int row0 = 2 * Z * j;
  int row1 = fj > 0.0 ? row0 + 2 * Z : row0;
  // ln L of sun layers s - 1 .. s + 2 (clamped to the axis).
  vec3 layers[4];
  for (int m = 0; m < 4; m++) {
    int n = clamp(s + m - 1, 0, uSkyNodes.x - 1) - s;
    vec2 view = soraTurnedView(zenith, phi, radians(soraSunElevationOfNode(s + n) - eDeg) * share, zh);
    int low = (s + n) * A + a;
    layers[m] = soraLayerLog(table, Z, F, K, cap, low, fa, fh, row0, row1, fj, view, r);
  }
  // The chord in ln L less its curvature: the second differences at nodes
  // s and s + 1 (zero at the axis's ends, each within +-1), blended.
  vec3 d0 = s > 0 ? clamp(layers[0] - 2.0 * layers[1] + layers[2], -1.0, 1.0) : vec3(0.0);
  vec3 d1 = s + 2 < uSkyNodes.x ? clamp(layers[1] - 2.0 * layers[2] + layers[3], -1.0, 1.0) : vec3(0.0);
  vec3 whole = mix(layers[1], layers[2], fs) - 0.5 * fs * (1.0 - fs) * mix(d0, d1, fs);
  // Below the planet's shadow's edge, the layers with the sun below the
  // horizon alone (the axis cut at the last of them, `top`; beyond it the
  // chord of the last two extended), blended in by soraShadowReadShare.
  int top = int(ceil(soraSunCoordinate(0.0))) - 1;
  float below = soraShadowReadShare(zenith, phi, eDeg, zh);
  if (below > 0.0 && top >= 1 && top + 1 < uSkyNodes.x && s + 2 > top && s <= top) {
    vec3 shadow = s == top
      ? mix(layers[0], layers[1], 1.0 + fs)
      : mix(layers[1], layers[2], fs) - 0.5 * fs * (1.0 - fs) * (1.0 - fs) * d0;
    whole = mix(whole, shadow, below);
  }
  return exp(whole);
}

// Sky radiance (XYZ, W m^-2 sr^-1 nm^-1) seen at altitude h (m) toward
// zenith angle `zenith` (rad) and azimuth `phi` (rad, 0..pi) from the
// sun's, with the sun at elevation eDeg (degrees). No sun disc. The sky
// table's read (lookup.rs's table_sky_xyz): the Rust lookup's sky_xyz for
// an eye on the ground or tables without the march's. For an eye above
// the ground with march tables sky_xyz is soraRaisedSkyXyz (below), a
// separate entry, so that a host drawing an eye on the ground compiles
// no march (docs/engine-tables.md, "The shader's functions").
vec3 soraSkyXyz(float h, float zenith, float phi, float eDeg) {
  return soraLayersXyz(uSky, uSkyNodes.z, ivec2(uSkyZenithFineCells, uSkyZenithWideCells), uSkyNodes.w, SORA_ZENITH_CAP_CELLS, 0, 0.0, h, zenith, phi, eDeg);
}

float soraHorizonCosine(float r) {
  float q = min(uPlanetSun.x / r, 1.0);
  return -sqrt(max(1.0 - q * q, 0.0));
}

// Transmittance (XYZ of the transmitted sunlight / XYZ of the sunlight)
// from altitude h to the top along view cosine mu; zero below the horizon.
vec3 soraTransmittance(float h, float mu) {
  h = clamp(h, 0.0, soraThickness());
  float r = uPlanetSun.x + h;
  float muH = soraHorizonCosine(r);
  if (mu < muH) return vec3(0.0);
  int A = uTransmittanceNodes.x;
  int M = uTransmittanceNodes.y;
  int a; float fa; soraCell(soraAltitudeCoordinate(h, A), 0, A - 2, a, fa);
  // Each row at the view cosine's coordinate for its own altitude's horizon.
  float rA = uPlanetSun.x + soraThickness() / 50.0 * (exp(float(a) / float(A - 1) * log(51.0)) - 1.0);
  float rB = uPlanetSun.x + soraThickness() / 50.0 * (exp(float(a + 1) / float(A - 1) * log(51.0)) - 1.0);
  float muA = soraHorizonCosine(rA);
  float muB = soraHorizonCosine(rB);
  int m; float fm; soraCell(sqrt(clamp((mu - muA) / (1.0 - muA), 0.0, 1.0)) * float(M - 1), 0, M - 2, m, fm);
  int n; float fn; soraCell(sqrt(clamp((mu - muB) / (1.0 - muB), 0.0, 1.0)) * float(M - 1), 0, M - 2, n, fn);
  vec3 t0 = mix(texelFetch(uTransmittance, ivec2(m, a), 0).xyz, texelFetch(uTransmittance, ivec2(m + 1, a), 0).xyz, fm);
  vec3 t1 = mix(texelFetch(uTransmittance, ivec2(n, a + 1), 0).xyz, texelFetch(uTransmittance, ivec2(n + 1, a + 1), 0).xyz, fn);
  return mix(t0, t1, fa);
}

// Global horizontal irradiance (XYZ, W m^-2 nm^-1) at altitude h with the
// sun at eDeg: the diffuse table plus the direct beam. The irradiance table
// has its own altitude axis (the same mapping, its height's nodes:
// manifest tables.irradiance.altitude_nodes).
vec3 soraGroundIrradianceXyz(float h, float eDeg) {
  h = clamp(h, 0.0, soraThickness());
  int A = textureSize(uIrradiance, 0).y;
  int a; float fa; soraCell(soraAltitudeCoordinate(h, A), 0, A - 2, a, fa);
  int s; float fs; soraCell(soraSunCoordinate(eDeg), 0, uSkyNodes.x - 2, s, fs);
  vec3 low = mix(texelFetch(uIrradiance, ivec2(s, a), 0).xyz, texelFetch(uIrradiance, ivec2(s, a + 1), 0).xyz, fa);
  vec3 high = mix(texelFetch(uIrradiance, ivec2(s + 1, a), 0).xyz, texelFetch(uIrradiance, ivec2(s + 1, a + 1), 0).xyz, fa);
  float muSun = sin(radians(eDeg));
  return soraMixLog(low, high, fs) + uSunIrradianceXyz * soraTransmittance(h, muSun) * max(muSun, 0.0);
}

// The sun disc's radiance at angle gamma (rad) from its centre.
vec3 soraSunDiscXyz(float h, float eDeg, float gamma) {
  float alpha = uPlanetSun.z;
  if (gamma >= alpha) return vec3(0.0);
  float u = uPlanetSun.w;
  float cosA = sqrt(max(1.0 - (gamma / alpha) * (gamma / alpha), 0.0));
  float shape = (1.0 - u * (1.0 - cosA)) / (SORA_PI * alpha * alpha * (1.0 - u / 3.0));
  return uSunIrradianceXyz * soraTransmittance(h, sin(radians(eDeg))) * shape;
}

// Zenith angle and azimuth from the sun's of view v seen from a point
// whose local vertical is `up`, the sun toward `sun` (unit vectors).
vec2 soraLocalView(vec3 v, vec3 up, vec3 sun) {
  float mu = clamp(dot(v, up), -1.0, 1.0);
  vec3 vh = v - up * mu;
  vec3 sh = sun - up * dot(sun, up);
  float nv = length(vh), ns = length(sh);
  float cosPhi = (nv > 1e-6 && ns > 1e-6) ? clamp(dot(vh, sh) / (nv * ns), -1.0, 1.0) : 1.0;
  return vec2(acos(mu), acos(cosPhi));
}

// The sun's elevation (degrees) from its direction in the eye's
// east-north-up frame: atan(z, |xy|), not asin(z), whose float32 value
// near the zenith (SwiftShader's) was 0.12 degrees low a quarter of a
// degree below it, a step in the zenith's brightness against the sun.
float soraSunElevationDeg(vec3 sun) {
  return degrees(atan(sun.z, length(sun.xy)));
}

// Sky radiance for an eye at altitude h looking along unit v, the sun
// toward unit sun; v and sun in the eye's east-north-up frame (z up). The
// table's read (soraSkyXyz): the entry for an eye on the ground; for an
// eye above it soraRaisedSkyView (at the end of this file).
vec3 soraSkyView(float h, vec3 v, vec3 sun) {
  vec2 zp = soraLocalView(v, vec3(0.0, 0.0, 1.0), sun);
  return soraSkyXyz(h, zp.x, zp.y, soraSunElevationDeg(sun));
}

// Transmittance of the segment from the eye at altitude h to the point at
// distance d (m) along v (a ratio of two reads of the transmittance table;
// of the reversed rays when v meets the ground), each channel at most 1.
vec3 soraSegmentTransmittance(float h, vec3 v, float d) {
  float R = uPlanetSun.x;
  h = clamp(h, 0.0, soraThickness());
  float r = R + h;
  // The point relative to the planet's centre; computed in a form that
  // keeps precision for d << r.
  vec3 p = vec3(v.xy * d, r + v.z * d);
  float rp = length(p);
  vec3 upP = p / rp;
  float hp = clamp(rp - R, 0.0, soraThickness());
  float mu = v.z;
  float muP = dot(v, upP);
  vec3 near, far;
  if (mu < soraHorizonCosine(r)) {
    near = soraTransmittance(hp, -muP);
    far = soraTransmittance(h, -mu);
  } else {
    near = soraTransmittance(h, mu);
    far = soraTransmittance(hp, muP);
  }
  return min(near / max(far, vec3(SORA_FLOOR)), vec3(1.0));
}

// Length (m) of the ray from altitude h along view cosine mu to the ground
// (below the horizon) or the top of the atmosphere.
float soraRayLength(float h, float mu) {
  float r = uPlanetSun.x + clamp(h, 0.0, soraThickness());
  float b = r * mu, c = r * r;
  if (mu < soraHorizonCosine(r)) return max(-b - sqrt(max(b * b - c + uPlanetSun.x * uPlanetSun.x, 0.0)), 0.0);
  return max(-b + sqrt(max(b * b - c + uPlanetSun.y * uPlanetSun.y, 0.0)), 0.0);
}

// Aerial perspective between the eye at altitude h and the point at
// distance d (m) along v: in-scattered radiance (XYZ) and the segment's
// transmittance, so that L = L_point * transmittance + inscattered. The
// light is S(x, v) R(x, v, d) w per channel: S the sky, R the aerial
// table (read as the sky, linear between its distance slices, spaced in
// ln d from thickness / 1000 to the ray's end) and w = (1 - T) / (1 -
// T_end) the segment's share of the whole ray's extinction.
void soraAerialPerspectiveFromSky(float h, vec3 v, vec3 sun, float d, out vec3 inscattered, out vec3 transmittance);

void soraAerialPerspective(float h, vec3 v, vec3 sun, float d, out vec3 inscattered, out vec3 transmittance) {
  // Tables without an aerial table (uAerialNodes zero): the sky's difference.
  if (uAerialNodes.z < 2) {
    soraAerialPerspectiveFromSky(h, v, sun, d, inscattered, transmittance);
    return;
  }
  h = clamp(h, 0.0, soraThickness());
  transmittance = soraSegmentTransmittance(h, v, d);
  float length_ = soraRayLength(h, v.z);
  vec3 whole = soraSegmentTransmittance(h, v, length_);
  vec3 all_ = vec3(1.0) - whole;
  vec3 share = mix(vec3(1.0), clamp((vec3(1.0) - transmittance) / max(all_, vec3(1e-9)), 0.0, 1.0), greaterThan(all_, vec3(1e-9)));
  float nearest = soraThickness() / 1000.0;
  float last = max(length_, 2.0 * nearest);
  int D = uAerialNodes.z;
  float x = clamp(log(max(d, nearest) / nearest) / log(last / nearest), 0.0, 1.0) * float(D - 1);
  int j; float fj; soraCell(x, 0, D - 2, j, fj);
  vec2 zp = soraLocalView(v, vec3(0.0, 0.0, 1.0), sun);
  float eDeg = soraSunElevationDeg(sun);
  vec3 sky = soraSkyXyz(h, zp.x, zp.y, eDeg);
  vec3 ratio = soraLayersXyz(uAerial, uAerialNodes.x, ivec2(0), uAerialNodes.y, 0, j, fj, h, zp.x, zp.y, eDeg);
  inscattered = sky * ratio * share;
}

// The former aerial perspective from the sky table alone, S(x, v) - T S(p,
// v) (S read at each end's own altitude, zenith angle and sun elevation):
// no aerial table needed, but not within 2 % of the library for short
// segments (docs/engine-tables.md).
void soraAerialPerspectiveFromSky(float h, vec3 v, vec3 sun, float d, out vec3 inscattered, out vec3 transmittance) {
  float R = uPlanetSun.x;
  h = clamp(h, 0.0, soraThickness());
  vec3 p = vec3(v.xy * d, R + h + v.z * d);
  vec3 upP = normalize(p);
  float hp = clamp(length(p) - R, 0.0, soraThickness());
  transmittance = soraSegmentTransmittance(h, v, d);
  vec3 atEye = soraSkyView(h, v, sun);
  vec2 zp = soraLocalView(v, upP, sun);
  vec3 atPoint = soraSkyXyz(hp, zp.x, zp.y, degrees(asin(clamp(dot(sun, upP), -1.0, 1.0))));
  inscattered = max(atEye - transmittance * atPoint, vec3(0.0));
}

// Linear sRGB (Rec. 709 primaries, D65) of XYZ; the manifest's
// colour.linear_srgb_from_xyz.
vec3 soraXyzToLinearSrgb(vec3 xyz) {
  // Columns of the matrix (GLSL's mat3 constructor is column-major).
  return mat3(3.2406, -0.9689, 0.0557,
              -1.5372, 1.8758, -0.2040,
              -0.4986, 0.0415, 1.0570) * xyz;
}

// ---------------------------------------------------------------------------
// The aerial-perspective march (march.bin; `sora tables --march`). The
// functions below are crates/sora/src/engine_tables/lookup.rs's
// MarchTables::aerial_perspective_xyz and its helpers, step by step, with
// the same names (the Rust lookup is the oracle). Bind (docs/engine-tables.md,
// "Binding the tables"):
//   uMarchSource  sampler2DArray, RGBA16F: the array log_source (ln R) with
//                 its channels four to a texel (the last texel padded), texel
//                 (v * T + c / 4, s * azimuth_nodes + f, k), T = ceil(channels / 4):
//                 view zenith v, sun node s, azimuth f, level k
//   uMarchTables  sampler2D, R32F, SORA_MARCH_WIDTH texels wide: every other
//                 (32-bit) array of march.bin in file order, one after another;
//                 value n of the whole at texel (n % width, n / width)
// Uniforms, from the manifest's tables.march: uMarchOffsets[a] and
// uMarchLengths[a] the start (in values, within uMarchTables) and length of
// array a (SORA_MARCH_* below), the rest as named.
uniform highp sampler2DArray uMarchSource;
uniform highp sampler2D uMarchTables;
uniform int uMarchOffsets[20];
uniform int uMarchLengths[20];
// wavelengths, species, sun_nodes, density_nodes (zero: no march tables)
uniform ivec4 uMarchCounts;
// azimuth_nodes, view_zenith_nodes (of the source)
uniform ivec2 uMarchSourceNodes;
// sun_column_nodes (altitude A, view cosine M)
uniform ivec2 uMarchColumnNodes;
// phase_nodes, kernel_angles
uniform ivec2 uMarchPhaseNodes;
// kernel_blend_start_rad, kernel_radius_rad
uniform vec2 uMarchKernel;
// beam_first_elevation_deg, beam_step_deg (zero without a peak beam)
uniform vec2 uMarchBeamAxis;
// beam_elevations (zero without a peak beam)
uniform int uMarchBeamElevations;
// beam_range_deg: lowest, blend, highest
uniform vec3 uMarchBeamRange;
// has_forward_peaks (0 or 1)
uniform int uMarchPeaks;
// dark_log_source
uniform float uMarchDarkLogSource;
// march_steps: along the segment, beyond the point
uniform ivec2 uMarchSteps;

// The arrays of uMarchTables (march.bin's order, log_source left out).
const int SORA_MARCH_LEVELS = 0;            // source_levels_m
const int SORA_MARCH_SUN_ZENITH = 1;        // source_sun_zenith_rad
const int SORA_MARCH_CHANNELS = 2;          // source_wavelength_indices
const int SORA_MARCH_EXTINCTION = 3;
const int SORA_MARCH_SCALED_EXTINCTION = 4;
const int SORA_MARCH_SCALED_SCATTERING = 5;
const int SORA_MARCH_SCATTERING = 6;
const int SORA_MARCH_SOLAR = 7;
const int SORA_MARCH_XYZ = 8;
const int SORA_MARCH_DENSITY = 9;
const int SORA_MARCH_SUN_COLUMNS = 10;
const int SORA_MARCH_PHASE = 11;
const int SORA_MARCH_SMOOTH_PHASE = 12;
const int SORA_MARCH_KERNEL_X = 13;
const int SORA_MARCH_KERNEL = 14;
const int SORA_MARCH_BEAM_ALTITUDES = 15;   // beam_altitudes_m
const int SORA_MARCH_LN_BEAM = 16;
const int SORA_MARCH_GROUND_DIFFUSE = 17;
const int SORA_MARCH_GROUND_DIRECT = 18;
const int SORA_MARCH_AZIMUTHS = 19;         // source_azimuth_rad
const int SORA_MARCH_WIDTH = 2048;
// Capacities of the per-pixel arrays (not the tables' counts, which come
// from the uniforms): wavelengths and species at most.
const int SORA_MARCH_MAX_WAVELENGTHS = 32;
const int SORA_MARCH_MAX_SPECIES = 4;
const int SORA_MARCH_MAX_ROWS = SORA_MARCH_MAX_WAVELENGTHS * SORA_MARCH_MAX_SPECIES;

// acos(c) as atan2 (SwiftShader's acos is coarser: the march at sun -4
// degrees was 1.03 % off sora render at 10 km with it, 0.79 % with this).
float soraMarchAcos(float c) { return atan(sqrt(max((1.0 - c) * (1.0 + c), 0.0)), c); }

// Value n of march.bin's array `array`.
float soraMarchValue(int array, int n) {
  int at = uMarchOffsets[array] + n;
  return texelFetch(uMarchTables, ivec2(at % SORA_MARCH_WIDTH, at / SORA_MARCH_WIDTH), 0).x;
}

// The cell of the ascending array `array` holding x and the fraction of
// the way across it, clamped to the nodes (lookup.rs's locate; a binary
// search for partition_point).
void soraMarchLocate(int array, float x, out int k, out float f) {
  int count = uMarchLengths[array];
  int low = 0, high = count;
  while (low < high) {
    int middle = (low + high) / 2;
    if (soraMarchValue(array, middle) <= x) low = middle + 1;
    else high = middle;
  }
  k = clamp(low, 1, count - 1) - 1;
  float a = soraMarchValue(array, k), b = soraMarchValue(array, k + 1);
  f = clamp((x - a) / (b - a), 0.0, 1.0);
}

// Cosine of the horizon's zenith angle at altitude h (axes::horizon_cosine,
// written for float precision: 1 - (R / r)^2 = h (2 R + h) / r^2).
float soraMarchHorizonCosine(float h) {
  float R = uPlanetSun.x;
  h = max(h, 0.0);
  return -sqrt(h * (2.0 * R + h)) / (R + h);
}

// Altitude (m) of node `index` of `nodes` (axes::altitude_of_node).
float soraMarchAltitudeOfNode(int index, int nodes) {
  float h0 = soraThickness() / 50.0;
  return min(h0 * (exp(float(index) / float(nodes - 1) * log(51.0)) - 1.0), soraThickness());
}

// The march's k-th of `steps` nodes along a stretch of `length_` m: its
// distance from the stretch's start and its weight, m (march_node).
void soraMarchNode(float length_, int k, int steps, out float at, out float ds) {
  float u = (float(k) + 0.5) / float(steps);
  at = u * u * length_;
  ds = 2.0 * u * length_ / float(steps);
}

// The species' relative densities at altitude h (densities).
void soraMarchDensities(float h, out float rho[SORA_MARCH_MAX_SPECIES]) {
  int s = uMarchCounts.y, nodes = uMarchCounts.w;
  float x = clamp(h / soraThickness(), 0.0, 1.0) * float(nodes - 1);
  int n; float f; soraCell(x, 0, nodes - 2, n, f);
  for (int j = 0; j < s; j++) {
    float a = soraMarchValue(SORA_MARCH_DENSITY, n * s + j);
    float b = soraMarchValue(SORA_MARCH_DENSITY, (n + 1) * s + j);
    rho[j] = a + (b - a) * f;
  }
}

// p_j and the smooth phase at the scattering angle theta, [j * w + i]
// (phases: linear in u = sqrt(theta / pi)).
void soraMarchPhases(float theta, out float exactPhase[SORA_MARCH_MAX_ROWS], out float smoothPhase[SORA_MARCH_MAX_ROWS]) {
  int w = uMarchCounts.x, s = uMarchCounts.y, P = uMarchPhaseNodes.x;
  float x = sqrt(clamp(theta / SORA_PI, 0.0, 1.0)) * float(P - 1);
  int t; float f; soraCell(x, 0, P - 2, t, f);
  for (int j = 0; j < s; j++) {
    for (int i = 0; i < w; i++) {
      int n0 = (j * P + t) * w + i, n1 = (j * P + t + 1) * w + i;
      float a = soraMarchValue(SORA_MARCH_PHASE, n0), b = soraMarchValue(SORA_MARCH_PHASE, n1);
      exactPhase[j * w + i] = a + (b - a) * f;
      a = soraMarchValue(SORA_MARCH_SMOOTH_PHASE, n0);
      b = soraMarchValue(SORA_MARCH_SMOOTH_PHASE, n1);
      smoothPhase[j * w + i] = a + (b - a) * f;
    }
  }
}

// The sun zenith cell of a sun cosine (locate_sun: linear in the angle).
void soraMarchLocateSun(float sunCosine, out int node, out float t) {
  soraMarchLocate(SORA_MARCH_SUN_ZENITH, soraMarchAcos(clamp(sunCosine, -1.0, 1.0)), node, t);
}

// The azimuth cell of the cosine of an azimuth from the sun
// (locate_azimuth): located by the angle among source_azimuth_rad, linear
// in the angle, but in the cosine within the first and the last cell (ln
// R is even in the azimuth about 0 and pi).
void soraMarchLocateAzimuth(float cosAzimuth, out int f, out float t) {
  float c = clamp(cosAzimuth, -1.0, 1.0);
  soraMarchLocate(SORA_MARCH_AZIMUTHS, soraMarchAcos(c), f, t);
  if (f == 0 || f + 2 == uMarchLengths[SORA_MARCH_AZIMUTHS]) {
    float a = cos(soraMarchValue(SORA_MARCH_AZIMUTHS, f)), b = cos(soraMarchValue(SORA_MARCH_AZIMUTHS, f + 1));
    t = clamp((a - c) / (a - b), 0.0, 1.0);
  }
}

// ln R at a node, quadrilinear in ln R over altitude level, sun zenith
// node, view zenith and azimuth (source_azimuth_rad's nodes), at every wavelength (log_source and
// source_table.rs's interpolate_log_source): the source's channels, then
// linear in the wavelength's index between them.
void soraMarchLogSource(float altitude, float sunCosine, float viewCosine, float cosAzimuth, out float logSource[SORA_MARCH_MAX_WAVELENGTHS]) {
  int w = uMarchCounts.x;
  int channelCount = uMarchLengths[SORA_MARCH_CHANNELS];
  int texels = (channelCount + 3) / 4;
  int azimuths = uMarchSourceNodes.x, views = uMarchSourceNodes.y;
  int k; float tz; soraMarchLocate(SORA_MARCH_LEVELS, altitude, k, tz);
  int s; float ts; soraMarchLocateSun(sunCosine, s, ts);
  float y = soraMarchAcos(clamp(viewCosine, -1.0, 1.0)) / SORA_PI * float(views - 1);
  int v = min(int(y), views - 2);
  float tv = y - float(v);
  int f; float tf; soraMarchLocateAzimuth(cosAzimuth, f, tf);
  float channels[SORA_MARCH_MAX_WAVELENGTHS];
  for (int c4 = 0; c4 < texels; c4++) {
    vec4 sum = vec4(0.0);
    for (int n = 0; n < 8; n++) {
      int kk = k + (n & 1), ss = s + ((n >> 1) & 1), ff = f + (n >> 2);
      float weight = ((n & 1) == 1 ? tz : 1.0 - tz) * (((n >> 1) & 1) == 1 ? ts : 1.0 - ts) * ((n >> 2) == 1 ? tf : 1.0 - tf);
      vec4 low = texelFetch(uMarchSource, ivec3(v * texels + c4, ss * azimuths + ff, kk), 0);
      vec4 high = texelFetch(uMarchSource, ivec3((v + 1) * texels + c4, ss * azimuths + ff, kk), 0);
      sum += weight * (1.0 - tv) * low + weight * tv * high;
    }
    for (int n = 0; n < 4; n++) {
      if (4 * c4 + n < channelCount) channels[4 * c4 + n] = sum[n];
    }
  }
  // Linear in the wavelength's index between the kept ones.
  if (channelCount == 1) {
    for (int i = 0; i < w; i++) logSource[i] = channels[0];
    return;
  }
  for (int pair = 0; pair + 1 < channelCount; pair++) {
    int a = int(soraMarchValue(SORA_MARCH_CHANNELS, pair) + 0.5);
    int b = int(soraMarchValue(SORA_MARCH_CHANNELS, pair + 1) + 0.5);
    for (int i = a; i <= b; i++) {
      float t = float(i - a) / float(b - a);
      logSource[i] = channels[pair] + t * (channels[pair + 1] - channels[pair]);
    }
  }
}

// The species' columns toward the sun from altitude h with the sun's
// zenith cosine mu there (sun_columns: bilinear over the transmittance
// table's axes); false below the point's horizon (the planet's shadow).
bool soraMarchSunColumns(float h, float mu, out float toSun[SORA_MARCH_MAX_SPECIES]) {
  float R = uPlanetSun.x;
  int s = uMarchCounts.y;
  int aCount = uMarchColumnNodes.x, mCount = uMarchColumnNodes.y;
  h = clamp(h, 0.0, soraThickness());
  for (int j = 0; j < s; j++) toSun[j] = 0.0;
  if (mu < soraMarchHorizonCosine(h)) return false;
  int a; float fa; soraCell(soraAltitudeCoordinate(h, aCount), 0, aCount - 2, a, fa);
  for (int row = 0; row < 2; row++) {
    float muH = soraMarchHorizonCosine(soraMarchAltitudeOfNode(a + row, aCount));
    int m; float fm;
    soraCell(sqrt(clamp((mu - muH) / (1.0 - muH), 0.0, 1.0)) * float(mCount - 1), 0, mCount - 2, m, fm);
    float weight = row == 0 ? 1.0 - fa : fa;
    for (int j = 0; j < s; j++) {
      float p = soraMarchValue(SORA_MARCH_SUN_COLUMNS, ((a + row) * mCount + m) * s + j);
      float q = soraMarchValue(SORA_MARCH_SUN_COLUMNS, ((a + row) * mCount + m + 1) * s + j);
      toSun[j] += weight * (p + (q - p) * fm);
    }
  }
  return true;
}

// The peak beam B at altitude h with the sun's zenith cosine mu into
// `beam`, and the share the scaled beam takes (peak_beam: 0 beyond the
// table's elevations).
float soraMarchPeakBeam(float h, float mu, out float beam[SORA_MARCH_MAX_WAVELENGTHS]) {
  // Defined where the share is 0 too (it multiplies B - through there).
  for (int i = 0; i < uMarchCounts.x; i++) beam[i] = 0.0;
  int elevations = uMarchBeamElevations;
  if (elevations < 2) return 0.0;
  float elevation = degrees(atan(clamp(mu, -1.0, 1.0), sqrt(max((1.0 - mu) * (1.0 + mu), 0.0))));
  float lowest = uMarchBeamRange.x, blend = uMarchBeamRange.y, highest = uMarchBeamRange.z;
  if (!(elevation >= lowest && elevation < highest)) return 0.0;
  float share = min((highest - elevation) / (highest - blend), 1.0);
  int last = uMarchLengths[SORA_MARCH_BEAM_ALTITUDES] - 1;
  float z = clamp(h, 0.0, soraMarchValue(SORA_MARCH_BEAM_ALTITUDES, last));
  int a; float ta; soraMarchLocate(SORA_MARCH_BEAM_ALTITUDES, z, a, ta);
  float xe = clamp((elevation - uMarchBeamAxis.x) / uMarchBeamAxis.y, 0.0, float(elevations - 1));
  int e = min(int(xe), elevations - 2);
  float te = xe - float(e);
  int w = uMarchCounts.x;
  for (int i = 0; i < w; i++) {
    float c00 = soraMarchValue(SORA_MARCH_LN_BEAM, (a * elevations + e) * w + i);
    float c01 = soraMarchValue(SORA_MARCH_LN_BEAM, (a * elevations + e + 1) * w + i);
    float c10 = soraMarchValue(SORA_MARCH_LN_BEAM, ((a + 1) * elevations + e) * w + i);
    float c11 = soraMarchValue(SORA_MARCH_LN_BEAM, ((a + 1) * elevations + e + 1) * w + i);
    beam[i] = exp((1.0 - ta) * ((1.0 - te) * c00 + te * c01) + ta * ((1.0 - te) * c10 + te * c11));
  }
  return share;
}

// The forward-peak term (W m^-2 sr^-1 nm^-1) at wavelength i and the
// scattering angle theta (peak_radiance): `rows` is the species rows
// already summed with their weights beta_sca,j q_j (the smooth phase), q
// and qx the peak-only rows Q and Q X; E rows plus within the kernel's
// radius (1 - wide) E Q e^(-X) G(theta; X) e^X at X = Q X / Q.
float soraMarchPeakRadiance(float theta, int i, float rows, float q, float qx) {
  int w = uMarchCounts.x;
  float solar = soraMarchValue(SORA_MARCH_SOLAR, i);
  float out_ = solar * rows;
  float start = uMarchKernel.x, radius = uMarchKernel.y;
  int angles = uMarchPhaseNodes.y;
  int xCount = uMarchLengths[SORA_MARCH_KERNEL_X];
  if (uMarchLengths[SORA_MARCH_KERNEL] == 0 || theta >= radius || q <= 0.0) return out_;
  float wide = clamp((theta - start) / (radius - start), 0.0, 1.0);
  float position = sqrt(theta / radius) * float(angles - 1);
  int t = min(int(position), angles - 2);
  float ft = position - float(t);
  float last = soraMarchValue(SORA_MARCH_KERNEL_X, xCount - 1);
  float xMean = clamp(qx / q, 0.0, last);
  int x; float fx; soraMarchLocate(SORA_MARCH_KERNEL_X, xMean, x, fx);
  float k00 = soraMarchValue(SORA_MARCH_KERNEL, (x * angles + t) * w + i);
  float k01 = soraMarchValue(SORA_MARCH_KERNEL, (x * angles + t + 1) * w + i);
  float k10 = soraMarchValue(SORA_MARCH_KERNEL, ((x + 1) * angles + t) * w + i);
  float k11 = soraMarchValue(SORA_MARCH_KERNEL, ((x + 1) * angles + t + 1) * w + i);
  float value = (1.0 - fx) * ((1.0 - ft) * k00 + ft * k01) + fx * ((1.0 - ft) * k10 + ft * k11);
  return out_ + (1.0 - wide) * solar * q * value * exp(xMean);
}

// The ground's light (W m^-2 sr^-1 nm^-1) at wavelength i with the sun's
// zenith cosine sunCosine at the ground point (ground_light's lerp: in
// ln between sun nodes where both are positive).
float soraMarchGroundLight(int i, float sunCosine) {
  int w = uMarchCounts.x;
  int node; float t; soraMarchLocateSun(sunCosine, node, t);
  float light = 0.0;
  for (int table = SORA_MARCH_GROUND_DIFFUSE; table <= SORA_MARCH_GROUND_DIRECT; table++) {
    float a = soraMarchValue(table, node * w + i), b = soraMarchValue(table, (node + 1) * w + i);
    light += (a > 0.0 && b > 0.0) ? exp((1.0 - t) * log(a) + t * log(b)) : (1.0 - t) * a + t * b;
  }
  return light;
}

// Altitude (m) of the point at distance t along unit v from the eye at
// altitude h, and its radius: written for float precision (|p|^2 - R^2 =
// t^2 + 2 r0 v.z t + h (2 R + h)).
float soraMarchAltitudeAlong(float h, vec3 v, float t, out float r) {
  float R = uPlanetSun.x;
  float r0 = R + h;
  vec3 p = vec3(v.xy * t, r0 + v.z * t);
  r = length(p);
  return max((t * t + 2.0 * r0 * v.z * t + h * (2.0 * R + h)) / (r + R), 0.0);
}

// Aerial perspective by the march (MarchTables::aerial_perspective_xyz):
// an eye at altitude h (m), the unit view v and sun (east-north-up), a
// point at distance d (m): the light scattered into the segment (XYZ, W
// m^-2 sr^-1 nm^-1) and the segment's transmittance (XYZ of the
// transmitted solar spectrum over XYZ of the solar spectrum per channel),
// so that L = L_point * transmittance + inscattered.
//
// uMarchSteps.x nodes along the segment (u = sqrt(s / length) uniform, the
// midpoint rule) and uMarchSteps.y from the point to the ray's end; at each
// node the densities and columns from the eye (trapezoids), the columns
// toward the sun, the source ln R and the peak beam. Gathered per
// wavelength: single scattering, the scaled field over the segment and
// beyond it, the forward-peak integrals; then
//   L_air = S_seg + F_seg + (1 - T / T*) (F_beyond + G_sky) + P(forward) - P(behind).
// As lookup.rs, except that the forward-peak rows are kept summed over
// species with their weights beta_sca,j q_j (peak_radiance's first sum;
// the same sum, taken per node), and each row only where it is read: the
// species rows over the segment (forward_segment) and over the ray beyond
// it (scaled - scaled_segment), Q and Q X over both (forward_segment and
// forward - forward_segment).
//
// soraMarchXyz is lookup.rs's MarchTables::march_xyz: with `whole` false
// the above; with `whole` true (MarchTables::whole_ray_xyz, d the split)
// the nodes beyond d are counted as the segment's too, so that the light
// and the transmittance are the whole ray's, its nodes crowded toward the
// eye and toward d.
void soraMarchXyz(float h, vec3 v, vec3 sun, float d, bool whole, out vec3 inscattered, out vec3 transmittance);

void soraAerialPerspectiveMarch(float h, vec3 v, vec3 sun, float d, out vec3 inscattered, out vec3 transmittance) {
  soraMarchXyz(h, v, sun, d, false, inscattered, transmittance);
}

// The march's light of the whole ray from the eye at altitude h along v to
// its end (the top or the ground) and the whole ray's transmittance, its
// two stretches of nodes split at splitM (MarchTables::whole_ray_xyz).
void soraWholeRayMarch(float h, vec3 v, vec3 sun, float splitM, out vec3 light, out vec3 transmittance) {
  soraMarchXyz(h, v, sun, splitM, true, light, transmittance);
}

void soraMarchXyz(float h, vec3 v, vec3 sun, float d, bool whole, out vec3 inscattered, out vec3 transmittance) {
  int w = uMarchCounts.x, s = uMarchCounts.y;
  float R = uPlanetSun.x;
  float thickness = soraThickness();
  h = clamp(h, 0.0, thickness);
  float r0 = R + h;
  // segment_in_atmosphere from inside the atmosphere (enter = 0), its
  // roots in the forms without cancellation.
  float b = r0 * v.z;
  float cTop = (h - thickness) * (r0 + uPlanetSun.y);
  float rootTop = sqrt(max(b * b - cTop, 0.0));
  float topFar = b > 0.0 ? -cTop / (b + rootTop) : -b + rootTop;
  inscattered = vec3(0.0);
  transmittance = vec3(1.0);
  if (topFar <= 0.0) return;
  float enter = 0.0;
  float exit_ = topFar;
  float cGround = h * (2.0 * R + h);
  float discGround = b * b - cGround;
  bool onGround = false;
  if (b < 0.0 && discGround >= 0.0) {
    float groundNear = cGround / (-b + sqrt(discGround));
    if (groundNear >= enter && groundNear < topFar) {
      exit_ = groundNear;
      onGround = true;
    }
  }
  float length_ = max(min(exit_, d) - enter, 0.0);
  float beyond = exit_ - enter - length_;
  // The phase functions at the view's one scattering angle.
  float cosTheta = clamp(dot(v, sun), -1.0, 1.0);
  // theta from the chord, 2 atan(|v - sun|, |v + sun|), not from the
  // cosine: near the sun 1 - cos(theta) is lost to 32-bit rounding
  // (SwiftShader: 2.15 degrees for a view 1.46 degrees from the sun by
  // acos as atan2, the forward peak's phase and kernel read there).
  float theta = 2.0 * atan(length(v - sun), length(v + sun));
  float exactPhase[SORA_MARCH_MAX_ROWS], smoothPhase[SORA_MARCH_MAX_ROWS];
  soraMarchPhases(theta, exactPhase, smoothPhase);
  float extinction[SORA_MARCH_MAX_ROWS], scaledExtinction[SORA_MARCH_MAX_ROWS];
  float scaledScattering[SORA_MARCH_MAX_ROWS], scattering[SORA_MARCH_MAX_ROWS];
  for (int n = 0; n < w * s; n++) {
    extinction[n] = soraMarchValue(SORA_MARCH_EXTINCTION, n);
    scaledExtinction[n] = soraMarchValue(SORA_MARCH_SCALED_EXTINCTION, n);
    scaledScattering[n] = soraMarchValue(SORA_MARCH_SCALED_SCATTERING, n);
    scattering[n] = soraMarchValue(SORA_MARCH_SCATTERING, n);
  }
  float single[SORA_MARCH_MAX_WAVELENGTHS], field[SORA_MARCH_MAX_WAVELENGTHS], fieldBeyond[SORA_MARCH_MAX_WAVELENGTHS];
  // The species rows (summed, see above) and Q, Q X.
  float forwardSegment[SORA_MARCH_MAX_WAVELENGTHS], scaledBeyond[SORA_MARCH_MAX_WAVELENGTHS];
  float qSegment[SORA_MARCH_MAX_WAVELENGTHS], qxSegment[SORA_MARCH_MAX_WAVELENGTHS];
  float qBeyond[SORA_MARCH_MAX_WAVELENGTHS], qxBeyond[SORA_MARCH_MAX_WAVELENGTHS];
  for (int i = 0; i < w; i++) {
    single[i] = 0.0; field[i] = 0.0; fieldBeyond[i] = 0.0;
    forwardSegment[i] = 0.0; scaledBeyond[i] = 0.0;
    qSegment[i] = 0.0; qxSegment[i] = 0.0; qBeyond[i] = 0.0; qxBeyond[i] = 0.0;
  }
  float columns[SORA_MARCH_MAX_SPECIES], columnsSegment[SORA_MARCH_MAX_SPECIES];
  float rho[SORA_MARCH_MAX_SPECIES], previousRho[SORA_MARCH_MAX_SPECIES], toSun[SORA_MARCH_MAX_SPECIES];
  float logSource[SORA_MARCH_MAX_WAVELENGTHS], beam[SORA_MARCH_MAX_WAVELENGTHS];
  for (int j = 0; j < s; j++) { columns[j] = 0.0; columnsSegment[j] = 0.0; toSun[j] = 0.0; }
  float unused;
  soraMarchDensities(soraMarchAltitudeAlong(h, v, enter, unused), previousRho);
  float previous = 0.0;
  int steps = uMarchSteps.x, stepsBeyond = uMarchSteps.y;
  bool segmentDone = false;
  for (int node = 0; node < steps + stepsBeyond; node++) {
    // Beyond the first stretch, the whole ray's nodes are the segment's.
    bool inSegment = node < steps || whole;
    float at, ds;
    if (node < steps) {
      soraMarchNode(length_, node, steps, at, ds);
    } else {
      soraMarchNode(beyond, node - steps, stepsBeyond, at, ds);
      at += length_;
    }
    if (!inSegment && !segmentDone) {
      soraMarchDensities(soraMarchAltitudeAlong(h, v, enter + length_, unused), rho);
      for (int j = 0; j < s; j++) {
        columns[j] += 0.5 * (previousRho[j] + rho[j]) * (length_ - previous);
        previousRho[j] = rho[j];
        columnsSegment[j] = columns[j];
      }
      previous = length_;
      segmentDone = true;
    }
    if (ds <= 0.0) continue;
    float r;
    float altitude = soraMarchAltitudeAlong(h, v, enter + at, r);
    // The cosines at the point: v.p / r and sun.p / r.
    float viewCosine = clamp((enter + at + r0 * v.z) / r, -1.0, 1.0);
    float sunCosine = clamp(((enter + at) * cosTheta + r0 * sun.z) / r, -1.0, 1.0);
    float sines = sqrt(max((1.0 - viewCosine * viewCosine) * (1.0 - sunCosine * sunCosine), 0.0));
    float cosAzimuth = sines > 1e-6 ? clamp((cosTheta - viewCosine * sunCosine) / sines, -1.0, 1.0) : 1.0;
    soraMarchLogSource(altitude, sunCosine, viewCosine, cosAzimuth, logSource);
    soraMarchDensities(altitude, rho);
    for (int j = 0; j < s; j++) columns[j] += 0.5 * (previousRho[j] + rho[j]) * (at - previous);
    previous = at;
    for (int i = 0; i < w; i++) {
      float tau = 0.0, scatteringSum = 0.0;
      for (int j = 0; j < s; j++) {
        tau += scaledExtinction[i * s + j] * columns[j];
        scatteringSum += scaledScattering[i * s + j] * rho[j];
      }
      if (logSource[i] > uMarchDarkLogSource) {
        float add = ds * scatteringSum * exp(logSource[i] - tau);
        if (inSegment) field[i] += add;
        else fieldBeyond[i] += add;
      }
    }
    bool lit = soraMarchSunColumns(altitude, sunCosine, toSun);
    float share = uMarchPeaks == 1 ? soraMarchPeakBeam(altitude, sunCosine, beam) : 0.0;
    for (int i = 0; i < w; i++) {
      vec4 depths = vec4(0.0);
      float peak = 0.0, source = 0.0, rowWeight = 0.0;
      for (int j = 0; j < s; j++) {
        float scaledExt = scaledExtinction[i * s + j], ext = extinction[i * s + j];
        float sunColumn = lit ? toSun[j] : 0.0;
        depths += vec4(scaledExt * columns[j], ext * columns[j], scaledExt * sunColumn, ext * sunColumn);
        peak += (ext - scaledExt) * rho[j];
        source += scattering[i * s + j] * exactPhase[j * w + i] * rho[j];
        rowWeight += scattering[i * s + j] * smoothPhase[j * w + i] * rho[j];
      }
      vec4 transmitted = exp(-depths);
      float viewBeam = transmitted.x, viewDirect = transmitted.y;
      float sunBeam = lit ? transmitted.z : 0.0, sunDirect = lit ? transmitted.w : 0.0;
      if (inSegment && lit) {
        single[i] += ds * soraMarchValue(SORA_MARCH_SOLAR, i) * source * viewDirect * sunDirect;
      }
      if (uMarchPeaks != 1) continue;
      // As the library's march (add_tilted_forward_peak).
      float through = sunBeam - sunDirect;
      float scattered = through + share * (beam[i] - through);
      float excess = ds * (viewBeam * scattered + sunDirect * (viewBeam - viewDirect));
      float beamWeight = ds * viewBeam * (scattered + sunDirect);
      if (inSegment) forwardSegment[i] += excess * rowWeight;
      else scaledBeyond[i] += beamWeight * rowWeight;
      if (lit && sunBeam > 0.0) {
        float only = ds * viewDirect * sunDirect * peak * ((sunDirect + scattered) / sunBeam);
        float x = (depths.y + depths.w) - (depths.x + depths.z);
        if (inSegment) { qSegment[i] += only; qxSegment[i] += only * x; }
        else { qBeyond[i] += only; qxBeyond[i] += only * x; }
      }
    }
    for (int j = 0; j < s; j++) previousRho[j] = rho[j];
  }
  if (!segmentDone) {
    for (int j = 0; j < s; j++) columnsSegment[j] = columns[j];
  }
  // The ground's light where the ray ends on it, through the whole ray's
  // scaled transmittance (onGround: the ray's end is the ground's root).
  float rEnd;
  soraMarchAltitudeAlong(h, v, exit_, rEnd);
  float groundSunCosine = clamp((exit_ * cosTheta + r0 * sun.z) / rEnd, -1.0, 1.0);
  vec3 light = vec3(0.0), through = vec3(0.0), solarXyz = vec3(0.0);
  for (int i = 0; i < w; i++) {
    float tau = 0.0, tauScaled = 0.0, tauScaledWhole = 0.0;
    for (int j = 0; j < s; j++) {
      tau += extinction[i * s + j] * columnsSegment[j];
      tauScaled += scaledExtinction[i * s + j] * columnsSegment[j];
      tauScaledWhole += scaledExtinction[i * s + j] * columns[j];
    }
    float solar = soraMarchValue(SORA_MARCH_SOLAR, i);
    float share = 1.0 - exp(tauScaled - tau);
    float depth = tau - tauScaled;
    float groundLight = onGround ? exp(-tauScaledWhole) * soraMarchGroundLight(i, groundSunCosine) : 0.0;
    float value = single[i] + field[i] + share * (fieldBeyond[i] + groundLight);
    if (uMarchPeaks == 1) {
      float peakForward = soraMarchPeakRadiance(theta, i, forwardSegment[i] + share * scaledBeyond[i],
                                                qSegment[i] + qBeyond[i], qxSegment[i] + qxBeyond[i]);
      float hidden = soraMarchPeakRadiance(theta, i, 0.0, qBeyond[i], qxBeyond[i] - depth * qBeyond[i]);
      value += peakForward - hidden;
    }
    vec3 spike = vec3(soraMarchValue(SORA_MARCH_XYZ, 3 * i), soraMarchValue(SORA_MARCH_XYZ, 3 * i + 1), soraMarchValue(SORA_MARCH_XYZ, 3 * i + 2));
    light += value * spike;
    through += solar * exp(-tau) * spike;
    solarXyz += solar * spike;
  }
  inscattered = light;
  transmittance = clamp(through / max(solarXyz, vec3(1e-30)), 0.0, 1.0);
}

// ---------------------------------------------------------------------------
// The sky for an eye above the ground from the march's tables (lookup.rs's
// EngineTables::raised_sky_xyz, whole_ray_sky_xyz, composed_below_xyz; the
// Rust lookup is the oracle; docs/engine-tables.md, "An eye between the
// altitude nodes").

// The eye's height above a view's perigee (a share of the thickness) from
// which the whole ray's march splits at the perigee (PERIGEE_SPLIT_RAMP).
const float SORA_PERIGEE_SPLIT_RAMP = 0.05;

// Zenith angle of the horizon (rad) at altitude h (axes::horizon_zenith,
// pi - asin(R / r), written for float precision as pi / 2 + atan(sqrt(h (2
// R + h)), R)).
float soraHorizonZenith(float h) {
  float R = uPlanetSun.x;
  h = max(h, 0.0);
  return 0.5 * SORA_PI + atan(sqrt(h * (2.0 * R + h)), R);
}

// The split of the whole ray's march from an eye at h toward the unit v,
// a view above the eye's horizon (whole_ray_sky_xyz): for a view going
// down, between the perigee (where the eye is at least
// SORA_PERIGEE_SPLIT_RAMP times the thickness above it) and the ray's end
// (the eye at the perigee's altitude), smoothstep in the eye's height
// above the perigee; the ray's end otherwise.
float soraWholeRaySplit(float h, vec3 v) {
  float r = uPlanetSun.x + h;
  float length_ = soraRayLength(h, v.z);
  if (v.z >= 0.0) return length_;
  float perigee = -r * v.z;
  // r - sqrt(r^2 - perigee^2) = r v.z^2 / (1 + sin z), without cancellation.
  float above = r * v.z * v.z / (1.0 + sqrt(max((1.0 - v.z) * (1.0 + v.z), 0.0)));
  float w = smoothstep(0.0, SORA_PERIGEE_SPLIT_RAMP * soraThickness(), above);
  return length_ + (min(perigee, length_) - length_) * w;
}

// Where the ray from an eye at h toward the unit v first meets the sphere
// of altitude hNode (at or below the eye; composed_below_xyz's t: 0 where
// the eye is on it), the near root -b - sqrt(b^2 - c) written as c / (-b +
// sqrt(b^2 - c)), without cancellation; and the table's read there
// (zenith angle, azimuth from the sun, sun elevation in the point's own
// frame) into `read` (x = altitude hNode).
float soraComposedBelowGeometry(float h, vec3 v, vec3 sun, float hNode, out vec4 read) {
  float R = uPlanetSun.x;
  float r = R + h;
  float b = r * v.z;
  float c = (h - hNode) * (2.0 * R + h + hNode);
  float disc = max(b * b - c, 0.0);
  float t = 0.0;
  if (h > hNode) {
    float q = -b + sqrt(disc);
    t = q > 0.0 ? max(c / q, 0.0) : 0.0;
  }
  vec3 p = vec3(v.xy * t, r + v.z * t);
  vec3 up = p / length(p);
  vec2 zp = soraLocalView(v, up, sun);
  read = vec4(hNode, zp.x, zp.y, degrees(asin(clamp(dot(sun, up), -1.0, 1.0))));
  return t;
}

// value times (want / got)^share per channel, each floored at SORA_FLOOR
// (raised_sky_xyz's `scaled`).
vec3 soraScaledXyz(vec3 value, vec3 want, vec3 got, float share) {
  vec3 k = log(max(want, vec3(SORA_FLOOR))) - log(max(got, vec3(SORA_FLOOR)));
  return value * exp(k * share);
}

// The sky for an eye above the ground, from the march's tables
// (raised_sky_xyz): above the eye's horizon the march's light of the whole
// ray (soraWholeRayMarch split at soraWholeRaySplit), in the first
// altitude cell times the ratio of the table's read on the ground to the
// march's there (the view at the same place relative to the ground's
// horizon), that ratio's logarithm fading linearly in h to none at the
// first node; below it the composition at the lower altitude node's
// sphere (composed_below_xyz: the march of the segment to where the ray
// meets it plus the segment's transmittance times the table's read there,
// the table's read itself where the eye is on it) times the ratio of the
// table's read at the upper node to the same composition from there (the
// view at the same place relative to that node's horizon), that ratio's
// logarithm linear in h. Without march tables or on the ground, the
// table's read (soraSkyXyz): so this is the Rust lookup's sky_xyz.
//
// Within 0.071 % of EngineTables::sky_xyz per channel over 96 reads
// (web/tests/raised-eye.mjs: earth-clear, 3 altitude nodes, eyes at 5 and
// 50 km, one in each altitude cell, suns 30, 3 and -4, views on both sides
// of the horizon). Written as at most three table reads and two marches,
// each from one call in a loop, so that a compiler that inlines every
// call holds one copy of each. A separate entry (soraRaisedSkyView), not
// soraSkyXyz's read: in a program, even where it never runs the march (an
// eye on the ground), it drew the ground eye's fisheye at 2.9 s a frame on
// SwiftShader against 0.26-0.41 s (docs/engine-tables.md, "An eye between
// the altitude nodes").
vec3 soraRaisedSkyXyz(float h, float zenith, float phi, float eDeg) {
  vec4 reads[3];        // the table's reads: altitude, zenith, azimuth, sun elevation
  vec4 marches[2];      // the marches: the eye's altitude, the distance (split), whole (1) or segment (0)
  vec3 views[2];
  int readCount = 1, marchCount = 0;
  reads[0] = vec4(h, zenith, phi, eDeg);
  bool raised = uMarchCounts.w > 0 && h > 0.0;
  bool above = true, scaled = false;
  float share = 0.0;
  vec3 sun = vec3(1.0, 0.0, 0.0);
  if (raised) {
    h = clamp(h, 0.0, soraThickness());
    float z = zenith;
    float e = radians(eDeg);
    sun = vec3(cos(e), 0.0, sin(e));
    int A = uSkyNodes.y;
    int a; float fa; soraCell(soraAltitudeCoordinate(h, A), 0, A - 2, a, fa);
    float fh = soraAltitudeShare(h, a, A);
    float horizon = soraHorizonZenith(h);
    vec3 v = vec3(sin(z) * cos(phi), sin(z) * sin(phi), cos(z));
    above = z < horizon;
    if (above) {
      // The whole ray; in the first cell also the whole ray on the ground
      // and the table's read there.
      readCount = 0;
      marchCount = 1;
      views[0] = v;
      marches[0] = vec4(h, soraWholeRaySplit(h, v), 1.0, 0.0);
      if (!(a > 0 || fh >= 1.0)) {
        float z0 = z * soraHorizonZenith(0.0) / horizon;
        vec3 v0 = vec3(sin(z0) * cos(phi), sin(z0) * sin(phi), cos(z0));
        views[1] = v0;
        marches[1] = vec4(0.0, soraWholeRaySplit(0.0, v0), 1.0, 0.0);
        marchCount = 2;
        reads[0] = vec4(0.0, z0, phi, eDeg);
        readCount = 1;
        scaled = true;
        share = 1.0 - fh;
      }
    } else {
      // The composition at the lower node's sphere; between the nodes also
      // the same from the upper node and the table's read there.
      float hA = soraAltitudeOfNode(a, A);
      views[0] = v;
      float t0 = soraComposedBelowGeometry(h, v, sun, hA, reads[0]);
      marches[0] = vec4(h, t0, 0.0, 0.0);
      marchCount = 1;
      if (fh > 0.0) {
        float hB = soraAltitudeOfNode(a + 1, A);
        float zB = SORA_PI - (SORA_PI - z) * (SORA_PI - soraHorizonZenith(hB)) / (SORA_PI - horizon);
        vec3 vB = vec3(sin(zB) * cos(phi), sin(zB) * sin(phi), cos(zB));
        views[1] = vB;
        float t1 = soraComposedBelowGeometry(hB, vB, sun, hA, reads[1]);
        marches[1] = vec4(hB, t1, 0.0, 0.0);
        marchCount = 2;
        reads[2] = vec4(hB, zB, phi, eDeg);
        readCount = 3;
        scaled = true;
        share = fh;
      }
    }
  }
  vec3 tables[3];
  for (int k = 0; k < readCount; k++) {
    tables[k] = soraSkyXyz(reads[k].x, reads[k].y, reads[k].z, reads[k].w);
  }
  if (!raised) return tables[0];
  // Each march's light: the whole ray's, or the composition (the table's
  // read itself where the segment has no length).
  vec3 lights[2];
  for (int k = 0; k < marchCount; k++) {
    bool whole = marches[k].z > 0.5;
    if (!whole && marches[k].y <= 0.0) {
      lights[k] = tables[k];
      continue;
    }
    vec3 light, transmittance;
    soraMarchXyz(marches[k].x, views[k], sun, marches[k].y, whole, light, transmittance);
    lights[k] = whole ? light : light + transmittance * tables[k];
  }
  if (!scaled) return lights[0];
  return soraScaledXyz(lights[0], tables[above ? 0 : 2], lights[1], share);
}

// Sky radiance for an eye at altitude h looking along unit v, the sun
// toward unit sun (east-north-up, z up), as the Rust lookup's sky_xyz
// reads it (soraRaisedSkyXyz): the entry for an eye above the ground. A
// program that calls it compiles the march, which costs an eye on the
// ground even where it never runs (see soraRaisedSkyXyz), so a host draws
// an eye on the ground with a program calling soraSkyView instead (the
// same read there): web/realtime.js compiles this one when the eye rises.
// Call it from one place in a program (every call is inlined).
vec3 soraRaisedSkyView(float h, vec3 v, vec3 sun) {
  vec2 zp = soraLocalView(v, vec3(0.0, 0.0, 1.0), sun);
  return soraRaisedSkyXyz(h, zp.x, zp.y, soraSunElevationDeg(sun));
}
