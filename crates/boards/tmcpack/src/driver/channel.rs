//! One motor as the driver sees it: what the pack last reported, what the driver last
//! commanded, and the script of requests that carries out the current goal.
//!
//! How goals become instructions (manual 8.3/8.4):
//! - **Stop** (decelerate, then hold): `$25` rotation with velocity 0 — "The change to
//!   rotation happens immediately, even if the motor is still active" and "The maximum
//!   acceleration is obeyed when the velocity is to be changed" — from any action (ramp,
//!   rotation, PI controller, reference search), after `$14` sets amax from the goal's
//!   deceleration (rounded up: never gentler than asked) when the pack has another amax.
//!   So the motor decelerates from whatever velocity it really has, at the requested rate.
//!   The `$25` is sent even when the driver believes the motor idle (it may have been left
//!   running by someone else), and a stop goes before every other queued command. From the
//!   end of the deceleration expected from the speed it was stopped from, the motor is polled
//!   back to back until it is seen at rest (two polls at the same position, or inactive), so
//!   that the frames show the rest within a few exchanges (docs/ARCHITECTURE.md "The
//!   deadman's bound per board"). Once the motor is at rest, `$23` ends the rotation ("If rotation has been active, the motor is
//!   only stopped by this command"), leaving it inactive; a motor that was switched off is
//!   energised again with its configured `$11` (a stop holds). `$2A` is not used: it sets
//!   the target to the actual position, and "motors driving beyond vstart will overshoot and
//!   return driving another ramp back"; nor is the PI controller (`$24`), whose
//!   deceleration the manual does not bound.
//! - **Position** / **RampPosition**: `$14` (vmax/amax: the axis limits, or the goal's),
//!   then `$26` target and `$23` with the same target, as 8.4 advises ("use command $26,
//!   and follow it by command $23 with the same target position, to ensure that the motor
//!   also starts if it stood still before"). A motor that rotates or searches its
//!   reference is stopped first (as above), since `$23` would only stop it.
//! - **Velocity**: `$14` (amax from the goal, vmax the axis limit), `$25` velocity.
//! - **Home**: stop first if moving ($16 may only change at standstill), `$16` vrefmax,
//!   `$22`. The start-up `$16` sets "stop after reference search", so the motor ends at the
//!   new zero point, inactive; then `$27` sets the configured home position if it is not 0.
//!   A search the pack repeats (its action code goes back to an earlier phase: "the whole
//!   procedure repeats by first stopping again"), a stop condition during the search
//!   (`$20` P6), or a search that ends anywhere but inactive at the zero point is
//!   [`DeviceFault::HomeFailed`]; the driver then stops the motor.
//! - **Position** with `position_mode = "pi"`: `$24`, the PI controller on the target
//!   (after `$14` with the axis limits when a ramp goal left others; a motor that
//!   rotates, searches or runs a ramp is stopped first). A new target while the PI
//!   controller runs is one more `$24`: "When the PI-controller was already active the
//!   target position will be reprogrammed immediately". A `$24` waits for a query after
//!   the previous one, so a path's stream of targets takes turns with the polls. The PI
//!   controller holds the target (action 10): the axis counts as at rest when two polls
//!   find it at the same position, as arrived when that is the target. Stop, Off, Home,
//!   a ramp goal and a SetPosition leave it through a stop (`$25` 0, then `$23`).
//! - **SetPosition**: `$27`; the axis counts as referenced from the first poll after it.
//! - **Off**: stop as above, then `$11` with every current level at 0 %; the next motion
//!   goal sends the configured `$11` first.

use core::time::Duration;

use motion_base::{FixedQueue, counts_to_i32};

use tmcpack::{Action, CurrentLevel, MAX_VELOCITY, MotorOptions, Request};

use super::config::{Currents, Scale, TmcpackChannel};
use super::script::{MAX_STEPS, Script, Step};
use crate::PositionMode;
use motion_drivers::{ChannelState, DeviceFault, Goal, GoalError, GoalKind};

/// What the driver last told the motor to do.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Motion {
    /// Nothing since (re)start: the polled action tells.
    Unknown,
    /// Inactive, or a ramp ($23/$26) the driver started.
    Ramp,
    /// Rotation ($25) at this velocity.
    Rotation(i16),
    /// Reference search ($22).
    Reference,
    /// The PI controller ($24) on the target of [`Channel::target`].
    Pi,
}

/// Progress of a reference search the driver started.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Homing {
    Idle,
    /// `$22` sent with this sequence number; waiting to see the search.
    Sent(u64),
    /// A poll showed the search running.
    Running,
}

/// One configured motor.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
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
    steps: FixedQueue<Step, MAX_STEPS>,
    /// Earliest instant the `AwaitRest` step may finish.
    pub rest_at: Option<Duration>,
    /// When the stopping motor may stand, from the speed it was stopped from (measured, or
    /// the rotation commanded if faster): its back-to-back polls start here.
    pub rest_poll_at: Option<Duration>,
    /// The speed (velocity units) the current stop started from.
    stop_speed: u16,
    /// When the rotation running now went out and the speed it started from (velocity
    /// units): its ramp's speed at any later instant is bounded from these.
    rotation_from: Option<(Duration, u16)>,
    /// Sequence number and send time of the request behind the last poll answer.
    pub polled_seq: u64,
    pub polled_sent_at: Duration,
    /// The previous poll: position and receive time (velocity estimate).
    prev: Option<(i32, Duration)>,
    /// Stop an active motor at its first poll after a (re)start: goals were voided.
    pub stop_if_active: bool,
    /// The script is a stop (Stop, Off): it goes before every other command.
    urgent: bool,
    /// The last reference search failed (reported until the next goal).
    home_failed: bool,
    /// The highest reference-search phase (action − 20) seen in the current search.
    ref_phase: Option<u8>,
    /// A `$27` was sent with this sequence number: referenced from the next poll on.
    pub(super) confirm_position: Option<u64>,
    /// No request of the goal set last has been sent yet.
    pub goal_unsent: bool,
    /// A poll showed the motor moving since the last `$45` check (or since the start).
    pub(super) moved_since_check: bool,
    /// The motor was moving (or told to move) when the driver lost the pack, or moved since
    /// the last check before it saw the pack in its power-down state: a position restored
    /// from EEPROM is not trusted as its reference.
    pub lost_in_motion: bool,
    /// The axis was referenced when the driver lost the pack (or saw it in its power-down
    /// state): the one thing the pack does not save with the positions.
    pub referenced_at_loss: bool,
    /// The position a previous run of the server saved for this axis, referenced and at
    /// rest (module `restore`), until the first configuration after the start.
    pub saved: Option<i32>,
    /// A poll after the request sent with this sequence number confirms the saved position
    /// (module `restore`).
    pub(super) confirm_saved: Option<(u64, i32)>,
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
            steps: FixedQueue::new(),
            rest_at: None,
            rest_poll_at: None,
            stop_speed: 0,
            rotation_from: None,
            polled_seq: 0,
            polled_sent_at: Duration::ZERO,
            prev: None,
            stop_if_active: true,
            urgent: false,
            home_failed: false,
            ref_phase: None,
            confirm_position: None,
            goal_unsent: false,
            moved_since_check: false,
            lost_in_motion: false,
            referenced_at_loss: false,
            saved: None,
            confirm_saved: None,
        }
    }

    /// The board restarted or the link came back: what was commanded is void.
    pub fn restart(&mut self, fault: DeviceFault) {
        // Moving at the last poll, or told to move after it: the pack may have been lost
        // with the motor running.
        let commanded = self.motion_seq > self.polled_seq
            && !matches!(self.motion, Motion::Unknown | Motion::Rotation(0));
        self.lost_in_motion |= self.state.moving || commanded;
        self.referenced_at_loss |= self.state.homed;
        self.moved_since_check = false;
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
        self.urgent = false;
        self.home_failed = false;
        self.ref_phase = None;
        self.confirm_position = None;
        self.confirm_saved = None;
        self.state.fault = Some(fault);
        self.state.arrived = false;
        if fault == DeviceFault::Reset {
            self.state.homed = false;
        }
    }

    pub fn clear_script(&mut self) {
        self.steps.clear();
        self.rest_at = None;
        self.rest_poll_at = None;
        self.goal_unsent = false;
    }

    /// Whether the script has steps left.
    pub fn pending(&self) -> bool {
        !self.steps.is_empty()
    }

    /// The step to do next.
    pub fn current(&self) -> Option<Step> {
        self.steps.front()
    }

    /// The current step is done.
    pub fn advance(&mut self) {
        self.steps.pop();
    }

    /// Whether the next step is a request that may go now.
    pub fn ready(&self) -> bool {
        matches!(self.current(), Some(Step::Send(_)))
    }

    /// Whether the next step is a request of a stop (goes before other commands).
    pub fn urgent(&self) -> bool {
        self.urgent && self.ready()
    }

    /// Whether a stop's `$25` is out, the motor may stand by now (its deceleration from
    /// the speed it was stopped from has run) and it is not seen at rest yet: it is then
    /// polled back to back (before the other motors' round-robin polls, and on a shared
    /// bus before the other packs' polls), so that the frames show velocity 0 within a few
    /// exchanges of the rest — two polls with the same position (or the pack's own
    /// inactive action) — instead of a round-robin period or two later
    /// (docs/ARCHITECTURE.md "The deadman's bound per board"). During the deceleration the
    /// round-robin polls go on, so the other motors do not all fall due at once.
    pub fn awaits_rest(&self, now: Duration) -> bool {
        self.current() == Some(Step::AwaitRest) && self.rest_poll_at.is_some_and(|at| now >= at)
    }

    /// The speed (velocity units) a stop at `at` starts from: the measured one rounded up,
    /// or the speed the rotation's ramp has reached by `at` if that is faster (a jog still
    /// accelerating, or the frames behind the pack's real speed): from the speed it started
    /// at, amax / divisor more every 2 ms cycle since it went out (8.3 `$14`: "1/64 amax is
    /// accumulated with 500Hz"), never beyond the rotation commanded.
    fn speed_now(&self, at: Duration) -> u16 {
        let measured = self.measured_speed();
        let Motion::Rotation(v) = self.motion else {
            return measured;
        };
        let commanded = v.unsigned_abs();
        let ramp = match self.rotation_from {
            Some((from, start)) => {
                let cycles = at.saturating_sub(from).as_millis() / 2 + 1;
                let gained = cycles.saturating_mul(u128::from(self.board_amax))
                    / u128::from(self.scale.divisor.get());
                u128::from(start)
                    .saturating_add(gained)
                    .min(u128::from(commanded)) as u16
            }
            None => commanded,
        };
        measured.max(ramp)
    }

    /// The measured speed, velocity units, rounded up.
    fn measured_speed(&self) -> u16 {
        let measured = (self.state.velocity.abs() / self.scale.hz).ceil();
        if measured.is_finite() {
            measured.min(f64::from(MAX_VELOCITY)) as u16
        } else {
            MAX_VELOCITY
        }
    }

    /// Replaces the script with the one for `goal`.
    pub fn plan(&mut self, goal: Goal) -> Result<(), GoalError> {
        let motor = self.motor;
        let mut script = Script::default();
        let kind = goal.kind();
        let range = GoalError::OutOfBoardRange(kind);
        let axis_decel = self.cfg.max_accel;
        match goal {
            Goal::Off => {
                self.plan_stop(&mut script, motor, axis_decel);
                let off = CurrentLevel::Off;
                let currents = Currents {
                    i0: off,
                    i1: off,
                    i2: off,
                    i3: off,
                    ..self.cfg.currents
                };
                script.send(currents.request(motor));
            }
            Goal::Stop { decel } => {
                let decel = if decel.is_finite() && decel > 0.0 {
                    decel
                } else {
                    axis_decel
                };
                self.plan_stop(&mut script, motor, decel);
                // "Hold": a motor that was switched off holds with its currents again.
                self.power_on(&mut script, motor);
            }
            Goal::Power { .. } => return Err(GoalError::Unsupported(kind)),
            Goal::Position { counts } if self.cfg.position_mode == PositionMode::Pi => {
                let target = counts_to_i32(counts).ok_or(range)?;
                if self.retarget_pi(target) {
                    return Ok(());
                }
                self.plan_pi(&mut script, motor, target);
            }
            Goal::Position { counts } => {
                let target = counts_to_i32(counts).ok_or(range)?;
                self.plan_ramp(&mut script, motor, target, self.scale.vmax, self.scale.amax);
            }
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => {
                let target = counts_to_i32(counts).ok_or(range)?;
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
                    self.plan_stop(&mut script, motor, axis_decel);
                }
                self.power_on(&mut script, motor);
                if vrefmax != self.board_vrefmax {
                    script.send(Request::ReferenceParameters {
                        motor,
                        vrefmax,
                        debounce_mask: self.cfg.debounce_mask,
                        flags: super::config::REFERENCE_FLAGS,
                    });
                }
                script.send(Request::ReferenceSearch { motor });
            }
            Goal::SetPosition { counts } => {
                let position = counts_to_i32(counts).ok_or(range)?;
                if self.in_pi() {
                    // The PI controller would drive to its old target in the new
                    // coordinates: it is stopped (and left) first.
                    self.plan_stop(&mut script, motor, axis_decel);
                }
                script.send(Request::SetPosition { motor, position });
            }
        }
        self.take_script(script.finish(range)?, kind);
        Ok(())
    }

    /// `steps` carry out a new goal of `kind` from now on.
    fn take_script(&mut self, steps: FixedQueue<Step, MAX_STEPS>, kind: GoalKind) {
        self.steps = steps;
        self.stop_if_active = false;
        self.urgent = matches!(kind, GoalKind::Stop | GoalKind::Off);
        self.rest_at = None;
        self.state.arrived = false;
        self.state.at_limit = false;
        // A new goal ends whatever search ran (a stop must not count as its end).
        self.homing = Homing::Idle;
        self.home_failed = false;
        self.ref_phase = None;
        if kind == GoalKind::Home {
            self.state.homed = false;
        }
    }

    /// Whether the motor stands still, inactive, with nothing queued: `$50` may include it
    /// ("The motors have to stand still before execution", manual 8.7).
    pub fn at_rest(&self) -> bool {
        self.action == Some(Action::Inactive)
            && !self.state.moving
            && !self.pending()
            && !matches!(self.motion, Motion::Rotation(_) | Motion::Reference)
    }

    /// The script of one leg of a `$50` line: currents on, `$14` with the leg's vmax and
    /// amax, `$26` with its target; the pack-wide `$50` follows once every leg's script is
    /// out. Replaces the current script, as a goal does.
    pub fn plan_leg(&mut self, target: i32, vmax: u16, amax: u16) -> Result<(), GoalError> {
        let motor = self.motor;
        let mut script = Script::default();
        self.power_on(&mut script, motor);
        self.limits(&mut script, motor, vmax, amax);
        script.send(Request::SetTarget { motor, target });
        let kind = GoalKind::RampPosition;
        self.take_script(script.finish(GoalError::OutOfBoardRange(kind))?, kind);
        Ok(())
    }

    /// The `$50` that includes this motor went out with sequence number `seq`: it ramps
    /// to `target` (arrived when a later poll finds it there, inactive).
    pub fn on_line_started(&mut self, target: i32, seq: u64) {
        self.motion = Motion::Ramp;
        self.motion_seq = seq;
        self.target = Some((target, seq));
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

    /// `$25` velocity 0 at `decel` (microsteps/s²), then wait for rest. The pack gets the
    /// stop's amax rounded up; when the amax it has is no gentler than the one rounded
    /// down (the usual case after a move at the same limit) the `$25` goes first and the
    /// exact amax right after it, so the deceleration starts one word earlier.
    fn plan_stop(&self, script: &mut Script, motor: u8, decel: f64) {
        let up = self.scale.stop_amax(decel).unwrap_or(self.scale.amax);
        let down = self.scale.amax(decel).unwrap_or(up).min(up);
        let (_, planned_amax) = script.limits.unwrap_or((self.board_vmax, self.board_amax));
        let vmax = script.limits.map_or(self.board_vmax, |(v, _)| v);
        if planned_amax >= down {
            script.send(Request::Rotate { motor, velocity: 0 });
            self.limits(script, motor, vmax, up);
        } else {
            self.limits(script, motor, vmax, up);
            script.send(Request::Rotate { motor, velocity: 0 });
        }
        script.push(Step::AwaitRest);
    }

    fn plan_ramp(&self, script: &mut Script, motor: u8, target: i32, vmax: u16, amax: u16) {
        if self.needs_stop() {
            self.plan_stop(script, motor, self.cfg.max_accel);
        }
        self.power_on(script, motor);
        self.limits(script, motor, vmax, amax);
        script.send(Request::SetTarget { motor, target });
        script.send(Request::StartRamp { motor, target });
    }

    /// A `Position` goal in the PI position mode: `$24` ("Switching to PI-controller
    /// happens immediately, even if the motor is inactive. When the PI-controller was
    /// already active the target position will be reprogrammed immediately"), after `$14`
    /// puts the axis limits back when a ramp goal left others (the PI output is read as
    /// bounded by vmax and amax, as the ramps are: the manual states no bound of its own).
    /// A motor that rotates, searches its reference or runs a ramp is stopped first (the
    /// manual does not say how the PI controller takes over a moving motor).
    fn plan_pi(&self, script: &mut Script, motor: u8, target: i32) {
        if self.pi_needs_stop() {
            self.plan_stop(script, motor, self.cfg.max_accel);
        }
        self.power_on(script, motor);
        self.limits(script, motor, self.scale.vmax, self.scale.amax);
        script.send(Request::PiTarget { motor, target });
    }

    /// A new PI target while the script of the last one still waits to send its `$24`
    /// (the line busy, or a stop before it): only the target changes, so that a stream of
    /// targets never restarts the stop before them.
    fn retarget_pi(&mut self, target: i32) -> bool {
        if self.urgent {
            return false;
        }
        match self.steps.back_mut() {
            Some(Step::Send(Request::PiTarget { target: t, .. })) => {
                *t = target;
                self.state.arrived = false;
                true
            }
            _ => false,
        }
    }

    /// Whether the PI controller cannot take the motor over as it is: anything but
    /// inactive or the PI controller itself (what the last poll saw if it is newer than the
    /// last motion command, else that command).
    fn pi_needs_stop(&self) -> bool {
        if self.polled_seq > self.motion_seq || self.motion == Motion::Unknown {
            return !matches!(self.action, Some(Action::Inactive | Action::PiController));
        }
        self.motion != Motion::Pi
    }

    /// Whether the PI controller holds (or may hold) the motor.
    fn in_pi(&self) -> bool {
        self.motion == Motion::Pi || self.action == Some(Action::PiController)
    }

    fn power_on(&self, script: &mut Script, motor: u8) {
        if !self.powered {
            script.send(self.cfg.currents.request(motor));
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
                if self.motion == Motion::Rotation(0)
                    && let Some(at) = self.rest_at
                {
                    // The amax of a stop already under way: the rest bound from now on.
                    let bound = self.scale.stop_time(self.board_vmax, self.board_amax);
                    self.rest_at = Some(at.max(wire_end + bound));
                    let expected = self.scale.stop_time(self.stop_speed, self.board_amax);
                    self.rest_poll_at = self.rest_poll_at.map(|at| at.max(wire_end + expected));
                }
            }
            Request::ReferenceParameters { vrefmax, .. } => self.board_vrefmax = vrefmax,
            Request::CurrentControl { i3, .. } => {
                self.powered = i3 != CurrentLevel::Off;
            }
            Request::Rotate { velocity, .. } => {
                if velocity == 0 {
                    self.stop_speed = self.speed_now(wire_end);
                    let expected = self.scale.stop_time(self.stop_speed, self.board_amax);
                    self.rest_poll_at = Some(wire_end + expected);
                }
                // A new rotation ramps from where the last one's ramp (or the motor) is.
                let start = self.speed_now(wire_end);
                self.rotation_from = Some((wire_end, start));
                self.motion = Motion::Rotation(velocity);
                self.motion_seq = seq;
                self.target = None;
                if velocity == 0 {
                    let bound = self.scale.stop_time(self.board_vmax, self.board_amax);
                    self.rest_at = Some(wire_end + bound);
                }
            }
            Request::StartRamp { target, .. } => {
                self.motion = Motion::Ramp;
                self.motion_seq = seq;
                self.target = Some((target, seq));
            }
            Request::PiTarget { target, .. } => {
                self.motion = Motion::Pi;
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
                self.confirm_position = Some(seq);
                self.target = None;
                self.prev = None;
            }
            _ => {}
        }
    }

    /// A `$20` answer for this channel, to a request sent with `seq` at `sent_at`.
    /// Returns `true` when the driver should stop the channel (active after a restart, or
    /// a failed reference search).
    pub fn on_poll(
        &mut self,
        now: Duration,
        seq: u64,
        sent_at: Duration,
        position: i32,
        action: Action,
        stopped: bool,
    ) -> bool {
        let delta = self.prev.map(|(p, _)| self.travel(p, position));
        let velocity = match (self.prev, delta) {
            (Some((_, t)), Some(d)) if now > t && action.is_active() => {
                d as f64 / (now - t).as_secs_f64()
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
        let still = delta == Some(0);
        self.prev = Some((position, now));
        self.action = Some(action);
        self.polled_seq = seq;
        self.polled_sent_at = sent_at;
        let failed = self.track_homing(seq, position, action, stopped);
        if stopped && !self.cfg.options.contains(MotorOptions::STOP_SOFT) {
            // An abrupt stop: "the precise motor position may be lost" (8.5 $31).
            self.state.homed = false;
        }
        if self.confirm_position.is_some_and(|sent| seq > sent) {
            self.confirm_position = None;
            self.state.homed = true;
        }
        self.confirm_saved_position(seq, position, action, stopped);
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
        // The PI controller stays active (action 10) while it holds its target.
        let pi_rest = action == Action::PiController && still;
        let moving =
            action.is_active() && !(action == Action::Rotation && rotation_rest) && !pi_rest;
        self.moved_since_check |= moving;
        let arrived = self.target.is_some_and(|(t, sent)| {
            seq > sent && t == position && (!action.is_active() || pi_rest)
        });
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
            fault: if self.home_failed {
                Some(DeviceFault::HomeFailed)
            } else {
                stopped.then_some(DeviceFault::LimitSwitch)
            },
        };
        (restarted || failed) && action.is_active()
    }

    /// Microsteps from `from` to `to`: on a rotary axis (the pack reports the position
    /// modulo poslimit) the shorter way round.
    fn travel(&self, from: i32, to: i32) -> i64 {
        let d = i64::from(to.wrapping_sub(from));
        if !self.cfg.cyclic() {
            return d;
        }
        let l = i64::from(self.cfg.poslimit);
        let w = d.rem_euclid(l);
        if w > l / 2 { w - l } else { w }
    }

    /// Follows a reference search the driver started; `true` when it failed at this poll.
    fn track_homing(&mut self, seq: u64, position: i32, action: Action, stopped: bool) -> bool {
        let phase = match action {
            Action::ReferenceSearch(p) => Some(p),
            _ => None,
        };
        let ended_at_zero = position == 0 && action == Action::Inactive && !stopped;
        match self.homing {
            Homing::Sent(sent) if seq <= sent => false,
            Homing::Idle => false,
            Homing::Sent(_) | Homing::Running if action.is_referencing() => {
                let repeated = matches!((self.ref_phase, phase), (Some(q), Some(p)) if p < q);
                if stopped || repeated {
                    self.fail_homing();
                    return true;
                }
                self.homing = Homing::Running;
                self.ref_phase = self.ref_phase.max(phase);
                false
            }
            // Not searching (any more): finished at the new zero point (it stops there,
            // inactive), or not.
            Homing::Sent(_) | Homing::Running if ended_at_zero => {
                self.finish_homing();
                false
            }
            Homing::Sent(_) | Homing::Running => {
                self.fail_homing();
                true
            }
        }
    }

    fn fail_homing(&mut self) {
        self.homing = Homing::Idle;
        self.motion = Motion::Unknown;
        self.home_failed = true;
        self.state.homed = false;
        self.ref_phase = None;
    }

    fn finish_homing(&mut self) {
        self.homing = Homing::Idle;
        self.motion = Motion::Ramp;
        self.ref_phase = None;
        if self.cfg.home_position == 0 {
            self.state.homed = true;
        } else if !self.pending() {
            // The zero point takes the configured home position; referenced once a poll
            // after the `$27` confirms it.
            self.steps.clear();
            self.steps.push(Step::Send(Request::SetPosition {
                motor: self.motor,
                position: self.cfg.home_position,
            }));
            self.urgent = false;
        }
    }

    /// Puts `step` before the current one (the `$23` that ends a rotation at rest).
    fn insert_now(&mut self, step: Step) {
        self.steps.push_front(step);
    }
}
