//! Sending commands and waiting for their replies.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{CommandKind, CommandReply, CommandRequest};

use crate::{Client, ClientError};

/// Longest single sleep while waiting for a reply. The server answers in the tick and then
/// notifies the tick event, which wakes us earlier; this only bounds a missed wake-up.
const REPLY_POLL_CAP: Duration = Duration::from_millis(2);

/// A command the server accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Accepted {
    /// The sequence number the client gave the request.
    pub sequence: u64,
    /// The tick in which the command took effect.
    pub tick: u64,
}

impl<S: Service> Client<S> {
    /// Sends one request and returns the server's reply as it is (accepted or not).
    /// `axis` is an axis index or [`CommandRequest::ALL_AXES`]; `values` as tabled on
    /// [`CommandKind`].
    pub fn send(
        &self,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, ClientError> {
        let sequence = self.sequence.get().wrapping_add(1);
        self.sequence.set(sequence);
        let request = CommandRequest::new(self.id, sequence, axis, kind).with_values(values);
        let pending = self
            .commands
            .send_copy(request)
            .map_err(|error| ClientError::ipc("send a command", error))?;
        if pending.number_of_server_connections() == 0 {
            return Err(ClientError::NoServer { kind: kind.name() });
        }
        let started = Instant::now();
        let deadline = started + self.reply_timeout;
        loop {
            let response = pending
                .receive()
                .map_err(|error| ClientError::ipc("receive a command reply", error))?;
            if let Some(response) = response {
                let reply = *response.payload();
                if reply.sequence == sequence {
                    return Ok(reply);
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
            let nap = (deadline - now).min(REPLY_POLL_CAP);
            match self.tick.timed_wait(|_| {}, nap) {
                Ok(_) | Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => {}
                Err(error) => return Err(ClientError::ipc("wait for a command reply", error)),
            }
        }
    }

    /// Sends one request; `Ok` when accepted, [`ClientError::Refused`] with the server's
    /// typed [`Reason`](motion_ipc::Reason) otherwise.
    pub fn command(
        &self,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<Accepted, ClientError> {
        let reply = self.send(axis, kind, values)?;
        match reply.result() {
            Ok(()) => {
                self.note_goal(axis, reply.tick_applied);
                Ok(Accepted {
                    sequence: reply.sequence,
                    tick: reply.tick_applied,
                })
            }
            Err(reason) => Err(ClientError::refused(
                reply.kind,
                self.axis_label(axis),
                reason,
                reply.tick_applied,
            )),
        }
    }

    fn note_goal(&self, axis: u32, tick: u64) {
        let mut ticks = self.goal_ticks.borrow_mut();
        if axis == CommandRequest::ALL_AXES {
            ticks.iter_mut().for_each(|slot| *slot = tick);
        } else if let Some(slot) = ticks.get_mut(axis as usize) {
            *slot = tick;
        }
    }

    /// Emergency stop: every axis stops and holds; latched until [`Client::reset`].
    pub fn estop(&self) -> Result<Accepted, ClientError> {
        self.command(CommandRequest::ALL_AXES, CommandKind::EStop, [0.0; 3])
    }

    /// Clears a latched e-stop and faults; targets become the current positions.
    pub fn reset(&self) -> Result<Accepted, ClientError> {
        self.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3])
    }

    /// Stops every axis (decelerate and hold).
    pub fn stop_all(&self) -> Result<Accepted, ClientError> {
        self.command(CommandRequest::ALL_AXES, CommandKind::Stop, [0.0; 3])
    }
}
