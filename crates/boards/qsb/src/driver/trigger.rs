//! Position capture and the trigger output: what the counter's events do (MDR1 B4–B7, DIG
//! I/O CONFIG B12), the compare position (DTR), and how the driver counts captures and
//! trigger pulses for the `capture` and `trigger` pins.
//!
//! Command list, "Digital I/O": "Any of the four digital inputs can be configured to
//! capture the current encoder count value upon a positive or negative step change in the
//! digital input state … Digital output, bit 0, can be configured to output a pulse in
//! response to a quadrature counter index, match, underflow or overflow event. The event
//! trigger is enabled in the MDR1 register. The pulse duration is set using the INTERVAL
//! RATE register." MDR1: "B4 Trigger/Capture on Index … B5 Trigger on Match … B6 Trigger
//! on Underflow … B7 Trigger on Overflow"; "Capture-on-index or capture-on-interrupt events
//! cause the current counter value (CNTR) to be copied to the CAPTURE register. Also, an
//! output pulse is generated, on Digital I/O bit 0, if a trigger flag is set. Bit-12, of
//! the DIG I/O CONFIG register, must also be enabled in both cases for an output pulse to
//! occur." DIG I/O CONFIG B12: "a trigger event (see register MDR1) causes an output
//! signal on digital I/O bit 0 for a duration specified by the INTERVAL RATE register. The
//! output pulse polarity depends on the initial output state of digital I/O bit 0." DTR:
//! "In compare operations, whereby compare flag is set, the DTR is compared with the
//! CNTR."
//!
//! How the driver reads them:
//! - **Captures.** CAPTURE is streamed (`S05`: "a new value is output when the register
//!   value changes"). The line that answers `S05` is the register as it is, not a capture;
//!   every later line is one capture (an edge of `capture_input`, or an index with
//!   `capture_index`). A capture of the same count as the one before changes nothing in
//!   the register and sends no line: the command list offers no capture counter or flag,
//!   so it is not seen. Two captures within one data output tick are one line (the
//!   second's count).
//! - **Trigger pulses.** STR is streamed (`S06`, on change); a line with the latch of an
//!   enabled source set (CMP for match, IDX for index, BW for underflow, CY for overflow)
//!   is one pulse, and the driver clears STR (`W093`, CLEAR REG 3) to see the next. Events
//!   until that clear is answered (about one request's round trip) are one.
//! - **The compare position** is DTR in normal operation (free-running or single-cycle
//!   counting: in range-limit and modulo-n DTR is `count_limit`, and "match" is the limit).
//!   A home search and a set-position use DTR themselves: they switch every trigger off
//!   (MDR1 without B4–B7) first, so neither fires the output nor captures, and write DTR
//!   and MDR1 back after them ([`Step::NormalCounter`](super::program::Step::NormalCounter)).
//!   A new compare position ([`Driver::set_pin_value`](motion_drivers::Driver::set_pin_value))
//!   is written when the board runs in normal operation, else after what runs.
//! - The pulse is INTERVAL RATE long: the stream's data output interval
//!   (`stream_interval_ms`), one register for both.

use ::qsb::{DigIoConfig, Mdr1, Register, Str, Write};

use super::QsbDriver;
use motion_drivers::GoalError;

/// The counter's events and what they do (`capture_index`, `trigger_on`,
/// `compare_position`, `trigger_active`; docs/keys/qsb.md "Capture and trigger").
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TriggerSetup {
    /// MDR1 B4 "Trigger/Capture on Index": the index loads CAPTURE (and pulses the output
    /// when `pulse`).
    pub index: bool,
    /// MDR1 B5 "Trigger on Match": CNTR = DTR.
    pub on_match: bool,
    /// MDR1 B6 "Trigger on Underflow".
    pub underflow: bool,
    /// MDR1 B7 "Trigger on Overflow".
    pub overflow: bool,
    /// DIG I/O CONFIG B12 "Trigger pulse enable": the sources above pulse DIG I/O bit 0,
    /// an output, for INTERVAL RATE (the `trigger` pin).
    pub pulse: bool,
    /// The pulse drives bit 0 high (the line rests low between pulses); `false`, the
    /// default: the line rests high (released, the pull-up) and the pulse pulls it low.
    pub active_high: bool,
    /// The compare position, counts (DTR), for `on_match` in free-running or single-cycle
    /// counting.
    pub compare: Option<i32>,
}

impl TriggerSetup {
    /// MDR1 of normal operation, over `base` (its index polarity).
    pub fn mdr1(&self, base: Mdr1) -> Mdr1 {
        Mdr1 {
            trigger_on_index: self.index,
            trigger_on_match: self.on_match,
            trigger_on_underflow: self.underflow,
            trigger_on_overflow: self.overflow,
            ..base
        }
    }

    /// The sources as `motionctl list` shows them (`trigger_on`): "match, index" or
    /// "none".
    pub fn sources_text(&self) -> String {
        let names: Vec<&str> = [
            (self.pulse && self.on_match, "match"),
            (self.pulse && self.index, "index"),
            (self.pulse && self.underflow, "underflow"),
            (self.pulse && self.overflow, "overflow"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect();
        if names.is_empty() {
            "none".to_owned()
        } else {
            names.join(", ")
        }
    }
}

/// The driver's capture and trigger state.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default)]
pub(crate) struct EventState {
    /// Captures seen (CAPTURE stream lines after the one answering `S05`).
    pub captures: u32,
    /// Trigger pulses seen (STR lines with an enabled source's latch set).
    pub pulses: u32,
    /// STR must be cleared before a latch counts: one was counted, or the sources were
    /// just switched on (a clear not answered yet).
    pub latched: bool,
    /// The compare position asked for (counts): the config's, then the clients'.
    pub compare: Option<i32>,
    /// The compare position the board was last seen to take (a DTR write of it
    /// answered), and when.
    pub compare_held: Option<i32>,
    pub compare_at: Option<core::time::Duration>,
}

impl QsbDriver {
    /// MDR1 with no trigger and no capture on index: during a home search and a
    /// set-position, which use DTR and the index themselves.
    pub(super) fn quiet_mdr1(&self) -> Mdr1 {
        Mdr1 {
            invert_index: self.config.invert_index,
            ..Mdr1::default()
        }
    }

    /// MDR1 of normal operation.
    pub(super) fn normal_mdr1(&self) -> Mdr1 {
        self.config.trigger.mdr1(self.quiet_mdr1())
    }

    /// DTR of normal operation: `count_limit` in range-limit and modulo-n, else the
    /// compare position (when match triggers).
    pub(super) fn normal_dtr(&self) -> Option<u32> {
        self.config.counter.dtr().or_else(|| {
            self.events
                .compare
                .filter(|_| self.config.trigger.on_match)
                .map(|c| c as u32)
        })
    }

    /// The first write of normal operation's MDR0, DTR and MDR1 (in that order: a home
    /// search's index stops acting before DTR changes, and the triggers come on last)
    /// the board does not hold.
    pub(super) fn normal_counter_write(&self) -> Option<Write> {
        let dtr = self.normal_dtr().map(Write::Dtr);
        [
            Some(Write::Mdr0(self.config.counter.mdr0())),
            dtr,
            Some(Write::Mdr1(self.normal_mdr1())),
        ]
        .into_iter()
        .flatten()
        .find(|write| !self.holds(*write))
    }

    /// Whether the trigger output's pulses are counted: the board holds DIG I/O CONFIG
    /// with B12 and an MDR1 with a trigger source.
    fn sources_on_board(&self) -> Option<Mdr1> {
        let held = |register: Register| {
            self.board
                .get(usize::from(register.number()))
                .copied()
                .flatten()
        };
        let pulse = held(Register::DigIoConfig)
            .and_then(|data| DigIoConfig::from_data(data).ok())
            .is_some_and(|config| config.trigger_pulse);
        let mdr1 = held(Register::Mdr1).and_then(|data| Mdr1::from_data(data).ok())?;
        pulse.then_some(mdr1)
    }

    /// Whether STR is streamed in normal operation (the trigger's pulses are counted).
    pub(super) fn str_wanted(&self) -> bool {
        self.config.trigger.pulse
    }

    /// A streamed STR line: a pulse when an enabled source's latch is set.
    pub(super) fn trigger_status(&mut self, status: Str) {
        let Some(mdr1) = self.sources_on_board() else {
            return;
        };
        let fired = (status.compare && mdr1.trigger_on_match)
            || (status.index && mdr1.trigger_on_index)
            || (status.borrow && mdr1.trigger_on_underflow)
            || (status.carry && mdr1.trigger_on_overflow);
        if fired && !self.events.latched {
            self.events.pulses = self.events.pulses.wrapping_add(1);
            self.events.latched = true;
        }
    }

    /// MDR1 was written: with a trigger source on, STR is cleared before a latch counts
    /// (a latch set while the sources were off, a home search's, is no pulse).
    pub(super) fn mdr1_written(&mut self, mdr1: Mdr1) {
        if mdr1.trigger_on_index
            || mdr1.trigger_on_match
            || mdr1.trigger_on_underflow
            || mdr1.trigger_on_overflow
        {
            self.events.latched = true;
        }
    }

    /// The STR clear that re-arms the pulse count, when one is due.
    pub(super) fn trigger_clear_due(&self) -> Option<Write> {
        (self.events.latched && self.status.online && self.str_streaming)
            .then_some(Write::Clear(::qsb::ClearTarget::Str))
    }

    /// The DTR write of a compare position asked for while the board runs in normal
    /// operation (MDR1 as normal, no set-position on its way): a home search or a
    /// set-position write it back themselves when they end.
    pub(super) fn compare_due(&self) -> Option<Write> {
        let compare = self
            .events
            .compare
            .filter(|_| self.config.trigger.on_match)?;
        if self.config.counter.dtr().is_some() || !self.status.online || !self.preset.is_empty() {
            return None;
        }
        let normal = self.holds(Write::Mdr1(self.normal_mdr1()))
            && self.holds(Write::Mdr0(self.config.counter.mdr0()));
        let write = Write::Dtr(compare as u32);
        (normal && !self.holds(write)).then_some(write)
    }

    /// A DTR write the board took: the compare position when it is that.
    pub(super) fn dtr_written(&mut self, value: u32, now: core::time::Duration) {
        if self.config.trigger.on_match
            && self.config.counter.dtr().is_none()
            && self.events.compare == Some(value as i32)
        {
            self.events.compare_held = Some(value as i32);
            self.events.compare_at = Some(now);
        }
    }

    /// [`Driver::set_pin_value`](motion_drivers::Driver::set_pin_value) of the trigger
    /// pin: a new compare position, counts.
    pub(super) fn set_compare(
        &mut self,
        pin: motion_drivers::Pin,
        counts: f64,
    ) -> Result<(), GoalError> {
        let trigger = self.config.trigger;
        if !trigger.on_match || self.config.counter.dtr().is_some() {
            return Err(GoalError::NoSuchPin(pin));
        }
        self.check_online()?;
        let value = motion_base::counts_to_i32(counts).ok_or(GoalError::OutOfBoardRange(
            motion_drivers::GoalKind::Position,
        ))?;
        self.events.compare = Some(value);
        Ok(())
    }
}
