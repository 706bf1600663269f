//! Fault injection through the binary: `--noise-every` puts random bytes on an idle pty,
//! `--drop-rate 1` loses every byte so no request gets an answer.

mod pty_support;

use std::time::Duration;

use motion_link::Link;
use motion_link::serial::{SerialConfig, SerialLink};
use pty_support::{Served, read_until};

#[test]
fn noise_arrives_on_an_idle_pty() {
    let served = Served::start(&["--model", "qsb", "--pty", "--noise-every", "2"]);
    let mut link = SerialLink::open(SerialConfig::new(&served.first_line, 230_400)).expect("open");
    let got = read_until(&mut link, Duration::from_secs(5), |b| b.len() >= 5);
    assert!(
        got.len() >= 5,
        "noise: {got:02x?}; stderr:\n{}",
        served.stderr()
    );
    assert!(served.stderr().contains("noise 1 byte every"));
    served.stop_and_check(Duration::from_secs(5));
}

#[test]
fn a_wire_that_loses_every_byte_answers_nothing() {
    let served = Served::start(&["--model", "qsb", "--pty", "--drop-rate", "1"]);
    let mut link = SerialLink::open(SerialConfig::new(&served.first_line, 230_400)).expect("open");
    assert_eq!(link.write(Duration::ZERO, b"R14\r\n").expect("write"), 5);
    let got = read_until(&mut link, Duration::from_millis(200), |b| !b.is_empty());
    assert!(got.is_empty(), "{got:02x?}");
    served.stop_and_check(Duration::from_secs(5));
}
