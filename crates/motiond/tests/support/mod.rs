//! Starting motiond as a child process and talking to it with plain iceoryx2: the harness
//! lives in `crates/motion-testkit` (shared with the reliability campaigns); this names the
//! binary under test so that `Server::start(config)` needs nothing else.
#![allow(dead_code, unused_imports)]

pub mod pty_board {
    pub use motion_testkit::pty_board::*;
}
pub mod socket_board {
    pub use motion_testkit::socket_board::*;
}

pub use motion_testkit::{RawClient, next_frame, open_frames, unique_name, write_config};

/// The motiond this crate's tests run: the one cargo built for them.
#[derive(Debug, Clone, Copy)]
pub struct ThisMotiond;

impl motion_testkit::ServerBinary for ThisMotiond {
    fn path() -> std::path::PathBuf {
        env!("CARGO_BIN_EXE_motiond").into()
    }
}

/// A running motiond; killed on drop if still running.
pub type Server = motion_testkit::Server<ThisMotiond>;

/// A simulated SPI_motor stepper, axis `a` (index 0: 1 step a unit, ±10 000 steps,
/// 500 steps/s, 5000 steps/s²), with `server_keys` added to `[server]`.
pub fn stepper_config(name: &str, server_keys: &str) -> std::path::PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"
{server_keys}

[[link]]
name = "spi"
type = "sim"

[[device]]
name = "m"
link = "spi"
model = "spimotor"

[[axis]]
name = "a"
device = "m"
channel = 0
unit = "step"
counts_per_unit = 1.0
min = -10000.0
max = 10000.0
max_velocity = 500.0
max_accel = 5000.0
"#
        ),
    )
}

/// A QSB as device `io_board` on the serial link `usb` at `tty` (230400 baud), with the
/// `[[signal]]` tables `signals`.
pub fn qsb_io_config(name: &str, tty: &std::path::Path, signals: &str) -> std::path::PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "usb"
type = "serial"
path = "{}"
baud = 230400

[[device]]
name = "io_board"
link = "usb"
model = "qsb"

{signals}"#,
            tty.display()
        ),
    )
}

/// Axis 0's board is online and its measurement fresh.
pub fn axis0_online(frame: &motion_ipc::MotionFrame) -> bool {
    let axis = frame.axes()[0];
    axis.device_state() == Ok(motion_ipc::DeviceState::Online)
        && !axis.flags().contains(motion_ipc::AxisFlags::STALE)
}

/// The names of the threads of process `pid` (`/proc/PID/task/*/comm`).
pub fn thread_names(pid: u32) -> Vec<String> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .flatten()
        .filter_map(|task| std::fs::read_to_string(task.path().join("comm")).ok())
        .map(|comm| comm.trim().to_owned())
        .collect()
}
