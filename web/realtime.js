// The explorer's real-time view: draws the sky, a scene with aerial
// perspective, and the difference from the exact (CPU) image through WebGL2
// from the engine tables the worker baked (crates/sora-web, request
// "tables"). A frame is table reads only: the reference reader
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
//     as L_point * T + L_air (soraAerialPerspectiveFromSky: the tables
//     baked here have no aerial-perspective table);
//   2 difference: the fisheye's relative luminance difference from the
//     exact image (uExact, XYZ): red where the real-time sky is brighter,
//     blue where it is dimmer, full colour at +-DIFFERENCE_SCALE; grey
//     where the exact image is black (a night sky below its floor);
//   3 XYZ: the fisheye's XYZ without the sun's disc, into a float target
//     (what the browser test reads back).

// Ridges: distance (m), base and relief (m above the ground).
export const RIDGES = [
  [1000, 0, 60],
  [4000, 40, 260],
  [12000, 100, 700],
  [35000, 300, 1800],
  [90000, 800, 3500],
];
export const DIFFERENCE_SCALE = 0.05;

const VERTEX = `#version 300 es
void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)); gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }`;

function fragment(reader) {
  const ridges = RIDGES.map(([d, base, relief]) => `vec3(${d.toFixed(1)}, ${base.toFixed(1)}, ${relief.toFixed(1)})`).join(', ');
  return `#version 300 es
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
out vec4 colour;

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

vec3 skyWithSun(vec3 v, vec3 sun) {
  float gamma = acos(clamp(dot(v, sun), -1.0, 1.0));
  return soraSkyView(uAltitudeM, v, sun) + soraSunDiscXyz(uAltitudeM, uSunElevationDeg, gamma);
}

// Height (m above the ground) of ridge i toward azimuth az (rad).
float ridgeHeight(int i, float az) {
  float c = float(i) * 1.7;
  float n = 0.5 * sin(3.0 * az + c) + 0.3 * sin(7.0 * az + 2.0 * c) + 0.2 * sin(17.0 * az + 3.0 * c);
  return RIDGES[i].y + RIDGES[i].z * (0.5 + 0.5 * n);
}

// The scene along v (east-north-up at the eye): the sky, or a ridge or the
// ground at slant distance d, lit where it stands, seen through the air.
vec3 scene(vec3 v, vec3 sun) {
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
  if (d < 0.0) return skyWithSun(v, sun);
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
  soraAerialPerspectiveFromSky(uAltitudeM, v, sun, d, inscattered, transmittance);
  return lit * transmittance + inscattered;
}

vec3 perspectiveView() {
  float yaw = radians(uLookAzimuthDeg), pitch = radians(12.0);
  vec3 f = vec3(sin(yaw) * cos(pitch), cos(yaw) * cos(pitch), sin(pitch));
  vec3 r = vec3(cos(yaw), -sin(yaw), 0.0);
  vec3 u = cross(r, f);
  float tanX = tan(radians(40.0));
  float tanY = tanX * uSize.y / uSize.x;
  vec2 s = (2.0 * gl_FragCoord.xy - uSize) / uSize;
  return normalize(f + s.x * tanX * r + s.y * tanY * u);
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

void main() {
  vec3 sun = sunDirection();
  vec3 v;
  if (uMode == 1) {
    colour = vec4(display(scene(perspectiveView(), sun)), 1.0);
    return;
  }
  if (!fisheyeView(v)) { colour = vec4(0.0); return; }
  if (uMode == 0) {
    colour = vec4(display(skyWithSun(v, sun)), 1.0);
  } else if (uMode == 3) {
    colour = vec4(soraSkyView(uAltitudeM, v, sun), 1.0);
  } else {
    vec3 realtime = soraSkyView(uAltitudeM, v, sun);
    // The exact image's rows run top first.
    vec3 exact = texelFetch(uExact, ivec2(int(gl_FragCoord.x), int(uSize.y) - 1 - int(gl_FragCoord.y)), 0).xyz;
    if (!(exact.y > 0.0)) { colour = vec4(vec3(0.08), 1.0); return; } // a night sky: no difference
    float t = clamp((realtime.y - exact.y) / max(exact.y, 1e-30) / ${DIFFERENCE_SCALE.toFixed(4)}, -1.0, 1.0);
    vec3 grey = vec3(0.08);
    colour = vec4(t > 0.0 ? mix(grey, vec3(1.0, 0.25, 0.1), t) : mix(grey, vec3(0.2, 0.55, 1.0), -t), 1.0);
  }
}`;
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
    const program = gl.createProgram();
    gl.attachShader(program, compile(gl.VERTEX_SHADER, VERTEX));
    gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fragment(await response.text())));
    gl.linkProgram(program);
    if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(`real-time shader: ${gl.getProgramInfoLog(program)}`);
    gl.useProgram(program);
    this.program = program;
    this.uniform = (name) => gl.getUniformLocation(program, name);
    gl.uniform1i(this.uniform('uSky'), 0);
    gl.uniform1i(this.uniform('uTransmittance'), 1);
    gl.uniform1i(this.uniform('uIrradiance'), 2);
    gl.uniform1i(this.uniform('uExact'), 3);
    this.textures = [0, 1, 2, 3].map(() => gl.createTexture());
    this.floatTarget = Boolean(gl.getExtension('EXT_color_buffer_float'));
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
    gl.uniform4i(this.uniform('uSkyNodes'), sky.sun_nodes, sky.altitude_nodes, sky.zenith_nodes_per_half, sky.azimuth_nodes);
    gl.uniform1i(this.uniform('uSkyZenithFineCells'), sky.zenith_fine_cells_per_half ?? 0);
    gl.uniform2i(this.uniform('uTransmittanceNodes'), t.height, t.width);
    gl.uniform4f(this.uniform('uPlanetSun'), m.planet.ground_radius_m, m.planet.top_radius_m, m.sun.angular_radius_rad, m.sun.limb_darkening);
    gl.uniform3fv(this.uniform('uSunIrradianceXyz'), m.sun.irradiance_xyz_w_m2_nm);
    gl.uniform1f(this.uniform('uSunAxisWidthDeg'), m.sun.axis_width_deg);
    this.tables = json;
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
    const mode = { fisheye: 0, scene: 1, difference: 2, xyz: 3 }[state.mode];
    if (mode === 2 && !this.exact) return false;
    gl.viewport(0, 0, width, height);
    gl.uniform1i(this.uniform('uMode'), mode);
    gl.uniform2f(this.uniform('uSize'), width, height);
    gl.uniform1f(this.uniform('uSunElevationDeg'), Math.min(Math.max(state.sunElevationDeg, -90), 90));
    gl.uniform1f(this.uniform('uSunAzimuthDeg'), state.sunAzimuthDeg);
    gl.uniform1f(this.uniform('uAltitudeM'), state.altitudeM);
    gl.uniform1f(this.uniform('uLookAzimuthDeg'), state.lookAzimuthDeg);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    return true;
  }

  // The fisheye's XYZ at `size` pixels (rows bottom first, RGBA floats).
  readXyz(state, size) {
    const gl = this.gl;
    if (!this.floatTarget) throw new Error('real-time view: no EXT_color_buffer_float to read floats back');
    const target = gl.createTexture();
    gl.activeTexture(gl.TEXTURE4);
    gl.bindTexture(gl.TEXTURE_2D, target);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, size, size);
    const framebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
    this.draw({ ...state, mode: 'xyz' }, size, size);
    const pixels = new Float32Array(size * size * 4);
    gl.readPixels(0, 0, size, size, gl.RGBA, gl.FLOAT, pixels);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.deleteFramebuffer(framebuffer);
    gl.deleteTexture(target);
    return pixels;
  }

  // Mean time of `frames` draws of `state` into the canvas, each waited
  // for by reading a pixel back (gl.finish does not wait for Chromium's
  // GPU process), in ms.
  timeFrames(state, frames) {
    const gl = this.gl;
    const pixel = new Uint8Array(4);
    this.draw(state);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    const start = performance.now();
    for (let i = 0; i < frames; i++) {
      this.draw({ ...state, sunElevationDeg: state.sunElevationDeg + 0.01 * i });
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    }
    return (performance.now() - start) / frames;
  }
}
