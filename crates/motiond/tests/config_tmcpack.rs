//! tmcpack machine keys in the config: every malformed value fails `motiond --check-config`
//! with file:line:column, the key and what is allowed; a key on the wrong model names the
//! models where it is valid. The mapping of every key to the wire is in `mapping`.

#[path = "config_tmcpack/drive.rs"]
mod drive;
#[path = "config_tmcpack/mapping.rs"]
mod mapping;

use std::path::PathBuf;
use std::process::Command;

/// A SIXpack with a linear axis (motor 0) and a rotary one (motor 1).
pub const GOOD: &str = r#"
[server]
name = "t"

[[link]]
name = "bus"
type = "serial"
path = "/dev/does-not-exist-motiond-test"
baud = 19200

[[device]]
name = "pack"
link = "bus"
model = "tmcpack"
address = 1

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

[[axis]]
name = "turn"
device = "pack"
channel = 1
unit = "deg"
counts_per_unit = 8.8889
min = 0.0
max = 359.0
max_velocity = 90.0
max_accel = 360.0
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-tmcpack-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write config");
    path
}

/// Runs `--check-config` and returns (exit code, stderr).
fn check(name: &str, text: &str) -> (Option<i32>, String) {
    let path = write(name, text);
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

/// The 1-based line of the `nth` (0-based) occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str, nth: usize) -> usize {
    let offset = text
        .match_indices(needle)
        .nth(nth)
        .unwrap_or_else(|| panic!("{needle:?} #{nth} not in config"))
        .0;
    text[..offset].matches('\n').count() + 1
}

/// `text` fails with an issue at the line of `needle` (its `nth` occurrence), naming `key`,
/// saying `says`.
fn fails_at(name: &str, text: &str, needle: &str, nth: usize, key: &str, says: &str) {
    let (code, stderr) = check(name, text);
    assert_eq!(code, Some(1), "{name}: exit status; stderr:\n{stderr}");
    let location = format!("{name}:{}:", line_of(text, needle, nth));
    let found = stderr.lines().any(|line| {
        line.contains(&location)
            && (line.contains(&format!("`{key}`")) || line.contains(&format!(".{key}`")))
            && line.contains(says)
    });
    assert!(
        found,
        "{name}: expected {location} `{key}` … {says:?} in:\n{stderr}"
    );
}

/// `GOOD` with `extra` added to axis `x` (after its max_accel).
fn on_x(extra: &str) -> String {
    GOOD.replacen(
        "max_accel = 100.0",
        &format!("max_accel = 100.0\n{extra}"),
        1,
    )
}

/// `GOOD` with `extra` added to the device.
fn on_device(extra: &str) -> String {
    GOOD.replacen("address = 1", &format!("address = 1\n{extra}"), 1)
}

#[test]
fn the_good_config_and_every_key_set_pass() {
    let (code, stderr) = check("good.toml", GOOD);
    assert_eq!(code, Some(0), "{stderr}");
    let (code, stderr) = check("all.toml", mapping::ALL_KEYS);
    assert_eq!(code, Some(0), "{stderr}");
    let example =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/examples/tmcpack-real.toml");
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

#[test]
fn current_values_outside_the_manual_are_refused() {
    let text = on_x("current = { peak = 120.0 }");
    fails_at(
        "peak.toml",
        &text,
        "current =",
        0,
        "axis[0].current.peak",
        "0..=100",
    );
    let text = on_x("current = { standstill = 40.0 }");
    fails_at(
        "level.toml",
        &text,
        "current =",
        0,
        "axis[0].current.standstill",
        "allowed: 100, 75, 50, 38, 25, 19, 13, 9, 0",
    );
    let text = on_x("current = { accel = 37.5 }");
    fails_at(
        "accel.toml",
        &text,
        "current =",
        0,
        "axis[0].current.accel",
        "not a current level",
    );
    for bad in ["3", "0", "131072"] {
        let text = on_x(&format!("current = {{ standby_delay_ms = {bad} }}"));
        fails_at(
            "delay.toml",
            &text,
            "current =",
            0,
            "axis[0].current.standby_delay_ms",
            "an even number of ms 2..=131070",
        );
    }
    let text = on_x("current = { peak = \"half\" }");
    fails_at(
        "type.toml",
        &text,
        "\"half\"",
        0,
        "current.peak",
        "invalid type",
    );
}

#[test]
fn a_motor_pair_takes_one_peak_current() {
    let text = on_x("current = { peak = 50.0 }").replacen(
        "max_accel = 360.0",
        "max_accel = 360.0\ncurrent = { peak = 75.0 }",
        1,
    );
    fails_at(
        "pair.toml",
        &text,
        "current =",
        1,
        "axis[1].current.peak",
        "share one peak current",
    );
    let same = text.replace("peak = 75.0", "peak = 50.0");
    let (code, stderr) = check("pair_ok.toml", &same);
    assert_eq!(code, Some(0), "{stderr}");
    let (code, stderr) = check("pair_one.toml", &on_x("current = { peak = 50.0 }"));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("applies to axis `turn` too"),
        "{stderr}"
    );
}

#[test]
fn reference_values_outside_the_manual_are_refused() {
    let cases = [
        (
            "active = \"maybe\"",
            "axis[0].reference.active",
            "allowed: \"low\"",
        ),
        (
            "debounce_ms = 31",
            "axis[0].reference.debounce_ms",
            "0..=30",
        ),
        (
            "debounce_ms = 5",
            "axis[0].reference.debounce_ms",
            "even number",
        ),
        (
            "test_range = 200.0",
            "axis[0].reference.test_range",
            "65535 microsteps",
        ),
        (
            "test_range = -1.0",
            "axis[0].reference.test_range",
            "a distance >= 0",
        ),
        (
            "null_offset = nan",
            "axis[0].reference.null_offset",
            "a finite distance",
        ),
        (
            "null_offset = 1e7",
            "axis[0].reference.null_offset",
            "signed 32-bit",
        ),
        ("side = \"up\"", "axis[0].reference.side", "unknown side"),
        ("fast = 1", "reference.fast", "invalid type"),
    ];
    for (value, key, says) in cases {
        let text = on_x(&format!("reference = {{ {value} }}"));
        fails_at("reference.toml", &text, "reference =", 0, key, says);
    }
}

/// Manual, instruction set, `$27` "Set actual Position": "Can lead to unintended reference
/// searches at detection of zero switches"; `$15` P5 bit 6 StopNull stops the motor and
/// searches again "if zero switch is active outside the tolerance area around zero point".
/// After a search the driver sets `home.position` with `$27`: with StopNull on, a position
/// outside ±testnullrange puts the switch outside that area.
#[test]
fn a_home_position_outside_the_test_range_with_stop_null_is_refused() {
    // x: 640 microsteps a mm; the default testnullrange is 240 microsteps (0.375 mm).
    let text = on_x("reference = { stop_at_switch = true }\nhome = { position = 10.0 }");
    fails_at(
        "stopnull.toml",
        &text,
        "home =",
        0,
        "axis[0].home.position",
        "unintended reference searches",
    );
    let text = on_x(
        "reference = { stop_at_switch = true, test_range = 50.0 }\nhome = { position = 60.0 }",
    );
    fails_at(
        "stopnull_range.toml",
        &text,
        "home =",
        0,
        "axis[0].home.position",
        "within ±50 mm",
    );
    // Within the range, without StopNull, or at zero: accepted.
    for extra in [
        "reference = { stop_at_switch = true }\nhome = { position = 0.25 }",
        "reference = { stop_at_switch = true, test_range = 50.0 }\nhome = { position = 40.0 }",
        "reference = { stop_at_switch = false }\nhome = { position = 10.0 }",
        "home = { position = 10.0 }",
        "reference = { stop_at_switch = true }",
    ] {
        let (code, stderr) = check("stopnull_ok.toml", &on_x(extra));
        assert_eq!(code, Some(0), "{extra}: {stderr}");
    }
}

#[test]
fn rotary_revolution_and_poslimit_are_checked() {
    let text = on_x("rotary = true");
    fails_at(
        "rotary.toml",
        &text,
        "[[axis]]",
        0,
        "axis[0].revolution",
        "missing; a rotary axis needs its units per revolution",
    );
    let text = on_x("revolution = 5.0");
    fails_at(
        "linear.toml",
        &text,
        "revolution",
        0,
        "axis[0].revolution",
        "applies only to an axis with `rotary = true`",
    );
    let text = on_x("rotary = true\nrevolution = -5.0");
    fails_at(
        "negative.toml",
        &text,
        "revolution",
        0,
        "axis[0].revolution",
        "a finite distance > 0",
    );
    // 100 mm at 3e7 µsteps/mm: 3e9 > 0x7FFFFFFF.
    let text = GOOD.replacen("counts_per_unit = 640.0", "counts_per_unit = 3e7", 1);
    fails_at(
        "poslimit.toml",
        &text,
        "max = 100.0",
        0,
        "axis[0].max",
        "poslimit allows at most 2147483647",
    );
    // A "deg" axis turns 360 per revolution unless told otherwise.
    let text = GOOD.replacen("max_accel = 360.0", "max_accel = 360.0\nrotary = true", 1);
    let (code, stderr) = check("deg.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn analog_stop_limits_are_adc_counts_rising_to_the_right() {
    let text = on_x("analog_stop = { left = 2000 }");
    fails_at(
        "left.toml",
        &text,
        "analog_stop",
        0,
        "axis[0].analog_stop.left",
        "allowed: 0..=1023",
    );
    let text = on_x("analog_stop = { left = 600, right = 400 }");
    fails_at(
        "order.toml",
        &text,
        "analog_stop",
        0,
        "axis[0].analog_stop.right",
        "must be above left",
    );
    let text = on_x("analog_stop = { left = 600, right = 1023 }");
    let (code, stderr) = check("left_only.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn reply_addresses_never_collide_with_a_pack_address() {
    let text = on_device("reply_address = 300");
    fails_at(
        "range.toml",
        &text,
        "reply_address",
        0,
        "device[0].reply_address",
        "allowed: 0..=255",
    );
    let text = on_device("reply_address = 1");
    fails_at(
        "own.toml",
        &text,
        "reply_address",
        0,
        "device[0].reply_address",
        "is the address of pack `pack`",
    );
    // The default reply address 254 and a second pack at 254: both directions.
    let second = r#"
[[device]]
name = "other"
link = "bus"
model = "tmcpack"
address = 254
"#;
    let text = format!("{GOOD}{second}");
    fails_at(
        "default.toml",
        &text,
        "address = 254",
        0,
        "device[1].address",
        "is the reply address pack `pack` uses",
    );
    let fixed = text.replacen("address = 1", "address = 1\nreply_address = 200", 1);
    fails_at(
        "other.toml",
        &fixed,
        "address = 254",
        0,
        "device[1].address",
        "is the reply address pack `other` uses",
    );
    let both = fixed.replace("address = 254", "address = 254\nreply_address = 200");
    let (code, stderr) = check("both.toml", &both);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn line_timing_keys_are_in_2_ms_units_and_fit_a_word() {
    let cases = [
        (
            "switchover_ms = 3",
            "device[0].switchover_ms",
            "an even number of ms 2..=2000",
        ),
        (
            "switchover_ms = 2002",
            "device[0].switchover_ms",
            "2..=2000",
        ),
        (
            "packet_timeout_ms = 2",
            "device[0].packet_timeout_ms",
            "4..=131070",
        ),
        (
            "packet_timeout_ms = 7",
            "device[0].packet_timeout_ms",
            "even number",
        ),
        // One 9-byte word at 19200 baud takes 4.7 ms.
        (
            "packet_timeout_ms = 4",
            "device[0].packet_timeout_ms",
            "shorter than one 9-byte word",
        ),
    ];
    for (value, key, says) in cases {
        let text = on_device(value);
        let needle = value.split(' ').next().unwrap_or(value);
        fails_at("timing.toml", &text, needle, 0, key, says);
    }
}

/// `host_latency_ms` (part of every reply window) and `silence_ms` (the silence
/// before the verdict): in range, a short silence warned about.
#[test]
fn host_latency_and_silence_are_checked() {
    for good in [
        "host_latency_ms = 0",
        "host_latency_ms = 16.5",
        "silence_ms = 500",
        "silence_ms = 60000",
    ] {
        let (code, stderr) = check("answering.toml", &on_device(good));
        assert_eq!(code, Some(0), "{good}: {stderr}");
    }
    let (code, stderr) = check("short.toml", &on_device("silence_ms = 100"));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("silence_ms") && stderr.contains("a host that stalls longer"),
        "{stderr}"
    );
    let cases = [
        (
            "host_latency_ms = -1",
            "device[0].host_latency_ms",
            "0..=1000",
        ),
        (
            "host_latency_ms = 1001",
            "device[0].host_latency_ms",
            "0..=1000",
        ),
        ("silence_ms = 99", "device[0].silence_ms", "100..=60000"),
        ("silence_ms = 60001", "device[0].silence_ms", "100..=60000"),
    ];
    for (value, key, says) in cases {
        let text = on_device(value);
        let needle = value.split(' ').next().unwrap_or(value);
        fails_at("answering.toml", &text, needle, 0, key, says);
    }
}

/// The two readings of `$14` ("1/64 amax is accumulated with 500Hz" against 7.1's
/// "increments v by 128/16=8 each 2 ms") and of `$15` P6 ("Bit 5: StopNoRef" against
/// "StopNoRef(P6, Bit 6)") are the only values; anything else is refused at its line.
#[test]
fn firmware_readings_take_only_the_manuals_two_values() {
    for good in [
        "amax_divisor = 64",
        "amax_divisor = 16",
        "stop_no_ref_bit = 5",
        "stop_no_ref_bit = 6",
    ] {
        let (code, stderr) = check("reading.toml", &on_device(good));
        assert_eq!(code, Some(0), "{good}: {stderr}");
    }
    let cases = [
        ("amax_divisor = 32", "device[0].amax_divisor", "allowed: 64"),
        (
            "amax_divisor = 0",
            "device[0].amax_divisor",
            "or 16 (manual 7.1",
        ),
        (
            "amax_divisor = -64",
            "device[0].amax_divisor",
            "not a reading of $14",
        ),
        (
            "stop_no_ref_bit = 7",
            "device[0].stop_no_ref_bit",
            "allowed: 5",
        ),
        (
            "stop_no_ref_bit = 0",
            "device[0].stop_no_ref_bit",
            "or 6 (its prose",
        ),
        (
            "stop_no_ref_bit = 261",
            "device[0].stop_no_ref_bit",
            "not a reading of $15 P6",
        ),
    ];
    for (value, key, says) in cases {
        let text = on_device(value);
        let needle = value.split(' ').next().unwrap_or(value);
        fails_at("reading.toml", &text, needle, 0, key, says);
    }
    // Not an integer: the TOML type is refused at the key.
    let (code, stderr) = check("reading.toml", &on_device("amax_divisor = \"64\""));
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("amax_divisor"), "{stderr}");
}

#[test]
fn the_ready_output_names_motors_of_the_variant_and_owns_ttlout1() {
    let text = on_device("ready_output = { motors = [0, 7] }");
    fails_at(
        "motor.toml",
        &text,
        "ready_output",
        0,
        "device[0].ready_output.motors",
        "allowed: 0..=5",
    );
    let quad = on_device("variant = \"quadpack\"\nready_output = { reference = [4] }");
    fails_at(
        "quad.toml",
        &quad,
        "ready_output",
        0,
        "device[0].ready_output.reference",
        "allowed: 0..=3",
    );
    let twice = on_device("ready_output = { motors = [1, 1] }");
    fails_at(
        "twice.toml",
        &twice,
        "ready_output",
        0,
        "device[0].ready_output.motors",
        "listed twice",
    );
    let signal = r#"
[[signal]]
name = "lamp"
device = "pack"
kind = "digital-out"
pin = "ttlout1"
"#;
    let text = format!("{}{signal}", on_device("ready_output = {}"));
    fails_at(
        "ttlout1.toml",
        &text,
        "pin = \"ttlout1\"",
        0,
        "signal[0].pin",
        "is its ready output",
    );
    let (code, stderr) = check("lamp.toml", &format!("{GOOD}{signal}"));
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn tmcpack_keys_on_another_model_name_the_model_where_they_are_valid() {
    let qq2drv = r#"
[[link]]
name = "spi"
type = "sim"

[[device]]
name = "drive"
link = "spi"
model = "qq2drv"

[[axis]]
name = "w"
device = "drive"
channel = 0
unit = "deg"
counts_per_unit = 55.0
min = -10.0
max = 10.0
max_velocity = 1.0
max_accel = 1.0
current = { peak = 50.0 }
reference = { active = "high" }
rotary = true
analog_stop = { left = 10 }
"#;
    for key in ["current", "reference", "rotary", "analog_stop"] {
        fails_at(
            "model.toml",
            qq2drv,
            &format!("{key} ="),
            0,
            &format!("axis[0].{key}"),
            &format!("`{key}` is not a key of qq2drv axes; it is valid on: tmcpack"),
        );
    }
    let device = qq2drv.replace(
        "model = \"qq2drv\"",
        "model = \"qq2drv\"\nreply_address = 3\nswitchover_ms = 4\npacket_timeout_ms = 10\nready_output = {}\namax_divisor = 16\nstop_no_ref_bit = 6",
    );
    for key in [
        "reply_address",
        "switchover_ms",
        "packet_timeout_ms",
        "ready_output",
        "amax_divisor",
        "stop_no_ref_bit",
    ] {
        fails_at(
            "device_model.toml",
            &device,
            &format!("{key} ="),
            0,
            &format!("device[0].{key}"),
            "it is valid on: tmcpack",
        );
    }
}
