//! Machine keys: what depends on the motor, the mechanics and the wiring of one board
//! model. One module per model validates its own keys into their typed struct (defined with
//! the drivers' neutral spec, `motion_drivers::spec`); this module dispatches, and refuses a
//! key on a model that does not have it, naming the models where it is valid.

pub mod qq2drv;
pub mod qsb;
pub mod spimotor;
pub mod tmcpack;

use motion_drivers::Model;
pub use motion_drivers::spec::{AxisMachine, DeviceMachine};
use toml::Spanned;

use super::{TableSpan, Validator};
use crate::config::ServerConfig;
use crate::config::raw::{RawAxis, RawConfig, RawDevice};

/// Where a device table is, for the board modules' issues.
#[derive(Debug, Clone)]
pub(in crate::config) struct DeviceContext {
    /// Index of the `[[device]]` table.
    pub index: usize,
}

impl DeviceContext {
    /// `device[i].key`.
    pub fn key(&self, key: &str) -> String {
        format!("device[{}].{key}", self.index)
    }
}

/// Where an axis table is and what the board modules need to convert units.
#[derive(Debug, Clone)]
pub(in crate::config) struct AxisContext<'a> {
    /// Index of the `[[axis]]` table.
    pub index: usize,
    /// Span of the whole table.
    pub table: TableSpan,
    /// The axis's `counts_per_unit`, when valid.
    pub counts_per_unit: Option<f64>,
    /// The axis's soft limits, when valid.
    pub min: Option<f64>,
    /// The axis's soft limits, when valid.
    pub max: Option<f64>,
    /// The axis's unit, when valid.
    pub unit: Option<&'a str>,
}

impl AxisContext<'_> {
    /// `axis[i].key`.
    pub fn key(&self, key: &str) -> String {
        format!("axis[{}].{key}", self.index)
    }
}

/// Device keys that only some models have: (key, span if set, models).
fn device_key_models(raw: &RawDevice) -> Vec<(&'static str, Option<TableSpan>, &'static [Model])> {
    const QSB: &[Model] = &[Model::QSB];
    const TMC: &[Model] = &[Model::TMCPACK];
    const SPI: &[Model] = &[Model::SPIMOTOR];
    fn at<T>(value: &Option<Spanned<T>>) -> Option<TableSpan> {
        value.as_ref().map(Spanned::span)
    }
    vec![
        (
            "address",
            at(&raw.address),
            &[Model::TMCPACK, Model::SPIMOTOR],
        ),
        ("variant", at(&raw.variant), &[Model::TMCPACK, Model::QSB]),
        ("drive", at(&raw.drive), SPI),
        ("counts_per_step", at(&raw.counts_per_step), QSB),
        ("home_direction", at(&raw.home_direction), QSB),
        ("home_max_travel", at(&raw.home_max_travel), QSB),
        ("home_offset", at(&raw.home_offset), QSB),
        ("index_polarity", at(&raw.index_polarity), QSB),
        ("stream_interval_ms", at(&raw.stream_interval_ms), QSB),
        ("host_latency_ms", at(&raw.host_latency_ms), QSB),
        ("enable_output", at(&raw.enable_output), QSB),
        ("enable_active", at(&raw.enable_active), QSB),
        ("input_mode", at(&raw.input_mode), QSB),
        ("capture_input", at(&raw.capture_input), QSB),
        ("capture_edge", at(&raw.capture_edge), QSB),
        ("reply_address", at(&raw.reply_address), TMC),
        ("switchover_ms", at(&raw.switchover_ms), TMC),
        ("packet_timeout_ms", at(&raw.packet_timeout_ms), TMC),
        ("ready_output", at(&raw.ready_output), TMC),
        ("intensity", at(&raw.intensity), SPI),
        ("coils", at(&raw.coils), SPI),
    ]
}

/// Axis keys that only some models have.
fn axis_key_models(raw: &RawAxis) -> Vec<(&'static str, Option<TableSpan>, &'static [Model])> {
    const TMC: &[Model] = &[Model::TMCPACK];
    const QQ: &[Model] = &[Model::QQ2DRV];
    fn at<T>(value: &Option<Spanned<T>>) -> Option<TableSpan> {
        value.as_ref().map(Spanned::span)
    }
    let home = raw.home.as_ref().map(Spanned::get_ref);
    let home_at = |value: Option<TableSpan>| value;
    vec![
        (
            "home",
            at(&raw.home),
            &[Model::QQ2DRV, Model::TMCPACK, Model::QSB],
        ),
        ("home.input", home_at(home.and_then(|h| at(&h.input))), QQ),
        (
            "home.active_high",
            home_at(home.and_then(|h| at(&h.active_high))),
            QQ,
        ),
        (
            "home.positive_end",
            home_at(home.and_then(|h| at(&h.positive_end))),
            QQ,
        ),
        (
            "home.spacing",
            home_at(home.and_then(|h| at(&h.spacing))),
            QQ,
        ),
        ("current", at(&raw.current), TMC),
        ("reference", at(&raw.reference), TMC),
        ("rotary", at(&raw.rotary), TMC),
        ("revolution", at(&raw.revolution), TMC),
        ("analog_stop", at(&raw.analog_stop), TMC),
        ("pid_position", at(&raw.pid_position), QQ),
        ("pid_velocity", at(&raw.pid_velocity), QQ),
        ("power_limit", at(&raw.power_limit), QQ),
    ]
}

fn model_list(models: &[Model]) -> String {
    models.iter().map(|m| m.id()).collect::<Vec<_>>().join(", ")
}

impl Validator<'_, '_> {
    /// Refuses every key of `raw` that `model` does not have; `false` when one was found.
    pub(super) fn device_keys_fit(&mut self, index: usize, raw: &RawDevice, model: Model) -> bool {
        let mut fit = true;
        for (key, span, models) in device_key_models(raw) {
            if let Some(span) = span
                && !models.contains(&model)
            {
                fit = false;
                self.issue(
                    span,
                    &format!("device[{index}].{key}"),
                    format!(
                        "`{key}` is not a key of {model} devices; it is valid on: {}",
                        model_list(models)
                    ),
                );
            }
        }
        fit
    }

    /// Refuses every key of axis `raw` that its device's `model` does not have.
    pub(super) fn axis_keys_fit(&mut self, index: usize, raw: &RawAxis, model: Model) -> bool {
        let mut fit = true;
        for (key, span, models) in axis_key_models(raw) {
            if let Some(span) = span
                && !models.contains(&model)
            {
                fit = false;
                let why = if key == "home" && model == Model::SPIMOTOR {
                    "; an SPI_motor has no reference input, so its axes cannot home"
                } else {
                    ""
                };
                self.issue(
                    span,
                    &format!("axis[{index}].{key}"),
                    format!(
                        "`{key}` is not a key of {model} axes; it is valid on: {}{why}",
                        model_list(models)
                    ),
                );
            }
        }
        fit
    }

    /// The model's device keys.
    pub(super) fn device_machine(
        &mut self,
        ctx: &DeviceContext,
        model: Model,
        raw: &RawDevice,
    ) -> Option<DeviceMachine> {
        Some(match model {
            Model::TMCPACK => DeviceMachine::new(tmcpack::device_keys(self, ctx, raw)?),
            Model::SPIMOTOR => DeviceMachine::new(spimotor::device_keys(self, ctx, raw)?),
            Model::QSB => DeviceMachine::new(qsb::device_keys(self, ctx, raw)?),
            _ => DeviceMachine::PLAIN,
        })
    }

    /// The model's axis keys.
    pub(super) fn axis_machine(
        &mut self,
        ctx: &AxisContext<'_>,
        model: Model,
        raw: &RawAxis,
    ) -> Option<AxisMachine> {
        Some(match model {
            Model::QQ2DRV => AxisMachine::new(qq2drv::axis_keys(self, ctx, raw)?),
            Model::TMCPACK => AxisMachine::new(tmcpack::axis_keys(self, ctx, raw)?),
            _ => AxisMachine::PLAIN,
        })
    }

    /// Checks across tables (keys that must agree between axes of one device, addresses
    /// against other devices), after everything else was validated.
    pub(super) fn machine_cross_checks(&mut self, config: &ServerConfig, raw: &RawConfig) {
        tmcpack::cross_check(self, config, raw);
        qq2drv::cross_check(self, config, raw);
        qsb::cross_check(self, config, raw);
        spimotor::cross_check(self, config, raw);
    }
}
