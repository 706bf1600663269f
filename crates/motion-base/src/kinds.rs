//! The plain facts that crates which must not depend on each other all speak: whether a
//! link carries a byte stream or SPI transactions ([`LinkKind`]) and what a board pin or a
//! configured signal is ([`SignalKind`]). One enum each, re-exported where each crate's
//! users look for it (`motion_link`, `motion_drivers`, `motion_ipc`).

use core::fmt;

/// Whether a link carries a byte stream or SPI transactions.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LinkKind {
    /// A byte stream (RS-232, RS-485, USB CDC): writes queue bytes, reads return whatever
    /// the device sent; one request in flight on a shared bus.
    Stream,
    /// SPI: every write is one chip-select assertion, and the same number of MISO bytes
    /// becomes readable; they belong to the transaction's owner.
    Spi,
}

impl fmt::Display for LinkKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Stream => "stream",
            Self::Spi => "spi",
        })
    }
}

/// What a pin can be used as, and the kind of a configured signal. Travels as its `u8`
/// value in the shared-memory contract (`SignalState::kind`, `SignalInfo::kind`).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum SignalKind {
    /// A digital input (a switch, a jumper, a board status bit): value 0.0 or 1.0 after
    /// `invert`.
    DigitalIn = 1,
    /// A digital output (open drain, TTL): value 0.0 or 1.0 as commanded (after
    /// `invert`), set with `SetOutput`.
    DigitalOut = 2,
    /// An analogue input (ADC counts on the board): value = raw × scale + offset, in the
    /// signal's unit.
    AnalogIn = 3,
    /// A position captured by the board on an event (an input edge, an index): value = the
    /// captured count × scale + offset; every capture the board reports counts one in the
    /// signal's `sequence`, with the tick that took it in.
    Capture = 4,
    /// A position-triggered output (the board pulses a line when its counter matches a
    /// compare position, or at an index, an underflow, an overflow): value = the compare
    /// position (counts × scale + offset), set with `SetOutput`; every pulse the board
    /// reports counts one in the signal's `sequence`.
    Trigger = 5,
}

impl SignalKind {
    /// Every kind.
    pub const ALL: [Self; 5] = [
        Self::DigitalIn,
        Self::DigitalOut,
        Self::AnalogIn,
        Self::Capture,
        Self::Trigger,
    ];

    /// The config and CLI name (`kind = "digital-in"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::DigitalIn => "digital-in",
            Self::DigitalOut => "digital-out",
            Self::AnalogIn => "analog-in",
            Self::Capture => "capture",
            Self::Trigger => "trigger",
        }
    }
}

/// A `u8` that is no [`SignalKind`] (a value from a newer writer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnknownKind(pub u8);

impl fmt::Display for UnknownKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown kind {}", self.0)
    }
}

impl std::error::Error for UnknownKind {}

impl TryFrom<u8> for SignalKind {
    type Error = UnknownKind;
    fn try_from(value: u8) -> Result<Self, Self::Error> {
        Self::ALL
            .into_iter()
            .find(|kind| *kind as u8 == value)
            .ok_or(UnknownKind(value))
    }
}

#[cfg(test)]
mod tests {
    use super::{LinkKind, SignalKind, UnknownKind};

    #[test]
    fn signal_kinds_round_trip_through_u8() {
        for kind in SignalKind::ALL {
            assert_eq!(SignalKind::try_from(kind as u8), Ok(kind));
        }
        assert_eq!(SignalKind::try_from(0), Err(UnknownKind(0)));
        assert_eq!(SignalKind::try_from(6), Err(UnknownKind(6)));
        assert_eq!(SignalKind::Capture.name(), "capture");
        assert_eq!(SignalKind::AnalogIn.name(), "analog-in");
        assert_eq!(LinkKind::Spi.to_string(), "spi");
    }
}
