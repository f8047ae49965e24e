// The browser flags (webdriver.json, used by launchBrowser) give a headless Chromium in which
// both renderer backends really draw: WebGL2, and WebGPU presenting to a canvas. Without the
// SwiftShader/Vulkan flags WebGPU hands out an adapter but the canvas stays blank; this catches that.

import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { launchBrowser, startServer } from './browser.mjs';

let server;
let browser;
let page;

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  page = await browser.newPage();
  await page.goto(server.url); // a secure (localhost) context, as WebGPU requires
});

after(async () => {
  await browser?.close();
  await server?.close();
});

/** Copies a canvas into a 2D canvas and returns the RGBA of its centre pixel. */
const CENTRE_PIXEL = `(canvas) => {
  const copy = document.createElement('canvas');
  copy.width = canvas.width;
  copy.height = canvas.height;
  const ctx = copy.getContext('2d');
  ctx.drawImage(canvas, 0, 0);
  return Array.from(ctx.getImageData(canvas.width >> 1, canvas.height >> 1, 1, 1).data);
}`;

const near = (actual, expected, tol = 3) =>
  actual.length === expected.length && actual.every((v, i) => Math.abs(v - expected[i]) <= tol);

test('WebGL2 clears a canvas to a colour', async () => {
  const pixel = await page.evaluate(`(() => {
    const canvas = document.createElement('canvas');
    canvas.width = canvas.height = 16;
    const gl = canvas.getContext('webgl2', { preserveDrawingBuffer: true });
    if (!gl) return 'no webgl2 context';
    gl.clearColor(0.0, 0.5, 1.0, 1.0);
    gl.clear(gl.COLOR_BUFFER_BIT);
    return (${CENTRE_PIXEL})(canvas);
  })()`);
  assert.ok(near(pixel, [0, 128, 255, 255]), `centre pixel ${JSON.stringify(pixel)}`);
});

test('WebGPU draws a triangle into a canvas', async () => {
  const pixel = await page.evaluate(`(async () => {
    if (!navigator.gpu) return 'navigator.gpu missing';
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) return 'no WebGPU adapter';
    const device = await adapter.requestDevice();
    const canvas = document.createElement('canvas');
    canvas.width = canvas.height = 16;
    const context = canvas.getContext('webgpu');
    const format = navigator.gpu.getPreferredCanvasFormat();
    context.configure({ device, format, alphaMode: 'opaque' });
    const module = device.createShaderModule({ code: \`
      @vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
        let p = array(vec2f(-1.0, -1.0), vec2f(3.0, -1.0), vec2f(-1.0, 3.0));
        return vec4f(p[i], 0.0, 1.0);
      }
      @fragment fn fs() -> @location(0) vec4f { return vec4f(0.0, 1.0, 0.0, 1.0); }
    \` });
    const pipeline = device.createRenderPipeline({
      layout: 'auto',
      vertex: { module, entryPoint: 'vs' },
      fragment: { module, entryPoint: 'fs', targets: [{ format }] },
    });
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginRenderPass({ colorAttachments: [{
      view: context.getCurrentTexture().createView(),
      clearValue: { r: 1, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store',
    }] });
    pass.setPipeline(pipeline);
    pass.draw(3);
    pass.end();
    device.queue.submit([encoder.finish()]);
    await device.queue.onSubmittedWorkDone();
    return (${CENTRE_PIXEL})(canvas);
  })()`);
  assert.ok(near(pixel, [0, 255, 0, 255]), `centre pixel ${JSON.stringify(pixel)}`);
});
