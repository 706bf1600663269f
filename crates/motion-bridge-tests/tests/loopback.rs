//! A remote client through a bridge over loopback TCP, against the fake motiond of
//! `motion-client` (in this process): what crosses the network, what the bridge lets
//! through, and what it never does on its own.

use core::time::Duration;

use iceoryx2::prelude::ipc;
use motion_bridge_tests::{BridgeThread, DEADLINE, Result, eventually, fake, remote};
use motion_client::ipc::{AxisFlags, AxisMode, CommandKind, CommandRequest, Reason};
use motion_client::{Client, ClientError};

/// `operator` may do anything, `viewer` only stop and e-stop; nobody else anything.
const RULES: &str = r#"
[[remote]]
identity = "operator"
allow = ["all"]

[[remote]]
identity = "viewer"
allow = ["stop", "estop"]
"#;

fn count(requests: &[CommandRequest], kind: CommandKind, axis: u32) -> usize {
    requests
        .iter()
        .filter(|r| r.kind == kind as u32 && r.axis == axis)
        .count()
}

#[test]
fn a_remote_client_describes_moves_and_reads_as_a_local_one_does() -> Result {
    let server = fake("bridge-describe")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let client = remote(server.name(), &bridge.endpoint, "operator")?;
    assert!(client.is_remote());
    assert_eq!(client.remote_identity(), Some("operator"));

    let info = client.info()?;
    let names: Vec<&str> = info.axes().iter().map(|axis| axis.name()).collect();
    assert_eq!(names, ["x", "y", "a"]);
    assert_eq!((info.tick_hz, info.command_timeout_ms), (500, 250));
    assert_eq!(info.signals().len(), 4);
    let params = client.machine_params()?;
    assert!(
        params
            .entries()
            .iter()
            .any(|p| p.key() == "baud" && p.value() == "19200 baud"),
        "{:?}",
        params.entries().first()
    );
    eventually("statistics arrive", || Ok(client.stats()?.is_some()))?;

    client.wait_ready(DEADLINE)?;
    let x = client.axis("x")?;
    x.ramp_to(12.5, 0.0, 0.0)?;
    x.wait_until_arrived(DEADLINE)?;
    let state = x.state()?;
    assert!((state.position - 12.5).abs() < 1e-9, "{state:?}");
    assert!(state.flags().contains(AxisFlags::ARRIVED));

    // The server's own refusals pass through with their reason.
    match x.position(1e6) {
        Err(ClientError::Refused {
            reason: Reason::OutOfRange,
            ..
        }) => {}
        other => return Err(format!("expected OutOfRange, got {other:?}").into()),
    }
    // Every request reached the server from the bridge's node, without a client id of
    // its own (an id from another host would be refused as borrowed).
    let requests = server.requests();
    assert!(requests.iter().all(|r| r.client.is_none()), "{requests:?}");
    assert_eq!(count(&requests, CommandKind::RampPosition, 0), 1);
    Ok(())
}

#[test]
fn a_command_not_on_the_allow_list_never_reaches_the_server() -> Result {
    let server = fake("bridge-allow")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let viewer = remote(server.name(), &bridge.endpoint, "viewer")?;
    let y = viewer.axis("y")?;
    match y.ramp_to(5.0, 0.0, 0.0) {
        Err(ClientError::BridgeRefused { code, message, .. }) => {
            assert_eq!(code, "not-allowed");
            assert!(
                message.contains("ramp-position") && message.contains("viewer"),
                "{message}"
            );
        }
        other => return Err(format!("expected a refusal by the bridge, got {other:?}").into()),
    }
    y.stop()?;
    let requests = server.requests();
    assert_eq!(
        count(&requests, CommandKind::RampPosition, 1),
        0,
        "{requests:?}"
    );
    assert_eq!(count(&requests, CommandKind::Stop, 1), 1);

    // An identity without a [[remote]] entry (and no `*` entry) may not even stop.
    let stranger = remote(server.name(), &bridge.endpoint, "stranger")?;
    match stranger.axis("y")?.stop() {
        Err(ClientError::BridgeRefused { code, message, .. }) => {
            assert_eq!(code, "not-allowed");
            assert!(message.contains("stranger"), "{message}");
        }
        other => return Err(format!("expected a refusal by the bridge, got {other:?}").into()),
    }
    // Reading is open to every identity.
    assert_eq!(stranger.info()?.axes().len(), 3);
    Ok(())
}

#[test]
fn the_bridge_never_renews_a_jog_on_its_own() -> Result {
    let server = fake("bridge-deadman")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let client = remote(server.name(), &bridge.endpoint, "operator")?;
    client.wait_ready(DEADLINE)?;
    // One velocity request, no guard to renew it: the server's deadman (250 ms) ends it.
    let reply = client.send(0, CommandKind::Velocity, [5.0, 0.0, 0.0])?;
    assert_eq!(reply.result(), Ok(()));
    eventually("the deadman stops x", || {
        let state = client.axis("x")?.state()?;
        Ok(state.flags().contains(AxisFlags::DEADMAN_EXPIRED))
    })?;
    let requests = server.requests();
    assert_eq!(
        count(&requests, CommandKind::Velocity, 0),
        1,
        "{requests:?}"
    );
    assert_eq!(count(&requests, CommandKind::Stop, 0), 0);
    Ok(())
}

#[test]
fn a_remote_jog_is_renewed_by_its_guard_and_stopped_when_the_client_vanishes() -> Result {
    let server = fake("bridge-vanish")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let client = remote(server.name(), &bridge.endpoint, "operator")?;
    client.wait_ready(DEADLINE)?;
    let jog = client.axis("x")?.jog(5.0, 0.0)?;
    // Read frames for longer than the deadman: the guard renews through the bridge.
    let until = std::time::Instant::now() + Duration::from_millis(900);
    while std::time::Instant::now() < until {
        client.next_frame(Duration::from_secs(1))?;
    }
    let state = client.axis("x")?.state()?;
    assert_eq!(state.mode(), Ok(AxisMode::RampVelocity), "{state:?}");
    assert!(!state.flags().contains(AxisFlags::DEADMAN_EXPIRED));
    let renewals = count(&server.requests(), CommandKind::RampVelocity, 0);
    assert!(renewals > 1, "renewed {renewals} times");

    // The client vanishes without stopping (as a killed process): no stop from it, its
    // zenoh session closes, and the bridge stops the jog it forwarded.
    std::mem::forget(jog);
    drop(client);
    eventually("the bridge stops x for the vanished client", || {
        Ok(count(&server.requests(), CommandKind::Stop, 0) == 1)
    })?;
    let local = Client::<ipc::Service>::connect(server.name())?;
    eventually("x stops", || {
        let state = local.axis("x")?.state()?;
        Ok(state.mode() == Ok(AxisMode::Hold))
    })?;
    Ok(())
}

#[test]
fn claims_belong_to_the_remote_client_that_took_them() -> Result {
    let server = fake("bridge-claims")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let first = remote(server.name(), &bridge.endpoint, "operator")?;
    let second = remote(server.name(), &bridge.endpoint, "operator")?;
    first.wait_ready(DEADLINE)?;
    let guard = first.axis("y")?.claim_guard()?;
    match second.axis("y")?.ramp_to(3.0, 0.0, 0.0) {
        Err(ClientError::Refused {
            reason: Reason::ClaimedByOther,
            ..
        }) => {}
        other => return Err(format!("expected ClaimedByOther, got {other:?}").into()),
    }
    match second.axis("y")?.release() {
        Err(ClientError::Refused {
            reason: Reason::NotClaimed,
            ..
        }) => {}
        other => return Err(format!("expected NotClaimed, got {other:?}").into()),
    }
    // Anyone may stop any axis.
    second.axis("y")?.stop()?;
    first.axis("y")?.ramp_to(3.0, 0.0, 0.0)?;
    // The server never saw the second client's goal.
    assert_eq!(count(&server.requests(), CommandKind::RampPosition, 1), 1);
    guard.release()?;
    second.axis("y")?.ramp_to(4.0, 0.0, 0.0)?;
    Ok(())
}

#[test]
fn without_a_server_behind_it_the_bridge_says_so() -> Result {
    let bridge = BridgeThread::start("bridge-nobody", RULES)?;
    let started = std::time::Instant::now();
    let error = motion_client::ClientBuilder::new("bridge-nobody")
        .connect_timeout(Duration::from_millis(600))
        .remote(&bridge.endpoint)
        .connect::<ipc::Service>()
        .expect_err("no server");
    let text = error.to_string();
    assert!(
        text.contains("no motion-bridge") || text.contains("description"),
        "{text}"
    );
    assert!(started.elapsed() < DEADLINE);
    // And with no bridge at all: the endpoint nobody listens on.
    let port = motion_bridge_tests::free_port()?;
    let error = motion_client::ClientBuilder::new("bridge-nobody")
        .connect_timeout(Duration::from_millis(300))
        .remote(&format!("tcp/127.0.0.1:{port}"))
        .connect::<ipc::Service>()
        .expect_err("no bridge");
    // Why is a type, not words: zenoh's own error, or the key nobody answered.
    assert!(
        matches!(
            error,
            motion_client::ConnectError::NoBridge {
                why: motion_client::Unanswered::Remote(_)
                    | motion_client::Unanswered::NoAnswer { .. }
                    | motion_client::Unanswered::NoBridge { .. },
                ..
            }
        ),
        "{error:?}"
    );
    Ok(())
}

#[test]
fn a_bridge_that_stops_stops_the_remote_jogs_first() -> Result {
    let server = fake("bridge-exit")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let client = remote(server.name(), &bridge.endpoint, "operator")?;
    client.wait_ready(DEADLINE)?;
    let reply = client.send(1, CommandKind::Velocity, [5.0, 0.0, 0.0])?;
    assert_eq!(reply.result(), Ok(()));
    drop(bridge);
    let requests = server.requests();
    assert_eq!(count(&requests, CommandKind::Stop, 1), 1, "{requests:?}");
    Ok(())
}

#[test]
fn a_server_restart_behind_the_bridge_is_noticed_by_the_remote_client() -> Result {
    let mut server = fake("bridge-restart")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let client = remote(server.name(), &bridge.endpoint, "operator")?;
    client.wait_ready(DEADLINE)?;
    client.axis("x")?.ramp_to(1.0, 0.0, 0.0)?;
    server.restart()?;
    // The bridge passes the new server's node along with its description.
    eventually("the remote client notices the restart", || {
        Ok(client.check_server().is_err())
    })?;
    match client.axis("x")?.ramp_to(2.0, 0.0, 0.0) {
        Err(ClientError::ServerRestarted(restart)) => assert_eq!(restart.count, 1),
        other => return Err(format!("expected ServerRestarted, got {other:?}").into()),
    }
    assert!(client.acknowledge_restart().is_some());
    eventually("the new server takes commands through the bridge", || {
        Ok(client.axis("x")?.ramp_to(2.0, 0.0, 0.0).is_ok())
    })?;
    Ok(())
}
