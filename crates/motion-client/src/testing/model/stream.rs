//! The fake's setpoint streams, minimal: `Stream` on a group every member of which the
//! sender claimed; setpoints from the streaming node queued for their tick (from any other
//! node, of another mode, not finite: `refused`; too far ahead: `early`); each applies on
//! its own time, `motion_ipc::playout`'s rule as in the server (a late one grows the
//! stream's delay, never skipping one); no setpoint for `stream_timeout` ticks: `stale`,
//! the group stops; `Cancel` ends the stream idle. Velocities are integrated, positions
//! taken as they are; no limits.

use motion_ipc::{
    AxisMode, ClientId, GroupAbort, GroupMotion, GroupState, MAX_GROUP_AXES, PathKind, Reason,
    SCHEMA_VERSION, Setpoint, StreamFlags, StreamMode, StreamState,
};

use motion_ipc::playout::{Playout, Timed};

use super::Model;
use super::judged::Judged;

/// A setpoint waiting for its tick.
#[derive(Debug, Clone, Copy)]
struct Queued {
    sequence: u64,
    for_tick: u64,
    values: [f64; MAX_GROUP_AXES],
}

impl Timed for Queued {
    fn for_tick(&self) -> u64 {
        self.for_tick
    }
    fn sequence(&self) -> u64 {
        self.sequence
    }
}

/// One group's stream (its counters live in the group's [`GroupState`]).
#[derive(Debug, Clone, Default)]
pub(in crate::testing) struct SimStream {
    mode: StreamMode,
    queue: Vec<Queued>,
    playout: Playout,
    last_received: u64,
    /// Per member: the velocity streamed last (velocity mode).
    velocity: Vec<f64>,
}

impl Model {
    /// Whether group `index` streams.
    pub(super) fn streaming(&self, index: usize) -> bool {
        self.groups.get(index).is_some_and(|group| {
            group.state.kind == PathKind::Stream as u8
                && group.state.stream == StreamState::Streaming as u8
        })
    }

    /// `Stream` (`mode` = `values[0]`) on group `index` from `client`.
    pub(super) fn start_stream(&mut self, index: usize, mode: f64, client: ClientId) -> Judged {
        let mode = [
            StreamMode::Position,
            StreamMode::Velocity,
            StreamMode::Power,
        ]
        .into_iter()
        .find(|m| f64::from(*m as u32) == mode);
        let Some(mode) = mode else {
            return Reason::OutOfRange.into();
        };
        if client.is_none() {
            return Reason::NoClientId.into();
        }
        let members = self.groups[index].config.axes.clone();
        if members
            .iter()
            .any(|&member| self.axes[member].1.state.claimed_by.is_none())
        {
            return Reason::NotClaimed.into();
        }
        if let Some(refused) = self.members_refuse(index, client) {
            return refused;
        }
        if self.groups[index].motion().active() {
            return Judged::at(Reason::GroupBusy, None, members[0], 0.0, 0.0);
        }
        let powerless = |member: &&usize| {
            !self.axes[**member]
                .0
                .capabilities
                .supports(motion_ipc::CommandKind::Power)
        };
        if mode == StreamMode::Power
            && let Some(&member) = members.iter().find(powerless)
        {
            return Judged::at(Reason::Unsupported, None, member, 0.0, 0.0);
        }
        let tick = self.tick;
        let group = &mut self.groups[index];
        group.state = GroupState {
            owner: client,
            feed: 1.0,
            feed_set: group.state.feed_set,
            motion: GroupMotion::Moving as u8,
            kind: PathKind::Stream as u8,
            stream: StreamState::Streaming as u8,
            stream_mode: mode as u8,
            ..GroupState::IDLE
        };
        group.stream = SimStream {
            mode,
            queue: Vec::new(),
            playout: Playout::starting_at(tick),
            last_received: tick,
            velocity: vec![0.0; members.len()],
        };
        for member in members {
            self.axes[member].1.state.mode = AxisMode::Group as u8;
        }
        Reason::Accepted.into()
    }

    /// A setpoint that arrived from node `sender`, before the tick `self.tick` runs.
    pub(in crate::testing) fn handle_setpoint(&mut self, sender: ClientId, setpoint: &Setpoint) {
        let tick = self.tick;
        let streaming = self.streaming(setpoint.group as usize);
        let Some(group) = self.groups.get_mut(setpoint.group as usize) else {
            return;
        };
        let count = group.config.axes.len();
        let valid = setpoint.schema_version == SCHEMA_VERSION
            && setpoint.mode() == Ok(group.stream.mode)
            && setpoint.values[..count].iter().all(|v| v.is_finite());
        if !streaming || sender.is_none() || sender != group.state.owner || !valid {
            group.state.refused += 1;
            return;
        }
        if setpoint.for_tick > tick + u64::from(group.config.stream_buffer) {
            group.state.early += 1;
            return;
        }
        // As the server: only a setpoint that can still apply keeps the stream alive.
        let playout = &group.stream.playout;
        let buffer = u64::from(group.config.stream_buffer);
        if setpoint.sequence > playout.last_sequence
            && setpoint.for_tick > playout.last_for_tick
            && setpoint.for_tick.saturating_add(buffer) >= tick
        {
            group.stream.last_received = tick;
        }
        group.stream.queue.push(Queued {
            sequence: setpoint.sequence,
            for_tick: setpoint.for_tick,
            values: setpoint.values,
        });
    }

    /// `Cancel` of a streaming group: the stream ends idle, the motion done, the axes hold.
    pub(super) fn cancel_stream(&mut self, index: usize) -> Judged {
        let group = &mut self.groups[index];
        group.state.stream = StreamState::Idle as u8;
        group.state.motion = GroupMotion::Done as u8;
        group.state.owner = ClientId::NONE;
        group.stream.queue.clear();
        for member in group.config.axes.clone() {
            let sim = &mut self.axes[member].1;
            sim.state.mode = AxisMode::Hold as u8;
            sim.state.velocity = 0.0;
            sim.state.target = sim.state.position;
        }
        Reason::Accepted.into()
    }

    /// One tick of streaming group `index`: staleness, the setpoint due.
    pub(super) fn stream_tick(&mut self, index: usize, dt: f64) {
        let tick = self.tick;
        let group = &mut self.groups[index];
        group.state.stream_flags = 0;
        if tick.saturating_sub(group.stream.last_received) >= u64::from(group.config.stream_timeout)
        {
            group.stream.queue.clear();
            self.abort_group(index, GroupAbort::StreamStale, None, (0.0, 0.0));
            self.groups[index].state.stream = StreamState::Stale as u8;
            return;
        }
        let mut late = 0;
        let buffer = u64::from(group.config.stream_buffer);
        let stream = &mut group.stream;
        let chosen = stream
            .playout
            .take_due(&mut stream.queue, tick, buffer, &mut late)
            .map(|(setpoint, _)| setpoint);
        group.state.late += late;
        group.state.stream_delay = u16::try_from(stream.playout.delay).unwrap_or(u16::MAX);
        let members = group.config.axes.clone();
        if let Some(setpoint) = chosen {
            group.state.last_sequence = setpoint.sequence;
            group.state.last_applied_tick = tick;
            group.state.applied += 1;
            group.state.stream_flags = StreamFlags::APPLIED.0;
        }
        let mode = group.stream.mode;
        for (slot, member) in members.into_iter().enumerate() {
            let value = chosen.map(|setpoint| setpoint.values[slot]);
            let sim = &mut self.axes[member].1;
            let before = sim.state.position;
            match mode {
                StreamMode::Position => {
                    if let Some(position) = value {
                        sim.state.position = position;
                    }
                }
                StreamMode::Velocity => {
                    let velocity = &mut self.groups[index].stream.velocity[slot];
                    if let Some(value) = value {
                        *velocity = value;
                    }
                    sim.state.position += *velocity * dt;
                }
                StreamMode::Power | StreamMode::None => {}
            }
            sim.state.velocity = if dt > 0.0 {
                (sim.state.position - before) / dt
            } else {
                0.0
            };
            sim.state.desired_position = sim.state.position;
            sim.state.desired_velocity = sim.state.velocity;
            sim.state.target = sim.state.position;
        }
    }
}
