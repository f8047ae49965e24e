// End-to-end test of scoring against ground truth in the page: the sample pair (rendered by
// `soup synth`, the generator of www/sample/) with its exact depth as PFM through the picker, as
// Sintel .dpt dropped on the page, and the exact flow as .flo: the MRE shown equals the MRE of
// `soup eval` on the same files (the same Rust metrics on the same reconstruction), the error
// picture is drawn, report.json carries the scores, and a reload scores the same files again. A
// ground truth of another size, a damaged file and a depth PNG without a scale each give a
// message while the result stays.
//
// Runs the `soup` CLI through `cargo run` (the dev profile, optimised, which `cargo test` in
// check.sh has built already).

import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { ROOT, browserSession } from './browser.mjs';
import { alertText, download, openPage, waitForRunEnd, waitForState } from './page-helpers.mjs';
import { makePng } from './png.mjs';

const session = browserSession();
const work = mkdtempSync(path.join(tmpdir(), 'soup-truth-'));
after(() => rmSync(work, { recursive: true, force: true }));

function soup(...args) {
  const done = spawnSync('cargo', ['run', '--quiet', '--bin', 'soup', '--', ...args], {
    cwd: ROOT,
    stdio: ['ignore', 'pipe', 'inherit'],
    encoding: 'utf8',
  });
  assert.equal(done.status, 0, `soup ${args.join(' ')} failed`);
  return done.stdout;
}

/** PFM (Pf, little-endian, rows bottom to top) → { width, height, data (rows top to bottom) }. */
function readPfm(bytes) {
  let offset = 0;
  const tokens = [];
  while (tokens.length < 4) {
    while (/\s/.test(String.fromCharCode(bytes[offset]))) offset++;
    const start = offset;
    while (!/\s/.test(String.fromCharCode(bytes[offset]))) offset++;
    tokens.push(bytes.toString('latin1', start, offset));
  }
  offset += 1;
  const [width, height, scale] = [Number(tokens[1]), Number(tokens[2]), Number(tokens[3])];
  assert.ok(scale < 0, 'little-endian PFM expected');
  const data = new Float32Array(width * height);
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      data[y * width + x] = bytes.readFloatLE(offset + 4 * ((height - 1 - y) * width + x));
    }
  }
  return { width, height, data };
}

/** Sintel .dpt: tag 202021.25, width, height (i32), then the depths row by row from the top. */
function writeDpt({ width, height, data }) {
  const out = Buffer.alloc(12 + 4 * data.length);
  out.writeFloatLE(202021.25, 0);
  out.writeInt32LE(width, 4);
  out.writeInt32LE(height, 8);
  data.forEach((z, i) => out.writeFloatLE(z, 12 + 4 * i));
  return out;
}

/** Drops `files` ([{ name, buffer }]) on the page as a user would (a DataTransfer of Files). */
async function drop(page, files) {
  await page.evaluate((files) => {
    const transfer = new DataTransfer();
    for (const { name, base64 } of files) {
      const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
      transfer.items.add(new File([bytes], name));
    }
    document.body.dispatchEvent(new DragEvent('drop', { dataTransfer: transfer, bubbles: true, cancelable: true }));
  }, files.map(({ name, buffer }) => ({ name, base64: buffer.toString('base64') })));
}

/** Waits for the ground-truth scoring to end; resolves to its state ("scored" or "error"). */
async function scored(page) {
  await page.waitForFunction(() => ['scored', 'error'].includes(document.body.dataset.truth), null, { timeout: 60_000 });
  return page.evaluate(() => document.body.dataset.truth);
}

test('ground truth scored in the page equals soup eval, and bad files are explained', async () => {
  // The sample's case folder: frames, intrinsics, exact depth and flow.
  soup('synth', work, '--scene', 'street', '--size', '768x328');
  const caseDir = path.join(work, 'street');
  for (const name of ['frame1.png', 'frame2.png']) {
    assert.ok(readFileSync(path.join(caseDir, name)).equals(readFileSync(path.join(ROOT, 'www/sample', name))),
      `${name} differs from www/sample/ (run scripts/make-sample.sh)`);
  }
  // Intrinsics as a user types them. (The sample's own, 614.4000000000001, are the same camera;
  // but the reconstruction is sensitive to the last bits of its input, and for those the wasm
  // build's math functions happen to take another branch than native's: a different MRE.)
  const intrinsics = { fx: '614.4', fy: '614.4', cx: '383.5', cy: '163.5' };
  writeFileSync(path.join(caseDir, 'intrinsics.txt'), `${Object.values(intrinsics).join(' ')}\n`);
  // The page's flow preset (`PAGE_FLOW_PRESET` in src/web/reconstruct.rs) is fine, and it
  // refines with 2 iterations of 8 particles (`page_params`); the command line's defaults are
  // high and 6 of 16.
  const pageParams = path.join(work, 'page-params.json');
  writeFileSync(pageParams, JSON.stringify({ refine: { iterations: 2, particles: 8 } }));
  soup('eval', caseDir, '--preset', 'fine', '--params', pageParams, '--json', path.join(work, 'eval.json'));
  const cli = JSON.parse(readFileSync(path.join(work, 'eval.json'), 'utf8'))[0].metrics;
  const pfm = readFileSync(path.join(caseDir, 'depth1.pfm'));
  const dpt = writeDpt(readPfm(pfm));
  const flo = readFileSync(path.join(caseDir, 'flow12.flo'));

  const { page, errors } = await openPage(session.browser, session.server.url);
  const frames = ['frame1.png', 'frame2.png'].map((name) => ({ name, mimeType: 'image/png', buffer: readFileSync(path.join(caseDir, name)) }));
  await page.setInputFiles('#file-input', frames);
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  // The case's intrinsics, as soup eval uses them.
  await page.click('#params-details summary');
  for (const [name, value] of Object.entries(intrinsics)) {
    await page.fill(`#params [name="${name}"]`, value);
  }
  await page.click('#run-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  const used = JSON.parse(await download(page, 'report.json')).camera.intrinsics;
  assert.deepEqual(used, { fx: 614.4, fy: 614.4, cx: 383.5, cy: 163.5 });

  // PFM through the picker.
  await page.setInputFiles('#truth-input', [{ name: 'depth1.pfm', mimeType: '', buffer: pfm }]);
  assert.equal(await scored(page), 'scored', await alertText(page));
  const mre = Number(await page.getAttribute('#truth-results', 'data-mre'));
  assert.ok(Math.abs(mre - cli.mre) <= 1e-4, `page MRE ${mre}, soup eval MRE ${cli.mre}`);
  assert.equal(await page.textContent('dd[data-metric="MRE"]'), mre.toFixed(4));
  assert.match(await page.textContent('#truth-metrics'), /AbsRel\d\.\d{4}δ<1\.25\d\.\d{3}/);
  // The error picture is drawn at the working size, with more than one colour.
  const picture = await page.$eval('#picture-error', (canvas) => {
    const { data } = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height);
    const seen = new Set();
    for (let i = 0; i < data.length; i += 4 * 31) seen.add(`${data[i]},${data[i + 1]},${data[i + 2]}`);
    return { width: canvas.width, height: canvas.height, colours: seen.size, hidden: canvas.closest('figure').hidden };
  });
  assert.deepEqual([picture.width, picture.height, picture.hidden], [768, 328, false]);
  assert.ok(picture.colours > 3, `${picture.colours} colours`);
  assert.equal(await page.textContent('#error-legend-high'), '≥ 50 %');

  // The same depth as Sintel .dpt dropped on the page, with the flow: same MRE, and an EPE.
  await page.evaluate(() => { document.body.dataset.truth = ''; });
  await drop(page, [{ name: 'depth1.dpt', buffer: dpt }, { name: 'flow12.flo', buffer: flo }]);
  assert.equal(await scored(page), 'scored', await alertText(page));
  assert.equal(Number(await page.getAttribute('#truth-results', 'data-mre')), mre);
  const epe = Number(await page.getAttribute('#truth-results', 'data-epe'));
  assert.ok(epe > 0 && epe < 5, `EPE ${epe}`);
  assert.match(await page.textContent('dd[data-metric="Flow EPE"]'), /^\d+\.\d{3} px/);

  // The report carries the scores.
  const report = JSON.parse(await download(page, 'report.json'));
  assert.equal(report.ground_truth.depth.file, 'depth1.dpt');
  assert.equal(report.ground_truth.depth.metrics.mre, mre);
  assert.equal(report.ground_truth.flow.metrics.epe, epe);

  // A reload restores the result and scores the same ground truth again.
  await page.reload();
  await page.waitForFunction(() => document.body.dataset.restored === 'shown');
  assert.equal(await waitForState(page, ['done', 'error']), 'done', await alertText(page));
  assert.equal(await scored(page), 'scored', await alertText(page));
  assert.equal(Number(await page.getAttribute('#truth-results', 'data-mre')), mre);
  assert.equal(Number(await page.getAttribute('#truth-results', 'data-epe')), epe);
  assert.equal(await page.textContent('dd[data-metric="Depth ground truth"]'), 'depth1.dpt');

  // Bad files: a message each, the result stays and the scores shown stay.
  const expectMessage = async (files) => {
    await page.evaluate(() => { document.body.dataset.truth = ''; });
    await page.setInputFiles('#truth-input', files);
    assert.equal(await scored(page), 'error');
    assert.equal(await page.evaluate(() => document.body.dataset.state), 'done');
    return alertText(page);
  };
  const small = writeDpt({ width: 100, height: 50, data: new Float32Array(5000).fill(2) });
  assert.equal(
    await expectMessage([{ name: 'other.dpt', mimeType: '', buffer: small }]),
    'other.dpt: The ground-truth depth is 100×50 but frame 1 is 768×328: ' +
      'it must be frame 1\'s, at the photo\'s own size.',
  );
  assert.match(
    await expectMessage([{ name: 'broken.pfm', mimeType: '', buffer: Buffer.from('Pf\n768 328\n-1\n') }]),
    /^broken\.pfm: Invalid PFM data: 768×328 needs 1007616 bytes of samples, file has 0\.$/,
  );
  const png = makePng(8, 8, () => [1, 2, 3]);
  assert.match(
    await expectMessage([{ name: 'depth.png', mimeType: 'image/png', buffer: png }]),
    /^depth\.png: /,
  );
  assert.equal(Number(await page.getAttribute('#truth-results', 'data-mre')), mre);
  assert.equal(await page.isHidden('#results'), false);

  // The page stays usable: a new run works.
  await page.click('#run-button');
  assert.equal(await waitForState(page, ['done', 'error']), 'done', await alertText(page));
  assert.deepEqual(errors, []);
  await page.context().close();
});
