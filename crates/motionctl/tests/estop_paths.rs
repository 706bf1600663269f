//! `motionctl estop` gets through whatever is exhausted: frame subscriber slots (command
//! path), command client slots (estop event path), and event notifier slots too (SIGUSR1 to
//! the process that runs the server's node: this test process, whose fake server latches
//! on SIGUSR1 like motiond). One test in its own binary: the SIGUSR1 handler is
//! process-wide, so no other fake server may run in this process meanwhile.

mod common;

use iceoryx2::node::NodeBuilder;
use iceoryx2::prelude::{ServiceName, ipc};
use motion_client::ipc::{CommandKind, CommandReply, CommandRequest, MotionFrame, ServiceNames};
use motion_client::testing::unique_name;

use common::*;

#[test]
fn estop_gets_through_exhausted_frame_command_and_event_slots() -> Result {
    // 0. A server process that does not catch SIGUSR1 (this one, before any fake installs
    //    the handler) is never sent it: the default action would end it.
    {
        let server = fake("nosigusr1")?;
        let names = ServiceNames::new(server.name());
        let hog = NodeBuilder::new().create::<ipc::Service>()?;
        let commands = hog
            .service_builder(&ServiceName::new(&names.command())?)
            .request_response::<CommandRequest, CommandReply>()
            .open()?;
        let event = hog
            .service_builder(&ServiceName::new(&names.estop())?)
            .event()
            .open()?;
        let mut held_clients = Vec::new();
        while let Ok(client) = commands.client_builder().create() {
            held_clients.push(client);
        }
        let mut held_notifiers = Vec::new();
        while let Ok(notifier) = event.notifier_builder().create() {
            held_notifiers.push(notifier);
        }
        let refused = run(server.name(), &["estop"])?;
        assert_fails(&refused, 1, "does not handle SIGUSR1");
        assert!(!server.estop_latched());
    }

    let server = fake_with("paths", |config| config.latch_on_sigusr1 = true)?;
    let names = ServiceNames::new(server.name());
    let slots = server.config().max_clients;
    let hog = NodeBuilder::new().create::<ipc::Service>()?;

    // 1. Every frame subscriber slot taken: estop, stop (all) and stop AXIS still work.
    let frames = hog
        .service_builder(&ServiceName::new(&names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .open()?;
    let mut held_frames = Vec::new();
    while let Ok(subscriber) = frames.subscriber_builder().create() {
        held_frames.push(subscriber);
    }
    assert_eq!(held_frames.len(), slots);
    let status = run(server.name(), &["status"])?;
    assert_fails(&status, 3, "no free subscriber slot");
    let estop = run(server.name(), &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    assert!(
        stdout(&estop).contains("via the command service"),
        "{estop:?}"
    );
    assert!(server.estop_latched());
    let stop = run(server.name(), &["stop"])?;
    assert!(stop.status.success(), "{stop:?}");
    let stop_x = run(server.name(), &["stop", "x"])?;
    assert!(stop_x.status.success(), "{stop_x:?}");
    let stops: Vec<u32> = server
        .requests()
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::Stop))
        .map(|request| request.axis)
        .collect();
    assert_eq!(stops, [CommandRequest::ALL_AXES, 0]);
    assert!(run(server.name(), &["reset"])?.status.success());
    assert!(!server.estop_latched());

    // 2. Every command client slot taken too: the estop event.
    let commands = hog
        .service_builder(&ServiceName::new(&names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .open()?;
    let mut held_clients = Vec::new();
    while let Ok(client) = commands.client_builder().create() {
        held_clients.push(client);
    }
    assert_eq!(held_clients.len(), slots);
    assert_fails(&run(server.name(), &["stop"])?, 3, "no free client slot");
    let estop = run(server.name(), &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    assert!(
        stdout(&estop).contains("via the estop event service"),
        "{estop:?}"
    );
    poll_latched(&server)?;

    // Free one client slot to reset, then take it again.
    held_clients.pop();
    assert!(run(server.name(), &["reset"])?.status.success());
    assert!(!server.estop_latched());
    held_clients.push(commands.client_builder().create()?);

    // 3. Every estop notifier slot taken too: SIGUSR1 to the server's process.
    let event = hog
        .service_builder(&ServiceName::new(&names.estop())?)
        .event()
        .open()?;
    let mut held_notifiers = Vec::new();
    while let Ok(notifier) = event.notifier_builder().create() {
        held_notifiers.push(notifier);
    }
    assert_eq!(held_notifiers.len(), slots);
    let estop = run(server.name(), &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    let said = stdout(&estop);
    assert!(
        said.contains(&format!(
            "via SIGUSR1 to the server process (pid {})",
            std::process::id()
        )),
        "{said}"
    );
    poll_latched(&server)?;
    assert_eq!(server.estop_sources(), ["command", "event", "signal"]);

    // No server at all: exit 3, one line.
    let absent = run(&unique_name("absent"), &["estop"])?;
    assert_fails(&absent, 3, "NOT delivered");
    Ok(())
}

fn poll_latched(server: &motion_client::testing::FakeServer) -> Result {
    let until = std::time::Instant::now() + DEADLINE;
    while !server.estop_latched() {
        if std::time::Instant::now() > until {
            return Err("the e-stop never latched".into());
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    Ok(())
}
