//! The keys of the pack's drive functions beyond the ramp (issue 29 items 1, 7, 8;
//! docs/keys/tmcpack.md): the `$45` power-down mode (`power_down`, `reference.restore`),
//! the `$13` starting velocity (`start_velocity`), the `$17` motor characteristics table
//! (`microstep_table`) and the `$24` PI controller with its `$19` parameters
//! (`position_mode`, `pi`). Each is checked against the range the Trinamic SIXpack/QUADpack
//! manual (V2.43) gives for the instruction it becomes and reported at its place in the
//! file.

use motion_board::keys::{AxisContext, DeviceContext, Int, KeyIssues, Spanned};
use motion_board::machine::MachineView;
use motion_drivers::Model;

use super::raw::{RawAxis, RawDevice, RawPi};
use crate::{PiKeys, PositionMode, PowerDownMode, TmcpackAxisKeys, TmcpackDeviceKeys};

/// The `$45` power-down keys and the `$17` table of a `[[device]]`; `false` when one is
/// refused.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    raw: &RawDevice,
    keys: &mut TmcpackDeviceKeys,
) -> bool {
    let mut ok = true;
    if let Some(value) = &raw.power_down {
        keys.power_down = v.one_of(
            value,
            &ctx.key("power_down"),
            &[
                ("off", PowerDownMode::Off),
                ("save", PowerDownMode::Save),
                ("restore", PowerDownMode::Restore),
            ],
            "power-down mode",
            "\"off\" (no $45, the default), \"save\" ($45 bit 2: stop the motors and save \
             their positions below 13 V), \"restore\" (save, and load the saved positions after \
             the pack booted: the axes count as referenced)",
        );
        ok &= keys.power_down.is_some();
    }
    if let Some(list) = &raw.microstep_table {
        keys.microstep_table = microstep_table(v, &ctx.key("microstep_table"), list);
        ok &= keys.microstep_table.is_some();
    }
    ok
}

/// `microstep_table`: exactly 16 entries 0..=255 ($17: "P1..P4 # 4 table entries
/// (0..255)", "only the lower half (16 entries) has to be programmed").
fn microstep_table(
    v: &mut dyn KeyIssues,
    key: &str,
    list: &Spanned<Vec<Spanned<Int>>>,
) -> Option<[u8; 16]> {
    let entries = list.get_ref();
    if entries.len() != 16 {
        v.issue(
            list.span(),
            key,
            format!(
                "{} entries; the table has exactly 16 (manual 8.3 $17: \"only the lower half \
                 (16 entries) has to be programmed\"; the factory table is 255 × \
                 sin([0.5..15.5]/32 π): [13, 37, 62, 86, 109, 131, 152, 171, 189, 205, 219, \
                 231, 240, 247, 252, 255])",
                entries.len()
            ),
        );
        return None;
    }
    let mut table = [0u8; 16];
    let mut fine = true;
    for (slot, entry) in table.iter_mut().zip(entries) {
        match v.int_in(entry, key, 0..=255) {
            Some(value) => *slot = value as u8,
            None => fine = false,
        }
    }
    fine.then_some(table)
}

/// The starting velocity, the position mode, the PI parameters of an `[[axis]]`; `false`
/// when one is refused.
pub(crate) fn axis_keys(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    raw: &RawAxis,
    keys: &mut TmcpackAxisKeys,
) -> bool {
    let mut ok = true;
    if let Some(value) = &raw.start_velocity {
        keys.start_velocity = start_velocity(v, ctx, value);
        ok &= keys.start_velocity.is_some();
    }
    if let Some(value) = &raw.position_mode {
        keys.position_mode = v.one_of(
            value,
            &ctx.key("position_mode"),
            &[("ramp", PositionMode::Ramp), ("pi", PositionMode::Pi)],
            "position mode",
            "\"ramp\" ($14/$26/$23: the trapezoidal ramp, the default), \"pi\" ($24: the \
             pack's PI controller, the target reprogrammed on the fly)",
        );
        ok &= keys.position_mode.is_some();
    }
    if let Some(pi) = &raw.pi {
        match pi_keys(v, ctx, pi.get_ref()) {
            Some(parsed) => keys.pi = parsed,
            None => ok = false,
        }
        if keys.position_mode != Some(PositionMode::Pi) {
            v.warn(
                pi.span(),
                &ctx.key("pi"),
                "the PI parameters ($19) act only on the PI controller: with position_mode = \
                 \"ramp\" (the default) no goal uses it; set position_mode = \"pi\"",
            );
        }
    }
    ok
}

/// `start_velocity`, units/s: `$13` vstart, "starting and ending velocity for acceleration
/// ramp". At least max_accel × 2 ms: the pack adds at most vstart to the velocity each 2 ms
/// (`$14` "0 < amax <= vstart * 64", amax/64 per 2 ms; under the 7.1 reading amax/16 and
/// vstart · 16), so a smaller vstart would cap the axis's acceleration and every stop
/// below `max_accel`. At most `max_velocity`.
fn start_velocity(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    value: &Spanned<f64>,
) -> Option<f64> {
    let s = *value.get_ref();
    let unit = ctx.unit.unwrap_or("units");
    let min = ctx
        .max_accel
        .map(|a| a * tmcpack::convert::TICK.as_secs_f64());
    let max = ctx.max_velocity;
    let fits = s.is_finite()
        && s > 0.0
        && min.is_none_or(|m| s >= m * (1.0 - 1e-9))
        && max.is_none_or(|m| s <= m);
    if fits {
        return Some(s);
    }
    let range = match (min, max) {
        (Some(lo), Some(hi)) => format!("{lo}..={hi} {unit}/s"),
        _ => format!("a speed > 0 ({unit}/s)"),
    };
    v.issue(
        value.span(),
        &ctx.key("start_velocity"),
        format!(
            "{s} is not allowed; {range}: at least max_accel × 2 ms (the pack adds at most \
             vstart to the velocity every 2 ms, manual 8.3 $14: \"0 < amax <= vstart * 64\", \
             so a smaller vstart would cap the acceleration and every stop below max_accel), \
             at most max_velocity"
        ),
    );
    None
}

/// `pi = { … }`: the `$19` ranges.
fn pi_keys(v: &mut dyn KeyIssues, ctx: &AxisContext<'_>, raw: &RawPi) -> Option<PiKeys> {
    let key = |k: &str| ctx.key(&format!("pi.{k}"));
    let mut ok = true;
    let mut get = |value: &Option<Spanned<Int>>, k: &str, range| match value {
        Some(value) => {
            let got = v.int_in(value, &key(k), range);
            ok &= got.is_some();
            got
        }
        None => None,
    };
    let keys = PiKeys {
        propdiv: get(&raw.propdiv, "propdiv", 1..=255).map(|x| x as u8),
        intdiv: get(&raw.intdiv, "intdiv", 1..=32_767).map(|x| x as u16),
        intclip: get(&raw.intclip, "intclip", 1..=32_767).map(|x| x as u16),
        intinpclip: get(&raw.intinpclip, "intinpclip", 0..=255).map(|x| x as u8),
    };
    ok.then_some(keys)
}

/// Checks across tables: `reference.restore` has an effect only on a device with
/// `power_down = "restore"`.
pub(crate) fn cross_check(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for axis in &machine.axes {
        let Some(device) = machine.devices.get(axis.device) else {
            continue;
        };
        if device.model != Model::TMCPACK {
            continue;
        }
        let mode = device
            .machine
            .get::<TmcpackDeviceKeys>()
            .and_then(|k| k.power_down)
            .unwrap_or_default();
        if mode == PowerDownMode::Restore {
            continue;
        }
        let span = axis
            .keys
            .parse_quiet::<RawAxis>()
            .and_then(|raw| raw.reference)
            .and_then(|r| r.into_inner().restore)
            .map(|restore| restore.span());
        if let Some(span) = span {
            v.warn(
                span,
                &format!("axis[{}].reference.restore", axis.index),
                format!(
                    "has no effect: device `{}` restores no positions (power_down = \
                     \"restore\" loads them from EEPROM after the pack booted, $45 bit 0)",
                    device.name
                ),
            );
        }
    }
}
