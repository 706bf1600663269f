//! DC motor and quadrature encoder of one channel, and the firmware's capture-based velocity.

use std::collections::VecDeque;

use qq2drv::limits::{POWER_MAX, TRANSITIONS_PER_DETENT, VELOCITY_RESOLUTION};

use super::config::MotorConfig;

/// Capture events kept per channel (History Length is at most 127).
const EVENT_CAPACITY: usize = 128;

/// One capture event: the instant (seconds since the model's epoch) a detent boundary was
/// crossed, and the direction of the crossing.
#[derive(Debug, Clone, Copy)]
struct Capture {
    at: f64,
    forward: bool,
}

/// A DC motor under PWM with an incremental encoder on its shaft.
#[derive(Debug, Clone)]
pub(crate) struct Motor {
    cfg: MotorConfig,
    /// Per-channel gain factor (drawn from the seeded generator).
    gain: f64,
    /// Shaft position in quadrature transitions (continuous).
    position: f64,
    /// Shaft velocity, transitions/s.
    velocity: f64,
    /// Output power currently applied, −8191..=8191.
    power: i16,
    captures: VecDeque<Capture>,
}

impl Motor {
    pub(crate) fn new(cfg: MotorConfig, gain: f64) -> Self {
        Self {
            cfg,
            gain,
            position: 0.0,
            velocity: 0.0,
            power: 0,
            captures: VecDeque::with_capacity(EVENT_CAPACITY),
        }
    }

    pub(crate) fn position(&self) -> f64 {
        self.position
    }

    pub(crate) fn velocity(&self) -> f64 {
        self.velocity
    }

    pub(crate) fn power(&self) -> i16 {
        self.power
    }

    pub(crate) fn set_power(&mut self, power: i16) {
        self.power = power.clamp(-POWER_MAX, POWER_MAX);
    }

    /// The encoder count: whole transitions.
    pub(crate) fn count(&self) -> i64 {
        self.position.floor() as i64
    }

    /// Quadrature lines A = B = 0 (one state in four per detent).
    pub(crate) fn ab_zero(&self) -> bool {
        self.count().rem_euclid(i64::from(TRANSITIONS_PER_DETENT)) == 0
    }

    /// Steady-state velocity for the applied power (friction is a dead band).
    fn steady_velocity(&self) -> f64 {
        let c = f64::from(self.power) / f64::from(POWER_MAX);
        let f = self.cfg.friction.clamp(0.0, 0.99);
        let effective = (c.abs() - f).max(0.0) / (1.0 - f);
        effective.copysign(c) * self.cfg.no_load_velocity * self.gain
    }

    /// Advances the shaft by `dt` seconds ending at `t_end` (seconds), recording the detent
    /// crossings as capture events. Exact for a first-order lag under constant power.
    pub(crate) fn step(&mut self, dt: f64, t_end: f64) {
        if dt <= 0.0 {
            return;
        }
        let v_ss = self.steady_velocity();
        let tau = self.cfg.time_constant.as_secs_f64().max(1e-6);
        let decay = (-dt / tau).exp();
        let v0 = self.velocity;
        let x0 = self.position;
        let x1 = x0 + v_ss * dt + (v0 - v_ss) * tau * (1.0 - decay);
        self.velocity = v_ss + (v0 - v_ss) * decay;
        self.position = x1;
        self.record_captures(x0, x1, t_end - dt, dt);
    }

    /// Moves the shaft by an external force (test hook): the count jumps, no captures.
    pub(crate) fn displace(&mut self, delta: f64) {
        self.position += delta;
    }

    fn record_captures(&mut self, x0: f64, x1: f64, t0: f64, dt: f64) {
        let detent = f64::from(TRANSITIONS_PER_DETENT);
        let d0 = (x0 / detent).floor();
        let d1 = (x1 / detent).floor();
        if d0 == d1 || x1 == x0 {
            return;
        }
        let forward = d1 > d0;
        let crossings = (d1 - d0).abs().min(EVENT_CAPACITY as f64) as i64;
        for k in 1..=crossings {
            let boundary = if forward {
                (d0 + k as f64) * detent
            } else {
                (d0 - k as f64 + 1.0) * detent
            };
            let frac = ((boundary - x0) / (x1 - x0)).clamp(0.0, 1.0);
            if self.captures.len() == EVENT_CAPACITY {
                self.captures.pop_front();
            }
            self.captures.push_back(Capture {
                at: t0 + frac * dt,
                forward,
            });
        }
    }

    /// The velocity the firmware reports at `now` (seconds): the average over the last
    /// `history_length` capture events no older than `max_averaging` seconds, winding down
    /// when the events stop coming, quantised to the 4 transitions/s resolution.
    pub(crate) fn measured_velocity(
        &self,
        now: f64,
        history_length: u8,
        max_averaging: f64,
    ) -> i32 {
        let oldest_allowed = now - max_averaging;
        let take = usize::from(history_length).max(2);
        let mut count = 0usize;
        let mut first = now;
        let mut last = now;
        let mut net = 0i64;
        let mut oldest_dir = 0i64;
        for c in self
            .captures
            .iter()
            .rev()
            .take_while(|c| c.at >= oldest_allowed)
            .take(take)
        {
            let dir = if c.forward { 1 } else { -1 };
            net += dir;
            oldest_dir = dir;
            if count == 0 {
                last = c.at;
            }
            count += 1;
            first = c.at;
        }
        if count < 2 {
            return 0;
        }
        // The oldest event only opens the first interval; every later one closes one.
        let net = (net - oldest_dir) as f64;
        let intervals = (count - 1) as f64;
        let span = (last - first).max(1e-9);
        // No new event for longer than the average interval: the average winds down.
        let span = if now - last > span / intervals {
            now - first
        } else {
            span
        };
        let v = f64::from(TRANSITIONS_PER_DETENT) * net / span;
        let res = f64::from(VELOCITY_RESOLUTION);
        let q = (v / res).round() * res;
        q.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }

    /// Forgets capture history (position set by a command does not move the shaft, but a
    /// power cycle does clear it).
    pub(crate) fn clear_captures(&mut self) {
        self.captures.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::{Motor, MotorConfig};

    #[test]
    fn full_power_approaches_no_load_velocity() {
        let cfg = MotorConfig {
            friction: 0.0,
            ..MotorConfig::default()
        };
        let mut m = Motor::new(cfg, 1.0);
        m.set_power(8191);
        let mut t = 0.0;
        for _ in 0..2000 {
            t += 1e-4;
            m.step(1e-4, t);
        }
        assert!(
            (m.velocity() - cfg.no_load_velocity).abs() < 1.0,
            "{}",
            m.velocity()
        );
        let measured = m.measured_velocity(t, 31, 0.67);
        assert!(
            (f64::from(measured) - cfg.no_load_velocity).abs() < 20.0,
            "{measured}"
        );
    }

    #[test]
    fn friction_dead_band_holds_the_shaft() {
        let mut m = Motor::new(MotorConfig::default(), 1.0);
        m.set_power(100);
        m.step(0.5, 0.5);
        assert_eq!(m.velocity(), 0.0);
        assert_eq!(m.count(), 0);
    }

    #[test]
    fn measured_velocity_winds_down_after_stop() {
        let cfg = MotorConfig {
            friction: 0.0,
            ..MotorConfig::default()
        };
        let mut m = Motor::new(cfg, 1.0);
        m.set_power(-4000);
        let mut t = 0.0;
        for _ in 0..1000 {
            t += 1e-4;
            m.step(1e-4, t);
        }
        let moving = m.measured_velocity(t, 31, 0.67);
        assert!(moving < -2000, "{moving}");
        m.set_power(0);
        for _ in 0..5000 {
            t += 1e-4;
            m.step(1e-4, t);
        }
        assert_eq!(m.measured_velocity(t + 1.0, 31, 0.67), 0);
        assert_eq!(moving % 4, 0);
    }
}
