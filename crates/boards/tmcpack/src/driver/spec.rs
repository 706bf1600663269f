//! The driver config of a Trinamic pack from the neutral [`DriverSpec`]: its axes, machine
//! keys and signals (docs/keys/tmcpack.md), and the packs sharing its link; the manual's
//! ranges the config is validated against; and the parameters that config gives the pack,
//! as `motionctl list` shows them.

use core::time::Duration;

use motion_base::counts_to_i32_saturating;
use tmcpack::convert::{byte_time, debounce_mask, debounce_ms, peak_percent, peak_value};
use tmcpack::{
    AmaxDivisor, CurrentLevel, FRAME_LEN, MotorMask, MotorOptions, MotorType, OptionsLayout,
    Variant,
};

use super::{
    Currents, DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS, PinSet, ReadyOutput, TmcpackChannel,
    TmcpackDriverConfig, TmcpackIo, default_packet_timeout_units,
};
use crate::{PackVariant, TmcpackAxisKeys, TmcpackDeviceKeys};
use motion_drivers::spec::{
    DeviceMachine, Direction, DriverAxis, DriverSignal, DriverSpec, FromSpec, Param, ParamOwner,
    SpecError,
};
use motion_drivers::{Model, SignalKind};

/// Highest `$16` de-bounce time, ms.
pub const MAX_DEBOUNCE_MS: u16 = tmcpack::convert::MAX_DEBOUNCE_MS;

/// Highest `$15` poslimit, microsteps.
pub const MAX_POSLIMIT: u32 = tmcpack::MAX_POSLIMIT;

/// Whether `percent` is a current level of `$11` (100, 75, 50, 38, 25, 19, 13, 9, 0).
pub fn is_current_level(percent: u8) -> bool {
    CurrentLevel::from_percent(percent).is_some()
}

/// Whether `percent` is a current level below 19 %, the lowest that microsteps properly
/// (manual 7.1 "Setting of Motor Current"; 0 % switches the motor off).
pub fn is_weak_current(percent: u8) -> bool {
    matches!(
        CurrentLevel::from_percent(percent),
        Some(CurrentLevel::P13 | CurrentLevel::P9)
    )
}

/// The wire time of one 9-byte word at `baud`.
pub fn word_time(baud: u32) -> Duration {
    byte_time(baud) * FRAME_LEN as u32
}

impl From<PackVariant> for Variant {
    fn from(variant: PackVariant) -> Self {
        match variant {
            PackVariant::Sixpack => Self::SixPack,
            PackVariant::Quadpack => Self::QuadPack,
        }
    }
}

fn device_keys(machine: &DeviceMachine) -> TmcpackDeviceKeys {
    machine.get_or_default()
}

fn axis_keys(axis: &DriverAxis) -> TmcpackAxisKeys {
    axis.machine.get_or_default()
}

/// The $41 timeout of a pack with `machine` keys on a line of `line_rate`, 2 ms units.
fn packet_timeout_units(machine: &DeviceMachine, line_rate: Option<u32>) -> u16 {
    match device_keys(machine).packet_timeout_ms {
        Some(ms) => (ms / 2).min(u32::from(u16::MAX)) as u16,
        None => default_packet_timeout_units(line_rate.unwrap_or(19_200)),
    }
}

/// The inputs, outputs and ready output of a pack with `signals` and `machine` keys.
fn io(signals: &[DriverSignal], machine: &DeviceMachine) -> TmcpackIo {
    let mut io = TmcpackIo::default();
    for signal in signals {
        match signal.kind {
            SignalKind::DigitalIn | SignalKind::AnalogIn => io.inputs = io.inputs.with(signal.pin),
            SignalKind::DigitalOut => io.outputs = io.outputs.with(signal.pin),
            // No pin of the pack captures or triggers.
            SignalKind::Capture | SignalKind::Trigger => {}
        }
    }
    io.ready = device_keys(machine).ready_output.map(|r| ReadyOutput {
        motors: MotorMask::from_bits_retain(r.motors),
        reference: MotorMask::from_bits_retain(r.reference),
    });
    io
}

/// The `$11` level of a `current.<key>` percentage; `None` when not given.
fn level(
    percent: Option<u8>,
    channel: usize,
    key: &'static str,
) -> Result<Option<CurrentLevel>, SpecError> {
    percent
        .map(|p| {
            CurrentLevel::from_percent(p).ok_or_else(|| SpecError {
                channel: Some(channel),
                key,
                message: format!("{p} is not a current level of the pack (manual 8.3 $11)"),
            })
        })
        .transpose()
}

/// `flags` with each flag of `given` set as its key says (`with`: the flags type's
/// setter); a key not written leaves its flag as it is, the driver's default.
fn given_flags<F: Copy>(flags: F, given: &[(F, Option<bool>)], with: fn(F, F, bool) -> F) -> F {
    given.iter().fold(flags, |flags, &(flag, on)| {
        on.map_or(flags, |on| with(flags, flag, on))
    })
}

/// The driver's view of the motor behind `axis`: limits in microsteps, and the machine keys.
fn channel_config(axis: &DriverAxis) -> Result<TmcpackChannel, SpecError> {
    let keys = axis_keys(axis);
    let d = TmcpackChannel::default();
    let cpu = axis.counts_per_unit;
    let scale = cpu.abs();
    let r = keys.reference;
    let c = keys.current;
    // `reference.side` / `home.direction` are in axis units; NullLeft is in microsteps.
    let null_left = (axis.home.direction == Direction::Negative) == (cpu > 0.0);
    let rotary = keys.rotary == Some(true);
    let motor_type = given_flags(
        d.motor_type
            .with(MotorType::NULL_LEFT, null_left)
            .with(MotorType::ROTARY, rotary),
        &[
            (MotorType::NULL_CENTER, r.center),
            (MotorType::STOP_NULL, r.stop_at_switch),
        ],
        MotorType::with,
    );
    let options = given_flags(
        d.options,
        &[
            (MotorOptions::NULL_POSITIVE, r.active_high),
            (MotorOptions::STOP_SOFT, r.soft_stop),
            (MotorOptions::FAST_REF, r.fast),
            (MotorOptions::MECH_REF, r.mechanical),
        ],
        MotorOptions::with,
    );
    let range = match keys.revolution {
        Some(revolution) if rotary => revolution,
        _ => axis.max - axis.min,
    };
    let poslimit = (range * scale).round().clamp(0.0, f64::from(MAX_POSLIMIT)) as u32;
    let counts = |units: f64| (units * scale).round();
    let channel = axis.channel;
    let limits = axis.limits();
    let mut config = TmcpackChannel {
        max_velocity: limits.max_velocity,
        max_accel: limits.max_accel,
        poslimit,
        motor_type,
        options,
        debounce_mask: r
            .debounce_ms
            .and_then(|ms| debounce_mask(ms).ok())
            .unwrap_or(d.debounce_mask),
        nulloffset: r
            .null_offset
            .map_or(d.nulloffset, |u| counts_to_i32_saturating(counts(u))),
        testnullrange: r
            .test_range
            .map_or(d.testnullrange, |u| counts(u).clamp(0.0, 65535.0) as u16),
        currents: Currents {
            i0: level(c.standby, channel, "current.standby")?.unwrap_or(d.currents.i0),
            i1: level(c.standstill, channel, "current.standstill")?.unwrap_or(d.currents.i1),
            i2: level(c.constant, channel, "current.constant")?.unwrap_or(d.currents.i2),
            i3: level(c.accel, channel, "current.accel")?.unwrap_or(d.currents.i3),
            t0: c
                .standby_delay_ms
                .map_or(d.currents.t0, |ms| (ms / 2).clamp(1, 65_535) as u16),
        },
        peak_current: c.peak.and_then(|p| peak_value(p).ok()).or(d.peak_current),
        analog_stop: (
            keys.analog_stop_left.unwrap_or(d.analog_stop.0),
            keys.analog_stop_right.unwrap_or(d.analog_stop.1),
        ),
        home_position: counts_to_i32_saturating(axis.home.position * cpu),
        ..d
    };
    super::spec_drive::channel(axis, &keys, &mut config);
    Ok(config)
}

fn level_text(l: CurrentLevel) -> String {
    format!("{} %", l.percent())
}

fn yes(b: bool) -> String {
    b.to_string()
}

/// A distance for people: at most 3 decimals, trailing zeros dropped.
fn num(x: f64) -> String {
    let text = format!("{x:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

fn mask_list(mask: MotorMask) -> String {
    let motors: Vec<String> = (0..6u8)
        .filter(|m| mask.has(*m))
        .map(|m| m.to_string())
        .collect();
    format!("[{}]", motors.join(", "))
}

impl FromSpec for TmcpackDriverConfig {
    /// The driver config of the tmcpack device `spec` describes, and of the packs sharing
    /// its link: every pack on a link shares its polling budget (axes and input polls) and
    /// frames every word on it (the longest packet timeout spaces the words).
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError> {
        let keys = device_keys(&spec.machine);
        let mut driver = Self {
            address: spec.address as u8,
            variant: device_keys(&spec.machine).variant.into(),
            reply_address: keys.reply_address.unwrap_or(DEFAULT_REPLY_ADDRESS),
            switchover_units: Some(
                keys.switchover_ms
                    .map_or(DEFAULT_SWITCHOVER_UNITS, |ms| (ms / 2).max(1)),
            ),
            io: io(&spec.signals, &spec.machine),
            ..Self::default()
        };
        match spec.framing {
            // The link's rate is the CAN bit rate; the pack's RS-232 side keeps its own.
            motion_drivers::LinkFraming::Can => {
                driver.can_bitrate = Some(spec.line_rate.unwrap_or(tmcpack::CAN_DEFAULT_BITRATE));
            }
            motion_drivers::LinkFraming::Bytes => {
                if let Some(baud) = spec.line_rate {
                    driver.baud = baud;
                }
            }
        }
        driver.target_baud = keys.baud;
        // Packet timeouts cover a word at the slower of the link's rate and the `baud`.
        let line_rate = match (spec.line_rate, keys.baud) {
            (Some(link), Some(target)) => Some(link.min(target)),
            (link, target) => link.or(target),
        };
        if let Some(d) = keys.amax_divisor {
            driver.amax_divisor =
                AmaxDivisor::from_divisor(u32::from(d)).ok_or_else(|| SpecError {
                    channel: None,
                    key: "amax_divisor",
                    message: format!("{d} is not a reading of $14; allowed: 64, 16"),
                })?;
        }
        if let Some(bit) = keys.stop_no_ref_bit {
            driver.options_layout =
                OptionsLayout::from_stop_no_ref_bit(bit).ok_or_else(|| SpecError {
                    channel: None,
                    key: "stop_no_ref_bit",
                    message: format!("{bit} is not a reading of $15 P6; allowed: 5, 6"),
                })?;
        }
        driver.packet_timeout_units = Some(packet_timeout_units(&spec.machine, line_rate));
        super::spec_drive::device(&keys, &mut driver);
        super::spec_timing::config(&keys, &mut driver);
        let axes: usize = spec.bus.iter().map(|peer| peer.axes).sum();
        let input_polls = spec
            .bus
            .iter()
            .filter(|peer| {
                peer.model == Model::TMCPACK
                    && io(&peer.signals, &peer.machine).inputs != PinSet::EMPTY
            })
            .count();
        driver.bus_motors = (axes + input_polls).min(usize::from(u8::MAX)) as u8;
        driver.bus_packet_timeout_units = spec
            .bus
            .iter()
            .filter(|peer| peer.model == Model::TMCPACK)
            .map(|peer| packet_timeout_units(&peer.machine, line_rate))
            .max()
            .unwrap_or(0);
        for axis in &spec.axes {
            if let Some(slot) = driver.channels.get_mut(axis.channel) {
                *slot = Some(channel_config(axis)?);
            }
        }
        Ok(driver)
    }

    /// The machine parameters of the pack and its axes, as the driver uses them.
    fn params(&self, spec: &DriverSpec) -> Vec<Param> {
        let mut out = Vec::new();
        let mut row = |owner: ParamOwner, key: &'static str, value: String| {
            out.push(Param { owner, key, value });
        };
        let dev = ParamOwner::Device;
        row(
            dev,
            "reply_address",
            match self.can_bitrate {
                // Manual 6.2: "For responding the address is shifted to the left by 3 bits".
                Some(_) => format!(
                    "{0} (0x{0:02X}; CAN answers on ${1:03X}, the pack's commands on ${2:03X})",
                    self.reply_address,
                    u16::from(self.reply_address) << 3,
                    u16::from(self.address) << 3
                ),
                None => format!("{0} (0x{0:02X})", self.reply_address),
            },
        );
        let switchover = self.switchover_units.unwrap_or(DEFAULT_SWITCHOVER_UNITS);
        let serial_only = |value: String| match self.can_bitrate {
            Some(_) => "not sent on CAN (the RS-232 / RS-485 line's)".to_owned(),
            None => value,
        };
        row(
            dev,
            "switchover_ms",
            serial_only(format!("{} ms ($40)", 2 * u32::from(switchover))),
        );
        row(
            dev,
            "baud",
            match self.target_baud {
                Some(baud) => format!(
                    "{baud} ($40 divisor {} at start-up; the link follows)",
                    tmcpack::convert::baud_divisor(baud).unwrap_or(0)
                ),
                None => format!("{} (the link's rate, not changed)", self.baud),
            },
        );
        row(
            dev,
            "packet_timeout_ms",
            serial_only(format!("{} ms ($41)", 2 * u32::from(self.packet_timeout()))),
        );
        row(
            dev,
            "ready_output",
            match self.io.ready {
                Some(r) => format!(
                    "motors {}, reference {} (TTLOUT1: $32 P3 = 1, $33)",
                    mask_list(r.motors),
                    mask_list(r.reference)
                ),
                None => "off".into(),
            },
        );
        row(
            dev,
            "amax_divisor",
            match self.amax_divisor {
                AmaxDivisor::By64 => "64 ($14 text: amax/64 per 2 ms)",
                AmaxDivisor::By16 => "16 (7.1 defaults: amax/16 per 2 ms)",
            }
            .into(),
        );
        row(
            dev,
            "stop_no_ref_bit",
            match self.options_layout {
                OptionsLayout::Table => "5 ($15 table: StopNoRef bit 5)",
                OptionsLayout::Prose => "6 ($15 prose: StopNoRef bit 6)",
            }
            .into(),
        );
        self.drive_device_rows(&mut row);
        super::spec_timing::rows(self, &mut row);
        let pack = Variant::from(device_keys(&spec.machine).variant);
        for (a, axis) in spec.axes.iter().enumerate() {
            let Some(Some(ch)) = self.channels.get(axis.channel) else {
                continue;
            };
            let owner = ParamOwner::Axis(a);
            let unit = axis.unit.as_str();
            let per_unit = axis.counts_per_unit.abs();
            // The pair's value: the even motor's, else the odd one's (manual 8.3 $10).
            let pair = axis.channel & !1;
            let peak = [pair, pair + 1].into_iter().find_map(|m| {
                self.channels
                    .get(m)
                    .copied()
                    .flatten()
                    .and_then(|c| c.peak_current)
            });
            row(
                owner,
                "current.peak",
                match peak {
                    Some(v) => {
                        let amps = pack.peak_current_amps(v, 100);
                        let dip = if pack == Variant::QuadPack {
                            " × the DIP setting"
                        } else {
                            ""
                        };
                        format!("{:.1} % ($10 = {v}, {amps:.2} A{dip})", peak_percent(v))
                    }
                    None => "not written: the pack keeps its own (factory $10 = 128, 50 %)".into(),
                },
            );
            let c = ch.currents;
            row(owner, "current.standby", level_text(c.i0));
            row(owner, "current.standstill", level_text(c.i1));
            row(owner, "current.constant", level_text(c.i2));
            row(owner, "current.accel", level_text(c.i3));
            row(
                owner,
                "current.standby_delay_ms",
                format!("{} ms (T0 = {})", 2 * u32::from(c.t0), c.t0),
            );
            let null_left = ch.motor_type.contains(MotorType::NULL_LEFT);
            let side = match axis.home.direction {
                Direction::Negative => "left",
                Direction::Positive => "right",
            };
            row(
                owner,
                "reference.side",
                format!(
                    "{side} ($15 NullLeft {})",
                    if null_left { "set" } else { "clear" }
                ),
            );
            let high = ch.options.contains(MotorOptions::NULL_POSITIVE);
            row(
                owner,
                "reference.active",
                if high { "high" } else { "low" }.into(),
            );
            row(
                owner,
                "reference.center",
                yes(ch.motor_type.contains(MotorType::NULL_CENTER)),
            );
            row(
                owner,
                "reference.stop_at_switch",
                yes(ch.motor_type.contains(MotorType::STOP_NULL)),
            );
            row(
                owner,
                "reference.soft_stop",
                yes(ch.options.contains(MotorOptions::STOP_SOFT)),
            );
            row(
                owner,
                "reference.debounce_ms",
                format!(
                    "{} ms ($16 mask ${:04X})",
                    debounce_ms(ch.debounce_mask),
                    ch.debounce_mask
                ),
            );
            // A distance of the pack's, in units and microsteps.
            let distance =
                |steps: i64| format!("{} {unit} ({steps} µsteps)", num(steps as f64 / per_unit));
            row(
                owner,
                "reference.null_offset",
                distance(i64::from(ch.nulloffset)),
            );
            row(
                owner,
                "reference.test_range",
                distance(i64::from(ch.testnullrange)),
            );
            row(
                owner,
                "reference.fast",
                yes(ch.options.contains(MotorOptions::FAST_REF)),
            );
            row(
                owner,
                "reference.mechanical",
                yes(ch.options.contains(MotorOptions::MECH_REF)),
            );
            let rotary = ch.motor_type.contains(MotorType::ROTARY);
            row(owner, "rotary", yes(rotary));
            row(
                owner,
                "revolution",
                if rotary {
                    format!(
                        "{} {unit} (poslimit {} µsteps)",
                        num(f64::from(ch.poslimit) / per_unit),
                        ch.poslimit
                    )
                } else {
                    format!(
                        "none: linear, poslimit = the travel, {} µsteps",
                        ch.poslimit
                    )
                },
            );
            let (left, right) = ch.analog_stop;
            row(
                owner,
                "analog_stop.left",
                if left == 0 {
                    "0 (no function)".into()
                } else {
                    left.to_string()
                },
            );
            row(
                owner,
                "analog_stop.right",
                if right >= 1023 {
                    format!("{right} (no function)")
                } else {
                    right.to_string()
                },
            );
            self.drive_axis_rows(axis, ch, &mut |key, value| row(owner, key, value));
        }
        out
    }
}

impl TmcpackChannel {
    /// Whether the reference search runs towards decreasing microsteps ($15 NullLeft).
    pub fn searches_toward_lower(&self) -> bool {
        self.motor_type.contains(MotorType::NULL_LEFT)
    }

    /// Whether the reference switch is active high, an opener ($15 NullPositive).
    pub fn switch_active_high(&self) -> bool {
        self.options.contains(MotorOptions::NULL_POSITIVE)
    }

    /// Whether the reference is a mechanical end stop ($15 MechRef).
    pub fn mechanical_reference(&self) -> bool {
        self.options.contains(MotorOptions::MECH_REF)
    }
}
