//! The effective machine parameters published on `motiond/<name>/params`: every board
//! key as its driver uses it (from `boards::describe`), plus every axis's supervision and
//! homing values, each marked as set by the config file or left at its default.

use motion_ipc::{MAX_PARAMS, MachineParam, MachineParams, ParamOwner, write_text};

use motion_config::boards::ParamRow;
use motion_config::{Owner, ServerConfig};

/// Keys that have another spelling in the config file (one fact, two names): a row under
/// the first counts as configured when the second was set on the related table.
fn aliases(key: &str) -> &'static [&'static str] {
    match key {
        "home.direction" => &["reference.side", "home.positive_end"],
        "home_direction" => &["home.direction"],
        "home_max_travel" => &["home.max_travel"],
        "home_offset" => &["home.position"],
        "home.max_travel" => &["home_max_travel"],
        "home.position" => &["home_offset"],
        _ => &[],
    }
}

/// Whether the config file set `key` on `owner` (directly, or through an alias on the
/// device/axis pair it belongs to).
pub fn from_config(config: &ServerConfig, owner: Owner, key: &str) -> bool {
    if config.given.contains(owner, key) {
        return true;
    }
    let related: Vec<Owner> = match owner {
        Owner::Axis(index) => {
            let mut related = vec![owner];
            if let Some(axis) = config.axes.get(index) {
                related.push(Owner::Device(axis.device));
            }
            related
        }
        Owner::Device(index) => {
            let mut related = vec![owner];
            related.extend(
                config
                    .axes
                    .iter()
                    .enumerate()
                    .filter(|(_, axis)| axis.device == index)
                    .map(|(axis, _)| Owner::Axis(axis)),
            );
            related
        }
        other => vec![other],
    };
    aliases(key).iter().any(|alias| {
        related
            .iter()
            .any(|owner| config.given.contains(*owner, alias))
    })
}

/// `value` with at most six significant digits (17.99998560001152 → 18).
fn short(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let digits = 6 - 1 - value.abs().log10().floor() as i32;
    let rounded = if digits > 0 {
        let scale = 10f64.powi(digits);
        (value * scale).round() / scale
    } else {
        value.round()
    };
    format!("{rounded}")
}

/// Every axis's supervision and homing values (all models).
fn axis_rows(config: &ServerConfig, out: &mut Vec<ParamRow>) {
    for (index, (axis, spec)) in config.axes.iter().zip(&config.axis_specs).enumerate() {
        let owner = Owner::Axis(index);
        let unit = &axis.unit;
        let mut row = |key: &str, value: String| {
            out.push(ParamRow {
                owner,
                key: key.to_owned(),
                value,
            });
        };
        row(
            "position_tolerance",
            format!("{} {unit}", short(axis.position_tolerance)),
        );
        row(
            "following_error",
            format!("{} {unit}", short(axis.following_error)),
        );
        row("overspeed_factor", short(axis.overspeed_factor));
        row("estop", axis.estop.id().to_owned());
        row("home.direction", spec.home.direction.id().to_owned());
        row(
            "home.max_travel",
            format!("{} {unit}", short(spec.home.max_travel)),
        );
        row(
            "home.position",
            format!("{} {unit}", short(spec.home.position)),
        );
    }
}

/// The parameters of `config`, ready to publish.
pub fn machine_params(config: &ServerConfig) -> Box<MachineParams> {
    let mut rows = motion_config::boards::describe(config);
    axis_rows(config, &mut rows);
    rows.sort_by_key(|row| row.owner);
    let mut params = Box::new(MachineParams::EMPTY);
    for (row, out) in rows.iter().zip(params.entries.iter_mut()) {
        let (kind, index) = match row.owner {
            Owner::Device(index) => (ParamOwner::Device, index),
            Owner::Axis(index) => (ParamOwner::Axis, index),
            Owner::Server | Owner::Link(_) | Owner::Signal(_) | Owner::Group(_) => continue,
        };
        *out = MachineParam::EMPTY;
        write_text(&mut out.key, &row.key);
        write_text(&mut out.value, &row.value);
        out.owner_kind = kind as u8;
        out.owner_index = u16::try_from(index).unwrap_or(u16::MAX);
        out.from_config = u8::from(from_config(config, row.owner, &row.key));
        params.count += 1;
    }
    params.truncated = u32::from(rows.len() > MAX_PARAMS);
    params
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    const CONFIG: &str = r#"
[server]
name = "p"

[[link]]
name = "l"
type = "sim"

[[device]]
name = "d"
link = "l"
model = "qq2drv"

[[axis]]
name = "a"
device = "d"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -10.0
max = 10.0
max_velocity = 5.0
max_accel = 50.0
following_error = 0.5
home = { input = "home", positive_end = true }
"#;

    #[test]
    fn figures_are_shown_with_six_significant_digits() {
        assert_eq!(short(17.99998560001152), "18");
        assert_eq!(short(0.03599997120002304), "0.036");
        assert_eq!(short(1.5625), "1.5625");
        assert_eq!(short(2_500_000.0), "2500000");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn supervision_rows_are_marked_config_or_default() {
        let config = ServerConfig::parse(Path::new("p.toml"), CONFIG).expect("valid");
        let params = machine_params(&config);
        let find = |key: &str| {
            params
                .entries()
                .iter()
                .find(|p| p.key() == key && p.owner() == Ok(ParamOwner::Axis))
                .copied()
                .unwrap_or_else(|| panic!("{key} listed"))
        };
        assert_eq!(find("following_error").value(), "0.5 mm");
        assert_eq!(find("following_error").from_config, 1);
        assert_eq!(find("overspeed_factor").value(), "1.5");
        assert_eq!(find("overspeed_factor").from_config, 0);
        assert_eq!(find("home.direction").value(), "positive");
        assert_eq!(find("home.direction").from_config, 1, "set as positive_end");
        assert_eq!(find("home.max_travel").value(), "25 mm");
        assert_eq!(find("home.max_travel").from_config, 0);
        assert_eq!(params.truncated, 0);
    }
}
