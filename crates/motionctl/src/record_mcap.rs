//! `record --out FILE.mcap`: an MCAP file (the `mcap` crate's writer: chunked, with the
//! summary section and its indexes, which Foxglove and PlotJuggler need to open it).
//!
//! Channels, each one message per recorded tick unless said otherwise, log and publish time
//! = the tick's stamp (below), sequence = the tick (mod 2³²):
//! - `/motiond/<server>/joint_states`: ROS 2 `sensor_msgs/msg/JointState` in CDR
//!   ([`joint_state_cdr`](crate::joint_state_cdr)): the recorded axes' names, measured
//!   positions and velocities in their configured units; `effort` is empty (a frame carries
//!   no measured effort or power).
//! - `/motiond/<server>/axes`: JSON, the recorded axes as `motionctl status --json` shows
//!   them plus the desired position and velocity.
//! - `/motiond/<server>/signals`: JSON, every signal (when the server has any).
//! - `/motiond/<server>/groups`: JSON, every group's motion and stream (when it has any).
//! - `/motiond/<server>/faults`: JSON, one message when a recorded axis's fault code
//!   changes (a fault already latched in the first tick counts as a change from none).
//!
//! The stamp: the tick's deadline (`time_ns`, CLOCK_MONOTONIC of the server) minus the
//! server's start (`start_time_ns` of its description) plus the server's start on the
//! wall clock (this machine's CLOCK_REALTIME − CLOCK_MONOTONIC; through `--remote`, where
//! the clocks are another machine's, estimated from the newest frame's age). Metadata
//! records: `motiond.description` (`motionctl list --json`: the description and the
//! machine parameters), `motiond.config` (the parameters in effect, `list`'s lines: the
//! config file itself is not served to clients), `motiond.versions`, `motiond.recording`.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use mcap::records::{MessageHeader, Metadata};
use motion_client::Client;
use motion_client::ipc::{MotionFrame, SCHEMA_VERSION, ServerInfo, StreamState, read_text};
use nix::time::{ClockId, clock_gettime};
use serde_json::{Value, json};

use crate::Service;
use crate::describe::{fault_name, fault_text, info_json};
use crate::group::groups_json;
use crate::io::signal_states_json;
use crate::joint_state_cdr::{JOINT_STATE_DEFINITION, JOINT_STATE_SCHEMA_NAME, JointState, Stamp};
use crate::machine::{ParamTable, params_lines};
use crate::record_output::Recording;

/// A JSON schema for an object with a tick and the named array or fields.
fn object_schema(title: &str, properties: Value) -> String {
    let mut all = json!({ "tick": { "type": "integer" } });
    if let (Some(all), Some(more)) = (all.as_object_mut(), properties.as_object()) {
        all.extend(more.clone());
    }
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": title,
        "type": "object",
        "properties": all,
    })
    .to_string()
}

/// An array of objects with these typed fields (the fields a plot or a table wants; the
/// messages carry more). Plain types only: no `null` unions, which not every reader takes.
fn array_of_objects(fields: &[(&str, &str)]) -> Value {
    let properties: serde_json::Map<String, Value> = fields
        .iter()
        .map(|(name, kind)| ((*name).to_owned(), json!({ "type": kind })))
        .collect();
    json!({ "type": "array", "items": { "type": "object", "properties": properties } })
}

/// The server's start (tick 0's deadline) on the wall clock, ns since the epoch (see the
/// module's docs).
fn server_start_wall_ns(client: &Client<Service>, info: &ServerInfo) -> anyhow::Result<i128> {
    let ns = |clock| -> anyhow::Result<i128> {
        let time = clock_gettime(clock).context("read the clock")?;
        Ok(i128::from(time.tv_sec()) * 1_000_000_000 + i128::from(time.tv_nsec()))
    };
    let since_start = if client.is_remote() {
        // The server's clocks are another machine's: its newest frame is "now".
        i128::from(client.latest()?.time_ns) - i128::from(info.start_time_ns)
    } else {
        // Same machine, same CLOCK_MONOTONIC: exact.
        ns(ClockId::CLOCK_MONOTONIC)? - i128::from(info.start_time_ns)
    };
    Ok(ns(ClockId::CLOCK_REALTIME)? - since_start)
}

/// The channel ids, `None` for a channel the server has nothing for.
#[derive(Debug, Clone, Copy)]
struct Channels {
    joint_states: u16,
    axes: u16,
    signals: Option<u16>,
    groups: Option<u16>,
    faults: u16,
}

/// An MCAP file being written.
pub struct McapRecording {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<File>>,
    channels: Channels,
    info: Box<ServerInfo>,
    axes: Vec<usize>,
    names: Vec<String>,
    start_wall_ns: i128,
    faults: Vec<u16>,
    first_tick: Option<u64>,
    last_tick: Option<u64>,
    messages: u64,
}

impl core::fmt::Debug for McapRecording {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("McapRecording")
            .field("path", &self.path)
            .field("axes", &self.names)
            .finish_non_exhaustive()
    }
}

impl McapRecording {
    /// Creates the file: its schemas, channels and the metadata known before the first tick.
    pub fn create(client: &Client<Service>, axes: &[usize], path: &Path) -> anyhow::Result<Self> {
        let info = Box::new(*client.info()?);
        let server = read_text(&info.name).to_owned();
        let names: Vec<String> = axes
            .iter()
            .map(|&index| info.axes().get(index).map(|a| a.name().to_owned()))
            .collect::<Option<_>>()
            .context("axis list changed")?;
        let units: Vec<String> = axes
            .iter()
            .filter_map(|&index| info.axes().get(index))
            .map(|a| format!("{}={}", a.name(), a.unit()))
            .collect();
        let file = File::create(path).context("create the file")?;
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("motionctl {}", env!("CARGO_PKG_VERSION")));
        let mut writer = options.create(BufWriter::new(file))?;
        let topic = |what: &str| format!("/motiond/{server}/{what}");
        let mut joint_metadata = BTreeMap::new();
        joint_metadata.insert("units".to_owned(), units.join(","));
        let joint_schema = writer.add_schema(
            JOINT_STATE_SCHEMA_NAME,
            "ros2msg",
            JOINT_STATE_DEFINITION.as_bytes(),
        )?;
        let joint_states =
            writer.add_channel(joint_schema, &topic("joint_states"), "cdr", &joint_metadata)?;
        let mut json_channel = |what: &str, title: &str, properties: Value| {
            let schema = object_schema(title, properties);
            let id = writer.add_schema(title, "jsonschema", schema.as_bytes())?;
            writer.add_channel(id, &topic(what), "json", &BTreeMap::new())
        };
        let axes_channel = json_channel(
            "axes",
            "motiond.Axes",
            json!({ "axes": array_of_objects(&[
                ("name", "string"),
                ("unit", "string"),
                ("mode", "string"),
                ("position", "number"),
                ("velocity", "number"),
                ("target", "number"),
                ("desired_position", "number"),
                ("desired_velocity", "number"),
            ]) }),
        )?;
        let signals = if info.signals().is_empty() {
            None
        } else {
            Some(json_channel(
                "signals",
                "motiond.Signals",
                json!({ "signals": array_of_objects(&[
                    ("name", "string"),
                    ("kind", "string"),
                    ("unit", "string"),
                    ("value", "number"),
                ]) }),
            )?)
        };
        let groups = if info.groups().is_empty() {
            None
        } else {
            Some(json_channel(
                "groups",
                "motiond.Groups",
                json!({ "groups": array_of_objects(&[
                    ("name", "string"),
                    ("motion", "string"),
                    ("stream", "string"),
                    ("time", "number"),
                    ("duration", "number"),
                    ("feed", "number"),
                ]) }),
            )?)
        };
        let faults = json_channel(
            "faults",
            "motiond.FaultChange",
            json!({
                "axis": { "type": "string" },
                "fault": { "type": "string" },
                "previous": { "type": "string" },
                "code": { "type": "integer" },
                "text": { "type": "string" },
                "value": { "type": "number" },
                "limit": { "type": "number" },
            }),
        )?;
        let params = ParamTable::new(client.machine_params());
        write_metadata(
            &mut writer,
            "motiond.description",
            [("json", info_json(&info, &params).to_string())],
        )?;
        let mut config = vec![(
            "note",
            "the config file is not served to clients: these are the server's machine \
             parameters in effect and its description"
                .to_owned(),
        )];
        config.push(("machine_params", params_lines(&info, &params).join("\n")));
        if let Some(error) = params.error() {
            config.push(("machine_params_error", error.to_owned()));
        }
        write_metadata(&mut writer, "motiond.config", config)?;
        write_metadata(
            &mut writer,
            "motiond.versions",
            [
                ("motionctl", env!("CARGO_PKG_VERSION").to_owned()),
                ("motion_ipc_schema_version", SCHEMA_VERSION.to_string()),
                ("server_schema_version", info.schema_version.to_string()),
            ],
        )?;
        let start_wall_ns = server_start_wall_ns(client, &info)?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            channels: Channels {
                joint_states,
                axes: axes_channel,
                signals,
                groups,
                faults,
            },
            faults: vec![0; axes.len()],
            axes: axes.to_vec(),
            names,
            info,
            start_wall_ns,
            first_tick: None,
            last_tick: None,
            messages: 0,
        })
    }

    fn stamp_ns(&self, frame: &MotionFrame) -> anyhow::Result<u64> {
        let since_start = i128::from(frame.time_ns) - i128::from(self.info.start_time_ns);
        u64::try_from(since_start + self.start_wall_ns).context("the tick's stamp is before 1970")
    }

    fn write(
        &mut self,
        channel_id: u16,
        frame: &MotionFrame,
        stamp: u64,
        data: &[u8],
    ) -> anyhow::Result<()> {
        let header = MessageHeader {
            channel_id,
            sequence: frame.tick as u32,
            log_time: stamp,
            publish_time: stamp,
        };
        self.writer.write_to_known_channel(&header, data)?;
        self.messages += 1;
        Ok(())
    }

    fn write_json(
        &mut self,
        channel_id: u16,
        frame: &MotionFrame,
        stamp: u64,
        value: &Value,
    ) -> anyhow::Result<()> {
        let data = serde_json::to_vec(value)?;
        self.write(channel_id, frame, stamp, &data)
    }

    /// A message on the faults channel per recorded axis whose fault code changed.
    fn fault_changes(&mut self, frame: &MotionFrame, stamp: u64) -> anyhow::Result<()> {
        for slot in 0..self.axes.len() {
            let index = self.axes[slot];
            let state = frame.axes().get(index).copied().unwrap_or_default();
            let previous = self.faults[slot];
            if state.fault == previous {
                continue;
            }
            self.faults[slot] = state.fault;
            let mut before = state;
            before.fault = previous;
            let text = self
                .info
                .axes()
                .get(index)
                .and_then(|axis| fault_text(axis, &state));
            let value = json!({
                "tick": frame.tick,
                "axis": self.names[slot],
                "fault": fault_name(&state).unwrap_or_else(|| "none".to_owned()),
                "previous": fault_name(&before).unwrap_or_else(|| "none".to_owned()),
                "code": state.fault,
                "text": text.unwrap_or_default(),
                "value": state.fault_value,
                "limit": state.fault_limit,
            });
            self.write_json(self.channels.faults, frame, stamp, &value)?;
        }
        Ok(())
    }
}

fn write_metadata<'a>(
    writer: &mut mcap::Writer<BufWriter<File>>,
    name: &str,
    entries: impl IntoIterator<Item = (&'a str, String)>,
) -> anyhow::Result<()> {
    let metadata = entries
        .into_iter()
        .map(|(key, value)| (key.to_owned(), value))
        .collect();
    writer.write_metadata(&Metadata {
        name: name.to_owned(),
        metadata,
    })?;
    Ok(())
}

impl Recording for McapRecording {
    fn frame(&mut self, frame: &MotionFrame) -> anyhow::Result<()> {
        let stamp = self.stamp_ns(frame)?;
        self.first_tick.get_or_insert(frame.tick);
        self.last_tick = Some(frame.tick);
        let states: Vec<_> = self
            .axes
            .iter()
            .map(|&index| frame.axes().get(index).copied().unwrap_or_default())
            .collect();
        let position: Vec<f64> = states.iter().map(|s| s.position).collect();
        let velocity: Vec<f64> = states.iter().map(|s| s.velocity).collect();
        let name: Vec<&str> = self.names.iter().map(String::as_str).collect();
        let message = JointState {
            stamp: Stamp::from_ns(stamp)?,
            frame_id: "",
            name: &name,
            position: &position,
            velocity: &velocity,
            effort: &[],
        };
        let cdr = message.to_cdr()?;
        self.write(self.channels.joint_states, frame, stamp, &cdr)?;

        let axes: Vec<Value> = self
            .axes
            .iter()
            .zip(&states)
            .filter_map(|(&index, state)| {
                let axis = self.info.axes().get(index)?;
                let mut value = motion_wire::json::axis_state(axis, state, frame.tick, "motionctl");
                value["desired_position"] = json!(state.desired_position);
                value["desired_velocity"] = json!(state.desired_velocity);
                Some(value)
            })
            .collect();
        let value = json!({ "tick": frame.tick, "axes": axes });
        self.write_json(self.channels.axes, frame, stamp, &value)?;
        if let Some(channel) = self.channels.signals {
            let signals = signal_states_json(&self.info, frame);
            let value = json!({ "tick": frame.tick, "signals": signals });
            self.write_json(channel, frame, stamp, &value)?;
        }
        if let Some(channel) = self.channels.groups {
            let mut groups = groups_json(&self.info, frame);
            if let Some(list) = groups.as_array_mut()
                && list.len() == frame.groups().len()
            {
                for (value, raw) in list.iter_mut().zip(frame.groups()) {
                    value["stream"] = json!(
                        StreamState::try_from(raw.stream).map_or("unknown", StreamState::name)
                    );
                    value["stream_applied"] = json!(raw.applied);
                    value["stream_late"] = json!(raw.late);
                    value["stream_early"] = json!(raw.early);
                    value["stream_clamped"] = json!(raw.clamped);
                    value["stream_refused"] = json!(raw.refused);
                    value["stream_last_sequence"] = json!(raw.last_sequence);
                }
            }
            let value = json!({ "tick": frame.tick, "groups": groups });
            self.write_json(channel, frame, stamp, &value)?;
        }
        self.fault_changes(frame, stamp)
    }

    fn finish(mut self: Box<Self>) -> anyhow::Result<()> {
        let span = match (self.first_tick, self.last_tick) {
            (Some(first), Some(last)) => format!("{first}..={last}"),
            _ => "none".to_owned(),
        };
        let server = read_text(&self.info.name).to_owned();
        let recording = [
            ("server", server),
            ("tick_hz", self.info.tick_hz.to_string()),
            ("ticks", span),
            ("axes", self.names.join(",")),
            ("messages", self.messages.to_string()),
            (
                "stamp",
                "the tick's deadline on the server's CLOCK_MONOTONIC, moved to the wall clock \
                 by the server's start time"
                    .to_owned(),
            ),
        ];
        write_metadata(&mut self.writer, "motiond.recording", recording)?;
        self.writer.finish()?;
        let McapRecording { writer, .. } = *self;
        writer.into_inner().flush()?;
        Ok(())
    }

    fn path(&self) -> &Path {
        &self.path
    }
}
