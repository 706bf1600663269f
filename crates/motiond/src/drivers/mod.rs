//! One driver per configured device, configured from its axes and machine keys: one module
//! per board model (`build`, `describe`), reached through the model registry (boards.rs).

pub(crate) mod qq2drv;
pub(crate) mod qsb;
pub(crate) mod spimotor;
pub(crate) mod tmcpack;

pub use tmcpack::driver_config as tmcpack_driver_config;

use crate::config::{DeviceSpec, Owner, ServerConfig, Transport};

/// One effective machine parameter, as `motionctl list` shows it: the key as the config
/// spells it (dotted for tables: `current.standstill`) on its device or axis, and the value
/// the driver uses, with its unit (`"50 %"`, `"-4"`, `"left"`). Whether the value came from
/// the config or is the default is decided from [`ServerConfig::given`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamRow {
    /// The device or axis.
    pub owner: Owner,
    /// Config key.
    pub key: String,
    /// Effective value.
    pub value: String,
}

/// Velocity and acceleration limits of `device`'s channel `channel` in counts, from the axis
/// that drives it.
fn channel_limits(config: &ServerConfig, device: usize, channel: usize) -> Option<(f64, f64)> {
    config
        .axes
        .iter()
        .find(|axis| axis.device == device && axis.channel == channel)
        .map(|axis| {
            let scale = axis.counts_per_unit.abs();
            (axis.max_velocity * scale, axis.max_accel * scale)
        })
}

/// The line rate of `device`'s link (baud or SPI clock), when the config gives one.
fn line_rate(config: &ServerConfig, device: &DeviceSpec) -> Option<u32> {
    match &config.links.get(device.link)?.transport {
        Transport::Serial { baud, .. } => Some(*baud),
        Transport::Spidev { speed_hz, .. } => Some(*speed_hz),
        Transport::Sim { rate } => Some(*rate),
        Transport::SpiSocket { .. } => None,
    }
}
