//! Command to wire: client request → first byte of the resulting board command at the link,
//! on each of the four boards ([`WireBoard`]).
//!
//! The bench hosts the boards itself (so that it sees the bytes arrive, and can cross-check
//! motiond's own stamp of the write, the frame's `AxisWire::wire_ns`): it starts its own
//! motiond on a generated config with four links — a QSB-M on a pty at 230400 baud and a
//! SIXpack on a pty at 19200 ([`crate::pty`]), a QuadQuad2Drv and an SPI_motor stepper on
//! SPI sockets ([`crate::spi_board`]) — every board simulated by a thread of the bench. For
//! each board in turn it sends `Velocity` commands to the board's axis (alternately +v and
//! −v, each a refresh of the deadman) stamped t0 = CLOCK_MONOTONIC just before
//! `send_copy`, and the board's thread stamps t1 when the first byte of the message that
//! carries the goal's first request reaches it (a pty master's read, the SPI socket's
//! length header): [`WireBoard::goal_sign`] says which message that is.
//!
//! Baseline, same phase, per board: no motiond — the bench writes the same message through
//! the same kind of transport itself (into a pty's slave side, or as a transaction on an
//! SPI socket) at t0 and the board's thread stamps it the same way: the transport, the
//! pacing thread and the wake-ups alone, so the ratio is what motiond adds (the wait for
//! its next tick, the engine, the driver's turn on the line and the I/O thread).

use core::time::Duration;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

use motion_ipc::{AxisFlags, AxisWire, ClientId, CommandKind, CommandRequest, ServiceNames};

use crate::delivery::duration_ns;
use crate::dist::{Dist, Summary};
use crate::ipc;
use crate::pty::LineSeen;
use crate::report::{Row, Unit};
use crate::rt::{XorShift, now_ns, sleep_until_ns};
use crate::stream_wire::StreamWire;
use crate::sweep::{Server, ServerRt, last_line};
use crate::wire_board::{Served, WireBoard, config_text};

/// The QSB's jog plan ends with COMMAND 9, MOTOR JOG.
const JOG_COMMAND: &[u8] = b"W169";
/// A reply or a message later than this is counted as lost.
const TIMEOUT_NS: u64 = 500_000_000;
/// The SPI_motor's ramp is over when no write went to it for this long (its profile is
/// rewritten every 2 ms poll period while it ramps).
const QUIET_NS: u64 = 10_000_000;

/// What the phase measured on one board.
#[derive(Debug)]
pub struct BoardWire {
    /// The board.
    pub board: WireBoard,
    /// motiond: request sent → first byte of the goal's first message at the board, ns.
    pub ours: Dist,
    /// The bench writing the same message through the same transport itself → its first
    /// byte at the board, ns.
    pub baseline: Dist,
    /// motiond's own stamp of the goal's first write (`AxisWire::wire_ns`) → the first byte
    /// of that message at the board, ns (the cross-check of the stamps).
    pub stamp_to_link: Dist,
    /// Requests whose frame stamp did not show within 50 ms, or came after the byte.
    pub stamp_missing: u64,
    /// Requests whose stamp came after the board's read of the first byte (the board's
    /// thread, on the other core, can read the byte before the I/O thread's `write(2)`
    /// returns and it takes the stamp), and the most such a stamp was late, ns.
    pub stamp_after: (u64, u64),
    /// motiond's own count: `AxisWire.wire_tick − goal_tick`, the ticks from the tick that
    /// set the goal to the tick during which its first request was written (0: the same).
    pub wire_ticks: Dist,
    /// Requests whose first write was in the tick that set the goal.
    pub same_tick: u64,
    /// Requests answered with something other than `Accepted`, by reason.
    pub refused: BTreeMap<String, u64>,
    /// Requests without a reply, or without their message within 500 ms.
    pub lost: u64,
    /// Baseline writes whose message did not come back within 500 ms.
    pub baseline_lost: u64,
    /// The last goal message motiond sent for a negative (index 0) and a positive (index 1) jog:
    /// the baseline writes the same bytes.
    pub messages: [Option<Vec<u8>>; 2],
}

impl BoardWire {
    fn new(board: WireBoard) -> Self {
        Self {
            board,
            ours: Dist::new(),
            baseline: Dist::new(),
            stamp_to_link: Dist::new(),
            stamp_missing: 0,
            stamp_after: (0, 0),
            wire_ticks: Dist::new(),
            same_tick: 0,
            refused: BTreeMap::new(),
            lost: 0,
            baseline_lost: 0,
            messages: [None, None],
        }
    }
}

/// What the phase measured.
#[derive(Debug)]
pub struct WireRun {
    /// Per board, in [`WireBoard::ALL`] order.
    pub boards: Vec<BoardWire>,
    /// motiond: `reply.tick_applied` − newest frame tick at send, every board's requests.
    pub ticks: Dist,
    /// How long until every axis was fresh after motiond started.
    pub online_after: Duration,
    /// The real-time keys the bench's motiond ran with.
    pub rt: ServerRt,
    /// Setpoint → wire on the SPI boards ([`crate::stream_wire`]), after the commands.
    pub streams: Vec<StreamWire>,
}

/// A served board and where its messages arrive.
struct Fixture {
    board: WireBoard,
    served: Served,
    seen: Receiver<LineSeen>,
    link: PathBuf,
}

fn link_path(dir: &Path, board: WireBoard, what: &str) -> PathBuf {
    let ext = match board {
        WireBoard::Qsb | WireBoard::Tmcpack => "tty",
        WireBoard::Qq2drv | WireBoard::Spimotor => "sock",
    };
    dir.join(format!(
        "wire-{what}-{}-{}.{ext}",
        board.slug(),
        std::process::id()
    ))
}

fn serve(board: WireBoard, link: PathBuf) -> Result<Fixture, String> {
    let (sender, seen) = channel();
    let served = board.serve(&link, sender)?;
    Ok(Fixture {
        board,
        served,
        seen,
        link,
    })
}

/// Runs the phase: motiond with every board, `duration` per board, then each board's
/// baseline for a third of it (at least a second). Files (config, log, pty links,
/// sockets) go into `dir`.
pub fn run(
    motiond: &Path,
    tick_hz: u32,
    rt: ServerRt,
    duration: Duration,
    dir: &Path,
) -> Result<WireRun, String> {
    let mut result = WireRun {
        boards: WireBoard::ALL.into_iter().map(BoardWire::new).collect(),
        ticks: Dist::new(),
        online_after: Duration::ZERO,
        rt,
        streams: Vec::new(),
    };
    {
        let mut fixtures = Vec::new();
        for board in WireBoard::ALL {
            fixtures.push(serve(board, link_path(dir, board, "motiond"))?);
        }
        let name = format!("bench-wire-{}", std::process::id());
        let config = dir.join("command-to-wire.toml");
        let log = dir.join("command-to-wire.log");
        let links = WireBoard::ALL.map(|board| {
            let link = fixtures
                .iter()
                .find(|f| f.board == board)
                .map_or(Path::new(""), |f| f.link.as_path());
            (board, link)
        });
        std::fs::write(&config, config_text(&name, tick_hz, rt, &links))
            .map_err(|e| format!("{}: {e}", config.display()))?;
        let mut server = Server::start(motiond, &config, &log)?;
        let outcome = with_motiond(&mut server, &name, &fixtures, duration, &log, &mut result);
        server.stop();
        for fixture in &mut fixtures {
            fixture.served.stop();
        }
        outcome?;
        for fixture in &fixtures {
            if let Some(failure) = fixture.served.failure() {
                return Err(format!(
                    "the simulated {} failed: {failure}",
                    fixture.board.name()
                ));
            }
        }
    }
    let base_duration = (duration / 3).max(Duration::from_secs(1));
    for wire in &mut result.boards {
        let mut fixture = serve(wire.board, link_path(dir, wire.board, "baseline"))?;
        let outcome = baseline(&fixture, base_duration, wire);
        fixture.served.stop();
        outcome.map_err(|e| format!("{} baseline: {e}", wire.board.name()))?;
    }
    Ok(result)
}

fn with_motiond(
    server: &mut Server,
    name: &str,
    fixtures: &[Fixture],
    duration: Duration,
    log: &Path,
    result: &mut WireRun,
) -> Result<(), String> {
    let names = ServiceNames::new(name);
    let node = ipc::node("wire")?;
    let started = Instant::now();
    let frames = loop {
        if let Some(status) = server.child.try_wait().map_err(|e| e.to_string())? {
            return Err(format!("motiond exited ({status}): {}", last_line(log)));
        }
        if let Ok(frames) = ipc::open_frames(&node, &names, Duration::from_millis(200)) {
            break frames;
        }
        if started.elapsed() > Duration::from_secs(15) {
            return Err(format!("no frame service after 15 s: {}", last_line(log)));
        }
    };
    let client = ipc::open_commands(&node, &names)?;
    // Every axis must be online (link open, board answered) before a jog is accepted.
    loop {
        if let Some(frame) = ipc::latest(&frames)?
            && frame.axes().len() == WireBoard::ALL.len()
            && frame
                .axes()
                .iter()
                .all(|axis| !axis.flags().contains(AxisFlags::STALE))
        {
            break;
        }
        if started.elapsed() > Duration::from_secs(15) {
            return Err(format!(
                "the four axes not all online after 15 s: {}",
                last_line(log)
            ));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    result.online_after = started.elapsed();
    let _ = crate::rt::set_up_thread(None, None);
    let id = ClientId::from_u128(node.id().value());
    let mut random = XorShift::new(u64::from(std::process::id()) ^ now_ns());
    let mut sequence = 0u64;
    for (fixture, wire) in fixtures.iter().zip(result.boards.iter_mut()) {
        let board = fixture.board;
        let axis = board.axis();
        let end = now_ns() + duration_ns(duration);
        let mut count = 0u64;
        while now_ns() < end {
            sleep_until_ns(now_ns() + 1_000_000 + random.below(board.pace_ns()));
            let newest_tick = ipc::latest(&frames)?.map(|frame| frame.tick);
            while fixture.seen.try_recv().is_ok() {}
            sequence += 1;
            count += 1;
            let positive = count % 2 == 1;
            let velocity = if positive {
                board.velocity()
            } else {
                -board.velocity()
            };
            let request = CommandRequest::new(id, sequence, axis, CommandKind::Velocity)
                .with_values([velocity, 0.0, 0.0]);
            let t0 = now_ns();
            let Ok(pending) = client.send_copy(request) else {
                wire.lost += 1;
                continue;
            };
            let reply = loop {
                match pending.receive() {
                    Ok(Some(response)) => break Some(*response.payload()),
                    Ok(None) if now_ns() - t0 > TIMEOUT_NS => break None,
                    Ok(None) => std::hint::spin_loop(),
                    Err(e) => return Err(format!("receive a reply: {e:?}")),
                }
            };
            let Some(reply) = reply.filter(|r| r.sequence == sequence) else {
                wire.lost += 1;
                continue;
            };
            if let Err(reason) = reply.result() {
                *wire.refused.entry(format!("{reason:?}")).or_default() += 1;
                // Let the motor reverse before the next try.
                std::thread::sleep(Duration::from_millis(20));
                continue;
            }
            if let Some(at_send) = newest_tick {
                result
                    .ticks
                    .record(reply.tick_applied.saturating_sub(at_send));
            }
            let Some((t1, message)) = wait_goal(fixture, t0, positive) else {
                wire.lost += 1;
                continue;
            };
            wire.ours.record(t1 - t0);
            wire.messages[usize::from(positive)] = Some(message);
            let stamp = wire_stamp(&frames, reply.tick_applied, axis)?;
            if trace() {
                eprintln!(
                    "wire {}: t1 +{} ns, tick at send {newest_tick:?}, applied {}, stamp {stamp:?} (+{} ns)",
                    board.slug(),
                    t1 - t0,
                    reply.tick_applied,
                    stamp.map_or(0, |s| s.wire_ns.wrapping_sub(t0))
                );
            }
            if let Some(stamp) = stamp {
                let ticks = stamp.wire_tick.saturating_sub(stamp.goal_tick);
                wire.wire_ticks.record_count(ticks);
                if ticks == 0 {
                    wire.same_tick += 1;
                }
            }
            match stamp {
                Some(stamp) if stamp.wire_ns <= t1 => {
                    wire.stamp_to_link.record(t1 - stamp.wire_ns);
                }
                Some(stamp) => {
                    let late = stamp.wire_ns - t1;
                    wire.stamp_after = (wire.stamp_after.0 + 1, wire.stamp_after.1.max(late));
                }
                None => wire.stamp_missing += 1,
            }
            // The next request only once this plan is through, so that every request
            // starts a plan of its own instead of rewriting one half sent.
            if !wait_end_of_plan(fixture, t1) {
                wire.lost += 1;
            }
        }
        let stop = CommandRequest::new(id, sequence + 1, axis, CommandKind::Stop);
        sequence += 1;
        if let Ok(pending) = client.send_copy(stop) {
            let deadline = now_ns() + TIMEOUT_NS;
            while now_ns() < deadline && matches!(pending.receive(), Ok(None)) {
                std::thread::sleep(Duration::from_micros(200));
            }
        }
    }
    // Setpoint → wire on the SPI boards, from the same node.
    let setpoints = open_setpoints(&node, &names)?;
    let ports = crate::stream_wire::Ports {
        commands: &client,
        id,
        frames: &frames,
        setpoints: &setpoints,
    };
    let length = (duration / 2).max(Duration::from_secs(1));
    for fixture in fixtures {
        if matches!(fixture.board, WireBoard::Qq2drv | WireBoard::Spimotor) {
            // Let the axis come to rest from its last jog.
            std::thread::sleep(Duration::from_millis(300));
            let run = crate::stream_wire::run(
                &ports,
                fixture.board,
                &fixture.seen,
                length,
                &mut sequence,
            );
            result.streams.push(run);
        }
    }
    Ok(())
}

fn open_setpoints(
    node: &iceoryx2::node::Node<ipc::Ipc>,
    names: &ServiceNames,
) -> Result<iceoryx2::port::publisher::Publisher<ipc::Ipc, motion_ipc::Setpoint, ()>, String> {
    let name = iceoryx2::prelude::ServiceName::new(&names.setpoints())
        .map_err(|e| format!("{}: {e:?}", names.setpoints()))?;
    node.service_builder(&name)
        .publish_subscribe::<motion_ipc::Setpoint>()
        .open()
        .map_err(|e| format!("open {}: {e:?}", names.setpoints()))?
        .publisher_builder()
        .create()
        .map_err(|e| format!("setpoint publisher: {e:?}"))
}

/// motiond's stamp of the first write of the goal set in `tick` on `axis`, from the
/// frames, waiting up to 50 ms for it.
fn wire_stamp(frames: &ipc::Frames, tick: u64, axis: u32) -> Result<Option<AxisWire>, String> {
    let deadline = now_ns() + 50_000_000;
    while now_ns() < deadline {
        if let Some(frame) = ipc::latest(frames)?
            && let Some(wire) = frame.wire().get(axis as usize)
            && wire.goal_tick == tick
            && wire.written()
        {
            return Ok(Some(*wire));
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    Ok(None)
}

/// Waits for the first message of the goal whose first byte came at or after `t0` and whose
/// velocity has the requested sign (any goal message, on a board whose messages carry no
/// sign); its first-byte stamp and the message.
fn wait_goal(fixture: &Fixture, t0: u64, positive: bool) -> Option<(u64, Vec<u8>)> {
    loop {
        let seen = next_message(&fixture.seen, t0, TIMEOUT_NS)?;
        if trace() {
            eprintln!(
                "wire {}: +{} ns {:02x?}",
                fixture.board.slug(),
                seen.first_byte_ns.wrapping_sub(t0),
                seen.line
            );
        }
        let sign = fixture.board.goal_sign(&seen.line);
        if seen.first_byte_ns >= t0 && sign.is_some_and(|s| s.is_none_or(|p| p == positive)) {
            return Some((seen.first_byte_ns, seen.line));
        }
    }
}

/// Waits until the plan whose first message came at `t1` is through: the QSB's `W169`
/// line (MOTOR JOG); the SPI_motor's ramp (no write for [`QUIET_NS`]). The other boards'
/// goals are one message.
fn wait_end_of_plan(fixture: &Fixture, t1: u64) -> bool {
    match fixture.board {
        WireBoard::Qsb => {
            while let Some(seen) = next_message(&fixture.seen, t1, TIMEOUT_NS) {
                if trace() {
                    eprintln!(
                        "wire qsb: +{} ns {} (end of plan)",
                        seen.first_byte_ns.wrapping_sub(t1),
                        String::from_utf8_lossy(&seen.line)
                    );
                }
                if seen.first_byte_ns >= t1 && seen.line == JOG_COMMAND {
                    return true;
                }
            }
            false
        }
        WireBoard::Spimotor => {
            while now_ns() < t1 + TIMEOUT_NS {
                if next_message(&fixture.seen, now_ns(), QUIET_NS).is_none() {
                    return true;
                }
            }
            false
        }
        WireBoard::Tmcpack | WireBoard::Qq2drv => true,
    }
}

/// The next reported message, waiting at most until `since` + `limit`.
fn next_message(seen: &Receiver<LineSeen>, since: u64, limit: u64) -> Option<LineSeen> {
    let left = (since + limit).saturating_sub(now_ns());
    seen.recv_timeout(Duration::from_nanos(left)).ok()
}

/// `BENCH_WIRE_TRACE=1`: every message the phase looks at, on stderr.
fn trace() -> bool {
    std::env::var_os("BENCH_WIRE_TRACE").is_some()
}

fn baseline(fixture: &Fixture, duration: Duration, wire: &mut BoardWire) -> Result<(), String> {
    let board = fixture.board;
    let mut host = board.open_host(&fixture.link)?;
    let _ = crate::rt::set_up_thread(None, None);
    let mut random = XorShift::new(u64::from(std::process::id()) ^ now_ns());
    let end = now_ns() + duration_ns(duration);
    let mut sequence = 0u64;
    while now_ns() < end {
        sleep_until_ns(now_ns() + 1_000_000 + random.below(board.pace_ns()));
        // The model's answers to earlier messages: read and dropped, as a host would.
        WireBoard::drain(&mut host);
        while fixture.seen.try_recv().is_ok() {}
        sequence += 1;
        let positive = sequence % 2 == 1;
        let message = match wire.messages.get(usize::from(positive)) {
            Some(Some(seen)) => seen.clone(),
            _ => board.fallback_message(positive),
        };
        let t0 = now_ns();
        if !board.write(&mut host, &message) {
            wire.baseline_lost += 1;
            continue;
        }
        match wait_goal(fixture, t0, positive) {
            Some((t1, _)) => wire.baseline.record(t1 - t0),
            None => wire.baseline_lost += 1,
        }
    }
    Ok(())
}

/// The rows of the phase: per board, figure 9 and the stamp cross-check; then figure 10
/// (command → applied in ticks, every board's requests) beside `ticks_baseline`.
pub fn rows(run: &WireRun, ticks_baseline: Option<Summary>) -> Vec<Row> {
    let mut rows = Vec::new();
    for wire in &run.boards {
        let board = wire.board;
        let refused: Vec<String> = wire
            .refused
            .iter()
            .map(|(k, v)| format!("{k} ×{v}"))
            .collect();
        rows.push(Row {
            figure: format!(
                "command → first byte at the link, {} ({}): Velocity → {}",
                board.name(),
                board.transport(),
                board.message()
            ),
            unit: Unit::Ns,
            ours: wire.ours.summary(),
            baseline: Some(wire.baseline.summary()),
            baseline_label: format!(
                "the bench writing the same message through a {} itself, no motiond",
                board.transport()
            ),
            note: format!(
                "a motiond started by the bench ({}) with all four boards simulated in the bench (online after {:.1} s); \
                 t0 = CLOCK_MONOTONIC before send_copy, t1 = the board thread's read of the message's first byte; \
                 Velocity ±{} alternating, 1 ms + up to {} ms apart; lost {}, refused [{}]; baseline lost {}",
                run.rt.describe(),
                run.online_after.as_secs_f64(),
                board.velocity(),
                board.pace_ns() / 1_000_000,
                wire.lost,
                refused.join(", "),
                wire.baseline_lost
            ),
        });
        rows.push(Row {
            figure: format!(
                "motiond's own stamp of that write (frame AxisWire.wire_ns) → the message's first byte at the board, {}",
                board.name()
            ),
            unit: Unit::Ns,
            ours: wire.stamp_to_link.summary(),
            baseline: Some(wire.baseline.summary()),
            baseline_label: format!(
                "the {} alone, as above (write → first byte at the board)",
                board.transport()
            ),
            note: format!(
                "cross-check of the link stamps: the I/O thread stamps right after the transport took the message, \
                 so ours should sit at or under the transport alone; {} requests without a stamp in 50 ms; \
                 {} stamped after the board read the byte (write(2) returned after the board's thread on the other core had it; \
                 at most {:.1} µs after)",
                wire.stamp_missing,
                wire.stamp_after.0,
                wire.stamp_after.1 as f64 / 1000.0
            ),
        });
        rows.push(Row {
            figure: format!(
                "goal → its first request written, in ticks (frame AxisWire.wire_tick − goal_tick), {}",
                board.name()
            ),
            unit: Unit::Ticks,
            ours: wire.wire_ticks.summary(),
            baseline: None,
            baseline_label: "motiond's own count of the same requests; 0 = written in the tick that set the goal".to_owned(),
            note: format!(
                "{} of {} written in the goal's own tick; the tick that took the request is the goal tick, so this is the \
                 driver's turn on the link plus the I/O thread's wake-up, in ticks",
                wire.same_tick,
                wire.wire_ticks.summary().samples
            ),
        });
    }
    let streams: Vec<_> = run
        .streams
        .iter()
        .map(|stream| {
            let baseline = run
                .boards
                .iter()
                .find(|b| b.board == stream.board)
                .map(|b| b.baseline.summary())
                .unwrap_or_default();
            (stream, baseline)
        })
        .collect();
    rows.extend(crate::stream_wire::rows(&streams));
    rows.push(Row {
        figure: "command → applied in ticks, same Velocity requests (reply.tick_applied − newest frame tick at send)".to_owned(),
        unit: Unit::Ticks,
        ours: run.ticks.summary(),
        baseline: ticks_baseline,
        baseline_label: "the ticking plain peer of row 7, same computation".to_owned(),
        note: "the µs figures above include this wait for the tick plus the driver's turn on the link".to_owned(),
    });
    rows
}

/// The `--out` files of the phase: slug, title, distribution.
pub fn files(run: &WireRun) -> Vec<(String, String, &Dist)> {
    let mut files = Vec::new();
    for wire in &run.boards {
        let (slug, name) = (wire.board.slug(), wire.board.name());
        files.push((
            format!("command-to-wire-{slug}-motiond"),
            format!("command → first byte at the link, motiond, {name}"),
            &wire.ours,
        ));
        files.push((
            format!("command-to-wire-{slug}-baseline"),
            format!("message written by the bench → first byte at the board, {name}"),
            &wire.baseline,
        ));
    }
    for stream in &run.streams {
        files.push((
            format!("setpoint-to-wire-{}-motiond", stream.board.slug()),
            format!(
                "position setpoint → first byte of a transaction carrying it, {}",
                stream.board.name()
            ),
            &stream.latency,
        ));
    }
    files.push((
        "command-to-wire-ticks-motiond".to_owned(),
        "Velocity → applied, ticks".to_owned(),
        &run.ticks,
    ));
    files
}
