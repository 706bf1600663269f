//! A recording's outputs as `motionctl record` and its writers share them: the file
//! formats ([`RecordFormat`], also told by a file's extension) and what every output does
//! with the recorded frames ([`Recording`]; written by [`record_csv`](crate::record_csv),
//! [`record_mcap`](crate::record_mcap) and [`record_plot`](crate::record_plot), driven by
//! [`record`](crate::record)).

use std::path::Path;

use clap::ValueEnum;
use motion_client::ipc::MotionFrame;

/// A recording's file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RecordFormat {
    /// One CSV row per tick.
    Csv,
    /// MCAP: ROS 2 `sensor_msgs/msg/JointState` (CDR) and JSON channels, for Foxglove and
    /// PlotJuggler.
    Mcap,
}

impl RecordFormat {
    /// The format the file's extension names (`.csv`, `.mcap`, any case).
    pub fn from_extension(path: &Path) -> Option<Self> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        match extension.as_str() {
            "csv" => Some(Self::Csv),
            "mcap" => Some(Self::Mcap),
            _ => None,
        }
    }
}

/// One output of a recording: told every recorded frame, in tick order, then finished (on
/// the recording's writer thread).
pub trait Recording: Send {
    /// Writes one tick.
    fn frame(&mut self, frame: &MotionFrame) -> anyhow::Result<()>;
    /// Completes the file.
    fn finish(self: Box<Self>) -> anyhow::Result<()>;
    /// The file written.
    fn path(&self) -> &Path;
}
