//! What a [`TmcpackDriver`](super::TmcpackDriver) is built from, and the board settings
//! derived from it (manual 7.1 "Velocity Configuration", 8.2 step-rate formula, 8.3 $13/$14).

use core::time::Duration;

use tmcpack::convert::{DEFAULT_BAUD, F_CLK_HZ, MAX_MICROSTEP_HZ, RAMP_HZ, TICK, byte_time};
use tmcpack::{
    AmaxDivisor, CurrentLevel, FRAME_LEN, MAX_AMAX, MAX_ANALOG, MAX_CLKDIV, MAX_DIV, MAX_VELOCITY,
    MotorOptions, MotorType, OptionsLayout, ReferenceFlags, Request, StepClock, Variant,
};

use super::io::TmcpackIo;
use crate::{PositionMode, PowerDownMode};

/// $16 P5 the driver always sets: "1=Stop after reference search", so that a `Home` goal
/// ends at the new zero point with the motor inactive (0 would resume the previous action,
/// e.g. drive back to where the search started).
pub(crate) const REFERENCE_FLAGS: ReferenceFlags = ReferenceFlags::STOP_AFTER_SEARCH;

/// The response address the driver puts in its queries unless configured otherwise. The
/// pack executes any word whose first byte is its own address, replies included, so this
/// must be an address no pack on the bus has (rotary switches 0x01, 0x02… in practice).
pub const DEFAULT_REPLY_ADDRESS: u8 = 0xFE;

/// The $40 switch-over delay the driver programs at start-up by default: 1 unit = 2 ms
/// (factory: 3 units = 6 ms). A query then costs request 4.7 ms + 2 ms + reply 4.7 ms +
/// 2 ms hold ≈ 13.4 ms at 19200 baud instead of ≈ 21.4 ms.
pub const DEFAULT_SWITCHOVER_UNITS: u16 = 1;

/// What the host adds to an exchange by default, both ways (key `host_latency_ms`): a USB
/// serial adapter takes a request to the wire and hands received bytes over in 1 ms frames
/// (and holds them up to its latency timer, 1 ms when set low, FTDI's factory 16 ms), the
/// link's I/O thread wakes for them, the tick takes them in. The same figure as the QSB's: one fact,
/// `motion_drivers::DEFAULT_HOST_LATENCY`.
pub const DEFAULT_HOST_LATENCY: Duration = motion_drivers::DEFAULT_HOST_LATENCY;

/// Slack of the default $41 packet timeout beyond one word's wire time: two byte times (a
/// host or adapter may pause between the bytes of one write).
pub const PACKET_TIMEOUT_SLACK_BYTES: u32 = 2;

/// The $41 packet timeout the driver programs by default, 2 ms units: the word time plus
/// [`PACKET_TIMEOUT_SLACK_BYTES`], rounded up to 2 ms, at least the 2 units $41 allows.
/// At 19200 baud: 11 byte times = 5.7 ms → 3 units = 6 ms. A complete word always fits;
/// a word whose tail was lost is aborted 6 ms after its first byte, and the driver starts no
/// word sooner than that after the previous one (see `TmcpackDriver`), so the torn word is
/// discarded before the next one begins instead of swallowing its first bytes.
pub fn default_packet_timeout_units(baud: u32) -> u16 {
    let wire = byte_time(baud).saturating_mul(FRAME_LEN as u32 + PACKET_TIMEOUT_SLACK_BYTES);
    let units = wire.as_nanos().div_ceil(TICK.as_nanos());
    units.clamp(2, u128::from(u16::MAX)) as u16
}

/// $11 current control of one motor (manual 8.3).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Currents {
    /// I0: power-down current after `t0` of standstill.
    pub i0: CurrentLevel,
    /// I1: standstill current.
    pub i1: CurrentLevel,
    /// I2: current at constant velocity.
    pub i2: CurrentLevel,
    /// I3: current while accelerating.
    pub i3: CurrentLevel,
    /// T0: power-down delay in 2 ms units, 1..=65535.
    pub t0: u16,
}

impl Default for Currents {
    /// The manual 7.1 defaults, except I0: a stopped axis keeps holding at I1 (50 %)
    /// instead of being de-energised after T0 (a `Stop` goal means "hold").
    fn default() -> Self {
        Self {
            i0: CurrentLevel::P50,
            i1: CurrentLevel::P50,
            i2: CurrentLevel::P75,
            i3: CurrentLevel::P100,
            t0: 500,
        }
    }
}

impl Currents {
    /// `$11` setting these currents on `motor` (T0 at least 1: the manual's range starts
    /// there).
    pub(crate) fn request(self, motor: u8) -> Request {
        Request::CurrentControl {
            motor,
            i0: self.i0,
            i1: self.i1,
            i2: self.i2,
            i3: self.i3,
            t0: self.t0.max(1),
        }
    }
}

/// One configured motor: its axis limits in microsteps and its $15/$16/$18 settings.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct TmcpackChannel {
    /// Velocity limit, microsteps/s (> 0; at most 200 kHz, manual 8.2).
    pub max_velocity: f64,
    /// Acceleration limit, microsteps/s² (> 0).
    pub max_accel: f64,
    /// $15 poslimit: microsteps per revolution (rotary) or the whole travel (linear); the
    /// reference search gives up and repeats after 5/4 of it.
    pub poslimit: u32,
    /// $15 P5 motor type. The driver clears PiMode (positions use the trapezoidal ramp)
    /// and AutoNullCmd (homing only on a `Home` goal).
    pub motor_type: MotorType,
    /// $15 P6 options.
    pub options: MotorOptions,
    /// $16 de-bounce mask of the reference switch.
    pub debounce_mask: u16,
    /// $18 nulloffset: distance between the switch edge and the zero point.
    pub nulloffset: i32,
    /// $18 testnullrange.
    pub testnullrange: u16,
    /// $11 currents.
    pub currents: Currents,
    /// $10 peak current (0..=255 of the pack's full scale). The pack sets it per pair of
    /// motors (0+1, 2+3, 4+5) from the even motor's value; `None` leaves it as it is.
    pub peak_current: Option<u8>,
    /// $31 analogue stop limits of the motor's A_In: (left minimum, right maximum) in ADC
    /// counts; 0 and ≥ 1023 are "no function".
    pub analog_stop: (u16, u16),
    /// The position the axis takes at the zero point a reference search found, microsteps
    /// (`$27` after the search when not 0).
    pub home_position: i32,
    /// `$13` vstart asked for as a speed, microsteps/s (`start_velocity`): ramps start and
    /// end there. `None`: the smallest vstart the axis's acceleration allows. Never below
    /// that ("0 < amax <= vstart * 64") nor above vmax.
    pub start_velocity: Option<f64>,
    /// How `Position` goals are run: the trapezoidal ramp or the `$24` PI controller.
    pub position_mode: PositionMode,
    /// `$19` PI parameters written at start-up; `None` writes none unless the position
    /// mode is the PI controller (which writes [`PiParams::default`], the manual's).
    pub pi: Option<PiParams>,
    /// Positions the pack loads from EEPROM (`$45` bit 0) count as referenced on this axis
    /// (`reference.restore`).
    pub restore: bool,
}

/// `$19` PI controller parameters (manual 8.3): "The proportional part is 64 * position
/// difference / propdiv. The integral part integrates the part of the position difference
/// clipped to a maximum limit by intinpclip. The influence of the integral part is
/// determined by the divisor intdiv."
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct PiParams {
    /// propdiv 1..=255.
    pub propdiv: u8,
    /// intdiv 1..=32767.
    pub intdiv: u16,
    /// intclip 1..=32767.
    pub intclip: u16,
    /// intinpclip 0..=255.
    pub intinpclip: u8,
}

impl Default for PiParams {
    /// Manual 7.1 "Default Values": "propdiv=8; intdiv=129; intclip=129; intinpclip=1".
    fn default() -> Self {
        Self {
            propdiv: 8,
            intdiv: 129,
            intclip: 129,
            intinpclip: 1,
        }
    }
}

impl PiParams {
    /// `$19` with these parameters for `motor`.
    pub(crate) fn request(self, motor: u8) -> Request {
        Request::PiParameters {
            motor,
            propdiv: self.propdiv,
            intdiv: self.intdiv,
            intclip: self.intclip,
            intinpclip: self.intinpclip,
        }
    }
}

impl TmcpackChannel {
    /// The `$19` the start-up writes: the configured parameters, or the manual's defaults
    /// for a motor in the PI position mode; none otherwise (the pack keeps its own).
    pub fn written_pi(&self) -> Option<PiParams> {
        self.pi
            .or((self.position_mode == PositionMode::Pi).then(PiParams::default))
    }

    /// Whether the $15 type says rotary with a usable poslimit (the pack then reports the
    /// position modulo poslimit).
    pub fn cyclic(&self) -> bool {
        self.motor_type.contains(MotorType::ROTARY) && self.poslimit > 0
    }
}

impl Default for TmcpackChannel {
    /// One revolution of a 200-step motor per second (3200 microsteps/s), reached in
    /// 0.2 s; the manual 7.1 reference defaults (poslimit 400·16, FilterSwitch, FastRef,
    /// de-bounce $0FFF, testnullrange 15·16) without NullCenter.
    fn default() -> Self {
        Self {
            max_velocity: 3200.0,
            max_accel: 16_000.0,
            poslimit: 400 * 16,
            motor_type: MotorType::FILTER_SWITCH,
            options: MotorOptions::FAST_REF,
            debounce_mask: 0x0FFF,
            nulloffset: 0,
            testnullrange: 15 * 16,
            currents: Currents::default(),
            peak_current: None,
            analog_stop: (0, MAX_ANALOG),
            home_position: 0,
            start_velocity: None,
            position_mode: PositionMode::Ramp,
            pi: None,
            restore: true,
        }
    }
}

/// Everything a [`TmcpackDriver`](super::TmcpackDriver) needs.
#[derive(Debug, Clone, PartialEq)]
pub struct TmcpackDriverConfig {
    /// RS-232 / RS-485 address of the pack (rotary switches).
    pub address: u8,
    /// SIXpack (6 motors) or QUADpack (4).
    pub variant: Variant,
    /// The line rate of the link, baud: the rate it opens at (wire-time budgets; without
    /// `target_baud` the driver writes this same rate back with $40, so the pack's rate is
    /// never changed behind the link's back).
    pub baud: u32,
    /// The rate the pack is switched to with `$40` at start-up (key `baud`), the link
    /// following; `None`: the pack stays at the link's rate (driver module `rate`).
    pub target_baud: Option<u32>,
    /// Response address of the driver's queries (see [`DEFAULT_REPLY_ADDRESS`]).
    pub reply_address: u8,
    /// $40 transmitter switch-over delay to program at start-up, 2 ms units (1..=1000);
    /// `None` leaves the pack's setting (factory 6 ms) and sends no $40.
    pub switchover_units: Option<u16>,
    /// $41 packet timeout to program at start-up, 2 ms units (2..=65535); `None`: the
    /// default for the baud rate ([`default_packet_timeout_units`]).
    pub packet_timeout_units: Option<u16>,
    /// The longest packet timeout of any pack on the bus, 2 ms units (0: this pack's own).
    /// Every pack frames every word on the bus, so the driver spaces its words by this.
    pub bus_packet_timeout_units: u16,
    /// Motors polled on the whole bus this pack shares (all packs); 0 = this pack's own.
    /// Only sizes [`refresh_budget`](motion_drivers::Driver::refresh_budget).
    pub bus_motors: u8,
    /// Per motor 0..=5: `Some` for a motor with an axis (configured, polled, driven).
    pub channels: [Option<TmcpackChannel>; 6],
    /// Inputs to poll, outputs to drive, the ready output.
    pub io: TmcpackIo,
    /// How much of `$14` amax the pack's firmware adds per 2 ms tick: amax/64 (the `$14`
    /// text, default) or amax/16 (7.1's defaults); key `amax_divisor`.
    pub amax_divisor: AmaxDivisor,
    /// Where the pack's firmware keeps StopNoRef in `$15` P6: bit 5 (the table, default)
    /// or bit 6 (the prose; NullPositive then bit 5); key `stop_no_ref_bit`.
    pub options_layout: OptionsLayout,
    /// On a CAN link (manual 6.2): its bit rate, bits per second; `None` on RS-232 /
    /// RS-485. The driver then frames CAN telegrams (`address << 3`) and times them by the
    /// pack's command cache (the `can` module).
    pub can_bitrate: Option<u32>,
    /// The `$45` power-down mode (key `power_down`): off (no `$45`), save, or restore.
    pub power_down: PowerDownMode,
    /// The `$17` motor characteristics table to write at start-up (key
    /// `microstep_table`); `None` leaves the pack's (the factory sine after a reset).
    pub microstep_table: Option<[u8; 16]>,
    /// How much later than on the wire an answer may reach the driver (key
    /// `host_latency_ms`, [`DEFAULT_HOST_LATENCY`]): part of every reply window.
    pub host_latency: Duration,
    /// How long the pack must have been silent (with [`MAX_TIMEOUTS`](super::MAX_TIMEOUTS)
    /// requests unanswered in a row) before it is declared not answering, and how long an
    /// unanswered query's answer is taken for late (key `silence_ms`,
    /// [`motion_drivers::DEFAULT_SILENCE`]).
    pub not_answering: Duration,
}

impl TmcpackDriverConfig {
    /// The $41 packet timeout the driver programs, 2 ms units.
    pub fn packet_timeout(&self) -> u16 {
        self.packet_timeout_units
            .unwrap_or_else(|| default_packet_timeout_units(self.baud))
    }
}

impl Default for TmcpackDriverConfig {
    /// Address 1, SIXpack, 19200 baud, replies to 0xFE, 2 ms switch-over, no motors.
    fn default() -> Self {
        Self {
            address: 1,
            variant: Variant::SixPack,
            baud: DEFAULT_BAUD,
            target_baud: None,
            reply_address: DEFAULT_REPLY_ADDRESS,
            switchover_units: Some(DEFAULT_SWITCHOVER_UNITS),
            packet_timeout_units: None,
            bus_packet_timeout_units: 0,
            bus_motors: 0,
            channels: [None; 6],
            io: TmcpackIo::default(),
            amax_divisor: AmaxDivisor::By64,
            options_layout: OptionsLayout::Table,
            can_bitrate: None,
            power_down: PowerDownMode::Off,
            microstep_table: None,
            host_latency: DEFAULT_HOST_LATENCY,
            not_answering: motion_drivers::DEFAULT_SILENCE,
        }
    }
}

/// A motor's fixed scales: divider, microstep frequency per velocity unit and the ramp
/// values its axis limits give (manual 7.1: "div_i should be set so, that the maximum
/// velocity vmax could be set between 256 and 511").
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scale {
    pub clock: StepClock,
    /// Microsteps/s of velocity 1.
    pub hz: f64,
    /// vmax from the axis velocity limit.
    pub vmax: u16,
    /// amax from the axis acceleration limit.
    pub amax: u16,
    /// The pack's `$14` reading: amax / divisor per 2 ms tick.
    pub divisor: AmaxDivisor,
    /// vstart: the smallest value with amax <= vstart · divisor ($14: "vstart * 64" under
    /// its own reading), for the amax of a stop at the axis limit too (rounded up, see
    /// [`Scale::stop_amax`]); or the channel's `start_velocity` rounded down when that is
    /// more; at most vmax.
    pub vstart: u16,
    /// vrefmax programmed at start-up: a quarter of vmax, at least vstart.
    pub vrefmax: u16,
}

/// Slack so that values that are exact multiples are not floored one unit down by
/// rounding.
const EPS: f64 = 1e-6;

/// Microsteps/s of velocity 1 at `clkdiv`, `div`.
fn hz_per_unit(clkdiv: u8, div: u8) -> f64 {
    f64::from(F_CLK_HZ) / (f64::from(clkdiv) + 1.0) / f64::from(1u32 << (14 + u32::from(div)))
}

/// Velocity limit of a channel as the pack can reach it (at most 200 kHz).
fn reachable(max_velocity: f64) -> f64 {
    if max_velocity.is_finite() && max_velocity > 0.0 {
        max_velocity.min(MAX_MICROSTEP_HZ)
    } else {
        0.0
    }
}

/// The global clkdiv (manual 7.1: chosen "so that the required maximum step velocity is
/// achieved with v_i = 511 and small values div_i = 0"): the largest clkdiv at which the
/// fastest configured motor still reaches its limit with v = 511, div = 0.
pub(crate) fn clkdiv_for(channels: &[Option<TmcpackChannel>]) -> u8 {
    let fastest = channels
        .iter()
        .flatten()
        .map(|c| reachable(c.max_velocity))
        .fold(0.0, f64::max);
    if fastest <= 0.0 {
        return StepClock::DEFAULT.clkdiv();
    }
    let top = f64::from(F_CLK_HZ) * f64::from(MAX_VELOCITY) / f64::from(1u32 << 14);
    let plus_one = (top / fastest + EPS).floor();
    (plus_one - 1.0).clamp(0.0, f64::from(MAX_CLKDIV)) as u8
}

impl Scale {
    /// The scales of `channel` under the global `clkdiv` and the pack's `$14` reading.
    pub fn new(clkdiv: u8, channel: &TmcpackChannel, divisor: AmaxDivisor) -> Self {
        let limit = reachable(channel.max_velocity);
        let mut div = 0;
        for d in (0..=MAX_DIV).rev() {
            if hz_per_unit(clkdiv, d) * f64::from(MAX_VELOCITY) >= limit {
                div = d;
                break;
            }
        }
        let clock = StepClock::new(clkdiv, div).unwrap_or(StepClock::DEFAULT);
        let hz = clock.hz_per_unit();
        let vmax = units(limit, hz).clamp(1, MAX_VELOCITY);
        let mut amax = amax_units(channel.max_accel, hz, divisor).clamp(1, MAX_AMAX);
        let stop = amax_up(channel.max_accel, hz, divisor).clamp(1, MAX_AMAX);
        let per = divisor.get() as u16;
        let mut vstart = stop.max(amax).div_ceil(per).max(1);
        if let Some(asked) = channel.start_velocity {
            // `start_velocity`, rounded down, but never below one tick's change at amax.
            vstart = vstart.max(units(reachable(asked), hz));
        }
        if vstart > vmax {
            vstart = vmax;
            amax = amax.min(vmax.saturating_mul(per));
        }
        let vrefmax = (vmax / 4).clamp(vstart, vmax);
        Self {
            clock,
            hz,
            vmax,
            amax,
            divisor,
            vstart,
            vrefmax,
        }
    }

    /// The smallest velocity and acceleration this motor's clock represents: velocity 1
    /// (microsteps/s, manual "Instruction Set": f = f_clk / (clkdiv + 1) · v / 2^(14 + div))
    /// and amax 1 (amax / divisor is accumulated at 500 Hz: 500/64 or 500/16 velocity
    /// units/s²).
    pub fn floor(&self) -> motion_drivers::RateFloor {
        motion_drivers::RateFloor {
            velocity: self.hz,
            profile_velocity: self.hz,
            accel: self.hz * f64::from(RAMP_HZ) / f64::from(self.divisor.get()),
        }
    }

    /// The velocity value for a magnitude in microsteps/s, rounded down (never faster than
    /// asked); `None` when it is not finite or beyond the board (±511, 200 kHz).
    pub fn velocity(&self, hz: f64) -> Option<u16> {
        if !hz.is_finite() || hz.abs() > MAX_MICROSTEP_HZ * (1.0 + EPS) {
            return None;
        }
        let v = (hz.abs() / self.hz + EPS).floor();
        (v <= f64::from(MAX_VELOCITY)).then_some(v as u16)
    }

    /// The amax for an acceleration in microsteps/s², rounded down, at least 1 and at most
    /// vstart · divisor (the $14 relation); `None` when not finite or not positive.
    pub fn amax(&self, accel: f64) -> Option<u16> {
        if !accel.is_finite() || accel <= 0.0 {
            return None;
        }
        Some(amax_units(accel, self.hz, self.divisor).clamp(1, self.amax_cap()))
    }

    /// The largest amax the $14 relation allows with this vstart.
    fn amax_cap(&self) -> u16 {
        self.vstart
            .saturating_mul(self.divisor.get() as u16)
            .min(MAX_AMAX)
    }

    /// The amax of a stop at `decel` microsteps/s², rounded UP (a stop is never gentler
    /// than asked), at least 1 and at most vstart · divisor (the $14 relation); `None` when
    /// not finite or not positive.
    pub fn stop_amax(&self, decel: f64) -> Option<u16> {
        if !decel.is_finite() || decel <= 0.0 {
            return None;
        }
        Some(amax_up(decel, self.hz, self.divisor).clamp(1, self.amax_cap()))
    }

    /// Upper bound of the time a motor at `v` needs to stop with `amax` (amax / divisor
    /// per 2 ms tick), plus two ticks.
    pub fn stop_time(&self, v: u16, amax: u16) -> Duration {
        let ticks = (u32::from(v) * self.divisor.get()).div_ceil(u32::from(amax.max(1))) + 2;
        Duration::from_millis(2 * u64::from(ticks))
    }
}

fn units(hz: f64, per_unit: f64) -> u16 {
    (hz / per_unit + EPS)
        .floor()
        .clamp(0.0, f64::from(u16::MAX)) as u16
}

/// amax for `accel`, rounded up.
fn amax_up(accel: f64, per_unit: f64, divisor: AmaxDivisor) -> u16 {
    if !accel.is_finite() || accel <= 0.0 {
        return 1;
    }
    let a = accel * f64::from(divisor.get()) / f64::from(RAMP_HZ) / per_unit;
    (a - EPS).ceil().clamp(0.0, f64::from(u16::MAX)) as u16
}

fn amax_units(accel: f64, per_unit: f64, divisor: AmaxDivisor) -> u16 {
    if !accel.is_finite() || accel <= 0.0 {
        return 1;
    }
    let a = accel * f64::from(divisor.get()) / f64::from(RAMP_HZ) / per_unit;
    (a + EPS).floor().clamp(0.0, f64::from(u16::MAX)) as u16
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(v: f64, a: f64) -> TmcpackChannel {
        TmcpackChannel {
            max_velocity: v,
            max_accel: a,
            ..TmcpackChannel::default()
        }
    }

    #[test]
    fn clkdiv_lets_the_fastest_motor_reach_its_limit_with_v_511_div_0() {
        // 8.2: f = 20 MHz / (clkdiv+1) · v / 2^(14+div). 32000 µsteps/s: 20e6·511/16384 =
        // 623779 Hz → clkdiv+1 = 19 gives 32830 Hz ≥ 32000, 20 would give 31189.
        let chans = [
            Some(channel(32_000.0, 160_000.0)),
            None,
            None,
            None,
            None,
            None,
        ];
        let clkdiv = clkdiv_for(&chans);
        assert_eq!(clkdiv, 18);
        let scale = Scale::new(clkdiv, &channel(32_000.0, 160_000.0), AmaxDivisor::By64);
        assert_eq!(scale.clock.div(), 0);
        assert_eq!(scale.vmax, 498); // 32000 / 64.25 = 498.05
        assert!(f64::from(scale.vmax) * scale.hz <= 32_000.0);
        // 7.1: vmax between 256 and 511 for resolution.
        assert!(scale.vmax >= 256);
        // amax = 160000 · 64 / 500 / 64.25 = 318.8
        assert_eq!(scale.amax, 318);
        assert_eq!(scale.vstart, 5);
    }

    #[test]
    fn slow_motors_get_a_larger_divider() {
        let clkdiv = 18;
        let scale = Scale::new(clkdiv, &channel(1600.0, 6400.0), AmaxDivisor::By64);
        // div is at most 3: 1600 / (64.25 / 8) = 199.2, the finest the pack has.
        assert_eq!(scale.clock.div(), 3);
        assert_eq!(scale.vmax, 199);
        assert!(f64::from(scale.vmax) * scale.hz <= 1600.0);
        let medium = Scale::new(clkdiv, &channel(12_000.0, 6400.0), AmaxDivisor::By64);
        assert_eq!(medium.clock.div(), 1);
        assert!(medium.vmax >= 256, "vmax {}", medium.vmax);
    }

    #[test]
    fn the_200_khz_limit_caps_clkdiv_and_vmax() {
        let chans = [Some(channel(1e9, 1e6)), None, None, None, None, None];
        let clkdiv = clkdiv_for(&chans);
        let scale = Scale::new(clkdiv, &channel(1e9, 1e6), AmaxDivisor::By64);
        assert!(f64::from(scale.vmax) * scale.hz <= MAX_MICROSTEP_HZ);
        assert!(scale.velocity(250_000.0).is_none());
        assert!(scale.velocity(f64::NAN).is_none());
    }

    #[test]
    fn no_channels_keep_the_factory_clock() {
        assert_eq!(clkdiv_for(&[None; 6]), 5);
    }

    #[test]
    fn a_stop_decelerates_at_least_as_hard_as_asked() {
        let scale = Scale::new(18, &channel(32_000.0, 160_000.0), AmaxDivisor::By64);
        // 160000 · 64 / 500 / 64.25 = 318.8: a move uses 318, a stop 319.
        assert_eq!(scale.amax(160_000.0), Some(318));
        assert_eq!(scale.stop_amax(160_000.0), Some(319));
        assert!(u32::from(scale.vstart) * 64 >= 319);
        let a = |amax: u16| f64::from(amax) / 64.0 * 500.0 * scale.hz;
        assert!(a(319) >= 160_000.0);
        assert_eq!(scale.stop_amax(f64::NAN), None);
        assert_eq!(scale.stop_amax(0.0), None);
    }

    #[test]
    fn the_default_packet_timeout_holds_a_word_and_two_byte_times() {
        // 19200 baud: 11 · 0.52 ms = 5.7 ms → 3 units.
        assert_eq!(default_packet_timeout_units(19_200), 3);
        // 9600 baud: 11.5 ms → 6 units; 115200: 0.95 ms → the $41 minimum of 2 units.
        assert_eq!(default_packet_timeout_units(9_600), 6);
        assert_eq!(default_packet_timeout_units(115_200), 2);
        for baud in [1200, 9600, 19_200, 57_600] {
            let t = tmcpack::convert::units(default_packet_timeout_units(baud));
            assert!(t >= byte_time(baud) * 11);
        }
    }

    #[test]
    fn stop_time_counts_ticks_of_amax_over_64() {
        // 511 · 64 / 128 = 255.5 → 256 ticks + 2.
        let scale = Scale::new(18, &channel(32_000.0, 160_000.0), AmaxDivisor::By64);
        assert_eq!(scale.stop_time(511, 128), Duration::from_millis(516));
    }

    /// Manual 7.1 "Default Values": "amax=128; // increments v by 128/16=8 each 2 ms". A
    /// pack read that way gets a quarter of the amax for the same acceleration, a vstart
    /// that keeps one tick's change within it, and stops in a quarter of the ticks.
    #[test]
    fn the_7_1_reading_divides_amax_by_16() {
        let ch = channel(32_000.0, 160_000.0);
        let by64 = Scale::new(18, &ch, AmaxDivisor::By64);
        let by16 = Scale::new(18, &ch, AmaxDivisor::By16);
        // 160000 · 16 / 500 / 64.25 = 79.7: a move uses 79, a stop 80.
        assert_eq!(by16.amax, 79);
        assert_eq!(by16.amax(160_000.0), Some(79));
        assert_eq!(by16.stop_amax(160_000.0), Some(80));
        // vstart: the smallest with 80 <= vstart · 16, as 319 <= 5 · 64 under $14's text.
        assert_eq!((by64.vstart, by16.vstart), (5, 5));
        let a = |amax: u16| f64::from(amax) / 16.0 * 500.0 * by16.hz;
        assert!(a(80) >= 160_000.0 && a(79) <= 160_000.0);
        // The smallest acceleration the pack represents is 4× coarser.
        assert!((by16.floor().accel - 4.0 * by64.floor().accel).abs() < 1e-9);
        // 511 · 16 / 128 = 63.9 → 64 ticks + 2.
        assert_eq!(by16.stop_time(511, 128), Duration::from_millis(132));
    }
}
