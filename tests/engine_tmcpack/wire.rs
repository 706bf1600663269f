//! Command → wire on a Trinamic pack (issue 18 item 2): the pack must never get a second
//! request before its answer (manual 7.1 "Interlacing of Requests"), so a new goal waits
//! for at most the one exchange in flight — a 9-byte query, the switch-over, the 9-byte
//! answer, the switch-over again (6.1) — and the tick that takes the answer in.

use super::*;
use crate::support::lag::PROMPT;
use crate::support::wire::{alternating, goal_to_wire_ticks};

/// One query exchange at 19200 baud with the driver's `$40` of 2 ms: two 9-byte words
/// (10 bits a byte) and the switch-over on both sides of the answer.
fn exchange() -> Duration {
    let word = Duration::from_secs_f64(90.0 / f64::from(BAUD));
    2 * word + 2 * Duration::from_millis(2)
}

#[test]
fn a_goal_waits_for_at_most_the_one_exchange_in_flight_and_the_tick_that_takes_it_in() {
    let (mut rig, _board, _) = single(1);
    rig.stamp_io(PROMPT);
    wait_online(&mut rig, 2);
    let bound = 2 + exchange().as_millis() as u64 + 1;
    // Every phase of the polls' exchanges.
    let ticks = goal_to_wire_ticks(
        &mut rig,
        &alternating(40, 10.0, -10.0),
        Duration::from_millis(100),
        |request| request * 7 % 17,
    );
    assert!(
        ticks.iter().all(|t| *t <= bound),
        "{ticks:?} beyond {bound}"
    );
    assert!(
        ticks.contains(&0),
        "a free line takes a goal at once: {ticks:?}"
    );
}

/// Two packs on one RS-485 pair at 19200 baud, at the factory 6 ms switch-over (no `$40`)
/// and at 2 ms, each taking the longest processing our reading of the manual allows (2 ms,
/// 6.2's figure) before its switch-over: moves and a jog stopped on both packs, and
/// neither pack ever gets a request while an answer of its is due or it drives the pair
/// (manual 7.1), nor does any query go unanswered.
#[test]
fn two_packs_at_6_and_2_ms_switch_over_are_never_interlaced() {
    for switchover_units in [None, Some(1)] {
        let slow = |address, variant| {
            TmcpackSim::new(TmcpackSimConfig {
                address,
                variant,
                processing_time: Duration::from_millis(2),
                ..TmcpackSimConfig::default()
            })
        };
        let (six, six_board) = Shared::new(slow(1, Variant::SixPack));
        let (quad, quad_board) = Shared::new(slow(2, Variant::QuadPack));
        let bus = StreamBus::new().with(six).with(quad);
        let (wire, bus) = Shared::new(bus);
        let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
        let config = engine_config(
            vec![device("six", 1), device("quad", 2)],
            vec![axis("x", 0, 0), axis("y", 0, 1), axis("g", 1, 0)],
        );
        let mut drivers: Vec<Box<dyn Driver>> = Vec::new();
        for (address, variant, motors) in [
            (1, Variant::SixPack, &[0usize, 1][..]),
            (2, Variant::QuadPack, &[0][..]),
        ] {
            let mut channels = [None; 6];
            for &m in motors {
                channels[m] = Some(TmcpackChannel {
                    max_velocity: MAX_VELOCITY_MM * COUNTS,
                    max_accel: MAX_ACCEL_MM * COUNTS,
                    ..TmcpackChannel::default()
                });
            }
            drivers.push(Box::new(TmcpackDriver::new(TmcpackDriverConfig {
                address,
                variant,
                baud: BAUD,
                switchover_units,
                bus_motors: 3,
                channels,
                ..TmcpackDriverConfig::default()
            })));
        }
        let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
        wait_online(&mut rig, 3);
        let expected = switchover_units.map_or(6, |u| 2 * u64::from(u));
        for board in [&six_board, &quad_board] {
            assert_eq!(
                board.lock().unwrap().switchover(),
                Duration::from_millis(expected)
            );
        }
        accepted(&mut rig, 0, CommandKind::Position, [10.0, 0.0, 0.0]);
        accepted(&mut rig, 2, CommandKind::Position, [-7.5, 0.0, 0.0]);
        accepted(&mut rig, 1, CommandKind::Velocity, [15.0, 0.0, 0.0]);
        rig.run(150);
        accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
        assert!(rig.run_until(Duration::from_secs(4), |frame| {
            frame.axes[0].flags & AxisFlags::ARRIVED.0 != 0
                && frame.axes[2].flags & AxisFlags::ARRIVED.0 != 0
                && frame.axes[1].mode == AxisMode::Hold as u8
        }));
        // Past a `$43` reset check of each pack.
        rig.run(1200);
        let label = format!("{expected} ms");
        for index in 0..2 {
            let status = rig.engine.driver(index).expect("driver").status();
            assert_eq!(status.timeouts, 0, "{label}: every answer in its window");
            assert_eq!(status.verdicts, 0, "{label}");
        }
        for board in [&six_board, &quad_board] {
            let stats = board.lock().unwrap().stats();
            assert_eq!(stats.interlaced, 0, "{label}: manual 7.1");
            assert_eq!(stats.replaced_replies, 0, "{label}");
            assert_eq!(stats.lost_bytes, 0, "{label}");
        }
        assert_eq!(bus.lock().unwrap().collisions(), 0, "{label}");
    }
}
