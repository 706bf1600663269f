//! `motionctl record --duration D --out FILE…`: every frame of the ticks
//! `first .. first + D × tick_hz` (server time), to each file in its format (CSV or MCAP,
//! [`record_csv`](crate::record_csv), [`record_mcap`](crate::record_mcap)), and with
//! `--plot` to an SVG of desired and measured position and velocity per axis
//! ([`record_plot`](crate::record_plot)). Every output sees exactly the same ticks.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::sync::mpsc;

use anyhow::{Context as _, bail};
use motion_client::ipc::MotionFrame;
use motion_client::{Client, ClientError};

use crate::Service;
use crate::describe::select_axes;
use crate::record_csv::CsvRecording;
use crate::record_mcap::McapRecording;
use crate::record_output::{RecordFormat, Recording};
use crate::record_plot::PlotRecording;

/// How long to wait for a frame before calling the server silent.
const FRAME_TIMEOUT: Duration = Duration::from_secs(2);

/// What `motionctl record` was asked for.
#[derive(Debug)]
pub struct RecordRequest<'a> {
    /// Server time to record.
    pub duration: Duration,
    /// The files to write, each in its format.
    pub outs: &'a [PathBuf],
    /// The format of every file, overriding their extensions.
    pub format: Option<RecordFormat>,
    /// The SVG to plot the recorded axes into.
    pub plot: Option<&'a Path>,
    /// The axes to record (all when empty).
    pub axes: &'a [String],
}

fn format_of(path: &Path, forced: Option<RecordFormat>) -> anyhow::Result<RecordFormat> {
    forced
        .or_else(|| RecordFormat::from_extension(path))
        .with_context(|| {
            format!(
                "{}: cannot tell the format from the extension: name it .csv or .mcap, or pass \
             --format csv|mcap",
                path.display()
            )
        })
}

/// Opens every output before the first frame, so a bad path fails before recording.
fn open_outputs(
    client: &Client<Service>,
    request: &RecordRequest<'_>,
    axes: &[usize],
) -> anyhow::Result<Vec<Box<dyn Recording>>> {
    if request.outs.is_empty() && request.plot.is_none() {
        bail!("nothing to write: give --out FILE (.csv or .mcap) or --plot FILE.svg");
    }
    let mut outputs: Vec<Box<dyn Recording>> = Vec::new();
    for out in request.outs {
        let opened: anyhow::Result<Box<dyn Recording>> = match format_of(out, request.format)? {
            RecordFormat::Csv => CsvRecording::create(client, axes, out).map(|r| Box::new(r) as _),
            RecordFormat::Mcap => {
                McapRecording::create(client, axes, out).map(|r| Box::new(r) as _)
            }
        };
        outputs.push(opened.with_context(|| format!("record to {}", out.display()))?);
    }
    if let Some(plot) = request.plot {
        let recording = PlotRecording::create(client, axes, plot)
            .with_context(|| format!("plot to {}", plot.display()))?;
        outputs.push(Box::new(recording));
    }
    Ok(outputs)
}

/// Writes every frame received on `frames` to every output, then finishes them; the paths
/// written, in order.
fn write_all(
    mut outputs: Vec<Box<dyn Recording>>,
    frames: mpsc::Receiver<Box<MotionFrame>>,
) -> anyhow::Result<Vec<PathBuf>> {
    for frame in frames {
        for output in &mut outputs {
            output
                .frame(&frame)
                .with_context(|| format!("write {}", output.path().display()))?;
        }
    }
    outputs
        .into_iter()
        .map(|output| {
            let path = output.path().to_path_buf();
            output
                .finish()
                .with_context(|| format!("finish {}", path.display()))?;
            Ok(path)
        })
        .collect()
}

/// Records the ticks `first .. first + duration × tick_hz` (server time) to every output.
///
/// This thread only copies each frame out of the server's buffer (which holds a few ticks)
/// and hands it to a writer thread, so encoding (JSON, CDR, MCAP chunks) slower than the
/// tick rate delays the files' completion instead of losing ticks.
pub fn run(client: &Client<Service>, request: &RecordRequest<'_>) -> anyhow::Result<()> {
    let axes = select_axes(client, request.axes)?;
    let tick_hz = client.info()?.tick_hz.max(1);
    let wanted = (request.duration.as_secs_f64() * f64::from(tick_hz))
        .round()
        .max(1.0) as u64;
    let outputs = open_outputs(client, request, &axes)?;
    let (sender, frames) = mpsc::channel::<Box<MotionFrame>>();
    let writer = std::thread::Builder::new()
        .name("record-writer".to_owned())
        .spawn(move || write_all(outputs, frames))
        .context("start the writer thread")?;
    let mut first = None;
    let mut last = None;
    let mut ticks = 0u64;
    let mut interrupted = false;
    // Start from fresh frames, not from whatever waited in the buffer.
    drop(client.latest()?);
    let read: anyhow::Result<()> = loop {
        let frame = match client.next_frame(FRAME_TIMEOUT) {
            Ok(frame) => frame,
            Err(ClientError::Interrupted) => {
                interrupted = true;
                break Ok(());
            }
            Err(error) => break Err(error.into()),
        };
        let start = *first.get_or_insert(frame.tick);
        if frame.tick.saturating_sub(start) >= wanted {
            break Ok(());
        }
        last = Some(frame.tick);
        if sender.send(Box::new(*frame)).is_err() {
            // The writer stopped on an error, reported below.
            break Ok(());
        }
        ticks += 1;
    };
    drop(sender);
    let written = match writer.join() {
        Ok(result) => result?,
        Err(_) => bail!("the writer thread panicked"),
    };
    read?;
    let span = match (first, last) {
        (Some(from), Some(to)) => format!("ticks {from}..={to}"),
        _ => "no ticks".to_owned(),
    };
    for path in written {
        eprintln!("recorded {ticks} ticks ({span}) to {}", path.display());
    }
    if interrupted {
        eprintln!("stopped early by a signal");
    } else if ticks < wanted {
        eprintln!(
            "warning: {} ticks were missed (motionctl was descheduled for longer than the \
             server's frame buffer); they are absent from the recording",
            wanted - ticks
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_names_the_format_in_any_case() {
        assert_eq!(
            RecordFormat::from_extension(Path::new("run.mcap")),
            Some(RecordFormat::Mcap)
        );
        assert_eq!(
            RecordFormat::from_extension(Path::new("a/run.CSV")),
            Some(RecordFormat::Csv)
        );
        assert_eq!(RecordFormat::from_extension(Path::new("run.bag")), None);
        assert_eq!(RecordFormat::from_extension(Path::new("run")), None);
    }

    #[test]
    fn an_unknown_extension_without_format_is_a_clear_error() {
        let error = format_of(Path::new("run.bag"), None).expect_err("no format");
        assert!(error.to_string().contains("--format csv|mcap"), "{error}");
        assert_eq!(
            format_of(Path::new("run.bag"), Some(RecordFormat::Mcap)).ok(),
            Some(RecordFormat::Mcap)
        );
    }
}
