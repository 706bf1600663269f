//! The simulated boards behind `type = "sim"` links, built from the config: one module per
//! board model (`model`), reached through the model registry (boards.rs, `sim_link`).

pub(crate) mod qq2drv;
pub(crate) mod qsb;
pub(crate) mod spimotor;
pub(crate) mod tmcpack;
