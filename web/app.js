// Fovea thin client: one WebSocket, the mouse (or a synthetic eye) as gaze, frames drawn
// newest-first. Protocol v1: JSON text both ways; frames are binary
// [u32 LE header length][JSON header][image]. Every (re)connect starts a fresh session state;
// a lost connection is retried with backoff, and a full server is retried too.

import { H264Player, h264Supported } from './h264.js';
import { composeInset, composePacked } from './inset.js';
import { Stats, overlayText, sparkline } from './overlay.js';
import { SyntheticEye } from './synthetic-eye.js';
import { bindControls, controls, drawFovea, showBanner, hideBanner, setStatus } from './ui.js';

const canvas = document.getElementById('view');
const ctx = canvas.getContext('2d');

const BACKOFF_MS = [1000, 2000, 4000, 8000, 10000];
const SLOW_FRAME_MS = 500;
// The inset's width, degrees, when the encoding menu asks for one.
const INSET_DEG = 20;

// Exposed for people poking in the console and for the browser tests.
const state = {
  ws: null,
  welcome: null,
  seq: 0,
  lastHeader: null,   // header of the frame on screen (this session)
  framesShown: 0,     // this session
  totalFrames: 0,     // every session of this page
  connects: 0,
  moves: 0,           // sessions moved to another instance after a goodbye
  moving: false,      // a goodbye came and no new session has said welcome yet
  pending: null,      // decoded frame waiting for the next animation frame
  player: null,       // the H.264 decoder of an h264 session
  codecNote: null,    // why the page shows JPEG where H.264 was chosen (or `auto`)
  h264Failed: null,   // why this page gave up on its H.264 decoder (until reloaded)
  lastImage: null,    // an inset frame's image bytes (both images), or its decoded H.264
                      // picture where keepPictures is set: for the browser tests
  keepPictures: false,
  drawScheduled: false,
  stats: new Stats(),
  errors: [],
  waitingSince: null, // when we asked for a frame that has not come yet
  retry: null,        // { at, attempt, reason } while a reconnect is scheduled
  saidHello: false,   // this session's hello is out: other messages may follow
  gazeHeld: false,    // a gaze came before the hello, to send after it
};
window.fovea = state;

// Until the session's hello is out (the page may still be asking WebCodecs what it decodes)
// the server would refuse anything else with no_hello: it is dropped, and a gaze held back is
// sent right after the hello.
function send(msg) {
  if (!state.ws || state.ws.readyState !== WebSocket.OPEN) return;
  if (msg.type !== 'hello' && !state.saidHello) return;
  state.ws.send(JSON.stringify(msg));
}

function ack(frame, dropped) {
  send({ type: 'ack', frame, t_ms: performance.now(), dropped });
}

// Everything that belongs to one session starts afresh: frame numbers restart at 1.
function resetSession() {
  if (state.pending) state.pending.bitmap.close();
  if (state.player) state.player.close();
  state.player = null;
  Object.assign(state, {
    welcome: null, lastHeader: null, pending: null, framesShown: 0, stats: new Stats(), waitingSince: null,
  });
}

let retryTimer = null;
let attempt = 0;

export function connect() {
  clearTimeout(retryTimer);
  state.retry = null;
  if (state.ws) {
    const old = state.ws;
    state.ws = null;
    old.close(1000, 'reconnecting');
  }
  resetSession();
  state.saidHello = false;
  state.gazeHeld = false;
  state.waitingSince = performance.now(); // the first frame is awaited from here
  const [width, height] = controls.size.value.split('x').map(Number);
  // Assigning a canvas's size clears it: only when it changes, so the last frame stays up
  // while the page moves to another instance or reconnects.
  if (canvas.width !== width) canvas.width = width;
  if (canvas.height !== height) canvas.height = height;
  const proto = location.protocol === 'https:' ? 'wss' : 'ws';
  // A server started with --token wants it: the page's own ?token= is passed on.
  const token = new URLSearchParams(location.search).get('token');
  const query = token ? `?token=${encodeURIComponent(token)}` : '';
  const ws = new WebSocket(`${proto}://${location.host}/ws${query}`);
  ws.binaryType = 'arraybuffer';
  state.ws = ws;
  state.connects += 1;
  setStatus('connecting…', 'connecting');
  ws.onopen = async () => {
    const codec = await chooseCodec(controls.codec.value, width, height);
    if (state.ws !== ws) return;
    send({
      type: 'hello', v: 1, scene: controls.scene.value, width, height, preset: controls.preset.value,
      codec, quality: 85, max_in_flight: 2, ...encodingFields(controls.encoding.value),
    });
    state.saidHello = true;
    sendSettings();
    if (state.gazeHeld) resendGaze();
  };
  ws.onmessage = (ev) => {
    if (state.ws !== ws) return;
    if (typeof ev.data === 'string') onText(ev.data); else onFrame(ev.data, ws);
  };
  ws.onclose = (ev) => {
    if (state.ws !== ws) return; // replaced on purpose
    state.ws = null;
    resetSession(); // the session is over: nothing of it may linger into the next
    const why = state.moving ? 'moving to another instance'
      : `connection closed${ev.reason ? ` (${ev.reason})` : ''}`;
    scheduleRetry(ev.code === 1013 ? 'server full' : why, ev.code === 1013);
  };
}

// For `h264` and `auto` (the default: H.264 had JPEG's latency for about a quarter of its
// bytes, docs/encoding.md): H.264 where this browser decodes it with WebCodecs and the size is
// even, as 4:2:0 needs, and its decoder has not failed on this page; JPEG otherwise, saying
// why in the stats (and, where H.264 was chosen, in a banner after the welcome).
async function chooseCodec(chosen, width, height) {
  state.codecNote = null;
  if (chosen !== 'h264' && chosen !== 'auto') return chosen;
  const even = width % 2 === 0 && height % 2 === 0;
  if (even && !state.h264Failed && await h264Supported(width, height)) return 'h264';
  if (state.h264Failed) state.codecNote = 'its decoder kept failing here (reload to retry)';
  else if (even) state.codecNote = 'this browser has no WebCodecs H.264 decoder';
  else state.codecNote = `4:2:0 needs an even size, not ${width}×${height}`;
  return 'jpeg';
}

// The hello's foveated-encoding fields for the page's encoding choice.
function encodingFields(choice) {
  if (choice === 'lowpass') return { foveated_encoding: true };
  return choice === 'inset' ? { inset_deg: INSET_DEG } : {};
}

function scheduleRetry(reason, full) {
  const delay = BACKOFF_MS[Math.min(attempt, BACKOFF_MS.length - 1)];
  attempt += 1;
  state.retry = { at: performance.now() + delay, attempt, reason };
  retryTimer = setTimeout(connect, delay);
  showRetry(full);
}

function showRetry(full) {
  if (!state.retry) return;
  const secs = Math.max(0, Math.ceil((state.retry.at - performance.now()) / 1000));
  const text = full ? `server full, retrying in ${secs} s` : `${state.retry.reason}: reconnecting in ${secs} s`;
  setStatus(full ? 'server full' : 'reconnecting', 'waiting');
  showBanner(text, 'info');
  if (secs > 0) setTimeout(() => showRetry(full), 1000);
}

function onText(text) {
  const msg = JSON.parse(text);
  if (msg.type === 'welcome') {
    attempt = 0;
    state.moving = false;
    hideBanner();
    // After the welcome, which clears the connection's banners.
    if (state.codecNote && controls.codec.value === 'h264') {
      showBanner(`H.264 cannot be shown (${state.codecNote}): showing JPEG`, 'info', 6000);
    }
    state.welcome = msg;
    setStatus(`live · session ${msg.session}`, 'live');
    document.getElementById('adapter').textContent = `GPU: ${msg.adapter}`;
    const fill = (sel, names) => {
      const current = sel.value;
      sel.replaceChildren(...names.map((name) => new Option(name, name, false, name === current)));
    };
    fill(controls.scene, msg.scenes);
    fill(controls.preset, msg.presets);
    if (msg.codec === 'h264') {
      state.player = new H264Player(msg.width, msg.height, {
        onPicture: presentPicture,
        onDropped: (header) => { state.stats.dropped += 1; ack(header.frame, true); },
        askKeyframe: () => send({ type: 'keyframe' }),
        onFailed: (why) => {
          console.warn(`giving up on H.264: ${why}`);
          state.h264Failed = why;
          connect();
        },
      });
    }
    const link = document.getElementById('recording');
    link.hidden = !msg.recording;
    if (msg.recording) link.href = msg.recording;
  } else if (msg.type === 'goodbye') {
    // The server is draining: frames keep coming until we leave, so open the next session
    // (the balancer picks another instance) after the delay it asked for.
    showBanner('server is being replaced: moving to another instance…', 'info', 4000);
    state.moves += 1;
    state.moving = true; // until a session elsewhere says welcome
    clearTimeout(retryTimer);
    retryTimer = setTimeout(connect, msg.retry_ms);
  } else if (msg.type === 'error') {
    state.errors.push(msg);
    console.warn(`server error ${msg.code}: ${msg.message}`);
    // A refused hello is followed by no_hello replies to the settings sent behind it: they
    // would hide the refusal, which is what the viewer needs to read.
    if (msg.code === 'no_hello' && !state.welcome) return;
    if (msg.code === 'over_budget' && !state.welcome) {
      setStatus('refused: over the frame budget', 'waiting');
      showBanner(`server: ${msg.message}`, 'error');
      return;
    }
    showBanner(`server: ${msg.message}`, 'error', 8000);
  }
}

// `ws`: the socket the frame came on. A JPEG decodes asynchronously; if the page has moved to
// another session meanwhile, the frame belongs to none: it is not drawn, and not acknowledged,
// since its number would be a stranger's in the new session (which answers with bad_ack).
async function onFrame(buffer, ws) {
  const view = new DataView(buffer);
  const headerLen = view.getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, headerLen)));
  state.stats.frameReceived(performance.now(), buffer.byteLength);
  if (header.codec === 'h264') {
    // Every frame is decoded (the next ones refer to it); drawing stays newest-first.
    if (state.player) state.player.push(header, new Uint8Array(buffer, 4 + headerLen));
    else ack(header.frame, true);
    return;
  }
  const type = header.codec === 'png' ? 'image/png' : 'image/jpeg';
  const bytes = new Uint8Array(buffer, 4 + headerLen);
  let bitmap;
  try {
    bitmap = header.inset ? await composeInset(header, bytes, type)
      : await createImageBitmap(new Blob([bytes], { type }));
  } catch (e) {
    console.warn(`frame ${header.frame} did not decode`, e);
    if (state.ws === ws) ack(header.frame, true);
    return;
  }
  if (state.ws !== ws) {
    bitmap.close();
    return;
  }
  // An inset frame's bytes stay with it, for the browser test that checks its composition.
  present(header, bitmap, header.inset ? bytes : null);
}

// A decoded H.264 picture: an inset frame's picture holds both parts, composed here (the
// browser tests set `keepPictures` to check the composition against the picture itself).
async function presentPicture(header, picture) {
  if (!header.inset) return present(header, picture);
  const ws = state.ws; // as in onFrame: a session left while composing gets nothing of it
  let bitmap, image = null;
  try {
    if (state.keepPictures) image = await createImageBitmap(picture);
    bitmap = composePacked(header, picture);
  } catch (e) {
    console.warn(`frame ${header.frame} did not compose`, e);
    if (state.ws === ws) ack(header.frame, true);
    return;
  } finally {
    picture.close();
  }
  if (state.ws !== ws) {
    bitmap.close();
    return;
  }
  present(header, bitmap, image);
}

// Draw only the newest frame; anything it overtakes is acknowledged as dropped so its
// credit returns to the server at once. `bitmap`: an ImageBitmap or a VideoFrame.
function present(header, bitmap, image = null) {
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
  state.pending = { header, bitmap, image };
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
  // Same clock on both ends: t_ms came from this page's performance.now(). Only a frame that
  // answers a new sample measures gaze-to-display; one made for a settings change shows an
  // older sample again.
  const answersGaze = (frame.header.trigger ?? 'gaze') === 'gaze' && frame.header.t_ms != null;
  state.stats.frameShown(now, answersGaze ? now - frame.header.t_ms : NaN);
  state.lastHeader = frame.header;
  state.lastImage = frame.image;
  state.framesShown += 1;
  state.totalFrames += 1;
  state.waitingSince = null;
  ack(frame.header.frame, false);
  drawFovea(frame.header);
  document.getElementById('overlay').textContent = overlayText(state.stats, frame.header, now);
}

// Knobs that change live, without reconnecting. A knob left empty keeps the preset's value.
export function sendSettings(presetChanged = false) {
  const msg = { type: 'settings', overlay: controls.overlay.value, dof: controls.dof.checked, prediction: controls.predict.checked };
  if (presetChanged || !state.welcome) msg.preset = controls.preset.value;
  for (const name of ['mar_slope', 'mar_w0_deg', 'min_probability']) {
    const v = controls[name].value;
    if (v !== '' && !presetChanged) msg[name] = Number(v);
  }
  if (controls.reconstruction.dataset.touched && !presetChanged) msg.reconstruction = controls.reconstruction.value;
  for (const name of ['edges_at_mar', 'coarse_gather']) {
    if (controls[name].dataset.touched && !presetChanged) msg[name] = controls[name].checked;
  }
  send(msg);
  expectFrame();
}

// A camera move (orbit, pan, dolly or reset); the server answers with a new frame.
export function sendCamera(move) {
  send({ type: 'camera', ...move });
  expectFrame();
}

function expectFrame() {
  if (state.waitingSince == null) state.waitingSince = performance.now();
}

let lastGaze = { x: 0.5, y: 0.5 };
export function sendGaze(x, y, pupil) {
  lastGaze = { x, y };
  if (state.ws && !state.saidHello) state.gazeHeld = true;
  send({ type: 'gaze', seq: ++state.seq, t_ms: performance.now(), x, y, pupil_mm: pupil ?? Number(controls.pupil.value) });
}

export function resendGaze() {
  sendGaze(lastGaze.x, lastGaze.y);
}

// Auto gaze: the synthetic eye at 120 Hz. Blinks send nothing (the server keeps the last gaze).
let autoTimer = null;
export function setAutoGaze(on) {
  clearInterval(autoTimer);
  autoTimer = null;
  if (!on) return;
  const eye = new SyntheticEye(1, { widthCm: 53, distanceCm: 60, aspect: canvas.height / canvas.width });
  const t0 = performance.now();
  autoTimer = setInterval(() => {
    const { deg, pupil } = eye.step(performance.now() - t0);
    if (!deg) return;
    const [x, y] = eye.toFrame(deg);
    const clamp = (v) => Math.min(1, Math.max(0, v));
    sendGaze(clamp(x), clamp(y), pupil);
  }, 8);
}

// Four times a second: stats panel, sparklines, and the progress indicator for slow frames.
setInterval(() => {
  const now = performance.now();
  state.stats.sample(now, state.lastHeader);
  const note = state.codecNote ? `\nJPEG, not H.264: ${state.codecNote}` : '';
  document.getElementById('overlay').textContent = overlayText(state.stats, state.lastHeader, now) + note;
  const h = state.stats.history;
  sparkline(document.getElementById('spark-latency'), h.latency);
  sparkline(document.getElementById('spark-fps'), h.fps);
  sparkline(document.getElementById('spark-bytes'), h.bytes);
  sparkline(document.getElementById('spark-stages'), h.stages);
  const progress = document.getElementById('progress');
  const waited = state.waitingSince == null || !state.ws ? 0 : now - state.waitingSince;
  progress.hidden = waited < SLOW_FRAME_MS;
  if (!progress.hidden) document.getElementById('progress-text').textContent = `rendering… ${(waited / 1000).toFixed(1)} s`;
}, 250);

// ?scene=…&size=WxH&preset=…&codec=…&encoding=… preselect the controls, so a view can be shared as a link.
const params = new URLSearchParams(location.search);
for (const name of ['scene', 'size', 'preset', 'codec', 'encoding']) {
  const v = params.get(name);
  if (v == null) continue;
  const sel = controls[name];
  if (![...sel.options].some((o) => o.value === v)) sel.add(new Option(v, v));
  sel.value = v;
}
bindControls({ connect, sendSettings, sendGaze, resendGaze, setAutoGaze, expectFrame, sendCamera });
connect();
