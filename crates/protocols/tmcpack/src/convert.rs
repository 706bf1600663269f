//! Unit conversions of manual 8.2 (microstep frequency), 8.3 ($14 acceleration, $10 current),
//! 8.5 (supply voltage) and 8.6 ($40 baud rate, 2 ms time units).
//!
//! Microstep frequency: `f = 20 MHz / (clkdiv + 1) · v / 2^(14 + div)`, with clkdiv 0..=31,
//! div 0..=3, v −511..=511, and f at most 200 kHz. Acceleration: `amax / d` is added to the
//! velocity 500 times a second, where the manual gives two readings of `d` ([`AmaxDivisor`]):
//! 64 in the `$14` text, 16 in section 7.1's defaults.

use core::time::Duration;

use crate::Error;
use crate::request::{MAX_AMAX, MAX_CLKDIV, MAX_DIV, MAX_VELOCITY};

/// The pack's clock, 20 MHz.
pub const F_CLK_HZ: u32 = 20_000_000;
/// Upper limit of the microstep frequency (manual 8.2 note).
pub const MAX_MICROSTEP_HZ: f64 = 200_000.0;
/// Rate of the velocity accumulation and of the PI controller, 500 Hz.
pub const RAMP_HZ: u32 = 500;
/// One ramp tick, 2 ms; also the unit of T0, $40 delays and $41 timeouts.
pub const TICK: Duration = Duration::from_millis(2);
/// The largest `$14` divisor: `amax / AMAX_DIVISOR` is accumulated per tick under the
/// default reading ([`AmaxDivisor::By64`]); a velocity in 1/`AMAX_DIVISOR` units represents
/// either reading exactly.
pub const AMAX_DIVISOR: u32 = 64;

/// How much of `$14` amax the pack adds to the velocity every 2 ms tick. The manual gives
/// two readings ("SIXpack / QUADpack manual" V2.43, docs/ARCHITECTURE.md); nothing on the
/// wire tells them apart before a ramp runs, so it is a per-device setting
/// (`amax_divisor`, docs/keys/tmcpack.md).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum AmaxDivisor {
    /// amax / 64 per tick: 8.3 `$14`, "1/64 amax is accumulated with 500Hz during
    /// acceleration to vact", with "0 < amax <= vstart * 64". The default.
    #[default]
    By64,
    /// amax / 16 per tick: 7.1 "Default Values", "amax=128; // increments v by 128/16=8
    /// each 2 ms". Every ramp is 4× harsher than under [`AmaxDivisor::By64`].
    By16,
}

impl AmaxDivisor {
    /// The divisor, 64 or 16.
    pub const fn get(self) -> u32 {
        match self {
            Self::By64 => 64,
            Self::By16 => 16,
        }
    }

    /// The reading of divisor `d`; `None` for anything but 64 and 16.
    pub const fn from_divisor(d: u32) -> Option<Self> {
        match d {
            64 => Some(Self::By64),
            16 => Some(Self::By16),
            _ => None,
        }
    }
}
/// Microsteps per full step (resolution 1/16).
pub const MICROSTEPS_PER_FULLSTEP: u32 = 16;
/// Clock cycles per ramp tick: 20 MHz / 500 Hz. A motor at velocity v advances
/// `TICK_CYCLES · v / ((clkdiv+1) · 2^(14+div))` microsteps per tick.
pub const TICK_CYCLES: i64 = (F_CLK_HZ / RAMP_HZ) as i64;
/// The factory baud rate (manual 6.1).
pub const DEFAULT_BAUD: u32 = 19_200;
/// The factory transmitter switch-over delay, 3 × 2 ms = 6 ms (manual 6.1, $40).
pub const DEFAULT_SWITCHOVER_UNITS: u16 = 3;
/// Supply-voltage channel 7 scale: "1V equals value 22" (manual 8.5).
pub const SUPPLY_COUNTS_PER_VOLT: f64 = 22.0;

/// `clkdiv` and `div_i`: the two settings that turn a velocity into a step rate.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StepClock {
    clkdiv: u8,
    div: u8,
}

impl StepClock {
    /// The factory setting, clkdiv = 5 and div = 2 (manual 7.1 "Default Values").
    pub const DEFAULT: Self = Self { clkdiv: 5, div: 2 };

    /// Checks clkdiv 0..=31 and div 0..=3.
    pub const fn new(clkdiv: u8, div: u8) -> Result<Self, Error> {
        if clkdiv > MAX_CLKDIV {
            Err(Error::OutOfRange { field: "clkdiv" })
        } else if div > MAX_DIV {
            Err(Error::OutOfRange { field: "div" })
        } else {
            Ok(Self { clkdiv, div })
        }
    }

    /// clkdiv.
    pub const fn clkdiv(self) -> u8 {
        self.clkdiv
    }

    /// div_i.
    pub const fn div(self) -> u8 {
        self.div
    }

    /// `(clkdiv + 1) · 2^(14 + div)`: the denominator of the step rate. A velocity v moves
    /// `TICK_CYCLES · v / denominator()` microsteps per 2 ms tick.
    pub const fn denominator(self) -> i64 {
        (self.clkdiv as i64 + 1) << (14 + self.div as u32)
    }

    /// Microstep frequency of velocity 1.
    pub fn hz_per_unit(self) -> f64 {
        f64::from(F_CLK_HZ) / self.denominator() as f64
    }

    /// The microstep frequency of velocity `v` (signed: negative is the other direction).
    pub fn microstep_hz(self, v: i16) -> Result<f64, Error> {
        if v.unsigned_abs() > MAX_VELOCITY {
            return Err(Error::OutOfRange { field: "velocity" });
        }
        let f = self.hz_per_unit() * f64::from(v);
        if f.abs() > MAX_MICROSTEP_HZ {
            return Err(Error::FrequencyTooHigh);
        }
        Ok(f)
    }

    /// The velocity value closest to a microstep frequency.
    pub fn velocity_for_hz(self, hz: f64) -> Result<i16, Error> {
        if !hz.is_finite() {
            return Err(Error::OutOfRange { field: "frequency" });
        }
        if hz.abs() > MAX_MICROSTEP_HZ {
            return Err(Error::FrequencyTooHigh);
        }
        let v = (hz / self.hz_per_unit()).round();
        if v.abs() > f64::from(MAX_VELOCITY) {
            return Err(Error::OutOfRange { field: "velocity" });
        }
        Ok(v as i16)
    }

    /// The microstep acceleration (Hz/s) of `amax`: amax/d velocity units per 2 ms, `d`
    /// the divisor of the pack's reading.
    pub fn accel_hz_per_s(self, amax: u16, divisor: AmaxDivisor) -> Result<f64, Error> {
        if amax == 0 || amax > MAX_AMAX {
            return Err(Error::OutOfRange { field: "amax" });
        }
        Ok(f64::from(amax) / f64::from(divisor.get()) * f64::from(RAMP_HZ) * self.hz_per_unit())
    }

    /// The `amax` closest to a microstep acceleration in Hz/s under the pack's reading.
    pub fn amax_for_accel(self, hz_per_s: f64, divisor: AmaxDivisor) -> Result<u16, Error> {
        if !hz_per_s.is_finite() || hz_per_s <= 0.0 {
            return Err(Error::OutOfRange {
                field: "acceleration",
            });
        }
        let amax =
            (hz_per_s * f64::from(divisor.get()) / f64::from(RAMP_HZ) / self.hz_per_unit()).round();
        if amax < 1.0 || amax > f64::from(MAX_AMAX) {
            return Err(Error::OutOfRange { field: "amax" });
        }
        Ok(amax as u16)
    }
}

/// Checks the relations between ramp parameters that manual 8.3 states:
/// `0 < amax <= vstart · d` (the `$14` text's "vstart * 64" under its own reading: one
/// tick's change at most vstart; under the 7.1 reading, d = 16, the same bound is
/// `vstart · 16`), `vmin <= vstart`, `vstart <= vrefmax <= vmax <= 511`.
pub fn check_ramp_relations(
    vmin: u16,
    vstart: u16,
    vmax: u16,
    vrefmax: u16,
    amax: u16,
    divisor: AmaxDivisor,
) -> Result<(), Error> {
    let ok = |c: bool, field| {
        if c {
            Ok(())
        } else {
            Err(Error::OutOfRange { field })
        }
    };
    ok(
        amax > 0 && u32::from(amax) <= u32::from(vstart) * divisor.get(),
        "amax",
    )?;
    ok(vmin <= vstart, "vmin")?;
    ok(vstart <= vrefmax && vrefmax <= vmax, "vrefmax")?;
    ok(vmax <= MAX_VELOCITY, "vmax")
}

/// The $40 divisor for a baud rate: `20 MHz / (16 · baud)`, rounded.
pub fn baud_divisor(baud: u32) -> Result<u16, Error> {
    if baud == 0 {
        return Err(Error::OutOfRange { field: "baud rate" });
    }
    let d = (f64::from(F_CLK_HZ) / (16.0 * f64::from(baud))).round();
    if !(1.0..=65535.0).contains(&d) {
        return Err(Error::OutOfRange {
            field: "baud rate divisor",
        });
    }
    Ok(d as u16)
}

/// The exact baud rate a divisor gives.
pub fn baud_of_divisor(divisor: u16) -> f64 {
    f64::from(F_CLK_HZ) / (16.0 * f64::from(divisor.max(1)))
}

/// Standard rates a divisor is matched against by [`nominal_baud`].
pub const STANDARD_BAUDS: &[u32] = &[
    300, 600, 1200, 2400, 4800, 9600, 14_400, 19_200, 28_800, 38_400, 57_600, 76_800, 115_200,
    230_400, 250_000, 312_500, 416_667, 625_000, 1_250_000,
];

/// The standard rate a divisor stands for when within 2.5 % (what a UART tolerates), or the
/// exact rate rounded (divisor 65 → 19200, since 20 MHz/(16·65) = 19231).
pub fn nominal_baud(divisor: u16) -> u32 {
    let exact = baud_of_divisor(divisor);
    STANDARD_BAUDS
        .iter()
        .copied()
        .find(|&b| (exact - f64::from(b)).abs() <= f64::from(b) * 0.025)
        .unwrap_or(exact.round() as u32)
}

/// The rates a pack can be set to with `$40`: the standard rates ([`STANDARD_BAUDS`])
/// whose divisor (`20 MHz / (16 · baud)`, rounded) gives the rate within 2.5 % — what a
/// UART at the nominal rate takes. 230400, for one, is not among them: divisor 5 gives
/// 250000, 8.5 % off. In increasing order.
pub fn listed_bauds() -> impl Iterator<Item = u32> {
    STANDARD_BAUDS
        .iter()
        .copied()
        .filter(|&baud| baud_divisor(baud).is_ok_and(|d| nominal_baud(d) == baud))
}

/// The `$40` divisor of a rate [`listed_bauds`] has; [`Error::OutOfRange`] for any other.
pub fn listed_baud_divisor(baud: u32) -> Result<u16, Error> {
    match baud_divisor(baud) {
        Ok(divisor) if STANDARD_BAUDS.contains(&baud) && nominal_baud(divisor) == baud => {
            Ok(divisor)
        }
        _ => Err(Error::OutOfRange { field: "baud rate" }),
    }
}

/// The wire time of one byte, 8N1 (10 bit times).
pub fn byte_time(baud: u32) -> Duration {
    Duration::from_nanos(10_000_000_000 / u64::from(baud.max(1)))
}

/// A count of 2 ms units as a duration (T0, $40 delay, $41 timeout).
pub const fn units(n: u16) -> Duration {
    Duration::from_millis(2 * n as u64)
}

/// Highest de-bounce delay of the reference switch, ms ($16: "$FFFF=30ms").
pub const MAX_DEBOUNCE_MS: u16 = 30;

/// The $16 de-bounce mask for a delay of `ms` (0..=30 in 2 ms steps): "$0001=0ms,
/// $0003=2ms, $FFFF=30ms", one more mask bit per 2 ms cycle (the 7.1 default $0FFF is
/// "Filter delay 12-1 cycles = 22 ms").
pub const fn debounce_mask(ms: u16) -> Result<u16, Error> {
    if ms > MAX_DEBOUNCE_MS || !ms.is_multiple_of(2) {
        return Err(Error::OutOfRange {
            field: "de-bounce delay",
        });
    }
    let bits = ms / 2 + 1;
    Ok(if bits >= 16 {
        u16::MAX
    } else {
        (1 << bits) - 1
    })
}

/// The de-bounce delay in ms a $16 mask gives: (mask bits − 1) · 2 ms.
pub const fn debounce_ms(mask: u16) -> u16 {
    let bits = mask.count_ones() as u16;
    if bits == 0 { 0 } else { (bits - 1) * 2 }
}

/// The $10 value for a peak current of `percent` % of the pack's full scale
/// ("Imax = 0,8A * value/256"): `round(percent / 100 · 256)`, at most 255.
pub fn peak_value(percent: f64) -> Result<u8, Error> {
    if !percent.is_finite() || !(0.0..=100.0).contains(&percent) {
        return Err(Error::OutOfRange {
            field: "peak current",
        });
    }
    Ok((percent / 100.0 * 256.0).round().min(255.0) as u8)
}

/// The peak current in % of full scale a $10 value gives (`value / 256`).
pub fn peak_percent(value: u8) -> f64 {
    f64::from(value) / 256.0 * 100.0
}

/// A time in ms as a count of 2 ms units (T0, $40 delays, $41 timeouts): `None` unless it
/// is an even number of ms.
pub const fn units_of_ms(ms: u32) -> Option<u32> {
    if ms.is_multiple_of(2) {
        Some(ms / 2)
    } else {
        None
    }
}

/// The board variant: SIXpack drives six motors of up to 0.8 A, QUADpack four of 1.5 A.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum Variant {
    /// SIXpack, 6 channels, 800 mA peak.
    #[default]
    SixPack,
    /// QUADpack, 4 channels, 1500 mA peak (scaled by its DIP switches).
    QuadPack,
}

impl Variant {
    /// Number of motors.
    pub const fn motors(self) -> u8 {
        match self {
            Self::SixPack => 6,
            Self::QuadPack => 4,
        }
    }

    /// Peak coil current in A for a $10 value: SIXpack 0.8 A · value/256; QUADpack
    /// 1.5 A · value/256 · DIP setting (`dip_percent` 0, 33, 66 or 100; ignored on SIXpack).
    pub fn peak_current_amps(self, value: u8, dip_percent: u8) -> f64 {
        let v = f64::from(value) / 256.0;
        match self {
            Self::SixPack => 0.8 * v,
            Self::QuadPack => 1.5 * v * f64::from(dip_percent.min(100)) / 100.0,
        }
    }
}

/// Supply voltage from an analogue channel 7 value.
pub fn supply_volts(value: u16) -> f64 {
    f64::from(value) / SUPPLY_COUNTS_PER_VOLT
}
