//! The flight recorder ("black box", docs/ARCHITECTURE.md "The black box"): the tick
//! journals every input it hands the engine and every output it takes into a lock-free
//! queue ([`journal`]); a recorder thread keeps the last `[server] blackbox_seconds` of it
//! ([`recorder`]) and writes it to MCAP ([`file`]) on a fault, an e-stop, SIGUSR2 or a
//! clean exit; `motiond --replay` feeds a saved journal through the same drivers and engine
//! and compares every output ([`replay`]).
#![warn(missing_docs)]

pub mod digest;
pub mod directory;
pub mod file;
pub mod journal;
pub mod record;
pub mod recorder;
pub mod replay;
pub mod ring;

pub use file::{BlackboxFile, Recording, SaveError, read};
pub use journal::Journal;
pub use recorder::{RecorderSetup, SaveReason};
pub use replay::{Divergence, ReplayError, Replayed, replay};
pub use ring::Ring;
