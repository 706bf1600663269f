//! Commissioning: changes of a board's own settings that outlive the server — its bus
//! address, its line rate, a reset to its factory settings — asked of a driver with
//! [`Driver::commission`](crate::Driver::commission) (`motionctl commission`).
//!
//! A driver that takes one sends it to the board and then finds the board again where it
//! now answers (the new address, the new rate; after a factory reset, its factory rate):
//! until then its status is not online, and a board not found is reported
//! [`DeviceFault::NotResponding`](crate::DeviceFault::NotResponding) as at start-up. The
//! config still names the old setting: the client tells its user what to put there.

use core::fmt;

/// One change of a board's own settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Commission {
    /// A new bus address (the Trinamic pack's `$42`, the SPI_motor's 0xf1/0xf2/0xf0
    /// sequence), in the form the config's `address` key takes.
    Address(u32),
    /// A new line rate, baud (the Trinamic pack's `$40`); the link follows.
    Baud(u32),
    /// Back to the factory settings (the Trinamic pack's `$CC`: every parameter, the
    /// address from the rotary switches, 19200 baud).
    FactoryReset,
}

impl Commission {
    /// The change's name as the CLI and the command's `values[0]` spell it.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Address(_) => "address",
            Self::Baud(_) => "baud",
            Self::FactoryReset => "factory reset",
        }
    }
}

/// Why a driver refused a [`Commission`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CommissionError {
    /// The board has no such setting (or none the driver can change).
    Unsupported,
    /// A value the board does not take (an address outside its range, a rate its manual
    /// does not list).
    OutOfRange,
    /// The board is not answering (or its link is down).
    Offline,
    /// The board is still starting (probing, configuring), or busy with an earlier change.
    Starting,
}

impl fmt::Display for CommissionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Unsupported => "the board cannot change this setting",
            Self::OutOfRange => "the board does not take this value",
            Self::Offline => "the board is offline",
            Self::Starting => "the board is starting or busy with an earlier change",
        })
    }
}

impl std::error::Error for CommissionError {}
