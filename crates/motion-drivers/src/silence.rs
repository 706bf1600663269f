//! How long a board may say nothing while it owes an answer before its driver declares it
//! not answering: the default and the range of the `silence_ms` device key (qsb, qq2drv,
//! spimotor; docs/ARCHITECTURE.md "What evidence each board verdict needs"); and how much
//! later than on the wire an answer may reach its driver, `host_latency_ms` (qsb, tmcpack).
//!
//! A reply delayed on the host is not a silent board: a server or a board's process (a
//! pty- or socket-served emulator) without CPU holds every byte back, then hands them over
//! at once, in order. The issue that asked for this (39) saw such stalls up to 200 ms on a
//! loaded two-core machine without SCHED_FIFO; the development machines' cyclictest max
//! wake-up latency is 4–100 ms per 30 s (docs/ARCHITECTURE.md "Measured on the development
//! machines"). 500 ms is more than twice the longest stall a verdict must survive; what it
//! costs is the time a board that really went silent is reported `not-answering` — the
//! axis shows `STALE` after its refresh budget long before, and nothing could have been
//! sent to a board that owes an answer anyway (one request at a time).

use core::ops::RangeInclusive;
use core::time::Duration;

/// The default of `silence_ms`.
pub const DEFAULT_SILENCE: Duration = Duration::from_millis(500);

/// The values `silence_ms` takes, milliseconds: at least the longest reply window of the
/// boards' drivers with room for a scheduling hiccup, at most a minute.
pub const SILENCE_RANGE_MS: RangeInclusive<i64> = 100..=60_000;

/// The default of `host_latency_ms`: how much later than on the wire an answer may reach
/// the driver (the serial or USB adapter, the I/O thread), part of every reply window.
pub const DEFAULT_HOST_LATENCY: Duration = Duration::from_millis(5);

/// The values `host_latency_ms` takes, milliseconds.
pub const HOST_LATENCY_RANGE_MS: RangeInclusive<f64> = 0.0..=1000.0;
