//! One driver per configured device.

use anyhow::bail;
use motion_drivers::{Driver, Model};

use crate::config::ServerConfig;

/// Builds the drivers of `config`'s devices, in config order.
pub fn build(config: &ServerConfig) -> anyhow::Result<Vec<Box<dyn Driver>>> {
    let drivers: Vec<Box<dyn Driver>> = Vec::with_capacity(config.devices.len());
    if let Some(device) = config.devices.first() {
        match device.model {
            Model::Qq2drv | Model::Tmcpack | Model::Spimotor | Model::Qsb => bail!(
                "device `{}`: the {} driver is not built yet (issue \"Board drivers and the deterministic engine\")",
                device.name,
                device.model
            ),
        }
    }
    Ok(drivers)
}
