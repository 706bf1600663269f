//! Start-up (module docs, "Start-up"): the identification and serial reads, the
//! stepper's survey (what the board does now), then the configuration; and what a restart
//! (silence, a board reset, the link) voids.

use core::fmt::Write as _;
use core::time::Duration;

use spimotor::{Identification, ReadPort, Reply, SerialNumber, StepDelay, Write};

use super::ramp::Motion;
use super::stepper::ABSENT_READING;
use super::wire::Op;
use super::{Phase, SpimotorDriver};
use motion_drivers::{DeviceFault, FIRMWARE_LEN, Priority, Seconds, Verdict};

/// Survey readings that disagree in a row before the board is started over.
pub const SURVEY_ATTEMPTS: u32 = 8;

/// One complete survey reading: position and when it was read, target, step delay.
type Reading = ((i32, Duration), i32, StepDelay);

/// The survey's readings so far.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct Survey {
    /// The position read and when its transaction went out.
    position: Option<(i32, Duration)>,
    target: Option<i32>,
    /// The previous complete reading: the survey is believed when two in a row agree
    /// (garbage on MISO rarely repeats itself).
    candidate: Option<Reading>,
    attempts: u32,
}

/// Whether two readings describe one board: the same target and step delay, and a
/// position no farther on than the board can step in between.
fn agree(a: Reading, b: Reading) -> bool {
    let ((pa, at_a), ta, da) = a;
    let ((pb, at_b), tb, db) = b;
    let window = at_b.saturating_sub(at_a).as_secs_f64() + 0.005;
    let reach = super::ramp::fastest_rate() * window + 2.0;
    ta == tb && da == db && (i64::from(pb) - i64::from(pa)).unsigned_abs() as f64 <= reach
}

impl SpimotorDriver {
    /// Stepper: reads position, target and step delay before writing anything.
    pub(super) fn begin_survey(&mut self) {
        self.phase = Phase::Survey;
        self.survey = Survey::default();
        self.queue_survey();
    }

    fn queue_survey(&mut self) {
        for port in [
            ReadPort::CurrentPosition,
            ReadPort::TargetPosition,
            ReadPort::StepDelay,
        ] {
            self.push_command(Op::read(port), Priority::Setup, 0);
        }
    }

    /// One of the survey's reads completed (its transaction went out at `sent_at`).
    pub(super) fn survey_reading(&mut self, now: Duration, reply: Reply, sent_at: Duration) {
        match reply {
            Reply::CurrentPosition(position) => self.survey.position = Some((position, sent_at)),
            Reply::TargetPosition(target) => self.survey.target = Some(target),
            Reply::StepDelay(delay) => {
                let (Some(position), Some(target)) =
                    (self.survey.position.take(), self.survey.target.take())
                else {
                    return;
                };
                let reading = (position, target, delay);
                match self.survey.candidate {
                    Some(before) if agree(before, reading) => {
                        self.survey = Survey::default();
                        self.surveyed(now, position, target, delay);
                    }
                    _ => {
                        self.survey.candidate = Some(reading);
                        self.survey.attempts = self.survey.attempts.saturating_add(1);
                        if self.survey.attempts > SURVEY_ATTEMPTS {
                            // Nothing consistent comes back: a stuck or noisy MISO line.
                            self.bad_reply();
                            self.raise(motion_drivers::DeviceFault::Protocol);
                            self.restart(now, 0);
                        } else {
                            self.queue_survey();
                        }
                    }
                }
            }
            Reply::Identification(_) | Reply::Serial(_) => {}
        }
    }

    /// The survey is complete: the registers are what the board has, the board is online,
    /// and the configuration goes out.
    fn surveyed(
        &mut self,
        now: Duration,
        position: (i32, Duration),
        target: i32,
        delay: StepDelay,
    ) {
        if (position.0, target, delay.tenths_ms()) == ABSENT_READING {
            // Undriven MISO after all: nobody is there.
            let address = self.config.address.get();
            self.absent(
                now,
                Verdict::new(
                    DeviceFault::NotResponding,
                    now,
                    format_args!(
                        "the survey at address 0x{address:02x} read position -1, target -1, \
                         step delay 255 twice, the last at {}: MISO all 0xFF, nobody drives it",
                        Seconds(now),
                    ),
                ),
            );
            return;
        }
        self.good_reply();
        self.written.delay = delay;
        self.written.target = Some(target);
        self.planned = self.written;
        self.stepper.surveyed(now, position, target, delay);
        self.refreshed(now);
        self.status.online = true;
        self.phase = Phase::Running;
        self.next_poll_at = now;
        self.polls_done = 0;
        let moving = target != position.0;
        self.configure(now, moving);
    }

    /// Queues the start-up writes. A standing stepper: stop where it is (0x42 ← 0), coils,
    /// the resting step delay, intensity. A stepper that moves (left running by another
    /// program): coils and intensity only, and a stop that ramps its step rate down from
    /// the one it runs at (at the stop's deceleration if one was asked for, else the axis's
    /// max acceleration); an `Off` asked for meanwhile stops it at once instead. Brushed:
    /// stop A and B (0x22, 0x32).
    pub(super) fn configure(&mut self, now: Duration, moving: bool) {
        if !self.is_stepper() {
            for motor in spimotor::Motor::ALL {
                self.push_command(
                    Op::Write(Write::Stop(motor)),
                    Priority::Setup,
                    motor.channel(),
                );
            }
            return;
        }
        let off = self.stepper.is_off();
        let intensity = if off {
            0
        } else {
            self.config.stepper_intensity
        };
        if moving && !off {
            for write in [
                Write::Coils(self.config.coils),
                Write::StepperIntensity(intensity),
            ] {
                self.push_command(Op::Write(write), Priority::Setup, 0);
            }
            let decel = match self.stepper.motion() {
                Motion::Stopping { decel } => decel,
                _ => self.stepper.max_accel(),
            };
            let rate = self.board_rate(now);
            self.stepper.stop_from(now, decel, rate);
            return;
        }
        if let Motion::Stopping { decel } = self.stepper.motion() {
            // A stop asked for while starting: the board stands, nothing to ramp.
            self.stepper.stop_from(now, decel, 0.0);
        }
        for write in [
            Write::RelativePosition(0),
            Write::Coils(self.config.coils),
            Write::StepDelay(self.stepper.rest_delay),
            Write::StepperIntensity(intensity),
        ] {
            self.push_command(Op::Write(write), Priority::Setup, 0);
        }
    }

    /// Starts the board again from the identification read (goals are lost).
    pub(super) fn restart(&mut self, now: Duration, attempts: u32) {
        self.phase = Phase::Identify {
            attempts,
            next_at: now,
        };
        self.status.online = false;
        self.commands.clear();
        self.polls.clear();
        self.planned = self.written;
        self.presence_misses = 0;
        self.stepper.forget(now);
    }

    pub(super) fn set_firmware(&mut self, serial: SerialNumber) {
        let mut text = motion_base::FixedText::<FIRMWARE_LEN>::new();
        let identification = self.identification;
        let id = identification
            .as_ref()
            .and_then(Identification::as_str)
            .unwrap_or("?");
        let _ = write!(text, "{id} sn {:08x}", serial.0);
        self.status.set_firmware(text.as_str());
    }

    /// Queues the start-up read of the current phase when due.
    pub(super) fn schedule_startup(&mut self, now: Duration) {
        if !self.link_up || !self.commands.is_empty() {
            return;
        }
        let op = match self.phase {
            Phase::Identify { next_at, .. }
                if now >= next_at && !self.in_flight.reading(ReadPort::Identification) =>
            {
                Op::read(ReadPort::Identification)
            }
            Phase::Serial if !self.in_flight.reading(ReadPort::Serial) => {
                Op::read(ReadPort::Serial)
            }
            _ => return,
        };
        if let Phase::Identify { attempts, .. } = self.phase {
            // No second read before this one is answered or times out.
            self.phase = Phase::Identify {
                attempts,
                next_at: now.saturating_add(self.reply_timeout()),
            };
        }
        self.push_command(op, Priority::Setup, 0);
    }
}
