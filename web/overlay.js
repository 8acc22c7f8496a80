// Rolling statistics for the stats panel: frames shown per second, gaze-to-display latency,
// bytes per second and the server's stage times, with sparklines of their recent history.

export class Stats {
  constructor(windowSize = 120) {
    this.windowSize = windowSize;
    this.latencies = [];
    this.shownAt = [];
    this.bytes = [];       // [time, bytes] of frames received in the last second
    this.dropped = 0;
    // One point per half second for the sparklines.
    this.history = { latency: [], fps: [], bytes: [], stages: [] };
  }

  frameReceived(nowMs, byteLength) {
    this.bytes.push([nowMs, byteLength]);
    while (this.bytes.length > 0 && nowMs - this.bytes[0][0] > 1000) this.bytes.shift();
  }

  // `latencyMs` is NaN for frames that answer no new gaze sample (start, settings changes):
  // they count for the frame rate, not for gaze-to-display latency.
  frameShown(nowMs, latencyMs) {
    this.shownAt.push(nowMs);
    while (this.shownAt.length > 0 && nowMs - this.shownAt[0] > 1000) this.shownAt.shift();
    if (Number.isFinite(latencyMs)) {
      this.latencies.push(latencyMs);
      if (this.latencies.length > this.windowSize) this.latencies.shift();
    }
  }

  fps(nowMs) {
    return this.shownAt.filter((t) => nowMs - t <= 1000).length;
  }

  bytesPerSecond(nowMs) {
    return this.bytes.filter(([t]) => nowMs - t <= 1000).reduce((s, [, b]) => s + b, 0);
  }

  percentile(p) {
    if (this.latencies.length === 0) return NaN;
    const sorted = [...this.latencies].sort((a, b) => a - b);
    const i = Math.min(sorted.length - 1, Math.floor((p / 100) * sorted.length));
    return sorted[i];
  }

  // Appends one point to every history (called twice a second).
  sample(nowMs, header) {
    const push = (list, v) => { list.push(v); if (list.length > 120) list.shift(); };
    push(this.history.latency, this.percentile(50));
    push(this.history.fps, this.fps(nowMs));
    push(this.history.bytes, this.bytesPerSecond(nowMs) * 8 / 1000);
    const s = header?.stages_ms;
    push(this.history.stages, s ? [s.queue, s.render, s.readback, s.encode] : [NaN, NaN, NaN, NaN]);
  }
}

const ms = (v) => (Number.isFinite(v) ? v.toFixed(1).padStart(6) : '     –');

export function overlayText(stats, header, nowMs) {
  const lines = [`fps ${String(stats.fps(nowMs)).padStart(4)}   dropped ${stats.dropped}   ${(stats.bytesPerSecond(nowMs) * 8 / 1000).toFixed(0)} kbit/s`];
  lines.push(`gaze→display p50 ${ms(stats.percentile(50))} ms  p95 ${ms(stats.percentile(95))} ms`);
  if (header) {
    const s = header.stages_ms;
    lines.push(`server queue ${ms(s.queue)} render ${ms(s.render)}`);
    lines.push(`       readback ${ms(s.readback)} encode ${ms(s.encode)} ms`);
    lines.push(`frame ${header.frame} (${header.trigger ?? 'gaze'})  ${header.width}×${header.height} ${header.codec}${header.keyframe ? ' (key)' : ''}${header.inset ? ` inset ${header.inset.width}×${header.inset.height} over ${header.inset.base_width}×${header.inset.base_height}` : ''}`);
    lines.push(`shaded ${(100 * header.sampled).toFixed(1)}%  gaze ${header.gaze.x.toFixed(3)}, ${header.gaze.y.toFixed(3)}`);
    // The server shades a foveated session's frame whole where foveation does not pay.
    if (header.unfoveated) lines.push(header.unfoveated);
    const gi = header.radiosity;
    if (gi) {
      // The scene's radiosity solve: the preview sharpens until it converges.
      const state = gi.converged ? 'converged' : 'refining';
      lines.push(`radiosity ${state}: ${gi.shots} shots, ${gi.elements} elements, ${(100 * gi.unshot).toFixed(2)}% unshot`);
    }
  }
  return lines.join('\n');
}

const COLOURS = ['#ff40c8', '#5ec8ff', '#9be36b', '#ffc247'];

// Draws one or more series (arrays of numbers, or of tuples) scaled to the canvas, newest right.
export function sparkline(canvas, values) {
  const g = canvas.getContext('2d');
  const { width: w, height: h } = canvas;
  g.clearRect(0, 0, w, h);
  const series = values.length && Array.isArray(values[0])
    ? values[0].map((_, i) => values.map((v) => v[i]))
    : [values];
  const finite = series.flat().filter(Number.isFinite);
  if (finite.length === 0) return;
  const max = Math.max(...finite, 1e-9);
  series.forEach((points, k) => {
    g.strokeStyle = COLOURS[k % COLOURS.length];
    g.lineWidth = 1.5;
    g.beginPath();
    let started = false;
    points.forEach((v, i) => {
      if (!Number.isFinite(v)) { started = false; return; }
      const x = w - (points.length - 1 - i) * (w / 119);
      const y = h - 2 - (v / max) * (h - 6);
      if (started) g.lineTo(x, y); else g.moveTo(x, y);
      started = true;
    });
    g.stroke();
  });
  g.fillStyle = '#8a93a6';
  g.font = '10px ui-monospace, monospace';
  g.fillText(max >= 100 ? max.toFixed(0) : max.toFixed(1), 2, 10);
}
