//! Stepper stops through engine + driver + simulator: ramped down from the rate the board
//! steps at (a jog the deadman ends, a stepper left running by another program), and always
//! on the wire.

use super::*;

/// Writes `writes` into the simulated board at `now`, as another program would.
fn poke(board: &Board, now: Duration, writes: &[spimotor::Write]) {
    use motion_link::sim::SpiDevice;
    for write in writes {
        let mut mosi = [0u8; 16];
        let n = Transaction::write(Address::DEFAULT, *write)
            .encode(&mut mosi)
            .expect("encodes");
        let mut miso = [0u8; 16];
        board
            .lock()
            .unwrap()
            .transfer(now, &mosi[..n], &mut miso[..n]);
    }
}

/// Ticks until the stepper stands, checking every tick that its step rate falls no
/// faster than `decel` allows (from `rate` at the start, with one quantisation step of the
/// board's 0.1 ms step delay and one profile period of slack); returns how long it took.
fn watch_stop(rig: &mut Rig, board: &Board, rate: f64, decel: f64, limit: Duration) -> Duration {
    let start = rig.now;
    let mut last = rate.abs();
    while board.lock().unwrap().is_moving() {
        assert!(rig.now - start <= limit, "still stepping after {limit:?}");
        rig.tick();
        let now_rate = board.lock().unwrap().velocity(0).unwrap().abs();
        if now_rate == 0.0 {
            break;
        }
        // The delay quantisation near `last`: the next slower delay's rate.
        let delay =
            spimotor::StepDelay::from_tenths_ms(((10_000.0 / last).ceil() as u8).saturating_add(1));
        let quantum = last - 1.0 / delay.duration().as_secs_f64();
        assert!(
            last - now_rate <= decel * 0.003 + quantum + 1e-6,
            "rate dropped from {last} to {now_rate} at {:?}",
            rig.now - start
        );
        last = now_rate;
    }
    rig.now - start
}

#[test]
fn the_deadman_ramps_a_jog_down_from_its_step_rate() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Velocity, [20.0, 0.0, 0.0]);
    // The fastest the board stepped before the deadman fired (its stop's first, slower
    // step delay is on the wire in the tick that fires it).
    let mut rate: f64 = 0.0;
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        let expired = frame.axes[0].flags & AxisFlags::DEADMAN_EXPIRED.0 != 0;
        if !expired {
            rate = rate.max(board.lock().unwrap().velocity(0).unwrap());
        }
        expired
    }));
    assert_eq!(rate, 2_000.0, "at its max velocity until the deadman fired");
    assert!(
        board.lock().unwrap().velocity(0).unwrap() < rate,
        "slowing down from the tick that fired it"
    );
    let decel = MAX_ACCEL_MM * STEPS_PER_MM;
    // 2000 → 39 steps/s at 20 000 steps/s²: 98 ms, plus a profile period (2 ms) and the
    // tick that carries the last write.
    let bound = Duration::from_secs_f64((rate - SLOWEST_RATE) / decel) + Duration::from_millis(6);
    let took = watch_stop(&mut rig, &board, rate, decel, Duration::from_millis(500));
    assert!(took <= bound, "{took:?} > {bound:?}");
    assert!(
        took >= Duration::from_millis(80),
        "ramped, not stopped dead: {took:?}"
    );
    rig.run(20);
    assert_eq!(rig.axis(0).mode, AxisMode::Hold as u8);
}

#[test]
fn a_stepper_left_running_is_ramped_down_once_online() {
    let (mut rig, board, _) = stepper_rig(0x90);
    // Before the server starts, another program left the stepper running at 0.4 ms per
    // step (2500 steps/s, above this axis's 2000) towards a far target.
    poke(
        &board,
        Duration::ZERO,
        &[
            spimotor::Write::StepDelay(spimotor::StepDelay::from_tenths_ms(4)),
            spimotor::Write::TargetPosition(1_000_000),
        ],
    );
    let rate = board.lock().unwrap().velocity(0).unwrap();
    assert!(rate > 2_000.0, "stepping at its own rate: {rate}");
    // No command at all: the engine's start-up stop, once the board is probed, ramps it
    // down from the 2500 steps/s it steps at, at the axis's max acceleration. The bound
    // adds the driver's start-up survey (two reads of position, target and delay).
    let decel = MAX_ACCEL_MM * STEPS_PER_MM;
    let bound =
        Duration::from_secs_f64((2_500.0 - SLOWEST_RATE) / decel) + Duration::from_millis(40);
    let took = watch_stop(&mut rig, &board, rate, decel, Duration::from_millis(500));
    assert!(took <= bound, "{took:?} > {bound:?}");
    wait_online(&mut rig, 1);
    let sim = board.lock().unwrap();
    assert!(!sim.is_moving());
    assert_eq!(
        sim.current_position(),
        sim.target_position(),
        "stopped where it was"
    );
    assert_eq!(sim.stepper_intensity(), 0x20, "energised: a stop holds");
}

#[test]
fn a_stop_on_a_standing_stepper_still_goes_on_the_wire() {
    let (mut rig, board, _) = stepper_rig(0x90);
    rig.log_wire = true;
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 1.0, Duration::from_secs(1));
    rig.run(10);
    let from = rig.wire_log(0).len();
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    rig.run(5);
    let writes: Vec<spimotor::Write> = rig.wire_log(0)[from..]
        .iter()
        .filter_map(
            |(_, mosi)| match Transaction::decode(mosi).expect("valid") {
                Transaction {
                    request: Request::Write(write),
                    ..
                } => Some(write),
                _ => None,
            },
        )
        .collect();
    assert!(
        writes.contains(&spimotor::Write::RelativePosition(0)),
        "0x42 ← 0 (stop where it is): {writes:?}"
    );
}
