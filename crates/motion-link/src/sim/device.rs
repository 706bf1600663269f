//! The interface between a simulated wire and a device model.
//!
//! A model (crate `motion-sim`) implements one of these traits; a simulated link, a shared
//! bus or the `motion-sim` binary (pty / SPI socket server) drives it. Time is always passed
//! in as the duration since an arbitrary epoch of the caller's clock; a model never reads a
//! clock itself, and `now` never decreases from one call to the next.

use core::time::Duration;

/// A device model attached to a byte-stream wire: RS-232, RS-485 multi-drop, USB CDC.
pub trait StreamDevice: Send {
    /// `bytes` finished arriving at the device's receiver at `now`. The caller has already
    /// charged their wire time; on a shared bus this includes bytes other devices sent.
    fn receive(&mut self, now: Duration, bytes: &[u8]);

    /// Advances the model to `now` and moves into `out` the bytes whose transmission the
    /// device has started at or before `now`. Returns how many were written; bytes that do
    /// not fit stay queued in the model for the next call.
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize;

    /// The earliest instant at which the model will have something new to transmit or its
    /// state changes by itself (a reply after its processing time, a stream interval), so a
    /// server can sleep until then. `None`: nothing scheduled.
    fn next_event(&self, now: Duration) -> Option<Duration>;

    /// The line rate the device is listening at, in baud, when the model knows it (a baud
    /// change command moves it). A wire whose rate differs delivers garbled bytes.
    fn baud(&self) -> Option<u32> {
        None
    }

    /// The host's side of the wire runs at `baud` from now on (said when a
    /// [`SimLink`](crate::sim::SimLink) is made and at each of its
    /// [`set_baud`](crate::Link::set_baud)). A bus uses it to garble what crosses between the
    /// line and a device at another rate; a single device needs nothing (the link garbles
    /// what crosses at another rate than [`baud`](Self::baud)). By default nothing.
    fn line_rate(&mut self, baud: u32) {
        let _ = baud;
    }
}

/// A device model on an SPI bus. One call is one chip-select assertion.
pub trait SpiDevice: Send {
    /// Clocks `mosi` into the device while `miso` (same length) is clocked out, the
    /// transaction completing at `now`. Returns `true` when the device drove MISO, `false`
    /// when it left the line floating (another address on a shared bus); `miso` is then
    /// left untouched.
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool;

    /// Advances the model's physics to `now` without a transaction.
    fn advance(&mut self, now: Duration);
}
