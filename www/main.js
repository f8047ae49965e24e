// The page's script (ES module). It loads the wasm build of the library (www/pkg, made by
// scripts/build-web.sh) and drives the page. document.body.dataset.state tells tests and styles
// where the page is: "loading" → "idle" (ready) ⇄ "busy" (working on a file); "error" when the
// wasm module cannot be loaded at all.

const $ = (id) => document.getElementById(id);

let wasm = null;

function setState(state) {
  document.body.dataset.state = state;
}

function setStatus(text) {
  $('status').textContent = text;
}

function showError(message) {
  const el = $('error');
  el.textContent = message;
  el.hidden = false;
}

function clearError() {
  const el = $('error');
  el.textContent = '';
  el.hidden = true;
}

function formatFocal(mm) {
  return mm === undefined ? 'not in the file' : `${mm} mm`;
}

function showInfo(file, info) {
  $('info-name').textContent = file.name;
  $('info-size').textContent = `${info.width} × ${info.height} pixels`;
  $('info-focal').textContent = formatFocal(info.focal35mm);
  $('image-info').hidden = false;
  if (info.exifWarning !== undefined) {
    setStatus(info.exifWarning);
  }
}

async function readFile(file) {
  setState('busy');
  clearError();
  $('image-info').hidden = true;
  setStatus(`Reading ${file.name}…`);
  try {
    const bytes = new Uint8Array(await file.arrayBuffer());
    const info = wasm.decodeImageInfo(bytes);
    try {
      setStatus(`Decoded ${file.name}.`);
      showInfo(file, info);
    } finally {
      info.free();
    }
  } catch (e) {
    setStatus('');
    showError(`${file.name}: ${e instanceof Error ? e.message : String(e)}`);
  } finally {
    setState('idle');
  }
}

async function main() {
  try {
    wasm = await import('./pkg/superpixel_soup.js');
    await wasm.default();
  } catch (e) {
    setState('error');
    setStatus('');
    showError(`Could not load the WebAssembly module (build it with ./serve.sh): ${e.message ?? e}`);
    return;
  }
  $('version').textContent = wasm.version();
  const input = $('file-input');
  input.disabled = false;
  input.addEventListener('change', () => {
    if (input.files.length > 0) {
      readFile(input.files[0]);
    }
  });
  setStatus('Ready.');
  setState('idle');
}

main();
