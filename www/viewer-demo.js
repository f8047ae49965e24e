// The viewer test page (viewer.html): shows a deterministic synthetic moving scene in the wasm
// point-cloud viewer, without the reconstruction pipeline. Used by hand, by the end-to-end test
// (tests/e2e/viewer.test.mjs) and by the benchmark (benches/viewer.mjs).
//
// URL options: backend=auto|webgpu|webgl2 (default auto), points=N (default 200000).
// document.body.dataset.state is "loading", then "ready" or "error"; dataset.backend names the
// backend in use. window.viewerDemo exposes the viewer and measureFrames() for tests.

import { wireViewerControls } from './viewer-controls.js';

const $ = (id) => document.getElementById(id);

const params = new URLSearchParams(location.search);
const BACKEND = params.get('backend') ?? 'auto';
const POINTS = Math.max(1, Math.min(20_000_000, Number(params.get('points') ?? 200_000) || 200_000));

/** Seeded PRNG (mulberry32): the same scene on every load. */
function random(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/**
 * A synthetic scene in camera 1's frame (x right, y down, z forward, metres): a tiled floor, a
 * brick wall, a box that slides and turns on the floor, and a striped ball that rises, all as
 * `count` points with frame-1 and frame-2 positions, colours and superpixel-like labels (one
 * per floor tile, brick, box-face cell and ball patch). Only the box and the ball move.
 */
export function syntheticScene(count) {
  const pos1 = new Float32Array(count * 3);
  const pos2 = new Float32Array(count * 3);
  const rgb = new Uint8Array(count * 3);
  const labels = new Uint32Array(count);
  const rand = random(2017);
  const jitter = (c, amount) => Math.max(0, Math.min(255, Math.round(c + (rand() - 0.5) * amount)));

  let i = 0;
  const put = (p, q, colour, label) => {
    pos1.set(p, 3 * i);
    pos2.set(q, 3 * i);
    rgb.set(colour, 3 * i);
    labels[i] = label;
    i += 1;
  };

  const floorCount = Math.round(count * 0.3);
  const wallCount = Math.round(count * 0.3);
  const boxCount = Math.round(count * 0.25);
  const ballCount = count - floorCount - wallCount - boxCount;

  // Floor: y = 1.2 below the camera, 0.5 m checkerboard tiles, as far as camera 1 sees it
  // (|x| ≤ z/2, 3 ≤ z ≤ 13). A floor patch at depth z covers ∝ 1/z³ of the picture, so z is
  // drawn with density ∝ 1/z² (times the row width ∝ z): uniform per pixel, like a reconstruction.
  for (let k = 0; k < floorCount; k++) {
    const z = 1 / (1 / 3 - rand() * (1 / 3 - 1 / 13));
    const x = (rand() - 0.5) * z;
    const [tx, tz] = [Math.floor(x / 0.5), Math.floor(z / 0.5)];
    const light = (tx + tz) % 2 === 0;
    const base = light ? [205, 195, 170] : [115, 105, 95];
    const p = [x, 1.2, z];
    put(p, p, base.map((c) => jitter(c, 16)), 1000 + (tx + 16) * 64 + tz);
  }

  // Back wall: z = 13, bricks 0.6 × 0.3 m in offset rows, light mortar.
  for (let k = 0; k < wallCount; k++) {
    const x = -6.5 + 13 * rand();
    const y = -3 + 4.2 * rand();
    const row = Math.floor((y + 3) / 0.3);
    const shifted = x + (row % 2) * 0.3;
    const column = Math.floor((shifted + 6.5) / 0.6);
    const [u, v] = [(shifted + 6.5) / 0.6 - column, (y + 3) / 0.3 - row];
    const mortar = u < 0.06 || v < 0.12;
    const tone = ((column * 7 + row * 13) % 5) * 10;
    const base = mortar ? [200, 200, 195] : [150 + tone, 60 + tone / 2, 45];
    const p = [x, y, 13];
    put(p, p, base.map((c) => jitter(c, 20)), 5000 + row * 32 + column);
  }

  // Box: 1.4 m cube standing on the floor (its bottom face, on the floor, is left out); in
  // frame 2 turned by 35° about the vertical and moved.
  const centre = [-1.2, 0.5, 6.5];
  const half = 0.7;
  const angle = (35 * Math.PI) / 180;
  const [cos, sin] = [Math.cos(angle), Math.sin(angle)];
  const shift = [1.8, 0, -1.0];
  const faceColours = [
    [220, 70, 60], [60, 150, 220], [240, 190, 50], [80, 180, 110], [170, 90, 200], [240, 130, 60],
  ];
  for (let k = 0; k < boxCount; k++) {
    const face = [0, 1, 2, 4, 5][Math.floor(rand() * 5)]; // not 3 (+y: the bottom)
    const [a, b] = [2 * rand() - 1, 2 * rand() - 1];
    const axis = face >> 1;
    const sign = face & 1 ? 1 : -1;
    const local = axis === 0 ? [sign, a, b] : axis === 1 ? [a, sign, b] : [a, b, sign];
    const [lx, ly, lz] = local.map((c) => c * half);
    const p = [centre[0] + lx, centre[1] + ly, centre[2] + lz];
    const q = [
      centre[0] + cos * lx + sin * lz + shift[0],
      centre[1] + ly + shift[1],
      centre[2] - sin * lx + cos * lz + shift[2],
    ];
    const [cu, cv] = [Math.min(3, Math.floor((a + 1) * 2)), Math.min(3, Math.floor((b + 1) * 2))];
    const grid = Math.abs(((a + 1) * 2) % 1 - 0.5) > 0.45 || Math.abs(((b + 1) * 2) % 1 - 0.5) > 0.45;
    const base = grid ? [30, 30, 35] : faceColours[face];
    put(p, q, base.map((c) => jitter(c, 12)), 9000 + face * 16 + cu * 4 + cv);
  }

  // Ball: radius 0.9 m with coloured latitude stripes; it rises and drifts left in frame 2.
  const ball = [1.6, -0.2, 8];
  const radius = 0.9;
  const lift = [-0.6, -0.8, 0.5];
  const stripes = [[250, 250, 245], [40, 90, 200], [250, 200, 40], [200, 40, 60]];
  for (let k = 0; k < ballCount; k++) {
    const s = 2 * rand() - 1;
    const phi = 2 * Math.PI * rand();
    const ring = Math.sqrt(1 - s * s);
    const p = [ball[0] + radius * ring * Math.cos(phi), ball[1] + radius * s, ball[2] + radius * ring * Math.sin(phi)];
    const q = [p[0] + lift[0], p[1] + lift[1], p[2] + lift[2]];
    const band = Math.min(7, Math.floor((s + 1) * 4));
    const sector = Math.floor((phi / (2 * Math.PI)) * 8);
    put(p, q, stripes[band % 4].map((c) => jitter(c, 14)), 12000 + band * 8 + sector);
  }
  return { pos1, pos2, rgb, labels };
}

function setState(state) {
  document.body.dataset.state = state;
}

function showError(message) {
  const el = $('error');
  el.textContent = message;
  el.hidden = false;
}

const BACKEND_NAMES = { webgpu: 'WebGPU', webgl2: 'WebGL2' };

async function main() {
  let wasm;
  try {
    wasm = await import('./pkg/superpixel_soup.js');
    await wasm.default();
  } catch (e) {
    setState('error');
    $('status').textContent = '';
    showError(`Could not load the WebAssembly module (build it with scripts/build-web.sh): ${e.message ?? e}`);
    return;
  }

  let viewer;
  try {
    viewer = await wasm.Viewer.create($('view'), { backend: BACKEND });
  } catch (e) {
    setState('error');
    $('status').textContent = '';
    showError(`The 3D view cannot run in this browser. ${e.message ?? e}`);
    return;
  }
  document.body.dataset.backend = viewer.backend;

  const scene = syntheticScene(POINTS);
  const start = performance.now();
  viewer.setCloud(scene.pos1, scene.pos2, scene.rgb, scene.labels);
  const setCloudMs = performance.now() - start;
  $('status').textContent =
    `${BACKEND_NAMES[viewer.backend]} · ${viewer.pointCount.toLocaleString('en')} points ` +
    `(${viewer.shownPointCount.toLocaleString('en')} drawn) · setCloud ${setCloudMs.toFixed(0)} ms`;

  wireViewerControls(viewer);
  window.viewerDemo = { viewer, setCloudMs, measureFrames: (frames) => measureFrames(viewer, frames) };
  $('controls').hidden = false;
  setState('ready');
}

/** Mean milliseconds per frame over `frames` back-to-back redraws, GPU work included. */
async function measureFrames(viewer, frames) {
  // Let a redraw the viewer scheduled by itself happen first, outside the measurement.
  for (let k = 0; k < 2; k++) {
    await new Promise(requestAnimationFrame);
  }
  viewer.render();
  await viewer.finish();
  const start = performance.now();
  for (let k = 0; k < frames; k++) {
    viewer.render();
  }
  await viewer.finish();
  return (performance.now() - start) / frames;
}

main();
