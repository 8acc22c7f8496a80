//! A session's pacing, as a pure state machine: credits, coalescing, what triggers a frame,
//! and stall detection. No socket, no GPU and no clock of its own (every call takes `now`), so
//! its unit tests below run anywhere.
//!
//! Only the newest gaze sample matters: samples that arrive while a frame is being made are
//! coalesced into the next one, never queued. A frame is made when there is something new to
//! show (a sample, a settings change, or the session's start) and the client has a free credit
//! (`max_in_flight` minus frames not yet acknowledged), so a slow client simply gets fewer
//! frames.

use std::collections::BTreeSet;
use std::time::{Duration, Instant};

use crate::protocol::{Gaze, Trigger};

/// What the next frame answers, and since when it has been waiting.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pending {
    trigger: Trigger,
    since: Instant,
}

/// A frame to make: its number, the gaze it shows and what it answers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ticket {
    pub frame: u64,
    /// The newest sample (or, for a frame without a new one, the last shown; `None` before
    /// any gaze arrived).
    pub gaze: Option<Gaze>,
    pub trigger: Trigger,
    /// When the sample, settings change or start that this frame answers arrived: the
    /// frame's queue stage starts here.
    pub arrived: Instant,
    /// Samples received so far (lost = sent − this).
    pub samples: u64,
}

/// What became of one gaze sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GazeOutcome {
    /// It replaced a sample that had not been rendered yet.
    pub coalesced: bool,
    /// …and the client had no credit, so that earlier sample's frame was skipped.
    pub skipped: bool,
}

#[derive(Debug)]
pub struct Pacer {
    max_in_flight: usize,
    stall_timeout: Duration,
    /// Frames sent (or being made) and not yet acknowledged: each holds one credit.
    unacked: BTreeSet<u64>,
    frames_made: u64,
    latest: Option<Gaze>,
    shown: Option<Gaze>,
    pending: Option<Pending>,
    /// Last sign of life while frames are outstanding (an ack, or a frame sent).
    last_progress: Instant,
    pub samples: u64,
    pub coalesced: u64,
}

impl Pacer {
    /// A session that has just said hello: its first frame shows the scene before any gaze.
    pub fn new(max_in_flight: u32, stall_timeout: Duration, now: Instant) -> Pacer {
        Pacer {
            max_in_flight: max_in_flight as usize,
            stall_timeout,
            unacked: BTreeSet::new(),
            frames_made: 0,
            latest: None,
            shown: None,
            pending: Some(Pending {
                trigger: Trigger::Start,
                since: now,
            }),
            last_progress: now,
            samples: 0,
            coalesced: 0,
        }
    }

    pub fn on_gaze(&mut self, gaze: Gaze, now: Instant) -> GazeOutcome {
        self.samples += 1;
        let coalesced = self.latest.is_some();
        let skipped = coalesced && self.unacked.len() >= self.max_in_flight;
        if coalesced {
            self.coalesced += 1;
        }
        self.latest = Some(gaze);
        // The frame answers the newest sample, so its wait starts with that sample.
        self.pending = Some(Pending {
            trigger: Trigger::Gaze,
            since: now,
        });
        GazeOutcome { coalesced, skipped }
    }

    /// Settings changed: the next frame answers them unless a newer sample is waiting.
    pub fn on_settings(&mut self, now: Instant) {
        if self.pending.is_none_or(|p| p.trigger != Trigger::Gaze) {
            self.pending = Some(Pending {
                trigger: Trigger::Settings,
                since: now,
            });
        }
    }

    /// Returns the credit of `frame`; `Err(frames made so far)` if it was not outstanding.
    pub fn on_ack(&mut self, frame: u64, now: Instant) -> Result<(), u64> {
        if self.unacked.remove(&frame) {
            self.last_progress = now;
            Ok(())
        } else {
            Err(self.frames_made)
        }
    }

    /// The next frame to make, if something is new and a credit is free.
    pub fn next_frame(&mut self) -> Option<Ticket> {
        if self.unacked.len() >= self.max_in_flight {
            return None;
        }
        let pending = self.pending.take()?;
        if let Some(g) = self.latest.take() {
            self.shown = Some(g);
        }
        self.frames_made += 1;
        self.unacked.insert(self.frames_made);
        Some(Ticket {
            frame: self.frames_made,
            gaze: self.shown,
            trigger: pending.trigger,
            arrived: pending.since,
            samples: self.samples,
        })
    }

    /// A frame is ready for the socket, or reached it: the stall clock restarts, so a frame made
    /// long after the last ack gives the client a full `stall_timeout` to acknowledge it.
    pub fn frame_out(&mut self, now: Instant) {
        self.last_progress = now;
    }

    /// A frame failed and will never be sent: its credit comes back so the session goes on.
    pub fn frame_failed(&mut self, frame: u64) {
        self.unacked.remove(&frame);
    }

    /// When the client counts as stalled: frames outstanding, none being made, and no ack
    /// since `stall_timeout`. `None` while nothing is outstanding or a frame is being made.
    pub fn stall_deadline(&self, making: bool) -> Option<Instant> {
        (!self.unacked.is_empty() && !making).then(|| self.last_progress + self.stall_timeout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaze(seq: u64) -> Gaze {
        Gaze {
            seq,
            t_ms: seq as f64,
            x: 0.5,
            y: 0.5,
            pupil_mm: None,
            sample_t_ms: None,
        }
    }

    fn ms(t0: Instant, ms: u64) -> Instant {
        t0 + Duration::from_millis(ms)
    }

    const STALL: Duration = Duration::from_secs(10);

    #[test]
    fn the_first_frame_shows_the_scene_before_any_gaze() {
        let t0 = Instant::now();
        let mut p = Pacer::new(2, STALL, t0);
        let t = p.next_frame().unwrap();
        assert_eq!((t.frame, t.gaze, t.trigger), (1, None, Trigger::Start));
        assert_eq!(t.arrived, t0);
        assert!(p.next_frame().is_none(), "nothing new: no second frame");
    }

    #[test]
    fn samples_arriving_while_out_of_credit_coalesce_into_one_frame() {
        let t0 = Instant::now();
        let mut p = Pacer::new(1, STALL, t0);
        let first = p.next_frame().unwrap();
        assert!(!p.on_gaze(gaze(1), ms(t0, 5)).coalesced);
        let o = p.on_gaze(gaze(2), ms(t0, 6));
        assert!(
            o.coalesced && o.skipped,
            "no credit: sample 1's frame is skipped"
        );
        assert!(p.next_frame().is_none(), "the only credit is out");
        p.on_ack(first.frame, ms(t0, 20)).unwrap();
        let t = p.next_frame().unwrap();
        assert_eq!(
            t.gaze.map(|g| g.seq),
            Some(2),
            "only the newest sample is shown"
        );
        assert_eq!((t.trigger, t.arrived), (Trigger::Gaze, ms(t0, 6)));
        assert_eq!((p.samples, p.coalesced, t.samples), (2, 1, 2));
    }

    #[test]
    fn a_settings_change_is_timed_from_when_it_arrived_not_from_hello() {
        let t0 = Instant::now();
        let mut p = Pacer::new(2, STALL, t0);
        let f1 = p.next_frame().unwrap();
        p.on_ack(f1.frame, ms(t0, 10)).unwrap();
        p.on_gaze(gaze(1), ms(t0, 20));
        let f2 = p.next_frame().unwrap();
        p.on_ack(f2.frame, ms(t0, 30)).unwrap();
        p.on_settings(ms(t0, 15_000));
        let t = p.next_frame().unwrap();
        assert_eq!(t.trigger, Trigger::Settings);
        assert_eq!(t.arrived, ms(t0, 15_000));
        assert_eq!(
            t.gaze.map(|g| g.seq),
            Some(1),
            "the last sample is shown again"
        );
    }

    #[test]
    fn a_waiting_sample_outranks_a_later_settings_change() {
        let t0 = Instant::now();
        let mut p = Pacer::new(1, STALL, t0);
        let f1 = p.next_frame().unwrap();
        p.on_gaze(gaze(1), ms(t0, 5));
        p.on_settings(ms(t0, 7));
        p.on_ack(f1.frame, ms(t0, 9)).unwrap();
        let t = p.next_frame().unwrap();
        assert_eq!((t.trigger, t.arrived), (Trigger::Gaze, ms(t0, 5)));
    }

    #[test]
    fn acks_return_credits_and_unknown_acks_are_refused() {
        let t0 = Instant::now();
        let mut p = Pacer::new(2, STALL, t0);
        let f1 = p.next_frame().unwrap();
        p.on_gaze(gaze(1), t0);
        let f2 = p.next_frame().unwrap();
        p.on_gaze(gaze(2), t0);
        assert!(p.next_frame().is_none(), "two frames out, two credits");
        assert_eq!(p.on_ack(7, t0), Err(2));
        p.on_ack(f2.frame, t0).unwrap();
        assert_eq!(p.on_ack(f2.frame, t0), Err(2), "an ack counts once");
        assert!(p.next_frame().is_some());
        p.on_ack(f1.frame, t0).unwrap();
    }

    #[test]
    fn a_failed_frame_gives_its_credit_back() {
        let t0 = Instant::now();
        let mut p = Pacer::new(1, STALL, t0);
        let f1 = p.next_frame().unwrap();
        p.on_gaze(gaze(1), t0);
        assert!(p.next_frame().is_none());
        p.frame_failed(f1.frame);
        assert_eq!(p.next_frame().map(|t| t.frame), Some(2));
    }

    #[test]
    fn stalls_only_with_frames_outstanding_and_none_being_made() {
        let t0 = Instant::now();
        let mut p = Pacer::new(2, STALL, t0);
        assert_eq!(p.stall_deadline(false), None, "nothing outstanding");
        let f1 = p.next_frame().unwrap();
        assert_eq!(p.stall_deadline(true), None, "a frame is being made");
        p.frame_out(ms(t0, 100));
        assert_eq!(p.stall_deadline(false), Some(ms(t0, 100) + STALL));
        p.on_ack(f1.frame, ms(t0, 500)).unwrap();
        assert_eq!(p.stall_deadline(false), None);
    }

    #[test]
    fn a_frame_made_long_after_the_last_ack_does_not_stall_at_once() {
        // Found by the browser test: a settings change after 15 s idle made a frame whose
        // stall clock had started at the last ack, so the client was dropped at once.
        let t0 = Instant::now();
        let mut p = Pacer::new(2, STALL, t0);
        let f1 = p.next_frame().unwrap();
        p.frame_out(ms(t0, 100));
        p.on_ack(f1.frame, ms(t0, 200)).unwrap();
        p.on_settings(ms(t0, 15_000));
        p.next_frame().unwrap();
        p.frame_out(ms(t0, 15_150));
        assert_eq!(p.stall_deadline(false), Some(ms(t0, 15_150) + STALL));
    }

    #[test]
    fn zero_credits_never_make_a_frame() {
        let mut p = Pacer::new(0, STALL, Instant::now());
        assert!(p.next_frame().is_none());
    }
}
