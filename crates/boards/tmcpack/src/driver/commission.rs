//! Commissioning ([`Driver::commission`](motion_drivers::Driver::commission), `motionctl
//! commission`): the pack's address (`$42`), its line rate (`$40`) and its factory reset
//! (`$CC`), and finding it again afterwards.
//!
//! Manual 8.6: `$42` "Change Address of Unit (RS 232 / RS 485)", P0 the new address; the
//! rotary switches are "scanned on reset" (6.1), so the new address lasts until the pack is
//! reset or loses power. `$40` sets the baud rate divisor (module `rate`). `$CC` "Complete
//! Hardware Reset … All configured parameters will be replaced by the default parameters.
//! This command needs about 1 second": the address comes back from the rotary switches
//! (taken to be the configured one) and the rate to 19200.
//!
//! Each goes out as soon as the line is free (only while the pack is online, and never
//! while an axis moves: the engine refuses that), then the driver asks `$43` where the
//! pack now answers — after `$CC` once its second of start-up is over — and, found,
//! configures it as at start-up (after `$CC` the reset flag makes it a reset: the motors'
//! positions are void). Not found, it is `NotResponding` as at start-up, and keeps being
//! asked. The server keeps the new address or rate until it stops; the config still names
//! the old one, which the client tells its user to change.

use core::time::Duration;

use tmcpack::Request;
use tmcpack::convert::{DEFAULT_SWITCHOVER_UNITS as FACTORY_SWITCHOVER, listed_baud_divisor};

use super::wire::Pick;
use super::{Phase, TmcpackDriver};
use motion_drivers::{Commission, CommissionError, DeviceFault};

/// How long the driver leaves a pack alone after `$CC` ("needs about 1 second").
pub const RESET_WAIT: Duration = Duration::from_millis(1200);

/// A change of the pack's own settings waiting for the line.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Service {
    /// `$40` to this rate (the start-up's switch, or commissioned).
    Baud(u32),
    /// `$42` to this address.
    Address(u8),
    /// `$CC`.
    Reset,
}

impl TmcpackDriver {
    /// [`Driver::commission`](motion_drivers::Driver::commission) for the pack.
    pub(super) fn start_commission(&mut self, change: Commission) -> Result<(), CommissionError> {
        match self.phase {
            Phase::Online if self.service.is_none() => {}
            Phase::Down => return Err(CommissionError::Offline),
            Phase::Identify if self.status.fault == Some(DeviceFault::NotResponding) => {
                return Err(CommissionError::Offline);
            }
            _ => return Err(CommissionError::Starting),
        }
        let service = match change {
            Commission::Address(address) => {
                let address = u8::try_from(address).map_err(|_| CommissionError::OutOfRange)?;
                if address == self.reply_address {
                    // The pack would take the driver's answers for requests.
                    return Err(CommissionError::OutOfRange);
                }
                Service::Address(address)
            }
            Commission::Baud(baud) => {
                listed_baud_divisor(baud).map_err(|_| CommissionError::OutOfRange)?;
                Service::Baud(baud)
            }
            Commission::FactoryReset => Service::Reset,
        };
        if let Service::Baud(baud) = service {
            self.rate.commission(baud);
        }
        self.service = Some(service);
        // Not online from here on (the engine takes no goal for the pack) until it is
        // found again.
        self.status.online = false;
        Ok(())
    }

    /// The request of the change waiting, if any: it goes before everything else.
    pub(super) fn service_pick(&self) -> Option<Pick> {
        let request = match self.service? {
            Service::Baud(baud) => Request::SetBaud {
                divisor: listed_baud_divisor(baud)
                    .or_else(|_| tmcpack::convert::baud_divisor(baud))
                    .ok()?,
                switchover: self.switchover_units.unwrap_or(FACTORY_SWITCHOVER),
            },
            Service::Address(address) => Request::SetAddress { address },
            Service::Reset => Request::HardwareReset,
        };
        Some(Pick {
            request,
            expect: None,
            channel: None,
        })
    }

    /// `request` just went out: when it was the change waiting, the pack is now at its
    /// new address or rate (or resetting), and is asked `$43` there.
    pub(super) fn on_service_sent(&mut self, now: Duration, request: Request) {
        let Some(service) = self.service else {
            return;
        };
        match (service, request) {
            (Service::Baud(baud), Request::SetBaud { .. }) => {
                self.rate.switched(baud);
                self.retime();
                self.reprobe(now);
            }
            (Service::Address(address), Request::SetAddress { .. }) => {
                self.address = address;
                self.reprobe(now);
            }
            (Service::Reset, Request::HardwareReset) => {
                self.address = self.home_address;
                self.rate.factory();
                self.retime();
                self.assume_unknown_line();
                self.reprobe(now + RESET_WAIT);
            }
            _ => {}
        }
    }
}
