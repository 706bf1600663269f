//! The group features at the boards' real pace (issue 39 item 5): a gantry of three boards
//! on three links — x on a SIXpack at 19200 baud (RS-485, with the pack's switch-over at
//! the factory 6 ms and at 2 ms, manual 6.1 `$40`), feeder on a QSB-M (USB serial at
//! 230400, its encoder streamed at INTERVAL RATE 1.95 ms, "QSB Command List" 1.28) and lift
//! on a QuadQuad2Drv (SPI at 500 kHz, its 500 Hz loop) — stepped as motiond's loop does on
//! a fake clock, every simulated board keeping its datasheet's timing. Each feature runs 20
//! times in a row on each switch-over: a line, a trajectory, a hold and a resume, a cancel
//! and a position stream; each ends `done` with every axis within its `goal_tolerance` (a
//! cancel at rest with its reason), no board declared reset or not answering, no axis
//! faulted.

use core::time::Duration;

use motion_config::ServerConfig;
use motion_drivers::Driver;
use motion_engine::{CommandPort, Engine};
use motion_ipc::{
    AxisFlags, AxisMode, ClientId, CommandKind, CommandReply, CommandRequest, DeviceState,
    GroupAbort, GroupMotion, GroupPath, GroupState, MAX_GROUP_AXES, MotionFrame, PathKind, Reason,
    Setpoint, StreamMode, StreamState, Target,
};
use motion_link::Link;

const CLIENT: ClientId = ClientId::from_u128(42);
/// Repetitions of each feature.
const REPEATS: usize = 20;
/// The gantry's axes, in its order.
const AXES: [&str; 3] = ["x", "feeder", "lift"];
/// Their goal tolerances (the config below).
const GOAL_TOLERANCE: [f64; 3] = [0.01, 0.1, 0.02];

/// The three boards of `config/sim.toml`'s gantry, with the pack's switch-over `switchover`
/// ms.
fn config(switchover_ms: u32) -> ServerConfig {
    let text = format!(
        r#"
[server]
name = "pace"
tick_hz = 1000

[[link]]
name = "rs485"
type = "sim"
baud = 19200

[[device]]
name = "pack"
link = "rs485"
model = "tmcpack"
address = 1
variant = "sixpack"
switchover_ms = {switchover_ms}
sim = {{ seed = 21 }}

[[axis]]
name = "x"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 640.0
min = 0.0
max = 400.0
max_velocity = 50.0
max_accel = 250.0
current = {{ peak = 100.0, standstill = 50.0 }}

[[link]]
name = "usb0"
type = "sim"
baud = 230400

[[device]]
name = "feeder_qsb"
link = "usb0"
model = "qsb"
counts_per_step = 10.0
sim = {{ seed = 41 }}

[[axis]]
name = "feeder"
device = "feeder_qsb"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -1000.0
max = 1000.0
max_velocity = 100.0
max_accel = 1000.0

[[link]]
name = "spi0"
type = "sim"
speed_hz = 500000

[[device]]
name = "drive"
link = "spi0"
model = "qq2drv"
sim = {{ seed = 11 }}

[[axis]]
name = "lift"
device = "drive"
channel = 2
unit = "mm"
counts_per_unit = 400.0
min = 0.0
max = 300.0
max_velocity = 10.0
max_accel = 100.0

[[group]]
name = "gantry"
axes = ["x", "feeder", "lift"]
stream_buffer = 5
[group.path_tolerance]
x = 5.0
feeder = 1.0
lift = 2.0
[group.goal_tolerance]
x = {x}
feeder = {feeder}
lift = {lift}
"#,
        x = GOAL_TOLERANCE[0],
        feeder = GOAL_TOLERANCE[1],
        lift = GOAL_TOLERANCE[2],
    );
    ServerConfig::parse(std::path::Path::new("pace.toml"), &text).expect("a valid config")
}

struct Port {
    requests: std::collections::VecDeque<CommandRequest>,
    replies: Vec<CommandReply>,
    path: Option<Box<GroupPath>>,
}

impl CommandPort for Port {
    fn next_request(&mut self) -> Option<CommandRequest> {
        self.requests.pop_front()
    }
    fn reply(&mut self, reply: CommandReply) {
        self.replies.push(reply);
    }
    fn take_path(&mut self, _: ClientId, id: u64) -> Option<&GroupPath> {
        self.path.as_deref().filter(|path| path.id == id)
    }
}

/// The engine, its drivers and the simulated links, stepped as motiond's loop does.
struct Gantry {
    engine: Engine<motion_config::boards::AnyDriver>,
    links: Vec<Box<dyn Link>>,
    frame: Box<MotionFrame>,
    port: Port,
    now: Duration,
    period: Duration,
    sequence: u64,
    axes: [usize; 3],
}

impl Gantry {
    fn new(switchover_ms: u32) -> Self {
        let config = config(switchover_ms);
        let drivers = motion_config::boards::build(&config).expect("drivers");
        let mut engine = Engine::new(config.engine_config(), drivers).expect("engine");
        engine.stamp_links();
        let links = (0..config.links.len())
            .map(|index| Box::new(motion_config::boards::sim_link(&config, index)) as Box<dyn Link>)
            .collect();
        let axes = AXES.map(|name| {
            config
                .axes
                .iter()
                .position(|a| a.name == name)
                .expect("axis")
        });
        let period = engine.config().period();
        let mut gantry = Self {
            engine,
            links,
            frame: Box::new(MotionFrame::EMPTY),
            port: Port {
                requests: Default::default(),
                replies: Vec::new(),
                path: None,
            },
            now: Duration::ZERO,
            period,
            sequence: 0,
            axes,
        };
        gantry.until("every board online", 5000, |g| {
            (0..3).all(|device| g.frame.devices[device] == DeviceState::Online as u8)
        });
        gantry
    }

    fn tick(&mut self) {
        let now = self.now;
        let mut buf = [0u8; 512];
        for (index, link) in self.links.iter_mut().enumerate() {
            while let Ok(len) = link.read(now, &mut buf) {
                if len == 0 {
                    break;
                }
                self.engine.handle_link_rx(index, now, now, &buf[..len]);
            }
            self.engine.link_heard(index, now);
        }
        self.engine.step(now, &mut self.port, &mut self.frame);
        for (index, link) in self.links.iter_mut().enumerate() {
            while let Some(len) = self.engine.poll_link_transmit(index, now, &mut buf) {
                if let Some(baud) = self.engine.take_link_rate(index) {
                    link.set_baud(now, baud).expect("sim link rate");
                }
                link.write(now, &buf[..len]).expect("sim link write");
                self.engine.link_written(index, now);
            }
        }
        self.now += self.period;
        self.check_boards();
    }

    /// No board declared reset or not answering, no axis faulted, at any tick.
    fn check_boards(&self) {
        for device in 0..3 {
            let status = self.engine.driver(device).expect("driver").status();
            assert_eq!(
                status.verdicts, 0,
                "device {device} at {:?}: {:?}",
                self.now, status.verdict
            );
        }
        for &axis in &self.axes {
            let state = self.frame.axes[axis];
            assert_eq!(
                state.fault, 0,
                "axis {axis} faulted at {:?}: {state:?}",
                self.now
            );
        }
    }

    /// Ticks until `done` holds, at most `limit` ticks.
    fn until(&mut self, what: &str, limit: u64, done: impl Fn(&Self) -> bool) {
        for _ in 0..limit {
            self.tick();
            if done(self) {
                return;
            }
        }
        panic!(
            "{what}: not within {limit} ticks (at {:?}; group {:?})",
            self.now, self.frame.groups[0]
        );
    }

    fn group(&self) -> GroupState {
        self.frame.groups[0]
    }

    fn positions(&self) -> [f64; 3] {
        self.axes.map(|axis| self.frame.axes[axis].position)
    }

    /// Sends a group command; the reply must accept it. A motion refused `GroupBusy` (a
    /// member's own controller still settling from the last one: the QuadQuad2Drv's PID
    /// corrects a count or two after its hold) is sent again, as a client would, for at
    /// most 500 ticks.
    fn command(&mut self, kind: CommandKind, value: f64) {
        for _ in 0..500 {
            self.sequence += 1;
            let mut request =
                CommandRequest::new(CLIENT, self.sequence, 0, kind).with_values([value, 0.0, 0.0]);
            request.target = Target::Group as u32;
            self.port.requests.push_back(request);
            let replies = self.port.replies.len();
            self.tick();
            let reply = self.port.replies[replies..]
                .iter()
                .find(|reply| reply.sequence == self.sequence)
                .copied()
                .expect("answered in its tick");
            if reply.result() == Err(Reason::GroupBusy) {
                continue;
            }
            assert_eq!(
                reply.result(),
                Ok(()),
                "{kind:?}: {reply:?}; axes {:?}",
                self.axes.map(|axis| self.frame.axes[axis])
            );
            return;
        }
        panic!("{kind:?}: refused GroupBusy for 500 ticks");
    }

    /// Publishes `path` and runs it.
    fn run(&mut self, path: Box<GroupPath>) {
        let id = path.id;
        self.port.path = Some(path);
        self.command(CommandKind::Run, id as f64);
    }

    fn line(&mut self, targets: [f64; 3]) {
        let mut path = Box::new(GroupPath::EMPTY);
        path.set_line(0, self.sequence + 1000, &targets, (0.0, 0.0));
        self.run(path);
    }

    /// A trajectory through three points from where the axes are, by `by`, back halfway,
    /// and to `by` again, 0.6 s apart.
    fn trajectory(&mut self, by: [f64; 3]) -> [f64; 3] {
        let start = self.positions();
        let mut path = Box::new(GroupPath::EMPTY);
        path.kind = PathKind::Trajectory as u32;
        path.id = self.sequence + 1000;
        path.group = 0;
        path.axis_count = 3;
        path.point_count = 3;
        for (point, share) in [1.0, 0.5, 1.0].into_iter().enumerate() {
            path.times[point] = 0.8 + 0.6 * point as f64;
            for axis in 0..3 {
                path.positions[point * MAX_GROUP_AXES + axis] = start[axis] + by[axis] * share;
            }
        }
        let end = [0, 1, 2].map(|axis| start[axis] + by[axis]);
        self.run(path);
        end
    }

    /// Waits for the motion to end `done`, then checks every axis within its goal
    /// tolerance of `targets`.
    fn finish(&mut self, what: &str, targets: [f64; 3]) {
        self.until(what, 20_000, |g| {
            !g.group().motion().is_ok_and(|m| m.active())
        });
        let state = self.group();
        assert_eq!(state.motion(), Ok(GroupMotion::Done), "{what}: {state:?}");
        self.at_rest_within(what, targets);
    }

    fn at_rest_within(&mut self, what: &str, targets: [f64; 3]) {
        // Holding, and at rest (a board's own controller may settle a little after the
        // group's end): as a client waits before its next motion.
        self.until(what, 2000, |g| {
            g.axes.iter().all(|&axis| {
                let state = g.frame.axes[axis];
                state.mode() == Ok(AxisMode::Hold) && !state.flags().contains(AxisFlags::MOVING)
            })
        });
        let positions = self.positions();
        for axis in 0..3 {
            assert!(
                (positions[axis] - targets[axis]).abs() <= GOAL_TOLERANCE[axis],
                "{what}: {} at {} for {} (goal tolerance {})",
                AXES[axis],
                positions[axis],
                targets[axis],
                GOAL_TOLERANCE[axis]
            );
        }
    }
}

/// A line out and back, 20 times.
fn lines(gantry: &mut Gantry) {
    let home = gantry.positions();
    for repeat in 0..REPEATS {
        let out = repeat % 2 == 0;
        let targets = if out {
            [home[0] + 8.0, home[1] + 12.0, home[2] + 4.0]
        } else {
            home
        };
        gantry.line(targets);
        gantry.finish(&format!("line {repeat}"), targets);
    }
}

/// A trajectory out and one back, 20 times.
fn trajectories(gantry: &mut Gantry) {
    for repeat in 0..REPEATS {
        let sign = if repeat % 2 == 0 { 1.0 } else { -1.0 };
        let end = gantry.trajectory([6.0 * sign, 10.0 * sign, 2.0 * sign]);
        gantry.finish(&format!("trajectory {repeat}"), end);
    }
}

/// A line held a third of the way, resumed once at rest on the path, 20 times.
fn holds(gantry: &mut Gantry) {
    let home = gantry.positions();
    for repeat in 0..REPEATS {
        let targets = if repeat % 2 == 0 {
            [home[0] + 10.0, home[1] + 15.0, home[2] + 5.0]
        } else {
            home
        };
        gantry.line(targets);
        gantry.until("a third of the way", 10_000, |g| {
            let s = g.group();
            s.duration > 0.0 && s.time > s.duration / 3.0
        });
        gantry.command(CommandKind::Hold, 0.0);
        gantry.until(&format!("held {repeat}"), 10_000, |g| {
            g.group().motion() == Ok(GroupMotion::Held)
        });
        gantry.command(CommandKind::Resume, 0.0);
        gantry.finish(&format!("hold and resume {repeat}"), targets);
    }
}

/// A line cancelled halfway: it comes to rest on the path and ends `cancelled`; then a line
/// from there ends `done`. 20 times.
fn cancels(gantry: &mut Gantry) {
    let home = gantry.positions();
    for repeat in 0..REPEATS {
        gantry.line([home[0] + 10.0, home[1] + 15.0, home[2] + 5.0]);
        gantry.until("halfway", 10_000, |g| {
            let s = g.group();
            s.duration > 0.0 && s.time > s.duration / 2.0
        });
        gantry.command(CommandKind::Cancel, 0.0);
        gantry.until(&format!("cancelled {repeat}"), 10_000, |g| {
            g.group().motion() == Ok(GroupMotion::Aborted)
        });
        assert_eq!(gantry.group().abort(), Ok(GroupAbort::Cancelled));
        gantry.until(&format!("at rest after cancel {repeat}"), 3000, |g| {
            g.axes
                .iter()
                .all(|&axis| g.frame.axes[axis].mode() == Ok(AxisMode::Hold))
        });
        gantry.line(home);
        gantry.finish(&format!("back after cancel {repeat}"), home);
    }
}

/// A position stream (half a cosine, from rest to rest in 0.6 s, a setpoint per tick sent a
/// tick ahead), then a cancel: the stream ends idle and the group finishes on the last
/// setpoint, `done` with every axis there within its goal tolerance. 20 times.
fn streams(gantry: &mut Gantry) {
    let amplitude = [4.0, 6.0, 2.0];
    let omega = core::f64::consts::TAU / 1.2;
    for repeat in 0..REPEATS {
        gantry.command(CommandKind::Claim, 0.0);
        gantry.command(CommandKind::Stream, f64::from(StreamMode::Position as u32));
        let start = gantry.positions();
        let first = gantry.frame.tick + 1;
        let mut last = start;
        for k in 0..=600_u64 {
            let t = k as f64 / 1000.0;
            let mut setpoint = Setpoint {
                group: 0,
                sequence: k + 1,
                for_tick: first + k,
                mode: StreamMode::Position as u32,
                ..Setpoint::EMPTY
            };
            for axis in 0..3 {
                last[axis] = start[axis] + amplitude[axis] * (1.0 - (omega * t).cos()) / 2.0;
                setpoint.values[axis] = last[axis];
            }
            gantry.engine.handle_setpoint(CLIENT, &setpoint);
            gantry.tick();
        }
        let state = gantry.group();
        assert_eq!(
            state.stream(),
            Ok(StreamState::Streaming),
            "stream {repeat}: {state:?}"
        );
        assert_eq!(
            (state.applied, state.late, state.clamped),
            (601, 0, 0),
            "stream {repeat}: {state:?}"
        );
        gantry.command(CommandKind::Cancel, 0.0);
        let state = gantry.group();
        assert_eq!(
            state.stream(),
            Ok(StreamState::Idle),
            "stream {repeat}: {state:?}"
        );
        gantry.finish(&format!("stream {repeat}"), last);
        gantry.command(CommandKind::Release, 0.0);
    }
}

fn every_feature(switchover_ms: u32) {
    let mut gantry = Gantry::new(switchover_ms);
    // Away from the soft limits first (x and lift start at their minimum).
    gantry.line([20.0, 0.0, 20.0]);
    gantry.finish("to the middle", [20.0, 0.0, 20.0]);
    lines(&mut gantry);
    trajectories(&mut gantry);
    cancels(&mut gantry);
    streams(&mut gantry);
}

#[test]
fn every_group_feature_20_times_with_the_factory_switchover() {
    every_feature(6);
}

/// Holds and resumes, 20 times on each switch-over.
#[test]
fn holds_and_resumes_20_times_on_both_switchovers() {
    for switchover in [6, 2] {
        let mut gantry = Gantry::new(switchover);
        gantry.line([20.0, 0.0, 20.0]);
        gantry.finish("to the middle", [20.0, 0.0, 20.0]);
        holds(&mut gantry);
    }
}

#[test]
fn every_group_feature_20_times_with_a_2_ms_switchover() {
    every_feature(2);
}
