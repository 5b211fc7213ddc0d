// A small OpenEXR reader for the tests: single-part scan-line files with
// HALF or FLOAT channels, uncompressed or ZIP (one or sixteen scan lines a
// block), which is what sora writes (crates/sora/src/output/exr.rs).
// Returns { width, height, channels: { NAME: Float32Array } }, rows top first.

import { inflateSync } from 'node:zlib';

function halfToFloat(h) {
  const s = h & 0x8000 ? -1 : 1;
  const e = (h >> 10) & 0x1f;
  const f = h & 0x3ff;
  if (e === 0) return s * f * 2 ** -24;
  if (e === 31) return f ? NaN : s * Infinity;
  return s * (1 + f / 1024) * 2 ** (e - 15);
}

export function readExr(buffer) {
  const view = new DataView(buffer.buffer, buffer.byteOffset, buffer.byteLength);
  if (view.getUint32(0, true) !== 20000630) throw new Error('not an OpenEXR file');
  let p = 8;
  const cstring = () => {
    const end = buffer.indexOf(0, p);
    const text = buffer.toString('latin1', p, end);
    p = end + 1;
    return text;
  };
  const header = {};
  for (;;) {
    const name = cstring();
    if (name === '') break;
    const type = cstring();
    const size = view.getInt32(p, true);
    p += 4;
    header[name] = { type, start: p, size };
    p += size;
  }
  const channels = [];
  {
    let q = header.channels.start;
    for (;;) {
      const end = buffer.indexOf(0, q);
      const name = buffer.toString('latin1', q, end);
      q = end + 1;
      if (name === '') break;
      channels.push({ name, type: view.getInt32(q, true) });
      q += 16;
    }
  }
  const compression = buffer[header.compression.start];
  const w = header.dataWindow.start;
  const [xMin, yMin, xMax, yMax] = [0, 4, 8, 12].map((o) => view.getInt32(w + o, true));
  const width = xMax - xMin + 1;
  const height = yMax - yMin + 1;
  const linesPerBlock = { 0: 1, 2: 1, 3: 16 }[compression];
  if (linesPerBlock === undefined) throw new Error(`EXR compression ${compression} not supported`);
  const blocks = Math.ceil(height / linesPerBlock);
  const out = Object.fromEntries(channels.map((c) => [c.name, new Float32Array(width * height)]));
  const bytesPerLine = channels.reduce((n, c) => n + width * (c.type === 1 ? 2 : 4), 0);
  for (let b = 0; b < blocks; b++) {
    const offset = Number(view.getBigUint64(p + 8 * b, true));
    const y = view.getInt32(offset, true) - yMin;
    const size = view.getInt32(offset + 4, true);
    const lines = Math.min(linesPerBlock, height - y);
    let data = buffer.subarray(offset + 8, offset + 8 + size);
    if (size < lines * bytesPerLine) {
      // ZIP: zlib, then the predictor, then the two interleaved halves.
      const raw = inflateSync(data);
      for (let i = 1; i < raw.length; i++) raw[i] = (raw[i - 1] + raw[i] - 128) & 0xff;
      const plain = Buffer.alloc(raw.length);
      const half = (raw.length + 1) >> 1;
      for (let i = 0; i < raw.length; i++) plain[i] = i % 2 === 0 ? raw[i >> 1] : raw[half + (i >> 1)];
      data = plain;
    }
    const d = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let q = 0;
    for (let line = 0; line < lines; line++) {
      for (const c of channels) {
        const target = out[c.name];
        const row = (y + line) * width;
        for (let x = 0; x < width; x++) {
          if (c.type === 1) {
            target[row + x] = halfToFloat(d.getUint16(q, true));
            q += 2;
          } else {
            target[row + x] = d.getFloat32(q, true);
            q += 4;
          }
        }
      }
    }
  }
  return { width, height, channels: out };
}
