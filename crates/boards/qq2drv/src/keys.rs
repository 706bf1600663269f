//! qq2drv machine keys (docs/CONFIG.md, docs/keys/qq2drv.md): validated here into
//! `Qq2drvAxisKeys` (machine_keys.rs), turned into the driver's config by
//! `Qq2drvDriverConfig::from_spec`.
//!
//! Per `[[axis]]` (one QuadQuad2Drv channel):
//! - `pid_position = { p, i, d, windup }`: packet 30, Set Position Control PID Constants
//!   (U16 each; the Windup Limit's range is 0..=8191);
//! - `pid_velocity = { p, i, d }`: packet 32, Set Velocity Control PID Constants (it has no
//!   windup limit);
//! - `power_limit`: fraction 0.0..=1.0 of full power, packet 24 Set Power Limit
//!   (0..=8191).
//!
//! Per `[[device]]`:
//! - `velocity_ramp = "signed" | "unsigned"`: how the board reads packet 36's Velocity
//!   (an I32 with "Range: 0 - 100,000"; docs/ARCHITECTURE.md), default `"signed"`;
//! - `silence_ms`: how long the board may say nothing on MISO before it is declared not
//!   answering (100..=60000, default 500: `motion_drivers::DEFAULT_SILENCE`).
//!
//! Across tables: a link clocked above the datasheet's recommended 500 kHz ("We recommend
//! clocking SPI up to 500kHz") gets a warning on its `speed_hz`.

use motion_board::keys::{AxisContext, DeviceContext, Int, KeyIssues, KeyTable, Spanned};
use motion_board::machine::MachineView;
use motion_board::{AxisKeys, DeviceKeys, Given, HomeHints};
use motion_drivers::Model;
use motion_drivers::spec::{Direction, HomeInput, HomeInputKind};
use qq2drv::limits::VelocityRampSign;
use serde::Deserialize;

use crate::{PidKeys, Qq2drvAxisKeys, Qq2drvDeviceKeys};

/// The qq2drv keys of a `[[device]]` as written; its fields name the keys the board has
/// (`key_names`, for the server's key check).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    velocity_ramp: Option<Spanned<String>>,
    silence_ms: Option<Spanned<Int>>,
}

/// Validates the qq2drv keys of a `[[device]]` table.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    keys: &KeyTable<'_>,
) -> Option<DeviceKeys> {
    let raw: RawDevice = keys.parse(v)?;
    let mut out = Qq2drvDeviceKeys::default();
    if let Some(value) = &raw.velocity_ramp {
        out.velocity_ramp = Some(v.one_of(
            value,
            &ctx.key("velocity_ramp"),
            &[
                ("signed", VelocityRampSign::Signed),
                ("unsigned", VelocityRampSign::Unsigned),
            ],
            "reading of packet 36",
            "\"signed\" (packet 36 Velocity is an I32, as packet 22's \"-100,000 shl 12 - \
             100,000 shl 12\": reverse is negative; the default), \"unsigned\" (its \
             \"Range: 0 - 100,000\": reverse goes out as packets 28 and 22)",
        )?);
    }
    if let Some(value) = &raw.silence_ms {
        out.silence = Some(v.silence_ms(value, &ctx.key("silence_ms"))?);
    }
    Some(DeviceKeys::new(out, HomeHints::default()))
}

/// The qq2drv keys of an `[[axis]]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAxis {
    pid_position: Option<Spanned<RawPid>>,
    pid_velocity: Option<Spanned<RawPid>>,
    power_limit: Option<Spanned<f64>>,
    home: Option<Spanned<RawHome>>,
}

/// `pid_position = { p, i, d, windup }` (packet 30) / `pid_velocity = { p, i, d }`
/// (packet 32).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPid {
    p: Option<Spanned<Int>>,
    i: Option<Spanned<Int>>,
    d: Option<Spanned<Int>>,
    windup: Option<Spanned<Int>>,
}

/// The qq2drv keys of an axis's `home` table: the channel's IN pin as a home input.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHome {
    input: Option<Spanned<String>>,
    active_high: Option<Spanned<bool>>,
    positive_end: Option<Spanned<bool>>,
    spacing: Option<Spanned<f64>>,
}

/// The axis keys the board has (for the server's key check): `RawAxis`'s and, as
/// `home.<key>`, `RawHome`'s (`Board::axis_key_names` returns static names, so the nested
/// ones are written out here; a test checks them against the structs).
pub(crate) const AXIS_KEYS: &[&str] = &[
    "pid_position",
    "pid_velocity",
    "power_limit",
    "home.input",
    "home.active_high",
    "home.positive_end",
    "home.spacing",
];

/// The datasheet's recommended maximum SPI clock ("SPI Interface").
pub const RECOMMENDED_MAX_SPEED_HZ: i64 = 500_000;
/// Packet 30 Windup Limit range: "Range: 0 - 8,191".
pub const WINDUP_MAX: i64 = 8_191;

/// Validates the qq2drv keys of an `[[axis]]` table.
pub(crate) fn axis_keys(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    keys: &KeyTable<'_>,
) -> Option<AxisKeys> {
    let raw: RawAxis = keys.parse(v)?;
    let mut ok = true;
    let home = match &raw.home {
        Some(table) => home_hints(v, ctx, table),
        None => Some(HomeHints::default()),
    };
    ok &= home.is_some();
    let pid_position = match &raw.pid_position {
        Some(table) => pid(v, ctx, "pid_position", table.get_ref(), true).unwrap_or_else(|| {
            ok = false;
            PidKeys::default()
        }),
        None => PidKeys::default(),
    };
    let pid_velocity = match &raw.pid_velocity {
        Some(table) => pid(v, ctx, "pid_velocity", table.get_ref(), false).unwrap_or_else(|| {
            ok = false;
            PidKeys::default()
        }),
        None => PidKeys::default(),
    };
    let power_limit = match &raw.power_limit {
        None => None,
        Some(value) => {
            let fraction = *value.get_ref();
            let key = ctx.key("power_limit");
            if !(fraction.is_finite() && (0.0..=1.0).contains(&fraction)) {
                v.issue(
                    value.span(),
                    &key,
                    format!(
                        "{fraction} is out of range; allowed: 0.0..=1.0, the fraction of full \
                         power the board limits the motor output to (packet 24, 0..=8191)"
                    ),
                );
                ok = false;
                None
            } else {
                if fraction == 0.0 {
                    v.warn(
                        value.span(),
                        &key,
                        "0.0 limits the motor output to nothing: this axis cannot move",
                    );
                }
                Some(fraction)
            }
        }
    };
    ok.then_some(AxisKeys::new(
        Qq2drvAxisKeys {
            pid_position,
            pid_velocity,
            power_limit,
        },
        home?,
    ))
}

/// An axis's `home` table: the channel's IN pin as its home input (`input`,
/// `active_high`, `spacing`) and `positive_end` (the direction the search runs).
fn home_hints(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    table: &Spanned<RawHome>,
) -> Option<HomeHints> {
    let h = table.get_ref();
    let key = |k: &str| ctx.key(&format!("home.{k}"));
    let mut hints = HomeHints::default();
    if let Some(p) = &h.positive_end {
        hints.direction.push(Given {
            value: if *p.get_ref() {
                Direction::Positive
            } else {
                Direction::Negative
            },
            span: p.span(),
            key: key("positive_end"),
        });
    }
    let kind = match &h.input {
        None => {
            v.issue(
                table.span(),
                &key("input"),
                "missing; a qq2drv axis homes on its channel's IN pin: one of \"home\", \"index\", \"edge\"",
            );
            None
        }
        Some(input) => v.one_of(
            input,
            &key("input"),
            &[
                ("home", HomeInputKind::Home),
                ("index", HomeInputKind::Index),
                ("edge", HomeInputKind::Edge),
            ],
            "input",
            "\"home\" (switch, acts while active), \"index\" (encoder index), \"edge\" (inactive-to-active edge)",
        ),
    };
    let spacing = match &h.spacing {
        None => Some(None),
        Some(s) => {
            let value = *s.get_ref();
            let counts = ctx.counts_per_unit.map(|cpu| (value * cpu).abs().round());
            if !(value.is_finite() && value > 0.0) {
                v.issue(s.span(), &key("spacing"), format!("{value} is not allowed; a finite distance > 0 (units) between the positive-end and negative-end triggers"));
                None
            } else if counts.is_some_and(|c| !(1.0..=f64::from(u16::MAX)).contains(&c)) {
                v.issue(s.span(), &key("spacing"), format!("{value} is {} transitions; packet 14 Spacing is U16: allowed 1..=65535 transitions", counts.unwrap_or(0.0)));
                None
            } else {
                Some(Some(value))
            }
        }
    };
    hints.input = Some(HomeInput {
        kind: kind?,
        active_high: h.active_high.as_ref().is_none_or(|v| *v.get_ref()),
        spacing: spacing?,
    });
    Some(hints)
}

/// One PID table: `p`, `i`, `d` are U16; `windup` only where `with_windup`.
fn pid(
    v: &mut dyn KeyIssues,
    ctx: &AxisContext<'_>,
    table: &str,
    raw: &RawPid,
    with_windup: bool,
) -> Option<PidKeys> {
    let mut ok = true;
    let mut constant = |v: &mut dyn KeyIssues, value: &Option<Spanned<Int>>, name: &str| {
        let key = ctx.key(&format!("{table}.{name}"));
        let value = value.as_ref()?;
        let checked = v
            .int_in(value, &key, 0..=i64::from(u16::MAX))
            .and_then(|c| u16::try_from(c).ok());
        ok &= checked.is_some();
        checked
    };
    let p = constant(v, &raw.p, "p");
    let i = constant(v, &raw.i, "i");
    let d = constant(v, &raw.d, "d");
    let windup = match &raw.windup {
        None => None,
        Some(value) if !with_windup => {
            v.issue(
                value.span(),
                &ctx.key(&format!("{table}.windup")),
                "packet 32 (velocity PID constants) has no windup limit; `windup` is a key of \
                 pid_position only",
            );
            ok = false;
            None
        }
        Some(value) => {
            let checked = v
                .int_in(value, &ctx.key(&format!("{table}.windup")), 0..=WINDUP_MAX)
                .and_then(|c| u16::try_from(c).ok());
            ok &= checked.is_some();
            checked
        }
    };
    ok.then_some(PidKeys { p, i, d, windup })
}

/// Checks across tables for qq2drv devices (after everything else was validated): a link
/// clocked above the recommended 500 kHz.
pub(crate) fn cross_check(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (index, link) in machine.links.iter().enumerate() {
        let (Some(hz), Some(span)) = (link.line_rate, link.rate_span.clone()) else {
            continue;
        };
        let carries_qq2drv = machine
            .devices
            .iter()
            .any(|device| device.model == Model::QQ2DRV && device.link == index);
        if carries_qq2drv && i64::from(hz) > RECOMMENDED_MAX_SPEED_HZ {
            v.warn(
                span,
                &format!("link[{}].speed_hz", link.index),
                format!(
                    "{hz} Hz is above the QuadQuad2Drv datasheet's recommended 500000 Hz \
                     (\"We recommend clocking SPI up to 500kHz\"); the board may miss bytes"
                ),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use motion_board::keys::key_names;

    use super::{AXIS_KEYS, RawAxis, RawHome};

    #[test]
    fn the_axis_keys_are_the_fields_of_the_raw_structs() {
        let home = key_names::<RawHome>().iter().map(|k| format!("home.{k}"));
        let names: Vec<String> = key_names::<RawAxis>()
            .iter()
            .filter(|k| **k != "home")
            .map(|k| (*k).to_owned())
            .chain(home)
            .collect();
        assert_eq!(names, AXIS_KEYS);
    }
}
