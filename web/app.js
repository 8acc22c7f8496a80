// Fovea thin client: one WebSocket, the mouse as gaze, frames drawn newest-first.
// Protocol v1: JSON text both ways; frames are binary [u32 LE header length][JSON header][image].

import { Stats, overlayText } from './overlay.js';
import { SyntheticEye } from './synthetic-eye.js';

const canvas = document.getElementById('view');
const ctx = canvas.getContext('2d');
const overlay = document.getElementById('overlay');
const statusEl = document.getElementById('status');
const sceneSel = document.getElementById('scene');
const sizeSel = document.getElementById('size');
const codecSel = document.getElementById('codec');
const presetSel = document.getElementById('preset');
const overlaySel = document.getElementById('overlay-mode');
const dofBox = document.getElementById('dof');
const pupilRange = document.getElementById('pupil');
const autoBox = document.getElementById('auto-gaze');
const predictBox = document.getElementById('predict');

// Exposed for people poking in the console and for the browser test.
const state = {
  ws: null,
  welcome: null,
  seq: 0,
  lastHeader: null,   // header of the frame on screen
  framesShown: 0,
  pending: null,      // decoded frame waiting for the next animation frame
  drawScheduled: false,
  stats: new Stats(),
  errors: [],
};
window.fovea = state;

function setStatus(text, kind) {
  statusEl.textContent = text;
  statusEl.className = `status ${kind}`;
}

function send(msg) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) state.ws.send(JSON.stringify(msg));
}

function ack(frame, dropped) {
  send({ type: 'ack', frame, t_ms: performance.now(), dropped });
}

function connect() {
  if (state.ws) state.ws.close(1000, 'reconnecting');
  const [width, height] = sizeSel.value.split('x').map(Number);
  canvas.width = width;
  canvas.height = height;
  const proto = location.protocol === 'https:' ? 'wss' : 'ws';
  const ws = new WebSocket(`${proto}://${location.host}/ws`);
  ws.binaryType = 'arraybuffer';
  state.ws = ws;
  setStatus('connecting…', 'connecting');
  ws.onopen = () => {
    send({
      type: 'hello', v: 1, scene: sceneSel.value, width, height, preset: presetSel.value,
      codec: codecSel.value, quality: 85, max_in_flight: 2,
    });
    sendSettings();
  };
  ws.onmessage = (ev) => (typeof ev.data === 'string' ? onText(ev.data) : onFrame(ev.data));
  ws.onclose = (ev) => {
    if (state.ws !== ws) return;
    setStatus(`closed${ev.reason ? `: ${ev.reason}` : ''}`, 'error');
  };
  ws.onerror = () => setStatus('connection error', 'error');
}

function onText(text) {
  const msg = JSON.parse(text);
  if (msg.type === 'welcome') {
    state.welcome = msg;
    setStatus(`live · session ${msg.session}`, 'live');
    document.getElementById('adapter').textContent = `GPU: ${msg.adapter}`;
    const current = sceneSel.value;
    sceneSel.replaceChildren(...msg.scenes.map((name) => new Option(name, name, false, name === current)));
    const preset = presetSel.value;
    presetSel.replaceChildren(...msg.presets.map((name) => new Option(name, name, false, name === preset)));
  } else if (msg.type === 'error') {
    state.errors.push(msg);
    console.warn(`server error ${msg.code}: ${msg.message}`);
  }
}

async function onFrame(buffer) {
  const view = new DataView(buffer);
  const headerLen = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, headerLen)));
  const type = header.codec === 'png' ? 'image/png' : 'image/jpeg';
  let bitmap;
  try {
    bitmap = await createImageBitmap(new Blob([new Uint8Array(buffer, 4 + headerLen)], { type }));
  } catch (e) {
    console.warn(`frame ${header.frame} did not decode`, e);
    ack(header.frame, true);
    return;
  }
  // Draw only the newest frame; anything it overtakes is acknowledged as dropped so its
  // credit returns to the server at once.
  const newest = state.pending ? state.pending.header.frame : (state.lastHeader ? state.lastHeader.frame : 0);
  if (header.frame < newest) {
    bitmap.close();
    state.stats.dropped += 1;
    ack(header.frame, true);
    return;
  }
  if (state.pending) {
    state.pending.bitmap.close();
    state.stats.dropped += 1;
    ack(state.pending.header.frame, true);
  }
  state.pending = { header, bitmap };
  if (!state.drawScheduled) {
    state.drawScheduled = true;
    requestAnimationFrame(draw);
  }
}

function draw() {
  state.drawScheduled = false;
  const frame = state.pending;
  if (!frame) return;
  state.pending = null;
  ctx.drawImage(frame.bitmap, 0, 0, canvas.width, canvas.height);
  frame.bitmap.close();
  const now = performance.now();
  // Same clock on both ends: t_ms came from this page's performance.now().
  const latency = frame.header.t_ms == null ? NaN : now - frame.header.t_ms;
  state.stats.frameShown(now, latency);
  state.lastHeader = frame.header;
  state.framesShown += 1;
  ack(frame.header.frame, false);
  overlay.textContent = overlayText(state.stats, frame.header, now);
}

// Knobs that change live, without reconnecting.
function sendSettings() {
  send({ type: 'settings', preset: presetSel.value, overlay: overlaySel.value, dof: dofBox.checked, prediction: predictBox.checked });
}

let lastGaze = { x: 0.5, y: 0.5 };
function sendGaze(x, y) {
  lastGaze = { x, y };
  send({ type: 'gaze', seq: ++state.seq, t_ms: performance.now(), x, y, pupil_mm: Number(pupilRange.value) });
}

canvas.addEventListener('mousemove', (ev) => {
  if (autoBox.checked) return;
  const r = canvas.getBoundingClientRect();
  const clamp = (v) => Math.min(1, Math.max(0, v));
  sendGaze(clamp((ev.clientX - r.left) / r.width), clamp((ev.clientY - r.top) / r.height));
});

pupilRange.addEventListener('input', () => {
  document.getElementById('pupil-mm').textContent = Number(pupilRange.value).toFixed(1);
  sendGaze(lastGaze.x, lastGaze.y);
});
for (const el of [presetSel, overlaySel, dofBox, predictBox]) el.addEventListener('change', sendSettings);

// Auto gaze: the synthetic eye at 120 Hz. Blinks send nothing (the server keeps the last gaze).
let autoTimer = null;
autoBox.addEventListener('change', () => {
  clearInterval(autoTimer);
  autoTimer = null;
  if (!autoBox.checked) return;
  const eye = new SyntheticEye(1, { widthCm: 53, distanceCm: 60, aspect: canvas.height / canvas.width });
  const t0 = performance.now();
  autoTimer = setInterval(() => {
    const { deg, pupil } = eye.step(performance.now() - t0);
    if (!deg) return;
    const [x, y] = eye.toFrame(deg);
    const clamp = (v) => Math.min(1, Math.max(0, v));
    lastGaze = { x: clamp(x), y: clamp(y) };
    send({ type: 'gaze', seq: ++state.seq, t_ms: performance.now(), x: lastGaze.x, y: lastGaze.y, pupil_mm: pupil });
  }, 8);
});
for (const sel of [sceneSel, sizeSel, codecSel]) sel.addEventListener('change', connect);
setInterval(() => {
  overlay.textContent = overlayText(state.stats, state.lastHeader, performance.now());
}, 500);
connect();
