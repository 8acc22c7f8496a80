// The page's controls: panels, banner and status, fit-to-window and fullscreen, keyboard
// shortcuts, and the fovea ring. app.js owns the connection; this file only wires the page.

const $ = (id) => document.getElementById(id);

export const controls = {
  scene: $('scene'), size: $('size'), codec: $('codec'), encoding: $('encoding'), preset: $('preset'),
  overlay: $('overlay-mode'), dof: $('dof'), pupil: $('pupil'), predict: $('predict'),
  auto: $('auto-gaze'), ring: $('fovea-ring'), reconstruction: $('reconstruction'),
  edges_at_mar: $('edges_at_mar'), coarse_gather: $('coarse_gather'),
  mar_slope: $('mar_slope'), mar_w0_deg: $('mar_w0_deg'), min_probability: $('min_probability'),
};

export function setStatus(text, kind) {
  const el = $('status');
  el.textContent = text;
  el.className = `status ${kind}`;
}

let bannerTimer = null;
export function showBanner(text, kind, hideAfterMs) {
  const el = $('banner');
  el.textContent = text;
  el.className = kind;
  el.hidden = false;
  clearTimeout(bannerTimer);
  if (hideAfterMs) bannerTimer = setTimeout(hideBanner, hideAfterMs);
}

export function hideBanner() {
  $('banner').hidden = true;
}

function toggle(id, button) {
  const el = $(id);
  el.hidden = !el.hidden;
  $(button).setAttribute('aria-pressed', String(!el.hidden));
}

function toggleFit() {
  document.body.classList.toggle('fit');
  $('fit-button').setAttribute('aria-pressed', String(document.body.classList.contains('fit')));
}

function toggleFullscreen() {
  if (document.fullscreenElement) document.exitFullscreen();
  else $('stage').requestFullscreen?.().catch(() => {});
}

// The central 5° around the gaze the last frame used: where foveal quality is measured. The
// display is the protocol's default, 53 cm wide at 60 cm, filled by the frame's width.
const FOVEA_DEG = 5;
export function drawFovea(header) {
  const marks = $('marks');
  const view = $('view');
  if (marks.width !== view.width || marks.height !== view.height) {
    marks.width = view.width;
    marks.height = view.height;
  }
  const g = marks.getContext('2d');
  g.clearRect(0, 0, marks.width, marks.height);
  if (!controls.ring.checked || !header) return;
  const pxPerCm = marks.width / 53;
  const radius = 60 * Math.tan((FOVEA_DEG * Math.PI) / 180) * pxPerCm;
  g.strokeStyle = 'rgba(94, 200, 255, 0.9)';
  g.setLineDash([6, 4]);
  g.lineWidth = 2;
  g.beginPath();
  g.arc(header.gaze.x * marks.width, header.gaze.y * marks.height, radius, 0, 2 * Math.PI);
  g.stroke();
}

// Dragging moves the camera: the left button orbits, shift or the right button pans, the
// wheel dollies, a double-click goes back to the scene's camera. Moves are summed over an
// animation frame and sent as one `camera` message (the gaze keeps following the pointer).
function bindCamera(canvas, app) {
  let drag = null;
  let pending = null;
  const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
  const flush = () => {
    const m = pending;
    pending = null;
    if (m.orbit_deg) m.orbit_deg = m.orbit_deg.map((v) => clamp(v, -360, 360));
    if (m.pan) m.pan = m.pan.map((v) => clamp(v, -10, 10));
    if (m.dolly) m.dolly = clamp(m.dolly, 0.05, 20);
    app.sendCamera(m);
  };
  const queue = (m) => {
    if (!pending) {
      pending = {};
      requestAnimationFrame(flush);
    }
    for (const [k, v] of Object.entries(m)) {
      if (k === 'dolly') pending.dolly = (pending.dolly ?? 1) * v;
      else pending[k] = pending[k] ? pending[k].map((x, i) => x + v[i]) : v;
    }
  };
  canvas.addEventListener('pointerdown', (ev) => {
    drag = { x: ev.clientX, y: ev.clientY, pan: ev.shiftKey || ev.button === 2 };
    try { canvas.setPointerCapture(ev.pointerId); } catch { /* synthetic pointers have no capture */ }
  });
  canvas.addEventListener('pointermove', (ev) => {
    if (!drag) return;
    const r = canvas.getBoundingClientRect();
    const dx = (ev.clientX - drag.x) / r.height;
    const dy = (ev.clientY - drag.y) / r.height;
    drag.x = ev.clientX;
    drag.y = ev.clientY;
    if (dx === 0 && dy === 0) return;
    queue(drag.pan ? { pan: [-dx, dy] } : { orbit_deg: [-dx * 120, dy * 120] });
  });
  for (const end of ['pointerup', 'pointercancel']) canvas.addEventListener(end, () => { drag = null; });
  canvas.addEventListener('contextmenu', (ev) => ev.preventDefault());
  canvas.addEventListener('wheel', (ev) => {
    ev.preventDefault();
    queue({ dolly: Math.exp(ev.deltaY * 0.001) });
  }, { passive: false });
  canvas.addEventListener('dblclick', () => app.sendCamera({ reset: true }));
}

export function bindControls(app) {
  const canvas = $('view');
  canvas.addEventListener('mousemove', (ev) => {
    if (controls.auto.checked) return;
    const r = canvas.getBoundingClientRect();
    const clamp = (v) => Math.min(1, Math.max(0, v));
    app.sendGaze(clamp((ev.clientX - r.left) / r.width), clamp((ev.clientY - r.top) / r.height));
  });
  bindCamera(canvas, app);
  controls.pupil.addEventListener('input', () => {
    $('pupil-mm').textContent = Number(controls.pupil.value).toFixed(1);
    app.resendGaze();
  });
  controls.preset.addEventListener('change', () => {
    // A preset resets every knob: the knob inputs go back to "the preset's value".
    for (const name of ['mar_slope', 'mar_w0_deg', 'min_probability']) {
      controls[name].value = '';
      controls[name].placeholder = 'preset';
    }
    delete controls.reconstruction.dataset.touched;
    for (const box of [controls.edges_at_mar, controls.coarse_gather]) {
      delete box.dataset.touched;
      box.checked = false;
    }
    app.sendSettings(true);
  });
  for (const el of [controls.reconstruction, controls.edges_at_mar, controls.coarse_gather]) {
    el.addEventListener('change', () => {
      el.dataset.touched = '1';
      app.sendSettings();
    });
  }
  for (const el of [controls.overlay, controls.dof, controls.predict, controls.mar_slope, controls.mar_w0_deg, controls.min_probability]) {
    el.addEventListener('change', () => app.sendSettings());
  }
  controls.ring.addEventListener('change', () => drawFovea(window.fovea.lastHeader));
  controls.auto.addEventListener('change', () => app.setAutoGaze(controls.auto.checked));
  for (const sel of [controls.scene, controls.size, controls.codec, controls.encoding]) sel.addEventListener('change', app.connect);
  $('knobs-button').addEventListener('click', () => toggle('knobs', 'knobs-button'));
  $('stats-button').addEventListener('click', () => toggle('stats', 'stats-button'));
  $('fit-button').addEventListener('click', toggleFit);
  $('fullscreen-button').addEventListener('click', toggleFullscreen);
  $('help-button').addEventListener('click', () => $('help').showModal());
  document.addEventListener('keydown', (ev) => {
    if (ev.target instanceof HTMLInputElement || ev.target instanceof HTMLSelectElement) return;
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    const actions = {
      s: () => toggle('stats', 'stats-button'),
      k: () => toggle('knobs', 'knobs-button'),
      f: toggleFullscreen,
      w: toggleFit,
      v: () => { controls.ring.checked = !controls.ring.checked; drawFovea(window.fovea.lastHeader); },
      o: () => {
        const options = [...controls.overlay.options];
        controls.overlay.value = options[(controls.overlay.selectedIndex + 1) % options.length].value;
        app.sendSettings();
      },
      a: () => { controls.auto.checked = !controls.auto.checked; app.setAutoGaze(controls.auto.checked); },
      '?': () => $('help').showModal(),
    };
    const action = actions[ev.key];
    if (action) {
      ev.preventDefault();
      action();
    }
  });
}
