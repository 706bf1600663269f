//! The tmcpack device key `baud` in the config: a rate the pack's `$40` divisor reaches is
//! taken, any other fails `motiond --check-config` with file:line:column, the key and the
//! rates allowed; every pack on a link with a `baud` has the same one.

use std::path::PathBuf;
use std::process::Command;

const TWO_PACKS: &str = r#"
[server]
name = "t"

[[link]]
name = "bus"
type = "sim"
baud = 19200

[[device]]
name = "pack_a"
link = "bus"
model = "tmcpack"
address = 1
BAUD_A

[[device]]
name = "pack_b"
link = "bus"
model = "tmcpack"
address = 2
BAUD_B

[[axis]]
name = "x"
device = "pack_a"
channel = 0
unit = "mm"
counts_per_unit = 640.0
min = 0.0
max = 100.0
max_velocity = 20.0
max_accel = 100.0
"#;

fn config(a: &str, b: &str) -> String {
    TWO_PACKS.replace("BAUD_A", a).replace("BAUD_B", b)
}

/// Runs `--check-config` on `text` and returns (exit code, stderr).
fn check(name: &str, text: &str) -> (Option<i32>, String) {
    let dir = std::env::temp_dir().join(format!("motiond-baud-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path: PathBuf = dir.join(name);
    std::fs::write(&path, text).expect("write config");
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(&path)
        .output()
        .expect("run motiond");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// The 1-based line of the `nth` occurrence of `needle`.
fn line_of(text: &str, needle: &str, nth: usize) -> usize {
    let offset = text
        .match_indices(needle)
        .nth(nth)
        .expect("in the config")
        .0;
    text[..offset].matches('\n').count() + 1
}

fn fails_at(name: &str, text: &str, needle: &str, nth: usize, key: &str, says: &str) {
    let (code, stderr) = check(name, text);
    assert_eq!(code, Some(1), "{name}:\n{stderr}");
    let location = format!("{name}:{}:", line_of(text, needle, nth));
    assert!(
        stderr
            .lines()
            .any(|l| l.contains(&location) && l.contains(key) && l.contains(says)),
        "{name}: expected {location} {key} … {says:?} in:\n{stderr}"
    );
}

#[test]
fn a_listed_rate_on_every_pack_of_the_link_passes() {
    let text = config("baud = 115200", "baud = 115200");
    let (code, stderr) = check("good.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
    let text = config("baud = 57600", "baud = 57600");
    assert_eq!(check("good57.toml", &text).0, Some(0));
}

#[test]
fn a_rate_the_manual_does_not_give_is_refused_with_the_rates_it_does() {
    for (bad, says) in [
        ("230400", "its divisor 5 gives 250000 baud"),
        ("100000", "allowed: "),
        ("0", "allowed: "),
        ("-1", "allowed: "),
    ] {
        let text = config(&format!("baud = {bad}"), &format!("baud = {bad}"));
        fails_at("bad.toml", &text, "baud = ", 1, "device[0].baud", says);
    }
    let text = config("baud = 230400", "baud = 230400");
    let (_, stderr) = check("list.toml", &text);
    assert!(
        stderr.contains("9600, 14400, 19200, 28800, 38400, 57600, 76800, 115200"),
        "{stderr}"
    );
    let text = config("baud = \"fast\"", "");
    fails_at("type.toml", &text, "\"fast\"", 0, "baud", "invalid type");
}

#[test]
fn every_pack_on_the_link_talks_at_the_one_rate() {
    let text = config("baud = 115200", "");
    fails_at(
        "one.toml",
        &text,
        "[[device]]",
        1,
        "device[1].baud",
        "has no baud, but `pack_a` switches the link to 115200 baud",
    );
    let text = config("baud = 115200", "baud = 57600");
    fails_at(
        "two.toml",
        &text,
        "baud = 57600",
        0,
        "device[1].baud",
        "has baud = 57600",
    );
}
