//! The Python closed-loop client in the streaming phase: `PYTHON -m motiond.bench_stream
//! --server NAME --group base --duration SECONDS [--lead N]`
//! (`python/src/motiond/bench_stream.py`: the package's own `stream("velocity")` and
//! `run_each_tick`, answering each frame `k` with the setpoint for `k + lead`), run as a
//! child against the coordinated-motion phase's motiond right after the Rust client's
//! stream, twice — with lead 1 and with the package's default lead — optionally beside
//! `--busy-loops` spinning processes; each JSON document parsed into the share of ticks it
//! met (its setpoint sent before the server takes that tick's) and its frame →
//! received-by-the-server distribution, beside the Rust client's.

use core::time::Duration;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

use crate::dist::{Dist, Summary};
use crate::python::{PythonError, dist, field, last_line, number, run_with_timeout, string};
use crate::report::{Row, Unit};

/// The `format` of the document `python -m motiond.bench_stream` prints.
pub const FORMAT: &str = "motiond.bench_stream/2";

/// What the Python closed-loop client measured.
#[derive(Debug, Clone)]
pub struct PythonStream {
    /// Ticks ahead of the frame read it sent for.
    pub lead: u64,
    /// The stream's delay at the end (ticks it ran behind its setpoints' own ticks).
    pub stream_delay: u64,
    /// Busy loops that spun beside it.
    pub busy_loops: u32,
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

/// Processes spinning `while True: pass` for as long as the value lives (killed on drop).
struct BusyLoops(Vec<std::process::Child>);

impl BusyLoops {
    fn start(python: &Path, count: u32) -> Result<Self, String> {
        let mut loops = Self(Vec::new());
        for _ in 0..count {
            let child = Command::new(python)
                .args(["-c", "while True: pass"])
                .stdin(std::process::Stdio::null())
                .spawn()
                .map_err(|e| format!("a busy loop ({}): {e}", python.display()))?;
            loops.0.push(child);
        }
        Ok(loops)
    }
}

impl Drop for BusyLoops {
    fn drop(&mut self) {
        for child in &mut self.0 {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// The Python client twice, with lead 1 and with the package's default lead, each for
/// `duration` on `group` of `server`, beside `busy_loops` spinning processes.
pub fn measure_leads(
    python: &Path,
    server: &str,
    group: &str,
    duration: Duration,
    busy_loops: u32,
) -> Vec<Result<PythonStream, String>> {
    let loops = match BusyLoops::start(python, busy_loops) {
        Ok(loops) => loops,
        Err(e) => return vec![Err(e)],
    };
    let runs = [Some(1), None]
        .into_iter()
        .map(|lead| {
            measure(python, server, group, duration, lead).map(|mut run| {
                run.busy_loops = busy_loops;
                run
            })
        })
        .collect();
    drop(loops);
    runs
}

/// Runs the child for `duration` on `group` of `server` with `lead` (`None`: the package's
/// default); kills it after 2 × `duration` + [`crate::python::MARGIN`].
pub fn measure(
    python: &Path,
    server: &str,
    group: &str,
    duration: Duration,
    lead: Option<u64>,
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
    // The busy loops beside it (and a loaded machine) can hold its start-up past the
    // package's default 2 s: the bench measures the stream, not how fast Python connects.
    command.args(["--connect-timeout", "10"]);
    if let Some(lead) = lead {
        command.arg("--lead");
        command.arg(lead.to_string());
    }
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
        lead: number(stream, "lead")?,
        stream_delay: number(stream, "stream_delay")?,
        busy_loops: 0,
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

/// The Python rows: per run (lead 1, then the default lead) its share of ticks met, the
/// first beside the Rust client's (`rust_in_time`), the next beside the first; the frame →
/// received of the default lead's run beside the Rust client's (`rust_received`).
pub fn rows(
    runs: &[Result<PythonStream, String>],
    rust_in_time: Summary,
    rust_received: Summary,
) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut baseline = (
        rust_in_time,
        "the Rust client above, same motiond, same group, just \
                                       before"
            .to_owned(),
    );
    let mut received = None;
    for run in runs {
        let run = match run {
            Ok(run) => run,
            Err(e) => {
                rows.push(Row {
                    figure: "streaming to base, Python closed-loop client: not measured".to_owned(),
                    unit: Unit::CentiPercent,
                    ours: Summary::default(),
                    baseline: Some(baseline.0),
                    baseline_label: baseline.1.clone(),
                    note: e.clone(),
                });
                continue;
            }
        };
        let [applied, late, early, clamped, refused] = run.counters;
        let met = crate::dist::percent(run.before_deadline, run.ticks);
        let beside = match run.busy_loops {
            0 => String::new(),
            n => format!(", {n} busy loops beside"),
        };
        rows.push(Row {
            figure: format!(
                "streaming to base, Python closed-loop client (stream.run_each_tick), lead {}{}: \
                 ticks it met (setpoint sent before the server takes that tick's), % of the \
                 stream's ticks",
                run.lead, beside
            ),
            unit: Unit::CentiPercent,
            ours: met,
            baseline: Some(baseline.0),
            baseline_label: baseline.1.clone(),
            note: format!(
                "{}; python -m motiond.bench_stream --lead {}, the package's own loop answering \
                 every new frame; {} of {} ticks, {} frames missed; seen applied in their tick \
                 {}, later {}; the stream ran {} ticks behind at the end; the server's \
                 counters: applied {applied}, late {late}, early {early}, clamped {clamped}, \
                 refused {refused}",
                run.python,
                run.lead,
                run.before_deadline,
                run.ticks,
                run.lost_frames,
                run.applied.0,
                run.applied.1,
                run.stream_delay
            ),
        });
        baseline = (
            met,
            format!("the Python client with lead {}, the row above", run.lead),
        );
        received = Some(run);
    }
    if let Some(run) = received {
        rows.push(Row {
            figure: format!(
                "streaming to base, Python closed-loop client (lead {}): frame k published → its \
                 setpoint received by the server (GroupState.last_received_ns)",
                run.lead
            ),
            unit: Unit::Ns,
            ours: run.received_ns.summary(),
            baseline: Some(rust_received),
            baseline_label: "the Rust client, same figure".to_owned(),
            note: format!(
                "frame publish_ns → sent (the client's own stamp): p50 {} / p99 {} µs",
                run.sent_ns.summary().p50 / 1000,
                run.sent_ns.summary().p99 / 1000
            ),
        });
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_document_is_parsed_and_a_wrong_format_refused() {
        let document = r#"{"format":"motiond.bench_stream/2","python":"CPython 3.11.7","stream":{"lead":2,"stream_delay":1,"sent":3,"ticks":4,"before_deadline":2,"lost_frames":1,"applied_in_tick":2,"applied_later":1,"counters":{"applied":3,"late":0,"early":0,"clamped":0,"refused":0},"sent_ns":{"count":3,"samples":[10,20,30]},"received_ns":{"count":2,"samples":[900000,950000]}}}"#;
        let run = parse(&format!("noise\n{document}\n")).expect("a document");
        assert_eq!((run.sent, run.ticks, run.before_deadline), (3, 4, 2));
        assert_eq!((run.lost_frames, run.applied), (1, (2, 1)));
        assert_eq!(run.counters, [3, 0, 0, 0, 0]);
        assert_eq!(run.sent_ns.summary().samples, 3);
        assert_eq!(run.received_ns.summary().samples, 2);
        assert_eq!((run.lead, run.stream_delay), (2, 1));
        let other = document.replace("bench_stream/2", "bench/1");
        assert!(parse(&other).is_err());
        let mut first = run.clone();
        first.lead = 1;
        first.before_deadline = 1;
        let rows = rows(
            &[Ok(first), Ok(run)],
            Summary::default(),
            Summary::default(),
        );
        assert_eq!(rows.len(), 3, "a row per lead and the received row");
        assert_eq!(
            rows[0].ours.p50, 2500,
            "1 of 4 ticks, in hundredths of a percent"
        );
        assert_eq!(rows[1].ours.p50, 5000, "2 of 4 ticks");
        assert_eq!(rows[1].baseline.map(|b| b.p50), Some(2500), "beside lead 1");
        assert!(rows[1].figure.contains("lead 2"), "{}", rows[1].figure);
    }
}
