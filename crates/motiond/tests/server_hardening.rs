//! Hardening, attacked from other processes' point of view (this test's own iceoryx2 nodes
//! against a motiond child process):
//! - identity comes from the transport: a borrowed or invented client id is refused;
//! - a claim ends when its owner leaves, normally or not;
//! - an e-stop gets through with every frame slot taken (command service), with every
//!   command slot taken (the e-stop event), and by SIGUSR1; exhausted slots are logged;
//! - a server SIGKILLed while a client keeps the services open restarts on the same name,
//!   and the client sees the new server.

mod support;

use core::time::Duration;
use std::time::Instant;

use iceoryx2::prelude::*;
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, FrameFlags, MotionFrame, Reason,
    ServerInfo, ServiceNames,
};
use nix::sys::signal::Signal;
use support::*;

type CommandClient =
    iceoryx2::port::client::Client<ipc::Service, CommandRequest, (), CommandReply, ()>;

/// A simulated SPI_motor stepper (axis `a`), `max_clients` ports per service.
fn config(name: &str, max_clients: u32) -> std::path::PathBuf {
    stepper_config(
        name,
        &format!("max_clients = {max_clients}\nliveness_check_ms = 50"),
    )
}

fn service(name: &str) -> ServiceName {
    name.try_into().expect("service name")
}

/// A node with only a command client (no frame subscriber).
fn command_only(name: &str) -> (Node<ipc::Service>, CommandClient) {
    let node = NodeBuilder::new().create::<ipc::Service>().expect("node");
    let client = node
        .service_builder(&service(&ServiceNames::new(name).command()))
        .request_response::<CommandRequest, CommandReply>()
        .open()
        .expect("command service")
        .client_builder()
        .create()
        .expect("a command client slot");
    (node, client)
}

fn ask(client: &CommandClient, request: CommandRequest) -> Result<(), Reason> {
    let pending = client.send_copy(request).expect("send");
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        if let Ok(Some(reply)) = pending.receive() {
            assert_eq!(reply.sequence, request.sequence);
            return reply.result();
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("no reply to {request:?}");
}

fn ready(server: &str) -> RawClient {
    let client = RawClient::connect(server, Duration::from_secs(10));
    let (frame, up) = client.wait_frame(Duration::from_secs(10), |f| {
        f.device_state(0) == motion_ipc::DeviceState::Online
    });
    assert!(up, "{:?}", frame.axes());
    client
}

fn estop_latched(frame: &MotionFrame) -> bool {
    frame.flags().contains(FrameFlags::ESTOP_LATCHED)
}

#[test]
fn a_borrowed_or_invented_client_id_is_refused_and_claims_end_with_their_owner() {
    let name = unique_name("ident");
    let mut server = Server::start(&config(&name, 8));
    let watcher = ready(&name);
    let (a_node, a) = command_only(&name);
    let a_id = ClientId::from_u128(a_node.id().value());
    let (b_node, b) = command_only(&name);
    let b_id = ClientId::from_u128(b_node.id().value());
    assert_eq!(
        ask(&a, CommandRequest::new(a_id, 1, 0, CommandKind::Claim)),
        Ok(())
    );
    let (frame, claimed) =
        watcher.wait_frame(Duration::from_secs(1), |f| f.axes()[0].claimed_by == a_id);
    assert!(claimed, "{:?}", frame.axes()[0]);
    // B sends A's id: refused, whatever it asks.
    for (sequence, kind) in [
        (2, CommandKind::RampPosition),
        (3, CommandKind::Release),
        (4, CommandKind::Claim),
        (5, CommandKind::Off),
    ] {
        let forged = CommandRequest::new(a_id, sequence, 0, kind).with_values([10.0, 0.0, 0.0]);
        assert_eq!(ask(&b, forged), Err(Reason::IdentityMismatch), "{kind:?}");
    }
    // An invented id claims nothing.
    let invented = CommandRequest::new(
        ClientId {
            lo: 0x1234,
            hi: 0x5678,
        },
        6,
        0,
        CommandKind::Claim,
    );
    assert_eq!(ask(&b, invented), Err(Reason::IdentityMismatch));
    // B as itself (its own id, or none) is B: claimed by another.
    for id in [b_id, ClientId::NONE] {
        let own =
            CommandRequest::new(id, 7, 0, CommandKind::RampPosition).with_values([10.0, 0.0, 0.0]);
        assert_eq!(ask(&b, own), Err(Reason::ClaimedByOther));
    }
    // A exits normally (drops its port and node, no release): its claim ends.
    drop(a);
    drop(a_node);
    let (frame, released) =
        watcher.wait_frame(Duration::from_secs(2), |f| f.axes()[0].claimed_by.is_none());
    assert!(released, "{:?}", frame.axes()[0]);
    let own =
        CommandRequest::new(b_id, 8, 0, CommandKind::RampPosition).with_values([10.0, 0.0, 0.0]);
    assert_eq!(ask(&b, own), Ok(()));
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn e_stop_gets_through_with_every_slot_taken_and_exhausted_slots_are_logged() {
    let name = unique_name("slots");
    let mut server = Server::start(&config(&name, 4));
    let watcher = ready(&name);
    let names = ServiceNames::new(&name);
    // Another process takes every frame subscriber slot (the watcher holds one already).
    let hog = NodeBuilder::new().create::<ipc::Service>().expect("node");
    let frames = hog
        .service_builder(&service(&names.frame()))
        .publish_subscribe::<MotionFrame>()
        .open()
        .expect("frame service");
    let mut held = Vec::new();
    while let Ok(subscriber) = frames.subscriber_builder().create() {
        held.push(subscriber);
        assert!(held.len() < 100, "a limit exists");
    }
    assert_eq!(held.len(), 3, "4 slots, one the watcher's");
    assert!(
        server.wait_for_log(
            "frame: all 4 subscriber slots are taken",
            Duration::from_secs(3)
        ),
        "logged once with the key that raises it: {:#?}",
        server.log
    );
    assert!(
        server
            .log
            .iter()
            .any(|l| l.contains("raise [server] max_clients"))
    );
    // The e-stop needs no frame slot: it goes through the command service.
    let (node, client) = command_only(&name);
    let id = ClientId::from_u128(node.id().value());
    let estop = CommandRequest::new(id, 1, CommandRequest::ALL_AXES, CommandKind::EStop);
    assert_eq!(ask(&client, estop), Ok(()));
    // The reply is sent within the tick; that tick's frame is published right after it.
    let (_, latched) = watcher.wait_frame(Duration::from_secs(1), estop_latched);
    assert!(latched, "the e-stop's frame shows the latch");
    let reset = CommandRequest::new(id, 2, CommandRequest::ALL_AXES, CommandKind::Reset);
    assert_eq!(ask(&client, reset), Ok(()));
    // Every command client slot taken too (the watcher and `client` hold two): the e-stop
    // event still latches it.
    let commands = hog
        .service_builder(&service(&names.command()))
        .request_response::<CommandRequest, CommandReply>()
        .open()
        .expect("command service");
    let mut clients = Vec::new();
    while let Ok(port) = commands.client_builder().create() {
        clients.push(port);
        assert!(clients.len() < 100, "a limit exists");
    }
    assert!(
        server.wait_for_log(
            "command: all 4 client slots are taken",
            Duration::from_secs(3)
        ),
        "{:#?}",
        server.log
    );
    let notifier = hog
        .service_builder(&service(&names.estop()))
        .event()
        .open()
        .expect("estop event")
        .notifier_builder()
        .create()
        .expect("an e-stop notifier slot");
    notifier.notify().expect("notify");
    let (_, latched) = watcher.wait_frame(Duration::from_secs(2), estop_latched);
    assert!(latched, "the e-stop event latched it");
    assert!(server.wait_for_log("e-stop latched by the estop event", Duration::from_secs(2)));
    drop(clients);
    drop(held);
    assert_eq!(
        ask(
            &client,
            CommandRequest {
                sequence: 3,
                ..reset
            }
        ),
        Ok(())
    );
    // And SIGUSR1, the path that needs no port at all.
    let pid = nix::unistd::Pid::from_raw(server.child.id() as i32);
    nix::sys::signal::kill(pid, Signal::SIGUSR1).expect("kill");
    let (_, latched) = watcher.wait_frame(Duration::from_secs(2), estop_latched);
    assert!(latched, "SIGUSR1 latched it");
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn a_server_killed_while_a_client_lives_restarts_and_the_client_sees_it() {
    let name = unique_name("takeover");
    let path = config(&name, 8);
    let mut first = Server::start(&path);
    let mut client = ready(&name);
    let info_service = client
        .node
        .service_builder(&service(&ServiceNames::new(&name).info()))
        .publish_subscribe::<ServerInfo>()
        .open()
        .expect("info service")
        .subscriber_builder()
        .create()
        .expect("info subscriber");
    let pid_of = |info: &iceoryx2::port::subscriber::Subscriber<ipc::Service, ServerInfo, ()>| {
        let end = Instant::now() + Duration::from_secs(3);
        let mut last = None;
        while Instant::now() < end {
            while let Ok(Some(sample)) = info.receive() {
                last = Some(sample.server_pid);
            }
            if last.is_some() {
                return last;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        last
    };
    let first_pid = pid_of(&info_service).expect("the first server's info");
    // SIGKILL: no clean-up at all, and the client keeps every service open.
    assert_eq!(
        first.signal_and_wait(Signal::SIGKILL, Duration::from_secs(5)),
        None
    );
    let restarted = nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC).expect("clock");
    let restarted_ns = restarted.tv_sec() as u64 * 1_000_000_000 + restarted.tv_nsec() as u64;
    let mut second = Server::start(&path);
    assert!(
        second.wait_for_log("online", Duration::from_secs(10)),
        "the second server starts on the same name: {:#?}",
        second.log
    );
    // The client's own ports see the new server: frames published after the restart, a new
    // pid in the info, and commands answered.
    let (frame, fresh) = client.wait_frame(Duration::from_secs(5), |f| {
        f.publish_ns > restarted_ns && f.device_state(0) == motion_ipc::DeviceState::Online
    });
    assert!(
        fresh,
        "frames of the new server: {} ns (restart {restarted_ns} ns)",
        frame.publish_ns
    );
    let second_pid = pid_of(&info_service).expect("the second server's info");
    assert_ne!(first_pid, second_pid);
    assert_eq!(second_pid, second.child.id());
    let reply = client.command(0, CommandKind::RampPosition, [5.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    assert_eq!(
        second.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// Run as another user by `a_process_of_another_user_cannot_command_the_server`: tries to
/// command the instance named in `MOTIOND_PROBE_SERVER`; exit 0 when it could, 3 when it
/// could not open the command service, 4 when it got no answer.
#[test]
#[ignore = "helper process of a_process_of_another_user_cannot_command_the_server"]
fn command_probe_process() {
    let Some(name) = std::env::var_os("MOTIOND_PROBE_SERVER") else {
        return;
    };
    let name = name.to_string_lossy().into_owned();
    set_log_level(LogLevel::Fatal);
    let Ok(node) = NodeBuilder::new().create::<ipc::Service>() else {
        std::process::exit(3);
    };
    let Ok(service) = node
        .service_builder(&service(&ServiceNames::new(&name).command()))
        .request_response::<CommandRequest, CommandReply>()
        .open()
    else {
        std::process::exit(3);
    };
    let Ok(client) = service.client_builder().create() else {
        std::process::exit(3);
    };
    let request = CommandRequest::new(
        ClientId::NONE,
        1,
        CommandRequest::ALL_AXES,
        CommandKind::EStop,
    );
    let Ok(pending) = client.send_copy(request) else {
        std::process::exit(3);
    };
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        if let Ok(Some(_)) = pending.receive() {
            std::process::exit(0);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    std::process::exit(4);
}

#[test]
fn a_process_of_another_user_cannot_command_the_server() {
    use std::os::unix::process::CommandExt;
    if !nix::unistd::Uid::effective().is_root() {
        eprintln!("skipped: running another user's process needs root (setuid)");
        return;
    }
    let name = unique_name("perm");
    let mut server = Server::start(&config(&name, 8));
    let watcher = ready(&name);
    let probe = |uid: Option<u32>| {
        let mut command = std::process::Command::new(std::env::current_exe().expect("test binary"));
        command
            .args([
                "--ignored",
                "--exact",
                "command_probe_process",
                "--nocapture",
            ])
            .env("MOTIOND_PROBE_SERVER", &name)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        if let Some(uid) = uid {
            command.uid(uid).gid(uid);
        }
        command.status().expect("run the probe").code()
    };
    // The same user commands it (the probe latches the e-stop)...
    assert_eq!(probe(None), Some(0));
    let (_, latched) = watcher.wait_frame(Duration::from_secs(2), estop_latched);
    assert!(latched);
    // ...`nobody` cannot even open the command service: the shared memory is the owner's
    // alone (mode 0600).
    assert_eq!(probe(Some(65_534)), Some(3));
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
