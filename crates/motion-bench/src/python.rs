//! The "Python client" phase: `PYTHON -m motiond.bench --server NAME --duration SECONDS`
//! (the pip package in `python/`, `python/src/motiond/bench.py`) run as a child process
//! against the same motiond, its JSON document parsed into [`Dist`]s, and two rows: frame
//! delivery beside the Rust WaitSet client's, command round trip beside the Rust client's.
//!
//! The interpreter is `--python PATH`, else `py-venv/bin/python` in the target directory the
//! running program was built into (`./scripts/test` creates `target/py-venv`). A child that
//! cannot start, fails, hangs or prints something else than the document never stops the
//! bench: its phase is skipped with the reason ([`PythonError`]).

use core::time::Duration;
use std::collections::BTreeMap;
use std::io::Read;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde_json::Value;

use crate::args::CommandProbe;
use crate::dist::{Dist, Summary};
use crate::report::{Row, Unit};

/// The interpreter looked for under a target directory.
pub const VENV_PYTHON: &str = "py-venv/bin/python";
/// The `format` of the document `python -m motiond.bench` prints.
pub const FORMAT: &str = "motiond.bench/1";
/// What the child may take beyond its two parts of `duration` each: interpreter start,
/// imports, connecting (2 s at most), on a loaded machine.
pub const MARGIN: Duration = Duration::from_secs(30);
/// How long `import motiond.bench` may take when the interpreter is checked.
const CHECK_TIMEOUT: Duration = Duration::from_secs(30);
/// More stdout than this is not the document (at most about 1 MB): the child is killed.
const STDOUT_CAP: usize = 32 << 20;
/// Stderr kept for the error text.
const STDERR_CAP: usize = 64 << 10;

/// Why the Python client phase did not run or gave no figures.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PythonError {
    /// No `--python` and no `py-venv/bin/python` in the target directories looked at.
    NotFound(Vec<PathBuf>),
    /// The interpreter did not run, or cannot `import motiond.bench`.
    Unusable {
        /// The interpreter.
        python: PathBuf,
        /// Its own words, or why it could not be run.
        reason: String,
    },
    /// `python -m motiond.bench` could not start, failed, or hung and was killed.
    Child(String),
    /// Its stdout is not the document it prints.
    BadOutput(String),
}

impl core::fmt::Display for PythonError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NotFound(looked) => {
                let places: Vec<String> = looked.iter().map(|p| p.display().to_string()).collect();
                write!(
                    f,
                    "no Python interpreter given and none at {}",
                    places.join(", ")
                )
            }
            Self::Unusable { python, reason } => {
                write!(
                    f,
                    "{} cannot run `import motiond.bench`: {reason}",
                    python.display()
                )
            }
            Self::Child(text) => write!(f, "python -m motiond.bench: {text}"),
            Self::BadOutput(text) => write!(f, "python -m motiond.bench printed {text}"),
        }
    }
}

impl std::error::Error for PythonError {}

/// How to get the phase, for the note of a run without it.
pub const HOW_TO_ENABLE: &str = "./scripts/test creates target/py-venv with the package, or \
    `python3 -m venv target/py-venv && target/py-venv/bin/pip install ./python`; or pass \
    --python PATH (an interpreter that can `import motiond`)";

/// The interpreter: `explicit` when given (it must import the package), else
/// [`VENV_PYTHON`] under the directories holding the running program (up to three levels:
/// `target/release/motionctl`, `target/release/deps/latency-…`, `target/debug/deps/…`).
pub fn find_python(explicit: Option<&Path>) -> Result<PathBuf, PythonError> {
    if let Some(python) = explicit {
        check(python)?;
        return Ok(python.to_path_buf());
    }
    let exe =
        std::env::current_exe().map_err(|e| PythonError::Child(format!("own executable: {e}")))?;
    let looked: Vec<PathBuf> = exe
        .ancestors()
        .skip(1)
        .take(3)
        .map(|d| d.join(VENV_PYTHON))
        .collect();
    match looked.iter().find(|p| p.is_file()) {
        Some(python) => {
            check(python)?;
            Ok(python.clone())
        }
        None => Err(PythonError::NotFound(looked)),
    }
}

/// Whether `python` runs and has the package (with its bench module).
pub fn check(python: &Path) -> Result<(), PythonError> {
    let mut command = Command::new(python);
    command.args(["-c", "import motiond.bench"]);
    let unusable = |reason: String| PythonError::Unusable {
        python: python.to_path_buf(),
        reason,
    };
    let output = run_with_timeout(command, CHECK_TIMEOUT).map_err(unusable)?;
    if output.status.success() {
        Ok(())
    } else {
        Err(unusable(format!(
            "{}: {}",
            output.status,
            last_line(&output.stderr)
        )))
    }
}

/// What one Python client phase measured.
#[derive(Debug, Clone)]
pub struct PythonRun {
    /// `publish_ns` → frame in the Python client's hand, ns.
    pub frames: Dist,
    /// Frames received.
    pub received: u64,
    /// Ticks missing between received frames.
    pub lost: u64,
    /// Frames stamped after they were received (never recorded; 0 on one clock).
    pub negative: u64,
    /// How the client waited for frames, in its words.
    pub waiting: String,
    /// `Client.command` called → returned or raised, ns.
    pub rtt: Dist,
    /// Requests sent.
    pub sent: u64,
    /// Replies by reason name.
    pub replies: BTreeMap<String, u64>,
    /// Replies of another reason than `UNKNOWN_AXIS`.
    pub wrong_reason: u64,
    /// Requests without a reply within the client's reply timeout.
    pub no_reply: u64,
    /// The probe, in the client's words.
    pub probe: String,
    /// `CPython 3.11.7`.
    pub python: String,
    /// The iceoryx2 package's version.
    pub iceoryx2: String,
    /// The implementation of `time.monotonic_ns()`.
    pub clock: String,
}

/// Runs `python -m motiond.bench` against `server` (two parts of `duration` each); kills it
/// after 2 × `duration` + [`MARGIN`].
pub fn measure(python: &Path, server: &str, duration: Duration) -> Result<PythonRun, PythonError> {
    let mut command = Command::new(python);
    command.args(["-m", "motiond.bench", "--server", server, "--duration"]);
    command.arg(format!("{}", duration.as_secs_f64()));
    let output = run_with_timeout(command, duration * 2 + MARGIN).map_err(PythonError::Child)?;
    if !output.status.success() {
        return Err(PythonError::Child(format!(
            "{}: {}",
            output.status,
            last_line(&output.stderr)
        )));
    }
    parse(&String::from_utf8_lossy(&output.stdout))
}

/// Parses the document `python -m motiond.bench` prints (the whole text, or its last line
/// when something else was printed before it).
pub fn parse(text: &str) -> Result<PythonRun, PythonError> {
    let text = text.trim();
    if text.is_empty() {
        return Err(PythonError::BadOutput("nothing on stdout".to_owned()));
    }
    let document: Value = match serde_json::from_str(text) {
        Ok(value) => value,
        Err(whole) => {
            let last = text.lines().next_back().unwrap_or_default();
            serde_json::from_str(last).map_err(|_| {
                PythonError::BadOutput(format!("no JSON document ({whole}): {}", excerpt(text)))
            })?
        }
    };
    let format = string(&document, "format")?;
    if format != FORMAT {
        return Err(bad(format!("format {format:?}, expected {FORMAT:?}")));
    }
    let frames = field(&document, "frames")?;
    let commands = field(&document, "commands")?;
    let (frame_dist, frame_count) = dist(field(frames, "latency_ns")?, "frames.latency_ns")?;
    let received = number(frames, "received")?;
    let negative = number(frames, "negative")?;
    if frame_count + negative != received {
        return Err(bad(format!(
            "frames: received {received}, but {frame_count} latencies and {negative} negative"
        )));
    }
    let (rtt, answered) = dist(field(commands, "rtt_ns")?, "commands.rtt_ns")?;
    let replies_value = field(commands, "replies")?
        .as_object()
        .ok_or_else(|| bad("commands.replies is not an object".to_owned()))?;
    let mut replies = BTreeMap::new();
    for (reason, count) in replies_value {
        let count = count
            .as_u64()
            .ok_or_else(|| bad(format!("commands.replies.{reason} is not a count")))?;
        replies.insert(reason.clone(), count);
    }
    if replies.values().sum::<u64>() != answered {
        return Err(bad(format!(
            "commands: {answered} round trips but replies {replies:?}"
        )));
    }
    Ok(PythonRun {
        frames: frame_dist,
        received,
        lost: number(frames, "lost")?,
        negative,
        waiting: string(frames, "waiting")?.to_owned(),
        rtt,
        sent: number(commands, "sent")?,
        replies,
        wrong_reason: number(commands, "wrong_reason")?,
        no_reply: number(commands, "no_reply")?,
        probe: string(commands, "probe")?.to_owned(),
        python: string(&document, "python")?.to_owned(),
        iceoryx2: string(&document, "iceoryx2")?.to_owned(),
        clock: string(&document, "clock")?.to_owned(),
    })
}

fn bad(text: String) -> PythonError {
    PythonError::BadOutput(format!("an unexpected document: {text}"))
}

pub(crate) fn field<'a>(value: &'a Value, key: &str) -> Result<&'a Value, PythonError> {
    value.get(key).ok_or_else(|| bad(format!("no `{key}`")))
}

pub(crate) fn number(value: &Value, key: &str) -> Result<u64, PythonError> {
    field(value, key)?
        .as_u64()
        .ok_or_else(|| bad(format!("`{key}` is not a non-negative integer")))
}

pub(crate) fn string<'a>(value: &'a Value, key: &str) -> Result<&'a str, PythonError> {
    field(value, key)?
        .as_str()
        .ok_or_else(|| bad(format!("`{key}` is not a string")))
}

/// One distribution: `samples` (raw ns) or `histogram` (`[value, count]` pairs), with its
/// `count`; returns it and the count.
pub(crate) fn dist(value: &Value, what: &str) -> Result<(Dist, u64), PythonError> {
    let count = number(value, "count").map_err(|e| bad(format!("{what}: {e}")))?;
    let not_ns = |v: &Value| bad(format!("{what}: {v} is not a non-negative integer ns"));
    let mut dist = Dist::new();
    let mut total = 0u64;
    if let Some(samples) = value.get("samples").and_then(Value::as_array) {
        for sample in samples {
            dist.record(sample.as_u64().ok_or_else(|| not_ns(sample))?);
            total += 1;
        }
    } else if let Some(histogram) = value.get("histogram").and_then(Value::as_array) {
        for pair in histogram {
            let (Some(ns), Some(n)) = (
                pair.get(0).and_then(Value::as_u64),
                pair.get(1).and_then(Value::as_u64),
            ) else {
                return Err(bad(format!(
                    "{what}: histogram entry {pair} is not [ns, count]"
                )));
            };
            dist.record_n(ns, n);
            total = total.saturating_add(n);
        }
    } else {
        return Err(bad(format!("{what}: neither `samples` nor `histogram`")));
    }
    if total != count {
        return Err(bad(format!("{what}: count {count}, but {total} samples")));
    }
    Ok((dist, count))
}

fn excerpt(text: &str) -> String {
    let mut cut: String = text.chars().take(120).collect();
    if cut.len() < text.len() {
        cut.push('…');
    }
    format!("{cut:?}")
}

pub(crate) fn last_line(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .map_or_else(|| "(nothing on stderr)".to_owned(), |l| l.trim().to_owned())
}

/// The two rows: frame delivery against the Rust WaitSet client's (`rust_waitset`, both
/// sleep on the tick event), command round trip against the Rust client's (`rust_rtt`).
pub fn rows(
    run: &PythonRun,
    rust_waitset: Summary,
    rust_rtt: Summary,
    probe: CommandProbe,
) -> Vec<Row> {
    let replies: Vec<String> = run
        .replies
        .iter()
        .map(|(k, v)| format!("{k} ×{v}"))
        .collect();
    let baseline_probe = match probe {
        CommandProbe::UnknownAxis => "",
        CommandProbe::ClaimRelease => {
            "; the Rust baseline used --command claim-release, the Python client always the \
             unknown-axis probe"
        }
    };
    vec![
        Row {
            figure: "frame delivery, Python client (`for frame in client.frames()`, sleeping on the tick event)".to_owned(),
            unit: Unit::Ns,
            ours: run.frames.summary(),
            baseline: Some(rust_waitset),
            baseline_label: "the Rust client of row 3 (WaitSet on the tick event), same motiond, same run".to_owned(),
            note: format!(
                "publish_ns → time.monotonic_ns() when the iterator hands the frame over (implemented as {}, \
                 the clock of publish_ns); {}, iceoryx2 {}; {}: {} frames, lost ticks {}, stamped after receipt {}",
                run.clock, run.python, run.iceoryx2, run.waiting, run.received, run.lost, run.negative
            ),
        },
        Row {
            figure: "command round trip, Python client (Client.command, Stop on an unknown axis)".to_owned(),
            unit: Unit::Ns,
            ours: run.rtt.summary(),
            baseline: Some(rust_rtt),
            baseline_label: "the Rust client of row 5 (busy-polls for the reply), same motiond, same run".to_owned(),
            note: format!(
                "{}; called → returned or raised, a pseudo-random wait within one tick before each; the Python \
                 client sleeps on the tick event between reply checks; sent {}, replies: {}; other reasons {}; \
                 no reply {}{baseline_probe}",
                run.probe,
                run.sent,
                replies.join(", "),
                run.wrong_reason,
                run.no_reply
            ),
        },
    ]
}

/// A finished child's status and output.
#[derive(Debug)]
pub struct ChildOutput {
    /// How it ended.
    pub status: ExitStatus,
    /// Its stdout (at most 32 MiB).
    pub stdout: Vec<u8>,
    /// The end of its stderr (at most 64 KiB).
    pub stderr: Vec<u8>,
}

/// Reads `pipe` to its end, keeping at most `cap` bytes (the last ones when `keep_tail`);
/// raises `overflow` when there was more.
fn read_pipe(mut pipe: impl Read, cap: usize, keep_tail: bool, overflow: &AtomicBool) -> Vec<u8> {
    let mut kept = Vec::new();
    let mut buffer = [0u8; 8192];
    loop {
        match pipe.read(&mut buffer) {
            Ok(0) | Err(_) => return kept,
            Ok(n) => {
                kept.extend_from_slice(&buffer[..n]);
                if kept.len() > cap {
                    if keep_tail {
                        kept.drain(..kept.len() - cap);
                    } else {
                        kept.truncate(cap);
                        overflow.store(true, Ordering::Relaxed);
                        return kept;
                    }
                }
            }
        }
    }
}

/// Runs `command` (stdin closed, in a process group of its own) and collects its output;
/// kills the group when it runs longer than `timeout` or floods stdout.
pub fn run_with_timeout(mut command: Command, timeout: Duration) -> Result<ChildOutput, String> {
    let program = command.get_program().to_string_lossy().into_owned();
    command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0);
    // ETXTBSY ("Text file busy"): an executable written a moment ago (a script a test or
    // an installer just wrote) may still be open for writing in a child another thread
    // forked and has not yet exec'd; that passes within milliseconds.
    let mut attempts = 0;
    let mut child = loop {
        match command.spawn() {
            Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy && attempts < 50 => {
                attempts += 1;
                std::thread::sleep(Duration::from_millis(10));
            }
            spawned => break spawned.map_err(|e| format!("could not start {program}: {e}"))?,
        }
    };
    let group = nix::unistd::Pid::from_raw(i32::try_from(child.id()).unwrap_or(i32::MAX));
    let kill_group = || {
        let _ = nix::sys::signal::killpg(group, nix::sys::signal::Signal::SIGKILL);
    };
    let overflow = Arc::new(AtomicBool::new(false));
    let (stdout, stderr) = (child.stdout.take(), child.stderr.take());
    let flag = Arc::clone(&overflow);
    let out_thread = std::thread::spawn(move || {
        stdout
            .map(|p| read_pipe(p, STDOUT_CAP, false, &flag))
            .unwrap_or_default()
    });
    let never = Arc::new(AtomicBool::new(false));
    let err_thread = std::thread::spawn(move || {
        stderr
            .map(|p| read_pipe(p, STDERR_CAP, true, &never))
            .unwrap_or_default()
    });
    let started = Instant::now();
    let flooded = || format!("more than {} MiB on stdout; killed", STDOUT_CAP >> 20);
    let mut reaped = false;
    let status = loop {
        if overflow.load(Ordering::Relaxed) {
            break Err(flooded());
        }
        match child.try_wait() {
            Ok(Some(status)) => {
                reaped = true;
                // The stdout reader stops at the cap: the child may die of SIGPIPE first.
                if overflow.load(Ordering::Relaxed) {
                    break Err(flooded());
                }
                break Ok(status);
            }
            Ok(None) if started.elapsed() >= timeout => {
                break Err(format!(
                    "still running after {:.1} s; killed",
                    timeout.as_secs_f64()
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => break Err(format!("waiting for {program}: {e}")),
        }
    };
    if !reaped {
        kill_group();
        let _ = child.wait();
    }
    // Whatever the child left behind in its group holds the pipes open; it goes too.
    let joined = |thread: std::thread::JoinHandle<Vec<u8>>| {
        let deadline = Instant::now() + Duration::from_secs(2);
        while !thread.is_finished() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        if !thread.is_finished() {
            kill_group();
        }
        thread.join().unwrap_or_default()
    };
    let stdout = joined(out_thread);
    let stderr = joined(err_thread);
    let status = status.map_err(|e| {
        let said = last_line(&stderr);
        format!("{e} (last on stderr: {said})")
    })?;
    Ok(ChildOutput {
        status,
        stdout,
        stderr,
    })
}

#[cfg(test)]
#[path = "python_tests.rs"]
mod tests;
