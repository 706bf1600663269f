//! `motiond --replay FILE.mcap`: the recorded inputs fed, in their recorded order and at
//! their recorded times, through the same drivers and engine the server built from the
//! same config — no link, no clock, no client — and every output compared with the
//! recording: each frame's digest region by region, each link's bytes, each reply.

use core::time::Duration;
use std::iter::Peekable;

use motion_boards::AnyDriver;
use motion_drivers::{Driver as _, SavedReference};
use motion_engine::{CommandPort, Engine};
use motion_ipc::{
    ClientId, CommandReply, CommandRequest, FaultCode, GroupPath, MotionFrame, Setpoint,
};

use super::digest::{FrameDigest, Region};
use super::file::Recording;
use super::record::{JournalError, Kind, Record, Records, get_sparse, records};
use motion_config::ServerConfig;

/// A replay that went through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Replayed {
    /// Ticks replayed.
    pub ticks: u64,
    /// The first tick replayed.
    pub first: u64,
}

/// What differed, and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Divergence {
    /// A region of the frame.
    #[error("the frame's {0} differs")]
    Frame(String),
    /// The bytes queued for a link.
    #[error(
        "link `{link}` was sent other bytes (byte {at}: recorded {recorded}, replayed {replayed})"
    )]
    LinkTx {
        /// The link.
        link: String,
        /// First differing byte.
        at: usize,
        /// The recorded byte (`end` past the recorded message).
        recorded: String,
        /// The replayed byte.
        replayed: String,
    },
    /// A reply.
    #[error("the reply to request {sequence} differs")]
    Reply {
        /// The request's sequence number.
        sequence: u64,
    },
    /// The engine asked for other inputs than the recorded ones.
    #[error("the engine took other inputs than recorded ({0})")]
    Inputs(&'static str),
    /// The line rate the engine asked a link to take.
    #[error(
        "link `{link}` was asked for another line rate (recorded {recorded:?}, replayed {replayed:?})"
    )]
    LinkRate {
        /// The link.
        link: String,
        /// The recorded rate change, if any.
        recorded: Option<u32>,
        /// The replayed one, if any.
        replayed: Option<u32>,
    },
    /// The replayed engine's state (drivers included) differs from the recorded snapshot:
    /// the first line of its debug form that differs, replayed and recorded.
    #[error("the engine's state differs from the snapshot recorded here: {0}")]
    State(String),
}

/// Why a replay did not go through.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The drivers or the engine could not be built from the config.
    #[error("the config does not build: {0}")]
    Build(String),
    /// The recording does not start at the server's start and holds no snapshot of the
    /// engine's state to start from.
    #[error(
        "the recording starts at tick {first} (the ring of [server] blackbox_seconds had \
         wrapped) and holds no snapshot of the engine's state: a replay needs the run from \
         its start or from a snapshot (one every quarter of blackbox_seconds)"
    )]
    NotFromStart {
        /// Its first tick.
        first: u64,
    },
    /// The snapshot a replay starts from does not decode with this build.
    #[error(
        "tick {tick}: the engine's state snapshot does not decode ({reason}): replay with \
         the motiond build that recorded it (its version is in the file's metadata)"
    )]
    Snapshot {
        /// The tick of the snapshot.
        tick: u64,
        /// What the decoder said.
        reason: String,
    },
    /// The recorder lost records (its queue was full).
    #[error("tick {tick}: the recorder lost {count} records here: a replay cannot cross the hole")]
    Lost {
        /// The tick.
        tick: u64,
        /// Records lost.
        count: u64,
    },
    /// A record could not be read.
    #[error("tick {tick}: the journal is damaged: {source}")]
    Journal {
        /// The tick.
        tick: u64,
        /// What is wrong.
        source: JournalError,
    },
    /// An output differed from the recording.
    #[error("tick {tick}: {what}")]
    Diverged {
        /// The first tick that differs.
        tick: u64,
        /// What differs.
        what: Divergence,
    },
}

/// The recorded command traffic of one step, given back to the engine.
struct ReplayPort<'r, 'a> {
    records: &'r mut Peekable<Records<'a>>,
    sender: ClientId,
    sequence: u64,
    /// The buffer a recorded path is decoded into (one for the whole replay).
    path: &'r mut GroupPath,
    divergence: Option<Divergence>,
    damage: Option<JournalError>,
}

impl ReplayPort<'_, '_> {
    /// The next record if it is of `kind`, taken.
    fn take(&mut self, kinds: &[Kind]) -> Option<Record<'_>> {
        match self.records.peek() {
            Some(Ok(record)) if kinds.contains(&record.kind) => {
                self.records.next().and_then(Result::ok)
            }
            Some(Err(error)) => {
                self.damage.get_or_insert(*error);
                None
            }
            _ => None,
        }
    }

    fn diverged(&mut self, what: Divergence) {
        self.divergence.get_or_insert(what);
    }
}

impl CommandPort for ReplayPort<'_, '_> {
    fn next_request(&mut self) -> Option<CommandRequest> {
        let record = self.take(&[Kind::Request])?;
        let sender = record.client_at(0);
        let request = get_sparse::<CommandRequest>(record.rest(16));
        match request {
            Some(request) => {
                self.sender = sender;
                self.sequence = request.sequence;
                Some(request)
            }
            None => {
                self.diverged(Divergence::Inputs("a request that does not decode"));
                None
            }
        }
    }

    fn sender(&self) -> Option<ClientId> {
        Some(self.sender)
    }

    fn take_path(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let record = self.take(&[Kind::Path, Kind::NoPath])?;
        if record.client_at(0) != client || record.u64_at(16) != id {
            self.diverged(Divergence::Inputs("a path other than the recorded one"));
            return None;
        }
        if record.kind == Kind::NoPath {
            return None;
        }
        match get_sparse::<GroupPath>(record.rest(24)) {
            Some(path) => {
                *self.path = path;
                Some(&*self.path)
            }
            None => {
                self.diverged(Divergence::Inputs("a path that does not decode"));
                None
            }
        }
    }

    fn reply(&mut self, reply: CommandReply) {
        let sequence = self.sequence;
        let recorded = self
            .take(&[Kind::Reply])
            .and_then(|record| get_sparse::<CommandReply>(record.payload));
        if recorded != Some(reply) {
            self.diverged(Divergence::Reply { sequence });
        }
    }
}

/// Where the replayed `engine` and the recorded snapshot differ: the first line of their
/// debug forms that differs, with the lines that lead to it (the path to the field).
fn state_difference(engine: &Engine<AnyDriver>, recorded: &[u8]) -> String {
    let Ok(recorded) = postcard::from_bytes::<Engine<AnyDriver>>(recorded) else {
        return "the recorded snapshot does not decode".to_owned();
    };
    let replayed = format!("{engine:#?}");
    let recorded = format!("{recorded:#?}");
    let mut path: Vec<&str> = Vec::new();
    for (mine, theirs) in replayed.lines().zip(recorded.lines()) {
        if mine != theirs {
            let path = path.join(" ");
            return format!(
                "{path} … replayed `{}`, recorded `{}`",
                mine.trim(),
                theirs.trim()
            );
        }
        let depth = mine.len() - mine.trim_start().len();
        path.truncate(depth / 4);
        if mine.trim_end().ends_with(['{', '[', '(']) {
            path.push(mine.trim());
        }
    }
    "the serialized bytes differ, not the debug forms".to_owned()
}

fn link_name(config: &ServerConfig, link: usize) -> String {
    config
        .links
        .get(link)
        .map_or_else(|| link.to_string(), |l| l.name.clone())
}

fn at(ns: u64) -> Duration {
    Duration::from_nanos(ns)
}

fn region_name(region: Region, config: &ServerConfig) -> String {
    let axis = |i: usize| config.axes.get(i).map_or("?", |a| a.name.as_str());
    match region {
        Region::Header => "header (tick, flags, counts)".to_owned(),
        Region::Devices => "device states".to_owned(),
        Region::Axis(i) => format!("axes[{i}] (axis `{}`)", axis(i)),
        Region::Wire(i) => format!("wire[{i}] (axis `{}`)", axis(i)),
        Region::Signal(i) => format!(
            "signals[{i}] (signal `{}`)",
            config.signals.get(i).map_or("?", |s| s.name.as_str())
        ),
        Region::Group(i) => format!(
            "groups[{i}] (group `{}`)",
            config.groups.get(i).map_or("?", |g| g.name.as_str())
        ),
    }
}

/// Stack of the replay's thread: a path (`GroupPath`, 392 KiB) is decoded by value, and an
/// unoptimised build copies it several times on the way.
const REPLAY_STACK: usize = 256 << 20;

/// Replays `recording` on drivers and an engine built from `config` (on a thread of its
/// own with a stack large enough for the payloads it decodes).
pub fn replay(config: &ServerConfig, recording: &Recording) -> Result<Replayed, ReplayError> {
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("replay".into())
            .stack_size(REPLAY_STACK)
            .spawn_scoped(scope, || replay_here(config, recording))
            .map_err(|error| ReplayError::Build(format!("no replay thread: {error}")))?
            .join()
            .unwrap_or_else(|_| Err(ReplayError::Build("the replay thread panicked".into())))
    })
}

fn replay_here(config: &ServerConfig, recording: &Recording) -> Result<Replayed, ReplayError> {
    let tick_number = |bytes: &[u8]| {
        records(bytes)
            .next()
            .and_then(Result::ok)
            .map_or(0, |record| record.u64_at(8))
    };
    let first = recording
        .ticks
        .first()
        .map_or(0, |bytes| tick_number(bytes));
    let from_start = first == 0 && recording.dropped() == 0;
    let mut drivers =
        motion_config::boards::build(config).map_err(|e| ReplayError::Build(e.to_string()))?;
    // What start-up handed the drivers (references a previous run saved), as it did.
    let mut restored: Vec<Vec<SavedReference>> = vec![Vec::new(); drivers.len()];
    for record in records(&recording.head).filter_map(Result::ok) {
        if record.kind == Kind::RestoredReference
            && let Some(list) = restored.get_mut(record.u64_at(0) as usize)
        {
            list.push(SavedReference {
                channel: record.u64_at(8) as usize,
                counts: record.u64_at(16) as i64,
            });
        }
    }
    for (driver, saved) in drivers.iter_mut().zip(&restored) {
        if !saved.is_empty() {
            driver.restore_references(saved);
        }
    }
    let mut engine: Engine<AnyDriver> = Engine::new(config.engine_config(), drivers)
        .map_err(|e| ReplayError::Build(e.to_string()))?;
    // From the start: the engine built from the config, as the server built it. Else from
    // the first tick that holds a snapshot of the state the server's engine had then.
    let begin = if from_start {
        engine.stamp_links();
        for record in records(&recording.head) {
            let record = record.map_err(|source| ReplayError::Journal { tick: 0, source })?;
            match record.kind {
                Kind::Start => engine.set_clock_origin(at(record.u64_at(0))),
                Kind::LinkOpening => engine.link_opening(usize::from(record.link)),
                _ => {}
            }
        }
        0
    } else {
        recording
            .ticks
            .iter()
            .position(|bytes| {
                records(bytes)
                    .filter_map(Result::ok)
                    .any(|record| record.kind == Kind::Snapshot)
            })
            .ok_or(ReplayError::NotFromStart { first })?
    };
    let first = recording
        .ticks
        .get(begin)
        .map_or(first, |bytes| tick_number(bytes));
    // Until the snapshot is restored (a replay from the start has nothing to restore).
    let mut restoring = !from_start;
    let mut frame = Box::new(MotionFrame::EMPTY);
    let mut path = Box::new(GroupPath::EMPTY);
    let mut buf = [0u8; motion_drivers::MESSAGE_LEN];
    let mut ticks = 0;
    for bytes in &recording.ticks[begin..] {
        let mut now = Duration::ZERO;
        let mut iter = records(bytes).peekable();
        let diverged = |tick: u64, what: Divergence| ReplayError::Diverged { tick, what };
        while let Some(record) = iter.next() {
            let record = record.map_err(|source| ReplayError::Journal {
                tick: engine.tick(),
                source,
            })?;
            let link = usize::from(record.link);
            if restoring && !matches!(record.kind, Kind::Tick | Kind::Snapshot) {
                // Before the snapshot in its tick (a `Lost` record): the state has it.
                continue;
            }
            match record.kind {
                Kind::Tick => now = at(record.u64_at(0)),
                Kind::Snapshot if restoring => {
                    engine = postcard::from_bytes(record.payload).map_err(|error| {
                        ReplayError::Snapshot {
                            tick: first,
                            reason: error.to_string(),
                        }
                    })?;
                    restoring = false;
                }
                Kind::Snapshot => {
                    // Replayed from an earlier point: the replayed state must be the
                    // recorded one, number for number.
                    let replayed =
                        postcard::to_allocvec(&engine).map_err(|error| ReplayError::Snapshot {
                            tick: engine.tick(),
                            reason: error.to_string(),
                        })?;
                    if replayed != record.payload {
                        let what = state_difference(&engine, record.payload);
                        return Err(diverged(engine.tick(), Divergence::State(what)));
                    }
                }
                Kind::LinkDown => engine.link_down(link, now),
                Kind::LinkUp => engine.link_up(link, now),
                Kind::LinkWritten => engine.link_written(link, at(record.u64_at(0))),
                Kind::LinkRx => {
                    engine.handle_link_rx(link, now, at(record.u64_at(0)), record.rest(8))
                }
                Kind::LinkHeard => engine.link_heard(link, at(record.u64_at(0))),
                Kind::ClientDead => engine.client_dead(record.client_at(0)),
                Kind::Estop => engine.estop(),
                Kind::ReleaseClaims => engine.release_claims_of(record.client_at(0)),
                Kind::Shutdown => engine.begin_shutdown(),
                Kind::Setpoint => {
                    let Some(setpoint) = get_sparse::<Setpoint>(record.rest(24)) else {
                        return Err(diverged(
                            engine.tick(),
                            Divergence::Inputs("a setpoint that does not decode"),
                        ));
                    };
                    engine.handle_setpoint_at(record.client_at(0), &setpoint, record.u64_at(16));
                }
                Kind::Step => {
                    let mut port = ReplayPort {
                        records: &mut iter,
                        sender: ClientId::NONE,
                        sequence: 0,
                        path: &mut path,
                        divergence: None,
                        damage: None,
                    };
                    engine.step(now, &mut port, &mut frame);
                    if let Some(source) = port.damage {
                        return Err(ReplayError::Journal {
                            tick: engine.tick(),
                            source,
                        });
                    }
                    if let Some(what) = port.divergence {
                        return Err(diverged(engine.tick(), what));
                    }
                }
                Kind::Frame => {
                    if let Some(region) = FrameDigest::of(&frame).first_difference(record.payload) {
                        return Err(diverged(
                            engine.tick(),
                            Divergence::Frame(region_name(region, config)),
                        ));
                    }
                }
                Kind::LinkTx | Kind::LinkTxNone => {
                    let sent = engine.poll_link_transmit(link, now, &mut buf);
                    let replayed: &[u8] = sent.map_or(&[], |len| &buf[..len]);
                    let recorded = if record.kind == Kind::LinkTx {
                        Some(record.payload)
                    } else {
                        None
                    };
                    // A change of the line rate the engine asked for before this message.
                    let rate = sent.and_then(|_| engine.take_link_rate(link));
                    let recorded_rate = match iter.peek() {
                        Some(Ok(next)) if next.kind == Kind::LinkRate => {
                            let baud = u32::try_from(next.u64_at(0)).unwrap_or(u32::MAX);
                            iter.next();
                            Some(baud)
                        }
                        _ => None,
                    };
                    if rate != recorded_rate {
                        return Err(diverged(
                            engine.tick(),
                            Divergence::LinkRate {
                                link: link_name(config, link),
                                recorded: recorded_rate,
                                replayed: rate,
                            },
                        ));
                    }
                    if recorded != sent.map(|_| replayed) {
                        let recorded = recorded.unwrap_or(&[]);
                        let differ = (0..recorded.len().max(replayed.len()))
                            .find(|&i| recorded.get(i) != replayed.get(i))
                            .unwrap_or(0);
                        let byte = |bytes: &[u8]| {
                            bytes
                                .get(differ)
                                .map_or_else(|| "end".to_owned(), |b| format!("0x{b:02x}"))
                        };
                        return Err(diverged(
                            engine.tick(),
                            Divergence::LinkTx {
                                link: link_name(config, link),
                                at: differ,
                                recorded: byte(recorded),
                                replayed: byte(replayed),
                            },
                        ));
                    }
                }
                Kind::Skip => engine.skip_ticks(record.u64_at(0)),
                Kind::OverrunFault => engine.stop_all_with_fault(FaultCode::Overrun),
                Kind::Lost => {
                    return Err(ReplayError::Lost {
                        tick: engine.tick(),
                        count: record.u64_at(0),
                    });
                }
                Kind::Request | Kind::Path | Kind::NoPath | Kind::Reply | Kind::LinkRate => {
                    return Err(diverged(
                        engine.tick(),
                        Divergence::Inputs("a command the engine did not ask for"),
                    ));
                }
                Kind::Start | Kind::Trigger | Kind::LinkOpening | Kind::RestoredReference => {}
            }
        }
        ticks += 1;
    }
    Ok(Replayed { ticks, first })
}
