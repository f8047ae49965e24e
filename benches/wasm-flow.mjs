// Optical flow timings of the wasm build in Node: forward + backward flow with the
// forward–backward check per preset, single thread, on one case folder's frame1.png and
// frame2.png (e.g. the street scene written by `soup synth DIR --scene street`, the frames the
// native `cargo bench --bench flow` renders). Prints a Markdown table like benches/common.
//
// Usage: scripts/build-web.sh && node benches/wasm-flow.mjs CASE_DIR [RUNS] [PRESET...]
import { join } from 'node:path';
import { wasm, readPng, timeMs, printHeader, printRow } from './common/wasm.mjs';

const [caseDir, runsArg, ...presetArgs] = process.argv.slice(2);
if (!caseDir) {
  console.error('usage: node benches/wasm-flow.mjs CASE_DIR [RUNS] [PRESET...]');
  process.exit(2);
}
const runs = Number(runsArg ?? 5);
const presets = presetArgs.length ? presetArgs : ['fast', 'medium', 'fine', 'high'];
const frame1 = readPng(join(caseDir, 'frame1.png'));
const frame2 = readPng(join(caseDir, 'frame2.png'));
const size = `${frame1.width}×${frame1.height}`;

printHeader(`Optical flow (DIS + variational refinement), forward + backward, single thread, wasm in Node ${process.version}`);
for (const preset of presets) {
  const times = timeMs(runs, () =>
    wasm.computeFlow(frame1.rgba, frame2.rgba, frame1.width, frame1.height, preset).free(),
  );
  printRow(`flow, preset ${preset} (wasm)`, size, times);
}
