//! Which server this client talks to, and noticing when that changes (a restart).
//!
//! A server is known by its iceoryx2 node id: every sample (info, frame) and every command
//! reply says which node sent it. A new node on the same services, a changed
//! `server_pid`/`start_time_ns` in the description, or a tick that went backwards means the
//! server restarted. Samples still buffered from a server known to be gone are dropped.

use std::cell::{Cell, RefCell};

use crate::Restart;

/// Old server nodes remembered, to drop their leftover samples.
const RETIRED_KEPT: usize = 8;

/// What a sample or reply says about the server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Seen {
    /// The server we know.
    Current,
    /// A server known to be gone (a leftover sample): ignore it.
    Retired,
    /// A new server: the restart has been noted.
    Restarted,
}

#[derive(Debug)]
pub(crate) struct Session {
    server: String,
    node: Cell<u128>,
    pid: Cell<u32>,
    start_ns: Cell<u64>,
    /// Whether `pid`/`start_ns` were read from the current node's description.
    described: Cell<bool>,
    last_tick: Cell<Option<u64>>,
    epoch: Cell<u64>,
    acknowledged: Cell<u64>,
    retired: RefCell<Vec<u128>>,
    last: RefCell<Option<Restart>>,
}

impl Session {
    pub(crate) fn new(server: &str, node: u128, pid: u32, start_ns: u64) -> Self {
        Self {
            server: server.to_owned(),
            node: Cell::new(node),
            pid: Cell::new(pid),
            start_ns: Cell::new(start_ns),
            described: Cell::new(true),
            last_tick: Cell::new(None),
            epoch: Cell::new(0),
            acknowledged: Cell::new(0),
            retired: RefCell::new(Vec::new()),
            last: RefCell::new(None),
        }
    }

    /// How many restarts were seen.
    pub(crate) fn epoch(&self) -> u64 {
        self.epoch.get()
    }

    /// The process id of the current server (0 when not known yet).
    pub(crate) fn pid(&self) -> u32 {
        if self.described.get() {
            self.pid.get()
        } else {
            0
        }
    }

    /// The last restart, if it was not acknowledged.
    pub(crate) fn unacknowledged(&self) -> Option<Restart> {
        if self.acknowledged.get() == self.epoch.get() {
            return None;
        }
        self.last.borrow().clone()
    }

    /// The last restart seen, acknowledged or not.
    pub(crate) fn last_restart(&self) -> Option<Restart> {
        self.last.borrow().clone()
    }

    pub(crate) fn acknowledge(&self) -> Option<Restart> {
        let pending = self.unacknowledged();
        self.acknowledged.set(self.epoch.get());
        pending
    }

    fn is_retired(&self, node: u128) -> bool {
        self.retired.borrow().contains(&node)
    }

    fn restart(&self, node: u128, seen_in: &'static str) -> Seen {
        let old = self.node.get();
        if old != node {
            let mut retired = self.retired.borrow_mut();
            if retired.len() == RETIRED_KEPT {
                retired.remove(0);
            }
            retired.push(old);
        }
        let old_pid = self.pid();
        self.node.set(node);
        self.described.set(false);
        self.last_tick.set(None);
        self.epoch.set(self.epoch.get() + 1);
        *self.last.borrow_mut() = Some(Restart {
            server: self.server.clone(),
            old_pid,
            new_pid: None,
            count: self.epoch.get(),
            seen_in,
        });
        Seen::Restarted
    }

    /// A description (`ServerInfo`) from `node` saying `pid` and `start_ns`.
    pub(crate) fn observe_info(&self, node: u128, pid: u32, start_ns: u64) -> Seen {
        if self.is_retired(node) {
            return Seen::Retired;
        }
        let changed =
            self.described.get() && (pid != self.pid.get() || start_ns != self.start_ns.get());
        let seen = if node != self.node.get() || changed {
            self.restart(node, "server description")
        } else {
            Seen::Current
        };
        self.pid.set(pid);
        self.start_ns.set(start_ns);
        self.described.set(true);
        if let Some(restart) = self.last.borrow_mut().as_mut()
            && restart.count == self.epoch.get()
        {
            restart.new_pid = Some(pid);
        }
        seen
    }

    /// A frame from `node` at `tick`.
    pub(crate) fn observe_frame(&self, node: u128, tick: u64) -> Seen {
        if self.is_retired(node) {
            return Seen::Retired;
        }
        let seen = if node != self.node.get() {
            self.restart(node, "frame")
        } else if self.last_tick.get().is_some_and(|last| tick < last) {
            self.restart(node, "tick")
        } else {
            Seen::Current
        };
        self.last_tick.set(Some(tick));
        seen
    }

    /// A command reply from `node`.
    pub(crate) fn observe_reply(&self, node: u128) -> Seen {
        if self.is_retired(node) {
            return Seen::Retired;
        }
        if node != self.node.get() {
            return self.restart(node, "command reply");
        }
        Seen::Current
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_node_is_a_restart_and_old_samples_are_retired() {
        let session = Session::new("demo", 1, 100, 5);
        assert_eq!(session.observe_info(1, 100, 5), Seen::Current);
        assert_eq!(session.observe_frame(1, 10), Seen::Current);
        assert_eq!(session.observe_frame(1, 11), Seen::Current);
        assert_eq!(session.unacknowledged(), None);

        assert_eq!(session.observe_reply(2), Seen::Restarted);
        assert_eq!(session.epoch(), 1);
        let restart = session.unacknowledged().expect("restart noted");
        assert_eq!((restart.old_pid, restart.new_pid), (100, None));
        assert_eq!(restart.seen_in, "command reply");
        // The new server's description fills in its pid without another restart.
        assert_eq!(session.observe_info(2, 200, 9), Seen::Current);
        assert_eq!(session.unacknowledged().and_then(|r| r.new_pid), Some(200));
        // A frame the old server left in the buffer is dropped, not a second restart.
        assert_eq!(session.observe_frame(1, 12), Seen::Retired);
        assert_eq!(session.observe_frame(2, 0), Seen::Current);
        assert_eq!(session.epoch(), 1);

        let acknowledged = session.acknowledge().expect("pending");
        assert_eq!(acknowledged.count, 1);
        assert_eq!(session.unacknowledged(), None);
        assert!(session.last_restart().is_some());
        let text = acknowledged.to_string();
        assert!(text.contains("restarted (pid 100 → 200"), "{text}");
    }

    #[test]
    fn a_tick_going_backwards_or_a_new_pid_is_a_restart() {
        let session = Session::new("demo", 1, 100, 5);
        assert_eq!(session.observe_frame(1, 50), Seen::Current);
        assert_eq!(session.observe_frame(1, 3), Seen::Restarted);
        assert_eq!(session.unacknowledged().map(|r| r.seen_in), Some("tick"));
        session.acknowledge();
        assert_eq!(session.observe_info(1, 101, 5), Seen::Current); // pid learnt after restart
        assert_eq!(session.observe_info(1, 102, 6), Seen::Restarted);
        assert_eq!(session.epoch(), 2);
    }
}
