//! The host side of the half-duplex line: one request in flight, the pack's switch-over
//! time on both sides of its answer (manual 6.1), finding the answer in the byte stream,
//! and the polling plan (which request goes next, module docs "Polling plan").
//!
//! Timing of one query at 19200 baud with a 2 ms switch-over: the request takes 4.7 ms on
//! the wire; the pack answers after the switch-over delay; the answer takes 4.7 ms; the pack
//! then keeps driving the line for the switch-over time again, and bytes sent to it then
//! are lost. So after an answer the whole bus stays quiet for the switch-over time (the
//! driver reports [`awaiting_reply`](motion_drivers::Driver::awaiting_reply) until then, which holds
//! every other driver on the bus too).

use core::time::Duration;

use tmcpack::convert::units;
use tmcpack::{Command, MotorMask, Request, RequestFrame};

use super::channel::Channel;
use super::{PACK_PROCESSING, Phase, TmcpackDriver};
use motion_drivers::{Priority, Transmit};

/// What a query waits for.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Expect {
    pub command: Command,
    /// The motor a $20 or $21 answer must name, the channel a $30 answer must name.
    pub motor: Option<u8>,
    /// Which query this is.
    pub purpose: Purpose,
}

/// Why a query was sent.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Purpose {
    /// $43 of the start-up sequence.
    Startup,
    /// $43 checking the reset flag while online.
    ResetCheck,
    /// $20 of the polling plan.
    Poll,
    /// $28 of the start-up survey: which motors are active.
    Survey,
    /// $21 while stopping motors found active at start-up.
    Quiesce,
    /// $30 of the polling plan (inputs).
    Io,
    /// $45: the power-down steps of the start-up, or the state check while online.
    PowerDown,
    /// `$21` or `$30` in place of a query whose answer could be taken for a late one
    /// (module `late`): its answer only shows that the pack answers.
    Probe,
}

/// Who may use the line.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Wire {
    /// Free.
    Idle,
    /// A request without an answer is still on the wire (`number`: its message number,
    /// `IoStamps::sent`).
    Sending { until: Duration, number: u64 },
    /// Waiting for the answer to a query.
    Awaiting {
        expect: Expect,
        sent_at: Duration,
        deadline: Duration,
        number: u64,
    },
    /// The pack still drives the line after its answer, or the line is kept silent after
    /// a timeout so that the pack's packet timeout ($41) resynchronises it.
    Quiet { until: Duration },
}

impl Wire {
    /// When the line state changes by itself.
    pub fn deadline(&self) -> Option<Duration> {
        match *self {
            Self::Idle => None,
            Self::Sending { until, .. } | Self::Quiet { until } => Some(until),
            Self::Awaiting { deadline, .. } => Some(deadline),
        }
    }
}

/// The poll slot of the `$30` input poll, after the six motors.
const IO_SLOT: usize = 6;

/// What `pick` chose to send.
pub(super) struct Pick {
    pub(super) request: Request,
    pub(super) expect: Option<Expect>,
    pub(super) channel: Option<usize>,
}

/// What has waited too long for its poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Starved {
    /// A motor's `$20`.
    Motor(u8),
    /// A `$30` of this channel.
    Input(u8),
}

impl TmcpackDriver {
    /// The smallest spacing between the starts of two words: their wire time, and the
    /// packet timeout of every pack on the bus.
    pub(super) fn spacing(&self) -> Duration {
        if let Some(can) = &self.can {
            // A CAN frame arrives whole or not at all: no packet timeout to wait out.
            return can.frame_time;
        }
        self.word_time.max(self.pack_timeout).max(self.bus_timeout)
    }

    /// A configured motor (or input) whose data is older than half the refresh budget: its
    /// poll goes before every command but a stop, so that goals for every motor of the bus
    /// at once (the engine's start-up stops, a client's coordinated move) never make an
    /// axis or a signal stale.
    pub(super) fn starved(&self, now: Duration) -> Option<Starved> {
        let limit = self.budget / 2;
        let motor = self
            .channels
            .iter()
            .flatten()
            .filter_map(|c| c.state.refreshed_at.map(|at| (at, Starved::Motor(c.motor))));
        let input = self
            .io
            .stalest()
            .map(|(at, channel)| (at, Starved::Input(channel)));
        motor
            .chain(input)
            .filter(|(at, _)| now.saturating_sub(*at) > limit)
            .min_by_key(|(at, _)| *at)
            .map(|(_, starved)| starved)
    }

    /// What the driver would send now.
    pub(super) fn next_message(&self, now: Duration) -> Option<Priority> {
        if self.wire != Wire::Idle {
            return None;
        }
        if self.can.as_ref().is_some_and(|can| !can.may_send(now)) {
            // The pack's CAN cache has as many commands as the driver lets wait.
            return None;
        }
        if self.service.is_some() && self.phase != Phase::Down {
            // A change of the pack's settings (module `commission`) goes first.
            return Some(Priority::Setup);
        }
        match self.phase {
            Phase::Down => None,
            Phase::Identify => (now >= self.retry_at).then_some(Priority::Setup),
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) | Phase::PowerDown => {
                Some(Priority::Setup)
            }
            Phase::Online if self.channels.iter().flatten().any(Channel::urgent) => {
                Some(Priority::Stop)
            }
            Phase::Online
                if self.any_ready()
                    || self.starved(now).is_some()
                    || self.channels.iter().flatten().any(|c| c.awaits_rest(now)) =>
            {
                Some(Priority::Command)
            }
            Phase::Online => {
                let polls = self.channels.iter().any(Option::is_some) || self.io.polls();
                (polls || now >= self.reset_check_at || self.power_check_due(now))
                    .then_some(Priority::Poll)
            }
        }
    }

    /// Whether the poll of a motor awaiting rest goes next: it goes before every other poll
    /// of this pack, overdue ones included, but alternates with those, so that the
    /// back-to-back polls of a stop never leave the other motors without data (on a shared
    /// bus the other packs' commands and overdue polls take turns with it too: all are
    /// [`Priority::Command`]).
    fn rest_poll_due(&self, now: Duration) -> bool {
        self.channels.iter().flatten().any(|c| c.awaits_rest(now))
            && !(self.rest_polled && self.starved(now).is_some())
    }

    pub(super) fn query(
        &self,
        request: Request,
        command: Command,
        motor: Option<u8>,
        purpose: Purpose,
    ) -> Pick {
        Pick {
            request,
            expect: Some(Expect {
                command,
                motor,
                purpose,
            }),
            channel: None,
        }
    }

    /// Picks the request to send now; the core of `poll_transmit`.
    pub(super) fn pick(&mut self, now: Duration) -> Option<Pick> {
        let priority = self.next_message(now)?;
        let reply_to = self.reply_address;
        if let Some(pick) = self.service_pick() {
            return Some(pick);
        }
        match self.phase {
            Phase::Down => None,
            Phase::Identify => Some(self.query(
                Request::UnitInfo { reply_to },
                Command::UnitInfo,
                None,
                Purpose::Startup,
            )),
            Phase::Survey => Some(self.query(
                Request::QueryActions {
                    reply_to,
                    delay_mask: MotorMask::EMPTY,
                },
                Command::QueryActions,
                None,
                Purpose::Survey,
            )),
            Phase::Quiesce => self.pick_quiesce(now),
            Phase::PowerDown => Some(self.pick_power_down()),
            Phase::Configure(index) => {
                let request = self.resolve(self.plan.get(index)?);
                Some(Pick {
                    request,
                    expect: None,
                    channel: None,
                })
            }
            Phase::Online if priority >= Priority::Command => {
                let urgent = self.channels.iter().flatten().any(Channel::urgent);
                let rest = self.rest_poll_due(now);
                match self.starved(now) {
                    _ if rest && !urgent => self.pick_command().or_else(|| self.pick_poll(now)),
                    Some(Starved::Motor(motor)) if !urgent => Some(self.query(
                        Request::QueryPosition { motor, reply_to },
                        Command::QueryPosition,
                        Some(motor),
                        Purpose::Poll,
                    )),
                    Some(Starved::Input(channel)) if !urgent => Some(self.query(
                        Request::ReadInput { channel, reply_to },
                        Command::ReadInput,
                        Some(channel),
                        Purpose::Io,
                    )),
                    // No command ready: the poll of a stopping motor.
                    _ => self.pick_command().or_else(|| self.pick_poll(now)),
                }
            }
            Phase::Online => self.pick_poll(now),
        }
    }

    pub(super) fn pick_poll(&mut self, now: Duration) -> Option<Pick> {
        let reply_to = self.reply_address;
        let urgent = self
            .channels
            .iter()
            .flatten()
            .filter(|c| c.awaits_rest(now))
            // Several motors stopping at once (an e-stop): the one polled longest ago.
            .min_by_key(|c| c.state.refreshed_at)
            .map(|c| usize::from(c.motor));
        if urgent.is_none()
            && now >= self.reset_check_at
            && self.free_query(now, Command::UnitInfo, None)
        {
            return Some(self.query(
                Request::UnitInfo { reply_to },
                Command::UnitInfo,
                None,
                Purpose::ResetCheck,
            ));
        }
        if urgent.is_none()
            && self.free_query(now, Command::PowerDown, None)
            && let Some(pick) = self.pick_power_check(now)
        {
            return Some(pick);
        }
        let slot = urgent.or_else(|| {
            (0..=IO_SLOT)
                .map(|offset| (self.next_poll + offset) % (IO_SLOT + 1))
                .find(|&i| match i {
                    IO_SLOT => {
                        self.io.polls()
                            && self.free_query(
                                now,
                                Command::ReadInput,
                                Some(self.io.next_channel()),
                            )
                    }
                    _ => {
                        matches!(self.channels.get(i), Some(Some(_)))
                            && self.free_query(now, Command::QueryPosition, Some(i as u8))
                    }
                })
        });
        let Some(slot) = slot else {
            // Every poll's answer could be taken for a late one: a probe, whose answer
            // ends the driver's own (module `late`).
            let polls = self.channels.iter().any(Option::is_some) || self.io.polls();
            return if polls { self.probe(now) } else { None };
        };
        if urgent.is_none() {
            self.next_poll = (slot + 1) % (IO_SLOT + 1);
        }
        if slot == IO_SLOT {
            let channel = self.io.next_channel();
            return Some(self.query(
                Request::ReadInput { channel, reply_to },
                Command::ReadInput,
                Some(channel),
                Purpose::Io,
            ));
        }
        let motor = slot as u8;
        Some(self.query(
            Request::QueryPosition { motor, reply_to },
            Command::QueryPosition,
            Some(motor),
            Purpose::Poll,
        ))
    }

    /// Until when the answer to a query written at `written` can arrive (manual 6.1): the
    /// request on the wire (the write stamp is when the link took its last byte, which
    /// a UART or a USB adapter then clocks out), the pack's processing
    /// ([`PACK_PROCESSING`]), its switch-over delay ("an instruction will be transmitted
    /// only after an adjustable transmitter switchover time … has passed": the one the
    /// driver programmed, or the longer of the factory and the configured one while it does
    /// not know), the answer on the wire, and the host's latency (`host_latency_ms`). On
    /// CAN: the end of its processing behind the commands in the pack's cache, its answer's
    /// frame, and the same processing and latency as slack (6.2 "approx. 2 ms").
    pub(super) fn reply_deadline(&self, written: Duration) -> Duration {
        if let Some(can) = &self.can {
            return can.reply_deadline(written, PACK_PROCESSING + self.host_latency);
        }
        written + self.word_time * 2 + PACK_PROCESSING + self.switchover + self.host_latency
    }

    /// Whether a query of `command` for `selector` (motor or channel) may go at `now`: its
    /// answer could not be taken for a late one (module `late`).
    fn free_query(&self, now: Duration, command: Command, selector: Option<u8>) -> bool {
        self.free(
            now,
            &Expect {
                command,
                motor: selector,
                purpose: Purpose::Poll,
            },
        )
    }

    /// Writes the request `pick` chose into `buf`; the line, the start-up and the channel
    /// move on.
    pub(super) fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let pick = self.pick(now)?;
        let pick = self.avoid_late(now, pick)?;
        let request = pick.request;
        let len = match self.can.as_mut() {
            Some(can) => can.encode(now, self.address, request, buf)?,
            None => RequestFrame::new(self.address, request).encode(buf).ok()?,
        };
        self.seq += 1;
        let number = self.stamps.sent();
        let wire_end = now + self.word_time;
        if pick.channel.is_none()
            && self
                .line
                .is_some_and(|line| line.started && line.request() == request)
        {
            self.on_line_sent(self.seq);
        }
        self.on_service_sent(now, request);
        match request {
            Request::SetBaud { switchover, .. } => self.switchover = units(switchover),
            Request::PacketTimeout { timeout } => self.pack_timeout = units(timeout),
            Request::Outputs { .. } => {
                self.io.on_outputs_sent(now, request);
                if self.phase == Phase::Online {
                    self.io.outputs_pending = false;
                }
            }
            _ => {}
        }
        match (pick.expect, request) {
            (_, Request::PiTarget { .. }) => self.pi_since_poll = true,
            (Some(_), _) => self.pi_since_poll = false,
            _ => {}
        }
        match pick.expect {
            Some(expect) => {
                self.hunter.reset();
                self.wire = Wire::Awaiting {
                    expect,
                    sent_at: now,
                    deadline: self.reply_deadline(now),
                    number,
                };
            }
            None => {
                self.wire = Wire::Sending {
                    until: now + self.spacing(),
                    number,
                };
            }
        }
        match self.phase {
            Phase::Quiesce => {
                if let Some(quiesce) = self.quiesce.as_mut()
                    && pick.expect.is_none()
                {
                    quiesce.sent();
                }
            }
            Phase::Configure(index) => {
                let next = index + 1;
                if self.plan.get(next).is_some() {
                    self.phase = Phase::Configure(next);
                } else {
                    self.configured(now);
                }
            }
            _ => {}
        }
        self.rest_polled = match pick.expect {
            Some(Expect {
                purpose: Purpose::Poll,
                motor: Some(motor),
                ..
            }) => self
                .channels
                .get(usize::from(motor))
                .and_then(Option::as_ref)
                .is_some_and(|c| c.awaits_rest(now)),
            _ => false,
        };
        let mut goal_starts = 0;
        if let Some(index) = pick.channel
            && let Some(Some(channel)) = self.channels.get_mut(index)
        {
            channel.on_sent(request, self.seq, wire_end);
            channel.advance();
            if channel.goal_unsent {
                channel.goal_unsent = false;
                goal_starts = 1 << index;
            }
        }
        Some(Transmit {
            len,
            expects_reply: true,
            goal_starts,
        })
    }

    /// Message `number` went out at `at`: the line's times run from there.
    pub(super) fn on_written(&mut self, at: Duration) {
        let number = self.stamps.written();
        let spacing = self.spacing();
        let deadline = self.reply_deadline(at);
        match &mut self.wire {
            Wire::Awaiting {
                number: n,
                sent_at,
                deadline: d,
                ..
            } if *n == number => {
                *sent_at = at;
                *d = deadline;
            }
            Wire::Sending { until, number: n } if *n == number => *until = at + spacing,
            _ => {}
        }
    }
}
