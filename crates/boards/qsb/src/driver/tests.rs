//! Unit tests of the QSB driver against byte vectors of the `qsb` protocol crate: golden
//! command lines from the command list, answers encoded by the codec.

use core::time::Duration;

use ::qsb::{CommandLine, CommandType, Eor, ProductType, Response, ResponseType, TICK};

use super::config::DRIVER_EOR;
use super::{QsbDriver, QsbDriverConfig};
use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind, Priority};

/// A driver on a bench: the test plays the board.
pub(super) struct Bench {
    pub(super) driver: QsbDriver,
    pub(super) now: Duration,
    /// Board time stamp, 1/512 s ticks.
    pub(super) ts: u32,
    /// Whether the board answers with the driver's EOR (else the factory format).
    pub(super) configured: bool,
    pub(super) counter: i32,
    /// VERSION data the board answers.
    pub(super) version: u32,
    /// What reads and streams of other registers answer (register, data); 0 otherwise.
    pub(super) values: Vec<(u8, u32)>,
}

impl Bench {
    pub(super) fn new(variant: ProductType) -> Self {
        Self::with_config(QsbDriverConfig {
            variant,
            ..QsbDriverConfig::default()
        })
    }

    pub(super) fn with_config(config: QsbDriverConfig) -> Self {
        let variant = config.variant;
        Self {
            driver: QsbDriver::new(config),
            now: Duration::ZERO,
            ts: 1000,
            configured: false,
            counter: 0,
            version: match variant {
                ProductType::D => 0x0000_1013,
                ProductType::M => 0x0000_1113,
                ProductType::S => 0x0000_1213,
            },
            values: Vec::new(),
        }
    }

    pub(super) fn advance(&mut self, by: Duration) {
        self.now += by;
        self.ts += (by.as_nanos() / TICK.as_nanos()) as u32;
        self.driver.handle_timeout(self.now);
    }

    /// What the driver sends now, if anything.
    pub(super) fn sent(&mut self) -> Option<Vec<u8>> {
        self.driver.handle_timeout(self.now);
        let mut buf = [0u8; 256];
        let transmit = self.driver.poll_transmit(self.now, &mut buf)?;
        assert!(transmit.expects_reply);
        Some(buf[..transmit.len].to_vec())
    }

    pub(super) fn expect(&mut self, line: &[u8]) {
        let sent = self.sent();
        assert_eq!(
            sent.as_deref().map(String::from_utf8_lossy),
            Some(String::from_utf8_lossy(line)),
        );
    }

    pub(super) fn line(&self, ty: ResponseType, register: u8, data: u32) -> Vec<u8> {
        let mut response = Response::new(ty, register, data);
        let eor = if self.configured {
            response.time_stamp = Some(self.ts);
            DRIVER_EOR
        } else {
            Eor::FACTORY
        };
        let mut buf = [0u8; ::qsb::MAX_RESPONSE_LEN];
        let len = response.encode(eor, &mut buf).expect("fits");
        buf[..len].to_vec()
    }

    pub(super) fn rx(&mut self, bytes: &[u8]) {
        self.driver.handle_rx(self.now, bytes);
    }

    /// Answers `sent` as a board would: writes echo, reads and streams return `value`.
    pub(super) fn answer(&mut self, sent: &[u8], value: u32) {
        let line = CommandLine::decode(sent.strip_suffix(b"\r\n").expect("EOC")).expect("line");
        let (ty, data) = match line.ty {
            CommandType::Write => (ResponseType::Write, line.data.expect("data")),
            CommandType::Read => (ResponseType::Read, value),
            CommandType::Stream => (ResponseType::Stream, value),
        };
        if line.register == 0x15 {
            self.configured = data & 4 != 0;
        }
        let bytes = self.line(ty, line.register, data);
        self.rx(&bytes);
    }

    /// Sends and answers everything the driver wants until it is quiet; returns the lines.
    pub(super) fn run(&mut self) -> Vec<String> {
        let mut lines = Vec::new();
        for _ in 0..64 {
            let Some(sent) = self.sent() else { break };
            let register = CommandLine::decode(sent.strip_suffix(b"\r\n").expect("EOC"))
                .expect("line")
                .register;
            let extra = self
                .values
                .iter()
                .find(|(r, _)| *r == register)
                .map(|(_, v)| *v);
            let value = match &sent[..3] {
                b"R14" => self.version,
                b"S13" => 0x11,
                b"S0E" => self.counter as u32,
                _ => extra.unwrap_or(0),
            };
            self.advance(Duration::from_micros(500));
            self.answer(&sent, value);
            lines.push(String::from_utf8_lossy(&sent).trim_end().to_owned());
        }
        lines
    }

    /// One stream tick: the encoder line, then MD STATUS (-M order of the board).
    pub(super) fn tick(&mut self, md: Option<u32>) {
        self.advance(TICK);
        let mut bytes = self.line(ResponseType::Stream, 0x0E, self.counter as u32);
        if let Some(md) = md {
            bytes.extend(self.line(ResponseType::Stream, 0x13, md));
        }
        self.rx(&bytes);
    }

    pub(super) fn started(variant: ProductType) -> Self {
        Self::started_with(QsbDriverConfig {
            variant,
            ..QsbDriverConfig::default()
        })
    }

    pub(super) fn started_with(config: QsbDriverConfig) -> Self {
        let mut bench = Self::with_config(config);
        bench.run();
        assert!(bench.driver.status().online, "start-up completes");
        bench
    }
}

pub(super) const MD_DONE: u32 = 0x11; // done, drive enabled
pub(super) const MD_MOVING: u32 = 0x12; // moving, drive enabled
pub(super) const MD_JOGGING: u32 = 0x1A; // moving, jogging, drive enabled

#[test]
fn start_up_of_a_qsb_m_golden_lines() {
    let mut bench = Bench::new(ProductType::M);
    assert_eq!(
        bench.driver.wants_transmit(bench.now),
        Some(Priority::Setup)
    );
    let lines = bench.run();
    // COMMAND 1 "Deactivate … streaming", VERSION, MD ACCEL 10000 then COMMAND 4 (a
    // motor left running stops at the axis's acceleration), EOR 5 (LF + time stamp),
    // MODE quadrature, MDR0 "Sync Index, … Free Running, X4" without the index reset,
    // MDR1 "Count Up No Triggers", THRESHOLD 0, INTERVAL RATE 1 tick, MD STEP RATE 992
    // (1000 rounded down to 16), COMMAND 2, stream MD STATUS, stream READ ENCODER
    // ("Stream Encoder Value, S0E").
    assert_eq!(
        lines,
        [
            "W161", "R14", "W102710", "W164", "W155", "W000", "W0343", "W040", "W0B0", "W0C1",
            "W0F3E0", "W162", "S13", "S0E"
        ]
    );
    let status = bench.driver.status();
    assert!(status.online);
    assert_eq!(status.firmware(), "QSB-M SN 00001 fw 13");
    assert_eq!(status.fault, None);
    assert_eq!(bench.driver.product(), Some(ProductType::M));
    for kind in GoalKind::ALL {
        // Off needs the drive's enable line (`enable_output`).
        assert_eq!(
            bench.driver.capabilities(0).contains(kind),
            !matches!(kind, GoalKind::Power | GoalKind::Off)
        );
    }
    assert!(!bench.driver.capabilities(1).contains(GoalKind::Stop));
}

#[test]
fn start_up_of_a_qsb_s_has_no_drive_stop_is_a_no_op_and_off_unsupported() {
    let mut bench = Bench::new(ProductType::M); // configured -M, the board says -S
    bench.version = 0x0004_2213;
    let lines = bench.run();
    assert_eq!(
        lines,
        [
            "W161", "R14", "W155", "W000", "W0343", "W040", "W0B0", "W0C1", "S0E"
        ]
    );
    assert_eq!(bench.driver.status().firmware(), "QSB-S SN 00042 fw 13");
    let now = bench.now;
    assert_eq!(
        bench
            .driver
            .set_goal(now, 0, Goal::Position { counts: 5.0 }),
        Err(GoalError::Unsupported(GoalKind::Position))
    );
    assert_eq!(
        bench.driver.set_goal(now, 0, Goal::Home { velocity: 5.0 }),
        Err(GoalError::Unsupported(GoalKind::Home))
    );
    assert_eq!(
        bench.driver.set_goal(now, 0, Goal::Stop { decel: 1.0 }),
        Ok(())
    );
    // Nothing to de-energise: boards that cannot, refuse.
    assert_eq!(
        bench.driver.set_goal(now, 0, Goal::Off),
        Err(GoalError::Unsupported(GoalKind::Off))
    );
    assert!(!bench.driver.goals_pending());
    assert_eq!(bench.sent(), None, "nothing is driven, nothing to send");
    assert!(!bench.driver.capabilities(0).contains(GoalKind::Velocity));
}

#[test]
fn position_and_velocity_come_from_time_stamped_samples() {
    let mut bench = Bench::started(ProductType::S);
    for _ in 0..12 {
        bench.counter += 20; // 20 counts per 1/512 s tick
        bench.tick(None);
    }
    let state = bench.driver.channel(0);
    assert_eq!(state.position, f64::from(bench.counter));
    assert_eq!(state.raw_counts, i64::from(bench.counter));
    assert_eq!(state.velocity, 20.0 * 512.0);
    assert!(state.moving);
    assert_eq!(state.refreshed_at, Some(bench.now));
    for _ in 0..10 {
        bench.tick(None);
    }
    let state = bench.driver.channel(0);
    assert_eq!(state.velocity, 0.0);
    assert!(!state.moving);
    assert_eq!(
        bench.driver.channel(1),
        motion_drivers::ChannelState::UNKNOWN
    );
}

#[test]
fn negative_counts_are_twos_complement() {
    let mut bench = Bench::started(ProductType::D);
    // "Negative values must be entered as four hex bytes in two's-complement format."
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0xFFFF_FF9C);
    bench.advance(TICK);
    bench.rx(&bytes);
    // (A jump: taken when the next sample agrees.)
    bench.counter = -100;
    bench.tick(None);
    assert_eq!(bench.driver.channel(0).position, -100.0);
    // Set-position: DTR then LOAD REG 0 ("Transfer DTR to CNTR").
    let now = bench.now;
    bench
        .driver
        .set_goal(now, 0, Goal::SetPosition { counts: -100.0 })
        .expect("set-position");
    assert_eq!(bench.driver.wants_transmit(now), Some(Priority::Command));
    assert_eq!(bench.run(), ["W08FFFFFF9C", "W0A0"]);
    assert!(bench.driver.channel(0).homed);
    assert!(!bench.driver.goals_pending());
    assert_eq!(
        bench
            .driver
            .set_goal(now, 0, Goal::SetPosition { counts: 1e12 }),
        Err(GoalError::OutOfBoardRange(GoalKind::SetPosition))
    );
}

#[test]
fn a_move_is_relative_steps_then_corrected_from_the_encoder() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    bench.tick(None);
    let now = bench.now;
    bench
        .driver
        .set_goal(now, 0, Goal::Position { counts: 1000.0 })
        .expect("position");
    assert!(bench.driver.channel(0).moving, "a move is under way");
    // 1000 counts at 10 counts per step: "MD MOVE STEPS" 100, then COMMAND 8.
    assert_eq!(bench.run(), ["W1164", "W168"]);
    bench.tick(Some(MD_MOVING));
    for _ in 0..10 {
        bench.counter += 97;
        bench.tick(None);
    }
    // The motor lost three steps: 970 instead of 1000.
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    assert_eq!(bench.run(), ["W113", "W168"], "the correction");
    assert!(bench.driver.goals_pending());
    bench.counter += 30;
    bench.tick(Some(MD_MOVING));
    // The encoder line of a tick goes before its MD STATUS line: read at the same
    // instant, it is the final position.
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.run(), Vec::<String>::new());
    let state = bench.driver.channel(0);
    assert!(state.arrived);
    assert_eq!(state.position, 1000.0);
    assert!(!bench.driver.goals_pending());
}

#[test]
fn ramp_position_velocity_and_stop_write_the_rates_in_steps() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    let now = bench.now;
    let goal = Goal::RampPosition {
        counts: -20.0,
        velocity: 5_000.0,
        accel: 20_000.0,
    };
    bench.driver.set_goal(now, 0, goal).expect("ramp");
    // MD ACCEL 2000 = 0x7D0, MD STEP RATE 500 → 496 = 0x1F0, MD MOVE STEPS -2.
    assert_eq!(bench.run(), ["W107D0", "W0F1F0", "W11FFFFFFFE", "W168"]);
    let goal = Goal::Velocity {
        velocity: -10_000.0,
        accel: 100_000.0,
    };
    bench.driver.set_goal(bench.now, 0, goal).expect("jog");
    // -1000 steps/s rounds to -992 = FFFFFC20; COMMAND 9 "Motor Jog".
    assert_eq!(bench.run(), ["W102710", "W12FFFFFC20", "W169"]);
    bench.tick(Some(MD_JOGGING));
    assert!(bench.driver.channel(0).moving);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 50_000.0 })
        .expect("stop");
    // COMMAND 4 "Motor Stop - Stop the motor using the MD ACCEL rate": 5000 steps/s²
    // rounded up to 5008 = 0x1390 (a stop is never gentler than asked).
    assert_eq!(bench.run(), ["W101390", "W164"]);
    bench.tick(Some(MD_DONE));
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, Goal::Off),
        Err(GoalError::Unsupported(GoalKind::Off)),
        "no enable line configured"
    );
    assert_eq!(
        bench.driver.set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 200_000.0,
                accel: 1000.0
            }
        ),
        Err(GoalError::OutOfBoardRange(GoalKind::Velocity))
    );
    assert_eq!(
        bench.driver.set_goal(
            bench.now,
            0,
            Goal::RampPosition {
                counts: 1.0,
                velocity: 1000.0,
                accel: 100.0
            }
        ),
        Err(GoalError::OutOfBoardRange(GoalKind::RampPosition))
    );
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Power { fraction: 0.5 }),
        Err(GoalError::Unsupported(GoalKind::Power))
    );
    assert_eq!(
        bench.driver.set_goal(bench.now, 3, Goal::Off),
        Err(GoalError::NoSuchChannel(3))
    );
}

#[test]
fn home_resets_the_counter_at_the_index() {
    let mut bench = Bench::started(ProductType::M);
    bench.counter = 777;
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 2_000.0 })
        .expect("home");
    assert!(!bench.driver.channel(0).homed);
    // Jog -200 → -192 steps/s; MDR0 0x63 "Reset on Index"; clear STR; stream STR; jog.
    assert_eq!(bench.run(), ["W12FFFFFF40", "W0363", "W093", "S06", "W169"]);
    bench.counter -= 30;
    bench.tick(Some(MD_JOGGING));
    // The index: STR with IDX (B4) and count enable (B3), then the reset counter.
    bench.counter = 0;
    bench.advance(TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x06, 0x18);
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, 0));
    bench.rx(&bytes);
    assert!(bench.driver.channel(0).homed);
    assert_eq!(
        bench.driver.channel(0).velocity,
        0.0,
        "a reset is not a motion"
    );
    assert_eq!(bench.run(), ["W0343", "W164", "R06"]);
    assert!(!bench.driver.goals_pending());
}

#[test]
fn a_home_search_without_index_gives_up_after_its_travel() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 2_000.0 })
        .expect("home");
    bench.run();
    bench.tick(Some(MD_JOGGING));
    for _ in 0..60 {
        bench.counter -= 100;
        bench.tick(None);
    }
    assert_eq!(bench.run(), ["W164", "W0343", "R06"]);
    assert!(!bench.driver.channel(0).homed);
}

#[test]
fn an_e_answer_is_a_board_error_until_the_next_goal() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    let goal = Goal::Velocity {
        velocity: 5_000.0,
        accel: 100_000.0,
    };
    bench.driver.set_goal(bench.now, 0, goal).expect("jog");
    let sent = bench.sent().expect("jog rate");
    assert_eq!(sent, b"W121F0\r\n");
    let bytes = bench.line(ResponseType::Error, 0x12, 0x1F0);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::BoardError));
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::BoardError));
    assert_eq!(bench.sent(), None, "the rest of the plan is void");
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 100_000.0 })
        .expect("stop");
    assert_eq!(bench.driver.status().fault, None);
    assert_eq!(bench.run(), ["W164"]);
}

#[test]
fn an_e_line_right_after_garbage_is_still_surfaced_and_a_lost_answer_asked_again() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    let goal = Goal::Velocity {
        velocity: 5_000.0,
        accel: 100_000.0,
    };
    bench.driver.set_goal(bench.now, 0, goal).expect("jog");
    bench.expect(b"W121F0\r\n");
    // The answer is garbled on the wire (a byte lost): it is not coming, and once due the
    // request is asked again.
    bench.advance(Duration::from_micros(500));
    bench.rx(b"w1200001F");
    bench.rx(b"!\n");
    assert_eq!(bench.sent(), None, "not before its deadline");
    let deadline = bench.driver.poll_timeout().expect("deadline");
    bench.advance(deadline - bench.now);
    assert_eq!(bench.driver.status().timeouts, 1);
    bench.expect(b"W121F0\r\n");
    // "s0" + "e12000001F0<time stamp>!": the `e` first reads as a register digit of
    // the garbage line; in the driver's EOR (time stamp, no spaces) that line cannot
    // complete, and the decoder finds the `e` line in what it had buffered.
    let mut bytes = b"s0".to_vec();
    bytes.extend(bench.line(ResponseType::Error, 0x12, 0x1F0));
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::BoardError));
    assert!(!bench.driver.awaiting_reply());
}

#[test]
fn garbage_between_lines_is_skipped_and_counted() {
    let mut bench = Bench::started(ProductType::S);
    let before = bench.driver.status().bad_replies;
    bench.counter = 42;
    bench.advance(TICK);
    let mut bytes = b"\x00\xFFzq!!\r\n#".to_vec();
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, 42));
    for chunk in bytes.chunks(3) {
        bench.rx(chunk);
    }
    // A jump from 0 to 42 counts is held until the next sample confirms it (module
    // `guard`): the line after the garbage was decoded, and the next one agrees.
    assert_eq!(bench.driver.channel(0).position, 0.0);
    bench.tick(None);
    assert_eq!(bench.driver.channel(0).position, 42.0);
    assert!(bench.driver.status().bad_replies > before);
    assert_eq!(bench.driver.status().fault, None);
}

#[test]
fn a_line_in_the_factory_format_or_an_older_time_stamp_means_a_reset() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 0.0 })
        .expect("set-position");
    bench.run();
    assert!(bench.driver.channel(0).homed);
    // The board rebooted: its lines are back to the saved EOR (factory 0x0B).
    // One such line could be a corrupted one (module `guard`): held, no reset yet.
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().resets, 0);
    bench.rx(&bytes);
    let status = bench.driver.status();
    assert_eq!(status.fault, Some(DeviceFault::Reset));
    assert_eq!(status.resets, 1);
    let evidence = |bench: &Bench| bench.driver.status().verdict.expect("verdict").evidence;
    assert!(
        evidence(&bench).as_str().starts_with(
            "two lines in a row without the time stamp EOR 5 asks for, the last `s0E` at "
        ),
        "{}",
        evidence(&bench).as_str()
    );
    assert!(!bench.driver.channel(0).homed);
    assert_eq!(bench.run()[..4], ["W161", "R14", "W102710", "W164"]);
    // A time stamp that goes backwards: the counter restarted at power-up.
    bench.tick(Some(MD_DONE));
    bench.ts -= 100;
    bench.tick(None);
    assert_eq!(bench.driver.status().resets, 1, "one line is held");
    bench.tick(None);
    assert_eq!(bench.driver.status().resets, 2);
    assert!(
        evidence(&bench)
            .as_str()
            .starts_with("time stamp back from ")
            && evidence(&bench).as_str().contains("then `s0E` at "),
        "{}",
        evidence(&bench).as_str()
    );
    // And a -M whose drive shows disabled lost its COMMAND 2 (two MD STATUS lines).
    bench.run();
    bench.tick(Some(0x01));
    assert_eq!(bench.driver.status().resets, 2, "one line is held");
    bench.tick(Some(0x01));
    assert_eq!(bench.driver.status().resets, 3);
    assert!(
        evidence(&bench)
            .as_str()
            .starts_with("MD STATUS 01 on two lines in a row, the last at "),
        "{}",
        evidence(&bench).as_str()
    );
    assert_eq!(bench.driver.status().verdicts, 3);
}

#[test]
fn a_move_whose_answer_is_lost_is_never_sent_twice() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    bench.tick(None);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 100.0 })
        .expect("position");
    let sent = bench.sent().expect("steps");
    bench.answer(&sent, 0);
    bench.expect(b"W168\r\n");
    // The board moves but its answer is lost: the stream goes on past its deadline for a
    // whole reply window, so it is not coming.
    bench.counter = 100;
    let window = bench.driver.config().reply_timeout();
    let deadline = bench.driver.poll_timeout().expect("deadline");
    while bench.now < deadline + window + TICK {
        bench.tick(Some(MD_MOVING));
        assert_eq!(bench.sent(), None, "no second COMMAND 8");
    }
    assert_eq!(bench.driver.status().timeouts, 1);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    bench.tick(None);
    assert_eq!(bench.sent(), None);
    assert!(bench.driver.channel(0).arrived);
    // Its late answer, should it come after all, is recognised and changes nothing.
    let late = bench.driver.late_answers_seen();
    let bytes = bench.line(ResponseType::Write, 0x16, 8);
    bench.rx(&bytes);
    assert_eq!(bench.driver.late_answers_seen(), late + 1);
    assert_eq!(bench.sent(), None);
}

#[test]
fn link_down_faults_and_link_up_starts_again() {
    let mut bench = Bench::started(ProductType::S);
    bench.counter = 12;
    bench.tick(None);
    bench.tick(None);
    bench.driver.link_down(bench.now);
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::LinkDown));
    assert_eq!(
        bench.driver.channel(0).position,
        12.0,
        "last known state kept"
    );
    assert_eq!(bench.sent(), None);
    assert_eq!(bench.driver.poll_timeout(), None);
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Stop { decel: 1.0 }),
        Err(GoalError::Offline)
    );
    bench.driver.link_up(bench.now);
    bench.expect(b"W161\r\n");
}

mod random {
    use super::*;
    use ::qsb::Request;
    use proptest::prelude::*;

    #[derive(Debug, Clone)]
    enum Op {
        Noise(Vec<u8>),
        Line(u8, u8, u32, Option<u32>),
        Advance(u32),
        AnswerLast(u32),
        SetGoal(u8, f64, f64),
        Link(bool),
        Output(u16, bool),
    }

    fn op() -> impl Strategy<Value = Op> {
        prop_oneof![
            proptest::collection::vec(any::<u8>(), 1..40).prop_map(Op::Noise),
            (
                0u8..5,
                0u8..0x18,
                any::<u32>(),
                proptest::option::of(any::<u32>())
            )
                .prop_map(|(t, r, d, ts)| Op::Line(t, r, d, ts)),
            (0u32..30_000).prop_map(Op::Advance),
            any::<u32>().prop_map(Op::AnswerLast),
            (0u8..9, any::<f64>(), -1e6f64..1e6).prop_map(|(k, a, b)| Op::SetGoal(k, a, b)),
            any::<bool>().prop_map(Op::Link),
            (0u16..8, any::<bool>()).prop_map(|(pin, high)| Op::Output(pin, high)),
        ]
    }

    fn goal(kind: u8, a: f64, b: f64) -> Goal {
        match kind {
            0 => Goal::Off,
            1 => Goal::Stop { decel: b.abs() },
            2 => Goal::Power { fraction: a },
            3 => Goal::Position { counts: a },
            4 => Goal::Velocity {
                velocity: b,
                accel: a.abs(),
            },
            5 => Goal::RampPosition {
                counts: b,
                velocity: a.abs(),
                accel: b.abs(),
            },
            6 => Goal::Home { velocity: b.abs() },
            _ => Goal::SetPosition { counts: b },
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]

        /// Whatever the board sends, whatever the goals and the time: no panic, every
        /// message is a command line of the codec, at most one request in flight, and the
        /// channel state stays finite.
        #[test]
        fn any_traffic_goals_and_times_keep_the_driver_sane(
            started in any::<bool>(),
            machine in any::<bool>(),
            ops in proptest::collection::vec(op(), 0..120),
        ) {
            // Plain, or with an enable line, digital signals and the capture input.
            let config = if machine {
                QsbDriverConfig {
                    counts_per_step: -4.0,
                    home_position: 77,
                    enable: Some(super::super::EnableOutput { bit: 3, active_high: false }),
                    io: super::super::QsbIo {
                        digital_in: 1,
                        capture: Some(super::super::CaptureInput { bit: 0, falling: true }),
                        ..super::super::QsbIo::default()
                    },
                    ..QsbDriverConfig::default()
                }
            } else {
                QsbDriverConfig::default()
            };
            let mut bench = if started {
                Bench::started_with(config)
            } else {
                Bench::with_config(config)
            };
            let mut last: Option<Vec<u8>> = None;
            for op in ops {
                match op {
                    Op::Noise(bytes) => bench.rx(&bytes),
                    Op::Line(ty, register, data, ts) => {
                        let ty = [
                            ResponseType::Read,
                            ResponseType::Write,
                            ResponseType::Stream,
                            ResponseType::Error,
                            ResponseType::Unsupported,
                        ][usize::from(ty)];
                        let mut response = Response::new(ty, register, data);
                        response.time_stamp = ts;
                        let mut buf = [0u8; ::qsb::MAX_RESPONSE_LEN];
                        let len = response.encode(DRIVER_EOR, &mut buf).expect("fits");
                        bench.rx(&buf[..len]);
                    }
                    Op::Advance(micros) => bench.advance(Duration::from_micros(u64::from(micros))),
                    Op::AnswerLast(value) => {
                        if let Some(sent) = last.take() {
                            bench.answer(&sent, value);
                        }
                    }
                    Op::SetGoal(kind, a, b) => {
                        let online = bench.driver.status().online;
                        let result = bench.driver.set_goal(bench.now, 0, goal(kind, a, b));
                        if !online {
                            prop_assert!(result.is_err());
                        }
                    }
                    Op::Output(pin, high) => {
                        let pin = motion_drivers::Pin(pin);
                        let result = bench.driver.set_output(bench.now, pin, high);
                        if !bench.driver.status().online {
                            prop_assert!(result.is_err());
                        }
                        let _ = bench.driver.read_pin(pin);
                    }
                    Op::Link(up) => {
                        if up {
                            bench.driver.link_up(bench.now);
                        } else {
                            bench.driver.link_down(bench.now);
                        }
                    }
                }
                if let Some(sent) = bench.sent() {
                    let line = sent.strip_suffix(b"\r\n").expect("EOC");
                    prop_assert!(Request::decode(line).is_ok(), "{:?}", sent);
                    prop_assert!(bench.driver.awaiting_reply());
                    prop_assert_eq!(bench.sent(), None, "one request in flight");
                    last = Some(sent);
                }
                let state = bench.driver.channel(0);
                prop_assert!(state.position.is_finite() && state.velocity.is_finite());
            }
        }
    }
}
