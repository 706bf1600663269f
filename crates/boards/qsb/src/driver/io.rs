//! The QSB's I/O as signals see it: the pin table ([`pins`]), what the driver is configured
//! to read and drive ([`QsbIo`], [`EnableOutput`], [`CaptureInput`]), and the readings.
//!
//! Command list, DIG I/O (01): "A read returns the actual state measured at the four
//! digital I/O bit inputs, bit3 – bit0. A write sets the open-drain output state … 1 = Open
//! Drain Output High (internal pull-up) 0 = Open Drain Output Low". DIG I/O CONFIG (02)
//! B11–B8 sets the direction, B7–B4 the capture interrupt enable and B3–B0 its polarity;
//! "All I/O port pins will be set "high" after a write to this configuration register".
//! The -M has bits 0–3, the -D bit 0 only, the -S none. With the motor drive active,
//! "digital I/O bits 1 and 2 are reserved for motor drive" (step and direction).

use core::time::Duration;

use ::qsb::{AnalogSample, DigIo, DigIoConfig, EncoderMode, ProductType, Register, Write};

use super::QsbDriver;
use motion_drivers::{GoalError, Pin, PinInfo, PinReading, SignalKind, SignalKinds};

/// DIG I/O bits the -M motor drive uses (1 = step, 2 = direction).
pub const MOTOR_DRIVE_BITS: u8 = 0b0110;

/// The external stepper driver's enable line on a -M: a DIG I/O bit driven as an
/// open-drain output (`enable_output`, `enable_active`).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct EnableOutput {
    /// DIG I/O bit: 0 or 3 (1 and 2 are the motor drive's step and direction).
    pub bit: u8,
    /// The drive is enabled when the line is high (else when it is low, the default).
    /// An open-drain output released high by its pull-up also reads high after a board
    /// reset, so an active-low enable is the fail-safe wiring.
    pub active_high: bool,
}

/// The capture-on-edge interrupt (DIG I/O CONFIG B7–B4 enable, B3–B0 polarity): an edge on
/// `bit` loads the current count into CAPTURE (05), read as the `capture` pin.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct CaptureInput {
    /// DIG I/O bit (0–3 on the -M, 0 on the -D).
    pub bit: u8,
    /// Capture on the high-to-low edge (polarity bit 1), else on low-to-high (0).
    pub falling: bool,
}

/// What the driver reads and drives on the I/O pins (from the configured signals).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct QsbIo {
    /// DIG I/O bits read as inputs (bit n = `ion`).
    pub digital_in: u8,
    /// DIG I/O bits driven as open-drain outputs.
    pub digital_out: u8,
    /// The `encoder` pin (the PWM or analog value of READ ENCODER) is read.
    pub encoder: bool,
    /// The capture interrupt; the `capture` pin reads CAPTURE.
    pub capture: Option<CaptureInput>,
}

impl QsbIo {
    /// Adds the signal of `kind` on `pin` of a QSB of `product`; `false` when the pin
    /// cannot be that (the config validation refuses those).
    pub fn add(&mut self, product: ProductType, pin: Pin, kind: SignalKind) -> bool {
        match (PinRole::of(product, pin), kind) {
            (Some(PinRole::Io(bit)), SignalKind::DigitalIn) => self.digital_in |= 1 << bit,
            (Some(PinRole::Io(bit)), SignalKind::DigitalOut) => self.digital_out |= 1 << bit,
            (Some(PinRole::Encoder), SignalKind::AnalogIn) => self.encoder = true,
            (Some(PinRole::Capture), SignalKind::AnalogIn | SignalKind::Capture)
            | (Some(PinRole::Trigger), SignalKind::Trigger) => {}
            _ => return false,
        }
        true
    }
}

const DIGITAL: SignalKinds = SignalKinds::of(&[SignalKind::DigitalIn, SignalKind::DigitalOut]);
const ANALOG: SignalKinds = SignalKinds::of(&[SignalKind::AnalogIn]);
const CAPTURED: SignalKinds = SignalKinds::of(&[SignalKind::Capture, SignalKind::AnalogIn]);

const fn io(name: &'static str, description: &'static str) -> PinInfo {
    PinInfo {
        name,
        kinds: DIGITAL,
        full_scale: 1.0,
        description,
    }
}

const ENCODER: PinInfo = PinInfo {
    name: "encoder",
    kinds: ANALOG,
    full_scale: 4095.0,
    description: "READ ENCODER (0E) with input_mode = \"pwm\" (absolute position of a US Digital \
                  PWM encoder: 0..=4095 at 12 bits, 0..=1023 at 10 bits, MODE B4) or \
                  \"analog\" (10-bit 0-5 V value, 0..=1023, from the special analog data format)",
};

const CAPTURE: PinInfo = PinInfo {
    name: "capture",
    kinds: CAPTURED,
    full_scale: 2_147_483_647.0,
    description: "CAPTURE (05): the encoder count loaded by the capture_input edge (DIG I/O \
                  CONFIG B7-B0 interrupt) or by the index (capture_index, MDR1 B4), signed \
                  counts; each capture one event",
};

const TRIGGER: PinInfo = PinInfo {
    name: "trigger",
    kinds: SignalKinds::of(&[SignalKind::Trigger]),
    full_scale: 2_147_483_647.0,
    description: "DIG I/O bit 0 pulsed for INTERVAL RATE by the counter's events (trigger_on: \
                  MDR1 B4-B7, DIG I/O CONFIG B12); value: the compare position (DTR, counts), \
                  each pulse one event",
};

const IO0: PinInfo = io(
    "io0",
    "DIG I/O bit 0 (01): input, or open-drain output with pull-up (DIG I/O CONFIG B8)",
);

const M_PINS: &[PinInfo] = &[
    IO0,
    io(
        "io1",
        "DIG I/O bit 1: the step output while the motor drive is active (an axis on the -M), \
         else input or open-drain output",
    ),
    io(
        "io2",
        "DIG I/O bit 2: the direction output while the motor drive is active, else input or \
         open-drain output",
    ),
    io(
        "io3",
        "DIG I/O bit 3: input, or open-drain output with pull-up (DIG I/O CONFIG B11)",
    ),
    ENCODER,
    CAPTURE,
    TRIGGER,
];
const D_PINS: &[PinInfo] = &[IO0, CAPTURE, TRIGGER];
const S_PINS: &[PinInfo] = &[ENCODER, CAPTURE];

/// The QSB's I/O pins for `product` (command list "QSB Variations", DIG I/O, READ ENCODER,
/// CAPTURE, MDR1): `io0`..`io3` on the -M, `io0` on the -D, `encoder` (PWM / analog input
/// modes) on the -S and -M, `capture` on all three (an input edge: -M, -D; the index:
/// all), `trigger` (bit 0 pulsed) on the -M and -D.
pub fn pins(product: ProductType) -> &'static [PinInfo] {
    match product {
        ProductType::M => M_PINS,
        ProductType::D => D_PINS,
        ProductType::S => S_PINS,
    }
}

/// What a pin of the table is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PinRole {
    /// DIG I/O bit n.
    Io(u8),
    /// READ ENCODER in PWM or analog mode.
    Encoder,
    /// The CAPTURE register.
    Capture,
    /// DIG I/O bit 0 as the trigger output; its value the compare position.
    Trigger,
}

impl PinRole {
    /// The role of `pin` in `product`'s table.
    pub fn of(product: ProductType, pin: Pin) -> Option<Self> {
        let info = pins(product).get(usize::from(pin.0))?;
        Some(match info.name.as_bytes() {
            b"encoder" => Self::Encoder,
            b"capture" => Self::Capture,
            b"trigger" => Self::Trigger,
            [b'i', b'o', digit] => Self::Io(digit.checked_sub(b'0')?),
            _ => return None,
        })
    }
}

/// The driver's I/O state.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
pub(crate) struct IoState {
    /// Output levels the signals asked for (bit n; 1 = released high). Bits that are not
    /// outputs stay 1.
    pub outputs: u8,
    /// The external drive should be enabled.
    pub energised: bool,
    /// A DIG I/O write the board refused: not sent again until the levels change.
    pub refused: Option<u8>,
    /// Levels measured at the pins (DIG I/O stream, or the analog samples).
    pub levels: Option<u8>,
    pub levels_at: Option<Duration>,
    pub dio_streaming: bool,
    pub capture: Option<i32>,
    pub capture_at: Option<Duration>,
    pub capture_streaming: bool,
    pub encoder: Option<u32>,
    pub encoder_at: Option<Duration>,
}

impl IoState {
    pub(crate) const fn new() -> Self {
        Self {
            outputs: 0xF,
            energised: true,
            refused: None,
            levels: None,
            levels_at: None,
            dio_streaming: false,
            capture: None,
            capture_at: None,
            capture_streaming: false,
            encoder: None,
            encoder_at: None,
        }
    }
}

/// The product's DIG I/O bits as a mask.
const fn bits_of(product: ProductType) -> u8 {
    match product.digital_io_bits() {
        0 => 0,
        n => ((1u16 << n) - 1) as u8,
    }
}

/// Keeps only what the product and the configuration allow: bits the product has, not the
/// motor drive's bits while it is active, not the enable line's bit. (The config
/// validation refuses the rest with a reason; a driver built by hand gets the same rule.)
pub(crate) fn sanitise(config: &mut super::QsbDriverConfig) {
    let product = config.variant;
    let mut allowed = bits_of(product);
    if product == ProductType::M
        && config.motor_drive
        && config.input_mode == EncoderMode::Quadrature
    {
        allowed &= !MOTOR_DRIVE_BITS;
    }
    config.enable = config
        .enable
        .filter(|e| product == ProductType::M && e.bit < 4 && allowed & (1 << e.bit) != 0);
    if let Some(enable) = config.enable {
        allowed &= !(1 << enable.bit);
    }
    // The trigger output is bit 0 of a product with digital I/O.
    let trigger = &mut config.trigger;
    trigger.pulse &= bits_of(product) & allowed & 1 != 0;
    if trigger.pulse {
        allowed &= !1;
    }
    let io = &mut config.io;
    io.digital_in &= allowed;
    io.digital_out &= allowed & !io.digital_in;
    io.capture = io
        .capture
        .filter(|c| c.bit < 4 && allowed & !io.digital_out & (1 << c.bit) != 0);
    io.encoder &= product != ProductType::D && config.input_mode != EncoderMode::Quadrature;
}

impl QsbDriver {
    /// Whether the driver uses DIG I/O at all (otherwise it never touches registers 01
    /// and 02).
    pub(super) fn dio_used(&self) -> bool {
        let io = self.config.io;
        self.config.enable.is_some()
            || io.digital_in | io.digital_out != 0
            || io.capture.is_some()
            || self.config.trigger.pulse
    }

    /// Whether the DIG I/O register is streamed (the levels of the digital signals; in
    /// analog mode they come with every sample instead).
    pub(super) fn dio_streamed(&self) -> bool {
        let io = self.config.io;
        io.digital_in | io.digital_out != 0 && self.config.input_mode != EncoderMode::Analog
    }

    /// DIG I/O CONFIG as configured: outputs, the capture interrupt, the trigger pulse
    /// on bit 0 (an output); the motor drive's bits stay inputs ("Be careful if the motor
    /// drive is enabled, it uses I/O bits 1 and 2").
    pub(super) fn dio_config(&self) -> DigIoConfig {
        let io = self.config.io;
        let enable = self.config.enable.map_or(0, |e| 1 << e.bit);
        let capture = io.capture.map_or(0, |c| 1 << c.bit);
        let falling = io.capture.filter(|c| c.falling).map_or(0, |c| 1 << c.bit);
        let pulse = self.config.trigger.pulse;
        DigIoConfig {
            falling_edge: falling,
            interrupt_enable: capture,
            output: io.digital_out | enable | u8::from(pulse),
            trigger_pulse: pulse,
        }
    }

    /// The DIG I/O latch with the enable line for `energised`, and the trigger output at
    /// rest ("The output pulse polarity depends on the initial output state of digital
    /// I/O bit 0").
    pub(super) fn latch_with(&self, energised: bool) -> u8 {
        let mut latch = self.io.outputs | !self.config.io.digital_out;
        if self.config.trigger.pulse && self.config.trigger.active_high {
            latch &= !1;
        }
        if let Some(enable) = self.config.enable {
            let high = energised == enable.active_high;
            latch = if high {
                latch | 1 << enable.bit
            } else {
                latch & !(1 << enable.bit)
            };
        }
        latch & 0xF
    }

    /// The DIG I/O write the board should hold.
    pub(super) fn desired_outputs(&self) -> Write {
        Write::DigIo(DigIo(self.latch_with(self.io.energised)))
    }

    /// The DIG I/O write still to be sent, if the outputs differ from what the board holds.
    pub(super) fn outputs_due(&self) -> Option<Write> {
        let write = self.desired_outputs();
        let refused = self.io.refused == Some(write.data() as u8);
        (self.dio_used() && !refused && !self.holds(write)).then_some(write)
    }

    /// A streamed DIG I/O, CAPTURE or READ ENCODER (PWM / analog) line.
    pub(super) fn io_line(&mut self, now: Duration, register: Register, data: u32) {
        match register {
            Register::DigIo => {
                self.io.levels = Some((data & 0xF) as u8);
                self.io.levels_at = Some(now);
            }
            Register::Capture => {
                self.io.capture = Some(data as i32);
                self.io.capture_at = Some(now);
            }
            Register::ReadEncoder => match self.config.input_mode {
                EncoderMode::Analog => {
                    if let Ok(sample) = AnalogSample::from_data(data) {
                        self.io.encoder = Some(u32::from(sample.analog));
                        self.io.encoder_at = Some(now);
                        self.io.levels = Some(sample.digital);
                        self.io.levels_at = Some(now);
                    }
                }
                EncoderMode::Pwm => {
                    self.io.encoder = Some(data);
                    self.io.encoder_at = Some(now);
                }
                EncoderMode::Quadrature => {}
            },
            _ => {}
        }
    }

    /// When a value streamed on change was last known to hold: the line that brought it,
    /// or any later stream line while its stream runs (the board would have sent a change).
    fn on_change_at(&self, at: Option<Duration>, streaming: bool) -> Option<Duration> {
        let alive = self
            .last_sample_at
            .filter(|_| streaming && self.status.online);
        at.max(alive.filter(|_| at.is_some()))
    }

    /// [`Driver::read_pin`](motion_drivers::Driver::read_pin).
    pub(super) fn pin_reading(&self, pin: Pin) -> Option<PinReading> {
        let io = self.config.io;
        let reading = |value: Option<f64>, at: Option<Duration>| match value {
            Some(value) => PinReading::at(value, at),
            None => PinReading::UNKNOWN,
        };
        match PinRole::of(self.config.variant, pin)? {
            PinRole::Io(bit) if (io.digital_in | io.digital_out) & (1 << bit) != 0 => {
                let level = self.io.levels.map(|l| f64::from((l >> bit) & 1));
                let streamed =
                    self.io.dio_streaming || self.config.input_mode == EncoderMode::Analog;
                Some(reading(
                    level,
                    self.on_change_at(self.io.levels_at, streamed),
                ))
            }
            PinRole::Encoder if io.encoder => {
                Some(reading(self.io.encoder.map(f64::from), self.io.encoder_at))
            }
            PinRole::Capture if io.capture.is_some() || self.config.trigger.index => {
                Some(PinReading {
                    events: self.events.captures,
                    ..reading(
                        self.io.capture.map(f64::from),
                        self.on_change_at(self.io.capture_at, self.io.capture_streaming),
                    )
                })
            }
            PinRole::Trigger if self.config.trigger.pulse => {
                // Known since the board took the compare position (or came online), and
                // while STR streams: a pulse would have shown.
                let since = self
                    .status
                    .online
                    .then_some(self.online_at)
                    .max(self.events.compare_at);
                Some(PinReading {
                    value: f64::from(self.events.compare_held.unwrap_or(0)),
                    refreshed_at: self.on_change_at(since, self.str_streaming),
                    events: self.events.pulses,
                })
            }
            PinRole::Io(_) | PinRole::Encoder | PinRole::Capture | PinRole::Trigger => None,
        }
    }

    /// [`Driver::set_output`](motion_drivers::Driver::set_output).
    pub(super) fn drive_output(&mut self, pin: Pin, high: bool) -> Result<(), GoalError> {
        let bit = match PinRole::of(self.config.variant, pin) {
            Some(PinRole::Io(bit)) if self.config.io.digital_out & (1 << bit) != 0 => bit,
            _ => return Err(GoalError::NoSuchPin(pin)),
        };
        self.check_online()?;
        self.io.outputs = if high {
            self.io.outputs | 1 << bit
        } else {
            self.io.outputs & !(1 << bit)
        };
        self.io.refused = None;
        Ok(())
    }
}
