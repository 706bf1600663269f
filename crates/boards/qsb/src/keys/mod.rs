//! qsb machine keys (docs/CONFIG.md, `docs/keys/qsb.md`): validated here into
//! `crate::QsbDeviceKeys`, turned into the driver's config by
//! `QsbDriverConfig::from_spec`. The keys as written and the string-choice check are in
//! `raw`; the counter-mode keys in `counter`, the capture and trigger keys in `trigger`
//! (both called from here, in that order).
//!
//! The home keys (`home_direction`, `home_max_travel`, `home_offset`) are handed to the
//! server as `HomeHints`: it resolves them with the general `home` table into the axis's
//! `HomeSpec` and refuses a disagreement.

mod counter;
mod raw;
mod trigger;

use core::time::Duration;

use motion_board::keys::{DeviceContext, Int, KeyIssues, KeyTable, Spanned};
use motion_board::machine::MachineView;
use motion_board::{DeviceKeys, Given, HomeHints};
use motion_drivers::spec::Direction;

use crate::driver::{
    LONGEST_INTERVAL_TICKS, MOTOR_DRIVE_BITS, PinRole, QsbDriverConfig, TICK, interval_ticks,
};
use crate::{QsbDeviceKeys, QsbInputMode, QsbVariant};
use motion_drivers::{Model, SignalKind};
pub(crate) use raw::RawDevice;
use raw::choice;

/// The product a `variant` names; an issue for any other value.
fn variant(v: &mut dyn KeyIssues, ctx: &DeviceContext, raw: &RawDevice) -> Option<QsbVariant> {
    let Some(value) = &raw.variant else {
        return Some(QsbVariant::M);
    };
    v.one_of(
        value,
        &ctx.key("variant"),
        &[
            ("qsb-m", QsbVariant::M),
            ("qsb-s", QsbVariant::S),
            ("qsb-d", QsbVariant::D),
        ],
        "variant",
        "\"qsb-m\" (encoder, 4 digital I/O, stepper drive; default), \"qsb-s\" (encoder only), \"qsb-d\" (differential encoder, 1 digital I/O)",
    )
}

/// What the device's home keys say about its axis's reference search.
fn home_hints(v: &mut dyn KeyIssues, ctx: &DeviceContext, raw: &RawDevice) -> Option<HomeHints> {
    let mut hints = HomeHints::default();
    if let Some(value) = &raw.home_direction {
        let direction = v.one_of(
            value,
            &ctx.key("home_direction"),
            &[
                ("negative", Direction::Negative),
                ("positive", Direction::Positive),
            ],
            "direction",
            "\"negative\" (towards min; default), \"positive\" (towards max)",
        )?;
        hints.direction.push(Given {
            value: direction,
            span: value.span(),
            key: ctx.key("home_direction"),
        });
    }
    if let Some(value) = &raw.home_max_travel {
        hints.max_travel.push(Given {
            value: *value.get_ref(),
            span: value.span(),
            key: ctx.key("home_max_travel"),
        });
    }
    if let Some(value) = &raw.home_offset {
        hints.position.push(Given {
            value: *value.get_ref(),
            span: value.span(),
            key: ctx.key("home_offset"),
        });
    }
    Some(hints)
}

/// Validates the qsb keys of a `[[device]]` table.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    keys: &KeyTable<'_>,
) -> Option<DeviceKeys> {
    let raw: RawDevice = keys.parse(v)?;
    let home = home_hints(v, ctx, &raw);
    let product = variant(v, ctx, &raw)?;
    let mut keys = QsbDeviceKeys {
        variant: product,
        ..QsbDeviceKeys::default()
    };
    if let Some(value) = &raw.counts_per_step {
        let c = *value.get_ref();
        if c.is_finite() && c != 0.0 {
            keys.counts_per_step = Some(c);
        } else {
            v.issue(
                value.span(),
                &ctx.key("counts_per_step"),
                format!("{c} is not allowed; counter counts (in count_mode, x4 by default) per motor step: a finite number, not 0 (negative when the encoder counts down as the motor steps forward); default 10"),
            );
        }
    }
    if let Some(value) = &raw.index_polarity {
        let allowed = [("normal", false), ("inverted", true)];
        keys.index_inverted = choice(v, value, &ctx.key("index_polarity"), &allowed);
    }
    if let Some(value) = &raw.stream_interval_ms {
        keys.stream_interval_ticks = stream_interval(v, value, &ctx.key("stream_interval_ms"));
    }
    if let Some(value) = &raw.host_latency_ms {
        keys.host_latency = v
            .host_latency_ms(value, &ctx.key("host_latency_ms"))
            .map(|ms| Duration::from_secs_f64(ms / 1000.0));
    }
    if let Some(value) = &raw.silence_ms {
        keys.silence = v.silence_ms(value, &ctx.key("silence_ms"));
    }
    if let Some(value) = &raw.enable_output {
        keys.enable_output = enable_output(v, value, &ctx.key("enable_output"), product);
    }
    if let Some(value) = &raw.enable_active {
        let allowed = [("low", false), ("high", true)];
        keys.enable_active_high = choice(v, value, &ctx.key("enable_active"), &allowed);
        if raw.enable_output.is_none() {
            v.warn(
                value.span(),
                &ctx.key("enable_active"),
                "has no effect without enable_output (the DIG I/O bit of the drive's enable line)",
            );
        }
    }
    if let Some(value) = &raw.input_mode {
        let allowed = [
            ("quadrature", QsbInputMode::Quadrature),
            ("pwm", QsbInputMode::Pwm),
            ("analog", QsbInputMode::Analog),
        ];
        keys.input_mode = choice(v, value, &ctx.key("input_mode"), &allowed);
        if product == QsbVariant::D
            && keys
                .input_mode
                .is_some_and(|m| m != QsbInputMode::Quadrature)
        {
            v.issue(
                value.span(),
                &ctx.key("input_mode"),
                "a qsb-d reads one differential quadrature encoder; \"pwm\" and \"analog\" are valid on a qsb-s and a qsb-m (command list, \"QSB Variations\")",
            );
        }
    }
    if let Some(value) = &raw.capture_input {
        keys.capture_input = capture_input(v, value, &ctx.key("capture_input"), product);
        if keys.capture_input.is_some() && keys.capture_input == keys.enable_output {
            v.issue(
                value.span(),
                &ctx.key("capture_input"),
                "is the enable_output bit (an output); the capture interrupt needs an input",
            );
        }
    }
    if let Some(value) = &raw.capture_edge {
        let allowed = [("rising", false), ("falling", true)];
        keys.capture_falling = choice(v, value, &ctx.key("capture_edge"), &allowed);
        if raw.capture_input.is_none() {
            v.warn(
                value.span(),
                &ctx.key("capture_edge"),
                "has no effect without capture_input",
            );
        }
    }
    counter::device_keys(v, ctx, &raw, &mut keys);
    trigger::device_keys(v, ctx, &raw, &mut keys);
    // Keys in error stay unset here; the issues already refuse the file, and the other
    // tables are still checked against the rest (every issue at once).
    Some(DeviceKeys::new(keys, home?))
}

/// `stream_interval_ms`: whole ticks of 1/512 s, 1..=0xFFFE.
fn stream_interval(v: &mut dyn KeyIssues, value: &Spanned<f64>, key: &str) -> Option<u16> {
    let ms = *value.get_ref();
    let tick_ms = TICK.as_secs_f64() * 1000.0;
    let longest = f64::from(LONGEST_INTERVAL_TICKS) * tick_ms;
    let rate = Duration::try_from_secs_f64(ms / 1000.0)
        .ok()
        .filter(|_| ms.is_finite())
        .and_then(interval_ticks)
        .filter(|ticks| *ticks >= 1);
    let Some(rate) = rate else {
        v.issue(
            value.span(),
            key,
            format!("{ms} is out of range; allowed: {tick_ms}..={longest} ms (INTERVAL RATE 1..=0xFFFE ticks of 1/512 s; 0xFFFF would disable the stream)"),
        );
        return None;
    };
    let effective = f64::from(rate) * tick_ms;
    if (effective - ms).abs() > 1e-6 {
        v.warn(
            value.span(),
            key,
            format!(
                "{ms} ms is not a whole number of 1/512 s ticks; the board gets {} tick{} = {effective} ms",
                rate,
                if rate == 1 { "" } else { "s" }
            ),
        );
    }
    Some(rate)
}

/// `enable_output`: bit 0 or 3 of a qsb-m.
fn enable_output(
    v: &mut dyn KeyIssues,
    value: &Spanned<Int>,
    key: &str,
    product: QsbVariant,
) -> Option<u8> {
    let bit = value.get_ref().get();
    let why = match (product, bit) {
        (QsbVariant::M, 0 | 3) => return Some(bit as u8),
        (QsbVariant::M, 1 | 2) => {
            "io1 and io2 are the motor drive's step and direction lines (\"Be careful if the motor drive is enabled, it uses I/O bits 1 and 2\"); allowed: 0 or 3"
        }
        (QsbVariant::M, _) => {
            "allowed: 0 or 3 (the DIG I/O bit of the stepper driver's enable line)"
        }
        _ => {
            "the enable line of an external stepper driver exists only on a qsb-m (the -S has no digital I/O, the -D one bit and no motor drive)"
        }
    };
    v.issue(
        value.span(),
        key,
        format!("{} is not allowed; {why}", value.get_ref()),
    );
    None
}

/// `capture_input`: a DIG I/O bit of the product.
fn capture_input(
    v: &mut dyn KeyIssues,
    value: &Spanned<Int>,
    key: &str,
    product: QsbVariant,
) -> Option<u8> {
    let bit = value.get_ref().get();
    let bits = i64::from(product.digital_io_bits());
    if (0..bits).contains(&bit) {
        return Some(bit as u8);
    }
    let why = match product {
        QsbVariant::S => "a qsb-s has no digital I/O to capture on".to_owned(),
        _ => format!("allowed: 0..={} (a DIG I/O bit of this board)", bits - 1),
    };
    v.issue(
        value.span(),
        key,
        format!("{} is not allowed; {why}", value.get_ref()),
    );
    None
}

/// Checks across tables for qsb devices (after everything else was validated): no axis on
/// a device in PWM / analog mode, signals that clash with the motor drive, the enable line
/// or the capture input, and a stream the line cannot carry.
pub(crate) fn cross_check(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (index, device) in machine.devices_of(Model::QSB) {
        let Some(keys) = device.machine.get::<QsbDeviceKeys>() else {
            continue;
        };
        let Some(raw_device) = device.keys.parse_quiet::<RawDevice>() else {
            continue;
        };
        let dkey = |k: &str| format!("device[{}].{k}", device.index);
        let product = keys.variant;
        let mode = keys.input_mode.unwrap_or_default();
        let axes: Vec<_> = machine.axes_on(index).collect();
        if mode != QsbInputMode::Quadrature {
            for axis in &axes {
                v.issue(
                    axis.device_span.clone(),
                    &format!("axis[{}].device", axis.index),
                    format!("device `{}` has input_mode = \"{}\": it reads an absolute value as its `encoder` pin and carries no axis; use a [[signal]] with pin = \"encoder\" and kind = \"analog-in\"", device.name, if mode == QsbInputMode::Pwm { "pwm" } else { "analog" }),
                );
            }
        }
        let drive =
            product == QsbVariant::M && mode == QsbInputMode::Quadrature && !axes.is_empty();
        if let (Some(value), false) = (&raw_device.enable_output, drive) {
            v.warn(
                value.span(),
                &dkey("enable_output"),
                "has no effect: no axis drives this qsb-m's stepper (an axis in input_mode \"quadrature\")",
            );
        }
        if let (Some(value), Some(bit), true) =
            (&raw_device.capture_input, keys.capture_input, drive)
            && MOTOR_DRIVE_BITS & (1 << bit) != 0
        {
            v.issue(
                value.span(),
                &dkey("capture_input"),
                format!("io{bit} is the motor drive's {} line while an axis drives this qsb-m; use io0 or io3", if bit == 1 { "step" } else { "direction" }),
            );
        }
        signal_checks(v, machine, index, keys, drive);
        counter::cross_check(v, machine, index, &raw_device, keys, drive);
        trigger::cross_check(v, machine, index, &raw_device, keys);
        line_budget(v, machine, &raw_device, device.index, device.link, keys);
    }
}

/// The signals on qsb device `index`.
fn signal_checks(
    v: &mut dyn KeyIssues,
    machine: &MachineView<'_>,
    index: usize,
    keys: &QsbDeviceKeys,
    drive: bool,
) {
    let device = &machine.devices[index];
    let product = keys.variant;
    let mode = keys.input_mode.unwrap_or_default();
    for signal in machine.signals_on(index) {
        let key = format!("signal[{}].pin", signal.index);
        let why = match product.pin_role(signal.pin) {
            Some(PinRole::Io(bit)) if drive && MOTOR_DRIVE_BITS & (1 << bit) != 0 => format!(
                "io{bit} is the motor drive's {} line while an axis drives qsb-m `{}` (\"digital I/O bits 1 and 2 are reserved for motor drive\"); use io0 or io3",
                if bit == 1 { "step" } else { "direction" },
                device.name
            ),
            Some(PinRole::Io(bit)) if keys.enable_output == Some(bit) => format!(
                "io{bit} is the enable_output of device `{}` (the stepper driver's enable line); it is not a signal",
                device.name
            ),
            Some(PinRole::Io(0)) if keys.trigger_on.is_some_and(|t| t.any()) => format!(
                "io0 is the trigger output of device `{}` (trigger_on: \"Digital output, bit 0\" pulsed by the counter's events); read it as pin `trigger` with kind = \"trigger\"",
                device.name
            ),
            Some(PinRole::Io(bit))
                if keys.capture_input == Some(bit) && signal.kind == SignalKind::DigitalOut =>
            {
                format!(
                    "io{bit} is the capture_input of device `{}`; it must stay an input",
                    device.name
                )
            }
            Some(PinRole::Encoder) if mode == QsbInputMode::Quadrature => format!(
                "pin `encoder` carries a PWM or analog value: set input_mode = \"pwm\" or \"analog\" on device `{}`",
                device.name
            ),
            Some(PinRole::Capture)
                if keys.capture_input.is_none()
                    && keys.capture_index != Some(true)
                    && !keys.trigger_on.is_some_and(|t| t.index) =>
            {
                format!(
                    "pin `capture` reads the count an edge on capture_input (or the index, capture_index) loads: set capture_input (and capture_edge) or capture_index on device `{}`",
                    device.name
                )
            }
            Some(PinRole::Trigger) if !keys.trigger_on.is_some_and(|t| t.any()) => format!(
                "pin `trigger` is DIG I/O bit 0 pulsed by the counter's events: set trigger_on (and compare_position for \"match\") on device `{}`",
                device.name
            ),
            _ => continue,
        };
        v.issue(signal.pin_span.clone(), &key, why);
    }
}

/// Warns when the configured stream interval is shorter than an encoder line takes on the
/// wire.
fn line_budget(
    v: &mut dyn KeyIssues,
    machine: &MachineView<'_>,
    raw_device: &RawDevice,
    raw_index: usize,
    link: usize,
    keys: &QsbDeviceKeys,
) {
    let (Some(ticks), Some(value)) = (keys.stream_interval_ticks, &raw_device.stream_interval_ms)
    else {
        return;
    };
    let Some(baud) = machine.links.get(link).and_then(|l| l.line_rate) else {
        return;
    };
    let driver = QsbDriverConfig {
        baud,
        stream_interval: Some(ticks),
        ..QsbDriverConfig::default()
    };
    let load = driver.stream_load();
    if load > 1.0 {
        v.warn(
            value.span(),
            &format!("device[{raw_index}].stream_interval_ms"),
            format!("at {baud} baud one encoder line takes {:.0} % of this interval: the board will skip samples; a longer interval (or a faster line) keeps every sample", load * 100.0),
        );
    }
}
