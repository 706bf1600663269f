//! A goal's script while it is planned (module `channel`).

use motion_base::FixedQueue;
use tmcpack::Request;

use super::channel::{MAX_STEPS, Step};
use motion_drivers::GoalError;

/// A script being planned.
#[derive(Debug, Default)]
pub(super) struct Script {
    pub steps: FixedQueue<Step, MAX_STEPS>,
    overflow: bool,
    /// `$14` values the script has written so far.
    pub limits: Option<(u16, u16)>,
}

impl Script {
    pub fn push(&mut self, step: Step) {
        if !self.steps.push(step) {
            self.overflow = true;
        }
    }

    pub fn send(&mut self, request: Request) {
        self.push(Step::Send(request));
    }

    /// The steps, or `error` when the script overflowed or holds a request beyond the
    /// pack's ranges.
    pub fn finish(self, error: GoalError) -> Result<FixedQueue<Step, MAX_STEPS>, GoalError> {
        let invalid = self
            .steps
            .iter()
            .any(|step| matches!(step, Step::Send(request) if request.validate().is_err()));
        if self.overflow || invalid {
            return Err(error);
        }
        Ok(self.steps)
    }
}
