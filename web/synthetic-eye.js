// The synthetic eye, the same model as src/gaze/synthetic.rs (same generator, same constants):
// fixations with drift and microsaccades, main-sequence saccades (D = 2.2·A + 21 ms,
// minimum-jerk profile), smooth pursuit, blinks, and a smoothly varying pupil.

export function mulberry32(seed) {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

export const saccadeDurationMs = (amplitudeDeg) => 2.2 * amplitudeDeg + 21.0;
const minJerk = (t) => { const x = Math.min(1, Math.max(0, t)); return x * x * x * (10 - 15 * x + 6 * x * x); };

export class SyntheticEye {
  // display: {widthCm, distanceCm, aspect (height/width)}
  constructor(seed, display) {
    this.rand = mulberry32(seed);
    const halfW = Math.atan(0.5 * display.widthCm / display.distanceCm) * 180 / Math.PI;
    const halfH = Math.atan(0.5 * display.widthCm * display.aspect / display.distanceCm) * 180 / Math.PI;
    this.display = display;
    this.half = [halfW * 0.9, halfH * 0.9];
    this.pos = [0, 0];
    this.phase = { kind: 'fixation', until: 300, nextMicro: 400 };
    this.pupil = 4.0;
    this.nextBlink = this.range(2000, 6000);
    this.last = 0;
  }

  range(lo, hi) { return lo + (hi - lo) * this.rand(); }
  normal() { let s = 0; for (let i = 0; i < 4; i++) s += this.rand(); return s * Math.sqrt(3) - 2 * Math.sqrt(3); }
  clamp(p) { return [Math.max(-this.half[0], Math.min(this.half[0], p[0])), Math.max(-this.half[1], Math.min(this.half[1], p[1]))]; }

  startNext(t) {
    if (this.rand() < 0.15) {
      const speed = this.range(5, 20);
      const angle = this.range(0, 2 * Math.PI);
      this.phase = { kind: 'pursuit', velocity: [speed * Math.cos(angle), speed * Math.sin(angle)], until: t + this.range(500, 1500) };
    } else {
      const to = [this.range(-1, 1) * this.half[0], this.range(-1, 1) * this.half[1]];
      const a = Math.hypot(to[0] - this.pos[0], to[1] - this.pos[1]);
      this.phase = { kind: 'saccade', from: this.pos, to, start: t, duration: saccadeDurationMs(a) };
    }
  }

  // {deg: [x, y] or null during blinks, pupil: mm or null} at time t (ms, non-decreasing).
  step(t) {
    const dt = Math.max(0, t - this.last);
    this.last = t;
    const theta = dt / 2000;
    this.pupil += theta * (4 - this.pupil) + 0.8 * Math.sqrt(2 * theta) * this.normal();
    this.pupil = Math.min(8, Math.max(2, this.pupil));
    for (;;) {
      const p = this.phase;
      if (p.kind === 'blink') {
        if (t < p.until) return { deg: null, pupil: null };
        this.pos = p.resume;
        this.nextBlink = t + this.range(2000, 6000);
        this.phase = { kind: 'fixation', until: t + this.range(150, 450), nextMicro: t + 400 };
      } else if (p.kind === 'saccade') {
        const s = minJerk((t - p.start) / p.duration);
        this.pos = [p.from[0] + (p.to[0] - p.from[0]) * s, p.from[1] + (p.to[1] - p.from[1]) * s];
        if (t >= p.start + p.duration) {
          this.pos = p.to;
          this.phase = { kind: 'fixation', until: t + this.range(150, 450), nextMicro: t + this.range(300, 900) };
          continue;
        }
        return { deg: this.pos, pupil: this.pupil };
      } else if (p.kind === 'pursuit') {
        this.pos = this.clamp([this.pos[0] + p.velocity[0] * dt / 1000, this.pos[1] + p.velocity[1] * dt / 1000]);
        if (t >= p.until) this.phase = { kind: 'fixation', until: t + this.range(150, 450), nextMicro: t + 400 };
        return { deg: this.pos, pupil: this.pupil };
      } else {
        if (t >= this.nextBlink) { this.phase = { kind: 'blink', until: t + this.range(100, 300), resume: this.pos }; continue; }
        if (t >= p.until) { this.startNext(t); continue; }
        const k = 0.1 * Math.sqrt(dt / 1000);
        const dx = k * this.normal();
        const dy = k * this.normal();
        this.pos = this.clamp([this.pos[0] + dx, this.pos[1] + dy]);
        if (t >= p.nextMicro) {
          const a = this.range(0.1, 0.5);
          const angle = this.range(0, 2 * Math.PI);
          const to = this.clamp([this.pos[0] + a * Math.cos(angle), this.pos[1] + a * Math.sin(angle)]);
          this.phase = { kind: 'saccade', from: this.pos, to, start: t, duration: saccadeDurationMs(a) };
          continue;
        }
        return { deg: this.pos, pupil: this.pupil };
      }
    }
  }

  // Degrees from the screen centre → normalised frame coordinates.
  toFrame(deg) {
    const d = this.display;
    const xCm = d.distanceCm * Math.tan(deg[0] * Math.PI / 180);
    const yCm = d.distanceCm * Math.tan(deg[1] * Math.PI / 180);
    return [0.5 + xCm / d.widthCm, 0.5 + yCm / (d.widthCm * d.aspect)];
  }
}
