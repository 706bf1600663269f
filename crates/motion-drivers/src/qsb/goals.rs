//! Goals → plans of QSB requests, and the steps of a plan that wait for the board.

use core::time::Duration;

use ::qsb::{LoadTarget, ProductType, QsbCommand, Register, Request, Write};

use super::program::Step;
use super::{HOMING_MDR0, NORMAL_MDR0, QsbDriver, kinds_for};
use crate::goal::{Goal, GoalError, GoalKind};
use crate::state::DeviceFault;

/// Moves one position goal may make: the move and two corrections (lost steps, a move
/// whose answer was lost).
const MAX_MOVES: u8 = 3;

const fn command(command: QsbCommand) -> Step {
    Step::Send(Request::Write(Write::Command(command)))
}

/// The counter back in normal operation and no STR stream: the prefix of every plan that
/// may replace a home search.
const NORMAL_COUNTER: [Step; 2] = [Step::Ensure(Write::Mdr0(NORMAL_MDR0)), Step::EndStrStream];

/// A whole number of counts the 32-bit counter can hold.
fn counter_value(counts: f64) -> Option<i32> {
    let value = counts.round();
    (value.is_finite() && value >= f64::from(i32::MIN) && value <= f64::from(i32::MAX))
        .then_some(value as i32)
}

impl QsbDriver {
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
        let product = self.effective_product();
        if !kinds_for(product).contains(kind) {
            return Err(GoalError::Unsupported(kind));
        }
        if !self.link_up || !self.status.online {
            return Err(GoalError::Offline);
        }
        let out_of_range = GoalError::OutOfBoardRange(kind);
        let driven = product == ProductType::M;
        match goal {
            Goal::SetPosition { counts } => {
                let value = counter_value(counts).ok_or(out_of_range)?;
                self.preset.replace(&[
                    Step::Ensure(Write::Dtr(value as u32)),
                    Step::Send(Request::Write(Write::Load(LoadTarget::DtrToCntr))),
                ]);
                if driven {
                    // The engine holds after a set-position: so does the motor.
                    self.replace_goal(kind, &[Step::StopIfMoving]);
                }
            }
            // -S / -D: nothing is driven, so "not driving" already holds.
            Goal::Off | Goal::Stop { .. } if !driven => {}
            Goal::Off => {
                let [normal, end_str] = NORMAL_COUNTER;
                self.replace_goal(kind, &[command(QsbCommand::MotorQuit), normal, end_str]);
            }
            Goal::Stop { decel } => {
                let decel = self.config.stop_decel(decel);
                let [normal, end_str] = NORMAL_COUNTER;
                self.replace_goal(
                    kind,
                    &[
                        Step::Ensure(Write::Accel(decel)),
                        command(QsbCommand::MotorStop),
                        normal,
                        end_str,
                    ],
                );
            }
            Goal::Position { counts } => {
                let (rate, accel) = self.config.default_profile();
                self.plan_move(kind, counts, rate, accel)?;
            }
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => {
                let rate = self.config.step_rate(velocity).ok_or(out_of_range)?;
                let accel = self.config.accel(accel).ok_or(out_of_range)?;
                self.plan_move(kind, counts, rate, accel)?;
            }
            Goal::Velocity { velocity, accel } => {
                let rate = self.config.jog_rate(velocity).ok_or(out_of_range)?;
                let accel = self.config.accel(accel).ok_or(out_of_range)?;
                let [normal, end_str] = NORMAL_COUNTER;
                if rate == 0 {
                    self.replace_goal(
                        kind,
                        &[
                            normal,
                            end_str,
                            Step::Ensure(Write::Accel(accel)),
                            command(QsbCommand::MotorStop),
                        ],
                    );
                } else {
                    self.replace_goal(
                        kind,
                        &[
                            normal,
                            end_str,
                            Step::Ensure(Write::Accel(accel)),
                            Step::Ensure(Write::JogRate(rate)),
                            command(QsbCommand::MotorJog),
                        ],
                    );
                }
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
                self.replace_goal(
                    kind,
                    &[
                        Step::Ensure(Write::Accel(accel)),
                        Step::Ensure(Write::JogRate(rate)),
                        Step::Ensure(Write::Mdr0(HOMING_MDR0)),
                        Step::Send(Request::Write(Write::Clear(::qsb::ClearTarget::Str))),
                        Step::Send(Request::Stream(Register::Str)),
                        command(QsbCommand::MotorJog),
                        Step::WaitIndex,
                        Step::Ensure(Write::Mdr0(NORMAL_MDR0)),
                        command(QsbCommand::MotorStop),
                        Step::EndStrStream,
                    ],
                );
            }
            Goal::Power { .. } => return Err(GoalError::Unsupported(kind)),
        }
        if self.status.fault == Some(DeviceFault::BoardError) {
            self.status.fault = None;
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
    /// motor runs (a move is relative to where it stands), then move by what remains.
    fn plan_move(
        &mut self,
        kind: GoalKind,
        counts: f64,
        rate: u32,
        accel: u32,
    ) -> Result<(), GoalError> {
        let target = counter_value(counts).ok_or(GoalError::OutOfBoardRange(kind))?;
        let [normal, end_str] = NORMAL_COUNTER;
        self.replace_goal(
            kind,
            &[
                normal,
                end_str,
                Step::Ensure(Write::Accel(accel)),
                Step::Ensure(Write::StepRate(rate)),
                Step::StopIfMoving,
                Step::WaitDone,
                Step::MoveTo {
                    target: f64::from(target),
                    attempt: 0,
                },
            ],
        );
        Ok(())
    }

    /// Moves the goal plan on by one step if that needs no request; returns whether it
    /// did.
    pub(super) fn settle_goal_step(&mut self) -> bool {
        let Some(step) = self.goal.front() else {
            return false;
        };
        match step {
            Step::WaitDone => {
                let done = self.drive_done();
                if done {
                    self.goal.pop();
                }
                done
            }
            Step::MoveTo { target, attempt } => self.expand_move(target, attempt),
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
                let travel = f64::from(latest.count.wrapping_sub(start)).abs();
                if travel > self.config.home_max_travel {
                    // No index within the travel allowed: stop, not homed.
                    let [normal, end_str] = NORMAL_COUNTER;
                    self.goal
                        .replace(&[command(QsbCommand::MotorStop), normal, end_str]);
                    self.index_armed = false;
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

    /// Replaces a `MoveTo` with the move that remains (or ends the plan).
    fn expand_move(&mut self, target: f64, attempt: u8) -> bool {
        let Some(latest) = self.encoder.latest() else {
            return false;
        };
        let steps = self
            .config
            .steps(target - f64::from(latest.count))
            .map(f64::round);
        match steps {
            Some(0.0) => {
                self.goal.pop();
                self.arrived = true;
            }
            Some(steps) if attempt < MAX_MOVES && steps.abs() <= f64::from(i32::MAX) => {
                self.goal.expand_front(&[
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
