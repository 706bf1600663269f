//! The driver against the simulated board, tick by tick with a fake clock.

use core::time::Duration;

use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind};
use motion_link::sim::StreamDevice;

use super::{ExampleDriver, ExampleDriverConfig, OFFLINE_RETRY_PERIOD, PROTOCOL_LIMIT};
use crate::sim::{ExampleSim, ExampleSimConfig};

/// A driver wired to a simulated board; bytes cross at once, `silent` drops the board's.
pub(super) struct Bench {
    pub(super) driver: ExampleDriver,
    pub(super) board: ExampleSim,
    pub(super) now: Duration,
    pub(super) silent: bool,
    goal_starts: u8,
    /// While set, the board's bytes are held (the host starved) until this instant.
    pub(super) hold_until: Option<Duration>,
    held: Vec<u8>,
}

impl Bench {
    pub(super) fn new() -> Self {
        Self {
            driver: ExampleDriver::new(ExampleDriverConfig::default()),
            board: ExampleSim::new(ExampleSimConfig::default()),
            now: Duration::ZERO,
            silent: false,
            goal_starts: 0,
            hold_until: None,
            held: Vec::new(),
        }
    }

    /// One millisecond, in the engine's call order.
    pub(super) fn tick(&mut self) {
        let now = self.now;
        let mut buf = [0u8; 256];
        let len = self.board.transmit(now, &mut buf);
        if self.hold_until.is_some_and(|until| now < until) {
            self.held.extend(&buf[..len]);
        } else if !self.silent {
            let held = core::mem::take(&mut self.held);
            self.driver.handle_rx(now, &held);
            self.driver.handle_rx(now, &buf[..len]);
        }
        self.driver.handle_heard(now);
        self.driver.handle_timeout(now);
        while let Some(sent) = self.driver.poll_transmit(now, &mut buf) {
            self.goal_starts |= sent.goal_starts;
            self.board.receive(now, &buf[..sent.len]);
            self.driver.handle_written(now);
        }
        self.now += Duration::from_millis(1);
    }

    pub(super) fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.tick();
        }
    }

    pub(super) fn online(mut self) -> Self {
        self.run(20);
        assert!(self.driver.status().online, "{:?}", self.driver.status());
        self
    }

    pub(super) fn goal(&mut self, channel: usize, goal: Goal) {
        let now = self.now;
        self.driver
            .set_goal(now, channel, goal)
            .expect("goal taken");
    }
}

#[test]
fn it_identifies_the_board_goes_online_and_polls_within_its_budget() {
    let mut bench = Bench::new();
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, Goal::Off),
        Err(GoalError::Starting)
    );
    let bench = bench.online();
    let status = bench.driver.status();
    assert_eq!(status.firmware(), "AS2 1.4");
    assert_eq!(
        (status.fault, status.timeouts, status.bad_replies),
        (None, 0, 0)
    );
    for channel in 0..2 {
        let state = bench.driver.channel(channel);
        let age = bench.now - state.refreshed_at.expect("polled");
        assert!(age < bench.driver.refresh_budget(), "{age:?}");
        assert_eq!(state.fault, None);
    }
    assert_eq!(
        bench.driver.channel(2),
        motion_drivers::ChannelState::UNKNOWN
    );
    assert!(!bench.driver.capabilities(2).contains(GoalKind::Off));
}

#[test]
fn a_move_reaches_its_target_and_is_acknowledged() {
    let mut bench = Bench::new().online();
    bench.goal(
        1,
        Goal::RampPosition {
            counts: 3000.0,
            velocity: 5000.0,
            accel: 50_000.0,
        },
    );
    assert!(bench.driver.goals_pending());
    bench.run(2);
    assert!(!bench.driver.goals_pending(), "acknowledged");
    assert_eq!(bench.goal_starts, 0b10, "the goal's request was stamped");
    bench.run(100);
    assert!(bench.driver.channel(1).moving);
    // 3000 steps: 0.1 s ramps (250 steps each) and 0.5 s cruise, 0.7 s.
    bench.run(700);
    let state = bench.driver.channel(1);
    assert_eq!(
        (state.position, state.moving, state.arrived),
        (3000.0, false, true)
    );
    assert_eq!(bench.board.position(1), Some(3000));
}

#[test]
fn a_jog_runs_and_a_stop_stops_it() {
    let mut bench = Bench::new().online();
    bench.goal(
        0,
        Goal::Velocity {
            velocity: -2000.0,
            accel: 20_000.0,
        },
    );
    bench.run(300);
    let running = bench.driver.channel(0);
    assert_eq!(running.velocity, -2000.0);
    assert!(running.moving && running.position < -300.0, "{running:?}");
    bench.goal(0, Goal::Stop { decel: 20_000.0 });
    bench.run(200);
    let stopped = bench.driver.channel(0);
    assert!(!stopped.moving && stopped.velocity == 0.0, "{stopped:?}");
    bench.goal(0, Goal::SetPosition { counts: 0.0 });
    bench.run(20);
    let set = bench.driver.channel(0);
    assert!(set.homed && set.position == 0.0, "{set:?}");
}

#[test]
fn garbage_on_the_wire_is_counted_and_dropped_never_believed() {
    let mut bench = Bench::new().online();
    let before = bench.driver.channel(0);
    bench
        .driver
        .handle_rx(bench.now, b"\xff\xfeP0 999 0 I\r\x00\x00\rOK\rAS2 9\r");
    let status = bench.driver.status();
    // The position reply resynced out of the noise, but nothing was asked: dropped.
    assert!(status.bad_replies >= 3, "{status:?}");
    assert_eq!(bench.driver.channel(0).position, before.position);
    bench.run(20);
    assert_eq!(bench.driver.status().fault, None);
    // Garbage in a row long enough: a protocol fault, until a good reply.
    for _ in 0..PROTOCOL_LIMIT {
        bench.driver.handle_rx(bench.now, b"#?!\r");
    }
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::Protocol));
    bench.run(20);
    assert_eq!(bench.driver.channel(0).fault, None);
}

#[test]
fn a_silent_board_is_not_responding_and_comes_back() {
    let mut bench = Bench::new();
    bench.silent = true;
    let silence = bench.driver.config().silence;
    // The identify waits for its reply (it may be held up on the host) for `silence`.
    bench.run(silence.as_millis() as u64 - 10);
    assert_eq!(bench.driver.status().fault, None, "not before the silence");
    bench.run(20);
    let status = bench.driver.status();
    assert_eq!(status.fault, Some(DeviceFault::NotResponding));
    assert!(!status.online && status.timeouts == 1, "{status:?}");
    let evidence = status.verdict.expect("verdict").evidence;
    assert!(
        evidence.as_str().starts_with("`?` written at 0.000 s")
            && evidence.as_str().contains("ms of silence (silence 500 ms)"),
        "{}",
        evidence.as_str()
    );
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, Goal::Off),
        Err(GoalError::Offline)
    );
    bench.silent = false;
    bench.run(OFFLINE_RETRY_PERIOD.as_millis() as u64 + 50);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.channel(0).fault, None);

    // Online, then silent: not answering after `silence`, the goal dropped, start-up again.
    bench.goal(
        0,
        Goal::Velocity {
            velocity: 100.0,
            accel: 1000.0,
        },
    );
    bench.silent = true;
    bench.run(silence.as_millis() as u64 + 30);
    assert_eq!(
        bench.driver.channel(0).fault,
        Some(DeviceFault::NotResponding)
    );
    assert_eq!(bench.driver.status().verdicts, 2);
    assert!(!bench.driver.goals_pending(), "goals are void");
}

#[test]
fn silence_is_judged_only_up_to_the_links_horizon() {
    let mut bench = Bench::new().online();
    bench.silent = true;
    let mut buf = [0u8; 256];
    bench.run(1);
    let horizon = bench.now;
    // The I/O side stops looking: no horizon past `horizon`, however late it gets.
    let mut now = horizon;
    for _ in 0..1000 {
        bench.driver.handle_heard(horizon);
        bench.driver.handle_timeout(now);
        while let Some(sent) = bench.driver.poll_transmit(now, &mut buf) {
            let _ = sent;
            bench.driver.handle_written(now);
        }
        now += Duration::from_millis(1);
    }
    assert_eq!(bench.driver.status().timeouts, 0);
    assert_eq!(bench.driver.status().fault, None);
}

#[test]
fn an_error_answer_faults_the_channel_until_the_next_goal() {
    let mut bench = Bench::new().online();
    bench.goal(0, Goal::Position { counts: 5.0 });
    let mut buf = [0u8; 256];
    let sent = bench
        .driver
        .poll_transmit(bench.now, &mut buf)
        .expect("the move");
    assert_eq!(&buf[..sent.len], b"M0 5 1000 10000\r");
    bench.driver.handle_written(bench.now);
    bench.driver.handle_rx(bench.now, b"E3\r");
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::BoardError));
    assert_eq!(bench.driver.channel(1).fault, None);
    bench.goal(0, Goal::Stop { decel: 1000.0 });
    assert_eq!(bench.driver.channel(0).fault, None);
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Power { fraction: 0.5 }),
        Err(GoalError::Unsupported(GoalKind::Power))
    );
}

#[test]
fn the_link_going_down_faults_every_channel_and_voids_the_goals() {
    let mut bench = Bench::new().online();
    bench.goal(1, Goal::Off);
    bench.driver.link_down(bench.now);
    assert_eq!(bench.driver.channel(1).fault, Some(DeviceFault::LinkDown));
    assert!(!bench.driver.goals_pending());
    assert_eq!(bench.driver.poll_timeout(), None);
    let mut buf = [0u8; 256];
    assert!(bench.driver.poll_transmit(bench.now, &mut buf).is_none());
    bench.driver.link_up(bench.now);
    bench.run(20);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.channel(1).fault, None);
}
