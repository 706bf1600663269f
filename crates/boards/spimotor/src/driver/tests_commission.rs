//! Commissioning the board's address on the fake clock: the driver and the simulated board
//! on a simulated SPI wire.

use core::time::Duration;
use std::sync::{Arc, Mutex};

use motion_drivers::{Commission, CommissionError, Driver, LinkBus, LinkKind};
use motion_link::Link;
use motion_link::sim::{SimLink, SpiDevice};
use spimotor::{Address, Transaction, Write};

use super::*;
use crate::sim::{SpimotorSim, SpimotorSimConfig};

const MS: Duration = Duration::from_millis(1);

#[derive(Clone)]
struct Shared(Arc<Mutex<SpimotorSim>>);

impl SpiDevice for Shared {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        self.0.lock().unwrap().transfer(now, mosi, miso)
    }
    fn advance(&mut self, now: Duration) {
        self.0.lock().unwrap().advance(now);
    }
}

struct Rig {
    bus: LinkBus,
    link: SimLink,
    board: Arc<Mutex<SpimotorSim>>,
    now: Duration,
    sent: Vec<Transaction>,
}

impl Rig {
    fn new() -> Self {
        let board = Arc::new(Mutex::new(SpimotorSim::new(SpimotorSimConfig::default())));
        let driver = SpimotorDriver::new(SpimotorDriverConfig::default());
        Self {
            bus: LinkBus::new(LinkKind::Spi, vec![Box::new(driver) as Box<dyn Driver>]),
            link: SimLink::spi("spi", 1_000_000, Box::new(Shared(Arc::clone(&board)))),
            board,
            now: Duration::from_secs(1),
            sent: Vec::new(),
        }
    }

    fn driver(&self) -> &dyn Driver {
        self.bus.drivers()[0].as_ref()
    }

    fn tick(&mut self) {
        self.now += MS;
        let now = self.now;
        let mut buf = [0u8; 256];
        loop {
            let n = self.link.read(now, &mut buf).expect("read");
            if n == 0 {
                break;
            }
            self.bus.handle_rx(now, &buf[..n]);
        }
        self.bus.handle_timeout(now);
        while let Some((_, t)) = self.bus.poll_transmit(now, &mut buf) {
            if let Ok(transaction) = Transaction::decode(&buf[..t.len]) {
                self.sent.push(transaction);
            }
            self.link.write(now, &buf[..t.len]).expect("write");
        }
    }

    fn online_within(&mut self, limit: u32) {
        for _ in 0..limit {
            self.tick();
            if self.driver().status().online {
                return;
            }
        }
        panic!("not online within {limit} ms: {:?}", self.driver().status());
    }
}

#[test]
fn the_address_moves_with_the_unlock_sequence_and_the_board_is_found_there() {
    let mut rig = Rig::new();
    rig.online_within(500);
    let now = rig.now;
    let driver = rig.bus.driver_mut(0).expect("driver");
    assert_eq!(
        driver.commission(now, Commission::Baud(115_200)),
        Err(CommissionError::Unsupported)
    );
    assert_eq!(
        driver.commission(now, Commission::Address(0x93)),
        Err(CommissionError::OutOfRange),
        "bit 0 is the read flag"
    );
    assert_eq!(
        driver.commission(now, Commission::Address(0x1_00)),
        Err(CommissionError::OutOfRange)
    );
    let from = rig.sent.len();
    let driver = rig.bus.driver_mut(0).expect("driver");
    driver
        .commission(now, Commission::Address(0x92))
        .expect("taken");
    assert!(!rig.driver().status().online);
    rig.online_within(500);
    assert_eq!(rig.board.lock().unwrap().address(), 0x92);
    assert_eq!(rig.board.lock().unwrap().stats().address_changes, 1);
    // Protocol page: 0xf1 ← 0x55, 0xf2 ← 0xaa, 0xf0 ← the address, to the old address,
    // back to back; then the identification at the new one.
    let old = Address::DEFAULT;
    let new = Address::new(0x92).expect("even");
    let after: Vec<Transaction> = rig.sent[from..].to_vec();
    let at = after
        .iter()
        .position(|t| *t == Transaction::write(old, Write::UnlockAddress1))
        .expect("0xf1");
    assert_eq!(
        after[at..at + 3],
        [
            Transaction::write(old, Write::UnlockAddress1),
            Transaction::write(old, Write::UnlockAddress2),
            Transaction::write(old, Write::ChangeAddress(new)),
        ]
    );
    assert!(after[at + 3..].iter().all(|t| t.address == new));
    assert_eq!(rig.driver().status().fault, None);
}
