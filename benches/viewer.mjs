// Frame time of the point-cloud viewer in headless Chromium, both backends, on the synthetic
// scene of viewer.html (858 × 643 canvas, 2-pixel points). Software rendering (SwiftShader)
// makes this a record of this machine, not a target.
//
//   node benches/viewer.mjs [--points 500000] [--runs 3] [--frames 5]
//
// Needs the release wasm in www/pkg (scripts/build-web.sh). Each run loads the page afresh;
// the table reports the minimum over runs of setCloud (decimation, packing, copies; the GPU
// upload happens at the first frame) and of the mean time per frame over back-to-back redraws
// (GPU work included: the run waits for the GPU at the end).

import { parseArgs } from 'node:util';
import { launchBrowser, startServer } from '../tests/e2e/browser.mjs';

const { values } = parseArgs({
  options: {
    points: { type: 'string', default: '500000' },
    runs: { type: 'string', default: '3' },
    frames: { type: 'string', default: '5' },
  },
});
const [points, runs, frames] = [values.points, values.runs, values.frames].map(Number);

const server = await startServer();
const browser = await launchBrowser();
const rows = [];
try {
  for (const backend of ['webgpu', 'webgl2']) {
    const setCloud = [];
    const frame = [];
    let size = '';
    for (let run = 0; run < runs; run++) {
      const page = await browser.newPage({ viewport: { width: 900, height: 800 } });
      await page.goto(`${server.url}viewer.html?backend=${backend}&points=${points}`);
      await page.waitForFunction(() => document.body.dataset.state !== 'loading', null, {
        timeout: 120_000,
      });
      const state = await page.evaluate(() => document.body.dataset.state);
      if (state !== 'ready') {
        throw new Error(`${backend}: ${await page.textContent('[role="alert"]')}`);
      }
      setCloud.push(await page.evaluate(() => window.viewerDemo.setCloudMs));
      frame.push(await page.evaluate((n) => window.viewerDemo.measureFrames(n), frames));
      size = await page.evaluate(() => {
        const c = document.getElementById('view');
        return `${c.width}×${c.height}`;
      });
      await page.close();
    }
    rows.push(
      `| ${backend} | ${points.toLocaleString('en')} | ${size} | ${runs} | ` +
        `${Math.min(...setCloud).toFixed(0)} | ${Math.min(...frame).toFixed(0)} |`,
    );
  }
} finally {
  await browser.close();
  await server.close();
}

console.log('\nViewer in headless Chromium (SwiftShader), synthetic scene, 2-pixel points\n');
console.log('| backend | points | canvas | runs | setCloud min ms | frame min ms |');
console.log('| --- | --- | --- | --- | --- | --- |');
for (const row of rows) {
  console.log(row);
}
