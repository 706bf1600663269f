//! Unit tests of the machine parameters, the enable line, homing and the I/O pins of the
//! QSB driver: the bytes each key puts on the wire at start-up and after a reset, quoted
//! against the QSB Command List (document version 1.28).

use core::time::Duration;

use ::qsb::{AnalogSample, EncoderMode, ProductType, ResponseType, TICK};

use super::tests::{Bench, MD_DONE, MD_JOGGING};
use super::{CaptureInput, EnableOutput, QsbDriverConfig, QsbIo};
use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind, Pin, PinReading, SignalKind};

/// -M pins: io0..io3, encoder, capture.
const IO0: Pin = Pin(0);
const IO1: Pin = Pin(1);
const IO3: Pin = Pin(3);
const M_ENCODER: Pin = Pin(4);
const M_CAPTURE: Pin = Pin(5);

/// A -M with every machine key set: 4 counts per step, inverted index, a 5-tick stream, a
/// drive enable on io3 (active low), a digital input on io0 that also captures on its
/// falling edge.
fn machine() -> QsbDriverConfig {
    QsbDriverConfig {
        counts_per_step: 4.0,
        invert_index: true,
        stream_interval: Some(5),
        enable: Some(EnableOutput {
            bit: 3,
            active_high: false,
        }),
        io: QsbIo {
            digital_in: 0b0001,
            capture: Some(CaptureInput {
                bit: 0,
                falling: true,
            }),
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    }
}

/// The start-up of [`machine`] (10000 counts/s = 2500 steps/s → 2496 = 0x9C0; 100000
/// counts/s² = 25000 steps/s² → 24992 = 0x61A0).
const MACHINE_START_UP: [&str; 19] = [
    "W161", "R14", // quiet the streams, VERSION
    "W1061A0", "W164", // MD ACCEL, COMMAND 4 "Motor Stop"
    "W155", "W000", "W0343",  // EOR, MODE quadrature, MDR0
    "W048",   // MDR1 B3 "Invert Index"
    "W0B0",   // THRESHOLD
    "W0C5",   // INTERVAL RATE 5 ticks ("Set 9.8ms Interval, W0C5")
    "W0F9C0", // MD STEP RATE
    "R02",    // DIG I/O CONFIG as the board holds it
    // B11 io3 an output, B4 interrupt on io0, B0 "1= high-low"
    "W02811", // then "All I/O port pins will be set high"
    "W017",   // io3 low: the drive enabled
    "W162", "S13", // COMMAND 2 "Activate motor drive mode", stream MD STATUS
    "S01", "S05", "S0E", // stream DIG I/O, CAPTURE, READ ENCODER
];

#[test]
fn every_machine_key_is_written_at_start_up_and_again_after_a_reset() {
    let mut bench = Bench::with_config(machine());
    assert_eq!(bench.run(), MACHINE_START_UP);
    assert!(bench.driver.status().online);
    bench.tick(Some(MD_DONE));
    // The board rebooted: its lines are back in the factory format.
    // Two lines say so (one could be corrupted: module `guard`).
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::Reset));
    assert_eq!(bench.run(), MACHINE_START_UP, "every parameter again");
    assert!(bench.driver.status().online);
}

#[test]
fn a_dig_io_config_the_board_holds_is_not_written_again() {
    let mut bench = Bench::with_config(machine());
    bench.values.push((0x02, 0x811));
    let lines = bench.run();
    assert!(!lines.iter().any(|l| l.starts_with("W02")), "{lines:?}");
    assert!(lines.contains(&"W017".to_owned()), "the levels are written");
}

#[test]
fn counts_per_step_converts_moves_and_a_negative_one_reverses_them() {
    let mut bench = Bench::started_with(machine());
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    bench.tick(None);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 1000.0 })
        .expect("position");
    // 1000 counts at 4 counts per step: "MD MOVE STEPS" 250 = 0xFA.
    assert_eq!(bench.run(), ["W11FA", "W168"]);
    let mut reversed = Bench::started_with(QsbDriverConfig {
        counts_per_step: -4.0,
        ..machine()
    });
    reversed.tick(Some(MD_DONE));
    reversed.tick(None);
    reversed.tick(None);
    reversed
        .driver
        .set_goal(reversed.now, 0, Goal::Position { counts: 1000.0 })
        .expect("position");
    // "negative value indicates direction": -250 steps.
    assert_eq!(reversed.run(), ["W11FFFFFF06", "W168"]);
}

#[test]
fn off_quits_and_releases_the_enable_line_and_the_next_motion_enables_it_first() {
    let mut bench = Bench::started_with(machine());
    assert!(bench.driver.capabilities(0).contains(GoalKind::Off));
    for _ in 0..3 {
        bench.tick(Some(MD_DONE));
    }
    bench.driver.set_goal(bench.now, 0, Goal::Off).expect("off");
    // COMMAND 5 "Motor Quit - Immediately stop the motor", then io3 high: disabled.
    assert_eq!(bench.run(), ["W165", "W01F"]);
    assert!(!bench.driver.goals_pending());
    for _ in 0..3 {
        bench.tick(Some(MD_DONE));
    }
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 400.0 })
        .expect("position");
    assert_eq!(bench.run(), ["W017", "W1164", "W168"], "enable, then move");
    // A stop holds: after an Off it enables the drive again, after the stop itself.
    bench.tick(Some(MD_DONE));
    bench.driver.set_goal(bench.now, 0, Goal::Off).expect("off");
    bench.run();
    let stop = Goal::Stop { decel: 100_000.0 };
    bench.driver.set_goal(bench.now, 0, stop).expect("stop");
    // 25000 steps/s² rounds up to 25008 = 0x61B0.
    assert_eq!(bench.run(), ["W1061B0", "W164", "W017"]);
}

#[test]
fn a_stop_always_reaches_the_wire_and_writes_md_accel_only_when_it_differs() {
    let mut bench = Bench::started(ProductType::M);
    for _ in 0..3 {
        bench.tick(Some(MD_DONE));
    }
    // The motor is known to be idle; the stop goes out anyway.
    let stop = Goal::Stop { decel: 160_000.0 }; // 16000 steps/s² = 0x3E80
    bench.driver.set_goal(bench.now, 0, stop).expect("stop");
    assert_eq!(bench.run(), ["W103E80", "W164"]);
    bench.tick(Some(MD_DONE));
    bench.driver.set_goal(bench.now, 0, stop).expect("stop");
    assert_eq!(bench.run(), ["W164"], "MD ACCEL already holds the decel");
    // A -M without an enable line cannot de-energise: Off is refused.
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, Goal::Off),
        Err(GoalError::Unsupported(GoalKind::Off))
    );
}

#[test]
fn home_with_an_offset_loads_dtr_on_the_index_in_the_configured_direction() {
    let mut bench = Bench::started_with(QsbDriverConfig {
        home_positive: true,
        home_position: 1234,
        ..machine()
    });
    bench.tick(Some(MD_DONE));
    let home = Goal::Home { velocity: 2_000.0 };
    bench.driver.set_goal(bench.now, 0, home).expect("home");
    // Jog +500 → 496 steps/s, DTR = 1234, MDR0 0x53 "configure index as the "load CNTR"
    // input (transfers DTR to CNTR)", clear STR, stream STR, jog.
    assert_eq!(
        bench.run(),
        ["W121F0", "W084D2", "W0353", "W093", "S06", "W169"]
    );
    bench.counter += 40;
    bench.tick(Some(MD_JOGGING));
    bench.counter = 1234;
    bench.advance(TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x06, 0x18);
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, 1234));
    bench.rx(&bytes);
    let state = bench.driver.channel(0);
    assert!(state.homed);
    assert_eq!(state.position, 1234.0);
    assert_eq!(bench.run(), ["W0343", "W164", "R06"]);
}

#[test]
fn a_search_past_its_travel_stops_and_reports_home_failed_until_its_stop_is_done() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    let home = Goal::Home { velocity: 2_000.0 };
    bench.driver.set_goal(bench.now, 0, home).expect("home");
    bench.run();
    bench.tick(Some(MD_JOGGING));
    // 100 counts per tick: the default 5000-count limit is passed after 51 ticks.
    for _ in 0..50 {
        bench.counter -= 100;
        bench.tick(None);
        assert_eq!(bench.driver.channel(0).fault, None);
    }
    bench.counter -= 100;
    bench.tick(None);
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::HomeFailed));
    assert_eq!(bench.driver.status().fault, None, "a channel fault");
    // The engine stops the faulted axis: the fault stays while the motor stops.
    let stop = Goal::Stop { decel: 100_000.0 };
    bench.driver.set_goal(bench.now, 0, stop).expect("stop");
    assert_eq!(bench.run(), ["W164", "W0343", "R06"]);
    bench.tick(Some(MD_JOGGING));
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::HomeFailed));
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    bench.tick(None);
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, None, "the stop is complete");
    assert!(!state.homed);
}

#[test]
fn a_search_whose_encoder_does_not_count_fails_after_its_time_limit() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    let home = Goal::Home { velocity: 2_000.0 };
    bench.driver.set_goal(bench.now, 0, home).expect("home");
    bench.run();
    let started = bench.now;
    // 5000 counts = 500 steps at 192 steps/s: twice that is 5.21 s, plus the ramp
    // (192 / 10000 s) and 100 ms.
    let limit = Duration::from_secs_f64(2.0 * 500.0 / 192.0 + 192.0 / 10_000.0 + 0.1);
    while bench.now < started + limit - Duration::from_millis(20) {
        bench.tick(Some(MD_JOGGING));
        assert_eq!(bench.driver.channel(0).fault, None);
    }
    while bench.now < started + limit + Duration::from_millis(20) {
        bench.tick(None);
    }
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::HomeFailed));
    assert_eq!(bench.run(), ["W164", "W0343", "R06"]);
}

#[test]
fn digital_inputs_outputs_and_capture_are_read_and_driven() {
    let mut bench = Bench::started_with(QsbDriverConfig {
        io: QsbIo {
            digital_in: 0b0001,
            digital_out: 0b1000,
            capture: Some(CaptureInput {
                bit: 0,
                falling: false,
            }),
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    });
    assert_eq!(bench.driver.read_pin(IO1), None, "not a configured pin");
    assert_eq!(bench.driver.read_pin(M_ENCODER), None);
    // The `s` answers of S01 and S05 carried 0: every pin low, CAPTURE 0.
    assert_eq!(bench.driver.read_pin(IO0).map(|r| r.value), Some(0.0));
    bench.advance(TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x01, 0b1001);
    bytes.extend(bench.line(ResponseType::Stream, 0x05, (-5i32) as u32));
    bench.rx(&bytes);
    let now = bench.now;
    assert_eq!(
        bench.driver.read_pin(IO0),
        Some(PinReading {
            value: 1.0,
            refreshed_at: Some(now),
            events: 0,
        })
    );
    assert_eq!(bench.driver.read_pin(IO3).map(|r| r.value), Some(1.0));
    assert_eq!(
        bench.driver.read_pin(M_CAPTURE).map(|r| r.value),
        Some(-5.0)
    );
    // Streamed on change: a later encoder line says the levels still hold.
    bench.tick(None);
    assert_eq!(
        bench.driver.read_pin(IO0).and_then(|r| r.refreshed_at),
        Some(bench.now)
    );
    // An output: "A write sets the open-drain output state".
    bench
        .driver
        .set_output(bench.now, IO3, false)
        .expect("an output");
    assert_eq!(bench.run(), ["W017"]);
    assert!(!bench.driver.goals_pending());
    assert_eq!(
        bench.driver.set_output(bench.now, IO0, true),
        Err(GoalError::NoSuchPin(IO0)),
        "an input"
    );
    // A refused write is surfaced and not sent again and again.
    bench.driver.set_output(bench.now, IO3, true).expect("out");
    let sent = bench.sent().expect("the write");
    assert_eq!(sent, b"W01F\r\n");
    let bytes = bench.line(ResponseType::Error, 0x01, 0xF);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::BoardError));
    assert_eq!(bench.sent(), None);
}

#[test]
fn outputs_are_written_again_after_a_reset() {
    let config = QsbDriverConfig {
        io: QsbIo {
            digital_out: 0b0001,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut bench = Bench::started_with(config);
    bench.driver.set_output(bench.now, IO0, false).expect("out");
    assert_eq!(bench.run(), ["W01E"]);
    bench.tick(Some(MD_DONE));
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    bench.rx(&bytes);
    let lines = bench.run();
    let config_at = lines
        .iter()
        .position(|l| l == "W02100")
        .expect("io0 output");
    assert_eq!(lines[config_at + 1], "W01E", "{lines:?}");
}

#[test]
fn goals_and_outputs_during_start_up_are_refused_as_starting() {
    let config = QsbDriverConfig {
        io: QsbIo {
            digital_out: 0b0001,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut bench = Bench::with_config(config);
    bench.expect(b"W161\r\n");
    let stop = Goal::Stop { decel: 1000.0 };
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, stop),
        Err(GoalError::Starting)
    );
    assert_eq!(
        bench.driver.set_output(bench.now, IO0, false),
        Err(GoalError::Starting)
    );
    bench.driver.link_down(bench.now);
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, stop),
        Err(GoalError::Offline)
    );
}

#[test]
fn analog_mode_reads_the_special_data_format_and_carries_no_axis() {
    // "Time Stamp [16-bits] Digital I/O [4-bits] 00 Analog [10-bits]"
    let mut bench = Bench::with_config(QsbDriverConfig {
        variant: ProductType::S,
        input_mode: EncoderMode::Analog,
        io: QsbIo {
            encoder: true,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    });
    assert_eq!(
        bench.run(),
        [
            "W161", "R14", "W155", "W002", "W0343", "W040", "W0B0", "W0C1", "S0E"
        ],
        "MODE 10 = ANALOG MODE"
    );
    assert_eq!(
        bench.driver.capabilities(0),
        motion_drivers::GoalKinds::NONE
    );
    let sample = AnalogSample {
        time_stamp: 77,
        digital: 0xF,
        analog: 512,
    };
    bench.advance(TICK);
    let bytes = bench.line(ResponseType::Stream, 0x0E, sample.data());
    bench.rx(&bytes);
    let reading = bench.driver.read_pin(Pin(0)).expect("the encoder pin");
    assert_eq!(reading.value, 512.0);
    assert_eq!(reading.refreshed_at, Some(bench.now));
}

#[test]
fn analog_mode_on_a_qsb_m_takes_the_digital_inputs_from_the_samples() {
    let mut bench = Bench::started_with(QsbDriverConfig {
        input_mode: EncoderMode::Analog,
        io: QsbIo {
            digital_in: 0b0010, // io1: free, the motor drive is not active
            encoder: true,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    });
    let sample = AnalogSample {
        time_stamp: 5,
        digital: 0b1101,
        analog: 1023,
    };
    bench.advance(TICK);
    let bytes = bench.line(ResponseType::Stream, 0x0E, sample.data());
    bench.rx(&bytes);
    assert_eq!(bench.driver.read_pin(IO1).map(|r| r.value), Some(0.0));
    assert_eq!(
        bench.driver.read_pin(M_ENCODER).map(|r| r.value),
        Some(1023.0)
    );
}

#[test]
fn pwm_mode_on_a_qsb_m_has_no_motor_drive_and_frees_io1_and_io2() {
    let mut io = QsbIo {
        encoder: true,
        ..QsbIo::default()
    };
    assert!(io.add(ProductType::M, IO1, SignalKind::DigitalOut));
    assert!(!io.add(ProductType::M, M_ENCODER, SignalKind::DigitalIn));
    let mut bench = Bench::with_config(QsbDriverConfig {
        input_mode: EncoderMode::Pwm,
        io,
        ..QsbDriverConfig::default()
    });
    let lines = bench.run();
    assert!(lines.contains(&"W001".to_owned()), "MODE 01 = PWM MODE");
    assert!(
        lines.contains(&"W02200".to_owned()),
        "io1 an output: {lines:?}"
    );
    assert!(!lines.contains(&"W162".to_owned()), "no motor drive");
    bench.advance(TICK);
    let bytes = bench.line(ResponseType::Stream, 0x0E, 3000);
    bench.rx(&bytes);
    assert_eq!(
        bench.driver.read_pin(M_ENCODER).map(|r| r.value),
        Some(3000.0)
    );
    bench.driver.set_output(bench.now, IO1, false).expect("io1");
    assert_eq!(bench.run(), ["W01D"]);
}

#[test]
fn what_the_board_or_the_drive_cannot_have_is_dropped() {
    // With the motor drive active, io1 and io2 are step and direction: no signal there;
    // the enable line is not a signal either.
    let bench = Bench::started_with(QsbDriverConfig {
        io: QsbIo {
            digital_in: 0b1110,
            ..QsbIo::default()
        },
        enable: Some(EnableOutput {
            bit: 3,
            active_high: true,
        }),
        ..QsbDriverConfig::default()
    });
    assert_eq!(bench.driver.read_pin(IO1), None);
    assert_eq!(bench.driver.read_pin(Pin(2)), None);
    assert_eq!(bench.driver.read_pin(IO3), None);
    // A -S has no digital I/O and no drive to enable.
    let s = Bench::started_with(QsbDriverConfig {
        variant: ProductType::S,
        enable: Some(EnableOutput {
            bit: 0,
            active_high: false,
        }),
        io: QsbIo {
            digital_out: 1,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    });
    assert!(!s.driver.capabilities(0).contains(GoalKind::Off));
    assert_eq!(s.driver.read_pin(IO0), None);
}

#[test]
fn a_target_half_a_step_away_is_as_close_as_whole_steps_get() {
    // 4 counts per step: 2 counts is half a step — moving would land 2 counts beyond, and
    // the correction back where it started, forever.
    let mut bench = Bench::started_with(machine());
    for _ in 0..3 {
        bench.tick(Some(MD_DONE));
    }
    let goal = Goal::Position { counts: 2.0 };
    bench.driver.set_goal(bench.now, 0, goal).expect("position");
    assert_eq!(bench.run(), Vec::<String>::new());
    assert!(bench.driver.channel(0).arrived);
    let goal = Goal::Position { counts: 3.0 };
    bench.driver.set_goal(bench.now, 0, goal).expect("position");
    assert_eq!(bench.run(), ["W111", "W168"], "three quarters: one step");
}
