//! Every tmcpack key, from the config to the bytes on the wire (decoded with the protocol
//! crate) at start-up and again after the pack was power-cycled; `describe`; the defaults;
//! and a simulated pack built from the config that has its switch where the config says.

use core::time::Duration;
use motion_drivers::spec::FromSpec as _;
use std::path::Path;
use std::sync::{Arc, Mutex};

use board_tmcpack::driver::{Currents, TmcpackChannel};
use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_config::boards::describe;
use motion_config::boards::{ParamRow, driver_spec};
use motion_config::{Owner, ServerConfig};
use motion_drivers::{Driver, Goal};
use motion_link::Link;
use motion_link::sim::{Duplex, SimLink, StreamDevice};
use tmcpack::{
    CurrentLevel, MotorMask, MotorOptions, MotorType, ReferenceFlags, Request, RequestFrame,
};

/// Every tmcpack key set to something other than its default, on a simulated link.
pub const ALL_KEYS: &str = r#"
[server]
name = "t"

[[link]]
name = "bus"
type = "sim"
baud = 19200

[[device]]
name = "pack"
link = "bus"
model = "tmcpack"
address = 1
reply_address = 200
switchover_ms = 4
packet_timeout_ms = 10
ready_output = { motors = [0, 1], reference = [0] }
amax_divisor = 16
stop_no_ref_bit = 6
host_latency_ms = 16.5
silence_ms = 800

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
home = { position = 0.75 }  # within test_range: StopNull checks the switch there ($27)
current = { peak = 60.0, standby = 0.0, standstill = 38.0, constant = 75.0, accel = 100.0, standby_delay_ms = 500 }
reference = { side = "right", active = "high", center = true, stop_at_switch = true, soft_stop = true, debounce_ms = 10, null_offset = 0.5, test_range = 1.0, fast = false, mechanical = false }
analog_stop = { left = 100, right = 900 }

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
rotary = true
current = { peak = 60.0 }

[[signal]]
name = "door"
device = "pack"
kind = "digital-in"
pin = "ref2"

[[signal]]
name = "level"
device = "pack"
kind = "analog-in"
pin = "analog6"
"#;

fn parse(text: &str) -> ServerConfig {
    ServerConfig::parse(Path::new("test.toml"), text).expect("a valid config")
}

/// The simulated pack, shared between the wire and the test.
#[derive(Debug)]
struct Shared(Arc<Mutex<TmcpackSim>>);

impl StreamDevice for Shared {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.0.lock().expect("sim").receive(now, bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.0.lock().expect("sim").transmit(now, out)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.0.lock().expect("sim").next_event(now)
    }
    fn baud(&self) -> Option<u32> {
        self.0.lock().expect("sim").baud()
    }
}

/// Drives `driver` on `link` for `ms` 1 ms ticks from `from`, calling `each` every tick;
/// returns every request written, decoded, with its time.
fn run(
    driver: &mut dyn Driver,
    link: &mut dyn Link,
    from: Duration,
    ms: u64,
    mut each: impl FnMut(Duration, &mut dyn Driver),
) -> Vec<(Duration, Request)> {
    let mut buf = [0u8; 256];
    let mut rx = [0u8; 256];
    let mut sent = Vec::new();
    for tick in 0..ms {
        let now = from + Duration::from_millis(tick);
        let len = link.read(now, &mut rx).expect("sim link");
        driver.handle_rx(now, &rx[..len]);
        driver.handle_timeout(now);
        each(now, driver);
        if let Some(t) = driver.poll_transmit(now, &mut buf) {
            link.write(now, &buf[..t.len]).expect("sim link");
            let frame = RequestFrame::decode(&buf[..t.len]).expect("a valid 9-byte word");
            assert_eq!(frame.address, 1);
            sent.push((now, frame.request));
        }
    }
    sent
}

/// What the keys of `ALL_KEYS` must put on the wire (manual 8.3, 8.5, 8.6).
fn expected() -> Vec<Request> {
    vec![
        // switchover_ms = 4: $40 P2,P3 in 2 ms units; the divisor of 19200 baud (65).
        Request::SetBaud {
            divisor: 65,
            switchover: 2,
        },
        // packet_timeout_ms = 10: $41 in 2 ms units.
        Request::PacketTimeout { timeout: 5 },
        // peak = 60 %: round(0.6 · 256) = 154, through the even motor of the pair.
        Request::PeakCurrent {
            motor: 0,
            value: 154,
        },
        // standby 0 %, standstill 38 %, constant 75 %, accel 100 %, T0 = 500 ms / 2 ms.
        Request::CurrentControl {
            motor: 0,
            i0: CurrentLevel::Off,
            i1: CurrentLevel::P38,
            i2: CurrentLevel::P75,
            i3: CurrentLevel::P100,
            t0: 250,
        },
        // poslimit = travel 100 mm · 640; side right: NullLeft clear; center, stop_at_switch;
        // active high: NullPositive; soft_stop; fast = false; StopNoRef always.
        Request::MotorParameters {
            motor: 0,
            poslimit: 64_000,
            motor_type: MotorType::FILTER_SWITCH | MotorType::NULL_CENTER | MotorType::STOP_NULL,
            options: MotorOptions::NULL_POSITIVE
                | MotorOptions::STOP_SOFT
                | MotorOptions::STOP_NO_REF,
        },
        // debounce_ms = 10: 6 mask bits.
        Request::ReferenceParameters {
            motor: 0,
            vrefmax: 0,
            debounce_mask: 0x003F,
            flags: ReferenceFlags::STOP_AFTER_SEARCH,
        },
        // null_offset 0.5 mm, test_range 1 mm.
        Request::NullOffset {
            motor: 0,
            nulloffset: 320,
            testnullrange: 640,
        },
        Request::StopLimits {
            channel: 0,
            left_min: 100,
            right_max: 900,
        },
        // rotary, "deg": one revolution = 360 · 8.8889 = 3200 µsteps; side left (default).
        // stop_no_ref_bit = 6: StopNoRef in bit 6, where the table has NullPositive (the
        // manual's prose, "StopNoRef(P6, Bit 6)"); motor 0 above has both bits either way.
        Request::MotorParameters {
            motor: 1,
            poslimit: 3200,
            motor_type: MotorType::FILTER_SWITCH | MotorType::NULL_LEFT | MotorType::ROTARY,
            options: MotorOptions::FAST_REF | MotorOptions::NULL_POSITIVE,
        },
        Request::ReadyOutput {
            active_mask: MotorMask::M0 | MotorMask::M1,
            reference_mask: MotorMask::M0,
        },
        Request::Outputs {
            ttlout1: false,
            ttlio1_input: true,
            ttlio1: false,
            ttlout1_ready: true,
        },
    ]
}

/// Whether `sent` has `want` ($16's vrefmax is the driver's, not a key: ignored).
fn has(sent: &[Request], want: &Request) -> bool {
    sent.iter().any(|r| match (r, want) {
        (
            Request::ReferenceParameters {
                motor,
                debounce_mask,
                flags,
                ..
            },
            Request::ReferenceParameters {
                motor: m,
                debounce_mask: d,
                flags: f,
                ..
            },
        ) => motor == m && debounce_mask == d && flags == f,
        _ => r == want,
    })
}

#[test]
fn every_key_reaches_the_wire_at_start_up_and_again_after_a_power_cycle() {
    let config = parse(ALL_KEYS);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = drivers.get_mut(0).expect("the pack's driver");
    let sim = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let mut link = SimLink::stream_with(
        "bus",
        19_200,
        Duplex::Half,
        Box::new(Shared(Arc::clone(&sim))),
    );
    let sent = run(&mut *driver, &mut link, Duration::ZERO, 2000, |_, _| {});
    assert!(driver.status().online);
    let requests: Vec<Request> = sent.iter().map(|(_, r)| *r).collect();
    for want in expected() {
        assert!(has(&requests, &want), "{want:?} not in {requests:?}");
    }
    // Queries carry reply_address = 200; the inputs are polled with $30 channel 6.
    assert!(
        requests
            .iter()
            .all(|r| r.reply_to().is_none_or(|a| a == 200))
    );
    assert!(requests.contains(&Request::ReadInput {
        channel: 6,
        reply_to: 200
    }));
    let check_sim = |sim: &TmcpackSim| {
        assert_eq!(sim.switchover(), Duration::from_millis(4));
        assert_eq!(sim.packet_timeout(), Duration::from_millis(10));
        assert_eq!(
            sim.ready_output(),
            Some((MotorMask::M0 | MotorMask::M1, MotorMask::M0))
        );
        assert_eq!(sim.stop_limits(0), Some((100, 900)));
        assert_eq!(sim.stop_limits(1), Some((0, 1023)));
        assert_eq!(sim.ttlio1_output(), None, "TTLIO1 is an input");
    };
    check_sim(&sim.lock().expect("sim"));
    // Power off and on: the pack forgets everything ($CC "All configured parameters will be
    // replaced by the default parameters"); the driver sees the reset flag ($43) and writes
    // it all again.
    let cycled_at = Duration::from_millis(2000);
    sim.lock().expect("sim").power_cycle(cycled_at);
    assert_eq!(
        sim.lock().expect("sim").switchover(),
        Duration::from_millis(6),
        "factory default again"
    );
    let again = run(&mut *driver, &mut link, cycled_at, 6000, |_, _| {});
    let requests: Vec<Request> = again.iter().map(|(_, r)| *r).collect();
    for want in expected() {
        assert!(
            has(&requests, &want),
            "{want:?} not written again: {requests:?}"
        );
    }
    assert!(driver.status().online);
    assert!(driver.status().resets >= 1 || driver.status().timeouts >= 3);
    check_sim(&sim.lock().expect("sim"));
}

fn value<'r>(rows: &'r [ParamRow], owner: Owner, key: &str) -> &'r str {
    rows.iter()
        .find(|r| r.owner == owner && r.key == key)
        .map(|r| r.value.as_str())
        .unwrap_or_else(|| panic!("no row {owner:?} {key}"))
}

const DEVICE_KEYS: [&str; 8] = [
    "reply_address",
    "switchover_ms",
    "packet_timeout_ms",
    "ready_output",
    "amax_divisor",
    "stop_no_ref_bit",
    "host_latency_ms",
    "silence_ms",
];
const AXIS_KEYS: [&str; 20] = [
    "current.peak",
    "current.standby",
    "current.standstill",
    "current.constant",
    "current.accel",
    "current.standby_delay_ms",
    "reference.side",
    "reference.active",
    "reference.center",
    "reference.stop_at_switch",
    "reference.soft_stop",
    "reference.debounce_ms",
    "reference.null_offset",
    "reference.test_range",
    "reference.fast",
    "reference.mechanical",
    "rotary",
    "revolution",
    "analog_stop.left",
    "analog_stop.right",
];

#[test]
fn describe_lists_every_key_with_the_value_in_effect() {
    for text in [ALL_KEYS, super::GOOD] {
        let rows = describe(&parse(text));
        for key in DEVICE_KEYS {
            value(&rows, Owner::Device(0), key);
        }
        for axis in [0, 1] {
            for key in AXIS_KEYS {
                value(&rows, Owner::Axis(axis), key);
            }
        }
    }
    let rows = describe(&parse(ALL_KEYS));
    let dev = Owner::Device(0);
    let x = Owner::Axis(0);
    assert_eq!(value(&rows, dev, "reply_address"), "200 (0xC8)");
    assert_eq!(value(&rows, dev, "switchover_ms"), "4 ms ($40)");
    assert_eq!(value(&rows, dev, "packet_timeout_ms"), "10 ms ($41)");
    assert!(value(&rows, dev, "ready_output").starts_with("motors [0, 1], reference [0]"));
    assert!(value(&rows, dev, "amax_divisor").starts_with("16 (7.1 defaults"));
    assert!(value(&rows, dev, "stop_no_ref_bit").starts_with("6 ($15 prose"));
    assert_eq!(
        value(&rows, dev, "host_latency_ms"),
        "16.5 ms (in every reply window)"
    );
    assert_eq!(
        value(&rows, dev, "silence_ms"),
        "800 ms (silence before the verdict)"
    );
    // Whole in `MachineParam`'s 40 bytes, as `motionctl list` shows them.
    for key in [
        "amax_divisor",
        "stop_no_ref_bit",
        "host_latency_ms",
        "silence_ms",
    ] {
        assert!(
            value(&rows, dev, key).len() <= motion_ipc::PARAM_TEXT_LEN,
            "{key}"
        );
    }
    assert_eq!(
        value(&rows, x, "current.peak"),
        "60.2 % ($10 = 154, 0.48 A)"
    );
    assert_eq!(value(&rows, x, "current.standby"), "0 %");
    assert_eq!(value(&rows, x, "current.standstill"), "38 %");
    assert_eq!(
        value(&rows, x, "current.standby_delay_ms"),
        "500 ms (T0 = 250)"
    );
    assert_eq!(
        value(&rows, x, "reference.side"),
        "right ($15 NullLeft clear)"
    );
    assert_eq!(value(&rows, x, "reference.active"), "high");
    assert_eq!(
        value(&rows, x, "reference.debounce_ms"),
        "10 ms ($16 mask $003F)"
    );
    assert_eq!(
        value(&rows, x, "reference.null_offset"),
        "0.5 mm (320 µsteps)"
    );
    assert_eq!(value(&rows, x, "reference.test_range"), "1 mm (640 µsteps)");
    assert_eq!(value(&rows, x, "reference.fast"), "false");
    assert_eq!(value(&rows, x, "analog_stop.left"), "100");
    assert_eq!(value(&rows, Owner::Axis(1), "rotary"), "true");
    assert_eq!(
        value(&rows, Owner::Axis(1), "revolution"),
        "360 deg (poslimit 3200 µsteps)"
    );
    let rows = describe(&parse(super::GOOD));
    assert_eq!(value(&rows, dev, "reply_address"), "254 (0xFE)");
    assert_eq!(value(&rows, dev, "switchover_ms"), "2 ms ($40)");
    assert_eq!(value(&rows, dev, "packet_timeout_ms"), "6 ms ($41)");
    assert_eq!(value(&rows, dev, "ready_output"), "off");
    assert!(value(&rows, dev, "amax_divisor").starts_with("64 ($14 text"));
    assert!(value(&rows, dev, "stop_no_ref_bit").starts_with("5 ($15 table"));
    assert!(value(&rows, x, "current.peak").starts_with("not written"));
    assert_eq!(value(&rows, x, "reference.side"), "left ($15 NullLeft set)");
    assert_eq!(value(&rows, x, "analog_stop.right"), "1023 (no function)");
}

/// Unset keys keep today's driver defaults (`TmcpackChannel::default()`,
/// `Currents::default()`, `TmcpackDriverConfig::default()`).
#[test]
fn unset_keys_keep_the_driver_defaults() {
    let config = parse(super::GOOD);
    let driver = board_tmcpack::driver::TmcpackDriverConfig::from_spec(&driver_spec(
        &config,
        0,
        &config.devices[0],
    ))
    .expect("a valid spec");
    let d = TmcpackChannel::default();
    assert_eq!(driver.reply_address, 0xFE);
    assert_eq!(driver.switchover_units, Some(1));
    assert_eq!(driver.packet_timeout(), 3, "6 ms at 19200 baud");
    assert!(driver.io.ready.is_none());
    let x = driver.channels[0].expect("axis x");
    assert_eq!(x.currents, Currents::default());
    assert_eq!(x.peak_current, None);
    assert_eq!(x.debounce_mask, d.debounce_mask);
    assert_eq!(x.nulloffset, d.nulloffset);
    assert_eq!(x.testnullrange, d.testnullrange);
    assert_eq!(x.options, d.options);
    assert_eq!(x.analog_stop, d.analog_stop);
    // The search runs to decreasing positions by default (home.direction "negative").
    assert_eq!(x.motor_type, d.motor_type | MotorType::NULL_LEFT);
    // A linear axis's reference range is its travel, not the manual's 6400.
    assert_eq!(x.poslimit, 64_000);
    assert_eq!(x.home_position, 0);
}

/// The simulated pack built from the config has its switch where `reference.side` says:
/// a search each way finds it.
#[test]
fn the_simulated_pack_has_the_switch_on_the_configured_side() {
    for side in ["left", "right"] {
        let text = super::GOOD.replacen(
            "type = \"serial\"\npath = \"/dev/does-not-exist-motiond-test\"",
            "type = \"sim\"",
            1,
        );
        let text = text.replacen(
            "max_accel = 100.0",
            &format!("max_accel = 100.0\nreference = {{ side = \"{side}\", active = \"high\" }}"),
            1,
        );
        let config = parse(&text);
        let mut drivers = motion_config::boards::build(&config).expect("drivers");
        let driver = drivers.get_mut(0).expect("driver");
        let mut link = motion_config::boards::sim_link(&config, 0);
        let mut homing = false;
        let mut done = None;
        run(&mut *driver, &mut link, Duration::ZERO, 15_000, |now, d| {
            if !homing && d.status().online && now > Duration::from_millis(1500) {
                d.set_goal(
                    now,
                    0,
                    Goal::Home {
                        velocity: 20.0 * 640.0,
                    },
                )
                .expect("home");
                homing = true;
            }
            let state = d.channel(0);
            if homing && done.is_none() && (state.homed || state.fault.is_some()) {
                done = Some((state.homed, state.fault));
            }
        });
        assert_eq!(done, Some((true, None)), "side {side}: homed, no fault");
    }
}

/// The simulated pack of a device with `amax_divisor = 16` and `stop_no_ref_bit = 6` has
/// that firmware (`sim::machine`): with a closer (`active = "low"`) the driver's `$15` P6
/// has StopNoRef alone, in bit 6, which the table's reading would take for NullPositive
/// and search with the switch's polarity inverted. The search finds the switch.
#[test]
fn the_simulated_pack_has_the_firmware_readings_of_its_device() {
    let text = super::GOOD.replacen(
        "type = \"serial\"\npath = \"/dev/does-not-exist-motiond-test\"",
        "type = \"sim\"",
        1,
    );
    let text = text.replacen(
        "address = 1",
        "address = 1\namax_divisor = 16\nstop_no_ref_bit = 6",
        1,
    );
    let text = text.replacen(
        "max_accel = 100.0",
        "max_accel = 100.0\nreference = { side = \"left\", active = \"low\" }",
        1,
    );
    let config = parse(&text);
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let driver = drivers.get_mut(0).expect("driver");
    let mut link = motion_config::boards::sim_link(&config, 0);
    let mut homing = false;
    let mut done = None;
    let sent = run(&mut *driver, &mut link, Duration::ZERO, 15_000, |now, d| {
        if !homing && d.status().online && now > Duration::from_millis(1500) {
            d.set_goal(
                now,
                0,
                Goal::Home {
                    velocity: 20.0 * 640.0,
                },
            )
            .expect("home");
            homing = true;
        }
        let state = d.channel(0);
        if homing && done.is_none() && (state.homed || state.fault.is_some()) {
            done = Some((state.homed, state.fault));
        }
    });
    assert_eq!(done, Some((true, None)), "homed, no fault");
    let p6 = sent.iter().find_map(|(_, r)| match r {
        Request::MotorParameters {
            motor: 0, options, ..
        } => Some(options.bits() & 0x60),
        _ => None,
    });
    assert_eq!(
        p6,
        Some(0x40),
        "StopNoRef in bit 6, NullPositive (bit 5) clear"
    );
}
