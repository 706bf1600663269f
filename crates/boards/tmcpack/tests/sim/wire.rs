//! Wire rules: switch-over timing, baud change, one request in flight, packet timeout, a shared RS-485 pair.

use std::sync::{Arc, Mutex};

use super::host::*;

/// Manual 6.1: "an instruction will be transmitted only after an adjustable transmitter
/// switchover time (s. CMD $40; pre-set to 6ms) has passed"; bytes follow back to back. The
/// firmware acts on the word in its next 2 ms cycle (6.2's "approx. 2 ms per command").
#[test]
fn manual_6_1_reply_starts_after_switchover_delay() {
    let mut h = pack();
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    let got = h.wait(40 * MS);
    assert_eq!(got.len(), 9);
    for (k, (t, _)) in got.iter().enumerate() {
        assert_eq!(*t, cycle(end) + 6 * MS + bt() * k as u32, "byte {k}");
    }
    let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
    assert_eq!(
        ReplyFrame::decode(&bytes).map(|f| f.reply),
        Ok(Reply::UnitInfo {
            firmware: 149,
            reset: true,
            temperature: 35,
            serial: 1001
        })
    );
    // $40 with the same divisor and a 20 ms switch-over delay.
    h.send(
        1,
        Request::SetBaud {
            divisor: 65,
            switchover: 10,
        },
    );
    let (first, f) = h
        .query(1, Request::UnitInfo { reply_to: HOST })
        .expect("reply");
    assert!(first > end);
    assert!(
        matches!(f.reply, Reply::UnitInfo { reset: false, .. }),
        "reset flag read once"
    );
    // The pack drives the pair for the switch-over time after its answer, too.
    h.wait(10 * MS);
    let end = h.send(
        1,
        Request::QueryVelocity {
            motor: 0,
            reply_to: HOST,
        },
    );
    let got = h.wait(60 * MS);
    assert_eq!(got.first().map(|g| g.0), Some(cycle(end) + 20 * MS));
}

/// Manual 8.6 $40: "baud rate divisor=20MHz/(16*baud rate)": the pack listens at the new
/// rate at once and answers with the new byte time.
#[test]
fn manual_8_6_baud_change_40() {
    let mut h = pack();
    assert_eq!(h.dev.baud(), Some(19_200));
    h.send(
        1,
        Request::SetBaud {
            divisor: 11,
            switchover: 1,
        },
    );
    assert_eq!(h.dev.baud(), Some(115_200));
    h.bt = byte_time(115_200);
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    let got = h.wait(20 * MS);
    assert_eq!(got.len(), 9);
    assert_eq!(got[0].0, cycle(end) + 2 * MS);
    assert_eq!(got[8].0 - got[0].0, byte_time(115_200) * 8);
}

/// 7.1 "Requests must not be interlaced": a second query before the first answer replaces
/// it; bytes sent while the pack drives the pair are lost, and the pack resyncs after the
/// packet timeout.
#[test]
fn manual_7_1_interlaced_requests() {
    let mut h = pack();
    h.send(
        1,
        Request::QueryVelocity {
            motor: 0,
            reply_to: HOST,
        },
    );
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    let got = h.wait(40 * MS);
    let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
    assert_eq!(bytes.len(), 9, "one answer");
    assert_eq!(bytes[1], 0x43);
    assert_eq!(got[0].0, cycle(end) + 6 * MS);
    assert_eq!(h.dev.stats().replaced_replies, 1);
    assert_eq!(
        h.dev.stats().interlaced,
        1,
        "the $43 began while $21's answer was due"
    );
    // A request sent into the answer: the pack does not hear it.
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    h.now = cycle(end) + 6 * MS + 2 * bt();
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: 1000,
        },
    );
    let got = h.wait(200 * MS);
    assert_eq!(got.len(), 9);
    assert_eq!(h.dev.motor(0).expect("m0").action, Action::Inactive, "lost");
    assert!(h.dev.stats().lost_bytes > 0);
    let (_, f) = h
        .query(
            1,
            Request::QueryVelocity {
                motor: 0,
                reply_to: HOST,
            },
        )
        .expect("in step again");
    assert!(matches!(f.reply, Reply::Velocity { .. }));
    assert_eq!(
        h.dev.stats().interlaced,
        2,
        "the $23 began inside the answer"
    );
}

/// Manual 6.1: an incomplete word is aborted after the packet timeout, so garbage followed
/// by a pause does not upset the next request; $41 changes the timeout.
#[test]
fn manual_6_1_packet_timeout_resync() {
    let mut h = pack();
    h.send_raw(&[1, 0x23, 0, 0x55]);
    h.wait(25 * MS);
    let (_, f) = h
        .query(1, Request::UnitInfo { reply_to: HOST })
        .expect("reply");
    assert!(matches!(f.reply, Reply::UnitInfo { .. }));
    assert_eq!(h.dev.stats().aborted, 1);
    h.send(1, Request::PacketTimeout { timeout: 100 });
    h.send_raw(&[1, 0x23, 0]);
    h.wait(25 * MS);
    // Within 200 ms the rest completes the word ($23 motor 0 to $001000).
    h.send_raw(&[0, 0x10, 0, 0, 0, 0]);
    h.wait(4 * MS);
    assert_eq!(h.dev.motor(0).expect("m0").action, Action::Ramp);
    h.send_raw(&[0xAA; 3]);
    let now = h.now;
    h.dev.line_break(now);
    assert_eq!(h.dev.stats().aborted, 2);
}

/// A pack shared with the test through the bus.
struct Shared(Arc<Mutex<TmcpackSim>>);

impl StreamDevice for Shared {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.0.lock().expect("lock").receive(now, bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.0.lock().expect("lock").transmit(now, out)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.0.lock().expect("lock").next_event(now)
    }
    fn baud(&self) -> Option<u32> {
        self.0.lock().expect("lock").baud()
    }
}

/// Two packs, addresses 1 and 2, on one RS-485 pair: each answers only its own address,
/// hears the other's replies as foreign words and stays in step (6.1).
#[test]
fn two_packs_on_one_bus_answer_only_their_address() {
    let p1 = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig {
        address: 1,
        ..Default::default()
    })));
    let p2 = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig {
        address: 2,
        seed: 9,
        ..Default::default()
    })));
    let bus = StreamBus::new()
        .with(Box::new(Shared(p1.clone())))
        .with(Box::new(Shared(p2.clone())));
    let mut h = Host::new(bus);
    for round in 0..5 {
        for (addr, motor) in [(1u8, 0u8), (2, 1)] {
            let target = 1000 * i32::from(addr) + round;
            h.send(
                addr,
                Request::SetPosition {
                    motor,
                    position: target,
                },
            );
            let (_, f) = h
                .query(
                    addr,
                    Request::QueryPosition {
                        motor,
                        reply_to: HOST,
                    },
                )
                .expect("answer");
            assert_eq!(f.address, HOST);
            assert!(matches!(f.reply, Reply::Position { position, .. } if position == target));
        }
    }
    assert!(
        h.query(3, Request::UnitInfo { reply_to: HOST }).is_none(),
        "nobody at 3"
    );
    let (s1, s2) = (
        p1.lock().expect("lock").stats(),
        p2.lock().expect("lock").stats(),
    );
    assert_eq!((s1.replies, s2.replies), (5, 5));
    // Each heard the other's 5 requests, 5 set-positions, 5 replies, and the query to 3.
    assert_eq!((s1.foreign, s2.foreign), (16, 16));
    assert_eq!(
        (s1.aborted, s2.aborted, s1.invalid, s2.invalid),
        (0, 0, 0, 0)
    );
    assert_eq!(
        p1.lock().expect("lock").motor(1).expect("m1").position,
        0,
        "pack 1 untouched by pack 2's words"
    );
}

/// The pack cannot tell a reply from a request: a word is a request for the pack whose
/// address is its first byte (6.1). So the response address a host gives must be one no
/// pack on the bus uses — a reply sent to pack 1's address is executed by pack 1.
#[test]
fn a_reply_sent_to_a_pack_address_is_a_request_for_that_pack() {
    let p1 = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let p2 = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig {
        address: 2,
        ..Default::default()
    })));
    let bus = StreamBus::new()
        .with(Box::new(Shared(p1.clone())))
        .with(Box::new(Shared(p2.clone())));
    let mut h = Host::new(bus);
    h.send(2, Request::UnitInfo { reply_to: 1 });
    let got: Vec<u8> = h.wait(60 * MS).iter().map(|(_, b)| *b).collect();
    // Pack 2 answers to "1"; pack 1 takes that as $43 with response address 149 (the
    // firmware revision byte) and answers it.
    assert_eq!(got.len(), 18);
    assert_eq!(got[..9], [1, 0x43, 149, 1, 35, 0xE9, 0x03, 0, 0]);
    assert_eq!(got[9..11], [149, 0x43]);
    assert_eq!(p1.lock().expect("lock").stats().executed, 1);
}

/// End to end through motion-link's simulated RS-485 pair at 19200 baud: a $43 round trip
/// takes a word each way plus the 6 ms switch-over (docs/ARCHITECTURE.md: ~15 ms).
#[test]
fn round_trip_through_a_half_duplex_sim_link() {
    use motion_link::Link;
    use motion_link::sim::{Duplex, SimLink};
    let pack = Box::new(TmcpackSim::new(TmcpackSimConfig::default()));
    let mut link = SimLink::stream_with("rs485", 19_200, Duplex::Half, pack);
    let t0 = Duration::from_secs(1);
    let w = RequestFrame::new(1, Request::UnitInfo { reply_to: HOST })
        .to_word()
        .expect("valid");
    assert_eq!(link.write(t0, &w).expect("write"), 9);
    let (mut got, mut t) = (Vec::new(), t0);
    while got.len() < 9 && t < t0 + 100 * MS {
        t += Duration::from_micros(10);
        let mut buf = [0u8; 16];
        let n = link.read(t, &mut buf).expect("read");
        got.extend_from_slice(&buf[..n]);
    }
    let f = ReplyFrame::decode(&got).expect("reply");
    assert!(matches!(f.reply, Reply::UnitInfo { firmware: 149, .. }));
    let rtt = t - t0;
    let expected = (cycle(t0 + bt() * 9) - t0) + bt() * 9 + 6 * MS;
    assert!(
        rtt >= expected && rtt < expected + Duration::from_micros(20),
        "{rtt:?}"
    );
}

/// Manual 6.1 "The PACK continues to drive the line for a pre-set time after transmitting
/// a message" and 7.1 "Requests must not be interlaced": a request that begins before the
/// answer and that hold are over is counted as interlaced; one that begins as the hold
/// ends is not. A delayed `$28` answer may be outstanding in parallel ("However a delayed
/// response with RS 232 may be outstanding in parallel"): a request meanwhile is not.
#[test]
fn manual_7_1_a_request_inside_the_answer_or_its_hold_is_interlaced() {
    let mut h = pack();
    // Factory switch-over 6 ms, before and after the 9-byte answer.
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    let free = cycle(end) + 6 * MS + bt() * 9 + 6 * MS;
    h.collect_until(free);
    assert_eq!(h.now, free);
    h.send(
        1,
        Request::QueryVelocity {
            motor: 0,
            reply_to: HOST,
        },
    );
    assert_eq!(h.dev.stats().interlaced, 0, "began as the hold ended");
    let end = h.now;
    let free = cycle(end) + 6 * MS + bt() * 9 + 6 * MS;
    h.collect_until(free - bt());
    h.send(
        1,
        Request::QueryVelocity {
            motor: 1,
            reply_to: HOST,
        },
    );
    assert_eq!(
        h.dev.stats().interlaced,
        1,
        "began a byte before the hold ended"
    );
    h.wait(40 * MS);
    // A delayed $28 of a running motor, then a query: not interlaced, both answered.
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: 200_000,
        },
    );
    h.wait(10 * MS);
    h.send(
        1,
        Request::QueryActions {
            reply_to: HOST,
            delay_mask: MotorMask::M0,
        },
    );
    assert!(h.wait(10 * MS).is_empty(), "the $28 answer is delayed");
    let (_, f) = h
        .query(
            1,
            Request::QueryVelocity {
                motor: 0,
                reply_to: HOST,
            },
        )
        .expect("answered");
    assert!(matches!(f.reply, Reply::Velocity { .. }));
    assert_eq!(h.dev.stats().interlaced, 1, "none more");
}
