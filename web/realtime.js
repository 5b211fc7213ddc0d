// The explorer's real-time view: draws the sky, a scene with aerial
// perspective, and the difference from the exact (CPU) image through WebGL2
// from the engine tables the worker baked (crates/sora-web, request
// "tables"). For an eye on the ground a frame is table reads only; above
// the ground (tables with the march's) its sky is the Rust lookup's raised
// read, the whole ray marched per pixel (soraRaisedSkyView, in a program of
// its own: fragment's `raised`). The reference reader
// web/shaders/sora_sky.glsl (fetched, not copied) does every lookup; this
// file adds the cameras, the scene and the display mapping.
//
// Views (uniform uMode):
//   0 fisheye: the whole sky, zenith at the centre, north up, east left
//     (sora's fisheye), with the sun's disc;
//   1 scene: a perspective camera looking along `lookAzimuthDeg`, five
//     procedural ridges at 1, 4, 12, 35 and 90 km (heights in metres in
//     RIDGES), each point lit by the sky irradiance and the sun through the
//     transmittance at its own altitude and local vertical, and composited
//     as L_point * T + L_air, L_air and T read from the aerial-perspective
//     volume (below), or from the sky table's difference
//     (soraAerialPerspectiveFromSky) where the tables have no march's
//     tables (single scattering);
//   2 difference: the fisheye's relative luminance difference from the
//     exact image (uExact, XYZ): red where the real-time sky is brighter,
//     blue where it is dimmer, full colour at +-DIFFERENCE_SCALE; grey
//     where the exact image is black (a night sky below its floor);
//   3 XYZ: the fisheye's XYZ without the sun's disc, into a float target
//     (what the browser test reads back);
//   4, 5: the scene camera's L_air and T (XYZ) of a point uDistanceM along
//     each pixel's view, read from the volume as the scene reads it; 6, 7:
//     the same by the march itself per pixel (the browser test's);
//   8: the volume's fill (below).
//
// The aerial-perspective volume (Hillaire's, "A Scalable and Production
// Ready Sky and Atmosphere Rendering Technique", 2020): the march
// (soraAerialPerspectiveMarch, march.bin) run once per node of a grid over
// the scene camera's frustum, VOLUME.columns x VOLUME.rows views from edge
// to edge of the picture by VOLUME.slices distances geometric from
// VOLUME.nearM to VOLUME.farM, into two float textures (an atlas of the
// slices side by side) each time the sun, the eye or the camera moves; a
// pixel reads it bilinearly across views and by a cubic across slices.
// What is interpolated is not L_air and T but the segment's mean
// extinction tau / d (tau = -ln T) and its mean source S = L_air / (1 -
// T), per XYZ channel, Catmull-Rom in the slice coordinate through four
// slices (below the first, the first slice's): for a uniform path both
// are exact (tau / d = beta, S = the source), so the interpolation's
// error is only how far the path is from uniform between nodes (measured
// by the browser test against the march per pixel). The cubic follows
// the curve of L_air(d) where a view leaves the Earth's shadow (sun -4,
// 29 degrees up, looking away: at 43-60 km S grows 30 %), which linear
// interpolation between slices overshot by 2.7 % at 50 km.

import { marchTextures, setMarchUniforms, MARCH_WIDTH } from './march.js';

// Ridges: distance (m), base and relief (m above the ground).
export const RIDGES = [
  [1000, 0, 60],
  [4000, 40, 260],
  [12000, 100, 700],
  [35000, 300, 1800],
  [90000, 800, 3500],
];
export const DIFFERENCE_SCALE = 0.05;
// The aerial-perspective volume's nodes (see above).
export const VOLUME = { columns: 16, rows: 24, slices: 20, nearM: 250, farM: 200000 };

// The scene camera: its picture's size (pixels) and half-angle across.
export const SCENE = { width: 512, height: 256, halfAngleXDeg: 40, pitchDeg: 12 };

// The scene camera's view (east-north-up) through screen point (sx, sy),
// -1..1 edge to edge (the shader's cameraRay), and its elevation and
// azimuth in degrees.
export function sceneView(lookAzimuthDeg, sx, sy) {
  const rad = Math.PI / 180;
  const yaw = lookAzimuthDeg * rad;
  const pitch = SCENE.pitchDeg * rad;
  const f = [Math.sin(yaw) * Math.cos(pitch), Math.cos(yaw) * Math.cos(pitch), Math.sin(pitch)];
  const r = [Math.cos(yaw), -Math.sin(yaw), 0];
  const u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]];
  const tanX = Math.tan(SCENE.halfAngleXDeg * rad);
  const tanY = (tanX * SCENE.height) / SCENE.width;
  const v = [0, 1, 2].map((i) => f[i] + sx * tanX * r[i] + sy * tanY * u[i]);
  const length = Math.hypot(...v);
  const [x, y, z] = v.map((c) => c / length);
  return { elevationDeg: Math.asin(z) / rad, azimuthDeg: ((Math.atan2(x, y) / rad) + 360) % 360 };
}

// The volume's axes (the shader's uVolumeAxes): the largest azimuth from
// the camera's over the picture and its lowest and highest elevation
// (rad, its edges' extremes, a hair wider).
function volumeAxes(lookAzimuthDeg) {
  let azimuth = 0;
  let lowest = Infinity;
  let highest = -Infinity;
  for (let i = 0; i <= 8; i++) {
    for (const [sx, sy] of [[-1 + i / 4, -1], [-1 + i / 4, 1], [-1, -1 + i / 4], [1, -1 + i / 4]]) {
      const v = sceneView(lookAzimuthDeg, sx, sy);
      azimuth = Math.max(azimuth, Math.abs(((v.azimuthDeg - lookAzimuthDeg + 540) % 360) - 180));
      lowest = Math.min(lowest, v.elevationDeg);
      highest = Math.max(highest, v.elevationDeg);
    }
  }
  const rad = Math.PI / 180;
  return [(azimuth + 0.1) * rad, (lowest - 0.1) * rad, (highest + 0.1) * rad];
}

const VERTEX = `#version 300 es
void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)); gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }`;

// The fragment shader of the views (march false) or of the march's
// program (march true: the volume's fill, mode 8, and the march per pixel,
// modes 6 and 7), apart so that the views' program neither compiles the
// march nor binds the volume it fills. The views' program comes in two:
// raised false reads the sky as the table's read (soraSkyView), what an
// eye on the ground reads, and raised true as the Rust lookup's sky_xyz at
// any altitude (soraRaisedSkyView: for an eye above the ground with the
// march's tables, the march of the whole ray per pixel). The host draws an
// eye above the ground with the second and compiles it only then: a
// program holding the march drew the ground eye's fisheye several times
// slower on SwiftShader though the march never ran (docs/engine-tables.md,
// "An eye between the altitude nodes"). Each program reads the sky from
// one place (main), so that the march is inlined once.
function fragment(reader, march, raised = false) {
  const float = (x) => x.toFixed(1);
  const ridges = RIDGES.map(([d, base, relief]) => `vec3(${d.toFixed(1)}, ${base.toFixed(1)}, ${relief.toFixed(1)})`).join(', ');
  return `#version 300 es
#define SORA_SCENE_MARCH ${march ? 1 : 0}
#define SORA_RAISED_SKY ${raised ? 1 : 0}
precision highp float;
precision highp int;
${reader}
uniform int uMode;
uniform vec2 uSize;
uniform float uSunElevationDeg;
uniform float uSunAzimuthDeg;
uniform float uAltitudeM;
uniform float uLookAzimuthDeg;
uniform highp sampler2D uExact;
// The scene camera's tan of its half-angles (x, y).
uniform vec2 uTan;
// Distance (m) along each view of modes 4-7.
uniform float uDistanceM;
#if SORA_SCENE_MARCH
layout(location = 0) out vec4 colour;
layout(location = 1) out vec4 colour2;
#else
// 1: the aerial-perspective volume is filled (the tables have the march's).
uniform int uVolumeFilled;
// The volume: S = L_air / (1 - T) and tau = -ln T (XYZ), node (column c,
// row r, slice k) at texel (k * columns + c, r).
uniform highp sampler2D uVolumeSource;
uniform highp sampler2D uVolumeDepth;
out vec4 colour;
#endif

const ivec3 VOLUME_NODES = ivec3(${VOLUME.columns}, ${VOLUME.rows}, ${VOLUME.slices});
const vec2 VOLUME_RANGE_M = vec2(${float(VOLUME.nearM)}, ${float(VOLUME.farM)});

const int RIDGE_COUNT = ${RIDGES.length};
const vec3 RIDGES[RIDGE_COUNT] = vec3[](${ridges});
const float ALBEDO = 0.15;

vec3 sunDirection() {
  float e = radians(uSunElevationDeg), a = radians(uSunAzimuthDeg);
  return vec3(sin(a) * cos(e), cos(a) * cos(e), sin(e));
}

// sora's fisheye: equidistant, zenith at the centre, north up, east left.
bool fisheyeView(out vec3 v) {
  float sx = (2.0 * gl_FragCoord.x - uSize.x) / uSize.x;
  float sy = (2.0 * gl_FragCoord.y - uSize.y) / uSize.y;
  float radius = length(vec2(sx, sy));
  if (radius > 1.0) return false;
  float z = radius * 0.5 * SORA_PI;
  float horizontal = radius > 0.0 ? sin(z) / radius : 0.0;
  v = vec3(-sx * horizontal, sy * horizontal, cos(z));
  return true;
}

// The sky toward v (no disc): the Rust lookup's sky_xyz (the raised
// program) or the table's read (the eye on the ground). Called from main
// alone.
vec3 skyView(vec3 v, vec3 sun) {
#if SORA_RAISED_SKY
  return soraRaisedSkyView(uAltitudeM, v, sun);
#else
  return soraSkyView(uAltitudeM, v, sun);
#endif
}

vec3 sunDisc(vec3 v, vec3 sun) {
  float gamma = acos(clamp(dot(v, sun), -1.0, 1.0));
  return soraSunDiscXyz(uAltitudeM, uSunElevationDeg, gamma);
}

// The scene camera: forward, right and up (east-north-up), 12 degrees up.
void cameraBasis(out vec3 f, out vec3 r, out vec3 u) {
  float yaw = radians(uLookAzimuthDeg), pitch = radians(12.0);
  f = vec3(sin(yaw) * cos(pitch), cos(yaw) * cos(pitch), sin(pitch));
  r = vec3(cos(yaw), -sin(yaw), 0.0);
  u = cross(r, f);
}

// The view through screen point s (-1..1 edge to edge), and back.
vec3 cameraRay(vec2 s) {
  vec3 f, r, u;
  cameraBasis(f, r, u);
  return normalize(f + s.x * uTan.x * r + s.y * uTan.y * u);
}

vec3 perspectiveView() {
  return cameraRay((2.0 * gl_FragCoord.xy - uSize) / uSize);
}

// Distance (m) of the volume's slice k.
float volumeDistance(int k) {
  return VOLUME_RANGE_M.x * pow(VOLUME_RANGE_M.y / VOLUME_RANGE_M.x, float(k) / float(VOLUME_NODES.z - 1));
}

// The volume's views: columns uniform in the azimuth from the camera's,
// -A..A; rows in the elevation e between the picture's lowest and
// highest, uniform in x = sign(e - e_h) warp(|e - e_h|) with the eye's
// horizon e_h on a row, warp(q) = sqrt(q) + VOLUME_WARP q (q in rad): the
// rows closest where the light changes fastest, as in Hillaire's
// sky-view table, less so far from it; no row straddles the horizon.
// uVolumeAxes: A, lowest e, highest e (rad).
uniform vec3 uVolumeAxes;
const float VOLUME_WARP = 2.0;
float volumeWarp(float q) { return sqrt(q) + VOLUME_WARP * q; }
float volumeUnwarp(float x) {
  float y = (sqrt(1.0 + 4.0 * VOLUME_WARP * x) - 1.0) / (2.0 * VOLUME_WARP);
  return y * y;
}

// The horizon's elevation (rad), within the picture's, and its row.
void volumeHorizon(out float eh, out int jh) {
  float R = uPlanetSun.x, h = max(uAltitudeM, 0.0);
  eh = clamp(-asin(sqrt(h * (2.0 * R + h)) / (R + h)), uVolumeAxes.y, uVolumeAxes.z);
  float below = volumeWarp(eh - uVolumeAxes.y), above = volumeWarp(uVolumeAxes.z - eh);
  jh = clamp(int(floor(below / (below + above) * float(VOLUME_NODES.y - 1) + 0.5)), 0, VOLUME_NODES.y - 1);
}

// The view of column c and row j.
vec3 volumeView(int c, int j) {
  float eh; int jh;
  volumeHorizon(eh, jh);
  float e = eh;
  if (j < jh) {
    e = eh - volumeUnwarp(float(jh - j) / float(jh) * volumeWarp(eh - uVolumeAxes.y));
  } else if (j > jh) {
    e = eh + volumeUnwarp(float(j - jh) / float(VOLUME_NODES.y - 1 - jh) * volumeWarp(uVolumeAxes.z - eh));
  }
  float a = radians(uLookAzimuthDeg) + uVolumeAxes.x * (2.0 * float(c) / float(VOLUME_NODES.x - 1) - 1.0);
  return vec3(sin(a) * cos(e), cos(a) * cos(e), sin(e));
}

// The column and row coordinates of view v (volumeView's inverse).
vec2 volumeNodeOf(vec3 v) {
  float eh; int jh;
  volumeHorizon(eh, jh);
  float e = asin(clamp(v.z, -1.0, 1.0));
  float j = float(jh);
  if (e < eh && jh > 0) j -= volumeWarp(eh - e) / volumeWarp(eh - uVolumeAxes.y) * float(jh);
  if (e > eh && jh < VOLUME_NODES.y - 1) j += volumeWarp(e - eh) / volumeWarp(uVolumeAxes.z - eh) * float(VOLUME_NODES.y - 1 - jh);
  float a = atan(v.x, v.y) - radians(uLookAzimuthDeg);
  a -= 2.0 * SORA_PI * floor((a + SORA_PI) / (2.0 * SORA_PI));
  return vec2((a / uVolumeAxes.x + 1.0) * 0.5 * float(VOLUME_NODES.x - 1), j);
}

#if SORA_SCENE_MARCH
// The volume's fill (mode 8): the march at node (column, row, slice) of
// the texel, S and tau into the two targets.
void fillVolume(vec3 sun) {
  ivec2 p = ivec2(gl_FragCoord.xy);
  int c = p.x % VOLUME_NODES.x, k = p.x / VOLUME_NODES.x;
  vec3 v = volumeView(c, p.y);
  float d = volumeDistance(k);
  // A node whose point lies beyond the ground along its view (no scene
  // point is there) takes the view grazing the horizon at the same
  // azimuth instead: with the eye on the ground every view below the
  // horizon meets it at once, and the rows above would otherwise be
  // interpolated toward zero light.
  float R = uPlanetSun.x, h = max(uAltitudeM, 0.0), r0 = R + h;
  float b = r0 * v.z, cGround = h * (2.0 * R + h), disc = b * b - cGround;
  if (b < 0.0 && disc >= 0.0 && d > cGround / (-b + sqrt(disc))) {
    float z = -sqrt(cGround) / r0 + 1e-4;
    v = vec3(normalize(v.xy) * sqrt(1.0 - z * z), z);
  }
  vec3 inscattered, transmittance;
  soraAerialPerspectiveMarch(uAltitudeM, v, sun, d, inscattered, transmittance);
  colour = vec4(inscattered / max(1.0 - transmittance, vec3(1e-7)), 1.0);
  colour2 = vec4(-log(max(transmittance, vec3(1e-30))), 1.0);
}

#else
// Bilinear read of the volume's slice k at node coordinates (x, y).
void volumeSlice(int k, ivec2 n, vec2 t, out vec3 source, out vec3 depth) {
  ivec2 base = ivec2(k * VOLUME_NODES.x, 0) + n;
  vec3 s00 = texelFetch(uVolumeSource, base, 0).xyz, s10 = texelFetch(uVolumeSource, base + ivec2(1, 0), 0).xyz;
  vec3 s01 = texelFetch(uVolumeSource, base + ivec2(0, 1), 0).xyz, s11 = texelFetch(uVolumeSource, base + ivec2(1, 1), 0).xyz;
  vec3 d00 = texelFetch(uVolumeDepth, base, 0).xyz, d10 = texelFetch(uVolumeDepth, base + ivec2(1, 0), 0).xyz;
  vec3 d01 = texelFetch(uVolumeDepth, base + ivec2(0, 1), 0).xyz, d11 = texelFetch(uVolumeDepth, base + ivec2(1, 1), 0).xyz;
  source = mix(mix(s00, s10, t.x), mix(s01, s11, t.x), t.y);
  depth = mix(mix(d00, d10, t.x), mix(d01, d11, t.x), t.y);
}

// L_air and T of a point d (m) along v from the volume: bilinear in the
// views' node coordinates, and across the slices a Catmull-Rom cubic in
// x = the slice coordinate (uniform in ln d) through slices k - 1..k + 2
// (the end slices repeated) of S and of tau / d (the mean extinction):
// both constant along a uniform path, so exact there as before; below the
// first slice x is 0 (S and tau / d the first slice's, tau in proportion
// to d). See the file's comment.
void volumeAerialPerspective(vec3 v, float d, out vec3 inscattered, out vec3 transmittance) {
  vec2 xy = clamp(volumeNodeOf(v), vec2(0.0), vec2(VOLUME_NODES.xy - 1));
  ivec2 n = min(ivec2(xy), VOLUME_NODES.xy - 2);
  vec2 t = xy - vec2(n);
  float x = clamp(log(max(d, VOLUME_RANGE_M.x) / VOLUME_RANGE_M.x) / log(VOLUME_RANGE_M.y / VOLUME_RANGE_M.x) * float(VOLUME_NODES.z - 1), 0.0, float(VOLUME_NODES.z - 1));
  int k = min(int(x), VOLUME_NODES.z - 2);
  float u = x - float(k);
  vec4 w = 0.5 * vec4(((2.0 - u) * u - 1.0) * u, (3.0 * u - 5.0) * u * u + 2.0, ((4.0 - 3.0 * u) * u + 1.0) * u, (u - 1.0) * u * u);
  vec3 source = vec3(0.0), extinction = vec3(0.0);
  for (int i = 0; i < 4; i++) {
    int ki = clamp(k - 1 + i, 0, VOLUME_NODES.z - 1);
    vec3 s, tau;
    volumeSlice(ki, n, t, s, tau);
    source += w[i] * s;
    extinction += w[i] * tau / volumeDistance(ki);
  }
  transmittance = exp(-max(extinction, vec3(0.0)) * d);
  inscattered = max(source, vec3(0.0)) * (1.0 - transmittance);
}

// The scene's aerial perspective: the volume's, or the sky table's
// difference without the march's tables.
void sceneAerialPerspective(vec3 v, vec3 sun, float d, out vec3 inscattered, out vec3 transmittance) {
  if (uVolumeFilled == 1) volumeAerialPerspective(v, d, inscattered, transmittance);
  else soraAerialPerspectiveFromSky(uAltitudeM, v, sun, d, inscattered, transmittance);
}

// Height (m above the ground) of ridge i toward azimuth az (rad).
float ridgeHeight(int i, float az) {
  float c = float(i) * 1.7;
  float n = 0.5 * sin(3.0 * az + c) + 0.3 * sin(7.0 * az + 2.0 * c) + 0.2 * sin(17.0 * az + 3.0 * c);
  return RIDGES[i].y + RIDGES[i].z * (0.5 + 0.5 * n);
}

// The scene along v (east-north-up at the eye): false where v sees the
// sky, else true and into xyz a ridge or the ground at slant distance d,
// lit where it stands, seen through the air.
bool sceneSurface(vec3 v, vec3 sun, out vec3 xyz) {
  float R = uPlanetSun.x;
  float horizontal = max(length(v.xy), 1e-6);
  float tanElevation = v.z / horizontal;
  float az = atan(v.x, v.y);
  float d = -1.0;
  vec3 normal = vec3(0.0, 0.0, 1.0);
  // The ground (a plane at altitude 0 near the eye) before the ridges.
  float ground = v.z < 0.0 ? uAltitudeM / -tanElevation : 1e30;
  for (int i = 0; i < RIDGE_COUNT; i++) {
    float D = RIDGES[i].x;
    if (ground < D) { d = ground / horizontal; break; }
    // The ridge's top as seen from the eye, the planet's curvature included.
    float top = (ridgeHeight(i, az) - uAltitudeM - D * D / (2.0 * R)) / D;
    if (tanElevation < top) {
      d = D / horizontal;
      // Slopes facing the eye.
      normal = normalize(vec3(-v.xy / horizontal * 0.6, 0.8));
      break;
    }
  }
  if (d < 0.0) return false;
  // The point's own altitude and vertical (as soraAerialPerspectiveFromSky finds them).
  vec3 p = vec3(v.xy * d, R + uAltitudeM + v.z * d);
  vec3 up = normalize(p);
  float hp = max(length(p) - R, 0.0);
  float muSun = dot(sun, up);
  float eP = degrees(asin(clamp(muSun, -1.0, 1.0)));
  vec3 transmittanceSun = soraTransmittance(hp, muSun);
  vec3 direct = uSunIrradianceXyz * transmittanceSun;
  vec3 diffuse = soraGroundIrradianceXyz(hp, eP) - direct * max(muSun, 0.0);
  // The normal, tilted from the eye's vertical to the point's.
  vec3 n = normalize(normal + (up - vec3(0.0, 0.0, 1.0)));
  vec3 lit = ALBEDO / SORA_PI * (diffuse * 0.5 * (1.0 + dot(n, up)) + direct * max(dot(n, sun), 0.0));
  vec3 inscattered, transmittance;
  sceneAerialPerspective(v, sun, d, inscattered, transmittance);
  xyz = lit * transmittance + inscattered;
  return true;
}


vec3 display(vec3 xyz) {
  // Auto exposure from the tables: mid grey for the mean sky radiance
  // (the diffuse horizontal irradiance over pi) at the eye.
  vec3 sun = sunDirection();
  vec3 diffuse = soraGroundIrradianceXyz(uAltitudeM, uSunElevationDeg)
    - uSunIrradianceXyz * soraTransmittance(uAltitudeM, sun.z) * max(sun.z, 0.0);
  float exposure = 0.18 / max(diffuse.y / SORA_PI, 1e-30);
  vec3 rgb = clamp(soraXyzToLinearSrgb(xyz * exposure), 0.0, 1.0);
  return mix(12.92 * rgb, 1.055 * pow(rgb, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, rgb));
}

#endif

#if SORA_SCENE_MARCH
void main() {
  vec3 sun = sunDirection();
  if (uMode == 8) {
    fillVolume(sun);
    return;
  }
  vec3 inscattered, transmittance;
  soraAerialPerspectiveMarch(uAltitudeM, perspectiveView(), sun, uDistanceM, inscattered, transmittance);
  colour = vec4(uMode == 6 ? inscattered : transmittance, 1.0);
  colour2 = vec4(0.0);
}
#else
void main() {
  vec3 sun = sunDirection();
  if (uMode == 4 || uMode == 5) {
    vec3 inscattered, transmittance;
    sceneAerialPerspective(perspectiveView(), sun, uDistanceM, inscattered, transmittance);
    colour = vec4(uMode == 4 ? inscattered : transmittance, 1.0);
    return;
  }
  // The view: the scene camera's (mode 1, where a ridge or the ground may
  // stand in front of the sky) or the fisheye's; the sky read here alone.
  vec3 v, xyz;
  bool sky = true;
  if (uMode == 1) {
    v = perspectiveView();
    sky = !sceneSurface(v, sun, xyz);
  } else if (!fisheyeView(v)) {
    colour = vec4(0.0);
    return;
  }
  if (sky) xyz = skyView(v, sun);
  if (uMode == 0 || uMode == 1) {
    if (sky) xyz += sunDisc(v, sun);
    colour = vec4(display(xyz), 1.0);
  } else if (uMode == 3) {
    colour = vec4(xyz, 1.0);
  } else {
    vec3 realtime = xyz;
    // The exact image's rows run top first.
    vec3 exact = texelFetch(uExact, ivec2(int(gl_FragCoord.x), int(uSize.y) - 1 - int(gl_FragCoord.y)), 0).xyz;
    if (!(exact.y > 0.0)) { colour = vec4(vec3(0.08), 1.0); return; } // a night sky: no difference
    float t = clamp((realtime.y - exact.y) / max(exact.y, 1e-30) / ${DIFFERENCE_SCALE.toFixed(4)}, -1.0, 1.0);
    vec3 grey = vec3(0.08);
    colour = vec4(t > 0.0 ? mix(grey, vec3(1.0, 0.25, 0.1), t) : mix(grey, vec3(0.2, 0.55, 1.0), -t), 1.0);
  }
}
#endif`;
}

export class RealtimeView {
  constructor(canvas) {
    this.canvas = canvas;
    this.gl = canvas.getContext('webgl2', { preserveDrawingBuffer: true });
    this.tables = null;
    this.exact = null; // {width, height} of the uploaded exact image
  }

  get supported() {
    return Boolean(this.gl);
  }

  async init() {
    const gl = this.gl;
    if (!gl) throw new Error('real-time view: this browser has no WebGL2');
    const response = await fetch(new URL('./shaders/sora_sky.glsl', import.meta.url));
    if (!response.ok) throw new Error(`shaders/sora_sky.glsl: HTTP ${response.status}`);
    const compile = (type, source) => {
      const shader = gl.createShader(type);
      gl.shaderSource(shader, source);
      gl.compileShader(shader);
      if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(`real-time shader: ${gl.getShaderInfoLog(shader)}`);
      return shader;
    };
    const reader = await response.text();
    this.link = (march, raised) => {
      const program = gl.createProgram();
      gl.attachShader(program, compile(gl.VERTEX_SHADER, VERTEX));
      gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fragment(reader, march, raised)));
      gl.linkProgram(program);
      if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`real-time shader: ${gl.getProgramInfoLog(program)}`);
      return program;
    };
    // The views' program (the table's sky: an eye on the ground), the
    // march's, and the views' for an eye above the ground (the Rust
    // lookup's sky, the march per pixel), linked when first drawn
    // (use(2)); how long that took (ms).
    this.programs = [this.link(false, false), this.link(true, false), null];
    this.raisedLinkMs = null;
    this.tableUniforms = null;
    this.forEachProgram(() => this.setUnits());
    this.textures = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9].map(() => gl.createTexture());
    this.floatTarget = Boolean(gl.getExtension('EXT_color_buffer_float'));
    // Every sampler's unit holds a texture of its kind (the aerial table's
    // and, until a bake with them, the march's: one texel).
    this.bind(9, gl.TEXTURE_2D_ARRAY);
    gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, 1, 1, 1, 0, gl.RGBA, gl.FLOAT, new Float32Array(4));
    this.setMarch(null);
    for (const unit of [7, 8]) {
      this.bind(unit, gl.TEXTURE_2D);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, VOLUME.columns * VOLUME.slices, VOLUME.rows, 0, gl.RGBA, gl.FLOAT, null);
    }
    this.volumeFramebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.volumeFramebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.textures[7], 0);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT1, gl.TEXTURE_2D, this.textures[8], 0);
    this.volumeComplete = this.floatTarget && gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE;
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    this.volumeKey = null; // what the volume was filled for
    this.volumeFills = 0;
  }

  // Each sampler's texture unit, in the program in use.
  setUnits() {
    const gl = this.gl;
    gl.uniform1i(this.uniform('uSky'), 0);
    gl.uniform1i(this.uniform('uTransmittance'), 1);
    gl.uniform1i(this.uniform('uIrradiance'), 2);
    gl.uniform1i(this.uniform('uExact'), 3);
    // Unit 4: readFloats' target.
    gl.uniform1i(this.uniform('uMarchSource'), 5);
    gl.uniform1i(this.uniform('uMarchTables'), 6);
    gl.uniform1i(this.uniform('uVolumeSource'), 7);
    gl.uniform1i(this.uniform('uVolumeDepth'), 8);
    gl.uniform1i(this.uniform('uAerial'), 9);
  }

  // Uses program 0 (the views', the table's sky), 1 (the march's) or 2
  // (the views' with the raised eye's sky, linked now if not yet, its
  // uniforms set as the others'); uniform(name) is then its uniform's
  // location.
  use(index) {
    if (!this.programs[index]) {
      const started = performance.now();
      this.programs[index] = this.link(false, true);
      this.program = this.programs[index];
      this.gl.useProgram(this.program);
      this.setUnits();
      if (this.tableUniforms) this.tableUniforms(this.program);
      this.raisedLinkMs = performance.now() - started;
    }
    this.program = this.programs[index];
    this.gl.useProgram(this.program);
    this.lastProgram = index;
  }

  uniform(name) {
    return this.gl.getUniformLocation(this.program, name);
  }

  // Runs `set` with each linked program in use, then the views'.
  forEachProgram(set) {
    for (const index of [2, 1, 0]) {
      if (!this.programs[index]) continue;
      this.use(index);
      set(this.program);
    }
  }

  // The march's tables (marchTextures' reply), or one texel each (null).
  setMarch(march) {
    const gl = this.gl;
    this.bind(5, gl.TEXTURE_2D_ARRAY);
    if (march) {
      const [width, height, depth] = march.sourceSize;
      gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA16F, width, height, depth, 0, gl.RGBA, gl.HALF_FLOAT, march.source);
    } else {
      gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA16F, 1, 1, 1, 0, gl.RGBA, gl.HALF_FLOAT, new Uint16Array(4));
    }
    this.bind(6, gl.TEXTURE_2D);
    if (march) {
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, MARCH_WIDTH, march.tablesHeight, 0, gl.RED, gl.FLOAT, march.tables);
    } else {
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, 1, 1, 0, gl.RED, gl.FLOAT, new Float32Array(1));
    }
    this.hasMarch = Boolean(march);
    this.volumeKey = null;
  }

  bind(unit, target) {
    const gl = this.gl;
    gl.activeTexture(gl.TEXTURE0 + unit);
    gl.bindTexture(target, this.textures[unit]);
    gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  }

  // The reply of the engine's "tables" request: JSON and bytes.
  setTables(json, bytes) {
    const gl = this.gl;
    const floats = (name) => {
      const t = json.tables[name];
      return new Float32Array(bytes, t.offset_bytes, t.width * t.height * 4);
    };
    const m = json.manifest;
    const sky = m.tables.sky;
    const layers = sky.sun_nodes * sky.altitude_nodes;
    this.bind(0, gl.TEXTURE_2D_ARRAY);
    gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, sky.width, sky.height / layers, layers, 0, gl.RGBA, gl.FLOAT, floats('sky'));
    this.bind(1, gl.TEXTURE_2D);
    const t = m.tables.transmittance;
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, t.width, t.height, 0, gl.RGBA, gl.FLOAT, floats('transmittance'));
    this.bind(2, gl.TEXTURE_2D);
    const e = m.tables.irradiance;
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, e.width, e.height, 0, gl.RGBA, gl.FLOAT, floats('irradiance'));
    // The march's tables (multiple scattering): the scene's volume.
    const march = json.tables.march && m.tables.march
      ? marchTextures(m.tables.march, new Uint8Array(bytes, json.tables.march.offset_bytes, json.tables.march.length_bytes))
      : null;
    this.setMarch(march);
    // The tables' uniforms, kept for the raised program when it is linked.
    this.tableUniforms = (program) => {
      gl.uniform4i(this.uniform('uSkyNodes'), sky.sun_nodes, sky.altitude_nodes, sky.zenith_nodes_per_half, sky.azimuth_nodes);
      gl.uniform1i(this.uniform('uSkyZenithFineCells'), sky.zenith_fine_cells_per_half ?? 0);
      gl.uniform1i(this.uniform('uSkyZenithWideCells'), sky.zenith_wide_cells_per_half ?? 0);
      gl.uniform2i(this.uniform('uTransmittanceNodes'), t.height, t.width);
      gl.uniform4f(this.uniform('uPlanetSun'), m.planet.ground_radius_m, m.planet.top_radius_m, m.sun.angular_radius_rad, m.sun.limb_darkening);
      gl.uniform3fv(this.uniform('uSunIrradianceXyz'), m.sun.irradiance_xyz_w_m2_nm);
      gl.uniform1f(this.uniform('uSunAxisWidthDeg'), m.sun.axis_width_deg);
      if (march) setMarchUniforms(gl, program, m.tables.march, march);
    };
    this.forEachProgram(this.tableUniforms);
    this.tables = json;
  }

  // Whether the scene reads the volume: the tables have the march's and a
  // float target holds it.
  get volumeUsed() {
    return this.hasMarch && this.volumeComplete;
  }

  // Fills the aerial-perspective volume for `state` unless it already
  // holds it (the uniforms of `state` set); true when filled now.
  fillVolume(state) {
    const gl = this.gl;
    const key = JSON.stringify([state.sunElevationDeg, state.sunAzimuthDeg, state.altitudeM, state.lookAzimuthDeg]);
    if (key === this.volumeKey) return false;
    const framebuffer = gl.getParameter(gl.FRAMEBUFFER_BINDING);
    const program = this.program;
    this.use(1);
    this.setState(state);
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.volumeFramebuffer);
    gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
    gl.viewport(0, 0, VOLUME.columns * VOLUME.slices, VOLUME.rows);
    gl.uniform1i(this.uniform('uMode'), 8);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    this.use(this.programs.indexOf(program));
    this.volumeKey = key;
    this.volumeFills += 1;
    return true;
  }

  // The exact image's XYZ (the engine's "render_xyz" reply).
  setExact(json, bytes) {
    const gl = this.gl;
    const xyz = new Float32Array(bytes);
    const rgba = new Float32Array(json.width * json.height * 4);
    for (let i = 0; i < json.width * json.height; i++) rgba.set(xyz.subarray(3 * i, 3 * i + 3), 4 * i);
    this.bind(3, gl.TEXTURE_2D);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, json.width, json.height, 0, gl.RGBA, gl.FLOAT, rgba);
    this.exact = { width: json.width, height: json.height };
  }

  // Draws `state` ({mode, sunElevationDeg, sunAzimuthDeg, altitudeM,
  // lookAzimuthDeg}) into the canvas (or the bound framebuffer).
  draw(state, width = this.canvas.width, height = this.canvas.height) {
    const gl = this.gl;
    if (!this.tables) return false;
    const mode = {
      fisheye: 0, scene: 1, difference: 2, xyz: 3,
      'aerial-inscattered': 4, 'aerial-transmittance': 5, 'march-inscattered': 6, 'march-transmittance': 7,
    }[state.mode];
    if (mode === 2 && !this.exact) return false;
    if (this.volumeUsed && (mode === 1 || mode === 4 || mode === 5)) this.fillVolume(state);
    this.use(mode === 6 || mode === 7 ? 1 : this.raisedSky(state) && mode <= 3 ? 2 : 0);
    this.setState(state);
    // state.fromSky: the sky table's difference even with a volume (the
    // browser test's comparison).
    gl.uniform1i(this.uniform('uVolumeFilled'), this.volumeUsed && !state.fromSky ? 1 : 0);
    gl.viewport(0, 0, width, height);
    gl.uniform1i(this.uniform('uMode'), mode);
    gl.uniform2f(this.uniform('uSize'), width, height);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    return true;
  }

  // Whether `state`'s sky is drawn by the raised program: an eye above the
  // ground and the march's tables (without them the raised read is the
  // table's, what program 0 reads).
  raisedSky(state) {
    return this.hasMarch && state.altitudeM > 0;
  }

  // The uniforms of `state` in the program in use.
  setState(state) {
    const gl = this.gl;
    gl.uniform1f(this.uniform('uSunElevationDeg'), Math.min(Math.max(state.sunElevationDeg, -90), 90));
    gl.uniform1f(this.uniform('uSunAzimuthDeg'), state.sunAzimuthDeg);
    gl.uniform1f(this.uniform('uAltitudeM'), state.altitudeM);
    gl.uniform1f(this.uniform('uLookAzimuthDeg'), state.lookAzimuthDeg);
    const tanX = Math.tan((SCENE.halfAngleXDeg * Math.PI) / 180);
    gl.uniform2f(this.uniform('uTan'), tanX, (tanX * SCENE.height) / SCENE.width);
    gl.uniform1f(this.uniform('uDistanceM'), state.distanceM ?? 0);
    gl.uniform3fv(this.uniform('uVolumeAxes'), volumeAxes(state.lookAzimuthDeg));
  }

  // The fisheye's XYZ at `size` pixels (rows bottom first, RGBA floats).
  readXyz(state, size) {
    return this.readFloats({ ...state, mode: 'xyz' }, size, size);
  }

  // `state`'s mode drawn into a float target of width x height pixels
  // (rows bottom first, RGBA floats): the scene's aerial perspective
  // (modes aerial-* and march-*, at state.distanceM) or the fisheye's XYZ.
  readFloats(state, width, height) {
    const gl = this.gl;
    if (!this.floatTarget) throw new Error('real-time view: no EXT_color_buffer_float to read floats back');
    const target = gl.createTexture();
    gl.activeTexture(gl.TEXTURE4);
    gl.bindTexture(gl.TEXTURE_2D, target);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, width, height);
    const framebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    this.draw(state, width, height);
    const pixels = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(framebuffer);
    gl.deleteTexture(target);
    return pixels;
  }

  // Mean time of `frames` draws of `state` into the canvas, each waited
  // for by reading a pixel back (gl.finish does not wait for Chromium's
  // GPU process), in ms; the sun moved 0.01 degrees a frame (the scene's
  // volume filled again each frame) unless `still`.
  timeFrames(state, frames, still = false) {
    const gl = this.gl;
    const pixel = new Uint8Array(4);
    this.draw(state);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    const start = performance.now();
    for (let i = 0; i < frames; i++) {
      this.draw({ ...state, sunElevationDeg: state.sunElevationDeg + (still ? 0 : 0.01 * (i + 1)) });
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    }
    return (performance.now() - start) / frames;
  }
}
