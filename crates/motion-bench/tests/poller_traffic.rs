//! The bare poller sends what motiond's drivers send to the I/O phase's idle boards, at the
//! same rates, and gets the same answers back: the drivers motiond builds from the I/O
//! phase's own config and the poller's schedules ([`motion_bench::poller_boards::Idle`])
//! each run against the boards the bench simulates, on simulated wires at the links' rates,
//! tick by tick on a fake clock; after the start-up has settled, every kind of message each
//! board got is counted, with the bytes each board sent back.

use core::time::Duration;
use std::collections::BTreeMap;
use std::path::Path;

use motion_base::Model;
use motion_bench::io_links::{Links, config_text};
use motion_bench::poller_boards::{Idle, PACK_BAUD, SPIM_ADDRESS};
use motion_bench::pty::BAUD;
use motion_bench::sim_boards::{serial_board, spi_board};
use motion_bench::sweep::ServerRt;
use motion_drivers::Driver;
use motion_link::Link;
use motion_link::sim::SimLink;

/// motiond's tick in the I/O phase (the bench's default rate).
const TICK: Duration = Duration::from_millis(1);
/// Start-up and its settling (the I/O phase waits for every device online, then 1 s).
const SETTLE: Duration = Duration::from_secs(2);
/// The window counted.
const WINDOW: Duration = Duration::from_secs(6);
const BOARDS: [&str; 4] = ["qsb", "pack", "quad", "spim"];

/// The four boards, as the I/O phase serves them, on simulated wires at the links' rates
/// (the QSB's bytes at the end of each 1 ms USB frame, as its pty does).
fn sim_links() -> Vec<Box<dyn Link>> {
    let board = |model| serial_board(model).expect("a serial board");
    vec![
        Box::new(SimLink::stream("qsb", BAUD, board(Model::QSB)).with_host_frames(TICK)),
        Box::new(SimLink::stream("pack", PACK_BAUD, board(Model::TMCPACK))),
        Box::new(SimLink::spi(
            "quad",
            500_000,
            spi_board(Model::QQ2DRV, None, None).expect("an SPI board"),
        )),
        Box::new(SimLink::spi(
            "spim",
            500_000,
            spi_board(Model::SPIMOTOR, Some(SPIM_ADDRESS), Some("stepper")).expect("an SPI board"),
        )),
    ]
}

/// What one board got and gave in the window.
#[derive(Debug, Default, Clone, PartialEq)]
struct Traffic {
    /// Messages by kind (decoded with the board's protocol crate).
    sent: BTreeMap<String, u64>,
    /// Bytes the board sent back.
    received: u64,
}

/// A message's kind, in words of its protocol crate.
fn kind(board: usize, bytes: &[u8]) -> String {
    match board {
        0 => String::from_utf8_lossy(bytes).trim().to_owned(),
        1 => format!(
            "{:?}",
            tmcpack::RequestFrame::decode(bytes).map(|frame| frame.request)
        ),
        2 if bytes.iter().all(|&b| b == 0) => format!("filler of {} bytes", bytes.len()),
        2 => format!("requests, {} bytes", bytes.len()),
        _ => format!("{:?}", spimotor::Transaction::decode(bytes)),
    }
}

fn counting(now: Duration) -> bool {
    (SETTLE..WINDOW).contains(&now)
}

/// motiond's drivers for the I/O phase's config, each stepped as motiond's tick steps it:
/// what arrived, the time, then every message it wants out.
fn drivers() -> Vec<Traffic> {
    let paths = Links {
        qsb: "/dev/null".into(),
        pack: "/dev/null".into(),
        quad: "/dev/null".into(),
        spim: "/dev/null".into(),
    };
    let text = config_text("poller-traffic", 1000, ServerRt::default(), &paths);
    let config = motion_config::ServerConfig::parse(Path::new("io.toml"), &text)
        .expect("the I/O phase's config is valid");
    let mut drivers = motion_config::boards::build(&config).expect("drivers");
    let mut links = sim_links();
    let mut traffic = vec![Traffic::default(); 4];
    let mut buf = [0u8; 4096];
    let mut now = Duration::ZERO;
    while now < WINDOW {
        for (index, (driver, link)) in drivers.iter_mut().zip(links.iter_mut()).enumerate() {
            loop {
                let len = link.read(now, &mut buf).expect("read");
                if len == 0 {
                    break;
                }
                if counting(now) {
                    traffic[index].received += len as u64;
                }
                driver.handle_rx(now, &buf[..len]);
            }
            driver.handle_timeout(now);
            while driver.wants_transmit(now).is_some() {
                let Some(transmit) = driver.poll_transmit(now, &mut buf) else {
                    break;
                };
                let bytes = &buf[..transmit.len];
                link.write(now, bytes).expect("write");
                driver.handle_written(now);
                if counting(now) {
                    *traffic[index].sent.entry(kind(index, bytes)).or_default() += 1;
                }
            }
        }
        now += TICK;
    }
    for (index, driver) in drivers.iter().enumerate() {
        assert!(driver.status().online, "{} online", BOARDS[index]);
    }
    traffic
}

/// The bare poller's schedules on the same boards.
fn poller() -> Vec<Traffic> {
    let mut links = sim_links();
    let mut idle = Idle::new();
    let mut traffic = vec![Traffic::default(); 4];
    let mut buf = [0u8; 4096];
    let mut now = Duration::ZERO;
    while now < WINDOW {
        for (index, link) in links.iter_mut().enumerate() {
            loop {
                let len = link.read(now, &mut buf).expect("read");
                if len == 0 {
                    break;
                }
                if counting(now) {
                    traffic[index].received += len as u64;
                }
                idle.take(index, &buf[..len]);
            }
        }
        idle.tick(now, &mut links, |index, bytes| {
            if counting(now) {
                *traffic[index].sent.entry(kind(index, bytes)).or_default() += 1;
            }
        })
        .expect("write");
        now += TICK;
    }
    assert!(idle.started(), "every board's start-up is done");
    traffic
}

/// Within 2 % (or 2 messages, for rare ones).
fn close(a: u64, b: u64) -> bool {
    a.abs_diff(b) <= (a.max(b) / 50).max(2)
}

#[test]
fn the_poller_sends_what_the_drivers_send_and_reads_as_much_back() {
    let drivers = drivers();
    let poller = poller();
    for (index, name) in BOARDS.iter().enumerate() {
        let (ours, bare) = (&drivers[index], &poller[index]);
        println!("{name}: drivers {ours:?}\n{name}: poller  {bare:?}");
        assert!(
            ours.received > 0,
            "{name}: the board answers motiond's driver"
        );
        assert_eq!(
            ours.sent.keys().collect::<Vec<_>>(),
            bare.sent.keys().collect::<Vec<_>>(),
            "{name}: the same kinds of message"
        );
        for (kind, &count) in &ours.sent {
            let theirs = bare.sent.get(kind).copied().unwrap_or(0);
            assert!(
                close(count, theirs),
                "{name}: {kind}: the drivers sent {count}, the poller {theirs}"
            );
        }
        assert!(
            close(ours.received, bare.received),
            "{name}: the board sent back {} bytes to the drivers, {} to the poller",
            ours.received,
            bare.received
        );
    }
    // The idle boards that are polled are polled (an empty schedule matches nothing).
    for (index, name) in BOARDS.iter().enumerate().skip(1) {
        assert!(
            !drivers[index].sent.is_empty(),
            "{name} is polled while idle"
        );
    }
}
