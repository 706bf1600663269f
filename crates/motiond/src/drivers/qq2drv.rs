//! The QuadQuad2Drv driver of a `[[device]]`, configured from its axes and machine keys.

use motion_drivers::Driver;
use motion_drivers::qq2drv::{
    HomeInput, PINS_PER_CHANNEL, PositionPid, Qq2drvDriver, Qq2drvDriverConfig, VelocityPid,
};
use qq2drv::limits::POWER_LIMIT_MAX;

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{
    AxisMachine, DeviceSpec, Direction, HomeInputKind, Owner, Qq2drvAxisKeys, ServerConfig,
};

/// The machine keys of the axis on `device`'s `channel`, if one drives it.
fn axis_of(
    config: &ServerConfig,
    device: usize,
    channel: usize,
) -> Option<(usize, &Qq2drvAxisKeys)> {
    config
        .axes
        .iter()
        .zip(&config.axis_specs)
        .enumerate()
        .find(|(_, (axis, _))| axis.device == device && axis.channel == channel)
        .and_then(|(index, (_, spec))| match &spec.machine {
            AxisMachine::Qq2drv(keys) => Some((index, keys)),
            _ => None,
        })
}

/// Packet 24 Power Limit for a `power_limit` fraction (0.0..=1.0 of full power).
pub(crate) fn power_limit_counts(fraction: f64) -> u16 {
    let counts = (fraction.clamp(0.0, 1.0) * f64::from(POWER_LIMIT_MAX)).round();
    // 0 ≤ counts ≤ 8191.
    counts as u16
}

/// The driver configuration of qq2drv device `index`: its link's clock, each channel's axis
/// limits, PID constants, power limit and home input, and the pins its signals read.
pub(crate) fn driver_config(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> Qq2drvDriverConfig {
    let mut driver = Qq2drvDriverConfig::default();
    if let Some(speed) = line_rate(config, device) {
        driver.speed_hz = speed;
    }
    for (channel, slot) in driver.channels.iter_mut().enumerate() {
        match channel_limits(config, index, channel) {
            Some((max_velocity, max_accel)) => {
                slot.enabled = true;
                slot.limits.max_velocity = max_velocity;
                slot.limits.max_accel = max_accel;
            }
            None => slot.enabled = false,
        }
        if let Some((_, keys)) = axis_of(config, index, channel) {
            let defaults = PositionPid::default();
            let given = keys.pid_position;
            slot.position_pid = PositionPid {
                p: given.p.unwrap_or(defaults.p),
                i: given.i.unwrap_or(defaults.i),
                d: given.d.unwrap_or(defaults.d),
                windup: given.windup.unwrap_or(defaults.windup),
            };
            let defaults = VelocityPid::default();
            let given = keys.pid_velocity;
            slot.velocity_pid = VelocityPid {
                p: given.p.unwrap_or(defaults.p),
                i: given.i.unwrap_or(defaults.i),
                d: given.d.unwrap_or(defaults.d),
            };
            if let Some(fraction) = keys.power_limit {
                slot.power_limit = power_limit_counts(fraction);
            }
        }
        let home = config
            .axes
            .iter()
            .zip(&config.axis_specs)
            .find(|(axis, _)| axis.device == index && axis.channel == channel)
            .and_then(|(axis, spec)| {
                spec.home
                    .input
                    .map(|input| (axis.counts_per_unit, spec.home, input))
            });
        slot.home = home.map(|(counts_per_unit, home, input)| HomeInput {
            mode: match input.kind {
                HomeInputKind::Home => qq2drv::InputMode::Home,
                HomeInputKind::Index => qq2drv::InputMode::Index,
                HomeInputKind::Edge => qq2drv::InputMode::Edge,
            },
            active_high: input.active_high,
            // The direction is in axis units; a negative counts_per_unit turns it round.
            positive_end: (home.direction == Direction::Positive) == (counts_per_unit > 0.0),
            position: (home.position * counts_per_unit).round() as i32,
            // Validated: 1..=65535 transitions when given.
            spacing: input.spacing.map_or(0, |units| {
                (units * counts_per_unit).abs().round().clamp(1.0, 65_535.0) as u16
            }),
        });
    }
    for signal in config.signals.iter().filter(|s| s.device == index) {
        let pin = usize::from(signal.pin.0);
        if let Some(slot) = driver.channels.get_mut(pin / PINS_PER_CHANNEL) {
            slot.pins |= 1 << (pin % PINS_PER_CHANNEL);
        }
    }
    driver
}

/// The driver of qq2drv device `index`.
pub(crate) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    Box::new(Qq2drvDriver::new(driver_config(config, index, device)))
}

/// The machine parameters of qq2drv device `index` and its axes, as the driver uses them:
/// per axis the PID constants (packets 30, 32), the power limit (packet 24) and the home
/// input (packet 14). The board has no device-level machine keys.
pub(crate) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let driver = driver_config(config, index, device);
    for (channel, slot) in driver.channels.iter().enumerate() {
        let Some((axis, _)) = axis_of(config, index, channel) else {
            continue;
        };
        let unit = config.axes[axis].unit.as_str();
        let mut row = |key: &str, value: String| {
            out.push(ParamRow {
                owner: Owner::Axis(axis),
                key: key.to_owned(),
                value,
            });
        };
        let pid = slot.position_pid;
        row("pid_position.p", pid.p.to_string());
        row("pid_position.i", pid.i.to_string());
        row("pid_position.d", pid.d.to_string());
        row("pid_position.windup", pid.windup.to_string());
        let pid = slot.velocity_pid;
        row("pid_velocity.p", pid.p.to_string());
        row("pid_velocity.i", pid.i.to_string());
        row("pid_velocity.d", pid.d.to_string());
        row(
            "power_limit",
            format!(
                "{:.3} ({} of {POWER_LIMIT_MAX})",
                f64::from(slot.power_limit) / f64::from(POWER_LIMIT_MAX),
                slot.power_limit
            ),
        );
        let spec = &config.axis_specs[axis];
        match (slot.home, spec.home.input) {
            (Some(home), Some(input)) => {
                let kind = match input.kind {
                    HomeInputKind::Home => "home",
                    HomeInputKind::Index => "index",
                    HomeInputKind::Edge => "edge",
                };
                row("home.input", kind.to_owned());
                row("home.active_high", home.active_high.to_string());
                row(
                    "home.spacing",
                    match input.spacing {
                        Some(units) => format!("{units} {unit} ({} transitions)", home.spacing),
                        None => "0 (a single end-stop)".to_owned(),
                    },
                );
            }
            _ => row("home.input", "none (the axis cannot home)".to_owned()),
        }
    }
}
