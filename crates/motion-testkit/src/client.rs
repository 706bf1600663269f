//! A plain iceoryx2 client of one motiond instance: frames and commands, no motion-client.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::prelude::*;
use motion_ipc::{CommandKind, CommandReply, CommandRequest, MotionFrame, ServiceNames};

use crate::KitError;

/// The frame subscriber type.
pub type FrameSubscriber = iceoryx2::port::subscriber::Subscriber<ipc::Service, MotionFrame, ()>;
/// The command client type.
pub type CommandClient =
    iceoryx2::port::client::Client<ipc::Service, CommandRequest, (), CommandReply, ()>;

fn service_name(name: &str) -> Result<ServiceName, KitError> {
    name.try_into()
        .map_err(|e| KitError::Ipc(format!("service name {name:?}: {e:?}")))
}

/// Opens the frame service of instance `name`, retrying until `timeout`.
pub fn open_frames(
    node: &Node<ipc::Service>,
    name: &str,
    timeout: Duration,
) -> Option<FrameSubscriber> {
    try_open_frames(node, name, timeout).ok()
}

/// [`open_frames`] with the reason when it fails.
pub fn try_open_frames(
    node: &Node<ipc::Service>,
    name: &str,
    timeout: Duration,
) -> Result<FrameSubscriber, KitError> {
    let service_name = service_name(ServiceNames::new(name).frame().as_str())?;
    let end = Instant::now() + timeout;
    let mut last = String::from("never tried");
    while Instant::now() < end {
        match node
            .service_builder(&service_name)
            .publish_subscribe::<MotionFrame>()
            .open()
        {
            Ok(service) => {
                return service
                    .subscriber_builder()
                    .create()
                    .map_err(|e| KitError::Ipc(format!("frame subscriber: {e:?}")));
            }
            Err(e) => last = format!("{e:?}"),
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Err(KitError::Timeout(format!(
        "frame service of `{name}` within {timeout:?} ({last})"
    )))
}

/// The newest frame within `timeout`.
pub fn next_frame(subscriber: &FrameSubscriber, timeout: Duration) -> Option<MotionFrame> {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        let mut latest = None;
        while let Ok(Some(sample)) = subscriber.receive() {
            latest = Some(*sample);
        }
        if latest.is_some() {
            return latest;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    None
}

/// A plain iceoryx2 client of one motiond instance: frames and commands.
#[derive(Debug)]
pub struct RawClient {
    /// Its node (its id is the client id the server sees).
    pub node: Node<ipc::Service>,
    /// Frame subscriber.
    pub frames: FrameSubscriber,
    /// Command client.
    pub commands: CommandClient,
    sequence: u64,
}

impl RawClient {
    /// Connects to instance `name`, waiting up to `timeout` for it to appear; panics when it
    /// does not.
    pub fn connect(name: &str, timeout: Duration) -> Self {
        Self::try_connect(name, timeout).unwrap_or_else(|e| panic!("connect to {name}: {e}"))
    }

    /// [`RawClient::connect`] with the reason when it fails.
    pub fn try_connect(name: &str, timeout: Duration) -> Result<Self, KitError> {
        set_log_level(LogLevel::Error);
        let node = NodeBuilder::new()
            .create::<ipc::Service>()
            .map_err(|e| KitError::Ipc(format!("client node: {e:?}")))?;
        let frames = try_open_frames(&node, name, timeout)?;
        let service_name = service_name(ServiceNames::new(name).command().as_str())?;
        let commands = node
            .service_builder(&service_name)
            .request_response::<CommandRequest, CommandReply>()
            .open()
            .map_err(|e| KitError::Ipc(format!("command service: {e:?}")))?
            .client_builder()
            .create()
            .map_err(|e| KitError::Ipc(format!("command client: {e:?}")))?;
        Ok(Self {
            node,
            frames,
            commands,
            sequence: 0,
        })
    }

    /// This client's id as the server sees it.
    pub fn id(&self) -> motion_ipc::ClientId {
        motion_ipc::ClientId::from_u128(self.node.id().value())
    }

    /// Sends one command and waits (up to 2 s) for its reply; panics without one.
    pub fn command(&mut self, axis: u32, kind: CommandKind, values: [f64; 3]) -> CommandReply {
        self.try_command(axis, kind, values)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// [`RawClient::command`] with the reason when no reply came.
    pub fn try_command(
        &mut self,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, KitError> {
        self.sequence += 1;
        let request = CommandRequest::new(self.id(), self.sequence, axis, kind).with_values(values);
        self.request(request, Duration::from_secs(2))
    }

    /// Sends `request` as it is and waits up to `timeout` for its reply.
    pub fn request(
        &self,
        request: CommandRequest,
        timeout: Duration,
    ) -> Result<CommandReply, KitError> {
        let pending = self
            .commands
            .send_copy(request)
            .map_err(|e| KitError::Ipc(format!("send {request:?}: {e:?}")))?;
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            if let Ok(Some(reply)) = pending.receive() {
                return Ok(*reply);
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        Err(KitError::Timeout(format!(
            "no reply to {request:?} within {timeout:?}"
        )))
    }

    /// The newest frame (waiting up to 2 s); panics without one.
    pub fn frame(&self) -> MotionFrame {
        self.try_frame(Duration::from_secs(2))
            .unwrap_or_else(|| panic!("no frame within 2 s"))
    }

    /// The newest frame, waiting up to `timeout`.
    pub fn try_frame(&self, timeout: Duration) -> Option<MotionFrame> {
        next_frame(&self.frames, timeout)
    }

    /// Polls frames until `done` holds or `timeout` passes; returns the last frame and
    /// whether `done` held.
    pub fn wait_frame(
        &self,
        timeout: Duration,
        mut done: impl FnMut(&MotionFrame) -> bool,
    ) -> (MotionFrame, bool) {
        let end = Instant::now() + timeout;
        let mut last = self.frame();
        while Instant::now() < end {
            last = self.frame();
            if done(&last) {
                return (last, true);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        (last, false)
    }

    /// [`RawClient::wait_frame`] that never panics: `None` when no frame came at all.
    pub fn try_wait_frame(
        &self,
        timeout: Duration,
        mut done: impl FnMut(&MotionFrame) -> bool,
    ) -> Option<(MotionFrame, bool)> {
        let end = Instant::now() + timeout;
        let mut last = None;
        loop {
            if let Some(frame) = self.try_frame(Duration::from_millis(200)) {
                if done(&frame) {
                    return Some((frame, true));
                }
                last = Some(frame);
            }
            if Instant::now() >= end {
                return last.map(|frame| (frame, false));
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }
}
