//! The driver config of a QuadQuad2Drv from the neutral [`DriverSpec`]: its link's clock,
//! each channel's axis limits, PID constants, power limit and home input, and the pins its
//! signals read; and the parameters that config gives the board, as `motionctl list` shows
//! them.

use qq2drv::InputMode;
use qq2drv::limits::POWER_LIMIT_MAX;

use super::{HomeInput, PINS_PER_CHANNEL, PositionPid, Qq2drvDriverConfig, VelocityPid};
use crate::{Qq2drvAxisKeys, Qq2drvDeviceKeys};
use motion_drivers::spec::{
    Direction, DriverSpec, FromSpec, HomeInputKind, Param, ParamOwner, SpecError,
};
use qq2drv::limits::VelocityRampSign;

/// The machine keys of the axis on `channel`, if one drives it, with its index in
/// `spec.axes`.
fn axis_of(spec: &DriverSpec, channel: usize) -> Option<(usize, &Qq2drvAxisKeys)> {
    spec.axes
        .iter()
        .enumerate()
        .find(|(_, axis)| axis.channel == channel)
        .and_then(|(index, axis)| Some((index, axis.machine.get::<Qq2drvAxisKeys>()?)))
}

/// Packet 24 Power Limit for a `power_limit` fraction (0.0..=1.0 of full power).
pub(crate) fn power_limit_counts(fraction: f64) -> u16 {
    let counts = (fraction.clamp(0.0, 1.0) * f64::from(POWER_LIMIT_MAX)).round();
    // 0 ≤ counts ≤ 8191.
    counts as u16
}

impl FromSpec for Qq2drvDriverConfig {
    /// The driver configuration of the qq2drv device `spec` describes: its link's clock,
    /// each channel's axis limits, PID constants, power limit and home input, and the pins
    /// its signals read.
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError> {
        let mut driver = Self::default();
        if let Some(speed) = spec.line_rate {
            driver.speed_hz = speed;
        }
        let device_keys = spec.machine.get_or_default::<Qq2drvDeviceKeys>();
        let velocity_ramp = device_keys.velocity_ramp.unwrap_or_default();
        if let Some(silence) = device_keys.silence {
            driver.silence = silence;
        }
        for (channel, slot) in driver.channels.iter_mut().enumerate() {
            match spec.channel_limits(channel) {
                Some(limits) => {
                    slot.enabled = true;
                    slot.limits = limits;
                }
                None => slot.enabled = false,
            }
            slot.velocity_ramp = velocity_ramp;
            if let Some((_, keys)) = axis_of(spec, channel) {
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
            let home = spec.axis_on(channel).and_then(|(_, axis)| {
                axis.home
                    .input
                    .map(|input| (axis.counts_per_unit, axis.home, input))
            });
            slot.home = home.map(|(counts_per_unit, home, input)| HomeInput {
                mode: match input.kind {
                    HomeInputKind::Home => InputMode::Home,
                    HomeInputKind::Index => InputMode::Index,
                    HomeInputKind::Edge => InputMode::Edge,
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
        for signal in &spec.signals {
            let pin = usize::from(signal.pin.0);
            if let Some(slot) = driver.channels.get_mut(pin / PINS_PER_CHANNEL) {
                slot.pins |= 1 << (pin % PINS_PER_CHANNEL);
            }
        }
        Ok(driver)
    }

    /// The machine parameters of the device's axes, as the driver uses them: per axis the
    /// PID constants (packets 30, 32), the power limit (packet 24) and the home input
    /// (packet 14); for the device, how it reads packet 36 (`velocity_ramp`).
    fn params(&self, spec: &DriverSpec) -> Vec<Param> {
        let mut out = Vec::new();
        let reading = self
            .channels
            .first()
            .map_or(VelocityRampSign::Signed, |c| c.velocity_ramp);
        out.push(Param {
            owner: ParamOwner::Device,
            key: "velocity_ramp",
            value: match reading {
                // At most 40 bytes: `MachineParam`'s text.
                VelocityRampSign::Signed => "signed (36 velocity an I32)",
                VelocityRampSign::Unsigned => "unsigned (reverse by packets 28, 22)",
            }
            .to_owned(),
        });
        out.push(Param {
            owner: ParamOwner::Device,
            key: "silence_ms",
            value: format!("{} ms", self.silence.as_millis()),
        });
        for (channel, slot) in self.channels.iter().enumerate() {
            let Some((axis, _)) = axis_of(spec, channel) else {
                continue;
            };
            let unit = spec.axes[axis].unit.as_str();
            let mut row = |key: &'static str, value: String| {
                out.push(Param {
                    owner: ParamOwner::Axis(axis),
                    key,
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
            let home = &spec.axes[axis].home;
            match (slot.home, home.input) {
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
                            Some(units) => {
                                format!("{units} {unit} ({} transitions)", home.spacing)
                            }
                            None => "0 (a single end-stop)".to_owned(),
                        },
                    );
                }
                _ => row("home.input", "none (the axis cannot home)".to_owned()),
            }
        }
        out
    }
}
