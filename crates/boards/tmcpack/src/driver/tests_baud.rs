//! The line rate and commissioning on the fake clock: the driver and the simulated pack on a
//! simulated wire whose host side takes every rate change the link bus asks for (as the
//! I/O thread does), and garbles what crosses at another rate than the pack's.

use core::time::Duration;
use std::sync::{Arc, Mutex};

use motion_drivers::{Commission, CommissionError, Driver, LinkBus, LinkKind};
use motion_link::Link;
use motion_link::sim::{SimLink, SimWire, StreamBus, StreamDevice};
use tmcpack::Request;

use super::bench::{MS, config};
use super::*;
use crate::sim::{TmcpackSim, TmcpackSimConfig};

/// The simulated pack, shared with the test.
#[derive(Clone)]
struct Shared(Arc<Mutex<TmcpackSim>>);

impl StreamDevice for Shared {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.0.lock().unwrap().receive(now, bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.0.lock().unwrap().transmit(now, out)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.0.lock().unwrap().next_event(now)
    }
    fn baud(&self) -> Option<u32> {
        self.0.lock().unwrap().baud()
    }
}

struct Rig {
    bus: LinkBus,
    link: SimLink,
    pack: Arc<Mutex<TmcpackSim>>,
    now: Duration,
    /// Every rate change the bus asked for, with its instant.
    changes: Vec<(Duration, u32)>,
    /// Every request the driver sent, decoded.
    sent: Vec<(Duration, Request)>,
}

impl Rig {
    /// The pack at address 1 on a bus (as motiond's sim links have it) at `link` baud, the
    /// driver configured with `target`.
    fn new(link: u32, target: Option<u32>) -> Self {
        let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
        let bus = StreamBus::new().with(Box::new(Shared(Arc::clone(&pack))));
        let driver = TmcpackDriver::new(TmcpackDriverConfig {
            baud: link,
            target_baud: target,
            ..config()
        });
        Self {
            bus: LinkBus::new(LinkKind::Stream, vec![Box::new(driver) as Box<dyn Driver>]),
            link: SimLink::stream("rs485", link, Box::new(bus)),
            pack,
            now: Duration::from_secs(1),
            changes: Vec::new(),
            sent: Vec::new(),
        }
    }

    fn driver(&self) -> &dyn Driver {
        self.bus.drivers()[0].as_ref()
    }

    fn driver_mut(&mut self) -> &mut Box<dyn Driver> {
        self.bus.driver_mut(0).expect("driver")
    }

    fn link_baud(&self) -> u32 {
        match self.link.wire() {
            SimWire::Serial { baud, .. } => baud,
            SimWire::Spi { .. } => 0,
        }
    }

    /// One millisecond: what came back, time, then everything the bus sends (a rate change
    /// before the message it was asked for).
    fn tick(&mut self) {
        self.now += MS;
        let now = self.now;
        let mut buf = [0u8; 256];
        loop {
            match self.link.read(now, &mut buf) {
                Ok(0) => break,
                Ok(n) => self.bus.handle_rx(now, &buf[..n]),
                // A byte with a stop bit missing: garbage, as a tty would drop it.
                Err(_) => {}
            }
        }
        self.bus.handle_timeout(now);
        while let Some((_, t)) = self.bus.poll_transmit(now, &mut buf) {
            if let Some(rate) = self.bus.take_rate_change() {
                self.link.flush(now).expect("flush");
                self.link.set_baud(now, rate).expect("set_baud");
                self.changes.push((now, rate));
            }
            if let Ok(frame) = tmcpack::RequestFrame::decode(&buf[..t.len]) {
                self.sent.push((now, frame.request));
            }
            assert_eq!(self.link.write(now, &buf[..t.len]).expect("write"), t.len);
        }
    }

    /// Ticks until the driver is online, at most `limit` ms; the time it took.
    fn online_within(&mut self, limit: u32) -> Duration {
        let start = self.now;
        for _ in 0..limit {
            self.tick();
            if self.driver().status().online {
                return self.now - start;
            }
        }
        panic!(
            "not online within {limit} ms: {:?}, pack at {} baud address {}, link at {}",
            self.driver().status(),
            self.pack.lock().unwrap().baud_rate(),
            self.pack.lock().unwrap().address(),
            self.link_baud()
        );
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Mean interval between the `$20` polls of motor 0 over the next `ms`.
    fn poll_interval(&mut self, ms: u32) -> Duration {
        let from = self.sent.len();
        self.run(ms);
        let polls: Vec<Duration> = self.sent[from..]
            .iter()
            .filter(|(_, r)| matches!(r, Request::QueryPosition { motor: 0, .. }))
            .map(|(at, _)| *at)
            .collect();
        assert!(polls.len() > 2, "{polls:?}");
        (polls[polls.len() - 1] - polls[0]) / (polls.len() as u32 - 1)
    }
}

#[test]
fn a_factory_pack_is_switched_to_its_baud_and_polled_faster() {
    let mut slow = Rig::new(19_200, None);
    slow.online_within(500);
    // Said (the bus does not know the link's rate), and never changed.
    assert_eq!(slow.driver().line_rate(), Some(19_200));
    assert_eq!(
        slow.changes.iter().map(|(_, r)| *r).collect::<Vec<_>>(),
        [19_200]
    );
    let slow_interval = slow.poll_interval(1000);

    let mut fast = Rig::new(19_200, Some(115_200));
    fast.online_within(500);
    assert_eq!(fast.pack.lock().unwrap().baud_rate(), 115_200);
    assert_eq!(fast.link_baud(), 115_200);
    assert_eq!(fast.driver().line_rate(), Some(115_200));
    // Manual 8.6 $40: divisor 20 MHz / (16 · 115200) = 10.85 → 11, switch-over 1 · 2 ms.
    let switches: Vec<_> = fast
        .sent
        .iter()
        .filter(|(_, r)| matches!(r, Request::SetBaud { .. }))
        .map(|(_, r)| *r)
        .collect();
    assert_eq!(
        switches.first(),
        Some(&Request::SetBaud {
            divisor: 11,
            switchover: 1
        })
    );
    assert!(
        switches
            .iter()
            .all(|r| matches!(r, Request::SetBaud { divisor: 11, .. })),
        "the start-up's $40 keeps the new rate: {switches:?}"
    );
    // Said at 19200 first (the bus does not know the link's rate), then 115200 after $40.
    assert_eq!(
        fast.changes.iter().map(|(_, r)| *r).collect::<Vec<_>>(),
        [19_200, 115_200]
    );
    let fast_interval = fast.poll_interval(1000);
    assert!(
        fast_interval * 2 < slow_interval,
        "{fast_interval:?} against {slow_interval:?}"
    );
}

#[test]
fn a_pack_left_at_its_baud_is_found_on_the_second_try_without_a_new_switch() {
    let mut rig = Rig::new(19_200, Some(115_200));
    rig.pack.lock().unwrap().act_behind_the_back(
        rig.now,
        Request::SetBaud {
            divisor: 11,
            switchover: 1,
        },
    );
    rig.online_within(300);
    let unit_infos = rig
        .sent
        .iter()
        .filter(|(_, r)| matches!(r, Request::UnitInfo { .. }))
        .count();
    assert_eq!(unit_infos, 2, "one $43 at 19200 unanswered, one at 115200");
    assert_eq!(rig.driver().status().timeouts, 1);
    assert_eq!(rig.link_baud(), 115_200);
}

#[test]
fn a_pack_that_lost_power_is_found_at_19200_and_switched_again() {
    let mut rig = Rig::new(19_200, Some(115_200));
    rig.online_within(500);
    let now = rig.now;
    rig.pack.lock().unwrap().power_cycle(now);
    rig.run(1100); // its second of start-up
    rig.online_within(2000);
    assert_eq!(rig.pack.lock().unwrap().baud_rate(), 115_200);
    assert_eq!(rig.link_baud(), 115_200);
    assert_eq!(rig.driver().status().resets, 1);
}

#[test]
fn a_link_rate_already_at_the_baud_needs_no_switch_and_finds_a_factory_pack_too() {
    // The link configured at the pack's baud: a restart finds it at once…
    let mut rig = Rig::new(115_200, Some(115_200));
    rig.pack.lock().unwrap().act_behind_the_back(
        rig.now,
        Request::SetBaud {
            divisor: 11,
            switchover: 1,
        },
    );
    rig.online_within(200);
    assert_eq!(rig.driver().status().timeouts, 0);
    // …and a pack fresh from the factory on the second try, at 19200.
    let mut rig = Rig::new(115_200, Some(115_200));
    rig.online_within(500);
    assert_eq!(rig.pack.lock().unwrap().baud_rate(), 115_200);
}

#[test]
fn commissioning_the_address_moves_the_pack_and_the_driver_finds_it_there() {
    let mut rig = Rig::new(19_200, None);
    rig.online_within(500);
    let now = rig.now;
    assert_eq!(
        rig.driver_mut().commission(now, Commission::Address(0xFE)),
        Err(CommissionError::OutOfRange),
        "the reply address"
    );
    assert_eq!(
        rig.driver_mut().commission(now, Commission::Address(256)),
        Err(CommissionError::OutOfRange)
    );
    rig.driver_mut()
        .commission(now, Commission::Address(5))
        .expect("taken");
    assert_eq!(
        rig.driver_mut().commission(now, Commission::Address(6)),
        Err(CommissionError::Starting),
        "one change at a time"
    );
    rig.tick();
    assert!(!rig.driver().status().online, "found again first");
    rig.online_within(500);
    assert_eq!(rig.pack.lock().unwrap().address(), 5);
    // Manual 8.6 $42: P0 the new address, sent to the old one.
    let word = rig
        .sent
        .iter()
        .find(|(_, r)| matches!(r, Request::SetAddress { .. }))
        .map(|(_, r)| *r);
    assert_eq!(word, Some(Request::SetAddress { address: 5 }));
    let polls_before = rig.pack.lock().unwrap().stats().executed;
    rig.run(200);
    assert!(rig.pack.lock().unwrap().stats().executed > polls_before + 5);
    assert_eq!(rig.driver().status().fault, None);
}

#[test]
fn commissioning_the_rate_switches_pack_and_link_and_a_refused_rate_changes_nothing() {
    let mut rig = Rig::new(19_200, None);
    rig.online_within(500);
    let now = rig.now;
    assert_eq!(
        rig.driver_mut().commission(now, Commission::Baud(230_400)),
        Err(CommissionError::OutOfRange),
        "divisor 5 is 250000 baud"
    );
    assert_eq!(rig.driver().line_rate(), Some(19_200));
    rig.driver_mut()
        .commission(now, Commission::Baud(57_600))
        .expect("taken");
    rig.online_within(500);
    assert_eq!(rig.pack.lock().unwrap().baud_rate(), 57_600);
    assert_eq!(rig.link_baud(), 57_600);
    // Lost power: found at 19200 and switched to the commissioned rate again.
    let now = rig.now;
    rig.pack.lock().unwrap().power_cycle(now);
    rig.run(1100);
    rig.online_within(2000);
    assert_eq!(rig.pack.lock().unwrap().baud_rate(), 57_600);
}

#[test]
fn a_factory_reset_waits_for_the_pack_then_configures_it_again() {
    let mut rig = Rig::new(19_200, Some(115_200));
    rig.online_within(500);
    let now = rig.now;
    rig.driver_mut()
        .commission(now, Commission::FactoryReset)
        .expect("taken");
    rig.run(20);
    assert!(
        rig.sent
            .iter()
            .any(|(_, r)| matches!(r, Request::HardwareReset))
    );
    let took = rig.online_within(3000);
    assert!(took >= RESET_WAIT, "{took:?}");
    assert_eq!(rig.driver().status().resets, 1, "the reset flag was read");
    // Back at the configured rate, configured again.
    assert_eq!(rig.pack.lock().unwrap().baud_rate(), 115_200);
    assert_eq!(rig.driver().status().fault, None);
}

#[test]
fn commissioning_is_refused_until_the_pack_is_online() {
    let mut rig = Rig::new(19_200, None);
    let now = rig.now;
    assert_eq!(
        rig.driver_mut().commission(now, Commission::FactoryReset),
        Err(CommissionError::Starting)
    );
    rig.driver_mut().link_down(now);
    assert_eq!(
        rig.driver_mut().commission(now, Commission::FactoryReset),
        Err(CommissionError::Offline)
    );
}
