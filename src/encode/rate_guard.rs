//! Which quantiser range an H.264 stream encodes with: quality while the picture is still,
//! the bitrate target once it moves.
//!
//! openh264 picks a keyframe's quantiser from the bits per pixel and then moves each P-frame's
//! only a few steps from the last, so with the quantiser free (up to 51) a still view stays at
//! the keyframe's coarse first pass (foveal FLIP 0.069 against 0.066 with QP ≤ 22 on `gallery`
//! at 640×480, 4000 kbit/s, for more bytes). But QP ≤ 22 cannot meet a target once the whole
//! picture changes: with the camera turning 20°/s, 1280×720 `gallery` came out at 22.9 Mbit/s
//! whatever the target (500 to 8000 kbit/s). The quantiser range cannot change without a new
//! encoder (openh264 copies it only when it resets, with a keyframe), so the guard switches
//! rarely and at a keyframe's cost:
//!
//! * **quality → target** when the last `WINDOW` P-frames came at a median rate over `OVER`
//!   times the target (each frame's bytes over the time since the one before, so a slow
//!   renderer's frames get the time they took; the median, so one saccade's large frame does
//!   not count): a moving picture; the next frame is a keyframe of a new encoder whose
//!   quantiser is free, and rate control holds the target from there;
//! * **target → quality** only at a check (every 2 s of the stream, `h264::GUARD_CHECK_MS`, and
//!   at any keyframe sent anyway): where the last `WINDOW` P-frames came at a median rate under
//!   `CALM` of the target (the picture is still enough that QP ≤ 22 fits), or else as a try, at
//!   the first such check and then, each time a try overruns again within `TRIAL` P-frames, at
//!   every 2nd, 4th, up to `MAX_TRY_EVERY`th one. (The checks were the periodic keyframes
//!   until those became 10 s apart: a check that keeps the range costs nothing.)
//!   The rate alone cannot tell: a still picture with the quantiser free spends 0.35 of a
//!   4000 kbit/s target but 0.64 of a 1000 kbit/s one, about what QP ≤ 22 would (the free
//!   range stays near its keyframe's quality instead: foveal FLIP 0.100 against 0.077, 640×480
//!   `gallery`). Through a long camera move a failed try costs `WINDOW` frames over the target
//!   and one keyframe every 16 s; after the move the fine range is back within that.
//!
//! `OVER`, `CALM` and `WINDOW` were set from those runs at 640×480 along the 1000 Hz recording;
//! docs/encoding.md reports 1280×720 along the 500 Hz one.
//!
//! Where the target pays for it (`FINE_BITS_PER_PIXEL`) the quality range is QP 10 alone:
//! a still picture's last refinement, which the fovea's FLIP needs, for a larger keyframe.

use std::collections::VecDeque;

/// The quantiser range (H.264: 0 finest … 51 coarsest).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QpCap {
    /// QP 10–22, or 10 alone where the target pays for it (`FINE_BITS_PER_PIXEL`): a still
    /// picture refines, the target may be overrun.
    Quality,
    /// QP 10–51: the target holds, a still picture stays near its keyframe's quality.
    Target,
}

/// From this many bits per pixel of a 60 fps frame (1280×720 at 5530 kbit/s, 640×480 at
/// 1843) the quality range is QP 10 alone. A still picture keeps its keyframe's quality, and
/// with the range's top at 22 a still `bunny-marble` stopped at foveal FLIP 0.0204 however
/// much the target allowed (0.0203 at 16, 0.0199 at 10, 1280×720 at 8000 kbit/s; the
/// stream's rate fell, 814 → 715 kbit/s, as its P-frames had less to refine). The price is
/// the keyframe (11 → 19 kB there; 65 → 141 kB on `gallery`) and, before the guard frees the
/// quantiser, a moving picture's first frames (docs/encoding.md has both). Set between the
/// default target at 720p (0.072) and 8000 kbit/s there (0.145), on `bunny-marble` only.
pub const FINE_BITS_PER_PIXEL: f64 = 0.1;

impl QpCap {
    pub const MIN_QP: u8 = 10;

    /// The range's top for a target of `kbps` at `width`×`height`.
    pub fn max_qp(self, kbps: u32, width: u32, height: u32) -> u8 {
        match self {
            QpCap::Quality if bits_per_pixel(kbps, width, height) >= FINE_BITS_PER_PIXEL => {
                Self::MIN_QP
            }
            QpCap::Quality => 22,
            QpCap::Target => 51,
        }
    }
}

/// A target's bits per pixel of a frame at 60 fps (0 for an empty picture).
fn bits_per_pixel(kbps: u32, width: u32, height: u32) -> f64 {
    let pixels = f64::from(width) * f64::from(height);
    if pixels > 0.0 {
        f64::from(kbps) * 1000.0 / (pixels * 60.0)
    } else {
        0.0
    }
}

/// The P-frames whose median rate decides.
pub const WINDOW: usize = 6;
/// Quality → target above this many times the target rate.
pub const OVER: f64 = 2.0;
/// Target → quality (at a check) under this share of the target rate.
pub const CALM: f64 = 0.5;

/// What a stream should do with its encoder before the next frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    Keep,
    /// A new encoder with this range (its first frame is a keyframe).
    To(QpCap),
}

/// A try of the fine range that overruns within this many P-frames failed.
pub const TRIAL: usize = 2 * WINDOW;
/// The most checks between tries.
pub const MAX_TRY_EVERY: u32 = 8;

/// One stream's recent P-frames (bytes, ms since the frame before) and its current range.
#[derive(Debug, Clone)]
pub struct RateGuard {
    cap: QpCap,
    recent: VecDeque<(usize, u64)>,
    /// P-frames since the last switch.
    since_switch: usize,
    /// At the fine range as a try (not since the stream began).
    trying: bool,
    /// Checks at the target range since the last switch, and how many to wait before trying
    /// the fine range again.
    waited: u32,
    try_every: u32,
}

impl Default for RateGuard {
    fn default() -> Self {
        RateGuard {
            cap: QpCap::Quality,
            recent: VecDeque::with_capacity(WINDOW),
            since_switch: 0,
            trying: false,
            waited: 0,
            try_every: 1,
        }
    }
}

impl RateGuard {
    pub fn cap(&self) -> QpCap {
        self.cap
    }

    /// Records an encoded frame of `bytes` that came `ms` after the one before. Keyframes cost
    /// what a picture costs whatever it does, so only P-frames say whether the picture moves.
    pub fn record(&mut self, bytes: usize, keyframe: bool, ms: u64) {
        if keyframe {
            return;
        }
        self.since_switch += 1;
        if self.recent.len() == WINDOW {
            self.recent.pop_front();
        }
        self.recent.push_back((bytes, ms));
    }

    /// Before encoding a frame: `kbps` is the target, `check` that the range may go back to
    /// quality at this frame (a check is due, or the frame is a keyframe anyway).
    pub fn decide(&mut self, kbps: f64, check: bool) -> Switch {
        if !(kbps > 0.0) {
            return Switch::Keep;
        }
        let rate = self.rate();
        match self.cap {
            QpCap::Quality if rate.is_some_and(|r| r > OVER * kbps) => {
                // A try that overran at once waits twice as long for the next.
                self.try_every = if self.trying && self.since_switch <= TRIAL {
                    (self.try_every * 2).min(MAX_TRY_EVERY)
                } else {
                    1
                };
                self.switch(QpCap::Target)
            }
            QpCap::Target if check => {
                self.waited += 1;
                let calm = rate.is_some_and(|r| r < CALM * kbps);
                if calm || self.waited >= self.try_every {
                    self.switch(QpCap::Quality)
                } else {
                    Switch::Keep
                }
            }
            _ => Switch::Keep,
        }
    }

    /// The median kbit/s (bytes per ms × 8) of the last `WINDOW` P-frames, once there are that
    /// many with time between them. The median, not the mean: a saccade moves a foveated
    /// encoding's sharp region and costs one large frame (23 kB among frames of 600 bytes on
    /// `gallery` with the camera still), which is no reason to leave the fine range; a moving
    /// camera makes every frame large.
    fn rate(&self) -> Option<f64> {
        let mut rates: Vec<f64> = self
            .recent
            .iter()
            .filter(|r| r.1 > 0)
            .map(|r| r.0 as f64 * 8.0 / r.1 as f64)
            .collect();
        if rates.len() < WINDOW {
            return None;
        }
        rates.sort_by(f64::total_cmp);
        Some(0.5 * (rates[WINDOW / 2 - 1] + rates[WINDOW / 2]))
    }

    fn switch(&mut self, to: QpCap) -> Switch {
        self.trying = to == QpCap::Quality;
        self.cap = to;
        // The new encoder's frames are judged on their own.
        self.recent.clear();
        self.since_switch = 0;
        self.waited = 0;
        Switch::To(to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames 8 ms apart, so `bytes` each is `bytes` kbit/s.
    fn feed(g: &mut RateGuard, bytes: usize, n: usize) {
        for _ in 0..n {
            g.record(bytes, false, 8);
        }
    }

    #[test]
    fn a_target_that_pays_for_it_fixes_the_quality_range_at_the_floor() {
        // 1280×720: the default target keeps the top at 22, 8000 kbit/s fixes QP 10.
        assert_eq!(QpCap::Quality.max_qp(4000, 1280, 720), 22);
        assert_eq!(QpCap::Quality.max_qp(8000, 1280, 720), QpCap::MIN_QP);
        // The same target over fewer pixels pays for more.
        assert_eq!(QpCap::Quality.max_qp(4000, 640, 480), QpCap::MIN_QP);
        assert_eq!(QpCap::Quality.max_qp(1000, 640, 480), 22);
        // Just under and at the threshold (1843.2 kbit/s at 640×480).
        assert_eq!(QpCap::Quality.max_qp(1843, 640, 480), 22);
        assert_eq!(QpCap::Quality.max_qp(1844, 640, 480), QpCap::MIN_QP);
        // The target range never narrows; no picture is no budget.
        assert_eq!(QpCap::Target.max_qp(50_000, 16, 16), 51);
        assert_eq!(QpCap::Quality.max_qp(50_000, 0, 720), 22);
    }

    #[test]
    fn a_still_picture_keeps_quality_and_a_moving_one_switches_to_the_target() {
        let mut g = RateGuard::default();
        assert_eq!(g.cap(), QpCap::Quality);
        // Too few frames to judge, however large.
        feed(&mut g, 1_000_000, WINDOW - 1);
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        // Still: under the budget, and keyframes never count.
        let mut g = RateGuard::default();
        feed(&mut g, 700, WINDOW);
        g.record(50_000, true, 8);
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        assert_eq!(g.decide(1000.0, true), Switch::Keep);
        // Moving: twice the target is not yet over it, just over is.
        feed(&mut g, 2000, WINDOW);
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        feed(&mut g, 2001, WINDOW);
        assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
        assert_eq!(g.cap(), QpCap::Target);
        // The old encoder's frames are forgotten: no second switch on them.
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
    }

    #[test]
    fn the_target_returns_to_quality_only_at_a_check() {
        let mut g = RateGuard::default();
        feed(&mut g, 10_000, WINDOW);
        assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
        // Calm, but no check due: switches (each a keyframe) stay rare.
        feed(&mut g, 300, WINDOW);
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        assert_eq!(g.decide(1000.0, true), Switch::To(QpCap::Quality));
    }

    #[test]
    fn tries_of_the_fine_range_back_off_while_the_picture_keeps_moving() {
        let mut g = RateGuard::default();
        // Checks while at the target range, before each try; the picture keeps moving.
        let mut waits = Vec::new();
        for _ in 0..6 {
            feed(&mut g, 10_000, WINDOW);
            assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
            let mut n = 0;
            loop {
                // Rate control holds the target while it moves: not calm.
                feed(&mut g, 900, WINDOW);
                n += 1;
                if g.decide(1000.0, true) == Switch::To(QpCap::Quality) {
                    break;
                }
                assert!(n <= MAX_TRY_EVERY, "never tried again");
            }
            waits.push(n);
        }
        assert_eq!(waits, [1, 2, 4, 8, 8, 8]);
        // A try that holds (the move ended) resets the wait: the next move tries at once.
        feed(&mut g, 300, TRIAL + 1);
        feed(&mut g, 10_000, WINDOW);
        assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
        feed(&mut g, 900, WINDOW);
        assert_eq!(g.decide(1000.0, true), Switch::To(QpCap::Quality));
    }

    #[test]
    fn no_budget_or_no_frames_never_switches() {
        let mut g = RateGuard::default();
        assert_eq!(g.decide(1000.0, true), Switch::Keep);
        feed(&mut g, usize::MAX, WINDOW);
        for kbps in [0.0, -1.0, f64::NAN] {
            assert_eq!(g.decide(kbps, true), Switch::Keep, "{kbps}");
        }
        assert_eq!(g.decide(f64::INFINITY, true), Switch::Keep);
        // Frames with no time between them say nothing about a rate.
        let mut g = RateGuard::default();
        for _ in 0..WINDOW {
            g.record(1_000_000, false, 0);
        }
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
    }

    #[test]
    fn one_large_frame_among_small_ones_is_a_saccade_not_motion() {
        let mut g = RateGuard::default();
        feed(&mut g, 600, WINDOW - 1);
        g.record(23_000, false, 8);
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        // Half the window large is motion.
        feed(&mut g, 23_000, WINDOW / 2);
        assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
    }

    #[test]
    fn the_rate_counts_the_time_frames_took() {
        // 100 kB frames look huge at 60 fps but are 800 kbit/s a second apart (a software
        // adapter's frame rate): no switch at a 1000 kbit/s target.
        let mut g = RateGuard::default();
        for _ in 0..WINDOW {
            g.record(100_000, false, 1000);
        }
        assert_eq!(g.decide(1000.0, false), Switch::Keep);
        for _ in 0..WINDOW {
            g.record(100_000, false, 16);
        }
        assert_eq!(g.decide(1000.0, false), Switch::To(QpCap::Target));
    }
}
