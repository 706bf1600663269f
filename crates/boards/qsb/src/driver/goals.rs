//! Goals → plans of QSB requests, and the steps of a plan that wait for the board.

use core::time::Duration;

use motion_base::counts_to_i32;

use ::qsb::{
    EncoderMode, IndexMode, LoadTarget, ProductType, QsbCommand, Register, Request, Write,
};

use super::QsbDriver;
use super::program::Step;
use super::wire::Origin;
use motion_drivers::{DeviceFault, Goal, GoalError, GoalKind, GoalKinds};

/// Moves one position goal may make: the move and two corrections (lost steps, a move
/// whose answer was lost).
const MAX_MOVES: u8 = 3;

const fn command(command: QsbCommand) -> Step {
    Step::Send(Request::Write(Write::Command(command)))
}

/// A home search that has not found its index after this many times the time its travel
/// limit takes at the search velocity has failed (the encoder may not count at all).
const HOME_TIME_FACTOR: f64 = 2.0;

/// Slack added to a home search's time limit (start-up of the jog, wire time).
const HOME_TIME_SLACK: Duration = Duration::from_millis(100);

impl QsbDriver {
    /// The counter back in normal operation (MDR0, DTR, MDR1) and STR as normal
    /// operation streams it: the prefix of every plan that may replace a home search.
    fn normal_counter(&self) -> [Step; 2] {
        [Step::NormalCounter, Step::NormalStrStream]
    }

    /// Whether channel 0 drives the -M's stepper: a -M (as reported), its motor drive
    /// configured, counting quadrature.
    pub(super) fn drive_active(&self) -> bool {
        self.effective_product() == ProductType::M
            && self.config.motor_drive
            && self.config.input_mode == EncoderMode::Quadrature
    }

    /// `Ok` when goals and outputs can be taken: `Starting` during the start-up,
    /// `Offline` when the link is down or the board stopped answering.
    pub(super) fn check_online(&self) -> Result<(), GoalError> {
        if self.link_up && self.status.online {
            Ok(())
        } else if self.link_up && self.restart_at.is_none() && !self.setup.is_empty() {
            Err(GoalError::Starting)
        } else {
            Err(GoalError::Offline)
        }
    }

    /// The goals channel 0 takes.
    pub(super) fn kinds(&self) -> GoalKinds {
        if self.config.input_mode != EncoderMode::Quadrature {
            // PWM / analog: an absolute value read as the `encoder` pin, no axis.
            return GoalKinds::NONE;
        }
        if !self.drive_active() {
            return GoalKinds::of(&[GoalKind::Stop, GoalKind::SetPosition]);
        }
        let moves = [
            GoalKind::Stop,
            GoalKind::Position,
            GoalKind::Velocity,
            GoalKind::RampPosition,
            GoalKind::Home,
            GoalKind::SetPosition,
            GoalKind::Off,
        ];
        let with_off = if self.config.enable.is_some() { 7 } else { 6 };
        GoalKinds::of(moves.get(..with_off).unwrap_or(&moves))
    }

    /// Checks `goal` and turns it into the plan of requests (replacing the previous one).
    pub(super) fn plan_goal(
        &mut self,
        _now: Duration,
        channel: usize,
        goal: Goal,
    ) -> Result<(), GoalError> {
        if channel != 0 {
            return Err(GoalError::NoSuchChannel(channel));
        }
        let kind = goal.kind();
        if !self.kinds().contains(kind) {
            return Err(GoalError::Unsupported(kind));
        }
        self.check_online()?;
        let out_of_range = GoalError::OutOfBoardRange(kind);
        let driven = self.drive_active();
        let energise = Step::Enable(true);
        match goal {
            Goal::SetPosition { counts } => {
                let value = counts_to_i32(counts).ok_or(out_of_range)?;
                // DTR is the range limit or the modulus: the value must be a count the
                // counter can hold.
                if let Some(limit) = self.config.counter.dtr()
                    && (value < 0 || value as u32 > limit)
                {
                    return Err(out_of_range);
                }
                // No trigger while DTR holds the value (CNTR = DTR after the load); DTR
                // goes back to the limit or the compare position after it.
                self.preset.replace(&[
                    Step::Ensure(Write::Mdr1(self.quiet_mdr1())),
                    Step::Ensure(Write::Dtr(value as u32)),
                    Step::Send(Request::Write(Write::Load(LoadTarget::DtrToCntr))),
                    Step::NormalCounter,
                ]);
                if driven {
                    // The engine holds after a set-position: so does the motor.
                    self.replace_goal(kind, &[Step::StopIfMoving]);
                }
            }
            // -S / -D: nothing is driven, so "stopped" already holds.
            Goal::Stop { .. } if !driven => {}
            // (Only with an enable line: `kinds` refuses it otherwise.)
            Goal::Off => {
                let [normal, end_str] = self.normal_counter();
                self.replace_goal(
                    kind,
                    &[
                        command(QsbCommand::MotorQuit),
                        Step::Enable(false),
                        normal,
                        end_str,
                    ],
                );
            }
            Goal::Stop { decel } => {
                // Always on the wire, whatever the driver believes the motor does (a motor
                // left jogging by someone else must stop), at the decel asked for.
                let decel = self.config.stop_decel(decel);
                let [normal, end_str] = self.normal_counter();
                self.replace_goal(
                    kind,
                    &[
                        Step::Ensure(Write::Accel(decel)),
                        command(QsbCommand::MotorStop),
                        energise,
                        normal,
                        end_str,
                    ],
                );
            }
            Goal::Position { counts } => {
                let (rate, accel) = self.config.default_profile();
                self.plan_move(kind, counts, rate, accel, false)?;
            }
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => {
                let rate = self.config.step_rate(velocity).ok_or(out_of_range)?;
                let accel = self.config.accel(accel).ok_or(out_of_range)?;
                self.plan_move(kind, counts, rate, accel, false)?;
            }
            Goal::Velocity { velocity, accel } => {
                let rate = self.config.jog_rate(velocity).ok_or(out_of_range)?;
                let accel = self.config.accel(accel).ok_or(out_of_range)?;
                let [normal, end_str] = self.normal_counter();
                let mut steps = [
                    energise,
                    normal,
                    end_str,
                    Step::Ensure(Write::Accel(accel)),
                    Step::Ensure(Write::JogRate(rate)),
                    command(QsbCommand::MotorJog),
                ];
                let len = if rate == 0 {
                    // A stop at `accel`: MOTOR STOP in the jog rate's place.
                    if let Some(slot) = steps.get_mut(4) {
                        *slot = command(QsbCommand::MotorStop);
                    }
                    steps.len() - 1
                } else {
                    steps.len()
                };
                self.replace_goal(kind, steps.get(..len).unwrap_or(&steps));
            }
            Goal::Home { velocity } => {
                let direction = if self.config.home_positive { 1.0 } else { -1.0 };
                let rate = self
                    .config
                    .jog_rate(direction * velocity.abs())
                    .filter(|rate| *rate != 0)
                    .ok_or(out_of_range)?;
                let (_, accel) = self.config.default_profile();
                self.homed = false;
                self.index_seen = false;
                self.index_armed = false;
                self.home_start = None;
                self.home_deadline = None;
                // The counter value at the index: 0 by "reset CNTR", anything else by
                // "load CNTR" from DTR.
                // MDR0 is the normal mode with the index acting: "configure index as the
                // "reset CNTR" input" (W0363 in x4) or "load CNTR" (transfers DTR to CNTR).
                let offset = self.config.home_position;
                let counter = self.config.counter;
                let (dtr, mdr0) = if offset == 0 {
                    let mdr0 = counter.homing_mdr0(IndexMode::ResetCntr);
                    (Step::Ensure(Write::Mdr0(mdr0)), mdr0)
                } else {
                    let mdr0 = counter.homing_mdr0(IndexMode::LoadCntr);
                    (Step::Ensure(Write::Dtr(offset as u32)), mdr0)
                };
                // No trigger and no capture on index during the search: DTR and the index
                // are the search's; normal operation's come back after it.
                self.replace_goal(
                    kind,
                    &[
                        energise,
                        Step::Ensure(Write::Mdr1(self.quiet_mdr1())),
                        Step::Ensure(Write::Accel(accel)),
                        Step::Ensure(Write::JogRate(rate)),
                        dtr,
                        Step::Ensure(Write::Mdr0(mdr0)),
                        Step::Send(Request::Write(Write::Clear(::qsb::ClearTarget::Str))),
                        Step::Send(Request::Stream(Register::Str)),
                        command(QsbCommand::MotorJog),
                        Step::WaitIndex,
                        Step::Ensure(Write::Mdr0(counter.mdr0())),
                        command(QsbCommand::MotorStop),
                        Step::NormalCounter,
                        Step::NormalStrStream,
                    ],
                );
            }
            Goal::Power { .. } => return Err(GoalError::Unsupported(kind)),
        }
        if self.status.fault == Some(DeviceFault::BoardError) {
            self.status.fault = None;
        }
        if kind != GoalKind::Stop {
            self.home_failed = false;
        }
        Ok(())
    }

    fn replace_goal(&mut self, kind: GoalKind, steps: &[Step]) {
        self.goal.replace(steps);
        self.goal_kind = Some(kind);
        self.arrived = false;
        if self.in_flight.is_none() {
            self.attempts = 0;
        }
    }

    /// A move to `counts` at MD STEP RATE `rate` and MD ACCEL `accel`: stop first if the
    /// motor runs (a move is relative to where it stands), then move by what remains;
    /// `armed`: the move waits at [`Step::Armed`] for the engine's start.
    fn plan_move(
        &mut self,
        kind: GoalKind,
        counts: f64,
        rate: u32,
        accel: u32,
        armed: bool,
    ) -> Result<(), GoalError> {
        let target = counts_to_i32(counts).ok_or(GoalError::OutOfBoardRange(kind))?;
        let [normal, end_str] = self.normal_counter();
        let move_to = Step::MoveTo {
            target: f64::from(target),
            attempt: 0,
        };
        let mut steps = [
            Step::Enable(true),
            normal,
            end_str,
            Step::Ensure(Write::Accel(accel)),
            Step::Ensure(Write::StepRate(rate)),
            Step::StopIfMoving,
            Step::WaitDone,
            Step::Armed,
            move_to,
        ];
        let len = if armed {
            steps.len()
        } else {
            // The move in the `Armed` step's place.
            if let Some(slot) = steps.get_mut(7) {
                *slot = move_to;
            }
            steps.len() - 1
        };
        self.replace_goal(kind, steps.get(..len).unwrap_or(&steps));
        Ok(())
    }

    /// Moves the goal plan on by one step if that needs no request; returns whether it
    /// did.
    pub(super) fn settle_goal_step(&mut self, now: Duration) -> bool {
        let Some(step) = self.goal.front() else {
            return false;
        };
        match step {
            Step::Enable(on) => {
                self.io.energised = on;
                let held = self.request_of(step).is_none();
                if held {
                    self.goal.pop();
                }
                held
            }
            Step::WaitDone => {
                let done = self.drive_done();
                if done {
                    self.goal.pop();
                }
                done
            }
            Step::MoveTo { target, attempt } => self.expand_move(target, attempt),
            // Until the engine starts or resumes the move.
            Step::Armed | Step::Paused => false,
            Step::WaitIndex => {
                if self.index_seen {
                    self.goal.pop();
                    self.homed = true;
                    return true;
                }
                let Some(latest) = self.encoder.latest() else {
                    return false;
                };
                let start = *self.home_start.get_or_insert(latest.count);
                let limit = self.home_time_limit();
                let deadline = *self
                    .home_deadline
                    .get_or_insert_with(|| now.saturating_add(limit));
                let travel = f64::from(latest.count.wrapping_sub(start)).abs();
                if travel > self.config.home_max_travel || now >= deadline {
                    // No index within the travel allowed (or the time that takes): stop,
                    // not homed, and say so.
                    let [normal, end_str] = self.normal_counter();
                    self.goal
                        .replace(&[command(QsbCommand::MotorStop), normal, end_str]);
                    self.index_armed = false;
                    self.home_failed = true;
                    return true;
                }
                false
            }
            step => {
                let nothing_to_send = self.request_of(step).is_none();
                if nothing_to_send {
                    self.goal.pop();
                }
                nothing_to_send
            }
        }
    }

    /// How long a home search may run: [`HOME_TIME_FACTOR`] times its travel limit at the
    /// search rate, plus the ramp to that rate and [`HOME_TIME_SLACK`].
    fn home_time_limit(&self) -> Duration {
        let rate = self
            .board
            .get(usize::from(Register::MdJogRate.number()))
            .copied()
            .flatten()
            .map_or(0.0, |r| f64::from((r as i32).unsigned_abs()));
        let accel = f64::from(self.config.default_profile().1);
        let steps = self.config.steps(self.config.home_max_travel).map(f64::abs);
        let seconds = match steps {
            Some(steps) if rate > 0.0 => HOME_TIME_FACTOR * steps / rate + rate / accel,
            _ => 0.0,
        };
        Duration::try_from_secs_f64(seconds)
            .unwrap_or(Duration::MAX)
            .saturating_add(HOME_TIME_SLACK)
    }

    /// A group's line on this motor ([`Driver::lead_line`](motion_drivers::Driver::lead_line)):
    /// one leg, a position move with the leg's step rate and acceleration (MD STEP RATE, MD
    /// ACCEL, then at the start MD MOVE STEPS and COMMAND 8), which the board runs as its
    /// own trapezoid. Taken only from rest.
    pub(super) fn prepare_line(
        &mut self,
        legs: &[motion_drivers::LineLeg],
    ) -> Result<bool, GoalError> {
        let [leg] = legs else {
            return Ok(false);
        };
        if leg.channel != 0 {
            return Err(GoalError::NoSuchChannel(leg.channel));
        }
        let kind = GoalKind::RampPosition;
        if !self.drive_active() || !self.kinds().contains(kind) {
            return Ok(false);
        }
        self.check_online()?;
        if self.drive_moving() || !self.goal.is_empty() {
            return Ok(false);
        }
        let out_of_range = GoalError::OutOfBoardRange(kind);
        // Rounded down to the board's 16 steps/s (and steps/s²) increments; a rate a hair
        // under an increment (the path's arithmetic) is that increment.
        let nudge = 1.0 + 1e-9;
        let rate = self
            .config
            .step_rate(leg.velocity * nudge)
            .ok_or(out_of_range)?;
        let accel = self.config.accel(leg.accel * nudge).ok_or(out_of_range)?;
        let per_step = self.config.steps(1.0).map_or(0.0, |s| 1.0 / s.abs());
        if !leg.represented_within(f64::from(rate) * per_step, f64::from(accel) * per_step) {
            // Too far from the line's pace in 16-step increments: the engine follows.
            return Ok(false);
        }
        self.plan_move(kind, leg.counts, rate, accel, true)?;
        self.home_failed = false;
        Ok(true)
    }

    /// Whether a prepared line waits only for its start.
    pub(super) fn line_armed(&self) -> bool {
        self.goal.front() == Some(Step::Armed)
    }

    /// Whether a started line's move has not been answered yet: its MD MOVE STEPS or
    /// COMMAND 8 is still to go (or in flight).
    pub(super) fn line_firing(&self) -> bool {
        matches!(self.goal_kind, Some(GoalKind::RampPosition))
            && match self.goal.front() {
                Some(Step::MoveTo { attempt: 0, .. }) => true,
                Some(Step::Ensure(Write::MoveSteps(_))) => true,
                Some(Step::Send(request)) => {
                    request == Request::Write(Write::Command(QsbCommand::MotorMove))
                }
                _ => false,
            }
    }

    /// Starts a prepared line: the move goes out next.
    pub(super) fn fire_line(&mut self) {
        if self.line_armed() {
            self.goal.pop();
        }
    }

    /// Whether the drive runs the move of the current position goal: its COMMAND 8 was
    /// answered and the plan waits for it to be done.
    fn running_move(&self) -> bool {
        matches!(
            self.goal_kind,
            Some(GoalKind::Position | GoalKind::RampPosition)
        ) && self.goal.front() == Some(Step::WaitDone)
            && matches!(self.goal.second(), Some(Step::MoveTo { attempt, .. }) if attempt > 0)
            && self.in_flight.is_none_or(|f| f.origin != Origin::Goal)
    }

    /// COMMAND 6 "Motor Pause - Pause the motor using the MD ACCEL rate" for a move the
    /// drive runs now; the plan then waits at [`Step::Paused`].
    pub(super) fn pause_move(&mut self, channel: usize) -> Result<bool, GoalError> {
        if channel != 0 {
            return Err(GoalError::NoSuchChannel(channel));
        }
        self.check_online()?;
        if !self.drive_active() || !self.running_move() {
            return Ok(false);
        }
        self.goal.expand_front([
            command(QsbCommand::MotorPause),
            Step::Paused,
            Step::WaitDone,
        ]);
        Ok(true)
    }

    /// COMMAND 7 "Motor Resume - Resume motor operation if previously stopped using the
    /// Motor Pause command. Use the programmed motor acceleration."
    pub(super) fn resume_move(&mut self, channel: usize) -> Result<bool, GoalError> {
        if channel != 0 {
            return Err(GoalError::NoSuchChannel(channel));
        }
        self.check_online()?;
        // A pause not answered yet is not resumed: the engine then follows the rest
        // of the line with goals.
        if self.goal.front() != Some(Step::Paused) {
            return Ok(false);
        }
        self.goal.expand_front([command(QsbCommand::MotorResume)]);
        Ok(true)
    }

    /// Replaces a `MoveTo` with the move that remains (or ends the plan).
    fn expand_move(&mut self, target: f64, attempt: u8) -> bool {
        let Some(latest) = self.encoder.latest() else {
            return false;
        };
        let steps = self.config.steps(target - f64::from(latest.count));
        match steps.map(f64::round) {
            // Within half a step: as close as whole steps get (a target half-way between
            // two steps must not make the motor hop between them).
            _ if steps.is_some_and(|s| s.abs() <= 0.5) => {
                self.goal.pop();
                self.arrived = true;
            }
            Some(steps) if attempt < MAX_MOVES && steps.abs() <= f64::from(i32::MAX) => {
                self.goal.expand_front([
                    Step::Ensure(Write::MoveSteps(steps as i32)),
                    command(QsbCommand::MotorMove),
                    Step::WaitDone,
                    Step::MoveTo {
                        target,
                        attempt: attempt + 1,
                    },
                ]);
            }
            // Out of moves (or steps): the goal ends where the encoder says it is.
            _ => self.goal.pop(),
        }
        true
    }
}
