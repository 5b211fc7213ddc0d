// The sora sky explorer: controls, the sky image, a direction's spectrum
// and the optical depths, all computed by the sora library in a Web Worker
// (worker.js, sora_web.wasm). Plain ES module, no dependencies.
//
// Progressive rendering: every change asks for a 128-pixel preview (coarse
// tables, every 40 nm) and a 256-pixel refinement (the library's wavelengths,
// a somewhat coarser field and image tables, see quality_settings in
// crates/sora-web/src/engine.rs), at once,
// from two engines in two workers (two cores: the refinement does not wait
// for the preview, and a slider drag's previews do not wait for a
// refinement or a spectrum). Changes that arrive while an engine is busy
// are coalesced: it computes only the latest state, and a result older
// than the image shown is not drawn.
//
// Real-time view (realtime.js): when its checkbox is on, a third engine
// bakes the atmosphere's engine tables (again when an atmosphere control or
// the scattering changes; the worker reports the bake's progress), and the
// page draws the sky, a scene with aerial perspective, or the difference
// from the exact image through WebGL2 from them: moving the sun redraws at
// once, with no engine request. With the eye above the ground (the observer
// altitude) the sky is the tables' raised read, the march per pixel
// (realtime.js's raised program): far slower on a software renderer.
//
// window.soraExplorer exposes the state the browser tests read (timings,
// the last spectrum, counts); it is not an API.

import { RealtimeView, RIDGES, DIFFERENCE_SCALE, SCENE, VOLUME, sceneView } from './realtime.js';

const $ = (id) => document.getElementById(id);

// ---- the engines ----------------------------------------------------------
// One worker (its own sora_web.wasm instance and caches) for the previews,
// one for everything else: refinements, spectra, files, controls.
function startEngine() {
  const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  let nextId = 1;
  const pending = new Map();
  const progress = new Map();
  let resolveReady;
  const ready = new Promise((resolve) => { resolveReady = resolve; });
  worker.onmessage = (event) => {
    const message = event.data;
    if (message.id === 0) {
      if (message.ready) resolveReady();
      else showError(message.json.error);
      return;
    }
    if (message.progress !== undefined) {
      progress.get(message.id)?.(message.progress);
      return;
    }
    pending.get(message.id)(message);
    pending.delete(message.id);
    progress.delete(message.id);
  };
  // onProgress(fraction): called as the engine reports progress.
  const call = (request, onProgress) => new Promise((resolve) => {
    const id = nextId++;
    pending.set(id, resolve);
    if (onProgress) progress.set(id, onProgress);
    worker.postMessage({ id, request });
  });
  return { call, ready };
}

const mainEngine = startEngine();
const previewEngine = startEngine();
const ready = Promise.all([mainEngine.ready, previewEngine.ready]);
const engine = mainEngine.call;

// ---- state ----------------------------------------------------------------
// Each atmosphere control: element id, key of the engine's AtmosphereSpec
// (and of its Controls reply).
const ATMOSPHERE_CONTROLS = [
  ['aerosol-optical-depth', 'aerosol_optical_depth'],
  ['aerosol-median-radius', 'aerosol_median_radius_um'],
  ['aerosol-width', 'aerosol_geometric_std_dev'],
  ['aerosol-k', 'aerosol_imaginary_index'],
  ['ozone', 'ozone_column_du'],
  ['ground-albedo', 'ground_albedo'],
];
const SKY_CONTROLS = ['sun-elevation', 'sun-azimuth', 'observer-altitude', 'ev100'];

const explorer = {
  atmosphere: { preset: 'earth-clear' }, // preset or {toml}, without the controls
  atmosphereLabel: 'earth-clear',
  defaults: {}, // the atmosphere's own control values
  shown: {}, // those values as their fields show them (4 significant digits)
  overrides: {}, // controls the user changed
  view: null, // {elevation_deg, azimuth_deg} of the last click
  lastSpectrum: null,
  stats: { renders: 0, previews: 0, refinements: 0, lastPreview: null, lastRefinement: null, errors: 0 },
  lastError: null,
};
window.soraExplorer = explorer;

function atmosphereSpec() {
  return { ...explorer.atmosphere, ...explorer.overrides };
}

function number(id) {
  return Number.parseFloat($(`${id}-value`).value);
}

function skySpec() {
  return {
    atmosphere: atmosphereSpec(),
    sun_elevation_deg: number('sun-elevation'),
    sun_azimuth_deg: number('sun-azimuth'),
    observer_altitude_m: number('observer-altitude'),
    scattering: $('scattering').value,
    polarisation: $('polarisation').value,
  };
}

function imageSpec(quality) {
  const side = quality === 'preview' ? 128 : 256;
  const panorama = $('camera').value === 'equirect';
  const spec = {
    camera: $('camera').value,
    width: panorama ? 2 * side : side,
    height: side,
    quality,
  };
  if (!$('auto-exposure').checked) spec.ev100 = number('ev100');
  return spec;
}

// ---- messages -------------------------------------------------------------
function showError(text) {
  explorer.lastError = text;
  explorer.stats.errors += 1;
  $('message').textContent = text;
  $('message').hidden = false;
}

function clearError() {
  $('message').hidden = true;
  $('message').textContent = '';
}

function status(text) {
  $('status').textContent = text;
}

// ---- rendering ------------------------------------------------------------
// Each change is a new generation; each engine computes the latest one when
// it is free. The image shown is that of `shown` (generation, refined).
let generation = 0;
let changedAt = 0;
const shown = { generation: 0, refined: false };
const previews = { busy: false, done: 0 };
const refinements = { busy: false, done: 0 };

function changed() {
  generation += 1;
  changedAt = performance.now();
  pumpPreview();
  pumpRefinement();
  realtimeChanged();
}

async function pumpPreview() {
  if (previews.busy || previews.done === generation) return;
  previews.busy = true;
  const [mine, started, sky] = [generation, changedAt, skySpec()];
  previews.done = mine;
  try {
    const preview = await previewEngine.call({ op: 'render', sky, image: imageSpec('preview') });
    if (mine < shown.generation || (mine === shown.generation && shown.refined)) return;
    if (!preview.ok) {
      showError(preview.json.error);
      return;
    }
    clearError();
    draw(preview);
    Object.assign(shown, { generation: mine, refined: false });
    explorer.stats.previews += 1;
    explorer.stats.lastPreview = { ms: performance.now() - started, engineMs: preview.ms, sky, width: preview.json.width };
    status(describe('preview', preview));
  } finally {
    previews.busy = false;
    pumpPreview();
  }
}

async function pumpRefinement() {
  if (refinements.busy || refinements.done === generation) return;
  refinements.busy = true;
  const [mine, started, sky] = [generation, changedAt, skySpec()];
  refinements.done = mine;
  try {
    const refined = await engine({ op: 'render', sky, image: imageSpec('refined') });
    if (mine !== generation) return; // stale: the newer state's come next
    if (!refined.ok) {
      showError(refined.json.error);
      return;
    }
    clearError();
    draw(refined);
    Object.assign(shown, { generation: mine, refined: true });
    explorer.stats.refinements += 1;
    explorer.stats.lastRefinement = { ms: performance.now() - started, engineMs: refined.ms, sky, width: refined.json.width };
    status(describe('refined', refined));
    explorer.shownSky = sky;
    if (explorer.view) await showSpectrum(explorer.view);
  } finally {
    refinements.busy = false;
    explorer.stats.renders += 1;
    pumpRefinement();
  }
}

function describe(stage, reply) {
  const { width, height, wavelengths, night, night_floor_cd_m2: floor } = reply.json;
  const night_note = night ? ` — night: the whole sky is darker than ${floor.toExponential(0)} cd/m² (no airglow or stars in the model), shown black` : '';
  return `${stage} ${width}×${height}, ${wavelengths} wavelengths: ${reply.ms.toFixed(0)} ms${night_note}`;
}

function draw(reply) {
  const { width, height } = reply.json;
  const canvas = $('sky');
  canvas.width = width;
  canvas.height = height;
  canvas.style.height = `${(512 * height) / width}px`;
  const pixels = new ImageData(new Uint8ClampedArray(reply.bytes), width, height);
  canvas.getContext('2d').putImageData(pixels, 0, 0);
  explorer.imageSpec = { ...imageSpec('refined'), width, height };
}

// ---- real-time view -------------------------------------------------------
// bakes/lastBake: the tables baked (ms: the engine's wall time in the
// worker); progress: the fractions the last bake reported; frames: draws.
const realtime = {
  view: null, engine: null, baking: false, bakedFor: null, failedFor: null,
  bakes: 0, lastBake: null, progress: [], frames: 0,
  exact: null, exactBusy: false, exactFor: null,
};
explorer.realtime = realtime;

function realtimeStatus(text) {
  $('realtime-status').textContent = text;
}

function tablesRequest() {
  return { op: 'tables', atmosphere: atmosphereSpec(), scattering: $('scattering').value };
}

function realtimeState(sky = skySpec()) {
  return {
    mode: $('realtime-mode').value,
    sunElevationDeg: sky.sun_elevation_deg,
    sunAzimuthDeg: sky.sun_azimuth_deg,
    altitudeM: sky.observer_altitude_m,
    lookAzimuthDeg: number('look-azimuth'),
  };
}

async function enableRealtime() {
  const on = $('realtime').checked;
  $('realtime-canvas').hidden = !on;
  if (!on) return;
  try {
    if (!realtime.view) {
      const view = new RealtimeView($('realtime-canvas'));
      if (!view.supported) throw new Error('real-time view: this browser has no WebGL2');
      await view.init();
      realtime.engine = startEngine();
      await realtime.engine.ready;
      realtime.view = view;
    }
    realtimeChanged();
  } catch (error) {
    showError(String(error.message || error));
  }
}

function realtimeChanged() {
  if (!$('realtime').checked || !realtime.view) return;
  pumpBake();
  if ($('realtime-mode').value === 'difference') pumpExact();
  requestDraw();
}

function describeTables() {
  const { ms, settings: t, sizeBytes } = realtime.lastBake;
  return `tables: ${t.sun_nodes} suns × ${t.altitude_nodes} altitudes × ${2 * t.zenith_nodes_per_half}×${t.azimuth_nodes} views, ${t.wavelengths} wavelengths (${t.quality} sky), ${(sizeBytes / 1e6).toFixed(1)} MB, baked in ${(ms / 1000).toFixed(1)} s in this browser`;
}

async function pumpBake() {
  const request = tablesRequest();
  const key = JSON.stringify(request);
  if (realtime.baking || realtime.bakedFor === key || realtime.failedFor === key) return;
  realtime.baking = true;
  realtime.progress = [];
  const previous = realtime.bakedFor ? ' (the view shows the previous tables until then)' : '';
  realtimeStatus(`baking the engine tables${previous}…`);
  try {
    const reply = await realtime.engine.call(request, (fraction) => {
      realtime.progress.push(fraction);
      realtimeStatus(`baking the engine tables: ${Math.round(100 * fraction)} % of the sky table's layers${previous}`);
    });
    if (!reply.ok) {
      realtime.failedFor = key;
      showError(reply.json.error);
      realtimeStatus('the tables did not bake');
      return;
    }
    realtime.view.setTables(reply.json, reply.bytes);
    realtime.bakedFor = key;
    realtime.bakes += 1;
    realtime.lastBake = { ms: reply.ms, settings: reply.json.settings, sizeBytes: reply.json.size_bytes, request };
    realtimeStatus(describeTables());
    if ($('realtime-mode').value === 'difference') pumpExact();
    requestDraw();
  } finally {
    realtime.baking = false;
    if ($('realtime').checked) pumpBake();
  }
}

// The exact image the difference view compares with: the refinement's
// sky as XYZ, fisheye, 256 pixels, no sun disc.
async function pumpExact() {
  // The engine tables hold scalar light (docs/engine-tables.md), so the
  // image they are compared with is scalar too.
  const sky = { ...skySpec(), polarisation: 'scalar' };
  const key = JSON.stringify(sky);
  if (realtime.exactBusy || realtime.exactFor === key) return;
  realtime.exactBusy = true;
  try {
    const reply = await engine({ op: 'render_xyz', sky, image: { camera: 'fisheye', width: 256, height: 256, quality: 'refined', sun_disc: false } });
    if (!reply.ok) {
      showError(reply.json.error);
      return;
    }
    realtime.view.setExact(reply.json, reply.bytes);
    realtime.exactFor = key;
    realtime.exact = { sky, ms: reply.ms };
    requestDraw();
  } finally {
    realtime.exactBusy = false;
    if ($('realtime-mode').value === 'difference' && $('realtime').checked) pumpExact();
  }
}

let drawRequested = false;
function requestDraw() {
  if (drawRequested) return;
  drawRequested = true;
  requestAnimationFrame(() => {
    drawRequested = false;
    drawRealtime();
  });
}

function drawRealtime() {
  const view = realtime.view;
  if (!view || !view.tables) return;
  const mode = $('realtime-mode').value;
  let state = realtimeState();
  const canvas = $('realtime-canvas');
  // As many pixels as the exact image: a software renderer (SwiftShader)
  // takes about 0.2 s a frame at this size; CSS scales them to 512 across.
  const [width, height] = mode === 'scene' ? [SCENE.width, SCENE.height] : [256, 256];
  if (canvas.width !== width || canvas.height !== height) Object.assign(canvas, { width, height });
  canvas.style.height = `${(512 * height) / width}px`;
  let note = '';
  if (mode === 'difference') {
    // The difference is drawn for the exact image's sky, tables of the
    // same atmosphere: a sun slider's newer state waits for its image.
    const tablesKey = JSON.stringify({ op: 'tables', atmosphere: realtime.exact?.sky.atmosphere, scattering: realtime.exact?.sky.scattering });
    if (!realtime.exact || tablesKey !== realtime.bakedFor) {
      realtimeStatus('computing the exact image for the difference…');
      return;
    }
    state = realtimeState(realtime.exact.sky);
    note = ` — luminance (real-time − exact) / exact: red brighter, blue dimmer, full colour at ±${100 * DIFFERENCE_SCALE} %; sun ${state.sunElevationDeg}°`;
  } else if (mode === 'scene') {
    const air = view.volumeUsed
      ? `aerial perspective from a ${VOLUME.columns}×${VOLUME.rows}×${VOLUME.slices} volume marched from the tables`
      : 'aerial perspective from the sky table (no march tables)';
    note = ` — ridges at ${RIDGES.map(([d]) => d / 1000).join(', ')} km, looking toward azimuth ${state.lookAzimuthDeg}°; ${air}`;
  }
  if (view.raisedSky(state)) {
    note += ` — eye ${state.altitudeM} m up: its sky marched per pixel from the march's tables`;
  }
  const started = performance.now();
  view.draw(state);
  realtime.frames += 1;
  realtime.lastDraw = { state, ms: performance.now() - started };
  if (!realtime.baking) realtimeStatus(`${describeTables()}${note}`);
}

// For the browser test: the fisheye's XYZ from the tables, and the exact
// image of the same sky at `quality`, both `size` pixels (scalar light, the
// tables' own, as the difference view's).
realtime.compare = async (quality, size) => {
  const sky = { ...skySpec(), polarisation: 'scalar' };
  const gpu = realtime.view.readXyz(realtimeState(sky), size);
  const reply = await engine({ op: 'render_xyz', sky, image: { camera: 'fisheye', width: size, height: size, quality, sun_disc: false } });
  if (!reply.ok) throw new Error(reply.json.error);
  return { sky, gpu: Array.from(gpu), cpu: Array.from(new Float32Array(reply.bytes)), cpuMs: reply.ms };
};
realtime.timeFrames = (mode, frames, still = false) => {
  $('realtime-mode').value = mode;
  drawRealtime();
  return realtime.view.timeFrames(realtimeState(), frames, still);
};
// For the browser test: the scene camera's aerial perspective of a point
// at each of `distances` (m) along the views through the centres of a
// columns x rows grid over its picture (rows bottom first), read from the
// volume, marched per pixel and from the sky table's difference (the
// scene's before the volume) (XYZ, RGBA floats), and the library's (the
// engine's aerial_perspective at `quality`, XYZ triples).
realtime.compareAerial = async ({ distances, columns, rows, quality }) => {
  const sky = { ...skySpec(), polarisation: 'scalar' };
  const state = realtimeState(sky);
  const views = [];
  for (let row = 0; row < rows; row++) {
    for (let column = 0; column < columns; column++) {
      const v = sceneView(state.lookAzimuthDeg, (2 * (column + 0.5) - columns) / columns, (2 * (row + 0.5) - rows) / rows);
      views.push([v.elevationDeg, v.azimuthDeg]);
    }
  }
  const read = (mode, distanceM, fromSky = false) => Array.from(realtime.view.readFloats({ ...state, mode, distanceM, fromSky }, columns, rows));
  // The library only for the views above the eye's horizon (the others
  // meet the ground at once from an eye on it): segment 0 for them.
  const R = realtime.view.tables.manifest.planet.ground_radius_m;
  const dipDeg = (Math.acos(R / (R + Math.max(state.altitudeM, 0))) * 180) / Math.PI;
  const kept = views.flatMap(([elevation], i) => (elevation > -dipDeg + 0.05 ? [i] : []));
  const reply = await engine({ op: 'aerial_perspective', sky, views: kept.map((i) => views[i]), distances_m: distances, quality });
  if (!reply.ok) throw new Error(reply.json.error);
  const spread = (values, fill) => {
    const all = views.map(() => fill);
    kept.forEach((i, n) => { all[i] = values[n]; });
    return all;
  };
  const results = distances.map((distanceM, n) => ({
    distanceM,
    volume: { inscattered: read('aerial-inscattered', distanceM), transmittance: read('aerial-transmittance', distanceM) },
    march: { inscattered: read('march-inscattered', distanceM), transmittance: read('march-transmittance', distanceM) },
    fromSky: { inscattered: read('aerial-inscattered', distanceM, true), transmittance: read('aerial-transmittance', distanceM, true) },
    library: {
      inscattered: spread(reply.json.inscattered_xyz[n], [0, 0, 0]),
      transmittance: spread(reply.json.transmittance_xyz[n], [1, 1, 1]),
      segmentM: spread(reply.json.segment_m[n], 0),
    },
  }));
  return { sky, views, volumeUsed: realtime.view.volumeUsed, libraryMs: reply.ms, results };
};
// For the browser test: the time to fill the volume and draw the scene
// once (a pixel read back), and to fill it alone, in ms, averaged.
realtime.timeVolume = (frames) => {
  const view = realtime.view;
  const gl = view.gl;
  const pixel = new Uint8Array(4);
  const state = { ...realtimeState(), mode: 'scene' };
  view.draw(state);
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
  const start = performance.now();
  for (let i = 0; i < frames; i++) {
    view.draw({ ...state, sunElevationDeg: state.sunElevationDeg + 0.01 * (i + 1) }, 1, 1);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
  }
  return (performance.now() - start) / frames;
};

// ---- spectrum -------------------------------------------------------------
async function showSpectrum(view) {
  const reply = await engine({
    op: 'spectrum',
    sky: skySpec(),
    view_elevation_deg: view.elevation_deg,
    view_azimuth_deg: view.azimuth_deg,
  });
  if (!reply.ok) {
    showError(reply.json.error);
    return;
  }
  explorer.lastSpectrum = { ...reply.json, sky: skySpec() };
  $('download-csv').disabled = false;
  $('direction').textContent = `elevation ${view.elevation_deg.toFixed(1)}°, azimuth ${view.azimuth_deg.toFixed(1)}°`;
  plotSpectrum(reply.json);
  const [r, g, b] = reply.json.linear_srgb;
  const peak = Math.max(r, g, b, 1e-300);
  const encode = (c) => {
    const v = Math.min(Math.max(c / peak, 0), 1);
    return Math.round(255 * (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055));
  };
  $('swatch').style.background = `rgb(${encode(r)}, ${encode(g)}, ${encode(b)})`;
  const xy = reply.json.chromaticity_xy;
  $('colour-text').textContent = `${reply.json.luminance_cd_m2.toPrecision(4)} cd/m²` +
    (xy ? `, chromaticity x ${xy[0].toFixed(4)}, y ${xy[1].toFixed(4)}` : '');
}

function plotSpectrum(spectrum) {
  const canvas = $('plot');
  const context = canvas.getContext('2d');
  const { width, height } = canvas;
  const margin = { left: 62, right: 10, top: 10, bottom: 34 };
  context.clearRect(0, 0, width, height);
  const wavelengths = spectrum.wavelength_nm;
  const series = [
    { values: spectrum.radiance_w_m2_sr_nm, colour: '#7cf', label: spectrum.single_scattering_w_m2_sr_nm === spectrum.radiance_w_m2_sr_nm ? 'radiance' : 'all orders' },
    { values: spectrum.single_scattering_w_m2_sr_nm, colour: '#fa6', label: 'single scattering' },
  ];
  const top = Math.max(...series.flatMap((s) => s.values), 1e-300) * 1.05;
  const x = (nm) => margin.left + ((nm - wavelengths[0]) / (wavelengths.at(-1) - wavelengths[0])) * (width - margin.left - margin.right);
  const y = (v) => height - margin.bottom - (v / top) * (height - margin.top - margin.bottom);
  context.strokeStyle = '#666';
  context.fillStyle = '#bbb';
  context.font = '11px system-ui';
  context.beginPath();
  context.moveTo(margin.left, margin.top);
  context.lineTo(margin.left, height - margin.bottom);
  context.lineTo(width - margin.right, height - margin.bottom);
  context.stroke();
  for (let nm = 400; nm <= 780; nm += 100) {
    context.fillText(String(nm), x(nm) - 10, height - margin.bottom + 14);
  }
  context.fillText('wavelength, nm', width / 2 - 30, height - 4);
  for (let k = 0; k <= 4; k += 1) {
    const v = (top * k) / 4;
    context.fillText(v.toExponential(1), 4, y(v) + 4);
  }
  context.save();
  context.translate(10, height / 2 + 40);
  context.restore();
  context.fillText('W m⁻² sr⁻¹ nm⁻¹', margin.left + 6, margin.top + 10);
  series.forEach((s, k) => {
    context.strokeStyle = s.colour;
    context.lineWidth = 2;
    context.beginPath();
    s.values.forEach((v, i) => (i ? context.lineTo(x(wavelengths[i]), y(v)) : context.moveTo(x(wavelengths[i]), y(v))));
    context.stroke();
    context.fillStyle = s.colour;
    context.fillText(s.label, width - 120, margin.top + 14 + 14 * k);
  });
}

// ---- atmosphere -----------------------------------------------------------
async function setAtmosphere(atmosphere, label) {
  const reply = await engine({ op: 'controls', atmosphere });
  if (!reply.ok) {
    showError(reply.json.error);
    return false;
  }
  const optics = await engine({ op: 'optics', atmosphere });
  if (!optics.ok) {
    showError(optics.json.error);
    return false;
  }
  explorer.atmosphere = atmosphere;
  explorer.atmosphereLabel = label;
  explorer.defaults = reply.json;
  explorer.overrides = {};
  $('atmosphere-name').textContent = label;
  for (const [id, key] of ATMOSPHERE_CONTROLS) {
    const value = reply.json[key];
    const usable = value !== null && value !== undefined;
    $(id).disabled = !usable;
    $(`${id}-value`).disabled = !usable;
    const text = usable ? String(Number(value.toPrecision(4))) : '';
    explorer.shown[key] = text;
    $(id).value = usable ? value : $(id).min;
    $(`${id}-value`).value = text;
  }
  const reference = reply.json.aerosol_reference_wavelength_nm;
  $('aerosol-reference').textContent = reference ? `at ${reference} nm` : '';
  showOptics(optics.json);
  clearError();
  changed();
  return true;
}

function showOptics(optics) {
  const columns = [400, 500, 600, 700].map((nm) => optics.wavelength_nm.indexOf(nm));
  const at500 = optics.wavelength_nm.indexOf(500);
  const rows = optics.species.map((s) => `<tr><td>${escape(s.name)} <span class="note">${s.kind}</span></td>${columns.map((i) => `<td>${s.optical_depth[i].toPrecision(3)}</td>`).join('')}<td>${s.single_scattering_albedo[at500].toFixed(3)}</td><td>${s.asymmetry_g[at500].toFixed(3)}</td></tr>`);
  const total = `<tr><th>total</th>${columns.map((i) => `<th>${optics.total_optical_depth[i].toPrecision(3)}</th>`).join('')}<th></th><th></th></tr>`;
  $('optics').innerHTML = `<tr><th>species</th><th>τ 400 nm</th><th>500</th><th>600</th><th>700</th><th>ω 500</th><th>g 500</th></tr>${rows.join('')}${total}`;
}

function escape(text) {
  return text.replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' })[c]);
}

async function loadAtmosphereFile(file) {
  const text = await file.text();
  await setAtmosphere({ toml: text }, file.name);
}

// ---- downloads ------------------------------------------------------------
function download(blob, name) {
  const link = document.createElement('a');
  link.href = URL.createObjectURL(blob);
  link.download = name;
  link.click();
  setTimeout(() => URL.revokeObjectURL(link.href), 10000);
}

function spectrumCsv(spectrum) {
  const lines = ['wavelength_nm,radiance_w_m2_sr_nm,single_scattering_w_m2_sr_nm'];
  spectrum.wavelength_nm.forEach((nm, i) => {
    lines.push(`${nm},${spectrum.radiance_w_m2_sr_nm[i]},${spectrum.single_scattering_w_m2_sr_nm[i]}`);
  });
  return `${lines.join('\n')}\n`;
}
explorer.spectrumCsv = () => (explorer.lastSpectrum ? spectrumCsv(explorer.lastSpectrum) : null);

// ---- wiring ---------------------------------------------------------------
function linkSlider(id, onChange) {
  const slider = $(id);
  const field = $(`${id}-value`);
  slider.addEventListener('input', () => {
    field.value = slider.value;
    onChange();
  });
  field.addEventListener('change', () => {
    if (field.value !== '') slider.value = field.value;
    onChange();
  });
}

function atmosphereControlChanged() {
  explorer.overrides = {};
  for (const [id, key] of ATMOSPHERE_CONTROLS) {
    const field = $(`${id}-value`);
    // A field still showing the atmosphere's (rounded) value keeps the
    // atmosphere's exact one.
    if (field.disabled || field.value === '' || field.value === explorer.shown[key]) continue;
    const value = Number.parseFloat(field.value);
    explorer.overrides[key] = Number.isNaN(value) ? field.value : value;
  }
  engine({ op: 'optics', atmosphere: atmosphereSpec() }).then((reply) => reply.ok && showOptics(reply.json));
  changed();
}

async function start() {
  for (const id of SKY_CONTROLS) linkSlider(id, changed);
  for (const [id] of ATMOSPHERE_CONTROLS) linkSlider(id, atmosphereControlChanged);
  for (const id of ['scattering', 'polarisation', 'camera']) $(id).addEventListener('change', changed);
  $('realtime').addEventListener('change', enableRealtime);
  $('realtime-mode').addEventListener('change', realtimeChanged);
  linkSlider('look-azimuth', requestDraw);
  $('auto-exposure').addEventListener('change', () => {
    $('ev100').disabled = $('auto-exposure').checked;
    $('ev100-value').disabled = $('auto-exposure').checked;
    changed();
  });
  $('preset').addEventListener('change', () => setAtmosphere({ preset: $('preset').value }, $('preset').value));
  $('atmosphere-file').addEventListener('change', () => {
    const [file] = $('atmosphere-file').files;
    if (file) loadAtmosphereFile(file);
  });
  document.body.addEventListener('dragover', (event) => {
    event.preventDefault();
    document.body.classList.add('dragging');
  });
  document.body.addEventListener('dragleave', () => document.body.classList.remove('dragging'));
  document.body.addEventListener('drop', (event) => {
    event.preventDefault();
    document.body.classList.remove('dragging');
    const [file] = event.dataTransfer.files;
    if (file) loadAtmosphereFile(file);
  });
  $('sky').addEventListener('click', async (event) => {
    const canvas = $('sky');
    const bounds = canvas.getBoundingClientRect();
    const column = Math.floor(((event.clientX - bounds.left) / bounds.width) * canvas.width);
    const row = Math.floor(((event.clientY - bounds.top) / bounds.height) * canvas.height);
    const reply = await engine({ op: 'view_at_pixel', image: explorer.imageSpec, column, row });
    if (!reply.ok) return showError(reply.json.error);
    if (reply.json.elevation_deg === null) return status('outside the sky: click inside the circle');
    explorer.view = reply.json;
    await showSpectrum(explorer.view);
  });
  $('download-png').addEventListener('click', () => $('sky').toBlob((blob) => download(blob, 'sky.png'), 'image/png'));
  $('download-exr').addEventListener('click', async () => {
    const reply = await engine({ op: 'exr', sky: skySpec(), image: imageSpec('refined') });
    if (!reply.ok) return showError(reply.json.error);
    download(new Blob([reply.bytes], { type: 'image/x-exr' }), 'sky.exr');
  });
  $('download-csv').addEventListener('click', () => {
    download(new Blob([spectrumCsv(explorer.lastSpectrum)], { type: 'text/csv' }), 'spectrum.csv');
  });
  $('download-toml').addEventListener('click', async () => {
    const reply = await engine({ op: 'atmosphere_toml', atmosphere: atmosphereSpec() });
    if (!reply.ok) return showError(reply.json.error);
    download(new Blob([reply.json.toml], { type: 'text/plain' }), 'atmosphere.toml');
  });

  await ready;
  const presets = await engine({ op: 'presets' });
  for (const preset of presets.json.presets) {
    const option = new Option(`${preset.name}: ${preset.description}`, preset.name);
    $('preset').add(option);
  }
  $('preset').value = 'earth-clear';
  await setAtmosphere({ preset: 'earth-clear' }, 'earth-clear');
}

start().catch((error) => showError(String(error.message || error)));
