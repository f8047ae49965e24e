// The parameters panel: filled from the page's defaults (the library's, but for the flow preset and the refinement), read into the run's options, and
// the camera intrinsics (from EXIF or the default guess, or the user's own).

import { $, page } from './ui.js';

export const INTRINSIC_FIELDS = ['fx', 'fy', 'cx', 'cy'];

/**
 * The numeric fields of the form (by `name`) and where each lives in the run's options: a new
 * setting of the library needs one line here and one <input> in index.html.
 */
export const NUMBER_FIELDS = [
  { name: 'maxSide', path: ['maxSide'] },
  { name: 'count', path: ['params', 'superpixels', 'count'] },
  { name: 'compactness', path: ['params', 'superpixels', 'compactness'] },
  { name: 'k', path: ['params', 'k'] },
  { name: 'sigma', path: ['params', 'scales', 'sigma'] },
  { name: 'refineIterations', path: ['params', 'refine', 'iterations'] },
  { name: 'particles', path: ['params', 'refine', 'particles'] },
  { name: 'ensembleMembers', path: ['params', 'ensemble', 'members'] },
];

const getPath = (object, path) => path.reduce((o, key) => o?.[key], object);

function setPath(object, path, value) {
  const last = path[path.length - 1];
  path.slice(0, -1).reduce((o, key) => o[key], object)[last] = value;
}

/** Fills the form with `options` (RunOptions of the library). */
export function fillForm(options) {
  const form = $('params');
  const select = form.elements.flowPreset;
  if (select.options.length === 0) {
    for (const name of page.defaults.flowPresets) {
      select.add(new Option(name, name));
    }
  }
  select.value = options.flowPreset;
  for (const { name, path } of NUMBER_FIELDS) {
    const value = getPath(options, path);
    if (form.elements[name] !== undefined && value !== undefined) {
      form.elements[name].value = value;
    }
  }
}


/** Fills the intrinsics from the library's resolution (EXIF of frame 1, else the default). */
export async function refreshIntrinsics() {
  const [frame] = page.frames;
  if (frame === undefined) {
    return;
  }
  const { camera } = await page.pipeline.request('intrinsics', {
    width: frame.width,
    height: frame.height,
    focal35mm: frame.exif.focal35mm,
  });
  const source = camera.source === 'exif'
    ? `EXIF of frame 1 (${frame.exif.focal35mm} mm, 35 mm equivalent)`
    : 'default guess (no EXIF focal length): f = long side, centre of the image; the run estimates f from the two frames where they fix it';
  setIntrinsics(camera.intrinsics, 'auto', source);
}

/**
 * The intrinsics last put in the form, exactly, and as shown (rounded to 0.001): a field the user
 * has not edited gives its exact value to the run (the reconstruction reacts to the last bits).
 */
let shown = null;

export function setIntrinsics(intrinsics, mode, source) {
  page.intrinsicsMode = mode;
  const form = $('params');
  shown = { exact: { ...intrinsics }, text: {} };
  for (const name of INTRINSIC_FIELDS) {
    form.elements[name].value = String(Math.round(intrinsics[name] * 1000) / 1000);
    shown.text[name] = form.elements[name].value;
  }
  $('intrinsics-source').textContent = source;
  $('intrinsics-reset').hidden = mode !== 'user';
}

/** The intrinsics in the form: the exact values where the shown ones were not edited. */
export function formIntrinsics() {
  const form = $('params');
  return Object.fromEntries(INTRINSIC_FIELDS.map((name) => {
    const text = form.elements[name].value;
    return [name, shown !== null && shown.text[name] === text ? shown.exact[name] : Number(text)];
  }));
}

/** The run's options from the form (library defaults for what the form does not show). */
export function readOptions(resizeSecond) {
  const form = $('params');
  for (const input of form.querySelectorAll('input')) {
    if (!input.checkValidity()) {
      const label = input.closest('label')?.firstChild?.textContent?.trim() ?? input.name;
      throw new Error(`${label}: ${input.validationMessage}`);
    }
  }
  const number = (name) => Number(form.elements[name].value);
  const options = structuredClone(page.defaults.options);
  options.flowPreset = form.elements.flowPreset.value;
  for (const { name, path } of NUMBER_FIELDS) {
    if (form.elements[name] !== undefined) {
      setPath(options, path, number(name));
    }
  }
  if (page.intrinsicsMode === 'user') {
    options.intrinsics = formIntrinsics();
  }
  // The frames are decoded at the working size; the library is told the photos' own sizes.
  options.photoSizes = page.frames.map((f) => [f.width, f.height]);
  options.exif1 = page.frames[0].exif;
  options.exif2 = page.frames[1].exif;
  options.resizeSecond = resizeSecond;
  return options;
}
