//! A server that restarts under its clients, and a client that needs only the ports it uses
//! (frames subscribed lazily; an e-stop that gets through exhausted command ports).

use core::time::Duration;
use std::time::Instant;

use iceoryx2::node::NodeBuilder;
use iceoryx2::prelude::{ServiceName, local};
use motion_client::ipc::{
    AxisMode, CommandKind, CommandReply, CommandRequest, MotionFrame, ServerInfo, ServiceNames,
};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientBuilder, ClientError, ConnectError, EstopPath, estop, stop_all};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(5);

fn start(prefix: &str) -> Result<(FakeServer, Client<local::Service>)> {
    let server = FakeServer::start::<local::Service>(FakeConfig::demo(&unique_name(prefix)))?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

fn count(server: &FakeServer, kind: CommandKind) -> usize {
    server
        .requests()
        .iter()
        .filter(|request| request.kind() == Ok(kind))
        .count()
}

/// Reads frames until `until` passes.
fn read_frames_for(client: &Client<local::Service>, span: Duration) -> Result {
    let until = Instant::now() + span;
    while Instant::now() < until {
        match client.next_frame(WAIT) {
            Ok(_) => {}
            Err(ClientError::ServerRestarted(_)) => {}
            Err(error) => return Err(error.into()),
        }
    }
    Ok(())
}

#[test]
fn a_jog_guard_never_renews_on_a_restarted_server() -> Result {
    let (mut server, client) = start("jogrestart")?;
    let x = client.axis("x")?;
    let jog = x.jog(10.0, 0.0)?;
    read_frames_for(&client, Duration::from_millis(200))?;
    assert!(
        count(&server, CommandKind::RampVelocity) >= 2,
        "renewed before the restart"
    );
    server.restart()?;
    // Three renewal periods of the 250 ms deadman.
    read_frames_for(&client, Duration::from_millis(300))?;
    let restart = client.restart().ok_or("restart not noticed")?;
    assert_eq!(restart.count, 1);
    assert_eq!(restart.new_pid, Some(std::process::id()));
    let error = jog.check().expect_err("the guard reports the restart");
    assert!(
        matches!(error, ClientError::ServerRestarted(_)),
        "{error:?}"
    );
    assert!(error.to_string().contains("restarted"), "{error}");
    let error = jog.set(5.0).expect_err("never re-sent");
    assert!(
        matches!(error, ClientError::ServerRestarted(_)),
        "{error:?}"
    );
    drop(jog); // sends nothing to the new server
    assert_eq!(
        server.requests_since_restart(),
        [],
        "nothing reached the new server"
    );
    assert_eq!(x.state()?.mode(), Ok(AxisMode::Hold));
    Ok(())
}

#[test]
fn goals_wait_for_the_restart_to_be_acknowledged_but_stops_do_not() -> Result {
    let (mut server, client) = start("ackrestart")?;
    let x = client.axis("x")?;
    x.ramp_to(90.0, 1.0, 0.0)?;
    server.restart()?;
    let aborted = x.wait_until_arrived(WAIT).expect_err("the goal died");
    assert!(
        matches!(aborted, ClientError::ServerRestarted(_)),
        "{aborted:?}"
    );
    let before = server.requests().len();
    let refused = x.position(1.0).expect_err("not acknowledged");
    assert!(
        matches!(refused, ClientError::ServerRestarted(_)),
        "{refused:?}"
    );
    assert_eq!(server.requests().len(), before, "the goal was not sent");
    x.stop()?; // always sent
    client.check_server().expect_err("still pending");
    let acknowledged = client.acknowledge_restart().ok_or("nothing pending")?;
    assert_eq!(acknowledged.count, 1);
    client.check_server()?;
    x.position(1.0)?;
    x.wait_until_arrived(WAIT)?;
    Ok(())
}

#[test]
fn a_claim_guard_reports_the_restart_and_sends_no_release() -> Result {
    let (mut server, client) = start("claimrestart")?;
    let guard = client.axis("y")?.claim_guard()?;
    guard.renew()?;
    server.restart()?;
    let until = Instant::now() + WAIT;
    while guard.check().is_ok() {
        assert!(Instant::now() < until, "restart never seen");
        std::thread::sleep(Duration::from_millis(10));
    }
    let before = server.requests().len();
    assert!(matches!(
        guard.renew(),
        Err(ClientError::ServerRestarted(_))
    ));
    let error = guard.release().expect_err("nothing to release");
    assert!(
        matches!(error, ClientError::ServerRestarted(_)),
        "{error:?}"
    );
    assert_eq!(server.requests().len(), before);
    Ok(())
}

/// Holds every subscriber slot of the frame service.
fn take_frame_slots(
    node: &iceoryx2::node::Node<local::Service>,
    name: &str,
    slots: usize,
) -> Result<Vec<iceoryx2::port::subscriber::Subscriber<local::Service, MotionFrame, ()>>> {
    let service = node
        .service_builder(&ServiceName::new(&ServiceNames::new(name).frame())?)
        .publish_subscribe::<MotionFrame>()
        .open()?;
    let mut held = Vec::new();
    for _ in 0..slots {
        held.push(service.subscriber_builder().create()?);
    }
    Ok(held)
}

/// A client that can open the info service only at the end of its connect timeout (every
/// node slot of the service taken until then: it retries) still gets the server
/// description: it was told "published no server description …; is it still starting
/// up?" (found by the reliability campaign 5, 64 clients churning past `max_clients`).
#[test]
fn a_client_that_waited_for_a_node_slot_still_gets_the_description() -> Result {
    // A slow server (4 ticks/s: history delivered up to 250 ms after the subscriber came).
    let mut config = FakeConfig::demo(&unique_name("late_slot"));
    config.tick_hz = 4;
    let server = FakeServer::start::<local::Service>(config)?;
    let name = server.name().to_owned();
    let (held_tx, held_rx) = std::sync::mpsc::channel();
    // Every node slot of the info service, held by nodes of a thread of its own (ports stay
    // on their thread) until shortly before the client's connect timeout ends.
    let hog = std::thread::spawn(move || -> core::result::Result<usize, String> {
        let service_name =
            ServiceName::new(&ServiceNames::new(&name).info()).map_err(|e| format!("{e:?}"))?;
        let mut held = Vec::new();
        loop {
            let node = NodeBuilder::new()
                .create::<local::Service>()
                .map_err(|e| format!("{e:?}"))?;
            match node
                .service_builder(&service_name)
                .publish_subscribe::<ServerInfo>()
                .open()
            {
                Ok(service) => held.push((service, node)),
                Err(_) if !held.is_empty() => break,
                Err(e) => return Err(format!("{e:?}")),
            }
        }
        let count = held.len();
        let _ = held_tx.send(());
        std::thread::sleep(Duration::from_millis(940));
        drop(held);
        Ok(count)
    });
    held_rx.recv_timeout(WAIT)?;
    let started = Instant::now();
    let client = ClientBuilder::new(server.name())
        .connect_timeout(Duration::from_secs(1))
        .connect::<local::Service>();
    let held = hog.join().map_err(|_| "the slot holder panicked")??;
    let client = client?;
    assert!(held > 0);
    assert!(
        started.elapsed() >= Duration::from_millis(900),
        "the slots were held"
    );
    assert_eq!(client.axis("x")?.name(), "x");
    Ok(())
}

#[test]
fn a_client_commands_while_every_frame_slot_is_taken() -> Result {
    let server = FakeServer::start::<local::Service>(FakeConfig::demo(&unique_name("slots")))?;
    let hog = NodeBuilder::new().create::<local::Service>()?;
    let _held = take_frame_slots(&hog, server.name(), server.config().max_clients)?;
    let client = Client::<local::Service>::connect(server.name())?;
    client.axis("x")?.position(5.0)?;
    client.stop_all()?;
    let error = client.latest().expect_err("no frame slot left");
    assert!(
        matches!(
            error,
            ClientError::Connect(ConnectError::PortsExhausted { .. })
        ),
        "{error:?}"
    );
    assert!(error.to_string().contains("max_clients"), "{error}");
    Ok(())
}

#[test]
fn estop_takes_the_command_path_then_the_event_when_command_slots_are_taken() -> Result {
    let server = FakeServer::start::<local::Service>(FakeConfig::demo(&unique_name("paths")))?;
    let done = estop::<local::Service>(server.name(), WAIT)?;
    assert!(matches!(done.path, EstopPath::Command { .. }), "{done:?}");
    // Seen in a frame of the accepting tick or later.
    let EstopPath::Command { tick } = done.path else {
        unreachable!()
    };
    assert!(
        done.seen_in_frame.is_some_and(|seen| seen >= tick),
        "{done:?}"
    );
    assert!(server.estop_latched());
    stop_all::<local::Service>(server.name(), WAIT)?;
    assert_eq!(count(&server, CommandKind::Stop), 1);

    let client = Client::<local::Service>::connect(server.name())?;
    client.reset()?;
    let hog = NodeBuilder::new().create::<local::Service>()?;
    let service = hog
        .service_builder(&ServiceName::new(
            &ServiceNames::new(server.name()).command(),
        )?)
        .request_response::<CommandRequest, CommandReply>()
        .open()?;
    // The client above holds one slot; take the rest.
    let mut held = Vec::new();
    while let Ok(port) = service.client_builder().create() {
        held.push(port);
    }
    assert_eq!(held.len() + 1, server.config().max_clients);
    let error = stop_all::<local::Service>(server.name(), WAIT).expect_err("no client slot");
    assert!(error.to_string().contains("client slot"), "{error}");
    let done = estop::<local::Service>(server.name(), WAIT)?;
    assert_eq!(done.path, EstopPath::Event { listeners: 1 });
    assert_eq!(
        done.path.to_string(),
        "the estop event service (1 listener notified)"
    );
    // An event has no reply: only a frame showing the latch made it a success.
    assert!(done.seen_in_frame.is_some(), "{done:?}");
    let until = Instant::now() + WAIT;
    while !server.estop_latched() {
        assert!(Instant::now() < until, "the event never latched the e-stop");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(server.estop_sources(), ["command", "event"]);
    Ok(())
}

#[test]
fn a_renewal_that_reached_a_restarted_server_is_stopped_at_once() -> Result {
    // The new server describes itself only after 0.5 s, and the client reads no frames:
    // it learns of the restart from the reply to a renewal that the new server took (the
    // start-up race of a real restart, made certain).
    let mut config = FakeConfig::demo(&unique_name("latedesc"));
    config.info_delay_ticks = 250;
    let mut server = FakeServer::start::<local::Service>(config)?;
    let client = Client::<local::Service>::connect(server.name())?;
    let x = client.axis("x")?;
    let jog = x.jog(10.0, 0.0)?;
    server.restart()?;
    let until = Instant::now() + Duration::from_millis(300);
    while Instant::now() < until {
        client.keep_alive();
        std::thread::sleep(Duration::from_millis(5));
    }
    let restart = client.restart().ok_or("restart not noticed")?;
    assert_eq!(restart.seen_in, "command reply");
    assert!(matches!(jog.check(), Err(ClientError::ServerRestarted(_))));
    drop(jog);
    let after: Vec<(Option<CommandKind>, u32)> = server
        .requests_since_restart()
        .iter()
        .map(|request| (request.kind().ok(), request.axis))
        .collect();
    assert_eq!(
        after,
        [
            (Some(CommandKind::RampVelocity), 0),
            (Some(CommandKind::Stop), 0)
        ],
        "one renewal got through and was stopped in the same breath; nothing more"
    );
    client.next_frame(WAIT)?;
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(x.state()?.mode(), Ok(AxisMode::Hold));
    Ok(())
}
