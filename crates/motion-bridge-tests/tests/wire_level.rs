//! The bridge's network contract as a peer in another language would see it: raw zenoh,
//! bytes in the `motion-ipc` C layout, the attachments and the refusal texts of
//! `motion_wire::keys`.

use core::time::Duration;
use std::time::Instant;

use motion_bridge_tests::raw::{Granted, Sign, Z as _, command, open_session, session};
use motion_bridge_tests::{BridgeThread, DEADLINE, Result, fake};
use motion_client::ipc::{ClientId, CommandKind, CommandRequest, MotionFrame, Reason, ServerInfo};
use motion_wire::keys::{Keys, Origin, Refusal};
use motion_wire::wire;
use zenoh::Wait as _;

const RULES: &str = r#"
frame_rate = 50

[[remote]]
identity = "tool"
allow = ["all"]

[[remote]]
identity = "slow"
allow = ["all"]
rate = 1
burst = 2
"#;

#[test]
fn frames_are_decimated_and_every_sample_says_which_server_wrote_it() -> Result {
    let server = fake("wire-frames")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let keys = Keys::new(server.name())?;
    let session = session(&bridge.endpoint)?;
    let frames = session.declare_subscriber(keys.frame()).wait().z()?;
    // The bridge answers "no-server" until its subscriber has the server's description,
    // which may come a moment after the bridge started: ask until it has.
    let until = Instant::now() + DEADLINE;
    let info = loop {
        let reply = session
            .get(keys.info())
            .timeout(DEADLINE)
            .wait()
            .z()?
            .recv_timeout(DEADLINE)
            .z()?
            .ok_or("no description")?;
        match reply.into_result() {
            Ok(sample) => break sample,
            Err(error) if Instant::now() < until => {
                let text = String::from_utf8_lossy(&error.payload().to_bytes()).into_owned();
                assert!(text.starts_with("no-server"), "{text}");
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(error) => return Err(format!("{error:?}").into()),
        }
    };
    let description = wire::decode::<ServerInfo>(&info.payload().to_bytes())?;
    let server_node =
        Origin::decode(&info.attachment().ok_or("no origin")?.to_bytes()).ok_or("bad origin")?;
    assert_eq!(description.name(), server.name());
    assert_ne!(server_node, Origin(0));

    let mut ticks = Vec::new();
    while ticks.len() < 12 {
        let sample = frames.recv_timeout(DEADLINE).z()?.ok_or("no frame")?;
        let bytes = sample.payload().to_bytes();
        assert_eq!(bytes.len(), 21968, "the C layout of MotionFrame");
        let frame = wire::decode::<MotionFrame>(&bytes)?;
        assert_eq!(frame.axes().len(), 3);
        let origin = Origin::decode(&sample.attachment().ok_or("no origin")?.to_bytes());
        assert_eq!(origin, Some(server_node));
        ticks.push(frame.tick);
    }
    // 500 Hz ticks at 50 frames/s: every 10th tick at most, never two from one window.
    for pair in ticks.windows(2) {
        assert!(pair[1] >= pair[0] + 10, "{ticks:?}");
    }

    let states = session.declare_subscriber(keys.state_json()).wait().z()?;
    let sample = states.recv_timeout(DEADLINE).z()?.ok_or("no JSON state")?;
    let state: serde_json::Value = serde_json::from_slice(&sample.payload().to_bytes())?;
    assert_eq!(state["server"], server.name());
    assert_eq!(state["axes"][2]["name"], "a");
    assert_eq!(state["axes"][2]["unit"], "deg");
    assert_eq!(state["devices"][1]["name"], "aux");
    assert_eq!(
        state["devices"][1]["model"], "qsb",
        "named by DeviceInfo::model_id"
    );
    Ok(())
}

#[test]
fn malformed_late_and_too_frequent_requests_are_refused_by_the_bridge() -> Result {
    let server = fake("wire-refusals")?;
    let bridge = BridgeThread::start(server.name(), RULES)?;
    let keys = Keys::new(server.name())?;
    let session = session(&bridge.endpoint)?;
    // The remote's own clock, 10 s ahead of the test's start.
    let start = Instant::now();
    let clock = || start.elapsed() + Duration::from_secs(10);
    let ns = |sent: Duration| sent.as_nanos() as u64;
    let tool = open_session(&session, &keys, "tool", ns(clock()))??;
    let tool_again = open_session(&session, &keys, "tool", ns(clock()))??;
    let slow = open_session(&session, &keys, "slow", ns(clock()))??;
    assert_ne!(tool.token, tool_again.token, "every opening its own secret");
    let meta = |grant: &Granted, sent: Duration| Sign::of(grant, ns(sent));
    let stop = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Stop);
    let position = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Position)
        .with_values([1.0, 0.0, 0.0]);

    // A stop needs no attachment; anything else needs a session.
    let (reply, _) = command(&session, &keys, "tool", &stop, None)?
        .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Ok(()));
    let refused = command(&session, &keys, "tool", &position, None)?.expect_err("refused");
    assert_eq!(
        Refusal::parse(&refused).map(|r| r.0),
        Some(Refusal::NoSession),
        "{refused}"
    );
    // A short payload.
    let replies = session
        .get(keys.command("tool"))
        .payload(vec![1u8, 2, 3])
        .attachment(meta(&tool, clock()).meta("tool", &[1, 2, 3]).encode())
        .wait()
        .z()?;
    let reply = replies.recv_timeout(DEADLINE).z()?.ok_or("no reply")?;
    let text = reply
        .result()
        .err()
        .ok_or("accepted garbage")?
        .payload()
        .try_to_string()?
        .into_owned();
    assert!(
        text.starts_with("bad-request: ") && text.contains("3 bytes"),
        "{text}"
    );

    // The bare command key is the identity `anonymous` (no rule here: not allowed).
    let replies = session
        .get(format!("motiond/{}/command", server.name()))
        .payload(wire::encode(&stop))
        .attachment(
            meta(&tool, clock())
                .meta("anonymous", &wire::encode(&stop))
                .encode(),
        )
        .wait()
        .z()?;
    let reply = replies.recv_timeout(DEADLINE).z()?.ok_or("no reply")?;
    let text = reply
        .result()
        .err()
        .ok_or("anonymous was allowed")?
        .payload()
        .try_to_string()?
        .into_owned();
    assert!(
        text.starts_with("not-allowed: ") && text.contains("`anonymous`"),
        "{text}"
    );

    // A request on time is forwarded; the reply comes from the server, with its node.
    let (reply, origin) = command(&session, &keys, "tool", &stop, Some(meta(&tool, clock())))?
        .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Ok(()));
    assert_eq!((reply.sequence, reply.kind), (1, CommandKind::Stop as u32));
    assert_ne!(origin, Origin(0));

    // A renewal that says it was sent 2 s ago (the deadman is 250 ms) is not applied; a
    // stop as late is.
    let velocity = CommandRequest::new(ClientId::NONE, 2, 0, CommandKind::Velocity)
        .with_values([1.0, 0.0, 0.0]);
    let two_seconds_ago = clock() - Duration::from_secs(2);
    // (The session's clock must have been seen on time first: sent "now" above.)
    let late = command(
        &session,
        &keys,
        "tool",
        &velocity,
        Some(meta(&tool, two_seconds_ago)),
    )?
    .expect_err("late");
    assert!(late.starts_with("late: "), "{late}");
    let (reply, _) = command(
        &session,
        &keys,
        "tool",
        &stop,
        Some(meta(&tool, two_seconds_ago)),
    )?
    .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Ok(()));
    let velocities = server
        .requests()
        .iter()
        .filter(|r| r.kind == CommandKind::Velocity as u32)
        .count();
    assert_eq!(velocities, 0);

    // `slow` may send 2 at once, then 1 a second (its opening took one); stops always pass.
    let mut outcomes = Vec::new();
    for sequence in 10..14 {
        let request = CommandRequest::new(ClientId::NONE, sequence, 1, CommandKind::Position)
            .with_values([1.0, 0.0, 0.0]);
        outcomes.push(command(
            &session,
            &keys,
            "slow",
            &request,
            Some(meta(&slow, clock())),
        )?);
    }
    assert!(outcomes[0].is_ok(), "{outcomes:?}");
    let limited = outcomes[3].as_ref().expect_err("over the rate");
    assert!(limited.starts_with("rate-limited: "), "{limited}");
    let (reply, _) = command(&session, &keys, "slow", &stop, Some(meta(&slow, clock())))?
        .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Ok(()));

    // Claims between remotes are answered for the server, as a CommandReply.
    let claim = CommandRequest::new(ClientId::NONE, 20, 2, CommandKind::Claim);
    let (reply, _) = command(&session, &keys, "tool", &claim, Some(meta(&tool, clock())))?
        .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Ok(()));
    let (reply, _) = command(
        &session,
        &keys,
        "tool",
        &claim,
        Some(meta(&tool_again, clock())),
    )?
    .map_err(|text| format!("refused: {text}"))?;
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    Ok(())
}
