//! One motor as the driver sees it: what the pack last reported, what the driver last
//! commanded, and the script of requests that carries out the current goal.
//!
//! How goals become instructions (manual 8.3/8.4):
//! - **Stop** (decelerate, then hold): `$25` rotation with velocity 0 — "The change to
//!   rotation happens immediately, even if the motor is still active" and "The maximum
//!   acceleration is obeyed when the velocity is to be changed" — from any action (ramp,
//!   rotation, reference search), after `$14` sets amax from the goal's deceleration. Once
//!   the motor is at rest, `$23` ends the rotation ("If rotation has been active, the motor
//!   is only stopped by this command"), leaving it inactive. `$2A` is not used: it sets the
//!   target to the actual position, and "motors driving beyond vstart will overshoot and
//!   return".
//! - **Position** / **RampPosition**: `$14` (vmax/amax: the axis limits, or the goal's),
//!   then `$26` target and `$23` with the same target, as 8.4 advises ("use command $26,
//!   and follow it by command $23 with the same target position, to ensure that the motor
//!   also starts if it stood still before"). A motor that rotates or searches its
//!   reference is stopped first (as above), since `$23` would only stop it.
//! - **Velocity**: `$14` (amax from the goal, vmax the axis limit), `$25` velocity.
//! - **Home**: stop first if moving ($16 may only change at standstill), `$16` vrefmax,
//!   `$22`. The start-up `$16` sets "stop after reference search", so the motor ends at the
//!   new zero point, inactive.
//! - **SetPosition**: `$27`.
//! - **Off**: stop as above, then `$11` with every current level at 0 %; the next motion
//!   goal sends the configured `$11` first.

use core::time::Duration;

use tmcpack::{Action, CurrentLevel, MAX_VELOCITY, Request};

use super::config::{Scale, TmcpackChannel};
use crate::goal::{Goal, GoalError, GoalKind};
use crate::state::{ChannelState, DeviceFault};

/// Longest script one goal needs.
pub(crate) const MAX_STEPS: usize = 10;

/// One step of a goal's script.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// Send this request (none of them is answered).
    Send(Request),
    /// Wait until the rotation stop sent before has come to rest, then end the rotation
    /// with `$23` if a fresh poll still shows it.
    AwaitRest,
}

/// What the driver last told the motor to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Motion {
    /// Nothing since (re)start: the polled action tells.
    Unknown,
    /// Inactive, or a ramp ($23/$26) the driver started.
    Ramp,
    /// Rotation ($25) at this velocity.
    Rotation(i16),
    /// Reference search ($22).
    Reference,
}

/// Progress of a reference search the driver started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Homing {
    Idle,
    /// `$22` sent with this sequence number; waiting to see the search.
    Sent(u64),
    /// A poll showed the search running.
    Running,
}

/// One configured motor.
#[derive(Debug, Clone)]
pub(crate) struct Channel {
    /// Motor number on the pack.
    pub motor: u8,
    pub cfg: TmcpackChannel,
    pub scale: Scale,
    pub state: ChannelState,
    /// Last polled action (`None`: not polled since (re)start).
    pub action: Option<Action>,
    pub motion: Motion,
    /// Sequence number of the request that set `motion`.
    motion_seq: u64,
    pub homing: Homing,
    /// vmax and amax as last written with `$14`, vrefmax with `$16`.
    pub board_vmax: u16,
    pub board_amax: u16,
    pub board_vrefmax: u16,
    /// Currents are on (the last `$11` was the configured one).
    pub powered: bool,
    /// Target of the last `$23` and the sequence number it was sent with.
    pub target: Option<(i32, u64)>,
    /// The script of the current goal.
    steps: [Option<Step>; MAX_STEPS],
    next: usize,
    /// Earliest instant the `AwaitRest` step may finish.
    pub rest_at: Option<Duration>,
    /// Sequence number and send time of the request behind the last poll answer.
    pub polled_seq: u64,
    pub polled_sent_at: Duration,
    /// The previous poll: position and receive time (velocity estimate).
    prev: Option<(i32, Duration)>,
    /// Stop an active motor at its first poll after a (re)start: goals were voided.
    pub stop_if_active: bool,
}

impl Channel {
    pub fn new(motor: u8, cfg: TmcpackChannel, scale: Scale) -> Self {
        Self {
            motor,
            cfg,
            scale,
            state: ChannelState::UNKNOWN,
            action: None,
            motion: Motion::Unknown,
            motion_seq: 0,
            homing: Homing::Idle,
            board_vmax: scale.vmax,
            board_amax: scale.amax,
            board_vrefmax: scale.vrefmax,
            powered: true,
            target: None,
            steps: [None; MAX_STEPS],
            next: MAX_STEPS,
            rest_at: None,
            polled_seq: 0,
            polled_sent_at: Duration::ZERO,
            prev: None,
            stop_if_active: true,
        }
    }

    /// The board restarted or the link came back: what was commanded is void.
    pub fn restart(&mut self, fault: DeviceFault) {
        self.clear_script();
        self.action = None;
        self.motion = Motion::Unknown;
        self.homing = Homing::Idle;
        self.board_vmax = self.scale.vmax;
        self.board_amax = self.scale.amax;
        self.board_vrefmax = self.scale.vrefmax;
        self.powered = true;
        self.target = None;
        self.prev = None;
        self.stop_if_active = true;
        self.state.fault = Some(fault);
        self.state.arrived = false;
        if fault == DeviceFault::Reset {
            self.state.homed = false;
        }
    }

    pub fn clear_script(&mut self) {
        self.steps = [None; MAX_STEPS];
        self.next = MAX_STEPS;
        self.rest_at = None;
    }

    /// Whether the script has steps left.
    pub fn pending(&self) -> bool {
        self.steps.get(self.next).is_some_and(Option::is_some)
    }

    /// The step to do next.
    pub fn current(&self) -> Option<Step> {
        self.steps.get(self.next).copied().flatten()
    }

    /// The current step is done.
    pub fn advance(&mut self) {
        self.next = (self.next + 1).min(MAX_STEPS);
    }

    /// Whether the next step is a request that may go now.
    pub fn ready(&self) -> bool {
        matches!(self.current(), Some(Step::Send(_)))
    }

    /// Whether the `AwaitRest` step waits for a fresh poll (its time bound has passed).
    pub fn wants_rest_poll(&self, now: Duration) -> bool {
        self.current() == Some(Step::AwaitRest) && self.rest_at.is_some_and(|at| now >= at)
    }

    /// Replaces the script with the one for `goal`.
    pub fn plan(&mut self, goal: Goal) -> Result<(), GoalError> {
        let motor = self.motor;
        let mut script = Script::default();
        let kind = goal.kind();
        let range = GoalError::OutOfBoardRange(kind);
        match goal {
            Goal::Off => {
                self.plan_stop(&mut script, motor, self.scale.amax);
                let off = CurrentLevel::Off;
                script.send(Request::CurrentControl {
                    motor,
                    i0: off,
                    i1: off,
                    i2: off,
                    i3: off,
                    t0: self.cfg.currents.t0.max(1),
                });
            }
            Goal::Stop { decel } => {
                let amax = self.scale.amax(decel).unwrap_or(self.scale.amax);
                self.plan_stop(&mut script, motor, amax);
            }
            Goal::Power { .. } => return Err(GoalError::Unsupported(kind)),
            Goal::Position { counts } => {
                let target = position(counts).ok_or(range)?;
                self.plan_ramp(&mut script, motor, target, self.scale.vmax, self.scale.amax);
            }
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => {
                let target = position(counts).ok_or(range)?;
                let vmax = self.scale.velocity(velocity).filter(|&v| v >= 1);
                let amax = self.scale.amax(accel);
                let (Some(vmax), Some(amax)) = (vmax, amax) else {
                    return Err(range);
                };
                self.plan_ramp(&mut script, motor, target, vmax, amax);
            }
            Goal::Velocity { velocity, accel } => {
                let v = self.scale.velocity(velocity).ok_or(range)?;
                if v == 0 && velocity != 0.0 {
                    // Slower than one velocity unit: the pack cannot run it.
                    return Err(range);
                }
                let amax = self.scale.amax(accel).ok_or(range)?;
                let signed = if velocity < 0.0 {
                    -(v as i16)
                } else {
                    v as i16
                };
                self.power_on(&mut script, motor);
                self.limits(&mut script, motor, self.scale.vmax.max(v), amax);
                script.send(Request::Rotate {
                    motor,
                    velocity: signed,
                });
            }
            Goal::Home { velocity } => {
                let v = self.scale.velocity(velocity).ok_or(range)?;
                if v < self.scale.vstart {
                    // $16: "511 >= vmax >= vrefmax >= vstart".
                    return Err(range);
                }
                let vrefmax = v.min(self.board_vmax.max(self.scale.vmax));
                if self.needs_stop() {
                    self.plan_stop(&mut script, motor, self.scale.amax);
                }
                self.power_on(&mut script, motor);
                if vrefmax != self.board_vrefmax {
                    script.send(Request::ReferenceParameters {
                        motor,
                        vrefmax,
                        debounce_mask: self.cfg.debounce_mask,
                        flags: super::startup::REFERENCE_FLAGS,
                    });
                }
                script.send(Request::ReferenceSearch { motor });
            }
            Goal::SetPosition { counts } => {
                let position = position(counts).ok_or(range)?;
                script.send(Request::SetPosition { motor, position });
            }
        }
        if script.overflow {
            return Err(range);
        }
        for step in script.steps.iter().flatten() {
            if let Step::Send(request) = step
                && request.validate().is_err()
            {
                return Err(range);
            }
        }
        self.steps = script.steps;
        self.next = 0;
        self.stop_if_active = false;
        self.rest_at = None;
        self.state.arrived = false;
        self.state.at_limit = false;
        if kind == GoalKind::Home {
            self.state.homed = false;
        }
        Ok(())
    }

    /// Whether a ramp start would only stop the motor (rotation, reference search, PI):
    /// what the last poll saw if it is newer than the last motion command, else that
    /// command.
    fn needs_stop(&self) -> bool {
        if self.polled_seq > self.motion_seq || self.motion == Motion::Unknown {
            return !matches!(self.action, Some(Action::Inactive | Action::Ramp));
        }
        !matches!(self.motion, Motion::Ramp)
    }

    fn plan_stop(&self, script: &mut Script, motor: u8, amax: u16) {
        self.limits(script, motor, self.board_vmax, amax);
        script.send(Request::Rotate { motor, velocity: 0 });
        script.push(Step::AwaitRest);
    }

    fn plan_ramp(&self, script: &mut Script, motor: u8, target: i32, vmax: u16, amax: u16) {
        if self.needs_stop() {
            self.plan_stop(script, motor, self.scale.amax);
        }
        self.power_on(script, motor);
        self.limits(script, motor, vmax, amax);
        script.send(Request::SetTarget { motor, target });
        script.send(Request::StartRamp { motor, target });
    }

    fn power_on(&self, script: &mut Script, motor: u8) {
        if !self.powered {
            let c = self.cfg.currents;
            script.send(Request::CurrentControl {
                motor,
                i0: c.i0,
                i1: c.i1,
                i2: c.i2,
                i3: c.i3,
                t0: c.t0.max(1),
            });
        }
    }

    /// `$14` unless the board already has these values. Planned against what the board
    /// has now; a script that changes them writes them again later.
    fn limits(&self, script: &mut Script, motor: u8, vmax: u16, amax: u16) {
        let planned = script.limits.unwrap_or((self.board_vmax, self.board_amax));
        if planned != (vmax, amax) {
            script.send(Request::VelocityAcceleration { motor, amax, vmax });
            script.limits = Some((vmax, amax));
        }
    }

    /// A request of this channel's script was put on the wire with sequence number `seq`.
    pub fn on_sent(&mut self, request: Request, seq: u64, wire_end: Duration) {
        match request {
            Request::VelocityAcceleration { amax, vmax, .. } => {
                self.board_amax = amax;
                self.board_vmax = vmax;
            }
            Request::ReferenceParameters { vrefmax, .. } => self.board_vrefmax = vrefmax,
            Request::CurrentControl { i3, .. } => {
                self.powered = i3 != CurrentLevel::Off;
            }
            Request::Rotate { velocity, .. } => {
                self.motion = Motion::Rotation(velocity);
                self.motion_seq = seq;
                self.target = None;
                if velocity == 0 {
                    let bound = Scale::stop_time(self.board_vmax, self.board_amax);
                    self.rest_at = Some(wire_end + bound);
                }
            }
            Request::StartRamp { target, .. } => {
                self.motion = Motion::Ramp;
                self.motion_seq = seq;
                self.target = Some((target, seq));
            }
            Request::ReferenceSearch { .. } => {
                self.motion = Motion::Reference;
                self.motion_seq = seq;
                self.homing = Homing::Sent(seq);
                self.target = None;
            }
            Request::SetPosition { .. } => {
                self.state.homed = true;
                self.target = None;
                self.prev = None;
            }
            _ => {}
        }
    }

    /// A `$20` answer for this channel, to a request sent with `seq` at `sent_at`.
    /// Returns `true` when the channel should be stopped (active after a restart).
    pub fn on_poll(
        &mut self,
        now: Duration,
        seq: u64,
        sent_at: Duration,
        position: i32,
        action: Action,
        stopped: bool,
    ) -> bool {
        let velocity = match self.prev {
            Some((p, t)) if now > t && action.is_active() => {
                f64::from(position.wrapping_sub(p)) / (now - t).as_secs_f64()
            }
            _ => 0.0,
        };
        // Faster than the motor can run: the coordinates jumped (a reference search set
        // the new zero point), not the rotor.
        let velocity = if velocity.abs() > self.scale.hz * f64::from(MAX_VELOCITY) {
            0.0
        } else {
            velocity
        };
        let still = self.prev.is_some_and(|(p, _)| p == position);
        let mut refused = false;
        self.prev = Some((position, now));
        self.action = Some(action);
        self.polled_seq = seq;
        self.polled_sent_at = sent_at;
        match self.homing {
            Homing::Sent(sent) if seq > sent && action.is_referencing() => {
                self.homing = Homing::Running;
            }
            Homing::Sent(sent) if seq > sent => {
                // Not searching at the first poll after $22: finished already (it ends at
                // the new zero point, inactive) or refused by the pack.
                if position == 0 && action == Action::Inactive {
                    self.finish_homing();
                } else {
                    self.homing = Homing::Idle;
                    self.motion = Motion::Unknown;
                    refused = true;
                }
            }
            Homing::Running if !action.is_referencing() => self.finish_homing(),
            _ => {}
        }
        if self.motion == Motion::Ramp && action == Action::Rotation {
            self.motion = Motion::Unknown;
        }
        let rotation_rest = self.motion == Motion::Rotation(0) && still;
        if self.current() == Some(Step::AwaitRest)
            && self
                .rest_at
                .is_some_and(|at| sent_at >= at || rotation_rest || action == Action::Inactive)
        {
            self.advance();
            if action == Action::Rotation {
                self.insert_now(Step::Send(Request::StartRamp {
                    motor: self.motor,
                    target: position,
                }));
            } else if action == Action::Inactive {
                self.motion = Motion::Ramp;
            }
        }
        let moving = action.is_active() && !(action == Action::Rotation && rotation_rest);
        let arrived = self
            .target
            .is_some_and(|(t, sent)| seq > sent && t == position && !action.is_active());
        let restarted = core::mem::take(&mut self.stop_if_active);
        self.state = ChannelState {
            position: f64::from(position),
            velocity,
            raw_counts: i64::from(position),
            refreshed_at: Some(now),
            moving,
            homed: self.state.homed,
            at_limit: stopped,
            arrived,
            fault: if refused {
                Some(DeviceFault::BoardError)
            } else {
                stopped.then_some(DeviceFault::LimitSwitch)
            },
        };
        restarted && action.is_active()
    }

    fn finish_homing(&mut self) {
        self.homing = Homing::Idle;
        self.motion = Motion::Ramp;
        self.state.homed = true;
    }

    /// Puts `step` before the current one (the `$23` that ends a rotation at rest).
    fn insert_now(&mut self, step: Step) {
        if self.next > 0 {
            self.next -= 1;
            if let Some(slot) = self.steps.get_mut(self.next) {
                *slot = Some(step);
            }
        }
    }
}

/// A target in counts as the pack's signed 32-bit position.
fn position(counts: f64) -> Option<i32> {
    let rounded = counts.round();
    (rounded.is_finite() && rounded >= f64::from(i32::MIN) && rounded <= f64::from(i32::MAX))
        .then_some(rounded as i32)
}

/// A script being planned.
#[derive(Debug, Default)]
struct Script {
    steps: [Option<Step>; MAX_STEPS],
    len: usize,
    overflow: bool,
    /// `$14` values the script has written so far.
    limits: Option<(u16, u16)>,
}

impl Script {
    fn push(&mut self, step: Step) {
        match self.steps.get_mut(self.len) {
            Some(slot) => {
                *slot = Some(step);
                self.len += 1;
            }
            None => self.overflow = true,
        }
    }

    fn send(&mut self, request: Request) {
        self.push(Step::Send(request));
    }
}
