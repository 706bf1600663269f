//! What every board's sans-I/O driver shares: the [`Driver`] trait, its goals, pins and
//! state, the [`LinkBus`], and the neutral machine description a driver is built from
//! ([`spec`]). The drivers themselves live in their board crates
//! (`crates/boards/<board>/src/driver/`, docs/ARCHITECTURE.md "How to add a board").
//!
//! A driver implements [`Driver`]: goals in counts ([`Goal`]), received bytes and `now` in;
//! bytes to send and [`ChannelState`] out. Drivers never read a clock and never touch a
//! file descriptor. A [`LinkBus`] puts several drivers on one link and enforces what no
//! single driver sees: one request in flight on a shared serial bus, commands before polls,
//! MISO bytes back to the transaction's owner.
//!
//! The four boards' driver modules share one skeleton:
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | the module docs (wire, start-up, goals, faults), the driver struct and its `impl Driver`, whose methods hand over to the files below |
//! | `config.rs` | the driver's config and what is derived from it (scales, budgets, wire times) |
//! | `startup.rs` | the probe / version / configuration sequence, going online, restarts and resets |
//! | `goals.rs` | the goals a channel accepts, a goal turned into a plan of wire traffic (`set_goal`, `set_output`) |
//! | `rx.rs` | received bytes and answers decoded into channel and board state; unanswered requests |
//! | `wire.rs` | requests and transactions in flight, which one goes next (commands before polls), the poll plan and the passing of time |
//! | `spec.rs` | the driver config built from the neutral [`spec::DriverSpec`] (`from_spec`: unit conversions, protocol encodings), the board facts a config is validated against, and `params` (the effective machine parameters) |
//!
//! Board-specific parts sit beside them: the pin tables (`pins.rs` / `io.rs`), per-channel
//! state machines (board-qq2drv's and board-tmcpack's `channel.rs`, board-spimotor's
//! `stepper.rs` and `brushed.rs`), the stepper's rate profile (board-spimotor's `ramp.rs`),
//! the QSB's encoder track and request programs (board-qsb's `encoder.rs`, `program.rs`).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod bus;
mod commission;
mod driver;
mod goal;
mod late;
mod pin;
mod silence;
pub mod spec;
mod stamps;
mod state;

pub use bus::{LinkBus, MAX_SENDS_PER_STEP, SPI_PENDING_CAPACITY, UNWRITTEN_CAPACITY, Unwritten};
pub use commission::{Commission, CommissionError};
pub use driver::{
    Driver, Follow, LINE_RATE_TOLERANCE, LineLeg, MESSAGE_LEN, Model, Priority, SavedReference,
    Transmit,
};
pub use goal::{Goal, GoalError, GoalKind, GoalKinds, RateFloor};
pub use late::{LATE_ANSWERS, LATE_PREFIX_LEN, LateAnswer};
/// Whether a link carries a byte stream or SPI transactions (one enum with `motion_link`).
pub use motion_base::LinkKind;
pub use motion_base::{CanRecord, LinkFraming};
pub use pin::{Pin, PinInfo, PinReading, SignalKind, SignalKinds, find_pin};
pub use silence::{DEFAULT_HOST_LATENCY, DEFAULT_SILENCE, HOST_LATENCY_RANGE_MS, SILENCE_RANGE_MS};
pub use stamps::IoStamps;
pub use state::{
    ChannelState, DeviceFault, DeviceStatus, EVIDENCE_LEN, FIRMWARE_LEN, Seconds, Verdict,
};
