// The page end to end in headless Chromium: two photos picked through the file input until the
// result is shown (decode, worker, pipeline in wasm, pictures, 3D view), with default
// parameters, the time of each pipeline stage in the worker, and the peak memory of the tab;
// plus how fast the page and its worker load.
//
//   node benches/page.mjs [--runs 3] [--no-loading] [--scene street] [--pair DIR] [--worker scalar]
//
// Needs the release wasm in www/pkg (scripts/build-web.sh); builds the `soup` CLI (release) to
// render the inputs with `soup synth`:
// - 1024×436: the street scene as PNGs (the paper's Sintel size; nothing is downscaled);
// - 4032×3024: the street rendered at 1008×756 and upscaled 4× in the browser to JPEGs
//   (quality 0.92), like a phone's 12-megapixel photos; the page decodes them to the working
//   size (long side 1024);
// - 6000×4000 (24 megapixels): the street rendered at 1500×1000, upscaled 4× the same way.
// `--no-loading` skips the page-load rows (the memory and end-to-end rows only). `--scene` renders
// another synthetic scene instead of the street (`soup synth --help` lists them; the crowd, whose
// first pass with the page's flow pins too few scales, shows what a second pass costs).
// `--pair DIR` benches DIR's frame1.png and frame2.png instead of the synthetic inputs (a pair
// of any size, for example one of ../shared/eval's, as a person would pick them). `--worker scalar`
// (or `full`) runs the end-to-end rows with the page's `?worker=scalar`: the lean build without
// wasm SIMD (www/worker.js), to compare with the default.
// Each run uses a fresh browser. The photos are picked as files on disk, as a person picks them
// (Playwright given buffers instead passes them through the page's JavaScript heap as base64:
// about 100 MiB of garbage in the renderer for the 24 MP pair). Times are the minimum over runs;
// memory is the largest peak resident size of the renderer process, the tab with its workers
// (the GPU process, which rasterises with SwiftShader here, is apart), over runs: the larger of
// its VmHWM at the end and its VmRSS sampled every 20 ms during the run (VmHWM alone missed a
// 200 MiB spike of the browser's photo decoding).
// Loading: a fresh browser (empty cache) opens the page on localhost and on an emulated
// 10 Mbit/s line, with the worker on the lean module (the default) and on the full one
// (`?worker=full`); "ready" is the page usable (the worker's module loaded), "viewer" the 3D view
// created (the full module, loaded after the worker's); a cancel's worker restart is timed too.

import { spawnSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { gzipSync } from 'node:zlib';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { parseArgs } from 'node:util';
import { ROOT, launchBrowser, startServer } from '../tests/e2e/browser.mjs';

const { values } = parseArgs({
  options: {
    runs: { type: 'string', default: '3' },
    'no-loading': { type: 'boolean', default: false },
    worker: { type: 'string', default: '' },
    scene: { type: 'string', default: 'street' },
    pair: { type: 'string' },
  },
});
const runs = Number(values.runs);
if (!['', 'lean', 'scalar', 'full'].includes(values.worker)) {
  console.error(`--worker ${values.worker}: expected lean, scalar or full`);
  process.exit(2);
}
const scene = values.scene;

const work = mkdtempSync(path.join(tmpdir(), 'soup-page-bench-'));
const soup = (...args) => {
  const done = spawnSync('cargo', ['run', '--quiet', '--release', '--bin', 'soup', '--', ...args], {
    cwd: ROOT,
    stdio: ['ignore', 'ignore', 'inherit'],
  });
  if (done.status !== 0) {
    throw new Error(`soup ${args.join(' ')} failed`);
  }
};
const pair = values.pair;
if (pair === undefined) {
  soup('synth', path.join(work, 'small'), '--scene', scene, '--size', '1024x436');
  soup('synth', path.join(work, 'photo'), '--scene', scene, '--size', '1008x756');
  soup('synth', path.join(work, 'photo24'), '--scene', scene, '--size', '1500x1000');
}
const png = (dir, name) => readFileSync(path.join(work, dir, scene, name));

const server = await startServer();

/** The process ids of the browser's renderer processes. */
async function rendererPids(browser) {
  const cdp = await browser.newBrowserCDPSession();
  const { processInfo } = await cdp.send('SystemInfo.getProcessInfo');
  await cdp.detach();
  return processInfo.filter((p) => p.type === 'renderer').map((p) => p.id);
}

/** The largest `key` (VmHWM, VmRSS) of processes `pids`, in MiB. */
function largest(pids, key) {
  const kib = (pid) => {
    const status = readFileSync(`/proc/${pid}/status`, 'utf8');
    return Number(status.match(new RegExp(`^${key}:\\s+(\\d+) kB`, 'm'))[1]);
  };
  return Math.max(...pids.map(kib)) / 1024;
}

/** JPEGs of `pngs` scaled to `width × height` in the page (browser image scaling). */
async function upscaleToJpeg(page, pngs, width, height) {
  const out = [];
  for (const buffer of pngs) {
    const base64 = await page.evaluate(
      async ({ data, width, height }) => {
        const bytes = Uint8Array.from(atob(data), (c) => c.charCodeAt(0));
        const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
        const canvas = new OffscreenCanvas(width, height);
        const ctx = canvas.getContext('2d');
        ctx.imageSmoothingQuality = 'high';
        ctx.drawImage(bitmap, 0, 0, width, height);
        const blob = await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 });
        const jpeg = new Uint8Array(await blob.arrayBuffer());
        let text = '';
        for (let i = 0; i < jpeg.length; i += 0x8000) {
          text += String.fromCharCode(...jpeg.subarray(i, i + 0x8000));
        }
        return btoa(text);
      },
      { data: buffer.toString('base64'), width, height },
    );
    out.push(Buffer.from(base64, 'base64'));
  }
  return out;
}

/**
 * One end-to-end run of `files` (paths) in a fresh browser: { ms, stages, wasmMemory, memory,
 * workingSize }.
 */
async function endToEnd(files) {
  const browser = await launchBrowser();
  let sampling = true;
  let sampler = Promise.resolve();
  try {
    const page = await browser.newPage({ viewport: { width: 1100, height: 900 } });
    await page.goto(values.worker === '' ? server.url : `${server.url}?worker=${values.worker}`);
    await page.waitForFunction(() => document.body.dataset.state === 'idle', null, { timeout: 120_000 });
    await page.evaluate(() => window.soupPage.viewerReady);
    const pids = await rendererPids(browser);
    let sampled = 0;
    sampler = (async () => {
      while (sampling) {
        sampled = Math.max(sampled, largest(pids, 'VmRSS'));
        await new Promise((resolve) => setTimeout(resolve, 20));
      }
    })();
    await page.setInputFiles('#file-input', files);
    await page.waitForFunction(() => ['done', 'error'].includes(document.body.dataset.state), null, {
      timeout: 600_000,
    });
    if ((await page.evaluate(() => document.body.dataset.state)) !== 'done') {
      throw new Error(await page.textContent('[role="alert"]'));
    }
    const run = await page.evaluate(() => window.soupPage.lastRun);
    // The report comes from the result computed again in the background (www/pipeline.js): the
    // memory is read once that is done too.
    const report = JSON.parse(await page.evaluate(async () => {
      const { bytes } = await window.soupPage.pipeline.request('export', { name: 'report.json' });
      return new TextDecoder().decode(bytes);
    }));
    sampling = false;
    await sampler;
    return {
      ms: run.endToEndMs,
      stages: Object.values(run.stagesMs).reduce((a, b) => a + b, 0),
      stagesMs: run.stagesMs,
      wasmMemory: run.memoryBytes / 2 ** 20,
      memory: Math.max(largest(pids, 'VmHWM'), sampled),
      workingSize: report.working_size.join('×'),
      build: await page.evaluate(() => document.body.dataset.workerBuild),
    };
  } finally {
    sampling = false;
    await sampler.catch(() => {});
    await browser.close();
  }
}

/** A network for the loading rows: `null` is localhost as it is. */
const NETWORKS = [
  ['localhost', null],
  ['10 Mbit/s, 40 ms RTT', { offline: false, latency: 40, downloadThroughput: 10e6 / 8, uploadThroughput: 5e6 / 8 }],
];

/**
 * Page load in a fresh context (empty cache) on `network`, the worker with its `module` build:
 * milliseconds to ready (usable: the worker's module loaded) and to the viewer; the worker's
 * start, and its restart after a cancel (module cached).
 */
async function loading(module, network) {
  const browser = await launchBrowser();
  try {
    const context = await browser.newContext();
    const page = await context.newPage();
    if (network !== null) {
      const cdp = await context.newCDPSession(page);
      await cdp.send('Network.enable');
      await cdp.send('Network.emulateNetworkConditions', network);
    }
    await page.goto(`${server.url}?worker=${module}`);
    await page.waitForFunction(() => document.body.dataset.state === 'idle', null, { timeout: 120_000 });
    await page.evaluate(() => window.soupPage.viewerReady);
    const marks = await page.evaluate(() => ({
      ready: window.soupPage.readyMs,
      viewer: window.soupPage.viewerReadyMs,
      worker: window.soupPage.workerStartMs[0],
    }));
    marks.restart = await page.evaluate(async () => {
      const started = performance.now();
      window.soupPage.pipeline.restart();
      await window.soupPage.pipeline.ready;
      return performance.now() - started;
    });
    return marks;
  } finally {
    await browser.close();
  }
}

const min = (xs) => Math.min(...xs);
const max = (xs) => Math.max(...xs);
const rows = [];
const stageRows = [];
try {
  const cases = [];
  if (pair !== undefined) {
    cases.push([`PNG pair ${path.basename(pair)}`, ['frame1.png', 'frame2.png'].map((name) => path.join(pair, name))]);
  } else {
    cases.push([`1024×436 PNG pair (${scene})`, ['frame1.png', 'frame2.png'].map((name) => path.join(work, 'small', scene, name))]);
    const browser = await launchBrowser();
    const page = await browser.newPage();
    await page.goto(`${server.url}www/favicon.svg`);
    for (const [dir, width, height, label] of [['photo', 4032, 3024, '12 MP'], ['photo24', 6000, 4000, '24 MP']]) {
      const jpegs = await upscaleToJpeg(page, [png(dir, 'frame1.png'), png(dir, 'frame2.png')], width, height);
      mkdirSync(path.join(work, `${dir}-jpeg`));
      const files = jpegs.map((buffer, i) => {
        const file = path.join(work, `${dir}-jpeg`, `photo${i + 1}.jpg`);
        writeFileSync(file, buffer);
        return file;
      });
      cases.push([
        `${width}×${height} JPEG pair (${label}, ${scene} upscaled; ${(jpegs[0].length / 2 ** 20).toFixed(1)} MB each)`,
        files,
      ]);
    }
    await browser.close();
  }
  let lastBuild = '';
  for (const [name, files] of cases) {
    const results = [];
    for (let run = 0; run < runs; run++) {
      results.push(await endToEnd(files));
    }
    lastBuild = results[0].build;
    const stageNames = Object.keys(results[0].stagesMs);
    stageRows.push(
      `| ${name} | ` + stageNames.map((s) => `${s} ${min(results.map((r) => r.stagesMs[s])).toFixed(0)}`).join(' · ') + ' |',
    );
    rows.push(
      `| ${name} | ${results[0].workingSize} | ${(min(results.map((r) => r.ms)) / 1000).toFixed(2)} s | ` +
        `${(min(results.map((r) => r.stages)) / 1000).toFixed(2)} s | ` +
        `${max(results.map((r) => r.memory)).toFixed(0)} MiB | ${max(results.map((r) => r.wasmMemory)).toFixed(0)} MiB |`,
    );
  }
  const size = (name) => {
    const file = path.join(ROOT, 'www/pkg', `${name}_bg.wasm`);
    const gz = gzipSync(readFileSync(file), { level: 6 }).length;
    return `${(statSync(file).size / 1024).toFixed(0)} KiB, ${(gz / 1024).toFixed(0)} KiB gzipped`;
  };
  const loadRows = [];
  for (const [label, network] of values['no-loading'] ? [] : NETWORKS) {
    for (const [module, name] of [['lean', 'soup_worker_simd'], ['full', 'superpixel_soup']]) {
      const loads = [];
      for (let run = 0; run < runs; run++) {
        loads.push(await loading(module, network));
      }
      const ms = (key) => `${min(loads.map((l) => l[key])).toFixed(0)} ms`;
      loadRows.push(`| ${label} | ${module} (${size(name)}) | ${ms('ready')} | ${ms('viewer')} | ${ms('worker')} | ${ms('restart')} |`);
    }
  }
  console.log(`\nThe page end to end in headless Chromium, default parameters, minimum of ${runs} runs (fresh browser each; the worker's wasm build: ${lastBuild})\n`);
  console.log('| input | working size | end to end (pick → result shown) | pipeline stages in wasm | peak tab memory (renderer, VmHWM or sampled VmRSS) | worker wasm memory |');
  console.log('| --- | --- | --- | --- | --- | --- |');
  console.log(rows.join('\n'));
  console.log(`\nThe pipeline's stages in the worker (ms, minimum of ${runs} runs each)\n`);
  console.log('| input | stages |');
  console.log('| --- | --- |');
  console.log(stageRows.join('\n'));
  if (loadRows.length > 0) {
    console.log(`\nFirst load (empty cache, gzip from scripts/serve.py), minimum of ${runs}\n`);
    console.log('| network | worker module | page ready (worker loaded) | 3D viewer ready | worker start | worker restart (cancel) |');
    console.log('| --- | --- | --- | --- | --- | --- |');
    console.log(loadRows.join('\n'));
  }
} finally {
  await server.close();
  rmSync(work, { recursive: true, force: true });
}
