//! Whose frame the render thread runs next: the stream that has had the least render time
//! (start-time fair queueing). A stream's clock is charged with what each of its frames (or
//! frame parts) took, so a session asking for 4K reference frames slows only itself: everyone
//! else's frames run between its parts. A stream that comes back after a pause starts level
//! with the thread's clock, so time spent idle is not a credit it can spend all at once.

use std::collections::HashMap;

#[derive(Debug, Default)]
pub struct Turns {
    /// Render milliseconds each stream has been charged, on one clock.
    used: HashMap<u64, f64>,
    /// The clock: the charge of the work last started.
    now: f64,
}

impl Turns {
    /// Streams the thread is serving (those that have asked for a frame and not ended).
    pub fn streams(&self) -> usize {
        self.used.len()
    }

    /// `stream` has work again.
    pub fn arrive(&mut self, stream: u64) {
        let now = self.now;
        let used = self.used.entry(stream).or_insert(now);
        *used = used.max(now);
    }

    /// Which of `waiting` (stream, arrival number) runs next: the least charged stream, the
    /// earliest arrival among equals. `None` when nothing waits.
    pub fn pick(&mut self, waiting: &[(u64, u64)]) -> Option<usize> {
        let i = waiting
            .iter()
            .enumerate()
            .min_by(|(_, a), (_, b)| {
                self.used(a.0)
                    .total_cmp(&self.used(b.0))
                    .then(a.1.cmp(&b.1))
            })
            .map(|(i, _)| i)?;
        self.now = self.now.max(self.used(waiting[i].0));
        Some(i)
    }

    /// `stream`'s work just took `ms`.
    pub fn charge(&mut self, stream: u64, ms: f64) {
        if ms.is_finite() && ms > 0.0 {
            *self.used.entry(stream).or_insert(self.now) += ms;
        }
    }

    /// `stream`'s first piece of a frame of a kind it never rendered took `ms`. That piece makes
    /// the stream's targets and may compile pipelines or build the scene's maps that every
    /// stream then uses (650 ms on a cold software driver, against 15 ms a frame after), so
    /// whoever happens to be first would otherwise be charged for everyone and wait its whole
    /// cost out while the others render. It is charged at most one slice, like the longest
    /// piece anyone else waits behind.
    pub fn charge_cold(&mut self, stream: u64, ms: f64) {
        self.charge(stream, ms.min(super::scheduler::SLICE_MS));
    }

    /// The stream ended.
    pub fn forget(&mut self, stream: u64) {
        self.used.remove(&stream);
    }

    fn used(&self, stream: u64) -> f64 {
        self.used.get(&stream).copied().unwrap_or(self.now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs a heavy stream (1) in `part_ms` parts and light streams (2..) whose next frame
    /// arrives as soon as the last one is done; returns each light stream's longest wait.
    fn simulate(light: u64, light_ms: f64, part_ms: f64, steps: usize) -> Vec<f64> {
        let mut t = Turns::default();
        let mut clock = 0.0;
        let mut seq = 0;
        let mut waiting: Vec<(u64, u64, f64)> = Vec::new();
        let mut arrive = |t: &mut Turns, w: &mut Vec<(u64, u64, f64)>, s, at| {
            t.arrive(s);
            seq += 1;
            w.push((s, seq, at));
        };
        arrive(&mut t, &mut waiting, 1, 0.0);
        for s in 2..2 + light {
            arrive(&mut t, &mut waiting, s, 0.0);
        }
        let mut worst = vec![0.0f64; light as usize];
        for _ in 0..steps {
            let keys: Vec<(u64, u64)> = waiting.iter().map(|w| (w.0, w.1)).collect();
            let i = t.pick(&keys).unwrap();
            let (s, _, at) = waiting.remove(i);
            let ms = if s == 1 { part_ms } else { light_ms };
            if s != 1 {
                worst[(s - 2) as usize] = worst[(s - 2) as usize].max(clock - at);
            }
            clock += ms;
            t.charge(s, ms);
            arrive(&mut t, &mut waiting, s, clock);
        }
        worst
    }

    #[test]
    fn a_light_stream_waits_at_most_one_part_of_a_heavy_one() {
        let worst = simulate(1, 30.0, 100.0, 500);
        assert!(worst[0] <= 100.0 + 1e-9, "{worst:?}");
    }

    #[test]
    fn several_light_streams_each_wait_at_most_one_turn_of_everyone_else() {
        let worst = simulate(3, 30.0, 100.0, 1000);
        for w in &worst {
            assert!(*w <= 100.0 + 2.0 * 30.0 + 1e-9, "{worst:?}");
        }
    }

    #[test]
    fn idle_time_is_no_credit_and_new_streams_start_level() {
        let mut t = Turns::default();
        t.arrive(1);
        t.arrive(2);
        for _ in 0..100 {
            let i = t.pick(&[(1, 0), (2, 1)]).unwrap();
            t.charge([1, 2][i], 10.0);
        }
        // Stream 3 was away the whole time: it is level with the clock, not 1000 ms behind.
        t.arrive(3);
        let mut threes = 0;
        for k in 0..30 {
            let i = t.pick(&[(1, k), (2, k), (3, k)]).unwrap();
            t.charge([1, 2, 3][i], 10.0);
            threes += usize::from(i == 2);
        }
        assert!((9..=11).contains(&threes), "{threes} turns of 30");
        t.forget(3);
        assert_eq!(t.pick(&[]), None);
    }

    #[test]
    fn a_cold_first_frame_is_not_waited_out() {
        // Three streams start together; stream 1's first frame compiles what all use (650 ms),
        // then every frame takes 15 ms. Over the next 2 s of render time each gets a third.
        let mut t = Turns::default();
        for s in 1..=3 {
            t.arrive(s);
        }
        t.charge_cold(1, 650.0);
        t.charge_cold(2, 15.0);
        t.charge_cold(3, 15.0);
        let mut turns = [0usize; 3];
        for k in 0..133 {
            let i = t.pick(&[(1, k), (2, k), (3, k)]).unwrap();
            t.charge(i as u64 + 1, 15.0);
            turns[i] += 1;
        }
        let (lo, hi) = (turns.iter().min().unwrap(), turns.iter().max().unwrap());
        assert!(*lo * 10 >= *hi * 8, "turns {turns:?}");
        // Charged in full, stream 1 would have waited 43 of the others' frames out.
        let mut full = Turns::default();
        for s in 1..=3 {
            full.arrive(s);
        }
        full.charge(1, 650.0);
        let first = (0..40)
            .map(|k| {
                full.pick(&[(1, k), (2, k), (3, k)]).inspect(|&i| {
                    full.charge(i as u64 + 1, 15.0);
                })
            })
            .filter(|i| *i == Some(0))
            .count();
        assert_eq!(first, 0);
    }

    #[test]
    fn nonsense_charges_are_ignored() {
        let mut t = Turns::default();
        t.arrive(1);
        t.arrive(2);
        t.charge(1, f64::NAN);
        t.charge(1, f64::INFINITY);
        t.charge(1, -5.0);
        t.charge(2, 1.0);
        assert_eq!(t.pick(&[(2, 0), (1, 1)]), Some(1));
    }
}
