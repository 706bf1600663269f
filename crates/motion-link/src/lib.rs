//! Byte transports for motiond (work in progress).
#![forbid(unsafe_code)]

pub mod sim;
