//! Loopback tests on real hardware, ignored by default. Wire the loop, name the device in
//! an environment variable and run the ignored tests:
//!
//! ```text
//! # SPI: MISO wired to MOSI
//! MOTIOND_TEST_SPIDEV=/dev/spidev0.0 cargo test -p motion-link --test hardware -- --ignored spidev
//! # serial: TX wired to RX (a loopback plug, or RS-232 pins 2–3)
//! MOTIOND_TEST_SERIAL=/dev/ttyUSB0 cargo test -p motion-link --test hardware -- --ignored serial
//! ```

use std::time::{Duration, Instant};

use motion_link::Link;
use motion_link::serial::{SerialConfig, SerialLink};
use motion_link::spidev::{SpidevConfig, SpidevLink};

fn device(var: &str) -> String {
    std::env::var(var)
        .unwrap_or_else(|_| panic!("set {var} to the device path (see the file docs)"))
}

fn read_back(link: &mut dyn Link, n: usize) -> Vec<u8> {
    let start = Instant::now();
    let mut got = Vec::new();
    let mut buf = [0u8; 256];
    while got.len() < n && start.elapsed() < Duration::from_secs(5) {
        let k = link
            .read_wait(start.elapsed(), &mut buf, Duration::from_millis(50))
            .expect("read");
        got.extend_from_slice(&buf[..k]);
    }
    got
}

#[test]
#[ignore = "needs an SPI loopback: MOTIOND_TEST_SPIDEV"]
fn spidev_loopback() {
    let path = device("MOTIOND_TEST_SPIDEV");
    let mut link = SpidevLink::open(SpidevConfig::new(path, 0, 1_000_000)).expect("open");
    let pattern: Vec<u8> = (0..=255).collect();
    assert_eq!(link.write(Duration::ZERO, &pattern).expect("transfer"), 256);
    assert_eq!(read_back(&mut link, 256), pattern);
    // One transaction in three parts (transfer_multiple, chip select held).
    let parts: [&[u8]; 3] = [&[1, 2], &[3], &[4, 5, 6]];
    assert_eq!(
        link.write_parts(Duration::ZERO, &parts).expect("transfer"),
        6
    );
    assert_eq!(read_back(&mut link, 6), [1, 2, 3, 4, 5, 6]);
    assert_eq!(link.stats().transactions, 2);
}

#[test]
#[ignore = "needs a serial loopback: MOTIOND_TEST_SERIAL"]
fn serial_loopback() {
    let path = device("MOTIOND_TEST_SERIAL");
    let mut link = SerialLink::open(SerialConfig::new(path, 115_200)).expect("open");
    let pattern: Vec<u8> = (0..=255).collect();
    let mut sent = 0;
    while sent < pattern.len() {
        sent += link.write(Duration::ZERO, &pattern[sent..]).expect("write");
    }
    link.flush(Duration::ZERO).expect("flush");
    assert_eq!(read_back(&mut link, 256), pattern);
}
