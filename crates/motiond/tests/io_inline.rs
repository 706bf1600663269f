//! Links the tick runs itself (`[[link]] io = "tick"`, `motiond::io::inline`): the tick's
//! `transfer` writes what it queued within its wire-time budget and `look` takes what came
//! back at the next tick; neither waits for a peer, a failed link is taken down and
//! reopened with the I/O threads' backoff, and none of it allocates.

use core::time::Duration;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use motion_link::Link;
use motion_link::sim::{SimLink, SpiDevice};
use motion_link::spi_socket::{SpiSocketConfig, SpiSocketLink};
use motion_testkit::counting_alloc::{CountingAllocator, counted};
use motion_testkit::socket_board::SocketBoard;
use motiond::io::inline::{self, wire_time};
use motiond::io::{LinkEvent, LinkPort, PACKET_LEN, Packet};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// How long a test waits for something that should come at once.
const PATIENCE: Duration = Duration::from_secs(10);

/// Answers every MOSI byte with its complement.
struct Complement;

impl SpiDevice for Complement {
    fn transfer(&mut self, _now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        for (out, byte) in miso.iter_mut().zip(mosi) {
            *out = !byte;
        }
        true
    }
    fn advance(&mut self, _now: Duration) {}
}

fn epoch() -> Duration {
    motiond::rt::monotonic_now()
}

fn socket_path(tag: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("motiond-inline-{tag}-{}.sock", std::process::id()))
}

fn socket_link(path: &std::path::Path) -> Box<dyn Link> {
    let config = SpiSocketConfig::new(path.to_string_lossy());
    Box::new(SpiSocketLink::new(config).expect("valid"))
}

fn inline_port(link: Box<dyn Link>, budget: Duration, bit_rate: Option<u32>) -> LinkPort {
    inline::start(link, epoch(), budget, bit_rate).expect("port")
}

fn events(port: &mut LinkPort) -> Vec<LinkEvent> {
    let mut got = Vec::new();
    while let Ok(event) = port.events.pop() {
        got.push(event);
    }
    got
}

/// Looks (as the tick does at the start of each tick) until `want` bytes came back.
fn take(port: &mut LinkPort, want: usize) -> Vec<u8> {
    let started = Instant::now();
    let mut got = Vec::new();
    while got.len() < want && started.elapsed() < PATIENCE {
        port.inline.as_mut().expect("inline").look();
        while let Ok(packet) = port.rx.pop() {
            got.extend_from_slice(packet.bytes());
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    got
}

#[test]
fn the_tick_writes_its_transfers_and_takes_their_miso_bytes_at_its_next_look() {
    let path = socket_path("miso");
    let _board = SocketBoard::start(&path, Arc::new(Mutex::new(Complement)), Instant::now());
    let mut port = inline_port(socket_link(&path), Duration::from_micros(250), None);
    assert_eq!(events(&mut port), [LinkEvent::Up], "opened at start");
    for message in [&[0x01u8, 0x02][..], &[0x10, 0x20, 0x30], &[0xF0]] {
        port.tx.push(Packet::new(message)).expect("room");
    }
    port.inline.as_mut().expect("inline").transfer();
    // An SPI socket's writes only queue: all three went at once, none deferred.
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 3);
    assert_eq!(port.counters.deferred.load(Ordering::Relaxed), 0);
    let mut written = 0;
    while port.written.pop().is_ok() {
        written += 1;
    }
    assert_eq!(written, 3, "every message is reported written");
    assert_eq!(take(&mut port, 6), [0xFE, 0xFD, 0xEF, 0xDF, 0xCF, 0x0F]);
    assert!(
        port.heard() > Duration::ZERO,
        "the look publishes a horizon"
    );
}

#[test]
fn what_does_not_fit_the_wire_time_budget_waits_for_the_next_tick_and_is_counted() {
    // 100 bytes at 1 MHz hold the bus 800 µs: a 1000 µs budget takes one a tick.
    let rate = 1_000_000;
    assert_eq!(wire_time(100, Some(rate)), Duration::from_micros(800));
    let link = SimLink::spi("budget", rate, Box::new(Complement));
    let mut port = inline_port(Box::new(link), Duration::from_micros(1000), Some(rate));
    assert_eq!(events(&mut port), [LinkEvent::Up]);
    for fill in 1..=3u8 {
        port.tx.push(Packet::new(&[fill; 100])).expect("room");
    }
    let inline = port.inline.as_mut().expect("inline");
    inline.transfer();
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 1);
    assert_eq!(
        port.counters.deferred.load(Ordering::Relaxed),
        2,
        "two left"
    );
    let inline = port.inline.as_mut().expect("inline");
    inline.transfer();
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 2);
    assert_eq!(
        port.counters.deferred.load(Ordering::Relaxed),
        3,
        "one more"
    );
    let inline = port.inline.as_mut().expect("inline");
    inline.transfer();
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 3);
    assert_eq!(port.counters.deferred.load(Ordering::Relaxed), 3);
    // In order, each answered.
    let got = take(&mut port, 300);
    let want: Vec<u8> = (1..=3u8).flat_map(|fill| [!fill; 100]).collect();
    assert_eq!(got, want);
    // A message longer than the whole budget still goes, alone, as a tick's first.
    port.tx.push(Packet::new(&[7; PACKET_LEN])).expect("room");
    port.tx.push(Packet::new(&[8; 1])).expect("room");
    port.inline.as_mut().expect("inline").transfer();
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 4);
    port.inline.as_mut().expect("inline").transfer();
    assert_eq!(port.counters.transactions.load(Ordering::Relaxed), 5);
}

#[test]
fn a_peer_that_stops_answering_never_holds_the_tick() {
    let path = socket_path("hung");
    let device = Arc::new(Mutex::new(Complement));
    let _board = SocketBoard::start(&path, Arc::clone(&device), Instant::now());
    let mut port = inline_port(socket_link(&path), Duration::from_micros(250), None);
    assert_eq!(events(&mut port), [LinkEvent::Up]);
    // The board's thread blocks on its model: it reads no more transactions and answers
    // none, as a hung bridge would.
    let hung = device.lock().expect("model");
    let started = Instant::now();
    let mut answered = 0;
    for _ in 0..2000 {
        port.tx.push(Packet::new(&[0x55; 64])).expect("room");
        let inline = port.inline.as_mut().expect("inline");
        inline.transfer();
        inline.look();
        while let Ok(packet) = port.rx.pop() {
            answered += packet.bytes().len();
        }
    }
    // 2000 ticks' worth of calls against a hung peer: if one had waited for an answer
    // (or for room in the socket) it would have waited for ever, so finishing at all is
    // the proof; PATIENCE only keeps a broken build from hanging the run.
    assert!(started.elapsed() < PATIENCE);
    // At most the one transaction the board had read before it blocked was answered.
    assert!(answered <= 64, "{answered} bytes answered by a hung peer");
    drop(hung);
}

#[test]
fn look_and_transfer_allocate_nothing_even_across_a_lost_and_reopened_peer() {
    let path = socket_path("alloc");
    let board = SocketBoard::start(&path, Arc::new(Mutex::new(Complement)), Instant::now());
    let mut port = inline_port(socket_link(&path), Duration::from_micros(250), None);
    assert_eq!(events(&mut port), [LinkEvent::Up]);
    let mut allocations = 0;
    let mut answered = 0;
    let mut tick = |port: &mut LinkPort, allocations: &mut u64| {
        // The tick's side: its queue push, transfer, look and pops.
        let ((), count) = counted(|| {
            let _ = port.tx.push(Packet::new(&[0x0F; 8]));
            let inline = port.inline.as_mut().expect("inline");
            inline.transfer();
            std::thread::sleep(Duration::from_micros(100));
            let inline = port.inline.as_mut().expect("inline");
            inline.look();
            while let Ok(packet) = port.rx.pop() {
                answered += packet.bytes().len();
            }
            while port.written.pop().is_ok() {}
        });
        *allocations += count;
    };
    for _ in 0..1000 {
        tick(&mut port, &mut allocations);
    }
    // The peer goes away: the link goes down at a look, is tried again after its backoff
    // (the socket is gone: refused), and comes back up once a peer listens again.
    drop(board);
    let started = Instant::now();
    while !events(&mut port).contains(&LinkEvent::Down) {
        assert!(started.elapsed() < PATIENCE, "the link never went down");
        tick(&mut port, &mut allocations);
    }
    let down_at = Instant::now();
    while down_at.elapsed() < Duration::from_millis(300) {
        tick(&mut port, &mut allocations);
    }
    let errors_while_down = port.counters.errors.load(Ordering::Relaxed);
    assert!(
        errors_while_down >= 2,
        "reopens were tried: {errors_while_down}"
    );
    let _board = SocketBoard::start(&path, Arc::new(Mutex::new(Complement)), Instant::now());
    let started = Instant::now();
    while !events(&mut port).contains(&LinkEvent::Up) {
        assert!(started.elapsed() < PATIENCE, "the link never came back");
        tick(&mut port, &mut allocations);
    }
    for _ in 0..200 {
        tick(&mut port, &mut allocations);
    }
    assert_eq!(
        allocations, 0,
        "the tick's link I/O allocated {allocations} times"
    );
    assert!(answered > 1000 * 8 / 2, "{answered} bytes came back");
}
