//! One rulebook: the same table of requests, from the same two clients, goes to the engine
//! (over a queue port that reports the sender as the transport would) and to the fake server
//! of `motion_client::testing` (over iceoryx2, identity from the sending node), with the same
//! machine and the same changes of state between requests (a device starting, a board fault,
//! the e-stop, the shutdown). Every answer must be the same reason on both.
//!
//! Both judge through `motion_ipc::rules`; this test catches a side that stops doing so, or
//! one that carries a verdict out differently (a reset that ends claims, an off-all that
//! skips differently), which the next request then shows.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use iceoryx2::prelude::*;
use motion_client::testing::{
    FakeAxis, FakeConfig, FakeDevice, FakeGroup, FakeServer, FakeSignal, unique_name,
};
use motion_drivers::{DeviceFault, GoalKind, LinkKind, Pin, RateFloor, SignalKind as PinKind};
use motion_engine::{
    AxisConfig, BusConfig, CommandPort, DeviceConfig, Engine, EngineConfig, GroupConfig,
    SignalConfig, StreamLimit,
};
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, DeviceModel, DeviceState, FaultCode,
    MotionFrame, Reason, ServerInfo, ServiceNames, SignalKind, StreamMode, Target,
};
use support::{BoardControl, IdealBoard};

/// A queue port that reports a transport identity for each request.
#[derive(Default)]
struct Port {
    pending: Option<(CommandRequest, ClientId)>,
    sender: Option<ClientId>,
    reply: Option<CommandReply>,
}

impl CommandPort for Port {
    fn next_request(&mut self) -> Option<CommandRequest> {
        let (request, sender) = self.pending.take()?;
        self.sender = Some(sender);
        Some(request)
    }
    fn reply(&mut self, reply: CommandReply) {
        self.reply = Some(reply);
    }
    fn sender(&self) -> Option<ClientId> {
        self.sender
    }
}

struct EngineSide {
    engine: Engine,
    boards: Vec<Arc<Mutex<BoardControl>>>,
    port: Port,
    frame: Box<MotionFrame>,
    now: Duration,
}

impl EngineSide {
    fn tick(&mut self) {
        self.engine.step(self.now, &mut self.port, &mut self.frame);
        let mut buf = [0u8; 256];
        for link in 0..self.engine.config().links.len() {
            while self
                .engine
                .poll_link_transmit(link, self.now, &mut buf)
                .is_some()
            {}
        }
        self.now += Duration::from_millis(1);
    }

    fn send(&mut self, request: CommandRequest, sender: ClientId) -> Reason {
        self.port.pending = Some((request, sender));
        self.tick();
        let reply = self.port.reply.take().expect("answered in the tick");
        Reason::try_from(reply.reason).expect("a known reason")
    }
}

/// A raw iceoryx2 client of the fake: its node id is its identity.
struct Raw {
    node: Node<local::Service>,
    client: iceoryx2::port::client::Client<local::Service, CommandRequest, (), CommandReply, ()>,
}

impl Raw {
    fn connect(name: &str) -> Self {
        let node = NodeBuilder::new().create::<local::Service>().expect("node");
        let service: ServiceName = ServiceNames::new(name)
            .command()
            .as_str()
            .try_into()
            .expect("service name");
        let client = node
            .service_builder(&service)
            .request_response::<CommandRequest, CommandReply>()
            .open()
            .expect("the fake's command service")
            .client_builder()
            .create()
            .expect("client port");
        Self { node, client }
    }

    fn id(&self) -> ClientId {
        ClientId::from_u128(self.node.id().value())
    }

    fn send(&self, request: CommandRequest) -> Reason {
        let pending = self.client.send_copy(request).expect("send");
        let end = Instant::now() + Duration::from_secs(5);
        while Instant::now() < end {
            if let Ok(Some(reply)) = pending.receive() {
                return Reason::try_from(reply.reason).expect("a known reason");
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        panic!("the fake did not answer {request:?}");
    }
}

fn axis(name: &str, device: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "mm".into(),
        device,
        channel: 0,
        counts_per_unit: 100.0,
        min: -100.0,
        max: 100.0,
        max_velocity: 50.0,
        max_accel: 500.0,
        position_tolerance: 0.01,
        following_error: 0.0,
        overspeed_factor: 0.0,
        ..AxisConfig::default()
    }
}

fn signal(name: &str, pin: u16, kind: PinKind) -> SignalConfig {
    SignalConfig {
        name: name.into(),
        unit: String::new(),
        device: 0,
        pin: Pin(pin),
        pin_name: format!("p{pin}"),
        kind,
        invert: false,
        scale: 1.0,
        offset: 0.0,
        full_scale: 1.0,
        safe: Some(false),
    }
}

/// `x` on a board that does everything, `y` on one that can neither de-energise nor home;
/// an output `lamp` and an input `door` on the first board.
fn engine_side() -> EngineSide {
    engine_side_with(Vec::new())
}

/// [`engine_side`] with `groups` of its axes.
fn engine_side_with(groups: Vec<GroupConfig>) -> EngineSide {
    let link = |name: &str| BusConfig {
        name: name.into(),
        kind: LinkKind::Stream,
    };
    let config = EngineConfig {
        name: "parity".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: vec![link("bus0"), link("bus1")],
        devices: vec![
            DeviceConfig {
                name: "full".into(),
                link: 0,
                address: 1,
            },
            DeviceConfig {
                name: "plain".into(),
                link: 1,
                address: 2,
            },
        ],
        axes: vec![axis("x", 0), axis("y", 1)],
        signals: vec![
            signal("lamp", 1, PinKind::DigitalOut),
            signal("door", 0, PinKind::DigitalIn),
        ],
        groups,
        ..EngineConfig::default()
    };
    let (full, full_control) = IdealBoard::boxed(1, &GoalKind::ALL);
    // Its smallest steps at 100 counts/mm: 0.5 mm/s (velocity goals, searches), 0.2 mm/s
    // (position profiles), 10 mm/s².
    full_control.lock().unwrap().floor = RateFloor {
        velocity: 50.0,
        profile_velocity: 20.0,
        accel: 1000.0,
    };
    let plain_goals: Vec<GoalKind> = GoalKind::ALL
        .into_iter()
        .filter(|kind| !matches!(kind, GoalKind::Off | GoalKind::Home))
        .collect();
    let (plain, plain_control) = IdealBoard::boxed(1, &plain_goals);
    let engine = Engine::new(config, vec![full, plain]).expect("valid config");
    let mut side = EngineSide {
        engine,
        boards: vec![full_control, plain_control],
        port: Port::default(),
        frame: Box::new(MotionFrame::EMPTY),
        now: Duration::ZERO,
    };
    for _ in 0..50 {
        side.tick();
    }
    assert_eq!(side.engine.device_state(0), Some(DeviceState::Online));
    side
}

/// The same machine as the fake sees it: limits, rates, capabilities and tolerance taken from
/// the engine's own description.
fn fake_config(engine: &Engine) -> FakeConfig {
    let mut info = Box::new(ServerInfo::EMPTY);
    engine.fill_info(&mut info);
    let mut config = FakeConfig::demo(&unique_name("parity"));
    config.tick_hz = 1000;
    config.starting_ticks = 0;
    config.devices = vec![
        FakeDevice::new("full", DeviceModel::QQ2DRV, "fw"),
        FakeDevice::new("plain", DeviceModel::QQ2DRV, "fw"),
    ];
    config.axes = info.axes[..info.axis_count as usize]
        .iter()
        .map(|a| {
            let mut fake = FakeAxis::new(a.name(), a.min, a.max, a.max_velocity);
            fake.device = usize::from(a.device_index);
            fake.max_accel = a.max_accel;
            fake.capabilities = motion_ipc::Capabilities(a.capabilities);
            fake.position_tolerance = 0.01;
            fake
        })
        .collect();
    let mut lamp = FakeSignal::digital("lamp", 0, "p1", SignalKind::DigitalOut);
    lamp.safe = Some(false);
    // The fake learns x's smallest steps from the test (no payload carries them).
    config.axes[0].min_velocity = 0.5;
    config.axes[0].min_profile_velocity = 0.2;
    config.axes[0].min_accel = 10.0;
    config.signals = vec![
        lamp,
        FakeSignal::digital("door", 0, "p0", SignalKind::DigitalIn),
    ];
    config.params = Vec::new();
    config.groups = engine
        .config()
        .groups
        .iter()
        .map(|group| {
            let mut fake = FakeGroup::new(&group.name, &group.axes);
            fake.path_tolerance.clone_from(&group.path_tolerance);
            fake.goal_tolerance.clone_from(&group.goal_tolerance);
            fake.goal_time_tolerance = group.goal_time_tolerance.as_secs_f64();
            fake.stream_timeout = group.stream_timeout;
            fake.stream_buffer = group.stream_buffer;
            fake
        })
        .collect();
    config
}

/// One row of the table.
enum Step {
    /// Client `.0` (0 = A, 1 = B) sends a request.
    Send(usize, CommandRequest),
    /// Client `.0` sends a request whose payload names the other client.
    Forge(usize, CommandRequest),
    /// A device's readiness changes.
    Device(usize, DeviceState),
    /// Axis `.0`'s board reports a fault until [`Step::FaultGone`] (the fake: injected).
    Fault(usize),
    /// The board of axis `.0` no longer reports its fault.
    FaultGone(usize),
    /// The server begins its shutdown.
    ShutDown,
    /// Both sides carry out what was asked (a stop comes to rest).
    Settle,
}

fn axis_request(axis: u32, kind: CommandKind, values: [f64; 3]) -> CommandRequest {
    CommandRequest::new(ClientId::NONE, 0, axis, kind).with_values(values)
}

fn signal_request(signal: u32, kind: CommandKind, value: f64) -> CommandRequest {
    CommandRequest::for_signal(ClientId::NONE, 0, signal, kind).with_values([value, 0.0, 0.0])
}

fn table() -> Vec<Step> {
    use CommandKind::*;
    use Step::{Device, Fault, FaultGone, Forge, Send, ShutDown};
    let all = CommandRequest::ALL_AXES;
    let mut bad_schema = axis_request(0, Stop, [0.0; 3]);
    bad_schema.schema_version = 1;
    let mut bad_kind = axis_request(0, Stop, [0.0; 3]);
    bad_kind.kind = 99;
    let mut bad_target = axis_request(0, Stop, [0.0; 3]);
    bad_target.target = 7;
    vec![
        // Form: schema, kind, finite values, target, index.
        Send(0, bad_schema),
        Send(0, bad_kind),
        Send(0, axis_request(0, Position, [f64::NAN, 0.0, 0.0])),
        Send(0, axis_request(0, RampVelocity, [f64::INFINITY, 0.0, 0.0])),
        Send(0, bad_target),
        Send(0, axis_request(5, Position, [1.0, 0.0, 0.0])),
        Send(0, axis_request(0, SetOutput, [1.0, 0.0, 0.0])),
        // Limits and rates, at rest at 0.
        Send(0, axis_request(0, Position, [100.5, 0.0, 0.0])),
        Send(0, axis_request(0, Position, [-100.0, 0.0, 0.0])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        Send(0, axis_request(0, RampVelocity, [10.0, -1.0, 0.0])),
        Send(0, axis_request(0, RampVelocity, [10.0, 600.0, 0.0])),
        Send(0, axis_request(0, Velocity, [51.0, 0.0, 0.0])),
        Send(0, axis_request(0, RampPosition, [10.0, -5.0, 0.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 0.0, -5.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 60.0, 0.0])),
        Send(0, axis_request(0, Power, [1.5, 0.0, 0.0])),
        Send(0, axis_request(0, Home, [-1.0, 0.0, 0.0])),
        Send(0, axis_request(0, Home, [80.0, 0.0, 0.0])),
        Send(0, axis_request(0, SetPosition, [200.0, 0.0, 0.0])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        // Below the board's smallest steps (x: 0.5 mm/s, profiles 0.2 mm/s, 10 mm/s²; y has
        // none).
        Send(0, axis_request(0, RampVelocity, [0.2, 0.0, 0.0])),
        Send(0, axis_request(0, RampVelocity, [-0.2, 0.0, 0.0])),
        Send(0, axis_request(0, RampVelocity, [5.0, 5e-324, 0.0])),
        Send(0, axis_request(0, Velocity, [5e-324, 0.0, 0.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 0.4, 0.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 0.1, 0.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 0.0, 9.0])),
        Send(0, axis_request(0, RampPosition, [10.0, 0.5, 10.0])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        Send(0, axis_request(0, Home, [0.1, 0.0, 0.0])),
        Send(0, axis_request(1, RampPosition, [10.0, 0.4, 5e-300])),
        Send(0, axis_request(1, Stop, [0.0; 3])),
        // Capabilities.
        Send(0, axis_request(1, Off, [0.0; 3])),
        Send(0, axis_request(1, Home, [0.0; 3])),
        Send(0, axis_request(0, Off, [0.0; 3])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        // Claims and identity.
        Forge(1, axis_request(0, Claim, [0.0; 3])),
        Send(0, axis_request(0, Claim, [0.0; 3])),
        Send(1, axis_request(0, Claim, [0.0; 3])),
        Send(1, axis_request(0, Position, [1.0, 0.0, 0.0])),
        Send(1, axis_request(0, Off, [0.0; 3])),
        Send(1, axis_request(0, Release, [0.0; 3])),
        Send(1, axis_request(0, Stop, [0.0; 3])),
        Send(1, axis_request(all, Off, [0.0; 3])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        Send(0, axis_request(0, Release, [0.0; 3])),
        Send(0, axis_request(0, Release, [0.0; 3])),
        Send(1, axis_request(0, Claim, [0.0; 3])),
        // A reset never ends a claim: after A's reset B still holds x, A is refused and
        // B's move is taken; only B's release frees x for A.
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Send(0, axis_request(0, Position, [0.0, 0.0, 0.0])),
        Send(1, axis_request(0, Position, [0.0, 0.0, 0.0])),
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Send(1, axis_request(0, Release, [0.0; 3])),
        Send(0, axis_request(0, Position, [0.0, 0.0, 0.0])),
        // Signals.
        Send(0, signal_request(0, SetOutput, 1.0)),
        Send(0, signal_request(1, SetOutput, 1.0)),
        Send(0, signal_request(9, SetOutput, 1.0)),
        Send(0, signal_request(0, SetOutput, 0.5)),
        Send(0, signal_request(0, SetOutput, 2.0)),
        Send(0, signal_request(0, SetOutput, -1.0)),
        Send(0, signal_request(0, SetOutput, 5e-324)),
        Send(0, signal_request(1, SetOutput, 0.5)),
        Send(0, signal_request(0, Claim, 0.0)),
        Send(1, axis_request(all, Reset, [0.0; 3])),
        Send(1, signal_request(0, SetOutput, 0.0)),
        Send(1, signal_request(0, Release, 0.0)),
        Send(0, signal_request(0, Release, 0.0)),
        Send(0, signal_request(0, Position, 0.0)),
        // Readiness.
        Device(1, DeviceState::Starting),
        Send(0, axis_request(1, Position, [1.0, 0.0, 0.0])),
        Send(0, axis_request(1, Position, [1000.0, 0.0, 0.0])),
        Send(0, axis_request(1, Stop, [0.0; 3])),
        Device(1, DeviceState::Online),
        Send(0, axis_request(1, Position, [0.0, 0.0, 0.0])),
        // A fault refuses motion until reset; a stop is always taken.
        Fault(0),
        Send(0, axis_request(0, Position, [1.0, 0.0, 0.0])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        FaultGone(0),
        Send(0, axis_request(0, Position, [1.0, 0.0, 0.0])),
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Send(0, axis_request(0, Position, [0.0, 0.0, 0.0])),
        // E-stop: motion and outputs refused, stops and off taken, reset clears.
        Send(1, axis_request(all, EStop, [0.0; 3])),
        Send(0, axis_request(0, Position, [1.0, 0.0, 0.0])),
        Send(0, signal_request(0, SetOutput, 1.0)),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        Send(0, axis_request(all, Stop, [0.0; 3])),
        Send(0, axis_request(0, Claim, [0.0; 3])),
        Send(0, axis_request(0, Release, [0.0; 3])),
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Send(0, axis_request(0, Position, [0.0, 0.0, 0.0])),
        // Shutdown: motion, outputs and reset refused; stops taken.
        ShutDown,
        Send(0, axis_request(0, Position, [1.0, 0.0, 0.0])),
        Send(0, signal_request(0, SetOutput, 1.0)),
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Send(0, axis_request(0, Stop, [0.0; 3])),
        Send(0, axis_request(all, EStop, [0.0; 3])),
    ]
}

#[test]
fn the_engine_and_the_fake_server_give_the_same_answer_to_every_request() {
    same_answers(engine_side(), table(), 60);
}

/// Starts the fake on `engine`'s machine, sends both every row of `steps`, and fails
/// naming every answer that differs (or when fewer than `at_least` requests were answered).
fn same_answers(mut engine: EngineSide, steps: Vec<Step>, at_least: usize) {
    let fake = FakeServer::start::<local::Service>(fake_config(&engine.engine)).expect("fake");
    let (answered, differences) = run(&mut engine, &fake, steps);
    assert!(answered > at_least, "{answered} requests");
    assert!(
        differences.is_empty(),
        "{} of {answered} answers differ:\n{}",
        differences.len(),
        differences.join("\n")
    );
    fake.shutdown().expect("fake shutdown");
}

/// The group rules (issue 41): the same machine with the group `xy` (x on the full board,
/// y on the plain one), and every group and stream request — form, claims, each motion
/// command with no motion, a stream started, busy, cancelled, in each mode, and refused
/// under the e-stop, a starting board, a faulted axis and the shutdown — answered alike.
#[test]
fn the_engine_and_the_fake_server_judge_group_and_stream_requests_alike() {
    let xy = GroupConfig {
        name: "xy".into(),
        axes: vec![0, 1],
        path_tolerance: vec![0.5, 0.5],
        goal_tolerance: vec![0.05, 0.05],
        goal_time_tolerance: Duration::from_millis(500),
        stream_limit: StreamLimit::Clamp,
        // A stream the table leaves alone must not go stale on either side's clock.
        stream_timeout: 1_000_000,
        stream_buffer: 3,
    };
    same_answers(engine_side_with(vec![xy]), group_table(), 80);
}

fn group_request(group: u32, kind: CommandKind, value: f64) -> CommandRequest {
    let mut request =
        CommandRequest::new(ClientId::NONE, 0, group, kind).with_values([value, 0.0, 0.0]);
    request.target = Target::Group as u32;
    request
}

fn group_table() -> Vec<Step> {
    use CommandKind::*;
    use Step::{Device, Fault, FaultGone, Send, Settle, ShutDown};
    let all = CommandRequest::ALL_AXES;
    let velocity = f64::from(StreamMode::Velocity as u32);
    let position = f64::from(StreamMode::Position as u32);
    let power = f64::from(StreamMode::Power as u32);
    let g = group_request;
    let mut steps = vec![
        // Form: the group, the kind, the values.
        Send(0, g(5, Claim, 0.0)),
        Send(0, g(0, Position, 1.0)),
        Send(0, g(0, Home, 0.0)),
        Send(0, g(0, Feed, f64::NAN)),
        Send(0, g(0, Feed, 2.0)),
        Send(0, g(0, Feed, -0.5)),
        Send(0, g(0, Stream, 99.0)),
        Send(0, g(0, Stream, 0.0)),
        Send(0, g(0, Stream, f64::INFINITY)),
        // Claims: a member held by another client.
        Send(1, axis_request(1, Claim, [0.0; 3])),
        Send(0, g(0, Claim, 0.0)),
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Run, 7.0)),
        Send(1, g(0, Release, 0.0)),
        Send(0, g(0, Claim, 0.0)),
        Send(1, g(0, Claim, 0.0)),
        Send(1, g(0, Stream, velocity)),
        Send(1, g(0, Cancel, 0.0)),
        Send(1, g(0, Hold, 0.0)),
        Send(1, g(0, Feed, 0.5)),
        // No motion yet.
        Send(0, g(0, Hold, 0.0)),
        Send(0, g(0, Resume, 0.0)),
        Send(0, g(0, Cancel, 0.0)),
        Send(0, g(0, Feed, 0.5)),
        Send(0, g(0, Stop, 0.0)),
        Send(0, g(0, Run, 7.0)),
        Send(0, g(0, Run, -1.0)),
        Send(0, g(0, Run, 0.5)),
    ];
    // A stream in each mode: started, busy, the members' own goals refused, cancelled.
    for mode in [velocity, position, power] {
        steps.extend([
            Send(0, g(0, Stream, mode)),
            Send(0, g(0, Stream, mode)),
            Send(0, g(0, Run, 7.0)),
            Send(0, axis_request(0, Position, [5.0, 0.0, 0.0])),
            Send(0, axis_request(1, Velocity, [5.0, 0.0, 0.0])),
            Send(1, g(0, Stop, 0.0)),
            Send(0, g(0, Feed, 0.5)),
            Send(0, g(0, Hold, 0.0)),
            Send(0, g(0, Resume, 0.0)),
            Send(0, g(0, Cancel, 0.0)),
            Settle,
            Send(0, g(0, Cancel, 0.0)),
        ]);
    }
    steps.extend([
        // A stop ends a stream as well.
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Stop, 0.0)),
        Settle,
        Send(0, g(0, Release, 0.0)),
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Release, 0.0)),
        // The e-stop.
        Send(0, g(0, Claim, 0.0)),
        Send(1, axis_request(all, EStop, [0.0; 3])),
        Settle,
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Run, 7.0)),
        Send(0, g(0, Claim, 0.0)),
        Send(0, g(0, Release, 0.0)),
        Send(0, g(0, Claim, 0.0)),
        Send(1, axis_request(all, Reset, [0.0; 3])),
        Settle,
        // The e-stop and the reset addressed to the group: every axis, as on an axis.
        Send(1, g(0, EStop, 0.0)),
        Settle,
        Send(0, g(0, Stream, velocity)),
        Send(0, axis_request(0, Position, [5.0, 0.0, 0.0])),
        Send(1, g(3, Reset, 0.0)),
        Settle,
        // A board starting, then an axis faulted.
        Device(1, DeviceState::Starting),
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Run, 7.0)),
        Device(1, DeviceState::Online),
        Fault(0),
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Run, 7.0)),
        FaultGone(0),
        Send(0, axis_request(all, Reset, [0.0; 3])),
        Settle,
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Cancel, 0.0)),
        Settle,
        // The shutdown.
        ShutDown,
        Send(0, g(0, Stream, velocity)),
        Send(0, g(0, Run, 7.0)),
        Send(0, g(0, Claim, 0.0)),
        Send(0, g(0, Release, 0.0)),
    ]);
    steps
}

/// Sends every row of `steps` to both sides; how many requests were answered, and a line
/// per answer that differs.
fn run(engine: &mut EngineSide, fake: &FakeServer, steps: Vec<Step>) -> (usize, Vec<String>) {
    let clients = [Raw::connect(fake.name()), Raw::connect(fake.name())];
    let ids = [clients[0].id(), clients[1].id()];
    let mut sequence = 0;
    let mut differences = Vec::new();
    let mut answered = 0;
    for (row, step) in steps.into_iter().enumerate() {
        let (client, mut request, forged) = match step {
            Step::Send(client, request) => (client, request, false),
            Step::Forge(client, request) => (client, request, true),
            Step::Device(device, state) => {
                engine.boards[device].lock().unwrap().starting = state == DeviceState::Starting;
                fake.set_device_state(device, state);
                settle(engine);
                continue;
            }
            Step::Fault(axis) => {
                engine.boards[axis].lock().unwrap().fault = Some(DeviceFault::BoardError);
                fake.fault_axis(axis, FaultCode::BoardError, 0.0, 0.0);
                settle(engine);
                assert!(
                    engine.engine.axis_fault(axis).is_some(),
                    "the engine latched it"
                );
                continue;
            }
            Step::FaultGone(axis) => {
                engine.boards[axis].lock().unwrap().fault = None;
                fake.control(motion_client::testing::FakeControl::FaultGone { axis });
                settle(engine);
                continue;
            }
            Step::ShutDown => {
                engine.engine.begin_shutdown();
                fake.control(motion_client::testing::FakeControl::ShutDown);
                settle(engine);
                continue;
            }
            Step::Settle => {
                settle(engine);
                continue;
            }
        };
        sequence += 1;
        request.sequence = sequence;
        request.client = if forged { ids[1 - client] } else { ids[client] };
        let by_engine = engine.send(request, ids[client]);
        let by_fake = clients[client].send(request);
        answered += 1;
        if by_engine != by_fake {
            differences.push(format!(
                "row {row}: {:?} target {} index {} values {:?} from {}: engine {by_engine:?}, fake {by_fake:?}",
                request.kind(),
                request.target,
                request.axis,
                request.values,
                ["A", "B"][client],
            ));
        }
        // Let both carry it out before the next row.
        for _ in 0..3 {
            engine.tick();
        }
    }
    (answered, differences)
}

/// Lets the engine see a board change and the fake (ticking at 1 kHz on its own thread)
/// apply a control, which it does at its next tick.
fn settle(engine: &mut EngineSide) {
    for _ in 0..20 {
        engine.tick();
    }
    std::thread::sleep(Duration::from_millis(20));
}
