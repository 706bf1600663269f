//! A server that restarts under a running motionctl: the jog and the claims end with a
//! clear message, and nothing is sent on their behalf to the new server.

mod common;

use core::time::Duration;
use std::process::Stdio;
use std::time::Instant;

use common::*;
use motion_client::ipc::CommandKind;

/// Waits until the fake logged a request of `kind`.
fn wait_for_request(server: &motion_client::testing::FakeServer, kind: CommandKind) -> Result {
    let until = Instant::now() + DEADLINE;
    while !server.requests().iter().any(|r| r.kind() == Ok(kind)) {
        if Instant::now() > until {
            return Err(format!("no {kind:?} request").into());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(())
}

#[test]
fn a_jog_ends_when_the_server_restarts_and_is_never_renewed_on_the_new_one() -> Result {
    let mut server = fake("jogrestart")?;
    let child = command(server.name(), &["jog", "x", "5"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    wait_for_request(&server, CommandKind::RampVelocity)?;
    std::thread::sleep(Duration::from_millis(300)); // renewed past the deadman
    server.restart()?;
    let output = finish(child, DEADLINE)?;
    assert_fails(&output, 1, "restarted");
    assert!(
        stderr(&output).contains("jog x ended: nothing more is sent to the new server"),
        "{output:?}"
    );
    let after: Vec<(Option<CommandKind>, u32)> = server
        .requests_since_restart()
        .iter()
        .map(|request| (request.kind().ok(), request.axis))
        .collect();
    // What the new server took from the jog: nothing, or one renewal that crossed the
    // restart and was stopped at once.
    assert!(
        after.is_empty()
            || after
                == [
                    (Some(CommandKind::RampVelocity), 0),
                    (Some(CommandKind::Stop), 0)
                ],
        "{after:?}"
    );
    assert_eq!(axis_field(&status_json(server.name())?, 0, "mode"), "hold");
    Ok(())
}

#[test]
fn claims_end_when_the_server_restarts() -> Result {
    let mut server = fake("claimrestart")?;
    let child = command(server.name(), &["claim", "y", "--duration", "20s"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    wait_for_request(&server, CommandKind::Claim)?;
    server.restart()?;
    let output = finish(child, DEADLINE)?;
    assert_fails(&output, 1, "restarted");
    let after: Vec<Option<CommandKind>> = server
        .requests_since_restart()
        .iter()
        .map(|request| request.kind().ok())
        .collect();
    assert!(
        !after.contains(&Some(CommandKind::Release)),
        "no release sent to the new server: {after:?}"
    );
    // The new server has no claim on y: another client moves it.
    assert!(
        run(server.name(), &["move", "y", "1", "--wait"])?
            .status
            .success()
    );
    Ok(())
}
