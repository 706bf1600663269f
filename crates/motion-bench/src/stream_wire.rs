//! Setpoint → wire on the two SPI boards: in the command-to-wire phase's motiond (its
//! QuadQuad2Drv and SPI_motor stepper on SPI sockets the bench serves and watches), a
//! position stream to a one-axis group per board ([`WireBoard::stream_group`]), one
//! setpoint per tick, and for each setpoint the first goal transaction at the board that
//! carries it. Timed are the setpoints that move the board's target by at least a count (a
//! position that rounds to the count before changes nothing the board is told: near the
//! swing's ends the SPI_motor's step count stays put for several ticks).
//!
//! The client polls the frames (every 50 µs) and after each new frame `k` publishes the
//! setpoint for `k + 1` (a `(1 − cos)` swing from where the axis is, within its limits),
//! stamped t0 = CLOCK_MONOTONIC just before `send_copy`. The board's thread stamps t1 when
//! a goal transaction's first bytes arrive (the same watch as figure 9's: packet 34/36 on
//! the QuadQuad2Drv, a write to 0x90 on the SPI_motor). A transaction written during tick
//! `j` (its first byte within `[time_ns(j), time_ns(j) + period)`, the frames' deadlines)
//! was made from every setpoint applied up to tick `j`, so it carries setpoint `j` and
//! every earlier one: per setpoint for tick `j`, t1 is the first goal transaction of a
//! tick `≥ j`. The SPI_motor (`Setpoints`) gets a position goal in the tick a setpoint
//! applies; the QuadQuad2Drv (`Segments`) a segment of its own trapezoid only once the
//! last is acknowledged and as long again (docs/ARCHITECTURE.md "Coordinated motion"), so
//! its figure includes that wait.
//!
//! Baseline: the board's transport alone, figure 9's (the bench writing a transaction on
//! the SPI socket itself → its first byte at the board), measured in the same phase.

use core::time::Duration;
use std::sync::mpsc::Receiver;

use iceoryx2::port::publisher::Publisher;
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, Reason, Setpoint, StreamMode, Target,
};

use crate::dist::{Dist, Summary};
use crate::ipc::{self, Commands, Frames, Ipc};
use crate::pty::LineSeen;
use crate::report::{Row, Unit};
use crate::rt::now_ns;
use crate::wire_board::WireBoard;

/// How long a command may wait for its reply, ns.
const REPLY_NS: u64 = 2_000_000_000;

/// What one board's stream measured.
#[derive(Debug)]
pub struct StreamWire {
    /// The board.
    pub board: WireBoard,
    /// Setpoint published → first byte of the first goal transaction carrying it, ns.
    pub latency: Dist,
    /// Setpoints sent.
    pub sent: u64,
    /// Of them, setpoints whose position rounded to the same count as the one before (the
    /// board's target does not change: nothing new to carry, not timed).
    pub same_count: u64,
    /// Goal transactions seen at the board while streaming.
    pub transactions: u64,
    /// Setpoints without a goal transaction of their tick or later before the stream ended.
    pub uncarried: u64,
    /// The server's counters at the end: applied, late, early, clamped, refused.
    pub counters: [u64; 5],
    /// Why the stream did not run, if it did not.
    pub error: Option<String>,
}

/// The ports the stream uses: the wire phase's node's command client, frames and a
/// setpoint publisher on the same node (the node the server takes the claim from).
pub struct Ports<'a> {
    /// Command client.
    pub commands: &'a Commands,
    /// Its node's id.
    pub id: ClientId,
    /// Frames.
    pub frames: &'a Frames,
    /// Setpoints.
    pub setpoints: &'a Publisher<Ipc, Setpoint, ()>,
}

impl core::fmt::Debug for Ports<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Ports")
            .field("id", &self.id)
            .finish_non_exhaustive()
    }
}

/// Streams to `board`'s group for `length`, watching `seen`; `sequence` numbers the
/// commands (shared with the caller's).
pub fn run(
    ports: &Ports<'_>,
    board: WireBoard,
    seen: &Receiver<LineSeen>,
    length: Duration,
    sequence: &mut u64,
) -> StreamWire {
    let mut result = StreamWire {
        board,
        latency: Dist::new(),
        sent: 0,
        same_count: 0,
        transactions: 0,
        uncarried: 0,
        counters: [0; 5],
        error: None,
    };
    let group = board.stream_group();
    if let Err(e) = stream(ports, board, seen, length, sequence, &mut result) {
        result.error = Some(e);
    }
    let _ = command(ports, sequence, group, CommandKind::Cancel, 0.0);
    let _ = command(ports, sequence, group, CommandKind::Release, 0.0);
    result
}

fn command(
    ports: &Ports<'_>,
    sequence: &mut u64,
    group: u32,
    kind: CommandKind,
    value: f64,
) -> Result<CommandReply, String> {
    *sequence += 1;
    let mut request =
        CommandRequest::new(ports.id, *sequence, group, kind).with_values([value, 0.0, 0.0]);
    request.target = Target::Group as u32;
    let pending = ports
        .commands
        .send_copy(request)
        .map_err(|e| format!("send {}: {e:?}", kind.name()))?;
    let started = now_ns();
    loop {
        match pending.receive() {
            Ok(Some(reply)) if reply.payload().sequence == *sequence => {
                return Ok(*reply.payload());
            }
            Ok(Some(_)) => {}
            Ok(None) if now_ns() - started < REPLY_NS => {
                std::thread::sleep(Duration::from_micros(100));
            }
            Ok(None) => return Err(format!("no reply to {} within 2 s", kind.name())),
            Err(e) => return Err(format!("receive a reply: {e:?}")),
        }
    }
}

/// `kind` on the group, retried for up to 2 s while the axis is still busy.
fn accepted(
    ports: &Ports<'_>,
    sequence: &mut u64,
    group: u32,
    kind: CommandKind,
    value: f64,
) -> Result<(), String> {
    let started = now_ns();
    loop {
        let reply = command(ports, sequence, group, kind, value)?;
        match reply.result() {
            Ok(()) => return Ok(()),
            Err(Reason::Busy | Reason::GroupBusy) if now_ns() - started < REPLY_NS => {
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(reason) => {
                return Err(format!(
                    "{} on group {group} refused: {reason}",
                    kind.name()
                ));
            }
        }
    }
}

fn stream(
    ports: &Ports<'_>,
    board: WireBoard,
    seen: &Receiver<LineSeen>,
    length: Duration,
    sequence: &mut u64,
    result: &mut StreamWire,
) -> Result<(), String> {
    let group = board.stream_group();
    let axis = board.axis() as usize;
    accepted(ports, sequence, group, CommandKind::Claim, 0.0)?;
    accepted(
        ports,
        sequence,
        group,
        CommandKind::Stream,
        f64::from(StreamMode::Position as u32),
    )?;
    let first = wait_frame(ports.frames, 0)?;
    let start = first.axes().get(axis).map_or(0.0, |a| a.desired_position);
    // A reference tick and its deadline: deadlines are t0 + k · period.
    let (ref_tick, ref_ns) = (first.tick, first.time_ns);
    let period = next_period(ports.frames, &first)?;
    let (amplitude, swing_s) = board.stream_swing();
    let omega = core::f64::consts::TAU / swing_s;
    let mut setpoint = Setpoint {
        group,
        mode: StreamMode::Position as u32,
        ..Setpoint::EMPTY
    };
    let counts_per_unit = board.counts_per_unit();
    let mut last_counts = (start * counts_per_unit).round();
    // (for_tick, t0) of every setpoint that moves the target by a count; (tick, t1) of
    // every goal transaction.
    let mut sent: Vec<(u64, u64)> = Vec::with_capacity(8192);
    let mut carried: Vec<(u64, u64)> = Vec::with_capacity(8192);
    while seen.try_recv().is_ok() {}
    let end = now_ns() + u64::try_from(length.as_nanos()).unwrap_or(u64::MAX);
    let mut last_tick = first.tick;
    let mut last = first;
    while now_ns() < end {
        while let Ok(line) = seen.try_recv() {
            let tick = tick_of(line.first_byte_ns, ref_tick, ref_ns, period);
            carried.push((tick, line.first_byte_ns));
        }
        let Some(frame) = ipc::latest(ports.frames)? else {
            std::thread::sleep(Duration::from_micros(50));
            continue;
        };
        if frame.tick <= last_tick {
            continue;
        }
        last_tick = frame.tick;
        let for_tick = frame.tick + 1;
        let t = (for_tick - first.tick) as f64 * period as f64 / 1e9;
        setpoint.sequence += 1;
        setpoint.for_tick = for_tick;
        let value = start + amplitude * (1.0 - (omega * t).cos());
        setpoint.values[0] = value;
        let t0 = now_ns();
        ports
            .setpoints
            .send_copy(setpoint)
            .map_err(|e| format!("send a setpoint: {e:?}"))?;
        result.sent += 1;
        let counts = (value * counts_per_unit).round();
        if counts == last_counts {
            result.same_count += 1;
        } else {
            sent.push((for_tick, t0));
        }
        last_counts = counts;
        last = frame;
    }
    // The last setpoints' transactions.
    let settle = now_ns() + 100_000_000;
    while let Ok(line) = seen.recv_timeout(Duration::from_nanos(settle.saturating_sub(now_ns()))) {
        let tick = tick_of(line.first_byte_ns, ref_tick, ref_ns, period);
        carried.push((tick, line.first_byte_ns));
    }
    let state = ipc::latest(ports.frames)?
        .unwrap_or(last)
        .groups()
        .get(group as usize)
        .copied()
        .unwrap_or(motion_ipc::GroupState::IDLE);
    result.counters = [
        state.applied,
        state.late,
        state.early,
        state.clamped,
        state.refused,
    ];
    result.transactions = carried.len() as u64;
    for (for_tick, t0) in sent {
        // The first transaction of the setpoint's tick or later, after it was sent.
        let from = carried.partition_point(|&(tick, t1)| tick < for_tick || t1 < t0);
        match carried[from..]
            .iter()
            .find(|&&(tick, t1)| tick >= for_tick && t1 >= t0)
        {
            Some(&(_, t1)) => result.latency.record(t1 - t0),
            None => result.uncarried += 1,
        }
    }
    Ok(())
}

/// The tick during which `ns` fell, from a reference tick and its deadline.
fn tick_of(ns: u64, ref_tick: u64, ref_ns: u64, period: u64) -> u64 {
    if ns >= ref_ns {
        ref_tick + (ns - ref_ns) / period.max(1)
    } else {
        ref_tick.saturating_sub((ref_ns - ns).div_ceil(period.max(1)))
    }
}

fn wait_frame(frames: &Frames, after: u64) -> Result<motion_ipc::MotionFrame, String> {
    let deadline = now_ns() + REPLY_NS;
    while now_ns() < deadline {
        if let Some(frame) = ipc::latest(frames)?
            && frame.tick > after
        {
            return Ok(frame);
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    Err("no frame within 2 s".to_owned())
}

/// The tick period, ns, from two frames' deadlines.
fn next_period(frames: &Frames, first: &motion_ipc::MotionFrame) -> Result<u64, String> {
    let next = wait_frame(frames, first.tick)?;
    Ok((next.time_ns.saturating_sub(first.time_ns) / (next.tick - first.tick)).max(1))
}

/// The rows: per board, setpoint → first byte, beside the board's transport alone
/// (`baseline`, figure 9's, same phase).
pub fn rows(runs: &[(&StreamWire, Summary)]) -> Vec<Row> {
    runs.iter()
        .map(|(run, baseline)| {
            let [applied, late, early, clamped, refused] = run.counters;
            Row {
                figure: format!(
                    "setpoint → first byte of a transaction carrying it, {} (SPI socket): a \
                     position stream, one setpoint per tick, the setpoints that move the \
                     target by a count",
                    run.board.name()
                ),
                unit: Unit::Ns,
                ours: run.latency.summary(),
                baseline: Some(*baseline),
                baseline_label: "the SPI socket alone, as in figure 9 (the bench writing a \
                                 transaction itself → its first byte at the board)"
                    .to_owned(),
                note: format!(
                    "{}; t0 = CLOCK_MONOTONIC before send_copy of the setpoint for tick j, t1 = \
                     the first goal transaction written during tick j or later; {} setpoints, of \
                     which {} rounded to the count before (the board's target unchanged: not \
                     timed), {} goal transactions, {} setpoints carried by none before the end; \
                     the server's counters: applied {applied}, late {late}, early {early}, \
                     clamped {clamped}, refused {refused}{}",
                    run.board.stream_follows(),
                    run.sent,
                    run.same_count,
                    run.transactions,
                    run.uncarried,
                    run.error
                        .as_ref()
                        .map_or_else(String::new, |e| format!("; the stream stopped: {e}"))
                ),
            }
        })
        .collect()
}
