//! Service names of one motiond instance.

/// The iceoryx2 service names of the instance called `name` (`[server] name` in the
/// config): `motiond/<name>/frame`, `…/tick`, `…/command`, `…/info`, `…/stats`,
/// `…/params`, `…/estop`. The one place these names are spelt: the network contract
/// (`motion-wire`'s key expressions) builds its keys on them, with [`ServiceNames::under`]
/// for the keys it adds.
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

    /// `motiond/<name>/<leaf>`: any name under this instance's prefix.
    pub fn under(&self, leaf: &str) -> String {
        format!("{}{leaf}", self.prefix)
    }

    /// Publish-subscribe, history 1: one [`MotionFrame`](crate::MotionFrame) per tick.
    pub fn frame(&self) -> String {
        self.under("frame")
    }

    /// Event: notified after every frame.
    pub fn tick(&self) -> String {
        self.under("tick")
    }

    /// Request-response: [`CommandRequest`](crate::CommandRequest) →
    /// [`CommandReply`](crate::CommandReply).
    pub fn command(&self) -> String {
        self.under("command")
    }

    /// Publish-subscribe, history 1: [`ServerInfo`](crate::ServerInfo).
    pub fn info(&self) -> String {
        self.under("info")
    }

    /// Publish-subscribe, about 1 Hz: [`ServerStats`](crate::ServerStats).
    pub fn stats(&self) -> String {
        self.under("stats")
    }

    /// Publish-subscribe, history 1: [`MachineParams`](crate::MachineParams), the machine
    /// parameters in effect.
    pub fn params(&self) -> String {
        self.under("params")
    }

    /// Publish-subscribe: [`GroupPath`](crate::GroupPath), the paths clients send groups
    /// (run by a `Run` command).
    pub fn paths(&self) -> String {
        self.under("paths")
    }

    /// Publish-subscribe: [`Setpoint`](crate::Setpoint), streamed setpoints of the groups
    /// (a `Stream` command starts a stream).
    pub fn setpoints(&self) -> String {
        self.under("setpoints")
    }

    /// Event: any notification latches the e-stop. Its own ports, separate from the
    /// command service's, so that an e-stop gets through when the command service's client
    /// slots are exhausted.
    pub fn estop(&self) -> String {
        self.under("estop")
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
