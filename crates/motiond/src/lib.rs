//! motiond, the real-time motion server: config, links, the timed loop around
//! `motion_engine::Engine::step`, iceoryx2 services.
#![forbid(unsafe_code)]

pub mod config;
