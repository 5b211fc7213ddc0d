// The reference shader's raised-eye sky (soraRaisedSkyXyz, web/shaders/sora_sky.glsl)
// against the Rust lookup's EngineTables::sky_xyz: DIR from the ignored test
// engine_tables::tests::raised_eye_reference (SORA_EYE_SHADER_OUT=DIR cargo test
// --release -p sora --lib -- --ignored raised_eye_reference: earth-clear baked as
// `sora tables --preset earth-clear --altitude-nodes 2`, the tables in DIR/tables,
// 96 reads at 5 and 50 km in DIR/raised.json); WebGL2 on SwiftShader draws the same
// reads, one pixel each, and the relative error per channel is printed (measured
// worst 0.061 %); it fails above 0.5 % (32-bit floats against the lookup's 64) or if
// the context is lost. Run by .ci/run; by hand: cd web/tests && npm ci && node raised-eye.mjs DIR
import { readFileSync } from 'node:fs';
import { chromium } from 'playwright-core';
import { readExr } from './exr.mjs';
import { marchTextures, setMarchUniforms } from '../march.js';
const dir = process.argv[2];
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
  return route.fulfill({ contentType: 'application/octet-stream', body: bodies[path] });
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
console.log(`worst |rel| ${(100 * worst).toFixed(3)} %; draw ${out.ms.toFixed(0)} ms; error ${out.err} lost ${out.lost}`);
await browser.close();
if (out.lost || out.err !== 0 || !(worst <= 0.005)) {
  console.error(`raised eye: the shader's sky is not the Rust lookup's (worst ${(100 * worst).toFixed(3)} %, bound 0.5 %; error ${out.err}, lost ${out.lost})`);
  process.exit(1);
}
