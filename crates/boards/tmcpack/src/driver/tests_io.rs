//! Unit tests of the driver's I/O (manual 8.5): `$30` polls, `read_pin`, `$32`/`$33`.

use core::time::Duration;

use tmcpack::{Action, MotorMask, RefInputs, Reply, Request, RequestFrame};

use super::bench::*;
use super::*;
use motion_drivers::find_pin;

fn pin(name: &str) -> Pin {
    find_pin(pins(Variant::SixPack), name).expect("a SIXpack pin")
}

fn io_config(inputs: &[&str], outputs: &[&str]) -> TmcpackDriverConfig {
    let mut io = TmcpackIo::default();
    for name in inputs {
        io.inputs = io.inputs.with(pin(name));
    }
    for name in outputs {
        io.outputs = io.outputs.with(pin(name));
    }
    TmcpackDriverConfig { io, ..config() }
}

fn input(value: u16, inputs: u8, ttlio1: bool) -> Reply {
    Reply::Input {
        channel: 0,
        value,
        reference: false,
        inputs: RefInputs::from_bits_retain(inputs),
        ttlio1,
    }
}

#[test]
fn one_30_per_round_of_motor_polls_refreshes_every_input() {
    let mut bench = Bench::new(io_config(&["ref0", "analog6", "jumper1", "ttlio1"], &[]));
    let startup = bench.online();
    // TTLIO1 read as an input: $32 P1 = 1 ("1=input").
    assert!(startup.contains(&Request::Outputs {
        ttlout1: false,
        ttlio1_input: true,
        ttlio1: false,
        ttlout1_ready: false
    }));
    // Motor 0's reference input reads 0 on the wire ("inverted") = high level; JP1 set.
    bench.input = input(512, 0b0100_0000, true);
    let sent = bench.serve(400, |m| position(m, 0, Action::Inactive));
    let polls: Vec<&Request> = sent
        .iter()
        .filter(|r| matches!(r, Request::QueryPosition { .. } | Request::ReadInput { .. }))
        .collect();
    for round in polls.chunks(3).filter(|c| c.len() == 3) {
        let inputs = round
            .iter()
            .filter(|r| matches!(r, Request::ReadInput { .. }))
            .count();
        assert_eq!(inputs, 1, "one $30 per round of motors 0 and 2: {round:?}");
    }
    assert!(polls.iter().all(|r| !matches!(
        r,
        Request::ReadInput { channel, .. } if *channel != 6
    )));
    let read = |bench: &Bench, name| bench.driver.read_pin(pin(name)).expect("configured");
    assert_eq!(read(&bench, "ref0").value, 1.0);
    assert_eq!(read(&bench, "jumper1").value, 1.0);
    assert_eq!(read(&bench, "ttlio1").value, 1.0);
    assert_eq!(read(&bench, "analog6").value, 512.0);
    assert!(read(&bench, "analog6").refreshed_at.is_some());
    assert_eq!(bench.driver.read_pin(pin("ref1")), None, "not configured");
    // The switch closes: bit 0 set = low level.
    bench.input = input(100, 0b0000_0001, false);
    bench.serve(60, |m| position(m, 0, Action::Inactive));
    assert_eq!(read(&bench, "ref0").value, 0.0);
    assert_eq!(read(&bench, "analog6").value, 100.0);
    assert_eq!(read(&bench, "ttlio1").value, 0.0);
}

#[test]
fn analogue_channels_take_turns() {
    let mut bench = Bench::new(io_config(&["analog1", "analog7"], &[]));
    let startup = bench.online();
    assert!(
        !startup.iter().any(|r| matches!(r, Request::Outputs { .. })),
        "no output configured: $32 left alone"
    );
    let sent = bench.serve(600, |m| position(m, 0, Action::Inactive));
    let channels: Vec<u8> = sent
        .iter()
        .filter_map(|r| match r {
            Request::ReadInput { channel, .. } => Some(*channel),
            _ => None,
        })
        .collect();
    assert!(channels.len() >= 4, "{channels:?}");
    assert!(channels.windows(2).all(|w| w[0] != w[1]), "{channels:?}");
    assert!(channels.iter().all(|c| *c == 1 || *c == 7));
}

#[test]
fn set_output_sends_one_32_with_both_levels_before_the_polls() {
    let mut bench = Bench::new(io_config(&[], &["ttlout1", "ttlio1"]));
    let startup = bench.online();
    assert!(startup.contains(&Request::Outputs {
        ttlout1: false,
        ttlio1_input: false,
        ttlio1: false,
        ttlout1_ready: false
    }));
    bench.serve(30, |m| position(m, 0, Action::Inactive));
    bench
        .driver
        .set_output(bench.now, pin("ttlio1"), true)
        .expect("driven");
    assert!(bench.driver.goals_pending());
    let (at, w) = bench.next(30).expect("$32");
    // Manual 8.5 $32: P0 TTLOUT1 level, P1 TTLIO1 direction (0 = output), P2 TTLIO1 level,
    // P3 ready function.
    assert_eq!(w, [0x01, 0x32, 0, 0, 1, 0, 0, 0, 0]);
    let reading = bench.driver.read_pin(pin("ttlio1")).expect("driven");
    assert_eq!(reading.value, 1.0);
    assert_eq!(reading.refreshed_at, Some(at));
    bench
        .driver
        .set_output(bench.now, pin("ttlout1"), true)
        .expect("driven");
    assert_eq!(
        bench.request(),
        Request::Outputs {
            ttlout1: true,
            ttlio1_input: false,
            ttlio1: true,
            ttlout1_ready: false
        }
    );
    assert!(!bench.driver.goals_pending());
    assert_eq!(
        bench.driver.set_output(bench.now, pin("ref0"), true),
        Err(GoalError::NoSuchPin(pin("ref0")))
    );
}

#[test]
fn outputs_are_written_again_with_their_levels_after_a_pack_reset() {
    let mut bench = Bench::new(io_config(&[], &["ttlout1"]));
    bench.online();
    bench
        .driver
        .set_output(bench.now, pin("ttlout1"), true)
        .expect("driven");
    bench.serve(30, |m| position(m, 0, Action::Inactive));
    let mut rewritten = None;
    for _ in 0..3000 {
        let Some(w) = bench.tick() else { continue };
        match RequestFrame::decode(&w).expect("decodes").request {
            Request::UnitInfo { .. } if rewritten.is_none() => {
                // The reset flag is set: the pack rebooted (manual 8.6 $43 P1).
                bench.now += 10 * MS;
                bench.rx(&UNIT_INFO);
                rewritten = Some(false);
            }
            Request::UnitInfo { .. } => {
                bench.now += 10 * MS;
                let mut info = UNIT_INFO;
                info[3] = 0;
                bench.rx(&info);
            }
            Request::QueryActions { .. } => {
                bench.now += 10 * MS;
                bench.rx(&word(Reply::Actions {
                    actions: [Action::Inactive; 6],
                }));
            }
            Request::QueryPosition { motor, .. } => {
                bench.now += 10 * MS;
                bench.rx(&position(motor, 0, Action::Inactive));
            }
            Request::Outputs { ttlout1, .. } if rewritten == Some(false) => {
                assert!(ttlout1, "the level set before the reset");
                rewritten = Some(true);
            }
            _ => {}
        }
    }
    assert_eq!(rewritten, Some(true));
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.status().resets, 1);
}

#[test]
fn the_ready_output_writes_33_and_32_p3() {
    let mut cfg = io_config(&[], &[]);
    cfg.io.ready = Some(ReadyOutput {
        motors: MotorMask::M0 | MotorMask::M2,
        reference: MotorMask::M0,
    });
    let mut bench = Bench::new(cfg);
    let startup = bench.online();
    let ready = startup
        .iter()
        .position(|r| {
            *r == Request::ReadyOutput {
                active_mask: MotorMask::M0 | MotorMask::M2,
                reference_mask: MotorMask::M0,
            }
        })
        .expect("$33");
    let outputs = startup
        .iter()
        .position(|r| {
            matches!(
                r,
                Request::Outputs {
                    ttlout1_ready: true,
                    ..
                }
            )
        })
        .expect("$32 P3 = 1");
    assert!(ready < outputs);
    // Manual 8.5 $33: P0 mask for active motors, P1 mask for reference search.
    let w = RequestFrame::new(1, startup[ready])
        .to_word()
        .expect("valid");
    assert_eq!(w, [0x01, 0x33, 0b101, 0b001, 0, 0, 0, 0, 0]);
}

#[test]
fn outputs_and_pins_are_refused_while_the_pack_is_not_online() {
    let mut bench = Bench::new(io_config(&["ref0"], &["ttlout1"]));
    assert_eq!(
        bench
            .driver
            .set_output(Duration::ZERO, pin("ttlout1"), true),
        Err(GoalError::Offline)
    );
    assert_eq!(
        bench.driver.read_pin(pin("ref0")),
        Some(PinReading::UNKNOWN),
        "configured, never read"
    );
    bench.next(10).expect("$43");
    bench.now += 11 * MS;
    bench.rx(&UNIT_INFO);
    assert_eq!(
        bench.driver.set_output(bench.now, pin("ttlout1"), true),
        Err(GoalError::Starting)
    );
}

/// docs/ARCHITECTURE.md: the refresh budget covers a round of polls; the input poll is part of it.
#[test]
fn the_input_poll_is_counted_in_the_refresh_budget() {
    let plain = TmcpackDriver::new(config()).refresh_budget();
    let with_io = TmcpackDriver::new(io_config(&["ref0"], &[])).refresh_budget();
    assert!(with_io > plain);
}
