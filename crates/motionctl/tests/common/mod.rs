//! Helpers shared by the end-to-end tests: run motionctl with a deadline, read
//! `status --json`, drive it in a pseudo-terminal.
#![allow(dead_code)]

pub mod real;

use core::time::Duration;
use std::io::{Read as _, Write as _};
use std::process::{Child, Command, Output, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use iceoryx2::prelude::ipc;
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use serde_json::Value;

pub type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

pub const DEADLINE: Duration = Duration::from_secs(20);

pub fn fake(prefix: &str) -> Result<FakeServer> {
    Ok(FakeServer::start::<ipc::Service>(FakeConfig::demo(
        &unique_name(prefix),
    ))?)
}

/// The demo fake with `change` applied to its config.
pub fn fake_with(prefix: &str, change: impl FnOnce(&mut FakeConfig)) -> Result<FakeServer> {
    let mut config = FakeConfig::demo(&unique_name(prefix));
    change(&mut config);
    Ok(FakeServer::start::<ipc::Service>(config)?)
}

/// The stdout of a successful run, as JSON.
pub fn json_of(output: &Output) -> Result<Value> {
    if !output.status.success() {
        return Err(format!("motionctl failed: {output:?}").into());
    }
    Ok(serde_json::from_slice(&output.stdout)?)
}

/// Runs `args` until `check` holds for its JSON output, up to DEADLINE.
pub fn poll_json(
    server: &str,
    args: &[&str],
    mut check: impl FnMut(&Value) -> bool,
) -> Result<Value> {
    let until = Instant::now() + DEADLINE;
    loop {
        let value = json_of(&run(server, args)?)?;
        if check(&value) {
            return Ok(value);
        }
        if Instant::now() > until {
            return Err(format!("never held: {args:?} → {value}").into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Asserts a one-line error (`motionctl: …` on stderr, beside any progress lines) with
/// `status` that contains `text`.
pub fn assert_fails(output: &Output, status: i32, text: &str) {
    assert_eq!(output.status.code(), Some(status), "{output:?}");
    let all = stderr(output);
    let errors: Vec<&str> = all
        .lines()
        .filter(|line| line.starts_with("motionctl:"))
        .collect();
    assert_eq!(errors.len(), 1, "one error line: {all}");
    assert!(errors[0].contains(text), "{text:?} not in {all}");
}

pub fn command(server: &str, args: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_motionctl"));
    command.arg("--server").arg(server).args(args);
    command
}

/// Waits for `child` up to `deadline`, killing it past that. Its output is read while it
/// runs: a child that writes more than a pipe holds (`list --json` of the simulated robot
/// is above 64 KiB) would otherwise block on its write and never finish.
pub fn finish(mut child: Child, deadline: Duration) -> Result<Output> {
    let readers = read_output(&mut child);
    let until = Instant::now() + deadline;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if Instant::now() > until {
            child.kill()?;
            let status = child.wait()?;
            let output = collect_output(status, readers);
            return Err(format!("motionctl did not finish in {deadline:?}: {output:?}").into());
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Ok(collect_output(status, readers))
}

type Readers = (
    Option<std::thread::JoinHandle<Vec<u8>>>,
    Option<std::thread::JoinHandle<Vec<u8>>>,
);

/// Threads reading the child's stdout and stderr to their ends.
fn read_output(child: &mut Child) -> Readers {
    fn drain(mut pipe: impl std::io::Read + Send + 'static) -> std::thread::JoinHandle<Vec<u8>> {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            bytes
        })
    }
    (
        child.stdout.take().map(drain),
        child.stderr.take().map(drain),
    )
}

fn collect_output(status: std::process::ExitStatus, (out, err): Readers) -> Output {
    let join = |reader: Option<std::thread::JoinHandle<Vec<u8>>>| {
        reader.and_then(|r| r.join().ok()).unwrap_or_default()
    };
    Output {
        status,
        stdout: join(out),
        stderr: join(err),
    }
}

pub fn run(server: &str, args: &[&str]) -> Result<Output> {
    let child = command(server, args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    finish(child, DEADLINE)
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn status_json(server: &str) -> Result<Value> {
    let output = run(server, &["status", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    Ok(serde_json::from_slice(&output.stdout)?)
}

pub fn axis_field(status: &Value, axis: usize, field: &str) -> Value {
    status["axes"][axis][field].clone()
}

/// Runs motionctl in a pseudo-terminal, waits until the screen shows `expect`, types
/// `keys`, and returns the exit status and everything drawn.
pub fn in_pty(server: &str, args: &[&str], expect: &str, keys: &[u8]) -> Result<(Output, String)> {
    use nix::pty::{Winsize, openpty};
    let size = Winsize {
        ws_row: 30,
        ws_col: 120,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    let pty = openpty(Some(&size), None)?;
    let child = command(server, args)
        .env("TERM", "xterm-256color")
        .stdin(Stdio::from(pty.slave.try_clone()?))
        .stdout(Stdio::from(pty.slave.try_clone()?))
        .stderr(Stdio::piped())
        .spawn()?;
    drop(pty.slave);
    let mut reader = std::fs::File::from(pty.master);
    let mut writer = reader.try_clone()?;
    let screen = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&screen);
    std::thread::spawn(move || {
        let mut buffer = [0u8; 4096];
        while let Ok(read @ 1..) = reader.read(&mut buffer) {
            if let (Ok(mut screen), Some(bytes)) = (sink.lock(), buffer.get(..read)) {
                screen.extend_from_slice(bytes);
            }
        }
    });
    let drawn = || {
        screen
            .lock()
            .map(|bytes| String::from_utf8_lossy(&bytes).into_owned())
            .unwrap_or_default()
    };
    let until = Instant::now() + DEADLINE;
    while !drawn().contains(expect) {
        if Instant::now() > until {
            let mut child = child;
            child.kill()?;
            return Err(format!("never drew {expect:?}: {:?}", drawn()).into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    writer.write_all(keys)?;
    let output = finish(child, DEADLINE)?;
    Ok((output, drawn()))
}
