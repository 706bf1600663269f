//! A brushed DC motor on one H-bridge: first-order speed response to the PWM intensity.

use core::time::Duration;

use spimotor::Direction;

use super::config::BrushedMotorConfig;

/// What the firmware drives an H-bridge with (ports 0x20–0x22 / 0x30–0x32).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Bridge {
    /// Stopped (power-on state, and after 0x22 / 0x32): the bridge brakes the motor.
    #[default]
    Stopped,
    /// Spinning in a direction with an intensity (0–255).
    Spin {
        /// Direction A (positive speed in the model) or B (negative).
        direction: Direction,
        /// PWM intensity, 255 = full.
        intensity: u8,
    },
}

/// True state of one brushed motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DcMotor {
    /// What the bridge is driving.
    pub bridge: Bridge,
    /// Speed factor drawn at the last spin command (`1 ± speed_noise`).
    pub factor: f64,
    /// Shaft speed, revolutions per second (direction A positive).
    pub velocity: f64,
    /// Shaft angle, revolutions since power-on of the simulation.
    pub position: f64,
}

impl DcMotor {
    pub const fn new() -> Self {
        Self {
            bridge: Bridge::Stopped,
            factor: 1.0,
            velocity: 0.0,
            position: 0.0,
        }
    }

    /// The speed the motor settles at under the current bridge command.
    pub fn settled_velocity(&self, config: &BrushedMotorConfig) -> f64 {
        match self.bridge {
            Bridge::Stopped => 0.0,
            Bridge::Spin {
                direction,
                intensity,
            } => {
                let sign = match direction {
                    Direction::A => 1.0,
                    Direction::B => -1.0,
                };
                sign * f64::from(intensity) / 255.0 * config.no_load_speed * self.factor
            }
        }
    }

    /// Integrates the first-order response exactly over `dt` (the bridge command is
    /// constant in between: commands only change at transactions).
    pub fn advance(&mut self, dt: Duration, config: &BrushedMotorConfig) {
        let dt = dt.as_secs_f64();
        if dt <= 0.0 {
            return;
        }
        let target = self.settled_velocity(config);
        let tau = config.time_constant.as_secs_f64();
        if tau <= 0.0 {
            self.velocity = target;
            self.position += target * dt;
            return;
        }
        let decay = (-dt / tau).exp();
        let gap = self.velocity - target;
        self.position += target * dt + gap * tau * (1.0 - decay);
        self.velocity = target + gap * decay;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_integration_does_not_depend_on_step_size() {
        let config = BrushedMotorConfig::default();
        let spin = Bridge::Spin {
            direction: Direction::B,
            intensity: 200,
        };
        let mut coarse = DcMotor::new();
        coarse.bridge = spin;
        let mut fine = coarse;
        coarse.advance(Duration::from_millis(100), &config);
        for _ in 0..1000 {
            fine.advance(Duration::from_micros(100), &config);
        }
        assert!((coarse.velocity - fine.velocity).abs() < 1e-9);
        assert!((coarse.position - fine.position).abs() < 1e-9);
        assert!(coarse.velocity < 0.0);
        let settled = coarse.settled_velocity(&config);
        assert!((settled + 200.0 / 255.0 * 100.0).abs() < 1e-9);
        // Never past the settled speed when starting from rest.
        assert!(coarse.velocity >= settled);
    }
}
