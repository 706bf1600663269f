//! A change of the line rate queued between two messages (`Packet::rate_change`): the I/O
//! thread writes the message before it at the old rate, lets it leave, sets the new rate
//! and writes the next one there; only messages are reported written.

use core::time::Duration;
use std::os::fd::AsFd;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use motion_link::serial::{SerialConfig, SerialLink, tty_speed};
use motiond::io::{self, LinkEvent, Packet};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

const PATIENCE: Duration = Duration::from_secs(10);

#[test]
fn the_rate_changes_between_the_two_messages_it_stands_between() {
    let pty = nix::pty::openpty(None, None).expect("openpty");
    let path = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
    let mut config = SerialConfig::new(path.to_string_lossy(), 19_200);
    config.exclusive = false;
    let link = SerialLink::new(config).expect("valid");
    let stop = Arc::new(AtomicBool::new(false));
    let options = io::IoThreadOptions {
        epoch: motiond::rt::monotonic_now(),
        idle: Duration::from_secs(3600),
        rt_priority: None,
        cpu: None,
    };
    let (mut port, thread) =
        io::spawn("rate", Box::new(link), options, Arc::clone(&stop)).expect("spawn");
    let started = Instant::now();
    while port.events.pop().ok() != Some(LinkEvent::Up) {
        assert!(started.elapsed() < PATIENCE, "never up");
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(tty_speed(pty.master.as_fd()).expect("speed"), 19_200);
    port.tx.push(Packet::new(b"at 19200")).expect("room");
    port.tx
        .push(Packet::rate_change(115_200, Duration::ZERO))
        .expect("room");
    port.tx.push(Packet::new(b"at 115200")).expect("room");
    port.waker.wake();
    let mut got = Vec::new();
    let started = Instant::now();
    while got.len() < 17 && started.elapsed() < PATIENCE {
        let mut fds = [PollFd::new(pty.master.as_fd(), PollFlags::POLLIN)];
        if poll(&mut fds, PollTimeout::from(100u16)).unwrap_or(0) == 0 {
            continue;
        }
        let mut buf = [0u8; 64];
        let n = nix::unistd::read(&pty.master, &mut buf).expect("read");
        got.extend_from_slice(&buf[..n]);
    }
    assert_eq!(got, b"at 19200at 115200");
    assert_eq!(tty_speed(pty.master.as_fd()).expect("speed"), 115_200);
    assert_eq!(port.counters.baud.load(Ordering::Relaxed), 115_200);
    let started = Instant::now();
    let mut reports = 0;
    while started.elapsed() < Duration::from_millis(200) {
        if port.written.pop().is_ok() {
            reports += 1;
        }
    }
    assert_eq!(reports, 2, "two messages; the rate change is none");
    stop.store(true, Ordering::Relaxed);
    thread.join();
}
