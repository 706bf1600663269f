//! The Python closed-loop client in the streaming phase: `PYTHON -m motiond.bench_stream
//! --server NAME --group base --duration SECONDS` (`python/src/motiond/bench_stream.py`:
//! the package's own `stream("velocity")` and `run_each_tick`, answering each frame `k`
//! with the setpoint for `k + 1`), run as a child against the coordinated-motion phase's
//! motiond right after the Rust client's stream, its JSON document parsed into the share
//! of ticks it made in time and its frame → received-by-the-server distribution, beside
//! the Rust client's.

use core::time::Duration;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::dist::{Dist, Summary};
use crate::python::{PythonError, dist, field, last_line, number, run_with_timeout, string};
use crate::report::{Row, Unit};

/// The `format` of the document `python -m motiond.bench_stream` prints.
pub const FORMAT: &str = "motiond.bench_stream/1";

/// What the Python closed-loop client measured.
#[derive(Debug, Clone)]
pub struct PythonStream {
    /// Setpoints sent.
    pub sent: u64,
    /// Ticks from the first setpoint's to the last's.
    pub ticks: u64,
    /// Setpoints sent before the deadline of their tick.
    pub before_deadline: u64,
    /// Frames the client never saw.
    pub lost_frames: u64,
    /// Seen applied in their tick, and later.
    pub applied: (u64, u64),
    /// The server's counters: applied, late, early, clamped, refused.
    pub counters: [u64; 5],
    /// Frame `publish_ns` → sent, ns.
    pub sent_ns: Dist,
    /// Frame `publish_ns` → received by the server, ns.
    pub received_ns: Dist,
    /// `CPython 3.11.7`.
    pub python: String,
}

/// Runs the child for `duration` on `group` of `server`; kills it after 2 × `duration` +
/// [`crate::python::MARGIN`].
pub fn measure(
    python: &Path,
    server: &str,
    group: &str,
    duration: Duration,
) -> Result<PythonStream, String> {
    let mut command = Command::new(python);
    command.args([
        "-m",
        "motiond.bench_stream",
        "--server",
        server,
        "--group",
        group,
    ]);
    command.arg("--duration");
    command.arg(format!("{}", duration.as_secs_f64()));
    let output = run_with_timeout(command, duration * 2 + crate::python::MARGIN)
        .map_err(|e| format!("python -m motiond.bench_stream: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "python -m motiond.bench_stream: {}: {}",
            output.status,
            last_line(&output.stderr)
        ));
    }
    parse(&String::from_utf8_lossy(&output.stdout)).map_err(|e| e.to_string())
}

/// Parses the document (its last line when something was printed before it).
pub fn parse(text: &str) -> Result<PythonStream, PythonError> {
    let last = text.trim().lines().next_back().unwrap_or_default();
    let document: Value = serde_json::from_str(last)
        .map_err(|e| PythonError::BadOutput(format!("no JSON document: {e}")))?;
    let format = string(&document, "format")?;
    if format != FORMAT {
        return Err(PythonError::BadOutput(format!(
            "format {format:?}, expected {FORMAT:?}"
        )));
    }
    let stream = field(&document, "stream")?;
    let counters = field(stream, "counters")?;
    let mut counted = [0; 5];
    for (slot, key) in ["applied", "late", "early", "clamped", "refused"]
        .into_iter()
        .enumerate()
    {
        counted[slot] = number(counters, key)?;
    }
    Ok(PythonStream {
        sent: number(stream, "sent")?,
        ticks: number(stream, "ticks")?,
        before_deadline: number(stream, "before_deadline")?,
        lost_frames: number(stream, "lost_frames")?,
        applied: (
            number(stream, "applied_in_tick")?,
            number(stream, "applied_later")?,
        ),
        counters: counted,
        sent_ns: dist(field(stream, "sent_ns")?, "stream.sent_ns")?.0,
        received_ns: dist(field(stream, "received_ns")?, "stream.received_ns")?.0,
        python: string(&document, "python")?.to_owned(),
    })
}

/// The Python rows: its in-time share beside the Rust client's (`rust_in_time`), its
/// frame → received beside the Rust client's (`rust_received`).
pub fn rows(
    run: &Result<PythonStream, String>,
    rust_in_time: Summary,
    rust_received: Summary,
) -> Vec<Row> {
    let run = match run {
        Ok(run) => run,
        Err(e) => {
            return vec![Row {
                figure: "streaming to base, Python closed-loop client: not measured".to_owned(),
                unit: Unit::CentiPercent,
                ours: Summary::default(),
                baseline: Some(rust_in_time),
                baseline_label: "the Rust client above".to_owned(),
                note: e.clone(),
            }];
        }
    };
    let [applied, late, early, clamped, refused] = run.counters;
    vec![
        Row {
            figure: "streaming to base, Python closed-loop client (stream.run_each_tick): ticks \
                     for which it sent its setpoint before the tick's deadline, % of the \
                     stream's ticks"
                .to_owned(),
            unit: Unit::CentiPercent,
            ours: crate::stream::percent(run.before_deadline, run.ticks),
            baseline: Some(rust_in_time),
            baseline_label: "the Rust client of the row above, same motiond, same group, just \
                             before"
                .to_owned(),
            note: format!(
                "{}; python -m motiond.bench_stream, the package's own loop answering every \
                 new frame (one_in_flight=False); {} of {} ticks, {} frames missed; seen \
                 applied in their tick {}, later {}; the server's counters: applied {applied}, \
                 late {late}, early {early}, clamped {clamped}, refused {refused}",
                run.python,
                run.before_deadline,
                run.ticks,
                run.lost_frames,
                run.applied.0,
                run.applied.1
            ),
        },
        Row {
            figure: "streaming to base, Python closed-loop client: frame k published → its \
                     setpoint for k + 1 received by the server (GroupState.last_received_ns)"
                .to_owned(),
            unit: Unit::Ns,
            ours: run.received_ns.summary(),
            baseline: Some(rust_received),
            baseline_label: "the Rust client, same figure".to_owned(),
            note: format!(
                "frame publish_ns → sent (the client's own stamp): p50 {} / p99 {} µs",
                run.sent_ns.summary().p50 / 1000,
                run.sent_ns.summary().p99 / 1000
            ),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_is_parsed_and_a_wrong_format_refused() {
        let document = r#"{"format":"motiond.bench_stream/1","python":"CPython 3.11.7","stream":{"sent":3,"ticks":4,"before_deadline":2,"lost_frames":1,"applied_in_tick":2,"applied_later":1,"counters":{"applied":3,"late":0,"early":0,"clamped":0,"refused":0},"sent_ns":{"count":3,"samples":[10,20,30]},"received_ns":{"count":2,"samples":[900000,950000]}}}"#;
        let run = parse(&format!("noise\n{document}\n")).expect("a document");
        assert_eq!((run.sent, run.ticks, run.before_deadline), (3, 4, 2));
        assert_eq!((run.lost_frames, run.applied), (1, (2, 1)));
        assert_eq!(run.counters, [3, 0, 0, 0, 0]);
        assert_eq!(run.sent_ns.summary().samples, 3);
        assert_eq!(run.received_ns.summary().samples, 2);
        let other = document.replace("bench_stream/1", "bench/1");
        assert!(parse(&other).is_err());
        let row = &rows(&Ok(run), Summary::default(), Summary::default())[0];
        assert_eq!(
            row.ours.p50, 5000,
            "2 of 4 ticks, in hundredths of a percent"
        );
    }
}
