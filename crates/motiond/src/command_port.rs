//! The engine's command port in the server: requests from the iceoryx2 command service,
//! paths from the paths service, replies back, each journaled for the black box.

use iceoryx2::active_request::ActiveRequest;
use iceoryx2::port::server::Server;
use motion_engine::CommandPort;
use motion_ipc::{ClientId, CommandReply, CommandRequest, GroupPath};

use crate::Ipc;
use crate::paths::PathInbox;
use crate::services::{ClientDirectory, CommandFactory};
use motion_blackbox::Journal;

/// The command port over the iceoryx2 server: one active request at a time, answered
/// exactly once. The sender is the node of the client port the request came through, as
/// iceoryx2 knows it — never the payload's `client` field.
pub(crate) struct IpcCommands<'a> {
    pub server: &'a Server<Ipc, CommandRequest, (), CommandReply, ()>,
    pub factory: &'a CommandFactory,
    pub directory: &'a mut ClientDirectory,
    pub current: Option<ActiveRequest<Ipc, CommandRequest, (), CommandReply, ()>>,
    pub sender: ClientId,
    /// Replies that could not be sent (counted into `ServerStats::replies_lost`).
    pub replies_lost: u64,
    /// The paths clients sent their groups.
    pub paths: &'a mut PathInbox,
    /// The black box: every request, path and reply.
    pub journal: &'a mut Journal,
}

impl CommandPort for IpcCommands<'_> {
    fn next_request(&mut self) -> Option<CommandRequest> {
        let active = self.server.receive().ok().flatten()?;
        let request = *active.payload();
        self.sender = self
            .directory
            .node_of(self.factory, active.origin().value());
        self.journal.request(self.sender, &request);
        self.current = Some(active);
        Some(request)
    }

    fn sender(&self) -> Option<ClientId> {
        Some(self.sender)
    }

    fn take_path(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        if !self.paths.holds(client, id) {
            // Published after this tick took in the paths, and run at once: take in what
            // arrived since.
            self.paths.receive();
        }
        let path = self.paths.take(client, id);
        self.journal.path(client, id, path);
        path
    }

    fn reply(&mut self, reply: CommandReply) {
        self.journal.reply(&reply);
        if let Some(active) = self.current.take()
            && active.send_copy(reply).is_err()
        {
            // A client that vanished meanwhile cannot be answered: counted, nothing else.
            self.replies_lost += 1;
        }
    }
}
