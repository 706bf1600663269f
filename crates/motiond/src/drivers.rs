//! The driver of each configured device starts from its [`DriverSpec`]: the device, its axes,
//! its signals and the devices sharing its link, in the drivers' neutral terms
//! (`motion_drivers::spec`), filled here from the validated config. Each board's crate
//! (`crates/boards/<board>`, its `<Board>DriverConfig::from_spec`) does the unit conversions
//! and protocol encodings, reached through the board registry (`motion_boards`: `boards.rs`
//! builds each device's driver from [`driver_spec`], names the config key of a refusal with
//! [`spec_error`], and places the parameters a board reports with [`param_rows`]).

use motion_drivers::spec::{
    BusPeer, DriverAxis, DriverSignal, DriverSpec, Param, ParamOwner, SpecError,
};
use motion_engine::AxisConfig;

use crate::boards::BuildError;
use crate::config::{AxisSpec, DeviceSpec, LinkSpec, Owner, ServerConfig};

/// One effective machine parameter, as `motionctl list` shows it: the key as the config
/// spells it (dotted for tables: `current.standstill`) on its device or axis, and the value
/// the driver uses, with its unit (`"50 %"`, `"-4"`, `"left"`). Whether the value came from
/// the config or is the default is decided from [`ServerConfig::given`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamRow {
    /// The device or axis.
    pub owner: Owner,
    /// Config key.
    pub key: String,
    /// Effective value.
    pub value: String,
}

/// The line rate of `device`'s link (baud, SPI clock or CAN bit rate), when the config
/// gives one.
fn line_rate(config: &ServerConfig, device: &DeviceSpec) -> Option<u32> {
    config.links.get(device.link)?.transport.rate()
}

/// Indexes (into [`ServerConfig::axes`]) of the axes on device `index`, in config order.
fn axes_on(config: &ServerConfig, index: usize) -> impl Iterator<Item = usize> + '_ {
    config
        .axes
        .iter()
        .enumerate()
        .filter(move |(_, axis)| axis.device == index)
        .map(|(i, _)| i)
}

fn driver_axis(axis: &AxisConfig, spec: &AxisSpec) -> DriverAxis {
    DriverAxis {
        channel: axis.channel,
        unit: axis.unit.clone(),
        counts_per_unit: axis.counts_per_unit,
        min: axis.min,
        max: axis.max,
        max_velocity: axis.max_velocity,
        max_accel: axis.max_accel,
        home: spec.home,
        machine: spec.machine.clone(),
    }
}

fn signals_on(config: &ServerConfig, index: usize) -> Vec<DriverSignal> {
    config
        .signals
        .iter()
        .filter(|signal| signal.device == index)
        .map(|signal| DriverSignal {
            pin: signal.pin,
            kind: signal.kind,
        })
        .collect()
}

/// The spec of device `index` (`device`) of `config`.
pub fn driver_spec(config: &ServerConfig, index: usize, device: &DeviceSpec) -> DriverSpec {
    DriverSpec {
        name: device.name.clone(),
        model: device.model,
        line_rate: line_rate(config, device),
        framing: config
            .links
            .get(device.link)
            .map_or(motion_drivers::LinkFraming::Bytes, LinkSpec::framing),
        address: device.address,
        machine: device.machine.clone(),
        axes: axes_on(config, index)
            .map(|i| driver_axis(&config.axes[i], &config.axis_specs[i]))
            .collect(),
        signals: signals_on(config, index),
        bus: config
            .devices
            .iter()
            .enumerate()
            .filter(|(_, peer)| peer.link == device.link)
            .map(|(i, peer)| BusPeer {
                model: peer.model,
                axes: axes_on(config, i).count(),
                signals: signals_on(config, i),
                machine: peer.machine.clone(),
            })
            .collect(),
    }
}

/// `error` of device `index`'s spec, naming the config key it is about.
pub fn spec_error(config: &ServerConfig, index: usize, error: &SpecError) -> BuildError {
    let device = config.devices.get(index).map_or("?", |d| d.name.as_str());
    let key = match error.channel {
        None => format!("device[{index}].{}", error.key),
        Some(channel) => axes_on(config, index)
            .find(|&i| config.axes[i].channel == channel)
            .map_or_else(
                || format!("device[{index}] channel {channel}: {}", error.key),
                |i| format!("axis[{i}].{}", error.key),
            ),
    };
    BuildError {
        device: device.to_owned(),
        key,
        message: error.message.clone(),
    }
}

/// `params` of device `index` as [`ParamRow`]s.
pub fn param_rows(config: &ServerConfig, index: usize, params: Vec<Param>) -> Vec<ParamRow> {
    let axes: Vec<usize> = axes_on(config, index).collect();
    params
        .into_iter()
        .filter_map(|param| {
            let owner = match param.owner {
                ParamOwner::Device => Owner::Device(index),
                ParamOwner::Axis(a) => Owner::Axis(*axes.get(a)?),
            };
            Some(ParamRow {
                owner,
                key: param.key.to_owned(),
                value: param.value,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use board_qsb::driver::{CaptureInput, EnableOutput, QsbDriverConfig};
    use motion_drivers::Pin;

    use super::*;

    /// The driver config of qsb device 0 of `config`.
    fn driver_config(config: &ServerConfig, index: usize, device: &DeviceSpec) -> QsbDriverConfig {
        QsbDriverConfig::from_spec(&driver_spec(config, index, device)).expect("a valid spec")
    }

    fn config(device_keys: &str, counts_per_unit: f64, signals: &str) -> ServerConfig {
        let text = format!(
            "[server]\nname = \"q\"\n\n[[link]]\nname = \"usb\"\ntype = \"serial\"\npath = \"/dev/null-qsb\"\nbaud = 115200\n\n[[device]]\nname = \"q\"\nlink = \"usb\"\nmodel = \"qsb\"\n{device_keys}\n\n[[axis]]\nname = \"a\"\ndevice = \"q\"\nchannel = 0\nunit = \"mm\"\ncounts_per_unit = {counts_per_unit}\nmin = -10.0\nmax = 30.0\nmax_velocity = 5.0\nmax_accel = 50.0\n{signals}"
        );
        ServerConfig::parse(Path::new("t.toml"), &text).expect("valid")
    }

    #[test]
    fn home_spec_maps_to_counts_with_the_sign_of_counts_per_unit() {
        let keys = "home_direction = \"positive\"\nhome_max_travel = 12.5\nhome_offset = -1.25";
        let up = config(keys, 100.0, "");
        let driver = driver_config(&up, 0, &up.devices[0]);
        assert!(driver.home_positive);
        assert_eq!(driver.home_max_travel, 1250.0);
        assert_eq!(driver.home_position, -125);
        assert_eq!(driver.baud, 115_200);
        assert_eq!((driver.max_velocity, driver.max_accel), (500.0, 5000.0));
        assert!(driver.motor_drive);
        // counts_per_unit < 0: positive units are negative counts.
        let down = config(keys, -100.0, "");
        let driver = driver_config(&down, 0, &down.devices[0]);
        assert!(!driver.home_positive);
        assert_eq!(driver.home_max_travel, 1250.0);
        assert_eq!(driver.home_position, 125);
        // Defaults: negative, 1.25 × the 40 mm range, 0.
        let plain = config("", 100.0, "");
        let driver = driver_config(&plain, 0, &plain.devices[0]);
        assert!(!driver.home_positive);
        assert_eq!(driver.home_max_travel, 5000.0);
        assert_eq!(driver.home_position, 0);
    }

    #[test]
    fn machine_keys_and_signals_reach_the_driver_config() {
        let keys = "counts_per_step = -2.5\nindex_polarity = \"inverted\"\nstream_interval_ms = 3.9\nhost_latency_ms = 12.0\nenable_output = 0\nenable_active = \"high\"\ncapture_input = 3\ncapture_edge = \"falling\"";
        let signals =
            "\n[[signal]]\nname = \"door\"\ndevice = \"q\"\nkind = \"digital-in\"\npin = \"io3\"\n";
        let set = config(keys, 100.0, signals);
        let driver = driver_config(&set, 0, &set.devices[0]);
        assert_eq!(driver.counts_per_step, -2.5);
        assert!(driver.invert_index);
        assert_eq!(driver.stream_interval, Some(2));
        assert_eq!(driver.latency, core::time::Duration::from_millis(12));
        assert_eq!(
            driver.enable,
            Some(EnableOutput {
                bit: 0,
                active_high: true
            })
        );
        assert_eq!(driver.io.digital_in, 0b1000);
        assert_eq!(
            driver.io.capture,
            Some(CaptureInput {
                bit: 3,
                falling: true
            })
        );
        assert_eq!(set.signals[0].pin, Pin(3));
    }
}
