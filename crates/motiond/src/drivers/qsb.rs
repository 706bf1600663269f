//! The QSB driver of a `[[device]]`, configured from its axis, its machine keys
//! (`docs/keys/qsb.md`) and its signals.

use motion_drivers::Driver;
use motion_drivers::qsb::{CaptureInput, EnableOutput, QsbDriver, QsbDriverConfig, QsbIo};
use qsb::{EncoderMode, TICK};

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{
    AxisSpec, DeviceMachine, DeviceSpec, Direction, Owner, QsbDeviceKeys, QsbVariant, ServerConfig,
};

/// The product of a configured variant.
fn product(variant: QsbVariant) -> qsb::ProductType {
    match variant {
        QsbVariant::M => qsb::ProductType::M,
        QsbVariant::S => qsb::ProductType::S,
        QsbVariant::D => qsb::ProductType::D,
    }
}

/// The axis on channel 0 of qsb device `index`, with its spec.
fn axis_of(config: &ServerConfig, index: usize) -> Option<(&motion_engine::AxisConfig, &AxisSpec)> {
    config
        .axes
        .iter()
        .zip(&config.axis_specs)
        .find(|(axis, _)| axis.device == index && axis.channel == 0)
}

/// The device's qsb keys (all `None` for a device without them).
fn keys_of(device: &DeviceSpec) -> QsbDeviceKeys {
    match &device.machine {
        DeviceMachine::Qsb(keys) => keys.clone(),
        _ => QsbDeviceKeys::default(),
    }
}

/// The driver config of qsb device `index`: the link's baud, the axis's limits and
/// `HomeSpec`, the machine keys, the signals. Shared by [`build`] and [`describe`].
pub(crate) fn driver_config(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> QsbDriverConfig {
    let keys = keys_of(device);
    let variant = product(device.qsb_variant);
    let mut driver = QsbDriverConfig {
        variant,
        ..QsbDriverConfig::default()
    };
    if let Some(baud) = line_rate(config, device) {
        driver.baud = baud;
    }
    if let Some((max_velocity, max_accel)) = channel_limits(config, index, 0) {
        driver.max_velocity = max_velocity;
        driver.max_accel = max_accel;
    }
    let axis = axis_of(config, index);
    if let Some((axis, spec)) = axis {
        let cpu = axis.counts_per_unit;
        // The search direction in counts: a negative counts_per_unit turns it round.
        driver.home_positive = (spec.home.direction == Direction::Positive) == (cpu > 0.0);
        driver.home_max_travel = spec.home.max_travel * cpu.abs();
        // (Validation keeps it within the 32-bit counter.)
        driver.home_position = (spec.home.position * cpu).round() as i32;
    }
    if let Some(c) = keys.counts_per_step {
        driver.counts_per_step = c;
    }
    driver.invert_index = keys.index_inverted.unwrap_or(false);
    driver.stream_interval = keys.stream_interval_ticks;
    if let Some(latency) = keys.host_latency {
        driver.latency = latency;
    }
    driver.input_mode = keys.input_mode.unwrap_or_default();
    driver.motor_drive = driver.input_mode == EncoderMode::Quadrature && axis.is_some();
    driver.enable = keys.enable_output.map(|bit| EnableOutput {
        bit,
        active_high: keys.enable_active_high.unwrap_or(false),
    });
    let mut io = QsbIo {
        capture: keys.capture_input.map(|bit| CaptureInput {
            bit,
            falling: keys.capture_falling.unwrap_or(false),
        }),
        ..QsbIo::default()
    };
    for signal in config.signals.iter().filter(|s| s.device == index) {
        io.add(variant, signal.pin, signal.kind);
    }
    driver.io = io;
    driver
}

/// The driver of qsb device `index`.
pub(crate) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    Box::new(QsbDriver::new(driver_config(config, index, device)))
}

/// A number as the config would write it (no trailing `.0` noise, full precision).
fn number(value: f64) -> String {
    format!("{value}")
}

/// The machine parameters of qsb device `index`, as the driver uses them.
pub(crate) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let driver = driver_config(config, index, device);
    let mut row = |key: &str, value: String| {
        out.push(ParamRow {
            owner: Owner::Device(index),
            key: key.to_owned(),
            value,
        });
    };
    row("counts_per_step", number(driver.counts_per_step));
    if let Some((axis, spec)) = axis_of(config, index) {
        row("home_direction", spec.home.direction.id().to_owned());
        row(
            "home_max_travel",
            format!("{} {}", number(spec.home.max_travel), axis.unit),
        );
        row(
            "home_offset",
            format!("{} {}", number(spec.home.position), axis.unit),
        );
    }
    let polarity = if driver.invert_index {
        "inverted"
    } else {
        "normal"
    };
    row("index_polarity", polarity.to_owned());
    let ticks = driver.interval().0;
    let ms = f64::from(ticks) * TICK.as_secs_f64() * 1000.0;
    let plural = if ticks == 1 { "" } else { "s" };
    row(
        "stream_interval_ms",
        format!("{} ms ({ticks} tick{plural})", number(ms)),
    );
    row(
        "host_latency_ms",
        format!("{} ms", number(driver.latency.as_secs_f64() * 1000.0)),
    );
    let enable = driver.enable;
    row(
        "enable_output",
        enable.map_or_else(|| "none".to_owned(), |e| e.bit.to_string()),
    );
    let active = enable.map_or_else(
        || keys_of(device).enable_active_high.unwrap_or(false),
        |e| e.active_high,
    );
    row(
        "enable_active",
        if active { "high" } else { "low" }.to_owned(),
    );
    let mode = match driver.input_mode {
        EncoderMode::Quadrature => "quadrature",
        EncoderMode::Pwm => "pwm",
        EncoderMode::Analog => "analog",
    };
    row("input_mode", mode.to_owned());
    let capture = driver.io.capture;
    row(
        "capture_input",
        capture.map_or_else(|| "none".to_owned(), |c| c.bit.to_string()),
    );
    let falling = capture.map_or_else(
        || keys_of(device).capture_falling.unwrap_or(false),
        |c| c.falling,
    );
    row(
        "capture_edge",
        if falling { "falling" } else { "rising" }.to_owned(),
    );
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use motion_drivers::{Pin, qsb::EnableOutput};

    use super::*;

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
