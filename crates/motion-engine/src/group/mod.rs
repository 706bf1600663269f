//! Axis groups (`[[group]]`): several axes, on any boards and links, moving together along
//! one path — a synchronized straight line in joint space or a time-parameterised
//! trajectory — with feed hold, resume and a feed override (docs/ARCHITECTURE.md
//! "Coordinated motion").
//!
//! The path is planned and checked by `motion-trajectory` when a `Run` is accepted (every
//! limit of every axis, exactly, before anything moves). Every tick the engine advances
//! the path's time by the feed, writes each member axis's desired position and velocity,
//! hands each board what it can follow (`Driver::follow`: a setpoint every tick, segments,
//! or velocities), and compares every fresh measurement with where the path had the axis
//! when the board measured it (`path_tolerance`). At the end every axis must come within
//! its `goal_tolerance` within `goal_time_tolerance`.
//!
//! | event | the group |
//! |---|---|
//! | a member axis faults, is stopped, switched off, or the e-stop latches | `aborted` (`axis-fault`, `stopped`, `e-stop`): every member stops by its stop category |
//! | a member axis's claim passes to another client | `aborted` (`claim-lost`) |
//! | the client that ran the motion dies | `aborted` (`client-dead`) |
//! | \|desired − measured\| > `path_tolerance` | `aborted` (`path-tolerance`, naming the axis and the distance) |
//! | an axis not within `goal_tolerance` `goal_time_tolerance` after the end | `aborted` (`goal-tolerance`); the axis faults `GoalTolerance` |
//! | `Hold` / `Cancel` | `holding` → `held` (feed to 0 along the path at the axes' acceleration limits); cancel then ends `aborted` (`cancelled`) |

mod follow;
mod history;
mod lead;
mod request;
mod run;
mod setpoint_limits;
mod stream;

use core::time::Duration;

use motion_drivers::Follow;
use motion_ipc::{ClientId, GroupAbort, GroupMotion, GroupState, MAX_PATH_POINTS, PathKind};
use motion_trajectory::{AxisLimits, Path, TimeScale};

use crate::config::GroupConfig;
use history::PathHistory;
use lead::{Arming, Lead};
use stream::Stream;

/// One member axis's following state.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(crate) struct Member {
    /// Index into the engine's axes.
    pub axis: usize,
    /// How its board follows.
    pub follow: Follow,
    /// When the last segment (or velocity) was handed to its driver, and when the driver
    /// was first seen to have acknowledged it.
    pub sent_at: Option<Duration>,
    pub acked_at: Option<Duration>,
    /// The segment length: how long the driver takes to get a goal acknowledged
    /// (measured; an average).
    pub lead: Duration,
    /// The last position target handed over, units (a segment's end).
    pub last_target: f64,
    /// The final goal (the path's end) was handed over.
    pub end_sent: bool,
    /// No new goal before this instant: after an acknowledged goal the link gets as
    /// long again for its own traffic (polls, the encoder stream), so that following a
    /// path never starves the measurements it is supervised by.
    pub next_at: Duration,
    /// The last velocity handed over (velocity following), units/s.
    pub last_velocity: f64,
    /// Whether its board runs the group's line itself (`lead.rs`).
    pub led: Lead,
}

impl Member {
    /// Its following starts afresh at `now`: the next goal goes out at once (a motion
    /// started, a board's own line handed back, a held path resumed — a goal that held the
    /// axis on the path is superseded, not waited for).
    pub(crate) fn restart(&mut self, now: Duration) {
        self.sent_at = None;
        self.acked_at = None;
        self.end_sent = false;
        self.next_at = now;
        self.last_velocity = f64::NAN;
    }
}

/// One group and its motion.
#[derive(serde::Serialize, serde::Deserialize, Debug)]
pub(crate) struct Group {
    pub config: GroupConfig,
    pub members: Vec<Member>,
    pub limits: Vec<AxisLimits>,
    /// The path running (or last run), and a spare one a new path is planned into (a
    /// refused plan leaves the running one untouched).
    pub path: Path,
    /// Scratch between requests (a plan writes it, then it is swapped with `path`): the
    /// state snapshot keeps its sizes only.
    #[serde(with = "motion_trajectory::serde_scratch_path")]
    pub spare: Path,
    pub scale: TimeScale,
    pub history: PathHistory,
    pub motion: GroupMotion,
    pub abort: GroupAbort,
    pub abort_axis: Option<usize>,
    pub abort_value: f64,
    pub abort_limit: f64,
    /// The client whose motion (or stream) runs (or ran).
    pub owner: ClientId,
    /// The motion's owner held a claim on every member axis when it started.
    pub claimed: bool,
    pub path_id: u64,
    pub kind: PathKind,
    pub point: u32,
    /// The feed the client set.
    pub feed_set: f64,
    /// A cancel is bringing the group to rest.
    pub cancelling: bool,
    /// The feed a line was handed to boards at (`lead.rs`): a resume at another feed
    /// follows it with goals.
    pub led_feed: f64,
    /// Boards were handed the line and prepare it, or were started and their starts are
    /// on their way: the path waits (`lead.rs`).
    pub arming: Arming,
    /// When the path's time reached its end.
    pub ended_at: Option<Duration>,
    /// Scratch: desired position, velocity, acceleration per member (time-scaled).
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub acceleration: Vec<f64>,
    /// Scratch: the path's state at a past instant (supervision).
    pub then: Vec<f64>,
    pub then_velocity: Vec<f64>,
    pub then_acceleration: Vec<f64>,
    /// Scratch: per member, its driver had a goal to acknowledge at the start of the tick.
    pub pending: Vec<bool>,
    /// The group's setpoint stream (kind `Stream`).
    pub stream: Stream,
    /// A power stream: the power per member (its desired position is where it is).
    pub power: Vec<f64>,
}

/// The segment length a board starts with before its acknowledgements are measured.
pub(crate) const FIRST_LEAD: Duration = Duration::from_millis(60);
/// The longest segment: a driver slower than this to acknowledge still gets targets this
/// far ahead, no farther.
pub(crate) const MAX_LEAD: Duration = Duration::from_millis(250);

impl Group {
    /// `members`: each member axis's index, follow style and limits.
    pub fn new(config: GroupConfig, members: Vec<(usize, Follow, AxisLimits)>) -> Self {
        let count = members.len();
        let path = Path::new(count, MAX_PATH_POINTS);
        let spare = Path::new(count, MAX_PATH_POINTS);
        Self {
            limits: members.iter().map(|(_, _, limits)| *limits).collect(),
            members: members
                .iter()
                .map(|(axis, follow, _)| Member {
                    axis: *axis,
                    follow: *follow,
                    sent_at: None,
                    acked_at: None,
                    lead: FIRST_LEAD,
                    last_target: 0.0,
                    end_sent: false,
                    next_at: Duration::ZERO,
                    last_velocity: f64::NAN,
                    led: Lead::No,
                })
                .collect(),
            stream: Stream::new(config.stream_buffer),
            config,
            path,
            spare,
            scale: TimeScale::new(),
            history: PathHistory::new(),
            motion: GroupMotion::Idle,
            abort: GroupAbort::None,
            abort_axis: None,
            abort_value: 0.0,
            abort_limit: 0.0,
            owner: ClientId::NONE,
            claimed: false,
            path_id: 0,
            kind: PathKind::None,
            point: 0,
            feed_set: 1.0,
            cancelling: false,
            led_feed: 0.0,
            arming: Arming::No,
            ended_at: None,
            position: vec![0.0; count],
            velocity: vec![0.0; count],
            acceleration: vec![0.0; count],
            then: vec![0.0; count],
            then_velocity: vec![0.0; count],
            then_acceleration: vec![0.0; count],
            pending: vec![false; count],
            power: vec![0.0; count],
        }
    }

    /// The group's entry of the frame; `common_claim`: the client holding every member
    /// axis's claim, if one does.
    pub fn state(&self, common_claim: ClientId) -> GroupState {
        let owner = if self.motion.active() || common_claim.is_none() {
            self.owner
        } else {
            common_claim
        };
        GroupState {
            owner,
            path_id: self.path_id,
            time: self.scale.time(),
            duration: self.path.duration(),
            feed: self.scale.feed(),
            feed_set: self.feed_set,
            abort_value: self.abort_value,
            abort_limit: self.abort_limit,
            point: self.point,
            abort_axis: self.abort_axis.map_or(u32::MAX, |axis| axis as u32),
            motion: self.motion as u8,
            abort: self.abort as u8,
            kind: self.kind as u32 as u8,
            stream: self.stream.state as u8,
            stream_mode: self.stream.mode as u32 as u8,
            stream_flags: self.stream.flags.0,
            stream_delay: u16::try_from(self.stream.playout.delay).unwrap_or(u16::MAX),
            last_sequence: self.stream.playout.last_sequence,
            last_applied_tick: self.stream.last_applied_tick,
            last_received_ns: self.stream.last_received_ns,
            applied: self.stream.applied,
            late: self.stream.late,
            early: self.stream.early,
            clamped: self.stream.clamped,
            refused: self.stream.refused,
        }
    }
}
