//! Starting motiond as a child process and talking to it with plain iceoryx2.
#![allow(dead_code)]

pub mod pty_board;
pub mod socket_board;

use core::time::Duration;
use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Instant;

use iceoryx2::prelude::*;
use motion_ipc::{MotionFrame, ServiceNames};

/// A unique instance name for one test.
pub fn unique_name(test: &str) -> String {
    format!("t{}-{test}", std::process::id())
}

/// Writes `text` to a temp config file.
pub fn write_config(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).expect("write config");
    path
}

/// A running motiond; killed on drop if still running.
pub struct Server {
    pub child: Child,
    pub stderr: mpsc::Receiver<String>,
    pub log: Vec<String>,
}

impl Server {
    /// Starts `motiond --config path`.
    pub fn start(path: &std::path::Path) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_motiond"))
            .arg("--config")
            .arg(path)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start motiond");
        let stderr = child.stderr.take().expect("stderr");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self {
            child,
            stderr: rx,
            log: Vec::new(),
        }
    }

    /// Collects stderr lines until one contains `needle` or `timeout` passes.
    pub fn wait_for_log(&mut self, needle: &str, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        if self.log.iter().any(|l| l.contains(needle)) {
            return true;
        }
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            match self.stderr.recv_timeout(left) {
                Ok(line) => {
                    let hit = line.contains(needle);
                    self.log.push(line);
                    if hit {
                        return true;
                    }
                }
                Err(_) => return false,
            }
        }
        false
    }

    /// Sends `signal` and waits up to `timeout` for the exit status.
    pub fn signal_and_wait(
        &mut self,
        signal: nix::sys::signal::Signal,
        timeout: Duration,
    ) -> Option<i32> {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        let _ = nix::sys::signal::kill(pid, signal);
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            if let Ok(Some(status)) = self.child.try_wait() {
                self.drain_log();
                return status.code();
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        None
    }

    pub fn drain_log(&mut self) {
        while let Ok(line) = self.stderr.try_recv() {
            self.log.push(line);
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Opens the frame service of instance `name`, retrying until `timeout`.
pub fn open_frames(
    node: &Node<ipc::Service>,
    name: &str,
    timeout: Duration,
) -> Option<iceoryx2::port::subscriber::Subscriber<ipc::Service, MotionFrame, ()>> {
    let names = ServiceNames::new(name);
    let service_name: ServiceName = names.frame().as_str().try_into().ok()?;
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        if let Ok(service) = node
            .service_builder(&service_name)
            .publish_subscribe::<MotionFrame>()
            .open()
        {
            return service.subscriber_builder().create().ok();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    None
}

/// The newest frame within `timeout`.
pub fn next_frame(
    subscriber: &iceoryx2::port::subscriber::Subscriber<ipc::Service, MotionFrame, ()>,
    timeout: Duration,
) -> Option<MotionFrame> {
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
pub struct RawClient {
    pub node: Node<ipc::Service>,
    pub frames: iceoryx2::port::subscriber::Subscriber<ipc::Service, MotionFrame, ()>,
    pub commands: iceoryx2::port::client::Client<
        ipc::Service,
        motion_ipc::CommandRequest,
        (),
        motion_ipc::CommandReply,
        (),
    >,
    sequence: u64,
}

impl RawClient {
    /// Connects to instance `name`, waiting up to `timeout` for it to appear.
    pub fn connect(name: &str, timeout: Duration) -> Self {
        set_log_level(LogLevel::Error);
        let node = NodeBuilder::new()
            .create::<ipc::Service>()
            .expect("client node");
        let frames = open_frames(&node, name, timeout).expect("frame service");
        let service_name: ServiceName = ServiceNames::new(name)
            .command()
            .as_str()
            .try_into()
            .expect("name");
        let commands = node
            .service_builder(&service_name)
            .request_response::<motion_ipc::CommandRequest, motion_ipc::CommandReply>()
            .open()
            .expect("command service")
            .client_builder()
            .create()
            .expect("command client");
        Self {
            node,
            frames,
            commands,
            sequence: 0,
        }
    }

    /// Sends one command and waits (up to 2 s) for its reply.
    pub fn command(
        &mut self,
        axis: u32,
        kind: motion_ipc::CommandKind,
        values: [f64; 3],
    ) -> motion_ipc::CommandReply {
        self.sequence += 1;
        let client = motion_ipc::ClientId::from_u128(self.node.id().value());
        let request =
            motion_ipc::CommandRequest::new(client, self.sequence, axis, kind).with_values(values);
        let pending = self.commands.send_copy(request).expect("send command");
        let end = Instant::now() + Duration::from_secs(2);
        while Instant::now() < end {
            if let Ok(Some(reply)) = pending.receive() {
                return *reply;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        panic!("no reply to {request:?} within 2 s");
    }

    /// The newest frame (waiting up to 2 s).
    pub fn frame(&self) -> MotionFrame {
        next_frame(&self.frames, Duration::from_secs(2)).expect("a frame")
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
}
