// End-to-end test of the last result surviving a reload (IndexedDB): the sample is
// reconstructed with a changed parameter, the tab is reloaded, and the page comes back with the
// same frames, parameters and result; "Start over" forgets it, also for the next reload.

import { test } from 'node:test';
import assert from 'node:assert/strict';
import { browserSession } from './browser.mjs';
import { alertText, openPage, waitForRunEnd, waitForState } from './page-helpers.mjs';

const session = browserSession();

/** What a result looks like to the user: frames, parameters, report and 3D cloud. */
function snapshot(page) {
  return page.evaluate(() => ({
    frames: [document.querySelector('#thumb1-info').textContent, document.querySelector('#thumb2-info').textContent],
    count: document.querySelector('#params [name="count"]').value,
    fx: document.querySelector('#params [name="fx"]').value,
    intrinsics: document.querySelector('#intrinsics-source').textContent,
    summary: document.querySelector('#summary').textContent,
    superpixels: document.querySelector('#superpixel-count').textContent,
    points: window.soupPage.points,
    shown: window.soupPage.viewer?.pointCount ?? null,
  }));
}

test('a reload restores the last result; start over forgets it', async () => {
  const { page, errors } = await openPage(session.browser, session.server.url);
  assert.equal(await page.isHidden('#start-over'), true);
  await page.click('#sample-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  // A changed parameter, run again.
  await page.click('#params-details summary');
  await page.fill('#params [name="count"]', '900');
  await page.click('#run-button');
  assert.equal(await waitForRunEnd(page), 'done', await alertText(page));
  await page.waitForFunction(() => document.body.dataset.saved === 'yes');
  const before = await snapshot(page);
  assert.equal(before.count, '900');
  assert.ok(before.points > 100_000, `${before.points} points`);

  await page.reload();
  // The kept outputs are shown at once, while the frames are reconstructed again.
  await page.waitForFunction(() => document.body.dataset.restored === 'shown');
  assert.equal(await page.isHidden('#results'), false);
  assert.equal(await page.textContent('#summary'), before.summary);
  assert.equal(await waitForState(page, ['done', 'error']), 'done', await alertText(page));
  assert.match(await page.textContent('#status'), /^Restored your last result/);
  const after = await snapshot(page);
  assert.deepEqual(after, before);
  assert.equal(await page.isHidden('#results'), false);
  assert.equal(await page.isVisible('#start-over'), true);

  // Start over: nothing shown, nothing kept.
  await page.click('#start-over');
  await waitForState(page, 'idle');
  assert.equal(await page.isHidden('#results'), true);
  assert.equal(await page.isHidden('#frames'), true);
  assert.equal(await page.inputValue('#params [name="count"]'), '1500');
  await page.reload();
  await waitForState(page, 'idle');
  // Give a restore (which there must not be) the time to start.
  await page.waitForTimeout(500);
  assert.equal(await page.evaluate(() => document.body.dataset.state), 'idle');
  assert.equal(await page.isHidden('#frames'), true);
  assert.deepEqual(errors, []);
  await page.context().close();
});
