//! The `setpoints` service: setpoints clients stream to their groups (`Setpoint`, 288
//! bytes), handed to the engine each tick with the node that sent each — from the
//! service's dynamic config, written by iceoryx2 when the port connected, never from the
//! payload — and the instant the tick took each from the service (CLOCK_MONOTONIC, the
//! clock of the frame's `publish_ns`: the frame's `GroupState::last_received_ns`). Nothing
//! is allocated after start-up.
//!
//! Any node may publish on the service, so each publishing node gets a budget per tick
//! (issue 40): at most [`SETPOINTS_PER_NODE`] of its setpoints reach the engine (and the
//! black box) in one tick, the rest are taken from the service and dropped unread, counted
//! in `over_budget`. A claimant sends one setpoint a tick, a few after a stall; a flood from
//! another process costs the tick only the receive of what its queue holds
//! ([`SETPOINTS_BUFFER`] per publisher), never the engine's or the journal's work for it.

use iceoryx2::prelude::*;
use motion_config::boards::AnyDriver;
use motion_engine::Engine;
use motion_ipc::{ClientId, Setpoint};

use crate::Ipc;
use crate::error::ServiceError;
use crate::inbox::Inbox;
use crate::rt::monotonic_now;

/// Setpoints a publisher may have queued before the tick takes them: enough for a client
/// that streams for several ticks ahead, and for one tick the server was late.
pub const SETPOINTS_BUFFER: usize = 16;

/// Setpoints taken from the service in one tick at most (the rest wait for the next).
pub const SETPOINTS_PER_TICK: usize = 256;

/// Setpoints of one node handed to the engine in one tick at most: a client that streams
/// one a tick catching up after a stall of a few ticks.
pub const SETPOINTS_PER_NODE: u32 = 8;

/// The server's end of `setpoints`.
#[derive(Debug)]
pub struct SetpointInbox {
    /// The service, and each sample's node.
    pub inbox: Inbox<Setpoint>,
    /// This tick's setpoints per node.
    spent: Vec<(ClientId, u32)>,
    /// Samples beyond their node's budget of the tick (dropped unread).
    pub over_budget: u64,
}

/// Creates (or opens) `name` with room for `max_clients` publishers and the server.
pub fn create(
    node: &Node<Ipc>,
    name: &str,
    max_clients: usize,
) -> Result<SetpointInbox, ServiceError> {
    Ok(SetpointInbox {
        inbox: Inbox::create(node, name, max_clients, SETPOINTS_BUFFER, 2)?,
        spent: Vec::with_capacity(max_clients + 2),
        over_budget: 0,
    })
}

impl SetpointInbox {
    /// Hands every setpoint that arrived since the last tick to `engine`, each with its
    /// sender's node and the instant it was taken from the service.
    pub fn deliver(
        &mut self,
        engine: &mut Engine<AnyDriver>,
        journal: &mut motion_blackbox::Journal,
    ) {
        self.spent.clear();
        for _ in 0..SETPOINTS_PER_TICK {
            let Some((node, sample)) = self.inbox.take() else {
                return;
            };
            let received_ns = crate::io::duration_ns(monotonic_now());
            if !self.spend(node) {
                self.over_budget += 1;
                continue;
            }
            journal.setpoint(node, received_ns, sample.payload());
            engine.handle_setpoint_at(node, sample.payload(), received_ns);
        }
    }

    /// Counts one setpoint of `node` in this tick; `false` when its budget is spent (or
    /// more nodes published this tick than there are slots: the extra ones wait).
    fn spend(&mut self, node: ClientId) -> bool {
        if let Some((_, spent)) = self.spent.iter_mut().find(|(n, _)| *n == node) {
            *spent += 1;
            return *spent <= SETPOINTS_PER_NODE;
        }
        if self.spent.len() == self.spent.capacity() {
            return false;
        }
        self.spent.push((node, 1));
        true
    }
}
