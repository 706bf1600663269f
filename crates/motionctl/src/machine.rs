//! The machine parameters in effect (the server's params service), grouped per device and
//! axis for `list`.

use motion_client::ipc::{MachineParam, ParamOwner, ServerInfo};
use motion_client::{ClientError, Params};
use serde_json::{Value, json};

use crate::Service;

/// The parameters as read, or why they could not be.
#[derive(Debug)]
pub struct ParamTable {
    params: Option<Params<Service>>,
    error: Option<String>,
}

impl ParamTable {
    /// From the result of `Client::machine_params`.
    pub fn new(result: Result<Params<Service>, ClientError>) -> Self {
        match result {
            Ok(params) => Self {
                params: Some(params),
                error: None,
            },
            Err(error) => Self {
                params: None,
                error: Some(error.to_string()),
            },
        }
    }

    /// Why there are none, if there are none.
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Whether the server had more than fit.
    pub fn truncated(&self) -> bool {
        self.params.as_ref().is_some_and(|p| p.truncated != 0)
    }

    /// The parameters of `owner` number `index`, in the server's order.
    pub fn rows(&self, owner: ParamOwner, index: usize) -> Vec<&MachineParam> {
        let Some(params) = &self.params else {
            return Vec::new();
        };
        params
            .entries()
            .iter()
            .filter(|p| p.owner() == Ok(owner) && usize::from(p.owner_index) == index)
            .collect()
    }

    fn json(&self, owner: ParamOwner, index: usize) -> Value {
        if self.params.is_none() {
            return Value::Null;
        }
        Value::Array(
            self.rows(owner, index)
                .into_iter()
                .map(|p| {
                    json!({
                        "key": p.key(),
                        "value": p.value(),
                        "from_config": p.from_config != 0,
                    })
                })
                .collect(),
        )
    }

    /// Device `index`'s parameters as a JSON array (`null` when unavailable).
    pub fn device_json(&self, index: usize) -> Value {
        self.json(ParamOwner::Device, index)
    }

    /// Axis `index`'s parameters as a JSON array (`null` when unavailable).
    pub fn axis_json(&self, index: usize) -> Value {
        self.json(ParamOwner::Axis, index)
    }
}

/// The text section of `list`: every device's then every axis's parameters, each marked
/// `config` (the config file set it) or `default`.
pub fn params_lines(info: &ServerInfo, table: &ParamTable) -> Vec<String> {
    if let Some(error) = table.error() {
        return vec![format!("machine parameters: not available ({error})")];
    }
    let mut lines = vec![
        "machine parameters (source: config = set in the config file, default = not set):"
            .to_owned(),
    ];
    let all = || {
        (0..info.devices().len())
            .flat_map(|index| table.rows(ParamOwner::Device, index))
            .chain((0..info.axes().len()).flat_map(|index| table.rows(ParamOwner::Axis, index)))
    };
    let key_width = all()
        .map(|row| row.key().chars().count())
        .max()
        .unwrap_or(0);
    let value_width = all()
        .map(|row| row.value().chars().count())
        .max()
        .unwrap_or(0);
    let mut section = |title: String, rows: Vec<&MachineParam>| {
        if rows.is_empty() {
            return;
        }
        lines.push(title);
        for row in rows {
            let source = if row.from_config != 0 {
                "config"
            } else {
                "default"
            };
            lines.push(format!(
                "  {:<key_width$}  {:<value_width$}  {source}",
                row.key(),
                row.value()
            ));
        }
    };
    for (index, device) in info.devices().iter().enumerate() {
        section(
            format!("device {}:", device.name()),
            table.rows(ParamOwner::Device, index),
        );
    }
    for (index, axis) in info.axes().iter().enumerate() {
        section(
            format!("axis {}:", axis.name()),
            table.rows(ParamOwner::Axis, index),
        );
    }
    if table.truncated() {
        lines.push("(more parameters than the params service holds: the list is cut)".to_owned());
    }
    lines
}
