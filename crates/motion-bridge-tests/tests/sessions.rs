//! A remote's session cannot be taken over, as a process sees it through zenoh: an id read
//! from a liveliness key or a session sent under another identity commands nothing; a peer
//! that sees commands (a queryable of its own on the command keys, zenoh's trace log) can
//! neither reuse nor replay them; a copy of a departed remote's liveliness key does not keep
//! its claim.

use core::time::Duration;
use std::process::{Command, Stdio};
use std::time::Instant;

use motion_bridge_tests::raw::{Sign, Z as _, command, open_session, session, wait_for_server};
use motion_bridge_tests::real;
use motion_bridge_tests::{
    BridgeThread, DEADLINE, Result, eventually, fake, free_port, remote, scratch,
};
use motion_client::ipc::{ClientId, CommandKind, CommandRequest};
use motion_wire::keys::{Keys, Refusal, RequestMeta, SessionToken};
use motion_wire::wire;
use zenoh::Wait as _;

/// The bridge's clock is not the test's: every remote keeps its own, here the test's
/// `Instant` since this start, shifted.
fn clock_ns(start: Instant, shift: Duration) -> u64 {
    (start.elapsed() + shift).as_nanos() as u64
}

#[test]
fn a_session_read_from_a_liveliness_key_or_copied_from_another_remote_is_refused() -> Result {
    let server = fake("hard-session")?;
    let rules = r#"
[[remote]]
identity = "operator"
allow = ["all"]

[[remote]]
identity = "intruder"
allow = ["all"]
"#;
    let bridge = BridgeThread::start(server.name(), rules)?;
    let keys = Keys::new(server.name())?;
    // The victim: a client that claims axis x.
    let victim = remote(server.name(), &bridge.endpoint, "operator")?;
    victim.wait_ready(DEADLINE)?;
    let _claim = victim.axis("x")?.claim_guard()?;

    // The attacker reads the victim's liveliness key, as anyone may.
    let attacker = session(&bridge.endpoint)?;
    let tokens = attacker
        .liveliness()
        .get(keys.remote_tokens())
        .timeout(Duration::from_secs(5))
        .wait()
        .z()?;
    let mut seen = Vec::new();
    while let Ok(reply) = tokens.recv() {
        if let Ok(sample) = reply.result()
            && let Some((identity, id)) = keys.remote_of(sample.key_expr().as_str())
        {
            seen.push((identity, id));
        }
    }
    let [(identity, public_id)] = &seen[..] else {
        return Err(format!("one remote token expected: {seen:?}").into());
    };
    assert_eq!(identity, "operator");

    let start = Instant::now();
    // The attacker's clock: 100 s since it booted.
    let now = || clock_ns(start, Duration::from_secs(100));
    let jog = CommandRequest::new(ClientId::NONE, 7, 0, CommandKind::Velocity)
        .with_values([5.0, 0.0, 0.0]);
    let no_session = |answer: core::result::Result<_, String>, what: &str| -> Result {
        match answer {
            Err(text) if Refusal::parse(&text).map(|r| r.0) == Some(Refusal::NoSession) => Ok(()),
            other => Err(format!("{what}: {other:?}").into()),
        }
    };
    // The public id as the secret, under the victim's identity: no session.
    let from_key = Sign {
        token: SessionToken(public_id.0.to_le_bytes()),
        session: *public_id,
        sent_ns: now(),
    };
    no_session(
        command(&attacker, &keys, "operator", &jog, Some(from_key))?,
        "the id of a liveliness key",
    )?;
    // A session of the attacker's own identity, its attachment sent under the victim's
    // identity — and a session of `operator` (opened by the attacker) sent under `intruder`.
    let own = open_session(&attacker, &keys, "intruder", now())??;
    let other = open_session(&attacker, &keys, "operator", now())??;
    for (identity, grant) in [("operator", own), ("intruder", other)] {
        let meta = Sign::of(&grant, now());
        match command(&attacker, &keys, identity, &jog, Some(meta))? {
            Err(text) => assert!(
                text.starts_with("no-session: ") && text.contains("another identity"),
                "{text}"
            ),
            Ok(reply) => return Err(format!("a copied session commanded: {reply:?}").into()),
        }
    }
    // A session's own first request, stamped 2 s before it opened, or 10 s ahead of its
    // clock: judged against the bridge's clock, not taken as the session's new normal.
    for (shift, what) in [(-2.0, "an old stamp"), (10.0, "a stamp from the future")] {
        let opened = open_session(&attacker, &keys, "intruder", now())??;
        let sent = (now() as f64 + shift * 1e9) as u64;
        let meta = Sign::of(&opened, sent);
        match command(&attacker, &keys, "intruder", &jog, Some(meta))? {
            Err(text) if text.starts_with("late: ") => {}
            other => return Err(format!("{what}: {other:?}").into()),
        }
    }
    let velocities = |server: &motion_client::testing::FakeServer| {
        server
            .requests()
            .iter()
            .filter(|r| r.kind == CommandKind::Velocity as u32)
            .count()
    };
    assert_eq!(
        velocities(&server),
        0,
        "the server never saw the attacker's jogs"
    );
    // The victim's own session goes on commanding its axis.
    victim.axis("x")?.velocity(1.0)?;
    assert_eq!(velocities(&server), 1);
    Ok(())
}

/// Under `--insecure` any peer may declare a queryable on the command keys and see every
/// command a remote sends. What it sees is a MAC, never the session's secret: the command
/// replayed is refused as a replay, its attachment on another request does not fit, and
/// no 16 bytes of it sign a request of the victim's session.
#[test]
fn a_peer_that_sees_a_command_cannot_command_with_it() -> Result {
    let server = fake("hard-mac")?;
    let rules = "[[remote]]\nidentity = \"operator\"\nallow = [\"all\"]\n";
    let bridge = BridgeThread::start(server.name(), rules)?;
    let keys = Keys::new(server.name())?;
    // The eavesdropper: a queryable of its own on every command key.
    let attacker = session(&bridge.endpoint)?;
    wait_for_server(&attacker, &keys)?;
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let kept = std::sync::Arc::clone(&seen);
    let _eavesdropper = attacker
        .declare_queryable(format!("motiond/{}/command/**", server.name()))
        .callback(move |query| {
            if let (Some(payload), Some(attachment)) = (query.payload(), query.attachment()) {
                kept.lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner)
                    .push((
                        payload.to_bytes().into_owned(),
                        attachment.to_bytes().into_owned(),
                    ));
            }
        })
        .wait()
        .z()?;
    // The victim jogs x through the bridge.
    let victim = remote(server.name(), &bridge.endpoint, "operator")?;
    victim.wait_ready(DEADLINE)?;
    victim.axis("x")?.velocity(1.0)?;
    let velocities = |server: &motion_client::testing::FakeServer| {
        server
            .requests()
            .iter()
            .filter(|r| r.kind == CommandKind::Velocity as u32)
            .count()
    };
    assert_eq!(velocities(&server), 1);
    let (payload, attachment) = seen
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .iter()
        .find(|(payload, _)| {
            wire::decode::<CommandRequest>(payload)
                .is_ok_and(|request| request.kind == CommandKind::Velocity as u32)
        })
        .cloned()
        .ok_or("the eavesdropper saw no jog")?;
    let meta = RequestMeta::decode(&attachment).ok_or("a 49-byte attachment")?;
    let ask = |payload: Vec<u8>, attachment: Vec<u8>| -> Result<String> {
        let reply = attacker
            .get(keys.command("operator"))
            .payload(payload)
            .attachment(attachment)
            .timeout(DEADLINE)
            .wait()
            .z()?
            .recv_timeout(DEADLINE)
            .z()?
            .ok_or("no answer")?;
        Ok(match reply.result() {
            Ok(_) => "accepted".to_owned(),
            Err(error) => error.payload().try_to_string()?.into_owned(),
        })
    };
    // 1. The same bytes again.
    let replayed = ask(payload.clone(), attachment.clone())?;
    assert!(
        replayed.starts_with("late: ") && replayed.contains("replay"),
        "{replayed}"
    );
    // 2. Its attachment on a faster jog.
    let faster = CommandRequest::new(ClientId::NONE, 9, 0, CommandKind::Velocity)
        .with_values([100.0, 0.0, 0.0]);
    let altered = ask(wire::encode(&faster), attachment.clone())?;
    assert!(
        altered.starts_with("no-session: ") && altered.contains("MAC"),
        "{altered}"
    );
    // 3. Every 16 bytes of what it saw, taken for the secret.
    let mut tried = 0;
    for window in attachment.windows(16).chain(payload.windows(16)) {
        let guess = SessionToken(window.try_into()?);
        let signed = RequestMeta::sign(
            guess,
            "operator",
            &wire::encode(&faster),
            meta.session,
            meta.counter + 1000 + tried,
            meta.sent_ns,
        );
        let answer = ask(wire::encode(&faster), signed.encode().to_vec())?;
        assert!(answer.starts_with("no-session: "), "{answer}");
        tried += 1;
    }
    eprintln!(
        "the eavesdropper's replay: {replayed}\nits attachment on another jog: {altered}\n{tried} \
         windows of what it saw tried as the secret: all refused"
    );
    assert_eq!(
        velocities(&server),
        1,
        "the server saw only the victim's jog"
    );
    victim.axis("x")?.velocity(2.0)?;
    assert_eq!(velocities(&server), 2, "the victim goes on");
    Ok(())
}

/// The `motion-bridge` binary with zenoh's trace log on: a session opened and commands sent
/// with it, and the session's secret appears nowhere in the log, in any of the forms a
/// log prints bytes in.
#[test]
fn the_secret_is_never_in_zenohs_trace_log() -> Result {
    let Some(binary) = real::binary("motion-bridge", "MOTION_BRIDGE_BIN") else {
        eprintln!(
            "SKIPPED the_secret_is_never_in_zenohs_trace_log: no motion-bridge beside this test \
             (`cargo build -p motion-bridge`, or ./scripts/test, builds it; or set \
             MOTION_BRIDGE_BIN)"
        );
        return Ok(());
    };
    let server = fake("hard-trace")?;
    let dir = scratch("hard-trace")?;
    let rules = dir.join("rules.toml");
    std::fs::write(
        &rules,
        "[[remote]]\nidentity = \"panel\"\nallow = [\"all\"]\n",
    )?;
    let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
    let mut child = Command::new(binary)
        .args([
            "--server",
            server.name(),
            "--listen",
            &endpoint,
            "--insecure",
            "--config",
        ])
        .arg(&rules)
        .env("RUST_LOG", "info,zenoh=trace")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()?;
    let pid = nix::unistd::Pid::from_raw(i32::try_from(child.id())?);
    // Read as it is written: a trace log fills a pipe at once.
    let mut stderr = child.stderr.take().ok_or("the bridge's stderr")?;
    let reader = std::thread::spawn(move || {
        let mut bytes = Vec::new();
        let _ = std::io::Read::read_to_end(&mut stderr, &mut bytes);
        bytes
    });
    let keys = Keys::new(server.name())?;
    let until = Instant::now() + DEADLINE;
    let zenoh = loop {
        match session(&endpoint) {
            Ok(zenoh) => break zenoh,
            Err(_) if Instant::now() < until => std::thread::sleep(Duration::from_millis(100)),
            Err(error) => return Err(format!("the bridge never listened: {error}").into()),
        }
    };
    wait_for_server(&zenoh, &keys)?;
    let start = Instant::now();
    let grant = open_session(&zenoh, &keys, "panel", clock_ns(start, Duration::ZERO))??;
    let jog = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Velocity)
        .with_values([1.0, 0.0, 0.0]);
    let mut attachments = Vec::new();
    for _ in 0..5 {
        let meta = Sign::of(&grant, clock_ns(start, Duration::ZERO))
            .meta("panel", &wire::encode(&jog))
            .encode();
        attachments.push(meta);
        let reply = zenoh
            .get(keys.command("panel"))
            .payload(wire::encode(&jog))
            .attachment(meta.to_vec())
            .timeout(DEADLINE)
            .wait()
            .z()?
            .recv_timeout(DEADLINE)
            .z()?
            .ok_or("no answer")?;
        reply
            .result()
            .map_err(|error| format!("refused: {error:?}"))?;
    }
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGTERM)?;
    real::finish(child, DEADLINE)?;
    let bytes = reader.join().map_err(|_| "the log's reader")?;
    let log = String::from_utf8_lossy(&bytes);
    let forms = |secret: &[u8]| {
        [
            secret
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect::<String>(),
            secret
                .iter()
                .map(|b| format!("{b:02X}"))
                .collect::<String>(),
            format!("{secret:?}"),
            format!("{secret:02x?}"),
            joined(secret, |b| format!("{b:02x}"), " "),
            // Inside a longer slice, as zenoh's trace prints a message's bytes.
            joined(secret, |b| format!("{b:02x}"), ", "),
            joined(secret, |b| b.to_string(), ", "),
            String::from_utf8_lossy(secret).into_owned(),
        ]
    };
    // What the commands carried is in the log (so the search would find a secret that
    // travelled with them, as the secret itself did before version 3 of the contract) ...
    let carried = attachments
        .iter()
        .filter(|meta| {
            forms(&meta[33..49])
                .iter()
                .any(|form| log.contains(form.as_str()))
        })
        .count();
    eprintln!(
        "{} lines of trace log, {} bytes; the MACs of {carried} of the 5 commands in it; the \
         secret searched for as {:?}",
        log.lines().count(),
        log.len(),
        forms(&grant.token.0)
    );
    std::fs::write("/tmp/trace-log.txt", log.as_bytes())?;
    assert!(
        carried > 0,
        "zenoh's trace log shows what a command carries"
    );
    // ... and the secret is not.
    for form in forms(&grant.token.0) {
        assert!(
            !log.contains(form.as_str()),
            "the secret is in the log as {form}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// `bytes`, each as `each` makes it, joined by `separator`.
fn joined(bytes: &[u8], each: impl Fn(&u8) -> String, separator: &str) -> String {
    bytes.iter().map(each).collect::<Vec<_>>().join(separator)
}

/// A remote's session ends with its own transport: another peer that declares a copy of the
/// departed remote's liveliness key (anyone may read it) does not keep its claim.
#[test]
fn a_copied_liveliness_key_does_not_keep_a_departed_remotes_claim() -> Result {
    let server = fake("hard-copy")?;
    let rules = "[[remote]]\nidentity = \"*\"\nallow = [\"all\"]\n";
    let bridge = BridgeThread::start(server.name(), rules)?;
    let keys = Keys::new(server.name())?;
    let victim = remote(server.name(), &bridge.endpoint, "operator")?;
    victim.wait_ready(DEADLINE)?;
    victim.axis("x")?.claim()?;
    // The copy: the victim's liveliness key, read and declared by another peer.
    let attacker = session(&bridge.endpoint)?;
    let replies = attacker
        .liveliness()
        .get(keys.remote_tokens())
        .timeout(Duration::from_secs(5))
        .wait()
        .z()?;
    let mut copied = Vec::new();
    while let Ok(reply) = replies.recv() {
        if let Ok(sample) = reply.result() {
            copied.push(
                attacker
                    .liveliness()
                    .declare_token(sample.key_expr().clone())
                    .wait()
                    .z()?,
            );
        }
    }
    assert_eq!(copied.len(), 1, "the victim's one liveliness key");
    let releases = |server: &motion_client::testing::FakeServer| {
        server
            .requests()
            .iter()
            .filter(|r| r.kind == CommandKind::Release as u32 && r.axis == 0)
            .count()
    };
    assert_eq!(releases(&server), 0);
    // The victim's process ends without releasing (its client is dropped; the claim was
    // not a guard): its transport closes, its liveliness key stays (the copy).
    drop(victim);
    eventually("the bridge released the departed remote's claim", || {
        Ok(releases(&server) == 1)
    })?;
    // Another remote claims x.
    let other = remote(server.name(), &bridge.endpoint, "other")?;
    other.axis("x")?.claim()?;
    drop(copied);
    Ok(())
}
