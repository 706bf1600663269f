//! `motionctl commission DEVICE --address N | --baud N | --factory-reset --yes`: a change of
//! a board's own settings through the running server (motion-client's `commission`
//! module), then the line to put in the config.

use core::time::Duration;

use anyhow::Context as _;
use motion_client::ipc::{CommissionWhat, Reason};
use motion_client::{Client, ClientError, Commissioned};

use crate::Service;
use crate::group::BadArguments;

/// What to change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Change {
    /// What.
    pub what: CommissionWhat,
    /// The new address or rate (0 for a factory reset).
    pub value: u32,
}

/// One `commission` command.
#[derive(Debug)]
pub struct Request<'a> {
    /// The device's name.
    pub device: &'a str,
    /// What to change.
    pub change: Change,
    /// How long to wait for the board to answer again.
    pub timeout: Duration,
    /// Print JSON.
    pub json: bool,
}

/// The change the options ask for (clap makes sure exactly one is given).
pub fn change(
    address: Option<u32>,
    baud: Option<u32>,
    factory_reset: bool,
    yes: bool,
) -> anyhow::Result<Change> {
    if factory_reset && !yes {
        return Err(BadArguments(
            "--factory-reset replaces every parameter of the pack by its factory default \
             (manual $CC \"Complete Hardware Reset\": its address from the rotary switches, \
             19200 baud); give --yes to confirm"
                .to_owned(),
        )
        .into());
    }
    Ok(match (address, baud) {
        (Some(value), _) => Change {
            what: CommissionWhat::Address,
            value,
        },
        (None, Some(value)) => Change {
            what: CommissionWhat::Baud,
            value,
        },
        (None, None) => Change {
            what: CommissionWhat::FactoryReset,
            value: 0,
        },
    })
}

/// The rates a Trinamic pack's `$40` takes, for messages.
fn pack_rates() -> String {
    tmcpack::convert::listed_bauds()
        .map(|b| b.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Runs one `commission` command.
pub fn run(client: &Client<Service>, request: &Request<'_>) -> anyhow::Result<()> {
    let Request {
        device,
        change,
        timeout,
        json,
    } = *request;
    let index = client.device_index(device)?;
    let info = client.info()?;
    let entry = info
        .devices()
        .get(index)
        .copied()
        .unwrap_or(motion_client::ipc::DeviceInfo::EMPTY);
    let model = entry.model_name();
    let old_address = entry.address;
    let link = motion_client::ipc::read_text(&entry.link).to_owned();
    // The other devices on the same link (they share its rate).
    let others: Vec<String> = info
        .devices()
        .iter()
        .enumerate()
        .filter(|(i, d)| *i != index && motion_client::ipc::read_text(&d.link) == link)
        .map(|(_, d)| d.name().to_owned())
        .collect();
    drop(info);
    if change.what == CommissionWhat::Baud && model == "tmcpack" {
        // Said here in the manual's terms; the server refuses it the same way.
        if tmcpack::convert::listed_baud_divisor(change.value).is_err() {
            return Err(BadArguments(format!(
                "--baud {}: not a rate the pack can be set to; allowed: {} (manual 8.6 $40 \
                 divisor 20 MHz / (16 · baud), within 2.5 %)",
                change.value,
                pack_rates()
            ))
            .into());
        }
    }
    let claims = client
        .claim_device(device)
        .with_context(|| format!("claim every axis and signal of device `{device}`"))?;
    let accepted = match client.commission(device, change.what, change.value) {
        Ok(accepted) => accepted,
        Err(ClientError::Refused {
            reason: Reason::OutOfRange,
            ..
        }) => {
            let why = match change.what {
                CommissionWhat::Address => format!(
                    "address {} is taken by another device on link `{link}`, or the board does \
                     not take it (a Trinamic pack: 0..=255 but not its reply address; an \
                     SPI_motor: an even byte)",
                    change.value
                ),
                CommissionWhat::Baud => format!(
                    "{} baud is not a rate the board takes (a Trinamic pack: {})",
                    change.value,
                    pack_rates()
                ),
                CommissionWhat::FactoryReset => "the board refused the reset".to_owned(),
            };
            return Err(anyhow::Error::new(ClientError::Refused {
                kind: "commission",
                target: format!("device {device}"),
                reason: Reason::OutOfRange,
                tick: 0,
                detail: Some(why),
            }));
        }
        // Another device on the link in use (a line rate): the client names it.
        Err(
            error @ ClientError::Refused {
                reason: Reason::GroupBusy | Reason::ClaimedByOther,
                detail: Some(_),
                ..
            },
        ) => return Err(error.into()),
        Err(ClientError::Refused {
            reason: Reason::GroupBusy,
            ..
        }) => {
            return Err(anyhow::Error::new(ClientError::Refused {
                kind: "commission",
                target: format!("device {device}"),
                reason: Reason::GroupBusy,
                tick: 0,
                detail: Some(format!(
                    "an axis of device `{device}` moves: stop it (`motionctl stop`) and \
                     commission once it rests"
                )),
            }));
        }
        Err(ClientError::Refused {
            reason: Reason::EstopLatched,
            ..
        }) => {
            return Err(anyhow::Error::new(ClientError::Refused {
                kind: "commission",
                target: format!("device {device}"),
                reason: Reason::EstopLatched,
                tick: 0,
                detail: Some(
                    "the e-stop is latched: a commission re-parameterises the board while it \
                     is meant to hold (a factory reset sets every parameter back); find why it \
                     was pressed, `motionctl reset`, and commission again"
                        .to_owned(),
                ),
            }));
        }
        Err(error) => return Err(error.into()),
    };
    if !json {
        eprintln!(
            "{device}: {} sent (tick {}); finding it again…",
            match change.what {
                CommissionWhat::Address => format!("address {}", change.value),
                CommissionWhat::Baud => format!("{} baud", change.value),
                CommissionWhat::FactoryReset => "factory reset".to_owned(),
            },
            accepted.tick
        );
    }
    let found = client.wait_commissioned(device, accepted, timeout);
    drop(claims);
    let found = found.with_context(|| match change.what {
        CommissionWhat::Address => format!(
            "device `{device}` did not answer at address {} within {timeout:?}; the server keeps \
             asking there (and the config's {old_address} still names the old one)",
            change.value
        ),
        CommissionWhat::Baud => format!(
            "device `{device}` did not answer at {} baud within {timeout:?}; the server keeps \
             asking at its link's rate, the new one and 19200 in turn",
            change.value
        ),
        CommissionWhat::FactoryReset => format!(
            "device `{device}` did not answer after its reset within {timeout:?} (at 19200 baud, \
             address {old_address}: are its rotary switches set so?)"
        ),
    })?;
    let advice = advice(device, &model, (&link, &others), change, &found);
    if json {
        let value = serde_json::json!({
            "device": device,
            "what": change.what.name(),
            "value": change.value,
            "address": found.address,
            "firmware": found.firmware,
            "took_ms": found.took.as_secs_f64() * 1000.0,
            "config": advice.config,
            "advice": advice.text,
        });
        out!("{value:#}");
    } else {
        out!("{}", advice.text);
    }
    Ok(())
}

/// What to tell the user.
struct Advice {
    /// The config line(s).
    config: String,
    /// The whole message.
    text: String,
}

fn advice(
    device: &str,
    model: &str,
    (link, others): (&str, &[String]),
    change: Change,
    found: &Commissioned,
) -> Advice {
    let trinamic = model == "tmcpack";
    let firmware = if found.firmware.is_empty() {
        String::new()
    } else {
        format!(" ({})", found.firmware)
    };
    match change.what {
        CommissionWhat::Address => {
            let config = if trinamic {
                format!("address = {}", found.address)
            } else {
                format!("address = {:#04x}", found.address)
            };
            let keep = if trinamic {
                format!(
                    " Set the pack's rotary switches to {} too: it reads them again at every \
                     reset and power-up (manual 6.1), and would be back at its old address.",
                    found.address
                )
            } else {
                String::new()
            };
            Advice {
                text: format!(
                    "{device} answers at address {}{firmware}, found after {:.0} ms. Put \
                     `{config}` in its [[device]] table (name = \"{device}\"): the config still \
                     names the old address, at which a restarted server would not find it.{keep}",
                    found.address,
                    found.took.as_secs_f64() * 1000.0
                ),
                config,
            }
        }
        CommissionWhat::Baud => {
            let config = format!("baud = {}", change.value);
            let shared = if others.is_empty() {
                String::new()
            } else {
                format!(
                    " {} on link `{link}` still talk at their own rate: the link changes its \
                     rate before every message to one or the other until they are \
                     commissioned too (`motionctl commission NAME --baud {}`); the config \
                     wants one `baud` for every pack on a link.",
                    others.join(", "),
                    change.value
                )
            };
            Advice {
                text: format!(
                    "{device} answers at {} baud{firmware}, found after {:.0} ms, the link \
                     `{link}` following. Put `{config}` in its [[device]] table (name = \
                     \"{device}\"), so that a restarted server switches it again after a power \
                     loss (the pack is back at 19200 then); `{config}` in the [[link]] table \
                     finds a running pack at once.{shared}",
                    change.value,
                    found.took.as_secs_f64() * 1000.0
                ),
                config,
            }
        }
        CommissionWhat::FactoryReset => Advice {
            config: String::new(),
            text: format!(
                "{device} was reset to its factory settings and answers at address {}{firmware}, \
                 found after {:.0} ms; the server configured it again from its config (the motors' \
                 positions were lost: home the axes). The config needs no change unless it \
                 names another address than the rotary switches give.",
                found.address,
                found.took.as_secs_f64() * 1000.0
            ),
        },
    }
}
