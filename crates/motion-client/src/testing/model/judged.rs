//! A request's answer as the fake server judged it ([`Judged`]): the reason and the reply's
//! detail fields (the point, the axis, the holder, the figures). The model's axis, group and
//! stream requests all answer with it; the server loop turns it into the reply.

use motion_ipc::{ClientId, Reason};

/// A request's answer with the reply's detail fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::testing) struct Judged {
    pub(in crate::testing) reason: Reason,
    pub(in crate::testing) at_point: u32,
    pub(in crate::testing) at_axis: u32,
    pub(in crate::testing) holder: ClientId,
    pub(in crate::testing) value: f64,
    pub(in crate::testing) limit: f64,
}

impl From<Reason> for Judged {
    fn from(reason: Reason) -> Self {
        Self {
            reason,
            at_point: u32::MAX,
            at_axis: u32::MAX,
            holder: ClientId::NONE,
            value: 0.0,
            limit: 0.0,
        }
    }
}

impl Judged {
    pub(super) fn at(
        reason: Reason,
        point: Option<usize>,
        axis: usize,
        value: f64,
        limit: f64,
    ) -> Self {
        Self {
            at_point: point.map_or(u32::MAX, |p| p as u32),
            at_axis: axis as u32,
            value,
            limit,
            ..Self::from(reason)
        }
    }
}
