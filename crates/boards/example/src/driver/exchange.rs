//! One exchange at a time: which request goes next (stops, then goals, then polls), the
//! replies matched against it, and the passing of time (poll rounds, reply timeouts,
//! identify retries).

use core::time::Duration;

use motion_drivers::{DeviceFault, Priority, Seconds, Transmit, Verdict};

use super::{
    ExampleDriver, InFlight, MISS_LIMIT, OFFLINE_RETRY_PERIOD, PROTOCOL_LIMIT, Phase, RETRY_PERIOD,
    START_ATTEMPTS,
};
use crate::codec::{CHANNELS, Motion, Reply, Request};

/// Whether `request` carries a goal (not a poll, not the identify).
pub(super) fn is_command(request: &Request) -> bool {
    !matches!(request, Request::Identify | Request::Position { .. })
}

/// Whether `reply` is of the kind `request` gets (a position reply names its channel).
fn answers(request: Request, reply: Reply) -> bool {
    match (request, reply) {
        (Request::Identify, Reply::Identity(_)) => true,
        (Request::Position { channel }, Reply::Position { channel: c, .. }) => channel == c,
        (_, Reply::Done | Reply::Error(_)) => is_command(&request),
        _ => false,
    }
}

/// A request as its line, without the `\r` (`P0?`, `M0 10 1000 10000`).
pub(super) struct Line(pub(super) Request);

impl core::fmt::Display for Line {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let mut buf = [0u8; crate::codec::MAX_LINE];
        let len = self.0.encode(&mut buf).unwrap_or(0);
        let text = buf.get(..len).unwrap_or_default();
        let text = text.strip_suffix(b"\r").unwrap_or(text);
        f.write_str(core::str::from_utf8(text).unwrap_or("?"))
    }
}

/// How urgent a request is on the bus.
fn priority(request: &Request) -> Priority {
    match request {
        Request::Stop { .. } | Request::Off { .. } => Priority::Stop,
        Request::Identify => Priority::Setup,
        Request::Position { .. } => Priority::Poll,
        Request::Move { .. } | Request::Jog { .. } | Request::SetPosition { .. } => {
            Priority::Command
        }
    }
}

impl ExampleDriver {
    /// The request that would go now, with its priority; `None` while one is in flight.
    pub(super) fn next_request(&self, now: Duration) -> Option<(Request, Priority)> {
        if !self.link_up || self.in_flight.is_some() {
            return None;
        }
        match self.phase {
            Phase::Identify { next_at, .. } => {
                (now >= next_at).then_some((Request::Identify, Priority::Setup))
            }
            Phase::Running => {
                let command = self
                    .commands
                    .iter()
                    .flatten()
                    .map(|request| (*request, priority(request)))
                    .max_by_key(|(_, priority)| *priority);
                command.or_else(|| {
                    let channel = self.poll_due.iter().position(|due| *due)?;
                    let request = Request::Position {
                        channel: channel as u8,
                    };
                    Some((request, Priority::Poll))
                })
            }
        }
    }

    /// Writes the next request into `buf`.
    pub(super) fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let (request, _) = self.next_request(now)?;
        let channel = request.channel().map(usize::from);
        match (request, channel) {
            (Request::Identify, _) => {
                if let Phase::Identify { attempts, .. } = self.phase {
                    // The next try, should this one get no answer (see `timed_out`).
                    self.phase = Phase::Identify {
                        attempts,
                        next_at: Duration::MAX,
                    };
                }
            }
            (Request::Position { .. }, Some(c)) => self.poll_due[c] = false,
            (_, Some(c)) => self.commands[c] = None,
            (_, None) => {}
        }
        // Goals were checked against the board's ranges when set; a buffer of 256 bytes
        // holds every line.
        let len = request.encode(buf).ok()?;
        let mut goal_starts = 0;
        if let Some(c) =
            channel.filter(|c| is_command(&request) && self.goal_unsent & (1 << c) != 0)
        {
            goal_starts = 1 << c;
            self.goal_unsent &= !(1 << c);
        }
        self.in_flight = Some(InFlight {
            request,
            written_at: None,
            garbled: false,
        });
        Some(Transmit {
            len,
            expects_reply: true,
            goal_starts,
        })
    }

    /// When the request in flight times out (`None`: none, or not written yet).
    pub(super) fn reply_deadline(&self) -> Option<Duration> {
        let written = self.in_flight?.written_at?;
        Some(written.saturating_add(self.config.reply_timeout()))
    }

    /// Lets time pass: the request in flight (judged up to the link's horizon) and poll
    /// rounds.
    pub(super) fn pass_time(&mut self, now: Duration) {
        let judged = self.heard.map_or(now, |heard| heard.min(now));
        if self
            .reply_deadline()
            .is_some_and(|deadline| deadline <= judged)
        {
            self.overdue(now, judged);
        }
        if self.phase == Phase::Running && self.link_up && now >= self.next_poll_at {
            for (due, polled) in self.poll_due.iter_mut().zip(self.config.polled) {
                *due |= polled;
            }
            self.next_poll_at = self
                .next_poll_at
                .saturating_add(self.config.poll_period)
                .max(now);
        }
    }

    /// The request in flight is past its reply timeout. The board answers each request
    /// once, in order, and sends nothing unasked (README "Commands"): a reply held up on
    /// the host comes later and is waited for — nothing else is sent meanwhile, one
    /// request at a time. It is lost only when a line that may have been it could not be
    /// taken; the board is not answering when it said nothing for `silence`.
    fn overdue(&mut self, now: Duration, judged: Duration) {
        let Some(in_flight) = self.in_flight else {
            return;
        };
        if in_flight.garbled {
            self.timed_out(now);
            return;
        }
        let written = in_flight.written_at.unwrap_or(now);
        let since = self.heard_at.map_or(written, |heard| heard.max(written));
        let silent = judged.saturating_sub(since);
        if silent < self.config.silence {
            return;
        }
        self.in_flight = None;
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        if self.status.fault != Some(DeviceFault::NotResponding) {
            self.status.declare(Verdict::new(
                DeviceFault::NotResponding,
                now,
                format_args!(
                    "`{}` written at {}, due by {}; nothing heard since {}, the link heard \
                     until {}: {} ms of silence (silence {} ms)",
                    Line(in_flight.request),
                    Seconds(written),
                    Seconds(written.saturating_add(self.config.reply_timeout())),
                    Seconds(since),
                    Seconds(judged),
                    silent.as_millis(),
                    self.config.silence.as_millis(),
                ),
            ));
        }
        self.raise(DeviceFault::NotResponding);
        self.restart(now.saturating_add(OFFLINE_RETRY_PERIOD), START_ATTEMPTS);
    }

    /// The reply of the request in flight is lost (a line where it was due could not be
    /// taken): counted, and sent again.
    fn timed_out(&mut self, now: Duration) {
        let Some(in_flight) = self.in_flight.take() else {
            return;
        };
        self.lost = Some(in_flight.request);
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        match self.phase {
            Phase::Identify { attempts, .. } => {
                self.phase = Phase::Identify {
                    attempts: attempts.saturating_add(1),
                    next_at: now.saturating_add(RETRY_PERIOD),
                };
            }
            Phase::Running => {
                self.misses += 1;
                if self.misses >= MISS_LIMIT {
                    if self.status.fault != Some(DeviceFault::NotResponding) {
                        self.status.declare(Verdict::new(
                            DeviceFault::NotResponding,
                            now,
                            format_args!(
                                "{MISS_LIMIT} replies in a row lost: where each was due came \
                                 a line that answers nothing in flight; the last for `{}`, \
                                 written at {}",
                                Line(in_flight.request),
                                Seconds(in_flight.written_at.unwrap_or(now)),
                            ),
                        ));
                    }
                    self.raise(DeviceFault::NotResponding);
                    self.restart(now, START_ATTEMPTS);
                    return;
                }
                // A goal's request goes again, unless a newer goal replaced it.
                if let Some(c) = in_flight.request.channel().map(usize::from)
                    && is_command(&in_flight.request)
                    && self.commands[c].is_none()
                {
                    self.commands[c] = Some(in_flight.request);
                }
            }
        }
    }

    /// Bytes from the board.
    pub(super) fn receive(&mut self, now: Duration, bytes: &[u8]) {
        for &byte in bytes {
            match self.decoder.push(byte) {
                None => {}
                Some(Ok(reply)) => {
                    self.heard_at = Some(now);
                    self.reply(now, reply);
                }
                Some(Err(_)) => {
                    self.heard_at = Some(now);
                    self.bad_reply();
                }
            }
        }
    }

    /// A line that is no reply, or no reply to what is in flight: if a request is in
    /// flight, this may have been its reply.
    fn bad_reply(&mut self) {
        if let Some(in_flight) = self.in_flight.as_mut() {
            in_flight.garbled = true;
        }
        self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        self.bad_in_row = self.bad_in_row.saturating_add(1);
        if self.bad_in_row >= PROTOCOL_LIMIT {
            self.raise(DeviceFault::Protocol);
        }
    }

    fn reply(&mut self, now: Duration, reply: Reply) {
        let Some(in_flight) = self.in_flight else {
            if self.lost.is_some_and(|lost| answers(lost, reply)) {
                // The reply of a request declared lost, after all: recognised, dropped.
                self.lost = None;
                self.late_replies = self.late_replies.saturating_add(1);
                return;
            }
            return self.bad_reply();
        };
        let request = in_flight.request;
        let channel = request.channel().map(usize::from).filter(|c| *c < CHANNELS);
        match (request, reply, channel) {
            (Request::Identify, Reply::Identity(version), _) => {
                let mut text = [0u8; 4 + crate::codec::VERSION_LEN];
                text[..4].copy_from_slice(b"AS2 ");
                let len = 4 + version.as_str().len();
                text[4..len].copy_from_slice(version.as_str().as_bytes());
                self.status
                    .set_firmware(core::str::from_utf8(&text[..len]).unwrap_or("AS2"));
                self.status.online = true;
                self.phase = Phase::Running;
                self.next_poll_at = now;
            }
            (
                Request::Position { channel: asked },
                Reply::Position {
                    channel: answered,
                    position,
                    velocity,
                    motion,
                },
                Some(c),
            ) if asked == answered => {
                let slot = &mut self.channels[c];
                let moving = motion == Motion::Moving;
                slot.state.position = f64::from(position);
                slot.state.raw_counts = i64::from(position);
                slot.state.velocity = f64::from(velocity);
                slot.state.moving = moving;
                slot.state.refreshed_at = Some(now);
                slot.state.arrived = !moving && slot.target == Some(position);
                // Fresh data: whatever kept the board faulted is over.
                self.status.fault = None;
            }
            (_, Reply::Done, Some(c)) if is_command(&request) => {
                if matches!(request, Request::SetPosition { .. }) {
                    self.channels[c].state.homed = true;
                }
            }
            (_, Reply::Error(_), Some(c)) if is_command(&request) => {
                self.channels[c].fault = Some(DeviceFault::BoardError);
            }
            _ => return self.bad_reply(),
        }
        self.in_flight = None;
        self.misses = 0;
        self.bad_in_row = 0;
        self.status.replies = self.status.replies.saturating_add(1);
    }
}
