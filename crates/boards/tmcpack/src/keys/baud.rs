//! The device key `baud` (docs/keys/tmcpack.md): the rate a pack is switched to at
//! start-up with `$40` (manual 8.6 "Adjust RS 232 / RS 485 Baud rate"), the link
//! following (driver module `rate`). Unset (the default), the pack stays at the link's
//! rate, 19200 from the factory.
//!
//! The manual gives no list of rates, only the divisor (`20 MHz / (16 · baud)`) and the
//! factory 19200: a rate is taken when it is a standard rate the divisor reaches within
//! 2.5 % ([`tmcpack::convert::listed_bauds`]). On a shared RS-485 pair every device must be a
//! pack with the same `baud` (all of them are switched; a board that stayed at the link's
//! rate would hear garbage).

use motion_board::keys::{DeviceContext, Int, KeyIssues, Spanned};
use motion_board::machine::MachineView;
use motion_drivers::Model;
use tmcpack::convert::{baud_divisor, baud_of_divisor, listed_baud_divisor, listed_bauds};

use super::raw::RawDevice;
use crate::TmcpackDeviceKeys;

/// The rates `baud` takes, for messages.
pub(crate) fn listed() -> String {
    listed_bauds()
        .map(|b| b.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// `baud`: a rate of [`listed_bauds`]; an issue naming them for any other.
pub(crate) fn baud(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    value: &Spanned<Int>,
) -> Option<u32> {
    let raw = value.get_ref().get();
    let rate = u32::try_from(raw).ok();
    if let Some(rate) = rate.filter(|&r| listed_baud_divisor(r).is_ok()) {
        return Some(rate);
    }
    let near = rate
        .and_then(|r| baud_divisor(r).ok())
        .map(|d| format!(" (its divisor {d} gives {:.0} baud)", baud_of_divisor(d)))
        .unwrap_or_default();
    v.issue(
        value.span(),
        &ctx.key("baud"),
        format!(
            "{raw} is not a rate the pack can be set to{near}; allowed: {} (manual 8.6 $40: \
             \"baud rate divisor=20MHz/(16*baud rate)\", within 2.5 % of the rate)",
            listed()
        ),
    );
    None
}

/// Every device on a link with a pack's `baud` is a pack with the same `baud`.
pub(crate) fn one_rate_per_link(v: &mut dyn KeyIssues, machine: &MachineView<'_>) {
    for (l, link) in machine.links.iter().enumerate() {
        let on: Vec<_> = machine.devices.iter().filter(|d| d.link == l).collect();
        let rate_of = |d: &&motion_board::machine::DeviceView<'_>| {
            (d.model == Model::TMCPACK)
                .then(|| d.machine.get::<TmcpackDeviceKeys>().and_then(|k| k.baud))
                .flatten()
        };
        let Some(first) = on.iter().find(|d| rate_of(d).is_some()) else {
            continue;
        };
        let rate = rate_of(first);
        for device in &on {
            if device.model == Model::TMCPACK && rate_of(device) == rate {
                continue;
            }
            let span = device
                .keys
                .parse_quiet::<RawDevice>()
                .and_then(|raw| raw.baud.map(|s| s.span()))
                .unwrap_or_else(|| device.table.clone());
            let what = if device.model == Model::TMCPACK {
                match rate_of(device) {
                    Some(other) => format!("baud = {other}"),
                    None => "no baud".to_owned(),
                }
            } else {
                format!(
                    "a {} board, which stays at the link's rate",
                    device.model.id()
                )
            };
            v.issue(
                span,
                &format!("device[{}].baud", device.index),
                format!(
                    "device `{}` on link `{}` has {what}, but `{}` switches the link to {} baud: \
                     every device on one link talks at one rate; give every pack on `{}` the same baud",
                    device.name,
                    link.name,
                    first.name,
                    rate.unwrap_or(0),
                    link.name
                ),
            );
        }
    }
}
