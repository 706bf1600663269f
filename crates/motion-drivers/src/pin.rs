//! Board I/O as the drivers see it: [`Pin`]s, what they can do ([`PinInfo`]) and what they
//! read ([`PinReading`]).
//!
//! Every board's driver publishes a static table of its pins (`board_qq2drv::driver::PINS`,
//! `board_tmcpack::driver::pins(variant)`, `board_qsb::driver::pins(variant)`, the board's
//! `Board::pins`) with the names the
//! config uses (`pin = "ttlio1"`). A [`Pin`] is the index into that table, so it means
//! something only together with its board's model. Values are raw: 0.0 / 1.0 for a digital
//! pin as the board reports its electrical level (no inversion), the ADC count for an
//! analogue one, the counter's count for a capture or a trigger's compare position.
//! Scaling, offsets and inversion are the engine's business.

use core::time::Duration;

/// One pin of a board: the index into the board's pin table.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord,
)]
pub struct Pin(pub u16);

/// What a pin can be used as; also the kind of a configured signal (one enum with the
/// engine and the shared-memory contract: `motion_base::SignalKind`).
pub use motion_base::SignalKind;

/// The bit of `kind` in a [`SignalKinds`].
const fn bit(kind: SignalKind) -> u8 {
    1 << (kind as u8)
}

/// A set of [`SignalKind`]s: what one pin can do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SignalKinds(u8);

impl SignalKinds {
    /// The set of `kinds`.
    pub const fn of(kinds: &[SignalKind]) -> Self {
        let mut bits = 0;
        let mut index = 0;
        while index < kinds.len() {
            bits |= bit(kinds[index]);
            index += 1;
        }
        Self(bits)
    }

    /// Whether `kind` is in the set.
    pub const fn contains(self, kind: SignalKind) -> bool {
        self.0 & bit(kind) != 0
    }
}

/// One row of a board's pin table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PinInfo {
    /// The config name (`"ttlio1"`, `"io3"`, `"in2"`), lower case.
    pub name: &'static str,
    /// What the pin can be configured as.
    pub kinds: SignalKinds,
    /// Full scale of an analogue reading in ADC counts (1023 for a 10-bit converter);
    /// 1.0 for a digital pin.
    pub full_scale: f64,
    /// One line for `motionctl io list` and the config docs: what the pin is, where the
    /// datasheet describes it.
    pub description: &'static str,
}

/// Finds `name` in a board's pin table.
pub fn find_pin(table: &[PinInfo], name: &str) -> Option<Pin> {
    table
        .iter()
        .position(|info| info.name == name)
        .and_then(|index| u16::try_from(index).ok())
        .map(Pin)
}

/// The last value a driver knows for a pin.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct PinReading {
    /// Raw value: 0.0 / 1.0 (electrical level), ADC counts, or counter counts (a capture,
    /// a trigger's compare position).
    pub value: f64,
    /// When the board last reported it (`None`: never). For an output without a read-back,
    /// when the board acknowledged the last write.
    pub refreshed_at: Option<Duration>,
    /// Events the board reported on the pin since the driver was made — captures of a
    /// capture pin, pulses of a trigger pin —, wrapping at 2³²; 0 for other pins. Only
    /// ever counts up: a board reset does not restart it.
    pub events: u32,
}

impl PinReading {
    /// Nothing known yet.
    pub const UNKNOWN: Self = Self {
        value: 0.0,
        refreshed_at: None,
        events: 0,
    };

    /// A reading of `value` reported at `refreshed_at`, no events.
    pub const fn at(value: f64, refreshed_at: Option<Duration>) -> Self {
        Self {
            value,
            refreshed_at,
            events: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_set_and_lookup() {
        let set = SignalKinds::of(&[SignalKind::DigitalIn, SignalKind::DigitalOut]);
        assert!(set.contains(SignalKind::DigitalIn));
        assert!(set.contains(SignalKind::DigitalOut));
        assert!(!set.contains(SignalKind::AnalogIn));
        let table = [
            PinInfo {
                name: "a",
                kinds: set,
                full_scale: 1.0,
                description: "",
            },
            PinInfo {
                name: "b",
                kinds: SignalKinds::of(&[SignalKind::AnalogIn]),
                full_scale: 1023.0,
                description: "",
            },
        ];
        assert_eq!(find_pin(&table, "b"), Some(Pin(1)));
        assert_eq!(find_pin(&table, "c"), None);
    }
}
