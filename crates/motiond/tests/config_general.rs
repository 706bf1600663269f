//! The keys every model has (supervision, stop category, the `home` table and its aliases,
//! claim leases) and `[[signal]]` tables: each malformed value fails `motiond
//! --check-config` with `file:line:column`, the dotted key and what is allowed.

use std::path::PathBuf;
use std::process::Command;

/// A QuadQuad2Drv with two axes and a QSB-M with one, on sim links.
const GOOD: &str = r#"
[server]
name = "general"
claim_lease_ms = 500

[[link]]
name = "spi"
type = "sim"

[[link]]
name = "usb"
type = "sim"

[[device]]
name = "drive"
link = "spi"
model = "qq2drv"

[[device]]
name = "io_board"
link = "usb"
model = "qsb"

[[axis]]
name = "a"
device = "drive"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -50.0
max = 50.0
max_velocity = 10.0
max_accel = 100.0
following_error = 0.5
overspeed_factor = 2.0
estop = "stop-off"
home = { input = "home", direction = "positive", max_travel = 120.0, position = 50.0 }

[[axis]]
name = "b"
device = "drive"
channel = 1
unit = "mm"
counts_per_unit = 100.0
min = -50.0
max = 50.0
max_velocity = 10.0
max_accel = 100.0

[[axis]]
name = "feeder"
device = "io_board"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 10.0
max_accel = 100.0

[[signal]]
name = "switch"
device = "drive"
pin = "in2"
kind = "digital-in"
invert = true

[[signal]]
name = "lamp"
device = "io_board"
pin = "io0"
kind = "digital-out"
safe = false
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-general-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write config");
    path
}

/// Runs `--check-config`: (exit code, stderr).
fn check(name: &str, text: &str) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(write(name, text))
        .output()
        .expect("run motiond");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

fn line_of(text: &str, needle: &str) -> usize {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in the config"));
    text[..offset].matches('\n').count() + 1
}

/// `text` fails with an issue on the line of `needle` about `key`, saying `says`.
fn fails(name: &str, text: &str, needle: &str, key: &str, says: &str) {
    let (code, stderr) = check(name, text);
    assert_eq!(code, Some(1), "{name}: exit status; stderr:\n{stderr}");
    let location = format!("{name}:{}:", line_of(text, needle));
    assert!(
        stderr.lines().any(|line| line.contains(&location)
            && line.contains(&format!("`{key}`"))
            && line.contains(says)),
        "{name}: expected {location} `{key}` … {says:?} in:\n{stderr}"
    );
}

#[test]
fn the_good_config_passes_without_warnings() {
    let (code, stderr) = check("good.toml", GOOD);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn supervision_keys_out_of_range_are_refused() {
    for (name, from, to, key, says) in [
        (
            "fe_negative.toml",
            "following_error = 0.5",
            "following_error = -1.0",
            "axis[0].following_error",
            "a finite number >= 0",
        ),
        (
            "fe_tolerance.toml",
            "following_error = 0.5",
            "following_error = 0.001",
            "axis[0].following_error",
            "smaller than position_tolerance",
        ),
        (
            "fe_type.toml",
            "following_error = 0.5",
            "following_error = \"big\"",
            "axis[0].following_error",
            "invalid type",
        ),
        (
            "overspeed_low.toml",
            "overspeed_factor = 2.0",
            "overspeed_factor = 0.5",
            "axis[0].overspeed_factor",
            "below 1",
        ),
        (
            "overspeed_nan.toml",
            "overspeed_factor = 2.0",
            "overspeed_factor = nan",
            "axis[0].overspeed_factor",
            "a finite number >= 0",
        ),
        (
            "estop.toml",
            "estop = \"stop-off\"",
            "estop = \"brake\"",
            "axis[0].estop",
            "allowed: \"hold\"",
        ),
        (
            "lease.toml",
            "claim_lease_ms = 500",
            "claim_lease_ms = -1",
            "server.claim_lease_ms",
            "allowed: 0..=3600000",
        ),
    ] {
        let text = GOOD.replace(from, to);
        fails(name, &text, to, key, says);
    }
}

#[test]
fn zero_turns_supervision_off_with_a_warning() {
    let text = GOOD
        .replace("following_error = 0.5", "following_error = 0.0")
        .replace("overspeed_factor = 2.0", "overspeed_factor = 0.0");
    let (code, stderr) = check("off.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
    for key in ["axis[0].following_error", "axis[0].overspeed_factor"] {
        assert!(
            stderr.contains(&format!("warning: `{key}`: 0 turns off")),
            "{key}: {stderr}"
        );
    }
}

#[test]
fn home_tables_and_their_aliases_are_checked() {
    for (name, from, to, key, says) in [
        (
            "direction.toml",
            "direction = \"positive\"",
            "direction = \"up\"",
            "axis[0].home.direction",
            "allowed: \"negative\"",
        ),
        (
            "travel.toml",
            "max_travel = 120.0",
            "max_travel = 0.0",
            "axis[0].home.max_travel",
            "a finite distance > 0",
        ),
        (
            "position.toml",
            "position = 50.0",
            "position = 1e12",
            "axis[0].home.position",
            "32-bit position counter",
        ),
        (
            "positive_end.toml",
            "direction = \"positive\"",
            "direction = \"positive\", positive_end = false",
            "axis[0].home.positive_end",
            "disagrees with `axis[0].home.direction`",
        ),
    ] {
        let text = GOOD.replace(from, to);
        fails(name, &text, to, key, says);
    }
    // The QSB's device keys are the same facts as its axis's home table: both, disagreeing.
    let text = GOOD
        .replace("model = \"qsb\"", "model = \"qsb\"\nhome_max_travel = 10.0")
        .replace(
            "max_velocity = 10.0\nmax_accel = 100.0\n\n[[signal]]",
            "max_velocity = 10.0\nmax_accel = 100.0\nhome = { max_travel = 20.0 }\n\n[[signal]]",
        );
    fails(
        "alias.toml",
        &text,
        "home_max_travel = 10.0",
        "device[1].home_max_travel",
        "disagrees with `axis[2].home.max_travel`",
    );
    // An SPI_motor cannot home.
    let text = GOOD.replace("model = \"qq2drv\"", "model = \"spimotor\"");
    let (code, stderr) = check("spimotor_home.toml", &text);
    assert_eq!(code, Some(1));
    assert!(
        stderr.contains("`axis[0].home`: `home` is not a key of spimotor axes; it is valid on: qq2drv, tmcpack, qsb; an SPI_motor has no reference input"),
        "{stderr}"
    );
}

#[test]
fn an_off_category_needs_a_board_that_can_de_energise() {
    // A QSB-M without an enable output cannot de-energise its drive.
    let text = GOOD.replace(
        "max_velocity = 10.0\nmax_accel = 100.0\n\n[[signal]]",
        "max_velocity = 10.0\nmax_accel = 100.0\nestop = \"off\"\n\n[[signal]]",
    );
    let path = write("estop_off.toml", &text);
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--config")
        .arg(&path)
        .output()
        .expect("run motiond");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("axis `feeder`") && stderr.contains("needs a board that can de-energise"),
        "{stderr}"
    );
}

#[test]
fn signals_are_checked_against_the_board_s_pins() {
    // (The kind a pin cannot take is reported at the pin.)
    let text = GOOD.replacen("kind = \"digital-in\"", "kind = \"digital-out\"", 1);
    fails(
        "kind.toml",
        &text,
        "pin = \"in2\"",
        "signal[0].pin",
        "pin `in2` cannot be digital-out; it can be: digital-in",
    );
    for (name, from, to, key, says) in [
        (
            "pin.toml",
            "pin = \"in2\"",
            "pin = \"in9\"",
            "signal[0].pin",
            "device `drive` has no pin `in9`; pins of a qq2drv board: in1",
        ),
        (
            "kind_name.toml",
            "kind = \"digital-in\"",
            "kind = \"switch\"",
            "signal[0].kind",
            "allowed: digital-in, digital-out, analog-in",
        ),
        (
            "device.toml",
            "device = \"drive\"\npin",
            "device = \"nothing\"\npin",
            "signal[0].device",
            "no device called `nothing`",
        ),
        (
            "scale.toml",
            "invert = true",
            "scale = 2.0",
            "signal[0].scale",
            "applies only to analog-in, capture and trigger signals",
        ),
        (
            "safe_in.toml",
            "invert = true",
            "safe = true",
            "signal[0].safe",
            "applies only to digital-out signals",
        ),
    ] {
        let text = GOOD.replacen(from, to, 1);
        fails(name, &text, to, key, says);
    }
    let text = GOOD.replace("name = \"lamp\"", "name = \"switch\"");
    fails(
        "name.toml",
        &text,
        "name = \"switch\"\ndevice = \"io_board\"",
        "signal[1].name",
        "a signal called `switch` is already defined",
    );
    // One pin, two signals.
    let text = GOOD
        .replace(
            "name = \"lamp\"\ndevice = \"io_board\"\npin = \"io0\"",
            "name = \"lamp\"\ndevice = \"drive\"\npin = \"in2\"",
        )
        .replace(
            "kind = \"digital-out\"\nsafe = false",
            "kind = \"digital-in\"",
        );
    let (code, stderr) = check("twice.toml", &text);
    assert_eq!(code, Some(1), "{stderr}");
    let pin_line = line_of(&text, "name = \"lamp\"") + 2;
    assert!(
        stderr.contains(&format!("twice.toml:{pin_line}:7: `signal[1].pin`: pin `in2` of device `drive` is already used by signal `switch`")),
        "{stderr}"
    );
    // A board without pins.
    let text = GOOD.replace("model = \"qq2drv\"", "model = \"spimotor\"").replace(
        "home = { input = \"home\", direction = \"positive\", max_travel = 120.0, position = 50.0 }\n",
        "",
    ).replace("estop = \"stop-off\"\n", "");
    fails(
        "no_pins.toml",
        &text,
        "pin = \"in2\"",
        "signal[0].pin",
        "a spimotor board has no I/O pins",
    );
}

/// `[server] io_rt_priority`: unless given, one below `rt_priority` (the tick preempts the
/// I/O threads, they preempt ordinary work); 0 keeps them at the normal policy; without
/// `rt_priority` they stay at the normal policy unless given.
#[test]
fn io_threads_take_the_priority_below_the_tick_s_unless_told_otherwise() {
    let plain = server_with("");
    assert_eq!((plain.rt_priority, plain.io_rt_priority), (None, None));
    let tick = server_with("rt_priority = 80");
    assert_eq!(
        (tick.rt_priority, tick.io_rt_priority),
        (Some(80), Some(79))
    );
    // The lowest tick priority leaves nothing below it: the I/O threads share it.
    assert_eq!(server_with("rt_priority = 1").io_rt_priority, Some(1));
    let off = server_with("rt_priority = 80\nio_rt_priority = 0");
    assert_eq!((off.rt_priority, off.io_rt_priority), (Some(80), None));
    let given = server_with("io_rt_priority = 60");
    assert_eq!((given.rt_priority, given.io_rt_priority), (None, Some(60)));
    for (name, to, says) in [
        ("io_rt_high.toml", "io_rt_priority = 100", "allowed: 0..=99"),
        (
            "io_rt_negative.toml",
            "io_rt_priority = -1",
            "allowed: 0..=99",
        ),
        (
            "io_rt_type.toml",
            "io_rt_priority = \"high\"",
            "invalid type",
        ),
    ] {
        let text = GOOD.replace("claim_lease_ms = 500", to);
        fails(name, &text, to, "server.io_rt_priority", says);
    }
}

/// `[server] io_cpu`: the I/O threads' core, not pinned unless given (not even beside a
/// pinned tick); out of range is refused with the key.
#[test]
fn io_threads_are_pinned_only_when_told() {
    assert_eq!(server_with("cpu = 1").io_cpu, None);
    let both = server_with("cpu = 1\nio_cpu = 1");
    assert_eq!((both.cpu, both.io_cpu), (Some(1), Some(1)));
    assert_eq!(server_with("io_cpu = 0").io_cpu, Some(0));
    for (name, to, says) in [
        ("io_cpu_high.toml", "io_cpu = 1024", "allowed: 0..=1023"),
        ("io_cpu_negative.toml", "io_cpu = -1", "allowed: 0..=1023"),
    ] {
        let text = GOOD.replace("claim_lease_ms = 500", to);
        fails(name, &text, to, "server.io_cpu", says);
    }
}

/// The `[server]` settings of [`GOOD`] with `server_keys` in place of its claim lease.
fn server_with(server_keys: &str) -> motion_config::ServerSettings {
    let text = GOOD.replace("claim_lease_ms = 500", server_keys);
    motion_config::ServerConfig::parse(std::path::Path::new("io.toml"), &text)
        .unwrap_or_else(|e| panic!("{server_keys}: {e}"))
        .server
}

/// The links of [`GOOD`] with `spi_keys` added to its SPI sim link and `usb_keys` to its
/// serial sim link.
fn links_with(spi_keys: &str, usb_keys: &str) -> Vec<motion_config::LinkSpec> {
    let text = GOOD
        .replace(
            "name = \"spi\"\ntype = \"sim\"",
            &format!("name = \"spi\"\ntype = \"sim\"\n{spi_keys}"),
        )
        .replace(
            "name = \"usb\"\ntype = \"sim\"",
            &format!("name = \"usb\"\ntype = \"sim\"\n{usb_keys}"),
        );
    motion_config::ServerConfig::parse(std::path::Path::new("io.toml"), &text)
        .unwrap_or_else(|e| panic!("{spi_keys} / {usb_keys}: {e}"))
        .links
}

/// `[[link]] io`: a sim link keeps its thread unless told (an `spi-socket` link's default
/// "tick" is in `server_inline_io.rs`); an SPI sim link told "tick" gets a quarter of the
/// period of wire time; a serial link refuses "tick"; the budget is checked against the
/// period and belongs to io = "tick" links only.
#[test]
fn spi_links_may_be_run_by_the_tick_and_serial_links_keep_their_threads() {
    use core::time::Duration;
    use motion_config::IoMode;
    let links = links_with("", "");
    assert_eq!((links[0].io, links[1].io), (IoMode::Thread, IoMode::Thread));
    let quarter = IoMode::Tick {
        budget: Duration::from_micros(250),
    };
    assert_eq!(links_with("io = \"tick\"", "")[0].io, quarter);
    assert_eq!(
        links_with("io = \"tick\"\nio_budget_us = 600", "")[0].io,
        IoMode::Tick {
            budget: Duration::from_micros(600)
        }
    );
    assert_eq!(
        links_with("", "io = \"thread\"")[1].io,
        IoMode::Thread,
        "saying the default is fine"
    );
    let spi = "name = \"spi\"\ntype = \"sim\"";
    let usb = "name = \"usb\"\ntype = \"sim\"";
    for (name, link, key, says) in [
        (
            "io_tick_serial.toml",
            (usb, "io = \"tick\""),
            "link[1].io",
            "a serial link keeps its I/O thread",
        ),
        (
            "io_unknown.toml",
            (spi, "io = \"inline\""),
            "link[0].io",
            "allowed: tick, thread",
        ),
        (
            "io_budget_thread.toml",
            (spi, "io = \"thread\"\nio_budget_us = 100"),
            "link[0].io_budget_us",
            "this link has its own I/O thread",
        ),
        (
            "io_budget_long.toml",
            (spi, "io = \"tick\"\nio_budget_us = 1001"),
            "link[0].io_budget_us",
            "allowed: 1..=1000",
        ),
        (
            "io_budget_zero.toml",
            (spi, "io = \"tick\"\nio_budget_us = 0"),
            "link[0].io_budget_us",
            "allowed: 1..=1000",
        ),
    ] {
        let (table, keys) = link;
        let text = GOOD.replace(table, &format!("{table}\n{keys}"));
        let needle = keys.lines().last().expect("a key");
        fails(name, &text, needle, key, says);
    }
}

/// `[server] state_dir`: where the references of `power_down = "restore"` devices and the
/// server's key are kept; unless given, the documented default for this process
/// (`motion_config::private_dir::default_state_dir`: root's is `/var/lib/motiond`), and
/// `blackbox_dir` under it unless given; an empty path refused with the key.
#[test]
fn the_state_dir_has_a_documented_default_and_refuses_an_empty_path() {
    let default = server_with("claim_lease_ms = 500");
    assert_eq!(default.state_dir, motion_config::default_state_dir());
    assert_eq!(default.blackbox_dir, default.state_dir.join("blackbox"));
    if nix::unistd::geteuid().is_root() && std::env::var_os("STATE_DIRECTORY").is_none() {
        assert_eq!(default.state_dir, PathBuf::from("/var/lib/motiond"));
    }
    let given = server_with("state_dir = \"/srv/motiond\"");
    assert_eq!(given.state_dir, PathBuf::from("/srv/motiond"));
    assert_eq!(given.blackbox_dir, PathBuf::from("/srv/motiond/blackbox"));
    let both = server_with("state_dir = \"/srv/motiond\"\nblackbox_dir = \"/srv/bb\"");
    assert_eq!(both.blackbox_dir, PathBuf::from("/srv/bb"));
    let to = "state_dir = \"\"";
    let text = GOOD.replace("claim_lease_ms = 500", to);
    fails(
        "state_dir_empty.toml",
        &text,
        to,
        "server.state_dir",
        "an empty path",
    );
}
