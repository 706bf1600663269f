//! Running the `motion-sim` binary from a test: start it, read the path it prints, stop
//! it with SIGTERM. Everything has a timeout, so a broken binary fails a test instead of
//! hanging it.
#![allow(dead_code)] // each test file uses a different part

use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use motion_link::Link;

/// A running `motion-sim`.
pub struct Served {
    child: Child,
    /// The first line it printed on stdout (the pty or socket path).
    pub first_line: String,
    stderr: Arc<Mutex<String>>,
}

impl Served {
    /// Starts `motion-sim ARGS` and waits (at most 10 s) for its first line of stdout.
    pub fn start(args: &[&str]) -> Self {
        let mut child = Command::new(env!("CARGO_BIN_EXE_motion-sim"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn motion-sim");
        let stderr = Arc::new(Mutex::new(String::new()));
        if let Some(mut pipe) = child.stderr.take() {
            let sink = stderr.clone();
            std::thread::spawn(move || {
                let mut buf = [0u8; 4096];
                while let Ok(n) = pipe.read(&mut buf) {
                    if n == 0 {
                        break;
                    }
                    sink.lock()
                        .unwrap()
                        .push_str(&String::from_utf8_lossy(&buf[..n]));
                }
            });
        }
        let stdout = child.stdout.take().expect("stdout");
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut lines = BufReader::new(stdout).lines();
            let _ = tx.send(lines.next());
            // Keep reading so the binary never blocks on a full pipe.
            for _ in lines {}
        });
        let first = rx.recv_timeout(Duration::from_secs(10));
        let mut served = Self {
            child,
            first_line: String::new(),
            stderr,
        };
        match first {
            Ok(Some(Ok(line))) => served.first_line = line,
            other => {
                let _ = served.child.kill();
                std::thread::sleep(Duration::from_millis(100));
                panic!(
                    "motion-sim printed no path ({other:?}); stderr:\n{}",
                    served.stderr()
                );
            }
        }
        served
    }

    /// What the binary logged so far.
    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// Sends SIGTERM and checks that the binary exits with status 0 within `timeout`.
    pub fn stop_and_check(mut self, timeout: Duration) {
        let pid = nix::unistd::Pid::from_raw(i32::try_from(self.child.id()).expect("pid"));
        nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM).expect("SIGTERM");
        let deadline = Instant::now() + timeout;
        loop {
            if let Some(status) = self.child.try_wait().expect("wait") {
                assert!(
                    status.success(),
                    "exit status {status}; stderr:\n{}",
                    self.stderr()
                );
                return;
            }
            assert!(
                Instant::now() < deadline,
                "motion-sim did not exit after SIGTERM; stderr:\n{}",
                self.stderr()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        if matches!(self.child.try_wait(), Ok(None)) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// A fresh path in the temp directory, unique to this process.
pub fn temp_path(name: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("motion-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_file(&path);
    path
}

/// One SPI transaction on `link`: writes `mosi`, waits (at most 5 s) for as many MISO bytes.
pub fn transact(link: &mut dyn Link, mosi: &[u8]) -> Vec<u8> {
    let start = Instant::now();
    link.write(start.elapsed(), mosi).expect("transaction");
    let mut miso = Vec::new();
    let mut buf = [0u8; 256];
    while miso.len() < mosi.len() {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "no answer: {miso:02x?}"
        );
        let n = link.read(start.elapsed(), &mut buf).expect("read");
        miso.extend_from_slice(&buf[..n]);
        if n == 0 {
            std::thread::sleep(Duration::from_micros(200));
        }
    }
    miso
}

/// Reads from a stream link until `done` says the bytes so far are complete, or `timeout`.
pub fn read_until(
    link: &mut dyn Link,
    timeout: Duration,
    mut done: impl FnMut(&[u8]) -> bool,
) -> Vec<u8> {
    let start = Instant::now();
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    while !done(&got) && start.elapsed() < timeout {
        let n = link.read(start.elapsed(), &mut buf).expect("read");
        got.extend_from_slice(&buf[..n]);
        if n == 0 {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    got
}
