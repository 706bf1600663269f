//! [`SetpointStream`]: a controller closes its loop through the server every tick. The
//! client holds the group's claim, starts a stream (`Stream` command) and publishes a
//! [`Setpoint`] per tick on `motiond/<name>/setpoints` from its own iceoryx2 node (the
//! server knows the sender from the transport, never from the payload). The server applies
//! each setpoint on its own time, once and in order: the one for tick `k` in tick
//! `k + delay`, where the stream's delay grows to the lateness of a setpoint that arrived
//! after its tick and never shrinks while it runs (`motion_ipc::playout`). A client sends
//! for `frame.tick + lead` after reading a frame: a lead larger than its scheduling jitter
//! keeps the delay at 0 ([`DEFAULT_STREAM_LEAD`]).

use core::fmt;
use core::ops::ControlFlow;
use core::time::Duration;
use std::rc::Rc;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{
    CommandKind, MAX_GROUP_AXES, MotionFrame, SCHEMA_VERSION, Setpoint, SetpointFlags, StreamMode,
    StreamState, Target,
};

use crate::ports::{self, Opening, SetpointPorts};
use crate::{
    Accepted, ClaimGuard, Client, ClientError, ConnectError, Frame, Group, StreamError, StreamRun,
    StreamStatus, Unanswered,
};

/// How long [`SetpointStream::run_each_tick`] waits for a frame before it gives up with
/// [`ClientError::NoFrame`] (the server stops the group long before: `stream_timeout`).
pub const STREAM_FRAME_TIMEOUT: Duration = Duration::from_secs(1);

/// The lead [`SetpointStream::run_each_tick`] sends with unless told otherwise: the
/// setpoint computed after reading frame `k` is for tick `k + 2`. A setpoint that arrives
/// late grows the stream's delay for the rest of the stream, so the lead is the latency a
/// client chooses up front rather than one the stream picks up on its worst tick.
/// `motionctl bench`'s stream phase measures the share of ticks a Python client meets with
/// lead 1 and with this lead, beside `--busy-loops N` spinning processes
/// (docs/PERFORMANCE.md "Coordinated motion and streams").
pub const DEFAULT_STREAM_LEAD: u64 = 2;

impl<S: Service> Client<S> {
    /// Takes this client's publisher slot on `setpoints` together with its command port
    /// (one try, never waiting): a claimant's stream then cannot be starved by another
    /// process that takes every publisher slot after the client first commanded
    /// (docs/SECURITY.md "Paths and setpoints no other process can starve"). A slot that
    /// cannot be had now is tried again by the first stream, whose error then says why.
    pub(crate) fn reserve_setpoint_port(&self) {
        if self.is_remote() || self.setpoints.borrow().is_some() {
            return;
        }
        let opening = Opening::once(&self.server);
        if let Ok(ports) = ports::open_setpoints(&self.node, &opening, &self.names.setpoints()) {
            *self.setpoints.borrow_mut() = Some(Rc::new(ports));
        }
    }

    /// The publisher on `setpoints`, taken with the command port or else on first use (one
    /// per client).
    fn setpoint_ports(&self) -> Result<Rc<SetpointPorts<S>>, ClientError> {
        if let Some(ports) = self.setpoints.borrow().as_ref() {
            return Ok(Rc::clone(ports));
        }
        let service = self.names.setpoints();
        let opening = Opening::new(&self.server, self.connect_timeout);
        let ports =
            ports::open_setpoints(&self.node, &opening, &service).map_err(|error| match error {
                ConnectError::NoServer { .. } => ClientError::NotPublished {
                    what: "setpoint service",
                    service: service.clone(),
                    why: Unanswered::NoService { schema: 7 },
                },
                other => other.into(),
            })?;
        let ports = Rc::new(ports);
        *self.setpoints.borrow_mut() = Some(Rc::clone(&ports));
        Ok(ports)
    }

    /// Publishes `setpoint`, reopening the service once if the server recreated it; how
    /// many subscribers (the server) got it.
    fn publish_setpoint(&self, setpoint: &Setpoint) -> Result<usize, ClientError> {
        let send = |ports: &SetpointPorts<S>| {
            ports
                .publisher
                .send_copy(*setpoint)
                .map_err(|error| ClientError::ipc("send a setpoint", error))
        };
        let ports = self.setpoint_ports()?;
        let delivered = send(&ports)?;
        if delivered > 0 {
            return Ok(delivered);
        }
        let now = ports::pubsub_id_now::<S, Setpoint>(&self.node, &self.names.setpoints());
        if now.is_none_or(|id| id == ports.service_id) {
            return Ok(0);
        }
        *self.setpoints.borrow_mut() = None;
        drop(ports);
        send(&*self.setpoint_ports()?)
    }
}

impl<'c, S: Service> Group<'c, S> {
    /// Claims the members this client does not hold yet (per the newest frame): the whole
    /// group at once when it holds none of them, else each missing axis (a claim it held
    /// before is never released by the stream).
    fn claim_for_stream(&self) -> Result<Vec<ClaimGuard<'c, S>>, ClientError> {
        let client = self.client();
        let members = self.info();
        let mine: Vec<bool> = {
            let frame = client.latest()?;
            members
                .axes()
                .iter()
                .map(|&axis| {
                    frame
                        .axes()
                        .get(axis as usize)
                        .is_some_and(|state| state.claimed_by == client.id())
                })
                .collect()
        };
        if mine.iter().all(|held| !held) {
            return Ok(vec![self.claim()?]);
        }
        members
            .axes()
            .iter()
            .zip(mine)
            .filter(|(_, held)| !held)
            .map(|(&axis, _)| ClaimGuard::take(client, Target::Axis, axis))
            .collect()
    }

    /// Starts streaming setpoints to the group in `mode`: claims every member axis (held by
    /// the stream, released when it ends), sends the `Stream` command and makes sure this
    /// client has its publisher on `setpoints`. The group must be at rest (no motion of its
    /// own running: `GroupBusy`); [`StreamMode::Power`] needs boards that take power goals.
    ///
    /// Dropping the returned stream (or [`SetpointStream::cancel`]) ends it: the axes stop
    /// and hold, and the claim the stream took is released (a claim this client already
    /// held on every member before stays).
    ///
    /// ```no_run
    /// use core::ops::ControlFlow;
    /// use iceoryx2::prelude::ipc;
    /// use motion_client::Client;
    /// use motion_client::ipc::StreamMode;
    ///
    /// let client = Client::<ipc::Service>::connect("demo")?;
    /// let mut stream = client.group("base")?.stream(StreamMode::Velocity)?;
    /// // Every tick: read the frame, write the velocities for the next tick.
    /// let run = stream.run_each_tick(Some(core::time::Duration::from_secs(2)), |frame, out| {
    ///     let t = frame.tick as f64 / 1000.0;
    ///     out.fill(20.0 * (t * core::f64::consts::TAU / 1.5).sin());
    ///     ControlFlow::Continue(())
    /// })?;
    /// println!("sent {} setpoints for ticks {:?}..={:?}", run.sent, run.first_tick, run.last_tick);
    /// stream.cancel()?; // the wheels stop and hold
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn stream(&self, mode: StreamMode) -> Result<SetpointStream<'c, S>, ClientError> {
        let client = self.client();
        if client.is_remote() {
            return Err(ClientError::LocalOnly { what: "groups" });
        }
        client.check_server()?;
        // The publisher first: it is connected to the server's subscriber by the time the
        // first setpoint goes out.
        client.setpoint_ports()?;
        let claims = self.claim_for_stream()?;
        let started = client.command_to(
            Target::Group,
            self.index(),
            CommandKind::Stream,
            [f64::from(mode as u32), 0.0, 0.0],
        )?;
        Ok(SetpointStream {
            group: *self,
            claims,
            mode,
            axes: self.info().axes().len(),
            started,
            epoch: client.session.epoch(),
            sequence: 0,
            last_for_tick: None,
            lead: DEFAULT_STREAM_LEAD,
            values: [0.0; MAX_GROUP_AXES],
            active: true,
        })
    }
}

/// A group's setpoint stream, started by [`Group::stream`]. Holds the group's claim; when
/// dropped it sends `Cancel` (the stream ends idle, every member stops and holds) and
/// releases the claim it took.
///
/// Values are per member axis in the group's order ([`Group::axes`]): positions (each
/// axis's unit), velocities (unit/s) or powers (−1.0..=1.0), as the stream's mode says.
/// Sequence numbers count up from 1 per stream.
#[must_use = "dropping the stream ends it at once"]
pub struct SetpointStream<'c, S: Service> {
    group: Group<'c, S>,
    /// The claims the stream took (none on members this client held before).
    claims: Vec<ClaimGuard<'c, S>>,
    mode: StreamMode,
    axes: usize,
    started: Accepted,
    epoch: u64,
    sequence: u64,
    last_for_tick: Option<u64>,
    /// Ticks ahead of the frame read that `run_each_tick` sends for.
    lead: u64,
    /// What `run_each_tick` hands its closure: the values sent last.
    values: [f64; MAX_GROUP_AXES],
    active: bool,
}

impl<S: Service> fmt::Debug for SetpointStream<'_, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SetpointStream")
            .field("group", &self.group.index())
            .field("mode", &self.mode)
            .field("sequence", &self.sequence)
            .field("last_for_tick", &self.last_for_tick)
            .finish_non_exhaustive()
    }
}

impl<'c, S: Service> SetpointStream<'c, S> {
    /// The group streamed to.
    pub fn group(&self) -> Group<'c, S> {
        self.group
    }

    /// The stream's mode.
    pub fn mode(&self) -> StreamMode {
        self.mode
    }

    /// The tick in which the server started the stream (accepted its `Stream` command).
    pub fn started_tick(&self) -> u64 {
        self.started.tick
    }

    /// The sequence number of the last setpoint sent (0 before the first).
    pub fn last_sequence(&self) -> u64 {
        self.sequence
    }

    /// The tick the last setpoint sent was for.
    pub fn last_for_tick(&self) -> Option<u64> {
        self.last_for_tick
    }

    /// How many ticks ahead of the frame it read [`run_each_tick`](Self::run_each_tick)
    /// sends for ([`DEFAULT_STREAM_LEAD`] unless set).
    pub fn lead(&self) -> u64 {
        self.lead
    }

    /// Sets the lead: after reading frame `k`, [`run_each_tick`](Self::run_each_tick)
    /// sends the setpoint for tick `k + lead`. 1 is the least latency and suits a client
    /// that always answers within the tick (SCHED_FIFO); a larger lead absorbs that much
    /// scheduling jitter before a setpoint arrives late (which grows the stream's delay for
    /// the rest of the stream). At most the group's `stream_buffer` + 1 (further ahead the
    /// server drops setpoints as early).
    pub fn set_lead(&mut self, lead: u64) -> Result<(), StreamError> {
        let buffer = u64::from(self.group.info().stream_buffer);
        if lead == 0 || lead > buffer + 1 {
            return Err(StreamError::Lead {
                group: self.group.name(),
                lead,
                most: buffer + 1,
            });
        }
        self.lead = lead;
        Ok(())
    }

    /// Sends the setpoint `values` for tick `for_tick` (a frame's `tick` + 1 is the next
    /// tick; up to the group's `stream_buffer` ticks further ahead may wait in the server)
    /// and returns its sequence number. Checked first: one value per member axis, every
    /// one finite.
    pub fn send(&mut self, for_tick: u64, values: &[f64]) -> Result<u64, StreamError> {
        self.publish(for_tick, values, None)
    }

    /// [`SetpointStream::send`] with a velocity feed-forward per axis (unit/s; position
    /// streams only): boards that follow by segments or velocities are given it instead of
    /// the difference of the last two setpoints.
    pub fn send_with_feed_forward(
        &mut self,
        for_tick: u64,
        values: &[f64],
        velocities: &[f64],
    ) -> Result<u64, StreamError> {
        if self.mode != StreamMode::Position {
            return Err(StreamError::FeedForwardNeedsPosition {
                group: self.group.name(),
                mode: self.mode.name(),
            });
        }
        self.publish(for_tick, values, Some(velocities))
    }

    /// Checks `values` ("values" or "velocities").
    fn check(&self, what: &'static str, values: &[f64]) -> Result<(), StreamError> {
        if values.len() != self.axes {
            return Err(StreamError::ValueCount {
                group: self.group.name(),
                axes: self.group.axes().join(", "),
                what,
                expected: self.axes,
                got: values.len(),
            });
        }
        if let Some((slot, value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(StreamError::NotFinite {
                group: self.group.name(),
                axis: self.group.axes().get(slot).cloned().unwrap_or_default(),
                what: if what == "values" {
                    "value"
                } else {
                    "velocity"
                },
                value: *value,
            });
        }
        Ok(())
    }

    fn publish(
        &mut self,
        for_tick: u64,
        values: &[f64],
        velocities: Option<&[f64]>,
    ) -> Result<u64, StreamError> {
        self.check("values", values)?;
        if let Some(velocities) = velocities {
            self.check("velocities", velocities)?;
        }
        let client = self.group.client();
        if client.session.epoch() != self.epoch
            && let Some(restart) = client.session.last_restart()
        {
            // The stream died with the old server.
            return Err(ClientError::ServerRestarted(restart).into());
        }
        let sequence = self.sequence + 1;
        let mut setpoint = Setpoint {
            schema_version: SCHEMA_VERSION,
            group: self.group.index(),
            sequence,
            for_tick,
            mode: self.mode as u32,
            flags: 0,
            ..Setpoint::EMPTY
        };
        setpoint.values[..self.axes].copy_from_slice(values);
        if let Some(velocities) = velocities {
            setpoint.velocities[..self.axes].copy_from_slice(velocities);
            setpoint.flags = SetpointFlags::FEED_FORWARD.0;
        }
        if client.publish_setpoint(&setpoint)? == 0 {
            return Err(StreamError::NotSent {
                group: self.group.name(),
                why: format!(
                    "no server subscribes to {} (is motiond stopping?)",
                    client.names.setpoints()
                ),
            });
        }
        self.sequence = sequence;
        self.last_for_tick = Some(for_tick);
        self.values[..self.axes].copy_from_slice(values);
        Ok(sequence)
    }

    /// The group's stream in the newest frame: its state and counters.
    pub fn state(&self) -> Result<StreamStatus, ClientError> {
        let frame = self.group.client().latest()?;
        Ok(self.status_in(&frame))
    }

    fn status_in(&self, frame: &MotionFrame) -> StreamStatus {
        let raw = frame
            .groups()
            .get(self.group.index() as usize)
            .copied()
            .unwrap_or_default();
        StreamStatus::from_state(frame.tick, &raw)
    }

    /// Waits until a frame shows the last setpoint sent applied (every earlier one was
    /// applied or dropped by then, so the counters are final for what was sent) — or every
    /// setpoint sent accounted for by the server's counters (`applied + late + early`: the
    /// last ones were dropped, reaching it too late or too early to apply), as Python's
    /// `wait_applied` — or the stream no longer streaming, and returns the stream's state
    /// in it; when `timeout` passes first, the state in the newest frame.
    pub fn wait_caught_up(&self, timeout: Duration) -> Result<StreamStatus, ClientError> {
        let client = self.group.client();
        let deadline = Instant::now() + timeout;
        loop {
            let frame = client.latest()?;
            let status = self.status_in(&frame);
            // A frame of the stream (not one from before it started) in which the last
            // setpoint sent was applied (never before its tick), or the stream ended.
            let current = frame.tick >= self.started.tick;
            let taken = status.last_sequence >= self.sequence
                || status.applied + status.late + status.early >= self.sequence;
            if current && (taken || status.state != StreamState::Streaming) {
                return Ok(status);
            }
            drop(frame);
            let now = Instant::now();
            if now >= deadline {
                return Ok(status);
            }
            client.wait_tick(deadline - now)?;
        }
    }

    /// The newest frame after tick `after`, waiting on the tick event; `None` once
    /// `deadline` passed.
    fn frame_after(
        &self,
        after: u64,
        deadline: Option<Instant>,
    ) -> Result<Option<Frame<S>>, StreamError> {
        let client = self.group.client();
        let silent = Instant::now() + STREAM_FRAME_TIMEOUT;
        loop {
            let frame = client.latest()?;
            if frame.tick > after {
                return Ok(Some(frame));
            }
            drop(frame);
            let now = Instant::now();
            if deadline.is_some_and(|deadline| now >= deadline) {
                return Ok(None);
            }
            if now >= silent {
                return Err(ClientError::NoFrame(STREAM_FRAME_TIMEOUT).into());
            }
            let until = deadline.map_or(silent, |deadline| deadline.min(silent));
            client.wait_tick(until - now)?;
        }
    }

    /// Closes a loop through the server every tick: waits for each frame on the tick
    /// event, calls `f` with the newest frame and the values to send (one per member axis,
    /// the group's order; holding what was sent last, at first the axes' positions for a
    /// position stream and zeros otherwise), and sends them for the frame's tick +
    /// [`lead`](Self::lead) — the values `f` computes are for that tick. Stops when `f`
    /// breaks or after `duration` (`None`: until `f` breaks).
    ///
    /// A frame the client was too slow for gets no setpoint (the next frame's does;
    /// [`StreamRun::skipped`]). The stream allocates nothing per tick (receiving a frame
    /// costs the client one small handle on the shared-memory sample). Ends with
    /// [`StreamError::Ended`] when a frame shows the stream is no longer streaming (stale,
    /// aborted), [`ClientError::Interrupted`] after SIGINT or SIGTERM (the stream ends when
    /// dropped), [`ClientError::NoFrame`] when the server stays silent for
    /// [`STREAM_FRAME_TIMEOUT`].
    pub fn run_each_tick(
        &mut self,
        duration: Option<Duration>,
        mut f: impl FnMut(&MotionFrame, &mut [f64]) -> ControlFlow<()>,
    ) -> Result<StreamRun, StreamError> {
        let deadline = duration.map(|duration| Instant::now() + duration);
        let mut run = StreamRun::default();
        // Frames before the stream started do not show it yet.
        let mut seen = self.started.tick.saturating_sub(1);
        if let Some(last) = self.last_for_tick {
            seen = seen.max(last.saturating_sub(1));
        }
        let mut values = self.values;
        loop {
            // Also when a newer frame is always waiting (a client slower than the tick).
            if deadline.is_some_and(|deadline| Instant::now() >= deadline) {
                break;
            }
            let Some(frame) = self.frame_after(seen, deadline)? else {
                break;
            };
            seen = frame.tick;
            let status = self.status_in(&frame);
            if status.state != StreamState::Streaming
                || status.owner != Some(self.group.client().id())
            {
                return Err(StreamError::Ended {
                    group: self.group.name(),
                    tick: frame.tick,
                    stream: status.state,
                    motion: status.motion,
                    abort: status.abort,
                });
            }
            // The setpoint sent last was due by this frame's tick (its own tick plus the
            // stream's delay) but is not applied.
            if self
                .last_for_tick
                .is_some_and(|last| last + status.delay <= frame.tick)
                && status.last_sequence < self.sequence
            {
                run.behind += 1;
            }
            if self.sequence == 0 && self.mode == StreamMode::Position {
                let members = self.group.info();
                for (slot, &axis) in members.axes().iter().enumerate() {
                    if let Some(state) = frame.axes().get(axis as usize) {
                        values[slot] = state.position;
                    }
                }
            }
            if f(&frame, &mut values[..self.axes]).is_break() {
                break;
            }
            drop(frame);
            let for_tick = seen + self.lead;
            let sequence = self.publish(for_tick, &values[..self.axes], None)?;
            run.note(for_tick, sequence);
        }
        Ok(run)
    }

    /// Ends the stream: sends `Cancel` (the stream ends idle, every member stops and holds)
    /// and releases the claims the stream took. A stream the server had already ended (stale, aborted) is
    /// refused with `NotMoving`; the claim is released all the same.
    pub fn cancel(mut self) -> Result<Accepted, ClientError> {
        self.active = false;
        let cancelled = self.send_cancel();
        let mut released = Ok(());
        for claim in self.claims.drain(..) {
            if let Err(error) = claim.release() {
                released = released.and(Err(error));
            }
        }
        let accepted = cancelled?;
        released?;
        Ok(accepted)
    }

    fn send_cancel(&self) -> Result<Accepted, ClientError> {
        let client = self.group.client();
        if client.session.epoch() != self.epoch
            && let Some(restart) = client.session.last_restart()
        {
            return Err(ClientError::ServerRestarted(restart));
        }
        client.command_to(
            Target::Group,
            self.group.index(),
            CommandKind::Cancel,
            [0.0; 3],
        )
    }
}

impl<S: Service> Drop for SetpointStream<'_, S> {
    fn drop(&mut self) {
        if self.active {
            // A stream of a client that is gone is ended by the server anyway (stale).
            let _ = self.send_cancel();
        }
        // The claim guards, dropped after this, release the claims the stream took.
    }
}
