// scripts/serve.py sends the content types and headers the page relies on.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { startServer } from './browser.mjs';

let server;
before(async () => {
  server = await startServer();
});
after(async () => {
  await server?.close();
});

async function head(file) {
  const res = await fetch(new URL(file, server.url));
  await res.arrayBuffer();
  return res;
}

test('wasm is served as application/wasm and modules as JavaScript', async () => {
  for (const file of ['www/pkg/superpixel_soup_bg.wasm', 'www/pkg/soup_worker_bg.wasm']) {
    const wasm = await head(file);
    assert.equal(wasm.status, 200, file);
    assert.equal(wasm.headers.get('content-type'), 'application/wasm', file);
  }
  for (const file of ['www/main.js', 'www/worker.js', 'www/pkg/superpixel_soup.js', 'www/pkg/soup_worker.js']) {
    const js = await head(file);
    assert.equal(js.status, 200, file);
    assert.equal(js.headers.get('content-type'), 'text/javascript', file);
  }
});

test('responses carry cross-origin isolation and no-cache headers', async () => {
  const page = await head('');
  assert.equal(page.status, 200);
  assert.match(page.headers.get('content-type'), /^text\/html/);
  assert.equal(page.headers.get('cross-origin-opener-policy'), 'same-origin');
  assert.equal(page.headers.get('cross-origin-embedder-policy'), 'require-corp');
  assert.equal(page.headers.get('cache-control'), 'no-cache');
});

test('a missing file is a 404', async () => {
  assert.equal((await head('no/such/file.js')).status, 404);
});
