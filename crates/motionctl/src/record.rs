//! `motionctl record --duration D --out FILE.csv`: every frame, one CSV row per tick: the
//! axes chosen and every signal.

use core::time::Duration;
use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::Path;

use anyhow::Context as _;
use motion_client::ipc::SignalKind;
use motion_client::{Client, ClientError};

use crate::Service;
use crate::describe::{flag_names, mode_name, select_axes};
use crate::io::signal_flag_names;

/// How long to wait for a frame before calling the server silent.
const FRAME_TIMEOUT: Duration = Duration::from_secs(2);

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

/// Records the ticks `first .. first + duration × tick_hz` (server time), one row each.
pub fn run(
    client: &Client<Service>,
    duration: Duration,
    out: &Path,
    names: &[String],
) -> anyhow::Result<()> {
    let axes = select_axes(client, names)?;
    let tick_hz = client.info()?.tick_hz.max(1);
    let signals = client.info()?.signals().len();
    let wanted = (duration.as_secs_f64() * f64::from(tick_hz))
        .round()
        .max(1.0) as u64;
    let mut file = BufWriter::new(File::create(out).context("create the file")?);
    writeln!(file, "{}", header(client, &axes)?)?;
    let mut first = None;
    let mut last = None;
    let mut rows = 0u64;
    let mut interrupted = false;
    // Start from fresh frames, not from whatever waited in the buffer.
    drop(client.latest()?);
    loop {
        let frame = match client.next_frame(FRAME_TIMEOUT) {
            Ok(frame) => frame,
            Err(ClientError::Interrupted) => {
                interrupted = true;
                break;
            }
            Err(error) => return Err(error.into()),
        };
        let start = *first.get_or_insert(frame.tick);
        if frame.tick.saturating_sub(start) >= wanted {
            break;
        }
        last = Some(frame.tick);
        let mut line = format!("{},{:.9}", frame.tick, frame.time_ns as f64 / 1e9);
        for &index in &axes {
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
        for index in 0..signals {
            let state = frame.signals().get(index).copied().unwrap_or_default();
            line.push_str(&format!(
                ",{},{}",
                state.value,
                signal_flag_names(state.flags()).join("|")
            ));
        }
        writeln!(file, "{line}")?;
        rows += 1;
    }
    file.flush()?;
    let span = match (first, last) {
        (Some(from), Some(to)) => format!("ticks {from}..={to}"),
        _ => "no ticks".to_owned(),
    };
    eprintln!("recorded {rows} rows ({span}) to {}", out.display());
    if interrupted {
        eprintln!("stopped early by a signal");
    } else if rows < wanted {
        eprintln!(
            "warning: {} ticks were missed (motionctl was descheduled for longer than the \
             server's frame buffer); their rows are absent",
            wanted - rows
        );
    }
    Ok(())
}
