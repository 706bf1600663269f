//! The per-channel control loop that runs at 500 Hz: the four control modes, the PID
//! controllers, the setpoint generators and the power/velocity/acceleration limits.
//!
//! The datasheet gives the PID constants' defaults but not their units. This model scales
//! them so that the defaults give a well-damped loop on the default motor:
//! position `power = P/4·e + I/5·∫e dt − D/1200·v` (e in transitions, v the measured
//! velocity in transitions/s, integral term clipped to ±Windup Limit and integrating only
//! while the setpoint is at rest and P·e is within the windup limit), velocity `power = P/100·e + I/5·∫e dt + D/100000·de/dt`
//! (e in transitions/s, integral term clipped to ±8191).

use qq2drv::limits::{POSITION_PID_DEFAULT, POWER_MAX, VELOCITY_PID_DEFAULT, from_fixed};
use qq2drv::{ControlMode, PositionPidEntry, VelocityPidEntry};

use super::ramp::{PositionProfile, VelocityRamp, min_limit};

/// Default velocity limit (packet 26): the top of its range, i.e. no limit.
pub(crate) const DEFAULT_VELOCITY_LIMIT: u32 = qq2drv::limits::VELOCITY_LIMIT_MAX;

/// Control state of one channel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Controller {
    pub(crate) mode: ControlMode,
    /// Packet 18 power, applied in Power mode.
    pub(crate) power: i16,
    /// Packet 24.
    pub(crate) power_limit: u16,
    /// Packet 26, shl 12 as sent.
    pub(crate) velocity_limit: u32,
    /// Packet 28, shl 12 as sent; 0 = not limited.
    pub(crate) acceleration_limit: u32,
    pub(crate) position_pid: PositionPidEntry,
    pub(crate) velocity_pid: VelocityPidEntry,
    pub(crate) profile: PositionProfile,
    /// Extra bounds of a packet-34 ramp (velocity, acceleration), until a new target.
    ramp_bounds: Option<(f64, f64)>,
    pub(crate) velocity_ramp: VelocityRamp,
    /// Extra acceleration bound of a packet-36 ramp.
    velocity_ramp_accel: f64,
    integral: f64,
    prev_error: f64,
    prev_count: f64,
    velocity_estimate: f64,
}

impl Controller {
    pub(crate) fn new() -> Self {
        let (p, i, d, windup) = POSITION_PID_DEFAULT;
        let (vp, vi, vd) = VELOCITY_PID_DEFAULT;
        let all = qq2drv::ChannelMask::ALL;
        Self {
            mode: ControlMode::Off,
            power: 0,
            power_limit: qq2drv::limits::POWER_LIMIT_MAX,
            velocity_limit: DEFAULT_VELOCITY_LIMIT,
            acceleration_limit: 0,
            position_pid: PositionPidEntry {
                channels: all,
                p,
                i,
                d,
                windup,
            },
            velocity_pid: VelocityPidEntry {
                channels: all,
                p: vp,
                i: vi,
                d: vd,
            },
            profile: PositionProfile::hold(0.0),
            ramp_bounds: None,
            velocity_ramp: VelocityRamp::default(),
            velocity_ramp_accel: 0.0,
            integral: 0.0,
            prev_error: 0.0,
            prev_count: 0.0,
            velocity_estimate: 0.0,
        }
    }

    fn velocity_limit(&self) -> f64 {
        from_fixed(self.velocity_limit)
    }

    fn acceleration_limit(&self) -> f64 {
        from_fixed(self.acceleration_limit)
    }

    /// Packet 16. Entering a PID mode holds the current position / velocity.
    pub(crate) fn set_mode(&mut self, mode: ControlMode, count: f64) {
        if mode == self.mode {
            return;
        }
        self.mode = mode;
        self.integral = 0.0;
        self.prev_error = 0.0;
        self.prev_count = count;
        self.ramp_bounds = None;
        match mode {
            ControlMode::PositionPid => self.profile = PositionProfile::hold(count),
            ControlMode::VelocityPid => {
                self.velocity_ramp = VelocityRamp {
                    velocity: self.velocity_estimate,
                    target: 0.0,
                    max_acceleration: 0.0,
                };
                self.velocity_ramp_accel = 0.0;
            }
            ControlMode::Off | ControlMode::Power => {}
        }
    }

    /// Packet 20: new target under the configured velocity and acceleration limits.
    pub(crate) fn set_position_target(&mut self, target: i32) {
        self.profile.target = f64::from(target);
        self.ramp_bounds = None;
    }

    /// Packet 34: ramp to `target` at `velocity` and `acceleration` (both shl 12).
    pub(crate) fn position_ramp(&mut self, target: i32, velocity: u32, acceleration: u32) {
        self.profile.target = f64::from(target);
        self.ramp_bounds = Some((from_fixed(velocity), from_fixed(acceleration)));
    }

    /// Packet 22: velocity target in transitions/s.
    pub(crate) fn set_velocity_target(&mut self, velocity: i32) {
        self.velocity_ramp.target = f64::from(velocity);
        self.velocity_ramp_accel = 0.0;
    }

    /// Packet 36: velocity target in transitions/s at `acceleration` (shl 12; 0 ignored).
    pub(crate) fn velocity_ramp(&mut self, velocity: i32, acceleration: u32) {
        self.velocity_ramp.target = f64::from(velocity);
        self.velocity_ramp_accel = from_fixed(acceleration);
    }

    /// The position counter was set (packet 10 or an input trigger): move the loop's
    /// position frame with it so the motor does not jump.
    pub(crate) fn shift(&mut self, delta: f64) {
        self.profile.position += delta;
        self.profile.target += delta;
        self.prev_count += delta;
    }

    /// One control period of `dt` seconds with the encoder at `count`; returns the power.
    pub(crate) fn tick(&mut self, count: f64, dt: f64) -> i16 {
        let raw_velocity = (count - self.prev_count) / dt;
        self.prev_count = count;
        // 5 ms low-pass on the count difference: the loop's velocity feedback.
        let alpha = dt / (0.005 + dt);
        self.velocity_estimate += alpha * (raw_velocity - self.velocity_estimate);
        let power = match self.mode {
            ControlMode::Off => 0.0,
            ControlMode::Power => f64::from(self.power),
            ControlMode::PositionPid => self.position_loop(count, dt),
            ControlMode::VelocityPid => self.velocity_loop(dt),
        };
        let limit = f64::from(self.power_limit.min(POWER_MAX.unsigned_abs()));
        power.clamp(-limit, limit).round() as i16
    }

    fn position_loop(&mut self, count: f64, dt: f64) -> f64 {
        let (vmax, amax) = match self.ramp_bounds {
            Some((v, a)) => (
                v.min(self.velocity_limit()),
                min_limit(a, self.acceleration_limit()),
            ),
            None => (self.velocity_limit(), self.acceleration_limit()),
        };
        self.profile.max_velocity = vmax;
        self.profile.max_acceleration = amax;
        self.profile.step(dt);
        let pid = self.position_pid;
        let error = self.profile.position - count;
        // The integrator only runs once the setpoint has arrived and the error is inside the
        // band where P alone stays below the windup limit: it removes the friction offset at
        // rest without winding up during a move and overshooting at its end.
        let kp = f64::from(pid.p) / 4.0;
        let windup = f64::from(pid.windup);
        if self.profile.done() && kp * error.abs() <= windup {
            self.integral =
                (self.integral + f64::from(pid.i) / 5.0 * error * dt).clamp(-windup, windup);
        }
        // Derivative on the measured velocity, not on the error: no kick from the setpoint.
        kp * error + self.integral - f64::from(pid.d) / 1200.0 * self.velocity_estimate
    }

    fn velocity_loop(&mut self, dt: f64) -> f64 {
        let vlim = self.velocity_limit();
        self.velocity_ramp.target = self.velocity_ramp.target.clamp(-vlim, vlim);
        self.velocity_ramp.max_acceleration =
            min_limit(self.velocity_ramp_accel, self.acceleration_limit());
        self.velocity_ramp.step(dt);
        let pid = self.velocity_pid;
        let error = self.velocity_ramp.velocity - self.velocity_estimate;
        let max = f64::from(POWER_MAX);
        self.integral = (self.integral + f64::from(pid.i) / 5.0 * error * dt).clamp(-max, max);
        let derivative = (error - self.prev_error) / dt;
        self.prev_error = error;
        f64::from(pid.p) / 100.0 * error + self.integral + f64::from(pid.d) / 100_000.0 * derivative
    }
}
