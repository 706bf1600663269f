//! The black box as an MCAP file: the journal (channel `/motiond/<name>/blackbox/journal`,
//! one message per tick holding that tick's records, the start-up records first), readable
//! channels of the same ticks for Foxglove or PlotJuggler (the bytes of every link in both
//! directions, the commands and their replies, the events), and a metadata record
//! `motiond.blackbox` with the config file's text, the server's name and rate, the versions
//! and the ticks held. [`read`] gives the journal back for a replay.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::{MessageHeader, Metadata, Record as McapRecord};
use motion_ipc::{CommandKind, CommandReply, CommandRequest, Reason};

use super::record::{Kind, Record, get_sparse, records};

/// The journal channel's message encoding.
pub const JOURNAL_ENCODING: &str = "application/x-motiond-journal";
/// The metadata record's name.
pub const METADATA_NAME: &str = "motiond.blackbox";

/// What a saved file says about the server.
#[derive(Debug, Clone, Default)]
pub struct BlackboxFile {
    /// The instance name.
    pub server_name: String,
    /// The tick rate.
    pub tick_hz: u32,
    /// The config file's path.
    pub config_path: PathBuf,
    /// The config file's text, as it was at start-up (empty if it could not be read).
    pub config_text: String,
    /// Link names, in link order.
    pub link_names: Vec<String>,
}

/// The records to write: the start-up records and the ring's ticks, oldest first.
#[derive(Debug)]
pub struct Ticks<'a> {
    /// The records before the first tick.
    pub head: &'a [u8],
    /// Per tick: its number and its records.
    pub ticks: Vec<(u64, Cow<'a, [u8]>)>,
    /// Ticks the ring dropped before the first one held.
    pub dropped: u64,
}

/// Why a file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum SaveError {
    /// The file system refused.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// The MCAP library refused.
    #[error("{}: MCAP: {source}", path.display())]
    Mcap {
        /// The path.
        path: PathBuf,
        /// The library's error.
        source: mcap::McapError,
    },
    /// `blackbox_dir` is not the server's own, or could not be made (motion_config::private_dir).
    #[error(transparent)]
    Dir(#[from] motion_config::private_dir::PrivateDirError),
    /// The file is MCAP but holds no black box.
    #[error("{}: {what}", path.display())]
    NotABlackbox {
        /// The path.
        path: PathBuf,
        /// What is missing.
        what: &'static str,
    },
}

/// A black box read back.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// The metadata's entries.
    pub metadata: BTreeMap<String, String>,
    /// The start-up records.
    pub head: Vec<u8>,
    /// Per tick: its records (journal messages in order).
    pub ticks: Vec<Vec<u8>>,
}

impl Recording {
    /// The recording of a ring's ticks (what a saved file reads back as), without a file.
    pub fn of(ticks: &Ticks<'_>) -> Self {
        let mut metadata = BTreeMap::new();
        metadata.insert("dropped_ticks".to_owned(), ticks.dropped.to_string());
        Self {
            metadata,
            head: ticks.head.to_vec(),
            ticks: ticks
                .ticks
                .iter()
                .map(|(_, bytes)| bytes.to_vec())
                .collect(),
        }
    }

    /// The config file's text as recorded.
    pub fn config_text(&self) -> &str {
        self.metadata.get("config").map_or("", String::as_str)
    }

    /// Ticks the ring dropped before the first one held.
    pub fn dropped(&self) -> u64 {
        self.metadata
            .get("dropped_ticks")
            .and_then(|text| text.parse().ok())
            .unwrap_or(0)
    }
}

fn hex(bytes: &[u8]) -> String {
    let mut text = String::with_capacity(bytes.len() * 2);
    for byte in bytes {
        let _ = write!(text, "{byte:02x}");
    }
    text
}

/// One readable JSON line of a record, with its channel; `None` for records only the
/// journal needs.
fn readable(record: &Record<'_>, links: &[String], tick: u64) -> Option<(usize, String)> {
    let link = || {
        links
            .get(usize::from(record.link))
            .map_or("?", String::as_str)
    };
    let json = |text: &str| text.replace('\\', "\\\\").replace('"', "\\\"");
    Some(match record.kind {
        Kind::LinkRx => (
            0,
            format!(
                r#"{{"tick":{tick},"link":"{}","at_ns":{},"bytes":"{}"}}"#,
                json(link()),
                record.u64_at(0),
                hex(record.rest(8))
            ),
        ),
        Kind::LinkTx => (
            1,
            format!(
                r#"{{"tick":{tick},"link":"{}","bytes":"{}"}}"#,
                json(link()),
                hex(record.payload)
            ),
        ),
        Kind::Request => {
            let request = get_sparse::<CommandRequest>(record.rest(16))?;
            let kind = request.kind().map_or_else(
                |_| format!("{}", request.kind),
                |kind: CommandKind| format!("{kind:?}"),
            );
            (
                2,
                format!(
                    r#"{{"tick":{tick},"request":"{kind}","sender":"{:016x}{:016x}","sequence":{},"axis":{},"values":[{},{},{}]}}"#,
                    record.client_at(0).hi,
                    record.client_at(0).lo,
                    request.sequence,
                    request.axis,
                    finite(request.values[0]),
                    finite(request.values[1]),
                    finite(request.values[2])
                ),
            )
        }
        Kind::Reply => {
            let reply = get_sparse::<CommandReply>(record.payload)?;
            let reason = Reason::try_from(reply.reason).map_or_else(
                |_| format!("{}", reply.reason),
                |reason| format!("{reason:?}"),
            );
            (
                2,
                format!(
                    r#"{{"tick":{tick},"reply":"{reason}","sequence":{},"axis":{}}}"#,
                    reply.sequence, reply.axis
                ),
            )
        }
        Kind::LinkDown | Kind::LinkUp => (
            3,
            format!(
                r#"{{"tick":{tick},"event":"{}","link":"{}"}}"#,
                if record.kind == Kind::LinkUp {
                    "link up"
                } else {
                    "link down"
                },
                json(link())
            ),
        ),
        Kind::Estop => (3, format!(r#"{{"tick":{tick},"event":"e-stop"}}"#)),
        Kind::Trigger => (3, format!(r#"{{"tick":{tick},"event":"trigger"}}"#)),
        Kind::Lost => (
            3,
            format!(
                r#"{{"tick":{tick},"event":"lost","records":{}}}"#,
                record.u64_at(0)
            ),
        ),
        Kind::Skip => (
            3,
            format!(
                r#"{{"tick":{tick},"event":"overrun","skipped":{}}}"#,
                record.u64_at(0)
            ),
        ),
        Kind::OverrunFault => (3, format!(r#"{{"tick":{tick},"event":"overrun fault"}}"#)),
        Kind::Shutdown => (3, format!(r#"{{"tick":{tick},"event":"shutdown"}}"#)),
        Kind::LinkRate => (
            3,
            format!(
                r#"{{"tick":{tick},"event":"line rate","link":"{}","baud":{}}}"#,
                json(link()),
                record.u64_at(0)
            ),
        ),
        Kind::Snapshot => (
            3,
            format!(
                r#"{{"tick":{tick},"event":"state snapshot","bytes":{}}}"#,
                record.payload.len()
            ),
        ),
        _ => return None,
    })
}

/// A number JSON can hold (NaN and infinities as null).
fn finite(value: f64) -> String {
    if value.is_finite() {
        format!("{value}")
    } else {
        "null".to_owned()
    }
}

impl BlackboxFile {
    /// Writes `ticks` to `path` (created, or truncated), saved for `reason`.
    pub fn write(&self, path: &Path, ticks: &Ticks<'_>, reason: &str) -> Result<(), SaveError> {
        let file = File::create(path).map_err(|source| SaveError::Io {
            path: path.to_owned(),
            source,
        })?;
        self.write_to(file, path, ticks, reason)
    }

    /// [`write`](Self::write) into `file`, already created at `path` (the recorder's, made
    /// `O_EXCL | O_NOFOLLOW` in the black box's directory), synced before it returns.
    pub fn write_to(
        &self,
        file: File,
        path: &Path,
        ticks: &Ticks<'_>,
        reason: &str,
    ) -> Result<(), SaveError> {
        let io = |source| SaveError::Io {
            path: path.to_owned(),
            source,
        };
        let mcap = |source| SaveError::Mcap {
            path: path.to_owned(),
            source,
        };
        let mut writer = mcap::WriteOptions::new()
            .compression(None)
            .library(format!("motiond {}", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(mcap)?;
        let topic = |what: &str| format!("/motiond/{}/blackbox/{what}", self.server_name);
        let none = BTreeMap::new();
        let journal = writer
            .add_channel(0, &topic("journal"), JOURNAL_ENCODING, &none)
            .map_err(mcap)?;
        let mut readable_channels = Vec::new();
        for (what, title) in [
            ("link_rx", "motiond.LinkRx"),
            ("link_tx", "motiond.LinkTx"),
            ("commands", "motiond.Command"),
            ("events", "motiond.Event"),
        ] {
            let schema = writer
                .add_schema(title, "jsonschema", br#"{"type":"object"}"#)
                .map_err(mcap)?;
            readable_channels.push(
                writer
                    .add_channel(schema, &topic(what), "json", &none)
                    .map_err(mcap)?,
            );
        }
        let epoch_ns = records(ticks.head)
            .filter_map(Result::ok)
            .find(|record| record.kind == Kind::Start)
            .map_or(0, |record| record.u64_at(0));
        let mut sequence = 0u32;
        let mut write =
            |writer: &mut mcap::Writer<BufWriter<File>>, channel: u16, time: u64, data: &[u8]| {
                sequence = sequence.wrapping_add(1);
                writer.write_to_known_channel(
                    &MessageHeader {
                        channel_id: channel,
                        sequence,
                        log_time: time,
                        publish_time: time,
                    },
                    data,
                )
            };
        write(&mut writer, journal, epoch_ns, ticks.head).map_err(mcap)?;
        for (tick, bytes) in &ticks.ticks {
            let (tick, bytes) = (*tick, bytes.as_ref());
            let now_ns = records(bytes)
                .next()
                .and_then(Result::ok)
                .map_or(0, |record| record.u64_at(0));
            let time = epoch_ns.saturating_add(now_ns);
            write(&mut writer, journal, time, bytes).map_err(mcap)?;
            for record in records(bytes).filter_map(Result::ok) {
                if let Some((channel, line)) = readable(&record, &self.link_names, tick) {
                    write(
                        &mut writer,
                        readable_channels[channel],
                        time,
                        line.as_bytes(),
                    )
                    .map_err(mcap)?;
                }
            }
        }
        let first = ticks.ticks.first().map_or(0, |(tick, _)| *tick);
        let last = ticks.ticks.last().map_or(0, |(tick, _)| *tick);
        let metadata = [
            ("server", self.server_name.clone()),
            ("tick_hz", self.tick_hz.to_string()),
            ("reason", reason.to_owned()),
            ("config_path", self.config_path.display().to_string()),
            ("config", self.config_text.clone()),
            ("links", self.link_names.join(",")),
            ("first_tick", first.to_string()),
            ("last_tick", last.to_string()),
            ("ticks", ticks.ticks.len().to_string()),
            ("dropped_ticks", ticks.dropped.to_string()),
            ("motiond_version", env!("CARGO_PKG_VERSION").to_owned()),
            ("schema_version", motion_ipc::SCHEMA_VERSION.to_string()),
        ];
        writer
            .write_metadata(&Metadata {
                name: METADATA_NAME.to_owned(),
                metadata: metadata
                    .into_iter()
                    .map(|(key, value)| (key.to_owned(), value))
                    .collect(),
            })
            .map_err(mcap)?;
        writer.finish().map_err(mcap)?;
        let file = writer
            .into_inner()
            .into_inner()
            .map_err(|error| io(error.into_error()))?;
        file.sync_all().map_err(io)
    }
}

/// Reads the black box in `path`.
pub fn read(path: &Path) -> Result<Recording, SaveError> {
    let bytes = std::fs::read(path).map_err(|source| SaveError::Io {
        path: path.to_owned(),
        source,
    })?;
    let mcap = |source| SaveError::Mcap {
        path: path.to_owned(),
        source,
    };
    let mut recording = Recording::default();
    let mut journal = None;
    let mut first = true;
    for record in mcap::read::ChunkFlattener::new(&bytes).map_err(mcap)? {
        match record.map_err(mcap)? {
            McapRecord::Channel(channel) if channel.message_encoding == JOURNAL_ENCODING => {
                journal = Some(channel.id);
            }
            McapRecord::Message { header, data } if Some(header.channel_id) == journal => {
                if first {
                    recording.head = data.into_owned();
                    first = false;
                } else {
                    recording.ticks.push(data.into_owned());
                }
            }
            McapRecord::Metadata(metadata) if metadata.name == METADATA_NAME => {
                recording.metadata = metadata.metadata;
            }
            _ => {}
        }
    }
    if journal.is_none() || first {
        return Err(SaveError::NotABlackbox {
            path: path.to_owned(),
            what: "no motiond black box journal in it",
        });
    }
    Ok(recording)
}
