//! Configuration of the simulated QSB: variant, identity, and the signals wired to it.

use core::time::Duration;

use qsb::{BaudRate, PROCESSING_DELAY};

/// The QSB product variant; the VERSION register's product type.
pub use qsb::ProductType as Variant;

/// Independent encoder motion for the -S and -D (which have no stepper drive): a constant
/// velocity plus a sine, in quadrature cycles, as a function of the time since the
/// caller's epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EncoderMotion {
    /// Constant part of the velocity, quadrature cycles per second.
    pub velocity: f64,
    /// Amplitude of the oscillation, quadrature cycles.
    pub amplitude: f64,
    /// Frequency of the oscillation, Hz.
    pub frequency_hz: f64,
}

impl Default for EncoderMotion {
    /// Half a revolution of a 500-cycle encoder back and forth every 4 s.
    fn default() -> Self {
        Self {
            velocity: 0.0,
            amplitude: 250.0,
            frequency_hz: 0.25,
        }
    }
}

impl EncoderMotion {
    /// Encoder position at `t` seconds, quadrature cycles.
    pub fn position(&self, t: f64) -> f64 {
        self.velocity * t + self.amplitude * (core::f64::consts::TAU * self.frequency_hz * t).sin()
    }
}

/// The analog input (MODE analog): a sine around an offset, plus uniform noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalogInput {
    /// Mean voltage, V (0–5 V is the converter range).
    pub offset_volts: f64,
    /// Amplitude, V.
    pub amplitude_volts: f64,
    /// Frequency, Hz.
    pub frequency_hz: f64,
    /// Peak noise, V (uniform, from the seeded generator).
    pub noise_volts: f64,
}

impl Default for AnalogInput {
    fn default() -> Self {
        Self {
            offset_volts: 2.5,
            amplitude_volts: 2.0,
            frequency_hz: 1.0,
            noise_volts: 0.01,
        }
    }
}

/// The enable input of the external stepper driver a -M's step and direction lines go to,
/// wired to one of its DIG I/O bits: while the line is inactive the motor is de-energised
/// and does not follow the step pulses (the encoder stays where it is).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriveEnable {
    /// DIG I/O bit (0 or 3; 1 and 2 are step and direction).
    pub bit: u8,
    /// The drive is enabled while the line is high (else while it is low).
    pub active_high: bool,
}

/// Parameters of a simulated QSB.
#[derive(Debug, Clone, PartialEq)]
pub struct QsbSimConfig {
    /// -S, -D or -M (default -M).
    pub variant: Variant,
    /// Seed of the noise generator (analog input noise).
    pub seed: u64,
    /// Serial number reported by VERSION (five hex digits).
    pub serial_number: u32,
    /// Firmware version reported by VERSION, as its two digits (`0x13` = "13", the first
    /// with the baud-rate selection command).
    pub firmware_version: u8,
    /// The saved line rate at power-up (factory 230400).
    pub baud: BaudRate,
    /// Time from a complete command line to the start of its answer, and the measurement
    /// time of a streamed value (100 µs quadrature/PWM per the command list; analog
    /// measurements take [`qsb::ANALOG_PROCESSING_DELAY`]).
    pub processing_delay: Duration,
    /// Quadrature cycles per stepper step on the -M (the encoder sits on the motor shaft):
    /// 2.5 is a 500-cycle encoder on a 200-step motor, 10 counts per step in x4. Negative
    /// when the encoder counts down as the motor steps forward. See
    /// [`QsbSimConfig::with_counts_per_step`].
    pub cycles_per_step: f64,
    /// Encoder motion on the -S and -D.
    pub motion: EncoderMotion,
    /// Quadrature cycles per revolution: one index pulse per revolution, a quarter cycle
    /// wide, at positions that are multiples of it.
    pub cycles_per_rev: u32,
    /// The connected PWM encoder has 12-bit resolution (250 Hz), else 10-bit (1 kHz).
    pub pwm_12bit: bool,
    /// The analog input signal.
    pub analog: AnalogInput,
    /// Levels the outside world leaves on digital I/O bits 3–0 (1 = not pulled low).
    pub digital_inputs: u8,
    /// The motor drive was enabled and saved (COMMAND 2 then 3) before power-up.
    pub motor_drive_enabled: bool,
    /// -M: the external stepper driver's enable input, when it is wired to a DIG I/O bit;
    /// `None`: always enabled.
    pub drive_enable: Option<DriveEnable>,
    /// Largest number of bytes queued for transmission; lines beyond it are dropped.
    pub tx_capacity: usize,
}

impl Default for QsbSimConfig {
    fn default() -> Self {
        Self {
            variant: Variant::M,
            seed: 0x05B,
            serial_number: 0x00001,
            firmware_version: 0x13,
            baud: BaudRate::FACTORY,
            processing_delay: PROCESSING_DELAY,
            cycles_per_step: 2.5,
            motion: EncoderMotion::default(),
            cycles_per_rev: 500,
            pwm_12bit: true,
            analog: AnalogInput::default(),
            digital_inputs: 0xF,
            motor_drive_enabled: false,
            drive_enable: None,
            tx_capacity: 4096,
        }
    }
}

impl QsbSimConfig {
    /// Sets [`cycles_per_step`](Self::cycles_per_step) from encoder counts per step as a
    /// host counting x4 quadrature (MDR0 B1 B0 = 11, "four counts per quadrature cycle")
    /// sees them: `counts / 4` cycles. Negative reverses the encoder.
    pub fn with_counts_per_step(mut self, counts: f64) -> Self {
        self.cycles_per_step = counts / 4.0;
        self
    }
}
