//! The encoder counter as the stream reports it: the latest count, and the velocity from
//! successive time-stamped samples.

use ::qsb::TICK;
use motion_base::FixedQueue;

/// Samples the velocity is measured over (8 × 1.95 ms ≈ 16 ms at the fastest stream):
/// long enough that one count of quantisation is small, short enough to follow a ramp.
pub(crate) const VELOCITY_WINDOW: usize = 8;

/// One streamed READ ENCODER value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct Sample {
    /// CNTR as a signed 32-bit count.
    pub count: i32,
    /// Board time stamp, 1/512 s ticks.
    pub time_stamp: u32,
}

/// Counts a sample may sit off the predicted count while the encoder moves: the counter
/// counts whole edges, so samples of a smooth motion sit up to one count either side.
const MOVING_SLACK: f64 = 2.0;

/// The same while it stands still: none (half a count for the floating point).
const STILL_SLACK: f64 = 0.5;

/// The latest samples.
#[derive(Debug, Clone)]
pub(crate) struct EncoderTrack {
    window: FixedQueue<Sample, VELOCITY_WINDOW>,
    velocity: f64,
    /// A sample that contradicted the track, waiting for the next one.
    held: Option<Sample>,
}

impl EncoderTrack {
    pub(crate) const fn new() -> Self {
        Self {
            window: FixedQueue::new(),
            velocity: 0.0,
            held: None,
        }
    }

    /// Offers a streamed sample through the line-noise guard (module `guard`). A sample
    /// where the track predicts it (the last count plus velocity × time, within what the
    /// acceleration limit `max_accel` (counts/s²) and the counter's quantisation allow;
    /// exactly the last count while the encoder stands still) is taken at once. One that
    /// is not is held until the next sample: if that one is where the old track predicts
    /// it, the held one was corrupted on the line and is dropped; if it too leaves the old
    /// track, the motion really changed and both are taken, one sample late. One corrupted
    /// sample is therefore never shown; it takes two in a row, or one that coincides with
    /// a change of motion beyond the acceleration limit. Returns whether the sample (and
    /// with it the newest count) was taken.
    pub(crate) fn offer(&mut self, sample: Sample, max_accel: f64) -> bool {
        let Some(last) = self.latest() else {
            self.push(sample);
            return true;
        };
        if self.predicts(last, sample, max_accel) {
            self.held = None;
            self.push(sample);
            return true;
        }
        match self.held.take() {
            Some(held) => {
                self.push(held);
                self.push(sample);
                true
            }
            None => {
                self.held = Some(sample);
                false
            }
        }
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
        let moved = f64::from(sample.count.wrapping_sub(from.count));
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
        *self = Self::new();
    }

    /// Takes a sample. Samples with the same time stamp as the newest replace it.
    fn push(&mut self, sample: Sample) {
        match self.window.back_mut() {
            Some(latest) if latest.time_stamp == sample.time_stamp => *latest = sample,
            _ => {
                self.window.push_overwrite(sample);
            }
        }
        let Some(oldest) = self.window.front() else {
            return;
        };
        let ticks = sample.time_stamp.wrapping_sub(oldest.time_stamp);
        if self.window.len() >= 2 && ticks > 0 && ticks < u32::MAX / 2 {
            let counts = f64::from(sample.count.wrapping_sub(oldest.count));
            self.velocity = counts / (TICK.as_secs_f64() * f64::from(ticks));
        }
    }
}

/// Seconds from `a` to `b` by their time stamps; `None` when `b` is older.
fn seconds_between(a: Sample, b: Sample) -> Option<f64> {
    let ticks = b.time_stamp.wrapping_sub(a.time_stamp);
    (ticks < u32::MAX / 2).then(|| TICK.as_secs_f64() * f64::from(ticks))
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
}
