//! Streaming setpoints: a client that claims `base` (the QuadQuad2Drv's wheels), sends
//! `Stream` (velocity) and then, after each frame `k`, publishes a velocity `Setpoint` for
//! tick `k + 1` on `setpoints` (a sine of ±20 °/s), written with plain iceoryx2 as the
//! bench's other clients are. It waits for frames in a WaitSet on the tick event, as the
//! WaitSet delivery client does.
//!
//! Figures: (a) the setpoints the server applied in the tick they were for (the frame's
//! `GroupState::last_sequence` / `last_applied_tick`), with the server's counters; (b) frame
//! `k` published (`MotionFrame::publish_ns`) → its setpoint sent (CLOCK_MONOTONIC in the
//! client, right after `send`): the server stamps no reception, so this is the client's part
//! of the exchange; and the share of ticks for which the client had sent before the next
//! tick's deadline. Baseline: a plain peer pair doing the same exchange in the same run — the
//! bench's peer process publishing a frame-sized sample each tick and draining a `setpoints`
//! service as motiond's at the start of the next (`streaming` peer), the same client loop
//! answering it.

use core::time::Duration;

use iceoryx2::port::listener::Listener;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use motion_ipc::{CommandKind, GroupMotion, GroupState, Setpoint, StreamMode, StreamState, Target};

use crate::args::PeerMode;
use crate::delivery::duration_ns;
use crate::dist::{Dist, Summary, percent};
use crate::group_client::{GroupClient, GroupDesc, Watch};
use crate::ipc::{self, Frames, Ipc};
use crate::peer::Peer;
use crate::report::{Row, Unit};
use crate::rt::{self, now_ns};

/// The sine's amplitude, °/s, and period, s.
const SPEED: f64 = 20.0;
const PERIOD_S: f64 = 1.5;

/// What one exchange loop saw.
#[derive(Debug)]
pub struct Exchange {
    /// Frame `publish_ns` → setpoint sent, ns.
    pub latency: Dist,
    /// Ours: frame `k`'s `publish_ns` → the server took the setpoint for `k + 1` from the
    /// service (`GroupState::last_received_ns`, of the setpoints seen applied), ns.
    pub received: Dist,
    /// Setpoints sent.
    pub sent: u64,
    /// Of them, sent before the deadline of the tick they were for.
    pub before_deadline: u64,
    /// Ticks from the first setpoint's tick to the last's.
    pub ticks: u64,
    /// Frames the client never saw (it answered the newest).
    pub lost_frames: u64,
    /// Ours: setpoints seen applied in the tick they were for.
    pub applied_in_tick: u64,
    /// Ours: setpoints seen applied in a later tick.
    pub applied_later: u64,
    /// Ours: the group in the last frame.
    pub last: Option<GroupState>,
}

/// Everything the streaming phase measured.
#[derive(Debug)]
pub struct StreamRun {
    /// Against motiond (`base`).
    pub ours: Exchange,
    /// Against the streaming peer.
    pub baseline: Exchange,
    /// The peer's count of setpoints taken in time, and late.
    pub peer_counts: (u64, u64),
    /// The peer's frame `k` published → setpoint for `k + 1` taken, its own stamps.
    pub peer_received: Summary,
    /// The Python closed-loop client on the same group, after ours, with lead 1 and with
    /// its default lead ([`crate::python_stream`]); empty without an interpreter.
    pub python: Vec<Result<crate::python_stream::PythonStream, String>>,
    /// The client thread's set-up.
    pub thread: String,
    /// How long each side streamed.
    pub length: Duration,
}

/// Streams to `base` on `client`'s server, then the same exchange with a streaming peer.
pub fn run(
    client: &mut GroupClient,
    base: &GroupDesc,
    tick_hz: u32,
    priority: Option<u8>,
    duration: Duration,
) -> Result<StreamRun, String> {
    let length = duration.clamp(Duration::from_secs(1), Duration::from_secs(5));
    let period = 1_000_000_000 / u64::from(tick_hz.max(1));
    let thread = rt::set_up_thread(priority, None).describe();
    let group = u32::try_from(base.index).unwrap_or(u32::MAX);
    client.accepted(Target::Group, group, CommandKind::Claim, [0.0; 3])?;
    let streamed = stream_to_base(client, base, group, period, length);
    // End the stream (every member stops and holds), then give the claim back, whatever
    // happened.
    let cancel = client.command(Target::Group, group, CommandKind::Cancel, [0.0; 3]);
    let release = client.command(Target::Group, group, CommandKind::Release, [0.0; 3]);
    let ours = streamed?;
    cancel?;
    release?;
    let peer = Peer::start(PeerMode::Streaming, tick_hz, priority, None)?;
    let node = ipc::node("stream-baseline")?;
    let frames = ipc::open_frames(&node, &peer.names, ipc::OPEN_TIMEOUT)?;
    let tick = ipc::open_tick(&node, &peer.names)?;
    let name = ServiceName::new(&peer.names.setpoints())
        .map_err(|e| format!("{}: {e:?}", peer.names.setpoints()))?;
    let publisher = node
        .service_builder(&name)
        .publish_subscribe::<Setpoint>()
        .open()
        .map_err(|e| format!("open {}: {e:?}", peer.names.setpoints()))?
        .publisher_builder()
        .create()
        .map_err(|e| format!("peer setpoint publisher: {e:?}"))?;
    let ports = Ports {
        frames: &frames,
        tick: &tick,
        publisher: &publisher,
    };
    let baseline = exchange(&ports, None, 0, period, length)?;
    drop((publisher, tick, frames, node));
    let figures = peer.stop()?;
    Ok(StreamRun {
        ours,
        baseline,
        peer_counts: (figures.setpoints_in_time, figures.setpoints_late),
        peer_received: figures.received,
        python: Vec::new(),
        thread,
        length,
    })
}

fn stream_to_base(
    client: &mut GroupClient,
    base: &GroupDesc,
    group: u32,
    period: u64,
    length: Duration,
) -> Result<Exchange, String> {
    let publisher = client.setpoint_publisher()?;
    let tick = ipc::open_tick(&client.node, &client.names)?;
    client.accepted(
        Target::Group,
        group,
        CommandKind::Stream,
        [f64::from(StreamMode::Velocity as u32), 0.0, 0.0],
    )?;
    let ports = Ports {
        frames: client.frames(),
        tick: &tick,
        publisher: &publisher,
    };
    let run = exchange(&ports, Some(base.index), group, period, length)?;
    // The last setpoints' ticks pass: their outcome shows in the frames to come.
    let watch = Watch {
        axes: Vec::new(),
        groups: vec![base.index],
    };
    let mut frames = Vec::new();
    client.frames_for(&watch, &mut frames, 5)?;
    let last = frames.last().map(|f| f.groups[0]).or(run.last);
    let Some(state) = last else {
        return Err("stream: no frame".to_owned());
    };
    if state.stream() != Ok(StreamState::Streaming)
        || GroupMotion::try_from(state.motion).is_ok_and(|m| m == GroupMotion::Aborted)
    {
        return Err(format!(
            "stream to base: {} after {} setpoints (motion {}, abort {}; applied {}, late {}, \
             early {}, refused {})",
            state.stream().map_or("?", StreamState::name),
            run.sent,
            GroupMotion::try_from(state.motion).map_or("?", GroupMotion::name),
            motion_ipc::GroupAbort::try_from(state.abort).map_or("?", |a| a.name()),
            state.applied,
            state.late,
            state.early,
            state.refused
        ));
    }
    Ok(Exchange {
        last: Some(state),
        ..run
    })
}

struct Ports<'a> {
    frames: &'a Frames,
    tick: &'a Listener<Ipc>,
    publisher: &'a Publisher<Ipc, Setpoint, ()>,
}

/// The client loop: after each wake-up, the newest frame `k` gets a setpoint for `k + 1`
/// (velocity of a sine); `group` (a frame index) is checked for what was applied, when
/// given. Runs for `length` of setpoints.
fn exchange(
    ports: &Ports<'_>,
    group: Option<usize>,
    group_index: u32,
    period: u64,
    length: Duration,
) -> Result<Exchange, String> {
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(|e| format!("wait set: {e:?}"))?;
    let guard = waitset
        .attach_notification(ports.tick)
        .map_err(|e| format!("attach the tick event: {e:?}"))?;
    let mut run = Exchange {
        latency: Dist::new(),
        received: Dist::new(),
        sent: 0,
        before_deadline: 0,
        ticks: 0,
        lost_frames: 0,
        applied_in_tick: 0,
        applied_later: 0,
        last: None,
    };
    let mut setpoint = Setpoint {
        group: group_index,
        mode: StreamMode::Velocity as u32,
        ..Setpoint::EMPTY
    };
    // for_tick of each sequence sent and the publish_ns of the frame it answered (index =
    // sequence − 1).
    let mut for_ticks: Vec<(u64, u64)> = Vec::with_capacity(8192);
    let mut last_tick: Option<u64> = None;
    let mut first_for: Option<u64> = None;
    let mut counted_sequence = 0;
    let _ = ports.tick.try_wait(|_| {});
    let _ = ipc::latest(ports.frames)?;
    let end = now_ns() + duration_ns(length);
    let mut failed = None;
    while now_ns() < end {
        waitset
            .wait_and_process_once_with_timeout(
                |id| {
                    if id.has_event_from(&guard)
                        && let Err(e) = ports.tick.try_wait(|_| {})
                    {
                        failed = Some(format!("take tick notifications: {e:?}"));
                    }
                    CallbackProgression::Continue
                },
                Duration::from_millis(500),
            )
            .map_err(|e| format!("wait in the wait set: {e:?}"))?;
        if let Some(error) = failed.take() {
            return Err(error);
        }
        // Every frame for the bookkeeping, the newest for the answer.
        let mut newest = None;
        loop {
            let sample = match ports.frames.receive() {
                Ok(Some(sample)) => sample,
                Ok(None) => break,
                Err(e) => return Err(format!("receive a frame: {e:?}")),
            };
            let frame = sample.payload();
            if let Some(index) = group
                && let Some(state) = frame.groups().get(index)
            {
                let sequence = state.last_sequence;
                if state.last_applied_tick == frame.tick && sequence > counted_sequence {
                    counted_sequence = sequence;
                    let sent = usize::try_from(sequence)
                        .ok()
                        .and_then(|s| s.checked_sub(1))
                        .and_then(|i| for_ticks.get(i));
                    if let Some(&(_, answered)) = sent
                        && state.last_received_ns >= answered
                    {
                        run.received.record(state.last_received_ns - answered);
                    }
                    match sent {
                        Some(&(tick, _)) if tick == frame.tick => run.applied_in_tick += 1,
                        Some(_) => run.applied_later += 1,
                        None => {}
                    }
                }
                run.last = Some(*state);
            }
            newest = Some((frame.tick, frame.time_ns, frame.publish_ns));
        }
        let Some((tick, time_ns, publish_ns)) = newest else {
            continue;
        };
        if let Some(last) = last_tick {
            if tick <= last {
                continue;
            }
            run.lost_frames += tick - last - 1;
        }
        last_tick = Some(tick);
        let for_tick = tick + 1;
        first_for.get_or_insert(for_tick);
        let elapsed = (for_tick - first_for.unwrap_or(for_tick)) as f64 * period as f64 / 1e9;
        let speed = SPEED * (elapsed * core::f64::consts::TAU / PERIOD_S).sin();
        setpoint.sequence += 1;
        setpoint.for_tick = for_tick;
        setpoint.values[0] = speed;
        setpoint.values[1] = -speed;
        ports
            .publisher
            .send_copy(setpoint)
            .map_err(|e| format!("send a setpoint: {e:?}"))?;
        let sent = now_ns();
        for_ticks.push((for_tick, publish_ns));
        run.sent += 1;
        run.latency.record(sent.saturating_sub(publish_ns));
        if sent < time_ns + period {
            run.before_deadline += 1;
        }
        run.ticks = for_tick - first_for.unwrap_or(for_tick) + 1;
    }
    Ok(run)
}

/// The streaming rows.
pub fn rows(run: &StreamRun) -> Vec<Row> {
    let ours = &run.ours;
    let base = &run.baseline;
    let counters = ours.last.map_or_else(String::new, |s| {
        format!(
            "; the server's counters: applied {}, late {}, early {}, clamped {}, refused {}",
            s.applied, s.late, s.early, s.clamped, s.refused
        )
    });
    let mut rows = vec![
        Row {
            figure: "streaming to base: frame k published → the client's setpoint for k + 1 \
                     received by the server (GroupState.last_received_ns)"
                .to_owned(),
            unit: Unit::Ns,
            ours: ours.received.summary(),
            baseline: Some(run.peer_received),
            baseline_label: "plain iceoryx2 peer pair: the peer's own stamps, its sample \
                             published → the setpoint for the next tick taken from its \
                             setpoints service (drained at the start of each tick, as motiond)"
                .to_owned(),
            note: format!(
                "the Rust client in a WaitSet answering each frame; the server stamps a setpoint \
                 when its tick takes it from the service (CLOCK_MONOTONIC, the clock of \
                 publish_ns), so this includes the wait for the next tick; {} of {} setpoints \
                 seen applied in a frame the client read",
                ours.received.summary().samples,
                ours.sent
            ),
        },
        Row {
            figure: "streaming to base: frame k published → the client's setpoint for k + 1 sent \
                     (client in a WaitSet, CLOCK_MONOTONIC)"
                .to_owned(),
            unit: Unit::Ns,
            ours: ours.latency.summary(),
            baseline: Some(base.latency.summary()),
            baseline_label: "plain iceoryx2 peer pair: the bench's peer publishing a frame-sized \
                             sample per tick, the same client loop publishing a setpoint on the \
                             peer's setpoints service"
                .to_owned(),
            note: format!(
                "{:.1} s each; client {}; a velocity sine of ±{SPEED} °/s on both wheels; the \
                 client's own stamp right after send_copy: its side of the exchange",
                run.length.as_secs_f64(),
                run.thread,
            ),
        },
        Row {
            figure: "streaming to base: setpoints applied in the tick they were for, % of the \
                     setpoints sent"
                .to_owned(),
            unit: Unit::CentiPercent,
            ours: percent(ours.applied_in_tick, ours.sent),
            baseline: Some(percent(run.peer_counts.0, base.sent)),
            baseline_label: "the plain peer pair: setpoints the peer took at the start of the \
                             tick they were for (or earlier)"
                .to_owned(),
            note: format!(
                "ours from the frames (GroupState last_sequence = the setpoint's, \
                 last_applied_tick = its for_tick): {} in their tick, {} in a later one, of {} \
                 sent (the rest applied in a frame the client missed){counters}; the peer took \
                 {} in time and {} late of {} sent",
                ours.applied_in_tick,
                ours.applied_later,
                ours.sent,
                run.peer_counts.0,
                run.peer_counts.1,
                base.sent
            ),
        },
        Row {
            figure: "streaming to base: ticks for which the client sent its setpoint before the \
                     tick's deadline, % of the stream's ticks"
                .to_owned(),
            unit: Unit::CentiPercent,
            ours: percent(ours.before_deadline, ours.ticks),
            baseline: Some(percent(base.before_deadline, base.ticks)),
            baseline_label: "the same client loop against the plain peer".to_owned(),
            note: format!(
                "client clock: sent before the deadline (MotionFrame.time_ns + one period) of \
                 the tick the setpoint is for; a tick whose frame the client missed (ours {}, \
                 baseline {}) has none; ours {} of {} ticks, baseline {} of {}",
                ours.lost_frames,
                base.lost_frames,
                ours.before_deadline,
                ours.ticks,
                base.before_deadline,
                base.ticks
            ),
        },
    ];
    if !run.python.is_empty() {
        rows.extend(crate::python_stream::rows(
            &run.python,
            percent(ours.before_deadline, ours.ticks),
            ours.received.summary(),
        ));
    }
    rows
}

/// The streaming distribution files.
pub fn files(run: &StreamRun) -> Vec<(String, String, &Dist)> {
    vec![
        (
            "stream-frame-to-setpoint-motiond".to_owned(),
            "frame publish → setpoint sent, motiond (base)".to_owned(),
            &run.ours.latency,
        ),
        (
            "stream-frame-to-received-motiond".to_owned(),
            "frame publish → setpoint received by motiond (base)".to_owned(),
            &run.ours.received,
        ),
        (
            "stream-frame-to-setpoint-baseline".to_owned(),
            "sample publish → setpoint sent, plain peer pair".to_owned(),
            &run.baseline.latency,
        ),
    ]
}
