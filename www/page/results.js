// The results views: the stage pictures (depth with its legend, superpixels, flow, the
// unorganised and organised soup), the report's summary and the timings. The 3D view is in
// view3d.js.

import { $, page } from './ui.js';
import { STAGE_LABELS } from './worker-client.js';
import { showCloud } from './view3d.js';

/** Shows a result from the worker: pictures, report and the 3D view. */
export async function showResult(result) {
  showPictures(result);
  page.points = result.cloud.count;
  const { confidence, params } = result.report;
  page.unconfident = confidence.flatMap((c, label) => (c < params.scales.min_confidence ? [label] : []));
  $('soup-mode').value = 'organised';
  await showCloud(result.cloud);
}

/**
 * Shows a result's pictures, legend and report ({ width, height, pictures, legend, report }:
 * the worker's, or the last one's kept across a reload, which has no cloud).
 */
export function showPictures(result) {
  const { width, height } = result;
  page.workingSize = [width, height];
  const draw = (id, rgba) => {
    const canvas = $(id);
    canvas.width = width;
    canvas.height = height;
    canvas.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(rgba.buffer), width, height), 0, 0);
  };
  draw('picture-depth', result.pictures.depth);
  draw('picture-organised', result.pictures.depth);
  draw('picture-unorganised', result.pictures.unorganised);
  draw('picture-superpixels', result.pictures.superpixels);
  draw('picture-flow', result.pictures.flow);
  draw('picture-confidence', result.pictures.confidence);
  drawLegend(result.legend);
  $('superpixel-count').textContent = result.report.superpixels.toLocaleString('en');
  fillSummary(result.report);
  $('results').hidden = false;
}

function drawLegend(legend) {
  const canvas = $('legend');
  if (legend === null) {
    $('legend-near').textContent = 'no depth known';
    $('legend-far').textContent = '';
    return;
  }
  canvas.width = legend.colours.length;
  const pixels = new Uint8ClampedArray(legend.colours.flatMap(([r, g, b]) => [r, g, b, 255]));
  canvas.getContext('2d').putImageData(new ImageData(pixels, legend.colours.length, 1), 0, 0);
  const depths = legend.depths;
  const format = (z) => (z >= 100 ? z.toFixed(0) : z.toPrecision(2));
  $('legend-near').textContent = `near ${format(depths[0])}`;
  $('legend-far').textContent = `far ${format(depths[depths.length - 1])} (relative units)`;
}

function fillSummary(report) {
  const k = report.camera.intrinsics;
  const rows = [
    ['Input size', `${report.input_size[0]} × ${report.input_size[1]}`],
    ['Working size', `${report.working_size[0]} × ${report.working_size[1]}`],
    ['Intrinsics (working size)', `fx ${k.fx.toFixed(1)}, fy ${k.fy.toFixed(1)}, cx ${k.cx.toFixed(1)}, cy ${k.cy.toFixed(1)}`],
    ['Intrinsics from', { user: 'you (or the sample)', exif: 'EXIF focal length', default: 'default guess (the frames do not fix the focal length)', estimated: 'the two frames (no EXIF focal length)' }[report.camera.source] ?? report.camera.source],
    ['Superpixels', `${report.superpixels} (${report.degenerate} without a plane of their own)`],
    ['Motion hypotheses', String(report.hypotheses)],
    ['Trusted flow', `${(100 * report.reliable_flow).toFixed(1)} % of pixels`],
    ['Scale energy', `${report.scales.energy_start.toPrecision(4)} → ${report.scales.energy_end.toPrecision(4)} (${report.scales.segments} rigid segments, ${report.scales.tail_pieces} superpixels taken from their neighbours)`],
    ['Refinement energy', report.refine === null
      ? 'off'
      : `${report.refine.energies[0].toPrecision(4)} → ${report.refine.energies.at(-1).toPrecision(4)} in ${report.refine.energies.length - 1} iterations, ${report.refine.expansion_energy.toPrecision(4)} after ${report.refine.expansions} scale expansions`],
    ['Depth guessed', `${report.unconfident} superpixels (no contact pins their scale, or they had too little trusted flow for a plane of their own: their depth relative to the rest is a guess)`],
  ];
  for (const note of report.notes) {
    rows.push(['Note', note]);
  }
  $('summary').replaceChildren(...rows.flatMap(([term, value]) => {
    const dt = document.createElement('dt');
    dt.textContent = term;
    const dd = document.createElement('dd');
    dd.textContent = value;
    return [dt, dd];
  }));
}

export function fillTimings(report, run) {
  const rows = report.timings_ms.map(([stage, ms]) => [STAGE_LABELS[stage] ?? stage, ms]);
  const members = report.ensemble?.counts.length ?? 0;
  const ensemble = rows.find((_, i) => report.timings_ms[i][0] === 'ensemble');
  if (ensemble !== undefined && members > 0) {
    // The members are made by the worker and its helpers (www/worker.js).
    const workers = 1 + (run.worker.helpers ?? 0);
    ensemble[0] += ` (${members} members, ${workers} worker${workers === 1 ? '' : 's'})`;
  }
  rows.unshift(['Reading the pixels (worker)', run.worker.pixelsMs]);
  rows.push(['Pictures and clouds (worker)', run.worker.collectMs]);
  rows.push(['Display (viewer, pictures)', run.showMs]);
  rows.push(['Total', run.totalMs]);
  for (const item of $('stages').children) {
    const ms = run.stagesMs[item.dataset.stage];
    item.querySelector('.time').textContent = ms === undefined ? '' : `${Math.round(ms)} ms`;
  }
  $('timings').tBodies[0].replaceChildren(...rows.map(([name, ms]) => {
    const row = document.createElement('tr');
    row.innerHTML = '<th scope="row"></th><td></td>';
    row.cells[0].textContent = name;
    row.cells[1].textContent = `${Math.round(ms)} ms`;
    return row;
  }));
}
