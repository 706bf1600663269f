//! The `paths` service: paths that clients send their groups (`GroupPath`, ≈400 KB each,
//! zero-copy), held until a `Run` command of the same node takes one.
//!
//! Every tick, before the engine steps, the inbox takes what arrived and notes for each
//! sample the node of the publisher that sent it — from the service's dynamic config,
//! written by iceoryx2 when the port connected, never from the payload. The engine then
//! asks for the newest path of an id from the node that sent the `Run`
//! (`CommandPort::take_path`). Nothing is copied and nothing allocated after start-up.
//!
//! Any node may publish on the service, so the room is shared by rule (issue 40): at most
//! [`PATHS_HELD`] samples in all and [`PATHS_PER_NODE`] per node (a node's own oldest goes
//! first). A path is privileged when its sender is its group's claimant — the node whose
//! motion runs on the group or that holds the claim on every member, as the last frame
//! said (`GroupState::owner`). When the room is full, an unprivileged path goes first; a new
//! unprivileged path finds no room among privileged ones and is dropped. So no node without
//! a claim can evict a claimant's path, however fast it publishes.

use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use motion_ipc::{ClientId, GroupPath, MAX_GROUPS, MotionFrame};

use crate::Ipc;
use crate::error::ServiceError;
use crate::inbox::Inbox;

/// Paths held between their arrival and their `Run`, all nodes together.
pub const PATHS_HELD: usize = 6;

/// Paths held per publishing node (its newest).
pub const PATHS_PER_NODE: usize = 2;

/// Paths a publisher may have queued for the server before it takes them (each tick).
pub const PATHS_BUFFER: usize = 2;

type PathSample = Sample<Ipc, GroupPath, ()>;

/// The server's end of `paths` and the samples it holds.
#[derive(Debug)]
pub struct PathInbox {
    /// The service, and each sample's node.
    pub inbox: Inbox<GroupPath>,
    /// (sender's node, sample), oldest first.
    held: Vec<(ClientId, PathSample)>,
    /// The path the engine took last (alive until the next take).
    taken: Option<PathSample>,
    /// Per group, its claimant as the last frame said (`GroupState::owner`).
    claimants: [ClientId; MAX_GROUPS],
    /// Samples dropped for want of room (those whose publisher had left are the inbox's
    /// `orphans`).
    pub dropped: u64,
}

/// Creates (or opens) `name` with room for `max_clients` publishers and the server.
pub fn create(node: &Node<Ipc>, name: &str, max_clients: usize) -> Result<PathInbox, ServiceError> {
    // The samples held, the one taken, and one being received.
    let inbox = Inbox::create(node, name, max_clients, PATHS_BUFFER, PATHS_HELD + 2)?;
    Ok(PathInbox {
        inbox,
        held: Vec::with_capacity(PATHS_HELD),
        taken: None,
        claimants: [ClientId::NONE; MAX_GROUPS],
        dropped: 0,
    })
}

impl PathInbox {
    /// Notes each group's claimant from `frame` (the last one published).
    pub fn note_claimants(&mut self, frame: &MotionFrame) {
        for (slot, group) in self.claimants.iter_mut().zip(frame.groups.iter()) {
            *slot = group.owner;
        }
    }

    /// Whether a path of `node` for group `group` is its claimant's.
    fn privileged(&self, node: ClientId, group: u32) -> bool {
        !node.is_none() && self.claimants.get(group as usize) == Some(&node)
    }

    /// Takes every path that arrived since the last tick, each with its sender's node.
    pub fn receive(&mut self) {
        while let Some((node, sample)) = self.inbox.take() {
            let privileged = self.privileged(node, sample.payload().group);
            if let Some(index) = self.room_for(node, privileged) {
                self.held.remove(index);
                self.dropped += 1;
            } else if self.held.len() == PATHS_HELD {
                // Full of claimants' paths, and this one is not: it goes.
                self.dropped += 1;
                continue;
            }
            self.held.push((node, sample));
        }
    }

    /// The held path to give up for a new one from `node`: its own oldest when it holds
    /// [`PATHS_PER_NODE`]; else, when the room is full, the oldest unprivileged one, or the
    /// oldest of all when the new one is privileged. `None`: nothing needs to go (room
    /// left), or nothing may (full of privileged paths, the new one is not).
    fn room_for(&self, node: ClientId, privileged: bool) -> Option<usize> {
        let own = self.held.iter().filter(|(from, _)| *from == node).count();
        if own >= PATHS_PER_NODE {
            return self.held.iter().position(|(from, _)| *from == node);
        }
        if self.held.len() < PATHS_HELD {
            return None;
        }
        let unprivileged = self
            .held
            .iter()
            .position(|(from, sample)| !self.privileged(*from, sample.payload().group));
        match unprivileged {
            Some(index) => Some(index),
            None if privileged => Some(0),
            None => None,
        }
    }

    /// Whether a path `id` from `client` is held.
    pub fn holds(&self, client: ClientId, id: u64) -> bool {
        self.held
            .iter()
            .any(|(from, sample)| *from == client && sample.payload().id == id)
    }

    /// The newest path `id` from `client`, taken (a path runs once).
    pub fn take(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let index = self
            .held
            .iter()
            .rposition(|(from, sample)| *from == client && sample.payload().id == id)?;
        let (_, sample) = self.held.remove(index);
        self.taken = Some(sample);
        self.taken.as_ref().map(|sample| sample.payload())
    }
}
