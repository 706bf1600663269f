//! An impostor cannot take `motionctl estop`'s signal (issue 30, item 1): a process that
//! names its iceoryx2 node `motiond-<name>` and catches SIGUSR1, while every command client
//! slot and every e-stop notifier slot of the real server is taken, either sees the real
//! server latched (every jogging axis stops, exit 0) or `motionctl estop` exits non-zero —
//! never "latched" with an axis still moving.
//!
//! The impostor is this test binary run again with `MOTIOND_IMPOSTOR` set (the
//! `impostor_process` "test" below does nothing otherwise).

mod common;

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use iceoryx2::node::NodeBuilder;
use iceoryx2::prelude::{NodeName, ServiceName, ipc};
use motion_client::Client;
use motion_client::ipc::{
    CommandReply, CommandRequest, FrameFlags, MotionFrame, ServerPidFile, ServiceNames,
};

use common::real::{RealServer, sim_config};
use common::*;

/// The axes jogged, one on each board: QuadQuad2Drv, SIXpack, SPI_motor, QSB.
const JOGS: [(&str, &str); 4] = [
    ("wheel_left", "40"),
    ("conveyor", "80"),
    ("focus", "150"),
    ("feeder", "40"),
];

/// Runs as the impostor when `MOTIOND_IMPOSTOR=<instance>` and `MOTIOND_IMPOSTOR_MARK=<file>`
/// are set: a node named as the server's, SIGUSR1 caught, a mark file written for every
/// signal received; runs until killed.
#[test]
fn impostor_process() {
    let (Some(name), Some(mark)) = (
        std::env::var_os("MOTIOND_IMPOSTOR"),
        std::env::var_os("MOTIOND_IMPOSTOR_MARK"),
    ) else {
        return;
    };
    let name = name.to_string_lossy().into_owned();
    let node_name = NodeName::new(&ServiceNames::new(&name).server_node()).unwrap();
    let _node = NodeBuilder::new()
        .name(&node_name)
        .create::<ipc::Service>()
        .unwrap();
    let caught = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGUSR1, Arc::clone(&caught)).unwrap();
    std::fs::write(PathBuf::from(&mark).with_extension("ready"), b"ready").unwrap();
    loop {
        if caught.swap(false, Ordering::Relaxed) {
            std::fs::write(&mark, b"SIGUSR1").unwrap();
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A child process killed when dropped.
struct Killed(Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn start_impostor(name: &str, mark: &Path) -> Result<Killed> {
    let child = Command::new(std::env::current_exe()?)
        .args(["--exact", "impostor_process", "--nocapture"])
        .env("MOTIOND_IMPOSTOR", name)
        .env("MOTIOND_IMPOSTOR_MARK", mark)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()?;
    let impostor = Killed(child);
    let until = Instant::now() + DEADLINE;
    while !mark.with_extension("ready").exists() {
        if Instant::now() > until {
            return Err("the impostor never started".into());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(impostor)
}

/// The sim robot with room for exactly `max_clients` clients.
fn server_with_slots(max_clients: u32) -> Result<RealServer> {
    let config = sim_config()?.replacen(
        "[server]\n",
        &format!("[server]\nmax_clients = {max_clients}\n"),
        1,
    );
    RealServer::start_with(&config)
}

/// The jogged axes' indices in the frame.
fn jogged_axes(client: &Client<ipc::Service>) -> Result<Vec<usize>> {
    JOGS.iter()
        .map(|(axis, _)| Ok(client.axis(axis)?.index() as usize))
        .collect()
}

/// Waits until `check` holds for a frame.
fn wait_frame(
    client: &Client<ipc::Service>,
    within: Duration,
    what: &str,
    mut check: impl FnMut(&MotionFrame) -> bool,
) -> Result<MotionFrame> {
    let until = Instant::now() + within;
    loop {
        let frame = client.next_frame(Duration::from_secs(1))?;
        if check(&frame) {
            return Ok(*frame);
        }
        if Instant::now() > until {
            return Err(format!("{what}: not within {within:?}").into());
        }
    }
}

/// Command client ports and e-stop notifiers of the instance, every free one, held by
/// `hog` until dropped.
#[allow(clippy::type_complexity)]
fn take_command_and_estop_slots(
    hog: &iceoryx2::node::Node<ipc::Service>,
    names: &ServiceNames,
) -> Result<(
    Vec<iceoryx2::port::client::Client<ipc::Service, CommandRequest, (), CommandReply, ()>>,
    Vec<iceoryx2::port::notifier::Notifier<ipc::Service>>,
)> {
    let commands = hog
        .service_builder(&ServiceName::new(&names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .open()?;
    let mut clients = Vec::new();
    while let Ok(port) = commands.client_builder().create() {
        clients.push(port);
    }
    let event = hog
        .service_builder(&ServiceName::new(&names.estop())?)
        .event()
        .open()?;
    let mut notifiers = Vec::new();
    while let Ok(notifier) = event.notifier_builder().create() {
        notifiers.push(notifier);
    }
    Ok((clients, notifiers))
}

#[test]
fn an_impostor_node_never_gets_the_estop_and_every_jog_stops() -> Result {
    // 4 jogs + this test's observer + 1 for motionctl estop's frame: 6 frame slots.
    let server = server_with_slots(6)?;
    let name = server.name.clone();
    let names = ServiceNames::new(&name);
    let mark = std::env::temp_dir().join(format!("{name}-impostor.mark"));
    let _ = std::fs::remove_file(&mark);
    let _impostor = start_impostor(&name, &mark)?;

    let observer = Client::<ipc::Service>::connect(&name)?;
    let axes = jogged_axes(&observer)?;
    let mut jogs = Vec::new();
    for (axis, velocity) in JOGS {
        jogs.push(Killed(
            command(&name, &["jog", axis, velocity])
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()?,
        ));
    }
    wait_frame(&observer, DEADLINE, "every jog moving", |frame| {
        axes.iter()
            .all(|&index| frame.axes()[index].velocity.abs() > 1.0)
    })?;

    // Every command client slot and every e-stop notifier slot taken.
    let hog = NodeBuilder::new().create::<ipc::Service>()?;
    let held = take_command_and_estop_slots(&hog, &names)?;
    assert!(!held.1.is_empty());
    assert_fails(&run(&name, &["stop"])?, 3, "no free client slot");

    let estop = run(&name, &["estop"])?;
    let said = stdout(&estop);
    // Never "latched" and a moving axis: motionctl reached the real server (the pid its pid
    // file names), the frame it saw is the real server's, and every jogging axis stops.
    assert!(estop.status.success(), "{estop:?}");
    assert!(
        said.contains(&format!(
            "via SIGUSR1 to the server process (pid {})",
            server.pid()?
        )),
        "{estop:?}"
    );
    assert!(said.contains("latched in the frame of tick"), "{said}");
    wait_frame(&observer, DEADLINE, "every jogging axis stopped", |frame| {
        frame.flags().contains(FrameFlags::ESTOP_LATCHED)
            && axes
                .iter()
                .all(|&index| frame.axes()[index].velocity.abs() < 1e-9)
    })?;
    assert!(
        !mark.exists(),
        "the impostor received SIGUSR1: {}",
        std::fs::read_to_string(&mark).unwrap_or_default()
    );
    let _ = std::fs::remove_file(mark.with_extension("ready"));
    Ok(())
}

#[test]
fn an_estop_no_frame_can_confirm_exits_non_zero_and_still_reaches_the_real_server() -> Result {
    let server = server_with_slots(2)?;
    let name = server.name.clone();
    let names = ServiceNames::new(&name);
    let mark = std::env::temp_dir().join(format!("{name}-impostor.mark"));
    let _ = std::fs::remove_file(&mark);
    let _impostor = start_impostor(&name, &mark)?;

    // The server's pid file names the server, not the impostor.
    let process = ServerPidFile::of(&name).read_verified()?;
    assert_eq!(process.pid, server.pid()?);

    // Every slot taken: command clients, notifiers and frame subscribers.
    let hog = NodeBuilder::new().create::<ipc::Service>()?;
    let _held = take_command_and_estop_slots(&hog, &names)?;
    let frames = hog
        .service_builder(&ServiceName::new(&names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .open()?;
    let mut held_frames = Vec::new();
    while let Ok(subscriber) = frames.subscriber_builder().create() {
        held_frames.push(subscriber);
    }
    assert_eq!(held_frames.len(), 2);

    // Sent to the real server, not seen: exit 5, saying what was sent.
    let estop = run(&name, &["estop"])?;
    assert_fails(&estop, 5, "NOT confirmed");
    assert!(
        stderr(&estop).contains(&format!(
            "SIGUSR1 to the server process (pid {})",
            server.pid()?
        )),
        "{estop:?}"
    );
    assert!(!mark.exists(), "the impostor received SIGUSR1");

    // It did latch: one frame slot freed, a frame shows it.
    held_frames.pop();
    let until = Instant::now() + DEADLINE;
    let latched = loop {
        if let Some(sample) = held_frames[0].receive()? {
            let frame = *sample.payload();
            if frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
                break frame;
            }
        }
        if Instant::now() > until {
            return Err("the real server never latched".into());
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    assert!(latched.tick > 0);
    let _ = std::fs::remove_file(mark.with_extension("ready"));
    Ok(())
}
