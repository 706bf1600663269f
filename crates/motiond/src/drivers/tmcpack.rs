//! The Trinamic pack driver of a `[[device]]`, configured from its axes, machine keys and
//! signals (docs/keys/tmcpack.md).

use motion_base::counts_to_i32_saturating;
use motion_drivers::tmcpack::{
    Currents, DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS, PinSet, ReadyOutput, TmcpackChannel,
    TmcpackDriver, TmcpackDriverConfig, TmcpackIo, default_packet_timeout_units,
};
use motion_drivers::{Driver, SignalKind};
use motion_engine::AxisConfig;
use tmcpack::convert::{debounce_mask, debounce_ms, peak_percent, peak_value};
use tmcpack::{CurrentLevel, MAX_POSLIMIT, MotorMask, MotorOptions, MotorType};

use super::{ParamRow, line_rate};
use crate::config::{
    AxisMachine, AxisSpec, DeviceMachine, DeviceSpec, Direction, Owner, PackVariant, ServerConfig,
    TmcpackAxisKeys, TmcpackDeviceKeys,
};

fn variant(device: &DeviceSpec) -> tmcpack::Variant {
    match device.variant {
        PackVariant::Sixpack => tmcpack::Variant::SixPack,
        PackVariant::Quadpack => tmcpack::Variant::QuadPack,
    }
}

fn device_keys(device: &DeviceSpec) -> TmcpackDeviceKeys {
    match &device.machine {
        DeviceMachine::Tmcpack(keys) => keys.clone(),
        _ => TmcpackDeviceKeys::default(),
    }
}

fn axis_keys(spec: &AxisSpec) -> TmcpackAxisKeys {
    match &spec.machine {
        AxisMachine::Tmcpack(keys) => keys.clone(),
        _ => TmcpackAxisKeys::default(),
    }
}

/// The $41 timeout device `device` gets, 2 ms units.
fn packet_timeout_units(config: &ServerConfig, device: &DeviceSpec) -> u16 {
    match device_keys(device).packet_timeout_ms {
        Some(ms) => (ms / 2).min(u32::from(u16::MAX)) as u16,
        None => default_packet_timeout_units(line_rate(config, device).unwrap_or(19_200)),
    }
}

/// The inputs, outputs and ready output of tmcpack device `index`.
fn io(config: &ServerConfig, index: usize, device: &DeviceSpec) -> TmcpackIo {
    let mut io = TmcpackIo::default();
    for signal in config.signals.iter().filter(|s| s.device == index) {
        match signal.kind {
            SignalKind::DigitalIn | SignalKind::AnalogIn => io.inputs = io.inputs.with(signal.pin),
            SignalKind::DigitalOut => io.outputs = io.outputs.with(signal.pin),
        }
    }
    io.ready = device_keys(device).ready_output.map(|r| ReadyOutput {
        motors: MotorMask::from_bits_retain(r.motors),
        reference: MotorMask::from_bits_retain(r.reference),
    });
    io
}

/// The driver's view of the motor behind `axis`: limits in microsteps, and the machine keys.
fn channel_config(axis: &AxisConfig, spec: &AxisSpec) -> TmcpackChannel {
    let keys = axis_keys(spec);
    let d = TmcpackChannel::default();
    let cpu = axis.counts_per_unit;
    let scale = cpu.abs();
    let r = keys.reference;
    let c = keys.current;
    // `reference.side` / `home.direction` are in axis units; NullLeft is in microsteps.
    let null_left = (spec.home.direction == Direction::Negative) == (cpu > 0.0);
    let rotary = keys.rotary == Some(true);
    let motor_type = d
        .motor_type
        .with(MotorType::NULL_LEFT, null_left)
        .with(
            MotorType::NULL_CENTER,
            r.center
                .unwrap_or(d.motor_type.contains(MotorType::NULL_CENTER)),
        )
        .with(
            MotorType::STOP_NULL,
            r.stop_at_switch
                .unwrap_or(d.motor_type.contains(MotorType::STOP_NULL)),
        )
        .with(MotorType::ROTARY, rotary);
    let options = d
        .options
        .with(
            MotorOptions::NULL_POSITIVE,
            r.active_high
                .unwrap_or(d.options.contains(MotorOptions::NULL_POSITIVE)),
        )
        .with(
            MotorOptions::STOP_SOFT,
            r.soft_stop
                .unwrap_or(d.options.contains(MotorOptions::STOP_SOFT)),
        )
        .with(
            MotorOptions::FAST_REF,
            r.fast.unwrap_or(d.options.contains(MotorOptions::FAST_REF)),
        )
        .with(
            MotorOptions::MECH_REF,
            r.mechanical
                .unwrap_or(d.options.contains(MotorOptions::MECH_REF)),
        );
    let range = match keys.revolution {
        Some(revolution) if rotary => revolution,
        _ => axis.max - axis.min,
    };
    let poslimit = (range * scale).round().clamp(0.0, f64::from(MAX_POSLIMIT)) as u32;
    let counts = |units: f64| (units * scale).round();
    TmcpackChannel {
        max_velocity: axis.max_velocity * scale,
        max_accel: axis.max_accel * scale,
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
            i0: c.standby.unwrap_or(d.currents.i0),
            i1: c.standstill.unwrap_or(d.currents.i1),
            i2: c.constant.unwrap_or(d.currents.i2),
            i3: c.accel.unwrap_or(d.currents.i3),
            t0: c
                .standby_delay_ms
                .map_or(d.currents.t0, |ms| (ms / 2).clamp(1, 65_535) as u16),
        },
        peak_current: c.peak.and_then(|p| peak_value(p).ok()).or(d.peak_current),
        analog_stop: (
            keys.analog_stop_left.unwrap_or(d.analog_stop.0),
            keys.analog_stop_right.unwrap_or(d.analog_stop.1),
        ),
        home_position: counts_to_i32_saturating(spec.home.position * cpu),
    }
}

/// The driver config of tmcpack device `index`: shared by `build`, `describe` and the
/// simulated pack.
pub fn driver_config(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> TmcpackDriverConfig {
    let keys = device_keys(device);
    let mut driver = TmcpackDriverConfig {
        address: device.address as u8,
        variant: variant(device),
        reply_address: keys.reply_address.unwrap_or(DEFAULT_REPLY_ADDRESS),
        switchover_units: Some(
            keys.switchover_ms
                .map_or(DEFAULT_SWITCHOVER_UNITS, |ms| (ms / 2).max(1)),
        ),
        io: io(config, index, device),
        ..TmcpackDriverConfig::default()
    };
    if let Some(baud) = line_rate(config, device) {
        driver.baud = baud;
    }
    driver.packet_timeout_units = Some(packet_timeout_units(config, device));
    // Every pack on the link shares its polling budget (axes and input polls) and frames
    // every word on it (the longest packet timeout spaces the words).
    let on_link: Vec<(usize, &DeviceSpec)> = config
        .devices
        .iter()
        .enumerate()
        .filter(|(_, d)| d.link == device.link)
        .collect();
    let axes = config
        .axes
        .iter()
        .filter(|axis| on_link.iter().any(|(i, _)| *i == axis.device))
        .count();
    let input_polls = on_link
        .iter()
        .filter(|(i, d)| {
            d.model == motion_drivers::Model::Tmcpack && io(config, *i, d).inputs != PinSet::EMPTY
        })
        .count();
    driver.bus_motors = (axes + input_polls).min(usize::from(u8::MAX)) as u8;
    driver.bus_packet_timeout_units = on_link
        .iter()
        .filter(|(_, d)| d.model == motion_drivers::Model::Tmcpack)
        .map(|(_, d)| packet_timeout_units(config, d))
        .max()
        .unwrap_or(0);
    for (axis, spec) in config.axes.iter().zip(&config.axis_specs) {
        if axis.device == index
            && let Some(slot) = driver.channels.get_mut(axis.channel)
        {
            *slot = Some(channel_config(axis, spec));
        }
    }
    driver
}

/// The driver of tmcpack device `index`.
pub(crate) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    Box::new(TmcpackDriver::new(driver_config(config, index, device)))
}

fn level(l: CurrentLevel) -> String {
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

/// The machine parameters of tmcpack device `index` and its axes, as the driver uses them.
pub(crate) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let driver = driver_config(config, index, device);
    let mut row = |owner: Owner, key: &str, value: String| {
        out.push(ParamRow {
            owner,
            key: key.to_owned(),
            value,
        });
    };
    let dev = Owner::Device(index);
    row(
        dev,
        "reply_address",
        format!("{0} (0x{0:02X})", driver.reply_address),
    );
    let switchover = driver.switchover_units.unwrap_or(DEFAULT_SWITCHOVER_UNITS);
    row(
        dev,
        "switchover_ms",
        format!("{} ms ($40)", 2 * u32::from(switchover)),
    );
    row(
        dev,
        "packet_timeout_ms",
        format!("{} ms ($41)", 2 * u32::from(driver.packet_timeout())),
    );
    row(
        dev,
        "ready_output",
        match driver.io.ready {
            Some(r) => format!(
                "motors {}, reference {} (TTLOUT1: $32 P3 = 1, $33)",
                mask_list(r.motors),
                mask_list(r.reference)
            ),
            None => "off".into(),
        },
    );
    let pack = variant(device);
    for (a, (axis, spec)) in config.axes.iter().zip(&config.axis_specs).enumerate() {
        if axis.device != index {
            continue;
        }
        let Some(Some(ch)) = driver.channels.get(axis.channel) else {
            continue;
        };
        let owner = Owner::Axis(a);
        let unit = axis.unit.as_str();
        let per_unit = axis.counts_per_unit.abs();
        // The pair's value: the even motor's, else the odd one's (manual 8.3 $10).
        let pair = axis.channel & !1;
        let peak = [pair, pair + 1].into_iter().find_map(|m| {
            driver
                .channels
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
                    let dip = if pack == tmcpack::Variant::QuadPack {
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
        row(owner, "current.standby", level(c.i0));
        row(owner, "current.standstill", level(c.i1));
        row(owner, "current.constant", level(c.i2));
        row(owner, "current.accel", level(c.i3));
        row(
            owner,
            "current.standby_delay_ms",
            format!("{} ms (T0 = {})", 2 * u32::from(c.t0), c.t0),
        );
        let null_left = ch.motor_type.contains(MotorType::NULL_LEFT);
        let side = match spec.home.direction {
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
        row(
            owner,
            "reference.null_offset",
            format!(
                "{} {unit} ({} µsteps)",
                num(f64::from(ch.nulloffset) / per_unit),
                ch.nulloffset
            ),
        );
        row(
            owner,
            "reference.test_range",
            format!(
                "{} {unit} ({} µsteps)",
                num(f64::from(ch.testnullrange) / per_unit),
                ch.testnullrange
            ),
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
    }
}
