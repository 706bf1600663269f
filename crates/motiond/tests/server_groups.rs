//! Axis groups from outside: a real motiond drives a QSB-M this test serves on a pty
//! (`feeder`) and a simulated QuadQuad2Drv (`lift`) as one group, `pair`.
//! - a line arrives on both boards, done;
//! - a motor that slips on one board (the test moves its encoder behind the server's back)
//!   aborts the group naming that axis, and every axis of the group stops;
//! - a client killed while its trajectory runs stops the group;
//! - a path is taken only from the node that published it.

mod support;

use core::time::Duration;
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{QsbSim, QsbSimConfig};
use iceoryx2::prelude::*;
use motion_ipc::{
    AxisFlags, AxisMode, CommandKind, CommandRequest, DeviceState, GroupAbort, GroupMotion,
    GroupPath, MAX_GROUP_AXES, MotionFrame, PathKind, Reason, ServiceNames, Target,
};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use support::pty_board::PtyBoard;
use support::*;

type Qsb = Arc<Mutex<QsbSim>>;

const FEEDER: usize = 0;
const LIFT: usize = 1;

/// The QSB-M on a pty, a simulated QuadQuad2Drv, the server and a client with both boards
/// online.
/// `path_tolerance`: the group's, mm.
fn setup(test: &str, path_tolerance: f64) -> (Qsb, PtyBoard, Server, RawClient, String, Instant) {
    let name = unique_name(test);
    let epoch = Instant::now();
    let board: Qsb = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let served = PtyBoard::start(&tty, Arc::clone(&board), epoch, 230_400);
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "usb"
type = "serial"
path = "{}"
baud = 230400

[[link]]
name = "spi"
type = "sim"

[[device]]
name = "feeder_qsb"
link = "usb"
model = "qsb"

[[device]]
name = "drive"
link = "spi"
model = "qq2drv"

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

[[axis]]
name = "lift"
device = "drive"
channel = 2
unit = "mm"
counts_per_unit = 400.0
min = 0.0
max = 300.0
max_velocity = 12.0
max_accel = 100.0

[[group]]
name = "pair"
axes = ["feeder", "lift"]
path_tolerance = {path_tolerance}
goal_tolerance = {{ feeder = 0.1, lift = 0.05 }}
goal_time_tolerance_ms = 2000
"#,
            tty.display()
        ),
    );
    let server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(15), |frame| {
        frame.axes().iter().all(|axis| {
            axis.device_state() == Ok(DeviceState::Online)
                && !axis.flags().contains(AxisFlags::STALE)
        })
    });
    assert!(ready, "both boards online: {:?}", frame.axes());
    (board, served, server, client, name, epoch)
}

/// A publisher on `paths` on the client's own node (the server takes a path only from the
/// node that sends the `Run`).
fn paths_publisher(
    node: &Node<ipc::Service>,
    name: &str,
) -> iceoryx2::port::publisher::Publisher<ipc::Service, GroupPath, ()> {
    let service = ServiceName::new(&ServiceNames::new(name).paths()).expect("service name");
    node.service_builder(&service)
        .publish_subscribe::<GroupPath>()
        .open()
        .expect("the paths service")
        .publisher_builder()
        .create()
        .expect("a paths publisher")
}

/// Runs `body` on a thread with room for a path sample passing through the stack (an
/// unoptimised build moves the ≈400 KB `GroupPath::EMPTY` through `write_payload` a few
/// times; an optimised one writes it straight into shared memory).
fn big_stack(body: impl FnOnce() + Send + 'static) {
    std::thread::Builder::new()
        .stack_size(32 << 20)
        .spawn(body)
        .expect("a test thread")
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
}

fn publish(
    publisher: &iceoryx2::port::publisher::Publisher<ipc::Service, GroupPath, ()>,
    fill: impl FnOnce(&mut GroupPath),
) {
    let sample = publisher.loan_uninit().expect("loan");
    let mut sample = sample.write_payload(GroupPath::EMPTY);
    fill(sample.payload_mut());
    sample.send().expect("send the path");
}

fn run(client: &mut RawClient, id: u64) -> motion_ipc::CommandReply {
    let mut request = CommandRequest::new(client.id(), id, 0, CommandKind::Run)
        .with_values([id as f64, 0.0, 0.0]);
    request.target = Target::Group as u32;
    client
        .request(request, Duration::from_secs(2))
        .expect("a reply")
}

fn wait_group(
    client: &RawClient,
    timeout: Duration,
    done: impl Fn(&MotionFrame) -> bool,
) -> MotionFrame {
    let (frame, ok) = client.wait_frame(timeout, done);
    assert!(ok, "{:?}\n{:?}", frame.groups()[0], &frame.axes()[..2]);
    frame
}

#[test]
fn a_line_arrives_on_both_boards() {
    big_stack(a_line_arrives_on_both_boards_body);
}

fn a_line_arrives_on_both_boards_body() {
    let (_board, _served, _server, mut client, name, _) = setup("group_line", 10.0);
    let publisher = paths_publisher(&client.node, &name);
    let start = client.frame();
    let targets = [
        start.axes[FEEDER].position + 30.0,
        start.axes[LIFT].position + 10.0,
    ];
    publish(&publisher, |path| path.set_line(0, 1, &targets, (0.0, 0.0)));
    let reply = run(&mut client, 1);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    let frame = wait_group(&client, Duration::from_secs(20), |frame| {
        !frame.groups()[0].motion().expect("known").active()
    });
    let state = frame.groups()[0];
    assert_eq!(state.motion(), Ok(GroupMotion::Done), "{state:?}");
    assert!((frame.axes[FEEDER].position - targets[0]).abs() <= 0.1);
    assert!((frame.axes[LIFT].position - targets[1]).abs() <= 0.05);
    // A path published by one node cannot be run by another. Asked once the axes are at
    // rest: the board may still report the lift settling after the group is done, and a
    // member still moving is refused `GroupBusy` before any path is looked up.
    wait_group(&client, Duration::from_secs(20), |frame| {
        frame.axes()[..2]
            .iter()
            .all(|axis| !axis.flags().contains(AxisFlags::MOVING))
    });
    let mut other = RawClient::connect(&name, Duration::from_secs(5));
    publish(&publisher, |path| {
        path.set_line(0, 2, &start_positions(&start), (0.0, 0.0))
    });
    let reply = run(&mut other, 2);
    assert_eq!(reply.result(), Err(Reason::NoPath));
}

fn start_positions(frame: &MotionFrame) -> [f64; 2] {
    [frame.axes[FEEDER].position, frame.axes[LIFT].position]
}

#[test]
fn a_slipping_motor_aborts_the_group_naming_its_axis() {
    big_stack(a_slipping_motor_aborts_the_group_naming_its_axis_body);
}

fn a_slipping_motor_aborts_the_group_naming_its_axis_body() {
    let (board, _served, _server, mut client, name, epoch) = setup("group_slip", 2.0);
    let publisher = paths_publisher(&client.node, &name);
    let start = client.frame();
    let targets = [
        start.axes[FEEDER].position + 200.0,
        start.axes[LIFT].position + 60.0,
    ];
    publish(&publisher, |path| path.set_line(0, 1, &targets, (0.2, 0.0)));
    assert_eq!(run(&mut client, 1).result(), Ok(()));
    wait_group(&client, Duration::from_secs(5), |frame| {
        frame.groups()[0].time > 0.5
    });
    // The feeder's motor slips 5 mm (500 encoder counts, x4) behind the server's back.
    board
        .lock()
        .expect("board")
        .nudge_encoder(epoch.elapsed(), -125.0);
    let frame = wait_group(&client, Duration::from_secs(5), |frame| {
        !frame.groups()[0].motion().expect("known").active()
    });
    let state = frame.groups()[0];
    assert_eq!(state.abort(), Ok(GroupAbort::PathTolerance), "{state:?}");
    assert_eq!(state.abort_axis(), Some(FEEDER as u32));
    assert!(
        state.abort_value > 2.0 && state.abort_limit == 2.0,
        "{state:?}"
    );
    for axis in [FEEDER, LIFT] {
        let mode = frame.axes[axis].mode().expect("mode");
        assert!(
            matches!(mode, AxisMode::Stopping | AxisMode::Hold),
            "{axis}: {mode:?}"
        );
    }
    // Both come to rest.
    wait_group(&client, Duration::from_secs(10), |frame| {
        [FEEDER, LIFT]
            .iter()
            .all(|&axis| frame.axes[axis].mode() == Ok(AxisMode::Hold))
    });
}

/// The child side of `a_client_killed_mid_trajectory_stops_the_group`: runs a slow
/// trajectory on the group of instance `$GROUP_CHILD`, prints "running", and waits to be
/// killed.
#[test]
fn group_child_client() {
    big_stack(group_child_client_body);
}

fn group_child_client_body() {
    let Ok(name) = std::env::var("GROUP_CHILD") else {
        return;
    };
    let mut client = RawClient::connect(&name, Duration::from_secs(5));
    let publisher = paths_publisher(&client.node, &name);
    let start = client.frame();
    let from = start_positions(&start);
    publish(&publisher, |path| {
        path.kind = PathKind::Trajectory as u32;
        path.id = 5;
        path.group = 0;
        path.axis_count = 2;
        path.point_count = 2;
        // Long enough that the server finds the dead node (its liveness check) before the
        // path ends, on a loaded machine too.
        path.times[0] = 30.0;
        path.times[1] = 60.0;
        path.positions[0] = from[0] + 100.0;
        path.positions[1] = from[1] + 40.0;
        path.positions[MAX_GROUP_AXES] = from[0];
        path.positions[MAX_GROUP_AXES + 1] = from[1];
    });
    // Under its claim: the server finds the client gone both by its dead node and by its
    // command port leaving (either ends the motion, as client-dead).
    let mut claim = CommandRequest::new(client.id(), 4, 0, CommandKind::Claim);
    claim.target = Target::Group as u32;
    let reply = client
        .request(claim, Duration::from_secs(2))
        .expect("a reply");
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    let reply = run(&mut client, 5);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    println!("running");
    std::thread::sleep(Duration::from_secs(60));
}

#[test]
fn a_client_killed_mid_trajectory_stops_the_group() {
    big_stack(a_client_killed_mid_trajectory_stops_the_group_body);
}

fn a_client_killed_mid_trajectory_stops_the_group_body() {
    let (_board, _served, _server, client, name, _) = setup("group_dead_client", 10.0);
    let mut child = Command::new(std::env::current_exe().expect("this test binary"))
        .args([
            "--exact",
            "group_child_client",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env("GROUP_CHILD", &name)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn the child client");
    let moving = wait_group(&client, Duration::from_secs(20), |frame| {
        frame.groups()[0].motion() == Ok(GroupMotion::Moving) && frame.groups()[0].time > 1.0
    });
    let owner = moving.groups()[0].owner;
    assert!(!owner.is_none());
    kill(Pid::from_raw(child.id() as i32), Signal::SIGKILL).expect("kill the child");
    let _ = child.wait();
    let frame = wait_group(&client, Duration::from_secs(40), |frame| {
        !frame.groups()[0].motion().expect("known").active()
    });
    let state = frame.groups()[0];
    assert_eq!(
        state.abort(),
        Ok(GroupAbort::ClientDead),
        "{state:?} {:?}",
        &frame.axes()[..2]
    );
    wait_group(&client, Duration::from_secs(10), |frame| {
        [FEEDER, LIFT]
            .iter()
            .all(|&axis| frame.axes[axis].mode() == Ok(AxisMode::Hold))
    });
}
