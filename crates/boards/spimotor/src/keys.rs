//! spimotor machine keys (docs/CONFIG.md, docs/keys/spimotor.md): validated here into
//! `crate::SpimotorDeviceKeys`, turned into the driver's config by
//! `SpimotorDriverConfig::from_spec`.
//!
//! `drive`: "stepper" (one axis on channel 0; default) or "brushed" (channels 0 = A,
//! 1 = B). `address` (the server's general key, checked here): an even number 2..=254,
//! bit 0 being the read flag; default 0x90.
//!
//! Per `[[device]]` (the SPI_motor "Motor protocol" page, write ports):
//! - `intensity`: port 0x10 "Set drive intensity for stepper mode (default is 0x20)",
//!   0..=255;
//! - `coils`: port 0x44 "Set number of driven coils. Writing 0x00 means driving one coil,
//!   other values mean driving two coils": 1 or 2.
//!
//! Both are stepper settings: on a `drive = "brushed"` board they would do nothing (the
//! brushed section's intensity is each spin command's byte), so they are an error there.
//!
//! - `silence_ms` (either drive): how long a transaction's MISO may stay away before the
//!   board is declared not answering (100..=60000, default 500:
//!   `motion_drivers::DEFAULT_SILENCE`).

use motion_board::keys::{DeviceContext, Int, KeyIssues, KeyTable, Spanned};
use motion_board::{DeviceKeys, HomeHints};
use serde::Deserialize;

use crate::{SpiDrive, SpimotorDeviceKeys};

/// The spimotor keys of a `[[device]]` as written; its fields name the keys the board has
/// (`key_names`, for the server's key check).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    drive: Option<Spanned<String>>,
    intensity: Option<Spanned<Int>>,
    coils: Option<Spanned<Int>>,
    silence_ms: Option<Spanned<Int>>,
}

/// `address`: "an even number 2..=254 (bit 0 is the read flag)".
pub(crate) fn check_address(value: i128) -> Result<u32, String> {
    if (2..=254).contains(&value) && value % 2 == 0 {
        Ok(value as u32)
    } else {
        Err(format!(
            "{value} is not an SPI_motor address; allowed: an even number 2..=254 (bit 0 is \
             the read flag), default 0x90 = 144"
        ))
    }
}

/// Validates the spimotor keys of a `[[device]]` table.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    keys: &KeyTable<'_>,
) -> Option<DeviceKeys> {
    let raw: RawDevice = keys.parse(v)?;
    let mut ok = true;
    let brushed = match &raw.drive {
        None => false,
        Some(drive) => v
            .one_of(
                drive,
                &ctx.key("drive"),
                &[("stepper", false), ("brushed", true)],
                "drive",
                "\"stepper\" (one axis, channel 0), \"brushed\" (channels 0 = A, 1 = B)",
            )
            .unwrap_or_else(|| {
                ok = false;
                false
            }),
    };
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
    let silence = match &raw.silence_ms {
        None => None,
        Some(value) => {
            let checked = v.silence_ms(value, &ctx.key("silence_ms"));
            ok &= checked.is_some();
            checked
        }
    };
    ok.then_some(DeviceKeys::new(
        SpimotorDeviceKeys {
            silence,
            drive: if brushed {
                SpiDrive::Brushed
            } else {
                SpiDrive::Stepper
            },
            intensity,
            coils,
        },
        HomeHints::default(),
    ))
}

/// `value` of a stepper-only key: an issue (and `None`) on a brushed board.
fn stepper_only<'a>(
    v: &mut dyn KeyIssues,
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
