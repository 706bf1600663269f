//! tmcpack machine keys (docs/CONFIG.md, docs/keys/tmcpack.md): validated here into
//! `board_tmcpack::{TmcpackDeviceKeys, TmcpackAxisKeys}`, turned into the driver's
//! config by `TmcpackDriverConfig::from_spec`. Every value is checked against the range the
//! Trinamic SIXpack/QUADpack manual (V2.43) gives for the instruction it becomes.
//!
//! This module checks a `[[device]]` and an `[[axis]]` table; the keys as written are in
//! `raw`; the drive functions' keys in `drive`, the line timing's in `timing`, the rate in
//! `baud`; the checks across tables (after everything else was validated) in `cross`.

mod baud;
mod cross;
mod drive;
mod raw;
mod timing;

use motion_board::keys::{AxisContext, DeviceContext, Int, KeyIssues, KeyTable, Spanned};
use motion_board::{AxisKeys, DeviceKeys, Given, HomeHints};
use motion_drivers::spec::Direction;

use crate::driver::{MAX_DEBOUNCE_MS, is_current_level, is_weak_current};
use crate::{PackVariant, ReadyOutputKeys, TmcpackAxisKeys, TmcpackDeviceKeys};
pub(crate) use cross::cross_check;
pub(crate) use raw::{RawAxis, RawDevice};

/// The pack variant a `variant` names; an issue for any other value.
fn variant(v: &mut dyn KeyIssues, ctx: &DeviceContext, raw: &RawDevice) -> Option<PackVariant> {
    let Some(value) = &raw.variant else {
        return Some(PackVariant::Sixpack);
    };
    v.one_of(
        value,
        &ctx.key("variant"),
        &[
            ("sixpack", PackVariant::Sixpack),
            ("quadpack", PackVariant::Quadpack),
        ],
        "variant",
        "\"sixpack\" (6 motors), \"quadpack\" (4)",
    )
}

/// `address`: the pack's RS-485 address, 0..=255 (manual 6.1); default 1.
pub(crate) fn check_address(value: i128) -> Result<u32, String> {
    if (0..=255).contains(&value) {
        Ok(value as u32)
    } else {
        Err(format!("{value} is out of range; allowed: 0..=255"))
    }
}

/// What `reference.side` says about the search direction.
fn side_hint(v: &mut dyn KeyIssues, ctx: &AxisContext<'_>, raw: &RawAxis) -> Option<HomeHints> {
    let mut hints = HomeHints::default();
    let Some(side) = raw
        .reference
        .as_ref()
        .and_then(|r| r.get_ref().side.as_ref())
    else {
        return Some(hints);
    };
    let key = ctx.key("reference.side");
    let direction = v.one_of(
        side,
        &key,
        &[("left", Direction::Negative), ("right", Direction::Positive)],
        "side",
        "\"left\" (zero point left of the driving range: the search runs to decreasing positions; NullLeft, default), \"right\"",
    )?;
    hints.direction.push(Given {
        value: direction,
        span: side.span(),
        key,
    });
    Some(hints)
}

/// Highest `poslimit` ($15 P1..P4).
pub const MAX_POSLIMIT: f64 = crate::driver::MAX_POSLIMIT as f64;

/// The current levels of $11, in %, as the error messages list them.
const LEVELS: &str = "100, 75, 50, 38, 25, 19, 13, 9, 0";

/// An even number of ms in `range`, for keys in the pack's 2 ms units.
fn even_ms(
    v: &mut dyn KeyIssues,
    value: &Spanned<Int>,
    key: &str,
    range: core::ops::RangeInclusive<i64>,
    what: &str,
) -> Option<i64> {
    let ms = value.get_ref().get();
    if range.contains(&ms) && ms % 2 == 0 {
        Some(ms)
    } else {
        v.issue(
            value.span(),
            key,
            format!(
                "{} is not allowed; an even number of ms {}..={} ({what} is set in 2 ms units)",
                value.get_ref(),
                range.start(),
                range.end()
            ),
        );
        None
    }
}

/// Validates the tmcpack keys of a `[[device]]` table.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    keys: &KeyTable<'_>,
) -> Option<DeviceKeys> {
    let raw: RawDevice = keys.parse(v)?;
    let raw = &raw;
    let mut ok = true;
    let variant = variant(v, ctx, raw)?;
    let mut keys = TmcpackDeviceKeys {
        variant,
        ..TmcpackDeviceKeys::default()
    };
    if let Some(value) = &raw.reply_address {
        match v.int_in(value, &ctx.key("reply_address"), 0..=255) {
            Some(a) => keys.reply_address = Some(a as u8),
            None => ok = false,
        }
    }
    if let Some(value) = &raw.switchover_ms {
        match even_ms(
            v,
            value,
            &ctx.key("switchover_ms"),
            2..=2000,
            "$40 switch-over delay",
        ) {
            Some(ms) => keys.switchover_ms = Some(ms as u16),
            None => ok = false,
        }
    }
    if let Some(value) = &raw.packet_timeout_ms {
        match even_ms(
            v,
            value,
            &ctx.key("packet_timeout_ms"),
            4..=131_070,
            "$41 packet timeout",
        ) {
            Some(ms) => keys.packet_timeout_ms = Some(ms as u32),
            None => ok = false,
        }
    }
    if let Some(value) = &raw.amax_divisor {
        keys.amax_divisor = crate::readings::amax_divisor(v, ctx, value);
        ok &= keys.amax_divisor.is_some();
    }
    if let Some(value) = &raw.stop_no_ref_bit {
        keys.stop_no_ref_bit = crate::readings::stop_no_ref_bit(v, ctx, value);
        ok &= keys.stop_no_ref_bit.is_some();
    }
    ok &= drive::device_keys(v, ctx, raw, &mut keys);
    ok &= timing::device_keys(v, ctx, raw, &mut keys);
    if let Some(value) = &raw.baud {
        keys.baud = baud::baud(v, ctx, value);
        ok &= keys.baud.is_some();
    }
    if let Some(ready) = &raw.ready_output {
        let motors: u8 = match variant {
            PackVariant::Quadpack => 4,
            PackVariant::Sixpack => 6,
        };
        let all = (1u8 << motors) - 1;
        let mut mask = |list: &Option<Spanned<Vec<Spanned<Int>>>>, k: &str| -> Option<u8> {
            let Some(list) = list else {
                // The manual's default masks ($3F): every motor.
                return Some(all);
            };
            let key = ctx.key(&format!("ready_output.{k}"));
            let mut bits = 0u8;
            let mut fine = true;
            for item in list.get_ref() {
                let m = item.get_ref().get();
                if !(0..i64::from(motors)).contains(&m) {
                    v.issue(
                        item.span(),
                        &key,
                        format!(
                            "{} is not a motor of this pack; allowed: 0..={}",
                            item.get_ref(),
                            motors - 1
                        ),
                    );
                    fine = false;
                } else if bits & (1 << m) != 0 {
                    v.issue(item.span(), &key, format!("motor {m} is listed twice"));
                    fine = false;
                } else {
                    bits |= 1 << m;
                }
            }
            fine.then_some(bits)
        };
        let r = ready.get_ref();
        let motors_mask = mask(&r.motors, "motors");
        let reference = mask(&r.reference, "reference");
        match (motors_mask, reference) {
            (Some(motors), Some(reference)) => {
                keys.ready_output = Some(ReadyOutputKeys { motors, reference });
            }
            _ => ok = false,
        }
    }
    ok.then_some(DeviceKeys::new(keys, HomeHints::default()))
}

/// A current level of $11 from a percentage.
fn level(v: &mut dyn KeyIssues, value: &Spanned<f64>, key: &str) -> Option<u8> {
    let p = *value.get_ref();
    let found = (p.is_finite() && p.fract() == 0.0 && (0.0..=100.0).contains(&p))
        .then_some(p as u8)
        .filter(|&level| is_current_level(level));
    match found {
        Some(level) => {
            if is_weak_current(level) {
                v.warn(
                    value.span(),
                    key,
                    format!("{p} % is below 19 %, the lowest current that microsteps properly (manual 7.1 \"Setting of Motor Current\")"),
                );
            }
            Some(level)
        }
        None => {
            v.issue(
                value.span(),
                key,
                format!("{p} is not a current level of the pack; allowed: {LEVELS} (% of the peak current, manual 8.3 $11)"),
            );
            None
        }
    }
}

fn flag(value: &Option<Spanned<bool>>) -> Option<bool> {
    value.as_ref().map(|b| *b.get_ref())
}

/// Validates the tmcpack keys of an `[[axis]]` table.
/// `home.position` with `reference.stop_at_switch`: after the reference search the driver
/// sets the position to `home.position` with `$27`, so the zero switch, still active where
/// the search ended, is then that far from zero. With StopNull the pack stops the motor
/// (and, without StopNoRef, which the driver sets, searches again) when the switch is
/// active outside ±testnullrange around zero (manual, instruction
/// set, `$27` "Set actual Position": "Can lead to unintended reference searches at detection
/// of zero switches"; `$15` P5 bit 6 StopNull: "if zero switch is active outside the
/// tolerance area around zero point"). Refused unless the position lies within that range.
fn home_position_fits_stop_null(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    reference: &crate::machine_keys::ReferenceKeys,
) -> bool {
    let (Some(true), Some((position, span)), Some(cpu)) = (
        reference.stop_at_switch,
        ctx.home_position.clone(),
        ctx.counts_per_unit.map(f64::abs),
    ) else {
        return true;
    };
    let range = reference.test_range.map_or(
        f64::from(crate::driver::TmcpackChannel::default().testnullrange),
        |units| (units * cpu).round(),
    );
    if !(position * cpu).is_finite() || (position * cpu).abs() <= range {
        return true;
    }
    v.issue(
        span,
        &ctx.key("home.position"),
        format!(
            "{position} with reference.stop_at_switch = true: after the reference search `$27` \
             sets the position to {position}, so the zero switch is active {} microsteps from \
             zero, outside testnullrange ±{range}: StopNull would stop the motor there as at a \
             limit switch (the driver sets StopNoRef; without it the pack would search again: \
             manual, instruction set, $27: \"Can lead to unintended reference searches at \
             detection of zero switches\"). Keep home.position within ±{} {}, raise \
             reference.test_range, or leave stop_at_switch off",
            (position * cpu).round(),
            range / cpu,
            ctx.unit.unwrap_or("units"),
        ),
    );
    false
}

pub(crate) fn axis_keys(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    keys: &KeyTable<'_>,
) -> Option<AxisKeys> {
    let raw: RawAxis = keys.parse(v)?;
    let raw = &raw;
    let home = side_hint(v, ctx, raw);
    let mut ok = home.is_some();
    let mut keys = TmcpackAxisKeys::default();
    let cpu = ctx.counts_per_unit.map(f64::abs);
    if let Some(current) = &raw.current {
        let c = current.get_ref();
        let key = |k: &str| ctx.key(&format!("current.{k}"));
        if let Some(peak) = &c.peak {
            let p = *peak.get_ref();
            if p.is_finite() && (0.0..=100.0).contains(&p) {
                keys.current.peak = Some(p);
            } else {
                ok = false;
                v.issue(
                    peak.span(),
                    &key("peak"),
                    format!("{p} is not allowed; 0..=100 (% of the pack's full scale: SIXpack 0.8 A, QUADpack 1.5 A × its DIP setting; manual 8.3 $10)"),
                );
            }
        }
        for (value, k, slot) in [
            (&c.standby, "standby", &mut keys.current.standby),
            (&c.standstill, "standstill", &mut keys.current.standstill),
            (&c.constant, "constant", &mut keys.current.constant),
            (&c.accel, "accel", &mut keys.current.accel),
        ] {
            if let Some(value) = value {
                *slot = level(v, value, &key(k));
                ok &= slot.is_some();
            }
        }
        if let Some(value) = &c.standby_delay_ms {
            let what = "T0, the standby delay ($11, also used by $15 DelayTestNull)";
            match even_ms(v, value, &key("standby_delay_ms"), 2..=131_070, what) {
                Some(ms) => keys.current.standby_delay_ms = Some(ms as u32),
                None => ok = false,
            }
        }
    }
    if let Some(reference) = &raw.reference {
        let r = reference.get_ref();
        let key = |k: &str| ctx.key(&format!("reference.{k}"));
        if let Some(active) = &r.active {
            keys.reference.active_high = v.one_of(
                active,
                &key("active"),
                &[("low", false), ("high", true)],
                "level",
                "\"low\" (a closer to ground; default), \"high\" (an opener, normally closed, as manual section 4 advises: $15 NullPositive)",
            );
            ok &= keys.reference.active_high.is_some();
        }
        keys.reference.center = flag(&r.center);
        keys.reference.stop_at_switch = flag(&r.stop_at_switch);
        keys.reference.soft_stop = flag(&r.soft_stop);
        keys.reference.fast = flag(&r.fast);
        keys.reference.mechanical = flag(&r.mechanical);
        keys.reference.restore = flag(&r.restore);
        if let Some(value) = &r.debounce_ms {
            let ms = value.get_ref().get();
            if (0..=i64::from(MAX_DEBOUNCE_MS)).contains(&ms) && ms % 2 == 0 {
                keys.reference.debounce_ms = Some(ms as u16);
            } else {
                ok = false;
                v.issue(
                    value.span(),
                    &key("debounce_ms"),
                    format!("{} is not allowed; an even number of ms 0..=30 (manual 8.3 $16: \"$0001=0ms, $0003=2ms, $FFFF=30ms\")", value.get_ref()),
                );
            }
        }
        if let Some(value) = &r.null_offset {
            let d = *value.get_ref();
            let counts = cpu.map(|c| (d * c).round());
            if !d.is_finite() || counts.is_some_and(|n| n.abs() > f64::from(i32::MAX)) {
                ok = false;
                v.issue(
                    value.span(),
                    &key("null_offset"),
                    format!("{d} is not allowed; a finite distance (units) whose microsteps fit the signed 32-bit nulloffset of $18"),
                );
            } else {
                keys.reference.null_offset = Some(d);
            }
        }
        if let Some(value) = &r.test_range {
            let d = *value.get_ref();
            let counts = cpu.map(|c| (d * c).round());
            if !(d.is_finite() && d >= 0.0) || counts.is_some_and(|n| n > f64::from(u16::MAX)) {
                ok = false;
                v.issue(
                    value.span(),
                    &key("test_range"),
                    format!(
                        "{d} is not allowed; a distance >= 0 (units) of at most 65535 microsteps ($18 testnullrange){}",
                        cpu.map(|c| format!(" = {} units", f64::from(u16::MAX) / c))
                            .unwrap_or_default()
                    ),
                );
            } else {
                keys.reference.test_range = Some(d);
            }
        }
    }
    ok &= home_position_fits_stop_null(v, ctx, &keys.reference);
    ok &= drive::axis_keys(v, ctx, raw, &mut keys);
    keys.rotary = flag(&raw.rotary);
    let rotary = keys.rotary == Some(true);
    match (&raw.revolution, rotary) {
        (Some(value), true) => {
            let r = *value.get_ref();
            if r.is_finite() && r > 0.0 {
                keys.revolution = Some(r);
            } else {
                ok = false;
                v.issue(
                    value.span(),
                    &ctx.key("revolution"),
                    format!("{r} is not allowed; a finite distance > 0 (units per revolution)"),
                );
            }
        }
        (Some(value), false) => {
            ok = false;
            v.issue(
                value.span(),
                &ctx.key("revolution"),
                "applies only to an axis with `rotary = true`; a linear axis's reference range is its travel (max − min)",
            );
        }
        (None, true) if ctx.unit == Some("deg") => keys.revolution = Some(360.0),
        (None, true) => {
            ok = false;
            v.issue(
                ctx.table.clone(),
                &ctx.key("revolution"),
                "missing; a rotary axis needs its units per revolution (360 is assumed only for unit = \"deg\")",
            );
        }
        (None, false) => {}
    }
    ok &= poslimit_fits(v, ctx, raw, keys.revolution);
    if let Some(stop) = &raw.analog_stop {
        let s = stop.get_ref();
        let key = |k: &str| ctx.key(&format!("analog_stop.{k}"));
        let left = s
            .left
            .as_ref()
            .map(|value| v.int_in(value, &key("left"), 0..=1023).map(|x| x as u16));
        let right = s
            .right
            .as_ref()
            .map(|value| v.int_in(value, &key("right"), 0..=1023).map(|x| x as u16));
        ok &= left.is_none_or(|x| x.is_some()) && right.is_none_or(|x| x.is_some());
        keys.analog_stop_left = left.flatten();
        keys.analog_stop_right = right.flatten();
        if let (Some(l), Some(r), Some(value)) =
            (keys.analog_stop_left, keys.analog_stop_right, &s.right)
            && l > 0
            && r < 1023
            && l >= r
        {
            ok = false;
            v.issue(
                value.span(),
                &key("right"),
                format!("{r} must be above left ({l}): the value rises to the right (manual 8.5 $31); 0 and 1023 switch a side off"),
            );
        }
    }
    ok.then_some(AxisKeys::new(keys, home?))
}

/// $15 poslimit: one revolution of a rotary axis, the travel of a linear one, in
/// microsteps; it must fit 0..=0x7FFFFFFF.
fn poslimit_fits(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    raw: &RawAxis,
    revolution: Option<f64>,
) -> bool {
    let Some(cpu) = ctx.counts_per_unit.map(f64::abs) else {
        return true;
    };
    let (units, span, key, what) = match (revolution, ctx.min, ctx.max) {
        (Some(r), _, _) => (
            r,
            raw.revolution
                .as_ref()
                .map_or(ctx.table.clone(), Spanned::span),
            ctx.key("revolution"),
            "one revolution",
        ),
        (None, Some(lo), Some(hi)) => (
            hi - lo,
            ctx.max_span.clone().unwrap_or_else(|| ctx.table.clone()),
            ctx.key("max"),
            "the travel max − min",
        ),
        _ => return true,
    };
    let counts = (units * cpu).round();
    if counts > MAX_POSLIMIT {
        v.issue(
            span,
            &key,
            format!("{what} is {counts} microsteps; the pack's $15 poslimit allows at most {} (0x7FFFFFFF)", crate::driver::MAX_POSLIMIT),
        );
        return false;
    }
    if let (Some(r), Some(lo), Some(hi)) = (revolution, ctx.min, ctx.max)
        && hi - lo > r
    {
        v.warn(
            ctx.max_span.clone().unwrap_or_else(|| ctx.table.clone()),
            &ctx.key("max"),
            format!("a rotary axis's positions lie within one revolution ({r}) of the zero point (manual 8.4 $23: \"0 <= position < poslimit\" for a switch on the left); min..max spans {}", hi - lo),
        );
    }
    true
}
