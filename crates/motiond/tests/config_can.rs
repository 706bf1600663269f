//! CAN links in the config (`type = "socketcan"`, `type = "sim-can"`): `motiond
//! --check-config` accepts a Trinamic pack on one, and refuses every bad one with file,
//! line, column and key — a board without CAN, an identifier outside the manual's $008 to
//! $7F8, a bit rate the pack's jumpers cannot select, serial keys on a CAN link, a missing
//! or malformed interface.

use std::path::PathBuf;
use std::process::Command;

/// A SIXpack at rotary address 2 on `can0` at 500 kbit/s.
const GOOD: &str = r#"
[server]
name = "c"

[[link]]
name = "can"
type = "socketcan"
interface = "can0"
bitrate = 500000

[[device]]
name = "pack"
link = "can"
model = "tmcpack"
address = 2

[[axis]]
name = "x"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 640.0
min = 0.0
max = 100.0
max_velocity = 20.0
max_accel = 100.0
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-can-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write config");
    path
}

/// Runs `--check-config` on `text`: (exit code, stdout, stderr).
fn check(name: &str, text: &str) -> (Option<i32>, String, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(write(name, text))
        .output()
        .expect("run motiond");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

/// `text` fails with an issue on the line of the first `needle`, naming `key`, saying
/// `says`.
fn fails_at(name: &str, text: &str, needle: &str, key: &str, says: &str) {
    let (code, _, stderr) = check(name, text);
    assert_eq!(code, Some(1), "{name}: exit status; stderr:\n{stderr}");
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in config"));
    let line = text[..offset].matches('\n').count() + 1;
    let location = format!("{name}:{line}:");
    let found = stderr
        .lines()
        .any(|l| l.contains(&location) && l.contains(&format!("`{key}`")) && l.contains(says));
    assert!(
        found,
        "{name}: expected {location} `{key}` … {says:?} in:\n{stderr}"
    );
}

#[test]
fn a_pack_on_a_socketcan_link_and_on_a_sim_can_link_is_accepted() {
    let (code, stdout, stderr) = check("good.toml", GOOD);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("SocketCan"), "{stdout}");
    assert!(stdout.contains("can0"), "{stdout}");
    // The default bit rate is the pack's factory one (no jumper: 250 kbit/s).
    let (code, stdout, stderr) = check("default.toml", &GOOD.replace("bitrate = 500000\n", ""));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("bitrate: 250000"), "{stdout}");
    let sim = GOOD.replace(
        "type = \"socketcan\"\ninterface = \"can0\"\n",
        "type = \"sim-can\"\n",
    );
    let (code, stdout, stderr) = check("sim.toml", &sim);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("SimCan { bitrate: 500000 }"), "{stdout}");
    // Every jumper setting of the table (6.2).
    for rate in [125_000, 250_000, 500_000, 1_000_000] {
        let text = GOOD.replace("500000", &rate.to_string());
        let (code, _, stderr) = check(&format!("rate{rate}.toml"), &text);
        assert_eq!(code, Some(0), "{rate}: {stderr}");
    }
    let example =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/examples/tmcpack-can.toml");
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(&example)
        .output()
        .expect("run motiond");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        !stderr.contains("warning"),
        "the example is clean: {stderr}"
    );
}

/// "Take care: According to the CAN standard 0 is no valid address! Address range: $008
/// to $7F8 (in increments of 8)." — address 0 is identifier $000, and a reply address 0
/// would have the pack answer on it.
#[test]
fn a_pack_needs_its_can_identifier_in_the_manual_s_range() {
    fails_at(
        "address0.toml",
        &GOOD.replace("address = 2", "address = 0"),
        "address = 0",
        "device[0].address",
        "CAN identifier $000",
    );
    fails_at(
        "reply0.toml",
        &GOOD.replace("address = 2", "address = 2\nreply_address = 0"),
        "reply_address = 0",
        "device[0].reply_address",
        "CAN identifier $000",
    );
    // The highest, 255 → $7F8, is fine.
    let (code, _, stderr) = check(
        "address255.toml",
        &GOOD.replace("address = 2", "address = 255"),
    );
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn a_board_without_can_is_refused_on_a_can_link() {
    let qsb = GOOD
        .replace("model = \"tmcpack\"\naddress = 2", "model = \"qsb\"")
        .replace("counts_per_unit = 640.0", "counts_per_unit = 2000.0");
    fails_at(
        "qsb.toml",
        &qsb,
        "link = \"can\"",
        "device[0].link",
        "a qsb board has no CAN interface",
    );
    let spimotor = GOOD
        .replace(
            "type = \"socketcan\"\ninterface = \"can0\"\n",
            "type = \"sim-can\"\n",
        )
        .replace("model = \"tmcpack\"\naddress = 2", "model = \"spimotor\"");
    fails_at(
        "spimotor.toml",
        &spimotor,
        "link = \"can\"",
        "device[0].link",
        "a spimotor board has no CAN interface",
    );
}

#[test]
fn bad_can_link_keys_are_refused_where_they_are_written() {
    fails_at(
        "rate.toml",
        &GOOD.replace("bitrate = 500000", "bitrate = 100000"),
        "bitrate = 100000",
        "link[0].bitrate",
        "allowed: 125000, 250000, 500000, 1000000",
    );
    fails_at(
        "noif.toml",
        &GOOD.replace("interface = \"can0\"\n", ""),
        "[[link]]",
        "link[0].interface",
        "missing",
    );
    fails_at(
        "badif.toml",
        &GOOD.replace("\"can0\"", "\"/dev/can0\""),
        "interface = ",
        "link[0].interface",
        "no network interface name",
    );
    fails_at(
        "baud.toml",
        &GOOD.replace("bitrate = 500000", "bitrate = 500000\nbaud = 19200"),
        "baud = 19200",
        "link[0].baud",
        "a CAN link has bitrate",
    );
    fails_at(
        "path.toml",
        &GOOD.replace(
            "bitrate = 500000",
            "bitrate = 500000\npath = \"/dev/ttyS0\"",
        ),
        "path = ",
        "link[0].path",
        "interface",
    );
    fails_at(
        "simif.toml",
        &GOOD.replace("type = \"socketcan\"", "type = \"sim-can\""),
        "interface = ",
        "link[0].interface",
        "no interface",
    );
    // CAN keys on a serial link.
    let serial = GOOD.replace(
        "type = \"socketcan\"\ninterface = \"can0\"\nbitrate = 500000",
        "type = \"serial\"\npath = \"/dev/ttyS0\"\nbaud = 19200\nbitrate = 500000",
    );
    fails_at(
        "serialrate.toml",
        &serial,
        "bitrate = 500000",
        "link[0].bitrate",
        "bitrate is for socketcan and sim-can links",
    );
    // The serial line's keys of the pack ($40, $41) on CAN.
    fails_at(
        "switchover.toml",
        &GOOD.replace("address = 2", "address = 2\nswitchover_ms = 2"),
        "switchover_ms = 2",
        "device[0].switchover_ms",
        "a CAN link",
    );
    // `io = "tick"` is for SPI links; a CAN link keeps its I/O thread.
    fails_at(
        "tick.toml",
        &GOOD.replace("bitrate = 500000", "bitrate = 500000\nio = \"tick\""),
        "io = \"tick\"",
        "link[0].io",
        "SPI links",
    );
    fails_at(
        "unknown.toml",
        &GOOD.replace("\"socketcan\"", "\"can\""),
        "type = \"can\"",
        "link[0].type",
        "socketcan, sim-can",
    );
}

/// `motionctl list` shows a pack's identifiers on CAN: its commands on address << 3, its
/// answers on reply address << 3; the serial line's `$40` / `$41` as not sent.
#[test]
fn the_parameters_name_the_can_identifiers() {
    let config =
        motion_config::ServerConfig::parse(std::path::Path::new("good.toml"), GOOD).expect("valid");
    let rows = motion_config::boards::describe(&config);
    let value = |key: &str| {
        rows.iter()
            .find(|row| row.key == key)
            .map(|row| row.value.clone())
            .unwrap_or_else(|| panic!("no {key} row in {rows:?}"))
    };
    let reply = value("reply_address");
    assert!(
        reply.contains("CAN answers on $7F0") && reply.contains("commands on $010"),
        "{reply}"
    );
    assert!(value("switchover_ms").contains("not sent on CAN"));
    assert!(value("packet_timeout_ms").contains("not sent on CAN"));
}
