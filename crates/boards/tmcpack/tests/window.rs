//! The pack's reply window on the fake clock (manual 6.1, 7.1 "Interlacing of Requests":
//! "Requests must not be interlaced. Each request should wait for the response of the
//! PACK before transmitting a new command."), per kind of request, at 19200 baud with the
//! factory 6 ms switch-over and with 2 ms, with one pack and with two on one RS-485 bus.
//!
//! For a query in flight while some other request waits (a stop `$25`, a `$50` line start,
//! the `$14`/`$26`/`$23` of a goal, a `$20` poll, a `$43`, a start-up configuration word),
//! its answer is replayed just inside its window — request on the wire, 2 ms of the pack's
//! processing, the switch-over, answer on the wire, the 5 ms host latency — and just
//! outside it:
//! - inside: the answer is paired (a `$20`'s position reaches the channel) and nothing is
//!   sent before it and the pack's switch-over hold after it;
//! - outside: the query counts as a timeout, the late answer is recognised and dropped (a
//!   `$20`'s position never reaches the channel) and nothing is sent before the window and
//!   the `$41` packet timeout have passed.
//!
//! And a pack silent for 50, 100, 200 ms with a goal in progress is neither declared
//! reset nor not answering, and keeps its goal.

#[path = "window/line.rs"]
mod line;

use core::time::Duration;

use line::*;
use motion_drivers::{Driver, Goal, LINE_RATE_TOLERANCE, LineLeg};
use tmcpack::Request;

/// Just inside or just outside the window.
const EDGE: Duration = Duration::from_micros(500);

/// What waits while the held query is in flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Next {
    /// A stop: `$25` velocity 0 ([`motion_drivers::Priority::Stop`]).
    Stop,
    /// A position goal: `$14`, `$26`, `$23`.
    Goal,
    /// A prepared `$50` line, started.
    Line,
    /// The next `$20` poll.
    Poll,
    /// The held query is the `$43` reset check; the next poll waits.
    ResetCheck,
}

fn switchover(units: Option<u16>) -> Duration {
    units.map_or(FACTORY_SWITCHOVER, |u| u32::from(u) * 2 * MS)
}

/// The first request of `next`'s kind among `sent`.
fn is_next(next: Next, request: &Request) -> bool {
    match next {
        Next::Stop => matches!(request, Request::Rotate { velocity: 0, .. }),
        Next::Goal => matches!(
            request,
            Request::VelocityAcceleration { .. }
                | Request::SetTarget { .. }
                | Request::StartRamp { .. }
        ),
        Next::Line => matches!(request, Request::Interpolate { .. }),
        Next::Poll | Next::ResetCheck => matches!(request, Request::QueryPosition { .. }),
    }
}

/// Sets up `next` on `driver` of `line` (the line prepared before the query is held).
fn prepare(line: &mut Line, driver: usize, next: Next) {
    if next == Next::Line {
        let legs = [leg(0, 3000.0), leg(2, 1500.0)];
        let now = line.now;
        let d = line.bus.driver_mut(driver).expect("driver");
        assert_eq!(d.lead_line(now, &legs), Ok(true));
        assert!(line.run_until(500 * MS, |l| l.driver(driver).line_ready()));
    }
    if next == Next::ResetCheck {
        // The `$43` reset check is due once a second.
        line.run_for(1100 * MS);
    }
}

fn leg(channel: usize, counts: f64) -> LineLeg {
    LineLeg {
        channel,
        counts,
        velocity: 6425.0,
        accel: 64_250.0,
        rate_tolerance: LINE_RATE_TOLERANCE,
    }
}

/// Right after the held query went out: what must wait is asked for.
fn trigger(line: &mut Line, driver: usize, next: Next) {
    let now = line.now;
    let d = line.bus.driver_mut(driver).expect("driver");
    match next {
        Next::Stop => d
            .set_goal(now, 0, Goal::Stop { decel: 160_000.0 })
            .expect("stop"),
        Next::Goal => d
            .set_goal(now, 2, Goal::Position { counts: 4000.0 })
            .expect("goal"),
        Next::Line => d.start_line(now),
        Next::Poll | Next::ResetCheck => {}
    }
}

/// The held query's command and its answer's window on `packs` packs; `waiter` is the
/// driver whose request waits (the held pack is 0).
fn case(next: Next, units: Option<u16>, packs: usize, inside: bool) {
    let switchovers = vec![units; packs];
    let mut line = Line::online(&switchovers);
    line.run_for(100 * MS);
    let waiter = packs - 1;
    prepare(&mut line, waiter, next);
    let command = if next == Next::ResetCheck { 0x43 } else { 0x20 };
    let s = switchover(units);
    let window = window_end(Duration::ZERO, s);
    let delay = if inside { window - EDGE } else { window + EDGE };
    let before = line.driver(0).status();
    let late_before: u32 = line.bus.drivers().iter().map(|d| d.late_replies()).sum();
    let written = line.hold_next(0, command, delay);
    // In the step that wrote the held query (the clock has moved one step past it).
    trigger(&mut line, waiter, next);
    let arrives = written + delay;
    // Just after the held answer arrived: paired or not.
    line.run_until(window + MS, |l| l.now > arrives + STEP);
    let held = line
        .bus
        .drivers()
        .iter()
        .flat_map(|d| [d.channel(0), d.channel(2)])
        .any(|c| c.raw_counts == i64::from(HELD_POSITION));
    line.run_for(window + 40 * MS);
    let label = format!("{next:?} {units:?} {packs} pack(s) inside {inside}");
    let after = line.driver(0).status();
    let late: u32 = line.bus.drivers().iter().map(|d| d.late_replies()).sum();
    let first = line.sent_after(written);
    let first = first.first().expect("something was sent after");
    if inside {
        assert_eq!(after.timeouts, before.timeouts, "{label}: no timeout");
        assert_eq!(late, late_before, "{label}: not late");
        assert!(
            first.at >= arrives + s,
            "{label}: {:?} at {:?}, before the answer at {arrives:?} and the hold",
            first.request,
            first.at
        );
        if command == 0x20 {
            assert!(held, "{label}: the answer was paired");
        }
    } else {
        assert_eq!(after.timeouts, before.timeouts + 1, "{label}: a timeout");
        assert_eq!(late, late_before + 1, "{label}: recognised as late");
        let free = written + window + PACKET_TIMEOUT.max(s);
        assert!(
            first.at >= free,
            "{label}: {:?} at {:?}, before the window and the packet timeout ended at {free:?}",
            first.request,
            first.at
        );
        assert!(!held, "{label}: the late answer was paired");
    }
    // What waited went out after all, first of its driver's words (a stop before polls).
    let waited = line
        .sent_after(written)
        .into_iter()
        .find(|s| s.driver == waiter && is_next(next, &s.request));
    assert!(waited.is_some(), "{label}: {next:?} went out");
    assert!(
        line.bus
            .drivers()
            .iter()
            .all(|d| d.status().online && d.status().verdicts == 0),
        "{label}: no verdict"
    );
    line.check_never_interlaced();
}

fn all_cases(next: Next) {
    for units in [None, Some(1)] {
        for packs in [1, 2] {
            for inside in [true, false] {
                case(next, units, packs, inside);
            }
        }
    }
}

#[test]
fn a_stop_waits_for_the_answer_or_the_end_of_its_window() {
    all_cases(Next::Stop);
}

#[test]
fn a_goal_waits_for_the_answer_or_the_end_of_its_window() {
    all_cases(Next::Goal);
}

#[test]
fn a_50_line_start_waits_for_the_answer_or_the_end_of_its_window() {
    all_cases(Next::Line);
}

#[test]
fn a_20_poll_waits_for_the_answer_or_the_end_of_its_window() {
    all_cases(Next::Poll);
}

#[test]
fn the_43_reset_check_is_answered_inside_its_window_or_counted_late() {
    all_cases(Next::ResetCheck);
}

/// Start-up (manual 7.1 "Strategy for Parameter Setting"): the `$28` survey's answer just
/// inside its window is paired and the configuration's first word (`$40`) waits for it and
/// the hold; just outside, the configuration waits for the window and the packet timeout
/// (the pack has its factory settings: 6 ms switch-over, our reading of its packet timeout
/// 20 ms), the late answer is dropped, and the survey is asked again.
#[test]
fn the_start_up_survey_is_answered_inside_its_window_or_counted_late() {
    for inside in [true, false] {
        let mut line = Line::new(vec![config(1, Some(1), 1)]);
        let window = window_end(Duration::ZERO, FACTORY_SWITCHOVER);
        let delay = if inside { window - EDGE } else { window + EDGE };
        let written = line.hold_next(0, 0x28, delay);
        assert!(line.run_until(2000 * MS, |l| l.driver(0).status().online));
        let after = line.sent_after(written);
        let first = after.first().expect("the start-up went on");
        let d = line.driver(0);
        if inside {
            assert_eq!(d.status().timeouts, 0);
            assert_eq!(d.late_replies(), 0);
            assert!(
                matches!(first.request, Request::SetBaud { .. }),
                "{first:?}"
            );
            assert!(first.at >= written + delay + FACTORY_SWITCHOVER);
        } else {
            assert_eq!(d.status().timeouts, 1);
            assert_eq!(d.late_replies(), 1);
            // The factory packet timeout the driver assumes (20 ms) until it programs $41.
            assert!(first.at >= written + window + 20 * MS, "{first:?}");
            // Its late answer came (and went) during the quiet time: asked again.
            assert!(
                matches!(first.request, Request::QueryActions { .. }),
                "{first:?}"
            );
        }
        assert_eq!(line.driver(0).status().verdicts, 0);
        line.check_never_interlaced();
    }
}

/// A pack whose configs have motor 0 only: every poll is `$20` motor 0.
fn one_motor(address: u8, packs: u8) -> board_tmcpack::driver::TmcpackDriverConfig {
    let mut c = config(address, Some(1), packs);
    c.channels[2] = None;
    c
}

/// The late answer of a `$20` comes after the next query went out (its host held it that
/// long): never paired. With one pack, the driver asks nothing whose answer begins like it
/// (its poll of the same motor waits, a probe goes); with two packs on one bus the other
/// pack's driver, whose only poll would look the same, is told by the bus and probes too;
/// the late word is recognised wherever it lands.
#[test]
fn a_late_answer_after_the_next_query_is_never_paired() {
    for packs in [1u8, 2] {
        let configs = (1..=packs).map(|a| one_motor(a, packs)).collect();
        let mut line = Line::online_with(configs);
        line.run_for(100 * MS);
        let window = window_end(Duration::ZERO, 2 * MS);
        // The next query goes at the window + the packet timeout; the late answer comes
        // 3 ms into it.
        let delay = window + PACKET_TIMEOUT + 3 * MS + 2 * STEP;
        let written = line.hold_next(0, 0x20, delay);
        let arrives = written + delay;
        let mut paired = false;
        while line.now < arrives + 30 * MS {
            line.step();
            paired |= line
                .bus
                .drivers()
                .iter()
                .any(|d| d.channel(0).raw_counts == i64::from(HELD_POSITION));
        }
        assert!(!paired, "{packs} pack(s): the late answer was paired");
        let in_flight = line
            .sent
            .iter()
            .rev()
            .find(|s| s.at <= arrives && s.request.command().has_reply())
            .expect("a query in flight when the late answer came");
        assert!(in_flight.at > written, "the next query was out");
        assert!(
            !matches!(in_flight.request, Request::QueryPosition { motor: 0, .. }),
            "{packs} pack(s): asked what the late answer looks like: {:?}",
            in_flight.request
        );
        let late: u32 = line.bus.drivers().iter().map(|d| d.late_replies()).sum();
        assert_eq!(late, 1, "{packs} pack(s)");
        // The pack answers again: its late answers are forgotten, the polls go on.
        line.run_for(200 * MS);
        let polled = line
            .sent_after(arrives + 30 * MS)
            .iter()
            .filter(|s| {
                s.driver == 0 && matches!(s.request, Request::QueryPosition { motor: 0, .. })
            })
            .count();
        assert!(polled > 0, "{packs} pack(s): motor 0 polled again");
        assert!(line.bus.drivers().iter().all(|d| d.status().verdicts == 0));
        line.check_never_interlaced();
    }
}

/// Start-up: before the driver has programmed `$40` in this run, the pack has either the
/// factory 6 ms (it rebooted) or the configured switch-over (a previous run programmed it,
/// and a pack keeps it until a reset): the first `$43` waits for the longer. A pack left at
/// 20 ms answers at the end of that window and is paired, not counted unanswered; with the
/// factory delay the window is 6 ms shorter than that and the answer just inside it pairs.
#[test]
fn before_40_the_window_holds_the_longer_of_the_factory_and_the_configured_switch_over() {
    for (units, left_at) in [(10u16, 20 * MS), (1, FACTORY_SWITCHOVER)] {
        let mut line = Line::new(vec![config(1, Some(units), 1)]);
        line.set_switchover(0, left_at);
        let window = window_end(Duration::ZERO, left_at.max(FACTORY_SWITCHOVER));
        line.hold_next(0, 0x43, window - EDGE);
        assert!(line.run_until(2000 * MS, |l| l.driver(0).status().online));
        let d = line.driver(0);
        assert_eq!(d.status().timeouts, 0, "{units} units");
        assert_eq!(d.late_replies(), 0, "{units} units");
        line.check_never_interlaced();
    }
}
