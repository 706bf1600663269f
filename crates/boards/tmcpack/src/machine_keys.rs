//! The Trinamic pack's machine keys as the server validated them: `None` fields were not set (the
//! driver's default applies). Values are in the config's terms (units, ms, %); the
//! driver's `from_spec` converts them. The server holds them opaquely in
//! `motion_drivers::spec::MachineKeys`.

/// Trinamic pack variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PackVariant {
    /// SIXpack: 6 motors.
    #[default]
    Sixpack,
    /// QUADpack: 4 motors.
    Quadpack,
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
    /// `$14` divisor of the pack's firmware: 64 (the `$14` text) or 16 (7.1's defaults).
    pub amax_divisor: Option<u8>,
    /// `$15` P6 bit of StopNoRef in the pack's firmware: 5 (the table) or 6 (the prose).
    pub stop_no_ref_bit: Option<u8>,
    /// `power_down`: the `$45` power-down mode.
    pub power_down: Option<PowerDownMode>,
    /// `microstep_table`: the 16 entries of the `$17` motor characteristics table.
    pub microstep_table: Option<[u8; 16]>,
    /// `$40` rate the pack is switched to at start-up, baud (the link follows).
    pub baud: Option<u32>,
    /// `host_latency_ms`: how much later than on the wire an answer may reach the driver.
    pub host_latency_ms: Option<f64>,
    /// `silence_ms`: the silence before the pack is declared not answering.
    pub silence_ms: Option<u32>,
}

/// `power_down` (manual 8.6 `$45`): what the driver asks of the pack's power-down mode.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum PowerDownMode {
    /// No `$45` at all (the default): the pack's own setting, off after a reset.
    #[default]
    Off,
    /// Bit 2 at start-up: the pack stops its motors and saves their positions in EEPROM when
    /// the supply falls below 13 V; the saved positions are invalidated at start-up (bit 1)
    /// and never loaded.
    Save,
    /// As `Save`, and after the pack booted (`$43` reset flag) bit 0 loads the saved
    /// positions first: an axis counts as referenced when the pack answers that it loaded
    /// valid ones (and `reference.restore` is not false on it).
    Restore,
}

/// `position_mode`: how a `position` goal (the board's own controller) is run.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum PositionMode {
    /// `$14`, `$26`, `$23`: the trapezoidal ramp at the axis limits (the default).
    #[default]
    Ramp,
    /// `$24`: the pack's PI controller on the target, reprogrammed on the fly by every
    /// new target; a group's path is followed with a target every exchange.
    Pi,
}

/// `pi = { propdiv, intdiv, intclip, intinpclip }` (`$19`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PiKeys {
    /// propdiv 1..=255.
    pub propdiv: Option<u8>,
    /// intdiv 1..=32767.
    pub intdiv: Option<u16>,
    /// intclip 1..=32767.
    pub intclip: Option<u16>,
    /// intinpclip 0..=255.
    pub intinpclip: Option<u8>,
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
    /// Positions the pack restores from EEPROM count as referenced on this axis
    /// (`power_down = "restore"`).
    pub restore: Option<bool>,
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
    /// `$13` vstart as a speed, units/s.
    pub start_velocity: Option<f64>,
    /// How `position` goals are run.
    pub position_mode: Option<PositionMode>,
    /// `$19` PI parameters.
    pub pi: PiKeys,
}
