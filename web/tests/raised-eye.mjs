// The raised eye's sky in the reference shader and in the real-time view,
// against the Rust lookup's EngineTables::sky_xyz: DIR from the ignored test
// engine_tables::tests::raised_eye_reference (SORA_EYE_SHADER_OUT=DIR cargo test
// --release -p sora --lib -- --ignored raised_eye_reference: earth-clear baked as
// `sora tables --preset earth-clear --altitude-nodes 3`, nodes at 0, 12.3 and 100
// km, the tables in DIR/tables). WebGL2 on SwiftShader draws
// - soraRaisedSkyXyz (web/shaders/sora_sky.glsl) at DIR/raised.json's 96 reads
//   (eyes at 5 and 50 km: both altitude cells), one pixel each (measured worst
//   0.071 %);
// - the real-time view (web/realtime.js's RealtimeView, the same tables, its
//   fisheye's XYZ read back) at DIR/fisheye.json's 32 x 32 fisheyes: eyes at 0
//   (its views' program, the table's read), 5 and 30 km (its raised program,
//   soraRaisedSkyView), suns 30, 3 and -4 (measured worst 0.32 %, p99 0.15 %);
// and prints the relative error per channel. It fails above BOUND (0.5 %: 32-bit
// floats against the lookup's 64), if a fisheye is drawn by the other program,
// or if the context is lost. It then times the real-time fisheye at 256 x 256 for
// the eye on the ground; with SORA_EYE_FRAMES=1 also at 5 km (about 47 s a frame on
// SwiftShader, the march per pixel). Run by .ci/run; by hand: cd web/tests && npm ci
// && node raised-eye.mjs DIR
import { readFileSync } from 'node:fs';
import { chromium } from 'playwright-core';
import { readExr } from './exr.mjs';
import { marchTextures, setMarchUniforms } from '../march.js';
const dir = process.argv[2];
// Relative error allowed per channel (32-bit floats against the lookup's 64).
const BOUND = 0.005;
const manifest = JSON.parse(readFileSync(`${dir}/tables/manifest.json`, 'utf8'));
const rows = JSON.parse(readFileSync(`${dir}/raised.json`, 'utf8'));
const table = (name) => {
  const exr = readExr(readFileSync(`${dir}/tables/${name}.exr`));
  const { X, Y, Z } = exr.channels;
  const rgba = new Float32Array(exr.width * exr.height * 4);
  for (let i = 0; i < exr.width * exr.height; i++) { rgba[4 * i] = X[i]; rgba[4 * i + 1] = Y[i]; rgba[4 * i + 2] = Z[i]; }
  return Buffer.from(rgba.buffer);
};
const tex = { sky: table('sky'), transmittance: table('transmittance'), irradiance: table('irradiance') };
const m = marchTextures(manifest.tables.march, readFileSync(`${dir}/tables/march.bin`));
const march = { offsets: m.offsets, lengths: m.lengths, tablesHeight: m.tablesHeight, sourceSize: m.sourceSize };
const bodies = { '/sky': tex.sky, '/transmittance': tex.transmittance, '/irradiance': tex.irradiance,
  '/marchSource': Buffer.from(m.source.buffer, m.source.byteOffset, m.source.byteLength), '/marchTables': Buffer.from(m.tables.buffer, m.tables.byteOffset, m.tables.byteLength) };
const shader = readFileSync(new URL('../shaders/sora_sky.glsl', import.meta.url), 'utf8');
const setMarch = setMarchUniforms.toString();
const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'] });
const page = await browser.newPage();
await page.route('http://check.test/**', (route) => {
  const path = new URL(route.request().url()).pathname;
  if (path === '/') return route.fulfill({ contentType: 'text/html', body: '<!doctype html><p>x</p>' });
  if (!bodies[path]) return route.fulfill({ status: 404, body: '' });
  return route.fulfill({ contentType: path.endsWith('.js') ? 'text/javascript' : 'application/octet-stream', body: bodies[path] });
});
await page.goto('http://check.test/');
const out = await page.evaluate(async ({ shader, manifest, march, rows, setMarch }) => {
  const get = async (name) => await (await fetch(name)).arrayBuffer();
  const tex = { sky: new Float32Array(await get('/sky')), transmittance: new Float32Array(await get('/transmittance')), irradiance: new Float32Array(await get('/irradiance')) };
  march.source = new Uint16Array(await get('/marchSource'));
  march.tables = new Float32Array(await get('/marchTables'));
  const setMarchUniforms = eval('(' + setMarch + ')');
  const canvas = document.createElement('canvas');
  const gl = canvas.getContext('webgl2');
  gl.getExtension('EXT_color_buffer_float');
  const t = manifest.tables;
  const layers = t.sky.sun_nodes * t.sky.altitude_nodes;
  const texture = (target, unit) => { const x = gl.createTexture(); gl.activeTexture(gl.TEXTURE0 + unit); gl.bindTexture(target, x);
    gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.NEAREST); gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.NEAREST); };
  texture(gl.TEXTURE_2D_ARRAY, 0);
  gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, t.sky.width, t.sky.height / layers, layers, 0, gl.RGBA, gl.FLOAT, tex.sky);
  texture(gl.TEXTURE_2D, 1);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, t.transmittance.width, t.transmittance.height, 0, gl.RGBA, gl.FLOAT, tex.transmittance);
  texture(gl.TEXTURE_2D, 2);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, t.irradiance.width, t.irradiance.height, 0, gl.RGBA, gl.FLOAT, tex.irradiance);
  texture(gl.TEXTURE_2D_ARRAY, 3);
  gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA32F, 1, 1, 1, 0, gl.RGBA, gl.FLOAT, new Float32Array(4));
  texture(gl.TEXTURE_2D_ARRAY, 4);
  const [w, h, d] = march.sourceSize;
  gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA16F, w, h, d, 0, gl.RGBA, gl.HALF_FLOAT, march.source);
  texture(gl.TEXTURE_2D, 5);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.R32F, 2048, march.tablesHeight, 0, gl.RED, gl.FLOAT, march.tables);
  texture(gl.TEXTURE_2D, 6);
  const params = new Float32Array(rows.length * 4);
  rows.forEach((r, i) => params.set([r[0], r[1], r[2], r[3]], 4 * i));
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, rows.length, 1, 0, gl.RGBA, gl.FLOAT, params);
  const vertex = `#version 300 es
    void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)); gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }`;
  const fragment = `#version 300 es
    precision highp float;
    precision highp int;
    ${shader}
    uniform highp sampler2D uParams;
    out vec4 colour;
    void main() {
      vec4 p = texelFetch(uParams, ivec2(int(gl_FragCoord.x), 0), 0);
      colour = vec4(soraRaisedSkyXyz(p.x, p.y, p.z, p.w), 1.0);
    }`;
  const compile = (type, source) => { const s = gl.createShader(type); gl.shaderSource(s, source); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s)); return s; };
  const program = gl.createProgram();
  gl.attachShader(program, compile(gl.VERTEX_SHADER, vertex));
  gl.attachShader(program, compile(gl.FRAGMENT_SHADER, fragment));
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  gl.useProgram(program);
  const u = (name) => gl.getUniformLocation(program, name);
  gl.uniform1i(u('uSky'), 0); gl.uniform1i(u('uTransmittance'), 1); gl.uniform1i(u('uIrradiance'), 2); gl.uniform1i(u('uAerial'), 3);
  gl.uniform1i(u('uMarchSource'), 4); gl.uniform1i(u('uMarchTables'), 5); gl.uniform1i(u('uParams'), 6);
  gl.uniform3i(u('uAerialNodes'), 0, 0, 0);
  gl.uniform4i(u('uSkyNodes'), t.sky.sun_nodes, t.sky.altitude_nodes, t.sky.zenith_nodes_per_half, t.sky.azimuth_nodes);
  gl.uniform1i(u('uSkyZenithFineCells'), t.sky.zenith_fine_cells_per_half ?? 0);
  gl.uniform1i(u('uSkyZenithWideCells'), t.sky.zenith_wide_cells_per_half ?? 0);
  gl.uniform2i(u('uTransmittanceNodes'), t.transmittance.height, t.transmittance.width);
  gl.uniform4f(u('uPlanetSun'), manifest.planet.ground_radius_m, manifest.planet.top_radius_m, manifest.sun.angular_radius_rad, manifest.sun.limb_darkening);
  gl.uniform3fv(u('uSunIrradianceXyz'), manifest.sun.irradiance_xyz_w_m2_nm);
  gl.uniform1f(u('uSunAxisWidthDeg'), manifest.sun.axis_width_deg);
  setMarchUniforms(gl, program, t.march, march);
  gl.activeTexture(gl.TEXTURE0 + 7);
  const target = gl.createTexture(); gl.bindTexture(gl.TEXTURE_2D, target);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, rows.length, 1);
  const fb = gl.createFramebuffer(); gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  gl.viewport(0, 0, rows.length, 1);
  const start = performance.now();
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const px = new Float32Array(rows.length * 4);
  gl.readPixels(0, 0, rows.length, 1, gl.RGBA, gl.FLOAT, px);
  return { px: Array.from(px), ms: performance.now() - start, err: gl.getError(), lost: gl.isContextLost() };
}, { shader, manifest, march, rows, setMarch });
let worst = 0;
for (const [i, r] of rows.entries()) {
  const s = out.px.slice(4 * i, 4 * i + 3);
  const rel = [0, 1, 2].map((c) => s[c] / r[4 + c] - 1);
  worst = Math.max(worst, ...rel.map(Math.abs));
  console.log(`h ${r[0]} e ${r[3]} z ${r[1]} phi ${r[2]}: Y rust ${r[5].toExponential(4)} shader ${s[1].toExponential(4)}  rel X ${(100*rel[0]).toFixed(3)} % Y ${(100*rel[1]).toFixed(3)} % Z ${(100*rel[2]).toFixed(3)} %`);
}
console.log(`soraRaisedSkyXyz: worst |rel| ${(100 * worst).toFixed(3)} %; draw ${out.ms.toFixed(0)} ms; error ${out.err} lost ${out.lost}`);
const failures = [];
if (out.lost || out.err !== 0 || !(worst <= BOUND)) {
  failures.push(`soraRaisedSkyXyz is not the Rust lookup's (worst ${(100 * worst).toFixed(3)} %, bound ${100 * BOUND} %; error ${out.err}, lost ${out.lost})`);
}

// The real-time view's drawing (web/realtime.js, RealtimeView: its views'
// program for the eye on the ground, the raised program above it) of
// DIR/fisheye.json's fisheyes, XYZ read back, against EngineTables::sky_xyz
// per pixel; then its frame times at 256 x 256 (each frame read back).
const realtimeTables = (() => {
  const blocks = [['sky', tex.sky], ['transmittance', tex.transmittance], ['irradiance', tex.irradiance]];
  const json = { manifest, tables: {} };
  let offset = 0;
  for (const [name, bytes] of blocks) {
    json.tables[name] = { offset_bytes: offset, width: manifest.tables[name].width, height: manifest.tables[name].height };
    offset += bytes.length;
  }
  const marchBin = readFileSync(`${dir}/tables/march.bin`);
  json.tables.march = { offset_bytes: offset, length_bytes: marchBin.length };
  return { json, bytes: Buffer.concat([...blocks.map(([, b]) => b), marchBin]) };
})();
bodies['/realtimeTables'] = realtimeTables.bytes;
for (const file of ['realtime.js', 'march.js', 'shaders/sora_sky.glsl']) {
  bodies[`/${file}`] = readFileSync(new URL(`../${file}`, import.meta.url));
}
const fisheye = JSON.parse(readFileSync(`${dir}/fisheye.json`, 'utf8'));
const drawn = await page.evaluate(async ({ json, fisheye, raisedFrames }) => {
  const { RealtimeView } = await import('/realtime.js');
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = 256;
  document.body.append(canvas);
  const view = new RealtimeView(canvas);
  await view.init();
  view.setTables(json, await (await fetch('/realtimeTables')).arrayBuffer());
  const state = (c) => ({ mode: 'xyz', sunElevationDeg: c.sun_elevation_deg, sunAzimuthDeg: c.sun_azimuth_deg, altitudeM: c.altitude_m, lookAzimuthDeg: 0 });
  const cases = [];
  for (const c of fisheye.cases) {
    const started = performance.now();
    const px = view.readXyz(state(c), fisheye.size);
    cases.push({ px: Array.from(px), program: view.lastProgram, ms: performance.now() - started });
  }
  const gl = view.gl;
  const frame = (altitudeM, frames) => view.timeFrames({ ...state(fisheye.cases[0]), mode: 'fisheye', sunElevationDeg: 3, altitudeM }, frames, true);
  const frameMs = { ground: frame(0, 5) };
  if (raisedFrames) Object.assign(frameMs, { raised5km: frame(5000, 1), groundAfter: frame(0, 5) });
  return { cases, frameMs, raisedLinkMs: view.raisedLinkMs, err: gl.getError(), lost: gl.isContextLost() };
}, { json: realtimeTables.json, fisheye, raisedFrames: process.env.SORA_EYE_FRAMES === '1' });
const n = fisheye.size;
for (const [k, c] of fisheye.cases.entries()) {
  const d = drawn.cases[k];
  const rel = [];
  let where = '';
  let caseWorst = 0;
  for (let i = 0; i < n * n; i++) {
    const ref = c.xyz[i];
    if (!ref) continue;
    for (let ch = 0; ch < 3; ch++) {
      const r = d.px[4 * i + ch] / ref[ch] - 1;
      rel.push(Math.abs(r));
      if (!(Math.abs(r) <= caseWorst)) { caseWorst = Number.isNaN(r) ? Infinity : Math.abs(r); where = `pixel (${i % n}, ${Math.floor(i / n)}) channel ${'XYZ'[ch]}: rust ${ref[ch].toExponential(4)} drawn ${d.px[4 * i + ch].toExponential(4)}`; }
    }
  }
  rel.sort((a, b) => a - b);
  const p99 = rel[Math.floor(0.99 * (rel.length - 1))];
  const program = c.altitude_m > 0 ? 2 : 0;
  console.log(`real-time view, eye ${c.altitude_m / 1000} km, sun ${c.sun_elevation_deg}: ${rel.length / 3} pixels, |rel| worst ${(100 * caseWorst).toFixed(3)} % (${where}), p99 ${(100 * p99).toFixed(3)} %; program ${d.program}; drawn in ${d.ms.toFixed(0)} ms`);
  if (d.program !== program) failures.push(`eye ${c.altitude_m} m: drawn by program ${d.program}, not ${program}`);
  if (!(caseWorst <= BOUND)) failures.push(`real-time view, eye ${c.altitude_m} m, sun ${c.sun_elevation_deg}: worst ${(100 * caseWorst).toFixed(3)} % > ${100 * BOUND} % against the Rust lookup`);
}
const raisedFrame = drawn.frameMs.raised5km === undefined ? '' : `, at 5 km ${drawn.frameMs.raised5km.toFixed(0)} ms (the eye on the ground again ${drawn.frameMs.groundAfter.toFixed(0)} ms)`;
console.log(`real-time view, fisheye 256 x 256 on SwiftShader: the eye on the ground ${drawn.frameMs.ground.toFixed(0)} ms a frame${raisedFrame}; the raised program linked in ${drawn.raisedLinkMs?.toFixed(0)} ms; error ${drawn.err} lost ${drawn.lost}`);
if (drawn.lost || drawn.err !== 0) failures.push(`real-time view: error ${drawn.err}, lost ${drawn.lost}`);
await browser.close();
if (failures.length > 0) {
  console.error(`raised eye: ${failures.join('; ')}`);
  process.exit(1);
}
