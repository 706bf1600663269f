//! The simulated QSB keeps the command list's timing on a USB wire, and counts a command
//! that came before the previous command's answer had left the board: "At the conclusion
//! of the command response, the QSB is ready to accept another command" (QSB Command List
//! 1.28, Command Acknowledgement Format).

use core::time::Duration;

use board_qsb::USB_FRAME;
use board_qsb::sim::{QsbSim, QsbSimConfig};
use motion_link::Link;
use motion_link::sim::SimLink;
use qsb::{Response, ResponseDecoder, ResponseType, TICK};

const US: Duration = Duration::from_micros(1);
const MS: Duration = Duration::from_millis(1);

/// Reads every 0.1 ms from `from` to `to`; the lines with the instant they were read.
fn lines(link: &mut SimLink, from: Duration, to: Duration) -> Vec<(Duration, Response)> {
    let mut decoder = ResponseDecoder::new();
    let mut out = Vec::new();
    let mut buf = [0u8; 256];
    let mut now = from;
    while now <= to {
        let n = link.read(now, &mut buf).expect("read");
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let (used, line) = decoder.decode(rest);
            out.extend(line.map(|line| (now, line)));
            rest = &rest[used..];
        }
        now += 100 * US;
    }
    out
}

#[test]
fn a_command_before_the_answer_ended_is_counted_one_after_it_is_not() {
    let (device, sim) = shared(QsbSim::new(QsbSimConfig::default()));
    let mut link = SimLink::stream("usb", 230_400, device).with_host_frames(USB_FRAME);
    let byte = Duration::from_nanos(10_000_000_000 / 230_400);
    link.write(Duration::ZERO, b"R14\r\n").expect("write");
    // R14 ends at its CR (4 bytes); the answer starts 100 µs later and takes 17 bytes
    // (`r 14 00001113 !\r\n`): it has left the board at 4 + 17 byte times + 100 µs =
    // 1.01 ms. Its `!` (byte 15, 0.92 ms) ends the line, which the host has at the end of
    // that USB frame, 1 ms.
    let answer_end = byte * 21 + 100 * US;
    let got = lines(&mut link, Duration::ZERO, 3 * MS);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].0, MS, "handed over at the end of its USB frame");
    assert_eq!(got[0].1.ty, ResponseType::Read);
    assert_eq!(sim.lock().expect("sim").stats().interlaced, 0);

    // The next command once the answer arrived: one at a time.
    link.write(3 * MS, b"R14\r\n").expect("write");
    let _ = lines(&mut link, 3 * MS, 6 * MS);
    assert_eq!(sim.lock().expect("sim").stats().interlaced, 0);

    // A command while the answer is still leaving the board: counted, and still
    // executed in turn (both answered, in order).
    let t = 10 * MS;
    link.write(t, b"R14\r\n").expect("write");
    let early = t + answer_end - byte * 3;
    link.write(early, b"R0D\r\n").expect("write");
    let got = lines(&mut link, t, t + 5 * MS);
    assert_eq!(sim.lock().expect("sim").stats().interlaced, 1);
    let registers: Vec<u8> = got.iter().map(|(_, line)| line.register).collect();
    assert_eq!(registers, [0x14, 0x0D]);
    // Its first byte beginning just after the answer's last byte ended is not early (1 µs:
    // the wire's and the board's byte times round apart by nanoseconds).
    link.write(20 * MS, b"R14\r\n").expect("write");
    link.write(20 * MS + answer_end + US, b"R14\r\n")
        .expect("write");
    let _ = lines(&mut link, 20 * MS, 25 * MS);
    assert_eq!(sim.lock().expect("sim").stats().interlaced, 1);
}

#[test]
fn the_stream_runs_on_the_1_95_ms_clock_and_its_stamps_count_it() {
    let (device, _sim) = shared(QsbSim::new(QsbSimConfig::default()));
    let mut link = SimLink::stream("usb", 230_400, device).with_host_frames(USB_FRAME);
    // EOR 5 (LF and the time stamp), INTERVAL RATE 1 (1.95 ms), THRESHOLD 0, S0E, each
    // after the previous answer arrived.
    let mut now = Duration::ZERO;
    for command in [&b"W155\r\n"[..], b"W0C1\r\n", b"W0B0\r\n", b"S0E\r\n"] {
        link.write(now, command).expect("write");
        now += 3 * MS;
        let _ = lines(&mut link, now - 3 * MS, now - 100 * US);
    }
    let got = lines(&mut link, now, now + 200 * MS);
    let stamps: Vec<u32> = got
        .iter()
        .filter(|(_, line)| line.ty == ResponseType::Stream)
        .map(|(_, line)| line.time_stamp.expect("EOR 5 stamps every line"))
        .collect();
    // "INTERVAL RATE … 1.95ms steps", the time stamp "incremented every 1.95ms": one line
    // a tick, each stamped one tick after the last; 200 ms is 102.4 ticks.
    assert!(
        (101..=103).contains(&stamps.len()),
        "{} lines",
        stamps.len()
    );
    assert!(stamps.windows(2).all(|w| w[1] == w[0] + 1), "{stamps:?}");
    // Each reaches the host at a USB frame end, never earlier than its wire time.
    assert!(got.iter().all(|(at, _)| at.as_micros() % 1000 == 0));
    let first = got.first().expect("lines").0;
    let last = got.last().expect("lines").0;
    let ticks = (last - first).as_secs_f64() / TICK.as_secs_f64();
    assert!((ticks - (stamps.len() - 1) as f64).abs() <= 1.0, "{ticks}");
}

/// A model shared between the wire and the test.
struct Shared(std::sync::Arc<std::sync::Mutex<QsbSim>>);

fn shared(sim: QsbSim) -> (Box<Shared>, std::sync::Arc<std::sync::Mutex<QsbSim>>) {
    let inner = std::sync::Arc::new(std::sync::Mutex::new(sim));
    (Box::new(Shared(inner.clone())), inner)
}

impl motion_link::sim::StreamDevice for Shared {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.0.lock().expect("sim").receive(now, bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.0.lock().expect("sim").transmit(now, out)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.0.lock().expect("sim").next_event(now)
    }
    fn baud(&self) -> Option<u32> {
        self.0.lock().expect("sim").baud()
    }
}
