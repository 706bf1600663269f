//! The dependency-free base every motiond crate shares: fixed-capacity helpers and the few
//! plain facts that crates which must not depend on each other all speak (drivers,
//! protocol crates and simulators use it without pulling in iceoryx2; `motion-ipc`,
//! `motion-link` and `motion-drivers` re-export what their users need).
//!
//! - [`FixedQueue`]: a bounded FIFO of `Copy` items that never allocates; a full queue
//!   refuses.
//! - [`write_text`] / [`read_text`] / [`FixedText`]: UTF-8 text in a fixed buffer, always
//!   cut on a character boundary.
//! - [`counts_to_i32`] / [`counts_to_i32_saturating`]: a position in counts as a board's
//!   signed 32-bit register.
//! - [`parse_duration`]: `500ms`, `10s`, `2m` as the command-line tools take them.
//! - [`LinkKind`] (stream or SPI) and [`SignalKind`] (digital in/out, analogue in): one
//!   enum each for what the links, the drivers, the engine and the shared-memory contract
//!   all mean.
//! - [`Model`] / [`ModelFacts`]: a board model, with its config id, contract code and link
//!   kind (an open set: board crates declare their own).
//! - [`CanRecord`] / [`LinkFraming`]: a CAN frame as the fixed 16 bytes a CAN link moves,
//!   and whether a link frames its boards' messages as bytes or as CAN frames.
//!
//! ```
//! use motion_base::{FixedQueue, FixedText, counts_to_i32};
//! use core::fmt::Write;
//!
//! let mut queue = FixedQueue::<u8, 2>::new();
//! assert!(queue.push(1) && queue.push(2) && !queue.push(3));
//! assert_eq!(queue.pop(), Some(1));
//!
//! let mut text = FixedText::<4>::new();
//! let _ = write!(text, "aéé");
//! assert_eq!(text.as_str(), "aé");
//!
//! assert_eq!(counts_to_i32(12.6), Some(13));
//! assert_eq!(counts_to_i32(f64::NAN), None);
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod can;
mod counts;
mod duration;
mod kinds;
mod model;
mod queue;
pub mod serde_boxed_array;
mod text;

pub use can::{CAN_RECORD_LEN, CAN_SFF_MAX, CanRecord, LinkFraming};
pub use counts::{counts_to_i32, counts_to_i32_saturating};
pub use duration::parse_duration;
pub use kinds::{LinkKind, SignalKind, UnknownKind};
pub use model::{Model, ModelFacts, UnknownModel};
pub use queue::FixedQueue;
pub use text::{FixedText, floor_char_boundary, read_text, write_text};
