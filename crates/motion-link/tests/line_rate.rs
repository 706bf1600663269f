//! Changing a serial link's line rate ([`Link::set_baud`]): the simulated wire garbles what
//! crosses between a host and a device at different rates and carries it whole once they
//! agree; a real tty takes the rate (seen from the master side of a pty, as a simulator
//! serving it sees it); a reopened link is back at its configured rate.

use std::os::fd::AsFd;
use std::time::Duration;

use motion_link::serial::{SerialConfig, SerialLink, tty_speed};
use motion_link::sim::{SimLink, SimWire, StreamBus, StreamDevice};
use motion_link::{Link, LinkErrorKind};

const T0: Duration = Duration::from_secs(10);
const MS: Duration = Duration::from_millis(1);

/// Echoes whole 9-byte words at its own rate (a pause of 2 ms aborts a partial word, as
/// the Trinamic pack's packet timeout does), and counts the words it heard.
struct Echo {
    baud: u32,
    last: Duration,
    frame: Vec<u8>,
    reply: Vec<u8>,
    words: usize,
}

impl Echo {
    fn at(baud: u32) -> Self {
        Self {
            baud,
            last: Duration::ZERO,
            frame: Vec::new(),
            reply: Vec::new(),
            words: 0,
        }
    }
}

impl StreamDevice for Echo {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        if now.saturating_sub(self.last) > 2 * MS {
            self.frame.clear();
        }
        self.last = now;
        for &byte in bytes {
            self.frame.push(byte);
            if self.frame.len() == 9 {
                if self.frame[0] == 1 {
                    self.words += 1;
                    self.reply = std::mem::take(&mut self.frame);
                }
                self.frame.clear();
            }
        }
    }
    fn transmit(&mut self, _now: Duration, out: &mut [u8]) -> usize {
        let n = out.len().min(self.reply.len());
        out[..n].copy_from_slice(&self.reply[..n]);
        self.reply.drain(..n);
        n
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        (!self.reply.is_empty()).then_some(now)
    }
    fn baud(&self) -> Option<u32> {
        Some(self.baud)
    }
}

const WORD: [u8; 9] = [1, 0x43, 0xFE, 0, 0, 0, 0, 0, 0];

/// Writes the word at `at` and collects what comes back within 20 ms (framing errors
/// skipped).
fn exchange(link: &mut SimLink, at: Duration) -> Vec<u8> {
    assert_eq!(link.write(at, &WORD).expect("write"), 9);
    let mut got = Vec::new();
    let mut buf = [0u8; 64];
    let mut now = at;
    while now < at + 20 * MS {
        now += MS / 10;
        loop {
            match link.read(now, &mut buf) {
                Ok(0) => break,
                Ok(n) => got.extend_from_slice(&buf[..n]),
                Err(e) => assert_eq!(e.kind(), LinkErrorKind::Framing),
            }
        }
    }
    got
}

#[test]
fn a_device_at_another_rate_hears_garbage_until_the_link_takes_its_rate() {
    for bus in [false, true] {
        let device: Box<dyn StreamDevice> = if bus {
            Box::new(StreamBus::new().with(Box::new(Echo::at(115_200))))
        } else {
            Box::new(Echo::at(115_200))
        };
        let mut link = SimLink::stream("pack", 19_200, device);
        let got = exchange(&mut link, T0);
        assert_ne!(
            got, WORD,
            "bus {bus}: a word at 19200 to a device at 115200"
        );
        link.set_baud(T0 + 30 * MS, 115_200).expect("set_baud");
        assert_eq!(
            link.wire(),
            SimWire::Serial {
                baud: 115_200,
                duplex: motion_link::sim::Duplex::Full
            }
        );
        assert!(link.name().ends_with("@ 115200 8N1"), "{}", link.name());
        let got = exchange(&mut link, T0 + 60 * MS);
        assert_eq!(got, WORD, "bus {bus}: both at 115200");
        link.reopen(T0 + 200 * MS).expect("reopen");
        assert!(
            link.name().ends_with("@ 19200 8N1"),
            "reopened at the configured rate: {}",
            link.name()
        );
    }
}

#[test]
fn an_spi_wire_has_no_line_rate() {
    struct Nothing;
    impl motion_link::sim::SpiDevice for Nothing {
        fn transfer(&mut self, _: Duration, _: &[u8], _: &mut [u8]) -> bool {
            false
        }
        fn advance(&mut self, _: Duration) {}
    }
    let mut link = SimLink::spi("spi", 1_000_000, Box::new(Nothing));
    let err = link.set_baud(T0, 115_200).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Unsupported);
}

#[test]
fn a_tty_takes_the_rate_and_the_master_side_of_its_pty_sees_it() {
    let pty = nix::pty::openpty(None, None).expect("openpty");
    let path = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
    let mut link =
        SerialLink::open(SerialConfig::new(path.to_string_lossy(), 19_200)).expect("open");
    assert_eq!(tty_speed(pty.master.as_fd()).expect("speed"), 19_200);
    for baud in [115_200, 250_000, 57_600] {
        link.set_baud(Duration::ZERO, baud).expect("set_baud");
        assert_eq!(link.baud(), baud);
        assert_eq!(tty_speed(pty.master.as_fd()).expect("speed"), baud);
        assert!(link.name().ends_with(&format!("@ {baud} 8N1")));
    }
    let err = link.set_baud(Duration::ZERO, 0).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Config);
    link.reopen(Duration::ZERO).expect("reopen");
    assert_eq!(link.baud(), 19_200, "reopened at the configured rate");
    assert_eq!(tty_speed(pty.master.as_fd()).expect("speed"), 19_200);
    // Not a tty.
    let file = std::fs::File::open("/dev/null").expect("/dev/null");
    assert!(tty_speed(file.as_fd()).is_err());
}
