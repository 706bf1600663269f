//! Commissioning ([`Driver::commission`](motion_drivers::Driver::commission), `motionctl
//! commission DEVICE --address N`): the SPI_motor's address, through its three write
//! ports (protocol page, "write ports"): 0x55 to 0xf1 "to start unlocking the change
//! address register", 0xaa to 0xf2 "to unlock" it (the page's table prints 0xf0 twice; the
//! second is read as 0xf2, docs/ARCHITECTURE.md), then the new address to 0xf0 "change
//! address. Requires a write to 0xf1 and 0xf2 first." The three go out back to back as the
//! next transactions to the board (nothing else addressed to it in between, which would
//! abort the sequence), at its old address; from the third on the driver talks to the new
//! one and starts the board there again from its identification read (no reset: the
//! board keeps its registers, the survey reads them). The board has no rate or factory
//! reset to change: those are `Unsupported`.

use core::time::Duration;

use spimotor::{Address, Write};

use super::wire::Op;
use super::{Phase, SpimotorDriver};
use motion_drivers::{Commission, CommissionError, DeviceFault, Priority};

impl SpimotorDriver {
    /// [`Driver::commission`](motion_drivers::Driver::commission) for the board.
    pub(super) fn start_commission(&mut self, change: Commission) -> Result<(), CommissionError> {
        let Commission::Address(address) = change else {
            return Err(CommissionError::Unsupported);
        };
        if !self.link_up {
            return Err(CommissionError::Offline);
        }
        if self.phase != Phase::Running || !self.status.online || !self.commands.is_empty() {
            return Err(if self.status.fault == Some(DeviceFault::NotResponding) {
                CommissionError::Offline
            } else {
                CommissionError::Starting
            });
        }
        // "7 bits wide", the lower bit the read flag: an even byte.
        let address = u8::try_from(address)
            .ok()
            .and_then(|a| Address::new(a).ok())
            .ok_or(CommissionError::OutOfRange)?;
        for write in [
            Write::UnlockAddress1,
            Write::UnlockAddress2,
            Write::ChangeAddress(address),
        ] {
            self.push_command(Op::Write(write), Priority::Setup, 0);
        }
        // Not online from here on (the engine takes no goal for it) until it is found at
        // the new address.
        self.status.online = false;
        Ok(())
    }

    /// The write of 0xf0 went out: from now on the board answers at `address`.
    pub(super) fn address_written(&mut self, now: Duration, address: Address) {
        self.config.address = address;
        self.status.fault = None;
        self.restart(now, 0);
    }
}
