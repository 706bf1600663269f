//! What a group's refusals and aborts carry: [`GroupRefusal`] (in
//! [`ClientError::GroupRefused`](crate::ClientError::GroupRefused)) and [`GroupAborted`] (in
//! [`ClientError::GroupAborted`](crate::ClientError::GroupAborted)).

use core::fmt;

use motion_ipc::{ClientId, GroupAbort, Reason};

/// The server refused a command to a group: the reason, and where the reply names them
/// the point and the axis at fault with the figure and the limit (a path), or the axis
/// and the client holding it (a claim).
#[derive(Debug, Clone, PartialEq)]
pub struct GroupRefusal {
    /// The command ("run", "claim", "hold", …).
    pub kind: &'static str,
    /// The group's name.
    pub group: String,
    /// The server's typed reason.
    pub reason: Reason,
    /// The tick in which the server refused it.
    pub tick: u64,
    /// The path's point at fault (its index), if any.
    pub point: Option<u32>,
    /// The axis at fault, by name, if any.
    pub axis: Option<String>,
    /// That axis's config index.
    pub axis_index: Option<u32>,
    /// That axis's unit ("" when no axis is named).
    pub unit: String,
    /// `ClaimedByOther`: the client holding the axis.
    pub holder: Option<ClientId>,
    /// The figure at fault (position, velocity, acceleration, distance), when the reply
    /// carries one.
    pub value: Option<f64>,
    /// The limit it broke.
    pub limit: Option<f64>,
}

/// What the figure of a refusal is, and its unit's suffix.
fn figure_words(reason: Reason) -> (&'static str, &'static str) {
    match reason {
        Reason::OutOfRange => ("position", ""),
        Reason::VelocityLimit => ("velocity", "/s"),
        Reason::AccelLimit => ("acceleration", "/s²"),
        Reason::PathStart => ("distance from where the group is", ""),
        _ => ("value", ""),
    }
}

impl fmt::Display for GroupRefusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} on group {} refused", self.kind, self.group)?;
        let mut at = Vec::new();
        if let Some(point) = self.point {
            at.push(format!("point {point}"));
        }
        if let Some(axis) = &self.axis {
            at.push(format!("axis `{axis}`"));
        }
        if !at.is_empty() {
            write!(f, " at {}", at.join(", "))?;
        }
        if let (Some(holder), Some(axis)) = (self.holder, &self.axis) {
            return write!(
                f,
                ": axis `{axis}` is claimed by client {:#x} ({})",
                holder.as_u128(),
                self.reason.message()
            );
        }
        if let (Some(value), Some(limit)) = (self.value, self.limit) {
            if self.reason == Reason::PathTimes {
                return write!(
                    f,
                    ": time {value} s, limit {limit} s ({})",
                    self.reason.message()
                );
            }
            let (what, per) = figure_words(self.reason);
            let unit = format!("{}{per}", self.unit);
            let unit = unit.trim();
            return write!(
                f,
                ": {what} {value:.4} {unit}, limit {limit:.4} {unit} ({})",
                self.reason.message()
            );
        }
        write!(f, ": {}", self.reason.message())
    }
}

/// A group's motion ended before its end ([`GroupMotion::Aborted`](motion_ipc::GroupMotion)):
/// why, the axis that aborted it with its figure and tolerance, where along the path.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupAborted {
    /// The group's name.
    pub group: String,
    /// Why.
    pub reason: GroupAbort,
    /// The axis that aborted it, by name, if one did.
    pub axis: Option<String>,
    /// That axis's unit ("" when none).
    pub unit: String,
    /// The figure (|desired − measured|, the axis's unit).
    pub value: f64,
    /// The tolerance it broke.
    pub limit: f64,
    /// The point the path was heading to.
    pub point: u32,
    /// Seconds along the path when it ended.
    pub time: f64,
    /// The path's length at feed 1, seconds.
    pub duration: f64,
    /// The path's id.
    pub path_id: u64,
    /// The tick of the frame that showed it.
    pub tick: u64,
}

impl GroupAborted {
    /// The reason in words, with the axis and the figures where it has them.
    pub fn why(&self) -> String {
        let axis = self.axis.as_deref().unwrap_or("?");
        let unit = &self.unit;
        match self.reason {
            GroupAbort::PathTolerance => format!(
                "axis `{axis}` was {:.4} {unit} from its path, tolerance {:.4} {unit}",
                self.value, self.limit
            ),
            GroupAbort::GoalTolerance => format!(
                "axis `{axis}` stayed {:.4} {unit} from its goal after the path's end, tolerance {:.4} {unit}",
                self.value, self.limit
            ),
            GroupAbort::AxisFault => format!("axis `{axis}` faulted"),
            GroupAbort::EStop => "the e-stop was latched".to_owned(),
            GroupAbort::ClaimLost => match &self.axis {
                Some(axis) => format!("the client that ran it lost its claim on axis `{axis}`"),
                None => "the client that ran it lost a claim on its axes".to_owned(),
            },
            GroupAbort::ClientDead => "the client that ran it died".to_owned(),
            GroupAbort::Stopped => match &self.axis {
                Some(axis) => format!("a stop of axis `{axis}` stopped it"),
                None => "a stop command stopped it".to_owned(),
            },
            GroupAbort::Cancelled => "cancelled: brought to rest along its path".to_owned(),
            GroupAbort::StreamStale => "its setpoint stream stopped coming".to_owned(),
            GroupAbort::StreamLimit => "a streamed setpoint broke a limit".to_owned(),
            GroupAbort::ShuttingDown => "the server is shutting down".to_owned(),
            GroupAbort::GoalRefused => {
                format!("the board of axis `{axis}` refused the goal that would follow the path")
            }
            GroupAbort::None => "no reason given".to_owned(),
        }
    }
}

impl fmt::Display for GroupAborted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "group {} aborted ({}) at {:.3} s of {:.3} s, heading to point {}: {}",
            self.group,
            self.reason.name(),
            self.time,
            self.duration,
            self.point,
            self.why()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refusal(reason: Reason) -> GroupRefusal {
        GroupRefusal {
            kind: "run",
            group: "arm".to_owned(),
            reason,
            tick: 5,
            point: Some(12),
            axis: Some("y".to_owned()),
            axis_index: Some(1),
            unit: "mm".to_owned(),
            holder: None,
            value: Some(250.0),
            limit: Some(200.0),
        }
    }

    #[test]
    fn a_path_refusal_names_point_axis_and_figures() {
        let text = refusal(Reason::VelocityLimit).to_string();
        assert!(
            text.starts_with(
                "run on group arm refused at point 12, axis `y`: velocity 250.0000 mm/s, limit 200.0000 mm/s"
            ),
            "{text}"
        );
        let text = refusal(Reason::OutOfRange).to_string();
        assert!(
            text.contains("position 250.0000 mm, limit 200.0000 mm"),
            "{text}"
        );
    }

    #[test]
    fn a_claim_refusal_names_the_holder() {
        let mut claim = refusal(Reason::ClaimedByOther);
        claim.kind = "claim";
        claim.point = None;
        claim.value = None;
        claim.limit = None;
        claim.holder = Some(ClientId::from_u128(0xabc));
        let text = claim.to_string();
        assert!(
            text.starts_with(
                "claim on group arm refused at axis `y`: axis `y` is claimed by client 0xabc"
            ),
            "{text}"
        );
    }

    #[test]
    fn an_abort_names_reason_axis_and_figures() {
        let aborted = GroupAborted {
            group: "arm".to_owned(),
            reason: GroupAbort::PathTolerance,
            axis: Some("z".to_owned()),
            unit: "mm".to_owned(),
            value: 0.8,
            limit: 0.5,
            point: 3,
            time: 1.25,
            duration: 4.0,
            path_id: 9,
            tick: 100,
        };
        let text = aborted.to_string();
        assert!(text.contains("aborted (path-tolerance)"), "{text}");
        assert!(
            text.contains("axis `z` was 0.8000 mm from its path, tolerance 0.5000 mm"),
            "{text}"
        );
    }
}
