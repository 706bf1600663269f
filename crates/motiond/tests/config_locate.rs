//! Which config `motiond` runs without `--config` (issue 28, "Installed layout"): the
//! first log line names the file and where it came from; with nothing to run, one line
//! says what to pass.

mod support;

use std::io::{BufRead as _, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};

use motion_config::locate::INSTALLED_CONFIG;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

/// A fresh empty directory to run motiond in (no `config/sim.toml` below it).
fn empty_dir() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(support::unique_name("locate-cwd"));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    dir
}

fn motiond() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_motiond"));
    command
        .env_remove("MOTIOND_CONFIG")
        .env("MOTIOND_LOG", "info");
    command
}

#[test]
fn motiond_config_names_the_file_it_runs_in_its_first_log_line() {
    let name = support::unique_name("locate");
    let config = support::stepper_config(&name, "");
    let dir = empty_dir();
    let mut child = motiond()
        .current_dir(dir.as_path())
        .env("MOTIOND_CONFIG", &config)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("motiond starts");
    let stderr = child.stderr.take().expect("stderr piped");
    let mut lines = BufReader::new(stderr).lines();
    let first = lines.next().and_then(Result::ok).unwrap_or_default();
    // Up: the tick thread reported its real-time set-up (SIGTERM is handled from then on).
    let up = lines
        .by_ref()
        .map_while(Result::ok)
        .any(|line| line.contains("real-time:"));
    assert!(up, "motiond did not come up after {first:?}");
    kill(Pid::from_raw(child.id() as i32), Signal::SIGTERM).expect("SIGTERM");
    let status = child.wait().expect("motiond ends");
    assert!(
        first.contains(&format!(
            "config {} (named by $MOTIOND_CONFIG)",
            config.display()
        )),
        "first line: {first:?}"
    );
    assert!(status.success(), "a clean shutdown on SIGTERM: {status:?}");
}

#[test]
fn motiond_with_a_missing_named_config_says_which_and_opens_nothing() {
    let dir = empty_dir();
    let missing = dir.as_path().join("nowhere.toml");
    let output = motiond()
        .current_dir(dir.as_path())
        .env("MOTIOND_CONFIG", &missing)
        .output()
        .expect("motiond runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    let first = stderr.lines().next().unwrap_or_default();
    assert!(
        first.contains(&format!("config {}", missing.display())),
        "{stderr}"
    );
    assert!(stderr.contains("is not a usable config"), "{stderr}");
}

#[test]
fn motiond_without_any_config_says_what_to_pass_in_one_line() {
    if Path::new(INSTALLED_CONFIG).exists() {
        eprintln!("skipped: this machine has {INSTALLED_CONFIG}, which motiond would run");
        return;
    }
    let dir = empty_dir();
    let output = motiond()
        .current_dir(dir.as_path())
        .output()
        .expect("motiond runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("--config FILE") && stderr.contains("MOTIOND_CONFIG"),
        "{stderr}"
    );
}
