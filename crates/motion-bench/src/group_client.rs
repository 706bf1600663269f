//! The group phases' raw client: plain iceoryx2 on the server's services, as any client
//! would open them (no motion-client): commands, paths, setpoints, the server's description
//! and the frames, reduced to what the group figures need.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use motion_ipc::{
    AxisInfo, AxisMode, ClientId, CommandKind, CommandReply, CommandRequest, DeviceState,
    GroupAbort, GroupMotion, GroupPath, GroupState, Reason, ServerInfo, ServiceNames, Setpoint,
    Target,
};

use crate::ipc::{self, Commands, Frames, Ipc};
use crate::rt::now_ns;

/// How long a command may wait for its reply.
const REPLY_TIMEOUT: Duration = Duration::from_secs(2);

/// One axis as the server describes it.
#[derive(Debug, Clone)]
pub struct AxisDesc {
    /// Config index (into the frame's axes).
    pub index: usize,
    /// Its name.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// Its board: `device (model)`.
    pub board: String,
    /// Its soft limits, its unit.
    pub min: f64,
    /// See `min`.
    pub max: f64,
}

/// One group as the server describes it.
#[derive(Debug, Clone)]
pub struct GroupDesc {
    /// Config index (into the frame's groups).
    pub index: usize,
    /// Its member axes, the group's order.
    pub axes: Vec<AxisDesc>,
    /// Per member: the goal tolerance, its unit.
    pub goal_tolerance: Vec<f64>,
}

/// One axis in one frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct AxisRec {
    /// Measured position.
    pub position: f64,
    /// Where the server wants it now.
    pub desired: f64,
    /// Tick of its last fresh measurement.
    pub refresh: u64,
    /// [`AxisMode`] value.
    pub mode: u8,
    /// Fault code (0: none).
    pub fault: u16,
    /// [`DeviceState`] value of its board.
    pub device: u8,
}

/// What the group phases keep of one frame: the watched axes and groups.
#[derive(Debug, Clone)]
pub struct FrameRec {
    /// The frame's tick.
    pub tick: u64,
    /// The tick's deadline (CLOCK_MONOTONIC ns).
    pub time_ns: u64,
    /// When it was published.
    pub publish_ns: u64,
    /// The watched axes, in the order asked for.
    pub axes: Vec<AxisRec>,
    /// The watched groups, in the order asked for.
    pub groups: Vec<GroupState>,
}

/// Which axes and groups a pump keeps (config indices).
#[derive(Debug, Clone, Default)]
pub struct Watch {
    /// Axes.
    pub axes: Vec<usize>,
    /// Groups.
    pub groups: Vec<usize>,
}

/// A client of one server: its node, command client, frame subscriber and path publisher.
pub struct GroupClient {
    /// The node every port belongs to (the server's identity of this client).
    pub node: Node<Ipc>,
    /// This node's id, as requests carry it.
    pub id: ClientId,
    /// The server's services.
    pub names: ServiceNames,
    commands: Commands,
    frames: Frames,
    paths: Publisher<Ipc, GroupPath, ()>,
    sequence: u64,
    path_id: u64,
    /// Frames never seen between two received into the same record (a measured window).
    pub lost_frames: u64,
    /// `Run`s answered `NoPath` for a path published just before, sent again.
    pub no_path_retries: u64,
    last_tick: Option<u64>,
}

impl core::fmt::Debug for GroupClient {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("GroupClient")
            .field("names", &self.names)
            .finish_non_exhaustive()
    }
}

fn service(name: &str) -> Result<ServiceName, String> {
    ServiceName::new(name).map_err(|e| format!("service name {name:?}: {e:?}"))
}

impl GroupClient {
    /// Opens the services of `names` from a node called `motiond-bench-<label>`.
    pub fn open(names: &ServiceNames, label: &str) -> Result<Self, String> {
        let node = ipc::node(label)?;
        let commands = ipc::open_commands(&node, names)?;
        let frames = ipc::open_frames(&node, names, ipc::OPEN_TIMEOUT)?;
        let paths = node
            .service_builder(&service(&names.paths())?)
            .publish_subscribe::<GroupPath>()
            .open()
            .map_err(|e| format!("open {}: {e:?}", names.paths()))?
            .publisher_builder()
            .max_loaned_samples(1)
            .create()
            .map_err(|e| format!("path publisher on {}: {e:?}", names.paths()))?;
        Ok(Self {
            id: ClientId::from_u128(node.id().value()),
            node,
            names: names.clone(),
            commands,
            frames,
            paths,
            sequence: 0,
            path_id: 0,
            lost_frames: 0,
            no_path_retries: 0,
            last_tick: None,
        })
    }

    /// The frame subscriber (for a client loop of its own).
    pub fn frames(&self) -> &Frames {
        &self.frames
    }

    /// A publisher of setpoints on the server's `setpoints` service, on this client's node
    /// (the node the server takes a stream's claim from).
    pub fn setpoint_publisher(&self) -> Result<Publisher<Ipc, Setpoint, ()>, String> {
        self.node
            .service_builder(&service(&self.names.setpoints())?)
            .publish_subscribe::<Setpoint>()
            .open()
            .map_err(|e| format!("open {}: {e:?}", self.names.setpoints()))?
            .publisher_builder()
            .create()
            .map_err(|e| format!("setpoint publisher: {e:?}"))
    }

    /// The groups called `names`, from the server's description (`Err` names the missing).
    pub fn describe(&self, groups: &[&str]) -> Result<Vec<GroupDesc>, String> {
        let subscriber = self
            .node
            .service_builder(&service(&self.names.info())?)
            .publish_subscribe::<ServerInfo>()
            .open()
            .map_err(|e| format!("open {}: {e:?}", self.names.info()))?
            .subscriber_builder()
            .create()
            .map_err(|e| format!("subscribe to {}: {e:?}", self.names.info()))?;
        let deadline = Instant::now() + Duration::from_secs(5);
        loop {
            match subscriber.receive() {
                Ok(Some(sample)) => return describe(sample.payload(), groups),
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(10));
                }
                Ok(None) => return Err(format!("no {} within 5 s", self.names.info())),
                Err(e) => return Err(format!("receive {}: {e:?}", self.names.info())),
            }
        }
    }

    /// Sends one request and waits for its reply (a full queue is retried).
    pub fn command(
        &mut self,
        target: Target,
        index: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, String> {
        loop {
            let reply = self.send(target, index, kind, values)?;
            if reply.result() != Err(Reason::Busy) {
                return Ok(reply);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// [`GroupClient::command`] that must be accepted.
    pub fn accepted(
        &mut self,
        target: Target,
        index: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, String> {
        let reply = self.command(target, index, kind, values)?;
        match reply.result() {
            Ok(()) => Ok(reply),
            Err(reason) => Err(refusal(kind, target, index, &reply, reason)),
        }
    }

    fn send(
        &mut self,
        target: Target,
        index: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> Result<CommandReply, String> {
        self.sequence += 1;
        let mut request = CommandRequest::new(self.id, self.sequence, index, kind);
        request.target = target as u32;
        request.values = values;
        let pending = self
            .commands
            .send_copy(request)
            .map_err(|e| format!("send {}: {e:?}", kind.name()))?;
        let deadline = Instant::now() + REPLY_TIMEOUT;
        loop {
            match pending.receive() {
                Ok(Some(reply)) if reply.payload().sequence == self.sequence => {
                    return Ok(*reply.payload());
                }
                Ok(Some(_)) => {}
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_micros(100));
                }
                Ok(None) => return Err(format!("no reply to {} within 2 s", kind.name())),
                Err(e) => return Err(format!("receive a reply: {e:?}")),
            }
        }
    }

    /// Publishes a path written by `write` (given the path and its new id) on `paths` and
    /// runs it on group `group`: the path's id and the tick the server accepted it in.
    pub fn run_path(
        &mut self,
        group: usize,
        write: &dyn Fn(&mut GroupPath, u64),
    ) -> Result<(u64, u64), String> {
        self.path_id += 1;
        let id = self.path_id;
        let sample = self
            .paths
            .loan_uninit()
            .map_err(|e| format!("loan a path: {e:?}"))?;
        let mut sample = sample.write_payload(GroupPath::EMPTY);
        write(sample.payload_mut(), id);
        let delivered = sample.send().map_err(|e| format!("send a path: {e:?}"))?;
        if delivered == 0 {
            return Err(format!("no server subscribes to {}", self.names.paths()));
        }
        let index = u32::try_from(group).unwrap_or(u32::MAX);
        let values = [id as f64, 0.0, 0.0];
        let mut reply = self.command(Target::Group, index, CommandKind::Run, values)?;
        if reply.result() == Err(Reason::NoPath) {
            // The tick takes in the paths that arrived before it takes the commands: a Run
            // sent right after its path can land between the two (motiond's race, counted
            // in the report). The path is still held: the next tick finds it.
            self.no_path_retries += 1;
            std::thread::sleep(Duration::from_millis(2));
            reply = self.command(Target::Group, index, CommandKind::Run, values)?;
        }
        match reply.result() {
            Ok(()) => Ok((id, reply.tick_applied)),
            Err(reason) => Err(refusal(
                CommandKind::Run,
                Target::Group,
                index,
                &reply,
                reason,
            )),
        }
    }

    /// Drains the frames that arrived, keeping `watch`'s axes and groups of each.
    pub fn take_frames(&mut self, watch: &Watch, into: &mut Vec<FrameRec>) -> Result<(), String> {
        loop {
            match self.frames.receive() {
                Ok(Some(sample)) => {
                    let frame = sample.payload();
                    // Gaps count within one record (a measured window), not between them.
                    if let Some(last) = self.last_tick
                        && !into.is_empty()
                        && frame.tick > last + 1
                    {
                        self.lost_frames += frame.tick - last - 1;
                    }
                    self.last_tick = Some(frame.tick);
                    let axes = frame.axes();
                    let groups = frame.groups();
                    into.push(FrameRec {
                        tick: frame.tick,
                        time_ns: frame.time_ns,
                        publish_ns: frame.publish_ns,
                        axes: watch
                            .axes
                            .iter()
                            .map(|&i| {
                                axes.get(i).map_or_else(AxisRec::default, |a| AxisRec {
                                    position: a.position,
                                    desired: a.desired_position,
                                    refresh: a.last_refresh_tick,
                                    mode: a.mode,
                                    fault: a.fault,
                                    device: a.device_state,
                                })
                            })
                            .collect(),
                        groups: watch
                            .groups
                            .iter()
                            .map(|&g| groups.get(g).copied().unwrap_or(GroupState::IDLE))
                            .collect(),
                    });
                }
                Ok(None) => return Ok(()),
                Err(e) => return Err(format!("receive a frame: {e:?}")),
            }
        }
    }

    /// Takes frames (every millisecond) until `done` says so for one of them (`Ok` with
    /// every frame seen) or `timeout` passes (`Err` naming `what`).
    pub fn pump(
        &mut self,
        watch: &Watch,
        frames: &mut Vec<FrameRec>,
        timeout: Duration,
        what: &str,
        mut done: impl FnMut(&FrameRec) -> Result<bool, String>,
    ) -> Result<(), String> {
        let deadline = Instant::now() + timeout;
        let mut checked = frames.len();
        loop {
            self.take_frames(watch, frames)?;
            while checked < frames.len() {
                checked += 1;
                if done(&frames[checked - 1])? {
                    return Ok(());
                }
            }
            if Instant::now() >= deadline {
                return Err(format!("{what}: not within {timeout:?}"));
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    /// Waits until each group slot's path `ids[slot]` is done; an abort is an error.
    pub fn wait_done(
        &mut self,
        watch: &Watch,
        frames: &mut Vec<FrameRec>,
        ids: &[(usize, u64, &GroupDesc)],
        timeout: Duration,
        what: &str,
    ) -> Result<(), String> {
        let mut done = vec![false; ids.len()];
        self.pump(watch, frames, timeout, what, |frame| {
            for (n, &(slot, id, desc)) in ids.iter().enumerate() {
                let state = frame.groups[slot];
                if state.path_id != id {
                    continue;
                }
                match GroupMotion::try_from(state.motion) {
                    Ok(GroupMotion::Done) => done[n] = true,
                    Ok(GroupMotion::Aborted) => {
                        let axis = state
                            .abort_axis()
                            .and_then(|index| desc.axes.iter().find(|a| a.index == index as usize));
                        return Err(format!(
                            "{what}: aborted ({}) in tick {} at {:.3} s of {:.3} s{}",
                            GroupAbort::try_from(state.abort).map_or("?", GroupAbort::name),
                            frame.tick,
                            state.time,
                            state.duration,
                            axis.map_or_else(String::new, |a| format!(
                                ": axis `{}` ({}) was {:.4} {} from its path, tolerance {:.4}",
                                a.name, a.board, state.abort_value, a.unit, state.abort_limit
                            ))
                        ));
                    }
                    _ => {}
                }
            }
            Ok(done.iter().all(|d| *d))
        })
    }

    /// Frames for `ticks` ticks from now (at least), appended to `frames`.
    pub fn frames_for(
        &mut self,
        watch: &Watch,
        frames: &mut Vec<FrameRec>,
        ticks: u64,
    ) -> Result<(), String> {
        let mut end = None;
        let timeout = Duration::from_millis(ticks.saturating_mul(4) + 2000);
        self.pump(watch, frames, timeout, "frames", |frame| {
            let end = *end.get_or_insert(frame.tick + ticks);
            Ok(frame.tick >= end)
        })
    }

    /// Waits (up to `timeout`) until every axis of `watch` is fresh within the last
    /// `max_age` ticks, its board online, without a fault, holding or off.
    pub fn wait_ready(&mut self, watch: &Watch, timeout: Duration) -> Result<(), String> {
        let mut frames = Vec::new();
        let started = now_ns();
        let mut last = String::new();
        let result = self.pump(watch, &mut frames, timeout, "axes ready", |frame| {
            let waiting: Vec<String> = frame
                .axes
                .iter()
                .zip(&watch.axes)
                .filter(|(a, _)| {
                    a.device != DeviceState::Online as u8
                        || a.fault != 0
                        || a.refresh + 500 < frame.tick
                        || a.mode != AxisMode::Hold as u8
                })
                .map(|(a, index)| {
                    format!(
                        "axis #{index}: board state {}, fault {}, mode {}, refreshed in tick {} of {}",
                        a.device, a.fault, a.mode, a.refresh, frame.tick
                    )
                })
                .collect();
            last = waiting.join("; ");
            Ok(waiting.is_empty())
        });
        result.map_err(|e| format!("{e} ({:.1} s): {last}", (now_ns() - started) as f64 / 1e9))
    }
}

fn describe(info: &ServerInfo, names: &[&str]) -> Result<Vec<GroupDesc>, String> {
    let axes = info.axes();
    let devices = info.devices();
    names
        .iter()
        .map(|name| {
            let index = info.group_index(name).ok_or_else(|| {
                format!(
                    "the server has no group `{name}` (it has: {})",
                    info.groups()
                        .iter()
                        .map(|g| g.name().to_owned())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })?;
            let group = &info.groups()[index];
            let members = group
                .axes()
                .iter()
                .map(|&axis| {
                    let a = axes.get(axis as usize).copied().unwrap_or(AxisInfo::EMPTY);
                    let model = devices
                        .get(usize::from(a.device_index))
                        .map_or_else(String::new, |d| format!(" ({})", d.model_name()));
                    AxisDesc {
                        index: axis as usize,
                        name: a.name().to_owned(),
                        unit: a.unit().to_owned(),
                        board: format!("{}{model}", a.device()),
                        min: a.min,
                        max: a.max,
                    }
                })
                .collect::<Vec<_>>();
            Ok(GroupDesc {
                index,
                goal_tolerance: group.goal_tolerance[..members.len()].to_vec(),
                axes: members,
            })
        })
        .collect()
}

/// A refused command in words.
pub fn refusal(
    kind: CommandKind,
    target: Target,
    index: u32,
    reply: &CommandReply,
    reason: Reason,
) -> String {
    let mut text = format!(
        "{} on {target:?} {index} refused in tick {}: {reason}",
        kind.name(),
        reply.tick_applied
    );
    if reply.at_axis != u32::MAX {
        text.push_str(&format!(" (axis #{}", reply.at_axis));
        if reply.at_point != u32::MAX {
            text.push_str(&format!(", point {}", reply.at_point));
        }
        text.push_str(&format!(", value {} limit {})", reply.value, reply.limit));
    }
    text
}
