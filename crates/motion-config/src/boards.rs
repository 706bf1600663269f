//! What motiond does with the boards of its config, through the board registry
//! (`motion_boards`): [`build`] the drivers, [`describe`] their machine parameters, serve a
//! `type = "sim"` link with simulated boards ([`sim_link`]), a `type = "sim-can"` link
//! ([`sim_can_link`]). motiond names no board here: each model's facts, driver, parameters
//! and simulator are its board crate's (`crates/boards/<board>/`, trait
//! `motion_board::Board`), its machine keys too (read and validated by the board through
//! `config/validate/machine/`).
//!
//! Each board's driver starts from its [`DriverSpec`]: the device, its axes, its signals
//! and the devices sharing its link, in the drivers' neutral terms
//! (`motion_drivers::spec`), filled here from the validated config ([`driver_spec`]). The
//! board's crate (its `<Board>DriverConfig::from_spec`) does the unit conversions and
//! protocol encodings; a refusal names its config key ([`spec_error`]), and the parameters
//! a board reports are placed on their device or axis ([`param_rows`]).

pub use motion_boards::AnyDriver;
use motion_boards::{Board, SimBoard};
use motion_drivers::spec::{
    BusPeer, DriverAxis, DriverSignal, DriverSpec, Param, ParamOwner, SpecError,
};
use motion_engine::AxisConfig;
use motion_link::sim::{CanBus, SimCanLink, SimLink, SpiBus, StreamBus};

use crate::{AxisSpec, DeviceSpec, LinkSpec, Owner, ServerConfig, Transport};

/// A device whose driver cannot be built from its validated config: the key and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("device `{device}`: {key}: {message}")]
pub struct BuildError {
    /// The device's name.
    pub device: String,
    /// The config key the board refused (`device[0].switchover_ms`, `axis[3].current.peak`).
    pub key: String,
    /// What is wrong with its value.
    pub message: String,
}

/// The board of `device`.
#[must_use]
pub fn board_of(device: &DeviceSpec) -> &'static dyn Board {
    motion_boards::board(device.model)
}

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

/// Builds the drivers of `config`'s devices, in config order, as the registry's enum the
/// tick holds (`AnyDriver`: static dispatch, each driver inline in its link's bus).
///
/// # Errors
/// The first device whose board refuses its spec.
pub fn build(config: &ServerConfig) -> Result<Vec<AnyDriver>, BuildError> {
    let mut built = Vec::with_capacity(config.devices.len());
    for (index, device) in config.devices.iter().enumerate() {
        let spec = driver_spec(config, index, device);
        let driver = AnyDriver::build(&spec).map_err(|error| spec_error(config, index, &error))?;
        built.push(driver);
    }
    Ok(built)
}

/// Every machine parameter of every device and axis, with the value in effect.
pub fn describe(config: &ServerConfig) -> Vec<ParamRow> {
    let mut rows = Vec::new();
    for (index, device) in config.devices.iter().enumerate() {
        let spec = driver_spec(config, index, device);
        // A device whose spec the driver refuses has no driver and so no parameters.
        if let Ok(params) = board_of(device).params(&spec) {
            rows.extend(param_rows(config, index, params));
        }
    }
    rows
}

/// The simulated link `link` of `config` (a `type = "sim"` link) with the models of its
/// devices, at its rate (baud for serial boards, SPI clock for SPI boards).
pub fn sim_link(config: &ServerConfig, link: usize) -> SimLink {
    let spec = &config.links[link];
    let name = spec.name.as_str();
    let rate = match spec.transport {
        Transport::Sim { rate } => rate,
        _ => 1_000_000,
    };
    let mut spi_bus = SpiBus::new();
    let mut stream_bus = StreamBus::new();
    let mut host_frame = None;
    for (index, device) in config.devices.iter().enumerate() {
        if device.link != link {
            continue;
        }
        let board = board_of(device);
        let model = board.simulate(&driver_spec(config, index, device), device.sim_seed);
        // Validation keeps SPI and stream models apart; a model of the other kind is left out.
        match (model, spec.kind) {
            (SimBoard::Spi(model), motion_drivers::LinkKind::Spi) => spi_bus.push(model),
            (SimBoard::Stream(model), motion_drivers::LinkKind::Stream) => {
                stream_bus.push(model);
            }
            (SimBoard::Spi(_) | SimBoard::Stream(_), _) => {}
        }
        // Devices behind USB share its frames (a link mixes no others in practice).
        host_frame = host_frame.max(board.link().host_frame);
    }
    match spec.kind {
        motion_drivers::LinkKind::Spi => SimLink::spi(name, rate, Box::new(spi_bus)),
        motion_drivers::LinkKind::Stream => {
            let link = SimLink::stream(name, rate, Box::new(stream_bus));
            match host_frame {
                Some(frame) => link.with_host_frames(frame),
                None => link,
            }
        }
    }
}

/// The simulated CAN bus `link` of `config` (a `type = "sim-can"` link) with the CAN
/// models of its devices, at its bit rate. A board without CAN is left off (validation
/// refuses it on a CAN link).
pub fn sim_can_link(config: &ServerConfig, link: usize) -> SimCanLink {
    let spec = &config.links[link];
    let bitrate = match spec.transport {
        Transport::SimCan { bitrate } | Transport::SocketCan { bitrate, .. } => bitrate,
        _ => 250_000,
    };
    let mut bus = CanBus::new();
    for (index, device) in config.devices.iter().enumerate() {
        if device.link != link {
            continue;
        }
        if let Some(model) =
            board_of(device).simulate_can(&driver_spec(config, index, device), device.sim_seed)
        {
            bus.push(model);
        }
    }
    SimCanLink::new(&spec.name, bitrate, Box::new(bus))
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
    use motion_drivers::spec::FromSpec as _;
    use motion_ipc::{DeviceInfo, write_text};

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

    /// The engine writes each model's id into `DeviceInfo::model_id`, where clients read
    /// the model's name: every registered id fits whole and reads back as itself.
    #[test]
    fn every_model_id_travels_whole_in_the_device_info() {
        for board in motion_boards::BOARDS {
            let id = board.model().id();
            let mut device = DeviceInfo::EMPTY;
            assert!(write_text(&mut device.model_id, id), "{id} is cut");
            assert_eq!(device.model_name(), id);
        }
    }
}
