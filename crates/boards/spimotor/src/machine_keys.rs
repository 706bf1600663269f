//! The SPI_motor's machine keys as the server validated them: `None` fields were not set (the
//! driver's default applies). Values are in the config's terms (units, ms, %); the
//! driver's `from_spec` converts them. The server holds them opaquely in
//! `motion_drivers::spec::MachineKeys`.

/// SPI_motor drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum SpiDrive {
    /// One stepper, channel 0.
    #[default]
    Stepper,
    /// Two brushed motors: channels 0 = A, 1 = B.
    Brushed,
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
    /// `silence_ms`: how long a transaction's MISO may stay away before the board is
    /// declared not answering.
    pub silence: Option<core::time::Duration>,
}
