//! One simulated stepper channel: a constant-acceleration (trapezoidal) profile, integrated
//! in fixed steps.

use crate::codec::Motion;

/// The integration step, seconds.
const DT: f64 = 100e-6;

/// What the channel was told to do last.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    /// Standing, coils on.
    Hold,
    /// Coils off.
    Off,
    /// `M`: to `target` at up to `speed`, ramping with `accel`.
    Move { target: f64, speed: f64, accel: f64 },
    /// `V`: towards `velocity` at `accel` (0 ends in `Hold`).
    Jog { velocity: f64, accel: f64 },
    /// `S`: down to standstill at `decel`, then `Hold`.
    Stop { decel: f64 },
}

/// One stepper channel of the simulated board. Steps are counted continuously and read
/// rounded; a stop settles on a whole step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stepper {
    position: f64,
    velocity: f64,
    mode: Mode,
}

/// `from` moved towards `to` by at most `by`.
fn approach(from: f64, to: f64, by: f64) -> f64 {
    if from < to {
        (from + by).min(to)
    } else {
        (from - by).max(to)
    }
}

impl Stepper {
    /// At step 0, holding.
    pub(super) const fn new() -> Self {
        Self {
            position: 0.0,
            velocity: 0.0,
            mode: Mode::Hold,
        }
    }

    /// The position counter, steps.
    pub(super) fn position(&self) -> i32 {
        self.position.round() as i32
    }

    /// The step rate, steps/s.
    pub(super) fn velocity(&self) -> i32 {
        self.velocity.round() as i32
    }

    /// The status letter's meaning.
    pub(super) fn motion(&self) -> Motion {
        match self.mode {
            Mode::Off => Motion::Off,
            Mode::Hold => Motion::Idle,
            Mode::Move { .. } | Mode::Jog { .. } | Mode::Stop { .. } => Motion::Moving,
        }
    }

    /// `M`: a move from wherever it is, at whatever rate it steps now.
    pub(super) fn go_to(&mut self, target: i32, speed: u32, accel: u32) {
        self.mode = Mode::Move {
            target: f64::from(target),
            speed: f64::from(speed),
            accel: f64::from(accel),
        };
    }

    /// `V`.
    pub(super) fn jog(&mut self, velocity: i32, accel: u32) {
        self.mode = Mode::Jog {
            velocity: f64::from(velocity),
            accel: f64::from(accel),
        };
    }

    /// `S` (a standing motor just holds).
    pub(super) fn stop(&mut self, decel: u32) {
        self.mode = match self.mode {
            Mode::Hold | Mode::Off => Mode::Hold,
            _ => Mode::Stop {
                decel: f64::from(decel),
            },
        };
    }

    /// `Z`: the counter is offset; a move's target moves with it.
    pub(super) fn set_position(&mut self, position: i32) {
        let offset = f64::from(position) - self.position.round();
        self.position += offset;
        if let Mode::Move { target, .. } = &mut self.mode {
            *target += offset;
        }
    }

    /// `O`: coils off; the model's rotor stops where it is.
    pub(super) fn off(&mut self) {
        self.mode = Mode::Off;
        self.velocity = 0.0;
    }

    /// Lets `seconds` pass.
    pub(super) fn advance(&mut self, seconds: f64) {
        let mut left = seconds;
        while left > 0.0 && !matches!(self.mode, Mode::Hold | Mode::Off) {
            let dt = left.min(DT);
            self.integrate(dt);
            left -= dt;
        }
    }

    fn integrate(&mut self, dt: f64) {
        match self.mode {
            Mode::Hold | Mode::Off => self.velocity = 0.0,
            Mode::Move {
                target,
                speed,
                accel,
            } => {
                let distance = target - self.position;
                // The fastest rate from which it still stops at the target, capped at speed.
                let wanted = distance.signum() * speed.min((2.0 * accel * distance.abs()).sqrt());
                self.velocity = approach(self.velocity, wanted, accel * dt);
                let next = self.position + self.velocity * dt;
                if distance.abs() < 0.5 || (target - next).signum() != distance.signum() {
                    self.position = target;
                    self.velocity = 0.0;
                    self.mode = Mode::Hold;
                } else {
                    self.position = next;
                }
            }
            Mode::Jog { velocity, accel } => {
                self.velocity = approach(self.velocity, velocity, accel * dt);
                self.position += self.velocity * dt;
                if velocity == 0.0 && self.velocity == 0.0 {
                    self.settle();
                }
            }
            Mode::Stop { decel } => {
                self.velocity = approach(self.velocity, 0.0, decel * dt);
                self.position += self.velocity * dt;
                if self.velocity == 0.0 {
                    self.settle();
                }
            }
        }
    }

    /// Standing still: on a whole step, holding.
    fn settle(&mut self) {
        self.position = self.position.round();
        self.mode = Mode::Hold;
    }
}

#[cfg(test)]
mod tests {
    use super::{Motion, Stepper};

    #[test]
    fn a_move_ramps_cruises_and_lands_on_its_target() {
        let mut stepper = Stepper::new();
        stepper.go_to(1000, 2000, 10_000);
        stepper.advance(0.1);
        // After 0.1 s at 10 000 steps/s²: 1000 steps/s, 50 steps.
        assert!((stepper.velocity() - 1000).abs() <= 2, "{stepper:?}");
        assert!((stepper.position() - 50).abs() <= 2, "{stepper:?}");
        assert_eq!(stepper.motion(), Motion::Moving);
        // Trapezoid: 0.2 s (200 steps) up to 2000 steps/s, 0.3 s cruise (600 steps), 0.2 s
        // (200 steps) down: 0.7 s.
        stepper.advance(0.3);
        assert_eq!(stepper.velocity(), 2000);
        stepper.advance(0.27);
        assert_eq!(stepper.motion(), Motion::Moving);
        stepper.advance(0.04);
        assert_eq!((stepper.position(), stepper.velocity()), (1000, 0));
        assert_eq!(stepper.motion(), Motion::Idle);
    }

    #[test]
    fn a_jog_runs_and_a_stop_ramps_down_onto_a_whole_step() {
        let mut stepper = Stepper::new();
        stepper.jog(-500, 5000);
        stepper.advance(1.0);
        assert_eq!(stepper.velocity(), -500);
        stepper.stop(1000);
        stepper.advance(0.25);
        assert_eq!(stepper.velocity(), -250);
        stepper.advance(0.3);
        assert_eq!((stepper.velocity(), stepper.motion()), (0, Motion::Idle));
        stepper.set_position(7);
        assert_eq!(stepper.position(), 7);
        stepper.off();
        assert_eq!(stepper.motion(), Motion::Off);
    }
}
