//! Pack-wide firmware state (everything $CC resets) and the non-volatile memory (what it
//! keeps).

use tmcpack::convert::{DEFAULT_BAUD, DEFAULT_SWITCHOVER_UNITS, baud_divisor};
use tmcpack::{DEFAULT_PACKET_TIMEOUT, MotorMask, Variant};

/// A $50 interpolation in progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Interp {
    pub master: usize,
    pub start: [i64; 6],
    pub dist: [i64; 6],
    pub mask: MotorMask,
}

/// A $28 answer waiting for motors to finish.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Delayed {
    pub reply_to: u8,
    pub mask: MotorMask,
}

/// Firmware state that $CC resets to defaults.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PackState {
    pub address: u8,
    pub clkdiv: u8,
    /// $10 peak current per motor pair (0+1, 2+3, 4+5); 7.1: "Peak current=128".
    pub peak: [u8; 3],
    pub table: [u8; 16],
    pub ttlout1: bool,
    pub ttlio1_is_input: bool,
    pub ttlio1_out: bool,
    pub ttlout1_ready: bool,
    /// 7.1: "Readymask=$3F; ReferReadymask=$3F".
    pub ready_active: MotorMask,
    pub ready_ref: MotorMask,
    /// $31 limits of channels 6 and 7 (stored; they belong to no motor).
    pub extra_limits: [(u16, u16); 2],
    pub divisor: u16,
    pub switchover_units: u16,
    pub timeout_units: u16,
    pub reset_flag: bool,
    pub can_rs232: (u8, u8),
    pub power_down_enabled: bool,
    pub flash_enabled: bool,
    pub flash_write: usize,
    pub flash_read: usize,
    pub interp: Option<Interp>,
    pub delayed: Option<Delayed>,
}

impl PackState {
    /// The state after power-on or $CC: rotary-switch address, factory baud rate and
    /// switch-over delay, manual 7.1 defaults.
    pub fn new(address: u8) -> Self {
        Self {
            address,
            clkdiv: 5,
            peak: [128; 3],
            table: tmcpack::table::SINE_TABLE,
            ttlout1: false,
            ttlio1_is_input: true,
            ttlio1_out: false,
            ttlout1_ready: false,
            ready_active: MotorMask::from_bits_retain(0x3F),
            ready_ref: MotorMask::from_bits_retain(0x3F),
            extra_limits: [(0, 1023); 2],
            divisor: baud_divisor(DEFAULT_BAUD).unwrap_or(65),
            switchover_units: DEFAULT_SWITCHOVER_UNITS,
            timeout_units: (DEFAULT_PACKET_TIMEOUT.as_millis() / 2) as u16,
            reset_flag: true,
            can_rs232: (0, 0),
            power_down_enabled: false,
            flash_enabled: false,
            flash_write: 0,
            flash_read: 0,
            interp: None,
            delayed: None,
        }
    }
}

/// EEPROM and flash: they survive $CC and power cycles.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct NonVolatile {
    pub eeprom: Vec<u16>,
    /// Positions saved by the power-down mode ($45), valid or not.
    pub saved_positions: Option<[i32; 6]>,
    pub flash: Vec<u8>,
}

/// Words of simulated EEPROM.
pub(crate) const EEPROM_WORDS: usize = 1024;

impl NonVolatile {
    pub fn new(flash_size: usize, variant: Variant) -> Self {
        // A recognisable, deterministic "firmware image".
        let flash = (0..flash_size)
            .map(|i| (i as u32).wrapping_mul(2_654_435_761).to_le_bytes()[3] ^ variant.motors())
            .collect();
        Self {
            eeprom: vec![0xFFFF; EEPROM_WORDS],
            saved_positions: None,
            flash,
        }
    }

    /// $F4: 16-bit sum of the flash bytes.
    pub fn checksum(&self) -> u16 {
        self.flash
            .iter()
            .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)))
    }
}
