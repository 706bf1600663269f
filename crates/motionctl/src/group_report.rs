//! What `group move|follow --wait` reports: per axis, the tick it arrived at its final
//! target (and stayed), and its largest path error while the group moved; built from the
//! frames seen during the wait.

use motion_client::GroupStatus;
use motion_client::ipc::{GroupMotion, GroupState, MotionFrame};
use serde_json::{Map, Value, json};

/// One member axis as the report follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportAxis {
    /// Its name.
    pub name: String,
    /// Its config index (into the frame's axes).
    pub index: usize,
    /// Its unit.
    pub unit: String,
    /// Where the path ends for it.
    pub target: f64,
    /// Its goal tolerance (the group's).
    pub goal_tolerance: f64,
}

#[derive(Debug, Clone, Default)]
struct Track {
    /// The first tick of the current run of frames within the goal tolerance.
    arrived: Option<u64>,
    /// The axis's `last_refresh_tick` in the previous frame seen.
    last_refresh: Option<u64>,
    /// Largest |desired − measured| on fresh frames while the group moved.
    max_path_error: Option<f64>,
}

/// The report of one run of a group's path, fed frame by frame.
#[derive(Debug, Clone)]
pub struct GroupReport {
    group: String,
    index: usize,
    path_id: u64,
    axes: Vec<ReportAxis>,
    tracks: Vec<Track>,
    first_tick: Option<u64>,
    /// The newest frame's tick and the group's state in it.
    last: Option<(u64, GroupState)>,
}

impl GroupReport {
    /// A report about path `path_id` of group `group` (config index `index`).
    pub fn new(group: &str, index: usize, path_id: u64, axes: Vec<ReportAxis>) -> Self {
        Self {
            group: group.to_owned(),
            index,
            path_id,
            tracks: vec![Track::default(); axes.len()],
            axes,
            first_tick: None,
            last: None,
        }
    }

    /// Takes one frame into account. Frames of another path (before the run shows, or
    /// after another replaced it) are ignored.
    pub fn observe(&mut self, frame: &MotionFrame) {
        let Some(group) = frame.groups().get(self.index) else {
            return;
        };
        if group.path_id != self.path_id {
            return;
        }
        self.first_tick.get_or_insert(frame.tick);
        self.last = Some((frame.tick, *group));
        let moving = GroupMotion::try_from(group.motion).is_ok_and(GroupMotion::active);
        for (axis, track) in self.axes.iter().zip(&mut self.tracks) {
            let Some(state) = frame.axes().get(axis.index) else {
                continue;
            };
            let fresh = match track.last_refresh {
                Some(previous) => previous != state.last_refresh_tick,
                None => state.last_refresh_tick == frame.tick,
            };
            track.last_refresh = Some(state.last_refresh_tick);
            if moving && fresh {
                let error = (state.desired_position - state.position).abs();
                track.max_path_error = Some(track.max_path_error.map_or(error, |m| m.max(error)));
            }
            if (state.position - axis.target).abs() <= axis.goal_tolerance {
                track.arrived.get_or_insert(frame.tick);
            } else {
                track.arrived = None;
            }
        }
    }

    /// The tick of the newest frame of the path and the group's state in it.
    pub fn last(&self) -> Option<(u64, GroupState)> {
        self.last
    }

    /// The report as one JSON object: `state` (the group's motion as the frame names it),
    /// `abort` (its reason, or null), `axes` keyed by name with `arrived_tick` and
    /// `max_path_error`, and the figures of the run.
    pub fn json(&self, end: &GroupStatus) -> Value {
        let mut axes = Map::new();
        for (axis, track) in self.axes.iter().zip(&self.tracks) {
            axes.insert(
                axis.name.clone(),
                json!({
                    "arrived_tick": track.arrived,
                    "max_path_error": track.max_path_error,
                    "target": axis.target,
                    "unit": axis.unit,
                }),
            );
        }
        let aborted = end.motion == GroupMotion::Aborted;
        json!({
            "group": self.group,
            "path_id": self.path_id,
            "state": end.motion.name(),
            "abort": aborted.then(|| end.abort.name()),
            "abort_axis": if aborted { json!(end.abort_axis) } else { Value::Null },
            "abort_value": if aborted { json!(end.abort_value) } else { Value::Null },
            "abort_limit": if aborted { json!(end.abort_limit) } else { Value::Null },
            "first_tick": self.first_tick,
            "end_tick": end.tick,
            "time": end.time,
            "duration": end.duration,
            "axes": axes,
        })
    }

    /// The report in words: a line for the group, one per axis.
    pub fn lines(&self, end: &GroupStatus) -> Vec<String> {
        let mut lines = vec![match end.motion {
            GroupMotion::Aborted => format!(
                "{}: aborted ({}) in tick {} at {:.3} s of {:.3} s (path {})",
                self.group,
                end.abort.name(),
                end.tick,
                end.time,
                end.duration,
                self.path_id
            ),
            motion => format!(
                "{}: {} in tick {} after {:.3} s (path {})",
                self.group,
                motion.name(),
                end.tick,
                end.time,
                self.path_id
            ),
        }];
        for (axis, track) in self.axes.iter().zip(&self.tracks) {
            let arrived = track.arrived.map_or_else(
                || "not within its goal tolerance".to_owned(),
                |tick| format!("arrived in tick {tick}"),
            );
            let error = track.max_path_error.map_or_else(
                || "no fresh sample while moving".to_owned(),
                |error| format!("max path error {error:.4} {}", axis.unit),
            );
            lines.push(format!(
                "  {:<12} {:>12.4} {:<4} {arrived}, {error}",
                axis.name, axis.target, axis.unit
            ));
        }
        lines
    }
}

#[cfg(test)]
mod tests {
    use motion_client::ipc::{AxisInfo, GroupAbort, GroupInfo, GroupState, ServerInfo, write_text};

    use super::*;

    fn axes() -> Vec<ReportAxis> {
        ["x", "feeder"]
            .iter()
            .enumerate()
            .map(|(index, name)| ReportAxis {
                name: (*name).to_owned(),
                index: index * 2,
                unit: "mm".to_owned(),
                target: 10.0,
                goal_tolerance: 0.1,
            })
            .collect()
    }

    /// A frame of tick `tick`: group 1 running path `path` in `motion`; axes 0 and 2 at
    /// `positions` (refreshed in `refresh`) with desired positions `desired`.
    fn frame(
        tick: u64,
        path: u64,
        motion: GroupMotion,
        positions: [f64; 2],
        desired: [f64; 2],
        refresh: [u64; 2],
    ) -> Box<MotionFrame> {
        let mut frame = Box::new(MotionFrame::EMPTY);
        frame.tick = tick;
        frame.axis_count = 3;
        frame.group_count = 2;
        frame.groups[1] = GroupState {
            path_id: path,
            motion: motion as u8,
            ..GroupState::IDLE
        };
        for slot in 0..2 {
            let axis = &mut frame.axes[slot * 2];
            axis.position = positions[slot];
            axis.desired_position = desired[slot];
            axis.last_refresh_tick = refresh[slot];
        }
        frame
    }

    fn end(tick: u64, motion: GroupMotion, abort: GroupAbort) -> GroupStatus {
        let mut info = Box::new(ServerInfo::EMPTY);
        info.axis_count = 3;
        for (index, name) in ["x", "y", "feeder"].iter().enumerate() {
            info.axes[index] = AxisInfo::EMPTY;
            write_text(&mut info.axes[index].name, name);
        }
        info.group_count = 2;
        for (index, name) in ["arm", "gantry"].iter().enumerate() {
            info.groups[index] = GroupInfo::EMPTY;
            write_text(&mut info.groups[index].name, name);
        }
        let mut last = frame(tick, 7, motion, [10.0, 10.0], [10.0, 10.0], [tick, tick]);
        last.groups[1].abort = abort as u8;
        if abort != GroupAbort::None {
            last.groups[1].abort_axis = 2;
            last.groups[1].abort_value = 0.8;
            last.groups[1].abort_limit = 0.5;
        }
        GroupStatus::read(&info, &last, 1).expect("group 1")
    }

    #[test]
    fn arrival_is_the_first_tick_of_the_last_stay_within_tolerance() {
        let mut report = GroupReport::new("gantry", 1, 7, axes());
        let moving = GroupMotion::Moving;
        // An older path's frame is not counted.
        report.observe(&frame(9, 6, moving, [50.0, 50.0], [0.0, 0.0], [9, 9]));
        report.observe(&frame(10, 7, moving, [5.0, 9.95], [5.1, 9.95], [10, 10]));
        // x passes through the target and leaves it again; feeder stays.
        report.observe(&frame(11, 7, moving, [10.05, 10.0], [10.0, 10.0], [11, 11]));
        report.observe(&frame(12, 7, moving, [10.3, 10.0], [10.0, 10.0], [12, 11]));
        report.observe(&frame(13, 7, moving, [10.0, 10.0], [10.0, 10.0], [13, 13]));
        report.observe(&frame(
            14,
            7,
            GroupMotion::Done,
            [10.0, 10.0],
            [10.0, 10.0],
            [14, 14],
        ));
        let value = report.json(&end(14, GroupMotion::Done, GroupAbort::None));
        assert_eq!(value["state"], "done");
        assert_eq!(value["abort"], Value::Null);
        assert_eq!(value["first_tick"], 10);
        assert_eq!(value["axes"]["x"]["arrived_tick"], 13);
        assert_eq!(value["axes"]["feeder"]["arrived_tick"], 10);
        let x_error = value["axes"]["x"]["max_path_error"].as_f64().unwrap();
        assert!((x_error - 0.3).abs() < 1e-9, "{x_error}");
        let keys: Vec<&String> = value["axes"].as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), 2);
    }

    #[test]
    fn path_error_counts_only_fresh_samples_while_moving() {
        let mut report = GroupReport::new("gantry", 1, 7, axes());
        let moving = GroupMotion::Moving;
        // First frame: fresh in its own tick counts; the feeder's stale data does not.
        report.observe(&frame(20, 7, moving, [1.0, 1.0], [1.5, 3.0], [20, 15]));
        // The same samples again (no refresh): a larger gap is not counted.
        report.observe(&frame(21, 7, moving, [1.0, 1.0], [2.5, 9.0], [20, 15]));
        // Fresh again.
        report.observe(&frame(22, 7, moving, [2.0, 2.0], [2.2, 2.4], [22, 22]));
        // Held still counts as moving with the group; done does not.
        report.observe(&frame(
            23,
            7,
            GroupMotion::Held,
            [2.0, 2.0],
            [2.0, 2.9],
            [23, 23],
        ));
        report.observe(&frame(
            24,
            7,
            GroupMotion::Done,
            [2.0, 2.0],
            [9.0, 9.0],
            [24, 24],
        ));
        let value = report.json(&end(24, GroupMotion::Done, GroupAbort::None));
        let error = |axis: &str| value["axes"][axis]["max_path_error"].as_f64().unwrap();
        assert!((error("x") - 0.5).abs() < 1e-9, "{}", error("x"));
        assert!((error("feeder") - 0.9).abs() < 1e-9, "{}", error("feeder"));
        assert_eq!(value["axes"]["x"]["arrived_tick"], Value::Null);
    }

    #[test]
    fn an_aborted_run_names_its_reason_and_axis() {
        let mut report = GroupReport::new("gantry", 1, 7, axes());
        report.observe(&frame(
            30,
            7,
            GroupMotion::Aborted,
            [3.0, 3.0],
            [3.0, 3.0],
            [29, 29],
        ));
        let status = end(31, GroupMotion::Aborted, GroupAbort::PathTolerance);
        let value = report.json(&status);
        assert_eq!(value["state"], "aborted");
        assert_eq!(value["abort"], "path-tolerance");
        assert_eq!(value["abort_axis"], "feeder");
        assert_eq!(value["abort_value"], 0.8);
        assert_eq!(value["axes"]["feeder"]["max_path_error"], Value::Null);
        let lines = report.lines(&status);
        assert!(
            lines[0].starts_with("gantry: aborted (path-tolerance) in tick 31"),
            "{lines:?}"
        );
        assert_eq!(lines.len(), 3);
    }
}
