//! The pack's additional inputs and outputs (manual 8.5): the pin tables, what the driver
//! was configured to read or drive, and its view of every pin.
//!
//! One `$30` answer carries the analogue value of one channel (0..5 the motors' A_In, 6 the
//! external input, 7 the supply voltage, "1V equals value 22"), every motor's reference
//! input and the jumpers (P4, "The reference inputs are inverted") and the state of TTLIO1
//! (P5). So the driver polls `$30` once per round of its motor polls, for the next
//! configured analogue channel in turn (or any channel when only digital inputs are
//! configured), and every answer refreshes all digital inputs at once.
//!
//! `$32` sets TTLOUT1, the direction of TTLIO1, the level of TTLIO1 and the ready function
//! of TTLOUT1 at once, so the driver keeps the levels of both outputs and writes all of them
//! with every change, at start-up and again after the pack was seen to reset.

use core::time::Duration;

use tmcpack::{MotorMask, RefInputs, Reply, Request, Variant};

use motion_drivers::{Pin, PinInfo, PinReading, SignalKind, SignalKinds};

/// Pins of the largest table (SIXpack).
pub const MAX_PINS: usize = 18;

/// Where a pin's value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    /// `$30` analogue value of channel n.
    Analog(u8),
    /// `$30` P4 bit n: motor n's reference input (reported inverted).
    Ref(u8),
    /// `$30` P4 bit 6.
    Jumper1,
    /// `$30` P4 bit 7.
    Jumper2,
    /// `$30` P5 bit 0, `$32` P1/P2.
    Ttlio1,
    /// `$32` P0.
    Ttlout1,
}

const ANALOG: SignalKinds = SignalKinds::of(&[SignalKind::AnalogIn]);
const DIN: SignalKinds = SignalKinds::of(&[SignalKind::DigitalIn]);
const DOUT: SignalKinds = SignalKinds::of(&[SignalKind::DigitalOut]);
const DIO: SignalKinds = SignalKinds::of(&[SignalKind::DigitalIn, SignalKind::DigitalOut]);

/// One pin: its row of the pin table, and where its value comes from.
type Row = (PinInfo, Source);

/// Analogue channel `channel` of `$30`.
const fn analog(channel: u8, name: &'static str, description: &'static str) -> Row {
    let info = PinInfo {
        name,
        kinds: ANALOG,
        full_scale: 1023.0,
        description,
    };
    (info, Source::Analog(channel))
}

/// Motor `motor`'s reference input, a digital input of `$30` P4.
const fn reference(motor: u8, name: &'static str, description: &'static str) -> Row {
    digital(Source::Ref(motor), name, DIN, description)
}

const fn digital(
    source: Source,
    name: &'static str,
    kinds: SignalKinds,
    description: &'static str,
) -> Row {
    let info = PinInfo {
        name,
        kinds,
        full_scale: 1.0,
        description,
    };
    (info, source)
}

const A0: Row = analog(
    0,
    "analog0",
    "motor 0's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 0)",
);
const A1: Row = analog(
    1,
    "analog1",
    "motor 1's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 1)",
);
const A2: Row = analog(
    2,
    "analog2",
    "motor 2's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 2)",
);
const A3: Row = analog(
    3,
    "analog3",
    "motor 3's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 3)",
);
const A4: Row = analog(
    4,
    "analog4",
    "motor 4's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 4)",
);
const A5: Row = analog(
    5,
    "analog5",
    "motor 5's analogue input A_In, ADC counts 0..1023 (manual 8.5 $30 channel 5)",
);
const A6: Row = analog(
    6,
    "analog6",
    "external analogue input, ADC counts 0..1023 (manual 8.5 $30 channel 6)",
);
const A7: Row = analog(
    7,
    "analog7",
    "supply voltage, 22 counts per volt: scale = 0.04545 for V (manual 8.5 $30 channel 7, \"1V equals value 22\")",
);
const R0: Row = reference(
    0,
    "ref0",
    "motor 0's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 0 reports it inverted; the driver undoes that)",
);
const R1: Row = reference(
    1,
    "ref1",
    "motor 1's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 1, inverted on the wire)",
);
const R2: Row = reference(
    2,
    "ref2",
    "motor 2's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 2, inverted on the wire)",
);
const R3: Row = reference(
    3,
    "ref3",
    "motor 3's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 3, inverted on the wire)",
);
const R4: Row = reference(
    4,
    "ref4",
    "motor 4's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 4, inverted on the wire)",
);
const R5: Row = reference(
    5,
    "ref5",
    "motor 5's reference switch input Ref_In, electrical level 1 = high (manual 8.5 $30 P4 bit 5, inverted on the wire)",
);
const J1: Row = digital(
    Source::Jumper1,
    "jumper1",
    DIN,
    "jumper JP1, 1 = set (manual 8.5 $30 P4 bit 6; 6.2 CAN bit rate)",
);
const J2: Row = digital(
    Source::Jumper2,
    "jumper2",
    DIN,
    "jumper JP2, 1 = set (manual 8.5 $30 P4 bit 7; 6.2 CAN bit rate)",
);
const IO1: Row = digital(
    Source::Ttlio1,
    "ttlio1",
    DIO,
    "TTLIO1, digital input ($30 P5) or output ($32 P1 direction, P2 level) (manual 8.5)",
);
const OUT1: Row = digital(
    Source::Ttlout1,
    "ttlout1",
    DOUT,
    "TTLOUT1 digital output ($32 P0, manual 8.5); not available when the device has a ready_output",
);

/// The SIXpack's pins, in table order (`Pin` = index), and where each comes from.
const SIXPACK_TABLES: ([PinInfo; 18], [Source; 18]) = split([
    A0, A1, A2, A3, A4, A5, A6, A7, R0, R1, R2, R3, R4, R5, J1, J2, IO1, OUT1,
]);
/// The QUADpack's: no motor 4 and 5.
const QUADPACK_TABLES: ([PinInfo; 14], [Source; 14]) =
    split([A0, A1, A2, A3, A6, A7, R0, R1, R2, R3, J1, J2, IO1, OUT1]);
static SIXPACK: [PinInfo; 18] = SIXPACK_TABLES.0;
static SIXPACK_SOURCES: [Source; 18] = SIXPACK_TABLES.1;
static QUADPACK: [PinInfo; 14] = QUADPACK_TABLES.0;
static QUADPACK_SOURCES: [Source; 14] = QUADPACK_TABLES.1;

/// The pin table of `rows` and, in the same order, where each pin comes from.
const fn split<const N: usize>(rows: [Row; N]) -> ([PinInfo; N], [Source; N]) {
    let mut infos = [rows[0].0; N];
    let mut sources = [rows[0].1; N];
    let mut i = 0;
    while i < N {
        infos[i] = rows[i].0;
        sources[i] = rows[i].1;
        i += 1;
    }
    (infos, sources)
}

/// The pack's I/O pins for `variant` (manual 8.5): `analog0..analog7` (a QUADpack has no
/// motor 4 and 5, so no `analog4`, `analog5`), `ref0..ref5` (`ref0..ref3` on a QUADpack),
/// `jumper1`, `jumper2`, `ttlio1`, `ttlout1`.
pub fn pins(variant: Variant) -> &'static [PinInfo] {
    match variant {
        Variant::SixPack => &SIXPACK,
        Variant::QuadPack => &QUADPACK,
    }
}

fn sources(variant: Variant) -> &'static [Source] {
    match variant {
        Variant::SixPack => &SIXPACK_SOURCES,
        Variant::QuadPack => &QUADPACK_SOURCES,
    }
}

fn source(variant: Variant, pin: Pin) -> Option<Source> {
    sources(variant).get(usize::from(pin.0)).copied()
}

/// A set of pins of one variant's table.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct PinSet(u32);

impl PinSet {
    /// No pin.
    pub const EMPTY: Self = Self(0);

    /// `self` and `pin` (pins beyond the table size are ignored).
    #[must_use]
    pub const fn with(self, pin: Pin) -> Self {
        if (pin.0 as usize) < MAX_PINS {
            Self(self.0 | 1 << pin.0)
        } else {
            self
        }
    }

    /// Whether `pin` is in the set.
    pub const fn contains(self, pin: Pin) -> bool {
        (pin.0 as usize) < MAX_PINS && self.0 & (1 << pin.0) != 0
    }

    /// Whether the set is empty.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }
}

/// TTLOUT1 as the ready output (manual 8.5 $32 P3, $33): "activated (low, open collector),
/// whenever a motor is active … or search of reference".
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadyOutput {
    /// $33 P0: motors whose activity counts.
    pub motors: MotorMask,
    /// $33 P1: motors whose reference search counts.
    pub reference: MotorMask,
}

/// What the driver reads and drives besides the motors.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TmcpackIo {
    /// Input pins to poll with `$30` (digital-in and analog-in signals; `ttlio1` here makes
    /// TTLIO1 an input).
    pub inputs: PinSet,
    /// Output pins the driver drives (`ttlout1`, `ttlio1` as digital-out).
    pub outputs: PinSet,
    /// TTLOUT1 as the ready output instead of a plain output.
    pub ready: Option<ReadyOutput>,
}

/// The driver's view of the pins.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct IoState {
    variant: Variant,
    cfg: TmcpackIo,
    readings: [PinReading; MAX_PINS],
    /// $32 P0 and P2 as the driver wants them.
    ttlout1: bool,
    ttlio1: bool,
    /// A `$32` with the current levels is due.
    pub outputs_pending: bool,
    /// The `$30` channel polled last.
    last_channel: u8,
}

impl IoState {
    pub fn new(variant: Variant, cfg: TmcpackIo) -> Self {
        Self {
            variant,
            cfg,
            readings: [PinReading::UNKNOWN; MAX_PINS],
            ttlout1: false,
            ttlio1: false,
            outputs_pending: false,
            last_channel: 7,
        }
    }

    pub fn config(&self) -> TmcpackIo {
        self.cfg
    }

    /// Whether any input is polled with `$30`.
    pub fn polls(&self) -> bool {
        !self.cfg.inputs.is_empty()
    }

    /// Whether the start-up writes `$32` (an output, TTLIO1's direction or the ready
    /// function is configured); otherwise the pack's outputs are left alone.
    pub fn writes_outputs(&self) -> bool {
        self.cfg.ready.is_some() || !self.cfg.outputs.is_empty() || self.ttlio1_input()
    }

    fn ttlio1_input(&self) -> bool {
        self.pin_of(Source::Ttlio1)
            .is_some_and(|pin| self.cfg.inputs.contains(pin))
    }

    fn pin_of(&self, wanted: Source) -> Option<Pin> {
        sources(self.variant)
            .iter()
            .position(|s| *s == wanted)
            .map(|i| Pin(i as u16))
    }

    /// The `$32` that sets every output as the driver wants it.
    pub fn outputs_request(&self) -> Request {
        let ttlio1_output = self
            .pin_of(Source::Ttlio1)
            .is_some_and(|pin| self.cfg.outputs.contains(pin));
        Request::Outputs {
            ttlout1: self.ttlout1,
            ttlio1_input: !ttlio1_output,
            ttlio1: self.ttlio1,
            ttlout1_ready: self.cfg.ready.is_some(),
        }
    }

    /// The `$33` of the ready output, if configured.
    pub fn ready_request(&self) -> Option<Request> {
        self.cfg.ready.map(|ready| Request::ReadyOutput {
            active_mask: ready.motors,
            reference_mask: ready.reference,
        })
    }

    /// The next `$30` channel: the configured analogue channels in turn, or channel 7 when
    /// only digital inputs are read.
    pub fn next_channel(&self) -> u8 {
        let analog: [Option<u8>; 8] = core::array::from_fn(|ch| {
            let ch = ch as u8;
            self.pin_of(Source::Analog(ch))
                .filter(|pin| self.cfg.inputs.contains(*pin))
                .map(|_| ch)
        });
        (1..=8u8)
            .map(|offset| (self.last_channel + offset) % 8)
            .find(|ch| analog.get(usize::from(*ch)).copied().flatten().is_some())
            .unwrap_or(7)
    }

    /// The configured input read longest ago (that has been read at all), and the `$30`
    /// channel whose answer refreshes it.
    pub fn stalest(&self) -> Option<(Duration, u8)> {
        sources(self.variant)
            .iter()
            .enumerate()
            .filter(|(index, _)| self.cfg.inputs.contains(Pin(*index as u16)))
            .filter_map(|(index, src)| {
                let at = self.readings.get(index)?.refreshed_at?;
                let channel = match *src {
                    Source::Analog(ch) => ch,
                    _ => self.next_channel(),
                };
                Some((at, channel))
            })
            .min_by_key(|(at, _)| *at)
    }

    /// A `$30` answer that arrived at `now`.
    pub fn on_input(&mut self, now: Duration, reply: Reply) {
        let Reply::Input {
            channel,
            value,
            inputs,
            ttlio1,
            ..
        } = reply
        else {
            return;
        };
        self.last_channel = channel;
        let variant = self.variant;
        for (index, src) in sources(variant).iter().enumerate() {
            let pin = Pin(index as u16);
            if !self.cfg.inputs.contains(pin) {
                continue;
            }
            let value = match *src {
                Source::Analog(ch) if ch == channel => f64::from(value),
                Source::Analog(_) | Source::Ttlout1 => continue,
                // "The reference inputs are inverted": the bit is 1 at a low level.
                Source::Ref(m) => bit(!inputs.contains(RefInputs::from_bits_retain(1 << m))),
                Source::Jumper1 => bit(inputs.contains(RefInputs::JUMPER1)),
                Source::Jumper2 => bit(inputs.contains(RefInputs::JUMPER2)),
                Source::Ttlio1 => bit(ttlio1),
            };
            if let Some(slot) = self.readings.get_mut(index) {
                *slot = PinReading {
                    value,
                    refreshed_at: Some(now),
                    events: 0,
                };
            }
        }
    }

    /// The last value of `pin`, for a configured pin.
    pub fn read(&self, pin: Pin) -> Option<PinReading> {
        let configured = self.cfg.inputs.contains(pin) || self.cfg.outputs.contains(pin);
        configured
            .then(|| self.readings.get(usize::from(pin.0)).copied())
            .flatten()
    }

    /// Sets output `pin` to `high`; `false` when the driver does not drive `pin`.
    pub fn set(&mut self, pin: Pin, high: bool) -> bool {
        if !self.cfg.outputs.contains(pin) {
            return false;
        }
        match source(self.variant, pin) {
            Some(Source::Ttlout1) if self.cfg.ready.is_none() => self.ttlout1 = high,
            Some(Source::Ttlio1) => self.ttlio1 = high,
            _ => return false,
        }
        self.outputs_pending = true;
        true
    }

    /// A `$32` went on the wire at `now`: the driven pins read as written.
    pub fn on_outputs_sent(&mut self, now: Duration, request: Request) {
        let Request::Outputs {
            ttlout1, ttlio1, ..
        } = request
        else {
            return;
        };
        for (index, src) in sources(self.variant).iter().enumerate() {
            let level = match src {
                Source::Ttlout1 => ttlout1,
                Source::Ttlio1 => ttlio1,
                _ => continue,
            };
            if self.cfg.outputs.contains(Pin(index as u16))
                && let Some(slot) = self.readings.get_mut(index)
            {
                *slot = PinReading {
                    value: bit(level),
                    refreshed_at: Some(now),
                    events: 0,
                };
            }
        }
    }
}

fn bit(level: bool) -> f64 {
    if level { 1.0 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_drivers::find_pin;

    #[test]
    fn tables_name_every_pin_of_8_5_once_per_variant() {
        let six: Vec<&str> = pins(Variant::SixPack).iter().map(|p| p.name).collect();
        assert_eq!(six.len(), 18);
        assert_eq!(
            &six[..8],
            &[
                "analog0", "analog1", "analog2", "analog3", "analog4", "analog5", "analog6",
                "analog7"
            ]
        );
        assert!(six.contains(&"ref5") && six.contains(&"ttlout1"));
        let quad: Vec<&str> = pins(Variant::QuadPack).iter().map(|p| p.name).collect();
        assert_eq!(quad.len(), 14);
        assert!(!quad.contains(&"ref4") && !quad.contains(&"analog5"));
        assert!(quad.contains(&"analog6") && quad.contains(&"analog7"));
        for variant in [Variant::SixPack, Variant::QuadPack] {
            assert_eq!(pins(variant).len(), sources(variant).len());
            let table = pins(variant);
            for (i, info) in table.iter().enumerate() {
                assert_eq!(find_pin(table, info.name), Some(Pin(i as u16)));
            }
        }
        let io1 = find_pin(pins(Variant::SixPack), "ttlio1").expect("ttlio1");
        let kinds = pins(Variant::SixPack)[usize::from(io1.0)].kinds;
        assert!(kinds.contains(SignalKind::DigitalIn) && kinds.contains(SignalKind::DigitalOut));
    }

    #[test]
    fn a_30_answer_refreshes_every_configured_input_with_the_reference_inputs_uninverted() {
        let table = pins(Variant::SixPack);
        let pin = |name| find_pin(table, name).expect("pin");
        let cfg = TmcpackIo {
            inputs: PinSet::EMPTY
                .with(pin("analog6"))
                .with(pin("ref1"))
                .with(pin("jumper2"))
                .with(pin("ttlio1")),
            ..TmcpackIo::default()
        };
        let mut io = IoState::new(Variant::SixPack, cfg);
        assert_eq!(io.next_channel(), 6);
        // P4 = bit 1 set: motor 1's input reads 1 on the wire = low level; bit 7: JP2 set.
        io.on_input(
            Duration::from_millis(5),
            Reply::Input {
                channel: 6,
                value: 700,
                reference: false,
                inputs: RefInputs::from_bits_retain(0b1000_0010),
                ttlio1: true,
            },
        );
        let value = |name| io.read(pin(name)).map(|r| r.value);
        assert_eq!(value("analog6"), Some(700.0));
        assert_eq!(value("ref1"), Some(0.0), "bit set = low level");
        assert_eq!(value("jumper2"), Some(1.0));
        assert_eq!(value("ttlio1"), Some(1.0));
        assert_eq!(io.read(pin("ref0")), None, "not configured");
        assert!(io.writes_outputs(), "TTLIO1 is made an input");
        assert_eq!(
            io.outputs_request(),
            Request::Outputs {
                ttlout1: false,
                ttlio1_input: true,
                ttlio1: false,
                ttlout1_ready: false
            }
        );
    }

    #[test]
    fn outputs_keep_both_levels_and_ttlout1_is_not_driven_as_ready_output() {
        let table = pins(Variant::QuadPack);
        let pin = |name| find_pin(table, name).expect("pin");
        let cfg = TmcpackIo {
            outputs: PinSet::EMPTY.with(pin("ttlio1")).with(pin("ttlout1")),
            ..TmcpackIo::default()
        };
        let mut io = IoState::new(Variant::QuadPack, cfg);
        assert!(io.set(pin("ttlio1"), true));
        assert!(io.set(pin("ttlout1"), true));
        assert!(!io.set(pin("ref0"), true));
        assert_eq!(
            io.outputs_request(),
            Request::Outputs {
                ttlout1: true,
                ttlio1_input: false,
                ttlio1: true,
                ttlout1_ready: false
            }
        );
        let ready = TmcpackIo {
            outputs: PinSet::EMPTY.with(pin("ttlout1")),
            ready: Some(ReadyOutput {
                motors: MotorMask::M0,
                reference: MotorMask::M0,
            }),
            ..TmcpackIo::default()
        };
        let mut io = IoState::new(Variant::QuadPack, ready);
        assert!(!io.set(pin("ttlout1"), true));
        assert!(matches!(
            io.outputs_request(),
            Request::Outputs {
                ttlout1_ready: true,
                ..
            }
        ));
    }
}
