// march.bin as web/shaders/sora_sky.glsl binds it (docs/engine-tables.md,
// "Binding the tables"): log_source (16-bit floats) with its channels
// padded to whole RGBA16F texels for uMarchSource, every other array one
// after another in MARCH_ARRAYS' order (the shader's SORA_MARCH_* order)
// as R32F rows of MARCH_WIDTH for uMarchTables, and the uniforms' offsets
// and lengths. Used by the real-time view (web/realtime.js) and the tables'
// browser test (web/tests/tables.test.mjs).

export const MARCH_ARRAYS = ['source_levels_m', 'source_sun_zenith_rad', 'source_wavelength_indices', 'extinction',
  'scaled_extinction', 'scaled_scattering', 'scattering', 'solar', 'xyz', 'density', 'sun_columns', 'phase',
  'smooth_phase', 'kernel_x', 'kernel', 'beam_altitudes_m', 'ln_beam', 'ground_diffuse', 'ground_direct',
  'source_azimuth_rad'];
export const MARCH_WIDTH = 2048;
// sora_sky.glsl's capacities (SORA_MARCH_MAX_WAVELENGTHS, _SPECIES).
export const MARCH_MAX = { wavelengths: 32, species: 4 };

// `march`: the manifest's tables.march; `bytes`: march.bin (an ArrayBuffer
// or a view of one). Throws on an array the shader does not bind, a type
// other than the manifest's, or counts above the shader's capacities.
export function marchTextures(march, bytes) {
  const view = ArrayBuffer.isView(bytes) ? bytes : new Uint8Array(bytes);
  const copy = (offset, length) => view.buffer.slice(view.byteOffset + offset, view.byteOffset + offset + length);
  const arrays = march.arrays;
  for (const name of Object.keys(arrays)) {
    if (name !== 'log_source' && !MARCH_ARRAYS.includes(name)) throw new Error(`march.bin's array ${name} is not bound`);
  }
  if (march.wavelengths > MARCH_MAX.wavelengths || march.species > MARCH_MAX.species) {
    throw new Error(`march.bin: ${march.wavelengths} wavelengths, ${march.species} species (the shader holds ${MARCH_MAX.wavelengths} and ${MARCH_MAX.species})`);
  }
  const offsets = [];
  const lengths = [];
  let total = 0;
  for (const name of MARCH_ARRAYS) {
    offsets.push(total);
    lengths.push(arrays[name].length);
    total += arrays[name].length;
  }
  const rows = Math.ceil(total / MARCH_WIDTH);
  const tables = new Float32Array(rows * MARCH_WIDTH);
  for (const [n, name] of MARCH_ARRAYS.entries()) {
    const a = arrays[name];
    if (a.type !== 'f32') throw new Error(`march.bin's ${name} is ${a.type}, not f32`);
    tables.set(new Float32Array(copy(a.offset_bytes, 4 * a.length)), offsets[n]);
  }
  const source = arrays.log_source;
  if (source.type !== 'f16') throw new Error(`march.bin's log_source is ${source.type}, not f16`);
  const channels = arrays.source_wavelength_indices.length;
  const texels = Math.ceil(channels / 4);
  const nodes = source.length / channels;
  const half = new Uint16Array(copy(source.offset_bytes, 2 * source.length));
  const padded = new Uint16Array(nodes * texels * 4);
  for (let node = 0; node < nodes; node++) {
    padded.set(half.subarray(node * channels, (node + 1) * channels), node * texels * 4);
  }
  return {
    offsets,
    lengths,
    tables,
    tablesHeight: rows,
    source: padded,
    // width: view zeniths x texels, height: sun nodes x azimuths, depth: levels.
    sourceSize: [march.view_zenith_nodes * texels, march.sun_nodes * march.azimuth_nodes, arrays.source_levels_m.length],
  };
}

// Sets sora_sky.glsl's uMarch* uniforms of the bound program `program`
// from the manifest's tables.march and marchTextures' `textures`.
export function setMarchUniforms(gl, program, m, textures) {
  const u = (name) => gl.getUniformLocation(program, name);
  gl.uniform1iv(u('uMarchOffsets'), textures.offsets);
  gl.uniform1iv(u('uMarchLengths'), textures.lengths);
  gl.uniform4i(u('uMarchCounts'), m.wavelengths, m.species, m.sun_nodes, m.density_nodes);
  gl.uniform2i(u('uMarchSourceNodes'), m.azimuth_nodes, m.view_zenith_nodes);
  gl.uniform2i(u('uMarchColumnNodes'), m.sun_column_nodes[0], m.sun_column_nodes[1]);
  gl.uniform2i(u('uMarchPhaseNodes'), m.phase_nodes, m.kernel_angles);
  gl.uniform2f(u('uMarchKernel'), m.kernel_blend_start_rad, m.kernel_radius_rad);
  gl.uniform2f(u('uMarchBeamAxis'), m.beam_first_elevation_deg ?? 0, m.beam_step_deg ?? 0);
  gl.uniform1i(u('uMarchBeamElevations'), m.beam_elevations ?? 0);
  gl.uniform3fv(u('uMarchBeamRange'), m.beam_range_deg ?? [0, 0, 0]);
  gl.uniform1i(u('uMarchPeaks'), m.has_forward_peaks ? 1 : 0);
  gl.uniform1f(u('uMarchDarkLogSource'), m.dark_log_source);
  gl.uniform2i(u('uMarchSteps'), m.march_steps[0], m.march_steps[1]);
}
