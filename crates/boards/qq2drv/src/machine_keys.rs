//! The QuadQuad2Drv's machine keys as the server validated them: `None` fields were not set
//! (the driver's default applies). Values are in the config's terms; the driver's
//! `Qq2drvDriverConfig::from_spec` converts them. The server holds them opaquely in
//! `motion_drivers::spec::MachineKeys`.

use qq2drv::limits::VelocityRampSign;

/// The qq2drv keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Qq2drvDeviceKeys {
    /// `velocity_ramp`: how the board reads packet 36's Velocity, `"signed"` (default) or
    /// `"unsigned"` ("Range: 0 - 100,000").
    pub velocity_ramp: Option<VelocityRampSign>,
    /// `silence_ms`: how long the board may say nothing before it is declared not
    /// answering.
    pub silence: Option<core::time::Duration>,
}

/// One PID table as given; `None` fields were not set (the datasheet default applies).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PidKeys {
    /// Proportional constant.
    pub p: Option<u16>,
    /// Integration constant.
    pub i: Option<u16>,
    /// Differential constant.
    pub d: Option<u16>,
    /// Integration windup limit (position PID only).
    pub windup: Option<u16>,
}

/// The qq2drv keys of one `[[axis]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Qq2drvAxisKeys {
    /// `pid_position` (packet 30).
    pub pid_position: PidKeys,
    /// `pid_velocity` (packet 32).
    pub pid_velocity: PidKeys,
    /// `power_limit`, fraction of full power 0.0..=1.0 (packet 24).
    pub power_limit: Option<f64>,
}
