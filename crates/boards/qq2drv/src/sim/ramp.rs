//! Setpoint generators of the control loop: the position profile (packets 20 and 34, with
//! the velocity and acceleration limits of 26 and 28) and the velocity ramp (22 and 36).
//!
//! Both step once per control period. An acceleration of 0 means "not limited".

/// Trapezoidal position setpoint that decelerates in advance so it stops on the target.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct PositionProfile {
    /// Internal position target (setpoint), transitions.
    pub(crate) position: f64,
    /// Setpoint velocity, transitions/s.
    pub(crate) velocity: f64,
    /// Final target, transitions.
    pub(crate) target: f64,
    /// Velocity bound, transitions/s.
    pub(crate) max_velocity: f64,
    /// Acceleration bound, transitions/s²; 0 = unlimited.
    pub(crate) max_acceleration: f64,
}

impl PositionProfile {
    /// Holds `position` still.
    pub(crate) fn hold(position: f64) -> Self {
        Self {
            position,
            velocity: 0.0,
            target: position,
            max_velocity: 0.0,
            max_acceleration: 0.0,
        }
    }

    /// Whether the setpoint has reached the target and stopped.
    pub(crate) fn done(&self) -> bool {
        self.position == self.target && self.velocity == 0.0
    }

    /// Advances the setpoint by one period of `dt` seconds.
    pub(crate) fn step(&mut self, dt: f64) {
        let d = self.target - self.position;
        let vmax = self.max_velocity.max(0.0);
        let a = self.max_acceleration;
        if a <= 0.0 {
            let v = (d / dt).clamp(-vmax, vmax);
            self.velocity = v;
            self.position = if (v * dt - d).abs() < 1e-9 {
                self.target
            } else {
                self.position + v * dt
            };
            if self.position == self.target {
                self.velocity = 0.0;
            }
            return;
        }
        // Fastest velocity from which we can still stop on the target in whole periods.
        let half = a * dt / 2.0;
        let brake = -half + (half * half + 2.0 * a * d.abs()).sqrt();
        let desired = brake.min(vmax).copysign(d);
        let dv = (desired - self.velocity).clamp(-a * dt, a * dt);
        let v = self.velocity + dv;
        let next = self.position + v * dt;
        let overshot = (self.target - next) * d < 0.0 || d == 0.0;
        if (overshot || (self.target - next).abs() < 1e-6) && v.abs() <= a * dt + 1e-9 {
            // Arrived: stop now if that is within one period's acceleration, else next period.
            self.position = self.target;
            self.velocity = if self.velocity.abs() <= a * dt + 1e-9 {
                0.0
            } else {
                v
            };
        } else {
            self.position = next;
            self.velocity = v;
        }
    }
}

/// Velocity setpoint ramped towards a target at a bounded rate.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct VelocityRamp {
    /// Setpoint velocity, transitions/s.
    pub(crate) velocity: f64,
    /// Final target, transitions/s (already clipped to the velocity limit).
    pub(crate) target: f64,
    /// Ramp rate, transitions/s²; 0 = jump.
    pub(crate) max_acceleration: f64,
}

impl VelocityRamp {
    /// Advances the setpoint by one period of `dt` seconds.
    pub(crate) fn step(&mut self, dt: f64) {
        let a = self.max_acceleration;
        self.velocity = if a <= 0.0 {
            self.target
        } else {
            self.velocity + (self.target - self.velocity).clamp(-a * dt, a * dt)
        };
    }
}

/// The smaller of two acceleration bounds where 0 means "no bound".
pub(crate) fn min_limit(a: f64, b: f64) -> f64 {
    match (a > 0.0, b > 0.0) {
        (true, true) => a.min(b),
        (true, false) => a,
        (false, true) => b,
        (false, false) => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::{PositionProfile, VelocityRamp, min_limit};

    #[test]
    fn profile_respects_limits_and_stops_on_target() {
        let dt = 0.002;
        let mut p = PositionProfile {
            target: 10_000.0,
            max_velocity: 3_000.0,
            max_acceleration: 20_000.0,
            ..PositionProfile::hold(0.0)
        };
        let mut prev_v = 0.0;
        let mut steps = 0;
        while !p.done() {
            p.step(dt);
            assert!(p.velocity.abs() <= 3_000.0 + 1e-9);
            assert!(
                (p.velocity - prev_v).abs() <= 20_000.0 * dt + 1e-6,
                "{steps} {prev_v} -> {} at {} ",
                p.velocity,
                p.position
            );
            assert!(p.position <= 10_000.0 + 1e-9);
            prev_v = p.velocity;
            steps += 1;
            assert!(steps < 10_000);
        }
        // 10 000 at 3 000/s plus the ramps: about 3.48 s.
        assert!((3.3..3.7).contains(&(f64::from(steps) * dt)), "{steps}");
    }

    #[test]
    fn profile_without_acceleration_limit_moves_at_velocity_limit() {
        let mut p = PositionProfile {
            target: -100.0,
            max_velocity: 10_000.0,
            ..PositionProfile::hold(0.0)
        };
        p.step(0.002);
        assert_eq!(p.position, -20.0);
        for _ in 0..4 {
            p.step(0.002);
        }
        assert!(p.done());
    }

    #[test]
    fn velocity_ramp_rate() {
        let mut r = VelocityRamp {
            velocity: 0.0,
            target: 1000.0,
            max_acceleration: 10_000.0,
        };
        r.step(0.002);
        assert_eq!(r.velocity, 20.0);
        assert_eq!(min_limit(0.0, 5.0), 5.0);
        assert_eq!(min_limit(3.0, 5.0), 3.0);
    }
}
