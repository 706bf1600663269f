//! One SPI transaction through the board's firmware: address filter, port dispatch, the
//! answer on MISO. Every byte is encoded and decoded by the `spimotor` protocol crate.

use core::time::Duration;

use spimotor::{Access, Address, Header, ReadPort, Reply, Transaction, Write};

use super::SpimotorSim;
use super::brushed::Bridge;

/// What MISO carries at offset 0: nothing drives the line while the address byte is
/// clocked (no board knows yet that it is selected), and an undriven MISO reads 0xFF.
pub const MISO_UNSELECTED: u8 = 0xFF;

/// What the selected board clocks out when it has nothing to say: at offset 1 (the port is
/// not known yet), during a write, and during a read of an undocumented port.
pub const MISO_IDLE: u8 = 0x00;

impl SpimotorSim {
    /// Handles one transaction completed at `now` (the model is already advanced to it).
    pub(super) fn handle(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        self.stats.transactions += 1;
        let Some(&first) = mosi.first() else {
            return false;
        };
        if Address::of_byte(first) != self.address {
            return false;
        }
        self.stats.addressed += 1;
        let len = mosi.len().min(miso.len());
        let miso = miso.get_mut(..len).unwrap_or_default();
        if let Some((head, rest)) = miso.split_first_mut() {
            *head = MISO_UNSELECTED;
            rest.fill(MISO_IDLE);
        }

        let write = match Header::decode(mosi) {
            Ok(Header {
                access: Access::Read,
                port,
                ..
            }) => {
                self.answer(port, miso);
                None
            }
            Ok(Header {
                access: Access::Write,
                ..
            }) => match Transaction::decode(mosi) {
                Ok(Transaction {
                    request: spimotor::Request::Write(write),
                    ..
                }) => Some(write),
                Ok(_) | Err(_) => {
                    self.stats.malformed += 1;
                    None
                }
            },
            Err(_) => {
                self.stats.malformed += 1;
                None
            }
        };

        let (stage, new_address) = self.unlock.next(write.as_ref());
        self.unlock = stage;
        if let Some(address) = new_address {
            self.address = address;
            self.stats.address_changes += 1;
        }
        if let Some(write) = write {
            self.apply(now, write);
        }
        true
    }

    /// Clocks out the answer of a read port. The board answers by port alone: it cannot
    /// know how many bytes the host will clock, so a short read gets the first bytes of the
    /// value and a long one gets padding after it.
    fn answer(&mut self, port: u8, miso: &mut [u8]) {
        let Some(port) = ReadPort::from_port(port) else {
            self.stats.malformed += 1;
            return;
        };
        let reply = match port {
            ReadPort::Identification => Reply::Identification(self.identification),
            ReadPort::Serial => Reply::Serial(self.serial),
            ReadPort::CurrentPosition => Reply::CurrentPosition(self.stepper.current),
            ReadPort::TargetPosition => Reply::TargetPosition(self.stepper.target),
            ReadPort::StepDelay => Reply::StepDelay(self.stepper.delay),
        };
        reply.encode_miso(miso);
    }

    /// Executes a write port.
    fn apply(&mut self, now: Duration, write: Write) {
        match write {
            Write::StepperIntensity(v) => self.stepper.intensity = v,
            Write::Spin {
                motor,
                direction,
                intensity,
            } => {
                let noise = self.config.brushed.speed_noise.abs();
                let noise = if noise.is_finite() { noise } else { 0.0 };
                let factor = 1.0 + self.rng.range_f64(-noise, noise);
                if let Some(m) = self.motors.get_mut(usize::from(motor.channel())) {
                    m.bridge = Bridge::Spin {
                        direction,
                        intensity,
                    };
                    m.factor = factor;
                }
            }
            Write::Stop(motor) => {
                if let Some(m) = self.motors.get_mut(usize::from(motor.channel())) {
                    m.bridge = Bridge::Stopped;
                }
            }
            Write::CurrentPosition(p) => self.stepper.set_current(now, p),
            Write::TargetPosition(p) => self.stepper.set_target(now, p),
            Write::RelativePosition(d) => self.stepper.set_relative(now, d),
            Write::StepDelay(d) => self.stepper.set_delay(now, d),
            Write::Coils(c) => self.stepper.coils = c,
            // Handled by the unlock sequence before this is called.
            Write::UnlockAddress1 | Write::UnlockAddress2 | Write::ChangeAddress(_) => {}
        }
    }
}
