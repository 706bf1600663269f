//! `record --out FILE.csv`: one CSV row per tick: tick and time, the axes chosen and every
//! signal.

use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use motion_client::Client;
use motion_client::ipc::{MotionFrame, SignalKind};

use crate::Service;
use crate::describe::{flag_names, mode_name};
use crate::io::signal_flag_names;
use crate::record_output::Recording;

/// The CSV header: tick and time, then per axis position, velocity, target (with units),
/// mode and flags, then per signal its value (with its unit; `0/1` for digital) and flags.
fn header(client: &Client<Service>, axes: &[usize]) -> anyhow::Result<String> {
    let info = client.info()?;
    let mut line = String::from("tick,time_s");
    for &index in axes {
        let axis = info.axes().get(index).context("axis list changed")?;
        let (name, unit) = (axis.name(), axis.unit());
        line.push_str(&format!(
            ",{name}.position[{unit}],{name}.velocity[{unit}/s],{name}.target[{unit}],{name}.mode,{name}.flags"
        ));
    }
    for signal in info.signals() {
        let name = signal.name();
        let unit = match signal.kind() {
            Ok(SignalKind::AnalogIn) => signal.unit(),
            _ => "0/1",
        };
        line.push_str(&format!(",{name}.value[{unit}],{name}.flags"));
    }
    Ok(line)
}

/// A CSV file being written.
#[derive(Debug)]
pub struct CsvRecording {
    path: PathBuf,
    file: BufWriter<File>,
    axes: Vec<usize>,
    signals: usize,
}

impl CsvRecording {
    /// Creates the file and writes the header.
    pub fn create(client: &Client<Service>, axes: &[usize], path: &Path) -> anyhow::Result<Self> {
        let signals = client.info()?.signals().len();
        let mut file = BufWriter::new(File::create(path).context("create the file")?);
        writeln!(file, "{}", header(client, axes)?)?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            axes: axes.to_vec(),
            signals,
        })
    }
}

impl Recording for CsvRecording {
    fn frame(&mut self, frame: &MotionFrame) -> anyhow::Result<()> {
        let mut line = format!("{},{:.9}", frame.tick, frame.time_ns as f64 / 1e9);
        for &index in &self.axes {
            let state = frame.axes().get(index).copied().unwrap_or_default();
            line.push_str(&format!(
                ",{},{},{},{},{}",
                state.position,
                state.velocity,
                state.target,
                mode_name(&state),
                flag_names(state.flags()).join("|")
            ));
        }
        for index in 0..self.signals {
            let state = frame.signals().get(index).copied().unwrap_or_default();
            line.push_str(&format!(
                ",{},{}",
                state.value,
                signal_flag_names(state.flags()).join("|")
            ));
        }
        writeln!(self.file, "{line}")?;
        Ok(())
    }

    fn finish(mut self: Box<Self>) -> anyhow::Result<()> {
        self.file.flush()?;
        Ok(())
    }

    fn path(&self) -> &Path {
        &self.path
    }
}
