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
//   uIrradiance    sampler2D, irradiance.exr (x = sun node, y = altitude node)
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

// Cell index and weight of fractional index x within lowest..highest.
void soraCell(float x, int lowest, int highest, out int i, out float f) {
  i = clamp(int(floor(max(x, 0.0))), lowest, highest);
  f = clamp(x - float(i), 0.0, 1.0);
}

// Zenith coordinate (y, lowest cell, highest cell) for an eye at radius r
// on an axis of half_ nodes per half.
void soraZenithCoordinate(float zenith, float r, int half_, out float y, out int lowest, out int highest) {
  float zh = SORA_PI - asin(min(uPlanetSun.x / r, 1.0));
  float last = float(half_ - 1);
  if (zenith < zh) {
    float u = clamp(zenith / (zh - 1e-6), 0.0, 1.0);
    y = (1.0 - sqrt(1.0 - u)) * last;
    lowest = 0;
    highest = half_ - 2;
  } else {
    float u = clamp((SORA_PI - zenith) / (SORA_PI - zh - 1e-6), 0.0, 1.0);
    y = float(2 * half_ - 1) - (1.0 - sqrt(1.0 - u)) * last;
    lowest = half_;
    highest = 2 * half_ - 2;
  }
}

// Bilinear read of slice row0 (its first row) of a layer of `table`.
vec3 soraLayer(highp sampler2DArray table, int layer, int row0, int i, float fy, int k, float fx) {
  vec3 a = mix(texelFetch(table, ivec3(k, row0 + i, layer), 0).xyz, texelFetch(table, ivec3(k + 1, row0 + i, layer), 0).xyz, fx);
  vec3 b = mix(texelFetch(table, ivec3(k, row0 + i + 1, layer), 0).xyz, texelFetch(table, ivec3(k + 1, row0 + i + 1, layer), 0).xyz, fx);
  return mix(a, b, fy);
}

vec3 soraMixLog(vec3 a, vec3 b, float f) {
  return exp(mix(log(max(a, vec3(SORA_FLOOR))), log(max(b, vec3(SORA_FLOOR))), f));
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
// horizon (its band keeps its zenith angle), 1 from 20 up; 0 for suns
// above 85 degrees (the zenith axis is coarser than the aureole there),
// 1 below 70; or, for suns below 2 degrees (0 above 6), 1 within 40
// degrees of the antisolar point, 0 beyond 80, horizon included
// (smoothstep ramps).
float soraTurnShare(float zenith, float phi, float eDeg, float zh) {
  float e = radians(eDeg);
  float cosTheta = cos(zenith) * sin(e) + sin(zenith) * cos(phi) * cos(e);
  float sunSide = smoothstep(cos(radians(40.0)), cos(radians(10.0)), cosTheta)
    * (1.0 - smoothstep(zh - radians(20.0), zh - radians(5.0), zenith))
    * (1.0 - smoothstep(70.0, 85.0, eDeg));
  // The planet's shadow, rising at the antisolar horizon as the sun sets,
  // turns with the antisolar point (horizon included).
  float shadow = smoothstep(cos(radians(80.0)), cos(radians(40.0)), -cosTheta)
    * (1.0 - smoothstep(2.0, 6.0, eDeg));
  return max(sunSide, shadow);
}

// A layer table (the sky, or the aerial-perspective table with Z zenith
// nodes per half, K azimuth nodes, and its distance slices j and j + 1
// blended by fj) at altitude h (m), toward zenith angle `zenith` (rad) and
// azimuth `phi` (rad, 0..pi) from the sun's, with the sun at elevation
// eDeg (degrees): bilinear in a layer, linear in altitude, in ln L between
// the two sun layers (the chord less the curvature of the four nearest),
// each read at the view turned with the sun to its node (soraTurnedView,
// by soraTurnShare of the step).
vec3 soraLayersXyz(highp sampler2DArray table, int Z, int K, int j, float fj, float h, float zenith, float phi, float eDeg) {
  h = clamp(h, 0.0, soraThickness());
  float r = uPlanetSun.x + h;
  float zh = SORA_PI - asin(min(uPlanetSun.x / r, 1.0));
  int A = uSkyNodes.y;
  int a; float fa; soraCell(soraAltitudeCoordinate(h, A), 0, A - 2, a, fa);
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
    float y; int lowest; int highest;
    soraZenithCoordinate(view.x, r, Z, y, lowest, highest);
    int i; float fy; soraCell(y, lowest, highest, i, fy);
    int k; float fx; soraCell(sqrt(clamp(view.y / SORA_PI, 0.0, 1.0)) * float(K - 1), 0, K - 2, k, fx);
    int low = (s + n) * A + a;
    vec3 ground = mix(soraLayer(table, low, row0, i, fy, k, fx), soraLayer(table, low, row1, i, fy, k, fx), fj);
    vec3 above = mix(soraLayer(table, low + 1, row0, i, fy, k, fx), soraLayer(table, low + 1, row1, i, fy, k, fx), fj);
    layers[m] = log(max(mix(ground, above, fa), vec3(SORA_FLOOR)));
  }
  // The chord in ln L less its curvature: the second differences at nodes
  // s and s + 1 (zero at the axis's ends, each within +-1), blended.
  vec3 d0 = s > 0 ? clamp(layers[0] - 2.0 * layers[1] + layers[2], -1.0, 1.0) : vec3(0.0);
  vec3 d1 = s + 2 < uSkyNodes.x ? clamp(layers[1] - 2.0 * layers[2] + layers[3], -1.0, 1.0) : vec3(0.0);
  return exp(mix(layers[1], layers[2], fs) - 0.5 * fs * (1.0 - fs) * mix(d0, d1, fs));
}

// Sky radiance (XYZ, W m^-2 sr^-1 nm^-1) seen at altitude h (m) toward
// zenith angle `zenith` (rad) and azimuth `phi` (rad, 0..pi) from the
// sun's, with the sun at elevation eDeg (degrees). No sun disc.
vec3 soraSkyXyz(float h, float zenith, float phi, float eDeg) {
  return soraLayersXyz(uSky, uSkyNodes.z, uSkyNodes.w, 0, 0.0, h, zenith, phi, eDeg);
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
// sun at eDeg: the diffuse table plus the direct beam.
vec3 soraGroundIrradianceXyz(float h, float eDeg) {
  h = clamp(h, 0.0, soraThickness());
  int A = uSkyNodes.y;
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

// Sky radiance for an eye at altitude h looking along unit v, the sun
// toward unit sun; v and sun in the eye's east-north-up frame (z up).
vec3 soraSkyView(float h, vec3 v, vec3 sun) {
  vec2 zp = soraLocalView(v, vec3(0.0, 0.0, 1.0), sun);
  return soraSkyXyz(h, zp.x, zp.y, degrees(asin(clamp(sun.z, -1.0, 1.0))));
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
  float eDeg = degrees(asin(clamp(sun.z, -1.0, 1.0)));
  vec3 sky = soraSkyXyz(h, zp.x, zp.y, eDeg);
  vec3 ratio = soraLayersXyz(uAerial, uAerialNodes.x, uAerialNodes.y, j, fj, h, zp.x, zp.y, eDeg);
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
