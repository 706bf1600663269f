//! Service names of one motiond instance.

/// The iceoryx2 service names of the instance called `name` (`[server] name` in the
/// config): `motiond/<name>/frame`, `…/tick`, `…/command`, `…/info`, `…/stats`,
/// `…/params`, `…/estop`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServiceNames {
    prefix: String,
}

impl ServiceNames {
    /// Names for the instance `name`.
    pub fn new(name: &str) -> Self {
        Self {
            prefix: format!("motiond/{name}/"),
        }
    }

    fn join(&self, leaf: &str) -> String {
        format!("{}{leaf}", self.prefix)
    }

    /// Publish-subscribe, history 1: one [`MotionFrame`](crate::MotionFrame) per tick.
    pub fn frame(&self) -> String {
        self.join("frame")
    }

    /// Event: notified after every frame.
    pub fn tick(&self) -> String {
        self.join("tick")
    }

    /// Request-response: [`CommandRequest`](crate::CommandRequest) →
    /// [`CommandReply`](crate::CommandReply).
    pub fn command(&self) -> String {
        self.join("command")
    }

    /// Publish-subscribe, history 1: [`ServerInfo`](crate::ServerInfo).
    pub fn info(&self) -> String {
        self.join("info")
    }

    /// Publish-subscribe, about 1 Hz: [`ServerStats`](crate::ServerStats).
    pub fn stats(&self) -> String {
        self.join("stats")
    }

    /// Publish-subscribe, history 1: [`MachineParams`](crate::MachineParams), the machine
    /// parameters in effect.
    pub fn params(&self) -> String {
        self.join("params")
    }

    /// Event: any notification latches the e-stop. Its own ports, separate from the
    /// command service's, so that an e-stop gets through when the command service's client
    /// slots are exhausted.
    pub fn estop(&self) -> String {
        self.join("estop")
    }

    /// The iceoryx2 node name the server runs under (`motiond-<name>`): how a client finds
    /// the server's process without opening any service.
    pub fn server_node(&self) -> String {
        format!(
            "motiond-{}",
            self.prefix
                .trim_start_matches("motiond/")
                .trim_end_matches('/')
        )
    }
}
