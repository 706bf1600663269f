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
