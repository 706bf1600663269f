//! The machine keys of each model as the server validated them: `None` fields were not set
//! (the driver's default applies). Values are in the config's terms (units, ms, %); the
//! drivers convert them.

use core::any::Any;
use core::fmt;
use core::time::Duration;
use std::sync::Arc;

use super::{PackVariant, QsbInputMode, QsbVariant, SpiDrive};

/// A device's or an axis's model-specific keys, validated: whatever typed struct its
/// board's crate defines (`TmcpackDeviceKeys`, `Qq2drvAxisKeys`, …), or none. The board
/// that validated the keys reads them back with [`get`](Self::get); nobody else needs to
/// know their type, so a board brings its keys without a variant here.
#[derive(Clone, Default)]
pub struct MachineKeys(Option<Arc<dyn AnyKeys>>);

/// The device-level [`MachineKeys`] (a `[[device]]`'s model keys).
pub type DeviceMachine = MachineKeys;
/// The axis-level [`MachineKeys`] (an `[[axis]]`'s model keys).
pub type AxisMachine = MachineKeys;

/// What keys a [`MachineKeys`] can hold: any comparable, printable, shareable value.
trait AnyKeys: Any + fmt::Debug + Send + Sync {
    fn as_any(&self) -> &dyn Any;
    fn same_as(&self, other: &dyn AnyKeys) -> bool;
}

impl<T: Any + fmt::Debug + PartialEq + Send + Sync> AnyKeys for T {
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn same_as(&self, other: &dyn AnyKeys) -> bool {
        other.as_any().downcast_ref::<T>() == Some(self)
    }
}

impl MachineKeys {
    /// No model keys (a model that has none).
    pub const PLAIN: Self = Self(None);

    /// `keys`, as a board's crate validated them.
    pub fn new<T: Any + fmt::Debug + PartialEq + Send + Sync>(keys: T) -> Self {
        Self(Some(Arc::new(keys)))
    }

    /// The keys, when they are a `T`.
    pub fn get<T: Any>(&self) -> Option<&T> {
        self.0.as_deref()?.as_any().downcast_ref::<T>()
    }

    /// The keys as a `T`, or `T`'s default (every key unset) when they are none or another
    /// type.
    pub fn get_or_default<T: Any + Clone + Default>(&self) -> T {
        self.get::<T>().cloned().unwrap_or_default()
    }
}

impl PartialEq for MachineKeys {
    fn eq(&self, other: &Self) -> bool {
        match (&self.0, &other.0) {
            (None, None) => true,
            (Some(a), Some(b)) => a.same_as(b.as_ref()),
            _ => false,
        }
    }
}

impl fmt::Debug for MachineKeys {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.0 {
            None => f.write_str("MachineKeys::PLAIN"),
            Some(keys) => keys.fmt(f),
        }
    }
}

/// `ready_output = { motors, reference }`: TTLOUT1 as the ready output ($32 P3, $33).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadyOutputKeys {
    /// $33 P0: bit n = motor n's activity switches the output.
    pub motors: u8,
    /// $33 P1: bit n = motor n's reference search switches the output.
    pub reference: u8,
}

/// The tmcpack keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TmcpackDeviceKeys {
    /// `variant`: SIXpack (default) or QUADpack.
    pub variant: PackVariant,
    /// Response address of the driver's queries.
    pub reply_address: Option<u8>,
    /// $40 transmitter switch-over delay, ms (even, 2..=2000).
    pub switchover_ms: Option<u16>,
    /// $41 packet timeout, ms (even, 4..=131070).
    pub packet_timeout_ms: Option<u32>,
    /// TTLOUT1 as the ready output.
    pub ready_output: Option<ReadyOutputKeys>,
}

/// `current = { … }` ($10, $11).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CurrentKeys {
    /// Peak current, % of the pack's full scale.
    pub peak: Option<f64>,
    /// I0, % of the peak current: on standby (a level of $11: 100, 75, 50, 38, 25, 19, 13, 9
    /// or 0).
    pub standby: Option<u8>,
    /// I1: at standstill.
    pub standstill: Option<u8>,
    /// I2: at constant velocity.
    pub constant: Option<u8>,
    /// I3: accelerating.
    pub accel: Option<u8>,
    /// T0, ms (even, 2..=131070).
    pub standby_delay_ms: Option<u32>,
}

/// `reference = { … }` ($15, $16, $18); `side` is resolved into the axis's `HomeSpec`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ReferenceKeys {
    /// NullPositive: the switch is active at a high level.
    pub active_high: Option<bool>,
    /// NullCenter.
    pub center: Option<bool>,
    /// StopNull.
    pub stop_at_switch: Option<bool>,
    /// StopSoft.
    pub soft_stop: Option<bool>,
    /// $16 de-bounce, ms (even, 0..=30).
    pub debounce_ms: Option<u16>,
    /// $18 nulloffset, units.
    pub null_offset: Option<f64>,
    /// $18 testnullrange, units.
    pub test_range: Option<f64>,
    /// FastRef.
    pub fast: Option<bool>,
    /// MechRef.
    pub mechanical: Option<bool>,
}

/// The tmcpack keys of one `[[axis]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TmcpackAxisKeys {
    /// `current`.
    pub current: CurrentKeys,
    /// `reference`.
    pub reference: ReferenceKeys,
    /// $15 motor type bit 1.
    pub rotary: Option<bool>,
    /// Units per revolution of a rotary axis (given, or 360 for unit "deg").
    pub revolution: Option<f64>,
    /// $31 left minimum, ADC counts.
    pub analog_stop_left: Option<u16>,
    /// $31 right maximum, ADC counts.
    pub analog_stop_right: Option<u16>,
}

/// The qsb keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct QsbDeviceKeys {
    /// `variant`: the product (QSB-M by default).
    pub variant: QsbVariant,
    /// `counts_per_step`: encoder counts (x4) per motor step, finite, not 0.
    pub counts_per_step: Option<f64>,
    /// `index_polarity = "inverted"` (MDR1 B3).
    pub index_inverted: Option<bool>,
    /// `stream_interval_ms` rounded to whole 1/512 s ticks (1..=0xFFFE).
    pub stream_interval_ticks: Option<u16>,
    /// `host_latency_ms`.
    pub host_latency: Option<Duration>,
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
}

/// The spimotor keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SpimotorDeviceKeys {
    /// `drive`: one stepper (default) or two brushed motors.
    pub drive: SpiDrive,
    /// `intensity`: stepper drive intensity, port 0x10 (0..=255).
    pub intensity: Option<u8>,
    /// `coils`: coils driven at a time, 1 or 2 (port 0x44).
    pub coils: Option<u8>,
}
