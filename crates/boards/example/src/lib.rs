//! The worked example of a motiond board.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod codec;
pub mod sim;
