//! A group's state in one frame, typed ([`GroupStatus`]), and how its motion ended
//! ([`GroupOutcome`], what [`Group::wait_done`](crate::Group::wait_done) returns).

use motion_ipc::{
    ClientId, GroupAbort, GroupMotion, GroupState, MotionFrame, PathKind, ServerInfo, StreamState,
};

use crate::{ClientError, GroupAborted};

/// A group's state in one frame, typed, with the abort's axis named.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupStatus {
    /// The group's name.
    pub name: String,
    /// The frame's tick.
    pub tick: u64,
    /// Where its motion is.
    pub motion: GroupMotion,
    /// Why its motion ended early ([`GroupAbort::None`] unless aborted).
    pub abort: GroupAbort,
    /// The axis that aborted it, by name.
    pub abort_axis: Option<String>,
    /// That axis's unit ("" when none).
    pub abort_unit: String,
    /// The figure that aborted it.
    pub abort_value: f64,
    /// The tolerance it broke.
    pub abort_limit: f64,
    /// The id of the path running or last run.
    pub path_id: u64,
    /// What that path is.
    pub kind: PathKind,
    /// The point the path is heading to.
    pub point: u32,
    /// Seconds along the path.
    pub time: f64,
    /// The path's length at feed 1, seconds.
    pub duration: f64,
    /// The feed in effect.
    pub feed: f64,
    /// The feed set by the client.
    pub feed_set: f64,
    /// The client whose motion runs, if any.
    pub owner: Option<ClientId>,
    /// Where its setpoint stream is.
    pub stream: StreamState,
    /// The state as the frame carries it.
    pub raw: GroupState,
}

fn unknown_group(info: &ServerInfo, group: usize) -> ClientError {
    ClientError::UnknownGroup {
        name: format!("#{group}"),
        known: info.groups().iter().map(|g| g.name().to_owned()).collect(),
    }
}

fn unknown(what: &'static str) -> impl Fn(motion_ipc::UnknownValue) -> ClientError {
    move |error| ClientError::UnknownValue {
        what,
        value: error.0,
    }
}

impl GroupStatus {
    /// The state of group `group` (config order) in `frame`, named with `info`.
    pub fn read(info: &ServerInfo, frame: &MotionFrame, group: usize) -> Result<Self, ClientError> {
        match frame.groups().get(group) {
            Some(raw) => Self::from_state(info, group, frame.tick, *raw),
            None => Err(unknown_group(info, group)),
        }
    }

    /// The state `raw` of group `group` (config order) seen in tick `tick`, named with
    /// `info`.
    pub fn from_state(
        info: &ServerInfo,
        group: usize,
        tick: u64,
        raw: GroupState,
    ) -> Result<Self, ClientError> {
        let Some(name) = info.groups().get(group).map(|g| g.name().to_owned()) else {
            return Err(unknown_group(info, group));
        };
        let abort_axis = raw.abort_axis().map(|axis| {
            info.axes()
                .get(axis as usize)
                .map_or_else(|| format!("#{axis}"), |a| a.name().to_owned())
        });
        let abort_unit = raw
            .abort_axis()
            .and_then(|axis| info.axes().get(axis as usize))
            .map(|axis| axis.unit().to_owned())
            .unwrap_or_default();
        Ok(Self {
            name,
            tick,
            motion: raw.motion().map_err(unknown("group motion"))?,
            abort: raw.abort().map_err(unknown("group abort reason"))?,
            abort_axis,
            abort_unit,
            abort_value: raw.abort_value,
            abort_limit: raw.abort_limit,
            path_id: raw.path_id,
            kind: PathKind::try_from(u32::from(raw.kind)).map_err(unknown("path kind"))?,
            point: raw.point,
            time: raw.time,
            duration: raw.duration,
            feed: raw.feed,
            feed_set: raw.feed_set,
            owner: (!raw.owner.is_none()).then_some(raw.owner),
            stream: raw.stream().map_err(unknown("stream state"))?,
            raw,
        })
    }

    /// The abort as an error value (whatever the motion; meant for `aborted`).
    pub fn aborted(&self) -> GroupAborted {
        GroupAborted {
            group: self.name.clone(),
            reason: self.abort,
            axis: self.abort_axis.clone(),
            unit: self.abort_unit.clone(),
            value: self.abort_value,
            limit: self.abort_limit,
            point: self.point,
            time: self.time,
            duration: self.duration,
            path_id: self.path_id,
            tick: self.tick,
        }
    }
}

/// A group's motion that ended at its end ([`Group::wait_done`](crate::Group::wait_done)).
#[derive(Debug, Clone, PartialEq)]
pub struct GroupOutcome {
    /// The group's name.
    pub group: String,
    /// `Done`; `Idle` when nothing ran that the wait was about.
    pub motion: GroupMotion,
    /// The id of the path that ended.
    pub path_id: u64,
    /// The tick of the frame that showed it.
    pub tick: u64,
    /// Seconds along the path at the end.
    pub time: f64,
    /// The path's length at feed 1, seconds.
    pub duration: f64,
}
