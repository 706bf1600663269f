//! The encoder counter as the stream reports it: the latest count, and the velocity from
//! successive time-stamped samples.

use ::qsb::TICK;
use motion_base::FixedQueue;

use super::counter::Wrap;

/// Samples the velocity is measured over (8 × 1.95 ms ≈ 16 ms at the fastest stream):
/// long enough that one count of quantisation is small, short enough to follow a ramp.
pub(crate) const VELOCITY_WINDOW: usize = 8;

/// One streamed READ ENCODER value.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Sample {
    /// CNTR as a signed 32-bit count.
    pub count: i32,
    /// Board time stamp, 1/512 s ticks.
    pub time_stamp: u32,
}

/// Samples in a row off the track after which the newest starts a new one: a real jump of
/// the counter is shown after this many stream periods; corrupted lines do not come in
/// such runs below a bit-error rate of about 1e-3.
pub(crate) const MAX_HELD: u8 = 3;

/// Counts a sample may sit off the predicted count while the encoder moves: the counter
/// counts whole edges, so samples of a smooth motion sit up to one count either side.
const MOVING_SLACK: f64 = 2.0;

/// The same while it stands still: none (half a count for the floating point).
const STILL_SLACK: f64 = 0.5;

/// The latest samples.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct EncoderTrack {
    window: FixedQueue<Sample, VELOCITY_WINDOW>,
    velocity: f64,
    /// A sample that contradicted the track, waiting for the next one.
    held: Option<Sample>,
    /// Samples in a row that contradicted the track.
    held_in_row: u8,
    /// How two counts are subtracted (the counter's wrap).
    wrap: Wrap,
}

impl EncoderTrack {
    #[cfg(test)]
    pub(crate) const fn new() -> Self {
        Self::with_wrap(Wrap::Bits32)
    }

    /// A track of a counter that wraps as `wrap` says.
    pub(crate) const fn with_wrap(wrap: Wrap) -> Self {
        Self {
            window: FixedQueue::new(),
            velocity: 0.0,
            held: None,
            held_in_row: 0,
            wrap,
        }
    }

    /// Counts from `a` to `b`.
    fn moved(&self, a: Sample, b: Sample) -> f64 {
        self.wrap.diff(a.count, b.count) as f64
    }

    /// Offers a streamed sample through the line-noise guard (module `guard`). A sample
    /// where the track predicts it (the last count plus velocity × time, within what the
    /// acceleration limit `max_accel` (counts/s²) and the counter's quantisation allow;
    /// exactly the last count while the encoder stands still) is taken at once. One that
    /// is not is held until the next sample: if that one is where the old track predicts
    /// it, the held one was corrupted on the line and is dropped; if it goes on from the
    /// held one at the velocity the held one implies (a change of motion) or stays there,
    /// both are taken,
    /// one sample late; else it is held instead, and after [`MAX_HELD`] samples in a row
    /// off the track the newest starts a new track (the counter really jumped). A corrupted
    /// sample is shown only when the next one is corrupted into the same line of motion,
    /// or when it lies within the acceleration and quantisation allowance. Returns whether
    /// the sample (and with it the newest count) was taken.
    pub(crate) fn offer(&mut self, sample: Sample, max_accel: f64) -> bool {
        let Some(last) = self.latest() else {
            self.push(sample);
            return true;
        };
        if self.predicts(last, sample, max_accel) {
            self.held = None;
            self.held_in_row = 0;
            self.push(sample);
            return true;
        }
        if let Some(held) = self.held.take()
            && goes_on(self.wrap, last, held, sample, max_accel)
        {
            self.held_in_row = 0;
            self.push(held);
            self.push(sample);
            return true;
        }
        self.held_in_row = self.held_in_row.saturating_add(1);
        if self.held_in_row >= MAX_HELD {
            self.clear();
            self.push(sample);
            return true;
        }
        self.held = Some(sample);
        false
    }

    /// Whether `sample` is where the track's velocity predicts it from `from`: within what
    /// `max_accel` allows over the gap (plus the velocity estimate's lag over the window
    /// while the encoder moves) and the counter's quantisation (none while it stands
    /// still).
    fn predicts(&self, from: Sample, sample: Sample, max_accel: f64) -> bool {
        let Some(dt) = seconds_between(from, sample) else {
            return false;
        };
        let still = self.velocity == 0.0;
        let lag = match (still, self.window.front(), self.window.back()) {
            (false, Some(oldest), Some(newest)) => seconds_between(oldest, newest).unwrap_or(0.0),
            _ => 0.0,
        };
        let quantisation = if still { STILL_SLACK } else { MOVING_SLACK };
        let allowed = max_accel.abs() * dt * (dt + lag) / 2.0 + quantisation;
        let moved = self.moved(from, sample);
        (moved - self.velocity * dt).abs() <= allowed
    }

    /// The newest sample.
    pub(crate) fn latest(&self) -> Option<Sample> {
        self.window.back()
    }

    /// Counts per second over the window (0 until two samples with different time
    /// stamps arrived).
    pub(crate) fn velocity(&self) -> f64 {
        self.velocity
    }

    /// Forgets everything (a new start-up, or the counter was loaded or reset: a jump,
    /// not a motion).
    pub(crate) fn clear(&mut self) {
        *self = Self::with_wrap(self.wrap);
    }

    /// Forgets the samples stamped after `time_stamp` (their stamp was corrupted).
    pub(crate) fn forget_after(&mut self, time_stamp: u32) {
        self.window
            .retain(|sample| time_stamp.wrapping_sub(sample.time_stamp) < u32::MAX / 2);
        self.held = None;
        self.held_in_row = 0;
        self.velocity = 0.0;
        if let (Some(oldest), Some(newest)) = (self.window.front(), self.window.back()) {
            self.update_velocity(oldest, newest);
        }
    }

    /// Takes a sample. Samples with the same time stamp as the newest replace it.
    fn push(&mut self, sample: Sample) {
        match self.window.back_mut() {
            Some(latest) if latest.time_stamp == sample.time_stamp => *latest = sample,
            _ => {
                self.window.push_overwrite(sample);
            }
        }
        if let Some(oldest) = self.window.front() {
            self.update_velocity(oldest, sample);
        }
    }

    /// The velocity from `oldest` to `newest` of the window (kept when they share a stamp).
    fn update_velocity(&mut self, oldest: Sample, newest: Sample) {
        let ticks = newest.time_stamp.wrapping_sub(oldest.time_stamp);
        if self.window.len() >= 2 && ticks > 0 && ticks < u32::MAX / 2 {
            let counts = self.moved(oldest, newest);
            self.velocity = counts / (TICK.as_secs_f64() * f64::from(ticks));
        }
    }
}

/// Seconds from `a` to `b` by their time stamps; `None` when `b` is older.
fn seconds_between(a: Sample, b: Sample) -> Option<f64> {
    let ticks = b.time_stamp.wrapping_sub(a.time_stamp);
    (ticks < u32::MAX / 2).then(|| TICK.as_secs_f64() * f64::from(ticks))
}

/// Whether `sample` goes on from `held` at the velocity `last` → `held` implies, within
/// `max_accel` over the gaps and a count of quantisation on each of the three samples, or
/// stays at `held` within a count: two independent corruptions of a line do neither.
fn goes_on(wrap: Wrap, last: Sample, held: Sample, sample: Sample, max_accel: f64) -> bool {
    let (Some(before), Some(dt)) = (seconds_between(last, held), seconds_between(held, sample))
    else {
        return false;
    };
    let moved = wrap.diff(held.count, sample.count) as f64;
    if before <= 0.0 {
        // The held sample replaced the last one's value at its own time stamp.
        return moved.abs() <= 1.0;
    }
    let velocity = wrap.diff(last.count, held.count) as f64 / before;
    let allowed = max_accel.abs() * dt * (dt + before) / 2.0 + 1.0 + 2.0 * dt / before;
    // Either the motion goes on, or it stopped at the held count (a step).
    (moved - velocity * dt).abs() <= allowed || moved.abs() <= 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(count: i32, time_stamp: u32) -> Sample {
        Sample { count, time_stamp }
    }

    #[test]
    fn velocity_over_the_window_from_time_stamps() {
        let mut track = EncoderTrack::new();
        track.push(sample(0, 100));
        assert_eq!(track.velocity(), 0.0);
        // 512 counts per tick = 512 × 512 counts/s.
        for k in 1..20 {
            track.push(sample(512 * k, 100 + k as u32));
        }
        assert_eq!(track.velocity(), 512.0 * 512.0);
        assert_eq!(track.latest(), Some(sample(512 * 19, 119)));
    }

    #[test]
    fn a_counter_wrap_is_a_small_step_and_a_still_encoder_reads_zero() {
        let mut track = EncoderTrack::new();
        track.push(sample(i32::MAX - 1, 0));
        track.push(sample(i32::MIN + 1, 2));
        assert_eq!(track.velocity(), 3.0 / (2.0 * TICK.as_secs_f64()));
        for k in 3..3 + VELOCITY_WINDOW as u32 {
            track.push(sample(i32::MIN + 1, k));
        }
        assert_eq!(track.velocity(), 0.0);
    }

    #[test]
    fn clear_forgets_history() {
        let mut track = EncoderTrack::new();
        track.push(sample(0, 0));
        track.push(sample(1000, 1));
        track.clear();
        assert_eq!(track.latest(), None);
        track.push(sample(-5, 2));
        assert_eq!(track.velocity(), 0.0);
        track.push(sample(-3, 4));
        assert_eq!(track.velocity(), 2.0 / (2.0 * TICK.as_secs_f64()));
    }

    const ACCEL: f64 = 100_000.0;

    fn still_track() -> EncoderTrack {
        let mut track = EncoderTrack::new();
        for k in 0..8 {
            assert!(track.offer(sample(500, k), ACCEL));
        }
        track
    }

    #[test]
    fn a_sample_off_a_still_track_is_held_and_dropped_when_the_next_is_on_it() {
        let mut track = still_track();
        assert!(!track.offer(sample(500 + 4096, 8), ACCEL), "held");
        assert_eq!(track.latest(), Some(sample(500, 7)));
        assert!(track.offer(sample(500, 9), ACCEL));
        assert_eq!(track.latest(), Some(sample(500, 9)));
        assert_eq!(track.velocity(), 0.0);
    }

    #[test]
    fn a_step_shows_one_sample_late_and_a_new_motion_too() {
        let mut track = still_track();
        assert!(!track.offer(sample(900, 8), ACCEL));
        assert!(track.offer(sample(900, 9), ACCEL), "it stayed: a step");
        assert_eq!(track.latest(), Some(sample(900, 9)));
        let mut track = still_track();
        assert!(!track.offer(sample(520, 8), ACCEL));
        assert!(track.offer(sample(540, 9), ACCEL), "it went on: a motion");
        // Far beyond the acceleration limit (20 counts per tick at once): each sample is
        // shown at most one sample late.
        for k in 10..40 {
            let count = 500 + 20 * (k as i32 - 7);
            track.offer(sample(count, k), ACCEL);
            let shown = track.latest().expect("a sample").count;
            assert!(shown >= count - 20, "{shown} behind {count}");
        }
    }

    #[test]
    fn samples_that_never_agree_start_a_new_track_after_max_held() {
        let mut track = still_track();
        let wild = [5_000, -9_000, 70_000];
        for (k, count) in wild.iter().enumerate() {
            let taken = track.offer(sample(*count, 8 + k as u32), ACCEL);
            assert_eq!(taken, k + 1 == usize::from(MAX_HELD), "sample {k}");
        }
        assert_eq!(track.latest(), Some(sample(70_000, 10)));
    }

    #[test]
    fn forgetting_a_corrupted_stamp_keeps_the_samples_before_it() {
        let mut track = still_track();
        assert!(
            track.offer(sample(500, 15), ACCEL),
            "a stamp run ahead, count right"
        );
        track.forget_after(8);
        assert_eq!(track.latest(), Some(sample(500, 7)));
        assert!(track.offer(sample(500, 9), ACCEL));
    }

    #[test]
    fn a_modulo_n_wrap_is_a_motion_for_the_guard_and_the_velocity() {
        // Modulo 500 (DTR 499): 7 counts per tick forward, through 499 → 0 twice.
        let mut track = EncoderTrack::with_wrap(Wrap::Modulo(500));
        // (The start of the motion, from a still track, is taken one sample late.)
        for k in 0..150u32 {
            let count = (7 * k as i32 + 300) % 500;
            assert_eq!(track.offer(sample(count, k), ACCEL), k != 1, "sample {k}");
            if k != 1 {
                assert_eq!(track.latest().map(|s| s.count), Some(count));
            }
        }
        assert_eq!(track.velocity(), 7.0 / TICK.as_secs_f64());
        // Backwards through 0 → 499.
        let mut track = EncoderTrack::with_wrap(Wrap::Modulo(500));
        for k in 0..20u32 {
            let count = (500 + 20 - 3 * k as i32) % 500;
            assert_eq!(track.offer(sample(count, k), ACCEL), k != 1, "sample {k}");
        }
        assert_eq!(track.velocity(), -3.0 / TICK.as_secs_f64());
        // The same counts read as a free-running counter are jumps the guard holds.
        let mut plain = EncoderTrack::new();
        let taken = (0..150u32)
            .filter(|k| plain.offer(sample((7 * *k as i32 + 300) % 500, *k), ACCEL))
            .count();
        assert!(taken < 150);
    }
}
