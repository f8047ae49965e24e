// End-to-end tests of the page (index.html), served by scripts/serve.py and driven in headless
// Chromium: the sample pair through the file input (WebGPU) with every download parsed, the
// sample button on a phone-sized touch screen (WebGL2), cancel, a video, EXIF intrinsics and
// the parameters panel. Bad inputs are in page-errors.test.mjs.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { ROOT, browserSession } from './browser.mjs';
import {
  SAMPLE,
  SAMPLE_SIZE,
  alertText,
  analyseView,
  convertImage,
  difference,
  download,
  openPage,
  readFloHeader,
  readPlyHeader,
  readPngHeader,
  waitForRunEnd,
  waitForState,
  withExifFocal,
} from './page-helpers.mjs';

const cargoVersion = readFileSync(path.join(ROOT, 'Cargo.toml'), 'utf8').match(
  /^version\s*=\s*"([^"]+)"/m,
)[1];

const session = browserSession();

test('the sample through the file input, drawn with WebGPU, with every download', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url, '?backend=webgpu');
  assert.equal(await page.title(), 'Superpixel Soup');
  assert.equal(await page.textContent('#version'), cargoVersion);
  assert.equal(await page.evaluate(() => globalThis.crossOriginIsolated), true);

  await page.setInputFiles('#file-input', SAMPLE);
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.equal(await alertText(page), null);
  assert.equal(await page.evaluate(() => document.body.dataset.backend), 'webgpu');
  assert.match(await page.textContent('#backend-name'), /WebGPU/);

  // Frames, intrinsics (no EXIF in the PNGs: the default guess) and the report.
  assert.match(await page.textContent('#thumb1-info'), /frame1\.png · 768 × 328/);
  assert.match(await page.textContent('#intrinsics-source'), /default guess/);
  assert.equal(await page.inputValue('#params [name="fx"]'), '768');
  const count = await page.evaluate(() => window.soupPage.points);
  assert.ok(count > 0.8 * SAMPLE_SIZE[0] * SAMPLE_SIZE[1], `${count} points`);
  const summary = await page.textContent('#summary');
  assert.match(summary, /Working size768 × 328/);
  assert.match(summary, /default guess/);
  // Every stage has a time, and the timings table adds them up.
  const stages = await page.$$eval('#stages li', (items) => items.map((li) => [li.dataset.stage, li.className, li.querySelector('.time').textContent]));
  assert.deepEqual(stages.map((s) => s[0]), ['flow', 'superpixels', 'motion', 'scales', 'refine', 'outputs', 'ensemble']);
  for (const [stage, state, time] of stages) {
    assert.equal(state, 'done', stage);
    assert.match(time, /^\d+ ms$/, stage);
  }
  assert.match(await page.textContent('#timings'), /Total\d+ ms/);

  // The 3D view shows the cloud; frame 2 differs from frame 1 (the camera drove forward).
  const frame1 = await analyseView(page);
  assert.ok(frame1.drawn > 0.2, `only ${frame1.drawn} of the view is drawn`);
  await page.check('input[name="frame"][value="2"]');
  const frame2 = await analyseView(page);
  assert.ok(difference(frame1, frame2) > 0.05, 'frame 2 looks like frame 1');
  // The soup of each stage is another cloud: unit scales, and scales before the refinement.
  for (const stage of ['unorganised', 'scaled']) {
    await page.selectOption('#soup-mode', stage);
    await page.waitForFunction(() => window.soupPage.viewer.pointCount > 0);
    const view = await analyseView(page);
    assert.ok(view.drawn > 0.1, `${stage}: only ${view.drawn} of the view is drawn`);
  }
  await page.selectOption('#soup-mode', 'organised');

  // Guessed pieces (report confidence below min_confidence): hidden, the drawn points drop
  // by exactly the points of those superpixels (counted in the worker's cloud), in both soups;
  // marked, every point is drawn again.
  const unknownPoints = (soup) => page.evaluate(async (soup) => {
    const { bytes } = await window.soupPage.pipeline.request('export', { name: 'report.json' });
    const { confidence, params } = JSON.parse(new TextDecoder().decode(bytes));
    const { cloud } = await window.soupPage.pipeline.request('cloud', { soup });
    return cloud.labels.filter((label) => confidence[label] < params.scales.min_confidence).length;
  }, soup);
  const hiddenIs = (n) => page.waitForFunction(
    (n) => window.soupPage.viewer.pointCount - window.soupPage.viewer.shownPointCount === n, n, { timeout: 60_000 });
  const unknownOrganised = await unknownPoints('organised');
  assert.ok(unknownOrganised > 0, 'the sample has superpixels of unknown scale');
  await page.selectOption('#unknown-scale', 'hide');
  await hiddenIs(unknownOrganised);
  await page.selectOption('#soup-mode', 'unorganised');
  await hiddenIs(await unknownPoints('unorganised'));
  await page.selectOption('#soup-mode', 'organised');
  await hiddenIs(unknownOrganised);
  await page.selectOption('#unknown-scale', 'mark');
  await hiddenIs(0);
  await page.selectOption('#unknown-scale', 'show');

  // Stage pictures at the working size, not blank.
  for (const id of ['picture-depth', 'picture-superpixels', 'picture-flow', 'picture-confidence', 'picture-unorganised', 'picture-organised']) {
    const { width, height, colours } = await page.$eval(`#${id}`, (canvas) => {
      const { data } = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height);
      const seen = new Set();
      for (let i = 0; i < data.length; i += 4 * 97) {
        seen.add((data[i] << 16) | (data[i + 1] << 8) | data[i + 2]);
      }
      return { width: canvas.width, height: canvas.height, colours: seen.size };
    });
    assert.deepEqual([width, height], SAMPLE_SIZE, id);
    assert.ok(colours > 20, `${id} has only ${colours} colours`);
  }
  assert.match(await page.textContent('#legend-near'), /^near \d/);

  // Downloads.
  for (const file of ['frame1.ply', 'frame2.ply']) {
    const ply = readPlyHeader(await download(page, file));
    assert.equal(ply.header[0], 'ply');
    assert.equal(ply.header[1], 'format binary_little_endian 1.0');
    assert.equal(ply.vertices, count, file);
    assert.ok(ply.header.includes('property float confidence'), file);
    assert.equal(ply.bodyLength, count * 19, file); // 3 floats + 3 bytes + 1 float per vertex
  }
  const depth = await download(page, 'depth16.png');
  assert.deepEqual(readPngHeader(depth), { width: 768, height: 328, bitDepth: 16, colourType: 0 });
  assert.ok(depth.includes('depth_scale'), 'the depth PNG carries its scale');
  const flo = await download(page, 'flow.flo');
  assert.deepEqual(readFloHeader(flo), { tag: 202021.25, width: 768, height: 328 });
  assert.equal(flo.length, 12 + 8 * 768 * 328);
  const report = JSON.parse((await download(page, 'report.json')).toString('utf8'));
  assert.equal(report.camera.source, 'default');
  assert.deepEqual(report.input_size, SAMPLE_SIZE);
  assert.equal(report.timings_ms.length, stages.length);
  const pfm = await download(page, 'depth.pfm');
  assert.equal(pfm.toString('latin1', 0, 3), 'Pf\n');
  const labels = readPngHeader(await download(page, 'labels.png'));
  assert.deepEqual([labels.width, labels.height, labels.bitDepth], [768, 328, 16]);

  // Swapping makes frame 2 the reference and runs again.
  await page.click('#swap-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.match(await page.textContent('#thumb1-info'), /frame2\.png/);
  assert.deepEqual(errors, []);
  await page.context().close();
});

test('the sample button on a phone-sized touch screen, drawn with WebGL2', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url, '?backend=webgl2', {
    viewport: { width: 390, height: 844 },
    deviceScaleFactor: 2,
    isMobile: true,
    hasTouch: true,
  });
  // Nothing wider than the screen.
  const overflow = () => page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  assert.ok((await overflow()) <= 0, `the page is ${await overflow()} px too wide`);
  await page.tap('#sample-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.equal(await page.evaluate(() => document.body.dataset.backend), 'webgl2');
  assert.ok((await overflow()) <= 0, `the result is ${await overflow()} px too wide`);
  // The sample's exact intrinsics are filled in and used.
  assert.match(await page.textContent('#intrinsics-source'), /sample/);
  assert.equal(await page.inputValue('#params [name="fx"]'), '614.4');
  const before = await analyseView(page);
  assert.ok(before.drawn > 0.2, `only ${before.drawn} of the view is drawn`);

  // A one-finger drag on the view orbits the camera.
  await page.locator('#view').scrollIntoViewIfNeeded();
  const box = await page.locator('#view').boundingBox();
  const client = await page.context().newCDPSession(page);
  const touch = (type, x) =>
    client.send('Input.dispatchTouchEvent', {
      type,
      touchPoints: type === 'touchEnd' ? [] : [{ x: box.x + x, y: box.y + box.height / 2 }],
    });
  await touch('touchStart', box.width * 0.3);
  for (let step = 1; step <= 8; step++) {
    await touch('touchMove', box.width * (0.3 + 0.05 * step));
  }
  await touch('touchEnd');
  const after = await analyseView(page);
  assert.ok(difference(before, after) > 0.05, 'the drag did not move the view');
  assert.deepEqual(errors, []);
  await page.context().close();
});

test('cancel stops a run at once and the next run works', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  await page.click('#sample-button');
  // The main thread shows the worker's progress while it computes: the page is responsive.
  await page.waitForFunction(() => document.querySelector('#stages li.active')?.dataset.stage === 'motion', null, { timeout: 60_000 });
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'running');
  await page.click('#cancel-button');
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'idle');
  assert.equal(await page.textContent('#status'), 'Cancelled.');
  assert.equal(await page.isHidden('#results'), true);
  assert.equal(await alertText(page), null);
  // The worker was replaced; the same frames run again.
  await page.click('#run-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  // Started: at load, after the cancel, and after the run handed over its result (the worker
  // that ran is replaced to free its memory; www/pipeline.js).
  await page.evaluate(() => window.soupPage.pipeline.ready);
  assert.equal(await page.evaluate(() => window.soupPage.workerStartMs.length), 3);
  assert.deepEqual(errors, []);
  await page.context().close();
});

test('the fusion\'s members made in helper workers, and the build without SIMD, give the result of the worker alone', async () => {
  // www/worker.js makes the members in helper workers (one per core, up to four workers in
  // all), and the first helper computes the first flow's backward direction meanwhile (given
  // back to the run that computes the result again for the downloads); `?threads=1` makes
  // everything in the pipeline's worker. It loads the lean build with
  // wasm SIMD where the browser has it (Chromium does), and `?worker=scalar` the one without.
  // The files are the same, byte for byte.
  const runWith = async (query) => {
    const { page, errors } = await openPage(session.browser, session.server.url, query);
    await page.setInputFiles('#file-input', SAMPLE);
    assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
    const { helpers, flowsApart } = await page.evaluate(() => window.soupPage.lastRun.worker);
    const cores = await page.evaluate(() => navigator.hardwareConcurrency);
    const build = await page.evaluate(() => document.body.dataset.workerBuild);
    const depth = await download(page, 'depth.pfm');
    const report = JSON.parse((await download(page, 'report.json')).toString('utf8'));
    assert.deepEqual(errors, []);
    await page.context().close();
    return { helpers, flowsApart, cores, build, depth, report };
  };
  const alone = await runWith('?threads=1');
  const helped = await runWith('?threads=2');
  const scalar = await runWith('?threads=2&worker=scalar');
  assert.equal(alone.helpers, 0);
  assert.equal(helped.helpers, helped.cores >= 2 ? 1 : 0);
  assert.equal(scalar.helpers, helped.helpers);
  assert.deepEqual([alone.flowsApart, helped.flowsApart > 0], [0, helped.helpers > 0]);
  assert.deepEqual([alone.build, helped.build, scalar.build], ['soup_worker_simd', 'soup_worker_simd', 'soup_worker']);
  for (const other of [helped, scalar]) {
    assert.ok(alone.depth.equals(other.depth), `the depth of ${other.build} with ${other.helpers} helpers differs`);
    for (const key of ['ensemble', 'confidence', 'unconfident', 'refine']) {
      assert.deepEqual(other.report[key], alone.report[key], key);
    }
  }
  assert.equal(alone.report.ensemble.counts.length, 4);
  assert.deepEqual(alone.report.ensemble.failed, []);
});

test('two frames picked from a video', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  // A WebM recorded in the page: the sample's frame 1 until the recorder has delivered data,
  // then its frame 2 for a second.
  const video = await page.evaluate(async () => {
    const load = async (name) => createImageBitmap(await (await fetch(`www/sample/${name}`)).blob());
    const [one, two] = await Promise.all([load('frame1.png'), load('frame2.png')]);
    const canvas = document.createElement('canvas');
    [canvas.width, canvas.height] = [one.width, one.height];
    const ctx = canvas.getContext('2d');
    const recorder = new MediaRecorder(canvas.captureStream(30), {
      mimeType: 'video/webm;codecs=vp8',
      videoBitsPerSecond: 8_000_000,
    });
    const chunks = [];
    let recording = null;
    recorder.ondataavailable = (e) => {
      chunks.push(e.data);
      recording ??= performance.now();
    };
    const stopped = new Promise((resolve) => (recorder.onstop = resolve));
    recorder.start(100);
    await new Promise((resolve) => {
      const draw = () => {
        const shown = recording === null ? 0 : performance.now() - recording;
        ctx.drawImage(shown < 500 ? one : two, 0, 0);
        if (shown < 1500) {
          requestAnimationFrame(draw);
        } else {
          resolve();
        }
      };
      draw();
    });
    recorder.stop();
    await stopped;
    const bytes = new Uint8Array(await new Blob(chunks).arrayBuffer());
    let text = '';
    for (let i = 0; i < bytes.length; i += 0x8000) {
      text += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
    }
    return btoa(text);
  });
  await page.setInputFiles('#file-input', {
    name: 'street.webm',
    mimeType: 'video/webm',
    buffer: Buffer.from(video, 'base64'),
  });
  await page.locator('#video-panel').waitFor({ state: 'visible' });
  assert.equal(await waitForState(page, ['idle', 'error']), 'idle', await alertText(page));
  assert.match(await page.textContent('#status'), /Pick two frames/);
  assert.match(await page.textContent('#thumb1-info'), /street\.webm at 0\.00 s · 768 × 328/);
  // Scrub to the end (the sample's frame 2) and take it as frame 2.
  const end = await page.$eval('#video-scrubber', (input) => {
    input.value = input.max;
    input.dispatchEvent(new Event('input'));
    return Number(input.max);
  });
  assert.ok(end > 0.5, `the video lasts ${end} s`);
  await page.click('#take-frame2');
  await page.waitForFunction((t) => document.querySelector('#thumb2-info').textContent.includes(`at ${t} s`), end.toFixed(2));
  await page.click('#run-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.ok((await page.evaluate(() => window.soupPage.points)) > 100_000);
  assert.deepEqual(errors, []);
  await page.context().close();
});

test('EXIF focal length fills the intrinsics; parameters reach the pipeline', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  const [one, two] = await Promise.all(SAMPLE.map((f) => convertImage(page, f.buffer, { type: 'image/jpeg', quality: 0.95 })));
  // A smaller working size and fewer superpixels, through the form.
  await page.click('#params-details summary');
  await page.fill('#params [name="maxSide"]', '384');
  await page.fill('#params [name="count"]', '400');
  await page.setInputFiles('#file-input', [
    { name: 'one.jpg', mimeType: 'image/jpeg', buffer: withExifFocal(one, 26) },
    { name: 'two.jpg', mimeType: 'image/jpeg', buffer: two },
  ]);
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  assert.match(await page.textContent('#intrinsics-source'), /EXIF of frame 1 \(26 mm/);
  // fx = f35 · long side / 36 at the photo's size.
  assert.equal(await page.inputValue('#params [name="fx"]'), String(Math.round((26 * 768 / 36) * 1000) / 1000));
  const report = JSON.parse((await download(page, 'report.json')).toString('utf8'));
  assert.equal(report.camera.source, 'exif');
  assert.deepEqual(report.working_size, [384, 164]);
  assert.ok(Math.abs(report.camera.intrinsics.fx - (26 * 384) / 36) < 1e-6, report.camera.intrinsics.fx);
  assert.equal(report.params.superpixels.count, 400);
  assert.ok(report.notes.some((n) => /downscaled from 768×328 to 384×164/.test(n)), report.notes);
  // Editing an intrinsic makes it the user's, used as given.
  await page.fill('#params [name="fx"]', '500');
  await page.fill('#params [name="fy"]', '500');
  assert.equal(await page.textContent('#intrinsics-source'), 'yours (edited)');
  await page.click('#run-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  const edited = JSON.parse((await download(page, 'report.json')).toString('utf8'));
  assert.equal(edited.camera.source, 'user');
  assert.ok(Math.abs(edited.camera.intrinsics.fx - 250) < 1e-6, edited.camera.intrinsics.fx);
  assert.deepEqual(errors, []);
  await page.context().close();
});
