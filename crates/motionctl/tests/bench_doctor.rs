//! `motionctl bench` and `motionctl doctor` as a user runs them: the bench's command line,
//! its refusal without a server, a short smoke run against a real motiond (its baseline
//! peer is motionctl re-executed; its Python client rows when `target/py-venv` exists);
//! the doctor on this machine and on a fake root.

mod common;

use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::path::Path;
use std::process::{Command, Stdio};

use common::real::{RealServer, motiond_binary};
use common::{Result, assert_fails, finish, stdout};
use serde_json::Value;

fn motionctl(args: &[&str]) -> Result<std::process::Output> {
    let child = Command::new(env!("CARGO_BIN_EXE_motionctl"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    finish(child, Duration::from_secs(60))
}

/// A QSB and its axis on the link `bus`: what makes a config one motiond would run.
const QSB_ON_BUS: &str = "\n[[device]]\nname = \"qsb\"\nlink = \"bus\"\nmodel = \"qsb\"\n\n[[axis]]\nname = \"x\"\ndevice = \"qsb\"\nchannel = 0\nunit = \"mm\"\ncounts_per_unit = 100.0\nmin = -100.0\nmax = 100.0\nmax_velocity = 50.0\nmax_accel = 500.0\n";

#[test]
fn bench_help_lists_the_suite_s_options_and_hides_the_peer() -> Result {
    let output = motionctl(&["bench", "--help"])?;
    assert!(output.status.success(), "{output:?}");
    let help = stdout(&output);
    for option in [
        "--server",
        "--duration",
        "--json",
        "--out",
        "--plot",
        "--rt-priority",
        "--cpu",
        "--command",
        "--axes-sweep",
        "--command-to-wire",
        "--motiond",
        "--python",
    ] {
        assert!(help.contains(option), "{option} missing:\n{help}");
    }
    assert!(
        !help.contains("--peer") && !help.contains("--motion-bench-peer"),
        "{help}"
    );
    // The peer's own command line is checked by the library, not taken as a subcommand.
    let output = motionctl(&["--motion-bench-peer", "ticking", "x", "0"])?;
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    assert!(
        String::from_utf8_lossy(&output.stderr).contains("usage: --motion-bench-peer"),
        "{output:?}"
    );
    Ok(())
}

#[test]
fn bench_without_a_server_exits_3() -> Result {
    let output = motionctl(&[
        "--server",
        "no-such-server-here",
        "bench",
        "--duration",
        "200ms",
    ])?;
    assert_fails(
        &output,
        3,
        "is motiond running with [server] name = \"no-such-server-here\"",
    );
    Ok(())
}

/// The smallest server motiond accepts: one simulated SPI_motor stepper.
const ONE_AXIS: &str = "[server]\nname = \"demo\"\ntick_hz = 1000\n\n[[link]]\nname = \"spi\"\ntype = \"sim\"\n\n[[device]]\nname = \"m\"\nlink = \"spi\"\nmodel = \"spimotor\"\n\n[[axis]]\nname = \"a\"\ndevice = \"m\"\nchannel = 0\nunit = \"step\"\ncounts_per_unit = 1.0\nmin = -100.0\nmax = 100.0\nmax_velocity = 100.0\nmax_accel = 1000.0\n";

#[test]
fn bench_smoke_run_prints_ratios_beside_their_baselines() -> Result {
    if motiond_binary().is_err() {
        eprintln!("skipped: no motiond binary (build it, or run cargo test --workspace)");
        return Ok(());
    }
    let server = RealServer::start_with(ONE_AXIS)?;
    let plots = std::env::temp_dir().join(format!("motionctl-bench-plots-{}", std::process::id()));
    let plots_arg = plots.to_str().ok_or("temp path")?;
    let output = motionctl(&[
        "--server",
        &server.name,
        "bench",
        "--duration",
        "300ms",
        "--json",
        "--plot",
        plots_arg,
    ])?;
    assert!(output.status.success(), "{output:?}\n{}", server.log());
    check_plots(&plots)?;
    let report: Value = serde_json::from_slice(&output.stdout)?;
    let rows = report["rows"].as_array().ok_or("no rows")?;
    assert!(rows.len() >= 8, "{report:#}");
    // Ratios with their baselines: every ns row of the eight has both sides measured by
    // the peer (motionctl re-executed) or the sleeper.
    let with_ratio: Vec<&Value> = rows
        .iter()
        .filter(|row| row["ratio_p50"].is_f64() && row["ratio_p99"].is_f64())
        .collect();
    assert!(with_ratio.len() >= 3, "{report:#}");
    for row in &with_ratio {
        assert!(row["baseline"]["samples"].as_u64() > Some(0), "{row:#}");
        assert!(row["ours"]["samples"].as_u64() > Some(0), "{row:#}");
    }
    // The command-to-wire phase found the motiond beside motionctl.
    assert!(
        rows.iter().any(|row| row["figure"]
            .as_str()
            .is_some_and(|f| f.contains("first byte"))),
        "{report:#}"
    );
    check_python_rows(&report, rows);
    Ok(())
}

/// `--plot DIR`: one SVG per figure (the distribution files beside them), index.html
/// showing each; the same pictures as plots_in_browser.rs checks in Chromium.
fn check_plots(dir: &Path) -> Result {
    let index = std::fs::read_to_string(dir.join("index.html"))?;
    let svgs: Vec<String> = std::fs::read_dir(dir)?
        .filter_map(|entry| entry.ok())
        .map(|entry| entry.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".svg"))
        .collect();
    // At least the eight rows' figures that have histograms of the bench's own.
    assert!(svgs.len() >= 8, "{svgs:?}");
    assert_eq!(index.matches("<img ").count(), svgs.len(), "{index}");
    for name in &svgs {
        assert!(
            index.contains(&format!("src=\"{name}\"")),
            "{name} not shown"
        );
        let svg = std::fs::read_to_string(dir.join(name))?;
        assert!(svg.starts_with("<svg ") && svg.contains("p99.9"), "{name}");
    }
    let rtt = std::fs::read_to_string(dir.join("command-rtt.svg"))?;
    assert!(
        rtt.contains("command-rtt-baseline-ticking"),
        "baseline overlaid"
    );
    std::fs::remove_dir_all(dir)?;
    Ok(())
}

/// The Python client phase: with `target/py-venv` (which `./scripts/test` creates before
/// the Rust tests) motionctl finds it beside its target directory and adds two rows with
/// ratios; without it the report says how to get them.
fn check_python_rows(report: &Value, rows: &[Value]) {
    let venv = Path::new(env!("CARGO_BIN_EXE_motionctl"))
        .parent()
        .and_then(Path::parent)
        .map(|target| target.join("py-venv/bin/python"))
        .unwrap_or_default();
    let python: Vec<&Value> = rows
        .iter()
        .filter(|row| {
            row["figure"]
                .as_str()
                .is_some_and(|f| f.contains("Python client"))
        })
        .collect();
    let notes = report["notes"].to_string();
    if !venv.is_file() {
        eprintln!(
            "Python rows not checked: no {} (./scripts/test creates it)",
            venv.display()
        );
        assert!(python.is_empty(), "{report:#}");
        assert!(
            notes.contains("Python client rows: skipped") && notes.contains("--python PATH"),
            "{notes}"
        );
        return;
    }
    assert_eq!(python.len(), 2, "{report:#}");
    for row in &python {
        assert!(row["ours"]["samples"].as_u64() > Some(0), "{row:#}");
        assert!(row["baseline"]["samples"].as_u64() > Some(0), "{row:#}");
        assert!(
            row["ratio_p50"].is_f64() && row["ratio_p99"].is_f64(),
            "{row:#}"
        );
    }
    let frames = python[0]["figure"].as_str().unwrap_or_default();
    assert!(frames.starts_with("frame delivery"), "{frames}");
    let note = python[1]["note"].as_str().unwrap_or_default();
    // The probe (Stop on axis 1 of a 1-axis server) is answered UnknownAxis, never else.
    assert!(
        note.contains("UNKNOWN_AXIS ×") && note.contains("other reasons 0"),
        "{note}"
    );
    assert!(
        report["context"]["python client"]
            .as_str()
            .is_some_and(|c| c.contains("iceoryx2 0.10")),
        "{report:#}"
    );
}

const IDS: [&str; 16] = [
    "kernel-preemption",
    "rt-throttling",
    "cpu-governor",
    "cpu-isolation",
    "irq-affinity",
    "cpu-dma-latency",
    "rtprio-limit",
    "memlock-limit",
    "sched-fifo",
    "usb-latency-timer",
    "device-access",
    "iceoryx2-shm",
    "logind-removeipc",
    "clocksource",
    "swap",
    "wakeup-latency",
];

#[test]
fn doctor_on_this_machine_prints_every_check_with_a_value() -> Result {
    let output = motionctl(&["doctor", "--wakeup", "300ms"])?;
    let text = stdout(&output);
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| ["PASS ", "WARN ", "FAIL "].iter().any(|s| l.starts_with(s)))
        .collect();
    assert_eq!(lines.len(), IDS.len(), "{text}");
    for (line, id) in lines.iter().zip(IDS) {
        let rest = line.get(5..).unwrap_or_default().trim_start();
        let value = rest
            .strip_prefix(id)
            .ok_or(format!("{id} expected: {line}"))?;
        assert!(!value.trim().is_empty(), "no value: {line}");
    }
    let fails = lines.iter().filter(|l| l.starts_with("FAIL")).count();
    assert_eq!(
        output.status.code(),
        Some(if fails > 0 { 1 } else { 0 }),
        "{output:?}"
    );
    assert!(text.contains(&format!("{fails} fail")), "{text}");
    Ok(())
}

#[test]
fn doctor_json_on_a_fake_root_gives_every_check_a_status_value_and_fix() -> Result {
    let root = std::env::temp_dir().join(format!("motionctl-doctor-e2e-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let file = |path: &str, text: &str| -> Result {
        let real = root.join(path.trim_start_matches('/'));
        std::fs::create_dir_all(real.parent().ok_or("parent")?)?;
        std::fs::write(real, text)?;
        Ok(())
    };
    file("/proc/version", "Linux version 6.1.0-rt #1 SMP PREEMPT_RT")?;
    file("/proc/sys/kernel/sched_rt_runtime_us", "950000")?;
    file(
        "/proc/swaps",
        "Filename Type Size Used Priority\n/dev/sda2 partition 100 0 -2\n",
    )?;
    file(
        "/proc/self/status",
        "Uid:\t998\t998\t998\t998\nGid:\t998\t998\t998\t998\nGroups:\t998\nCapEff:\t0000000000000000\n",
    )?;
    file(
        "/proc/self/limits",
        "Max locked memory 65536 65536 bytes\nMax realtime priority 0 0\n",
    )?;
    file("/sys/devices/system/cpu/online", "0-3")?;
    file(
        "/sys/devices/system/clocksource/clocksource0/current_clocksource",
        "hpet",
    )?;
    file("/dev/ttyUSB0", "")?;
    file("/sys/bus/usb-serial/devices/ttyUSB0/latency_timer", "16")?;
    std::fs::create_dir_all(root.join("dev/shm"))?;
    std::fs::set_permissions(
        root.join("dev/shm"),
        std::fs::Permissions::from_mode(0o1777),
    )?;
    let config = root.join("motiond.toml");
    std::fs::write(
        &config,
        format!(
            "[server]\nname = \"cell\"\nrt_priority = 80\ncpu = 3\nlock_memory = true\n\n[[link]]\nname = \"bus\"\ntype = \"serial\"\npath = \"/dev/ttyUSB0\"\nbaud = 230400\n{QSB_ON_BUS}"
        ),
    )?;
    let output = motionctl(&[
        "doctor",
        "--root",
        &root.to_string_lossy(),
        "--config",
        &config.to_string_lossy(),
        "--json",
        "--wakeup",
        "0s",
    ])?;
    let _ = std::fs::remove_dir_all(&root);
    let report: Value = serde_json::from_slice(&output.stdout)?;
    let checks = report["checks"].as_array().ok_or("no checks")?;
    let ids: Vec<&str> = checks.iter().filter_map(|c| c["id"].as_str()).collect();
    assert_eq!(ids, IDS);
    let status = |id: &str| {
        checks
            .iter()
            .find(|c| c["id"] == id)
            .and_then(|c| c["status"].as_str())
            .unwrap_or_default()
            .to_owned()
    };
    for check in checks {
        let passed = check["status"] == "pass";
        assert!(
            ["pass", "warn", "fail"].contains(&check["status"].as_str().unwrap_or("")),
            "{check}"
        );
        assert!(
            check["value"].as_str().is_some_and(|v| !v.is_empty()),
            "{check}"
        );
        assert_eq!(
            check["fix"].is_null(),
            passed,
            "a fix exactly when not passed: {check}"
        );
    }
    // What the fake root says, read through the binary.
    assert_eq!(status("kernel-preemption"), "pass");
    assert_eq!(status("clocksource"), "fail");
    assert_eq!(status("usb-latency-timer"), "fail");
    assert_eq!(status("rtprio-limit"), "fail");
    assert_eq!(status("memlock-limit"), "fail");
    assert_eq!(status("swap"), "warn");
    assert_eq!(status("cpu-isolation"), "warn");
    assert_eq!(status("wakeup-latency"), "warn");
    assert_eq!(
        report["summary"]["fail"].as_u64(),
        Some(checks.iter().filter(|c| c["status"] == "fail").count() as u64)
    );
    assert_eq!(output.status.code(), Some(1), "failed checks: exit 1");
    assert!(
        report["config"]
            .as_str()
            .is_some_and(|c| c.ends_with("motiond.toml"))
    );
    Ok(())
}

#[test]
fn doctor_refuses_a_bad_config_with_its_path() -> Result {
    let path =
        std::env::temp_dir().join(format!("motionctl-doctor-bad-{}.toml", std::process::id()));
    // Valid but for the priority: the doctor reads the config as motiond does and says
    // what motiond would refuse.
    std::fs::write(
        &path,
        format!(
            "[server]\nname = \"cell\"\nrt_priority = 0\n\n[[link]]\nname = \"bus\"\ntype = \"serial\"\npath = \"/dev/ttyUSB0\"\nbaud = 230400\n{QSB_ON_BUS}"
        ),
    )?;
    let output = motionctl(&[
        "doctor",
        "--config",
        &path.to_string_lossy(),
        "--wakeup",
        "0s",
    ])?;
    let _ = std::fs::remove_file(&path);
    assert_fails(&output, 1, "rt_priority");
    assert!(stdout(&output).is_empty(), "{output:?}");
    Ok(())
}
