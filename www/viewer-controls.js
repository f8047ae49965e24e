// The controls of the 3D viewer shared by the page (index.html) and the viewer test page
// (viewer.html): frame 1 / 2 radios (name "frame"), morph slider (#morph) and its play button
// (#play), point size (#point-size), colour mode (#colour-mode), reset view (#reset) and
// screenshot (#screenshot, saved as a PNG download).

const $ = (id) => document.getElementById(id);

/**
 * Connects the controls above to `viewer`: a wasm Viewer, or a function returning the one in
 * use (the page replaces its viewer when the GPU is lost; the controls follow).
 */
export function wireViewerControls(viewer) {
  const current = typeof viewer === 'function' ? viewer : () => viewer;
  const morph = $('morph');
  const setMorph = (t) => {
    current()?.setMorph(t);
    morph.value = String(t);
    for (const radio of document.querySelectorAll('input[name="frame"]')) {
      radio.checked = (radio.value === '1' && t === 0) || (radio.value === '2' && t === 1);
    }
  };

  for (const radio of document.querySelectorAll('input[name="frame"]')) {
    radio.addEventListener('change', () => setMorph(radio.value === '2' ? 1 : 0));
  }
  morph.addEventListener('input', () => setMorph(Number(morph.value)));

  let playing = null;
  $('play').addEventListener('click', () => {
    if (playing !== null) {
      cancelAnimationFrame(playing);
      playing = null;
      $('play').textContent = 'Play';
      return;
    }
    $('play').textContent = 'Pause';
    const start = performance.now() - Number(morph.value) * 1000;
    const step = (now) => {
      const phase = ((now - start) / 2000) % 1; // 0 → 1 → 0 every 2 s
      setMorph(Math.round((1 - Math.abs(2 * phase - 1)) * 100) / 100);
      playing = requestAnimationFrame(step);
    };
    playing = requestAnimationFrame(step);
  });

  $('point-size').addEventListener('input', () => current()?.setPointSize(Number($('point-size').value)));
  $('colour-mode').addEventListener('change', () => current()?.setColourMode($('colour-mode').value));
  $('reset').addEventListener('click', () => current()?.resetView());
  $('screenshot').addEventListener('click', async () => {
    const shown = current();
    if (!shown) {
      return;
    }
    const png = await shown.screenshot();
    const url = URL.createObjectURL(new Blob([png], { type: 'image/png' }));
    const link = document.createElement('a');
    link.href = url;
    link.download = 'superpixel-soup-view.png';
    link.click();
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  });
}

