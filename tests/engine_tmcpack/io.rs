//! I/O through the engine and the simulated pack (manual 8.5): inputs show in `read_pin`
//! within the refresh budget, outputs reach the pack, the polling of inputs keeps every
//! axis fresh.

use board_tmcpack::driver::{TmcpackIo, pins};
use board_tmcpack::sim::RefSwitch;
use motion_drivers::{Pin, find_pin};
use motion_link::Link;

use super::*;

pub(super) fn pin(variant: Variant, name: &str) -> Pin {
    find_pin(pins(variant), name).expect("a pin of the pack")
}

pub(super) fn io_config(variant: Variant, inputs: &[&str], outputs: &[&str]) -> TmcpackIo {
    let mut io = TmcpackIo::default();
    for name in inputs {
        io.inputs = io.inputs.with(pin(variant, name));
    }
    for name in outputs {
        io.outputs = io.outputs.with(pin(variant, name));
    }
    io
}

pub(super) fn driver_with_io(
    address: u8,
    variant: Variant,
    motors: &[usize],
    bus_motors: u8,
    io: TmcpackIo,
) -> TmcpackDriver {
    let mut channels = [None; 6];
    for &motor in motors {
        channels[motor] = Some(TmcpackChannel {
            max_velocity: MAX_VELOCITY_MM * COUNTS,
            max_accel: MAX_ACCEL_MM * COUNTS,
            ..TmcpackChannel::default()
        });
    }
    TmcpackDriver::new(TmcpackDriverConfig {
        address,
        variant,
        baud: BAUD,
        bus_motors,
        channels,
        io,
        ..TmcpackDriverConfig::default()
    })
}

/// Task: an input change in the sim shows in `read_pin` within the refresh budget.
#[test]
fn an_input_change_shows_in_read_pin_within_the_refresh_budget() {
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let config = engine_config(
        vec![device("pack", 1)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let inputs = io_config(Variant::SixPack, &["ref0", "analog6", "analog7"], &[]);
    let driver = driver_with_io(1, Variant::SixPack, &[0, 1], 0, inputs);
    let mut rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    wait_online(&mut rig, 2);
    rig.run(300);
    let read = |rig: &Rig, name| {
        rig.engine
            .driver(0)
            .expect("device 0")
            .read_pin(pin(Variant::SixPack, name))
            .expect("configured")
    };
    // Nothing actuates motor 0's switch (a closer at 3200..3519): Ref_In is high.
    assert_eq!(read(&rig, "ref0").value, 1.0);
    // 24 V supply, "1V equals value 22" (noise ±1 LSB).
    assert!((read(&rig, "analog7").value - 528.0).abs() <= 1.0);
    let budget = rig.engine.driver(0).expect("device 0").refresh_budget();
    let changed_at = rig.now;
    {
        let mut sim = board.lock().unwrap();
        sim.set_analog(6, 800);
        sim.set_ref_switch(
            0,
            Some(RefSwitch {
                from: -50,
                to: 50,
                opener: false,
            }),
        );
    }
    let seen = rig.run_until(budget, |_| false);
    assert!(!seen);
    let ref0 = read(&rig, "ref0");
    let analog6 = read(&rig, "analog6");
    assert_eq!(ref0.value, 0.0, "the closed switch pulls Ref_In low");
    assert!((analog6.value - 800.0).abs() <= 1.0, "{}", analog6.value);
    for reading in [ref0, analog6] {
        let at = reading.refreshed_at.expect("read");
        assert!(at > changed_at && at - changed_at <= budget);
    }
    assert!(fresh(&rig, 0) && fresh(&rig, 1));
}

/// Task: a `set_output` reaches the sim's output; on the wire it is one `$32` (decoded with
/// the protocol crate) with both levels.
#[test]
fn set_output_reaches_the_pack() {
    let variant = Variant::QuadPack;
    let mut driver = driver_with_io(
        2,
        variant,
        &[0],
        0,
        io_config(variant, &[], &["ttlio1", "ttlout1"]),
    );
    let (wire, board) = Shared::new(pack(2, variant));
    let mut link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let mut buf = [0u8; 256];
    let mut rx = [0u8; 256];
    let mut sent: Vec<(Duration, Request)> = Vec::new();
    let mut set_at = None;
    for tick in 0..3000u32 {
        let now = Duration::from_millis(u64::from(tick));
        let len = link.read(now, &mut rx).expect("sim link");
        driver.handle_rx(now, &rx[..len]);
        driver.handle_timeout(now);
        if set_at.is_none() && driver.status().online && tick > 1000 {
            driver
                .set_output(now, pin(variant, "ttlio1"), true)
                .expect("driven");
            set_at = Some(now);
        }
        if let Some(t) = driver.poll_transmit(now, &mut buf) {
            link.write(now, &buf[..t.len]).expect("sim link");
            let frame = RequestFrame::decode(&buf[..t.len]).expect("a valid word");
            sent.push((now, frame.request));
        }
    }
    let set_at = set_at.expect("online");
    let outputs: Vec<&(Duration, Request)> = sent
        .iter()
        .filter(|(_, r)| matches!(r, Request::Outputs { .. }))
        .collect();
    assert_eq!(outputs.len(), 2, "start-up and the change: {outputs:?}");
    assert_eq!(
        outputs[1].1,
        Request::Outputs {
            ttlout1: false,
            ttlio1_input: false,
            ttlio1: true,
            ttlout1_ready: false
        }
    );
    assert!(
        outputs[1].0 - set_at < Duration::from_millis(20),
        "commands before polls"
    );
    let sim = board.lock().unwrap();
    assert_eq!(sim.ttlio1_output(), Some(true));
    assert!(!sim.ttlout1());
    let reading = driver.read_pin(pin(variant, "ttlio1")).expect("driven");
    assert_eq!(reading.value, 1.0);
    assert_eq!(
        driver.read_pin(pin(variant, "ttlout1")).map(|r| r.value),
        Some(0.0)
    );
}

/// The refresh-budget test of the sim.toml bus (ten motors, two packs, 19200 baud) again,
/// with inputs polled on both packs: the `$30` polls do not let any axis go stale.
#[test]
fn ten_motors_with_inputs_on_one_bus_stay_fresh_within_the_refresh_budget() {
    let (six, six_board) = Shared::new(pack(1, Variant::SixPack));
    let (quad, quad_board) = Shared::new(pack(2, Variant::QuadPack));
    let (wire, bus) = Shared::new(StreamBus::new().with(six).with(quad));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let mut axes: Vec<AxisConfig> = (0..6).map(|m| axis(&format!("six{m}"), 0, m)).collect();
    axes.extend((0..4).map(|m| axis(&format!("quad{m}"), 1, m)));
    let config = engine_config(vec![device("six", 1), device("quad", 2)], axes);
    // Ten motors and one input poll per pack on the bus.
    let polls = 12;
    let six_io = io_config(
        Variant::SixPack,
        &["ref0", "ref5", "analog6", "jumper1"],
        &["ttlout1"],
    );
    let quad_io = io_config(Variant::QuadPack, &["analog7", "ttlio1"], &[]);
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(driver_with_io(
            1,
            Variant::SixPack,
            &[0, 1, 2, 3, 4, 5],
            polls,
            six_io,
        )),
        Box::new(driver_with_io(
            2,
            Variant::QuadPack,
            &[0, 1, 2, 3],
            polls,
            quad_io,
        )),
    ];
    let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
    wait_online(&mut rig, 10);
    let budget = rig.engine.driver(0).unwrap().refresh_budget();
    assert!(budget < Duration::from_millis(500), "{budget:?}");
    // One round of polls for the first $30 answers.
    rig.run_until(budget, |_| false);
    for index in 0..10u32 {
        let target = f64::from(index) - 4.5;
        accepted(&mut rig, index, CommandKind::Position, [target, 0.0, 0.0]);
    }
    let end = rig.now + Duration::from_secs(3);
    while rig.now < end {
        rig.tick();
        for index in 0..10 {
            assert!(fresh(&rig, index), "axis {index} stale at {:?}", rig.now);
        }
        for (device, name, variant) in [
            (0, "analog6", Variant::SixPack),
            (1, "analog7", Variant::QuadPack),
        ] {
            let reading = rig
                .engine
                .driver(device)
                .unwrap()
                .read_pin(pin(variant, name))
                .expect("configured");
            let at = reading.refreshed_at.expect("polled");
            assert!(rig.now - at <= budget, "{name} of device {device}");
        }
    }
    for index in 0..10usize {
        assert!(flag(&rig, index, AxisFlags::ARRIVED), "axis {index}");
    }
    assert_eq!(motor(&six_board, 5).position, 50);
    assert_eq!(motor(&quad_board, 3).position, 450);
    assert_eq!(bus.lock().unwrap().collisions(), 0);
}
