//! Streamed setpoints: a client that holds a group's claim sends the group's positions,
//! velocities or powers for coming ticks on `motiond/<name>/setpoints`, and the engine
//! applies them tick by tick (cyclic synchronous position / velocity).
//!
//! | rule | what happens |
//! |---|---|
//! | a setpoint from a node that does not hold the streaming group, of another mode, not finite, or for a group that does not stream | dropped, `refused` + 1; the stream is not disturbed |
//! | `for_tick` more than `stream_buffer` ticks ahead | dropped, `early` + 1 |
//! | tick `k` | the newest setpoint with `for_tick ≤ k` and a sequence above the last applied one is applied; the other due ones are dropped, `late` + 1 each |
//! | a position outside `min..max`, or a step needing more than `max_velocity` / `max_accel` | `stream_limit = "clamp"`: clamped to the limit, `clamped` + 1 and flagged; `"abort"`: the group stops (`stream-limit`) |
//! | no setpoint received for `stream_timeout` ticks | every member stops from its measured speed at its `max_accel` (the deadman rule), stream `stale` |
//!
//! A new stream starts only with a new `Stream` command.

use motion_drivers::Driver;
use motion_ipc::{
    ClientId, GroupAbort, GroupMotion, MAX_GROUP_AXES, PathKind, Reason, SCHEMA_VERSION, Setpoint,
    SetpointFlags, StreamFlags, StreamMode, StreamState,
};

use crate::Engine;
use crate::config::StreamLimit;

/// Setpoints waiting for their tick, per group (the oldest is dropped as late when full).
pub(crate) const STREAM_QUEUE: usize = 32;

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

impl Queued {
    const EMPTY: Self = Self {
        sequence: 0,
        for_tick: 0,
        feed_forward: false,
        received_ns: 0,
        values: [0.0; MAX_GROUP_AXES],
        velocities: [0.0; MAX_GROUP_AXES],
    };
}

/// One group's stream.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Stream {
    pub mode: StreamMode,
    pub state: StreamState,
    pub flags: StreamFlags,
    pub queue: [Queued; STREAM_QUEUE],
    pub queued: usize,
    /// The tick the last setpoint was received for (staleness counts from it).
    pub last_received: u64,
    pub last_sequence: u64,
    pub last_applied_tick: u64,
    /// When the shell received the last setpoint applied (its `received_ns`).
    pub last_received_ns: u64,
    /// The tick the last setpoint was applied in, or the stream started in.
    pub since_tick: u64,
    pub applied: u64,
    pub late: u64,
    pub early: u64,
    pub clamped: u64,
    pub refused: u64,
}

impl Stream {
    pub const IDLE: Self = Self {
        mode: StreamMode::None,
        state: StreamState::Idle,
        flags: StreamFlags(0),
        queue: [Queued::EMPTY; STREAM_QUEUE],
        queued: 0,
        last_received: 0,
        last_sequence: 0,
        last_applied_tick: 0,
        last_received_ns: 0,
        since_tick: 0,
        applied: 0,
        late: 0,
        early: 0,
        clamped: 0,
        refused: 0,
    };

    fn push(&mut self, setpoint: Queued) {
        if self.queued == STREAM_QUEUE {
            self.queue.copy_within(1.., 0);
            self.queued -= 1;
            self.late += 1;
        }
        self.queue[self.queued] = setpoint;
        self.queued += 1;
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
        if setpoint.for_tick > next_tick + buffer {
            stream.early += 1;
            return;
        }
        stream.last_received = next_tick;
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
        g.stream = Stream {
            mode,
            state: StreamState::Streaming,
            last_received: tick,
            since_tick: tick,
            ..Stream::IDLE
        };
        Reason::Accepted
    }

    /// One tick of a streaming group: staleness, the setpoint due, its limits.
    pub(crate) fn stream_tick(&mut self, group: usize) {
        let tick = self.tick;
        let dt = self.config.period().as_secs_f64();
        let g = &mut self.groups[group];
        g.stream.flags = StreamFlags(0);
        if tick.saturating_sub(g.stream.last_received) >= u64::from(g.config.stream_timeout) {
            self.end_stream(group, StreamState::Stale, GroupAbort::StreamStale, None);
            return;
        }
        // The newest due setpoint above the last applied sequence; the rest of the due
        // ones are late.
        let stream = &mut g.stream;
        let mut chosen: Option<Queued> = None;
        let mut kept = 0;
        for index in 0..stream.queued {
            let entry = stream.queue[index];
            if entry.for_tick > tick {
                stream.queue[kept] = entry;
                kept += 1;
                continue;
            }
            let newer =
                chosen.is_none_or(|c| (entry.for_tick, entry.sequence) > (c.for_tick, c.sequence));
            if entry.sequence > stream.last_sequence && newer {
                if chosen.is_some() {
                    stream.late += 1;
                }
                chosen = Some(entry);
            } else {
                stream.late += 1;
            }
        }
        stream.queued = kept;
        let mode = stream.mode;
        if let Some(setpoint) = chosen {
            let since = tick.saturating_sub(stream.since_tick).max(1) as f64 * dt;
            stream.last_sequence = setpoint.sequence;
            stream.last_applied_tick = tick;
            stream.last_received_ns = setpoint.received_ns;
            stream.since_tick = tick;
            stream.applied += 1;
            stream.flags = StreamFlags(stream.flags.0 | StreamFlags::APPLIED.0);
            if let Err((slot, value, limit)) = self.apply_setpoint(group, &setpoint, since) {
                let axis = self.groups[group].members[slot].axis;
                self.end_stream(
                    group,
                    StreamState::Aborted,
                    GroupAbort::StreamLimit,
                    Some((axis, value, limit)),
                );
                return;
            }
        } else if mode == StreamMode::Velocity {
            // Between setpoints a velocity stream goes on at the last velocity.
            let g = &mut self.groups[group];
            for slot in 0..g.members.len() {
                let limits = g.limits[slot];
                let next = g.position[slot] + g.velocity[slot] * dt;
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

    /// Applies `setpoint` (`since`: seconds since the last one applied) within every
    /// member's limits: clamped, or `Err` (slot, figure, limit) under `stream_limit =
    /// "abort"`.
    fn apply_setpoint(
        &mut self,
        group: usize,
        setpoint: &Queued,
        since: f64,
    ) -> Result<(), (usize, f64, f64)> {
        let dt = self.config.period().as_secs_f64();
        let g = &mut self.groups[group];
        let clamp = g.config.stream_limit == StreamLimit::Clamp;
        let mut clamped = false;
        for slot in 0..g.members.len() {
            let limits = g.limits[slot];
            let (p_prev, v_prev) = (g.position[slot], g.velocity[slot]);
            let value = setpoint.values[slot];
            match g.stream.mode {
                StreamMode::Position => {
                    let target = value.clamp(limits.min, limits.max);
                    if target != value {
                        if !clamp {
                            let limit = if value < limits.min {
                                limits.min
                            } else {
                                limits.max
                            };
                            return Err((slot, value, limit));
                        }
                        clamped = true;
                    }
                    let wanted = (target - p_prev) / since;
                    let reach = limits.max_accel * since;
                    let velocity = wanted
                        .clamp(-limits.max_velocity, limits.max_velocity)
                        .clamp(v_prev - reach, v_prev + reach);
                    if velocity != wanted {
                        if !clamp {
                            let (figure, limit) = if wanted.abs() > limits.max_velocity {
                                (wanted, limits.max_velocity)
                            } else {
                                ((wanted - v_prev) / since, limits.max_accel)
                            };
                            return Err((slot, figure, limit));
                        }
                        clamped = true;
                    }
                    g.position[slot] = p_prev + velocity * since;
                    g.velocity[slot] = if setpoint.feed_forward {
                        setpoint.velocities[slot].clamp(-limits.max_velocity, limits.max_velocity)
                    } else {
                        velocity
                    };
                }
                StreamMode::Velocity => {
                    let reach = limits.max_accel * since;
                    let velocity = value
                        .clamp(-limits.max_velocity, limits.max_velocity)
                        .clamp(v_prev - reach, v_prev + reach);
                    if velocity != value {
                        if !clamp {
                            let (figure, limit) = if value.abs() > limits.max_velocity {
                                (value, limits.max_velocity)
                            } else {
                                ((value - v_prev) / since, limits.max_accel)
                            };
                            return Err((slot, figure, limit));
                        }
                        clamped = true;
                    }
                    let next = p_prev + velocity * dt;
                    // A velocity that would carry the axis past a soft limit before it
                    // could stop there.
                    let stop = velocity * velocity / (2.0 * limits.max_accel);
                    let beyond = (velocity > 0.0 && next + stop > limits.max)
                        || (velocity < 0.0 && next - stop < limits.min);
                    if beyond {
                        if !clamp {
                            return Err((
                                slot,
                                next,
                                if velocity > 0.0 {
                                    limits.max
                                } else {
                                    limits.min
                                },
                            ));
                        }
                        clamped = true;
                        g.velocity[slot] = 0.0;
                    } else {
                        g.velocity[slot] = velocity;
                        g.position[slot] = next;
                    }
                }
                StreamMode::Power | StreamMode::None => {
                    let power = value.clamp(-1.0, 1.0);
                    if power != value {
                        if !clamp {
                            return Err((slot, value, 1.0));
                        }
                        clamped = true;
                    }
                    g.power[slot] = power;
                }
            }
        }
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
        self.groups[group].stream.queued = 0;
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
