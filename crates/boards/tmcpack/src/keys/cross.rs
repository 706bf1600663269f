//! The checks across tables for tmcpack devices, run after everything else was validated:
//! reply addresses no pack on the link has, CAN identifiers, the shared peak current of a
//! motor pair, TTLOUT1 as the ready output or a signal, packet timeouts that fit a word;
//! and those of the `drive` and `baud` keys.

use motion_board::keys::{KeyIssues, Spanned};
use motion_board::machine::MachineView;
use motion_drivers::{LinkFraming, Model, SignalKind};

use super::raw::{RawAxis, RawDevice};
use crate::driver::word_time;
use crate::{TmcpackAxisKeys, TmcpackDeviceKeys};

/// The reply address the driver uses unless `reply_address` is set.
pub const DEFAULT_REPLY_ADDRESS: u8 = crate::driver::DEFAULT_REPLY_ADDRESS;

/// Checks across tables for tmcpack devices (after everything else was validated).
pub(crate) fn cross_check(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    reply_addresses(v, machine);
    can_ids(v, machine);
    peak_pairs(v, machine);
    ready_output_signals(v, machine);
    packet_timeouts(v, machine);
    super::drive::cross_check(v, machine);
    super::baud::one_rate_per_link(v, machine);
}

/// The device keys of pack `d` (an index into the view's devices).
fn device_keys_of<'m>(machine: &'m MachineView<'_>, d: usize) -> Option<&'m TmcpackDeviceKeys> {
    machine.devices.get(d)?.machine.get::<TmcpackDeviceKeys>()
}

/// The pack executes every word that starts with its address, replies included: no reply
/// address may be the address of a pack on the same link (manual 6.1, 7.2 `$20`
/// "address of the receiver").
fn reply_addresses(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    let packs: Vec<_> = machine.devices_of(Model::TMCPACK).collect();
    for &(a, asking) in &packs {
        let Some(keys) = device_keys_of(machine, a) else {
            continue;
        };
        let reply = keys.reply_address.unwrap_or(DEFAULT_REPLY_ADDRESS);
        for &(_, other) in packs.iter().filter(|(_, d)| d.link == asking.link) {
            if other.address != u32::from(reply) {
                continue;
            }
            let link = machine.links.get(asking.link).map_or("?", |l| l.name);
            let explicit = asking
                .keys
                .parse_quiet::<RawDevice>()
                .and_then(|raw| raw.reply_address.map(|s| s.span()));
            match explicit {
                Some(span) => v.issue(
                    span,
                    &format!("device[{}].reply_address", asking.index),
                    format!("{reply} is the address of pack `{}` on link `{link}`: that pack would take the replies for requests; choose an address no pack on the link has", other.name),
                ),
                None => v.issue(
                    other.address_span.clone().unwrap_or(0..0),
                    &format!("device[{}].address", other.index),
                    format!("{reply} is the reply address pack `{}` uses (reply_address, default {DEFAULT_REPLY_ADDRESS}) on link `{link}`: this pack would take its replies for requests; change this address or set `reply_address` on `{}`", asking.name, asking.name),
                ),
            }
        }
    }
}

/// A pack on a CAN link (manual 6.2): its identifier is its address shifted left by 3,
/// and its answers' the response address shifted the same way — "Take care: According to
/// the CAN standard 0 is no valid address! Address range: $008 to $7F8 (in increments of
/// 8)." — so neither may be 0. `$40` and `$41` set up the RS-232 / RS-485 line, which the
/// driver does not send on CAN: their keys are refused there.
fn can_ids(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (_, device) in machine.devices_of(Model::TMCPACK) {
        let Some(link) = machine
            .links
            .get(device.link)
            .filter(|l| l.framing == LinkFraming::Can)
        else {
            continue;
        };
        let raw = device.keys.parse_quiet::<RawDevice>();
        let range = "Address range: $008 to $7F8 (in increments of 8)";
        if device.address == 0 {
            v.issue(
                device
                    .address_span
                    .clone()
                    .unwrap_or_else(|| device.table.clone()),
                &format!("device[{}].address", device.index),
                format!(
                    "address 0 is CAN identifier $000 on the CAN link `{}`, and \"according to \
                     the CAN standard 0 is no valid address! {range}\" (manual 6.2); set the \
                     pack's rotary switches to 1..=255 (identifier = address × 8) and give that \
                     address",
                    link.name
                ),
            );
        }
        let reply = device_keys_of_view(device).and_then(|k| k.reply_address);
        if reply == Some(0) {
            v.issue(
                raw.as_ref()
                    .and_then(|r| r.reply_address.as_ref().map(Spanned::span))
                    .unwrap_or_else(|| device.table.clone()),
                &format!("device[{}].reply_address", device.index),
                format!(
                    "reply address 0 would have the pack answer with CAN identifier $000 on the \
                     CAN link `{}` (\"For responding the address is shifted to the left by 3 \
                     bits\"), which is no valid identifier ({range}); choose 1..=255 that no \
                     pack on the link has (default {DEFAULT_REPLY_ADDRESS}, identifier ${:03X})",
                    link.name,
                    u16::from(DEFAULT_REPLY_ADDRESS) << 3
                ),
            );
        }
        let serial_keys = raw.as_ref().map(|r| {
            [
                (
                    "switchover_ms",
                    r.switchover_ms.as_ref().map(Spanned::span),
                    "$40",
                ),
                (
                    "packet_timeout_ms",
                    r.packet_timeout_ms.as_ref().map(Spanned::span),
                    "$41",
                ),
            ]
        });
        for (key, span, command) in serial_keys.into_iter().flatten() {
            if let Some(span) = span {
                v.issue(
                    span,
                    &format!("device[{}].{key}", device.index),
                    format!(
                        "{key} sets the pack's RS-232 / RS-485 line ({command}), and link `{}` is \
                         a CAN link: remove it (on CAN a telegram arrives whole, and the pack \
                         needs no line turn-around)",
                        link.name
                    ),
                );
            }
        }
    }
}

/// The tmcpack device keys of a device view.
fn device_keys_of_view<'m>(
    device: &'m motion_board::machine::DeviceView<'_>,
) -> Option<&'m TmcpackDeviceKeys> {
    device.machine.get::<TmcpackDeviceKeys>()
}

/// $10 "settings are done for pairs of motors, i.e. each two motors 0 + 1, 2 + 3
/// respectively 4 + 5 have the same peak current".
fn peak_pairs(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (i, axis) in machine.axes.iter().enumerate() {
        let Some(keys) = axis.machine.get::<TmcpackAxisKeys>() else {
            continue;
        };
        let partner = axis.channel ^ 1;
        let Some((j, other)) = machine
            .axes
            .iter()
            .enumerate()
            .find(|(_, o)| o.device == axis.device && o.channel == partner)
        else {
            continue;
        };
        let other_peak = other
            .machine
            .get::<TmcpackAxisKeys>()
            .and_then(|k| k.current.peak);
        let span = axis
            .keys
            .parse_quiet::<RawAxis>()
            .and_then(|raw| raw.current)
            .and_then(|c| c.into_inner().peak)
            .map(|peak| peak.span());
        let (Some(mine), Some(span)) = (keys.current.peak, span) else {
            continue;
        };
        let pair = format!("motors {} and {}", axis.channel & !1, axis.channel | 1);
        let key = format!("axis[{}].current.peak", axis.index);
        match other_peak {
            Some(theirs) if theirs != mine && j < i => v.issue(
                span,
                &key,
                format!("{mine} differs from axis `{}` ({theirs}): {pair} share one peak current (manual 8.3 $10: \"settings are done for pairs of motors\"); give both the same value", other.name),
            ),
            None => v.warn(
                span,
                &key,
                format!("{pair} share one peak current (manual 8.3 $10): {mine} % applies to axis `{}` too", other.name),
            ),
            _ => {}
        }
    }
}

/// TTLOUT1 is either the ready output or a plain output.
fn ready_output_signals(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for signal in &machine.signals {
        let ready = device_keys_of(machine, signal.device).and_then(|k| k.ready_output);
        if ready.is_none() || signal.pin_name != "ttlout1" || signal.kind != SignalKind::DigitalOut
        {
            continue;
        }
        let device = machine.devices.get(signal.device).map_or("?", |d| d.name);
        v.issue(
            signal.pin_span.clone(),
            &format!("signal[{}].pin", signal.index),
            format!("TTLOUT1 of device `{device}` is its ready output (ready_output, manual 8.5 $32 P3); it cannot also be a digital-out signal — remove ready_output or use ttlio1"),
        );
    }
}

/// $41: "The command word always has to be completely transmitted during a parameterized
/// timeout": a timeout shorter than one word at the link's rate would abort every request.
fn packet_timeouts(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (d, device) in machine.devices.iter().enumerate() {
        let Some(ms) = device_keys_of(machine, d).and_then(|k| k.packet_timeout_ms) else {
            continue;
        };
        let Some(baud) = machine
            .links
            .get(device.link)
            .filter(|l| l.framing == LinkFraming::Bytes)
            .and_then(|l| l.line_rate)
        else {
            continue;
        };
        let word = word_time(baud);
        if u128::from(ms) * 1000 < word.as_micros() {
            let span = device
                .keys
                .parse_quiet::<RawDevice>()
                .and_then(|raw| raw.packet_timeout_ms.map(|s| s.span()))
                .unwrap_or(0..0);
            v.issue(
                span,
                &format!("device[{}].packet_timeout_ms", device.index),
                format!("{ms} ms is shorter than one 9-byte word at {baud} baud ({:.1} ms): the pack would abort every request", word.as_secs_f64() * 1000.0),
            );
        }
    }
}
