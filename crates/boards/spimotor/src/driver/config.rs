//! What a [`SpimotorDriver`](super::SpimotorDriver) is built from.

use core::time::Duration;

use spimotor::{Address, Coils};

/// What is connected to the board's two H-bridges (config `drive = "stepper" | "brushed"`).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum SpimotorDrive {
    /// One stepper motor: channel 0 (ports 0x10, 0x40–0x44).
    #[default]
    Stepper,
    /// Two brushed DC motors: channel 0 = motor A (ports 0x20–0x22), channel 1 = motor B
    /// (ports 0x30–0x32).
    Brushed,
}

impl SpimotorDrive {
    /// Channels the drive exposes: 1 (stepper) or 2 (brushed A, B).
    pub const fn channels(self) -> usize {
        match self {
            Self::Stepper => 1,
            Self::Brushed => 2,
        }
    }
}

pub use motion_drivers::spec::AxisLimits;

/// A channel's limits when no axis is configured on it, counts/s and /s².
const DEFAULT_LIMITS: AxisLimits = AxisLimits {
    max_velocity: 1_000.0,
    max_accel: 10_000.0,
};

/// Everything the driver needs to know about one SPI_motor board.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct SpimotorDriverConfig {
    /// The board's SPI address (even byte form, default 0x90).
    pub address: Address,
    /// Stepper or two brushed motors.
    pub drive: SpimotorDrive,
    /// SPI clock of the link, Hz: sizes the reply timeout from the wire time.
    pub speed_hz: u32,
    /// How often the driver reads the board (stepper: position, target and step delay;
    /// brushed: the identification string as a presence check).
    pub poll_period: Duration,
    /// Per channel (index = channel) the axis limits in board counts (full steps for the
    /// stepper), as configured for the axis on that channel: the stepper's moves never
    /// step faster than `max_velocity`, and `Goal::Position` ramps with `max_accel`.
    pub limits: [AxisLimits; 2],
    /// Stepper drive intensity written at start-up and with every motion goal (port 0x10;
    /// the board's default is 0x20).
    pub stepper_intensity: u8,
    /// Coils driven by the stepper (port 0x44), written at start-up.
    pub coils: Coils,
    /// How long a transaction's MISO may stay away before the board is declared not
    /// answering (`silence_ms`, default [`DEFAULT_SILENCE`](motion_drivers::DEFAULT_SILENCE)):
    /// MISO held back on the host (an SPI socket peer or the server without CPU) comes
    /// later, every byte in order, and is waited for.
    pub silence: Duration,
}

impl Default for SpimotorDriverConfig {
    fn default() -> Self {
        Self {
            address: Address::DEFAULT,
            drive: SpimotorDrive::Stepper,
            speed_hz: 1_000_000,
            poll_period: Duration::from_millis(2),
            limits: [DEFAULT_LIMITS; 2],
            stepper_intensity: spimotor::port::DEFAULT_STEPPER_INTENSITY,
            coils: Coils::Two,
            silence: motion_drivers::DEFAULT_SILENCE,
        }
    }
}

impl SpimotorDriverConfig {
    /// The limits of `channel` (the defaults for a channel beyond the table).
    pub(super) fn limits(&self, channel: usize) -> AxisLimits {
        self.limits.get(channel).copied().unwrap_or(DEFAULT_LIMITS)
    }

    /// Wire time of `bytes` at the configured SPI clock.
    pub(super) fn wire_time(&self, bytes: usize) -> Duration {
        let bits = 8 * bytes as u64;
        Duration::from_nanos(bits.saturating_mul(1_000_000_000) / u64::from(self.speed_hz.max(1)))
    }
}
