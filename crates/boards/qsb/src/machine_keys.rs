//! The QSB's machine keys as the server validated them: `None` fields were not set (the
//! driver's default applies). Values are in the config's terms (units, ms, %); the
//! driver's `from_spec` converts them. The server holds them opaquely in
//! `motion_drivers::spec::MachineKeys`.

use core::time::Duration;

use qsb::{CountMode, CycleMode, IndexMode};

/// QSB product variant (command list "QSB Variations").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum QsbVariant {
    /// QSB-M: single-ended encoder, 4-bit digital I/O, stepper step/direction outputs.
    #[default]
    M,
    /// QSB-S: single-ended encoder only.
    S,
    /// QSB-D: differential encoder, 1-bit digital I/O.
    D,
}

impl QsbVariant {
    /// The config name.
    pub const fn id(self) -> &'static str {
        match self {
            Self::M => "qsb-m",
            Self::S => "qsb-s",
            Self::D => "qsb-d",
        }
    }
}

/// What a QSB's encoder input reads (`input_mode`, MODE B1 B0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum QsbInputMode {
    /// Quadrature: a counter, the axis's position.
    #[default]
    Quadrature,
    /// PWM: the duty cycle as an absolute value (the `encoder` pin).
    Pwm,
    /// Analog: the voltage as an absolute value (the `encoder` pin).
    Analog,
}

impl QsbInputMode {
    /// The config name.
    pub const fn id(self) -> &'static str {
        match self {
            Self::Quadrature => "quadrature",
            Self::Pwm => "pwm",
            Self::Analog => "analog",
        }
    }
}

/// The qsb keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct QsbDeviceKeys {
    /// `variant`: the product (QSB-M by default).
    pub variant: QsbVariant,
    /// `counts_per_step`: counter counts (in `count_mode`) per motor step, finite, not 0.
    pub counts_per_step: Option<f64>,
    /// `index_polarity = "inverted"` (MDR1 B3).
    pub index_inverted: Option<bool>,
    /// `stream_interval_ms` rounded to whole 1/512 s ticks (1..=0xFFFE).
    pub stream_interval_ticks: Option<u16>,
    /// `host_latency_ms`.
    pub host_latency: Option<Duration>,
    /// `silence_ms`: how long the board may say nothing while it owes an answer.
    pub silence: Option<Duration>,
    /// `enable_output`: the DIG I/O bit (0 or 3) of the stepper driver's enable line.
    pub enable_output: Option<u8>,
    /// `enable_active = "high"`.
    pub enable_active_high: Option<bool>,
    /// `input_mode` (MODE B1 B0).
    pub input_mode: Option<QsbInputMode>,
    /// `capture_input`: the DIG I/O bit whose edge loads CAPTURE.
    pub capture_input: Option<u8>,
    /// `capture_edge = "falling"`.
    pub capture_falling: Option<bool>,
    /// `count_mode` (MDR0 B1 B0).
    pub count_mode: Option<CountMode>,
    /// `count_range` (MDR0 B3 B2).
    pub count_range: Option<CycleMode>,
    /// `count_limit`: DTR of range-limit and modulo-n (1..=0x7FFFFFFF).
    pub count_limit: Option<u32>,
    /// `index_action` (MDR0 B5 B4 in normal operation).
    pub index_action: Option<IndexMode>,
    /// `index_sync = "synchronous"` (MDR0 B6).
    pub index_sync: Option<bool>,
    /// `capture_index = true` (MDR1 B4: the index loads CAPTURE).
    pub capture_index: Option<bool>,
    /// `trigger_on`: the counter events that pulse DIG I/O bit 0 (MDR1 B4–B7, DIG I/O
    /// CONFIG B12); `None` or empty: no trigger output.
    pub trigger_on: Option<TriggerSources>,
    /// `compare_position`: the position (axis units) at which "match" fires (DTR).
    pub compare_position: Option<f64>,
    /// `trigger_active = "high"`.
    pub trigger_active_high: Option<bool>,
}

/// The counter events of `trigger_on` (MDR1 B4–B7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TriggerSources {
    /// `"index"`: B4 "Trigger/Capture on Index".
    pub index: bool,
    /// `"match"`: B5 "Trigger on Match" (CNTR = DTR).
    pub on_match: bool,
    /// `"underflow"`: B6 "Trigger on Underflow".
    pub underflow: bool,
    /// `"overflow"`: B7 "Trigger on Overflow".
    pub overflow: bool,
}

impl TriggerSources {
    /// Whether any source is set.
    pub const fn any(self) -> bool {
        self.index || self.on_match || self.underflow || self.overflow
    }
}
