//! The AS-2 end to end through motiond, in one process with a fake clock: a config with an
//! `example` device on a `type = "sim"` link is validated by motiond's validator, its
//! driver is built and its simulated link served through the board registry
//! (`motion_config::boards`), and commands go through the engine as a client's would. A
//! counting allocator checks that the engine and the AS-2 driver allocate nothing once
//! running.

use core::time::Duration;
use std::cell::Cell;
use std::path::Path;

use motion_config::ServerConfig;
use motion_drivers::Driver as _;
use motion_engine::{CommandPort, Engine};
use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandReply, CommandRequest, DeviceModel, MotionFrame,
    ServerInfo,
};
use motion_link::Link;
use motion_link::sim::SimFaults;

const CONFIG: &str = r#"
[server]
name = "example-e2e"

[[link]]
name = "as2"
type = "sim"

[[device]]
name = "stage"
link = "as2"
model = "example"

[[axis]]
name = "x"
device = "stage"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 50.0
max_accel = 500.0
position_tolerance = 0.02
"#;

// The workspace's counting allocator (per thread), shared with the engine tests.
#[path = "support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

thread_local! {
    /// Allocations inside [`counted`] so far.
    static COUNTED: Cell<u64> = const { Cell::new(0) };
}

/// Runs `work` (the engine and its driver; not the simulated link), adding its
/// allocations to [`COUNTED`].
fn counted<T>(work: impl FnOnce() -> T) -> T {
    let before = allocations();
    let result = work();
    let made = allocations() - before;
    COUNTED.with(|count| count.set(count.get() + made));
    result
}

#[derive(Default)]
struct Queue {
    requests: Vec<CommandRequest>,
    replies: Vec<CommandReply>,
}

impl CommandPort for Queue {
    fn next_request(&mut self) -> Option<CommandRequest> {
        self.requests.pop()
    }
    fn reply(&mut self, reply: CommandReply) {
        self.replies.push(reply);
    }
}

/// motiond's loop, minus the threads: links read, the engine stepped, links written.
struct Server {
    engine: Engine<motion_config::boards::AnyDriver>,
    link: Box<dyn Link>,
    faults: SimFaults,
    frame: Box<MotionFrame>,
    port: Queue,
    now: Duration,
    period: Duration,
    sequence: u64,
}

impl Server {
    fn start() -> Self {
        let config = ServerConfig::parse(Path::new("example.toml"), CONFIG)
            .unwrap_or_else(|error| panic!("the example config validates: {error}"));
        let drivers = motion_config::boards::build(&config).expect("the example driver builds");
        let mut engine = Engine::new(config.engine_config(), drivers).expect("engine");
        engine.stamp_links();
        let link = motion_config::boards::sim_link(&config, 0);
        let faults = link.faults();
        let period = engine.config().period();
        Self {
            engine,
            link: Box::new(link),
            faults,
            frame: Box::new(MotionFrame::EMPTY),
            port: Queue::default(),
            now: Duration::ZERO,
            period,
            sequence: 0,
        }
    }

    fn tick(&mut self) {
        let now = self.now;
        let mut buf = [0u8; 512];
        while let Ok(len) = self.link.read(now, &mut buf) {
            if len == 0 {
                break;
            }
            counted(|| self.engine.handle_link_rx(0, now, now, &buf[..len]));
        }
        counted(|| self.engine.link_heard(0, now));
        counted(|| self.engine.step(now, &mut self.port, &mut self.frame));
        while let Some(len) = counted(|| self.engine.poll_link_transmit(0, now, &mut buf)) {
            self.link.write(now, &buf[..len]).expect("sim link write");
            counted(|| self.engine.link_written(0, now));
        }
        self.now += self.period;
    }

    fn run_for(&mut self, time: Duration) {
        let end = self.now + time;
        while self.now < end {
            self.tick();
        }
    }

    /// Sends a command and returns the engine's answer.
    fn command(&mut self, kind: CommandKind, values: [f64; 3]) -> CommandReply {
        self.sequence += 1;
        let request =
            CommandRequest::new(ClientId::from_u128(7), self.sequence, 0, kind).with_values(values);
        self.port.requests.push(request);
        self.tick();
        let reply = self
            .port
            .replies
            .pop()
            .expect("the engine answers every command");
        assert_eq!(reply.sequence, self.sequence);
        reply
    }

    fn axis(&self) -> motion_ipc::AxisState {
        self.frame.axes()[0]
    }
}

#[test]
fn the_example_board_runs_end_to_end_on_its_simulator() {
    let mut server = Server::start();

    // Start-up: identify, then polled; the axis is fresh and unfaulted.
    server.run_for(Duration::from_millis(100));
    let axis = server.axis();
    assert!(!axis.flags().contains(AxisFlags::STALE), "{axis:?}");
    assert!(!axis.flags().contains(AxisFlags::FAULT), "{axis:?}");

    // A move reaches its target within the axis's tolerance: 20 mm at 50 mm/s, 500 mm/s².
    let reply = server.command(CommandKind::RampPosition, [20.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    server.run_for(Duration::from_millis(200));
    assert!(server.axis().flags().contains(AxisFlags::MOVING));
    server.run_for(Duration::from_millis(800));
    let arrived = server.axis();
    assert!((arrived.position - 20.0).abs() <= 0.02, "{arrived:?}");
    assert!(arrived.flags().contains(AxisFlags::ARRIVED), "{arrived:?}");
    assert!(!arrived.flags().contains(AxisFlags::MOVING), "{arrived:?}");

    // A velocity goal moves, a stop stops.
    let reply = server.command(CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    server.run_for(Duration::from_millis(100));
    let jogging = server.axis();
    assert!(jogging.position < 19.5, "{jogging:?}");
    assert!((jogging.velocity + 10.0).abs() < 0.5, "{jogging:?}");
    let reply = server.command(CommandKind::Stop, [0.0; 3]);
    assert_eq!(reply.result(), Ok(()));
    server.run_for(Duration::from_millis(200));
    let stopped = server.axis();
    server.run_for(Duration::from_millis(100));
    assert_eq!(stopped.velocity, 0.0, "{stopped:?}");
    assert_eq!(server.axis().position, stopped.position, "it stays stopped");

    // Garbage on the wire: counted and dropped by the driver, no panic, no fault.
    for noise in [
        &b"\xff\xfe\x00garbage\r"[..],
        b"P0 99999 0 I\r",
        b"\r\r\r\x7f",
    ] {
        server.faults.inject_garbage(noise);
        server.run_for(Duration::from_millis(20));
    }
    server.faults.inject_noise(500);
    server.run_for(Duration::from_millis(200));
    let after = server.axis();
    assert!(!after.flags().contains(AxisFlags::STALE), "{after:?}");
    assert_eq!(
        after.position, stopped.position,
        "noise moved nothing: {after:?}"
    );

    // And it still takes goals afterwards.
    let reply = server.command(CommandKind::RampPosition, [0.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    server.run_for(Duration::from_millis(1000));
    let home = server.axis();
    assert!(home.position.abs() <= 0.02, "{home:?}");
    assert!(!home.flags().contains(AxisFlags::FAULT), "{home:?}");
}

/// Issue 39 item 4: the board's replies held up on the host (`SimFaults::hold`: a
/// starved server or board process) for 50, 100, 200 ms during a move are waited for — no
/// verdict, no timeout, no fault — and the move arrives.
#[test]
fn a_held_link_during_a_move_is_no_verdict_and_the_move_arrives() {
    for hold in [50, 100, 200] {
        let mut server = Server::start();
        server.run_for(Duration::from_millis(100));
        let reply = server.command(CommandKind::RampPosition, [20.0, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()));
        server.run_for(Duration::from_millis(150));
        server.faults.hold(server.now, Duration::from_millis(hold));
        let end = server.now + Duration::from_secs(2);
        while !server.axis().flags().contains(AxisFlags::ARRIVED) {
            assert!(server.now < end, "hold {hold} ms: {:?}", server.axis());
            server.tick();
            assert!(
                !server.axis().flags().contains(AxisFlags::FAULT),
                "hold {hold} ms: {:?}",
                server.axis()
            );
        }
        assert!((server.axis().position - 20.0).abs() <= 0.02);
        let status = server.engine.driver(0).expect("driver").status();
        assert_eq!(
            (status.verdicts, status.timeouts, status.resets),
            (0, 0, 0),
            "hold {hold} ms: {:?}",
            status.verdict
        );
    }
}

#[test]
fn the_engine_and_the_example_driver_allocate_nothing_once_running() {
    let mut server = Server::start();
    server.port.replies.reserve(16);
    server.run_for(Duration::from_millis(100));
    let before = COUNTED.with(Cell::get);
    // Polls, a move, a jog and a stop: the driver's every per-step path.
    let reply = server.command(CommandKind::RampPosition, [-5.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    server.run_for(Duration::from_millis(500));
    assert_eq!(
        server
            .command(CommandKind::Velocity, [3.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    server.run_for(Duration::from_millis(100));
    assert_eq!(server.command(CommandKind::Stop, [0.0; 3]).result(), Ok(()));
    server.run_for(Duration::from_millis(300));
    let allocations = COUNTED.with(Cell::get) - before;
    assert_eq!(
        allocations, 0,
        "the engine and the driver allocated {allocations} times"
    );
}

#[test]
fn motiond_describes_the_example_axis_with_its_limits_in_steps() {
    let config = ServerConfig::parse(Path::new("example.toml"), CONFIG).expect("valid");
    let rows = motion_config::boards::describe(&config);
    let values: Vec<(&str, &str)> = rows
        .iter()
        .map(|row| (row.key.as_str(), row.value.as_str()))
        .collect();
    assert!(
        values.contains(&("max_velocity", "5000 steps/s (M speed)")),
        "{values:?}"
    );
    assert!(
        values.contains(&("max_accel", "50000 steps/s² (M accel)")),
        "{values:?}"
    );
    // A limit the board cannot run is refused with the axis's key.
    let fast = CONFIG.replace("max_velocity = 50.0", "max_velocity = 600.0");
    let config = ServerConfig::parse(Path::new("example.toml"), &fast).expect("valid");
    let error = motion_config::boards::build(&config).expect_err("60 000 steps/s is too fast");
    assert!(error.key.contains("max_velocity"), "{error}");
}

#[test]
fn the_server_info_names_the_example_model_by_its_id() {
    let server = Server::start();
    let mut info = Box::new(ServerInfo::EMPTY);
    server.engine.fill_info(&mut info);
    let stage = &info.devices()[0];
    assert_eq!(stage.name(), "stage");
    assert_eq!(stage.model_id(), "example");
    assert_eq!(stage.model_name(), "example");
    // A client built with only the built-in boards has no `DeviceModel` for its code.
    assert!(stage.model().is_err(), "code {}", stage.model);
    assert!(
        DeviceModel::BUILT_IN
            .iter()
            .all(|m| m.code() != stage.model)
    );
}
