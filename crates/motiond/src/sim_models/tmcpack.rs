//! A simulated Trinamic pack as its `[[device]]` and axes describe it.

use motion_sim::tmcpack::{TmcpackSim, TmcpackSimConfig};

use crate::config::{DeviceSpec, PackVariant, ServerConfig};

/// The model of tmcpack device `index`.
pub(super) fn model(config: &ServerConfig, index: usize, device: &DeviceSpec) -> TmcpackSim {
    let _ = (config, index);
    TmcpackSim::new(TmcpackSimConfig {
        address: device.address as u8,
        variant: match device.variant {
            PackVariant::Sixpack => tmcpack::Variant::SixPack,
            PackVariant::Quadpack => tmcpack::Variant::QuadPack,
        },
        seed: device.sim_seed,
        ..TmcpackSimConfig::default()
    })
}
