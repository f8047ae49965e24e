// Optical flow timings of the wasm build in Node: forward + backward flow with the
// forward–backward check per preset, single thread, on one case folder's frame1.png and
// frame2.png (e.g. the street scene written by `soup synth DIR --scene street`, the frames the
// native `cargo bench --bench flow` renders). Prints a Markdown table like benches/common.
//
// Usage: scripts/build-web.sh && node benches/wasm-flow.mjs CASE_DIR [RUNS] [PRESET...]
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { inflateSync } from 'node:zlib';
import { initSync, computeFlow } from '../www/pkg/superpixel_soup.js';

initSync({ module: readFileSync(new URL('../www/pkg/superpixel_soup_bg.wasm', import.meta.url)) });

/** Decodes an 8-bit RGB or RGBA, non-interlaced PNG (what `soup synth` writes) into RGBA bytes. */
function decodePng(bytes) {
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

const [caseDir, runsArg, ...presetArgs] = process.argv.slice(2);
if (!caseDir) {
  console.error('usage: node benches/wasm-flow.mjs CASE_DIR [RUNS] [PRESET...]');
  process.exit(2);
}
const runs = Number(runsArg ?? 5);
const presets = presetArgs.length ? presetArgs : ['fast', 'medium', 'high'];
const frame1 = decodePng(readFileSync(join(caseDir, 'frame1.png')));
const frame2 = decodePng(readFileSync(join(caseDir, 'frame2.png')));
const size = `${frame1.width}×${frame1.height}`;

console.log(`\nOptical flow (DIS + variational refinement), forward + backward, single thread, wasm in Node ${process.version}\n`);
console.log('| what | size | runs | min ms | median ms |');
console.log('| --- | --- | --- | --- | --- |');
for (const preset of presets) {
  const run = () => computeFlow(frame1.rgba, frame2.rgba, frame1.width, frame1.height, preset).free();
  run(); // warm-up
  const times = [];
  for (let i = 0; i < runs; i++) {
    const start = performance.now();
    run();
    times.push(performance.now() - start);
  }
  times.sort((a, b) => a - b);
  const median = times[Math.floor(times.length / 2)];
  console.log(`| flow, preset ${preset} (wasm) | ${size} | ${runs} | ${times[0].toFixed(1)} | ${median.toFixed(1)} |`);
}
