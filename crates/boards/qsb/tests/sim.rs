//! The simulated QSB on the wire: datasheet golden exchanges, streaming, EOR formats,
//! errors, counter modes, digital I/O and the -M stepper drive. Quotes are from the QSB
//! Command List, document version 1.28.

use core::time::Duration;

use board_qsb::sim::{EncoderMotion, QsbSim, QsbSimConfig, Variant};
use motion_link::sim::StreamDevice;
use qsb::{
    AnalogSample, BaudRate, MdStatus, Register, Response, ResponseDecoder, ResponseType, Str, TICK,
    Value,
};

const MS: Duration = Duration::from_millis(1);
const US: Duration = Duration::from_micros(1);

/// A host on a perfect wire: sends lines, collects every response with the instant the
/// model started sending it.
struct Host {
    sim: QsbSim,
    decoder: ResponseDecoder,
    now: Duration,
    raw: Vec<u8>,
    log: Vec<(Duration, Response)>,
}

impl Host {
    fn new(config: QsbSimConfig) -> Self {
        Self {
            sim: QsbSim::new(config),
            decoder: ResponseDecoder::new(),
            now: Duration::ZERO,
            raw: Vec::new(),
            log: Vec::new(),
        }
    }

    /// A -S whose encoder stands still unless nudged.
    fn still(variant: Variant) -> Self {
        Self::new(QsbSimConfig {
            variant,
            motion: EncoderMotion {
                velocity: 0.0,
                amplitude: 0.0,
                frequency_hz: 0.0,
            },
            ..QsbSimConfig::default()
        })
    }

    fn send(&mut self, text: &str) {
        self.sim.receive(self.now, format!("{text}\r\n").as_bytes());
    }

    fn collect(&mut self) {
        let mut buf = [0u8; 64];
        loop {
            let n = self.sim.transmit(self.now, &mut buf);
            if n == 0 {
                return;
            }
            self.raw.extend_from_slice(&buf[..n]);
            let mut rest = &buf[..n];
            while !rest.is_empty() {
                let (used, r) = self.decoder.decode(rest);
                if let Some(r) = r {
                    self.log.push((self.now, r));
                }
                rest = &rest[used..];
            }
        }
    }

    /// Runs the model to `until`, event by event.
    fn run_until(&mut self, until: Duration) {
        loop {
            self.collect();
            match self.sim.next_event(self.now) {
                Some(t) if t > self.now && t <= until => self.now = t,
                _ => break,
            }
        }
        self.now = until;
        self.collect();
    }

    fn run_for(&mut self, d: Duration) {
        let until = self.now + d;
        self.run_until(until);
    }

    /// Sends a command and returns its answer (the first new line).
    fn ask(&mut self, text: &str) -> Response {
        let before = self.log.len();
        self.send(text);
        self.run_for(2 * MS);
        let (_, r) = self
            .log
            .get(before)
            .copied()
            .unwrap_or_else(|| panic!("no answer to {text}"));
        r
    }

    fn value(&mut self, text: &str) -> u32 {
        let r = self.ask(text);
        assert!(
            matches!(
                r.ty,
                ResponseType::Read | ResponseType::Write | ResponseType::Stream
            ),
            "{text} answered {r:?}"
        );
        r.data
    }

    fn raw_answer(&mut self, text: &str) -> Vec<u8> {
        let start = self.raw.len();
        self.ask(text);
        self.raw[start..].to_vec()
    }

    fn streamed(&self, register: u8, since: usize) -> Vec<(Duration, Response)> {
        self.log[since..]
            .iter()
            .filter(|(_, r)| r.ty == ResponseType::Stream && r.register == register)
            .copied()
            .collect()
    }
}

#[test]
fn version_r14_golden_exchange() {
    // VERSION 14: "Example, 00001201 = SN: 00001, Type: QSB-S, Version: 01"
    let mut host = Host::new(QsbSimConfig {
        variant: Variant::S,
        serial_number: 1,
        firmware_version: 0x01,
        ..QsbSimConfig::default()
    });
    // Factory EOR 0x0B: spaces, CR, LF (docs/ARCHITECTURE.md: `r 14 00001201 !`).
    assert_eq!(host.raw_answer("R14"), b"r 14 00001201 !\r\n");
    let Value::Version(v) = host.log[0].1.value().unwrap() else {
        panic!()
    };
    assert_eq!((v.serial, v.product, v.firmware), (1, Variant::S, 1));
    // The -M reports product type 1.
    let mut m = Host::new(QsbSimConfig::default());
    assert_eq!(m.value("R14") >> 8 & 0xF, 1);
}

#[test]
fn answer_starts_after_the_processing_delay() {
    let mut sim = QsbSim::new(QsbSimConfig::default());
    let mut out = [0u8; 64];
    sim.receive(Duration::from_secs(3), b"R14\r");
    assert_eq!(
        sim.next_event(Duration::from_secs(3)),
        Some(Duration::from_secs(3) + 100 * US)
    );
    assert_eq!(sim.transmit(Duration::from_secs(3) + 99 * US, &mut out), 0);
    let n = sim.transmit(Duration::from_secs(3) + 100 * US, &mut out);
    assert_eq!(&out[..n], b"r 14 00001113 !\r\n");
    // "a backspace character will erase a partially entered command"
    sim.receive(Duration::from_secs(4), b"W03\x08R03\n");
    let n = sim.transmit(Duration::from_secs(5), &mut out);
    assert_eq!(&out[..n], b"r 03 0000004F !\r\n");
}

#[test]
fn w0363_sets_sync_index_reset_on_index_free_running_x4() {
    // MDR0 03: "Example: Sync Index, Reset on Index, Free Running, X4 mode, W0363"
    let config = QsbSimConfig {
        variant: Variant::S,
        cycles_per_rev: 400,
        motion: EncoderMotion {
            velocity: 0.0,
            amplitude: 0.0,
            frequency_hz: 0.0,
        },
        ..QsbSimConfig::default()
    };
    // Factory MDR0 4F: x4, modulo-n (DTR 499 → modulo 500), index disabled.
    let mut factory = Host::new(config.clone());
    factory.sim.nudge_encoder(Duration::ZERO, 510.0);
    assert_eq!(factory.value("R07"), (510 * 4) % 500);

    let mut host = Host::new(config);
    assert_eq!(host.raw_answer("W0363"), b"w 03 00000063 !\r\n");
    assert_eq!(host.value("R03"), 0x63);
    let now = host.now;
    host.sim.nudge_encoder(now, 510.0);
    // The index at 400 cycles cleared CNTR; 110 cycles at x4 since.
    assert_eq!(host.value("R07"), 110 * 4);
    assert!(Str::from_data(host.value("R06")).unwrap().index);
    // Back over the index: moving down, the index acts on entering its quarter-cycle
    // window at 400.25 cycles; 10.25 cycles at x4 below it.
    let now = host.now;
    host.sim.nudge_encoder(now, -120.0);
    assert_eq!(host.value("R0E") as i32, -41);
}

#[test]
fn w02f00_makes_every_io_an_output() {
    // DIG I/O CONFIG 02: "Example: Set All I/O as Outputs, W02F00"
    let mut host = Host::new(QsbSimConfig::default());
    assert_eq!(host.value("R01"), 0xF);
    // As inputs, writing the outputs low changes nothing at the pins.
    host.ask("W010");
    assert_eq!(host.value("R01"), 0xF);
    assert_eq!(host.raw_answer("W02F00"), b"w 02 00000F00 !\r\n");
    // "All I/O port pins will be set high after a write to this configuration register"
    assert_eq!(host.value("R01"), 0xF);
    host.ask("W015");
    assert_eq!(host.value("R01"), 0x5);
    // Open drain: a pin released high can still be pulled low from outside.
    let now = host.now;
    host.sim.set_digital_inputs(now, 0b1011);
    assert_eq!(host.value("R01"), 0x1);
    // The -D has one bit, the -S none.
    let mut d = Host::new(QsbSimConfig {
        variant: Variant::D,
        ..QsbSimConfig::default()
    });
    assert_eq!(d.value("R01"), 0x1);
    let mut s = Host::new(QsbSimConfig {
        variant: Variant::S,
        ..QsbSimConfig::default()
    });
    assert_eq!(s.ask("R01").ty, ResponseType::Unsupported);
}

#[test]
fn w0c5_streams_the_encoder_every_9_8_ms_with_time_stamps() {
    // INTERVAL RATE 0C: "Example: Set 9.8ms Interval, W0C5"; "Stream Encoder Value, S0E";
    // EOR 15: "All Formatting Enabled, W15F".
    let mut host = Host::new(QsbSimConfig {
        variant: Variant::S,
        motion: EncoderMotion {
            velocity: 1000.0,
            amplitude: 0.0,
            frequency_hz: 0.0,
        },
        ..QsbSimConfig::default()
    });
    host.ask("W0303"); // x4, free running
    assert!(host.raw_answer("W15F").starts_with(b"w 15 0000000F "));
    host.ask("W0C5");
    let since = host.log.len();
    let start = host.now;
    host.send("S0E");
    host.run_for(100 * MS);
    let lines = host.streamed(0x0E, since);
    // The acknowledgement, then one line per 5 × 1/512 s.
    assert_eq!(lines.len(), 1 + 10, "{lines:?}");
    let period = TICK * 5;
    for (k, (at, r)) in lines.iter().enumerate() {
        let expected = start + period * k as u32 + 100 * US;
        assert_eq!(*at, expected, "line {k}");
        let ts = r.time_stamp.expect("time stamp");
        let sample = start + period * k as u32;
        assert_eq!(ts, (sample.as_nanos() / TICK.as_nanos()) as u32, "line {k}");
    }
    // 1000 cycles/s at x4: 39.06 counts per 9.77 ms.
    for pair in lines.windows(2) {
        let d = pair[1].1.data.wrapping_sub(pair[0].1.data);
        assert!((39..=40).contains(&d), "{d}");
    }
    // The wire format with everything enabled.
    let text = String::from_utf8_lossy(&host.raw).to_string();
    assert!(text.contains("s 0E "), "{text}");
}

#[test]
fn factory_interval_disables_stream_output() {
    // INTERVAL RATE: "A value of 0xFFFF will disable data output" (factory default FFFF).
    let mut host = Host::new(QsbSimConfig {
        variant: Variant::S,
        ..QsbSimConfig::default()
    });
    let since = host.log.len();
    host.ask("S0E");
    host.run_for(200 * MS);
    assert_eq!(
        host.streamed(0x0E, since).len(),
        1,
        "only the acknowledgement"
    );
    assert_eq!(host.sim.next_event(host.now), None);
}

#[test]
fn a_read_cancels_the_stream_of_that_register() {
    // READ ENCODER: "A read of the encoder value will disable the streaming mode."
    // MD STATUS: "A read of MD STATUS will cancel the streaming mode."
    let mut host = Host::new(QsbSimConfig::default());
    host.ask("W0C1");
    host.ask("W2"); // not a command: answered x
    host.ask("S0E");
    host.ask("S13");
    let since = host.log.len();
    host.run_for(20 * MS);
    assert!(host.streamed(0x0E, since).len() >= 9);
    assert_eq!(host.ask("R0E").ty, ResponseType::Read);
    let since = host.log.len();
    host.run_for(20 * MS);
    assert!(
        host.streamed(0x0E, since).is_empty(),
        "encoder stream cancelled"
    );
    // MD STATUS streams only on change: start a jog and it reports.
    host.ask("W162");
    host.ask("W169");
    host.run_for(20 * MS);
    let status = host.streamed(0x13, since);
    assert!(!status.is_empty(), "MD STATUS stream still running");
    let last = MdStatus::from_data(status.last().unwrap().1.data).unwrap();
    assert!(last.jogging && last.moving && last.enabled);
    // COMMAND 1: "Deactivate Encoder, Digital I/O and MD Status streaming data outputs."
    host.ask("S0E");
    host.ask("W161");
    let since = host.log.len();
    host.ask("W164");
    host.run_for(50 * MS);
    assert!(host.streamed(0x0E, since).is_empty());
    assert!(host.streamed(0x13, since).is_empty());
}

#[test]
fn w163_saves_parameters_across_power_cycles() {
    // COMMAND 16: "Example: Save Parameters, W163"
    let mut host = Host::new(QsbSimConfig::default());
    host.ask("W0363");
    host.ask("W081F4");
    host.ask("W0C5");
    host.ask("W153");
    host.sim.power_cycle(host.now);
    assert_eq!(host.value("R03"), 0x4F, "not saved: factory value");
    host.ask("W0363");
    host.ask("W081F4");
    host.ask("W0C5");
    host.ask("W153");
    assert_eq!(host.raw_answer("W163"), b"w1600000003!\r\n");
    host.ask("W0C9");
    host.sim.power_cycle(host.now);
    assert_eq!(host.raw_answer("R03"), b"r0300000063!\r\n");
    assert_eq!(host.value("R08"), 0x1F4);
    assert_eq!(host.value("R0C"), 5);
    // Volatile registers are back at their factory values.
    assert_eq!(host.value("R06"), 0x0A);
    assert_eq!(host.value("R13"), 0x01);
}

#[test]
fn w1660a_selects_the_baud_rate_after_the_answer() {
    // COMMAND 16: "Set 230400 Baud, W1660A"; "The new Baud rate is permanently saved"
    let mut host = Host::new(QsbSimConfig::default());
    assert_eq!(host.sim.baud(), Some(230_400));
    assert_eq!(host.raw_answer("W1660A"), b"w 16 0000060A !\r\n");
    assert_eq!(host.sim.baud(), Some(230_400));
    // 115200: the answer still goes at 230400, then the board listens at the new rate.
    let t0 = host.now;
    host.send("W1640A");
    host.run_until(t0 + 100 * US);
    assert_eq!(host.sim.baud(), Some(230_400));
    let line = 17u32; // "w 16 0000040A !\r\n"
    let end = t0 + 100 * US + Duration::from_nanos(10_000_000_000 / 230_400) * line;
    host.run_until(end);
    assert_eq!(host.sim.baud(), Some(115_200));
    host.sim.power_cycle(host.now + MS);
    assert_eq!(host.sim.baud(), Some(BaudRate::B115200.bits_per_second()));
    // Before firmware 13 the command does not exist.
    let mut old = Host::new(QsbSimConfig {
        firmware_version: 0x12,
        ..QsbSimConfig::default()
    });
    assert_eq!(old.ask("W1640A").ty, ResponseType::Unsupported);
    assert_eq!(old.sim.baud(), Some(230_400));
}

#[test]
fn eor_formats_every_combination() {
    let mut host = Host::new(QsbSimConfig::default());
    assert_eq!(host.raw_answer("W153"), b"w1500000003!\r\n");
    assert_eq!(host.raw_answer("R03"), b"r030000004F!\r\n");
    assert_eq!(host.raw_answer("W151"), b"w1500000001!\n");
    assert_eq!(host.raw_answer("W152"), b"w1500000002!\r");
    assert_eq!(host.raw_answer("W150"), b"w1500000000!");
    assert_eq!(host.raw_answer("W158"), b"w 15 00000008 !");
    // Negative values as two's complement.
    host.ask("W0303");
    let now = host.now;
    host.sim.nudge_encoder(now, -25.0);
    assert_eq!(host.raw_answer("R07"), b"r 07 FFFFFF9C !");
}

#[test]
fn error_and_unsupported_answers() {
    let mut host = Host::new(QsbSimConfig::default());
    assert_eq!(host.raw_answer("R17"), b"x 17 00000000 !\r\n");
    assert_eq!(host.raw_answer("W0712"), b"x 07 00000012 !\r\n");
    assert_eq!(host.raw_answer("S00"), b"x 00 00000000 !\r\n");
    // "If the error response is returned, Data will be the incorrect data value sent to the
    // QSB; this value will not be written to the device."
    assert_eq!(host.raw_answer("W0F1F"), b"e 0F 0000001F !\r\n");
    assert_eq!(host.value("R0F"), 0x20);
    assert_eq!(host.ask("W12FFFFCD37").ty, ResponseType::Error);
    assert_eq!(host.ask("Q12").ty, ResponseType::Unsupported);
    assert_eq!(host.ask("W0410001").ty, ResponseType::Error);
    let e = host.ask("W0013");
    assert_eq!(
        e.check(),
        Err(qsb::Error::Rejected {
            register: 0,
            data: 0x13
        })
    );
    // Products: the -D has no motor registers, and only COMMAND 1, 3 and X0A.
    let mut d = Host::new(QsbSimConfig {
        variant: Variant::D,
        ..QsbSimConfig::default()
    });
    assert_eq!(d.ask("R0F").ty, ResponseType::Unsupported);
    assert_eq!(d.ask("W169").ty, ResponseType::Error);
    assert_eq!(d.ask("W161").ty, ResponseType::Write);
    assert_eq!(host.sim.stats().unsupported, 4);
}

#[test]
fn m_move_arrives_within_step_rate_and_acceleration() {
    // MD STEP RATE "Example: 1000 steps/sec, W0F3E8"; MD MOVE STEPS "2000 steps, W117D0".
    let mut host = Host::new(QsbSimConfig::default());
    host.ask("W0303"); // x4 free running, so the count is not taken modulo 500
    host.ask("W0F3E8");
    host.ask("W102710"); // 10000 steps/s²
    host.ask("W117D0");
    host.ask("W162");
    assert!(MdStatus::from_data(host.value("R13")).unwrap().enabled);
    let start = host.now;
    host.ask("W168");
    let (vmax, accel) = host.sim.motor_limits();
    assert_eq!((vmax, accel), (992.0, 10000.0), "16 steps/s increments");
    let dt = 100 * US;
    let mut last_v = host.sim.motor_velocity();
    let mut t = host.now;
    let mut moving_seen = false;
    while host.sim.motor_velocity() != 0.0 || t < start + 10 * MS {
        t += dt;
        host.sim.transmit(t, &mut [0u8; 64]);
        let v = host.sim.motor_velocity();
        assert!(v.abs() <= vmax * (1.0 + 1e-9), "{v}");
        assert!(
            (v - last_v).abs() <= accel * dt.as_secs_f64() * (1.0 + 1e-6),
            "{v} {last_v}"
        );
        assert!(host.sim.motor_position() <= 2000.0 + 1e-9);
        moving_seen |= v > 0.0;
        last_v = v;
        assert!(t < start + Duration::from_secs(5), "never arrives");
    }
    assert!(moving_seen);
    host.now = t;
    assert_eq!(host.sim.motor_position(), 2000.0);
    // Trapezoid: 2000/992 + 992/10000 s.
    let expected = 2000.0 / vmax + vmax / accel;
    let took = (t - start).as_secs_f64();
    assert!((took - expected).abs() < 1e-3, "{took} vs {expected}");
    let status = MdStatus::from_data(host.value("R13")).unwrap();
    assert!(status.done && !status.moving && status.enabled);
    // The encoder on the shaft: 2.5 cycles per step at x4.
    assert_eq!(host.value("R0E"), 2000 * 10);
}

#[test]
fn m_jog_pause_resume_stop_quit() {
    let mut host = Host::new(QsbSimConfig::default());
    // Without the drive enabled, a jog is acknowledged but nothing moves.
    host.ask("W12FFFFFC18"); // -1000 steps/s
    host.ask("W169");
    host.run_for(100 * MS);
    assert_eq!(host.sim.motor_velocity(), 0.0);
    host.ask("W162");
    host.ask("W169");
    host.run_for(Duration::from_secs(1));
    assert_eq!(host.sim.motor_velocity(), -992.0);
    assert_eq!(
        host.sim.digital_pins() & 0b100,
        0,
        "direction line negative"
    );
    let s = MdStatus::from_data(host.value("R13")).unwrap();
    assert!(s.jogging && s.moving && !s.done);
    host.ask("W166"); // pause
    host.run_for(Duration::from_millis(100));
    let s = MdStatus::from_data(host.value("R13")).unwrap();
    assert!(s.paused && !s.moving && !s.done);
    host.ask("W167"); // resume
    host.run_for(Duration::from_millis(100));
    assert_eq!(host.sim.motor_velocity(), -992.0);
    host.ask("W164"); // stop with MD ACCEL (100000 steps/s²: 10 ms)
    host.run_for(5 * MS);
    assert!(host.sim.motor_velocity() < 0.0);
    host.run_for(10 * MS);
    assert_eq!(host.sim.motor_velocity(), 0.0);
    host.ask("W169");
    host.run_for(100 * MS);
    host.ask("W165"); // quit: at once
    assert_eq!(host.sim.motor_velocity(), 0.0);
    let s = MdStatus::from_data(host.value("R13")).unwrap();
    assert!(s.done && !s.moving && s.enabled);
    // COMMAND 0: drive inactive.
    host.ask("W160");
    assert_eq!(host.value("R13"), MdStatus::POWER_UP.data());
}

#[test]
fn counter_modes_x1_x2_x4_range_limit_single_cycle_and_direction() {
    let mut host = Host::still(Variant::D);
    let mut counts = |mdr0: &str, mdr1: &str, cycles: f64| {
        host.ask("W092"); // clear CNTR
        host.ask(mdr0);
        host.ask(mdr1);
        let now = host.now;
        host.sim.nudge_encoder(now, cycles);
        host.value("R07") as i32
    };
    assert_eq!(counts("W0301", "W040", 100.0), 100, "x1");
    assert_eq!(counts("W0302", "W040", 100.0), 200, "x2");
    assert_eq!(counts("W0303", "W040", 100.0), 400, "x4");
    assert_eq!(counts("W0300", "W040", 100.0), 100, "A = clock");
    assert_eq!(counts("W0303", "W04100", 100.0), -400, "count-down mode");
    assert_eq!(counts("W0303", "W044", 100.0), 0, "counting disabled");
    assert_eq!(
        counts("W030B", "W040", 200.0),
        0x1F3,
        "range-limit freezes at DTR"
    );
    assert_eq!(counts("W030F", "W040", 200.0), 800 % 500, "modulo-n");
    // Single-cycle: "disabled with a carry or borrow": the first count below zero.
    assert_eq!(counts("W0307", "W040", -1.0), -1);
    let status = Str::from_data(host.value("R06")).unwrap();
    assert!(!status.count_enabled && status.borrow && status.sign);
    let now = host.now;
    host.sim.nudge_encoder(now, 10.0);
    assert_eq!(host.value("R07") as i32, -1, "frozen");
    host.ask("W092");
    assert!(Str::from_data(host.value("R06")).unwrap().count_enabled);
    host.ask("W093");
    let status = Str::from_data(host.value("R06")).unwrap();
    assert!(!status.borrow && !status.sign);
    // Index as "load CNTR" (DTR → CNTR) and capture on index, from encoder position 0
    // (index pulses at multiples of 500 cycles).
    let mut host = Host::still(Variant::D);
    host.ask("W081F3");
    host.ask("W0313"); // x4, free running, index loads CNTR
    host.ask("W0410"); // capture on index
    host.ask("W092");
    let now = host.now;
    host.sim.nudge_encoder(now, 600.0); // index at 500 cycles
    assert_eq!(host.value("R05"), 2000, "captured at the index");
    assert_eq!(host.value("R07"), 0x1F3 + 400);
    // Index as "load OTR", LOAD REG 0 (DTR → CNTR).
    host.ask("W0A0");
    assert_eq!(host.value("R07"), 0x1F3);
}

#[test]
fn digital_input_edge_captures_the_count_and_trigger_pulses_bit0() {
    let mut host = Host::still(Variant::M);
    host.ask("W0303");
    // DIG I/O CONFIG: bit 3 interrupt enabled, high-to-low.
    host.ask("W02088");
    let now = host.now;
    host.sim.nudge_encoder(now, 10.0);
    host.sim.set_digital_inputs(now + MS, 0b0111);
    host.sim.nudge_encoder(now + 2 * MS, 10.0);
    host.run_for(3 * MS);
    assert_eq!(host.value("R05"), 40);
    assert_eq!(host.value("R07"), 80);
    // Trigger pulse: B12 with MDR1 trigger on match; INTERVAL RATE 10 = 19.5 ms.
    host.ask("W021100"); // trigger pulse enabled, bit 0 an output
    host.ask("W0420");
    host.ask("W0C0A");
    host.ask("W08C8"); // DTR 200
    assert_eq!(host.value("R01") & 1, 1);
    let now = host.now;
    host.sim.nudge_encoder(now, 40.0); // 80 → 240 counts, passing 200
    assert_eq!(host.sim.digital_pins() & 1, 0, "pulse on bit 0");
    host.run_for(TICK * 10 - 10 * US);
    assert_eq!(host.sim.digital_pins() & 1, 0);
    host.run_for(20 * US);
    assert_eq!(host.sim.digital_pins() & 1, 1, "pulse over");
}

#[test]
fn threshold_limits_stream_output() {
    // THRESHOLD 0B: a new value only when it moved at least THRESHOLD counts.
    let mut host = Host::new(QsbSimConfig {
        variant: Variant::S,
        motion: EncoderMotion {
            velocity: 100.0, // 400 counts/s at x4
            amplitude: 0.0,
            frequency_hz: 0.0,
        },
        ..QsbSimConfig::default()
    });
    host.ask("W0303");
    host.ask("W0B64"); // 100 counts
    host.ask("W0C1");
    let since = host.log.len();
    host.ask("S0E");
    host.run_for(Duration::from_secs(1));
    let lines = host.streamed(0x0E, since);
    // 400 counts in a second: the acknowledgement and about four more.
    assert!((4..=5).contains(&lines.len()), "{}", lines.len());
    for pair in lines.windows(2) {
        assert!(pair[1].1.data - pair[0].1.data >= 100);
    }
}

#[test]
fn analog_mode_streams_the_special_data_format() {
    // "Time Stamp [16-bits] Digital I/O [4-bits] 00 Analog [10-bits]"
    let mut host = Host::new(QsbSimConfig::default());
    host.ask("W002");
    let v = host.value("R0E");
    assert!(v <= 0x3FF, "plain read: the 10-bit value");
    host.ask("W0C2");
    let since = host.log.len();
    host.ask("S0E");
    host.run_for(100 * MS);
    let lines = host.streamed(0x0E, since);
    assert!(lines.len() > 20);
    let samples: Vec<AnalogSample> = lines
        .iter()
        .map(|(_, r)| AnalogSample::from_data(r.data).unwrap())
        .collect();
    for s in &samples {
        assert_eq!(s.digital, 0xF);
    }
    for pair in samples.windows(2) {
        // 2 × 1/512 s = 7.8 500-µs ticks.
        let d = pair[1].time_stamp.wrapping_sub(pair[0].time_stamp);
        assert!((7..=8).contains(&d), "{d}");
    }
    // MODE reports the PWM resolution bit only in PWM mode.
    host.ask("W161");
    host.ask("W001");
    assert_eq!(host.value("R00"), 0x11);
    assert!(host.value("R0E") < 4096);
}

#[test]
fn time_stamp_counts_1_95_ms_ticks_and_w0d1_clears_it() {
    // TIME STAMP 0D: "incremented every 1.95ms (1/512Hz clock)"; "Reset TIME STAMP, W0D1"
    let mut host = Host::new(QsbSimConfig::default());
    host.run_until(Duration::from_secs(1));
    assert_eq!(host.value("R0D"), 512);
    let cleared = host.now;
    host.send("W0D1");
    host.run_until(cleared + Duration::from_millis(500));
    assert_eq!(host.value("R0D"), 256);
}

#[test]
fn same_inputs_same_bytes() {
    let run = || {
        let mut host = Host::new(QsbSimConfig::default());
        for cmd in ["W002", "W0C1", "S0E", "W162", "W168", "S13"] {
            host.ask(cmd);
        }
        host.run_for(Duration::from_millis(300));
        host.raw
    };
    assert_eq!(run(), run());
    let _ = Register::ALL;
}

mod random {
    use super::*;
    use proptest::prelude::*;

    fn any_command() -> impl Strategy<Value = String> {
        (
            prop_oneof![Just('R'), Just('W'), Just('S'), Just('Q')],
            // INTERVAL RATE (0C) is left at its factory value, so the only `s` lines are
            // acknowledgements and every line has exactly one answer.
            (0u8..0x1A).prop_filter("not 0C", |r| *r != 0x0C),
            prop_oneof![
                Just(None),
                (0u32..0x20).prop_map(Some),
                (0u32..0x800).prop_map(Some),
                any::<u32>().prop_map(Some),
            ],
        )
            .prop_map(|(ty, reg, data)| match data {
                Some(d) => format!("{ty}{reg:02X}{d:X}\r"),
                None => format!("{ty}{reg:02X}\n"),
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn every_line_is_answered_once_and_the_motor_stays_in_limits(
            variant in prop_oneof![Just(Variant::S), Just(Variant::D), Just(Variant::M)],
            commands in proptest::collection::vec((any_command(), 0u64..200_000), 1..40),
        ) {
            let mut host = Host::new(QsbSimConfig { variant, ..QsbSimConfig::default() });
            let mut sent = 0usize;
            for (command, gap_us) in &commands {
                host.sim.receive(host.now, command.as_bytes());
                sent += 1;
                let mut left = *gap_us;
                while left > 0 {
                    let step = left.min(500);
                    host.run_for(Duration::from_micros(step));
                    left -= step;
                    let v = host.sim.motor_velocity();
                    prop_assert!(v.abs() <= 13_000.0 * (1.0 + 1e-9), "{}", v);
                    prop_assert!(host.sim.motor_position().is_finite());
                }
            }
            host.run_for(10 * MS);
            prop_assert_eq!(host.log.len(), sent);
            prop_assert_eq!(host.decoder.bad_frames(), 0);
            prop_assert_eq!(host.sim.stats().commands, sent as u64);
        }

        #[test]
        fn random_bytes_never_panic(
            chunks in proptest::collection::vec(
                (proptest::collection::vec(any::<u8>(), 0..40), 0u64..5_000),
                1..30,
            ),
        ) {
            let mut sim = QsbSim::new(QsbSimConfig::default());
            let mut now = Duration::ZERO;
            let mut out = [0u8; 64];
            for (bytes, gap) in &chunks {
                sim.receive(now, bytes);
                now += Duration::from_micros(*gap);
                while sim.transmit(now, &mut out) > 0 {}
                let _ = sim.next_event(now);
            }
        }
    }
}

mod on_a_sim_link {
    use super::*;
    use motion_link::Link;
    use motion_link::sim::SimLink;

    fn read_all(link: &mut SimLink, now: Duration, into: &mut Vec<u8>) {
        let mut buf = [0u8; 128];
        while let Ok(n) = link.read(now, &mut buf) {
            if n == 0 {
                break;
            }
            into.extend_from_slice(&buf[..n]);
        }
    }

    #[test]
    fn r14_round_trip_takes_its_wire_time_and_a_baud_change_garbles_the_old_rate() {
        // docs/ARCHITECTURE.md: `R0E\r\n` 5 bytes + ~14 bytes answer ≈ 0.8 ms at 230400 baud.
        let sim = QsbSim::new(QsbSimConfig::default());
        let mut link = SimLink::stream("qsb", 230_400, Box::new(sim));
        let byte = Duration::from_nanos(10_000_000_000 / 230_400);
        link.write(Duration::ZERO, b"R14\r\n").unwrap();
        // The line ends at its CR (the 4th byte); the LF is an empty line.
        let done = byte * 4 + 100 * US + byte * 17;
        let mut got = Vec::new();
        read_all(&mut link, done - US, &mut got);
        assert!(got.len() < 17, "{got:?}");
        read_all(&mut link, done + US, &mut got);
        assert_eq!(got, b"r 14 00001113 !\r\n");

        // W1640A: answered at 230400, then the board listens at 115200.
        let t = Duration::from_millis(10);
        link.write(t, b"W1640A\r\n").unwrap();
        got.clear();
        read_all(&mut link, t + 5 * MS, &mut got);
        assert_eq!(got, b"w 16 0000040A !\r\n");
        let t = t + 10 * MS;
        link.write(t, b"R14\r\n").unwrap();
        got.clear();
        read_all(&mut link, t + 10 * MS, &mut got);
        assert!(
            !got.windows(4).any(|w| w == b"r 14"),
            "a 230400 baud host cannot talk to a 115200 baud board: {got:?}"
        );
    }
}

#[test]
fn s_and_d_encoders_follow_the_configured_motion() {
    let motion = EncoderMotion {
        velocity: 50.0,
        amplitude: 100.0,
        frequency_hz: 2.0,
    };
    let mut host = Host::new(QsbSimConfig {
        variant: Variant::D,
        motion,
        cycles_per_rev: 1_000_000, // no index in the way
        ..QsbSimConfig::default()
    });
    host.ask("W0303");
    let cleared = host.now;
    host.ask("W092");
    let zero = motion.position(cleared.as_secs_f64());
    for _ in 0..20 {
        host.run_for(Duration::from_millis(37));
        let t = host.now;
        let expected = ((motion.position(t.as_secs_f64()) - zero) * 4.0).round() as i32;
        let got = host.value("R0E") as i32;
        assert!((got - expected).abs() <= 1, "{got} vs {expected}");
        assert!(
            (host.sim.encoder_position() - motion.position(host.now.as_secs_f64())).abs() < 1e-9
        );
    }
}

#[test]
fn on_change_streams_report_only_changes() {
    // DIG I/O: "In stream mode, a new I/O state is output only if the I/O bit state has
    // changed." CAPTURE: "a new value is output when the register value changes."
    let mut host = Host::still(Variant::M);
    host.ask("W0C1");
    host.ask("W02010"); // interrupt on bit 0, low-to-high
    let since = host.log.len();
    host.ask("S01");
    host.ask("S05");
    host.run_for(50 * MS);
    assert_eq!(host.streamed(0x01, since).len(), 1, "acknowledgement only");
    assert_eq!(host.streamed(0x05, since).len(), 1);
    let now = host.now;
    host.sim.set_digital_inputs(now, 0b1110);
    host.run_for(10 * MS);
    host.sim.nudge_encoder(host.now, 3.0);
    let now = host.now;
    host.sim.set_digital_inputs(now, 0b1111); // rising edge on bit 0: capture
    host.run_for(10 * MS);
    let dio: Vec<u32> = host
        .streamed(0x01, since)
        .iter()
        .map(|(_, r)| r.data)
        .collect();
    assert_eq!(dio, vec![0xF, 0xE, 0xF]);
    let capture: Vec<u32> = host
        .streamed(0x05, since)
        .iter()
        .map(|(_, r)| r.data)
        .collect();
    assert_eq!(capture, vec![0, 12]); // 3 cycles at x4 (factory modulo 500)
}

#[test]
fn every_trigger_source_pulses_bit0_and_latches_str() {
    // MDR1: "B4 Trigger/Capture on Index … B5 Trigger on Match … B6 Trigger on Underflow
    // … B7 Trigger on Overflow"; DIG I/O CONFIG B12 "a trigger event (see register MDR1)
    // causes an output signal on digital I/O bit 0 for a duration specified by the
    // INTERVAL RATE register."
    let mut host = Host::still(Variant::D);
    host.ask("W0303"); // free-running x4, index disabled
    host.ask("W021100"); // B12, bit 0 an output
    host.ask("W0C0A"); // 10 ticks: 19.5 ms
    host.ask("W040"); // no trigger yet
    let now = host.now;
    host.sim.nudge_encoder(now, 600.0); // past the index at 500 cycles
    assert_eq!(host.sim.trigger_pulses(), 0, "MDR1 without triggers");
    host.ask("W093");
    // Index: B4 (also captures the count at the index).
    host.ask("W0410");
    let now = host.now;
    host.sim.nudge_encoder(now, 500.0); // the index at 1000 cycles
    assert_eq!(host.sim.trigger_pulses(), 1);
    assert_eq!(host.sim.digital_pins() & 1, 0, "pulse on bit 0");
    assert_eq!(host.value("R05"), 4000, "captured at the index");
    assert_eq!(host.value("R06") & 0x10, 0x10, "STR IDX latched");
    host.run_for(TICK * 10);
    assert_eq!(host.sim.digital_pins() & 1, 1, "back at rest");
    // Underflow: B6, the free-running counter passing below zero.
    host.ask("W093");
    host.ask("W040");
    host.ask("W092"); // CNTR 0
    host.ask("W0440");
    let now = host.now;
    host.sim.nudge_encoder(now, -0.5);
    assert_eq!(host.sim.trigger_pulses(), 2);
    assert_eq!(host.value("R06") & 0x40, 0x40, "STR BW latched");
    host.run_for(TICK * 10);
    // Overflow: B7, passing above 0xFFFFFFFF.
    host.ask("W093");
    host.ask("W0480");
    let now = host.now;
    host.sim.nudge_encoder(now, 0.5);
    assert_eq!(host.sim.trigger_pulses(), 3);
    assert_eq!(host.value("R06") & 0x80, 0x80, "STR CY latched");
}

#[test]
fn an_event_during_a_pulse_lengthens_it_and_the_line_rests_where_it_was() {
    // "The output pulse polarity depends on the initial output state of digital I/O bit
    // 0": written low, the pulse drives it high.
    let mut host = Host::still(Variant::M);
    host.ask("W0303");
    host.ask("W021100");
    host.ask("W01E"); // bit 0 low at rest
    host.ask("W0C0A");
    host.ask("W0864"); // DTR 100
    host.ask("W0420"); // trigger on match
    assert_eq!(host.sim.digital_pins() & 1, 0);
    let now = host.now;
    host.sim.nudge_encoder(now, 30.0); // 0 → 120: through 100
    assert_eq!(host.sim.digital_pins() & 1, 1, "an active-high pulse");
    host.run_for(TICK * 5);
    let now = host.now;
    host.sim.nudge_encoder(now, -10.0); // 120 → 80: through 100 again
    assert_eq!(host.sim.trigger_pulses(), 2);
    assert!(host.sim.trigger_pulse_active());
    host.run_for(TICK * 10 - 10 * US);
    assert_eq!(
        host.sim.digital_pins() & 1,
        1,
        "lengthened by the second event"
    );
    host.run_for(20 * US);
    assert_eq!(host.sim.digital_pins() & 1, 0, "at rest again, low");
}

#[test]
fn a_capture_of_the_same_count_sends_no_line() {
    // CAPTURE: "In streaming mode, a new value is output when the register value
    // changes": two edges at the same count are one line.
    let mut host = Host::still(Variant::M);
    host.ask("W0C1");
    host.ask("W02010"); // interrupt on bit 0, low-to-high
    let since = host.log.len();
    host.ask("S05");
    host.sim.nudge_encoder(host.now, 5.0);
    for levels in [0b1110, 0b1111, 0b1110, 0b1111] {
        let now = host.now;
        host.sim.set_digital_inputs(now, levels);
        host.run_for(10 * MS);
    }
    assert_eq!(host.sim.captures(), 2);
    let capture: Vec<u32> = host
        .streamed(0x05, since)
        .iter()
        .map(|(_, r)| r.data)
        .collect();
    assert_eq!(capture, vec![0, 20], "the stream's start, then one capture");
}
