// SLIC timings of the wasm build in Node (`computeSuperpixels`, single thread, N = 1500,
// compactness 10) on the frame1.png of each case folder given, e.g. the scenes written by
// `soup synth DIR --size 1024x436` (the frames the native `cargo bench --bench superpixels`
// renders). Prints a Markdown table like benches/common, then the superpixel count of each
// frame and an FNV-1a hash of its labels, to compare with the native build
// (`soup superpixels FRAME --out labels.png`).
//
// Usage: scripts/build-web.sh && node benches/wasm-superpixels.mjs CASE_DIR... [--runs 5]
import { basename, join } from 'node:path';
import { parseArgs } from 'node:util';
import { wasm, readPng, timeMs, printHeader, printRow } from './common/wasm.mjs';

const { values, positionals } = parseArgs({
  options: { runs: { type: 'string', default: '5' }, n: { type: 'string', default: '1500' } },
  allowPositionals: true,
});
if (!positionals.length) {
  console.error('usage: node benches/wasm-superpixels.mjs CASE_DIR... [--runs 5] [--n 1500]');
  process.exit(2);
}
const [runs, n] = [Number(values.runs), Number(values.n)];

/** FNV-1a over the bytes of a typed array. */
function fnv1a(array) {
  const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
  let hash = 0x811c9dc5;
  for (const byte of bytes) hash = Math.imul(hash ^ byte, 0x01000193) >>> 0;
  return hash.toString(16).padStart(8, '0');
}

const results = [];
printHeader(`Superpixels (SLIC, N = ${n}, compactness 10), single thread, wasm in Node ${process.version}`);
for (const dir of positionals) {
  const frame = readPng(join(dir, 'frame1.png'));
  const run = () => wasm.computeSuperpixels(frame.rgba, frame.width, frame.height, n, 10);
  printRow(`SLIC N=${n} (${basename(dir)}, wasm)`, `${frame.width}×${frame.height}`, timeMs(runs, () => run().free()));
  const result = run();
  const sizes = result.sizes;
  results.push([basename(dir), result.count, Math.min(...sizes), fnv1a(result.labels)]);
  result.free();
}
console.log('\n| image | superpixels | smallest (px) | labels FNV-1a |');
console.log('| --- | --- | --- | --- |');
for (const [name, count, smallest, hash] of results) {
  console.log(`| ${name} | ${count} | ${smallest} | ${hash} |`);
}
