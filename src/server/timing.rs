//! One record of a frame's moments, from the arrival of what it answers to the last byte handed
//! to the socket. The frame header's stage times, the `/metrics` histograms and the per-frame
//! log line are all derived from this one record, so they always agree.

use std::time::{Duration, Instant};

use crate::protocol::{StageTimes, Trigger};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameTimes {
    /// What the frame answers.
    pub trigger: Trigger,
    /// The sample, settings change or hello this frame answers arrived.
    pub arrived: Instant,
    /// The job went to the render thread's queue.
    pub queued: Instant,
    /// The render thread took it.
    pub render_start: Instant,
    /// The GPU finished the frame's passes.
    pub render_end: Instant,
    /// The image reached host memory.
    pub readback_end: Instant,
    pub encode_start: Instant,
    pub encode_end: Instant,
    /// The frame's message was handed to the socket (set by the writer).
    pub sent: Option<Instant>,
}

fn ms(from: Instant, to: Instant) -> f64 {
    to.saturating_duration_since(from).as_secs_f64() * 1e3
}

impl FrameTimes {
    /// A frame that arrived at `arrived` and was queued now; later moments are filled in as
    /// they happen (until then they equal `queued`).
    pub fn new(trigger: Trigger, arrived: Instant, queued: Instant) -> FrameTimes {
        FrameTimes {
            trigger,
            arrived,
            queued,
            render_start: queued,
            render_end: queued,
            readback_end: queued,
            encode_start: queued,
            encode_end: queued,
            sent: None,
        }
    }

    /// The render thread's part: when it started, and how long rendering and readback took.
    pub fn rendered(&mut self, start: Instant, render: Duration, readback: Duration) {
        self.render_start = start;
        self.render_end = start + render;
        self.readback_end = self.render_end + readback;
    }

    /// The stage times a frame header carries.
    pub fn stages(&self) -> StageTimes {
        StageTimes {
            queue: ms(self.arrived, self.render_start),
            render: ms(self.render_start, self.render_end),
            readback: ms(self.render_end, self.readback_end),
            encode: ms(self.encode_start, self.encode_end),
        }
    }

    /// Handing the frame to the socket, once it has been sent.
    pub fn send_ms(&self) -> Option<f64> {
        self.sent.map(|s| ms(self.encode_end, s))
    }

    /// From arrival to the socket: what the viewer waits for, less the network.
    pub fn total_ms(&self) -> Option<f64> {
        self.sent.map(|s| ms(self.arrived, s))
    }

    /// Whether the frame answers a new gaze sample, so its wait is a gaze latency (frames
    /// made for the start or a settings change are left out of latency statistics).
    pub fn answers_gaze(&self) -> bool {
        self.trigger == Trigger::Gaze
    }

    /// Records the stages in the `fovea_stage_seconds` histograms (the queue stage and the
    /// gaze-to-sent total for gaze frames only).
    pub fn record_metrics(&self) {
        let s = self.stages();
        if self.answers_gaze() {
            super::metrics::stage("queue", s.queue);
            if let Some(total) = self.total_ms() {
                metrics::histogram!("fovea_gaze_to_sent_seconds").record(total / 1e3);
            }
        }
        for (stage, v) in [
            ("render", s.render),
            ("readback", s.readback),
            ("encode", s.encode),
        ] {
            super::metrics::stage(stage, v);
        }
        if let Some(send) = self.send_ms() {
            super::metrics::stage("send", send);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_come_from_one_record_and_add_up() {
        let t0 = Instant::now();
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        let mut t = FrameTimes::new(Trigger::Gaze, t0, at(2));
        t.rendered(at(5), Duration::from_millis(10), Duration::from_millis(3));
        t.encode_start = at(19);
        t.encode_end = at(23);
        t.sent = Some(at(24));
        let s = t.stages();
        assert_eq!(
            (s.queue, s.render, s.readback, s.encode),
            (5.0, 10.0, 3.0, 4.0)
        );
        assert_eq!(t.send_ms(), Some(1.0));
        assert_eq!(t.total_ms(), Some(24.0));
    }

    #[test]
    fn out_of_order_moments_give_zero_not_negative_times() {
        let t0 = Instant::now();
        let t = FrameTimes::new(Trigger::Settings, t0 + Duration::from_millis(5), t0);
        assert!(!t.answers_gaze());
        assert_eq!(t.stages().queue, 0.0);
    }
}
