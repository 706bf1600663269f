//! Home / index / edge input of one channel (packet 14) and its status bits.

use qq2drv::{EdgeAction, InputConfig, InputMode, Status};

use super::config::{InputPin, InputSource};

/// The electrical level of an IN pin for a shaft at `position` (transitions).
pub(crate) fn pin_level(pin: &InputPin, position: f64, transitions_per_rev: u32) -> bool {
    let actuated = match pin.source {
        InputSource::None => false,
        InputSource::EndStop {
            position: at,
            positive_end,
        } => {
            if positive_end {
                position >= at
            } else {
                position <= at
            }
        }
        InputSource::TwoEndStops { negative, positive } => {
            position <= negative || position >= positive
        }
        InputSource::Window { from, to } => (from..=to).contains(&position),
        InputSource::Index { offset, width } => {
            let rev = f64::from(transitions_per_rev.max(1));
            let phase = (position - offset).rem_euclid(rev);
            phase < width
        }
    };
    actuated == pin.actuated_high
}

/// What the input logic decided at one evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum InputAction {
    /// Nothing to do.
    None,
    /// Write this value into the position counter.
    SetCounter(i32),
}

/// Configuration (packet 14) and accumulated state of one input.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Input {
    pub(crate) config: InputConfig,
    pub(crate) spacing: u16,
    pub(crate) position: i32,
    active: bool,
    active_accumulator: bool,
    trigger_accumulator: u8,
    /// End (true = positive) and counter value of the last trigger.
    last_trigger: Option<(bool, i64)>,
    /// Last recorded trigger position (record-only edge settings).
    recorded: Option<i64>,
}

impl Input {
    /// Packet 14 for this channel.
    pub(crate) fn configure(&mut self, config: InputConfig, spacing: u16, position: i32) {
        self.config = config;
        self.spacing = spacing;
        self.position = position;
        self.last_trigger = None;
    }

    /// Input Active as last evaluated (after polarity).
    pub(crate) fn active(&self) -> bool {
        self.active
    }

    /// The last position recorded by a trigger.
    pub(crate) fn recorded(&self) -> Option<i64> {
        self.recorded
    }

    /// Evaluates the input with the pin at `level_high`, the counter at `counter`, the
    /// quadrature lines at A = B = 0 or not, and the shaft moving forward or not.
    pub(crate) fn evaluate(
        &mut self,
        level_high: bool,
        counter: i64,
        ab_zero: bool,
        forward: bool,
    ) -> InputAction {
        let was_active = self.active;
        self.active = level_high == self.config.active_high();
        self.active_accumulator |= self.active;
        let edge = self.config.edge();
        let triggered_end = match self.config.mode() {
            InputMode::Disabled => None,
            InputMode::Home => self.active.then(|| self.end(forward)),
            InputMode::Edge => (self.active && !was_active).then(|| self.end(forward)),
            // "When input mode is set to INDEX, the Positive Trigger will always be used."
            InputMode::Index => (self.active && ab_zero).then_some(true),
        };
        let Some(positive) = triggered_end else {
            return InputAction::None;
        };
        if self.config.mode() != InputMode::Index && self.blocked_by_hysteresis(positive, counter) {
            return InputAction::None;
        }
        self.trigger_accumulator |= if positive {
            Status::TRIGGER_POSITIVE
        } else {
            Status::TRIGGER_NEGATIVE
        };
        let set = match edge {
            EdgeAction::RecordPositive | EdgeAction::RecordNegative => false,
            EdgeAction::SetOnPositive => positive || self.config.mode() == InputMode::Index,
            EdgeAction::SetOnNegative => !positive || self.config.mode() == InputMode::Index,
        };
        if set {
            self.last_trigger = Some((positive, i64::from(self.position)));
            InputAction::SetCounter(self.position)
        } else {
            self.last_trigger = Some((positive, counter));
            self.recorded = Some(counter);
            InputAction::None
        }
    }

    /// Which end a trigger is on: with Spacing 0 a single end-stop whose end the Edge field
    /// names; otherwise the end the shaft is travelling towards.
    fn end(&self, forward: bool) -> bool {
        if self.spacing == 0 {
            matches!(
                self.config.edge(),
                EdgeAction::RecordPositive | EdgeAction::SetOnPositive
            )
        } else {
            forward
        }
    }

    /// A trigger on the other end than the last one counts only once the counter is at
    /// least Spacing away from where the last trigger happened.
    fn blocked_by_hysteresis(&self, positive: bool, counter: i64) -> bool {
        match self.last_trigger {
            Some((last_end, at)) if self.spacing != 0 && last_end != positive => {
                (counter - at).abs() < i64::from(self.spacing)
            }
            _ => false,
        }
    }

    /// The input bits of the Status byte; reading them clears the accumulators.
    pub(crate) fn take_status_bits(&mut self) -> u8 {
        let mut bits = self.trigger_accumulator;
        if self.active {
            bits |= Status::INPUT_ACTIVE;
        }
        if self.active_accumulator {
            bits |= Status::INPUT_ACTIVE_ACCUMULATOR;
        }
        self.active_accumulator = self.active;
        self.trigger_accumulator = 0;
        bits
    }
}

#[cfg(test)]
mod tests {
    use super::{Input, InputAction, pin_level};
    use crate::sim::config::{InputPin, InputSource};
    use qq2drv::{EdgeAction, InputConfig, InputMode, Status};

    #[test]
    fn edge_mode_sets_once_on_the_transition() {
        let mut i = Input::default();
        i.configure(
            InputConfig::new(InputMode::Edge, true, EdgeAction::SetOnPositive),
            0,
            500,
        );
        assert_eq!(i.evaluate(false, 10, false, true), InputAction::None);
        assert_eq!(
            i.evaluate(true, 11, false, true),
            InputAction::SetCounter(500)
        );
        assert_eq!(i.evaluate(true, 12, false, true), InputAction::None);
        let bits = i.take_status_bits();
        assert_eq!(
            bits,
            Status::INPUT_ACTIVE | Status::INPUT_ACTIVE_ACCUMULATOR | Status::TRIGGER_POSITIVE
        );
        assert_eq!(
            i.take_status_bits(),
            Status::INPUT_ACTIVE | Status::INPUT_ACTIVE_ACCUMULATOR
        );
    }

    #[test]
    fn single_negative_end_stop_does_not_set_on_positive_edge_setting() {
        let mut i = Input::default();
        i.configure(
            InputConfig::new(InputMode::Home, false, EdgeAction::RecordNegative),
            0,
            0,
        );
        // Active low: level false = active.
        assert_eq!(i.evaluate(false, -7, false, false), InputAction::None);
        assert_eq!(i.recorded(), Some(-7));
        assert_eq!(i.take_status_bits() & 0x03, Status::TRIGGER_NEGATIVE);
    }

    #[test]
    fn index_needs_a_equals_b_equals_zero() {
        let mut i = Input::default();
        i.configure(
            InputConfig::new(InputMode::Index, true, EdgeAction::SetOnNegative),
            0,
            0,
        );
        assert_eq!(i.evaluate(true, 5, false, true), InputAction::None);
        assert_eq!(i.evaluate(true, 4, true, true), InputAction::SetCounter(0));
    }

    #[test]
    fn pin_sources() {
        let stop = InputPin {
            source: InputSource::EndStop {
                position: 100.0,
                positive_end: true,
            },
            actuated_high: false,
        };
        assert!(pin_level(&stop, 0.0, 12));
        assert!(!pin_level(&stop, 100.0, 12));
        let index = InputPin {
            source: InputSource::Index {
                offset: 0.0,
                width: 4.0,
            },
            actuated_high: true,
        };
        assert!(pin_level(&index, 25.0, 12));
        assert!(!pin_level(&index, 30.0, 12));
    }
}
