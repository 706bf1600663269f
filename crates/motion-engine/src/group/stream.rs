//! Streamed setpoints: a client that holds a group's claim sends the group's positions,
//! velocities or powers for coming ticks on `motiond/<name>/setpoints`, and the engine
//! applies them tick by tick (cyclic synchronous position / velocity).
//!
//! Each setpoint is applied on its own time (`motion_ipc::playout`, the rule the fake
//! server of `motion-client::testing` follows too): the setpoint for tick `k` is applied in tick
//! `k + delay`, where the stream's `delay` starts at 0 and grows to the lateness of a
//! setpoint that arrives after its tick (at most `stream_buffer`); it never shrinks while
//! the stream runs (a shorter delay would skip a setpoint: a step in the path). So a client
//! whose setpoints arrive a tick late now and then, or several in one tick, moves the group
//! along exactly the path it sent, a few ticks behind, never with a spike; and the limits
//! judge that path by the setpoints' own ticks (`setpoint_limits`), never by when they
//! arrived or were applied.
//!
//! | rule | what happens |
//! |---|---|
//! | a setpoint from a node that does not hold the streaming group, of another mode, not finite, or for a group that does not stream | dropped, `refused` + 1; the stream is not disturbed |
//! | `for_tick` more than `stream_buffer` ticks ahead | dropped, `early` + 1 |
//! | tick `t` | the queued setpoint with the lowest `for_tick` (the newest sequence among equal ones) is applied when `for_tick + delay ≤ t`; if that is late (`t − for_tick > delay`) the delay grows to `t − for_tick`; one more than `stream_buffer` ticks behind is dropped, `late` + 1; one not above the last applied `for_tick` and sequence is dropped, `late` + 1 |
//! | the first setpoint of a position stream within the member's `goal_tolerance` of where the axis stood | the stream starts there, at rest (a measured position a count off is not a step) |
//! | a position outside `min..max`, or a step needing more than `max_velocity` / `max_accel` over the setpoints' own ticks | `stream_limit = "clamp"`: clamped to the limit, `clamped` + 1 and flagged; `"abort"`: the group stops (`stream-limit`) |
//! | no setpoint that can still apply (a sequence and a tick above the last applied, at most `stream_buffer` behind) received for `stream_timeout` ticks | every member stops from its measured speed at its `max_accel` (the deadman rule), stream `stale` |
//!
//! A new stream starts only with a new `Stream` command (at delay 0).

use motion_drivers::Driver;
use motion_ipc::playout::{Playout, Timed};
use motion_ipc::{
    ClientId, GroupAbort, GroupMotion, MAX_GROUP_AXES, PathKind, Reason, SCHEMA_VERSION, Setpoint,
    SetpointFlags, StreamFlags, StreamMode, StreamState,
};

use crate::Engine;
use crate::config::StreamLimit;
use crate::group::setpoint_limits::{self, Breach, Previous};

/// A setpoint waiting for its tick (the values of a group's members).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(crate) struct Queued {
    pub sequence: u64,
    pub for_tick: u64,
    pub feed_forward: bool,
    /// When the shell took it from the service (CLOCK_MONOTONIC ns; 0: not stamped).
    pub received_ns: u64,
    pub values: [f64; MAX_GROUP_AXES],
    pub velocities: [f64; MAX_GROUP_AXES],
}

/// One group's stream.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Stream {
    pub mode: StreamMode,
    pub state: StreamState,
    pub flags: StreamFlags,
    /// Setpoints waiting for their tick, in arrival order. Never longer than `room`
    /// (reserved when the group is built: nothing allocates while streaming).
    pub queue: Vec<Queued>,
    /// The queue's fixed capacity: a playout up to `stream_buffer` ticks behind and
    /// setpoints up to `stream_buffer` ticks ahead (`2 · stream_buffer + 2`).
    pub room: usize,
    /// The tick the last setpoint that could still apply was received for (staleness
    /// counts from it).
    pub last_received: u64,
    pub last_applied_tick: u64,
    /// When the shell received the last setpoint applied (its `received_ns`).
    pub last_received_ns: u64,
    /// When setpoints apply: the delay, the last applied `for_tick` and sequence
    /// (`motion_ipc::playout`, the rule the fake server follows too).
    pub playout: Playout,
    /// Per member, the velocity the last applied setpoint asked for (units/s), and the
    /// span it was judged over (s; 0 before the first): what the next one is judged from.
    pub asked_velocity: [f64; MAX_GROUP_AXES],
    pub asked_span: f64,
    /// Cancelled at rest: the stream takes no more setpoints and the group finishes on the
    /// last one applied, as a path finishes on its end (`done` within `goal_tolerance`).
    pub finishing: bool,
    pub applied: u64,
    pub late: u64,
    pub early: u64,
    pub clamped: u64,
    pub refused: u64,
}

impl Stream {
    /// An idle stream whose queue holds what `stream_buffer` allows.
    pub fn new(stream_buffer: u32) -> Self {
        let room = 2 * stream_buffer as usize + 2;
        Self::idle(Vec::with_capacity(room), room)
    }

    /// An idle stream around `queue` (no allocation).
    fn idle(queue: Vec<Queued>, room: usize) -> Self {
        Self {
            mode: StreamMode::None,
            state: StreamState::Idle,
            flags: StreamFlags(0),
            queue,
            room,
            last_received: 0,
            last_applied_tick: 0,
            last_received_ns: 0,
            playout: Playout::starting_at(0),
            asked_velocity: [0.0; MAX_GROUP_AXES],
            asked_span: 0.0,
            finishing: false,
            applied: 0,
            late: 0,
            early: 0,
            clamped: 0,
            refused: 0,
        }
    }

    /// A new stream of `mode` from tick `tick`: counters, delay and queue start afresh
    /// (the queue keeps its allocation).
    fn begin(&mut self, mode: StreamMode, tick: u64) {
        let mut queue = core::mem::take(&mut self.queue);
        queue.clear();
        *self = Self {
            mode,
            state: StreamState::Streaming,
            last_received: tick,
            playout: Playout::starting_at(tick),
            ..Self::idle(queue, self.room)
        };
    }

    /// Drops every queued setpoint (the stream ended).
    pub fn clear(&mut self) {
        self.queue.clear();
    }

    fn push(&mut self, setpoint: Queued) {
        if self.queue.len() >= self.room {
            self.queue.remove(0);
            self.late += 1;
        }
        self.queue.push(setpoint);
    }
}

impl Timed for Queued {
    fn for_tick(&self) -> u64 {
        self.for_tick
    }
    fn sequence(&self) -> u64 {
        self.sequence
    }
}

impl<D: Driver> Engine<D> {
    /// A setpoint that arrived on `setpoints` from the node `sender` (the transport's
    /// identity): queued for its tick, or dropped and counted. Call before
    /// [`step`](Self::step). Not stamped: [`handle_setpoint_at`](Self::handle_setpoint_at)
    /// with 0.
    pub fn handle_setpoint(&mut self, sender: ClientId, setpoint: &Setpoint) {
        self.handle_setpoint_at(sender, setpoint, 0);
    }

    /// [`handle_setpoint`](Self::handle_setpoint) of a setpoint the shell took from the
    /// service at `received_ns` (its clock, CLOCK_MONOTONIC ns in motiond: the engine reads
    /// no clock). When applied, the frame's `GroupState::last_received_ns` carries it.
    pub fn handle_setpoint_at(&mut self, sender: ClientId, setpoint: &Setpoint, received_ns: u64) {
        let next_tick = if self.started { self.tick + 1 } else { 0 };
        let Some(group) = self.groups.get_mut(setpoint.group as usize) else {
            return;
        };
        let count = group.members.len();
        let stream = &mut group.stream;
        let streaming = group.kind == PathKind::Stream && stream.state == StreamState::Streaming;
        let valid = setpoint.schema_version == SCHEMA_VERSION
            && setpoint.mode() == Ok(stream.mode)
            && setpoint.values[..count].iter().all(|v| v.is_finite())
            && setpoint.velocities[..count].iter().all(|v| v.is_finite());
        if !streaming || sender.is_none() || sender != group.owner || !valid {
            stream.refused += 1;
            return;
        }
        let buffer = u64::from(group.config.stream_buffer);
        if setpoint.for_tick > next_tick.saturating_add(buffer) {
            stream.early += 1;
            return;
        }
        // Staleness counts setpoints that can still apply: one already applied (its
        // sequence again, say, every tick) or too far behind keeps no stream alive.
        let playout = &stream.playout;
        let can_apply = setpoint.sequence > playout.last_sequence
            && setpoint.for_tick > playout.last_for_tick
            && setpoint.for_tick.saturating_add(buffer) >= next_tick;
        if can_apply {
            stream.last_received = next_tick;
        }
        stream.push(Queued {
            sequence: setpoint.sequence,
            for_tick: setpoint.for_tick,
            feed_forward: setpoint.flags().contains(SetpointFlags::FEED_FORWARD),
            received_ns,
            values: setpoint.values,
            velocities: setpoint.velocities,
        });
    }

    /// `Stream`: the client that holds the group's claim starts streaming `mode`.
    pub(crate) fn start_stream(&mut self, group: usize, client: ClientId, mode: f64) -> Reason {
        let mode = [
            StreamMode::Position,
            StreamMode::Velocity,
            StreamMode::Power,
        ]
        .into_iter()
        .find(|m| f64::from(*m as u32) == mode);
        let Some(mode) = mode else {
            return Reason::OutOfRange;
        };
        if client.is_none() {
            return Reason::NoClientId;
        }
        if self.groups[group]
            .members
            .iter()
            .any(|m| self.axes[m.axis].claimed_by.is_none())
        {
            return Reason::NotClaimed;
        }
        if let Some(reason) = self.members_refuse(group, client) {
            return reason;
        }
        if self.groups[group].motion.active() {
            let axis = self.groups[group].members[0].axis;
            return self.refuse_at(Reason::GroupBusy, axis, ClientId::NONE);
        }
        if mode == StreamMode::Power {
            let member = self.groups[group].members.iter().find(|m| {
                !self.axes[m.axis]
                    .capabilities
                    .supports(motion_ipc::CommandKind::Power)
            });
            if let Some(member) = member {
                let axis = member.axis;
                return self.refuse_at(Reason::Unsupported, axis, ClientId::NONE);
            }
        }
        let tick = self.tick;
        for slot in 0..self.groups[group].members.len() {
            let position = self.axes[self.groups[group].members[slot].axis].position();
            let g = &mut self.groups[group];
            g.position[slot] = position;
            g.velocity[slot] = 0.0;
            g.acceleration[slot] = 0.0;
            g.power[slot] = 0.0;
        }
        self.take_members(group, client, PathKind::Stream);
        let g = &mut self.groups[group];
        g.claimed = true;
        g.stream.begin(mode, tick);
        Reason::Accepted
    }

    /// `Cancel` of a stream: it takes no more setpoints. When every member's last asked
    /// velocity lets it stop within its `goal_tolerance` (the client brought the stream to
    /// rest), the group finishes on the last setpoint applied — every board handed it as its
    /// final position, `done` once every axis is there within its `goal_tolerance`, faults
    /// `goal-tolerance` after `goal_time_tolerance` — as a path finishes on its end; a
    /// stream cancelled while its setpoints still move (or a velocity or power stream)
    /// stops every member from its measured speed at its `max_accel` and ends `done`.
    pub(crate) fn cancel_stream(&mut self, group: usize) {
        let g = &mut self.groups[group];
        let at_rest = g.stream.mode == StreamMode::Position
            && g.stream.applied > 0
            && (0..g.members.len()).all(|slot| {
                let v = g.stream.asked_velocity[slot];
                v * v / (2.0 * g.limits[slot].max_accel) <= g.config.goal_tolerance[slot]
            });
        if !at_rest {
            self.end_stream(group, StreamState::Idle, GroupAbort::None, None);
            return;
        }
        g.stream.state = StreamState::Idle;
        g.stream.finishing = true;
        g.stream.clear();
        g.velocity.fill(0.0);
        g.ended_at = None;
    }

    /// One tick of a streaming group: staleness, the setpoint due, its limits.
    pub(crate) fn stream_tick(&mut self, group: usize) {
        let tick = self.tick;
        let period = self.config.period().as_secs_f64();
        let g = &mut self.groups[group];
        g.stream.flags = StreamFlags(0);
        if g.stream.finishing {
            for (slot, member) in g.members.iter().enumerate() {
                let axis = &mut self.axes[member.axis];
                axis.path_position = g.position[slot];
                axis.path_velocity = 0.0;
            }
            return;
        }
        if tick.saturating_sub(g.stream.last_received) >= u64::from(g.config.stream_timeout) {
            self.end_stream(group, StreamState::Stale, GroupAbort::StreamStale, None);
            return;
        }
        let buffer = u64::from(g.config.stream_buffer);
        let stream = &mut g.stream;
        let mode = stream.mode;
        let due = stream
            .playout
            .take_due(&mut stream.queue, tick, buffer, &mut stream.late);
        if let Some((setpoint, span)) = due {
            stream.last_applied_tick = tick;
            stream.last_received_ns = setpoint.received_ns;
            stream.applied += 1;
            stream.flags = StreamFlags(stream.flags.0 | StreamFlags::APPLIED.0);
            let span = span as f64 * period;
            if let Err((slot, breach)) = self.apply_setpoint(group, &setpoint, span) {
                let axis = self.groups[group].members[slot].axis;
                self.end_stream(
                    group,
                    StreamState::Aborted,
                    GroupAbort::StreamLimit,
                    Some((axis, breach.figure, breach.limit)),
                );
                return;
            }
        } else if mode == StreamMode::Velocity {
            // Between setpoints a velocity stream goes on at the last velocity.
            let g = &mut self.groups[group];
            for slot in 0..g.members.len() {
                let limits = g.limits[slot];
                let next = g.position[slot] + g.velocity[slot] * period;
                if next < limits.min || next > limits.max {
                    g.velocity[slot] = 0.0;
                } else {
                    g.position[slot] = next;
                }
            }
        }
        let g = &mut self.groups[group];
        for (slot, member) in g.members.iter().enumerate() {
            let axis = &mut self.axes[member.axis];
            axis.path_position = g.position[slot];
            axis.path_velocity = g.velocity[slot];
        }
    }

    /// Applies `setpoint` (`span`: seconds of the setpoints' own ticks since the last one
    /// applied) within every member's limits: clamped, or `Err` (slot, breach) under
    /// `stream_limit = "abort"`. Every member is judged before any moves.
    fn apply_setpoint(
        &mut self,
        group: usize,
        setpoint: &Queued,
        span: f64,
    ) -> Result<(), (usize, Breach)> {
        let period = self.config.period().as_secs_f64();
        let g = &mut self.groups[group];
        let clamp = g.config.stream_limit == StreamLimit::Clamp;
        let first = g.stream.asked_span == 0.0;
        let mut steps = [setpoint_limits::Step {
            position: 0.0,
            velocity: 0.0,
            clamped: false,
        }; MAX_GROUP_AXES];
        for (slot, out) in steps.iter_mut().enumerate().take(g.members.len()) {
            let limits = &g.limits[slot];
            let value = setpoint.values[slot];
            let previous = Previous {
                position: g.position[slot],
                velocity: g.stream.asked_velocity[slot],
                span: g.stream.asked_span,
            };
            let step = match g.stream.mode {
                StreamMode::Position
                    if first
                        && (value - previous.position).abs() <= g.config.goal_tolerance[slot]
                        && (limits.min..=limits.max).contains(&value) =>
                {
                    // The stream starts where the client says the axis stands.
                    Ok(setpoint_limits::Step {
                        position: value,
                        velocity: 0.0,
                        clamped: false,
                    })
                }
                StreamMode::Position => {
                    setpoint_limits::judge_position(&previous, value, span, limits, clamp)
                }
                StreamMode::Velocity => {
                    setpoint_limits::judge_velocity(&previous, value, span, period, limits, clamp)
                }
                StreamMode::Power | StreamMode::None => setpoint_limits::judge_power(value, clamp)
                    .map(|power| setpoint_limits::Step {
                        position: previous.position,
                        velocity: power,
                        clamped: power != value,
                    }),
            }
            .map_err(|breach| (slot, breach))?;
            *out = step;
        }
        let mut clamped = false;
        for (slot, step) in steps.iter().enumerate().take(g.members.len()) {
            clamped |= step.clamped;
            match g.stream.mode {
                StreamMode::Power | StreamMode::None => g.power[slot] = step.velocity,
                mode => {
                    g.position[slot] = step.position;
                    g.stream.asked_velocity[slot] = step.velocity;
                    g.velocity[slot] = if mode == StreamMode::Position && setpoint.feed_forward {
                        let limit = g.limits[slot].max_velocity;
                        setpoint.velocities[slot].clamp(-limit, limit)
                    } else {
                        step.velocity
                    };
                }
            }
        }
        g.stream.asked_span = span;
        if clamped {
            g.stream.clamped += 1;
            g.stream.flags = StreamFlags(g.stream.flags.0 | StreamFlags::CLAMPED.0);
        }
        Ok(())
    }

    /// Ends the group's stream: every member stops from its measured speed at its
    /// `max_accel` and holds.
    pub(crate) fn end_stream(
        &mut self,
        group: usize,
        state: StreamState,
        reason: GroupAbort,
        at: Option<(usize, f64, f64)>,
    ) {
        let (axis, value, limit) = at.map_or((None, 0.0, 0.0), |(a, v, l)| (Some(a), v, l));
        self.groups[group].stream.state = state;
        self.groups[group].stream.clear();
        if reason == GroupAbort::None {
            let g = &mut self.groups[group];
            g.motion = GroupMotion::Done;
            g.abort = GroupAbort::None;
            for slot in 0..self.groups[group].members.len() {
                let index = self.groups[group].members[slot].axis;
                if self.axes[index].group == Some(group) {
                    self.axes[index].group = None;
                    self.stop_axis(index, false);
                }
            }
        } else {
            self.abort_group(group, reason, axis, value, limit);
        }
    }
}
