//! Setpoint streams against the fake server (`FakeConfig::with_groups`: `xy` = x y, `all` =
//! x y a; 500 Hz): a stream claims its group, every setpoint is applied once in its tick,
//! the client checks what it sends, another node's setpoints are refused, a stream that
//! stops coming goes stale, dropping a stream stops the axes and releases the claim.

use core::ops::ControlFlow;
use core::time::Duration;
use std::time::Instant;

use iceoryx2::prelude::{NodeBuilder, ServiceName, local};
use motion_client::ipc::{
    CommandKind, GroupAbort, GroupMotion, PathKind, Reason, Setpoint, StreamMode, StreamState,
};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientError, StreamError};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(10);

/// The fake with groups; streams go stale after `stream_timeout` ticks (large by default:
/// a loaded test machine must not end a stream these tests do not mean to end).
fn start(prefix: &str, stream_timeout: u32) -> Result<(FakeServer, Client<local::Service>)> {
    let mut config = FakeConfig::demo(&unique_name(prefix)).with_groups();
    for group in &mut config.groups {
        group.stream_timeout = stream_timeout;
    }
    let server = FakeServer::start::<local::Service>(config)?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

/// Whether `client` holds axis `axis`, in a frame two ticks after the newest one (a command
/// just answered is in it).
fn claimed_by(client: &Client<local::Service>, axis: usize) -> Result<bool> {
    let after = client.latest()?.tick + 2;
    let until = Instant::now() + WAIT;
    loop {
        let frame = client.latest()?;
        if frame.tick >= after {
            return Ok(frame.axes()[axis].claimed_by == client.id());
        }
        drop(frame);
        if Instant::now() > until {
            return Err("no frames".into());
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Waits until `check` holds for group `group`'s state.
fn wait_for(
    client: &Client<local::Service>,
    group: &str,
    check: impl Fn(&motion_client::GroupStatus) -> bool,
) -> Result<motion_client::GroupStatus> {
    let handle = client.group(group)?;
    let until = Instant::now() + WAIT;
    loop {
        let state = handle.state()?;
        if check(&state) {
            return Ok(state);
        }
        if Instant::now() > until {
            return Err(format!("never held: {state:?}").into());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn every_setpoint_is_applied_once_in_its_tick() -> Result {
    let (server, client) = start("stream-run", 100_000)?;
    let xy = client.group("xy")?;
    let mut stream = xy.stream(StreamMode::Velocity)?;
    assert!(claimed_by(&client, 0)? && claimed_by(&client, 1)?);
    let requests = server.requests();
    let sent = requests
        .iter()
        .find(|r| r.kind() == Ok(CommandKind::Stream))
        .ok_or("no Stream request")?;
    assert_eq!(sent.values[0], f64::from(StreamMode::Velocity as u32));
    let mut calls = 0;
    let run = stream.run_each_tick(Some(Duration::from_millis(400)), |frame, out| {
        assert_eq!(out.len(), 2);
        if calls == 0 {
            assert_eq!(out, [0.0, 0.0], "a velocity stream starts from zeros");
        }
        calls += 1;
        assert_eq!(frame.groups()[0].stream, StreamState::Streaming as u8);
        out.copy_from_slice(&[10.0, -5.0]);
        ControlFlow::Continue(())
    })?;
    assert_eq!(run.sent, calls);
    assert!(run.sent > 20, "{run:?}");
    assert_eq!(run.last_sequence, run.sent, "sequences count up from 1");
    let (first, last) = (run.first_tick.ok_or("first")?, run.last_tick.ok_or("last")?);
    assert_eq!(last - first + 1, run.sent + run.skipped, "{run:?}");
    let status = stream.wait_caught_up(WAIT)?;
    assert_eq!(status.state, StreamState::Streaming);
    assert_eq!(status.mode, StreamMode::Velocity);
    assert_eq!(status.owner, Some(client.id()));
    assert_eq!(status.applied + status.late, run.sent, "{status:?} {run:?}");
    assert!(status.late <= run.behind, "{status:?} {run:?}");
    assert_eq!((status.early, status.refused), (0, 0), "{status:?}");
    assert_eq!(status.last_sequence, run.last_sequence);
    assert!(status.last_applied_tick >= last, "never before its tick");
    let frame = client.latest()?;
    let (x, y) = (frame.axes()[0].position, frame.axes()[1].position);
    drop(frame);
    assert!(
        x > 1.0 && y < -0.5,
        "x {x}, y {y}: the velocities were integrated"
    );
    let group = xy.state()?;
    assert_eq!(
        (group.kind, group.motion),
        (PathKind::Stream, GroupMotion::Moving)
    );
    stream.cancel()?;
    let ended = wait_for(&client, "xy", |s| s.stream == StreamState::Idle)?;
    assert_eq!(ended.motion, GroupMotion::Done);
    assert!(!claimed_by(&client, 0)?, "the claim was released");
    Ok(())
}

/// The lead: after reading frame `k` the stream sends for `k + lead` (the default unless
/// set); 0 and more than `stream_buffer` + 1 are refused with the range; a setpoint sent a
/// lead ahead applies in its own tick (no delay).
#[test]
fn run_each_tick_sends_a_lead_ahead_of_the_frame_it_read() -> Result {
    let (_server, client) = start("stream-lead", 100_000)?;
    let xy = client.group("xy")?;
    let buffer = u64::from(xy.info().stream_buffer);
    let mut stream = xy.stream(StreamMode::Velocity)?;
    assert_eq!(stream.lead(), motion_client::DEFAULT_STREAM_LEAD);
    for bad in [0, buffer + 2] {
        let error = stream.set_lead(bad).expect_err("outside 1..=buffer+1");
        assert!(
            matches!(error, StreamError::Lead { lead, most, .. } if lead == bad && most == buffer + 1),
            "{error}"
        );
    }
    stream.set_lead(buffer + 1)?;
    let mut first_frame = None;
    let run = stream.run_each_tick(Some(Duration::from_millis(200)), |frame, out| {
        first_frame.get_or_insert(frame.tick);
        out.copy_from_slice(&[1.0, 1.0]);
        ControlFlow::Continue(())
    })?;
    assert_eq!(run.first_tick, first_frame.map(|tick| tick + buffer + 1));
    let status = stream.wait_caught_up(WAIT)?;
    assert_eq!(status.applied + status.late, run.sent, "{status:?}");
    assert_eq!((status.early, status.refused), (0, 0), "{status:?}");
    stream.cancel()?;
    Ok(())
}

#[test]
fn the_client_checks_what_it_sends_and_counts_sequences() -> Result {
    let (_server, client) = start("stream-send", 100_000)?;
    let mut stream = client.group("all")?.stream(StreamMode::Velocity)?;
    let tick = client.latest()?.tick;
    let error = stream.send(tick + 1, &[1.0, 2.0]).expect_err("three axes");
    assert!(
        matches!(
            &error,
            StreamError::ValueCount {
                what: "values",
                expected: 3,
                got: 2,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(error.to_string().contains("(x, y, a)"), "{error}");
    let error = stream
        .send(tick + 1, &[0.0, f64::NAN, 0.0])
        .expect_err("not finite");
    assert!(
        matches!(&error, StreamError::NotFinite { axis, what: "value", .. } if axis == "y"),
        "{error:?}"
    );
    let error = stream
        .send_with_feed_forward(tick + 1, &[0.0; 3], &[0.0; 3])
        .expect_err("a velocity stream");
    assert!(
        matches!(
            &error,
            StreamError::FeedForwardNeedsPosition {
                mode: "velocity",
                ..
            }
        ),
        "{error:?}"
    );
    assert_eq!(stream.last_sequence(), 0, "nothing refused was sent");
    let tick = client.latest()?.tick;
    assert_eq!(stream.send(tick + 2, &[1.0, 1.0, 1.0])?, 1);
    assert_eq!(stream.send(tick + 3, &[1.0, 1.0, 1.0])?, 2);
    assert_eq!(stream.last_for_tick(), Some(tick + 3));
    let status = stream.wait_caught_up(WAIT)?;
    // Both taken: each applied in its tick, or the first dropped as late when the client
    // was so slow that both were due in one tick.
    assert_eq!(status.applied + status.late, 2, "{status:?}");
    assert_eq!(status.last_sequence, 2, "{status:?}");
    assert!(status.last_applied_tick >= tick + 3);
    drop(stream);

    // A position stream: run_each_tick starts from where the axes are, and takes a
    // feed-forward; a second stream on a streaming group is refused.
    let xy = client.group("xy")?;
    let mut stream = xy.stream(StreamMode::Position)?;
    let busy = client
        .group("all")?
        .stream(StreamMode::Position)
        .expect_err("x and y stream already");
    assert_eq!(busy.reason(), Some(Reason::GroupBusy), "{busy}");
    assert!(
        claimed_by(&client, 0)? && claimed_by(&client, 1)?,
        "the refused stream left the running one's claims alone"
    );
    assert!(!claimed_by(&client, 2)?, "and gave back the one it took");
    let here = {
        let frame = client.latest()?;
        [frame.axes()[0].position, frame.axes()[1].position]
    };
    let mut first = None;
    stream.run_each_tick(None, |_, out| {
        first = Some([out[0], out[1]]);
        ControlFlow::Break(())
    })?;
    assert_eq!(first, Some(here));
    let tick = client.latest()?.tick;
    stream.send_with_feed_forward(tick + 1, &[here[0] + 0.5, here[1]], &[1.0, 0.0])?;
    let status = stream.wait_caught_up(WAIT)?;
    assert_eq!((status.applied, status.late), (1, 0), "{status:?}");
    Ok(())
}

#[test]
fn a_stream_needs_the_group_free_and_other_nodes_setpoints_are_refused() -> Result {
    let (server, owner) = start("stream-refused", 100_000)?;
    let other = Client::<local::Service>::connect(server.name())?;
    let mut stream = owner.group("xy")?.stream(StreamMode::Velocity)?;
    let error = other
        .group("xy")?
        .stream(StreamMode::Velocity)
        .expect_err("claimed by the owner");
    let ClientError::GroupRefused(refusal) = &error else {
        panic!("not a group refusal: {error:?}");
    };
    assert_eq!(refusal.reason, Reason::ClaimedByOther);
    assert_eq!(refusal.holder, Some(owner.id()));

    // Setpoints published on the service from another node, right in every way but the
    // sender: dropped and counted.
    let node = NodeBuilder::new().create::<local::Service>()?;
    let name = ServiceName::new(&owner.service_names().setpoints())?;
    let publisher = node
        .service_builder(&name)
        .publish_subscribe::<Setpoint>()
        .open()?
        .publisher_builder()
        .create()?;
    let tick = owner.latest()?.tick;
    for step in 1..=5 {
        let mut intruder = Setpoint {
            group: 0,
            sequence: 1000 + step,
            for_tick: tick + step,
            mode: StreamMode::Velocity as u32,
            ..Setpoint::EMPTY
        };
        intruder.values[0] = 40.0;
        publisher.send_copy(intruder)?;
    }
    let run = stream.run_each_tick(Some(Duration::from_millis(100)), |_, out| {
        out.fill(1.0);
        ControlFlow::Continue(())
    })?;
    let status = stream.wait_caught_up(WAIT)?;
    assert_eq!(status.refused, 5, "{status:?}");
    assert_eq!(status.state, StreamState::Streaming);
    assert_eq!(status.applied + status.late, run.sent, "{status:?} {run:?}");
    assert!(
        status.last_sequence < 1000,
        "none of the intruder's applied"
    );
    Ok(())
}

#[test]
fn a_stream_that_stops_coming_goes_stale_and_dropping_one_stops_and_releases() -> Result {
    let (_server, client) = start("stream-stale", 20)?;
    let xy = client.group("xy")?;
    let mut stream = xy.stream(StreamMode::Velocity)?;
    let tick = client.latest()?.tick;
    stream.send(tick + 1, &[5.0, 5.0])?;
    let stale = wait_for(&client, "xy", |s| s.stream == StreamState::Stale)?;
    assert_eq!(
        (stale.motion, stale.abort),
        (GroupMotion::Aborted, GroupAbort::StreamStale)
    );
    let error = stream
        .run_each_tick(None, |_, _| ControlFlow::Continue(()))
        .expect_err("stale");
    assert!(
        matches!(
            &error,
            StreamError::Ended {
                stream: StreamState::Stale,
                abort: GroupAbort::StreamStale,
                ..
            }
        ),
        "{error:?}"
    );
    assert!(error.to_string().contains("stream stale"), "{error}");
    let refused = stream.cancel().expect_err("nothing to cancel");
    assert_eq!(refused.reason(), Some(Reason::NotMoving), "{refused}");
    assert!(!claimed_by(&client, 0)?, "released all the same");

    // Dropped while streaming: Cancel, then the claim released.
    let stream = xy.stream(StreamMode::Velocity)?;
    drop(stream);
    let ended = wait_for(&client, "xy", |s| s.stream == StreamState::Idle)?;
    assert_eq!(ended.motion, GroupMotion::Done);
    assert!(!claimed_by(&client, 0)? && !claimed_by(&client, 1)?);
    let frame = client.latest()?;
    assert_eq!(frame.axes()[0].velocity, 0.0, "the axes hold");
    Ok(())
}

#[test]
fn a_claim_held_before_the_stream_stays_after_it() -> Result {
    let (_server, client) = start("stream-held", 100_000)?;
    let xy = client.group("xy")?;
    let claim = xy.claim()?;
    let stream = xy.stream(StreamMode::Velocity)?;
    stream.cancel()?;
    wait_for(&client, "xy", |s| s.stream == StreamState::Idle)?;
    assert!(claimed_by(&client, 0)? && claimed_by(&client, 1)?);
    drop(claim);
    assert!(!claimed_by(&client, 0)?, "released by its own guard");
    Ok(())
}

#[test]
fn a_setpoint_no_server_takes_is_not_sent() -> Result {
    let (server, client) = start("stream-gone", 100_000)?;
    let mut stream = client.group("xy")?.stream(StreamMode::Velocity)?;
    let tick = client.latest()?.tick;
    server.shutdown()?;
    let until = Instant::now() + WAIT;
    // The fake's subscriber is gone with it: the setpoint reaches nobody.
    loop {
        match stream.send(tick + 1, &[0.0, 0.0]) {
            Err(StreamError::NotSent { why, .. }) => {
                assert!(why.contains("setpoints"), "{why}");
                break;
            }
            Err(StreamError::Client(error)) => return Err(error.into()),
            Err(other) => return Err(other.into()),
            Ok(_) if Instant::now() < until => std::thread::sleep(Duration::from_millis(10)),
            Ok(_) => return Err("still delivered after the server stopped".into()),
        }
    }
    drop(stream); // its Cancel finds no server: nothing to do
    Ok(())
}

/// A node of another process and the setpoint publishers it holds.
type SlotHolder = (
    iceoryx2::node::Node<local::Service>,
    Vec<iceoryx2::port::publisher::Publisher<local::Service, Setpoint, ()>>,
);

/// Opens publishers on `server`'s `setpoints` service from a node of its own until the
/// service refuses one: every slot left (docs/SECURITY.md "Paths and setpoints no other
/// process can starve").
fn take_every_setpoint_slot(server: &FakeServer) -> Result<SlotHolder> {
    let node = NodeBuilder::new().create::<local::Service>()?;
    let name = ServiceName::new(&format!("motiond/{}/setpoints", server.name()))?;
    let service = node
        .service_builder(&name)
        .publish_subscribe::<Setpoint>()
        .open()?;
    let mut held = Vec::new();
    while let Ok(publisher) = service.publisher_builder().create() {
        held.push(publisher);
        if held.len() > 1024 {
            return Err("the setpoints service never ran out of publisher slots".into());
        }
    }
    Ok((node, held))
}

#[test]
fn a_client_that_commanded_keeps_its_setpoint_slot_when_another_takes_the_rest() -> Result {
    let (server, client) = start("stream-slots", 100_000)?;
    let xy = client.group("xy")?;
    // Its first command takes its setpoint publisher with its command port.
    drop(xy.claim()?);
    let (_node, held) = take_every_setpoint_slot(&server)?;
    assert!(!held.is_empty(), "slots were left for another process");
    let mut stream = xy.stream(StreamMode::Velocity)?;
    let tick = client.latest()?.tick;
    stream.send(tick + 2, &[1.0, -1.0])?;
    wait_for(&client, "xy", |s| s.raw.applied >= 1)?;
    stream.cancel()?;

    // A client that first commands now finds no slot: its stream says which and why, and
    // takes no claim.
    let late = Client::<local::Service>::connect(server.name())?;
    let error = late
        .group("xy")?
        .stream(StreamMode::Velocity)
        .expect_err("no setpoint slot is free");
    let text = error.to_string();
    assert!(
        text.contains("setpoints") && text.contains("no free publisher slot"),
        "{text}"
    );
    assert!(text.contains("max_clients"), "{text}");
    assert!(!claimed_by(&late, 0)?, "the failed stream left no claim");
    Ok(())
}

#[test]
fn waiting_for_the_stream_ends_when_the_last_setpoint_was_dropped_late() -> Result {
    let (_server, client) = start("stream-dropped", 100_000)?;
    let mut stream = client.group("xy")?.stream(StreamMode::Velocity)?;
    let tick = client.latest()?.tick;
    stream.send(tick + 2, &[1.0, 1.0])?;
    wait_for(&client, "xy", |s| s.raw.applied >= 1)?;
    // For a tick long gone, far more than `stream_buffer` behind: dropped, counted late,
    // never applied; the last sequence applied stays the first one.
    let long_gone = client.latest()?.tick.saturating_sub(1_000).max(1);
    stream.send(long_gone, &[2.0, 2.0])?;
    let timeout = Duration::from_secs(30);
    let asked = Instant::now();
    let status = stream.wait_caught_up(timeout)?;
    assert!(
        asked.elapsed() < timeout / 2,
        "waited {:?} for a setpoint that can never apply",
        asked.elapsed()
    );
    assert_eq!((status.applied, status.late), (1, 1), "{status:?}");
    assert!(status.last_sequence < stream.last_sequence(), "{status:?}");
    stream.cancel()?;
    Ok(())
}
