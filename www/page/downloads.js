// Downloads of the output files (PLY, PFM, 16-bit PNG, .flo, labels, the JSON report), made by
// the worker's wasm module exactly as `soup reconstruct` writes them.

import { CancelledError } from '../pipeline.js';
import { page, saveFile, showAlert } from './ui.js';

/** Asks the worker for the output file `name` and saves it. */
export async function download(name) {
  try {
    const { bytes, mediaType } = await page.pipeline.request('export', { name });
    saveFile(bytes, name, mediaType);
  } catch (e) {
    if (!(e instanceof CancelledError)) {
      showAlert(`Could not make ${name}: ${e.message}`);
    }
  }
}
