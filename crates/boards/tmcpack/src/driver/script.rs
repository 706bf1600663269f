//! A goal's script: its steps ([`Step`], at most [`MAX_STEPS`]) and the script while it
//! is planned ([`Script`]; module `channel` plans and runs it).

use motion_base::FixedQueue;
use tmcpack::Request;

use motion_drivers::GoalError;

/// Longest script one goal needs.
pub(crate) const MAX_STEPS: usize = 10;

/// One step of a goal's script.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Step {
    /// Send this request (none of them is answered).
    Send(Request),
    /// Wait until the rotation stop sent before has come to rest, then end the rotation
    /// with `$23` if a fresh poll still shows it.
    AwaitRest,
}

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
