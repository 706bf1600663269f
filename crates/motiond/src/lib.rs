//! motiond, the real-time motion server: config, links, the timed loop around
//! `motion_engine::Engine::step`, iceoryx2 services.
#![warn(missing_docs)]
#![deny(unsafe_code)] // one exception: estop_watch.rs (borrowing the listener's descriptor), with a SAFETY note

pub mod app;
pub mod command_port;
pub mod error;
pub mod estop_watch;
pub mod inbox;
pub mod io;
pub mod node_records;
pub mod params;
pub mod paths;
pub mod phases;
pub mod references;
pub mod rt;
pub mod secret;
pub mod services;
pub mod setpoints;
pub mod stats;
pub mod systemd;
pub mod tick;

/// The service type motiond runs on: inter-process shared memory, single-threaded ports
/// (every port lives on the tick thread).
pub type Ipc = iceoryx2::prelude::ipc::Service;
