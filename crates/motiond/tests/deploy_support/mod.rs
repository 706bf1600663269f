//! motiond as a service manager starts it: a fake `$NOTIFY_SOCKET`, another user, given
//! limits or capabilities, a working directory of its own.
#![allow(dead_code)]

use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::os::unix::net::UnixDatagram;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A scratch directory every user can read, removed on drop.
pub struct Scratch {
    pub dir: PathBuf,
}

impl Scratch {
    pub fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("motiond-deploy-{}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        Self { dir }
    }

    /// Writes a file readable by everyone.
    pub fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.dir.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("dirs");
        }
        std::fs::write(&path, text).expect("write");
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// The service manager's end of `$NOTIFY_SOCKET`: a datagram socket any user may send to.
pub struct FakeManager {
    pub socket: UnixDatagram,
    pub path: PathBuf,
    /// Every notification so far, in order.
    pub messages: Vec<String>,
}

impl FakeManager {
    pub fn new(dir: &Path) -> Self {
        let path = dir.join("notify.sock");
        let socket = UnixDatagram::bind(&path).expect("bind the notify socket");
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o777)).expect("chmod");
        socket
            .set_read_timeout(Some(Duration::from_millis(50)))
            .expect("timeout");
        Self {
            socket,
            path,
            messages: Vec::new(),
        }
    }

    /// Receives until a notification satisfies `done` or `timeout` passes; returns it.
    pub fn wait_for(&mut self, timeout: Duration, done: impl Fn(&str) -> bool) -> Option<String> {
        if let Some(found) = self.messages.iter().find(|m| done(m)) {
            return Some(found.clone());
        }
        let end = Instant::now() + timeout;
        let mut buf = [0u8; 4096];
        while Instant::now() < end {
            if let Ok(len) = self.socket.recv(&mut buf) {
                let message = String::from_utf8_lossy(&buf[..len]).into_owned();
                self.messages.push(message.clone());
                if done(&message) {
                    return Some(message);
                }
            }
        }
        None
    }

    /// Collects notifications for `span`.
    pub fn collect(&mut self, span: Duration) {
        let _ = self.wait_for(span, |_| false);
    }
}

/// Two simulated SPI_motor boards on one bus, one axis each; the config's `[server]` table
/// gets `extra` lines.
pub fn config_text(name: &str, extra: &str) -> String {
    format!(
        r#"[server]
name = "{name}"
{extra}

[[link]]
name = "spi"
type = "sim"

[[device]]
name = "focus_drv"
link = "spi"
model = "spimotor"
address = 0x90

[[device]]
name = "pumps"
link = "spi"
model = "spimotor"
address = 0x92
drive = "brushed"

[[axis]]
name = "focus"
device = "focus_drv"
channel = 0
unit = "step"
counts_per_unit = 1.0
min = -5000.0
max = 5000.0
max_velocity = 500.0
max_accel = 5000.0

[[axis]]
name = "pump_a"
device = "pumps"
channel = 0
unit = "rev"
counts_per_unit = 1.0
min = -1000.0
max = 1000.0
max_velocity = 50.0
max_accel = 500.0
"#
    )
}

/// A running motiond (killed on drop) with its stderr lines: the testkit's server, started
/// from a whole command line (`Motiond::spawn_command`).
pub type Motiond = motion_testkit::Server;
