//! The keys of the pack's drive functions beyond the ramp (issue 29 items 1, 7, 8):
//! `power_down`, `microstep_table`, `start_velocity`, `position_mode`, `pi`,
//! `reference.restore`. Each bad value fails `--check-config` at its line; `describe` shows
//! every one with its default; the keys reach the wire at start-up and again after a power
//! cycle; and the simulated pack keeps a reference over an outage.

use core::time::Duration;
use std::path::Path;
use std::sync::{Arc, Mutex};

use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_config::boards::describe;
use motion_config::{Owner, ServerConfig};
use motion_drivers::{Driver, Goal};
use motion_link::Link;
use motion_link::sim::{Duplex, SimLink, StreamDevice};
use tmcpack::{PowerDownRequest, Request, RequestFrame};

use super::{GOOD, check, fails_at, on_device, on_x};

/// Every key of this module set, on a simulated link: x (640 µsteps/mm, 100 mm/s²) starts
/// its ramps at 2 mm/s; the rotary axis follows position targets with the PI controller.
const DRIVE_KEYS: &str = r#"
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
power_down = "restore"
microstep_table = [255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255]

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
start_velocity = 2.0
reference = { restore = false }

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
position_mode = "pi"
pi = { propdiv = 2, intdiv = 200, intclip = 50, intinpclip = 2 }
"#;

fn parse(text: &str) -> ServerConfig {
    ServerConfig::parse(Path::new("test.toml"), text).expect("a valid config")
}

#[test]
fn the_drive_keys_pass_and_each_bad_value_is_refused_at_its_line() {
    let (code, stderr) = check("drive.toml", DRIVE_KEYS);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let device = [
        (
            "power_down = \"always\"",
            "power_down",
            "device[0].power_down",
            "allowed: \"off\"",
        ),
        (
            "microstep_table = [1, 2, 3]",
            "microstep_table",
            "device[0].microstep_table",
            "3 entries; the table has exactly 16",
        ),
        (
            "microstep_table = [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 256]",
            "microstep_table",
            "device[0].microstep_table",
            "256 is out of range; allowed: 0..=255",
        ),
    ];
    for (value, needle, key, says) in device {
        fails_at("drive_device.toml", &on_device(value), needle, 0, key, says);
    }
    // x: max_velocity 20 mm/s, max_accel 100 mm/s²: start_velocity 0.2..=20.
    let axis = [
        (
            "start_velocity = 0.1",
            "start_velocity",
            "axis[0].start_velocity",
            "0.2..=20 mm/s: at least max_accel × 2 ms",
        ),
        (
            "start_velocity = 25.0",
            "start_velocity",
            "axis[0].start_velocity",
            "at most max_velocity",
        ),
        (
            "start_velocity = -1.0",
            "start_velocity",
            "axis[0].start_velocity",
            "-1 is not allowed",
        ),
        (
            "position_mode = \"servo\"",
            "position_mode",
            "axis[0].position_mode",
            "allowed: \"ramp\"",
        ),
        (
            "position_mode = \"pi\"\npi = { propdiv = 0 }",
            "pi =",
            "axis[0].pi.propdiv",
            "allowed: 1..=255",
        ),
        (
            "position_mode = \"pi\"\npi = { intdiv = 40000 }",
            "pi =",
            "axis[0].pi.intdiv",
            "allowed: 1..=32767",
        ),
        (
            "position_mode = \"pi\"\npi = { intclip = 0 }",
            "pi =",
            "axis[0].pi.intclip",
            "allowed: 1..=32767",
        ),
        (
            "position_mode = \"pi\"\npi = { intinpclip = 256 }",
            "pi =",
            "axis[0].pi.intinpclip",
            "allowed: 0..=255",
        ),
    ];
    for (value, needle, key, says) in axis {
        fails_at("drive_axis.toml", &on_x(value), needle, 0, key, says);
    }
    // An unknown key in `pi` and a wrong type are refused too.
    let (code, stderr) = check(
        "pi.toml",
        &on_x("position_mode = \"pi\"\npi = { gain = 3 }"),
    );
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("gain"), "{stderr}");
    let (code, stderr) = check("restore.toml", &on_x("reference = { restore = \"yes\" }"));
    assert_eq!(code, Some(1), "{stderr}");
}

/// Keys that would do nothing: `pi` without the PI position mode, `reference.restore`
/// without `power_down = "restore"`. The file is used; a warning says why.
#[test]
fn keys_without_effect_warn() {
    let (code, stderr) = check("pi_warn.toml", &on_x("pi = { propdiv = 4 }"));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("act only on the PI controller"),
        "{stderr}"
    );
    let (code, stderr) = check(
        "restore_warn.toml",
        &on_x("reference = { restore = false }"),
    );
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("restores no positions"),
        "{stderr}"
    );
}

fn value<'r>(rows: &'r [motion_config::boards::ParamRow], owner: Owner, key: &str) -> &'r str {
    rows.iter()
        .find(|r| r.owner == owner && r.key == key)
        .map(|r| r.value.as_str())
        .unwrap_or_else(|| panic!("no row {owner:?} {key}"))
}

#[test]
fn describe_shows_the_drive_keys_and_their_defaults() {
    let dev = Owner::Device(0);
    let (x, turn) = (Owner::Axis(0), Owner::Axis(1));
    let rows = describe(&parse(GOOD));
    assert_eq!(value(&rows, dev, "power_down"), "off (no $45)");
    assert_eq!(
        value(&rows, dev, "microstep_table"),
        "not written (the pack's; factory sine)"
    );
    // x: 100 mm/s² = 64000 µsteps/s²; its clock gives 38.1 µsteps/s per unit: vstart 4
    // (0.238 mm/s) is the smallest with one tick's change at amax within it.
    assert_eq!(
        value(&rows, x, "start_velocity"),
        "0.238 mm/s ($13 vstart 4, minimum)"
    );
    assert_eq!(value(&rows, x, "position_mode"), "ramp ($14, $26, $23)");
    assert_eq!(value(&rows, x, "pi.propdiv"), "8 (not written: the pack's)");
    assert_eq!(
        value(&rows, x, "reference.restore"),
        "true (power_down is not restore)"
    );
    let rows = describe(&parse(DRIVE_KEYS));
    assert_eq!(
        value(&rows, dev, "power_down"),
        "restore (save; loaded after a boot)"
    );
    assert_eq!(
        value(&rows, dev, "microstep_table"),
        "full step, all 255 (written, $17)"
    );
    assert_eq!(
        value(&rows, x, "start_velocity"),
        "1.967 mm/s ($13 vstart 33)"
    );
    assert_eq!(value(&rows, x, "reference.restore"), "false");
    assert_eq!(
        value(&rows, turn, "position_mode"),
        "pi ($24 PI controller)"
    );
    assert_eq!(value(&rows, turn, "pi.propdiv"), "2 ($19)");
    assert_eq!(value(&rows, turn, "pi.intdiv"), "200 ($19)");
    assert_eq!(value(&rows, turn, "pi.intclip"), "50 ($19)");
    assert_eq!(value(&rows, turn, "pi.intinpclip"), "2 ($19)");
    for rows in [describe(&parse(GOOD)), describe(&parse(DRIVE_KEYS))] {
        let mine = [
            "power_down",
            "microstep_table",
            "start_velocity",
            "position_mode",
            "pi.propdiv",
            "pi.intdiv",
            "pi.intclip",
            "pi.intinpclip",
            "reference.restore",
        ];
        for row in rows.iter().filter(|r| mine.contains(&r.key.as_str())) {
            assert!(
                row.value.len() <= motion_ipc::PARAM_TEXT_LEN,
                "{} = {:?} is cut in MachineParam",
                row.key,
                row.value
            );
        }
    }
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

/// Drives `driver` on `link` for `ms` 1 ms ticks from `from`, answering nothing itself;
/// `each` may set goals. Returns every request written, decoded.
fn run(
    driver: &mut dyn Driver,
    link: &mut dyn Link,
    from: Duration,
    ms: u64,
    mut each: impl FnMut(Duration, &mut dyn Driver),
) -> Vec<Request> {
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
            sent.push(frame.request);
        }
    }
    sent
}

fn power_down_steps(sent: &[Request]) -> Vec<PowerDownRequest> {
    sent.iter()
        .filter_map(|r| match r {
            Request::PowerDown { flags, .. } => Some(*flags),
            _ => None,
        })
        .collect()
}

/// From the config to the wire and the simulated pack: `$17` (four words), x's `$13`
/// vstart from `start_velocity` (2 mm/s = 1280 µsteps/s: 33 units of 38.1), turn's `$19`,
/// the `$45` steps; after a power cycle all of it again, with the positions the pack
/// saved loaded, and x (`reference.restore = false`) not referenced while turn, referenced
/// before, is.
#[test]
fn the_drive_keys_reach_the_wire_and_the_pack_keeps_turns_reference() {
    let config = parse(DRIVE_KEYS);
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
    assert_eq!(driver.status().firmware(), "SIXpack V1.4.9 #1001 PD armed");
    let check = |sent: &[Request], sim: &TmcpackSim| {
        for request in tmcpack::table::table_requests(&tmcpack::table::FULL_STEP_TABLE) {
            assert!(sent.contains(&request), "{request:?} in {sent:?}");
        }
        assert!(sent.iter().any(|r| matches!(
            r,
            Request::StartingVelocity {
                motor: 0,
                vstart: 33,
                ..
            }
        )));
        assert!(sent.contains(&Request::PiParameters {
            motor: 1,
            propdiv: 2,
            intdiv: 200,
            intclip: 50,
            intinpclip: 2,
        }));
        assert_eq!(sim.microstep_table(), [255; 16]);
    };
    check(&sent, &sim.lock().expect("sim"));
    // A fresh pack (reset flag 1): load (nothing valid), arm, invalidate; then a check (no
    // bit) every second.
    assert_eq!(
        power_down_steps(&sent)[..3],
        [
            PowerDownRequest::LOAD_POSITIONS,
            PowerDownRequest::ACTIVATE | PowerDownRequest::RESET_STATE,
            PowerDownRequest::INVALIDATE_POSITIONS,
        ]
    );
    // Both axes referenced by a set-position; turn is driven by the PI controller to 400
    // µsteps (45°).
    let mut goals = Some(());
    let sent = run(
        &mut *driver,
        &mut link,
        Duration::from_secs(2),
        6000,
        |now, d| {
            if goals.take().is_some() {
                d.set_goal(now, 0, Goal::SetPosition { counts: 320.0 })
                    .expect("x");
                d.set_goal(now, 1, Goal::SetPosition { counts: 0.0 })
                    .expect("turn");
            }
            if now == Duration::from_millis(2500) {
                d.set_goal(now, 1, Goal::Position { counts: 400.0 })
                    .expect("turn");
            }
        },
    );
    assert!(sent.contains(&Request::PiTarget {
        motor: 1,
        target: 400
    }));
    assert!(driver.channel(0).homed && driver.channel(1).homed);
    assert!((driver.channel(1).position - 400.0).abs() <= 2.0);
    assert!(!driver.channel(1).moving, "the PI controller holds it");
    // The supply goes away and comes back: the pack saved 320 and ~400 and boots.
    let out_at = Duration::from_secs(8);
    sim.lock().expect("sim").power_outage(out_at);
    let again = run(&mut *driver, &mut link, out_at, 8000, |_, _| {});
    check(&again, &sim.lock().expect("sim"));
    assert_eq!(
        power_down_steps(&again)[0],
        PowerDownRequest::LOAD_POSITIONS
    );
    assert!(driver.status().online);
    assert_eq!(driver.status().firmware(), "SIXpack V1.4.9 #1001 PD loaded");
    assert_eq!(driver.channel(0).position, 320.0, "loaded");
    assert!(!driver.channel(0).homed, "reference.restore = false");
    assert!(
        driver.channel(1).homed,
        "referenced before, at rest, restored"
    );
    assert!((driver.channel(1).position - 400.0).abs() <= 2.0);
}
