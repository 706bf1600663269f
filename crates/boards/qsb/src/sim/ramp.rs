//! The -M stepper drive: trapezoidal moves and jogs at MD STEP RATE / MD JOG RATE with MD
//! ACCEL, stop and pause with MD ACCEL, quit at once.
//!
//! The motion is integrated exactly, phase by phase (constant acceleration within a phase),
//! so it never exceeds the step rate or the acceleration and a move ends exactly on its
//! target step, whatever the time steps it is advanced by.

/// What the drive is doing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Goal {
    /// Standing still.
    Idle,
    /// Moving to an absolute step position.
    Move { target: f64 },
    /// Running at a signed rate, steps/s.
    Jog { rate: f64 },
    /// Decelerating to a standstill (stop or pause).
    Stop,
}

/// Stepper state, in steps and steps/s.
#[derive(Debug, Clone)]
pub(crate) struct Stepper {
    pub position: f64,
    pub velocity: f64,
    pub acceleration: f64,
    pub goal: Goal,
    /// The goal a pause interrupted, resumed by COMMAND 7.
    pub paused: Option<Goal>,
}

/// Relative tolerance of the phase arithmetic.
const EPS: f64 = 1e-9;

impl Stepper {
    pub(crate) fn new() -> Self {
        Self {
            position: 0.0,
            velocity: 0.0,
            acceleration: 0.0,
            goal: Goal::Idle,
            paused: None,
        }
    }

    /// The whole step the motor is on.
    pub(crate) fn step(&self) -> i64 {
        self.position.round() as i64
    }

    pub(crate) fn moving(&self) -> bool {
        self.velocity != 0.0 || !matches!(self.goal, Goal::Idle)
    }

    pub(crate) fn start_move(&mut self, steps: i32) {
        self.paused = None;
        self.goal = Goal::Move {
            target: self.step() as f64 + f64::from(steps),
        };
    }

    pub(crate) fn start_jog(&mut self, rate: f64) {
        self.paused = None;
        self.goal = Goal::Jog { rate };
    }

    /// COMMAND 4: decelerate to a standstill.
    pub(crate) fn stop(&mut self) {
        self.paused = None;
        if self.moving() {
            self.goal = Goal::Stop;
        }
    }

    /// COMMAND 5 and 0: stop at once.
    pub(crate) fn quit(&mut self) {
        self.paused = None;
        self.velocity = 0.0;
        self.acceleration = 0.0;
        self.goal = Goal::Idle;
    }

    /// COMMAND 6: decelerate, remembering the goal.
    pub(crate) fn pause(&mut self) {
        if matches!(self.goal, Goal::Move { .. } | Goal::Jog { .. }) {
            self.paused = Some(self.goal);
            self.goal = Goal::Stop;
        }
    }

    /// COMMAND 7: resume a paused goal.
    pub(crate) fn resume(&mut self) {
        if let Some(goal) = self.paused.take() {
            self.goal = goal;
        }
    }

    /// The acceleration to apply now and how long it holds, seconds (infinite for a
    /// cruise that ends only on a new command). `None`: the goal is reached.
    fn phase(&mut self, vmax: f64, accel: f64) -> Option<(f64, f64)> {
        let v = self.velocity;
        match self.goal {
            Goal::Idle => None,
            Goal::Stop => {
                if v == 0.0 {
                    self.goal = Goal::Idle;
                    None
                } else {
                    Some((-v.signum() * accel, v.abs() / accel))
                }
            }
            Goal::Jog { rate } => {
                if v == rate {
                    Some((0.0, f64::INFINITY))
                } else {
                    Some(((rate - v).signum() * accel, (rate - v).abs() / accel))
                }
            }
            Goal::Move { target } => {
                let d = target - self.position;
                if d.abs() <= EPS && v.abs() <= EPS {
                    self.position = target;
                    self.velocity = 0.0;
                    self.goal = Goal::Idle;
                    return None;
                }
                let s = if d.abs() <= EPS {
                    -v.signum()
                } else {
                    d.signum()
                };
                let dist = d.abs();
                let u = s * v; // speed towards the target
                if u < 0.0 {
                    return Some((s * accel, -u / accel));
                }
                let braking = u * u / (2.0 * accel);
                if braking >= dist * (1.0 - EPS) {
                    if braking <= dist * (1.0 + 1e-6) + EPS && dist > 0.0 {
                        // On the braking curve: land exactly on the target.
                        let a = u * u / (2.0 * dist);
                        return Some((-s * a, 2.0 * dist / u));
                    }
                    // Too fast to stop in time: stop, then come back.
                    return Some((-s * accel, u / accel));
                }
                if u > vmax * (1.0 + EPS) {
                    return Some((-s * accel, (u - vmax) / accel));
                }
                if u < vmax * (1.0 - EPS) {
                    let to_vmax = (vmax - u) / accel;
                    let to_brake = ((u * u / 2.0 + accel * dist).sqrt() - u) / accel;
                    return Some((s * accel, to_vmax.min(to_brake)));
                }
                let cruise = (dist - vmax * vmax / (2.0 * accel)) / vmax;
                Some((0.0, cruise.max(0.0)))
            }
        }
    }

    /// Advances by `dt` seconds at `vmax` (move rate, steps/s) and `accel` (steps/s²).
    pub(crate) fn advance(&mut self, mut dt: f64, vmax: f64, accel: f64) {
        for _ in 0..64 {
            let Some((a, duration)) = self.phase(vmax, accel) else {
                self.acceleration = 0.0;
                self.velocity = 0.0;
                return;
            };
            self.acceleration = a;
            if dt <= 0.0 {
                return;
            }
            let step = dt.min(duration);
            self.position += self.velocity * step + 0.5 * a * step * step;
            self.velocity += a * step;
            dt -= step;
            if step >= duration {
                self.finish_phase(vmax);
            }
        }
    }

    /// Snaps the state at a phase end so that rounding never accumulates.
    fn finish_phase(&mut self, vmax: f64) {
        match self.goal {
            Goal::Stop => {
                self.velocity = 0.0;
                self.goal = Goal::Idle;
            }
            Goal::Jog { rate } => {
                if (self.velocity - rate).abs() <= EPS * rate.abs().max(1.0) {
                    self.velocity = rate;
                }
            }
            Goal::Move { target } => {
                let d = target - self.position;
                if d.abs() <= 1e-6 && self.velocity.abs() <= 1e-3 {
                    self.position = target;
                    self.velocity = 0.0;
                    self.goal = Goal::Idle;
                } else if self.velocity.abs() <= EPS * vmax.max(1.0) {
                    self.velocity = 0.0;
                } else if (self.velocity.abs() - vmax).abs() <= EPS * vmax {
                    self.velocity = vmax * self.velocity.signum();
                }
            }
            Goal::Idle => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn move_lands_on_target_within_limits() {
        for (steps, vmax, accel, dt) in [
            (2000, 1000.0, 100_000.0, 1e-4),
            (2000, 1000.0, 64.0, 0.013),
            (-7, 13_000.0, 360_000.0, 1e-5),
            (1, 32.0, 64.0, 0.5),
            (100_000, 13_000.0, 1000.0, 0.01),
        ] {
            let mut s = Stepper::new();
            s.start_move(steps);
            let mut t = 0.0;
            let mut last_v = 0.0;
            while s.moving() {
                s.advance(dt, vmax, accel);
                t += dt;
                assert!(
                    s.velocity.abs() <= vmax * (1.0 + 1e-9),
                    "{steps} v {}",
                    s.velocity
                );
                assert!((s.velocity - last_v).abs() <= accel * dt * (1.0 + 1e-6) + 1e-9);
                last_v = s.velocity;
                assert!(t < 1000.0, "never arrives");
            }
            assert_eq!(s.position, f64::from(steps));
        }
    }

    #[test]
    fn pause_resume_and_reversal() {
        let mut s = Stepper::new();
        s.start_jog(-500.0);
        s.advance(1.0, 1000.0, 1000.0);
        assert_eq!(s.velocity, -500.0);
        s.start_move(10); // from a run in the other direction: stop, come back
        let mut guard = 0;
        while s.moving() {
            s.advance(0.001, 1000.0, 1000.0);
            guard += 1;
            assert!(guard < 100_000);
        }
        assert_eq!(s.step(), s.position as i64);
        s.start_move(5000);
        s.advance(0.5, 1000.0, 1000.0);
        s.pause();
        s.advance(2.0, 1000.0, 1000.0);
        assert_eq!(s.velocity, 0.0);
        assert!(s.paused.is_some());
        s.resume();
        s.advance(100.0, 1000.0, 1000.0);
        assert!(!s.moving());
    }
}
