//! The qsb machine keys of a config: every malformed value refused with file:line:column
//! and the key, the cross-table rules (axes, signals, the motor drive's lines), the
//! effective values `describe` shows, and the bytes the built driver puts on the wire.

use core::time::Duration;
use motion_drivers::Driver;
use std::path::Path;

use motion_config::{Owner, ServerConfig};
use motion_link::Link;
use qsb::{CommandDecoder, Request};

const GOOD: &str = r#"
[server]
name = "t"

[[link]]
name = "usb"
type = "serial"
path = "/dev/does-not-exist-motiond-qsb-test"
baud = 230400

[[device]]
name = "feeder_qsb"
link = "usb"
model = "qsb"
variant = "qsb-m"

[[axis]]
name = "feeder"
device = "feeder_qsb"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -1000.0
max = 1000.0
max_velocity = 100.0
max_accel = 1000.0
"#;

/// `GOOD` with `lines` added to the device table.
fn with_device_keys(lines: &str) -> String {
    GOOD.replace(
        "variant = \"qsb-m\"",
        &format!("variant = \"qsb-m\"\n{lines}"),
    )
}

fn parse(text: &str) -> Result<ServerConfig, String> {
    ServerConfig::parse(Path::new("qsb.toml"), text).map_err(|e| e.to_string())
}

/// The 1-based line of the first occurrence of `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in config"));
    text[..offset].matches('\n').count() + 1
}

/// `text` is refused at the line of `needle`, naming `key`, saying `says`.
fn refused(text: &str, needle: &str, key: &str, says: &str) {
    let error = match parse(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(error) => error,
    };
    let location = format!("qsb.toml:{}:", line_of(text, needle));
    let at = error
        .lines()
        .find(|l| l.contains(&format!("`{key}`")) || l.contains(&format!(".{key}`")))
        .unwrap_or_else(|| panic!("no issue for `{key}` in:\n{error}"));
    assert!(at.starts_with(&location), "expected {location} in: {at}");
    assert!(at.contains(says), "expected {says:?} in: {at}");
}

#[test]
fn the_good_config_and_every_key_set_well_pass() {
    let config = parse(GOOD).expect("good");
    assert!(config.warnings.is_empty());
    let all = with_device_keys(
        "counts_per_step = -4.0\nindex_polarity = \"inverted\"\nstream_interval_ms = 3.90625\nhost_latency_ms = 20.0\nsilence_ms = 300\nenable_output = 3\nenable_active = \"high\"\ninput_mode = \"quadrature\"\ncapture_input = 0\ncapture_edge = \"falling\"\nhome_direction = \"positive\"\nhome_max_travel = 50.0\nhome_offset = 1.5",
    );
    let config = parse(&all).expect("every key");
    assert!(config.warnings.is_empty(), "{:?}", config.warnings);
}

#[test]
fn malformed_values_of_every_key_are_refused_where_they_are() {
    let cases: [(&str, &str, &str, &str); 23] = [
        (
            "counts_per_step = 0.0",
            "counts_per_step",
            "device[0].counts_per_step",
            "not 0",
        ),
        (
            "counts_per_step = nan",
            "counts_per_step",
            "device[0].counts_per_step",
            "finite",
        ),
        (
            "counts_per_step = \"ten\"",
            "counts_per_step",
            "counts_per_step",
            "invalid type",
        ),
        (
            "index_polarity = \"upside-down\"",
            "index_polarity",
            "device[0].index_polarity",
            "allowed: \"normal\", \"inverted\"",
        ),
        (
            "stream_interval_ms = 0.5",
            "stream_interval_ms",
            "device[0].stream_interval_ms",
            "1..=0xFFFE ticks",
        ),
        (
            "stream_interval_ms = 200000.0",
            "stream_interval_ms",
            "device[0].stream_interval_ms",
            "out of range",
        ),
        (
            "stream_interval_ms = -2.0",
            "stream_interval_ms",
            "device[0].stream_interval_ms",
            "out of range",
        ),
        (
            "host_latency_ms = -1.0",
            "host_latency_ms",
            "device[0].host_latency_ms",
            "0..=1000 ms",
        ),
        (
            "host_latency_ms = 1000.5",
            "host_latency_ms",
            "device[0].host_latency_ms",
            "0..=1000 ms",
        ),
        (
            "silence_ms = 50",
            "silence_ms",
            "device[0].silence_ms",
            "allowed: 100..=60000",
        ),
        (
            "silence_ms = 0.5",
            "silence_ms",
            "silence_ms",
            "invalid type",
        ),
        (
            "enable_output = 1",
            "enable_output",
            "device[0].enable_output",
            "step and direction",
        ),
        (
            "enable_output = 4",
            "enable_output",
            "device[0].enable_output",
            "allowed: 0 or 3",
        ),
        (
            "enable_output = 0\nenable_active = \"sometimes\"",
            "enable_active",
            "device[0].enable_active",
            "allowed: \"low\", \"high\"",
        ),
        (
            "input_mode = \"sine\"",
            "input_mode",
            "device[0].input_mode",
            "allowed: \"quadrature\", \"pwm\", \"analog\"",
        ),
        (
            "capture_input = 4",
            "capture_input",
            "device[0].capture_input",
            "allowed: 0..=3",
        ),
        (
            "capture_input = 1",
            "capture_input",
            "device[0].capture_input",
            "step line",
        ),
        (
            "enable_output = 3\ncapture_input = 3",
            "capture_input",
            "device[0].capture_input",
            "enable_output",
        ),
        (
            "capture_input = 0\ncapture_edge = \"both\"",
            "capture_edge",
            "device[0].capture_edge",
            "allowed: \"rising\", \"falling\"",
        ),
        (
            "home_direction = \"up\"",
            "home_direction",
            "device[0].home_direction",
            "allowed",
        ),
        (
            "home_max_travel = -5.0",
            "home_max_travel",
            "device[0].home_max_travel",
            "> 0",
        ),
        (
            "home_offset = inf",
            "home_offset",
            "device[0].home_offset",
            "finite",
        ),
        (
            "home_offset = 3e7",
            "home_offset",
            "device[0].home_offset",
            "32-bit",
        ),
    ];
    for (lines, needle, key, says) in cases {
        refused(&with_device_keys(lines), needle, key, says);
    }
}

#[test]
fn keys_a_variant_does_not_have_are_refused() {
    let s = GOOD.replace(
        "variant = \"qsb-m\"",
        "variant = \"qsb-s\"\nenable_output = 0",
    );
    refused(
        &s,
        "enable_output",
        "device[0].enable_output",
        "only on a qsb-m",
    );
    let s = GOOD.replace(
        "variant = \"qsb-m\"",
        "variant = \"qsb-s\"\ncapture_input = 0",
    );
    refused(
        &s,
        "capture_input",
        "device[0].capture_input",
        "no digital I/O",
    );
    let d = GOOD.replace(
        "variant = \"qsb-m\"",
        "variant = \"qsb-d\"\ncapture_input = 1",
    );
    refused(
        &d,
        "capture_input",
        "device[0].capture_input",
        "allowed: 0..=0",
    );
    let d = GOOD.replace(
        "variant = \"qsb-m\"",
        "variant = \"qsb-d\"\ninput_mode = \"pwm\"",
    );
    refused(
        &d,
        "input_mode",
        "device[0].input_mode",
        "differential quadrature",
    );
}

#[test]
fn qsb_keys_on_another_model_name_qsb() {
    let text = GOOD
        .replace("model = \"qsb\"", "model = \"tmcpack\"")
        .replace("variant = \"qsb-m\"", "counts_per_step = 4.0");
    refused(
        &text,
        "counts_per_step",
        "device[0].counts_per_step",
        "valid on: qsb",
    );
}

#[test]
fn an_axis_on_a_device_in_pwm_or_analog_mode_is_refused() {
    for mode in ["pwm", "analog"] {
        let text = with_device_keys(&format!("input_mode = \"{mode}\""));
        refused(
            &text,
            "device = \"feeder_qsb\"",
            "axis[0].device",
            "carries no axis",
        );
    }
}

const SIGNAL: &str = "\n[[signal]]\nname = \"s\"\ndevice = \"feeder_qsb\"\n";

#[test]
fn signals_that_clash_with_the_motor_drive_the_enable_line_or_the_mode_are_refused() {
    let cases = [
        ("", "digital-in", "io1", "step line"),
        ("", "digital-out", "io2", "direction line"),
        ("enable_output = 3", "digital-in", "io3", "enable_output"),
        ("capture_input = 0", "digital-out", "io0", "capture_input"),
        (
            "",
            "analog-in",
            "encoder",
            "input_mode = \"pwm\" or \"analog\"",
        ),
        ("", "analog-in", "capture", "set capture_input"),
    ];
    for (keys, kind, pin, says) in cases {
        let mut text = with_device_keys(keys);
        text.push_str(&format!("{SIGNAL}kind = \"{kind}\"\npin = \"{pin}\"\n"));
        refused(&text, &format!("pin = \"{pin}\""), "signal[0].pin", says);
    }
    // Without an axis the -M's motor drive is off: io1 and io2 are I/O.
    let text = format!(
        "{}{SIGNAL}kind = \"digital-out\"\npin = \"io1\"\n",
        &GOOD[..GOOD.find("[[axis]]").expect("axis")]
    );
    let config = parse(&text).expect("io1 without a motor drive");
    assert_eq!(config.signals.len(), 1);
    // In pwm mode, no axis: the encoder pin.
    let text = format!(
        "{}input_mode = \"pwm\"\n{SIGNAL}kind = \"analog-in\"\npin = \"encoder\"\n",
        &GOOD[..GOOD.find("[[axis]]").expect("axis")]
    );
    parse(&text).expect("the encoder pin in pwm mode");
}

#[test]
fn warnings_for_keys_without_effect_and_a_stream_the_line_cannot_carry() {
    let warned = |text: &str, key: &str, says: &str| {
        let config = parse(text).expect("accepted with a warning");
        let warning = config
            .warnings
            .iter()
            .find(|w| w.key == key)
            .unwrap_or_else(|| panic!("no warning for {key}: {:?}", config.warnings));
        assert!(warning.message.contains(says), "{}", warning.message);
        assert_eq!(
            warning.line,
            line_of(text, key.rsplit('.').next().unwrap_or(key))
        );
    };
    warned(
        &with_device_keys("stream_interval_ms = 2.0"),
        "device[0].stream_interval_ms",
        "1 tick = 1.953125 ms",
    );
    warned(
        &with_device_keys("enable_active = \"high\""),
        "device[0].enable_active",
        "without enable_output",
    );
    warned(
        &with_device_keys("silence_ms = 150"),
        "device[0].silence_ms",
        "makes a healthy board look dead",
    );
    warned(
        &with_device_keys("capture_edge = \"falling\""),
        "device[0].capture_edge",
        "without capture_input",
    );
    // No axis (a signal keeps the server from being empty).
    let no_axis = format!(
        "{}enable_output = 0\n{SIGNAL}kind = \"digital-in\"\npin = \"io1\"\n",
        &GOOD[..GOOD.find("[[axis]]").expect("axis")]
    );
    warned(&no_axis, "device[0].enable_output", "no axis drives");
    let slow = with_device_keys("stream_interval_ms = 1.953125").replace("230400", "9600");
    warned(&slow, "device[0].stream_interval_ms", "skip samples");
}

/// The effective parameters of device 0.
fn rows(config: &ServerConfig) -> Vec<(String, String)> {
    motion_config::boards::describe(config)
        .into_iter()
        .filter(|row| row.owner == Owner::Device(0))
        .map(|row| (row.key, row.value))
        .collect()
}

fn owned(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect()
}

#[test]
fn describe_lists_every_key_with_its_effective_value() {
    let defaults = parse(GOOD).expect("good");
    assert_eq!(
        rows(&defaults),
        owned(&[
            ("counts_per_step", "10"),
            ("home_direction", "negative"),
            ("home_max_travel", "2500 mm"),
            ("home_offset", "0 mm"),
            ("index_polarity", "normal"),
            ("stream_interval_ms", "1.953125 ms (1 tick)"),
            ("host_latency_ms", "5 ms"),
            ("silence_ms", "500 ms"),
            ("enable_output", "none"),
            ("enable_active", "low"),
            ("input_mode", "quadrature"),
            ("count_mode", "x4"),
            ("count_range", "free-running"),
            ("index_action", "none"),
            ("index_sync", "synchronous"),
            ("capture_input", "none"),
            ("capture_edge", "rising"),
            ("capture_index", "false"),
            ("trigger_on", "none"),
            ("compare_position", "none"),
            ("trigger_active", "low"),
        ])
    );
    let set = parse(&with_device_keys(
        "counts_per_step = -4.0\nindex_polarity = \"inverted\"\nstream_interval_ms = 10.0\nhost_latency_ms = 20.0\nsilence_ms = 250\nenable_output = 3\ninput_mode = \"quadrature\"\ncapture_input = 0\ncapture_edge = \"falling\"\nhome_direction = \"positive\"\nhome_max_travel = 50.0\nhome_offset = 1.5",
    ))
    .expect("set");
    assert_eq!(
        rows(&set),
        owned(&[
            ("counts_per_step", "-4"),
            ("home_direction", "positive"),
            ("home_max_travel", "50 mm"),
            ("home_offset", "1.5 mm"),
            ("index_polarity", "inverted"),
            // 10 ms is nearest to 5 ticks of 1/512 s.
            ("stream_interval_ms", "9.765625 ms (5 ticks)"),
            ("host_latency_ms", "20 ms"),
            ("silence_ms", "250 ms"),
            ("enable_output", "3"),
            ("enable_active", "low"),
            ("input_mode", "quadrature"),
            ("count_mode", "x4"),
            ("count_range", "free-running"),
            ("index_action", "none"),
            ("index_sync", "synchronous"),
            ("capture_input", "0"),
            ("capture_edge", "falling"),
            ("capture_index", "false"),
            ("trigger_on", "none"),
            ("compare_position", "none"),
            ("trigger_active", "low"),
        ])
    );
}

/// Runs the built driver against the simulated board of `config`'s sim link 0 for `ms`
/// and returns the command lines it sent, decoded with the protocol crate.
fn start_up(config: &ServerConfig, ms: u64) -> Vec<String> {
    let mut drivers = motion_config::boards::build(config).expect("drivers");
    let driver = &mut drivers[0];
    let mut link = motion_config::boards::sim_link(config, 0);
    let mut lines = Vec::new();
    let mut buf = [0u8; 512];
    let mut commands = CommandDecoder::new();
    for tick in 0..ms {
        let now = Duration::from_millis(tick);
        while let Ok(n @ 1..) = link.read(now, &mut buf) {
            driver.handle_rx(now, &buf[..n]);
        }
        driver.handle_timeout(now);
        while let Some(sent) = driver.poll_transmit(now, &mut buf) {
            let bytes = &buf[..sent.len];
            link.write(now, bytes).expect("sim link");
            let (_, line) = commands.decode(bytes);
            let line = line.expect("a whole line").expect("a command line");
            Request::from_line(&line).expect("a command of the command list");
            let text = String::from_utf8_lossy(bytes).trim_end().to_owned();
            lines.push(text);
        }
    }
    assert!(driver.status().online, "{lines:?}");
    lines
}

#[test]
fn the_built_driver_writes_the_configured_parameters_to_the_simulated_board() {
    let text = with_device_keys(
        "counts_per_step = 4.0\nindex_polarity = \"inverted\"\nstream_interval_ms = 10.0\nenable_output = 3\ncapture_input = 0\ncapture_edge = \"falling\"",
    )
    .replace(
        "type = \"serial\"\npath = \"/dev/does-not-exist-motiond-qsb-test\"",
        "type = \"sim\"",
    );
    let config = parse(&text).expect("sim config");
    let lines = start_up(&config, 40);
    // 100 mm/s × 100 counts/mm / 4 = 2500 steps/s → 2496; 1000 mm/s² → 25000 → 24992.
    for expected in [
        "W1061A0", "W164", "W048", "W0C5", "W0F9C0", "R02", "W02811", "W017", "W162", "S05", "S0E",
    ] {
        assert!(
            lines.iter().any(|l| l == expected),
            "{expected} in {lines:?}"
        );
    }
    assert!(
        !lines.iter().any(|l| l == "S01"),
        "no digital signal to stream"
    );
}

#[test]
fn the_real_hardware_example_is_valid_and_means_what_its_comments_say() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/examples/qsb-real.toml");
    let config = ServerConfig::load(&path).expect("the example is valid");
    assert!(config.warnings.is_empty(), "{:?}", config.warnings);
    let rows = rows(&config);
    for (key, value) in [
        ("counts_per_step", "4"),
        ("home_direction", "positive"),
        ("home_max_travel", "60 mm"),
        ("home_offset", "0 mm"),
        ("enable_output", "3"),
        ("enable_active", "low"),
    ] {
        assert!(
            rows.contains(&(key.to_owned(), value.to_owned())),
            "{key} = {value} in {rows:?}"
        );
    }
    assert_eq!(config.signals.len(), 2);
}

/// `GOOD` as a qsb-d measuring wheel (a 500-cycle encoder, degrees) with `lines` added to
/// the device table: nothing is driven, so every counter mode is open to it.
fn measuring(lines: &str) -> String {
    GOOD.replace(
        "variant = \"qsb-m\"",
        &format!("variant = \"qsb-d\"\n{lines}"),
    )
    .replace(
        "counts_per_unit = 100.0",
        "counts_per_unit = 1.3888888888888888",
    )
    .replace("min = -1000.0", "min = 0.0")
    .replace("max = 1000.0", "max = 360.0")
}

#[test]
fn counter_modes_are_read_described_and_within_a_machine_param() {
    let text = measuring(
        "count_mode = \"x1\"\ncount_range = \"modulo-n\"\ncount_limit = 499\nindex_action = \"reset\"",
    );
    let config = parse(&text).expect("a modulo-n wheel");
    assert!(config.warnings.is_empty(), "{:?}", config.warnings);
    let described = rows(&config);
    for (key, value) in [
        ("count_mode", "x1"),
        ("count_range", "modulo-n 0..=499"),
        ("index_action", "reset"),
        ("index_sync", "synchronous"),
    ] {
        assert!(
            described.contains(&(key.to_owned(), value.to_owned())),
            "{key} = {value} in {described:?}"
        );
    }
    // The longest text a counter row can have fits whole in a MachineParam.
    let widest = measuring("count_range = \"range-limit\"\ncount_limit = 2147483647");
    let rows_widest = rows(&parse(&widest).expect("widest"));
    let (_, range) = rows_widest
        .iter()
        .find(|(key, _)| key == "count_range")
        .expect("count_range row");
    assert_eq!(range, "range-limit 0..=2147483647");
    assert!(range.len() <= motion_ipc::PARAM_TEXT_LEN);
    // Step and direction: the index is asynchronous ("Asynchronous index mode is set in
    // non-quadrature modes").
    let steps = parse(&measuring("count_mode = \"step-direction\"")).expect("steps");
    assert!(
        rows(&steps).contains(&("index_sync".to_owned(), "asynchronous".to_owned())),
        "{:?}",
        rows(&steps)
    );
}

#[test]
fn malformed_counter_keys_are_refused_where_they_are() {
    let cases = [
        (
            "count_mode = \"x3\"",
            "count_mode",
            "allowed: \"x4\", \"x2\", \"x1\", \"step-direction\"",
        ),
        (
            "count_range = \"wrap\"",
            "count_range",
            "allowed: \"free-running\", \"single-cycle\", \"range-limit\", \"modulo-n\"",
        ),
        (
            "count_range = \"modulo-n\"\ncount_limit = 0",
            "count_limit",
            "allowed: 1..=2147483647",
        ),
        (
            "count_range = \"range-limit\"\ncount_limit = 4294967295",
            "count_limit",
            "out of range",
        ),
        (
            "count_range = \"modulo-n\"\ncount_limit = 499\nindex_action = \"load-otr\"",
            "index_action",
            "allowed: \"none\", \"reset\", \"load\"",
        ),
        ("index_sync = \"maybe\"", "index_sync", "allowed"),
    ];
    for (lines, key, says) in cases {
        refused(&measuring(lines), key, &format!("device[0].{key}"), says);
    }
}

#[test]
fn counter_modes_that_cannot_work_are_refused_at_their_line() {
    // range-limit and modulo-n need their DTR value.
    for range in ["range-limit", "modulo-n"] {
        refused(
            &measuring(&format!("count_range = \"{range}\"")),
            "count_range",
            "device[0].count_range",
            "needs count_limit",
        );
    }
    // An index that resets or loads a counter that does not wrap makes it jump back.
    for action in ["reset", "load"] {
        refused(
            &measuring(&format!("index_action = \"{action}\"")),
            "index_action",
            "device[0].index_action",
            "needs count_range = \"modulo-n\"",
        );
    }
    // "Asynchronous index mode is set in non-quadrature modes".
    refused(
        &measuring("count_mode = \"step-direction\"\nindex_sync = \"synchronous\""),
        "index_sync",
        "device[0].index_sync",
        "non-quadrature",
    );
    // A qsb-m whose axis drives its stepper plans moves from the count: it must measure
    // the shaft, so only free-running.
    for range in ["single-cycle", "range-limit", "modulo-n"] {
        let text = with_device_keys(&format!("count_range = \"{range}\"\ncount_limit = 1999"));
        refused(
            &text,
            "count_range",
            "device[0].count_range",
            "cannot count for an axis that drives",
        );
    }
    // x1, x2 and step-direction are fine there (counts_per_step counts in that mode).
    for mode in ["x1", "x2", "step-direction"] {
        parse(&with_device_keys(&format!("count_mode = \"{mode}\""))).expect(mode);
    }
}

#[test]
fn counter_keys_without_effect_warn() {
    let config = parse(&measuring("count_limit = 99")).expect("accepted");
    let warning = config
        .warnings
        .iter()
        .find(|w| w.key == "device[0].count_limit")
        .expect("a warning");
    assert!(warning.message.contains("no effect"), "{}", warning.message);
    let no_axis = format!(
        "{}input_mode = \"pwm\"\ncount_mode = \"x1\"\n{SIGNAL}kind = \"analog-in\"\npin = \"encoder\"\n",
        &GOOD[..GOOD.find("[[axis]]").expect("axis")]
    );
    let config = parse(&no_axis).expect("accepted");
    assert!(
        config
            .warnings
            .iter()
            .any(|w| w.key == "device[0].count_mode" && w.message.contains("input_mode")),
        "{:?}",
        config.warnings
    );
}

#[test]
fn the_built_driver_writes_the_counter_mode_to_the_simulated_board() {
    let text = measuring(
        "count_mode = \"x1\"\ncount_range = \"modulo-n\"\ncount_limit = 499\nindex_action = \"reset\"",
    )
    .replace(
        "type = \"serial\"\npath = \"/dev/does-not-exist-motiond-qsb-test\"",
        "type = \"sim\"",
    );
    let config = parse(&text).expect("sim config");
    let lines = start_up(&config, 40);
    // DTR 499 ("Write 499 decimal to DTR, W081F3"), then MDR0 0x6D: sync index, reset
    // CNTR, modulo-n, x1.
    let dtr = lines.iter().position(|l| l == "W081F3");
    let mdr0 = lines.iter().position(|l| l == "W036D");
    assert!(
        matches!((dtr, mdr0), (Some(d), Some(m)) if d < m),
        "{lines:?}"
    );
}

/// `GOOD` with `lines` on the device and `signals` after the axis.
fn with_signals(lines: &str, signals: &str) -> String {
    format!("{}{signals}", with_device_keys(lines))
}

#[test]
fn capture_and_trigger_keys_are_read_and_described_in_the_axis_s_units() {
    let text = with_signals(
        "capture_input = 3\ncapture_index = false\ntrigger_on = [\"match\", \"index\"]\ncompare_position = 12.5\ntrigger_active = \"high\"",
        &format!(
            "{SIGNAL}kind = \"capture\"\npin = \"capture\"\n\n[[signal]]\nname = \"camera\"\ndevice = \"feeder_qsb\"\nkind = \"trigger\"\npin = \"trigger\"\n"
        ),
    );
    let config = parse(&text).expect("a camera trigger and a probe");
    assert!(config.warnings.is_empty(), "{:?}", config.warnings);
    let described = rows(&config);
    for (key, value) in [
        ("capture_input", "3"),
        ("capture_index", "true"),
        ("trigger_on", "match, index"),
        ("compare_position", "12.5 mm (1250 counts)"),
        ("trigger_active", "high"),
        ("trigger_pulse_ms", "1.953125 ms (INTERVAL RATE)"),
    ] {
        assert!(
            described.contains(&(key.to_owned(), value.to_owned())),
            "{key} = {value} in {described:?}"
        );
    }
    // A capture and a trigger read in the axis's units unless said otherwise: scale
    // 1 / counts_per_unit, its unit.
    for signal in &config.signals {
        assert_eq!(
            (signal.scale, signal.unit.as_str()),
            (0.01, "mm"),
            "{signal:?}"
        );
    }
    let scaled = text.replace(
        "kind = \"capture\"\n",
        "kind = \"capture\"\nscale = 1.0\nunit = \"counts\"\n",
    );
    let config = parse(&scaled).expect("counts");
    assert_eq!(
        (config.signals[0].scale, config.signals[0].unit.as_str()),
        (1.0, "counts")
    );
}

#[test]
fn malformed_capture_and_trigger_keys_are_refused_where_they_are() {
    let cases = [
        ("capture_index = 1", "capture_index", "invalid type"),
        (
            "trigger_on = [\"edge\"]",
            "trigger_on",
            "allowed: \"index\", \"match\", \"underflow\", \"overflow\"",
        ),
        ("trigger_on = \"match\"", "trigger_on", "invalid type"),
        (
            "trigger_on = [\"index\", \"index\"]",
            "trigger_on",
            "listed twice",
        ),
        (
            "trigger_on = [\"match\"]\ncompare_position = nan",
            "compare_position",
            "not a position",
        ),
        (
            "trigger_on = [\"index\"]\ntrigger_active = \"up\"",
            "trigger_active",
            "allowed: \"low\", \"high\"",
        ),
    ];
    for (lines, key, says) in cases {
        let needle = lines.lines().last().expect("a line");
        let needle = &needle[..needle.find(' ').unwrap_or(needle.len())];
        refused(
            &with_device_keys(lines),
            needle,
            &format!("device[0].{key}"),
            says,
        );
    }
}

#[test]
fn triggers_that_cannot_work_are_refused_at_their_line() {
    // "match" compares the counter with DTR: it needs the position.
    refused(
        &with_device_keys("trigger_on = [\"match\"]"),
        "trigger_on",
        "device[0].trigger_on",
        "needs compare_position",
    );
    // In modulo-n and range-limit DTR is count_limit.
    refused(
        &measuring(
            "count_range = \"modulo-n\"\ncount_limit = 499\ntrigger_on = [\"match\"]\ncompare_position = 90.0",
        ),
        "compare_position",
        "device[0].compare_position",
        "DTR is count_limit",
    );
    parse(&measuring(
        "count_range = \"modulo-n\"\ncount_limit = 499\ntrigger_on = [\"match\"]",
    ))
    .expect("match at the wrap, once a revolution");
    // The pulse is on DIG I/O bit 0: not on a qsb-s, not where io0 is something else.
    refused(
        &GOOD.replace(
            "variant = \"qsb-m\"",
            "variant = \"qsb-s\"\ntrigger_on = [\"index\"]",
        ),
        "trigger_on",
        "device[0].trigger_on",
        "a qsb-s has no digital I/O",
    );
    refused(
        &with_device_keys("enable_output = 0\ntrigger_on = [\"index\"]"),
        "trigger_on",
        "device[0].trigger_on",
        "io0 is the enable_output",
    );
    refused(
        &with_device_keys("capture_input = 0\ntrigger_on = [\"index\"]"),
        "trigger_on",
        "device[0].trigger_on",
        "io0 is the capture_input",
    );
    refused(
        &with_signals(
            "trigger_on = [\"index\"]",
            &format!("{SIGNAL}kind = \"digital-in\"\npin = \"io0\"\n"),
        ),
        "pin = \"io0\"",
        "signal[0].pin",
        "io0 is the trigger output",
    );
    // MDR1 B4 is "Trigger/Capture on Index": one bit.
    refused(
        &with_device_keys("capture_index = true\ntrigger_on = [\"match\"]\ncompare_position = 1.0"),
        "capture_index",
        "device[0].capture_index",
        "Trigger/Capture on Index",
    );
    // The pins need their keys.
    refused(
        &with_signals(
            "",
            &format!("{SIGNAL}kind = \"trigger\"\npin = \"trigger\"\n"),
        ),
        "pin = \"trigger\"",
        "signal[0].pin",
        "set trigger_on",
    );
    refused(
        &with_signals(
            "",
            &format!("{SIGNAL}kind = \"capture\"\npin = \"capture\"\n"),
        ),
        "pin = \"capture\"",
        "signal[0].pin",
        "capture_index",
    );
    refused(
        &with_signals(
            "trigger_on = [\"index\"]",
            &format!("{SIGNAL}kind = \"digital-out\"\npin = \"trigger\"\n"),
        ),
        "pin = \"trigger\"",
        "signal[0].pin",
        "cannot be digital-out",
    );
    // compare_position is in the units of the device's axis.
    let no_axis = format!(
        "{}trigger_on = [\"match\"]\ncompare_position = 5.0\n",
        &GOOD[..GOOD.find("[[axis]]").expect("axis")]
    );
    refused(
        &no_axis,
        "compare_position",
        "device[0].compare_position",
        "has no axis",
    );
    // Beyond the 32-bit counter at 100 counts/mm.
    refused(
        &with_device_keys("trigger_on = [\"match\"]\ncompare_position = 3e7"),
        "compare_position",
        "device[0].compare_position",
        "beyond the 32-bit counter",
    );
}

#[test]
fn capture_and_trigger_keys_without_effect_warn() {
    let config = parse(&with_device_keys(
        "trigger_on = [\"index\"]\ncompare_position = 2.0",
    ))
    .expect("accepted");
    assert!(
        config
            .warnings
            .iter()
            .any(|w| w.key == "device[0].compare_position" && w.message.contains("\"match\"")),
        "{:?}",
        config.warnings
    );
    let config = parse(&with_device_keys("trigger_active = \"high\"")).expect("accepted");
    assert!(
        config
            .warnings
            .iter()
            .any(|w| w.key == "device[0].trigger_active"),
        "{:?}",
        config.warnings
    );
}

#[test]
fn the_built_driver_writes_the_trigger_and_capture_to_the_simulated_board() {
    let text =
        with_device_keys("capture_input = 3\ntrigger_on = [\"match\"]\ncompare_position = 12.5")
            .replace(
                "type = \"serial\"\npath = \"/dev/does-not-exist-motiond-qsb-test\"",
                "type = \"sim\"",
            );
    let config = parse(&text).expect("sim config");
    let lines = start_up(&config, 40);
    // DTR 1250 (12.5 mm × 100 counts/mm) before MDR0, MDR1 "B5 Trigger on Match", DIG I/O
    // CONFIG 0x1180 (B12, bit 0 an output, the interrupt on io3), CAPTURE and STR
    // streamed, and STR cleared once online.
    let at = |line: &str| lines.iter().position(|l| l == line);
    let order = [
        at("W084E2"),
        at("W0343"),
        at("W0420"),
        at("W021180"),
        at("S05"),
        at("S06"),
        at("S0E"),
        at("W093"),
    ];
    assert!(order.iter().all(Option::is_some), "{lines:?}");
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{lines:?}");
}
