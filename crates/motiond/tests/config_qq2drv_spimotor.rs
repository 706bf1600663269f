//! The machine keys of the QuadQuad2Drv (`qq2drv`) and SPI_motor (`spimotor`) boards:
//! malformed values fail `motiond --check-config` with file:line:column and the key;
//! warnings are printed and the config is used; valid values reach the wire, decoded with
//! the boards' protocol crates, at start-up and again after the board resets; and
//! `describe` lists every key with the value in effect.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::Command;

use motion_config::{Owner, ServerConfig};
use motion_drivers::Driver;
use motion_link::sim::SpiDevice;

const QQ2DRV: &str = r#"
[server]
name = "t"

[[link]]
name = "spi"
type = "sim"
speed_hz = 500000

[[device]]
name = "quad"
link = "spi"
model = "qq2drv"

[[axis]]
name = "x"
device = "quad"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -50.0
max = 50.0
max_velocity = 20.0
max_accel = 200.0
pid_position = { p = 120, i = 400, d = 650, windup = 900 }
pid_velocity = { p = 90, i = 250, d = 0 }
power_limit = 0.5

[[axis]]
name = "y"
device = "quad"
channel = 2
unit = "mm"
counts_per_unit = -200.0
min = 0.0
max = 100.0
max_velocity = 10.0
max_accel = 100.0
home = { input = "edge", active_high = false, direction = "positive", spacing = 2.5 }
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-qq2spi-test-{}", std::process::id()));
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
    let location = format!("{name}:{}:", line_of(text, needle));
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

fn parse(text: &str) -> ServerConfig {
    ServerConfig::parse(Path::new("test.toml"), text).unwrap_or_else(|e| panic!("{e}"))
}

/// The value `describe` gives for `key` of `owner`.
fn described(config: &ServerConfig, owner: Owner, key: &str) -> String {
    motion_config::boards::describe(config)
        .into_iter()
        .find(|row| row.owner == owner && row.key == key)
        .unwrap_or_else(|| panic!("no row {key} for {owner:?}"))
        .value
}

// --- qq2drv: config errors -----------------------------------------------------------

#[test]
fn qq2drv_the_example_config_passes() {
    let (code, stderr) = check("qq2drv_good.toml", QQ2DRV);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn qq2drv_a_pid_constant_beyond_u16() {
    let text = QQ2DRV.replace("p = 120", "p = 70000");
    assert_fails(
        "qq2drv_pid_p.toml",
        &text,
        "p = 70000",
        "axis[0].pid_position.p",
        "70000 is out of range; allowed: 0..=65535",
    );
}

#[test]
fn qq2drv_a_windup_beyond_8191() {
    let text = QQ2DRV.replace("windup = 900", "windup = 8192");
    assert_fails(
        "qq2drv_windup.toml",
        &text,
        "windup = 8192",
        "axis[0].pid_position.windup",
        "allowed: 0..=8191",
    );
}

#[test]
fn qq2drv_the_velocity_pid_has_no_windup() {
    let text = QQ2DRV.replace("d = 0 }", "d = 0, windup = 10 }");
    assert_fails(
        "qq2drv_velocity_windup.toml",
        &text,
        "windup = 10",
        "axis[0].pid_velocity.windup",
        "packet 32 (velocity PID constants) has no windup limit",
    );
}

#[test]
fn qq2drv_a_negative_pid_constant_and_a_power_limit_above_one_are_both_reported() {
    let text = QQ2DRV
        .replace("i = 250", "i = -1")
        .replace("power_limit = 0.5", "power_limit = 1.5");
    assert_fails(
        "qq2drv_two.toml",
        &text,
        "i = -1",
        "axis[0].pid_velocity.i",
        "-1 is out of range",
    );
    assert_fails(
        "qq2drv_two.toml",
        &text,
        "power_limit = 1.5",
        "axis[0].power_limit",
        "1.5 is out of range; allowed: 0.0..=1.0",
    );
}

#[test]
fn qq2drv_a_pid_constant_of_the_wrong_type_or_an_unknown_pid_key() {
    let text = QQ2DRV.replace("d = 650", "d = 6.5");
    assert_fails(
        "qq2drv_type.toml",
        &text,
        "d = 6.5",
        "axis[0].pid_position.d",
        "expected an integer",
    );
    let text = QQ2DRV.replace("d = 650", "dd = 650");
    assert_fails(
        "qq2drv_unknown.toml",
        &text,
        "dd = 650",
        "axis[0].pid_position",
        "unknown field `dd`",
    );
}

#[test]
fn qq2drv_keys_on_a_tmcpack_axis_name_qq2drv() {
    let text = QQ2DRV
        .replace("model = \"qq2drv\"", "model = \"tmcpack\"\naddress = 1")
        .replace("type = \"sim\"\nspeed_hz = 500000", "type = \"sim\"\nbaud = 9600")
        .replace(
            "home = { input = \"edge\", active_high = false, direction = \"positive\", spacing = 2.5 }",
            "",
        );
    assert_fails(
        "qq2drv_on_tmcpack.toml",
        &text,
        "pid_position = {",
        "axis[0].pid_position",
        "`pid_position` is not a key of tmcpack axes; it is valid on: qq2drv",
    );
    assert_fails(
        "qq2drv_on_tmcpack.toml",
        &text,
        "power_limit = 0.5",
        "axis[0].power_limit",
        "valid on: qq2drv",
    );
}

#[test]
fn qq2drv_a_clock_above_500_khz_is_a_warning() {
    let text = QQ2DRV.replace("speed_hz = 500000", "speed_hz = 1000000");
    let (code, stderr) = check("qq2drv_fast.toml", &text);
    assert_eq!(code, Some(0), "a warning, not an error:\n{stderr}");
    let location = format!("qq2drv_fast.toml:{}:", line_of(&text, "speed_hz = 1000000"));
    assert!(stderr.contains(&location), "{stderr}");
    assert!(stderr.contains("warning: `link[0].speed_hz`"), "{stderr}");
    assert!(
        stderr.contains("recommend clocking SPI up to 500kHz"),
        "{stderr}"
    );
}

// --- qq2drv: the keys on the wire ------------------------------------------------------

/// Drives `driver` against `board` for `ticks` milliseconds from `from`; returns every
/// request written (parsed later) with its time.
fn run_qq2drv(
    driver: &mut dyn Driver,
    board: &mut board_qq2drv::sim::Qq2drvSim,
    from: Duration,
    ticks: u32,
) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut mosi = [0u8; 256];
    let mut miso = [0u8; 256];
    for tick in 0..ticks {
        let now = from + Duration::from_millis(u64::from(tick));
        driver.handle_timeout(now);
        while let Some(transmit) = driver.poll_transmit(now, &mut mosi) {
            let len = transmit.len;
            board.transfer(now, &mosi[..len], &mut miso[..len]);
            driver.handle_rx(now, &miso[..len]);
            let mut rest = &mosi[..len];
            while rest.first() == Some(&qq2drv::STX) {
                let size = usize::from(rest[1]);
                out.push(rest[..size].to_vec());
                rest = &rest[size..];
            }
        }
    }
    out
}

fn qq2drv_start_up_requests(packets: &[Vec<u8>]) -> (Vec<u8>, Vec<qq2drv::Request<'_>>) {
    let requests: Vec<qq2drv::Request<'_>> = packets
        .iter()
        .map(|p| qq2drv::Request::parse(p).expect("a valid request"))
        .collect();
    (requests.iter().map(|r| r.id().as_u8()).collect(), requests)
}

/// Checks the configuration requests for the keys of `QQ2DRV`.
fn assert_qq2drv_keys(requests: &[qq2drv::Request<'_>]) {
    use qq2drv::Request;
    let mut seen = 0;
    for request in requests {
        match request {
            // Packet 30 "Set Position Control PID Constants": axis x (channel 1) as given,
            // axis y (channel 3) at the datasheet defaults P 100, I 500, D 500, windup 600.
            Request::SetPositionPid(entries) => {
                let e: Vec<_> = entries
                    .iter()
                    .map(|e| (e.channels.0, e.p, e.i, e.d, e.windup))
                    .collect();
                assert_eq!(
                    e,
                    [(0b0001, 120, 400, 650, 900), (0b0100, 100, 500, 500, 600)]
                );
                seen |= 1;
            }
            // Packet 32: x as given, y at P 100, I 200, D 500.
            Request::SetVelocityPid(entries) => {
                let e: Vec<_> = entries
                    .iter()
                    .map(|e| (e.channels.0, e.p, e.i, e.d))
                    .collect();
                assert_eq!(e, [(0b0001, 90, 250, 0), (0b0100, 100, 200, 500)]);
                seen |= 2;
            }
            // Packet 24: 0.5 of 8191 = 4096 (rounded); y at full scale.
            Request::SetPowerLimit(entries) => {
                let e: Vec<_> = entries.iter().map(|e| (e.channels.0, e.limit)).collect();
                assert_eq!(e, [(0b0001, 4_096), (0b0100, 8_191)]);
                seen |= 4;
            }
            // Packet 14: y's edge input, active low, disarmed until a home search; Spacing
            // 2.5 mm × 200 transitions/mm = 500.
            Request::SetInputMode(entries) => {
                let e: Vec<_> = entries.iter().collect();
                assert_eq!(e.len(), 1);
                assert_eq!(e[0].channels.0, 0b0100);
                assert_eq!(e[0].config.mode(), qq2drv::InputMode::Disabled);
                assert!(!e[0].config.active_high());
                assert_eq!(e[0].spacing, 500);
                // `direction = "positive"` in axis units with counts_per_unit = -200 is the
                // negative end in board counts.
                assert_eq!(e[0].config.edge(), qq2drv::EdgeAction::SetOnNegative);
                seen |= 8;
            }
            _ => {}
        }
    }
    assert_eq!(seen, 15, "packets 30, 32, 24 and 14 were all written");
}

#[test]
fn qq2drv_keys_are_written_at_start_up_and_again_after_a_reset() {
    let config = parse(QQ2DRV);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = &mut drivers[0];
    let mut board = board_qq2drv::sim::Qq2drvSim::default();
    let packets = run_qq2drv(driver, &mut board, Duration::ZERO, 50);
    let (ids, requests) = qq2drv_start_up_requests(&packets);
    assert_eq!(&ids[..4], &[1, 7, 9, 5], "the probe");
    assert_qq2drv_keys(&requests);
    assert!(driver.status().online);
    assert_eq!(board.stats().rejected, 0, "the board took every value");
    // The board resets (power cycle): everything is written again.
    board.reset();
    let packets = run_qq2drv(driver, &mut board, Duration::from_millis(50), 200);
    let (_, requests) = qq2drv_start_up_requests(&packets);
    assert_qq2drv_keys(&requests);
    assert_eq!(driver.status().resets, 1);
    assert!(driver.status().online);
}

#[test]
fn qq2drv_a_home_search_runs_the_configured_way_in_board_counts() {
    use motion_drivers::Goal;
    let config = parse(QQ2DRV);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = &mut drivers[0];
    let mut board = board_qq2drv::sim::Qq2drvSim::default();
    run_qq2drv(driver, &mut board, Duration::ZERO, 50);
    // Axis y homes towards its max (positive in mm); 200 transitions/mm reversed.
    driver
        .set_goal(Duration::from_millis(50), 2, Goal::Home { velocity: 400.0 })
        .expect("y can home");
    let packets = run_qq2drv(driver, &mut board, Duration::from_millis(50), 5);
    let (_, requests) = qq2drv_start_up_requests(&packets);
    let (armed, ramp) =
        requests
            .iter()
            .fold((None, None), |(armed, ramp), request| match request {
                qq2drv::Request::SetInputMode(e) => (e.iter().next(), ramp),
                qq2drv::Request::VelocityRamp(e) => (armed, e.iter().next()),
                _ => (armed, ramp),
            });
    let armed = armed.expect("packet 14 armed");
    assert_eq!(armed.config.mode(), qq2drv::InputMode::Edge);
    assert_eq!(armed.config.edge(), qq2drv::EdgeAction::SetOnNegative);
    assert_eq!(armed.spacing, 500);
    assert_eq!(
        ramp.expect("packet 36").velocity,
        -400,
        "towards decreasing counts"
    );
    // Axis x has no home input.
    assert!(
        driver
            .set_goal(Duration::from_millis(55), 0, Goal::Home { velocity: 400.0 })
            .is_err()
    );
}

#[test]
fn qq2drv_describe_lists_every_key_with_its_value() {
    let config = parse(QQ2DRV);
    let x = Owner::Axis(0);
    let y = Owner::Axis(1);
    assert_eq!(described(&config, x, "pid_position.p"), "120");
    assert_eq!(described(&config, x, "pid_position.windup"), "900");
    assert_eq!(described(&config, x, "pid_velocity.d"), "0");
    assert_eq!(described(&config, x, "power_limit"), "0.500 (4096 of 8191)");
    assert_eq!(
        described(&config, x, "home.input"),
        "none (the axis cannot home)"
    );
    // Left at their defaults.
    assert_eq!(described(&config, y, "pid_position.i"), "500");
    assert_eq!(described(&config, y, "pid_velocity.i"), "200");
    assert_eq!(described(&config, y, "power_limit"), "1.000 (8191 of 8191)");
    assert_eq!(described(&config, y, "home.input"), "edge");
    assert_eq!(described(&config, y, "home.active_high"), "false");
    assert_eq!(
        described(&config, y, "home.spacing"),
        "2.5 mm (500 transitions)"
    );
    assert!(config.given.contains(x, "pid_position.p"));
    assert!(!config.given.contains(y, "pid_position.p"));
}

// --- spimotor -------------------------------------------------------------------------

const SPIMOTOR: &str = r#"
[server]
name = "t"

[[link]]
name = "spi"
type = "sim"
speed_hz = 250000

[[device]]
name = "focus_drv"
link = "spi"
model = "spimotor"
address = 0x90
drive = "stepper"
intensity = 96
coils = 1

[[device]]
name = "pumps"
link = "spi"
model = "spimotor"
address = 0x92
drive = "brushed"

[[axis]]
name = "focus"
device = "focus_drv"
channel = 0
unit = "step"
counts_per_unit = 1.0
min = -5000.0
max = 5000.0
max_velocity = 500.0
max_accel = 5000.0
"#;

#[test]
fn spimotor_the_example_config_passes() {
    let (code, stderr) = check("spimotor_good.toml", SPIMOTOR);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn spimotor_an_intensity_beyond_a_byte() {
    let text = SPIMOTOR.replace("intensity = 96", "intensity = 256");
    assert_fails(
        "spimotor_intensity.toml",
        &text,
        "intensity = 256",
        "device[0].intensity",
        "256 is out of range; allowed: 0..=255",
    );
}

#[test]
fn spimotor_coils_are_one_or_two() {
    let text = SPIMOTOR.replace("coils = 1", "coils = 0");
    assert_fails(
        "spimotor_coils.toml",
        &text,
        "coils = 0",
        "device[0].coils",
        "0 is not allowed; allowed: 1 (one coil at a time, port 0x44 ← 0x00) or 2",
    );
    let text = SPIMOTOR.replace("coils = 1", "coils = \"two\"");
    assert_fails(
        "spimotor_coils_type.toml",
        &text,
        "coils = \"two\"",
        "device[0].coils",
        "expected an integer",
    );
}

#[test]
fn spimotor_stepper_keys_on_a_brushed_board_are_errors() {
    let text = SPIMOTOR.replace(
        "drive = \"brushed\"",
        "drive = \"brushed\"\nintensity = 50\ncoils = 2",
    );
    assert_fails(
        "spimotor_brushed.toml",
        &text,
        "intensity = 50",
        "device[1].intensity",
        "`intensity` applies to drive = \"stepper\" only (port 0x10",
    );
    assert_fails(
        "spimotor_brushed.toml",
        &text,
        "coils = 2",
        "device[1].coils",
        "`coils` applies to drive = \"stepper\" only (port 0x44",
    );
}

/// Packet 36: an I32 "Velocity" with "Range: 0 - 100,000". `velocity_ramp` names the
/// board's reading ("signed" by default); anything else is refused at its line with both
/// readings listed, and the key is a qq2drv key only.
#[test]
fn qq2drv_velocity_ramp_names_a_reading_of_packet_36() {
    let device = Owner::Device(0);
    assert!(described(&parse(QQ2DRV), device, "velocity_ramp").starts_with("signed"));
    let with = |value: &str| {
        QQ2DRV.replacen(
            "model = \"qq2drv\"",
            &format!("model = \"qq2drv\"\nvelocity_ramp = {value}"),
            1,
        )
    };
    let unsigned = parse(&with("\"unsigned\""));
    let text = described(&unsigned, device, "velocity_ramp");
    assert!(text.starts_with("unsigned"), "{text}");
    assert!(
        text.len() <= motion_ipc::PARAM_TEXT_LEN,
        "whole in a MachineParam: {text}"
    );
    let drivers = motion_config::boards::build(&unsigned).expect("drivers");
    assert_eq!(drivers.len(), 1);
    for bad in ["\"reverse\"", "\"Signed\""] {
        assert_fails(
            "ramp.toml",
            &with(bad),
            "velocity_ramp",
            "device[0].velocity_ramp",
            "allowed: \"signed\"",
        );
    }
    let (code, stderr) = check("ramp.toml", &with("1"));
    assert_eq!(code, Some(1), "not a string: {stderr}");
    assert!(stderr.contains("velocity_ramp"), "{stderr}");
    let spimotor = SPIMOTOR.replacen(
        "intensity = 96",
        "intensity = 96\nvelocity_ramp = \"signed\"",
        1,
    );
    assert_fails(
        "ramp_on_spimotor.toml",
        &spimotor,
        "velocity_ramp",
        "device[0].velocity_ramp",
        "it is valid on: qq2drv",
    );
}

#[test]
fn spimotor_keys_on_a_qq2drv_name_spimotor() {
    let text = QQ2DRV.replace("model = \"qq2drv\"", "model = \"qq2drv\"\nintensity = 32");
    assert_fails(
        "spimotor_on_qq2drv.toml",
        &text,
        "intensity = 32",
        "device[0].intensity",
        "`intensity` is not a key of qq2drv devices; it is valid on: spimotor",
    );
}

#[test]
fn spimotor_an_intensity_of_zero_is_a_warning() {
    let text = SPIMOTOR.replace("intensity = 96", "intensity = 0");
    let (code, stderr) = check("spimotor_zero.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
    let location = format!("spimotor_zero.toml:{}:", line_of(&text, "intensity = 0"));
    assert!(stderr.contains(&location), "{stderr}");
    assert!(
        stderr.contains("warning: `device[0].intensity`"),
        "{stderr}"
    );
}

/// Drives `driver` against `board` for `ticks` milliseconds from `from`; returns every
/// write it made, decoded with the `spimotor` crate.
fn run_spimotor(
    driver: &mut dyn Driver,
    board: &mut board_spimotor::sim::SpimotorSim,
    from: Duration,
    ticks: u32,
) -> Vec<spimotor::Write> {
    let mut out = Vec::new();
    let mut mosi = [0u8; 256];
    let mut miso = [0u8; 256];
    for tick in 0..ticks {
        let now = from + Duration::from_millis(u64::from(tick));
        driver.handle_timeout(now);
        while let Some(transmit) = driver.poll_transmit(now, &mut mosi) {
            let len = transmit.len;
            miso[..len].fill(0xFF);
            board.transfer(now, &mosi[..len], &mut miso[..len]);
            driver.handle_rx(now, &miso[..len]);
            if let spimotor::Transaction {
                request: spimotor::Request::Write(write),
                ..
            } = spimotor::Transaction::decode(&mosi[..len]).expect("valid")
            {
                out.push(write);
            }
        }
    }
    out
}

#[test]
fn spimotor_keys_are_written_at_start_up_and_again_after_a_power_cycle() {
    use spimotor::{Coils, Write};
    let config = parse(SPIMOTOR);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = &mut drivers[0];
    let mut board = board_spimotor::sim::SpimotorSim::default();
    let writes = run_spimotor(driver, &mut board, Duration::ZERO, 30);
    // Port 0x10 "Set drive intensity for stepper mode" ← 96; port 0x44 ← 0x00 (one coil).
    assert!(writes.contains(&Write::StepperIntensity(96)), "{writes:?}");
    assert!(writes.contains(&Write::Coils(Coils::One)), "{writes:?}");
    assert!(driver.status().online);
    assert_eq!(board.stepper_intensity(), 96);
    assert_eq!(board.coils(), Coils::One);
    // Power cycle: the board is back at 0x20 and its power-on coils; the driver notices
    // (its polls read power-on registers) and writes both again.
    board.power_cycle(Duration::from_millis(30));
    let writes = run_spimotor(driver, &mut board, Duration::from_millis(30), 200);
    assert!(driver.status().resets >= 1);
    assert!(writes.contains(&Write::StepperIntensity(96)), "{writes:?}");
    assert!(writes.contains(&Write::Coils(Coils::One)), "{writes:?}");
    assert_eq!(board.stepper_intensity(), 96);
}

#[test]
fn spimotor_describe_lists_the_stepper_keys() {
    let config = parse(SPIMOTOR);
    let stepper = Owner::Device(0);
    assert_eq!(
        described(&config, stepper, "intensity"),
        "96 (0x60 of 0xff)"
    );
    assert_eq!(described(&config, stepper, "coils"), "1 (port 0x44 ← 0x00)");
    // Left at the defaults: 0x20 (the page's "default is 0x20") and two coils.
    let text = SPIMOTOR.replace("intensity = 96\ncoils = 1\n", "");
    let config = parse(&text);
    assert_eq!(
        described(&config, stepper, "intensity"),
        "32 (0x20 of 0xff)"
    );
    assert_eq!(described(&config, stepper, "coils"), "2 (port 0x44 ← 0x01)");
    let brushed: Vec<String> = motion_config::boards::describe(&config)
        .into_iter()
        .filter(|row| row.owner == Owner::Device(1))
        .map(|row| row.key)
        .collect();
    assert_eq!(
        brushed,
        ["silence_ms"],
        "a brushed board has no stepper keys"
    );
}

/// `silence_ms` (qq2drv, spimotor): how long the board may say nothing before it is
/// declared not answering; 500 ms by default, 100..=60000, below 250 a warning.
#[test]
fn silence_ms_is_described_checked_and_warned_about() {
    for (text, model) in [(QQ2DRV, "qq2drv"), (SPIMOTOR, "spimotor")] {
        let device = Owner::Device(0);
        assert_eq!(described(&parse(text), device, "silence_ms"), "500 ms");
        let with = |value: &str| {
            text.replacen(
                &format!("model = \"{model}\""),
                &format!("model = \"{model}\"\nsilence_ms = {value}"),
                1,
            )
        };
        assert_eq!(
            described(&parse(&with("800")), device, "silence_ms"),
            "800 ms"
        );
        assert_fails(
            "silence.toml",
            &with("50"),
            "silence_ms",
            "device[0].silence_ms",
            "allowed: 100..=60000",
        );
        let (code, stderr) = check("silence.toml", &with("150"));
        assert_eq!(code, Some(0), "{stderr}");
        assert!(
            stderr.contains("warning: `device[0].silence_ms`")
                && stderr.contains("makes a healthy board look dead"),
            "{stderr}"
        );
    }
}

// --- the example configs and the I/O ----------------------------------------------------

fn example(name: &str) -> ServerConfig {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../config/examples")
        .join(name);
    ServerConfig::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_real_machine_examples_are_valid_and_warning_free() {
    let qq = example("qq2drv-real.toml");
    assert!(qq.warnings.is_empty(), "{:?}", qq.warnings);
    assert_eq!(
        described(&qq, Owner::Axis(0), "power_limit"),
        "0.800 (6553 of 8191)"
    );
    assert_eq!(described(&qq, Owner::Axis(0), "pid_velocity.d"), "500");
    assert_eq!(
        described(&qq, Owner::Axis(3), "home.spacing"),
        "5 deg (278 transitions)"
    );
    assert_eq!(qq.signals.len(), 2);
    let spi = example("spimotor-real.toml");
    assert!(spi.warnings.is_empty(), "{:?}", spi.warnings);
    assert_eq!(
        described(&spi, Owner::Device(0), "intensity"),
        "64 (0x40 of 0xff)"
    );
    motion_config::boards::build(&qq).expect("qq2drv drivers");
    motion_config::boards::build(&spi).expect("spimotor drivers");
}

#[test]
fn a_signal_on_an_spi_motor_is_refused_and_on_a_qq2drv_streams_its_channel() {
    let text = format!(
        "{SPIMOTOR}\n[[signal]]\nname = \"s\"\ndevice = \"focus_drv\"\nkind = \"digital-in\"\npin = \"in1\"\n"
    );
    assert_fails(
        "spimotor_signal.toml",
        &text,
        "pin = \"in1\"",
        "signal[0].pin",
        "a spimotor board has no I/O pins",
    );
    // On a qq2drv: QUAD2 has no axis in QQ2DRV; its signal makes the driver stream it.
    let text = format!(
        "{QQ2DRV}\n[[signal]]\nname = \"door\"\ndevice = \"quad\"\nkind = \"digital-in\"\npin = \"in2\"\ninvert = true\n"
    );
    let config = parse(&text);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = &mut drivers[0];
    let mut board = board_qq2drv::sim::Qq2drvSim::default();
    run_qq2drv(driver, &mut board, Duration::ZERO, 50);
    assert_eq!(
        board.data_masks()[1],
        board_qq2drv::driver::STATUS_MASK,
        "channel 2 streams its Status byte"
    );
    let pin = config.signals[0].pin;
    let reading = driver.read_pin(pin).expect("the signal's pin is read");
    assert!(reading.refreshed_at.is_some());
    // Nothing pulls the pin: idle high, inactive under the power-up polarity (active low).
    assert_eq!(reading.value, 0.0);
    // A digital-out on this board cannot be configured.
    let text = format!(
        "{QQ2DRV}\n[[signal]]\nname = \"lamp\"\ndevice = \"quad\"\nkind = \"digital-out\"\npin = \"in2\"\n"
    );
    assert_fails(
        "qq2drv_output.toml",
        &text,
        "pin = \"in2\"",
        "signal[0].pin",
        "cannot be digital-out",
    );
}
