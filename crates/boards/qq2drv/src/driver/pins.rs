//! The board's I/O as pins: each channel's IN pin ("Home/index/edge Inputs", quadrature
//! blocks QUAD1..QUAD4) and the input and decoder bits of its Status byte (packet 2,
//! "Status"), all streamed in packet 3.
//!
//! The board has no general-purpose outputs (PWM and DIR are motor outputs), so every pin
//! is a digital input and [`Driver::set_output`](motion_drivers::Driver::set_output) refuses.
//!
//! Values are what the stream gives: 1.0 when the bit is set. `inN` is *Input Active*,
//! which the board evaluates "after polarity setting applied" (packet 14 Input Polarity):
//! with a home input configured the driver writes its polarity, otherwise the board's
//! power-up polarity applies (0x00, "Input is active when low"), so an unconfigured IN pin
//! reads 1.0 while it is pulled low — set `invert` on the signal to read the electrical
//! level. The other bits are the board's accumulators ("since the last time status was
//! transmitted"): the driver ORs every stream packet between two engine ticks, so a bit set
//! in any of them is seen by that tick.

use core::time::Duration;

use qq2drv::{CHANNELS, Status};

use motion_drivers::{Pin, PinInfo, PinReading, SignalKind, SignalKinds};

/// Pins per channel: `in`, `_seen`, `_trig_pos`, `_trig_neg`, `glitch`, `overspeed`.
pub const PINS_PER_CHANNEL: usize = 6;

const DIGITAL_IN: SignalKinds = SignalKinds::of(&[SignalKind::DigitalIn]);

const fn pin(name: &'static str, description: &'static str) -> PinInfo {
    PinInfo {
        name,
        kinds: DIGITAL_IN,
        full_scale: 1.0,
        description,
    }
}

macro_rules! channel_pins {
    ($n:literal) => {
        [
            pin(
                concat!("in", $n),
                concat!(
                    "QUAD",
                    $n,
                    " IN pin: Status bit 3 Input Active (packet 2), after the ",
                    "board's Input Polarity (packet 14; power-up: active when low)"
                ),
            ),
            pin(
                concat!("in", $n, "_seen"),
                concat!(
                    "QUAD",
                    $n,
                    " IN pin: Status bit 2 Input Active Accumulator (active at ",
                    "least once since the last stream packet)"
                ),
            ),
            pin(
                concat!("in", $n, "_trig_pos"),
                concat!(
                    "QUAD",
                    $n,
                    " IN pin: Status bit 0 Input Trigger Accumulator, positive ",
                    "end (only while an input mode is armed, i.e. during a home search)"
                ),
            ),
            pin(
                concat!("in", $n, "_trig_neg"),
                concat!(
                    "QUAD",
                    $n,
                    " IN pin: Status bit 1 Input Trigger Accumulator, negative ",
                    "end (only while an input mode is armed, i.e. during a home search)"
                ),
            ),
            pin(
                concat!("glitch", $n),
                concat!(
                    "QUAD",
                    $n,
                    " encoder: Status bit 7 Glitch (invalid A/B transition ",
                    "since the last stream packet)"
                ),
            ),
            pin(
                concat!("overspeed", $n),
                concat!(
                    "QUAD",
                    $n,
                    " encoder: Status bit 6 Overspeed (above the rated ",
                    "50 000 transitions/s)"
                ),
            ),
        ]
    };
}

const QUAD1: [PinInfo; PINS_PER_CHANNEL] = channel_pins!("1");
const QUAD2: [PinInfo; PINS_PER_CHANNEL] = channel_pins!("2");
const QUAD3: [PinInfo; PINS_PER_CHANNEL] = channel_pins!("3");
const QUAD4: [PinInfo; PINS_PER_CHANNEL] = channel_pins!("4");

const fn table() -> [PinInfo; CHANNELS * PINS_PER_CHANNEL] {
    let quads = [QUAD1, QUAD2, QUAD3, QUAD4];
    let mut out = [QUAD1[0]; CHANNELS * PINS_PER_CHANNEL];
    let mut c = 0;
    while c < CHANNELS {
        let mut k = 0;
        while k < PINS_PER_CHANNEL {
            out[c * PINS_PER_CHANNEL + k] = quads[c][k];
            k += 1;
        }
        c += 1;
    }
    out
}

const TABLE: [PinInfo; CHANNELS * PINS_PER_CHANNEL] = table();

/// The board's pins: for each channel 1..4 (`N`), `inN`, `inN_seen`, `inN_trig_pos`,
/// `inN_trig_neg`, `glitchN`, `overspeedN`, all digital inputs. Pin index =
/// channel (0-based) × [`PINS_PER_CHANNEL`] + the position in that list.
pub const PINS: &[PinInfo] = &TABLE;

/// The Status bit of a pin's position within its channel.
const fn status_bit(index: usize) -> u8 {
    match index {
        0 => Status::INPUT_ACTIVE,
        1 => Status::INPUT_ACTIVE_ACCUMULATOR,
        2 => Status::TRIGGER_POSITIVE,
        3 => Status::TRIGGER_NEGATIVE,
        4 => Status::GLITCH,
        _ => Status::OVERSPEED,
    }
}

/// The channel (0-based) and position within it of `pin`, if the board has it.
pub(super) fn locate(pin: Pin) -> Option<(usize, usize)> {
    let index = usize::from(pin.0);
    (index < PINS.len()).then_some((index / PINS_PER_CHANNEL, index % PINS_PER_CHANNEL))
}

/// The pin of `channel`'s `name` suffix position (for tests and configuration).
pub fn pin_of(channel: usize, index: usize) -> Option<Pin> {
    (channel < CHANNELS && index < PINS_PER_CHANNEL)
        .then(|| u16::try_from(channel * PINS_PER_CHANNEL + index).ok())
        .flatten()
        .map(Pin)
}

/// The Status bits of one channel as the pins see them.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct InputBits {
    /// The latest Status byte (Input Active is a level: the latest one counts).
    latest: u8,
    /// Accumulator bits ORed over every stream packet since the engine's last tick.
    accumulated: u8,
    /// The next stream packet starts a new accumulation (the engine has looked).
    fresh_batch: bool,
    refreshed_at: Option<Duration>,
}

impl InputBits {
    /// A stream packet's Status byte for this channel.
    pub(super) fn update(&mut self, now: Duration, status: Status) {
        if self.fresh_batch {
            self.accumulated = 0;
            self.fresh_batch = false;
        }
        self.latest = status.0;
        self.accumulated |= status.0;
        self.refreshed_at = Some(now);
    }

    /// The engine ticked (`handle_timeout`): what it read is consumed.
    pub(super) fn tick(&mut self) {
        self.fresh_batch = true;
    }

    /// The reading of the pin at `index` within the channel.
    pub(super) fn reading(&self, index: usize) -> PinReading {
        let bit = status_bit(index);
        let bits = if index == 0 {
            self.latest
        } else {
            self.accumulated
        };
        PinReading {
            value: if bits & bit != 0 { 1.0 } else { 0.0 },
            refreshed_at: self.refreshed_at,
            events: 0,
        }
    }

    /// Nothing known (the board reset: its bits mean nothing any more).
    pub(super) fn forget(&mut self) {
        *self = Self::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_drivers::find_pin;

    #[test]
    fn the_table_names_every_channel_and_bit() {
        assert_eq!(PINS.len(), 24);
        assert_eq!(find_pin(PINS, "in1"), Some(Pin(0)));
        assert_eq!(find_pin(PINS, "overspeed1"), Some(Pin(5)));
        assert_eq!(find_pin(PINS, "in3_trig_neg"), Some(Pin(15)));
        assert_eq!(find_pin(PINS, "glitch4"), Some(Pin(22)));
        assert_eq!(locate(Pin(22)), Some((3, 4)));
        assert_eq!(locate(Pin(24)), None);
        assert_eq!(pin_of(2, 3), Some(Pin(15)));
        assert!(PINS.iter().all(|p| p.kinds.contains(SignalKind::DigitalIn)
            && !p.kinds.contains(SignalKind::DigitalOut)));
        // Datasheet packet 2 "Status": bit 3 Input Active, bit 2 Input Active Accumulator,
        // bits 1..0 Input Trigger Accumulator (negative, positive edge), 7 Glitch, 6 Overspeed.
        assert_eq!(status_bit(0), 1 << 3);
        assert_eq!(status_bit(1), 1 << 2);
        assert_eq!(status_bit(2), 1 << 0);
        assert_eq!(status_bit(3), 1 << 1);
        assert_eq!(status_bit(4), 1 << 7);
        assert_eq!(status_bit(5), 1 << 6);
    }

    #[test]
    fn accumulators_hold_until_the_engine_ticks() {
        let ms = Duration::from_millis(1);
        let mut bits = InputBits::default();
        assert_eq!(bits.reading(0).refreshed_at, None);
        bits.update(ms, Status(Status::TRIGGER_POSITIVE | Status::INPUT_ACTIVE));
        bits.update(2 * ms, Status(0));
        // Two stream packets in one tick: the trigger of the first is still seen, the
        // level is the latest.
        assert_eq!(bits.reading(2).value, 1.0);
        assert_eq!(bits.reading(0).value, 0.0);
        assert_eq!(bits.reading(0).refreshed_at, Some(2 * ms));
        bits.tick();
        assert_eq!(bits.reading(2).value, 1.0, "kept until new data");
        bits.update(3 * ms, Status(Status::GLITCH));
        assert_eq!(bits.reading(2).value, 0.0);
        assert_eq!(bits.reading(4).value, 1.0);
    }
}
