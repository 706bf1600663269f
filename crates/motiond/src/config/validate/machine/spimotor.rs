//! spimotor machine keys (README "Config"): validated here into
//! `board_spimotor::SpimotorDeviceKeys`, turned into the driver's config by
//! `SpimotorDriverConfig::from_spec`.
//!
//! Per `[[device]]` (the SPI_motor "Motor protocol" page, write ports):
//! - `intensity`: port 0x10 "Set drive intensity for stepper mode (default is 0x20)",
//!   0..=255;
//! - `coils`: port 0x44 "Set number of driven coils. Writing 0x00 means driving one coil,
//!   other values mean driving two coils": 1 or 2.
//!
//! Both are stepper settings: on a `drive = "brushed"` board they would do nothing (the
//! brushed section's intensity is each spin command's byte), so they are an error there.

use board_spimotor::{SpiDrive, SpimotorDeviceKeys};
use toml::Spanned;

use super::DeviceContext;
use crate::config::ServerConfig;
use crate::config::raw::{Int, RawConfig, RawDevice};
use crate::config::validate::Validator;

/// Validates the spimotor keys of a `[[device]]` table.
pub(in crate::config) fn device_keys(
    v: &mut Validator<'_, '_>,
    ctx: &DeviceContext,
    raw: &RawDevice,
) -> Option<SpimotorDeviceKeys> {
    let brushed = raw
        .drive
        .as_ref()
        .is_some_and(|drive| drive.get_ref() == "brushed");
    let mut ok = true;
    let intensity = stepper_only(v, ctx, brushed, &raw.intensity, "intensity", &mut ok);
    let coils = stepper_only(v, ctx, brushed, &raw.coils, "coils", &mut ok);
    let intensity = match intensity {
        None => None,
        Some(value) => {
            let checked = v
                .int_in(value, &ctx.key("intensity"), 0..=255)
                .and_then(|i| u8::try_from(i).ok());
            if checked == Some(0) {
                v.warn(
                    value.span(),
                    &ctx.key("intensity"),
                    "0 leaves the stepper's coils without current: it can neither move nor \
                     hold (port 0x10; the board's default is 0x20 = 32)",
                );
            }
            ok &= checked.is_some();
            checked
        }
    };
    let coils = match coils {
        None => None,
        Some(value) => match value.get_ref().get() {
            1 => Some(1),
            2 => Some(2),
            _ => {
                v.issue(
                    value.span(),
                    &ctx.key("coils"),
                    format!(
                        "{} is not allowed; allowed: 1 (one coil at a time, port 0x44 ← \
                         0x00) or 2 (two coils, port 0x44 ← 0x01)",
                        value.get_ref()
                    ),
                );
                ok = false;
                None
            }
        },
    };
    ok.then_some(SpimotorDeviceKeys {
        drive: if brushed {
            SpiDrive::Brushed
        } else {
            SpiDrive::Stepper
        },
        intensity,
        coils,
    })
}

/// `value` of a stepper-only key: an issue (and `None`) on a brushed board.
fn stepper_only<'a>(
    v: &mut Validator<'_, '_>,
    ctx: &DeviceContext,
    brushed: bool,
    value: &'a Option<Spanned<Int>>,
    key: &str,
    ok: &mut bool,
) -> Option<&'a Spanned<Int>> {
    let value = value.as_ref()?;
    if brushed {
        let port = if key == "intensity" { "0x10" } else { "0x44" };
        v.issue(
            value.span(),
            &ctx.key(key),
            format!(
                "`{key}` applies to drive = \"stepper\" only (port {port} is a stepper \
                 setting); this board drives two brushed motors"
            ),
        );
        *ok = false;
        return None;
    }
    Some(value)
}

/// Checks across tables for spimotor devices (after everything else was validated): none
/// so far (addresses on a shared bus are checked with the devices).
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    let _ = (v, config, raw);
}
