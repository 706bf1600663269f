//! The default robot (`config/sim.toml`: all four boards, 18 axes) stepped in one process
//! with a fake clock: the engine and the four drivers allocate nothing in steady state, and
//! the same commands at the same ticks give byte-identical frames.

use core::time::Duration;
use std::path::PathBuf;

use motion_blackbox::{Journal, Recording, Ring, replay};
use motion_config::ServerConfig;
use motion_engine::{CommandPort, Engine};
use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandReply, CommandRequest, GroupMotion, GroupPath,
    GroupState, MAX_GROUP_AXES, MAX_PATH_POINTS, MotionFrame, PathKind, Target,
};
use motion_link::Link;
use motion_testkit::counting_alloc::{CountingAllocator, allocations, counting};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[path = "sim_robot/blackbox.rs"]
mod blackbox;
#[path = "sim_robot/features.rs"]
mod features;

/// Counts allocations of the engine (and its drivers) only, not of the simulated links.
fn engine<T>(work: impl FnOnce() -> T) -> T {
    counting(work)
}

struct Queue {
    requests: std::collections::VecDeque<CommandRequest>,
    replies: Vec<CommandReply>,
    /// A path "published" by the client (the engine takes it by reference).
    path: Option<Box<GroupPath>>,
    /// The black box's journal, as motiond's tick keeps it (every input and output).
    journal: Journal,
}

impl CommandPort for Queue {
    fn next_request(&mut self) -> Option<CommandRequest> {
        let request = self.requests.pop_front()?;
        // No transport identity here: the engine takes the request's own client.
        self.journal.request(request.client, &request);
        Some(request)
    }
    fn reply(&mut self, reply: CommandReply) {
        self.journal.reply(&reply);
        self.replies.push(reply);
    }
    fn take_path(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let path = self.path.as_deref().filter(|path| path.id == id);
        self.journal.path(client, id, path);
        path
    }
}

struct Robot {
    engine: Engine<motion_config::boards::AnyDriver>,
    links: Vec<Box<dyn Link>>,
    frame: Box<MotionFrame>,
    port: Queue,
    now: Duration,
    period: Duration,
    /// The recorder's end of the journal, and its ring (every tick kept).
    journal: rtrb::Consumer<u8>,
    ring: Ring,
    config: ServerConfig,
}

/// Ticks between two snapshots of the engine's state in the journal.
const SNAPSHOT_EVERY: u64 = 1000;

impl Robot {
    fn new() -> Self {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
        Self::with(ServerConfig::load(&path).expect("config/sim.toml is valid"))
    }

    /// The robot of `config` (all its links simulated).
    fn with(config: ServerConfig) -> Self {
        let drivers = motion_config::boards::build(&config).expect("drivers");
        let mut engine = Engine::new(config.engine_config(), drivers).expect("engine");
        // As motiond: every write and the links' horizons are reported.
        engine.stamp_links();
        let links: Vec<Box<dyn Link>> = config
            .links
            .iter()
            .enumerate()
            .map(|(index, spec)| {
                assert!(matches!(
                    spec.transport,
                    motion_config::Transport::Sim { .. }
                ));
                Box::new(motion_config::boards::sim_link(&config, index)) as Box<dyn Link>
            })
            .collect();
        let period = engine.config().period();
        let (producer, journal) = rtrb::RingBuffer::new(1 << 20);
        let mut port = Queue {
            requests: std::collections::VecDeque::with_capacity(64),
            replies: Vec::with_capacity(100_000),
            path: None,
            // A snapshot of the engine's state every 1000 ticks, as motiond's every quarter
            // of the ring.
            journal: Journal::new(producer, SNAPSHOT_EVERY),
        };
        port.journal.start(Duration::ZERO, links.len());
        port.journal.prepare_snapshots(&engine);
        Self {
            engine,
            links,
            frame: Box::new(MotionFrame::EMPTY),
            port,
            now: Duration::ZERO,
            period,
            journal,
            ring: Ring::new(usize::MAX, 64 << 20),
            config,
        }
    }

    /// One tick as motiond's runs it, every input and output journaled (the journal is
    /// counted with the engine: it must not allocate either).
    fn tick(&mut self) {
        let now = self.now;
        let mut buf = [0u8; 512];
        let journal = &mut self.port.journal;
        let state = &self.engine;
        engine(|| {
            journal.tick(now);
            if journal.snapshot_due() {
                journal.snapshot(state);
            }
        });
        for (index, link) in self.links.iter_mut().enumerate() {
            while let Ok(len) = link.read(now, &mut buf) {
                if len == 0 {
                    break;
                }
                engine(|| {
                    self.port.journal.link_rx(index, now, &buf[..len]);
                    self.engine.handle_link_rx(index, now, now, &buf[..len]);
                });
            }
            engine(|| {
                self.port.journal.link_heard(index, now);
                self.engine.link_heard(index, now);
            });
        }
        engine(|| {
            self.port.journal.step();
            self.engine.step(now, &mut self.port, &mut self.frame);
            self.port.journal.frame(&self.frame);
        });
        for (index, link) in self.links.iter_mut().enumerate() {
            loop {
                let (sent, rate) = engine(|| {
                    let sent = self.engine.poll_link_transmit(index, now, &mut buf);
                    let mut rate = None;
                    match sent {
                        Some(len) => {
                            self.port.journal.link_tx(index, &buf[..len]);
                            // As motiond: a change of the line rate before the message.
                            rate = self.engine.take_link_rate(index);
                            if let Some(baud) = rate {
                                self.port.journal.link_rate(index, baud);
                            }
                        }
                        None => self.port.journal.link_tx_none(index),
                    }
                    (sent, rate)
                });
                let Some(len) = sent else { break };
                if let Some(baud) = rate {
                    link.set_baud(now, baud).expect("sim link rate");
                }
                link.write(now, &buf[..len]).expect("sim link write");
                engine(|| {
                    self.port.journal.link_written(index, now);
                    self.engine.link_written(index, now);
                });
            }
        }
        // The recorder thread's work, outside the count.
        while let Ok(chunk) = self.journal.read_chunk(self.journal.slots()) {
            if chunk.is_empty() {
                break;
            }
            let (first, second) = chunk.as_slices();
            self.ring.push(first);
            self.ring.push(second);
            chunk.commit_all();
        }
        self.now += self.period;
    }

    fn axis(&self, name: &str) -> u32 {
        self.engine
            .config()
            .axes
            .iter()
            .position(|a| a.name == name)
            .expect("axis exists") as u32
    }
}

/// Commands at fixed ticks: moves, jogs (refreshed), power, a home, a set-position, an
/// e-stop and a reset across all four boards.
fn script(robot: &Robot, tick: u64) -> Vec<(u32, CommandKind, [f64; 3])> {
    let phase = tick % 4000;
    let mut commands = Vec::new();
    let mut at = |when: u64, axis: &str, kind: CommandKind, values: [f64; 3]| {
        if phase == when {
            commands.push((robot.axis(axis), kind, values));
        }
    };
    at(
        10,
        "wheel_left",
        CommandKind::RampPosition,
        [90.0, 0.0, 0.0],
    );
    at(10, "x", CommandKind::RampPosition, [5.0, 0.0, 0.0]);
    at(10, "focus", CommandKind::RampPosition, [200.0, 0.0, 0.0]);
    at(10, "feeder", CommandKind::RampPosition, [3.0, 0.0, 0.0]);
    at(20, "pump_a", CommandKind::Power, [0.5, 0.0, 0.0]);
    for refresh in [30, 130, 230] {
        at(refresh, "lift", CommandKind::Velocity, [5.0, 0.0, 0.0]);
        at(refresh, "conveyor", CommandKind::Velocity, [20.0, 0.0, 0.0]);
    }
    at(1500, "turret", CommandKind::SetPosition, [0.0, 0.0, 0.0]);
    at(
        2000,
        "wheel_left",
        CommandKind::RampPosition,
        [0.0, 0.0, 0.0],
    );
    at(2000, "x", CommandKind::RampPosition, [0.0, 0.0, 0.0]);
    at(2000, "focus", CommandKind::RampPosition, [0.0, 0.0, 0.0]);
    at(2000, "feeder", CommandKind::RampPosition, [0.0, 0.0, 0.0]);
    at(3000, "y", CommandKind::EStop, [0.0; 3]);
    at(3500, "y", CommandKind::Reset, [0.0; 3]);
    commands
}

fn run(robot: &mut Robot, from: u64, ticks: u64, mut each: impl FnMut(&Robot)) {
    let client = ClientId::from_u128(42);
    for tick in from..from + ticks {
        for (axis, kind, values) in script(robot, tick) {
            let request = CommandRequest::new(client, tick, axis, kind).with_values(values);
            robot.port.requests.push_back(request);
        }
        robot.tick();
        each(robot);
    }
}

#[test]
fn the_engine_and_all_four_drivers_allocate_nothing_in_steady_state() {
    let mut robot = Robot::new();
    // Start-up (boards boot, drivers configure them) is allowed to allocate nothing too,
    // but the claim is about steady state: warm up first.
    run(&mut robot, 0, 4000, |_| {});
    let online = robot
        .frame
        .axes()
        .iter()
        .all(|a| !a.flags().contains(AxisFlags::STALE));
    assert!(online, "every board answers: {:?}", robot.frame.axes());
    let before = allocations();
    run(&mut robot, 4000, 10_000, |_| {});
    let allocations = allocations() - before;
    assert_eq!(
        allocations, 0,
        "the engine allocated {allocations} times in 10 000 steps"
    );
    let accepted = robot
        .port
        .replies
        .iter()
        .filter(|r| r.result().is_ok())
        .count();
    assert!(
        accepted > 30,
        "the script's commands were taken: {accepted}"
    );
}

/// A trajectory of the gantry (x on the SIXpack, feeder on the QSB-M, lift on the
/// QuadQuad2Drv: the three ways a board follows) with 1024 points, 10 s long.
fn gantry_trajectory(robot: &Robot, id: u64) -> Box<GroupPath> {
    let group = robot
        .engine
        .config()
        .groups
        .iter()
        .position(|g| g.name == "gantry")
        .expect("sim.toml has the gantry");
    let mut path = Box::new(GroupPath::EMPTY);
    path.kind = PathKind::Trajectory as u32;
    path.id = id;
    path.group = group as u32;
    path.axis_count = 3;
    path.point_count = MAX_PATH_POINTS as u32;
    let start: Vec<f64> = ["x", "feeder", "lift"]
        .iter()
        .map(|name| robot.frame.axes[robot.axis(name) as usize].position)
        .collect();
    for point in 0..MAX_PATH_POINTS {
        let time = 0.5 + point as f64 * 0.01;
        path.times[point] = time;
        let phase = (point as f64 / (MAX_PATH_POINTS - 1) as f64) * core::f64::consts::PI;
        for (axis, amplitude) in [10.0, 20.0, 5.0].into_iter().enumerate() {
            path.positions[point * MAX_GROUP_AXES + axis] =
                start[axis] + amplitude * (1.0 - phase.cos()) / 2.0 + 1.0;
        }
    }
    path
}

#[test]
fn a_group_following_a_1024_point_trajectory_allocates_nothing() {
    let mut robot = Robot::new();
    run(&mut robot, 0, 4000, |_| {});
    // Let the script's moves end, then follow a trajectory on three boards.
    for _ in 0..3000 {
        robot.tick();
    }
    let path = gantry_trajectory(&robot, 7);
    let group = path.group;
    robot.port.path = Some(path);
    let mut run_request = CommandRequest::new(ClientId::from_u128(42), 1, group, CommandKind::Run)
        .with_values([7.0, 0.0, 0.0]);
    run_request.target = Target::Group as u32;
    robot.port.requests.push_back(run_request);
    let before = allocations();
    let mut done_at = None;
    for tick in 0..13_000 {
        robot.tick();
        let state = robot.frame.groups[group as usize];
        if tick == 0 {
            let reply = robot.port.replies.last().expect("answered");
            assert_eq!(reply.result(), Ok(()), "{reply:?}");
            assert_eq!(state.motion(), Ok(GroupMotion::Moving));
        }
        if !state.motion().expect("known").active() {
            done_at = Some((tick, state));
            break;
        }
    }
    let allocations = allocations() - before;
    assert_eq!(
        allocations, 0,
        "the engine allocated {allocations} times accepting and following a trajectory"
    );
    let (tick, state) = done_at.expect("the trajectory ended");
    assert_eq!(
        state.motion(),
        Ok(GroupMotion::Done),
        "after {tick} ticks: {state:?}"
    );
}

#[test]
fn same_commands_same_ticks_give_byte_identical_frames() {
    let record = || {
        let mut robot = Robot::new();
        let mut frames: Vec<u8> = Vec::new();
        run(&mut robot, 0, 6000, |robot| {
            let frame = &robot.frame;
            frames.extend_from_slice(&frame.tick.to_le_bytes());
            for axis in frame.axes() {
                for value in [axis.position, axis.velocity, axis.target] {
                    frames.extend_from_slice(&value.to_bits().to_le_bytes());
                }
                frames.extend_from_slice(&axis.raw_counts.to_le_bytes());
                frames.extend_from_slice(&axis.last_refresh_tick.to_le_bytes());
                frames.extend_from_slice(&axis.flags.to_le_bytes());
                frames.extend_from_slice(&[axis.mode, axis.fault as u8]);
            }
            for wire in frame.wire() {
                for value in [wire.goal_tick, wire.wire_tick, wire.wire_ns] {
                    frames.extend_from_slice(&value.to_le_bytes());
                }
            }
        });
        let replies: Vec<(u64, u32, u64)> = robot
            .port
            .replies
            .iter()
            .map(|r| (r.sequence, r.reason, r.tick_applied))
            .collect();
        (frames, replies)
    };
    let first = record();
    let second = record();
    assert_eq!(first.1, second.1, "same replies");
    assert!(
        first.0 == second.0,
        "frames differ between two identical runs"
    );
    // And the robot really moved.
    let mut robot = Robot::new();
    run(&mut robot, 0, 1500, |_| {});
    let index = robot.axis("wheel_left") as usize;
    let wheel = robot.frame.axes()[index];
    assert!(wheel.position > 1.0, "{wheel:?}");
    // Its goal reached the wire, stamped in the frame no earlier than it was set.
    let wire = robot.frame.wire()[index];
    assert!(wire.written(), "{wire:?}");
    assert!(wire.wire_tick >= wire.goal_tick, "{wire:?}");
}

/// A client streaming velocity setpoints to the base (both wheels of the QuadQuad2Drv)
/// every tick for 3 s, every 11th a tick late (sent with the next, a burst of two):
/// nothing allocated, every setpoint applied once, in order, on its own time — the stream
/// a tick behind from the first late one on (issue 39).
#[test]
fn streaming_setpoints_allocates_nothing_and_applies_each_in_its_tick() {
    let mut robot = Robot::new();
    run(&mut robot, 0, 4000, |_| {});
    for _ in 0..3000 {
        robot.tick();
    }
    let group = robot
        .engine
        .config()
        .groups
        .iter()
        .position(|g| g.name == "base")
        .expect("sim.toml has the base") as u32;
    let client = ClientId::from_u128(42);
    for (sequence, kind, value) in [(1, CommandKind::Claim, 0.0), (2, CommandKind::Stream, 2.0)] {
        let mut request =
            CommandRequest::new(client, sequence, group, kind).with_values([value, 0.0, 0.0]);
        request.target = Target::Group as u32;
        robot.port.requests.push_back(request);
        robot.tick();
        let reply = robot.port.replies.last().expect("answered");
        assert_eq!(reply.result(), Ok(()), "{reply:?}");
    }
    let before = allocations();
    let mut setpoint = motion_ipc::Setpoint {
        group,
        mode: motion_ipc::StreamMode::Velocity as u32,
        ..motion_ipc::Setpoint::EMPTY
    };
    let mut held = None;
    for tick in 0..3000_u64 {
        // A sine of ±20 °/s, period 1.5 s, for the next tick.
        let time = tick as f64 / 1000.0;
        let speed = 20.0 * (time * core::f64::consts::TAU / 1.5).sin();
        setpoint.sequence = tick + 1;
        setpoint.for_tick = robot.frame.tick + 1;
        setpoint.values[0] = speed;
        setpoint.values[1] = -speed;
        if let Some(late) = held.take() {
            engine(|| robot.engine.handle_setpoint(client, &late));
        }
        if tick % 11 == 5 {
            held = Some(setpoint);
        } else {
            engine(|| robot.engine.handle_setpoint(client, &setpoint));
        }
        robot.tick();
    }
    // The last one, applied a tick after its own.
    robot.tick();
    let allocations = allocations() - before;
    assert_eq!(
        allocations, 0,
        "the engine allocated {allocations} times streaming"
    );
    let state = robot.frame.groups[group as usize];
    assert_eq!(
        state.stream(),
        Ok(motion_ipc::StreamState::Streaming),
        "{state:?}"
    );
    assert_eq!(
        (state.applied, state.late, state.early, state.refused),
        (3000, 0, 0, 0)
    );
    assert_eq!((state.clamped, state.stream_delay), (0, 1), "{state:?}");
    assert_eq!(state.last_applied_tick, robot.frame.tick);
}

/// The robot after the script's moves, the e-stop and the reset, with every axis at rest.
fn robot_at_rest() -> Robot {
    let mut robot = Robot::new();
    run(&mut robot, 0, 4000, |_| {});
    for _ in 0..3000 {
        robot.tick();
    }
    robot
}

fn group_index(robot: &Robot, name: &str) -> usize {
    robot
        .engine
        .config()
        .groups
        .iter()
        .position(|g| g.name == name)
        .expect("sim.toml has the group")
}

/// Publishes `path` and sends the Run for it.
fn start_path(robot: &mut Robot, path: Box<GroupPath>) {
    let (group, id) = (path.group, path.id);
    robot.port.path = Some(path);
    let mut request = CommandRequest::new(ClientId::from_u128(42), id, group, CommandKind::Run)
        .with_values([id as f64, 0.0, 0.0]);
    request.target = Target::Group as u32;
    robot.port.requests.push_back(request);
}

/// A line of `group` from where its axes are, by `by` (one per axis of `names`).
fn line_by(
    robot: &Robot,
    group: usize,
    names: &[&str],
    by: &[f64],
    id: u64,
) -> (Box<GroupPath>, Vec<f64>) {
    let targets: Vec<f64> = names
        .iter()
        .zip(by)
        .map(|(name, by)| robot.frame.axes[robot.axis(name) as usize].position + by)
        .collect();
    let mut path = Box::new(GroupPath::EMPTY);
    path.set_line(group as u32, id, &targets, (0.0, 0.0));
    (path, targets)
}

/// Ticks until `group`'s motion ends (at most `limit` ticks), calling `each` after every
/// tick with the tick's index; returns the last state and, per axis of `names`, the
/// largest |desired − measured| at its fresh measurements (which includes the
/// measurement's age).
fn watch_group(
    robot: &mut Robot,
    group: usize,
    names: &[&str],
    limit: u64,
    mut each: impl FnMut(&mut Robot, u64),
) -> (GroupState, Vec<f64>) {
    let axes: Vec<usize> = names.iter().map(|name| robot.axis(name) as usize).collect();
    let mut worst = vec![0.0_f64; axes.len()];
    let mut last_refresh = vec![0_u64; axes.len()];
    let mut state = robot.frame.groups[group];
    for tick in 0..limit {
        robot.tick();
        each(robot, tick);
        state = robot.frame.groups[group];
        for (slot, &axis) in axes.iter().enumerate() {
            let a = robot.frame.axes[axis];
            if a.last_refresh_tick != last_refresh[slot] {
                last_refresh[slot] = a.last_refresh_tick;
                worst[slot] = worst[slot].max((a.desired_position - a.position).abs());
            }
        }
        if tick > 0 && !state.motion().expect("known").active() {
            break;
        }
    }
    (state, worst)
}

const GANTRY: [&str; 3] = ["x", "feeder", "lift"];
const ARM: [&str; 6] = ["x", "y", "z", "a", "b", "c"];

/// How closely each board of the gantry follows (printed: the figures of
/// docs/ARCHITECTURE.md "Coordinated motion").
#[test]
fn the_gantry_follows_a_trajectory_on_three_boards() {
    let mut robot = robot_at_rest();
    let path = gantry_trajectory(&robot, 9);
    let group = path.group as usize;
    let started = robot.ring.len();
    start_path(&mut robot, path);
    let (state, worst) = watch_group(&mut robot, group, &GANTRY, 13_000, |_, _| {});
    eprintln!(
        "gantry, 10.7 s trajectory: max |desired - measured| x {:.3} mm, feeder {:.3} mm, lift {:.3} mm",
        worst[0], worst[1], worst[2]
    );
    assert_eq!(state.motion(), Ok(GroupMotion::Done), "{state:?}");
    for name in GANTRY {
        let a = robot.frame.axes[robot.axis(name) as usize];
        assert_eq!(a.mode(), Ok(motion_ipc::AxisMode::Hold), "{a:?}");
        assert_eq!(a.fault, 0, "{a:?}");
    }

    // The black box of a ring that wrapped 2.5 s into the trajectory replays from the
    // snapshot taken mid-trajectory (the path's segments, the group's history, the
    // drivers' queues in it), every later snapshot equal to the replayed state.
    let recording = Recording::of(&robot.ring.ticks());
    let wrapped = blackbox::dropped(&recording, started + 2500);
    let replayed = replay(&robot.config, &wrapped).expect("the same frames from mid-trajectory");
    let first_snapshot = (started as u64 + 2500).div_ceil(SNAPSHOT_EVERY) * SNAPSHOT_EVERY;
    assert_eq!(replayed.first, first_snapshot);
    assert_eq!(
        replayed.ticks,
        recording.ticks.len() as u64 - first_snapshot
    );
}

/// The gantry's line of the README (x +200 mm, feeder +100 mm, lift +150 mm: the lift's
/// 10 mm/s sets the pace), printing how far each axis was from the path at its fresh
/// measurements (docs/ARCHITECTURE.md "Coordinated motion"). x runs the line as the
/// SIXpack's own ramp; the feeder's 6.7 mm/s is 4.5 % off the QSB-M's 16 steps/s
/// increments, so it follows by velocities; the lift by segments; nothing of it allocates
/// in the engine.
#[test]
fn the_gantry_moves_a_line_on_three_boards() {
    let mut robot = robot_at_rest();
    let group = group_index(&robot, "gantry");
    let (path, targets) = line_by(&robot, group, &GANTRY, &[200.0, 100.0, 150.0], 3);
    start_path(&mut robot, path);
    let before = allocations();
    let (state, worst) = watch_group(&mut robot, group, &GANTRY, 20_000, |_, _| {});
    let allocations = allocations() - before;
    eprintln!(
        "gantry line: max |desired - measured| x {:.3} mm, feeder {:.3} mm, lift {:.3} mm",
        worst[0], worst[1], worst[2]
    );
    assert_eq!(allocations, 0, "the engine allocated running a line");
    assert_eq!(state.motion(), Ok(GroupMotion::Done), "{state:?}");
    for (slot, name) in GANTRY.iter().enumerate() {
        let position = robot.frame.axes[robot.axis(name) as usize].position;
        assert!((position - targets[slot]).abs() < 0.1, "{name}: {position}");
    }
}

/// A hold of the gantry's line one second in: the QSB-M pauses its own move (COMMAND 6)
/// and resumes it (COMMAND 7), the others hold along the path; the line ends at its
/// targets. The lift's 46.875 mm sets the pace so that the feeder's 30 mm run at exactly
/// 64 steps/s and 640 steps/s², which the QSB-M represents (its own move; at 0.017 mm
/// from the path in this run).
#[test]
fn the_gantry_holds_and_resumes_a_line() {
    let mut robot = robot_at_rest();
    let group = group_index(&robot, "gantry");
    let (path, targets) = line_by(&robot, group, &GANTRY, &[60.0, 30.0, 46.875], 4);
    start_path(&mut robot, path);
    let command = |robot: &mut Robot, kind: CommandKind, sequence: u64| {
        let mut request =
            CommandRequest::new(ClientId::from_u128(42), sequence, group as u32, kind);
        request.target = Target::Group as u32;
        robot.port.requests.push_back(request);
    };
    let mut held_at = None;
    let (state, worst) = watch_group(&mut robot, group, &GANTRY, 30_000, |robot, tick| {
        let motion = robot.frame.groups[group].motion();
        if tick == 1000 {
            command(robot, CommandKind::Hold, 10);
        }
        if held_at.is_none() && motion == Ok(GroupMotion::Held) {
            held_at = Some(tick);
        }
        if held_at.is_some_and(|at| tick == at + 500) {
            command(robot, CommandKind::Resume, 11);
        }
    });
    eprintln!(
        "gantry line held and resumed: max |desired - measured| x {:.3} mm, feeder {:.3} mm, lift {:.3} mm",
        worst[0], worst[1], worst[2]
    );
    assert!(held_at.is_some(), "{state:?}");
    assert_eq!(state.motion(), Ok(GroupMotion::Done), "{state:?}");
    for (slot, name) in GANTRY.iter().enumerate() {
        let position = robot.frame.axes[robot.axis(name) as usize].position;
        assert!((position - targets[slot]).abs() < 0.1, "{name}: {position}");
    }
}

/// A line of the six axes of the SIXpack: the pack's own linear interpolation (`$26` per
/// motor, then one `$50`), started with the path.
#[test]
fn the_arm_moves_a_line_with_the_packs_interpolation() {
    let mut robot = robot_at_rest();
    let group = group_index(&robot, "arm");
    let (path, targets) = line_by(
        &robot,
        group,
        &ARM,
        &[30.0, 20.0, -10.0, 45.0, -30.0, 90.0],
        5,
    );
    start_path(&mut robot, path);
    let (state, worst) = watch_group(&mut robot, group, &ARM, 30_000, |_, _| {});
    eprintln!(
        "arm line: max |desired - measured| x {:.3} mm, y {:.3} mm, z {:.3} mm, a {:.3}°, b {:.3}°, c {:.3}°",
        worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]
    );
    assert_eq!(state.motion(), Ok(GroupMotion::Done), "{state:?}");
    for (slot, name) in ARM.iter().enumerate() {
        let position = robot.frame.axes[robot.axis(name) as usize].position;
        assert!((position - targets[slot]).abs() < 0.3, "{name}: {position}");
    }
}

/// An e-stop while the SIXpack runs the arm's line by its own interpolation (`$50`):
/// every motor of it stops (its `$25` 0 at the e-stop's rate, manual 8.4 "The change to
/// rotation happens immediately, even if the motor is still active"), the group aborts.
#[test]
fn an_estop_stops_the_packs_interpolation() {
    let mut robot = robot_at_rest();
    let group = group_index(&robot, "arm");
    let (path, _) = line_by(
        &robot,
        group,
        &ARM,
        &[60.0, 40.0, -20.0, 90.0, -60.0, 150.0],
        6,
    );
    start_path(&mut robot, path);
    let mut stopped_at = None;
    let (state, _) = watch_group(&mut robot, group, &ARM, 10_000, |robot, tick| {
        if tick == 400 {
            let estop = CommandRequest::new(ClientId::from_u128(42), 20, 0, CommandKind::EStop);
            robot.port.requests.push_back(estop);
        }
    });
    assert_eq!(state.motion(), Ok(GroupMotion::Aborted), "{state:?}");
    assert_eq!(
        state.abort(),
        Ok(motion_ipc::GroupAbort::EStop),
        "{state:?}"
    );
    for tick in 0..3000 {
        robot.tick();
        let still = ARM.iter().all(|name| {
            let a = robot.frame.axes[robot.axis(name) as usize];
            a.velocity == 0.0 && a.flags & AxisFlags::MOVING.0 == 0
        });
        if still {
            stopped_at = Some(tick);
            break;
        }
    }
    assert!(
        stopped_at.is_some(),
        "the arm's axes came to rest after the e-stop"
    );
    let after: Vec<f64> = ARM
        .iter()
        .map(|name| robot.frame.axes[robot.axis(name) as usize].position)
        .collect();
    for _ in 0..500 {
        robot.tick();
    }
    for (slot, name) in ARM.iter().enumerate() {
        let position = robot.frame.axes[robot.axis(name) as usize].position;
        assert_eq!(position, after[slot], "{name} moved after it came to rest");
    }
}
