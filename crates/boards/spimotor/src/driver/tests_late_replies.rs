//! A reply the tick takes in late (a busy machine, a late tick or I/O thread) must not make
//! the polls after it look implausible: the plausibility window of a moving stepper runs
//! from when each position read was on the wire, not from when its reply was taken in.
//! Measured from the take-in, one reply taken in 20 ms late shortened every later window
//! by 20 ms, each following poll of a motor cruising at 2000 steps/s looked 40 steps too
//! far, and after [`PROTOCOL_LIMIT`](super::PROTOCOL_LIMIT) of them the axis faulted
//! "its board's replies could not be decoded" in the middle of a move (seen on the
//! default robot's `focus` axis under load).

use core::time::Duration;

use super::tests::{Bench, stepper};
use motion_drivers::{DeviceFault, Driver, Goal};

const MS: Duration = Duration::from_millis(1);

/// Walks the scripted board towards its target at its step delay (tenths of a
/// millisecond a step) for `dt`; `carry` keeps the fraction of a step.
fn walk(bench: &mut Bench, dt: Duration, carry: &mut f64) {
    let board = &mut bench.board;
    let gap = i64::from(board.target) - i64::from(board.position);
    if gap == 0 {
        *carry = 0.0;
        return;
    }
    *carry += 10_000.0 / f64::from(board.delay.max(1)) * dt.as_secs_f64();
    let steps = carry.floor();
    *carry -= steps;
    let walked = (steps as i64).min(gap.abs());
    board.position = (i64::from(board.position) + gap.signum() * walked) as i32;
}

/// One engine-like step with a board that steps: what the driver sends is answered from
/// the board as it is now; its MISO is taken in at the next step, or `late` after it when
/// this step read the step delay (the last read of a poll: the poll is then taken in
/// late, while its position was read on time). Whether it read the step delay.
fn step(bench: &mut Bench, carry: &mut f64, late: Duration) -> bool {
    bench.driver.handle_timeout(bench.now);
    let mut miso = Vec::new();
    let mut buf = [0u8; 256];
    let mut delay_read = false;
    while bench.driver.wants_transmit(bench.now).is_some() {
        let transmit = bench
            .driver
            .poll_transmit(bench.now, &mut buf)
            .expect("sends");
        let mosi = &buf[..transmit.len];
        // Address 0x90 with the read bit, port 0x43 (SPI_motor "Motor protocol" page).
        delay_read |= mosi.starts_with(&[0x91, 0x43]);
        miso.extend(bench.board.transfer(mosi));
    }
    let late = if delay_read { late } else { Duration::ZERO };
    walk(bench, MS + late, carry);
    bench.now += MS + late;
    bench.driver.handle_rx(bench.now, &miso);
    delay_read
}

#[test]
fn a_reply_taken_in_late_does_not_make_the_polls_after_it_implausible() {
    let mut bench = Bench::started(stepper());
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 100_000.0 })
        .unwrap();
    let mut carry = 0.0;
    // Up to speed: 2000 steps/s (delay 5) after 0.1 s at 20 000 steps/s².
    for _ in 0..400 {
        let _ = step(&mut bench, &mut carry, Duration::ZERO);
    }
    assert_eq!(bench.board.delay, 5, "cruising at max velocity");
    let bad_before = bench.driver.status().bad_replies;
    let position_before = bench.board.position;

    while !step(&mut bench, &mut carry, 20 * MS) {}
    for _ in 0..500 {
        let _ = step(&mut bench, &mut carry, Duration::ZERO);
        assert_eq!(
            bench.driver.channel(0).fault,
            None,
            "faulted at board position {}",
            bench.board.position
        );
    }
    let bad = bench.driver.status().bad_replies - bad_before;
    assert!(bad <= 1, "{bad} polls discarded after one late reply");
    // Still cruising, and the axis follows the board.
    let walked = bench.board.position - position_before;
    assert!(walked > 900, "walked {walked} steps in 0.52 s");
    let seen = bench.driver.channel(0).position;
    assert!(
        (f64::from(bench.board.position) - seen).abs() < 60.0,
        "the channel follows: {seen} vs {}",
        bench.board.position
    );
}

/// Ticks the driver while the host holds every MISO byte back (a starved SPI socket peer
/// or server: the transactions run, their MISO waits); returns the bytes held.
fn hold_miso_until(bench: &mut Bench, until: Duration) -> Vec<u8> {
    let mut held = Vec::new();
    let mut buf = [0u8; 256];
    while bench.now < until {
        bench.driver.handle_timeout(bench.now);
        while bench.driver.wants_transmit(bench.now).is_some() {
            let transmit = bench
                .driver
                .poll_transmit(bench.now, &mut buf)
                .expect("sends");
            held.extend(bench.board.transfer(&buf[..transmit.len]));
        }
        bench.now += MS;
    }
    held
}

#[test]
fn miso_held_just_inside_silence_ms_is_taken() {
    let mut bench = Bench::started(stepper());
    let from = bench.now;
    let silence = bench.driver.config().silence;
    // The oldest transaction held goes out at `from`: its MISO may stay away until
    // `from + silence`.
    let held = hold_miso_until(&mut bench, from + silence - MS);
    assert!(!held.is_empty());
    bench.driver.handle_timeout(bench.now);
    let status = bench.driver.status();
    assert_eq!((status.verdicts, status.timeouts), (0, 0));
    assert!(status.online);
    for chunk in held.chunks(7) {
        bench.driver.handle_rx(bench.now, chunk);
    }
    assert_eq!(bench.driver.late_miso(), 0);
    assert!(
        bench
            .driver
            .channel(0)
            .refreshed_at
            .is_some_and(|at| at == bench.now)
    );
    assert_eq!(bench.driver.channel(0).fault, None);
    bench.steps(10);
    assert_eq!(bench.driver.status().verdicts, 0);
}

#[test]
fn miso_held_past_silence_ms_is_not_answering_and_comes_late_never_misread() {
    let mut bench = Bench::started(stepper());
    let from = bench.now;
    let silence = bench.driver.config().silence;
    let held = hold_miso_until(&mut bench, from + silence + MS);
    bench.driver.handle_timeout(bench.now);
    let status = bench.driver.status();
    assert_eq!(status.fault, Some(DeviceFault::NotResponding));
    assert_eq!(status.timeouts, 1, "counted as a timeout");
    let evidence = status.verdict.expect("verdict").evidence;
    assert!(
        evidence.as_str().starts_with("MISO of ")
            && evidence
                .as_str()
                .contains("transactions not back; the oldest (read port 0x")
            && evidence.as_str().ends_with("(silence_ms 500)"),
        "{}",
        evidence.as_str()
    );
    // The start-up begins again (its identification read goes out), then the held bytes
    // come, before that read's own: recognised as late, not taken for its answer.
    let mut buf = [0u8; 256];
    let transmit = bench
        .driver
        .poll_transmit(bench.now, &mut buf)
        .expect("the identification read");
    assert_eq!(&buf[..2], &[0x91, 0x01]);
    let own = bench.board.transfer(&buf[..transmit.len]);
    let mut late_and_own = held.clone();
    late_and_own.extend(own);
    bench.now += MS;
    for chunk in late_and_own.chunks(7) {
        bench.driver.handle_rx(bench.now, chunk);
    }
    assert_eq!(bench.driver.late_miso(), held.len() as u64);
    // The identification was read from its own bytes: the start-up goes on and the board
    // is back.
    bench.steps(20);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.channel(0).fault, None);
    assert_eq!(bench.driver.status().verdicts, 1);
}
