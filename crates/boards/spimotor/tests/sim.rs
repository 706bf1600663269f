//! The simulated SPI_motor board on the wire: datasheet golden exchanges, address
//! filtering and the address-change sequence, step timing and brushed-motor physics.

use std::time::Duration;

use board_spimotor::sim::{
    Bridge, Drive, MISO_IDLE, MISO_UNSELECTED, SpimotorSim, SpimotorSimConfig, UnlockStage,
};
use motion_link::sim::{SpiBus, SpiDevice};
use spimotor::{
    Address, Coils, Direction, Motor, Read, ReadPort, Reply, Request, SerialNumber, StepDelay,
    Transaction, Write,
};

const MS: Duration = Duration::from_millis(1);
const BOARD: Address = Address::DEFAULT;

fn stepper() -> SpimotorSim {
    SpimotorSim::new(SpimotorSimConfig::default())
}

fn brushed() -> SpimotorSim {
    SpimotorSim::new(SpimotorSimConfig {
        drive: Drive::Brushed,
        ..Default::default()
    })
}

/// Clocks one transaction through `dev` at `now`; returns (drove MISO, MISO bytes).
fn exchange(dev: &mut dyn SpiDevice, now: Duration, t: Transaction) -> (bool, Vec<u8>) {
    let mut mosi = vec![0u8; t.len()];
    t.encode(&mut mosi).expect("sized");
    let mut miso = vec![0xFFu8; mosi.len()];
    let drove = dev.transfer(now, &mosi, &mut miso);
    (drove, miso)
}

fn write(dev: &mut dyn SpiDevice, now: Duration, address: Address, w: Write) -> bool {
    exchange(dev, now, Transaction::write(address, w)).0
}

fn read(dev: &mut dyn SpiDevice, now: Duration, address: Address, port: ReadPort) -> Reply {
    let (drove, miso) = exchange(dev, now, Transaction::read(address, port));
    assert!(drove, "no board at {address} drove MISO");
    Reply::decode(port, &miso).expect("board answers a well-formed reply")
}

fn read_position(dev: &mut dyn SpiDevice, now: Duration, port: ReadPort) -> i32 {
    match read(dev, now, BOARD, port) {
        Reply::CurrentPosition(p) | Reply::TargetPosition(p) => p,
        other => panic!("unexpected {other:?}"),
    }
}

/// Datasheet "examples / read identification": `0x91 0x01 xx xx xx …` is answered with
/// `xx xx 0x73 's' 0x70 'p' 0x69 'i' …`, terminated with 0.
#[test]
fn golden_read_identification() {
    let mut sim = stepper();
    let mosi = [0x91, 0x01, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0];
    let mut miso = [0xAAu8; 12];
    assert!(sim.transfer(Duration::ZERO, &mosi, &mut miso));
    assert_eq!(
        miso,
        [
            MISO_UNSELECTED,
            MISO_IDLE,
            0x73,
            0x70,
            0x69,
            b'_',
            b'm',
            b'o',
            b't',
            b'o',
            b'r',
            0
        ]
    );
    let Reply::Identification(id) = Reply::decode(ReadPort::Identification, &miso).unwrap() else {
        panic!("not an identification");
    };
    assert_eq!(id.as_str(), Some("spi_motor"));
}

/// Datasheet "examples / move stepper to step 0x12345678": `0x90 0x41 0x78 0x56 0x34 0x12`
/// sets the target; the stepper then steps towards it at the default 20 ms per step.
#[test]
fn golden_move_stepper_to_0x12345678() {
    let mut sim = stepper();
    let mut miso = [0u8; 6];
    assert!(sim.transfer(
        Duration::ZERO,
        &[0x90, 0x41, 0x78, 0x56, 0x34, 0x12],
        &mut miso
    ));
    assert_eq!(miso, [MISO_UNSELECTED, 0, 0, 0, 0, 0]);
    // Read back on port 0x41: 0x91 0x41 xx xx xx xx → xx xx 78 56 34 12.
    let mut miso = [0u8; 6];
    assert!(sim.transfer(MS, &[0x91, 0x41, 0, 0, 0, 0], &mut miso));
    assert_eq!(&miso[2..], &[0x78, 0x56, 0x34, 0x12]);
    // Default step delay 200 = 20 ms: 50 steps in one second.
    assert_eq!(
        read_position(&mut sim, Duration::from_secs(1), ReadPort::CurrentPosition),
        50
    );
}

#[test]
fn every_read_port_answers_at_offset_two() {
    let mut sim = SpimotorSim::new(SpimotorSimConfig {
        serial: 0xDEAD_BEEF,
        identification: "spi_motor v1.2".into(),
        ..Default::default()
    });
    write(&mut sim, Duration::ZERO, BOARD, Write::CurrentPosition(-5));
    write(&mut sim, Duration::ZERO, BOARD, Write::TargetPosition(-5));
    let t = Duration::ZERO;
    assert_eq!(
        read(&mut sim, t, BOARD, ReadPort::Serial),
        Reply::Serial(SerialNumber(0xDEAD_BEEF))
    );
    let Reply::Identification(id) = read(&mut sim, t, BOARD, ReadPort::Identification) else {
        panic!()
    };
    assert_eq!(id.as_str(), Some("spi_motor v1.2"));
    assert_eq!(
        read(&mut sim, t, BOARD, ReadPort::CurrentPosition),
        Reply::CurrentPosition(-5)
    );
    assert_eq!(
        read(&mut sim, t, BOARD, ReadPort::TargetPosition),
        Reply::TargetPosition(-5)
    );
    // "0x43 read stepdelay … default 200": tenths of a millisecond both ways.
    assert_eq!(
        read(&mut sim, t, BOARD, ReadPort::StepDelay),
        Reply::StepDelay(StepDelay::DEFAULT)
    );
    write(
        &mut sim,
        t,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(15)),
    );
    assert_eq!(
        read(&mut sim, t, BOARD, ReadPort::StepDelay),
        Reply::StepDelay(StepDelay::from_tenths_ms(15))
    );
    assert_eq!(sim.stats().malformed, 0);
}

#[test]
fn short_and_long_reads_get_a_cut_answer_or_padding() {
    let mut sim = stepper();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::TargetPosition(0x0403_0201),
    );
    let t = |len| Transaction {
        address: BOARD,
        request: Request::Read(Read {
            port: ReadPort::TargetPosition,
            len,
        }),
    };
    let (_, miso) = exchange(&mut sim, Duration::ZERO, t(2));
    assert_eq!(miso, [MISO_UNSELECTED, MISO_IDLE, 1, 2]);
    let (_, miso) = exchange(&mut sim, Duration::ZERO, t(7));
    assert_eq!(miso, [MISO_UNSELECTED, MISO_IDLE, 1, 2, 3, 4, 0, 0, 0]);
}

/// The step delay is a lower bound on the time between steps: sampled every 50 µs, the
/// counter moves one step at a time, never sooner than one delay after the previous step
/// (or the command), and arrives exactly when the step count times the delay says.
#[test]
fn stepper_arrives_at_the_rate_the_step_delay_implies_never_faster() {
    let mut sim = stepper();
    let t0 = Duration::from_micros(12_345);
    write(
        &mut sim,
        t0,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(7)),
    );
    write(&mut sim, t0, BOARD, Write::TargetPosition(40));
    let delay = Duration::from_micros(700);
    let mut last_change = t0;
    let mut last = sim.current_position();
    let mut t = t0;
    let mut arrived = None;
    while t < t0 + 60 * MS {
        t += Duration::from_micros(50);
        sim.advance(t);
        let p = sim.current_position();
        assert!((0..=40).contains(&p), "{p} overshoots");
        assert_eq!(sim.rotor_steps(), i64::from(p));
        if p != last {
            assert_eq!(p - last, 1, "more than one step in 50 µs at {t:?}");
            let at = sim.last_step_at().expect("stepped");
            assert!(
                at - last_change >= delay,
                "steps {:?} apart",
                at - last_change
            );
            last_change = at;
            last = p;
            if p == 40 {
                arrived = Some(at);
            }
        }
    }
    // First step one delay after the command, then one per delay: 40 steps = 40 delays.
    assert_eq!(arrived, Some(t0 + 40 * delay));
    assert!(!sim.is_moving());
    assert_eq!(read_position(&mut sim, t, ReadPort::CurrentPosition), 40);
}

#[test]
fn changing_the_step_delay_mid_move_never_steps_faster_than_the_delay_in_force() {
    let mut sim = stepper();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(100)),
    );
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::TargetPosition(-1000),
    );
    // One step at 10 ms; at 12 ms switch to 1 ms: next step at 12 ms (10 + 1 is past).
    sim.advance(12 * MS);
    assert_eq!(sim.current_position(), -1);
    write(
        &mut sim,
        12 * MS,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(10)),
    );
    sim.advance(12 * MS);
    assert_eq!(sim.current_position(), -2);
    assert_eq!(sim.last_step_at(), Some(12 * MS));
    sim.advance(20 * MS);
    assert_eq!(sim.current_position(), -10);
    // Slowing down: the next step waits the whole new delay after the last one.
    write(
        &mut sim,
        20 * MS + Duration::from_micros(500),
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(50)),
    );
    sim.advance(24 * MS);
    assert_eq!(sim.current_position(), -10);
    sim.advance(25 * MS);
    assert_eq!(sim.current_position(), -11);
    assert_eq!(sim.velocity(0), Some(-200.0));
}

#[test]
fn relative_moves_are_relative_to_the_current_position() {
    let mut sim = stepper();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(10)),
    );
    write(&mut sim, Duration::ZERO, BOARD, Write::RelativePosition(30));
    assert_eq!(sim.target_position(), 30);
    let t = Duration::from_millis(100);
    assert_eq!(read_position(&mut sim, t, ReadPort::CurrentPosition), 30);
    write(&mut sim, t, BOARD, Write::RelativePosition(-50));
    assert_eq!(read_position(&mut sim, t, ReadPort::TargetPosition), -20);
    // Halfway through, a relative move counts from where the motor is, not the target.
    let mid = t + 10 * MS;
    assert_eq!(read_position(&mut sim, mid, ReadPort::CurrentPosition), 20);
    write(&mut sim, mid, BOARD, Write::RelativePosition(5));
    assert_eq!(sim.target_position(), 25);
    sim.advance(mid + 100 * MS);
    assert_eq!(sim.current_position(), 25);
    assert_eq!(sim.rotor_steps(), 25);
}

#[test]
fn setting_the_current_position_moves_the_counter_not_the_rotor() {
    let mut sim = stepper();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(10)),
    );
    write(&mut sim, Duration::ZERO, BOARD, Write::TargetPosition(10));
    sim.advance(50 * MS);
    assert_eq!((sim.current_position(), sim.rotor_steps()), (10, 10));
    // Redefine "here" as 1000 and the target with it: nothing moves.
    write(&mut sim, 50 * MS, BOARD, Write::CurrentPosition(1000));
    write(&mut sim, 50 * MS, BOARD, Write::TargetPosition(1000));
    sim.advance(100 * MS);
    assert_eq!((sim.current_position(), sim.rotor_steps()), (1000, 10));
    // Setting only the counter leaves a target to step back to, as the firmware would.
    write(&mut sim, 100 * MS, BOARD, Write::CurrentPosition(995));
    sim.advance(200 * MS);
    assert_eq!((sim.current_position(), sim.rotor_steps()), (1000, 15));
}

#[test]
fn coils_intensity_and_drive_pattern() {
    let mut sim = stepper();
    assert_eq!(sim.coils(), Coils::One);
    assert_eq!(sim.stepper_intensity(), 0x20);
    assert_eq!(sim.coil_drive(), [1, 0]);
    let mut miso = [0u8; 3];
    // "other values mean driving two coils"
    sim.transfer(Duration::ZERO, &[0x90, 0x44, 0x07], &mut miso);
    assert_eq!(sim.coils(), Coils::Two);
    assert_eq!(sim.coil_drive(), [1, 1]);
    write(&mut sim, Duration::ZERO, BOARD, Write::RelativePosition(1));
    sim.advance(20 * MS);
    assert_eq!(sim.coil_drive(), [-1, 1]);
    write(&mut sim, 20 * MS, BOARD, Write::Coils(Coils::One));
    assert_eq!(sim.coil_drive(), [0, 1]);
    write(&mut sim, 20 * MS, BOARD, Write::StepperIntensity(0));
    assert_eq!(sim.coil_drive(), [0, 0]);
}

#[test]
fn address_change_then_the_old_address_is_ignored() {
    let mut sim = stepper();
    let new = Address::new(0xA0).unwrap();
    let t = Duration::ZERO;
    assert!(write(&mut sim, t, BOARD, Write::UnlockAddress1));
    assert_eq!(sim.unlock_stage(), UnlockStage::Started);
    assert!(write(&mut sim, t, BOARD, Write::UnlockAddress2));
    assert_eq!(sim.unlock_stage(), UnlockStage::Unlocked);
    assert!(write(&mut sim, t, BOARD, Write::ChangeAddress(new)));
    assert_eq!(sim.address(), 0xA0);
    assert_eq!(sim.stats().address_changes, 1);

    // The old address: MISO left floating, nothing happens.
    let (drove, miso) = exchange(
        &mut sim,
        t,
        Transaction::read(BOARD, ReadPort::Identification),
    );
    assert!(!drove);
    assert!(miso.iter().all(|&b| b == 0xFF));
    assert!(!write(&mut sim, t, BOARD, Write::TargetPosition(77)));
    assert_eq!(sim.target_position(), 0);
    // The new one answers.
    assert!(write(&mut sim, t, new, Write::TargetPosition(77)));
    let Reply::TargetPosition(p) = read(&mut sim, t, new, ReadPort::TargetPosition) else {
        panic!()
    };
    assert_eq!(p, 77);
    // The address lives in EEPROM: it survives a power cycle, the target does not.
    sim.power_cycle(MS);
    assert_eq!(sim.address(), 0xA0);
    assert_eq!(sim.target_position(), 0);
}

#[test]
fn a_wrong_unlock_sequence_aborts() {
    let t = Duration::ZERO;
    let new = Address::new(0x92).unwrap();
    let mut miso = [0u8; 8];
    // Each case: the transactions before the final 0xf0 write.
    let cases: [&[&[u8]]; 6] = [
        &[],                                                           // 0xf0 alone
        &[&[0x90, 0xf1, 0x55]],                                        // 0xf2 step missing
        &[&[0x90, 0xf2, 0xaa], &[0x90, 0xf1, 0x55]],                   // wrong order
        &[&[0x90, 0xf1, 0x55], &[0x90, 0xf2, 0xab]],                   // wrong key
        &[&[0x90, 0xf1, 0x55], &[0x91, 0x01, 0], &[0x90, 0xf2, 0xaa]], // a read in between
        &[
            &[0x90, 0xf1, 0x55],
            &[0x90, 0xf2, 0xaa],
            &[0x90, 0x10, 0x20],
        ], // a write in between
    ];
    for (i, case) in cases.iter().enumerate() {
        let mut sim = stepper();
        for mosi in *case {
            assert!(sim.transfer(t, mosi, &mut miso[..mosi.len()]));
        }
        assert!(write(&mut sim, t, BOARD, Write::ChangeAddress(new)));
        assert_eq!(sim.address(), 0x90, "case {i} changed the address");
        assert_eq!(sim.unlock_stage(), UnlockStage::Locked);
    }
    // Transactions for other boards are not seen, so they do not abort.
    let mut sim = stepper();
    write(&mut sim, t, BOARD, Write::UnlockAddress1);
    write(
        &mut sim,
        t,
        Address::new(0x70).unwrap(),
        Write::TargetPosition(1),
    );
    write(&mut sim, t, BOARD, Write::UnlockAddress2);
    write(&mut sim, t, BOARD, Write::ChangeAddress(new));
    assert_eq!(sim.address(), 0x92);
    // An odd new address is malformed: ignored, sequence aborted.
    let mut sim = stepper();
    write(&mut sim, t, BOARD, Write::UnlockAddress1);
    write(&mut sim, t, BOARD, Write::UnlockAddress2);
    assert!(sim.transfer(t, &[0x90, 0xf0, 0x93], &mut miso[..3]));
    assert_eq!((sim.address(), sim.stats().malformed), (0x90, 1));
    assert_eq!(sim.unlock_stage(), UnlockStage::Locked);
}

#[test]
fn two_boards_on_one_bus() {
    let b = Address::new(0x92).unwrap();
    let mut bus = SpiBus::new()
        .with(Box::new(stepper()))
        .with(Box::new(SpimotorSim::new(SpimotorSimConfig {
            address: 0x92,
            drive: Drive::Brushed,
            identification: "spi_motor B".into(),
            serial: 2,
            ..Default::default()
        })));
    let t = Duration::ZERO;
    let Reply::Identification(id) = read(&mut bus, t, b, ReadPort::Identification) else {
        panic!()
    };
    assert_eq!(id.as_str(), Some("spi_motor B"));
    let Reply::Identification(id) = read(&mut bus, t, BOARD, ReadPort::Identification) else {
        panic!()
    };
    assert_eq!(id.as_str(), Some("spi_motor"));
    assert_eq!(
        read(&mut bus, t, b, ReadPort::Serial),
        Reply::Serial(SerialNumber(2))
    );
    assert_eq!(
        read(&mut bus, t, BOARD, ReadPort::Serial),
        Reply::Serial(SerialNumber(1))
    );

    // A target for one board leaves the other alone.
    write(&mut bus, t, BOARD, Write::TargetPosition(3));
    let target = |bus: &mut SpiBus, a| match read(
        bus,
        Duration::from_secs(1),
        a,
        ReadPort::TargetPosition,
    ) {
        Reply::TargetPosition(p) => p,
        other => panic!("{other:?}"),
    };
    assert_eq!(target(&mut bus, BOARD), 3);
    assert_eq!(target(&mut bus, b), 0);
    // Nobody at 0x94: MISO floats at 0xFF.
    let (drove, miso) = exchange(
        &mut bus,
        t,
        Transaction::read(Address::new(0x94).unwrap(), ReadPort::Serial),
    );
    assert!(!drove);
    assert_eq!(miso, [0xFF; 6]);
    assert_eq!(bus.contentions(), 0);
}

#[test]
fn brushed_motors_follow_speed_and_direction() {
    let mut sim = SpimotorSim::new(SpimotorSimConfig {
        drive: Drive::Brushed,
        seed: 42,
        ..Default::default()
    });
    let config = sim.config().brushed;
    let t = Duration::ZERO;
    // 0x20: motor A, direction A, full intensity. 0x31: motor B, direction B, half.
    write(
        &mut sim,
        t,
        BOARD,
        Write::Spin {
            motor: Motor::A,
            direction: Direction::A,
            intensity: 255,
        },
    );
    write(
        &mut sim,
        t,
        BOARD,
        Write::Spin {
            motor: Motor::B,
            direction: Direction::B,
            intensity: 128,
        },
    );
    let a_end = sim.motor_settled_velocity(Motor::A);
    let b_end = sim.motor_settled_velocity(Motor::B);
    let noise = config.speed_noise;
    assert!((a_end / config.no_load_speed - 1.0).abs() <= noise);
    assert!((b_end / (-128.0 / 255.0 * config.no_load_speed) - 1.0).abs() <= noise);
    // Sampled every millisecond: speeds move monotonically towards the settled value and
    // never past it; positions integrate the speed.
    let mut last = (0.0, 0.0);
    let mut now = t;
    for _ in 0..300 {
        now += MS;
        sim.advance(now);
        let (a, b) = (sim.motor_velocity(Motor::A), sim.motor_velocity(Motor::B));
        assert!(a >= last.0 && a <= a_end, "A {a}");
        assert!(b <= last.1 && b >= b_end, "B {b}");
        last = (a, b);
    }
    // After 10 time constants both are settled (within e^-10).
    assert!((sim.motor_velocity(Motor::A) - a_end).abs() < 1e-4 * config.no_load_speed);
    assert!((sim.motor_velocity(Motor::B) - b_end).abs() < 1e-4 * config.no_load_speed);
    assert_eq!(sim.velocity(0), Some(sim.motor_velocity(Motor::A)));
    let pa = sim.position(0).unwrap();
    let expected = a_end * (0.3 - config.time_constant.as_secs_f64());
    assert!(
        (pa - expected).abs() < 0.01 * expected,
        "{pa} vs {expected}"
    );
    assert!(sim.position(1).unwrap() < 0.0);
    assert_eq!(sim.position(2), None);

    // 0x22 stops motor A only; it brakes to rest.
    write(&mut sim, now, BOARD, Write::Stop(Motor::A));
    assert_eq!(sim.bridge(Motor::A), Bridge::Stopped);
    sim.advance(now + 500 * MS);
    assert!(sim.motor_velocity(Motor::A).abs() < 1e-3);
    assert!((sim.motor_velocity(Motor::B) - b_end).abs() < 1e-3);
    // 0x21 reverses it.
    write(
        &mut sim,
        now + 500 * MS,
        BOARD,
        Write::Spin {
            motor: Motor::A,
            direction: Direction::B,
            intensity: 64,
        },
    );
    sim.advance(now + 1000 * MS);
    assert!(sim.motor_velocity(Motor::A) < 0.0);
    write(&mut sim, now + 1000 * MS, BOARD, Write::Stop(Motor::B));
    sim.advance(now + 1500 * MS);
    assert!(sim.motor_velocity(Motor::B).abs() < 1e-3);
}

#[test]
fn stop_ports_take_no_data() {
    let mut sim = brushed();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::Spin {
            motor: Motor::B,
            direction: Direction::A,
            intensity: 9,
        },
    );
    let mut miso = [0u8; 2];
    assert!(sim.transfer(MS, &[0x90, 0x32], &mut miso));
    assert_eq!(sim.bridge(Motor::B), Bridge::Stopped);
    assert_eq!(sim.stats().malformed, 0);
}

#[test]
fn malformed_transactions_change_nothing() {
    let mut sim = stepper();
    let mut miso = [0u8; 8];
    let cases: [&[u8]; 6] = [
        &[0x90],                      // no port
        &[0x90, 0x41, 1, 2, 3],       // 3 of 4 bytes
        &[0x90, 0x41, 1, 2, 3, 4, 5], // 5 of 4 bytes
        &[0x90, 0x43],                // no value
        &[0x90, 0x99, 1],             // unknown write port
        &[0x91, 0x10, 0],             // 0x10 is not a read port
    ];
    for mosi in cases {
        let miso = &mut miso[..mosi.len()];
        assert!(sim.transfer(Duration::ZERO, mosi, miso), "{mosi:02x?}");
        assert_eq!(miso[0], MISO_UNSELECTED);
        assert!(miso[1..].iter().all(|&b| b == MISO_IDLE));
    }
    assert_eq!(sim.stats().malformed, 6);
    assert_eq!(
        (sim.target_position(), sim.step_delay()),
        (0, StepDelay::DEFAULT)
    );
    // An empty transaction selects nobody.
    assert!(!sim.transfer(Duration::ZERO, &[], &mut []));
}

#[test]
fn random_bytes_never_panic_and_the_model_is_deterministic() {
    let run = || {
        let mut sim = SpimotorSim::new(SpimotorSimConfig {
            drive: Drive::Brushed,
            seed: 7,
            ..Default::default()
        });
        let mut rng = motion_sim::rng::SimRng::new(99);
        let mut trace = Vec::new();
        let mut now = Duration::ZERO;
        for _ in 0..20_000 {
            now += Duration::from_micros(rng.next_u64() % 3000);
            let len = (rng.next_u64() % 10) as usize;
            let mut mosi = [0u8; 10];
            for b in &mut mosi[..len] {
                *b = rng.next_u64() as u8;
            }
            if len > 0 && rng.next_u64().is_multiple_of(2) {
                mosi[0] = 0x90 | (rng.next_u64() as u8 & 1);
            }
            let mut miso = [0u8; 10];
            let drove = sim.transfer(now, &mosi[..len], &mut miso[..len]);
            trace.push((
                drove,
                miso,
                sim.current_position(),
                sim.motor_position(Motor::A).to_bits(),
            ));
        }
        (trace, sim.stats())
    };
    let (a, stats) = run();
    assert_eq!(a, run().0);
    assert!(stats.addressed > 5_000 && stats.malformed > 0, "{stats:?}");
}

#[test]
fn power_cycle_clears_ram_but_not_eeprom_or_the_rotor() {
    let mut sim = stepper();
    write(
        &mut sim,
        Duration::ZERO,
        BOARD,
        Write::StepDelay(StepDelay::from_tenths_ms(1)),
    );
    write(&mut sim, Duration::ZERO, BOARD, Write::Coils(Coils::Two));
    write(&mut sim, Duration::ZERO, BOARD, Write::TargetPosition(100));
    sim.power_cycle(5 * MS);
    assert_eq!(sim.rotor_steps(), 50);
    assert_eq!((sim.current_position(), sim.target_position()), (0, 0));
    assert_eq!(
        (sim.step_delay(), sim.coils()),
        (StepDelay::DEFAULT, Coils::One)
    );
    assert!(!sim.is_moving());
    let Reply::Identification(id) = read(&mut sim, 6 * MS, BOARD, ReadPort::Identification) else {
        panic!()
    };
    assert_eq!(id.as_str(), Some("spi_motor"));
}

mod random_commands {
    use super::*;
    use proptest::prelude::*;

    #[derive(Debug, Clone, Copy)]
    enum Op {
        Target(i32),
        Relative(i32),
        Current(i32),
        Delay(u8),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            (-40..40i32).prop_map(Op::Target),
            (-40..40i32).prop_map(Op::Relative),
            (-40..40i32).prop_map(Op::Current),
            (0..30u8).prop_map(Op::Delay),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Under any sequence of commands, sampled every 50 µs (half the shortest step
        /// delay): one step at most per sample, each step towards the target, and never
        /// closer to the previous step than the step delay in force.
        #[test]
        fn steps_never_come_faster_than_the_delay_in_force(
            ops in proptest::collection::vec((0u64..8_000, op()), 1..16)
        ) {
            let mut sim = stepper();
            let mut now = Duration::ZERO;
            let mut delay = StepDelay::DEFAULT;
            let mut last_step: Option<Duration> = None;
            let check = |sim: &mut SpimotorSim, last_step: &mut Option<Duration>, now: Duration, delay: StepDelay| {
                let before = (sim.current_position(), sim.target_position());
                sim.advance(now);
                let after = sim.current_position();
                let step = sim.last_step_at();
                if step != *last_step {
                    let at = step.expect("a step was made");
                    prop_assert_eq!((after - before.0).abs(), 1);
                    prop_assert!((before.1 - after).abs() < (before.1 - before.0).abs());
                    if let Some(prev) = *last_step {
                        let min = delay.duration().max(StepDelay::UNIT);
                        prop_assert!(at - prev >= min, "{:?} after {:?}", at - prev, prev);
                    }
                    *last_step = step;
                } else {
                    prop_assert_eq!(after, before.0);
                }
                Ok(())
            };
            for (dt_us, op) in ops {
                let until = now + Duration::from_micros(dt_us);
                while now < until {
                    now = (now + Duration::from_micros(50)).min(until);
                    check(&mut sim, &mut last_step, now, delay)?;
                }
                let w = match op {
                    Op::Target(p) => Write::TargetPosition(p),
                    Op::Relative(d) => Write::RelativePosition(d),
                    Op::Current(p) => Write::CurrentPosition(p),
                    Op::Delay(d) => {
                        delay = StepDelay::from_tenths_ms(d);
                        Write::StepDelay(delay)
                    }
                };
                let before = sim.current_position();
                write(&mut sim, now, BOARD, w);
                // A shorter delay can make one step due at once, never more.
                if sim.last_step_at() != last_step {
                    let at = sim.last_step_at().expect("stepped");
                    prop_assert_eq!(at, now);
                    prop_assert!((sim.current_position() - before).abs() <= 1);
                    if let Some(prev) = last_step {
                        prop_assert!(at - prev >= delay.duration().max(StepDelay::UNIT));
                    }
                    last_step = Some(at);
                }
            }
        }
    }
}
