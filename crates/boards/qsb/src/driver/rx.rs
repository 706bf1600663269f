//! What the driver does with each response line: answers to its requests, streamed
//! samples, and the signs of a reset.

use core::time::Duration;

use ::qsb::{
    EncoderMode, IndexMode, LoadTarget, MdStatus, QsbCommand, Register, Request, Response,
    ResponseType, Str, Version, Write,
};

use super::encoder::Sample;
use super::guard::{StampReset, StampVerdict};
use super::liveness::{Answer, Line, answers, before};
use super::program::Step;
use super::wire::PROBE;
use super::{InFlight, Origin, QsbDriver};
use motion_drivers::{ChannelState, DeviceFault, GoalKind, Seconds, Verdict};

/// Probes answered in a row with no streamed sample between them before the streams are
/// asked for again.
const QUIET_PROBES: u8 = 2;

/// Data output ticks after a motor command before MD STATUS is trusted: the first tick
/// after the command may report the drive before it started, its MD STATUS line follows
/// the encoder line of that tick.
const DONE_AFTER_TICKS: u32 = 2;

/// Whether a write only changes a register (the driver may remember its value), rather
/// than doing something.
fn is_setting(write: Write) -> bool {
    !matches!(
        write,
        Write::Clear(_) | Write::Load(_) | Write::TimeStamp(_) | Write::Command(_)
    )
}

impl QsbDriver {
    /// One decoded line.
    pub(super) fn on_response(&mut self, now: Duration, response: Response) {
        self.heard(now);
        // Only a line that carries a value read from the board ("the time stamp value
        // recorded at the time the data was read") is judged by its stamp: a write's echo
        // without one says nothing about EOR.
        let stamped = response.time_stamp.is_some()
            || matches!(response.ty, ResponseType::Read | ResponseType::Stream);
        let verdict = if stamped {
            self.stamps.check(
                now,
                response.time_stamp,
                self.eor_configured,
                self.config.latency,
            )
        } else {
            StampVerdict::Accept
        };
        match verdict {
            StampVerdict::Accept => {}
            StampVerdict::Rewound => {
                // The line accepted before the held one carried a corrupted stamp: what it
                // brought is not on the timeline.
                if let Some(stamp) = response.time_stamp {
                    self.encoder.forget_after(stamp);
                }
            }
            StampVerdict::NewTimeline => {
                // Samples before the jump are no base for a velocity.
                self.encoder.clear();
            }
            StampVerdict::Hold => {
                // Corrupted on the line, or the first line of a change the next confirms.
                // If it was the answer in flight, that answer is lost (asked again once
                // due): the next line decides.
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
                if let Some(flight) = self.in_flight.as_mut()
                    && answers(flight.request, &response)
                {
                    flight.garbled = true;
                }
                return;
            }
            StampVerdict::Reset(reset) => {
                let verdict = match reset {
                    StampReset::Backwards { last, held, stamp } => Verdict::new(
                        DeviceFault::Reset,
                        now,
                        format_args!(
                            "time stamp back from {last:08X} to {held:08X}, then `{}` at {} \
                             with {stamp:08X}: the counter restarted (\"cleared on a \
                             power-cycle\")",
                            Answer(&response),
                            Seconds(now),
                        ),
                    ),
                    StampReset::Unstamped => Verdict::new(
                        DeviceFault::Reset,
                        now,
                        format_args!(
                            "two lines in a row without the time stamp EOR 5 asks for, the \
                             last `{}` at {}: the board answers in its saved EOR again",
                            Answer(&response),
                            Seconds(now),
                        ),
                    ),
                };
                self.board_reset(verdict);
                return;
            }
        }
        let flight = self.answered(&response);
        if response.ty == ResponseType::Stream {
            self.status.replies = self.status.replies.saturating_add(1);
            // The `s` line answering a stream request is the register as it is; the
            // lines after it are changes (a capture, a latch).
            let starts = flight.is_some_and(|f| matches!(f.request, Request::Stream(_)));
            self.on_stream(now, &response, starts);
        }
        match flight {
            Some(flight) => self.on_answer(now, flight, &response),
            None if response.ty != ResponseType::Stream => self.unanswered_line(&response),
            None => {}
        }
    }

    /// A streamed line (or the `s` answer that starts a stream).
    fn on_stream(&mut self, now: Duration, response: &Response, starts: bool) {
        match Register::from_u8(response.register) {
            Some(Register::ReadEncoder) => {
                let Some(time_stamp) = response.time_stamp else {
                    // A line of a stream left running before start-up configured EOR.
                    return;
                };
                if self.config.input_mode == EncoderMode::Quadrature {
                    if self.rebase_pending {
                        self.rebase_pending = false;
                        self.encoder.clear();
                    }
                    let sample = Sample {
                        count: response.signed(),
                        time_stamp,
                    };
                    if !self.encoder.offer(sample, self.config.max_accel) {
                        // Held by the line-noise guard until the next sample.
                        self.status.bad_replies = self.status.bad_replies.saturating_add(1);
                        return;
                    }
                    self.position = self.encoder.latest().map_or(sample.count, |s| s.count);
                } else {
                    self.io_line(now, Register::ReadEncoder, response.data);
                }
                self.last_sample_at = Some(now);
                self.samples_since_probe = true;
                self.quiet_probes = 0;
                // A probe not sent yet is no longer needed.
                self.probe_due = false;
                if self.status.online
                    && matches!(
                        self.status.fault,
                        Some(
                            DeviceFault::LinkDown
                                | DeviceFault::NotResponding
                                | DeviceFault::Reset
                                | DeviceFault::Protocol
                        )
                    )
                {
                    self.status.fault = None;
                }
            }
            Some(Register::MdStatus) => {
                if let Ok(md) = MdStatus::from_data(response.data) {
                    if self.status.online && self.drive_active() && !md.enabled {
                        // The drive was enabled at start-up: a board that reports it
                        // disabled has been reset (or stopped with COMMAND 0). Two lines
                        // in a row must say so: one may be corrupted on the line.
                        if !self.md_disabled_once {
                            self.md_disabled_once = true;
                            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
                            return;
                        }
                        self.board_reset(Verdict::new(
                            DeviceFault::Reset,
                            now,
                            format_args!(
                                "MD STATUS {:02X} on two lines in a row, the last at {}: the \
                                 drive enabled at start-up (COMMAND 2) is disabled (B4)",
                                response.data,
                                Seconds(now),
                            ),
                        ));
                        return;
                    }
                    self.md_disabled_once = false;
                    self.md = Some(md);
                }
            }
            Some(Register::Str) => {
                let Ok(status) = Str::from_data(response.data) else {
                    return;
                };
                if status.index && self.index_armed {
                    // The index reset CNTR (MDR0 0x63); this tick's encoder line is the
                    // first after the jump.
                    self.index_seen = true;
                    self.index_armed = false;
                    self.rebase_pending = true;
                }
                self.trigger_status(status);
            }
            Some(register @ (Register::DigIo | Register::Capture))
                if response.time_stamp.is_some() =>
            {
                if register == Register::Capture && !starts {
                    self.events.captures = self.events.captures.wrapping_add(1);
                }
                self.io_line(now, register, response.data);
            }
            _ => {}
        }
    }

    /// The answer to the request in flight.
    fn on_answer(&mut self, now: Duration, flight: InFlight, response: &Response) {
        self.in_flight = None;
        // The response ends with its EOR, after the `!` the line was decoded at: the next
        // command waits for it (module `liveness`).
        self.eor_until = Some(now.saturating_add(self.config.reply_timeout()));
        if matches!(response.ty, ResponseType::Error | ResponseType::Unsupported) {
            self.refused(now, flight);
            return;
        }
        self.attempts = 0;
        if response.ty != ResponseType::Stream {
            // (A stream's `s` answer was counted as a streamed line.)
            self.status.replies = self.status.replies.saturating_add(1);
        }
        if self.status.fault == Some(DeviceFault::BoardError) {
            self.status.fault = None;
        }
        match flight.request {
            // The pulse count's re-arming: the home search's index latch is none of its
            // business.
            Request::Write(Write::Clear(::qsb::ClearTarget::Str))
                if flight.origin == Origin::Event =>
            {
                self.events.latched = false;
            }
            Request::Write(write) => {
                if let Write::Dtr(value) = write {
                    self.dtr_written(value, now);
                }
                self.written(write, response.time_stamp);
            }
            Request::Read(Register::Version) => {
                if !self.version_read(now, response.data) {
                    return;
                }
            }
            PROBE if flight.origin == Origin::Probe => {
                if !self.probe_answered(now, flight, response.data) {
                    return;
                }
            }
            Request::Read(Register::Str) => self.str_streaming = false,
            Request::Stream(Register::Str) => self.str_streaming = true,
            Request::Stream(Register::DigIo) => self.io.dio_streaming = true,
            Request::Stream(Register::Capture) => self.io.capture_streaming = true,
            Request::Read(Register::DigIoConfig) => {
                // What the board holds: an equal configuration is not written again.
                if let Some(slot) = self
                    .board
                    .get_mut(usize::from(Register::DigIoConfig.number()))
                {
                    *slot = Some(response.data);
                }
            }
            Request::Read(_) | Request::Stream(_) => {}
        }
        self.advance(flight);
    }

    /// Pops the step whose request was answered, if its plan is still the same.
    pub(super) fn advance(&mut self, flight: InFlight) {
        let program = match flight.origin {
            Origin::Setup => &mut self.setup,
            Origin::Preset => &mut self.preset,
            Origin::Goal => &mut self.goal,
            Origin::Io | Origin::Event | Origin::Probe => return,
        };
        // Normal operation's counter registers are several writes: the step goes once
        // the board holds them all (`settle`).
        if program.generation() == flight.generation && program.front() != Some(Step::NormalCounter)
        {
            program.pop();
        }
    }

    /// What an accepted write changed.
    fn written(&mut self, write: Write, time_stamp: Option<u32>) {
        if is_setting(write)
            && let Some(slot) = self.board.get_mut(usize::from(write.register().number()))
        {
            *slot = Some(write.data());
        }
        match write {
            Write::Command(
                QsbCommand::MotorMove
                | QsbCommand::MotorJog
                | QsbCommand::MotorStop
                | QsbCommand::MotorQuit
                | QsbCommand::MotorPause
                | QsbCommand::MotorResume,
            ) => self.motor_commanded(time_stamp),
            Write::Command(QsbCommand::StopStreaming) => {
                self.str_streaming = false;
                self.io.dio_streaming = false;
                self.io.capture_streaming = false;
            }
            // "All I/O port pins will be set "high" after a write to this configuration
            // register".
            Write::DigIoConfig(_) => {
                if let Some(slot) = self.board.get_mut(usize::from(Register::DigIo.number())) {
                    *slot = Some(0xF);
                }
            }
            Write::Load(LoadTarget::DtrToCntr) => {
                self.rebase_pending = true;
                self.homed = true;
            }
            Write::Clear(::qsb::ClearTarget::Str) => {
                self.events.latched = false;
                // Armed when the index acts on the counter (a home search's MDR0).
                self.index_armed = self
                    .board
                    .get(usize::from(Register::Mdr0.number()))
                    .copied()
                    .flatten()
                    .and_then(|data| ::qsb::Mdr0::from_data(data).ok())
                    .is_some_and(|mdr0| mdr0.index != IndexMode::Disabled);
                self.index_seen = false;
            }
            Write::Mdr0(mdr0) if mdr0.index == IndexMode::Disabled => self.index_armed = false,
            Write::Mdr1(mdr1) => self.mdr1_written(mdr1),
            Write::Eor(eor) => self.eor_configured = eor.time_stamp,
            _ => {}
        }
    }

    /// A motor command was executed at `time_stamp`: MD STATUS counts from two ticks on.
    pub(super) fn motor_commanded(&mut self, time_stamp: Option<u32>) {
        let base = time_stamp
            .or(self.stamps.last())
            .or(self.encoder.latest().map(|s| s.time_stamp))
            .unwrap_or(0);
        self.done_after = base.wrapping_add(DONE_AFTER_TICKS);
    }

    /// The VERSION answer of the start-up. Returns whether the request's plan goes on.
    fn version_read(&mut self, now: Duration, data: u32) -> bool {
        let anomalous = Version::from_data(data).map_or(true, |version| {
            self.serial.is_some_and(|s| s != version.serial)
        });
        if anomalous && self.version_doubt != Some(data) {
            // No checksum on the line: an answer that names another board (or no product)
            // may be a corrupted one. Ask again; the same answer twice counts.
            self.version_doubt = Some(data);
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            return false;
        }
        self.version_doubt = None;
        let Ok(version) = Version::from_data(data) else {
            // Not a product type of the command list: not a QSB we know.
            self.restart_later(now);
            self.status.fault = Some(DeviceFault::Protocol);
            return false;
        };
        if let Some(serial) = self.serial.filter(|serial| *serial != version.serial) {
            // Another board on this port: whatever the old one was told is lost.
            self.record_version(version);
            self.board_reset(Verdict::new(
                DeviceFault::Reset,
                now,
                format_args!(
                    "VERSION {data:08X} at {} names serial {:05X} twice, the board was \
                     {serial:05X}: another board on this port",
                    Seconds(now),
                    version.serial,
                ),
            ));
            return false;
        }
        self.record_version(version);
        true
    }

    /// The liveness probe's answer: TIME STAMP now. Below the newest stamp seen before the
    /// probe was sent, the counter restarted (a reset); else the board is there, and a
    /// stream that stayed quiet over two probes is asked for again. Returns whether the
    /// request's plan goes on.
    fn probe_answered(&mut self, now: Duration, flight: InFlight, data: u32) -> bool {
        if let Some(floor) = flight.floor.filter(|floor| before(data, *floor)) {
            self.board_reset(Verdict::new(
                DeviceFault::Reset,
                now,
                format_args!(
                    "`{}` written at {} read TIME STAMP {data:08X} at {}, below {floor:08X} \
                     seen before it was sent: the counter restarted (\"cleared on a \
                     power-cycle\")",
                    Line(flight.request),
                    Seconds(flight.written),
                    Seconds(now),
                ),
            ));
            return false;
        }
        if self.samples_since_probe {
            self.quiet_probes = 0;
        } else {
            // Alive and not restarted, but its stream is quiet: held up on the host (the
            // lines come), starved by commands (they come when the commands slow), or
            // stopped without a reset (nobody else writes this port; asked for again).
            self.quiet_probes = self.quiet_probes.saturating_add(1);
            if self.quiet_probes >= QUIET_PROBES {
                self.quiet_probes = 0;
                self.restream();
            }
        }
        true
    }

    /// The board refused a request (`e`: data out of range; `x`: not supported).
    fn refused(&mut self, now: Duration, flight: InFlight) {
        self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        self.status.fault = Some(DeviceFault::BoardError);
        match flight.origin {
            Origin::Setup => {
                // A board that refuses its configuration is not usable as configured;
                // try again later rather than run half configured.
                self.restart_later(now);
                self.status.fault = Some(DeviceFault::BoardError);
            }
            Origin::Preset if self.preset.generation() == flight.generation => {
                self.preset.clear();
            }
            Origin::Goal if self.goal.generation() == flight.generation => self.goal.clear(),
            Origin::Io => {
                if let Request::Write(write) = flight.request {
                    self.io.refused = Some(write.data() as u8);
                }
            }
            Origin::Preset | Origin::Goal | Origin::Probe | Origin::Event => {}
        }
    }

    /// Everything received: each decoded line, the decoder's bad frames, then the plans
    /// move on.
    pub(super) fn receive(&mut self, now: Duration, mut bytes: &[u8]) {
        if !self.link_up {
            return;
        }
        while !bytes.is_empty() {
            self.eor_seen(bytes);
            let (used, response) = self.decoder.decode(bytes);
            bytes = bytes.get(used..).unwrap_or_default();
            if let Some(response) = response {
                self.on_response(now, response);
            }
        }
        let bad = self.decoder.bad_frames();
        let new_bad = bad.saturating_sub(self.decoder_bad_seen);
        self.decoder_bad_seen = bad;
        if new_bad > 0
            && let Some(flight) = self.in_flight.as_mut()
        {
            // It may have been the answer: once due, it is lost rather than late.
            flight.garbled = true;
        }
        self.status.bad_replies = self
            .status
            .bad_replies
            .saturating_add(u32::try_from(new_bad).unwrap_or(u32::MAX));
        self.settle(now);
    }

    /// Channel state of channel 0.
    pub(super) fn channel_state(&self) -> ChannelState {
        // A move paused by COMMAND 6 waits for its resume: it moves only while the drive
        // still decelerates.
        let motion_pending = !self.goal.is_empty()
            && self.goal.front() != Some(Step::Paused)
            && matches!(
                self.goal_kind,
                Some(
                    GoalKind::Position
                        | GoalKind::RampPosition
                        | GoalKind::Velocity
                        | GoalKind::Home
                )
            );
        let velocity = self.encoder.velocity();
        ChannelState {
            position: f64::from(self.position),
            velocity,
            raw_counts: i64::from(self.position),
            refreshed_at: self.last_sample_at,
            moving: motion_pending || self.drive_moving() || velocity != 0.0,
            homed: self.homed,
            at_limit: false,
            arrived: self.arrived,
            fault: self
                .status
                .fault
                .or(self.home_failed.then_some(DeviceFault::HomeFailed)),
        }
    }
}
