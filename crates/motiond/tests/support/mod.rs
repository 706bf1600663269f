//! Starting motiond as a child process and talking to it with plain iceoryx2.
#![allow(dead_code)]

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
