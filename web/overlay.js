// Rolling statistics for the overlay: frames shown per second and gaze-to-display latency.

export class Stats {
  constructor(windowSize = 120) {
    this.windowSize = windowSize;
    this.latencies = [];
    this.shownAt = [];
    this.dropped = 0;
  }

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

  percentile(p) {
    if (this.latencies.length === 0) return NaN;
    const sorted = [...this.latencies].sort((a, b) => a - b);
    const i = Math.min(sorted.length - 1, Math.floor((p / 100) * sorted.length));
    return sorted[i];
  }
}

const ms = (v) => (Number.isFinite(v) ? v.toFixed(1).padStart(6) : '     –');

export function overlayText(stats, header, nowMs) {
  const lines = [`fps ${String(stats.fps(nowMs)).padStart(4)}   dropped ${stats.dropped}`];
  lines.push(`gaze→display p50 ${ms(stats.percentile(50))} ms  p95 ${ms(stats.percentile(95))} ms`);
  if (header) {
    const s = header.stages_ms;
    lines.push(`server queue ${ms(s.queue)} render ${ms(s.render)} readback ${ms(s.readback)} encode ${ms(s.encode)}`);
    lines.push(`frame ${header.frame}  ${header.width}×${header.height} ${header.codec}  shaded ${(100 * header.sampled).toFixed(1)}%`);
    lines.push(`gaze ${header.gaze.x.toFixed(3)}, ${header.gaze.y.toFixed(3)}`);
    const gi = header.radiosity;
    if (gi) {
      // The scene's radiosity solve: the preview sharpens until it converges.
      const state = gi.converged ? 'converged' : 'refining';
      lines.push(`radiosity ${state}: ${gi.shots} shots, ${gi.elements} elements, ${(100 * gi.unshot).toFixed(2)}% unshot`);
    }
  }
  return lines.join('\n');
}
