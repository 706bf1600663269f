//! One channel: its goal as steps on the board, the step's progress, and the channel's last
//! known data.

use core::time::Duration;

use motion_base::counts_to_i32;

use qq2drv::limits::{
    ACCELERATION_MAX, LOOP_RATE_HZ, POWER_MAX, VELOCITY_LIMIT_MAX, VELOCITY_TARGET_MAX,
};
use qq2drv::{ControlMode, InputMode, Status};

use super::config::{ChannelConfig, HomeInput};
use super::wire::{Packet, Packets};
use motion_drivers::{ChannelState, DeviceFault, Goal, GoalError, GoalKind};

/// After a stop's ramp time, how long to wait for the reported velocity to reach standstill
/// before holding anyway.
pub const STOP_SETTLE: Duration = Duration::from_millis(300);
/// Reported speeds up to this (one step of the board's 4 transitions/s resolution) are
/// standstill.
pub const STANDSTILL: i32 = 4;
/// Within this many transitions of its target, a channel at standstill has arrived.
pub const ARRIVED_WITHIN: i64 = 2;
/// The board's control loop period ("Loop rate of 500Hz"): a stop's ramp goes out at
/// least this long after the board answered its first transaction, so that the loop has
/// taken the reset velocity setpoint in between.
pub const LOOP_PERIOD: Duration = Duration::from_nanos(1_000_000_000 / LOOP_RATE_HZ as u64);

/// One step of a goal on the board.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Step {
    /// Nothing commanded since start-up or a board reset.
    Idle,
    /// Control mode Off.
    Off,
    /// Power mode at ±8191.
    Power(i16),
    /// Position PID towards a target (configured velocity / acceleration limits).
    Position(i32),
    /// Position ramp (velocity and acceleration shl 12).
    Ramp {
        position: i32,
        velocity: u32,
        accel: u32,
    },
    /// Velocity PID, ramped (velocity plain, acceleration shl 12).
    Velocity { velocity: i32, accel: u32 },
    /// A stop as the engine asked for it (deceleration shl 12). It is planned when it is
    /// sent, from the velocity measured then: at standstill it is a [`Step::Hold`], else a
    /// [`Step::StopLift`].
    Stop { accel: u32 },
    /// Stop, first transaction: control mode Off then Velocity PID (the loop starts
    /// afresh), acceleration limit lifted (28 ← 0) and velocity target = the measured
    /// `velocity` with no ramp (36, acceleration 0), so the board's velocity setpoint is
    /// where the motor really runs, not where an earlier goal asked it to run.
    StopLift { accel: u32, velocity: i32 },
    /// Stop, second transaction, at least one board loop period after the first was
    /// answered: ramp that setpoint to 0 at the stop's deceleration (36), which takes
    /// `ramp`; then [`Step::Hold`].
    StopRamp { accel: u32, ramp: Duration },
    /// Position PID holding where the channel is when the step is sent; restores the
    /// acceleration limit.
    Hold,
    /// Counter ← value; holds there unless the motor is off.
    SetCounter(i32),
    /// Home with an edge input already active: move off the switch first.
    HomeBackoff { velocity: i32, accel: u32 },
    /// Home: run towards the switch with the input armed.
    HomeSearch { velocity: i32, accel: u32 },
}

impl Step {
    /// A stop is in progress (planned, lifting or ramping).
    pub(super) const fn stopping(self) -> bool {
        matches!(
            self,
            Self::Stop { .. } | Self::StopLift { .. } | Self::StopRamp { .. }
        )
    }

    /// The step needs the channel's measured data to be sent (velocity or position).
    pub(super) const fn needs_data(self) -> bool {
        matches!(self, Self::Stop { .. } | Self::StopLift { .. } | Self::Hold)
    }

    /// The step keeps the acceleration limit lifted (it is restored by every other step).
    pub(super) const fn keeps_limit_lifted(self) -> bool {
        matches!(self, Self::StopLift { .. } | Self::StopRamp { .. })
    }
}

/// One channel of the board.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(super) struct Channel {
    pub(super) config: ChannelConfig,
    pub(super) step: Step,
    /// The step's packets have yet to be sent.
    pub(super) unsent: bool,
    /// No packet of the goal set last has been sent yet.
    pub(super) goal_unsent: bool,
    /// Packets of the step sent and not yet answered.
    pub(super) unacked: u8,
    /// Generation of the step: answers to packets of older steps do not advance it.
    pub(super) seq: u32,
    /// When the board acknowledged the step's last packet.
    pub(super) done_at: Option<Duration>,
    /// Position the channel holds or goes to (for `arrived`).
    pub(super) target: Option<i32>,
    /// Control mode as the board last acknowledged it (Off at power-up and after a reset).
    pub(super) board_mode: ControlMode,
    /// Error answer to a goal packet, or overspeed/glitch: until the next goal.
    pub(super) fault: Option<DeviceFault>,
    pub(super) position: i32,
    pub(super) velocity: i32,
    pub(super) status: Status,
    pub(super) refreshed_at: Option<Duration>,
    pub(super) homed: bool,
    /// Stream data arrived since start-up, the last restart or a board reset: position and
    /// velocity are the board's current ones (a stop and a hold wait for this).
    pub(super) data_valid: bool,
    /// The home input may be armed on the board (an armed packet 14 went out and no
    /// Disabled one was answered since).
    pub(super) armed: bool,
    /// The acceleration limit may be lifted on the board (a stop's 28 ← 0 went out and no
    /// restore was answered since).
    pub(super) lifted: bool,
}

impl Channel {
    pub(super) fn new(config: ChannelConfig) -> Self {
        Self {
            config,
            step: Step::Idle,
            unsent: false,
            goal_unsent: false,
            unacked: 0,
            seq: 0,
            done_at: None,
            target: None,
            board_mode: ControlMode::Off,
            fault: None,
            position: 0,
            velocity: 0,
            status: Status(0),
            refreshed_at: None,
            homed: false,
            data_valid: false,
            armed: false,
            lifted: false,
        }
    }

    /// The step that carries out `goal`, or why the board cannot.
    pub(super) fn plan(&self, goal: Goal) -> Result<Step, GoalError> {
        let kind = goal.kind();
        Ok(match goal {
            Goal::Off => Step::Off,
            Goal::Power { fraction } => {
                if !(fraction.is_finite() && (-1.0..=1.0).contains(&fraction)) {
                    return Err(GoalError::OutOfBoardRange(kind));
                }
                // Packet 18: "Power … Range: -8,191 - 8,191".
                Step::Power((fraction * f64::from(POWER_MAX)).round() as i16)
            }
            Goal::Position { counts } => {
                Step::Position(counts_to_i32(counts).ok_or(GoalError::OutOfBoardRange(kind))?)
            }
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => Step::Ramp {
                position: counts_to_i32(counts).ok_or(GoalError::OutOfBoardRange(kind))?,
                velocity: fixed(kind, velocity, VELOCITY_LIMIT_MAX)?,
                accel: fixed(kind, accel, ACCELERATION_MAX)?,
            },
            Goal::Velocity { velocity, accel } => Step::Velocity {
                velocity: velocity_target(kind, velocity)?,
                accel: fixed(kind, accel, ACCELERATION_MAX)?,
            },
            Goal::Stop { decel } => Step::Stop {
                accel: self.stop_accel(decel),
            },
            Goal::SetPosition { counts } => {
                Step::SetCounter(counts_to_i32(counts).ok_or(GoalError::OutOfBoardRange(kind))?)
            }
            Goal::Home { velocity } => {
                let home = self.home().ok_or(GoalError::Unsupported(kind))?;
                let speed = velocity_target(kind, velocity)?;
                if speed <= 0 {
                    return Err(GoalError::OutOfBoardRange(kind));
                }
                let toward = if home.positive_end { speed } else { -speed };
                let accel = self.stop_accel(self.config.limits.max_accel);
                let already_on = home.mode == InputMode::Edge && self.status.input_active();
                if already_on {
                    Step::HomeBackoff {
                        velocity: -toward,
                        accel,
                    }
                } else {
                    Step::HomeSearch {
                        velocity: toward,
                        accel,
                    }
                }
            }
        })
    }

    /// The home input, when one is configured and enabled.
    pub(super) fn home(&self) -> Option<HomeInput> {
        self.config
            .home
            .filter(|home| home.mode != InputMode::Disabled)
    }

    /// A stop's deceleration in shl-12, always representable: clipped to the board's range,
    /// the axis's own when `decel` is not a positive number.
    fn stop_accel(&self, decel: f64) -> u32 {
        let decel = if decel.is_finite() && decel > 0.0 {
            decel
        } else {
            self.config.limits.max_accel
        };
        qq2drv::limits::to_fixed(decel)
            .unwrap_or(ACCELERATION_MAX)
            .clamp(1, ACCELERATION_MAX)
    }

    /// Whether the step can go out now (a stop and a hold need current data).
    pub(super) fn ready(&self) -> bool {
        !self.step.needs_data() || self.data_valid
    }

    /// Plans a stop from the velocity measured now, just before it is sent: at standstill
    /// it holds at once, else it resets the board's velocity setpoint first.
    pub(super) fn resolve(&mut self) {
        if let Step::Stop { accel } = self.step {
            self.step = if self.velocity.abs() <= STANDSTILL {
                Step::Hold
            } else {
                Step::StopLift {
                    accel,
                    velocity: self.velocity,
                }
            };
        }
    }

    /// Makes `step` the channel's step; its packets go out next.
    pub(super) fn set_step(&mut self, step: Step) {
        self.step = step;
        self.unsent = step != Step::Idle;
        self.unacked = 0;
        self.seq = self.seq.wrapping_add(1);
        self.done_at = None;
        self.target = match step {
            Step::Position(target) | Step::SetCounter(target) => Some(target),
            Step::Ramp { position, .. } => Some(position),
            _ => None,
        };
    }

    /// A new goal from the engine: its error latch clears.
    pub(super) fn set_goal(&mut self, step: Step) {
        self.fault = None;
        self.set_step(step);
    }

    /// The step's `packets` went out.
    pub(super) fn sent(&mut self, packets: &Packets) {
        self.unsent = false;
        self.unacked = 0;
        for packet in packets.iter() {
            self.unacked += 1;
            match packet {
                // Not the channel's own limit: a stop's 0, or a reverse ramp's acceleration
                // (`velocity_ramp = "unsigned"`); the next step writes it back.
                Packet::AccelLimit(limit) if limit != self.own_accel_limit() => {
                    self.lifted = true;
                }
                Packet::Input { config, .. } if config.mode() != InputMode::Disabled => {
                    self.armed = true;
                }
                _ => {}
            }
        }
        if self.step == Step::Hold {
            self.target = Some(self.position);
        }
    }

    /// The board answered `packet` of step generation `seq` with `code`.
    pub(super) fn answered(&mut self, now: Duration, seq: u32, packet: Packet, code: u8) {
        if code != 0 {
            if seq == self.seq {
                self.fault = Some(DeviceFault::BoardError);
                self.unacked = 0;
            }
            return;
        }
        match packet {
            Packet::Mode(mode) => self.board_mode = mode,
            // "Set absolute position value": the channel now has a reference.
            Packet::SetCounter(_) => self.homed = true,
            Packet::AccelLimit(limit) if limit == self.own_accel_limit() => self.lifted = false,
            Packet::Input { config, .. } if config.mode() == InputMode::Disabled => {
                self.armed = false;
            }
            _ => {}
        }
        if seq == self.seq && self.unacked > 0 {
            self.unacked -= 1;
            if self.unacked == 0 && !self.unsent {
                self.done_at = Some(now);
            }
        }
    }

    /// A packet of step generation `seq` got no answer: send the step again (a stop is
    /// planned again from the velocity measured then).
    pub(super) fn lost(&mut self, seq: u32) {
        if seq == self.seq && self.step != Step::Idle && self.fault.is_none() {
            self.unsent = true;
            self.unacked = 0;
            if let Step::StopLift { accel, .. } = self.step {
                self.step = Step::Stop { accel };
            }
        }
    }

    /// Fresh stream data. Home steps advance on the status bits.
    pub(super) fn data(&mut self, now: Duration, position: i32, velocity: i32, status: Status) {
        self.position = position;
        self.velocity = velocity;
        self.status = status;
        self.refreshed_at = Some(now);
        self.data_valid = true;
        if status.glitch() || status.overspeed() {
            self.fault = Some(DeviceFault::Overspeed);
        }
        if self.done_at.is_none() {
            return;
        }
        match self.step {
            Step::HomeBackoff { velocity, accel } if !status.input_active() => {
                self.set_step(Step::HomeSearch {
                    velocity: -velocity,
                    accel,
                });
            }
            Step::HomeSearch { accel, .. } if self.triggered(status) => {
                // Found: the input is disarmed by the stop's first packet.
                self.homed = true;
                self.set_step(Step::Stop { accel });
            }
            _ => {}
        }
    }

    /// The Input Trigger Accumulator shows the trigger the search waits for: the switch's
    /// end, or the positive trigger that INDEX mode always uses.
    fn triggered(&self, status: Status) -> bool {
        let Some(home) = self.home() else {
            return false;
        };
        let wanted = if home.positive_end || home.mode == InputMode::Index {
            Status::TRIGGER_POSITIVE
        } else {
            Status::TRIGGER_NEGATIVE
        };
        status.trigger_accumulator() & wanted != 0
    }

    /// Time-driven progress of a stop: one loop period after its setpoint reset was
    /// answered, the ramp; once the ramp has run and the channel stands still, the hold.
    pub(super) fn progress(&mut self, now: Duration) {
        let Some(done_at) = self.done_at else {
            return;
        };
        let elapsed = now.saturating_sub(done_at);
        match self.step {
            Step::StopLift { accel, velocity } if elapsed >= LOOP_PERIOD => {
                let decel = qq2drv::limits::from_fixed(accel);
                let seconds = f64::from(velocity).abs() / decel;
                let ramp = Duration::try_from_secs_f64(seconds).unwrap_or(STOP_SETTLE);
                self.set_step(Step::StopRamp { accel, ramp });
            }
            Step::StopRamp { ramp, .. } if elapsed >= ramp.saturating_add(LOOP_PERIOD) => {
                self.set_step(Step::Hold);
            }
            _ => {}
        }
    }

    /// The board lost its state (reset): it is Off and forgot every goal; its counter
    /// restarted, so the data known is void until the next stream packet.
    pub(super) fn board_reset(&mut self) {
        self.set_step(Step::Idle);
        self.board_mode = ControlMode::Off;
        self.homed = false;
        self.data_valid = false;
        self.armed = false;
        self.lifted = false;
    }

    /// Requests in flight were voided (restart): what was not answered goes again.
    pub(super) fn void_in_flight(&mut self) {
        if self.unacked > 0 {
            self.unsent = true;
            self.unacked = 0;
        }
    }

    /// The link went down: a channel that may be driving its motor gets a stop (at its
    /// axis's max acceleration) that goes out once the board is back.
    pub(super) fn stop_after_link_loss(&mut self) {
        let driving = !matches!(self.step, Step::Idle | Step::Off | Step::Hold)
            || matches!(
                self.board_mode,
                ControlMode::Power | ControlMode::VelocityPid
            );
        if driving {
            let decel = self.config.limits.max_accel;
            self.set_step(Step::Stop {
                accel: self.stop_accel(decel),
            });
        }
    }

    /// Whether the motor moves (or a stop / home is still under way).
    pub(super) fn moving(&self) -> bool {
        self.step.stopping()
            || matches!(
                self.step,
                Step::HomeBackoff { .. } | Step::HomeSearch { .. }
            )
            || self.velocity.abs() > STANDSTILL
    }

    /// Whether the goal is not yet acknowledged, or a stop still has its hold to send.
    pub(super) fn pending(&self) -> bool {
        self.unsent || self.unacked > 0 || (self.step.stopping() && self.fault.is_none())
    }

    /// The engine's view.
    pub(super) fn state(&self) -> ChannelState {
        let moving = self.moving();
        let arrived = !moving
            && !self.unsent
            && self.unacked == 0
            && self.target.is_some_and(|target| {
                (i64::from(self.position) - i64::from(target)).abs() <= ARRIVED_WITHIN
            });
        ChannelState {
            position: f64::from(self.position),
            velocity: f64::from(self.velocity),
            raw_counts: i64::from(self.position),
            refreshed_at: self.refreshed_at,
            moving,
            homed: self.homed,
            // An end-stop switch (HOME / EDGE input) is pressed; an index pulse is not a limit.
            at_limit: self
                .home()
                .is_some_and(|home| home.mode != InputMode::Index)
                && self.status.input_active(),
            arrived,
            fault: self.fault,
        }
    }
}

/// A velocity target of packet 36: plain transitions/s, ±100 000.
fn velocity_target(kind: GoalKind, velocity: f64) -> Result<i32, GoalError> {
    let rounded = velocity.round();
    let max = f64::from(VELOCITY_TARGET_MAX);
    if rounded.is_finite() && (-max..=max).contains(&rounded) {
        Ok(rounded as i32)
    } else {
        Err(GoalError::OutOfBoardRange(kind))
    }
}

/// A shl-12 velocity (packet 34) or acceleration (packets 34, 36): at least 1 (0 would
/// mean "not limited") and at most `max`.
fn fixed(kind: GoalKind, value: f64, max: u32) -> Result<u32, GoalError> {
    qq2drv::limits::to_fixed(value)
        .filter(|fixed| (1..=max).contains(fixed))
        .ok_or(GoalError::OutOfBoardRange(kind))
}
