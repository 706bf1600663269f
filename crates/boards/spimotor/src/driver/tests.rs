//! Unit tests of the SPI_motor driver against byte vectors of the `spimotor` crate.
//!
//! A scripted board answers reads with `Reply::encode_miso` (the protocol crate's own
//! MISO encoding) and takes writes at face value; it does not step. Golden transactions
//! quote the datasheet's "examples" section.

use core::time::Duration;

use spimotor::{
    Address, Coils, Identification, Motor, ReadPort, Reply, Request, SerialNumber, StepDelay,
    Transaction, Write,
};

use super::*;
use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind};

const MS: Duration = Duration::from_millis(1);

/// A board that answers by port and takes writes at once (no stepping).
#[derive(Debug, Clone)]
pub(super) struct Board {
    present: bool,
    pub(super) position: i32,
    pub(super) target: i32,
    pub(super) delay: u8,
    intensity: u8,
    spins: Vec<Write>,
    /// Port 0x42 counts from the old target instead of the current position.
    relative_to_target: bool,
}

impl Board {
    fn new() -> Self {
        Self {
            present: true,
            position: 0,
            target: 0,
            delay: 200,
            intensity: 0x20,
            spins: Vec::new(),
            relative_to_target: false,
        }
    }

    pub(super) fn transfer(&mut self, mosi: &[u8]) -> Vec<u8> {
        let mut miso = vec![0xFF; mosi.len()];
        if !self.present {
            return miso;
        }
        match Transaction::decode(mosi).expect("the driver sends valid transactions") {
            Transaction {
                request: Request::Read(read),
                ..
            } => {
                let reply = match read.port {
                    ReadPort::Identification => Reply::Identification(Identification::default()),
                    ReadPort::Serial => Reply::Serial(SerialNumber(0x1234)),
                    ReadPort::CurrentPosition => Reply::CurrentPosition(self.position),
                    ReadPort::TargetPosition => Reply::TargetPosition(self.target),
                    ReadPort::StepDelay => Reply::StepDelay(StepDelay::from_tenths_ms(self.delay)),
                };
                reply.encode_miso(&mut miso);
            }
            Transaction {
                request: Request::Write(write),
                ..
            } => match write {
                Write::CurrentPosition(p) => self.position = p,
                Write::TargetPosition(p) => self.target = p,
                Write::RelativePosition(p) if self.relative_to_target => {
                    self.target = self.target.wrapping_add(p);
                }
                Write::RelativePosition(p) => self.target = self.position.wrapping_add(p),
                Write::StepDelay(d) => self.delay = d.tenths_ms(),
                Write::StepperIntensity(i) => self.intensity = i,
                other => self.spins.push(other),
            },
        }
        miso
    }
}

/// The driver, a board, a clock and everything sent.
pub(super) struct Bench {
    pub(super) driver: SpimotorDriver,
    pub(super) board: Board,
    pub(super) now: Duration,
    sent: Vec<Vec<u8>>,
}

impl Bench {
    fn new(config: SpimotorDriverConfig) -> Self {
        Self {
            driver: SpimotorDriver::new(config),
            board: Board::new(),
            now: Duration::ZERO,
            sent: Vec::new(),
        }
    }

    /// One engine-like step: timeouts, then everything the driver sends; MISO comes back
    /// at the start of the next step. Returns this step's transactions.
    fn step(&mut self) -> Vec<Vec<u8>> {
        self.driver.handle_timeout(self.now);
        let mut out = Vec::new();
        let mut miso = Vec::new();
        let mut buf = [0u8; 256];
        while self.driver.wants_transmit(self.now).is_some() {
            let transmit = self
                .driver
                .poll_transmit(self.now, &mut buf)
                .expect("sends");
            let mosi = buf[..transmit.len].to_vec();
            miso.extend(self.board.transfer(&mosi));
            out.push(mosi);
        }
        self.sent.extend(out.iter().cloned());
        self.now += MS;
        // Odd chunking on purpose: the driver reassembles.
        for chunk in miso.chunks(5) {
            self.driver.handle_rx(self.now, chunk);
        }
        out
    }

    pub(super) fn steps(&mut self, count: usize) {
        for _ in 0..count {
            self.step();
        }
    }

    pub(super) fn started(config: SpimotorDriverConfig) -> Self {
        let mut bench = Self::new(config);
        bench.steps(5);
        assert!(bench.driver.status().online);
        assert_eq!(bench.driver.channel(0).fault, None);
        bench
    }
}

pub(super) fn stepper() -> SpimotorDriverConfig {
    SpimotorDriverConfig {
        limits: [AxisLimits {
            max_velocity: 2_000.0,
            max_accel: 20_000.0,
        }; 2],
        ..SpimotorDriverConfig::default()
    }
}

fn brushed() -> SpimotorDriverConfig {
    SpimotorDriverConfig {
        drive: SpimotorDrive::Brushed,
        ..SpimotorDriverConfig::default()
    }
}

#[test]
fn start_up_reads_identification_as_the_datasheet_example_then_configures() {
    let mut bench = Bench::new(stepper());
    // "read identification": 0x91 (address 0x90 for READ), 0x01 (identify), then xx.
    let first = bench.step();
    assert_eq!(first.len(), 1);
    assert_eq!(&first[0][..2], &[0x91, 0x01]);
    assert_eq!(
        first[0].len(),
        2 + usize::from(spimotor::IDENTIFICATION_READ_LEN)
    );
    let serial = bench.step();
    assert_eq!(serial, vec![vec![0x91, 0x02, 0, 0, 0, 0]]);
    // Before writing anything, what the board does now: read twice, believed when both
    // readings agree.
    for _ in 0..2 {
        assert!(!bench.driver.status().online);
        let survey = bench.step();
        assert_eq!(
            survey,
            vec![
                vec![0x91, 0x40, 0, 0, 0, 0],
                vec![0x91, 0x41, 0, 0, 0, 0],
                vec![0x91, 0x43, 0],
            ]
        );
    }
    assert!(
        bench.driver.status().online,
        "online once the survey is answered"
    );
    let configure = bench.step();
    let rest = ramp::delay_for(2_000.0).tenths_ms();
    assert_eq!(rest, 5, "2000 steps/s is a step every 0.5 ms");
    assert_eq!(
        &configure[..4],
        &[
            vec![0x90, 0x42, 0, 0, 0, 0],
            vec![0x90, 0x44, 0x01],
            vec![0x90, 0x43, rest],
            vec![0x90, 0x10, 0x20],
        ]
    );
    assert_eq!(
        &configure[4..],
        &[
            vec![0x91, 0x40, 0, 0, 0, 0],
            vec![0x91, 0x41, 0, 0, 0, 0],
            vec![0x91, 0x43, 0],
        ],
        "polls go after the configuration"
    );
    bench.step();
    let status = bench.driver.status();
    assert!(status.online);
    assert_eq!(status.firmware(), "spi_motor sn 00001234");
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, None);
    assert_eq!(state.refreshed_at, Some(5 * MS));
    assert_eq!(
        status.replies, 4,
        "identification, serial number, the survey, one poll"
    );
    assert_eq!(bench.board.delay, rest);
    assert_eq!(Coils::from_byte(0x01), Coils::Two);
}

#[test]
fn a_position_goal_writes_the_datasheet_target_bytes() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Position {
                counts: 305_419_896.0,
            },
        )
        .unwrap();
    let sent = bench.step();
    // "move stepper to step 0x12345678": 0x90, 0x41, 0x78, 0x56, 0x34, 0x12 — after the
    // slowest step delay the ramp starts with.
    assert_eq!(sent[0], vec![0x90, 0x43, 0xFF]);
    assert_eq!(sent[1], vec![0x90, 0x41, 0x78, 0x56, 0x34, 0x12]);
    assert!(bench.driver.goals_pending() || bench.driver.channel(0).moving);
    assert!(bench.driver.channel(0).moving);
}

#[test]
fn the_ramp_speeds_up_within_the_axis_limits() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 100_000.0 })
        .unwrap();
    let mut delays = Vec::new();
    for _ in 0..200 {
        for mosi in bench.step() {
            if mosi[..2] == [0x90, 0x43] {
                delays.push(mosi[2]);
            }
        }
    }
    // The board does not step here, so the profile cruises at max velocity: 2000 steps/s
    // is delay 5, reached after 0.1 s at 20 000 steps/s².
    assert_eq!(delays.first(), Some(&0xFF));
    assert_eq!(delays.last(), Some(&5));
    assert!(
        delays.windows(2).all(|w| w[1] <= w[0]),
        "monotonic speed-up"
    );
    assert!(
        delays.iter().all(|&d| d >= 5),
        "never faster than max velocity"
    );
}

#[test]
fn set_position_writes_current_then_target_with_a_slow_delay_around() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: -2.0 })
        .unwrap();
    let sent = bench.step();
    assert_eq!(
        &sent[..4],
        &[
            vec![0x90, 0x43, 0xFF],
            vec![0x90, 0x40, 0xFE, 0xFF, 0xFF, 0xFF],
            vec![0x90, 0x41, 0xFE, 0xFF, 0xFF, 0xFF],
            vec![0x90, 0x43, 5],
        ]
    );
    bench.steps(3);
    let state = bench.driver.channel(0);
    assert_eq!((state.position, state.raw_counts), (-2.0, -2));
    assert!(state.homed && !state.moving);
    assert_eq!(bench.driver.status().bad_replies, 0);
}

#[test]
fn a_stop_while_standing_stops_here_at_once() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 1_000.0 })
        .unwrap();
    let sent = bench.step();
    assert_eq!(sent[0], vec![0x90, 0x42, 0, 0, 0, 0]);
    bench.steps(2);
    assert!(!bench.driver.goals_pending());
    assert!(!bench.driver.channel(0).moving);
}

#[test]
fn velocity_goals_the_board_cannot_step_are_refused() {
    let mut bench = Bench::started(stepper());
    let now = bench.now;
    let driver = &mut bench.driver;
    for velocity in [10.0, -20_000.0, f64::NAN] {
        assert_eq!(
            driver.set_goal(
                now,
                0,
                Goal::Velocity {
                    velocity,
                    accel: 100.0
                }
            ),
            Err(GoalError::OutOfBoardRange(GoalKind::Velocity)),
            "{velocity}"
        );
    }
    assert_eq!(
        driver.set_goal(now, 0, Goal::Home { velocity: 100.0 }),
        Err(GoalError::Unsupported(GoalKind::Home))
    );
    assert_eq!(
        driver.set_goal(now, 0, Goal::Power { fraction: 0.5 }),
        Err(GoalError::Unsupported(GoalKind::Power))
    );
    assert_eq!(
        driver.set_goal(now, 0, Goal::Position { counts: 1e12 }),
        Err(GoalError::OutOfBoardRange(GoalKind::Position))
    );
    assert_eq!(
        driver.set_goal(
            now,
            0,
            Goal::RampPosition {
                counts: 5.0,
                velocity: 1.0,
                accel: 1.0
            }
        ),
        Err(GoalError::OutOfBoardRange(GoalKind::RampPosition))
    );
    assert_eq!(
        driver.set_goal(now, 1, Goal::Off),
        Err(GoalError::NoSuchChannel(1))
    );
    driver
        .set_goal(
            now,
            0,
            Goal::Velocity {
                velocity: -500.0,
                accel: 10_000.0,
            },
        )
        .unwrap();
    let sent = bench.step();
    // Runs towards a target 2^30 steps behind.
    assert!(sent.contains(&vec![0x90, 0x41, 0x00, 0x00, 0x00, 0xC0]));
}

#[test]
fn an_absent_board_is_reported_not_responding() {
    let mut bench = Bench::new(stepper());
    bench.board.present = false;
    bench.steps(100);
    let status = bench.driver.status();
    assert!(!status.online);
    assert_eq!(status.fault, Some(DeviceFault::NotResponding));
    assert_eq!(
        bench.driver.channel(0).fault,
        Some(DeviceFault::NotResponding)
    );
    assert!(
        bench.sent.iter().all(|mosi| mosi[..2] == [0x91, 0x01]),
        "nothing but identification reads to an unknown board"
    );
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Position { counts: 1.0 }),
        Err(GoalError::Offline)
    );
    // It comes back: retried every OFFLINE_RETRY_PERIOD.
    bench.board.present = true;
    bench.steps(250);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.channel(0).fault, None);
}

#[test]
fn a_board_that_vanishes_while_running_is_detected() {
    let mut bench = Bench::started(stepper());
    bench.board.present = false;
    bench.steps(100);
    assert_eq!(
        bench.driver.status().fault,
        Some(DeviceFault::NotResponding)
    );
    assert_eq!(
        bench.driver.channel(0).position,
        0.0,
        "last known state kept"
    );
}

#[test]
fn garbage_polls_are_discarded_and_a_reset_is_recognised() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 1_000.0 })
        .unwrap();
    bench.steps(5);
    assert_eq!(bench.driver.channel(0).position, 1_000.0);
    // One corrupted poll: the position jumps by far more than the board can step.
    let good = bench.board.clone();
    bench.board.position = 0x7700_1234;
    bench.steps(2);
    bench.board = good;
    let state = bench.driver.channel(0);
    assert_eq!(state.position, 1_000.0, "garbage never reaches the channel");
    assert_eq!(state.fault, None);
    assert!(bench.driver.status().bad_replies >= 1);
    // A power cycle: registers back to their power-on values, the same every poll.
    bench.board = Board::new();
    bench.steps(12);
    assert_eq!(bench.driver.status().resets, 1);
    let state = bench.driver.channel(0);
    assert!(!state.homed);
    bench.steps(10);
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, None, "started again");
    assert_eq!(state.position, 0.0);
    assert_eq!(bench.board.delay, 5, "configured again");
}

#[test]
fn reset_fault_is_visible_before_it_clears() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 500.0 })
        .unwrap();
    bench.steps(5);
    bench.board = Board::new();
    let mut seen = false;
    for _ in 0..30 {
        bench.step();
        seen |= bench.driver.channel(0).fault == Some(DeviceFault::Reset);
    }
    assert!(seen);
}

#[test]
fn link_down_keeps_the_last_state_and_link_up_starts_over() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 42.0 })
        .unwrap();
    bench.steps(3);
    assert_eq!(bench.driver.channel(0).position, 42.0);
    bench.driver.link_down(bench.now);
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, Some(DeviceFault::LinkDown));
    assert_eq!(state.position, 42.0);
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Stop { decel: 1.0 }),
        Err(GoalError::Offline)
    );
    assert!(bench.step().is_empty(), "nothing is sent on a down link");
    bench.driver.link_up(bench.now);
    let sent = bench.step();
    assert_eq!(&sent[0][..2], &[0x91, 0x01]);
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::LinkDown));
    bench.steps(5);
    assert_eq!(bench.driver.channel(0).fault, None);
}

#[test]
fn brushed_power_goals_spin_and_stop_the_motors() {
    let mut bench = Bench::started(brushed());
    let driver = &mut bench.driver;
    assert_eq!(driver.channel_count(), 2);
    assert!(driver.capabilities(1).contains(GoalKind::Power));
    assert!(!driver.capabilities(0).contains(GoalKind::Position));
    assert_eq!(driver.capabilities(2), GoalKinds::NONE);
    let now = bench.now;
    driver
        .set_goal(now, 0, Goal::Power { fraction: 0.5 })
        .unwrap();
    driver
        .set_goal(now, 1, Goal::Power { fraction: -1.0 })
        .unwrap();
    let sent = bench.step();
    // Port 0x20: spin motor A in direction A with intensity 128; 0x31: B, direction B.
    assert_eq!(
        &sent[..2],
        &[vec![0x90, 0x20, 0x80], vec![0x90, 0x31, 0xFF]]
    );
    assert!(bench.driver.channel(0).moving && bench.driver.channel(1).moving);
    let state = bench.driver.channel(0);
    assert_eq!((state.position, state.velocity), (0.0, 0.0), "no encoder");
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 5.0 })
        .unwrap();
    bench
        .driver
        .set_goal(bench.now, 1, Goal::Power { fraction: 0.001 })
        .unwrap();
    let sent = bench.step();
    assert_eq!(&sent[..2], &[vec![0x90, 0x22], vec![0x90, 0x32]]);
    assert!(!bench.driver.channel(0).moving && !bench.driver.channel(1).moving);
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Power { fraction: 1.5 }),
        Err(GoalError::OutOfBoardRange(GoalKind::Power))
    );
    assert_eq!(
        bench.driver.set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 1.0,
                accel: 1.0
            }
        ),
        Err(GoalError::Unsupported(GoalKind::Velocity))
    );
    assert!(bench.board.spins.contains(&Write::Stop(Motor::B)));
}

#[test]
fn brushed_channels_refresh_on_presence_reads() {
    let mut bench = Bench::started(brushed());
    let before = bench.driver.channel(1).refreshed_at.unwrap();
    bench.steps(10);
    let after = bench.driver.channel(1).refreshed_at.unwrap();
    assert!(after > before);
    // The presence read clocks only as many bytes as the known identification needs.
    let last = bench.sent.last().unwrap();
    assert_eq!(last.len(), 2 + b"spi_motor\0".len());
    bench.board.present = false;
    bench.steps(20);
    assert_eq!(
        bench.driver.channel(1).fault,
        Some(DeviceFault::NotResponding)
    );
}

#[test]
fn two_boards_have_their_own_addresses() {
    let config = SpimotorDriverConfig {
        address: Address::new(0x92).unwrap(),
        ..brushed()
    };
    let mut bench = Bench::new(config);
    let sent = bench.step();
    assert_eq!(sent[0][0], 0x93);
    assert_eq!(bench.driver.model(), motion_drivers::Model::SPIMOTOR);
}

#[test]
fn nothing_allocates_and_nothing_panics_on_random_miso() {
    // Random MISO of every length: the driver keeps running and never panics.
    let mut bench = Bench::started(stepper());
    let mut seed = 0x1234_5678_u32;
    let mut buf = [0u8; 256];
    for _ in 0..2_000 {
        bench.driver.handle_timeout(bench.now);
        while bench.driver.poll_transmit(bench.now, &mut buf).is_some() {}
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        let len = (seed % 40) as usize;
        let bytes: Vec<u8> = (0..len).map(|k| (seed >> (k % 24)) as u8).collect();
        bench.driver.handle_rx(bench.now, &bytes);
        bench.now += MS;
    }
    let _ = bench.driver.channel(0);
}

#[test]
fn a_stop_is_pinned_when_the_relative_port_counts_from_the_target() {
    let mut bench = Bench::started(stepper());
    bench.board.relative_to_target = true;
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 5_000.0 })
        .unwrap();
    bench.steps(3);
    // The board has walked a step or two (this scripted board jumps; more than its
    // step delay allows would be discarded as implausible).
    bench.board.position = 2;
    bench.steps(2);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 1e9 })
        .unwrap();
    bench.steps(8);
    assert_eq!(bench.board.target, 2, "pinned where it was");
    assert!(!bench.driver.channel(0).moving);
    assert_eq!(bench.driver.status().bad_replies, 0);
}

/// The step delays (port 0x43) written in `sent`, in tenths of a millisecond.
fn delays_written(sent: &[Vec<u8>]) -> Vec<u8> {
    sent.iter()
        .filter(|mosi| mosi[..2] == [0x90, 0x43])
        .map(|mosi| mosi[2])
        .collect()
}

#[test]
fn a_stepper_left_running_is_ramped_down_from_its_own_rate() {
    let mut bench = Bench::new(stepper());
    // Another program left it stepping at 0.2 ms (5000 steps/s) towards a far target.
    bench.board.delay = 2;
    bench.board.target = 1_000_000;
    bench.board.position = 10;
    bench.steps(4);
    assert!(bench.driver.status().online);
    assert!(bench.driver.channel(0).moving);
    assert!(bench.driver.goals_pending(), "its own stop is under way");
    for _ in 0..400 {
        bench.step();
        if !bench.driver.channel(0).moving {
            break;
        }
    }
    let sent = bench.sent.clone();
    // Nothing stopped it dead: no 0x42 before the ramp, and the first delay written is
    // within one ramp step of the 5000 steps/s it ran at.
    let first_stop = sent
        .iter()
        .position(|mosi| mosi[..2] == [0x90, 0x42])
        .expect("stopped at the end");
    let delays = delays_written(&sent[..first_stop]);
    assert!(!delays.is_empty());
    let first = ramp::rate_of(StepDelay::from_tenths_ms(delays[0]));
    // 20 000 steps/s² (the axis's max acceleration) over one 2 ms profile period.
    assert!(first >= 5_000.0 - 40.0 - 1_700.0, "first rate {first}");
    assert!(
        delays.windows(2).all(|w| w[1] >= w[0]),
        "monotonic slow-down"
    );
    // From 5000 steps/s at 20 000 steps/s²: 0.25 s (plus a profile period or two).
    let stopped_at = bench.now;
    assert!(
        stopped_at <= Duration::from_millis(4 + 250 + 10),
        "{stopped_at:?}"
    );
    assert!(
        stopped_at >= Duration::from_millis(200),
        "not abrupt: {stopped_at:?}"
    );
    // The coils and intensity were written at start-up all the same.
    assert!(sent.contains(&vec![0x90, 0x44, 0x01]));
    assert!(sent.contains(&vec![0x90, 0x10, 0x20]));
    assert!(!bench.driver.goals_pending());
}

#[test]
fn a_stop_ramps_from_the_rate_the_board_steps_at() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 2_000.0,
                accel: 20_000.0,
            },
        )
        .unwrap();
    bench.steps(200);
    assert_eq!(bench.board.delay, 5, "running at 2000 steps/s");
    let from = bench.sent.len();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 10_000.0 })
        .unwrap();
    let mut steps = 0;
    while bench.driver.channel(0).moving {
        bench.step();
        steps += 1;
        assert!(steps < 400);
    }
    let sent = bench.sent[from..].to_vec();
    let delays = delays_written(&sent);
    // 2000 → 39 steps/s at 10 000 steps/s²: about 196 ms, a new delay whenever the
    // ramped rate crosses to the next one.
    assert!(delays.len() > 20, "{delays:?}");
    assert!(delays.windows(2).all(|w| w[1] >= w[0]));
    let rates: Vec<f64> = delays
        .iter()
        .map(|d| ramp::rate_of(StepDelay::from_tenths_ms(*d)))
        .collect();
    assert!(rates[0] >= 2_000.0 - 20.0 - 700.0, "{}", rates[0]);
    assert!((190..=215).contains(&steps), "{steps} ms");
}

#[test]
fn off_de_energises_and_the_next_goal_energises_first() {
    let mut config = stepper();
    config.stepper_intensity = 0x60;
    config.coils = Coils::One;
    let mut bench = Bench::started(config);
    assert_eq!(
        bench.board.intensity, 0x60,
        "configured intensity at start-up"
    );
    assert!(bench.sent.contains(&vec![0x90, 0x44, 0x00]), "one coil");
    bench.driver.set_goal(bench.now, 0, Goal::Off).unwrap();
    let sent = bench.step();
    // Port 0x42 ← 0 (stop here), then 0x10 ← 0: the coils carry no current.
    assert_eq!(sent[0], vec![0x90, 0x42, 0, 0, 0, 0]);
    assert_eq!(sent[1], vec![0x90, 0x10, 0x00]);
    assert_eq!(bench.board.intensity, 0);
    bench.steps(3);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 50.0 })
        .unwrap();
    let sent = bench.step();
    assert_eq!(sent[0], vec![0x90, 0x10, 0x60], "intensity before the move");
    assert!(sent.iter().any(|mosi| mosi[..2] == [0x90, 0x41]));
}

#[test]
fn a_reset_board_gets_intensity_and_coils_again() {
    let mut config = stepper();
    config.stepper_intensity = 0x40;
    let mut bench = Bench::started(config);
    bench.steps(5);
    // Power cycle: registers back to power-on values.
    bench.board = Board::new();
    bench.board.intensity = 0x20;
    let from = bench.sent.len();
    for _ in 0..40 {
        bench.step();
    }
    assert!(bench.driver.status().resets >= 1);
    let sent = &bench.sent[from..];
    assert!(sent.contains(&vec![0x90, 0x10, 0x40]), "intensity again");
    assert!(sent.contains(&vec![0x90, 0x44, 0x01]), "coils again");
    assert_eq!(bench.board.intensity, 0x40);
}
