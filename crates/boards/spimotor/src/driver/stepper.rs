//! The stepper channel: goals onto ports 0x10 and 0x40–0x43, polls checked and taken in.

use core::time::Duration;

use motion_base::counts_to_i32;

use spimotor::{Reply, StepDelay, Write};

use super::config::SpimotorDriverConfig;
use super::ramp::{self, Motion, Observed, Ramp, TargetCommand};
use super::wire::{Expect, Op, Sent};
use super::{CONFIRMATIONS, PROTOCOL_LIMIT, SpimotorDriver};
use motion_drivers::{
    ChannelState, DeviceFault, Goal, GoalError, GoalKind, Priority, Seconds, Verdict,
};

/// A target as the driver knows it (`unknown` after a stop, until read).
struct Target(Option<i32>);

impl core::fmt::Display for Target {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some(target) => write!(f, "{target}"),
            None => f.write_str("unknown"),
        }
    }
}

/// Slack of the position plausibility check: time (for reads in flight) and steps.
const PLAUSIBILITY_SLACK: Duration = Duration::from_millis(5);
const PLAUSIBILITY_STEPS: f64 = 2.0;

/// What an absent board's MISO (all 0xFF) decodes to: position −1, target −1, delay 255.
pub(super) const ABSENT_READING: (i32, i32, u8) = (-1, -1, u8::MAX);

/// One poll's readings, gathered as its reads complete.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq)]
struct Cycle {
    /// The position read, what it should agree with, and when the board sampled it.
    position: Option<(i32, Expect, Duration)>,
    target: Option<(i32, Expect)>,
}

/// The stepper's last known state and the driver's plan for it.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(super) struct Stepper {
    /// Position counter read back, steps.
    position: i32,
    /// Target read back.
    target: Option<i32>,
    /// Step delay read back.
    delay: StepDelay,
    refreshed_at: Option<Duration>,
    /// When the board sampled the position read last (the read's transaction).
    sampled_at: Duration,
    /// A position was set since the board last (re)started.
    pub homed: bool,
    /// Step delay written at start-up and after a set-position.
    pub rest_delay: StepDelay,
    max_velocity: f64,
    max_accel: f64,
    motion: Motion,
    ramp: Ramp,
    /// Position of the last consistent poll and when its read was on the wire (the
    /// transaction's write stamp, else its queue time); `None` after start-up. Measured
    /// from the wire, not from when the tick took the reply in: a reply taken in late
    /// would otherwise shorten every later window by its lateness and make each following
    /// poll of a moving motor look too far.
    baseline: Option<(i32, Duration)>,
    cycle: Cycle,
    suspect: Option<(i32, i32, u8)>,
    repeats: u32,
    bad_in_row: u32,
    next_profile_at: Duration,
}

fn positive(value: f64) -> bool {
    value.is_finite() && value > 0.0
}

impl Stepper {
    pub fn new(config: &SpimotorDriverConfig) -> Self {
        let limits = config.limits(0);
        Self {
            position: 0,
            target: None,
            delay: StepDelay::DEFAULT,
            refreshed_at: None,
            sampled_at: Duration::ZERO,
            homed: false,
            rest_delay: ramp::delay_for(limits.max_velocity.min(ramp::fastest_rate())),
            max_velocity: limits.max_velocity,
            max_accel: limits.max_accel,
            motion: Motion::Hold,
            ramp: Ramp::default(),
            baseline: None,
            cycle: Cycle::default(),
            suspect: None,
            repeats: 0,
            bad_in_row: 0,
            next_profile_at: Duration::ZERO,
        }
    }

    /// Whether the axis limits leave the board a rate to move at (its slowest rate is
    /// 39.2 steps/s).
    pub fn can_move(&self) -> bool {
        positive(self.max_accel)
            && self.max_velocity.is_finite()
            && self.max_velocity >= ramp::slowest_rate()
    }

    /// The coils are de-energised by an `Off` goal.
    pub fn is_off(&self) -> bool {
        self.motion == Motion::Off
    }

    /// A run or a stop ramp is in progress (more writes will follow).
    pub fn ramping(&self) -> bool {
        matches!(self.motion, Motion::Run { .. } | Motion::Stopping { .. })
    }

    /// The board starts again: goals are gone, the next poll is the new baseline.
    pub fn forget(&mut self, now: Duration) {
        if self.motion != Motion::Off {
            self.motion = Motion::Hold;
        }
        self.ramp.rest(now);
        self.baseline = None;
        self.cycle = Cycle::default();
        self.suspect = None;
        self.repeats = 0;
        self.bad_in_row = 0;
    }

    /// The start-up survey read the board: this is what it does now (the baseline of the
    /// polls that follow).
    pub fn surveyed(
        &mut self,
        now: Duration,
        (position, sampled_at): (i32, Duration),
        target: i32,
        delay: StepDelay,
    ) {
        self.position = position;
        self.target = Some(target);
        self.delay = delay;
        self.refreshed_at = Some(now);
        self.sampled_at = sampled_at;
        self.baseline = Some((position, sampled_at));
        self.cycle = Cycle::default();
        self.suspect = None;
        self.repeats = 0;
        self.bad_in_row = 0;
    }

    /// What the driver is doing with the stepper.
    pub fn motion(&self) -> Motion {
        self.motion
    }

    /// The axis's acceleration limit, steps/s² (a stop the driver starts on its own).
    pub fn max_accel(&self) -> f64 {
        self.max_accel
    }

    /// Decelerates at `decel` from the signed step `rate` the board runs at now.
    pub fn stop_from(&mut self, now: Duration, decel: f64, rate: f64) {
        self.motion = Motion::Stopping {
            decel: if positive(decel) {
                decel
            } else {
                f64::INFINITY
            },
        };
        self.ramp.start_from(now, rate);
    }

    /// A write of the position counter (0x40) went out at `now`.
    pub fn position_written(&mut self, now: Duration, position: i32) {
        self.position = position;
        self.sampled_at = now;
        self.target = Some(position);
        self.baseline = Some((position, now));
        self.cycle = Cycle::default();
    }

    /// The channel as the engine sees it.
    pub fn state(&self) -> ChannelState {
        let board_moving = self.target.is_some_and(|t| t != self.position);
        let velocity = match self.target {
            Some(t) if t > self.position => ramp::rate_of(self.delay),
            Some(t) if t < self.position => -ramp::rate_of(self.delay),
            _ => 0.0,
        };
        let (moving, arrived) = match self.motion {
            Motion::Run { .. } | Motion::Stopping { .. } => (true, false),
            Motion::Move { target, .. } => (
                board_moving || target != self.position,
                !board_moving && target == self.position,
            ),
            Motion::Hold | Motion::Off => (board_moving, false),
        };
        ChannelState {
            position: f64::from(self.position),
            velocity,
            raw_counts: i64::from(self.position),
            refreshed_at: self.refreshed_at,
            moving,
            homed: self.homed,
            at_limit: false,
            arrived,
            fault: None,
        }
    }
}

impl SpimotorDriver {
    /// Makes sure the coils are energised with the configured intensity.
    fn energise(&mut self) {
        let intensity = self.config.stepper_intensity;
        if self.planned.intensity != Some(intensity) {
            self.push_command(
                Op::Write(Write::StepperIntensity(intensity)),
                Priority::Command,
                0,
            );
        }
    }

    fn push_goal_write(&mut self, write: Write) {
        self.push_command(Op::Write(write), Priority::Command, 0);
    }

    /// A goal for the stepper (channel 0); its kind is one the channel supports.
    pub(super) fn stepper_goal(&mut self, now: Duration, goal: Goal) -> Result<(), GoalError> {
        let running = self.running() && self.status.online;
        let motion = match goal {
            Goal::Off => {
                self.stepper.motion = Motion::Off;
                self.stepper.ramp.rest(now);
                if running {
                    self.drop_goals(0);
                    self.push_goal_write(Write::RelativePosition(0));
                    self.push_goal_write(Write::StepperIntensity(0));
                }
                return Ok(());
            }
            Goal::Stop { decel } => {
                // From the rate the board steps at now, not from the profile's.
                let rate = self.board_rate(now);
                self.stepper.stop_from(now, decel, rate);
                if running {
                    self.drop_goals(0);
                    self.energise();
                    self.drive_stepper(now, true);
                }
                return Ok(());
            }
            _ if !running => return Err(GoalError::Offline),
            Goal::Position { counts } => Motion::Move {
                target: counts_to_i32(counts)
                    .ok_or(GoalError::OutOfBoardRange(GoalKind::Position))?,
                velocity: self.stepper.max_velocity.min(ramp::fastest_rate()),
                accel: self.stepper.max_accel,
            },
            Goal::RampPosition {
                counts,
                velocity,
                accel,
            } => {
                let range = GoalError::OutOfBoardRange(GoalKind::RampPosition);
                if !(positive(accel) && velocity.is_finite() && velocity >= ramp::slowest_rate()) {
                    return Err(range);
                }
                Motion::Move {
                    target: counts_to_i32(counts).ok_or(range)?,
                    velocity: velocity.min(ramp::fastest_rate()),
                    accel,
                }
            }
            Goal::Velocity { velocity, accel } => {
                let speed = velocity.abs();
                let representable = speed == 0.0
                    || (speed >= ramp::slowest_rate() && speed <= ramp::fastest_rate());
                if !(positive(accel) && velocity.is_finite() && representable) {
                    return Err(GoalError::OutOfBoardRange(GoalKind::Velocity));
                }
                if speed == 0.0 {
                    let rate = self.board_rate(now);
                    self.stepper.stop_from(now, accel, rate);
                    if running {
                        self.drop_goals(0);
                        self.energise();
                        self.drive_stepper(now, true);
                    }
                    return Ok(());
                } else {
                    Motion::Run { velocity, accel }
                }
            }
            Goal::SetPosition { counts } => {
                let position = counts_to_i32(counts)
                    .ok_or(GoalError::OutOfBoardRange(GoalKind::SetPosition))?;
                self.drop_goals(0);
                self.stepper.motion = Motion::Hold;
                self.stepper.ramp.rest(now);
                self.energise();
                // A slow delay first, so that no step slips in between the two writes
                // (0x40 alone would walk back to the old target).
                self.push_goal_write(Write::StepDelay(ramp::SLOWEST_DELAY));
                self.push_goal_write(Write::CurrentPosition(position));
                self.push_goal_write(Write::TargetPosition(position));
                self.push_goal_write(Write::StepDelay(self.stepper.rest_delay));
                self.stepper.homed = true;
                return Ok(());
            }
            Goal::Power { .. } | Goal::Home { .. } => {
                return Err(GoalError::Unsupported(goal.kind()));
            }
        };
        self.stepper.motion = motion;
        if running {
            self.drop_goals(0);
            self.energise();
            self.drive_stepper(now, true);
        }
        Ok(())
    }

    /// One profile update: rewrites the step delay and target the ramp asks for. Runs
    /// every poll period (`force` runs it now, for a new goal).
    pub(super) fn drive_stepper(&mut self, now: Duration, force: bool) {
        if !force
            && (now < self.stepper.next_profile_at
                || self
                    .commands
                    .iter()
                    .any(|queued| queued.priority == Priority::Command))
        {
            return;
        }
        self.stepper.next_profile_at = now.saturating_add(self.config.poll_period);
        let position = self.stepper.position;
        let observed = Observed {
            position: self.estimated_position(now),
            target: self.planned.target,
            standing: self.stepper.target == Some(position)
                && self.planned.target == Some(position),
            lookahead: self.config.poll_period,
        };
        let stepper = &mut self.stepper;
        let rate_before = stepper.ramp.rate;
        let Some(step) = stepper.ramp.update(now, &mut stepper.motion, observed) else {
            return;
        };
        let writes = step.target != TargetCommand::Keep || step.delay != self.planned.delay;
        if !writes && (force || self.stepper.ramp.rate != rate_before) {
            // A new goal, or a profile on the move, that the board's 0.1 ms step delay
            // cannot show yet (a speed-up integrated over no time, or over less than one
            // delay step): the next tick updates again, not a whole poll period later, so
            // the first change is written in the first tick that has one.
            self.stepper.next_profile_at = now;
        }
        if step.target == TargetCommand::StopHere {
            self.push_goal_write(Write::RelativePosition(0));
        }
        if step.delay != self.planned.delay {
            self.push_goal_write(Write::StepDelay(step.delay));
        }
        if let TargetCommand::Set(target) = step.target {
            self.push_goal_write(Write::TargetPosition(target));
        }
    }

    /// The signed step rate the board runs at now: the step delay in force (as written,
    /// the last read confirming it) towards the target it has, 0 when it stands.
    pub(super) fn board_rate(&self, now: Duration) -> f64 {
        let position = self.estimated_position(now);
        let Some(target) = self.written.target.or(self.stepper.target) else {
            return 0.0;
        };
        let rate = ramp::rate_of(self.written.delay);
        match target.cmp(&position) {
            core::cmp::Ordering::Greater => rate,
            core::cmp::Ordering::Less => -rate,
            core::cmp::Ordering::Equal => 0.0,
        }
    }

    /// Where the board is now at the latest: the last position read, plus what the
    /// step delay in force lets it walk towards the target it had since that read was
    /// sampled (never past that target). Braking on this errs on the early side.
    fn estimated_position(&self, now: Duration) -> i32 {
        let stepper = &self.stepper;
        let Some(target) = stepper.target else {
            return stepper.position;
        };
        let gap = i64::from(target) - i64::from(stepper.position);
        let age = now.saturating_sub(stepper.sampled_at).as_secs_f64();
        let rate = ramp::rate_of(self.written.delay).max(ramp::rate_of(stepper.delay));
        // `travel` ≤ |gap| < 2^32: the sum stays between position and target.
        let travel = ((rate * age).floor() as i64).min(gap.abs());
        i32::try_from(i64::from(stepper.position) + gap.signum() * travel)
            .unwrap_or(stepper.position)
    }

    /// A stepper poll read completed.
    pub(super) fn stepper_reading(&mut self, now: Duration, reply: Reply, sent: Sent) {
        let expect = sent.expect;
        let cycle = &mut self.stepper.cycle;
        match reply {
            Reply::CurrentPosition(position) => {
                cycle.position = Some((position, expect, sent.at));
            }
            Reply::TargetPosition(target) => cycle.target = Some((target, expect)),
            Reply::StepDelay(delay) => {
                let taken = core::mem::take(cycle);
                if let (Some(position), Some(target)) = (taken.position, taken.target) {
                    self.check_poll(now, position, target, (delay, expect));
                }
            }
            Reply::Identification(_) | Reply::Serial(_) => {}
        }
    }

    /// Takes in one whole poll if it agrees with what the driver wrote.
    fn check_poll(
        &mut self,
        now: Duration,
        (position, position_expect, sampled_at): (i32, Expect, Duration),
        (target, target_expect): (i32, Expect),
        (delay, delay_expect): (StepDelay, Expect),
    ) {
        if position_expect.epoch != self.epoch {
            return; // The position counter was written since: this reading is void.
        }
        let delay_ok = delay == delay_expect.delay;
        let target_ok = target_expect.target.is_none_or(|t| t == target);
        // The board steps no faster than the step delay in force: the one read last, or the
        // one in force when this read went out, whichever is faster.
        let rate = ramp::rate_of(position_expect.delay).max(ramp::rate_of(self.stepper.delay));
        let plausible = self.stepper.baseline.is_none_or(|(before, at)| {
            let window = sampled_at
                .saturating_sub(at)
                .saturating_add(PLAUSIBILITY_SLACK);
            let reach = rate * window.as_secs_f64() + PLAUSIBILITY_STEPS;
            (i64::from(position) - i64::from(before)).unsigned_abs() as f64 <= reach
        });
        if delay_ok && target_ok && plausible {
            let stepper = &mut self.stepper;
            stepper.position = position;
            stepper.target = Some(target);
            stepper.delay = delay;
            stepper.refreshed_at = Some(now);
            stepper.sampled_at = sampled_at;
            stepper.baseline = Some((position, sampled_at));
            stepper.suspect = None;
            stepper.repeats = 0;
            stepper.bad_in_row = 0;
            // Learn a target left unknown by a stop, unless a target write went out since.
            if self.written.target.is_none() && target_expect.target_seq == self.written.target_seq
            {
                self.written.target = Some(target);
                if self.planned.target_seq == self.written.target_seq {
                    self.planned.target = Some(target);
                    let stopped = matches!(self.stepper.motion, Motion::Hold | Motion::Off);
                    if stopped && target != position {
                        // 0x42 ← 0 did not stop it (a firmware that counts the relative
                        // target from the old target): pin the target where it is now.
                        self.push_goal_write(Write::TargetPosition(position));
                    }
                }
            }
            if target == position && self.stepper.motion == Motion::Hold {
                self.stepper.ramp.rest(now);
            }
            self.good_reply();
            self.refreshed(now);
            return;
        }
        self.bad_reply();
        let stepper = &mut self.stepper;
        stepper.bad_in_row = stepper.bad_in_row.saturating_add(1);
        let reading = (position, target, delay.tenths_ms());
        if stepper.suspect == Some(reading) {
            stepper.repeats = stepper.repeats.saturating_add(1);
        } else {
            stepper.suspect = Some(reading);
            stepper.repeats = 1;
        }
        if stepper.repeats >= CONFIRMATIONS {
            let (tenths, written) = (delay.tenths_ms(), self.written);
            if reading == ABSENT_READING {
                let verdict = Verdict::new(
                    DeviceFault::NotResponding,
                    now,
                    format_args!(
                        "{CONFIRMATIONS} polls in a row read position -1, target -1, step \
                         delay 255, the last at {}: MISO all 0xFF, nobody drives it",
                        Seconds(now),
                    ),
                );
                self.absent(now, verdict);
            } else if (position == 0 && target == 0) || delay == StepDelay::DEFAULT {
                // Power-on registers (counter and target 0, "default 200" step delay):
                // the board lost its registers.
                let verdict = Verdict::new(
                    DeviceFault::Reset,
                    now,
                    format_args!(
                        "{CONFIRMATIONS} polls in a row read position {position}, target \
                         {target}, step delay {tenths} (power-on registers: counter and target \
                         0, or \"default 200\"), the last at {}; written were target {}, step \
                         delay {}: the board lost its registers",
                        Seconds(now),
                        Target(written.target),
                        written.delay.tenths_ms(),
                    ),
                );
                self.board_reset(now, verdict);
            } else {
                // Somebody else writes the board, or MISO is stuck: start it over.
                self.raise(DeviceFault::Protocol);
                self.restart(now, 0);
            }
        } else if stepper.bad_in_row >= PROTOCOL_LIMIT {
            self.raise(DeviceFault::Protocol);
        }
    }
}
