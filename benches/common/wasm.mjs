// Shared helpers of the Node benchmarks of the wasm build (benches/wasm-*.mjs), the JavaScript
// counterpart of benches/common/mod.rs: the release module from www/pkg (scripts/build-web.sh)
// instantiated synchronously, a PNG decoder for the frames `soup synth` writes, and timing that
// prints the same Markdown table rows as the native benchmarks.
import { readFileSync } from 'node:fs';
import { inflateSync } from 'node:zlib';
import * as wasm from '../../www/pkg/superpixel_soup.js';

wasm.initSync({
  module: readFileSync(new URL('../../www/pkg/superpixel_soup_bg.wasm', import.meta.url)),
});

/** The wasm module's exports, instantiated. */
export { wasm };

/** Decodes an 8-bit RGB or RGBA, non-interlaced PNG (what `soup synth` writes) into RGBA bytes. */
export function decodePng(bytes) {
  let offset = 8;
  let width = 0, height = 0, channels = 0;
  const idat = [];
  while (offset < bytes.length) {
    const length = bytes.readUInt32BE(offset);
    const type = bytes.toString('latin1', offset + 4, offset + 8);
    const data = bytes.subarray(offset + 8, offset + 8 + length);
    if (type === 'IHDR') {
      width = data.readUInt32BE(0);
      height = data.readUInt32BE(4);
      const [depth, colour, , , interlace] = data.subarray(8, 13);
      channels = { 2: 3, 6: 4 }[colour];
      if (depth !== 8 || !channels || interlace !== 0) throw new Error('only 8-bit RGB/RGBA PNGs');
    } else if (type === 'IDAT') {
      idat.push(data);
    }
    offset += 12 + length;
  }
  const raw = inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const pixels = new Uint8Array(height * stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let x = 0; x < stride; x++) {
      const a = x >= channels ? pixels[y * stride + x - channels] : 0;
      const b = y > 0 ? pixels[(y - 1) * stride + x] : 0;
      const c = x >= channels && y > 0 ? pixels[(y - 1) * stride + x - channels] : 0;
      const p = a + b - c;
      const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
      const paeth = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      const predictor = [0, a, b, (a + b) >> 1, paeth][filter];
      pixels[y * stride + x] = (line[x] + predictor) & 0xff;
    }
  }
  const rgba = new Uint8Array(width * height * 4);
  for (let i = 0; i < width * height; i++) {
    for (let k = 0; k < 3; k++) rgba[4 * i + k] = pixels[i * channels + k];
    rgba[4 * i + 3] = 255;
  }
  return { width, height, rgba };
}

/** Reads and decodes a PNG file (see decodePng). */
export function readPng(path) {
  return decodePng(readFileSync(path));
}

/** Runs `f` once to warm up, then `runs` times; returns the sorted wall-clock times in ms. */
export function timeMs(runs, f) {
  f();
  const times = [];
  for (let i = 0; i < Math.max(runs, 1); i++) {
    const start = performance.now();
    f();
    times.push(performance.now() - start);
  }
  return times.sort((a, b) => a - b);
}

/** Prints the header of the table that printRow fills. */
export function printHeader(title) {
  console.log(`\n${title}\n`);
  console.log('| what | size | runs | min ms | median ms |');
  console.log('| --- | --- | --- | --- | --- |');
}

/** Prints one table row for sorted `times` (from timeMs). */
export function printRow(what, size, times) {
  const median = times[Math.floor(times.length / 2)];
  console.log(`| ${what} | ${size} | ${times.length} | ${times[0].toFixed(1)} | ${median.toFixed(1)} |`);
}
