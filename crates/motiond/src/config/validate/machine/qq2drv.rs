//! qq2drv machine keys (README "Config"): validated here into
//! `board_qq2drv::Qq2drvAxisKeys`, turned into the driver's config by
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
//! Across tables: a link clocked above the datasheet's recommended 500 kHz ("We recommend
//! clocking SPI up to 500kHz") gets a warning on its `speed_hz`.

use board_qq2drv::{PidKeys, Qq2drvAxisKeys};
use motion_drivers::Model;
use toml::Spanned;

use super::AxisContext;
use crate::config::ServerConfig;
use crate::config::raw::{Int, RawAxis, RawConfig, RawPid};
use crate::config::validate::Validator;

/// The datasheet's recommended maximum SPI clock ("SPI Interface").
pub const RECOMMENDED_MAX_SPEED_HZ: i64 = 500_000;
/// Packet 30 Windup Limit range: "Range: 0 - 8,191".
pub const WINDUP_MAX: i64 = 8_191;

/// Validates the qq2drv keys of an `[[axis]]` table.
pub(in crate::config) fn axis_keys(
    v: &mut Validator<'_, '_>,
    ctx: &AxisContext<'_>,
    raw: &RawAxis,
) -> Option<Qq2drvAxisKeys> {
    let mut ok = true;
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
    ok.then_some(Qq2drvAxisKeys {
        pid_position,
        pid_velocity,
        power_limit,
    })
}

/// One PID table: `p`, `i`, `d` are U16; `windup` only where `with_windup`.
fn pid(
    v: &mut Validator<'_, '_>,
    ctx: &AxisContext<'_>,
    table: &str,
    raw: &RawPid,
    with_windup: bool,
) -> Option<PidKeys> {
    let mut ok = true;
    let mut constant = |v: &mut Validator<'_, '_>, value: &Option<Spanned<Int>>, name: &str| {
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
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    for (index, link) in raw.link.iter().enumerate() {
        let link = link.get_ref();
        let (Some(name), Some(speed)) = (&link.name, &link.speed_hz) else {
            continue;
        };
        let carries_qq2drv = config.devices.iter().any(|device| {
            device.model == Model::QQ2DRV
                && config
                    .links
                    .get(device.link)
                    .is_some_and(|l| &l.name == name.get_ref())
        });
        let hz = speed.get_ref().0;
        if carries_qq2drv && hz > i128::from(RECOMMENDED_MAX_SPEED_HZ) {
            v.warn(
                speed.span(),
                &format!("link[{index}].speed_hz"),
                format!(
                    "{hz} Hz is above the QuadQuad2Drv datasheet's recommended 500000 Hz \
                     (\"We recommend clocking SPI up to 500kHz\"); the board may miss bytes"
                ),
            );
        }
    }
}
