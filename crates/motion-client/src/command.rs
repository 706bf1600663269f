//! Sending commands and waiting for their replies.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::prelude::PayloadHeader as _;
use iceoryx2::service::Service;
use motion_ipc::{
    AxisFlags, CommandKind, CommandReply, CommandRequest, FaultCode, FrameFlags, Reason, Target,
    read_text,
};

use crate::session::Seen;
use crate::{Axis, Client, ClientError};

/// Longest single sleep while waiting for a reply. The server answers in the tick and then
/// notifies the tick event, which wakes a client with a frame subscription earlier; this
/// only bounds a missed wake-up.
const REPLY_POLL_CAP: Duration = Duration::from_millis(2);
/// Polling step of a client without a frame subscription (no tick event to sleep on).
const REPLY_POLL_NO_TICK: Duration = Duration::from_micros(200);

/// A command the server accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The sequence number the client gave the request.
    pub sequence: u64,
    /// The tick in which the command took effect.
    pub tick: u64,
}

/// Kinds that are sent whatever happened to the server: they only ever make a machine
/// safer (and a restarted server starts every axis stopped anyway).
pub(crate) const fn always_sent(kind: CommandKind) -> bool {
    matches!(
        kind,
        CommandKind::Stop | CommandKind::EStop | CommandKind::Off
    )
}

/// The outcome of one request on the wire.
enum Exchange {
    Reply(CommandReply, u128),
    NoServer,
}

impl<S: Service> Client<S> {
    fn next_sequence(&self) -> u64 {
        let sequence = self.sequence.get().wrapping_add(1);
        self.sequence.set(sequence);
        sequence
    }

    /// Sends `request` once and waits for its reply.
    fn exchange(
        &self,
        request: CommandRequest,
        kind: CommandKind,
    ) -> Result<Exchange, ClientError> {
        #[cfg(feature = "zenoh")]
        if let Some(link) = &self.remote {
            let (reply, node) = link.command(&request, self.reply_timeout)?;
            return Ok(Exchange::Reply(reply, node));
        }
        let ports = self.command_ports()?;
        let pending = ports
            .port
            .send_copy(request)
            .map_err(|error| ClientError::ipc("send a command", error))?;
        if pending.number_of_server_connections() == 0 {
            return Ok(Exchange::NoServer);
        }
        let deadline = Instant::now() + self.reply_timeout;
        loop {
            let response = pending
                .receive()
                .map_err(|error| ClientError::ipc("receive a command reply", error))?;
            if let Some(response) = response {
                let reply = *response.payload();
                if reply.sequence == request.sequence {
                    return Ok(Exchange::Reply(reply, response.header().node_id().value()));
                }
                continue;
            }
            let now = Instant::now();
            if now >= deadline {
                return Err(ClientError::NoReply {
                    kind: kind.name(),
                    waited: self.reply_timeout,
                });
            }
            // Not interruptible: a stop sent after Ctrl-C must still get its answer.
            let nap = deadline - now;
            let frames = self.frame_ports_if_open();
            match frames.as_ref().and_then(|frames| frames.tick.as_ref()) {
                Some(tick) => match tick.timed_wait(|_| {}, nap.min(REPLY_POLL_CAP)) {
                    Ok(_) | Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => {}
                    Err(error) => {
                        return Err(ClientError::ipc("wait for a command reply", error));
                    }
                },
                _ => std::thread::sleep(nap.min(REPLY_POLL_NO_TICK)),
            }
        }
    }

    /// Sends `request` and returns the server's reply, reopening the command port once if
    /// the command service was recreated under it.
    pub(crate) fn send_request(
        &self,
        request: CommandRequest,
    ) -> Result<CommandReply, ClientError> {
        let kind = request.kind().unwrap_or(CommandKind::Stop);
        let mut exchange = self.exchange(request, kind)?;
        if matches!(exchange, Exchange::NoServer) && self.reopen_commands_if_recreated()? {
            exchange = self.exchange(request, kind)?;
        }
        match exchange {
            Exchange::NoServer => Err(ClientError::NoServer { kind: kind.name() }),
            Exchange::Reply(reply, node) => {
                if self.session.observe_reply(node) == Seen::Restarted {
                    self.on_restart();
                }
                Ok(reply)
            }
        }
    }

    /// Sends one request about axis `axis` (or [`CommandRequest::ALL_AXES`]) and returns the
    /// server's reply as it is (accepted or not); `values` as tabled on [`CommandKind`].
    /// Unlike [`Client::command`], this sends even after an unacknowledged server restart.
    pub fn send(
        &self,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, ClientError> {
        let request =
            CommandRequest::new(self.id, self.next_sequence(), axis, kind).with_values(values);
        self.send_request(request)
    }

    /// Sends one request about axis `axis`; `Ok` when accepted, [`ClientError::Refused`]
    /// with the server's typed [`Reason`] (and, where the client can say more, the words of
    /// the case: the device that is starting, the fault sentence) otherwise.
    ///
    /// After a server restart that was not acknowledged
    /// ([`Client::acknowledge_restart`]), only stop, e-stop and off are sent; anything else
    /// fails with [`ClientError::ServerRestarted`]. A goal that reached a restarted server
    /// before the client could know (its reply came from a new server) is stopped at once
    /// and reported the same way.
    pub fn command(
        &self,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<Accepted, ClientError> {
        self.command_to(Target::Axis, axis, kind, values)
    }

    pub(crate) fn command_to(
        &self,
        target: Target,
        index: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<Accepted, ClientError> {
        // A new server's description usually arrives before it takes commands.
        self.refresh_info()?;
        if !always_sent(kind)
            && let Some(restart) = self.session.unacknowledged()
        {
            return Err(ClientError::ServerRestarted(restart));
        }
        let epoch = self.session.epoch();
        let mut request =
            CommandRequest::new(self.id, self.next_sequence(), index, kind).with_values(values);
        request.target = target as u32;
        let reply = self.send_request(request)?;
        if self.session.epoch() != epoch && !always_sent(kind) {
            let one = (target == Target::Axis && index != CommandRequest::ALL_AXES)
                || target == Target::Group;
            if reply.result().is_ok() && one {
                // Sent to a new server before we knew: take the goal back.
                let mut stop =
                    CommandRequest::new(self.id, self.next_sequence(), index, CommandKind::Stop);
                stop.target = target as u32;
                let _ = self.send_request(stop);
            }
            if let Some(restart) = self.session.unacknowledged() {
                return Err(ClientError::ServerRestarted(restart));
            }
        }
        match reply.result() {
            Ok(()) => {
                if target == Target::Axis {
                    self.note_goal(index, reply.tick_applied);
                }
                Ok(Accepted {
                    sequence: reply.sequence,
                    tick: reply.tick_applied,
                })
            }
            Err(reason) if target == Target::Group => Err(self.group_refusal(&reply, reason)),
            Err(reason) => Err(ClientError::refused(
                reply.kind,
                self.target_label(target, index),
                reason,
                reply.tick_applied,
                self.refusal_detail(target, index, reason, &reply),
            )),
        }
    }

    fn note_goal(&self, axis: u32, tick: u64) {
        let epoch = self.session.epoch();
        let mut ticks = self.goal_ticks.borrow_mut();
        if axis == CommandRequest::ALL_AXES {
            ticks.iter_mut().for_each(|slot| *slot = (tick, epoch));
        } else if let Some(slot) = ticks.get_mut(axis as usize) {
            *slot = (tick, epoch);
        }
    }

    /// The refusal in the words of this case, where the reason code alone says too little.
    fn refusal_detail(
        &self,
        target: Target,
        index: u32,
        reason: Reason,
        reply: &CommandReply,
    ) -> Option<String> {
        let device = match target {
            Target::Axis if index != CommandRequest::ALL_AXES => {
                Some(self.axis_info(index as usize).device_index)
            }
            Target::Signal => Some(self.signal_info(index as usize).device_index),
            Target::Device => u16::try_from(index).ok(),
            Target::Axis | Target::Group => None,
        };
        let device = || device.map(|d| self.device_name(usize::from(d)));
        match reason {
            Reason::DeviceStarting => device().map(|name| {
                format!(
                    "device `{name}` is starting: waiting for the board's first answer (and its \
                     start-up stop); `motionctl wait-ready` waits for it"
                )
            }),
            Reason::DeviceOffline => device()
                .map(|name| format!("device `{name}` is offline: its board is not answering")),
            Reason::AxisFaulted if target == Target::Axis => self.fault_text(index),
            Reason::GroupBusy | Reason::ClaimedByOther if target == Target::Device => {
                self.neighbour_in_use(index, reason, reply)
            }
            _ => None,
        }
    }

    /// A commission refused for the sake of another device on the link (the engine's
    /// `commission` module, rule 6: a line-rate change while a neighbour is in use; the
    /// reply's `value` names that device, `at_axis` its axis, `holder` the claimant), in
    /// words; `None` when the device at fault is the one commissioned.
    fn neighbour_in_use(&self, index: u32, reason: Reason, reply: &CommandReply) -> Option<String> {
        let at_fault = reply.value;
        if !(at_fault.fract() == 0.0 && at_fault >= 0.0 && at_fault != f64::from(index)) {
            return None;
        }
        let device = at_fault as usize;
        let info = self.info.current()?;
        let link = info
            .devices()
            .get(device)
            .map(|d| read_text(&d.link).to_owned())?;
        let name = self.device_name(device);
        let what = if reply.at_axis == u32::MAX {
            "one of its signals".to_owned()
        } else {
            format!(
                "its axis `{}`",
                self.axis_info(reply.at_axis as usize).name()
            )
        };
        let state = match reason {
            Reason::GroupBusy => {
                format!("{what} moves or has a goal (a move not done, a jog, a held move)")
            }
            _ => format!(
                "client {:#x} holds a claim on {what}",
                reply.holder.as_u128()
            ),
        };
        Some(format!(
            "device `{name}` shares link `{link}` and {state}: a new line rate would leave it \
             unreachable at the old one; commission once nothing on the link is in use"
        ))
    }

    /// The fault sentence of axis `index` from the newest frame, if it is faulted and a
    /// frame can be had.
    pub(crate) fn fault_text(&self, index: u32) -> Option<String> {
        let frame = self.newest_frame().ok()?;
        let state = frame.axes().get(index as usize)?;
        if !state.flags().contains(AxisFlags::FAULT) {
            return None;
        }
        let info = self.axis_info(index as usize);
        let code = state.fault().ok().filter(|code| *code != FaultCode::None)?;
        Some(code.explain(
            info.name(),
            state.fault_value,
            state.fault_limit,
            info.unit(),
        ))
    }

    /// Emergency stop through this client's command port: every axis stops with its e-stop
    /// category; latched until [`Client::reset`]. Returns once a frame of the accepting tick
    /// or later shows the e-stop latched; [`ClientError::EstopNotSeen`] when none does
    /// within the reply timeout (the server accepted it, but this client cannot say it is
    /// in force). For an e-stop that gets through when the command service's ports are
    /// exhausted, see the free function [`estop`](crate::estop).
    pub fn estop(&self) -> Result<Accepted, ClientError> {
        let accepted = self.command(CommandRequest::ALL_AXES, CommandKind::EStop, [0.0; 3])?;
        let started = Instant::now();
        let deadline = started + self.reply_timeout;
        let mut newest = None;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.next_frame(left) {
                Ok(frame) => {
                    newest = Some(frame.tick);
                    if frame.tick >= accepted.tick
                        && frame.flags().contains(FrameFlags::ESTOP_LATCHED)
                    {
                        return Ok(accepted);
                    }
                }
                Err(ClientError::NoFrame(_)) => {}
                Err(error) => return Err(error),
            }
            if Instant::now() >= deadline {
                return Err(ClientError::EstopNotSeen {
                    tick: accepted.tick,
                    waited: started.elapsed(),
                    newest,
                });
            }
        }
    }

    /// Clears a latched e-stop, deadman expiries and faults whose cause is gone; axes without
    /// a running goal hold where they are. Claims (this client's and others') stay.
    pub fn reset(&self) -> Result<Accepted, ClientError> {
        self.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3])
    }

    /// Stops every axis (decelerate and hold).
    pub fn stop_all(&self) -> Result<Accepted, ClientError> {
        self.command(CommandRequest::ALL_AXES, CommandKind::Stop, [0.0; 3])
    }

    /// De-energises every axis, one `Off` per axis so that each refusal (a board that
    /// cannot de-energise, a claim of another client) is reported for its axis.
    pub fn off_all(&self) -> Vec<(Axis<'_, S>, Result<Accepted, ClientError>)> {
        self.axes()
            .into_iter()
            .map(|axis| {
                let result = axis.off();
                (axis, result)
            })
            .collect()
    }
}
