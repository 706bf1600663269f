//! The brushed channels: power goals onto ports 0x20–0x22 (motor A) and 0x30–0x32 (B).

use spimotor::{Direction, Motor, Write};

use super::SpimotorDriver;
use super::wire::Op;
use motion_drivers::{Goal, GoalError, GoalKind, Priority};

/// What the driver last put on one motor's bridge.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct BrushedMotor {
    /// Signed intensity last written: + direction A, − direction B, 0 stopped.
    power: i16,
}

impl BrushedMotor {
    /// Records a spin or stop write that went out.
    pub fn written(&mut self, write: Write) {
        self.power = match write {
            Write::Spin {
                direction: Direction::A,
                intensity,
                ..
            } => i16::from(intensity),
            Write::Spin {
                direction: Direction::B,
                intensity,
                ..
            } => -i16::from(intensity),
            _ => 0,
        };
    }

    /// Whether the bridge is driven (the motor spins, as far as the board was told).
    pub fn driven(&self) -> bool {
        self.power != 0
    }
}

/// The write that puts `goal` on `motor`'s bridge.
pub(super) fn bridge_write(motor: Motor, goal: Goal) -> Result<Write, GoalError> {
    match goal {
        Goal::Power { fraction } => {
            if !(fraction.is_finite() && fraction.abs() <= 1.0) {
                return Err(GoalError::OutOfBoardRange(GoalKind::Power));
            }
            // |fraction| ≤ 1: the product is within 0..=255.
            let intensity = (fraction.abs() * f64::from(u8::MAX)).round() as u8;
            Ok(if intensity == 0 {
                Write::Stop(motor)
            } else {
                Write::Spin {
                    motor,
                    direction: if fraction > 0.0 {
                        Direction::A
                    } else {
                        Direction::B
                    },
                    intensity,
                }
            })
        }
        Goal::Off | Goal::Stop { .. } => Ok(Write::Stop(motor)),
        other => Err(GoalError::Unsupported(other.kind())),
    }
}

impl SpimotorDriver {
    /// A goal for brushed channel `channel` (0 = A, 1 = B).
    pub(super) fn brushed_goal(&mut self, channel: usize, goal: Goal) -> Result<(), GoalError> {
        let tag = u8::try_from(channel).map_err(|_| GoalError::NoSuchChannel(channel))?;
        let motor = Motor::from_channel(tag).ok_or(GoalError::NoSuchChannel(channel))?;
        let write = bridge_write(motor, goal)?;
        if !self.running() || !self.status.online {
            // Start-up stops both motors anyway; nothing else can be done offline.
            return if matches!(write, Write::Stop(_)) {
                Ok(())
            } else {
                Err(GoalError::Offline)
            };
        }
        self.drop_goals(tag);
        if self.push_command(Op::Write(write), Priority::Command, tag) {
            Ok(())
        } else {
            Err(GoalError::Offline)
        }
    }
}
