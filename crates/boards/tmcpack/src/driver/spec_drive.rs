//! The driver config and the parameter rows of the pack's drive functions beyond the ramp
//! (the `keys::drive` module's keys): `power_down`, `microstep_table`, `start_velocity`,
//! `position_mode`, `pi`, `reference.restore`. Every row's value fits `MachineParam`'s 40
//! bytes.

use motion_drivers::spec::{DriverAxis, ParamOwner};

use super::config::{PiParams, Scale, clkdiv_for};
use super::{TmcpackChannel, TmcpackDriverConfig};
use crate::{PositionMode, PowerDownMode, TmcpackAxisKeys, TmcpackDeviceKeys};

/// The device's `power_down` and `microstep_table`.
pub(super) fn device(keys: &TmcpackDeviceKeys, driver: &mut TmcpackDriverConfig) {
    driver.power_down = keys.power_down.unwrap_or_default();
    driver.microstep_table = keys.microstep_table;
}

/// The axis's `start_velocity` (units/s → microsteps/s), `position_mode`, `pi`,
/// `reference.restore`.
pub(super) fn channel(axis: &DriverAxis, keys: &TmcpackAxisKeys, channel: &mut TmcpackChannel) {
    channel.start_velocity = keys.start_velocity.map(|v| v * axis.counts_per_unit.abs());
    channel.position_mode = keys.position_mode.unwrap_or_default();
    let p = keys.pi;
    let given = [
        p.propdiv.is_some(),
        p.intdiv.is_some(),
        p.intclip.is_some(),
        p.intinpclip.is_some(),
    ];
    channel.pi = given.contains(&true).then(|| {
        let d = PiParams::default();
        PiParams {
            propdiv: p.propdiv.unwrap_or(d.propdiv),
            intdiv: p.intdiv.unwrap_or(d.intdiv),
            intclip: p.intclip.unwrap_or(d.intclip),
            intinpclip: p.intinpclip.unwrap_or(d.intinpclip),
        }
    });
    channel.restore = keys.reference.restore.unwrap_or(true);
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

impl TmcpackDriverConfig {
    /// `power_down` and `microstep_table`.
    pub(super) fn drive_device_rows(&self, row: &mut dyn FnMut(ParamOwner, &'static str, String)) {
        let dev = ParamOwner::Device;
        row(
            dev,
            "power_down",
            match self.power_down {
                PowerDownMode::Off => "off (no $45)",
                PowerDownMode::Save => "save ($45: stop and save below 13 V)",
                PowerDownMode::Restore => "restore (save; loaded after a boot)",
            }
            .into(),
        );
        row(
            dev,
            "microstep_table",
            match &self.microstep_table {
                None => "not written (the pack's; factory sine)".into(),
                Some(t) if *t == tmcpack::table::SINE_TABLE => "factory sine (written, $17)".into(),
                Some(t) if *t == tmcpack::table::FULL_STEP_TABLE => {
                    "full step, all 255 (written, $17)".into()
                }
                Some(t) => {
                    let hex: String = t.iter().map(|e| format!("{e:02X}")).collect();
                    format!("hex {hex}")
                }
            },
        );
    }

    /// `start_velocity`, `position_mode`, `pi.*`, `reference.restore` of `axis` (motor
    /// `ch`).
    pub(super) fn drive_axis_rows(
        &self,
        axis: &DriverAxis,
        ch: &TmcpackChannel,
        row: &mut dyn FnMut(&'static str, String),
    ) {
        let motors = usize::from(self.variant.motors()).min(self.channels.len());
        let clkdiv = clkdiv_for(&self.channels[..motors]);
        let scale = Scale::new(clkdiv, ch, self.amax_divisor);
        let per_unit = axis.counts_per_unit.abs();
        let speed = f64::from(scale.vstart) * scale.hz / per_unit;
        let how = if ch.start_velocity.is_some() {
            ""
        } else {
            ", minimum"
        };
        row(
            "start_velocity",
            format!(
                "{} {}/s ($13 vstart {}{how})",
                num(speed),
                axis.unit,
                scale.vstart
            ),
        );
        row(
            "position_mode",
            match ch.position_mode {
                PositionMode::Ramp => "ramp ($14, $26, $23)",
                PositionMode::Pi => "pi ($24 PI controller)",
            }
            .into(),
        );
        let written = ch.written_pi();
        let d = PiParams::default();
        let p = written.unwrap_or(d);
        for (key, value) in [
            ("pi.propdiv", u32::from(p.propdiv)),
            ("pi.intdiv", u32::from(p.intdiv)),
            ("pi.intclip", u32::from(p.intclip)),
            ("pi.intinpclip", u32::from(p.intinpclip)),
        ] {
            row(
                key,
                if written.is_some() {
                    format!("{value} ($19)")
                } else {
                    format!("{value} (not written: the pack's)")
                },
            );
        }
        row(
            "reference.restore",
            if self.power_down != PowerDownMode::Restore {
                format!("{} (power_down is not restore)", ch.restore)
            } else {
                ch.restore.to_string()
            },
        );
    }
}
