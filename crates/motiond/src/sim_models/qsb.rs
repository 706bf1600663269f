//! A simulated QSB as its `[[device]]` and axis describe it.

use motion_sim::qsb::{QsbSim, QsbSimConfig};

use crate::config::{DeviceSpec, ServerConfig};

/// The model of qsb device `index`.
pub(super) fn model(config: &ServerConfig, index: usize, device: &DeviceSpec) -> QsbSim {
    let _ = (config, index);
    QsbSim::new(QsbSimConfig {
        seed: device.sim_seed,
        ..QsbSimConfig::default()
    })
}
