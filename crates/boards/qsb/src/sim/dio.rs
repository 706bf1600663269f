//! The digital I/O port: open-drain outputs with pull-ups, inputs from the outside world,
//! the step and direction lines of the -M drive, and the capture interrupt.

use qsb::DigIoConfig;

/// Digital I/O bit the -M drive uses for step pulses.
pub const STEP_BIT: u8 = 1;
/// Digital I/O bit the -M drive uses for the direction (1 = positive).
pub const DIRECTION_BIT: u8 = 2;

#[derive(Debug, Clone)]
pub(crate) struct DigitalIo {
    /// Written output states (1 = released high).
    pub latch: u8,
    pub config: DigIoConfig,
    /// Levels the outside leaves on the pins (1 = not pulled low).
    pub external: u8,
    /// Pins the product has (mask).
    mask: u8,
    /// The motor drive owns bits 1 and 2: `Some(direction positive)`.
    pub drive: Option<bool>,
}

impl DigitalIo {
    pub(crate) fn new(bits: u8, latch: u8, config: DigIoConfig, external: u8) -> Self {
        Self {
            latch,
            config,
            external,
            mask: ((1u16 << bits) - 1) as u8,
            drive: None,
        }
    }

    /// Levels measured at the pins; pins the product lacks read 0.
    pub(crate) fn pins(&self) -> u8 {
        let mut levels = 0u8;
        for bit in 0..4u8 {
            let m = 1 << bit;
            let driven_low = self.config.output & m != 0 && self.latch & m == 0;
            let mut level = !driven_low && self.external & m != 0;
            if let Some(positive) = self.drive {
                if bit == STEP_BIT {
                    level = true; // idle between step pulses
                } else if bit == DIRECTION_BIT {
                    level = positive;
                }
            }
            if level {
                levels |= m;
            }
        }
        levels & self.mask
    }

    /// Whether going from pin levels `before` to the current ones is an enabled interrupt
    /// edge (DIG I/O CONFIG polarity: 1 = high-to-low, 0 = low-to-high).
    pub(crate) fn interrupt(&self, before: u8) -> bool {
        let after = self.pins();
        let rising = !before & after;
        let falling = before & !after;
        let enabled = self.config.interrupt_enable;
        let pol = self.config.falling_edge;
        (rising & enabled & !pol) | (falling & enabled & pol) != 0
    }
}
