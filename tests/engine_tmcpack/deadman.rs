//! The deadman on the sim.toml bus (a SIXpack and a QUADpack, ten motors polled on one
//! 19200-baud pair; docs/ARCHITECTURE.md "The deadman's bound per board"): the stop's
//! `$25` is the first word written after the tick that set it — no poll and no other
//! pack's command goes before it, only the one exchange already in flight ("Each request
//! should wait for the response of the PACK before transmitting a new command", manual 7.1
//! "Interlacing of Requests") — and the stopping motor is polled back to back until the
//! frames show it at rest.

use motion_ipc::CommandRequest;

use super::*;

/// `config/sim.toml`'s `x`: 640 microsteps per mm, 50 mm/s, 250 mm/s².
const X_COUNTS: f64 = 640.0;
const X_VELOCITY: f64 = 50.0;
const X_ACCEL: f64 = 250.0;

fn x_axis(name: &str, device: usize, channel: usize) -> AxisConfig {
    AxisConfig {
        counts_per_unit: X_COUNTS,
        min: -1000.0,
        max: 1000.0,
        max_velocity: X_VELOCITY,
        max_accel: X_ACCEL,
        ..axis(name, device, channel)
    }
}

fn x_driver(address: u8, variant: Variant, motors: usize) -> TmcpackDriver {
    let mut channels = [None; 6];
    for slot in channels.iter_mut().take(motors) {
        *slot = Some(TmcpackChannel {
            max_velocity: X_VELOCITY * X_COUNTS,
            max_accel: X_ACCEL * X_COUNTS,
            ..TmcpackChannel::default()
        });
    }
    TmcpackDriver::new(TmcpackDriverConfig {
        address,
        variant,
        baud: BAUD,
        bus_motors: 10,
        channels,
        ..TmcpackDriverConfig::default()
    })
}

/// Axes 0–5 on the SIXpack (address 1), 6–9 on the QUADpack (address 2), one bus.
fn sim_toml_bus() -> (Rig, Pack) {
    let (six, six_board) = Shared::new(pack(1, Variant::SixPack));
    let (quad, _quad_board) = Shared::new(pack(2, Variant::QuadPack));
    let (wire, _bus) = Shared::new(StreamBus::new().with(six).with(quad));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let mut axes: Vec<AxisConfig> = (0..6).map(|m| x_axis(&format!("six{m}"), 0, m)).collect();
    axes.extend((0..4).map(|m| x_axis(&format!("quad{m}"), 1, m)));
    let config = engine_config(vec![device("six", 1), device("quad", 2)], axes);
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(x_driver(1, Variant::SixPack, 6)),
        Box::new(x_driver(2, Variant::QuadPack, 4)),
    ];
    let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
    rig.log_wire = true;
    wait_online(&mut rig, 10);
    (rig, six_board)
}

/// Jogs axis 0 at `speed` mm/s, renewed until it runs at it; returns the tick (its `now`)
/// of the last renewal.
fn jog(rig: &mut Rig, speed: f64) -> Duration {
    for _ in 0..20 {
        accepted(rig, 0, CommandKind::Velocity, [speed, 0.0, 0.0]);
        rig.run(100);
        if (rig.axis(0).velocity - speed).abs() < speed.abs() * 0.05 {
            accepted(rig, 0, CommandKind::Velocity, [speed, 0.0, 0.0]);
            return rig.now - rig.period;
        }
    }
    panic!("the jog never reached {speed} mm/s: {:?}", rig.axis(0));
}

/// One query exchange at 19200 baud with the driver's `$40` of 2 ms (manual 6.1: the pack
/// answers after the switch-over time and keeps driving the line for it afterwards).
fn exchange() -> Duration {
    let word = byte_time(BAUD) * 9;
    2 * word + 2 * Duration::from_millis(2)
}

/// Task (issue 30 item 7): on a shared bus the deadman's stop goes out before any poll and
/// before another pack's command set in the same tick: the first word queued from the
/// deadman's tick on is the `$25`, within the one exchange in flight and the tick that
/// takes its answer in. Every phase of the polls' exchanges (the jog renewed at 13
/// offsets).
#[test]
fn the_deadman_stop_is_the_first_word_after_its_tick_on_a_shared_bus() {
    let (mut rig, _six) = sim_toml_bus();
    let mut sequence = 1_000_000;
    for offset in 0..13 {
        rig.run(offset);
        let renewed = jog(&mut rig, 10.0);
        let expires = renewed + Duration::from_millis(250);
        while rig.now < expires {
            rig.tick();
        }
        // In the deadman's own tick, a client's command for the other pack.
        sequence += 1;
        let target = if offset % 2 == 0 { 1.0 } else { 0.0 };
        let request = CommandRequest::new(rig.client, sequence, 6, CommandKind::Position)
            .with_values([target, 0.0, 0.0]);
        rig.port.requests.push_back(request);
        let fired = rig.now;
        rig.tick();
        assert!(
            flag(&rig, 0, AxisFlags::DEADMAN_EXPIRED),
            "the deadman fires at renewal + 250 ms"
        );
        assert_eq!(rig.port.replies.pop().map(|r| r.result()), Some(Ok(())));
        rig.run(30);
        let first = rig
            .wire_log(0)
            .iter()
            .find(|(at, _)| *at >= fired)
            .map(|(at, bytes)| (*at, RequestFrame::decode(bytes).expect("a valid word")))
            .expect("words after the deadman's tick");
        assert_eq!(
            (first.1.address, first.1.request),
            (
                1,
                Request::Rotate {
                    motor: 0,
                    velocity: 0
                }
            ),
            "offset {offset}: the first word after the deadman's tick"
        );
        let waited = first.0 - fired;
        assert!(
            waited <= exchange() + 2 * rig.period,
            "offset {offset}: the stop waited {waited:?}"
        );
        assert!(rig.run_until(Duration::from_secs(2), |frame| {
            frame.axes[0].mode == AxisMode::Hold as u8
                && frame.axes[6].flags & AxisFlags::ARRIVED.0 != 0
        }));
    }
}

/// Task: once its deceleration from the measured speed has run, the stopping motor is
/// polled back to back (taking turns with overdue polls), so the frame shows it at rest
/// (Hold, velocity 0) within a few exchanges — not a round-robin period over ten motors
/// (~134 ms) or two later. Both
/// speeds: the deceleration short (a quarter of the limit) and long (four fifths).
#[test]
fn a_deadman_stop_shows_at_rest_within_a_few_exchanges_of_the_deceleration() {
    let (mut rig, six) = sim_toml_bus();
    for speed in [X_VELOCITY / 4.0, -X_VELOCITY * 0.8] {
        let renewed = jog(&mut rig, speed);
        let mut measured: f64 = 0.0;
        let mut fired = None;
        let mut still = None;
        let rest = loop {
            rig.tick();
            let now = rig.now - rig.period;
            measured = measured.max(rig.axis(0).velocity.abs());
            if fired.is_none() && flag(&rig, 0, AxisFlags::DEADMAN_EXPIRED) {
                fired = Some(now);
            }
            if fired.is_some() && still.is_none() && motor(&six, 0).microstep_hz == 0.0 {
                still = Some(now);
            }
            if fired.is_some() && rig.axis(0).mode == AxisMode::Hold as u8 {
                break now;
            }
            assert!(
                now < renewed + Duration::from_secs(3),
                "at rest within 3 s: {:?} {:?}",
                rig.axis(0),
                motor(&six, 0)
            );
        };
        assert_eq!(rig.axis(0).velocity, 0.0);
        let fired = fired.expect("the deadman fired");
        let still = still.expect("the motor stood");
        let decel = Duration::from_secs_f64(measured / X_ACCEL);
        let word = byte_time(BAUD) * 9;
        // The exchange in flight, the tick, the `$25`, two pack cycles; then the `$14`
        // and three polls (the one in flight at rest, the first after, the one showing the
        // same position), each possibly behind one overdue poll of another motor of the
        // SIXpack and one message of the QUADpack.
        let to_wire = exchange() + rig.period + word + Duration::from_millis(4);
        let refresh = word + 9 * (exchange() + rig.period) + rig.period;
        let bound = to_wire + decel + refresh;
        eprintln!(
            "{speed} mm/s (measured {measured:.2}): motor still {:?}, frame at rest {:?} after \
             the deadman; bound {bound:?}",
            still - fired,
            rest - fired
        );
        assert!(
            rest - fired <= bound,
            "{speed} mm/s (measured {measured}): at rest {:?} after the deadman \
             (the motor stood after {:?}); bound {bound:?}",
            rest - fired,
            still - fired
        );
        assert!(
            rest - still <= refresh,
            "{speed} mm/s: the frame showed the rest {:?} after the motor stood",
            rest - still
        );
    }
}
