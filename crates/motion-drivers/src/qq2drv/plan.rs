//! The packets each step of a channel's goal sends ([`Step`] → [`Packets`]).

use qq2drv::{ControlMode, EdgeAction, InputConfig, InputMode};

use super::channel::Channel;
use super::config::HomeInput;
use super::packet::{Packet, Packets};
use super::step::Step;

impl Channel {
    /// Packet 14 for the home input: armed (mode, polarity, Spacing, set the counter on
    /// the switch's end) or disarmed (Disabled, polarity kept so Input Active stays
    /// meaningful).
    pub(super) fn input(&self, armed: bool) -> Packet {
        let home = self.config.home.unwrap_or(HomeInput {
            mode: InputMode::Disabled,
            active_high: false,
            positive_end: true,
            position: 0,
            spacing: 0,
        });
        let edge = if home.positive_end {
            EdgeAction::SetOnPositive
        } else {
            EdgeAction::SetOnNegative
        };
        let mode = if armed {
            home.mode
        } else {
            InputMode::Disabled
        };
        Packet::Input {
            config: InputConfig::new(mode, home.active_high, edge),
            spacing: home.spacing,
            position: home.position,
        }
    }

    /// Packet 28 with the channel's own acceleration limit (as start-up writes it).
    pub(super) fn accel_limit(&self) -> Packet {
        Packet::AccelLimit(super::startup::accel_limit(self.config.limits.max_accel))
    }

    /// The packets of the current step, in order.
    pub(super) fn packets(&self) -> Packets {
        use Packet::{Mode, Target, VelocityRamp};
        let position_mode = Mode(ControlMode::PositionPid);
        let velocity_mode = Mode(ControlMode::VelocityPid);
        let mut out = Packets::default();
        if self.step == Step::Idle {
            return out;
        }
        // Whatever was armed or lifted before is put back first (a home search's input,
        // a stop's lifted acceleration limit), except by the steps that need it so.
        if self.armed
            && !matches!(
                self.step,
                Step::HomeSearch { .. } | Step::HomeBackoff { .. }
            )
        {
            out.push(self.input(false));
        }
        if self.lifted && !self.step.keeps_limit_lifted() {
            out.push(self.accel_limit());
        }
        match self.step {
            Step::Idle => {}
            Step::Off => {
                out.push(Mode(ControlMode::Off));
            }
            Step::Power(power) => {
                out.push(Mode(ControlMode::Power));
                out.push(Packet::Power(power));
            }
            Step::Position(target) => {
                out.push(position_mode);
                out.push(Target(target));
            }
            Step::Ramp {
                position,
                velocity,
                accel,
            } => {
                out.push(position_mode);
                out.push(Packet::PositionRamp {
                    position,
                    velocity,
                    accel,
                });
            }
            Step::Velocity { velocity, accel } => {
                out.push(velocity_mode);
                out.push(VelocityRamp { velocity, accel });
            }
            Step::Stop { .. } | Step::StopLift { .. } => {
                let velocity = match self.step {
                    Step::StopLift { velocity, .. } => velocity,
                    _ => self.velocity,
                };
                out.push(Mode(ControlMode::Off));
                out.push(velocity_mode);
                out.push(Packet::AccelLimit(0));
                out.push(VelocityRamp { velocity, accel: 0 });
            }
            Step::StopRamp { accel, .. } => {
                out.push(VelocityRamp { velocity: 0, accel });
            }
            Step::Hold => {
                out.push(position_mode);
                out.push(Target(self.position));
            }
            Step::SetCounter(value) => {
                out.push(Packet::SetCounter(value));
                if self.board_mode != ControlMode::Off {
                    out.push(position_mode);
                    out.push(Target(value));
                }
            }
            Step::HomeBackoff { velocity, accel } => {
                out.push(self.input(false));
                out.push(velocity_mode);
                out.push(VelocityRamp { velocity, accel });
            }
            Step::HomeSearch { velocity, accel } => {
                out.push(self.input(true));
                out.push(velocity_mode);
                out.push(VelocityRamp { velocity, accel });
            }
        }
        out
    }
}
