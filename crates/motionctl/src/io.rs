//! `motionctl io list|get|set|compare|events|watch`, and the signal views shared with
//! `list`, `status`, `watch` and `record`.

use core::time::Duration;

use anyhow::Context as _;
use motion_client::ipc::{
    MotionFrame, ServerInfo, SignalFlags, SignalInfo, SignalInfoFlags, SignalKind, SignalState,
};
use motion_client::{Client, signal_value_text};
use motion_wire::json::{self, signal_kind_name};
use ratatui::layout::{Constraint, Layout};
use ratatui::style::{Modifier, Style};
use ratatui::widgets::{Cell, Paragraph, Row, Table};
use serde_json::{Value, json};

use crate::Service;
use crate::cli::IoCommand;
use crate::terminal::{print_until_terminated, redraw_until_quit};

/// Names of the set flags, in bit order.
pub fn signal_flag_names(flags: SignalFlags) -> Vec<&'static str> {
    flags.names()
}

fn is_digital(info: &SignalInfo) -> bool {
    matches!(
        info.kind(),
        Ok(SignalKind::DigitalIn | SignalKind::DigitalOut)
    )
}

/// Whether the signal has events (a capture, a trigger).
fn has_events(info: &SignalInfo) -> bool {
    matches!(info.kind(), Ok(SignalKind::Capture | SignalKind::Trigger))
}

/// A capture's or a trigger's events in words: "event 4 at tick 1234", "no event".
fn events_text(info: &SignalInfo, state: &SignalState) -> Option<String> {
    has_events(info).then(|| {
        if state.sequence == 0 && state.event_tick == 0 {
            "no event".to_owned()
        } else {
            format!("event {} at tick {}", state.sequence, state.event_tick)
        }
    })
}

/// The flags of a signal's state, with its events.
fn flags_text(info: &SignalInfo, state: &SignalState) -> String {
    let mut words: Vec<String> = signal_flag_names(state.flags())
        .into_iter()
        .map(str::to_owned)
        .collect();
    words.extend(events_text(info, state));
    words.join(",")
}

/// The safe state of an output: "on", "off", or `None`.
fn safe_name(info: &SignalInfo) -> Option<&'static str> {
    let flags = info.flags();
    flags.contains(SignalInfoFlags::HAS_SAFE_STATE).then(|| {
        if flags.contains(SignalInfoFlags::SAFE_ON) {
            "on"
        } else {
            "off"
        }
    })
}

/// A signal's static description as JSON.
pub fn signal_info_json(index: usize, info: &SignalInfo) -> Value {
    json!({
        "index": index,
        "name": info.name(),
        "device": info.device(),
        "device_index": info.device_index,
        "pin": info.pin(),
        "kind": signal_kind_name(info),
        "unit": info.unit(),
        "invert": info.flags().contains(SignalInfoFlags::INVERT),
        "safe": safe_name(info),
        "scale": info.scale,
        "offset": info.offset,
        "full_scale": info.full_scale,
    })
}

/// Every signal's state in `frame` as JSON, in config order ([`signal_state_json`]).
pub fn signal_states_json(info: &ServerInfo, frame: &MotionFrame) -> Vec<Value> {
    info.signals()
        .iter()
        .zip(frame.signals())
        .enumerate()
        .map(|(index, (signal, state))| signal_state_json(index, signal, state, frame.tick))
        .collect()
}

/// A signal's state in a frame as JSON (with the description's name, device, pin, kind and
/// unit): the bridge's view of it (`motion_wire::json`) and its value as text.
pub fn signal_state_json(index: usize, info: &SignalInfo, state: &SignalState, tick: u64) -> Value {
    let mut value = json::signal_state(index, info, state, tick);
    value["text"] = json!(signal_value_text(info, state.value));
    value
}

/// The signal table: with a frame, values and flags; without, the configuration.
pub fn signals_text(info: &ServerInfo, frame: Option<&MotionFrame>) -> Vec<String> {
    if info.signals().is_empty() {
        return Vec::new();
    }
    let mut lines = vec![format!(
        "{:<16} {:<12} {:<10} {:<12} {:<6} {:>12}  {}",
        "signal",
        "device",
        "pin",
        "kind",
        "unit",
        if frame.is_some() { "value" } else { "safe" },
        if frame.is_some() { "flags" } else { "invert" }
    )];
    for (index, signal) in info.signals().iter().enumerate() {
        let (value, flags) = match frame {
            Some(frame) => {
                let state = frame.signals().get(index).copied().unwrap_or_default();
                let value = if is_digital(signal) {
                    signal_value_text(signal, state.value)
                } else {
                    format!("{:.4}", state.value)
                };
                (value, flags_text(signal, &state))
            }
            None => (
                safe_name(signal).unwrap_or("-").to_owned(),
                if signal.flags().contains(SignalInfoFlags::INVERT) {
                    "yes"
                } else {
                    "no"
                }
                .to_owned(),
            ),
        };
        lines.push(format!(
            "{:<16} {:<12} {:<10} {:<12} {:<6} {:>12}  {}",
            signal.name(),
            signal.device(),
            signal.pin(),
            signal_kind_name(signal),
            signal.unit(),
            value,
            flags
        ));
    }
    lines
}

/// `motionctl io …`.
pub fn run(client: &Client<Service>, command: &IoCommand) -> anyhow::Result<()> {
    match command {
        IoCommand::List { json } => list(client, *json),
        IoCommand::Get { name, json } => get(client, name, *json),
        IoCommand::Set { name, value } => {
            let signal = client.signal(name)?;
            let word = if *value { "on" } else { "off" };
            signal
                .set(*value)
                .with_context(|| format!("set {name} {word}"))?;
            out!("{name}: set {word}");
            Ok(())
        }
        IoCommand::Compare { name, position } => {
            let signal = client.signal(name)?;
            let unit = signal.info().unit().to_owned();
            signal
                .set_value(*position)
                .with_context(|| format!("compare {name} at {position} {unit}"))?;
            out!("{name}: fires at {position} {unit}");
            Ok(())
        }
        IoCommand::Events {
            name,
            count,
            timeout,
            json,
        } => events(client, name, *count, *timeout, *json),
        IoCommand::Watch { json, interval } => watch(client, *json, *interval),
    }
}

/// `io events`: each capture or pulse as it comes.
fn events(
    client: &Client<Service>,
    name: &str,
    count: Option<u32>,
    timeout: Option<Duration>,
    json: bool,
) -> anyhow::Result<()> {
    let signal = client.signal(name)?;
    let info = signal.info();
    if !has_events(&info) {
        anyhow::bail!(
            "{name} is a {} signal: only capture and trigger signals have events",
            signal_kind_name(&info)
        );
    }
    let mut seen = signal.sequence()?;
    let mut printed = 0u32;
    // Without --timeout: until Ctrl-C (a wait that long never ends by itself).
    let wait = timeout.unwrap_or(Duration::from_secs(365 * 24 * 3600));
    while count.is_none_or(|count| printed < count) {
        let event = match signal.wait_event(seen, wait) {
            Ok(event) => event,
            Err(motion_client::ClientError::Interrupted) => return Ok(()),
            Err(error) => return Err(error.into()),
        };
        seen = event.sequence;
        printed += 1;
        if json {
            let value = json!({
                "signal": name,
                "value": event.value,
                "raw": event.raw,
                "unit": info.unit(),
                "sequence": event.sequence,
                "tick": event.tick,
                "missed": event.missed,
            });
            out!("{value}");
        } else {
            let missed = match event.missed {
                0 => String::new(),
                n => format!(" ({n} missed)"),
            };
            out!(
                "{name}: {} at tick {}, event {}{missed}",
                signal_value_text(&info, event.value),
                event.tick,
                event.sequence
            );
        }
    }
    Ok(())
}

fn all_json(info: &ServerInfo, frame: &MotionFrame) -> Vec<Value> {
    info.signals()
        .iter()
        .enumerate()
        .map(|(index, signal)| {
            let state = frame.signals().get(index).copied().unwrap_or_default();
            let mut value = signal_state_json(index, signal, &state, frame.tick);
            value["invert"] = json!(signal.flags().contains(SignalInfoFlags::INVERT));
            value["safe"] = json!(safe_name(signal));
            value
        })
        .collect()
}

fn list(client: &Client<Service>, json: bool) -> anyhow::Result<()> {
    let info = client.info()?;
    let frame = client.latest()?;
    if json {
        let value = json!({ "tick": frame.tick, "signals": all_json(&info, &frame) });
        out!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    if info.signals().is_empty() {
        out!("no signals configured ([[signal]] tables in the server's config)");
    }
    for line in signals_text(&info, Some(&frame)) {
        out!("{line}");
    }
    Ok(())
}

fn get(client: &Client<Service>, name: &str, json: bool) -> anyhow::Result<()> {
    let signal = client.signal(name)?;
    let info = signal.info();
    let frame = client.latest()?;
    let index = signal.index() as usize;
    let state = frame.signals().get(index).copied().unwrap_or_default();
    if json {
        let value = signal_state_json(index, &info, &state, frame.tick);
        out!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    let flags = flags_text(&info, &state);
    let flags = if flags.is_empty() {
        String::new()
    } else {
        format!(" [{flags}]")
    };
    out!("{name}: {}{flags}", signal_value_text(&info, state.value));
    Ok(())
}

fn watch(client: &Client<Service>, json: bool, interval: Duration) -> anyhow::Result<()> {
    if json {
        return print_until_terminated(client, interval, |info, frame| {
            json!({ "tick": frame.tick, "signals": all_json(info, frame) }).to_string()
        });
    }
    redraw_until_quit(client, "io watch", interval, |screen| {
        let frame = client.latest()?;
        let info = client.info()?;
        screen.terminal().draw(|ui| {
            let [head, table, foot] = Layout::vertical([
                Constraint::Length(1),
                Constraint::Min(3),
                Constraint::Length(1),
            ])
            .areas(ui.area());
            ui.render_widget(
                Paragraph::new(format!(
                    "signals of motiond \"{}\"  tick {}",
                    info.name(),
                    frame.tick
                ))
                .style(Style::default().add_modifier(Modifier::BOLD)),
                head,
            );
            ui.render_widget(signal_table(&info, &frame), table);
            ui.render_widget(Paragraph::new("q or Ctrl-C quits"), foot);
        })?;
        Ok(())
    })
}

/// The live signal table of `io watch` and `watch`.
pub fn signal_table<'a>(info: &'a ServerInfo, frame: &MotionFrame) -> Table<'a> {
    let rows = info.signals().iter().enumerate().map(|(index, signal)| {
        let state = frame.signals().get(index).copied().unwrap_or_default();
        let value = if is_digital(signal) {
            signal_value_text(signal, state.value)
        } else {
            format!("{:.4}", state.value)
        };
        Row::new(vec![
            Cell::from(signal.name().to_owned()),
            Cell::from(value),
            Cell::from(signal.unit().to_owned()),
            Cell::from(signal_kind_name(signal)),
            Cell::from(format!("{}/{}", signal.device(), signal.pin())),
            Cell::from(flags_text(signal, &state)),
        ])
    });
    let widths = [
        Constraint::Length(16),
        Constraint::Length(12),
        Constraint::Length(6),
        Constraint::Length(12),
        Constraint::Length(20),
        Constraint::Min(10),
    ];
    let header = Row::new(["signal", "value", "unit", "kind", "device/pin", "flags"])
        .style(Style::default().add_modifier(Modifier::BOLD));
    Table::new(rows, widths).header(header)
}
