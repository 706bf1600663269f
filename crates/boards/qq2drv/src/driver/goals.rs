//! Goals: what a channel accepts, a goal as the channel's next step (`channel.rs`), the
//! packets each step sends ([`Step`] → [`Packets`]) and the goal transaction that carries
//! them (module docs, "Goals").

use core::time::Duration;

use qq2drv::limits::VelocityRampSign;
use qq2drv::{CHANNELS, ControlMode, EdgeAction, InputConfig, InputMode};

use super::Qq2drvDriver;
use super::channel::{Channel, Step};
use super::config::HomeInput;
use super::wire::{Packet, Packets, Sent, Tag};
use motion_drivers::{Driver, Goal, GoalError, GoalKind, GoalKinds};

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
        Packet::AccelLimit(self.own_accel_limit())
    }

    /// The channel's own acceleration limit, shl 12.
    pub(super) fn own_accel_limit(&self) -> u32 {
        super::startup::accel_limit(self.config.limits.max_accel)
    }

    /// A velocity target ramped at `accel` (0: no ramp of its own, the limit applies):
    /// packet 36, or where the board reads packet 36 as forward only ("Range: 0 -
    /// 100,000") and `velocity` is negative, packet 28 with `accel` as the limit (none for
    /// 0; never above the channel's own, which "still applies" to packet 36 too) and packet
    /// 22, whose target the acceleration limit ramps the same way.
    fn velocity_ramp(&self, out: &mut Packets, velocity: i32, accel: u32) {
        if self.config.velocity_ramp == VelocityRampSign::Signed || velocity >= 0 {
            out.push(Packet::VelocityRamp { velocity, accel });
            return;
        }
        if accel != 0 {
            out.push(Packet::AccelLimit(accel.min(self.own_accel_limit())));
        }
        out.push(Packet::VelocityTarget(velocity));
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
                self.velocity_ramp(&mut out, velocity, accel);
            }
            Step::Stop { .. } | Step::StopLift { .. } => {
                let velocity = match self.step {
                    Step::StopLift { velocity, .. } => velocity,
                    _ => self.velocity,
                };
                out.push(Mode(ControlMode::Off));
                out.push(velocity_mode);
                out.push(Packet::AccelLimit(0));
                self.velocity_ramp(&mut out, velocity, 0);
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
                self.velocity_ramp(&mut out, velocity, accel);
            }
            Step::HomeSearch { velocity, accel } => {
                out.push(self.input(true));
                out.push(velocity_mode);
                self.velocity_ramp(&mut out, velocity, accel);
            }
        }
        out
    }
}

impl Qq2drvDriver {
    /// The goals `channel` accepts: every goal with a home input, all but `Home` without
    /// one, none on a channel without an axis.
    pub(super) fn kinds(&self, channel: usize) -> GoalKinds {
        match self.channels.get(channel) {
            Some(c) if c.config.enabled && c.home().is_some() => GoalKinds::of(&GoalKind::ALL),
            Some(c) if c.config.enabled => GoalKinds::of(&[
                GoalKind::Off,
                GoalKind::Stop,
                GoalKind::Power,
                GoalKind::Position,
                GoalKind::Velocity,
                GoalKind::RampPosition,
                GoalKind::SetPosition,
            ]),
            _ => GoalKinds::NONE,
        }
    }

    /// A goal becomes the channel's next step; its packets go out with the next goal
    /// transaction.
    pub(super) fn plan_goal(&mut self, channel: usize, goal: Goal) -> Result<(), GoalError> {
        let kind = goal.kind();
        if channel >= CHANNELS {
            return Err(GoalError::NoSuchChannel(channel));
        }
        if !self.capabilities(channel).contains(kind) {
            return Err(GoalError::Unsupported(kind));
        }
        if !self.link_up {
            return Err(GoalError::Offline);
        }
        let slot = self
            .channels
            .get_mut(channel)
            .ok_or(GoalError::NoSuchChannel(channel))?;
        let step = slot.plan(goal)?;
        slot.set_goal(step);
        slot.goal_unsent = true;
        Ok(())
    }

    /// Writes the unsent goal packets of every channel that fit; `starts` gets the bits of
    /// channels whose goal set last goes out for the first time.
    pub(super) fn write_goals(&mut self, now: Duration, buf: &mut [u8], starts: &mut u8) -> usize {
        let number = self.io_stamps.next_number();
        let mut len = 0;
        for (index, channel) in self.channels.iter_mut().enumerate() {
            if !(channel.config.enabled && channel.unsent && channel.ready()) {
                continue;
            }
            channel.resolve();
            let packets = channel.packets();
            let count = packets.iter().count();
            if !self.in_flight.has_room(count) {
                break;
            }
            let mut end = len;
            let mut fits = true;
            for packet in packets.iter() {
                match buf
                    .get_mut(end..)
                    .and_then(|rest| packet.encode(index, rest).ok())
                {
                    Some(n) => end += n,
                    None => {
                        fits = false;
                        break;
                    }
                }
            }
            if !fits {
                break;
            }
            len = end;
            for packet in packets.iter() {
                self.in_flight.push(Sent {
                    id: packet.id(),
                    at: now,
                    number,
                    tag: Tag::Goal {
                        channel: index as u8,
                        seq: channel.seq,
                        packet,
                    },
                    heard_after: None,
                });
            }
            channel.sent(&packets);
            if channel.goal_unsent {
                channel.goal_unsent = false;
                *starts |= 1 << index;
            }
        }
        len
    }
}
