//! `motionctl estop` gets through whatever is exhausted: frame subscriber slots (command
//! path), command client slots (estop event path), and event notifier slots too (SIGUSR1 to
//! the process the server's pid file names: this test process, whose fake server writes the
//! pid file and latches on SIGUSR1 like motiond). It reports success only when the server
//! said so: the command service's reply, or for an event or a signal a frame showing the
//! latch — with every frame slot taken those exit 5, "NOT confirmed". One test in its own
//! binary: the SIGUSR1 handler is process-wide, so no other fake server may run in this
//! process meanwhile.

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
    // No frame to see it in: the reply of the instance's one server port is the word.
    assert!(
        stdout(&estop).contains("no frame subscriber slot free to see it in a frame"),
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
    // An event has no reply: with every frame slot taken nothing can show the latch, so
    // the e-stop is not reported as done (exit 5), though the server did latch.
    let estop = run(server.name(), &["estop"])?;
    assert_fails(&estop, 5, "sent via the estop event service");
    assert_fails(&estop, 5, "NOT confirmed");
    poll_latched(&server)?;
    reset_through_one_free_slot(&server, &mut held_clients, &commands)?;
    // One frame slot free: a frame shows the latch.
    held_frames.pop();
    let estop = run(server.name(), &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    assert!(
        stdout(&estop).contains("via the estop event service"),
        "{estop:?}"
    );
    assert!(
        stdout(&estop).contains("latched in the frame of tick"),
        "{estop:?}"
    );
    poll_latched(&server)?;
    reset_through_one_free_slot(&server, &mut held_clients, &commands)?;

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
    // Every frame slot taken again: sent to the pid file's process, not confirmed.
    held_frames.push(frames.subscriber_builder().create()?);
    let estop = run(server.name(), &["estop"])?;
    assert_fails(&estop, 5, "NOT confirmed");
    assert!(
        stderr(&estop).contains(&format!(
            "sent via SIGUSR1 to the server process (pid {})",
            std::process::id()
        )),
        "{estop:?}"
    );
    poll_latched(&server)?;
    reset_through_one_free_slot(&server, &mut held_clients, &commands)?;
    held_frames.pop();
    let estop = run(server.name(), &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    let said = stdout(&estop);
    assert!(said.contains("latched in the frame of tick"), "{said}");
    assert!(
        said.contains(&format!(
            "via SIGUSR1 to the server process (pid {})",
            std::process::id()
        )),
        "{said}"
    );
    poll_latched(&server)?;
    assert_eq!(
        server.estop_sources(),
        ["command", "event", "event", "signal", "signal"]
    );

    // No server at all: exit 3, one line.
    let absent = run(&unique_name("absent"), &["estop"])?;
    assert_fails(&absent, 3, "NOT delivered");
    Ok(())
}

/// Frees one command client slot of `held`, resets the e-stop through it, takes it again.
fn reset_through_one_free_slot(
    server: &motion_client::testing::FakeServer,
    held: &mut Vec<
        iceoryx2::port::client::Client<ipc::Service, CommandRequest, (), CommandReply, ()>,
    >,
    commands: &iceoryx2::service::port_factory::request_response::PortFactory<
        ipc::Service,
        CommandRequest,
        (),
        CommandReply,
        (),
    >,
) -> Result {
    held.pop();
    let reset = run(server.name(), &["reset"])?;
    assert!(reset.status.success(), "{reset:?}");
    assert!(!server.estop_latched());
    held.push(commands.client_builder().create()?);
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
