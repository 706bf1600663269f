//! The files of `deploy/`: the systemd unit passes `systemd-analyze verify` (where systemd is
//! installed) and says what issues 14 and 40 ask of it; the udev rules and the tmpfiles.d
//! lines parse.

use std::path::{Path, PathBuf};
use std::process::Command;

fn deploy(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("deploy")
        .join(file)
}

fn read(file: &str) -> String {
    std::fs::read_to_string(deploy(file)).unwrap_or_else(|e| panic!("deploy/{file}: {e}"))
}

/// `Key=value` lines of one section of a unit file (comments and other sections skipped).
fn section<'a>(unit: &'a str, name: &str) -> Vec<(&'a str, &'a str)> {
    let mut current = "";
    let mut out = Vec::new();
    for line in unit.lines().map(str::trim) {
        if line.starts_with('#') || line.is_empty() {
            continue;
        }
        if line.starts_with('[') {
            current = line;
            continue;
        }
        if current == name
            && let Some((key, value)) = line.split_once('=')
        {
            out.push((key, value));
        }
    }
    out
}

#[test]
fn the_unit_runs_motiond_as_issue_14_asks() {
    let unit = read("motiond.service");
    let service = section(&unit, "[Service]");
    let value = |key: &str| -> Vec<&str> {
        service
            .iter()
            .filter(|(k, _)| *k == key)
            .map(|(_, v)| *v)
            .collect()
    };
    for (key, expected) in [
        ("Type", "notify"),
        ("User", "motion"),
        ("Group", "motion"),
        ("RemoveIPC", "no"),
        ("PrivateTmp", "no"),
        ("LimitMEMLOCK", "infinity"),
        ("AmbientCapabilities", "CAP_SYS_NICE CAP_IPC_LOCK"),
        ("CapabilityBoundingSet", "CAP_SYS_NICE CAP_IPC_LOCK"),
        ("NoNewPrivileges", "yes"),
        // Issue 40: the server's state and black box in a directory only its user writes.
        ("StateDirectory", "motiond"),
        ("StateDirectoryMode", "0750"),
    ] {
        assert_eq!(value(key), [expected], "{key}");
    }
    for key in ["WatchdogSec", "LimitRTPRIO", "ExecStart", "TimeoutStartSec"] {
        assert_eq!(value(key).len(), 1, "{key} set once");
    }
    assert!(value("ExecStart")[0].contains("--config /etc/motiond/motiond.toml"));
    assert!(value("DynamicUser").is_empty(), "no DynamicUser");
    assert!(
        !value("RestrictRealtime").contains(&"yes"),
        "SCHED_FIFO must stay allowed"
    );
    assert_eq!(
        section(&unit, "[Install]"),
        [("WantedBy", "multi-user.target")]
    );
}

#[test]
fn systemd_analyze_verifies_the_unit() {
    let Ok(output) = Command::new("systemd-analyze").arg("--version").output() else {
        eprintln!(
            "systemd-analyze is not installed: run `systemd-analyze verify deploy/motiond.service` \
             on a machine with systemd (apt-get install systemd)"
        );
        return;
    };
    assert!(output.status.success());
    // The unit names the installed binary; verify checks that ExecStart is executable, so a
    // copy points it at an executable that exists here (this test).
    let exe = std::env::current_exe().expect("own path");
    let unit = read("motiond.service").replace("/usr/local/bin/motiond", &exe.to_string_lossy());
    let dir = std::env::temp_dir().join(format!("motiond-unit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let copy = dir.join("motiond.service");
    std::fs::write(&copy, unit).expect("write the copy");
    let output = Command::new("systemd-analyze")
        .arg("verify")
        .arg(&copy)
        .output()
        .expect("run systemd-analyze");
    let _ = std::fs::remove_dir_all(&dir);
    let stderr = String::from_utf8_lossy(&output.stderr);
    // Warnings (an unknown key, a bad value) are printed without failing: none allowed.
    let complaints: Vec<&str> = stderr
        .lines()
        .filter(|line| line.contains("motiond.service"))
        .collect();
    assert!(
        output.status.success() && complaints.is_empty(),
        "systemd-analyze verify: {}\n{stderr}",
        output.status
    );
}

/// udev's operators and the keys our rules use.
const UDEV_OPERATORS: [&str; 6] = ["==", "!=", "+=", "-=", ":=", "="];
const UDEV_KEYS: [&str; 10] = [
    "ACTION",
    "KERNEL",
    "SUBSYSTEM",
    "DRIVER",
    "ATTR",
    "ATTRS",
    "GROUP",
    "MODE",
    "SYMLINK",
    "DRIVERS",
];

/// One `KEY{attr}OP"value"` of a udev rule.
fn udev_pair(pair: &str) -> Result<(&str, &str, &str), String> {
    let pair = pair.trim();
    let at = pair
        .find(['=', '!', '+', '-', ':'])
        .ok_or_else(|| format!("`{pair}`: no operator"))?;
    let (key, rest) = pair.split_at(at);
    let op = UDEV_OPERATORS
        .iter()
        .find(|op| rest.starts_with(**op))
        .ok_or_else(|| format!("`{pair}`: bad operator"))?;
    let value = &rest[op.len()..];
    if !(value.len() >= 2 && value.starts_with('"') && value.ends_with('"')) {
        return Err(format!("`{pair}`: the value is not quoted"));
    }
    let name = key.split('{').next().unwrap_or(key);
    if !UDEV_KEYS.contains(&name) {
        return Err(format!("`{pair}`: unknown key {name}"));
    }
    if key.contains('{') != key.ends_with('}') {
        return Err(format!("`{pair}`: unbalanced braces"));
    }
    Ok((key, op, &value[1..value.len() - 1]))
}

#[test]
fn the_udev_rules_parse_and_give_the_devices_to_group_motion() {
    let rules = read("udev/60-motiond.rules");
    let mut rules_seen = 0;
    for line in rules.lines().map(str::trim) {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        rules_seen += 1;
        let pairs: Vec<(&str, &str, &str)> = line
            .split(", ")
            .map(|pair| udev_pair(pair).unwrap_or_else(|e| panic!("{e} in: {line}")))
            .collect();
        let matches = pairs.iter().filter(|(_, op, _)| *op == "==").count();
        let assigns = pairs.iter().filter(|(_, op, _)| *op != "==").count();
        assert!(matches > 0 && assigns > 0, "match and assign: {line}");
        if pairs.iter().any(|(key, _, _)| *key == "GROUP") {
            assert!(pairs.contains(&("GROUP", "=", "motion")), "{line}");
            assert!(pairs.contains(&("MODE", "=", "0660")), "{line}");
        }
    }
    assert!(rules_seen >= 5, "{rules_seen} rules");
    for needed in [
        "KERNEL==\"cpu_dma_latency\"",
        "ATTR{latency_timer}=\"1\"",
        "SUBSYSTEM==\"spidev\"",
        "ATTRS{idVendor}==\"0403\"",
        "ATTRS{idVendor}==\"10c4\"",
    ] {
        assert!(rules.contains(needed), "{needed} missing");
    }
    // The parser refuses what udev refuses.
    for bad in [
        "GROUP=motion",
        "GROUPE=\"motion\"",
        "ATTR{x=\"1\"",
        "KERNEL\"x\"",
    ] {
        assert!(udev_pair(bad).is_err(), "{bad} accepted");
    }
}

#[test]
fn the_tmpfiles_lines_create_iceoryx2_s_and_the_state_directory_for_motion() {
    let text = read("tmpfiles.d/motiond.conf");
    let lines: Vec<Vec<&str>> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| l.split_whitespace().collect())
        .collect();
    assert_eq!(
        lines,
        [
            vec!["d", "/tmp/iceoryx2", "0750", "motion", "motion", "-"],
            vec!["x", "/tmp/iceoryx2"],
            vec!["d", "/var/lib/motiond", "0750", "motion", "motion", "-"],
        ]
    );
}
