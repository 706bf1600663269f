//! What a setpoint stream reports: its counters in a frame ([`StreamStatus`]), what one
//! [`run_each_tick`](crate::SetpointStream::run_each_tick) did ([`StreamRun`]), and why a
//! setpoint was not sent or a stream ended ([`StreamError`]).

use motion_ipc::{
    ClientId, GroupAbort, GroupMotion, GroupState, StreamFlags, StreamMode, StreamState,
};

use crate::ClientError;

/// Why a setpoint was not sent, or why a stream cannot go on: checked by the client before
/// anything is published (counts, finite values), seen in the frames (the stream ended),
/// or any error of the client underneath ([`StreamError::Client`]).
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// A setpoint gives values for another number of axes than the group has.
    #[error("group {group} has {expected} axes ({axes}), but {got} {what} were given")]
    ValueCount {
        /// The group's name.
        group: String,
        /// Its axes, comma separated, in its order.
        axes: String,
        /// "values" or "velocities".
        what: &'static str,
        /// The group's axis count.
        expected: usize,
        /// How many were given.
        got: usize,
    },
    /// A value is NaN or infinite (the server would drop the setpoint as refused).
    #[error("group {group}, axis `{axis}`: {what} {value} is not a finite number")]
    NotFinite {
        /// The group's name.
        group: String,
        /// The axis, by name.
        axis: String,
        /// "value" or "velocity".
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// Velocity feed-forward is for position streams only (the server ignores it otherwise).
    #[error("group {group}: feed-forward velocities are for position streams, not {mode}")]
    FeedForwardNeedsPosition {
        /// The group's name.
        group: String,
        /// The stream's mode.
        mode: &'static str,
    },
    /// A lead the group cannot take: 0, or more than its `stream_buffer` + 1 ticks.
    #[error("group {group}: a lead of {lead} ticks is outside 1..={most} (its stream_buffer + 1)")]
    Lead {
        /// The group's name.
        group: String,
        /// The lead asked for.
        lead: u64,
        /// The largest it takes.
        most: u64,
    },
    /// The setpoint reached no server: nobody subscribes to the `setpoints` service.
    #[error("the setpoint for group {group} was not sent: {why}")]
    NotSent {
        /// The group's name.
        group: String,
        /// Why, in words.
        why: String,
    },
    /// The server ended the stream: it went stale (no setpoint for `stream_timeout` ticks),
    /// was aborted (a limit under `stream_limit = "abort"`, a stop, the e-stop, a fault, a
    /// lost claim), or another client's motion took the group.
    #[error(
        "the stream of group {group} ended in tick {tick}: stream {}, motion {} ({})",
        .stream.name(), .motion.name(), .abort.name()
    )]
    Ended {
        /// The group's name.
        group: String,
        /// The tick of the frame that showed it.
        tick: u64,
        /// The stream's state then.
        stream: StreamState,
        /// The group's motion then.
        motion: GroupMotion,
        /// Why the motion ended, when it was aborted.
        abort: GroupAbort,
    },
    /// Reading frames, publishing or a command failed (a refusal, a server restart, an
    /// interrupt: [`ClientError::Interrupted`] after SIGINT or SIGTERM).
    #[error(transparent)]
    Client(#[from] ClientError),
}

impl StreamError {
    /// The client's error underneath, if this is one.
    pub fn client(&self) -> Option<&ClientError> {
        match self {
            Self::Client(error) => Some(error),
            _ => None,
        }
    }
}

/// A group's stream as one frame shows it (the counters are the current stream's: a new
/// `Stream` command starts them from zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamStatus {
    /// The frame's tick.
    pub tick: u64,
    /// Where the stream is.
    pub state: StreamState,
    /// Its mode.
    pub mode: StreamMode,
    /// What happened to it in this tick (applied, clamped).
    pub flags: StreamFlags,
    /// The group's motion (moving while streaming).
    pub motion: GroupMotion,
    /// Why the motion ended, when it was aborted (`stream-stale`, `client-dead`, …).
    pub abort: GroupAbort,
    /// The client that streams, if any.
    pub owner: Option<ClientId>,
    /// Sequence of the last setpoint applied.
    pub last_sequence: u64,
    /// The tick in which it was applied.
    pub last_applied_tick: u64,
    /// When the server took it from the `setpoints` service (CLOCK_MONOTONIC ns, the clock
    /// of the frame's `publish_ns`); 0 until one is applied.
    pub last_received_ns: u64,
    /// Setpoints applied.
    pub applied: u64,
    /// Ticks the stream runs behind its setpoints' own ticks: the server applies the
    /// setpoint for tick `k` in tick `k + delay`. 0 while every setpoint arrived before its
    /// tick; grows to the lateness of one that arrived after it (at most `stream_buffer`),
    /// never shrinks while the stream runs. A larger [`lead`](crate::SetpointStream::lead)
    /// keeps it at 0.
    pub delay: u64,
    /// Setpoints dropped because they could no longer apply: more than `stream_buffer`
    /// ticks behind, superseded by a newer sequence for the same tick, or not above the
    /// last applied tick and sequence.
    pub late: u64,
    /// Setpoints dropped because they were for more than `stream_buffer` ticks ahead.
    pub early: u64,
    /// Setpoints clamped to a limit (`stream_limit = "clamp"`).
    pub clamped: u64,
    /// Setpoints dropped because their sender does not hold the stream (or were invalid).
    pub refused: u64,
}

impl StreamStatus {
    /// The stream of `raw`, a group's state in the frame of tick `tick`. Values this build
    /// does not know read as the defaults (idle, none).
    pub fn from_state(tick: u64, raw: &GroupState) -> Self {
        Self {
            tick,
            state: raw.stream().unwrap_or_default(),
            mode: raw.stream_mode().unwrap_or_default(),
            flags: raw.stream_flags(),
            motion: raw.motion().unwrap_or_default(),
            abort: raw.abort().unwrap_or_default(),
            owner: (!raw.owner.is_none()).then_some(raw.owner),
            last_sequence: raw.last_sequence,
            last_applied_tick: raw.last_applied_tick,
            last_received_ns: raw.last_received_ns,
            delay: u64::from(raw.stream_delay),
            applied: raw.applied,
            late: raw.late,
            early: raw.early,
            clamped: raw.clamped,
            refused: raw.refused,
        }
    }
}

/// What one [`run_each_tick`](crate::SetpointStream::run_each_tick) did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StreamRun {
    /// Setpoints sent (one per frame the client read in time: a frame it was too slow for
    /// gets none).
    pub sent: u64,
    /// The tick the first setpoint was for.
    pub first_tick: Option<u64>,
    /// The tick the last setpoint was for.
    pub last_tick: Option<u64>,
    /// The sequence number of the last setpoint.
    pub last_sequence: u64,
    /// Ticks between the first and the last without a setpoint (frames the client did not
    /// read before the next one came).
    pub skipped: u64,
    /// Setpoints a frame of the tick they were due in (their own tick plus the stream's
    /// delay) or a later one did not show applied when the client read it (published after
    /// the server had taken that tick's setpoints, the client descheduled between reading a
    /// frame and publishing): the server applies each in a later tick and the stream's
    /// delay grows to match. A setpoint whose late application no frame read showed is not
    /// counted.
    pub behind: u64,
}

impl StreamRun {
    pub(crate) fn note(&mut self, for_tick: u64, sequence: u64) {
        if let Some(last) = self.last_tick {
            self.skipped += for_tick.saturating_sub(last + 1);
        }
        self.first_tick.get_or_insert(for_tick);
        self.last_tick = Some(for_tick);
        self.last_sequence = sequence;
        self.sent += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_counts_what_it_sent_and_the_ticks_it_skipped() {
        let mut run = StreamRun::default();
        run.note(10, 1);
        run.note(11, 2);
        run.note(14, 3);
        assert_eq!(
            run,
            StreamRun {
                sent: 3,
                first_tick: Some(10),
                last_tick: Some(14),
                last_sequence: 3,
                skipped: 2,
                behind: 0,
            }
        );
    }

    #[test]
    fn a_status_reads_the_counters_of_a_group_state() {
        let raw = GroupState {
            stream: StreamState::Stale as u8,
            stream_mode: StreamMode::Velocity as u8,
            motion: GroupMotion::Aborted as u8,
            abort: GroupAbort::StreamStale as u8,
            applied: 7,
            refused: 2,
            last_sequence: 7,
            last_applied_tick: 99,
            last_received_ns: 123_456_789,
            stream_delay: 2,
            ..GroupState::IDLE
        };
        let status = StreamStatus::from_state(150, &raw);
        assert_eq!(status.state, StreamState::Stale);
        assert_eq!(status.mode, StreamMode::Velocity);
        assert_eq!(status.abort, GroupAbort::StreamStale);
        assert_eq!((status.applied, status.refused), (7, 2));
        assert_eq!((status.last_sequence, status.last_applied_tick), (7, 99));
        assert_eq!(status.last_received_ns, 123_456_789);
        assert_eq!(status.delay, 2);
        assert_eq!(status.owner, None);
    }

    #[test]
    fn an_ended_stream_says_how() {
        let error = StreamError::Ended {
            group: "base".to_owned(),
            tick: 1234,
            stream: StreamState::Stale,
            motion: GroupMotion::Aborted,
            abort: GroupAbort::StreamStale,
        };
        assert_eq!(
            error.to_string(),
            "the stream of group base ended in tick 1234: stream stale, motion aborted \
             (stream-stale)"
        );
    }
}
