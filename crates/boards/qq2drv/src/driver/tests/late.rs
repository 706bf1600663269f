//! Replies judged on their own time (issue 39 item 3): the board answers in the master's
//! later transactions, in order. A reply just inside its reply window is paired; one the
//! board streamed past for a whole window is lost (counted, the goal sent again) and its
//! late copy recognised, never taken for the resend's; MISO held back on the host is
//! waited for, however long, below `silence_ms`.

use super::*;

/// A running driver with channel 0's position goal in flight (16, 20): its MOSI.
fn goal_in_flight() -> (Qq2drvDriver, Duration, Vec<u8>) {
    let (mut driver, mut now) = running();
    // One tick at the poll period first: the cadence (and so the reply timeout) is 1 ms.
    now += MS;
    driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
    drain(&mut driver, now);
    let mosi = goal_packets(&mut driver, now, 0, Goal::Position { counts: 5.0 });
    assert_eq!(packets(&mosi).len(), 2);
    (driver, now, mosi)
}

#[test]
fn a_reply_just_inside_its_window_is_paired() {
    let (mut driver, mut now, mosi) = goal_in_flight();
    let deadline = now + driver.reply_timeout();
    while now + MS < deadline {
        now += MS;
        driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
        drain(&mut driver, now);
    }
    now = deadline - Duration::from_micros(10);
    driver.handle_rx(now, &acks(&mosi, 0));
    drain(&mut driver, now);
    assert!(!driver.goals_pending(), "acknowledged");
    assert_eq!(driver.status().timeouts, 0);
    assert_eq!(driver.late_replies(), 0);
}

#[test]
fn a_reply_the_board_streamed_past_is_lost_and_its_late_copy_never_paired() {
    let (mut driver, mut now, mosi) = goal_in_flight();
    let timeout = driver.reply_timeout();
    let deadline = now + timeout;
    // Stream packets past the deadline for just under a reply window: the reply could
    // still be behind them; the goal is not sent again.
    let mut first_after = None;
    while first_after.is_none_or(|first| now + MS < first + timeout) {
        now += MS;
        driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
        if now >= deadline {
            first_after.get_or_insert(now);
        }
        let sent = drain(&mut driver, now);
        assert!(!sent.contains(&mosi), "not sent again at {now:?}");
        assert_eq!(driver.status().timeouts, 0);
    }
    // Just outside: lost, counted, sent again.
    now += MS;
    driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
    let sent = drain(&mut driver, now);
    assert_eq!(driver.status().timeouts, 2, "both packets");
    assert!(sent.contains(&mosi), "the goal goes again");
    // Both replies come after all: the first pair answers the resend (the same packets),
    // the second finds nothing in flight and is recognised as late.
    let bad = driver.status().bad_replies;
    let mut twice = acks(&mosi, 0);
    twice.extend(acks(&mosi, 0));
    driver.handle_rx(now + MS, &twice);
    assert!(!driver.goals_pending());
    assert_eq!(driver.late_replies(), 2);
    assert_eq!(driver.status().bad_replies, bad, "late, not bad");
}

#[test]
fn miso_held_up_on_the_host_is_waited_for_and_paired() {
    for hold_ms in [50u64, 100, 200] {
        let (mut driver, mut now, mosi) = goal_in_flight();
        // Nothing comes back while held: the polls go on, nothing is lost or declared.
        let end = now + Duration::from_millis(hold_ms);
        while now < end {
            now += MS;
            let sent = drain(&mut driver, now);
            assert!(!sent.contains(&mosi), "hold {hold_ms} ms: not sent again");
        }
        // Then everything, in the board's order: a stream packet, the acks, the stream.
        let mut burst = ours_stream([0; 3], [0; 3], [0; 3]);
        burst.extend(acks(&mosi, 0));
        for _ in 0..hold_ms {
            burst.extend(ours_stream([0; 3], [0; 3], [0; 3]));
        }
        for chunk in burst.chunks(48) {
            driver.handle_rx(now, chunk);
        }
        drain(&mut driver, now);
        let status = driver.status();
        assert!(!driver.goals_pending(), "hold {hold_ms} ms");
        assert_eq!(status.timeouts, 0, "hold {hold_ms} ms");
        assert_eq!((status.verdicts, status.resets), (0, 0));
        assert!(status.online);
    }
}

#[test]
fn a_packet_partly_read_is_read_out_before_a_request() {
    // "Master reads out one entire packet" (SPI Interface): a transaction that ended in
    // the middle of a packet is followed by its rest, clocked with filler, before the
    // next request starts — in the request's own transaction, so it is not delayed.
    let (mut driver, now) = running();
    let stream = ours_stream([0; 3], [0; 3], [0; 3]);
    let (head, tail) = stream.split_at(10);
    driver.handle_rx(now, head);
    driver
        .set_goal(now, 0, Goal::Position { counts: 5.0 })
        .expect("goal");
    let sent = drain(&mut driver, now);
    let (filler, request) = sent[0].split_at(tail.len());
    assert!(filler.iter().all(|b| *b == FILLER), "the rest first");
    assert_eq!(packets(request).len(), 2, "then the goal's packets");
    // Only STX arrived: the size is unknown, so a poll reads on before any request.
    let (mut driver, now) = running();
    driver.handle_rx(now, &stream[..1]);
    driver
        .set_goal(now, 0, Goal::Position { counts: 5.0 })
        .expect("goal");
    let sent = drain(&mut driver, now);
    assert!(sent[0].iter().all(|b| *b == FILLER), "a poll");
    assert_eq!(sent.len(), 1);
    driver.handle_rx(now + MS, &stream[1..]);
    let sent = drain(&mut driver, now + 2 * MS);
    assert_eq!(sent[0].first(), Some(&2), "then the goal");
}

#[test]
fn a_request_that_does_not_fit_behind_the_rest_waits_for_a_poll() {
    // A caller's buffer too small for the rest of the packet and the request: the rest
    // alone first (motiond's messages are 256 bytes; a configuration is ~200).
    let (mut driver, now) = running();
    let stream = ours_stream([0; 3], [0; 3], [0; 3]);
    driver.handle_rx(now, &stream[..2]);
    // 31 bytes of the 33-byte stream packet to come; the goal's packets are 15.
    assert_eq!(driver.decoder.missing(), Some(stream.len() - 2));
    driver
        .set_goal(now, 0, Goal::Position { counts: 5.0 })
        .expect("goal");
    let mut buf = [0u8; 40];
    let sent = driver.poll_transmit(now, &mut buf).expect("a transaction");
    assert!(
        buf[..sent.len].iter().all(|b| *b == FILLER),
        "the rest, as a poll"
    );
    assert!(!sent.expects_reply);
    assert!(driver.goals_pending(), "the goal still waits");
    driver.handle_rx(now + MS, &stream[2..]);
    let later = now + 2 * MS;
    driver.handle_timeout(later);
    let sent = driver.poll_transmit(later, &mut buf).expect("the goal");
    assert_eq!(buf[0], 2, "the goal's request, from its first byte");
    assert_eq!(packets(&buf[..sent.len]).len(), 2);
}
