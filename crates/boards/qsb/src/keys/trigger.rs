//! The capture and trigger keys of a qsb `[[device]]` (`capture_index`, `trigger_on`,
//! `compare_position`, `trigger_active`; docs/keys/qsb.md "Capture and trigger"),
//! validated against MDR1, DIG I/O CONFIG and DTR of the "QSB Command List" 1.28.
//!
//! What is refused, and why:
//! - `trigger_on` on a qsb-s: the pulse is on "Digital output, bit 0", which the -S lacks;
//!   a name other than "index", "match", "underflow", "overflow" (MDR1 B4–B7), or one
//!   twice.
//! - "match" without `compare_position` in free-running or single-cycle counting: DTR is
//!   what CNTR is compared with, and its factory 0x1F3 is no position anyone chose;
//!   `compare_position` in range-limit or modulo-n counting, where DTR is `count_limit`
//!   (there "match" fires at the limit, once per cycle).
//! - `capture_index` with a `trigger_on` that lacks "index": MDR1 B4 is "Trigger/Capture
//!   on Index", one bit, so every index would pulse the output too.
//! - io0 as `enable_output`, `capture_input` or a signal while `trigger_on` makes it the
//!   trigger output; `compare_position` on a device without an axis (it is in the axis's
//!   units).

use motion_board::keys::{DeviceContext, KeyIssues};
use motion_board::machine::MachineView;
use qsb::CycleMode;

use super::raw::{RawDevice, choice};
use crate::{QsbDeviceKeys, QsbInputMode, QsbVariant, TriggerSources};

/// Validates the capture and trigger keys of one device into `keys` (after the counter
/// keys: `count_range` decides what "match" compares with).
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    raw: &RawDevice,
    keys: &mut QsbDeviceKeys,
) {
    if let Some(value) = &raw.capture_index {
        keys.capture_index = Some(*value.get_ref());
    }
    if let Some(list) = &raw.trigger_on {
        keys.trigger_on = trigger_sources(v, ctx, list, keys.variant);
    }
    let sources = keys.trigger_on.unwrap_or_default();
    let dtr_is_limit = matches!(
        keys.count_range,
        Some(CycleMode::RangeLimit | CycleMode::ModuloN)
    );
    if let Some(value) = &raw.compare_position {
        let position = *value.get_ref();
        let key = ctx.key("compare_position");
        if !position.is_finite() {
            v.issue(
                value.span(),
                &key,
                format!("{position} is not a position; the axis position (its units) at which \"match\" pulses the trigger output"),
            );
        } else if dtr_is_limit {
            v.issue(
                value.span(),
                &key,
                "DTR is count_limit in range-limit and modulo-n counting: there \"match\" fires at the limit (CNTR = DTR), once per cycle; leave compare_position out",
            );
        } else if !sources.on_match {
            v.warn(
                value.span(),
                &key,
                "has no effect without \"match\" in trigger_on",
            );
        } else {
            keys.compare_position = Some(position);
        }
    }
    if let Some(list) = &raw.trigger_on
        && sources.on_match
        && !dtr_is_limit
        && raw.compare_position.is_none()
    {
        v.issue(
            list.span(),
            &ctx.key("trigger_on"),
            "\"match\" needs compare_position: DTR, compared with the counter (\"In compare operations … the DTR is compared with the CNTR\"), in the axis's units",
        );
    }
    if let Some(value) = &raw.capture_index
        && *value.get_ref()
        && sources.any()
        && !sources.index
    {
        v.issue(
            value.span(),
            &ctx.key("capture_index"),
            "MDR1 B4 is \"Trigger/Capture on Index\", one bit: with trigger_on set every index would pulse the trigger output too; add \"index\" to trigger_on, or leave capture_index out",
        );
    }
    if let Some(value) = &raw.trigger_active {
        let allowed = [("low", false), ("high", true)];
        keys.trigger_active_high = choice(v, value, &ctx.key("trigger_active"), &allowed);
        if !sources.any() {
            v.warn(
                value.span(),
                &ctx.key("trigger_active"),
                "has no effect without trigger_on",
            );
        }
    }
    if sources.any() {
        for (key, bit) in [
            ("enable_output", keys.enable_output),
            ("capture_input", keys.capture_input),
        ] {
            if bit == Some(0)
                && let Some(list) = &raw.trigger_on
            {
                v.issue(
                    list.span(),
                    &ctx.key("trigger_on"),
                    format!("io0 is the {key}; the trigger pulse is on \"Digital output, bit 0\": move {key} to another bit"),
                );
            }
        }
    }
}

/// `trigger_on`: distinct names of MDR1 B4–B7, on a product with DIG I/O bit 0.
fn trigger_sources(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    list: &motion_board::keys::Spanned<Vec<motion_board::keys::Spanned<String>>>,
    product: QsbVariant,
) -> Option<TriggerSources> {
    let key = ctx.key("trigger_on");
    if product == QsbVariant::S && !list.get_ref().is_empty() {
        v.issue(
            list.span(),
            &key,
            "a qsb-s has no digital I/O: the trigger pulse is on \"Digital output, bit 0\" of a qsb-m or qsb-d",
        );
        return None;
    }
    let mut sources = TriggerSources::default();
    let mut ok = true;
    for name in list.get_ref() {
        let allowed = [
            ("index", 0u8),
            ("match", 1),
            ("underflow", 2),
            ("overflow", 3),
        ];
        let Some(which) = choice(v, name, &key, &allowed) else {
            ok = false;
            continue;
        };
        let slot = match which {
            0 => &mut sources.index,
            1 => &mut sources.on_match,
            2 => &mut sources.underflow,
            _ => &mut sources.overflow,
        };
        if *slot {
            v.issue(
                name.span(),
                &key,
                format!("{:?} is listed twice", name.get_ref()),
            );
            ok = false;
        }
        *slot = true;
    }
    ok.then_some(sources)
}

/// Across tables: `compare_position` needs the device's axis (its units), io0 is no
/// signal while it is the trigger output, the `trigger` pin needs `trigger_on`, and a
/// device that does not count (PWM, analog) triggers and captures nothing.
pub(crate) fn cross_check(
    v: &mut dyn KeyIssues,
    machine: &MachineView<'_>,
    index: usize,
    raw: &RawDevice,
    keys: &QsbDeviceKeys,
) {
    let Some(device) = machine.devices.get(index) else {
        return;
    };
    let dkey = |k: &str| format!("device[{}].{k}", device.index);
    if let Some(value) = &raw.compare_position {
        let position = *value.get_ref();
        match machine.axes_on(index).next() {
            None => v.issue(
                value.span(),
                &dkey("compare_position"),
                format!(
                    "is in the units of the axis on device `{}` (its counts_per_unit converts it to DTR counts), and the device has no axis",
                    device.name
                ),
            ),
            Some(axis) if (position * axis.counts_per_unit).abs() > f64::from(i32::MAX) => {
                v.issue(
                    value.span(),
                    &dkey("compare_position"),
                    format!(
                        "{position} {} is {} counts at counts_per_unit = {} of axis `{}`: beyond the 32-bit counter (DTR)",
                        axis.unit,
                        (position * axis.counts_per_unit).round(),
                        axis.counts_per_unit,
                        axis.name
                    ),
                );
            }
            Some(_) => {}
        }
    }
    if keys.input_mode.unwrap_or_default() != QsbInputMode::Quadrature {
        let set = [
            (
                "capture_index",
                raw.capture_index.as_ref().map(|s| s.span()),
            ),
            ("trigger_on", raw.trigger_on.as_ref().map(|s| s.span())),
        ];
        for (key, span) in set {
            if let Some(span) = span {
                v.warn(
                    span,
                    &dkey(key),
                    "has no effect: input_mode is not \"quadrature\" (the counter counts nothing, no index, match or wrap)",
                );
            }
        }
    }
}
