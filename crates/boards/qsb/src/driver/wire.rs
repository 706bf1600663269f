//! The wire side of the driver: the one request in flight and who sent it, which request
//! goes next (start-up, then set-positions, goals and outputs, then the liveness probe),
//! and how every plan moves on as far as it can without the board.

use core::time::Duration;

use ::qsb::{QsbCommand, Register, Request, Write};

use super::QsbDriver;
use super::program::{self, Step};
use motion_drivers::{Priority, Transmit};

/// The liveness probe: TIME STAMP, "a 32-bit counter incremented every 1.95ms … cleared
/// on a power-cycle": its answer says the board is there, and whether it restarted.
pub(super) const PROBE: Request = Request::Read(Register::TimeStamp);

/// Who sent the request in flight.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Origin {
    Setup,
    Preset,
    Goal,
    /// A DIG I/O write of the signal outputs.
    Io,
    /// A new compare position (DTR), or the STR clear that re-arms the pulse count.
    Event,
    Probe,
}

/// The request awaiting its answer.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(super) struct InFlight {
    pub(super) request: Request,
    pub(super) origin: Origin,
    pub(super) generation: u32,
    pub(super) deadline: Duration,
    /// Its message number (`IoStamps::sent`).
    pub(super) number: u64,
    /// When it was written (queued, until the link reports the write).
    pub(super) written: Duration,
    /// The newest time stamp accepted before it was sent. The board executes a command
    /// after it received it, and every line the host had before it wrote the command was
    /// made before: its answer carries no older stamp ("recorded at the time the data was
    /// read"), so a line with an older one answers an earlier request.
    pub(super) floor: Option<u32>,
    /// A line that may have been its answer could not be decoded, or was held by the
    /// stamp guard: once it is due, it is lost rather than late.
    pub(super) garbled: bool,
    /// Its deadline has been judged passed (the link was heard up to it).
    pub(super) overdue: bool,
    /// When the first line after its deadline arrived.
    pub(super) heard_after_deadline: Option<Duration>,
}

impl QsbDriver {
    /// Whether the board is known to hold `write`'s value already (not while a write to
    /// that register awaits its answer: the board may yet take it, or refuse it).
    pub(super) fn holds(&self, write: Write) -> bool {
        let register = write.register();
        self.board
            .get(usize::from(register.number()))
            .copied()
            .flatten()
            == Some(write.data())
            && !self
                .in_flight
                .is_some_and(|f| matches!(f.request, Request::Write(w) if w.register() == register))
    }

    /// Whether a motor command (move, jog, stop, quit, pause, resume) awaits its answer.
    pub(super) fn motor_command_in_flight(&self) -> bool {
        self.in_flight.is_some_and(|f| {
            matches!(
                f.request,
                Request::Write(Write::Command(
                    QsbCommand::StopAll
                        | QsbCommand::MotorStop
                        | QsbCommand::MotorQuit
                        | QsbCommand::MotorPause
                        | QsbCommand::MotorResume
                        | QsbCommand::MotorMove
                        | QsbCommand::MotorJog
                ))
            )
        })
    }

    /// The request a step sends now, `None` for a step with nothing to send.
    pub(super) fn request_of(&self, step: Step) -> Option<Request> {
        match step {
            Step::Send(request) => Some(request),
            Step::Ensure(write) => (!self.holds(write)).then_some(Request::Write(write)),
            Step::Outputs => self.outputs_due().map(Request::Write),
            Step::Enable(on) => {
                let write = Write::DigIo(::qsb::DigIo(self.latch_with(on)));
                (self.config.enable.is_some() && !self.holds(write))
                    .then_some(Request::Write(write))
            }
            Step::NormalStrStream if self.str_wanted() => (!self.str_streaming
                && !self
                    .in_flight
                    .is_some_and(|f| f.request == Request::Stream(Register::Str)))
            .then_some(Request::Stream(Register::Str)),
            Step::NormalStrStream => (self.str_streaming
                || self
                    .in_flight
                    .is_some_and(|f| f.request == Request::Stream(Register::Str)))
            .then_some(Request::Read(Register::Str)),
            Step::NormalCounter => self.normal_counter_write().map(Request::Write),
            // Unless the drive is known to be done (a motor command just sent may not show
            // in MD STATUS yet), stop it.
            Step::StopIfMoving => (!self.drive_done())
                .then_some(Request::Write(Write::Command(QsbCommand::MotorStop))),
            Step::Configure
            | Step::Online
            | Step::WaitDone
            | Step::MoveTo { .. }
            | Step::WaitIndex
            | Step::Armed
            | Step::Paused => None,
        }
    }

    /// Whether `origin`'s plan has its front step in flight (it must not move on).
    pub(super) fn busy(&self, origin: Origin, generation: u32) -> bool {
        self.in_flight
            .is_some_and(|f| f.origin == origin && f.generation == generation)
    }

    /// The next request to send, who sends it and how urgent it is.
    pub(super) fn next_request(&self) -> Option<(Request, Origin, Priority)> {
        if !self.link_up || self.in_flight.is_some() || self.eor_until.is_some() {
            return None;
        }
        if let Some(step) = self.setup.front() {
            return self
                .request_of(step)
                .map(|r| (r, Origin::Setup, Priority::Setup));
        }
        if !self.status.online {
            return None;
        }
        for (program, origin) in [(&self.preset, Origin::Preset), (&self.goal, Origin::Goal)] {
            if let Some(request) = program.front().and_then(|step| self.request_of(step)) {
                return Some((request, origin, Priority::Command));
            }
        }
        if let Some(write) = self.outputs_due() {
            return Some((Request::Write(write), Origin::Io, Priority::Command));
        }
        if let Some(write) = self.compare_due().or_else(|| self.trigger_clear_due()) {
            return Some((Request::Write(write), Origin::Event, Priority::Command));
        }
        self.probe_due
            .then_some((PROBE, Origin::Probe, Priority::Poll))
    }

    /// Lets every plan move on as far as it can without the board.
    pub(super) fn settle(&mut self, now: Duration) {
        if self.home_failed && self.goal.is_empty() && (!self.drive_active() || self.drive_done()) {
            // The failed search's stop is complete.
            self.home_failed = false;
        }
        for _ in 0..4 * program::PROGRAM_CAPACITY {
            if self.busy(Origin::Setup, self.setup.generation()) {
                break;
            }
            match self.setup.front() {
                Some(Step::Configure) => match self.product {
                    Some(product) => self.configure(product),
                    // (Cannot happen: VERSION is read first.) Never sit offline for good.
                    None => self.restart_later(now),
                },
                Some(Step::Online) => {
                    self.setup.pop();
                    self.status.online = true;
                    self.online_at = now;
                }
                Some(step) if self.request_of(step).is_none() => self.setup.pop(),
                _ => break,
            }
        }
        if !self.status.online {
            return;
        }
        for _ in 0..4 * program::PROGRAM_CAPACITY {
            if self.busy(Origin::Preset, self.preset.generation()) {
                break;
            }
            match self.preset.front() {
                Some(step) if self.request_of(step).is_none() => self.preset.pop(),
                _ => break,
            }
        }
        for _ in 0..4 * program::PROGRAM_CAPACITY {
            if self.busy(Origin::Goal, self.goal.generation()) || !self.settle_goal_step(now) {
                break;
            }
        }
    }

    /// Lets time pass: the restart after silence, the request in flight (module
    /// `liveness`), the liveness probe when the stream went quiet.
    pub(super) fn pass_time(&mut self, now: Duration) {
        if !self.link_up {
            return;
        }
        if self.restart_at.is_some_and(|at| now >= at) {
            self.begin_startup();
        }
        if self
            .eor_until
            .is_some_and(|until| self.io_stamps.judged(now) >= until)
        {
            self.eor_until = None;
        }
        self.judge_in_flight(now);
        let quiet_since = self
            .last_sample_at
            .map_or(self.online_at, |at| at.max(self.online_at));
        if self.status.online
            && self.in_flight.is_none()
            && !self.probe_due
            && self.io_stamps.judged(now)
                >= quiet_since.saturating_add(self.config.refresh_budget())
        {
            self.probe_due = true;
            self.samples_since_probe = false;
        }
        self.settle(now);
    }

    /// Writes the next request into `buf` and puts it in flight.
    pub(super) fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let (request, origin, _) = self.next_request()?;
        let len = request.encode(buf).ok()?;
        if origin == Origin::Goal
            && let Some(Step::Enable(on)) = self.goal.front()
        {
            // The enable line goes with this write: the signal outputs written from now on
            // carry it (settling the step sets it too, when nothing needs to be sent).
            self.io.energised = on;
        }
        let generation = match origin {
            Origin::Setup => self.setup.generation(),
            Origin::Preset => self.preset.generation(),
            Origin::Goal => self.goal.generation(),
            Origin::Io | Origin::Event => 0,
            Origin::Probe => {
                self.probe_due = false;
                self.samples_since_probe = false;
                0
            }
        };
        self.in_flight = Some(InFlight {
            request,
            origin,
            generation,
            deadline: now.saturating_add(self.config.reply_timeout()),
            number: self.io_stamps.sent(),
            written: now,
            floor: self.stamps.last(),
            garbled: false,
            overdue: false,
            heard_after_deadline: None,
        });
        let mut goal_starts = 0;
        if matches!(origin, Origin::Goal | Origin::Preset) && self.goal_unsent {
            self.goal_unsent = false;
            goal_starts = 1;
        }
        Some(Transmit {
            len,
            expects_reply: true,
            goal_starts,
        })
    }

    /// A message went out at `at`: the reply timeout of the request in flight runs from
    /// there if it is that message.
    pub(super) fn on_written(&mut self, at: Duration) {
        let number = self.io_stamps.written();
        let timeout = self.config.reply_timeout();
        if let Some(flight) = self.in_flight.as_mut()
            && flight.number == number
        {
            flight.written = at;
            flight.deadline = at.saturating_add(timeout);
        }
    }
}
