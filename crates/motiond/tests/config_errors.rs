//! Malformed configs: each fails `motiond --check-config` with file:line:column and the key,
//! a non-zero exit status, and nothing opened (the links name device paths that do not
//! exist: opening any of them would fail differently).

use std::path::PathBuf;
use std::process::Command;

const GOOD: &str = r#"
[server]
name = "t"
tick_hz = 1000

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
variant = "quadpack"

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
    let dir = std::env::temp_dir().join(format!("motiond-config-test-{}", std::process::id()));
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

/// The 1-based line of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in config"));
    text[..offset].matches('\n').count() + 1
}

fn assert_fails(name: &str, text: &str, needle: &str, key: &str, says: &str) {
    let (code, stderr) = check(name, text);
    assert_eq!(code, Some(1), "{name}: exit status; stderr:\n{stderr}");
    let line = line_of(text, needle);
    let location = format!("{name}:{line}:");
    assert!(
        stderr.contains(&location),
        "{name}: expected {location} in:\n{stderr}"
    );
    assert!(
        stderr.contains(&format!("`{key}`")),
        "{name}: expected key `{key}` in:\n{stderr}"
    );
    assert!(
        stderr.contains(says),
        "{name}: expected {says:?} in:\n{stderr}"
    );
}

#[test]
fn the_good_config_passes() {
    let (code, stderr) = check("good.toml", GOOD);
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn unknown_key() {
    let text = GOOD.replace("tick_hz = 1000", "tick_hz = 1000\ntick_rate = 5");
    assert_fails(
        "unknown_key.toml",
        &text,
        "tick_rate",
        "tick_rate",
        "unknown field `tick_rate`",
    );
}

#[test]
fn wrong_type() {
    let text = GOOD.replace("tick_hz = 1000", "tick_hz = \"fast\"");
    assert_fails(
        "wrong_type.toml",
        &text,
        "\"fast\"",
        "server.tick_hz",
        "invalid type",
    );
}

#[test]
fn tick_hz_zero() {
    let text = GOOD.replace("tick_hz = 1000", "tick_hz = 0");
    assert_fails(
        "tick_zero.toml",
        &text,
        "tick_hz = 0",
        "server.tick_hz",
        "allowed: 1..=20000",
    );
}

#[test]
fn duplicate_axis() {
    let axis = &GOOD[GOOD.find("[[axis]]").unwrap()..];
    let text = format!("{GOOD}\n{}", axis.replace("channel = 0", "channel = 1"));
    let (code, stderr) = check("dup_axis.toml", &text);
    assert_eq!(code, Some(1));
    // On the second axis's `name` value (line and column), with the table's index in the
    // key, as every other issue (it was the table's first line and `axis.name`).
    let second = text.rfind("name = \"x\"").unwrap();
    let line = text[..second].matches('\n').count() + 1;
    assert!(
        stderr.contains(&format!("dup_axis.toml:{line}:8: `axis[1].name`")),
        "{stderr}"
    );
    assert!(stderr.contains("already defined"), "{stderr}");
}

#[test]
fn duplicate_link_and_device_names_are_located_at_the_name() {
    let link = &GOOD[GOOD.find("[[link]]").unwrap()..GOOD.find("[[device]]").unwrap()];
    let text = GOOD.replacen("[[device]]", &format!("{link}[[device]]"), 1);
    let (code, stderr) = check("dup_link.toml", &text);
    assert_eq!(code, Some(1));
    let second = text.rfind("name = \"bus\"").unwrap();
    let line = text[..second].matches('\n').count() + 1;
    assert!(
        stderr.contains(&format!("dup_link.toml:{line}:8: `link[1].name`")),
        "{stderr}"
    );
    let device = &GOOD[GOOD.find("[[device]]").unwrap()..GOOD.find("[[axis]]").unwrap()];
    let text = GOOD.replacen(
        "[[axis]]",
        &format!("{}[[axis]]", device.replace("address = 1", "address = 2")),
        1,
    );
    let (code, stderr) = check("dup_device.toml", &text);
    assert_eq!(code, Some(1));
    let second = text.rfind("name = \"pack\"").unwrap();
    let line = text[..second].matches('\n').count() + 1;
    assert!(
        stderr.contains(&format!("dup_device.toml:{line}:8: `device[1].name`")),
        "{stderr}"
    );
}

#[test]
fn a_table_of_the_wrong_type_is_called_a_table() {
    // serde says "expected struct RawCurrent": the parser's own type name.
    let text = GOOD.replace("max_accel = 100.0", "max_accel = 100.0\ncurrent = 7");
    assert_fails(
        "table_type.toml",
        &text,
        "current = 7",
        "axis[0].current",
        "expected a table",
    );
    let (_, stderr) = check("table_type.toml", &text);
    assert!(!stderr.contains("Raw"), "{stderr}");
}

#[test]
fn unknown_link() {
    let text = GOOD.replace("link = \"bus\"", "link = \"rs485\"");
    assert_fails(
        "unknown_link.toml",
        &text,
        "\"rs485\"",
        "device[0].link",
        "no link called `rs485`",
    );
}

#[test]
fn unknown_device() {
    let text = GOOD.replace("device = \"pack\"", "device = \"pak\"");
    assert_fails(
        "unknown_device.toml",
        &text,
        "\"pak\"",
        "axis[0].device",
        "no device called `pak`",
    );
}

#[test]
fn channel_out_of_range() {
    let text = GOOD.replace("channel = 0", "channel = 4");
    assert_fails(
        "channel.toml",
        &text,
        "channel = 4",
        "axis[0].channel",
        "allowed: 0..=3",
    );
}

#[test]
fn min_not_below_max() {
    let text = GOOD.replace("max = 100.0", "max = -5.0");
    assert_fails(
        "limits.toml",
        &text,
        "max = -5.0",
        "axis[0].max",
        "must be greater than min",
    );
}

#[test]
fn missing_key() {
    let text = GOOD.replace("unit = \"mm\"\n", "");
    assert_fails("missing.toml", &text, "[[axis]]", "axis[0].unit", "missing");
}

#[test]
fn model_on_the_wrong_link_type() {
    let text = GOOD
        .replace("model = \"tmcpack\"", "model = \"qq2drv\"")
        .replace("address = 1\n", "")
        .replace("variant = \"quadpack\"\n", "");
    assert_fails(
        "wrong_link.toml",
        &text,
        "\"serial\"",
        "link[0].type",
        "qq2drv and spimotor need spidev",
    );
}

#[test]
fn unknown_model() {
    let text = GOOD.replace("model = \"tmcpack\"", "model = \"tmc\"");
    assert_fails(
        "model.toml",
        &text,
        "\"tmc\"",
        "device[0].model",
        "allowed: qq2drv, tmcpack, spimotor, qsb",
    );
}

#[test]
fn nan_and_negative_limits() {
    let text = GOOD.replace("max_velocity = 20.0", "max_velocity = nan");
    assert_fails(
        "nan.toml",
        &text,
        "max_velocity = nan",
        "axis[0].max_velocity",
        "finite number > 0",
    );
    let text = GOOD.replace("max_accel = 100.0", "max_accel = -1.0");
    assert_fails(
        "neg.toml",
        &text,
        "max_accel = -1.0",
        "axis[0].max_accel",
        "finite number > 0",
    );
}

#[test]
fn duplicate_bus_address_and_every_issue_reported() {
    let device = &GOOD[GOOD.find("[[device]]").unwrap()..GOOD.find("[[axis]]").unwrap()];
    let text = format!(
        "{GOOD}\n{}",
        device.replace("name = \"pack\"", "name = \"pack2\"")
    )
    .replace("tick_hz = 1000", "tick_hz = 99999");
    let (code, stderr) = check("many.toml", &text);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("`server.tick_hz`"), "{stderr}");
    assert!(stderr.contains("address 1 is already used"), "{stderr}");
}

#[test]
fn unreadable_file_and_syntax_error() {
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .args(["--check-config", "/nonexistent/motiond.toml"])
        .output()
        .expect("run motiond");
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stderr).contains("/nonexistent/motiond.toml:1:1"));
    let text = GOOD.replace("[server]", "[server");
    let (code, stderr) = check("syntax.toml", &text);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("syntax.toml:2:"), "{stderr}");
}

#[test]
fn the_shipped_configs_are_valid() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut configs = vec![root.join("config/sim.toml")];
    if let Ok(entries) = std::fs::read_dir(root.join("config/examples")) {
        configs.extend(entries.flatten().map(|entry| entry.path()));
    }
    for path in configs {
        let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
            .arg("--check-config")
            .arg(&path)
            .output()
            .expect("run motiond");
        assert!(
            output.status.success(),
            "{}: {}",
            path.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
}

#[test]
fn home_inputs_are_for_qq2drv_axes_only_and_named() {
    let text = GOOD.replace(
        "max_accel = 100.0",
        "max_accel = 100.0\nhome = { input = \"index\" }",
    );
    assert_fails(
        "home_model.toml",
        &text,
        "home = {",
        "axis[0].home.input",
        "is not a key of tmcpack axes; it is valid on: qq2drv",
    );
    let qq2drv = r#"
[server]
name = "home"

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
home = { input = "switch" }
"#;
    assert_fails(
        "home_input.toml",
        qq2drv,
        "\"switch\"",
        "axis[0].home.input",
        "allowed: \"home\"",
    );
    let (code, stderr) = check(
        "home_ok.toml",
        &qq2drv.replace("\"switch\"", "\"edge\", active_high = false"),
    );
    assert_eq!(code, Some(0), "{stderr}");
}

// Issue: configs accepted that should not be, and misleading messages.

#[test]
fn an_empty_config_is_refused() {
    let (code, stderr) = check("empty.toml", "");
    assert_eq!(code, Some(1), "{stderr}");
    for (key, says) in [
        ("server.name", "missing [server]"),
        ("link", "no [[link]] table"),
        ("device", "no [[device]] table"),
        ("axis", "no [[axis]] or [[signal]] table"),
    ] {
        assert!(
            stderr.contains(&format!("`{key}`: {says}")),
            "{key}: {stderr}"
        );
    }
}

#[test]
fn a_nameless_server_is_refused() {
    let text = GOOD.replace("name = \"t\"\n", "");
    assert_fails(
        "nameless.toml",
        &text,
        "[server]",
        "server.name",
        "missing; the instance name",
    );
}

#[test]
fn integers_beyond_64_bits_are_range_errors_of_their_key() {
    let text = GOOD.replace("tick_hz = 1000", "tick_hz = 18446744073709551615");
    assert_fails(
        "tick_overflow.toml",
        &text,
        "18446744073709551615",
        "server.tick_hz",
        "18446744073709551615 is out of range; allowed: 1..=20000",
    );
    let text = GOOD.replace(
        "tick_hz = 1000",
        "tick_hz = 1000\ncommand_timeout_ms = 99999999999999999999",
    );
    let (code, stderr) = check("timeout_overflow.toml", &text);
    assert_eq!(code, Some(1), "{stderr}");
    assert!(
        stderr.contains(":5:22: `server.command_timeout_ms`: 99999999999999999999 is out of range; allowed: 0..=60000"),
        "{stderr}"
    );
    assert!(!stderr.contains("i128"), "{stderr}");
}

#[test]
fn a_dangling_reference_is_reported_first() {
    // An unrelated problem earlier in the file, then a device on a link that does not exist.
    let text = GOOD
        .replace("baud = 19200", "baud = 0")
        .replace("link = \"bus\"", "link = \"bux\"");
    let (code, stderr) = check("dangling.toml", &text);
    assert_eq!(code, Some(1), "{stderr}");
    let first = stderr.lines().next().unwrap_or("");
    assert!(
        first.contains("`device[0].link`: no link called `bux`"),
        "the dangling name comes first:\n{stderr}"
    );
    assert!(stderr.contains("link[0].baud"), "{stderr}");
}

#[test]
fn a_non_utf8_byte_is_reported_where_it_is() {
    let path = write("latin1.toml", "");
    let mut bytes = GOOD.as_bytes().to_vec();
    // Line 7 of GOOD is `path = "/dev/does-not-exist-motiond-test"`: put a Latin-1 é in it.
    let line7 = GOOD.lines().take(6).map(|l| l.len() + 1).sum::<usize>();
    bytes.insert(line7 + 8, 0xE9);
    std::fs::write(&path, &bytes).expect("write");
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(&path)
        .output()
        .expect("run motiond");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("latin1.toml:7:9: `(file)`: byte 0xE9 is not UTF-8"),
        "{stderr}"
    );
}

#[test]
fn server_and_device_names_are_identifiers() {
    for (file, from, to, key) in [
        (
            "server_dot.toml",
            "name = \"t\"",
            "name = \".\"",
            "server.name",
        ),
        (
            "server_dots.toml",
            "name = \"t\"",
            "name = \"..\"",
            "server.name",
        ),
        (
            "server_path.toml",
            "name = \"t\"",
            "name = \"a.b\"",
            "server.name",
        ),
        (
            "device_dot.toml",
            "name = \"pack\"",
            "name = \".\"",
            "device[0].name",
        ),
        (
            "device_dots.toml",
            "name = \"pack\"",
            "name = \"..\"",
            "device[0].name",
        ),
        (
            "link_slash.toml",
            "name = \"bus\"",
            "name = \"b/us\"",
            "link[0].name",
        ),
    ] {
        let text = GOOD.replacen(from, to, 1);
        assert_fails(file, &text, to, key, "is not a valid name");
    }
    // Letters, digits, `_` and `-` are names.
    let text = GOOD
        .replacen("name = \"t\"", "name = \"Cell_2-a\"", 1)
        .replace("name = \"pack\"", "name = \"pack_0-b\"")
        .replace("device = \"pack\"", "device = \"pack_0-b\"");
    let (code, stderr) = check("identifiers.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
}
