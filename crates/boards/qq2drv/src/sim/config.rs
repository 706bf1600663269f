//! Configuration of a simulated QuadQuad2Drv board.

use core::time::Duration;

/// Physics of one DC motor with its quadrature encoder, expressed in encoder units.
///
/// The speed follows a first-order lag towards `no_load_velocity × power / 8191` (less a
/// static-friction dead band), the way a small brushed gearmotor under PWM behaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorConfig {
    /// Velocity at full power without load, quadrature transitions per second.
    pub no_load_velocity: f64,
    /// Mechanical time constant of the speed response.
    pub time_constant: Duration,
    /// Fraction of full power (0..1) eaten by static friction: below it the shaft stays put.
    pub friction: f64,
    /// Quadrature transitions per shaft revolution (an index pulse comes once per revolution).
    pub transitions_per_rev: u32,
    /// Relative spread of the motor's gain, drawn once per channel from the seeded generator
    /// (`1 ± gain_spread`), so four channels are not perfectly identical.
    pub gain_spread: f64,
}

impl Default for MotorConfig {
    /// A Pololu HP N20 gearmotor with the 12-CPR extended-shaft encoder (the datasheet's
    /// suggested motor): about 30 000 rpm free-running at the motor shaft ≈ 6 000
    /// transitions/s, 20 ms mechanical time constant.
    fn default() -> Self {
        Self {
            no_load_velocity: 6_000.0,
            time_constant: Duration::from_millis(20),
            friction: 0.02,
            transitions_per_rev: 12,
            gain_spread: 0.0,
        }
    }
}

/// What drives a channel's IN pin (home / index / edge input).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum InputSource {
    /// Nothing connected: the pin reads its idle level.
    #[default]
    None,
    /// An end-stop switch actuated at and beyond `position` (transitions) in the positive
    /// direction (`positive_end`) or the negative one.
    EndStop {
        /// Where the switch is.
        position: f64,
        /// Actuated for positions ≥ `position` (true) or ≤ `position` (false).
        positive_end: bool,
    },
    /// Two end-stop switches wired to the same pin: actuated at ≤ `negative` or ≥ `positive`.
    TwoEndStops {
        /// Negative end.
        negative: f64,
        /// Positive end.
        positive: f64,
    },
    /// A home sensor (e.g. an infrared gate) actuated inside a window.
    Window {
        /// Lower edge of the window.
        from: f64,
        /// Upper edge of the window.
        to: f64,
    },
    /// The encoder's index output: actuated during the `width` transitions starting at
    /// `offset` of every revolution ([`MotorConfig::transitions_per_rev`]).
    Index {
        /// Start of the pulse within a revolution, transitions.
        offset: f64,
        /// Pulse width in transitions (4 = one detent, covering the A = B = 0 state once).
        width: f64,
    },
}

/// One channel's IN pin: what actuates it and which electrical level "actuated" is.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InputPin {
    /// What actuates the pin.
    pub source: InputSource,
    /// Electrical level while actuated: `true` high, `false` low (e.g. a switch to ground).
    /// The idle level is the opposite.
    pub actuated_high: bool,
}

/// Everything that makes one simulated board differ from another.
#[derive(Debug, Clone, PartialEq)]
pub struct Qq2drvSimConfig {
    /// Seed of the generator behind every random effect of the model.
    pub seed: u64,
    /// Firmware version reported by packet 1 (major, minor).
    pub firmware_version: (u8, u8),
    /// Protocol version reported by packet 1. The datasheet's worked example answers 0.
    pub protocol_version: u8,
    /// Time from the end of a request to its reply being ready on MISO.
    pub processing_time: Duration,
    /// Stream processing overhead: from capturing a stream packet's data until it is ready
    /// (the datasheet's example measures 8 × 40.96 µs).
    pub stream_overhead: Duration,
    /// SPI clock the board expects the master to use; places bytes in time within a
    /// transaction (the transaction completes at the `now` it is given).
    pub spi_clock_hz: u32,
    /// MISO filler byte clocked out when nothing is ready.
    pub filler: u8,
    /// Motor and encoder physics of channels 1..4.
    pub motors: [MotorConfig; 4],
    /// IN pins of channels 1..4.
    pub inputs: [InputPin; 4],
    /// Mean rate of random glitches (invalid A/B transitions from line noise) per channel,
    /// per second; 0 disables.
    pub glitch_rate: f64,
    /// Velocity (transitions/s) above which the decoder starts missing transitions and
    /// reports glitches. Above the rated 50 000 transitions/s it reports overspeed.
    pub glitch_velocity: f64,
    /// Upper bound on queued replies; requests beyond it are dropped unanswered.
    pub max_queued_replies: usize,
    /// Packet 3 starts with a Return Code (0), as its text says ("except for Return
    /// Code"); `false` (default): none, as its table shows.
    pub stream_return_code: bool,
    /// How the firmware reads packet 36's Velocity: signed (default), or forward only
    /// ("Range: 0 - 100,000"), answering a negative one with an out-of-range Return Code.
    pub velocity_ramp: qq2drv::limits::VelocityRampSign,
}

impl Default for Qq2drvSimConfig {
    fn default() -> Self {
        Self {
            seed: 0,
            firmware_version: (0, 1),
            protocol_version: 0,
            processing_time: Duration::from_micros(200),
            stream_overhead: Duration::from_nanos(8 * qq2drv::limits::STREAM_TICK_NS),
            spi_clock_hz: 500_000,
            filler: 0x00,
            motors: [MotorConfig::default(); 4],
            inputs: [InputPin::default(); 4],
            glitch_rate: 0.0,
            glitch_velocity: 80_000.0,
            max_queued_replies: 16,
            stream_return_code: false,
            velocity_ramp: qq2drv::limits::VelocityRampSign::Signed,
        }
    }
}
