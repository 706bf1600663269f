//! The QSB driver's I/O pins and enable line against the simulated board over a real
//! `SimLink` at 230400 baud, driven directly (the engine does not route pin reads and
//! writes yet): inputs within the refresh budget, outputs on the wire and at the pins, the
//! analog stream, Off through the drive's enable line.

use core::time::Duration;
use std::sync::{Arc, Mutex};

use board_qsb::driver::{CaptureInput, EnableOutput, QsbDriver, QsbDriverConfig, QsbIo};
use board_qsb::sim::{AnalogInput, DriveEnable, QsbSim, QsbSimConfig, Variant};
use motion_drivers::{Driver, Goal, GoalError, GoalKind, Pin};
use motion_link::Link;
use motion_link::sim::SimLink;
use qsb::{CommandDecoder, DigIo, EncoderMode, Register, Request, Write};

use super::support::rig::Shared;

const IO0: Pin = Pin(0);
const IO3: Pin = Pin(3);
const M_ENCODER: Pin = Pin(4);
const M_CAPTURE: Pin = Pin(5);

/// A driver and a simulated board on one simulated wire, stepped every millisecond.
struct Pair {
    driver: QsbDriver,
    link: SimLink,
    sim: Arc<Mutex<QsbSim>>,
    now: Duration,
    commands: CommandDecoder,
    /// Every request sent, decoded with the protocol crate.
    sent: Vec<Request>,
}

impl Pair {
    fn new(sim: QsbSimConfig, driver: QsbDriverConfig) -> Self {
        let (device, sim) = Shared::new(QsbSim::new(sim));
        let mut pair = Self {
            driver: QsbDriver::new(driver),
            link: SimLink::stream("usb0", 230_400, device),
            sim,
            now: Duration::ZERO,
            commands: CommandDecoder::new(),
            sent: Vec::new(),
        };
        assert!(
            pair.run_until(Duration::from_millis(100), |p| p.driver.status().online),
            "the QSB starts"
        );
        pair
    }

    fn step(&mut self) {
        let mut buf = [0u8; 512];
        while let Ok(n @ 1..) = self.link.read(self.now, &mut buf) {
            self.driver.handle_rx(self.now, &buf[..n]);
        }
        self.driver.handle_timeout(self.now);
        while let Some(sent) = self.driver.poll_transmit(self.now, &mut buf) {
            let bytes = &buf[..sent.len];
            self.link.write(self.now, bytes).expect("sim link");
            let (_, line) = self.commands.decode(bytes);
            let line = line.expect("one whole line").expect("a command line");
            self.sent
                .push(Request::from_line(&line).expect("a command of the command list"));
        }
        self.now += Duration::from_millis(1);
    }

    fn run_until(&mut self, limit: Duration, done: impl Fn(&Self) -> bool) -> bool {
        let end = self.now + limit;
        while self.now < end {
            self.step();
            if done(self) {
                return true;
            }
        }
        false
    }

    fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.step();
        }
    }

    fn value(&self, pin: Pin) -> Option<f64> {
        self.driver
            .read_pin(pin)
            .filter(|r| r.refreshed_at.is_some())
            .map(|r| r.value)
    }
}

fn m_with(io: QsbIo) -> Pair {
    Pair::new(
        QsbSimConfig::default(),
        QsbDriverConfig {
            io,
            ..QsbDriverConfig::default()
        },
    )
}

#[test]
fn an_input_change_is_read_within_the_refresh_budget() {
    let mut pair = m_with(QsbIo {
        digital_in: 0b0001,
        ..QsbIo::default()
    });
    assert!(pair.sent.contains(&Request::Stream(Register::DigIo)));
    assert_eq!(pair.value(IO0), Some(1.0), "pulled up");
    let budget = pair.driver.refresh_budget();
    let now = pair.now;
    pair.sim
        .lock()
        .expect("sim")
        .set_digital_inputs(now, 0b1110);
    let changed_at = pair.now;
    assert!(pair.run_until(budget, |p| p.value(IO0) == Some(0.0)));
    let reading = pair.driver.read_pin(IO0).expect("configured");
    let took = pair.now - changed_at;
    assert!(took <= budget, "{took:?} > {budget:?}");
    // Fresh while nothing changes: the stream would have said.
    pair.run(50);
    let later = pair.driver.read_pin(IO0).expect("configured");
    assert_eq!(later.value, 0.0);
    assert!(later.refreshed_at > reading.refreshed_at);
    assert!(pair.now - later.refreshed_at.expect("known") <= budget);
}

#[test]
fn an_output_reaches_the_pin_and_reads_back_the_level_measured_there() {
    let mut pair = m_with(QsbIo {
        digital_out: 0b1000,
        ..QsbIo::default()
    });
    // "Set the direction …": io3 an output (B11), the others inputs.
    assert!(
        pair.sent
            .iter()
            .any(|r| matches!(r, Request::Write(Write::DigIoConfig(c)) if c.output == 0b1000))
    );
    let now = pair.now;
    pair.driver.set_output(now, IO3, false).expect("io3");
    pair.run(5);
    assert_eq!(
        pair.sent.last(),
        Some(&Request::Write(Write::DigIo(DigIo(0b0111))))
    );
    assert_eq!(pair.sim.lock().expect("sim").digital_pins() & 0b1000, 0);
    assert!(pair.run_until(Duration::from_millis(10), |p| p.value(IO3) == Some(0.0)));
    // Released high, it reads what the pin is at: an open drain pulled low outside reads 0.
    let now = pair.now;
    pair.driver.set_output(now, IO3, true).expect("io3");
    assert!(pair.run_until(Duration::from_millis(10), |p| p.value(IO3) == Some(1.0)));
    let now = pair.now;
    pair.sim
        .lock()
        .expect("sim")
        .set_digital_inputs(now, 0b0111);
    assert!(pair.run_until(Duration::from_millis(10), |p| p.value(IO3) == Some(0.0)));
    assert_eq!(
        pair.driver.set_output(pair.now, IO0, true),
        Err(GoalError::NoSuchPin(IO0))
    );
}

#[test]
fn outputs_come_back_after_the_board_resets() {
    let mut pair = m_with(QsbIo {
        digital_out: 0b0001,
        ..QsbIo::default()
    });
    let now = pair.now;
    pair.driver.set_output(now, IO0, false).expect("io0");
    pair.run(5);
    assert_eq!(pair.sim.lock().expect("sim").digital_pins() & 1, 0);
    let now = pair.now;
    pair.sim.lock().expect("sim").reset(now);
    pair.run(2);
    assert_eq!(pair.sim.lock().expect("sim").digital_pins() & 1, 1, "reset");
    assert!(pair.run_until(Duration::from_millis(300), |p| {
        p.driver.status().online && p.sim.lock().expect("sim").digital_pins() & 1 == 0
    }));
    assert_eq!(pair.driver.status().resets, 1);
}

#[test]
fn the_capture_pin_reads_the_count_an_input_edge_latched() {
    let mut pair = m_with(QsbIo {
        capture: Some(CaptureInput {
            bit: 0,
            falling: true,
        }),
        ..QsbIo::default()
    });
    let now = pair.now;
    pair.sim.lock().expect("sim").nudge_encoder(now, 30.0); // 120 counts
    pair.run(5);
    let now = pair.now;
    pair.sim
        .lock()
        .expect("sim")
        .set_digital_inputs(now, 0b1110); // io0 high → low
    assert!(pair.run_until(Duration::from_millis(10), |p| {
        p.value(M_CAPTURE) == Some(120.0)
    }));
}

#[test]
fn analog_mode_streams_the_special_data_format_into_the_encoder_pin() {
    // 2.5 V, no noise: 2.5 / 5 × 1023 = 511.5 → 512.
    let sim = QsbSimConfig {
        variant: Variant::S,
        analog: AnalogInput {
            offset_volts: 2.5,
            amplitude_volts: 0.0,
            frequency_hz: 0.0,
            noise_volts: 0.0,
        },
        ..QsbSimConfig::default()
    };
    let driver = QsbDriverConfig {
        variant: Variant::S,
        input_mode: EncoderMode::Analog,
        io: QsbIo {
            encoder: true,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut pair = Pair::new(sim, driver);
    assert!(
        pair.sent.iter().any(
            |r| matches!(r, Request::Write(Write::Mode(m)) if m.encoder == EncoderMode::Analog)
        )
    );
    pair.run(20);
    let reading = pair.driver.read_pin(Pin(0)).expect("the encoder pin");
    assert_eq!(reading.value, 512.0);
    assert!(pair.now - reading.refreshed_at.expect("streamed") <= Duration::from_millis(4));
    assert_eq!(pair.driver.capabilities(0), motion_drivers::GoalKinds::NONE);
}

#[test]
fn pwm_mode_reads_the_absolute_position() {
    let sim = QsbSimConfig {
        motion: board_qsb::sim::EncoderMotion {
            velocity: 0.0,
            amplitude: 0.0,
            frequency_hz: 0.0,
        },
        ..QsbSimConfig::default()
    };
    let driver = QsbDriverConfig {
        input_mode: EncoderMode::Pwm,
        io: QsbIo {
            encoder: true,
            ..QsbIo::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut pair = Pair::new(sim, driver);
    let now = pair.now;
    pair.sim.lock().expect("sim").nudge_encoder(now, 125.0); // a quarter turn
    pair.run(10);
    // 12-bit: a quarter of 4096.
    assert_eq!(pair.value(M_ENCODER), Some(1024.0));
    assert!(!pair.sent.contains(&Request::Write(Write::Command(
        qsb::QsbCommand::EnableMotorDrive
    ))));
}

#[test]
fn off_releases_the_drive_enable_and_the_next_move_enables_it_first() {
    let enable = EnableOutput {
        bit: 3,
        active_high: false,
    };
    let sim = QsbSimConfig {
        drive_enable: Some(DriveEnable {
            bit: 3,
            active_high: false,
        }),
        ..QsbSimConfig::default()
    };
    let driver = QsbDriverConfig {
        enable: Some(enable),
        ..QsbDriverConfig::default()
    };
    let mut pair = Pair::new(sim, driver);
    assert!(pair.sim.lock().expect("sim").drive_energised());
    assert!(pair.driver.capabilities(0).contains(GoalKind::Off));
    let now = pair.now;
    pair.driver.set_goal(now, 0, Goal::Off).expect("off");
    pair.run(5);
    assert!(!pair.sim.lock().expect("sim").drive_energised());
    assert!(
        pair.sent
            .contains(&Request::Write(Write::Command(qsb::QsbCommand::MotorQuit)))
    );
    pair.run(10);
    let from = pair.sent.len();
    let now = pair.now;
    let goal = Goal::Position { counts: 1000.0 };
    pair.driver.set_goal(now, 0, goal).expect("move");
    assert!(pair.run_until(Duration::from_secs(2), |p| p.driver.channel(0).arrived));
    let enable_at = pair.sent[from..]
        .iter()
        .position(|r| *r == Request::Write(Write::DigIo(DigIo(0b0111))))
        .expect("enabled");
    let move_at = pair.sent[from..]
        .iter()
        .position(|r| *r == Request::Write(Write::Command(qsb::QsbCommand::MotorMove)))
        .expect("moved");
    assert!(enable_at < move_at, "{:?}", &pair.sent[from..]);
    assert!((pair.driver.channel(0).position - 1000.0).abs() <= 10.0);
}
