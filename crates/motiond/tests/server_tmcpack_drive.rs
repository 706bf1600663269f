//! The Trinamic pack's drive functions beyond the ramp end to end, from another process
//! (issue 29 items 1, 7, 8): motiond drives a simulated SIXpack on a pseudo-terminal with
//! `power_down = "restore"`, a `microstep_table`, a `start_velocity` and an axis in the PI
//! position mode. The pack's supply fails while the server runs on: x keeps its reference
//! at the position it had, without a search, and the device's description says the
//! positions were loaded; a position target changed on the fly is followed by the PI
//! controller; the keys are in the published parameters and on the wire.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use iceoryx2::prelude::*;
use motion_ipc::{
    AxisFlags, AxisMode, CommandKind, DeviceState, MachineParams, ServerInfo, ServiceNames,
};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;
use tmcpack::{Action, PowerDownRequest, Request, RequestFrame};

fn service(name: &str) -> ServiceName {
    name.try_into().expect("service name")
}

/// Waits up to 5 s for device 0's description to be `want`.
fn firmware_becomes(
    info: &iceoryx2::port::subscriber::Subscriber<ipc::Service, ServerInfo, ()>,
    want: &str,
) -> String {
    let end = Instant::now() + Duration::from_secs(5);
    let mut last = String::new();
    while Instant::now() < end {
        while let Ok(Some(sample)) = info.receive() {
            if let Some(d) = sample.devices().first() {
                last = d.firmware().to_owned();
            }
        }
        if last == want {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    last
}

fn homed(frame: &motion_ipc::MotionFrame, axis: usize) -> bool {
    frame.axes[axis].flags & AxisFlags::HOMED.0 != 0
}

#[test]
fn a_pack_keeps_its_reference_over_an_outage_and_follows_pi_targets() {
    let name = unique_name("tmcdrive");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let served = PtyBoard::start(&tty, Arc::clone(&pack), epoch, 19_200);
    // x: 100 µsteps/mm; the simulated pack's switch starts 32 mm to the right of where the
    // rotor stands. y: the PI controller, ramps starting at 5 mm/s.
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "rs485"
type = "serial"
path = "{}"
baud = 19200

[[device]]
name = "pack"
link = "rs485"
model = "tmcpack"
address = 1
power_down = "restore"
microstep_table = [20, 40, 60, 80, 100, 120, 140, 160, 180, 200, 215, 230, 240, 248, 253, 255]

[[axis]]
name = "x"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 50.0
max_accel = 250.0
reference = {{ side = "right" }}

[[axis]]
name = "y"
device = "pack"
channel = 1
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 50.0
max_accel = 250.0
start_velocity = 5.0
position_mode = "pi"
pi = {{ propdiv = 4 }}
"#,
            tty.display()
        ),
    );
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let names = ServiceNames::new(&name);
    let info = client
        .node
        .service_builder(&service(&names.info()))
        .publish_subscribe::<ServerInfo>()
        .open()
        .expect("info service")
        .subscriber_builder()
        .create()
        .expect("info subscriber");
    let params = client
        .node
        .service_builder(&service(&names.params()))
        .publish_subscribe::<MachineParams>()
        .open()
        .expect("params service")
        .subscriber_builder()
        .create()
        .expect("params subscriber");
    let (frame, ready) = client.wait_frame(Duration::from_secs(15), |f| {
        f.device_state(0) == DeviceState::Online && f.axes[0].flags & AxisFlags::STALE.0 == 0
    });
    assert!(ready, "{:?}", frame.axes()[0]);
    assert_eq!(
        firmware_becomes(&info, "SIXpack V1.4.9 #1001 PD armed"),
        "SIXpack V1.4.9 #1001 PD armed"
    );
    // The published parameters: the keys as the driver uses them, from the config.
    let mut rows = Vec::new();
    let end = Instant::now() + Duration::from_secs(3);
    while rows.is_empty() && Instant::now() < end {
        while let Ok(Some(sample)) = params.receive() {
            rows = sample
                .entries()
                .iter()
                .map(|p| (p.key().to_owned(), p.value().to_owned(), p.from_config != 0))
                .collect();
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let row = |key: &str| {
        rows.iter()
            .find(|(k, _, _)| k == key)
            .cloned()
            .unwrap_or_else(|| panic!("no {key} in {rows:?}"))
    };
    assert_eq!(
        row("power_down"),
        (
            "power_down".into(),
            "restore (save; loaded after a boot)".into(),
            true
        )
    );
    assert!(row("microstep_table").1.starts_with("hex 14283C50"));
    // One row per axis: x's (ramp, the default) comes first.
    assert_eq!(
        row("position_mode"),
        ("position_mode".into(), "ramp ($14, $26, $23)".into(), false)
    );

    // Home x at its switch, then to 20 mm.
    let reply = client.command(0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, done) = client.wait_frame(Duration::from_secs(15), |f| {
        homed(f, 0) && f.axes[0].mode == AxisMode::Hold as u8
    });
    assert!(done, "homed: {:?}", frame.axes()[0]);
    let reply = client.command(0, CommandKind::Position, [20.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, there) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes[0].flags & AxisFlags::ARRIVED.0 != 0 && (f.axes[0].position - 20.0).abs() < 0.01
    });
    assert!(there, "{:?}", frame.axes()[0]);
    std::thread::sleep(Duration::from_millis(200));
    let physical = pack.lock().expect("pack").motor(0).expect("m0").physical;

    // The pack's supply fails and comes back; the server runs on.
    pack.lock().expect("pack").power_outage(epoch.elapsed());
    let (_, lost) = client.wait_frame(Duration::from_secs(3), |f| {
        f.device_state(0) != DeviceState::Online
    });
    assert!(lost, "the server saw the pack go");
    let (frame, back) = client.wait_frame(Duration::from_secs(10), |f| {
        f.device_state(0) == DeviceState::Online
            && homed(f, 0)
            && f.axes[0].flags & AxisFlags::STALE.0 == 0
    });
    assert!(back, "referenced again: {:?}", frame.axes()[0]);
    assert!(
        (frame.axes[0].position - 20.0).abs() < 1e-9,
        "{:?}",
        frame.axes()[0]
    );
    assert!(!homed(&frame, 1), "y never had a reference");
    assert_eq!(
        firmware_becomes(&info, "SIXpack V1.4.9 #1001 PD loaded"),
        "SIXpack V1.4.9 #1001 PD loaded"
    );
    // No search: the rotor did not move, and 5 mm more are 500 µsteps of it.
    assert_eq!(
        pack.lock().expect("pack").motor(0).expect("m0").physical,
        physical
    );
    let reply = client.command(0, CommandKind::Position, [25.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, there) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes[0].flags & AxisFlags::ARRIVED.0 != 0 && (f.axes[0].position - 25.0).abs() < 0.01
    });
    assert!(there, "{:?}", frame.axes()[0]);
    assert_eq!(
        pack.lock().expect("pack").motor(0).expect("m0").physical - physical,
        500
    );

    // y: the PI controller, its target changed while it runs towards the first.
    let reply = client.command(1, CommandKind::Position, [30.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    std::thread::sleep(Duration::from_millis(150));
    let on_the_way = pack.lock().expect("pack").motor(1).expect("m1");
    assert_eq!(on_the_way.action, Action::PiController);
    assert!(
        on_the_way.position > 0 && on_the_way.position < 3000,
        "{on_the_way:?}"
    );
    let reply = client.command(1, CommandKind::Position, [40.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, there) = client.wait_frame(Duration::from_secs(10), |f| {
        f.axes[1].flags & AxisFlags::ARRIVED.0 != 0 && (f.axes[1].position - 40.0).abs() < 0.02
    });
    assert!(there, "{:?}", frame.axes()[1]);
    assert_eq!(
        pack.lock().expect("pack").motor(1).expect("m1").action,
        Action::PiController
    );

    // On the wire: $17 with the table, y's $13 from start_velocity (5 mm/s = 500 µsteps/s
    // at its clock), $19, the $45 steps, $24 targets.
    let words: Vec<u8> = served
        .received
        .lock()
        .expect("log")
        .iter()
        .map(|(_, byte)| *byte)
        .collect();
    let requests: Vec<Request> = words
        .windows(9)
        .filter_map(|w| RequestFrame::decode(w).ok())
        .filter(|f| f.address == 1)
        .map(|f| f.request)
        .collect();
    assert!(requests.contains(&Request::MicrostepTable {
        pointer: 12,
        entries: [240, 248, 253, 255]
    }));
    assert!(requests.iter().any(|r| matches!(
        r,
        Request::PiParameters {
            motor: 1,
            propdiv: 4,
            ..
        }
    )));
    assert!(requests.iter().any(|r| matches!(
        r,
        Request::PowerDown { flags, .. } if *flags == PowerDownRequest::LOAD_POSITIONS
    )));
    assert!(requests.contains(&Request::PiTarget {
        motor: 1,
        target: 4000
    }));
    let vstart = requests.iter().find_map(|r| match r {
        Request::StartingVelocity {
            motor: 1, vstart, ..
        } => Some(*vstart),
        _ => None,
    });
    assert!(vstart.is_some_and(|v| v > 5), "{vstart:?}");
    assert_eq!(pack.lock().expect("pack").microstep_table()[15], 255);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
