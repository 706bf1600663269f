//! Whether the board still answers, and the verdicts that drop its goals (module docs,
//! "Wire, liveness and resets"; docs/ARCHITECTURE.md "What evidence each board verdict
//! needs").
//!
//! The board takes one command at a time ("At the conclusion of the command response,
//! the QSB is ready to accept another command", QSB Command List 1.28, Command
//! Acknowledgement Format), and everything it sends — answers and streamed lines — leaves
//! its one UART in the order it was made. So a request's answer is:
//! - **awaited** while it may still come: until its deadline (the request and the answer on
//!   the wire, the stream lines that may be queued ahead of it, the processing time, the
//!   host latency), and after it for as long as the link stays silent — a host or a
//!   board's process without CPU holds every byte back, then hands them over at once, in
//!   order. Nothing else is sent meanwhile.
//! - **lost** once it is due and the board was heard past it: lines kept arriving for a
//!   whole reply window after the deadline (what the board made after the answer came, so
//!   the answer is not coming), or a line that may have been it could not be decoded.
//!   The request is counted in `timeouts` and may be sent again; [`MAX_ATTEMPTS`] lost in a
//!   row are a `not-answering` verdict.
//! - **not coming**: the board owes it and said nothing at all for `silence`
//!   ([`QsbDriverConfig::silence`](super::QsbDriverConfig::silence), the `silence_ms` key):
//!   a `not-answering` verdict.
//!
//! A response ends with its EOR ("Command Response[1] Register[2] Data[8] <Time Stamp[8]>
//! '!' <EOR>"), after the `!` the decoder completes the line at: the next command waits
//! until the EOR's last byte (LF, in the driver's EOR 5 and the factory 0x0B alike) or the
//! first byte of another line arrived, so that it never reaches the board while the
//! response is still leaving it (behind USB the `!` and the LF may come a 1 ms frame
//! apart). A board whose EOR has no LF is waited for a reply window at most.
//!
//! A line that answers a request declared lost, or one older than the request in flight
//! (its time stamp is below the newest the driver had seen when it sent the request), is
//! late: counted ([`QsbDriver::late_answers`]) and never taken for the answer of the request
//! in flight.

use core::fmt;
use core::time::Duration;

use ::qsb::{MAX_COMMAND_LEN, QsbCommand, Request, Response, ResponseType, Write};

use super::wire::{InFlight, Origin};
use super::{MAX_ATTEMPTS, QsbDriver, RESTART_DELAY};
use motion_drivers::{DeviceFault, Seconds, Verdict};

/// A request as its command line, without the end of command (`R0D`, `W121F0`).
pub(super) struct Line(pub(super) Request);

impl fmt::Display for Line {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut buf = [0u8; MAX_COMMAND_LEN];
        let len = self.0.encode(&mut buf).unwrap_or(0);
        let text = buf.get(..len).unwrap_or_default();
        let text = text.strip_suffix(b"\r\n").unwrap_or(text);
        f.write_str(core::str::from_utf8(text).unwrap_or("?"))
    }
}

/// A response line as the board sent it (type letter and register: `s0E`, `w16`).
pub(super) struct Answer<'a>(pub(super) &'a Response);

impl fmt::Display for Answer<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let letter = char::from(self.0.ty.letter());
        write!(f, "{letter}{:02X}", self.0.register)
    }
}

/// Whether `stamp` is before `floor` on the 32-bit time stamp's circle.
pub(super) fn before(stamp: u32, floor: u32) -> bool {
    floor.wrapping_sub(stamp).wrapping_sub(1) < u32::MAX / 2
}

/// Whether `response` answers `request`: same register, and the matching lower-case type
/// (a write echoes its data), or an `e`/`x` refusal.
pub(super) fn answers(request: Request, response: &Response) -> bool {
    if response.register != request.register().number() {
        return false;
    }
    match (request, response.ty) {
        (_, ResponseType::Error | ResponseType::Unsupported) => true,
        (Request::Read(_), ResponseType::Read) | (Request::Stream(_), ResponseType::Stream) => true,
        (Request::Write(write), ResponseType::Write) => response.data == write.data(),
        _ => false,
    }
}

impl QsbDriver {
    /// Lines that answered a request declared lost, or an earlier request than the one in
    /// flight (module docs): recognised, counted, never paired.
    pub fn late_answers_seen(&self) -> u64 {
        self.late_answers
    }

    /// A decoded line arrived at `now` (whatever it says): the board talks.
    pub(super) fn heard(&mut self, now: Duration) {
        self.heard_at = Some(now);
        if let Some(flight) = self.in_flight.as_mut()
            && now >= flight.deadline
            && flight.heard_after_deadline.is_none()
        {
            flight.heard_after_deadline = Some(now);
        }
    }

    /// The request in flight whose answer `response` is, if it is: same type and register
    /// (and data, for a write), and not older than the request (its time stamp).
    pub(super) fn answered(&self, response: &Response) -> Option<InFlight> {
        self.in_flight.filter(|flight| {
            answers(flight.request, response)
                && !matches!(
                    (response.time_stamp, flight.floor),
                    (Some(stamp), Some(floor)) if before(stamp, floor)
                )
        })
    }

    /// A line that answers nothing in flight (and is no streamed line): late if it answers
    /// the request declared lost last, else a bad reply.
    pub(super) fn unanswered_line(&mut self, response: &Response) {
        let late = self.late.is_some_and(|request| answers(request, response))
            || self
                .in_flight
                .is_some_and(|flight| answers(flight.request, response));
        if late {
            self.late_answers = self.late_answers.saturating_add(1);
        } else {
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        }
    }

    /// The bytes after an answer's `!`: its EOR ended at the first that is not CR or a
    /// space (the LF, or another line).
    pub(super) fn eor_seen(&mut self, bytes: &[u8]) {
        if self.eor_until.is_some() && bytes.iter().any(|b| !matches!(b, b'\r' | b' ')) {
            self.eor_until = None;
        }
    }

    /// When the request in flight is next judged: its deadline, then the end of the
    /// reply window the board has been heard through after it, or of the silence.
    pub(super) fn in_flight_look_by(&self) -> Option<Duration> {
        let flight = self.in_flight?;
        if !flight.overdue {
            return Some(flight.deadline);
        }
        let silence_end = self
            .silent_since(&flight)
            .saturating_add(self.config.silence);
        let flow_end = flight
            .heard_after_deadline
            .map(|first| first.saturating_add(self.config.reply_timeout()));
        Some(flow_end.map_or(silence_end, |flow| flow.min(silence_end)))
    }

    /// Since when the board has said nothing that the request in flight could wait for:
    /// its last line, or the request's write if that is later.
    fn silent_since(&self, flight: &InFlight) -> Duration {
        self.heard_at
            .map_or(flight.written, |heard| heard.max(flight.written))
    }

    /// Judges the request in flight up to the link's horizon (module docs).
    pub(super) fn judge_in_flight(&mut self, now: Duration) {
        let judged = self.io_stamps.judged(now);
        let Some(flight) = self.in_flight.as_mut() else {
            return;
        };
        if judged < flight.deadline {
            return;
        }
        flight.overdue = true;
        let flight = *flight;
        let silent_since = self.silent_since(&flight);
        if judged.saturating_sub(silent_since) >= self.config.silence {
            let silent = judged.saturating_sub(silent_since);
            let verdict = Verdict::new(
                DeviceFault::NotResponding,
                now,
                format_args!(
                    "`{}` written at {}, due by {}; nothing heard since {}, the link heard \
                     until {}: {} ms of silence (silence_ms {})",
                    Line(flight.request),
                    Seconds(flight.written),
                    Seconds(flight.deadline),
                    Seconds(silent_since),
                    Seconds(judged),
                    silent.as_millis(),
                    self.config.silence.as_millis(),
                ),
            );
            self.status.timeouts = self.status.timeouts.saturating_add(1);
            self.not_answering(now, verdict);
            return;
        }
        let window = self.config.reply_timeout();
        let heard_through = flight
            .heard_after_deadline
            .zip(self.heard_at)
            .is_some_and(|(first, last)| last >= first.saturating_add(window));
        if heard_through || flight.garbled {
            self.answer_lost(now, flight);
        }
    }

    /// The answer of `flight` is not coming (module docs): counted, and the request may go
    /// again — except COMMAND 8 (a move must never run twice).
    fn answer_lost(&mut self, now: Duration, flight: InFlight) {
        self.in_flight = None;
        self.late = Some(flight.request);
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.attempts = self.attempts.saturating_add(1);
        if self.attempts >= MAX_ATTEMPTS {
            let why = if flight.garbled {
                "a line where its answer was due could not be decoded"
            } else {
                "the board kept streaming past it"
            };
            let verdict = Verdict::new(
                DeviceFault::NotResponding,
                now,
                format_args!(
                    "{MAX_ATTEMPTS} requests in a row unanswered; the last, `{}`, written at \
                     {}, due by {}: {why} (last line at {})",
                    Line(flight.request),
                    Seconds(flight.written),
                    Seconds(flight.deadline),
                    Seconds(self.heard_at.unwrap_or(flight.written)),
                ),
            );
            self.not_answering(now, verdict);
            return;
        }
        match (flight.origin, flight.request) {
            (Origin::Goal, Request::Write(Write::Command(QsbCommand::MotorMove))) => {
                // The answer may be what was lost, not the command: a move must never run
                // twice. Carry on; the encoder tells what happened and the plan corrects.
                self.motor_commanded(None);
                self.advance(flight);
            }
            (Origin::Probe, _) => self.probe_due = true,
            _ => {}
        }
    }

    /// The board does not answer (`verdict` says why): everything in progress is void; its
    /// start-up is tried again after [`RESTART_DELAY`]. A board already declared not
    /// answering (a start-up tried again in vain) gets no new verdict.
    pub(super) fn not_answering(&mut self, now: Duration, verdict: Verdict) {
        if self.status.fault != Some(DeviceFault::NotResponding) {
            self.status.declare(verdict);
        }
        self.restart_later(now);
        self.status.fault = Some(DeviceFault::NotResponding);
    }

    /// Everything in progress is void; the start-up is tried again after
    /// [`RESTART_DELAY`] (the board did not answer, or refused its configuration).
    pub(super) fn restart_later(&mut self, now: Duration) {
        self.begin_startup();
        self.setup.clear();
        self.restart_at = Some(now.saturating_add(RESTART_DELAY));
    }

    /// The board rebooted, or another board answers (`verdict` says which line showed it):
    /// goals are lost, the start-up runs again.
    pub(super) fn board_reset(&mut self, verdict: Verdict) {
        self.status.declare(verdict);
        self.status.resets = self.status.resets.saturating_add(1);
        self.status.fault = Some(DeviceFault::Reset);
        self.homed = false;
        self.stamps.clear();
        self.begin_startup();
    }
}
