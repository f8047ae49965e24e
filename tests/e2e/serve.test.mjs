// scripts/serve.py sends the content types and headers the page relies on.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { request } from 'node:http';
import { gunzipSync } from 'node:zlib';
import { ROOT, startServer } from './browser.mjs';

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
  for (const file of ['www/pkg/superpixel_soup_bg.wasm', 'www/pkg/soup_worker_bg.wasm', 'www/pkg/soup_worker_simd_bg.wasm']) {
    const wasm = await head(file);
    assert.equal(wasm.status, 200, file);
    assert.equal(wasm.headers.get('content-type'), 'application/wasm', file);
  }
  for (const file of ['www/main.js', 'www/worker.js', 'www/pkg/superpixel_soup.js', 'www/pkg/soup_worker.js', 'www/pkg/soup_worker_simd.js']) {
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

test('wasm and text are sent gzipped when accepted, with the same bytes; PNGs as they are', async () => {
  // node:http does not decompress, so the encoding on the wire is visible.
  const get = (file, headers) =>
    new Promise((resolve, reject) => {
      request(new URL(file, server.url), { headers }, (res) => {
        const chunks = [];
        res.on('data', (c) => chunks.push(c));
        res.on('end', () => resolve({ res, body: Buffer.concat(chunks) }));
      })
        .on('error', reject)
        .end();
    });
  const file = 'www/pkg/soup_worker_bg.wasm';
  const original = readFileSync(`${ROOT}/${file}`);
  const zipped = await get(file, { 'accept-encoding': 'gzip, deflate' });
  assert.equal(zipped.res.headers['content-encoding'], 'gzip');
  assert.equal(zipped.res.headers['content-type'], 'application/wasm');
  assert.ok(zipped.body.length < original.length / 2, `${zipped.body.length} of ${original.length} bytes`);
  assert.ok(gunzipSync(zipped.body).equals(original));
  const plain = await get(file, {});
  assert.equal(plain.res.headers['content-encoding'], undefined);
  assert.ok(plain.body.equals(original));
  const png = await get('www/sample/frame1.png', { 'accept-encoding': 'gzip' });
  assert.equal(png.res.headers['content-encoding'], undefined);
  const cached = await get(file, { 'accept-encoding': 'gzip', 'if-modified-since': zipped.res.headers['last-modified'] });
  assert.equal(cached.res.statusCode, 304);
});
