//! Commissioning a device: a change of the board's own settings — its bus address, its line
//! rate, a reset to its factory settings — sent by the server's driver, which then finds
//! the board again where it now answers (`CommandKind::Commission`, `motionctl commission`).
//!
//! The server takes it only from a client that holds the claim of every axis and signal of
//! the device ([`Client::claim_device`]) while none of its axes moves. The config still
//! names the old setting afterwards: tell whoever keeps it ([`Commissioned`]).
//!
//! ```no_run
//! use core::time::Duration;
//! use iceoryx2::prelude::ipc;
//! use motion_client::Client;
//! use motion_client::ipc::CommissionWhat;
//!
//! let client = Client::<ipc::Service>::connect("demo")?;
//! let claims = client.claim_device("pack_aux")?;
//! let accepted = client.commission("pack_aux", CommissionWhat::Address, 5)?;
//! let found = client.wait_commissioned("pack_aux", accepted, Duration::from_secs(5))?;
//! println!("{} answers at address {} ({})", found.device, found.address, found.firmware);
//! drop(claims);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use core::time::Duration;
use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{CommandKind, CommissionWhat, DeviceState, Target};

use crate::{Accepted, ClaimGuard, Client, ClientError, DeviceStatus};

/// A device found again after a commission.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Commissioned {
    /// The device.
    pub device: String,
    /// Its bus address as the server now talks to it (`DeviceInfo::address`).
    pub address: u32,
    /// Its firmware as it reported it when found.
    pub firmware: String,
    /// From the accepting tick to the first frame showing it online.
    pub took: Duration,
}

impl<S: Service> Client<S> {
    /// The index (config order) of device `name`; [`ClientError::UnknownDevice`] when the
    /// server has none of that name.
    pub fn device_index(&self, name: &str) -> Result<usize, ClientError> {
        self.refresh_info()?;
        self.info
            .current()
            .and_then(|info| info.devices().iter().position(|d| d.name() == name))
            .ok_or_else(|| ClientError::UnknownDevice(name.to_owned()))
    }

    /// Claims every axis and every signal of device `name` (what a commission needs); the
    /// claims end when the guards are dropped. Fails on the first claim refused (another
    /// client holds it), releasing those taken.
    pub fn claim_device(&self, name: &str) -> Result<Vec<ClaimGuard<'_, S>>, ClientError> {
        let index = self.device_index(name)?;
        let info = self.info.current();
        let axes: Vec<u32> = info.as_ref().map_or_else(Vec::new, |info| {
            (0..info.axes().len())
                .filter(|&a| usize::from(info.axes()[a].device_index) == index)
                .map(|a| a as u32)
                .collect()
        });
        let signals: Vec<u32> = info.as_ref().map_or_else(Vec::new, |info| {
            (0..info.signals().len())
                .filter(|&s| usize::from(info.signals()[s].device_index) == index)
                .map(|s| s as u32)
                .collect()
        });
        let mut guards = Vec::with_capacity(axes.len() + signals.len());
        for axis in axes {
            guards.push(ClaimGuard::take(self, Target::Axis, axis)?);
        }
        for signal in signals {
            guards.push(ClaimGuard::take(self, Target::Signal, signal)?);
        }
        Ok(guards)
    }

    /// Asks the server to change `what` of device `device` to `value` (the new address or
    /// baud rate; ignored for [`CommissionWhat::FactoryReset`]). Accepted, the board is
    /// being found again: [`wait_commissioned`](Self::wait_commissioned). Refused with the
    /// server's reason: `EstopLatched` (reset the e-stop first), `NotClaimed` /
    /// `ClaimedByOther` (claim the device first), `GroupBusy` (an axis of it moves), for a
    /// baud rate on a link other devices share `GroupBusy` / `ClaimedByOther` while one of
    /// them is in use (another client's claim, a goal, a moving axis: the error's detail
    /// names the device), `Unsupported` (its board has no such setting), `OutOfRange` (a
    /// value it does not take, or another device's address on its link), `DeviceStarting` /
    /// `DeviceOffline` / `LinkDown`.
    pub fn commission(
        &self,
        device: &str,
        what: CommissionWhat,
        value: u32,
    ) -> Result<Accepted, ClientError> {
        let index = self.device_index(device)?;
        self.command_to(
            Target::Device,
            index as u32,
            CommandKind::Commission,
            [f64::from(what as u32), f64::from(value), 0.0],
        )
    }

    /// Waits until device `device` is online again after the commission `accepted`, up to
    /// `timeout`: what it was found as. [`ClientError::NotReady`] (with its state) when it
    /// is not online by then — not found at the new address or rate, or (after a factory
    /// reset) at its factory settings.
    pub fn wait_commissioned(
        &self,
        device: &str,
        accepted: Accepted,
        timeout: Duration,
    ) -> Result<Commissioned, ClientError> {
        let index = self.device_index(device)?;
        let started = Instant::now();
        let deadline = started + timeout;
        let mut state = DeviceState::Starting;
        let mut found_tick = None;
        while Instant::now() < deadline {
            match self.next_frame(deadline.saturating_duration_since(Instant::now())) {
                Ok(frame) if frame.tick >= accepted.tick => {
                    state = frame.device_state(index);
                    if state == DeviceState::Online {
                        found_tick = Some(frame.tick);
                        break;
                    }
                }
                Ok(_) | Err(ClientError::NoFrame(_)) => {}
                Err(error) => return Err(error),
            }
        }
        let Some(tick) = found_tick else {
            return Err(ClientError::NotReady {
                devices: vec![DeviceStatus {
                    index,
                    name: device.to_owned(),
                    state,
                }],
                waited: timeout,
            });
        };
        // The description is published again when a device's state changes.
        let settle = Instant::now() + Duration::from_millis(300);
        let mut info = motion_ipc::DeviceInfo::EMPTY;
        loop {
            self.refresh_info()?;
            if let Some(device) = self
                .info
                .current()
                .and_then(|i| i.devices().get(index).copied())
            {
                info = device;
                if device.state == DeviceState::Online as u32 {
                    break;
                }
            }
            if Instant::now() >= settle {
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let hz = self.info.current().map_or(1000, |i| i.tick_hz.max(1));
        Ok(Commissioned {
            device: device.to_owned(),
            address: info.address,
            firmware: info.firmware().to_owned(),
            took: Duration::from_nanos(
                tick.saturating_sub(accepted.tick)
                    .saturating_mul(1_000_000_000 / u64::from(hz)),
            ),
        })
    }
}
