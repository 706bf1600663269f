//! A driver's plan of requests: a short fixed-capacity queue of [`Step`]s, some of which
//! are resolved only when they reach the front (what to move by is computed from the
//! encoder reading at that moment, not when the goal was set).

use ::qsb::{Request, Write};
use motion_base::FixedQueue;

/// One step of a plan.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) enum Step {
    /// Send this request.
    Send(Request),
    /// Write the register unless the board is known to hold the value already.
    Ensure(Write),
    /// STR as normal operation has it: streamed when the trigger's pulses are counted,
    /// else not (a read of STR cancels its stream).
    NormalStrStream,
    /// DTR, MDR0 and MDR1 of normal operation (count limit or compare position, counter
    /// mode, triggers), each written unless the board holds it; the step stays at the
    /// front until all three are held.
    NormalCounter,
    /// Write DIG I/O with the signal outputs and the enable line, unless the board holds
    /// them already.
    Outputs,
    /// -M with an enable line: make it active (`true`) or inactive, unless it is already.
    Enable(bool),
    /// Start-up: the configuration for the product VERSION reported.
    Configure,
    /// Start-up: done; the board is online.
    Online,
    /// -M: COMMAND 4 if the drive reports motion.
    StopIfMoving,
    /// -M: wait until the drive reports done after the last motor command.
    WaitDone,
    /// -M: move by the whole steps that remain to `target` counts (`attempt` moves made).
    MoveTo {
        /// Target, counts.
        target: f64,
        /// Moves made so far for this goal.
        attempt: u8,
    },
    /// -M home search: wait for the index latch (or give up after the travel limit).
    WaitIndex,
    /// -M: a group's line waits here until the engine starts it.
    Armed,
    /// -M: a move paused with COMMAND 6 waits here until the engine resumes it.
    Paused,
}

/// Steps a plan can hold.
pub(crate) const PROGRAM_CAPACITY: usize = 24;

/// A fixed-capacity queue of steps.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Program {
    steps: FixedQueue<Step, PROGRAM_CAPACITY>,
    /// Changes whenever the plan is replaced, so that the answer to a request of an old
    /// plan never advances a new one.
    generation: u32,
}

impl Program {
    pub(crate) const fn new() -> Self {
        Self {
            steps: FixedQueue::new(),
            generation: 0,
        }
    }

    pub(crate) fn generation(&self) -> u32 {
        self.generation
    }

    pub(crate) fn front(&self) -> Option<Step> {
        self.steps.front()
    }

    /// The step after the front one.
    pub(crate) fn second(&self) -> Option<Step> {
        self.steps.iter().nth(1)
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    #[cfg(test)]
    pub(crate) fn iter(&self) -> impl Iterator<Item = Step> + '_ {
        self.steps.iter()
    }

    /// Replaces the whole plan with `steps` (cut to the capacity).
    pub(crate) fn replace(&mut self, steps: &[Step]) {
        self.generation = self.generation.wrapping_add(1);
        self.steps.clear();
        self.steps.extend_from_slice(steps);
    }

    /// Empties the plan.
    pub(crate) fn clear(&mut self) {
        self.replace(&[]);
    }

    /// Removes the front step.
    pub(crate) fn pop(&mut self) {
        self.steps.pop();
    }

    /// Replaces the front step with `steps` (keeping the rest behind them, as far as the
    /// capacity allows). The generation stays: this is the same plan unfolding.
    pub(crate) fn expand_front(&mut self, steps: impl IntoIterator<Item = Step>) {
        if self.steps.pop().is_none() {
            return;
        }
        let rest = self.steps;
        self.steps.clear();
        for step in steps.into_iter().chain(rest.iter()) {
            if !self.steps.push(step) {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ::qsb::Register;

    #[test]
    fn expand_front_keeps_the_rest_in_order() {
        let mut program = Program::new();
        program.replace(&[Step::Configure, Step::Online]);
        let generation = program.generation();
        let read = Step::Send(Request::Read(Register::Version));
        program.expand_front([read, Step::NormalStrStream]);
        let steps: Vec<Step> = program.iter().collect();
        assert_eq!(steps, [read, Step::NormalStrStream, Step::Online]);
        assert_eq!(program.generation(), generation);
        program.pop();
        program.pop();
        assert_eq!(program.front(), Some(Step::Online));
        program.pop();
        program.pop();
        assert!(program.is_empty());
        program.clear();
        assert_ne!(program.generation(), generation);
    }

    #[test]
    fn a_full_program_drops_what_does_not_fit() {
        let mut program = Program::new();
        program.replace(&[Step::WaitDone; PROGRAM_CAPACITY + 3]);
        assert_eq!(program.iter().count(), PROGRAM_CAPACITY);
        program.expand_front([Step::Online; 4]);
        assert_eq!(program.iter().count(), PROGRAM_CAPACITY);
        assert_eq!(program.front(), Some(Step::Online));
    }
}
