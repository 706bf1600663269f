//! Step-rate profiles for the stepper.
//!
//! The board steps towards its target at one constant rate, one step every step delay
//! (port 0x43, 0.1 ms units, one byte): it has no acceleration of its own. The driver
//! ramps that rate itself: at every profile update it integrates a signed rate towards
//! the goal's velocity with the goal's acceleration and writes the step delay of that rate,
//! rounded so that the board never steps faster than the profile (the delay is rounded
//! up). Below the board's slowest rate (delay 255, 39.2 steps/s) it steps at that slowest
//! rate: that is the board's start/stop rate, reached and left in one step.

use core::time::Duration;

use spimotor::StepDelay;

/// Slowest step delay the board has (one byte of 0.1 ms: 25.5 ms).
pub const SLOWEST_DELAY: StepDelay = StepDelay::from_tenths_ms(u8::MAX);
/// Fastest step delay the driver writes: 0.1 ms. A delay of 0 is not documented, so the
/// driver never writes it.
pub const FASTEST_DELAY: StepDelay = StepDelay::from_tenths_ms(1);
/// Board target distance used to run at a velocity: far enough for 29 hours at the
/// fastest rate, close enough that target − position never overflows 32 bits.
pub const RUN_DISTANCE: i64 = 1 << 30;

/// Steps per second at `delay` (a delay of 0 counts as one tick of 0.1 ms).
pub fn rate_of(delay: StepDelay) -> f64 {
    1.0 / delay.duration().max(StepDelay::UNIT).as_secs_f64()
}

/// The board's slowest rate, steps/s (39.2).
pub fn slowest_rate() -> f64 {
    rate_of(SLOWEST_DELAY)
}

/// The fastest rate the driver uses, steps/s (10 000).
pub fn fastest_rate() -> f64 {
    rate_of(FASTEST_DELAY)
}

/// The step delay that steps as fast as possible without exceeding `rate` steps/s;
/// [`SLOWEST_DELAY`] for a rate below the board's slowest, [`FASTEST_DELAY`] above 10 000.
pub fn delay_for(rate: f64) -> StepDelay {
    if !(rate.is_finite() && rate > 0.0) {
        return SLOWEST_DELAY;
    }
    let period_ns = (1e9 / rate).round();
    if period_ns >= SLOWEST_DELAY.duration().as_nanos() as f64 {
        return SLOWEST_DELAY;
    }
    // 0 < period_ns < 25.5e6: fits a u64.
    StepDelay::at_least(Duration::from_nanos(period_ns as u64))
        .unwrap_or(SLOWEST_DELAY)
        .max(FASTEST_DELAY)
}

/// What the driver is doing with the stepper.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Standing (or finishing a step the board already has), nothing to ramp.
    Hold,
    /// Coils de-energised (intensity 0).
    Off,
    /// Run at `velocity` steps/s (signed) until told otherwise.
    Run {
        /// Signed velocity, steps/s.
        velocity: f64,
        /// Acceleration, steps/s².
        accel: f64,
    },
    /// Go to `target` with at most `velocity` and `accel`.
    Move {
        /// Target, steps.
        target: i32,
        /// Velocity limit, steps/s.
        velocity: f64,
        /// Acceleration limit, steps/s².
        accel: f64,
    },
    /// Decelerate at `decel`, then stop where the rate reaches the board's slowest.
    Stopping {
        /// Deceleration, steps/s².
        decel: f64,
    },
}

/// What one update asks of the board's target.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum TargetCommand {
    /// Leave the target as it is.
    Keep,
    /// Write this target (port 0x41).
    Set(i32),
    /// Stop where the motor is now (port 0x42 ← 0: target = current position).
    StopHere,
}

/// The outcome of one profile update.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Step {
    /// Step delay to be in force.
    pub delay: StepDelay,
    /// What to do with the board's target.
    pub target: TargetCommand,
}

/// What the driver knows of the board when it updates the profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Observed {
    /// Last known position counter, steps.
    pub position: i32,
    /// The board target after every write already planned (`None`: unknown, after a stop).
    pub target: Option<i32>,
    /// The board was seen standing (position = target) and no write changed it since.
    pub standing: bool,
    /// Time until the next update: a move brakes as if it were that much further on.
    pub lookahead: Duration,
}

/// The signed step rate of the profile and when it was last integrated.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Default)]
pub struct Ramp {
    /// Signed rate, steps/s.
    pub rate: f64,
    at: Option<Duration>,
}

fn sign(value: f64) -> f64 {
    if value > 0.0 {
        1.0
    } else if value < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// `current` moved towards `desired` by at most `step`.
fn approach(current: f64, desired: f64, step: f64) -> f64 {
    if !step.is_finite() || (desired - current).abs() <= step {
        desired
    } else {
        current + step.copysign(desired - current)
    }
}

/// The rate (unsigned) whose step delay a profile at the signed `rate`, heading for
/// `desired` at `accel`, writes now: while it slows down, the rate it will have reached at
/// the next update (`lookahead` from now), so that a new goal's deceleration is on the wire
/// at once rather than one update later, and the board never steps faster than the profile
/// during the interval; while it speeds up or cruises, the rate now (never ahead of it).
fn rate_in_force(rate: f64, desired: f64, accel: f64, lookahead: Duration) -> f64 {
    let ahead = approach(rate, desired, accel * lookahead.as_secs_f64());
    if sign(ahead) != sign(rate) {
        // Through zero within the interval: the slowest rate the board has.
        0.0
    } else {
        ahead.abs().min(rate.abs())
    }
}

fn far_target(position: i32, direction: f64) -> i32 {
    let offset = if direction < 0.0 {
        -RUN_DISTANCE
    } else {
        RUN_DISTANCE
    };
    let far = (i64::from(position) + offset).clamp(i64::from(i32::MIN), i64::from(i32::MAX));
    i32::try_from(far).unwrap_or(position)
}

impl Ramp {
    /// Forgets the rate (the board was seen standing, stopped or restarted).
    pub fn rest(&mut self, now: Duration) {
        self.rate = 0.0;
        self.at = Some(now);
    }

    /// Continues from the signed `rate` the board steps at now (a stop ramps down from
    /// where the motor really is, not from where a profile had got to).
    pub fn start_from(&mut self, now: Duration, rate: f64) {
        self.rate = if rate.is_finite() { rate } else { 0.0 };
        self.at = Some(now);
    }

    /// Integrates the profile up to `now` and says what the board must do. `motion` turns
    /// into [`Motion::Hold`] when a stop completes. `None`: nothing to drive.
    pub fn update(&mut self, now: Duration, motion: &mut Motion, board: Observed) -> Option<Step> {
        let dt = self
            .at
            .map_or(0.0, |at| now.saturating_sub(at).as_secs_f64());
        self.at = Some(now);
        let slowest = slowest_rate();
        match *motion {
            Motion::Hold | Motion::Off => {
                self.rate = 0.0;
                None
            }
            Motion::Stopping { decel } => {
                self.rate = approach(self.rate, 0.0, decel * dt);
                if board.standing || self.rate.abs() <= slowest {
                    *motion = Motion::Hold;
                    self.rate = 0.0;
                    return Some(Step {
                        delay: SLOWEST_DELAY,
                        target: TargetCommand::StopHere,
                    });
                }
                let written = rate_in_force(self.rate, 0.0, decel, board.lookahead);
                Some(Step {
                    delay: delay_for(written.max(slowest)),
                    target: TargetCommand::Keep,
                })
            }
            Motion::Run { velocity, accel } => {
                let direction = sign(velocity);
                let reversing = self.rate != 0.0 && sign(self.rate) != direction;
                let desired = if reversing && self.rate.abs() > slowest {
                    0.0
                } else {
                    velocity
                };
                let mut rate = approach(self.rate, desired, accel * dt);
                if rate != 0.0 && sign(rate) != direction && rate.abs() <= slowest {
                    rate = 0.0;
                }
                self.rate = rate;
                let heading = if rate == 0.0 { direction } else { sign(rate) };
                let far = far_target(board.position, heading);
                let on_course = board.target.is_some_and(|t| {
                    let ahead = i64::from(t) - i64::from(board.position);
                    t == far || (sign(ahead as f64) == heading && ahead.abs() > RUN_DISTANCE / 2)
                });
                let target = if on_course {
                    TargetCommand::Keep
                } else {
                    TargetCommand::Set(far)
                };
                let written = rate_in_force(rate, desired, accel, board.lookahead);
                Some(Step {
                    delay: delay_for(written.max(slowest)),
                    target,
                })
            }
            Motion::Move {
                target,
                velocity,
                accel,
            } => {
                let remaining = i64::from(target) - i64::from(board.position);
                let direction = sign(remaining as f64);
                let reversing = self.rate != 0.0 && sign(self.rate) != direction;
                let desired = if reversing && self.rate.abs() > slowest {
                    0.0
                } else {
                    // Brake where the motor will be at the next update, so that the
                    // rate in force until then stays under the braking curve.
                    let ahead = self.rate.abs() * board.lookahead.as_secs_f64();
                    let reach = (remaining.unsigned_abs() as f64 - ahead).max(0.0);
                    let brake = (2.0 * accel * reach).sqrt();
                    direction * velocity.min(brake)
                };
                let mut rate = approach(self.rate, desired, accel * dt);
                if rate != 0.0 && sign(rate) != direction && rate.abs() <= slowest {
                    rate = 0.0;
                }
                if remaining == 0 && board.standing {
                    rate = 0.0;
                }
                self.rate = rate;
                let still_reversing = rate != 0.0 && sign(rate) != direction;
                let command = if still_reversing || board.target == Some(target) {
                    TargetCommand::Keep
                } else {
                    TargetCommand::Set(target)
                };
                Some(Step {
                    delay: delay_for(rate.abs().max(slowest)),
                    target: command,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    #[test]
    fn delays_never_step_faster_than_asked() {
        // Datasheet port 0x43: tenths of a millisecond; default 200 = 20 ms = 50 steps/s.
        assert_eq!(delay_for(50.0), StepDelay::from_tenths_ms(200));
        assert_eq!(delay_for(5_000.0), StepDelay::from_tenths_ms(2));
        assert_eq!(delay_for(7_000.0), StepDelay::from_tenths_ms(2));
        assert_eq!(delay_for(1e9), FASTEST_DELAY);
        assert_eq!(delay_for(1.0), SLOWEST_DELAY);
        assert_eq!(delay_for(f64::NAN), SLOWEST_DELAY);
        assert_eq!(delay_for(-3.0), SLOWEST_DELAY);
        for rate in [39.3, 40.0, 99.0, 333.3, 1_234.0, 9_999.0] {
            assert!(rate_of(delay_for(rate)) <= rate + 1e-9, "{rate}");
        }
        assert!((slowest_rate() - 10_000.0 / 255.0).abs() < 1e-9);
        assert!((fastest_rate() - 10_000.0).abs() < 1e-9);
    }

    #[test]
    fn a_move_ramps_up_and_brakes_into_the_target() {
        let mut ramp = Ramp::default();
        let mut motion = Motion::Move {
            target: 10_000,
            velocity: 2_000.0,
            accel: 10_000.0,
        };
        let mut board = Observed {
            position: 0,
            target: None,
            standing: true,
            lookahead: Duration::ZERO,
        };
        let first = ramp.update(Duration::ZERO, &mut motion, board).unwrap();
        assert_eq!(first.target, TargetCommand::Set(10_000));
        assert_eq!(first.delay, SLOWEST_DELAY);
        board.target = Some(10_000);
        board.standing = false;
        let mut last_rate = 0.0;
        for k in 1..=300 {
            let step = ramp.update(k * MS, &mut motion, board).unwrap();
            assert_eq!(step.target, TargetCommand::Keep);
            assert!(ramp.rate - last_rate <= 10.0 + 1e-9, "accel limit");
            assert!(rate_of(step.delay) <= 2_000.0 + 1e-9, "velocity limit");
            last_rate = ramp.rate;
        }
        assert!((ramp.rate - 2_000.0).abs() < 1e-9);
        // Close to the target the profile brakes.
        board.position = 9_990;
        let step = ramp.update(301 * MS, &mut motion, board).unwrap();
        assert!(ramp.rate < 2_000.0);
        assert!(rate_of(step.delay) <= ramp.rate);
    }

    #[test]
    fn a_reversing_run_decelerates_before_it_turns() {
        let mut ramp = Ramp {
            rate: 1_000.0,
            at: Some(Duration::ZERO),
        };
        let mut motion = Motion::Run {
            velocity: -1_000.0,
            accel: 100_000.0,
        };
        let board = Observed {
            position: 50,
            target: Some(50 + RUN_DISTANCE as i32),
            standing: false,
            lookahead: Duration::ZERO,
        };
        let step = ramp.update(5 * MS, &mut motion, board).unwrap();
        assert_eq!(step.target, TargetCommand::Keep, "still running forwards");
        assert!((ramp.rate - 500.0).abs() < 1e-9);
        let step = ramp.update(10 * MS, &mut motion, board).unwrap();
        assert_eq!(ramp.rate, 0.0);
        assert_eq!(
            step.target,
            TargetCommand::Set(50 - RUN_DISTANCE as i32),
            "turned at the start/stop rate"
        );
    }

    #[test]
    fn a_stop_decelerates_then_stops_here() {
        let mut ramp = Ramp {
            rate: 400.0,
            at: Some(Duration::ZERO),
        };
        let mut motion = Motion::Stopping { decel: 20_000.0 };
        let board = Observed {
            position: 0,
            target: Some(1 << 30),
            standing: false,
            lookahead: Duration::ZERO,
        };
        let step = ramp.update(10 * MS, &mut motion, board).unwrap();
        assert_eq!(step.target, TargetCommand::Keep);
        assert_eq!(step.delay, delay_for(200.0));
        let step = ramp.update(20 * MS, &mut motion, board).unwrap();
        assert_eq!(step.target, TargetCommand::StopHere);
        assert_eq!(motion, Motion::Hold);
        assert_eq!(ramp.update(30 * MS, &mut motion, board), None);
    }

    #[test]
    fn a_new_deceleration_is_written_at_once_with_the_rate_of_the_next_update() {
        // Running at 100 steps/s, profile integrated just now (a poll-period update in
        // this very tick): a reverse goal slows down from this update on, not the next.
        let board = Observed {
            position: 0,
            target: Some(1 << 30),
            standing: false,
            lookahead: 2 * MS,
        };
        let mut ramp = Ramp {
            rate: 100.0,
            at: Some(5 * MS),
        };
        let mut motion = Motion::Run {
            velocity: -100.0,
            accel: 5_000.0,
        };
        let step = ramp.update(5 * MS, &mut motion, board).unwrap();
        assert_eq!(ramp.rate, 100.0, "the profile itself is where it was");
        assert_eq!(step.delay, delay_for(90.0), "the rate 2 ms on");
        assert_eq!(step.target, TargetCommand::Keep, "still running forwards");
        // A stop the same.
        let mut motion = Motion::Stopping { decel: 5_000.0 };
        let step = ramp.update(5 * MS, &mut motion, board).unwrap();
        assert_eq!(step.delay, delay_for(90.0));
        // Speeding up never writes ahead of the profile.
        let mut motion = Motion::Run {
            velocity: 200.0,
            accel: 5_000.0,
        };
        let step = ramp.update(5 * MS, &mut motion, board).unwrap();
        assert_eq!(step.delay, delay_for(100.0));
    }

    #[test]
    fn far_targets_saturate_at_the_32_bit_range() {
        assert_eq!(far_target(i32::MAX - 5, 1.0), i32::MAX);
        assert_eq!(far_target(i32::MIN + 5, -1.0), i32::MIN);
        assert_eq!(far_target(0, 1.0), 1 << 30);
    }
}
