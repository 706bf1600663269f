//! Unit tests of the tmcpack driver against byte vectors of the tmcpack codec and the
//! manual.

use core::time::Duration;

use tmcpack::{Action, Reply, Request, RequestFrame};

use super::bench::*;
use super::*;
use motion_drivers::GoalKind;

#[test]
fn startup_reads_unit_info_then_writes_the_manual_parameters() {
    let mut bench = Bench::new(config());
    let sent = bench.online();
    assert_eq!(bench.driver.status().firmware(), "SIXpack V1.4.9 s/n 1001");
    // $40: divisor 20 MHz / (16 · 19200) = 65 (the link's own rate), switch-over 1 · 2 ms.
    assert_eq!(
        sent[0],
        Request::SetBaud {
            divisor: 65,
            switchover: 1
        }
    );
    // $41: 11 byte times at 19200 baud = 5.7 ms → 3 units of 2 ms.
    assert_eq!(sent[1], Request::PacketTimeout { timeout: 3 });
    // $12 clkdiv for 32000 µsteps/s at v = 511, div = 0 (8.2).
    assert_eq!(sent[2], Request::VelocitySetting { clkdiv: 18 });
    assert!(sent.contains(&Request::VelocityAcceleration {
        motor: 0,
        amax: 318,
        vmax: 498
    }));
    assert!(sent.contains(&Request::StartingVelocity {
        motor: 0,
        vmin: 0,
        vstart: 5,
        div: 0
    }));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::StartingVelocity {
            motor: 2,
            div: 3,
            ..
        }
    )));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::ReferenceParameters { motor: 0, flags, .. } if flags.bits() == 1
    )));
    assert!(
        sent.iter()
            .all(|r| r.motor().is_none_or(|m| m == 0 || m == 2)),
        "unconfigured motors are left alone"
    );
}

#[test]
fn the_first_bytes_on_the_wire_are_the_manual_word_for_43() {
    // Manual 8.6 $43: CMD $43, P0 response address; 6.1: address, command, P0..P6.
    let mut bench = Bench::new(config());
    let (at, w) = bench.next(5).expect("$43");
    assert_eq!(at, Duration::ZERO);
    assert_eq!(w, [0x01, 0x43, 0xFE, 0, 0, 0, 0, 0, 0]);
    assert!(bench.driver.awaiting_reply());
}

#[test]
fn the_line_stays_reserved_for_the_switchover_after_an_answer() {
    let mut bench = Bench::new(config());
    bench.next(5).expect("$43");
    bench.now = 15 * MS;
    bench.rx(&UNIT_INFO);
    // Factory switch-over: 6 ms of the pack driving the line after its answer.
    assert!(bench.driver.awaiting_reply());
    bench.driver.handle_timeout(20 * MS);
    assert!(bench.driver.awaiting_reply());
    bench.driver.handle_timeout(21 * MS);
    assert!(!bench.driver.awaiting_reply());
}

#[test]
fn a_request_without_answer_reserves_the_line_for_the_packet_timeout() {
    let mut bench = Bench::new(config());
    bench.next(5).expect("$43");
    bench.now += 11 * MS;
    bench.rx(&UNIT_INFO);
    bench.survey([Action::Inactive; 6]);
    let (t40, _) = bench.next(40).expect("$40");
    let (t41, w41) = bench.next(40).expect("$41");
    let (t12, _) = bench.next(40).expect("$12");
    let (t10, _) = bench.next(40).expect("$11");
    // Manual 8.6 $41: P0,P1 timeout in 2 ms units, LSB first.
    assert_eq!(w41, [0x01, 0x41, 3, 0, 0, 0, 0, 0, 0]);
    // Until $41 the pack may have its factory timeout (assumed 20 ms): a word torn by noise
    // must be aborted before the next word starts, so the next one waits for it.
    assert_eq!(t41 - t40, 20 * MS);
    // Then 6 ms: longer than one word's 4.69 ms wire time, and the pack's new timeout.
    assert_eq!(t12 - t41, 6 * MS);
    assert_eq!(t10 - t12, 6 * MS);
}

/// A pack that never answers is declared not answering once at least `MAX_TIMEOUTS`
/// requests went unanswered in a row and the first was written `silence_ms` before
/// (default 500 ms), not at its third timeout; the verdict names its evidence.
#[test]
fn a_silent_pack_is_declared_not_answering_after_the_silence_with_its_evidence() {
    let mut bench = Bench::new(config());
    let mut asked = Vec::new();
    let mut declared = None;
    for _ in 0..1200 {
        let at = bench.now;
        if let Some(w) = bench.tick() {
            asked.push((at, w));
        }
        let status = bench.driver.status();
        if declared.is_none() && status.fault == Some(DeviceFault::NotResponding) {
            declared = Some(at);
            assert!(status.timeouts >= MAX_TIMEOUTS);
        }
    }
    let declared = declared.expect("declared");
    assert!(declared >= motion_drivers::DEFAULT_SILENCE, "{declared:?}");
    assert!(
        declared < motion_drivers::DEFAULT_SILENCE + 60 * MS,
        "{declared:?}"
    );
    assert!(asked.len() >= 3);
    // `$43`, and while an unanswered `$43` may still be answered late, probes whose answer
    // cannot be taken for it (module `late`): `$21` / `$30`, nothing that changes the pack.
    assert_eq!(asked[0].1[1], 0x43);
    assert!(
        asked
            .iter()
            .all(|(_, w)| matches!(w[1], 0x43 | 0x21 | 0x30)),
        "{asked:?}"
    );
    let status = bench.driver.status();
    assert!(!status.online);
    assert_eq!(status.fault, Some(DeviceFault::NotResponding));
    assert_eq!(status.verdicts, 1, "declared once, not at every retry");
    let verdict = status.verdict.expect("a verdict");
    assert_eq!(verdict.fault, DeviceFault::NotResponding);
    assert_eq!(verdict.at, declared);
    let evidence = verdict.evidence.as_str();
    assert!(
        evidence.contains("requests unanswered in a row since 0.000 s")
            && evidence.contains("the last, `$")
            && evidence.contains("written at")
            && evidence.contains("due by")
            && evidence.contains("the link heard until"),
        "{evidence}"
    );
    assert_eq!(
        bench.driver.channel(0).fault,
        Some(DeviceFault::NotResponding)
    );
    assert_eq!(
        bench
            .driver
            .set_goal(bench.now, 0, Goal::Stop { decel: 1.0 }),
        Err(GoalError::Offline)
    );
    // Retries keep coming, spaced by the retry period once declared dead.
    let after: Vec<Duration> = asked
        .iter()
        .filter(|(at, _)| *at > declared)
        .map(|(at, _)| *at)
        .collect();
    assert!(after.len() >= 2, "{after:?}");
    assert!(after[0] >= declared + RETRY_PERIOD);
    assert!(
        after.windows(2).all(|w| w[1] - w[0] >= RETRY_PERIOD),
        "{after:?}"
    );
}

#[test]
fn polls_round_robin_over_configured_motors_and_fill_the_channel_state() {
    let mut bench = Bench::new(config());
    bench.online();
    let sent = bench.serve(200, |motor| position(motor, 1000, Action::Inactive));
    let polled: Vec<u8> = sent
        .iter()
        .filter_map(|r| match r {
            Request::QueryPosition { motor, reply_to } => {
                assert_eq!(*reply_to, 0xFE);
                Some(*motor)
            }
            _ => None,
        })
        .collect();
    assert!(polled.len() > 6);
    assert!(polled.windows(2).all(|w| w[0] != w[1]));
    let state = bench.driver.channel(0);
    assert_eq!(state.position, 1000.0);
    assert_eq!(state.raw_counts, 1000);
    assert!(!state.moving);
    assert_eq!(state.fault, None);
    assert!(state.refreshed_at.is_some());
    assert_eq!(bench.driver.channel(1), ChannelState::UNKNOWN);
}

#[test]
fn garbage_before_an_answer_is_skipped() {
    let mut bench = Bench::new(config());
    bench.online();
    let (_, w) = bench.next(50).expect("poll");
    assert_eq!(w[1], 0x20);
    bench.now += 10 * MS;
    let mut bytes = vec![0x55, 0xFE, 0x20, 0x99];
    bytes.extend_from_slice(&position(w[2], -42, Action::Ramp));
    bench.rx(&bytes);
    let state = bench.driver.channel(usize::from(w[2]));
    assert_eq!(state.position, -42.0);
    assert!(state.moving);
    assert!(bench.driver.status().bad_replies >= 1);
}

#[test]
fn velocity_goal_is_a_rotation_with_the_8_2_scale() {
    let mut bench = Bench::new(config());
    bench.online();
    // 16000 µsteps/s at clkdiv 18, div 0 (64.25 Hz per unit) = 249.0 → 249.
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: -16_000.0,
                accel: 80_000.0,
            },
        )
        .expect("accepted");
    assert!(bench.driver.goals_pending());
    // amax = 80000 · 64 / 500 / 64.25 = 159.4 → 159, vmax stays the axis limit.
    assert_eq!(
        bench.request(),
        Request::VelocityAcceleration {
            motor: 0,
            amax: 159,
            vmax: 498
        }
    );
    let (_, w) = bench.next(20).expect("$25");
    // $25: motnr, velocity LSB first: -249 = 0xFF07.
    assert_eq!(w, [0x01, 0x25, 0x00, 0x07, 0xFF, 0, 0, 0, 0]);
    assert!(!bench.driver.goals_pending());
}

#[test]
fn ramp_position_sets_target_then_starts_the_ramp() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::RampPosition {
                counts: 10_000.0,
                velocity: 6425.0,
                accel: 160_000.0,
            },
        )
        .expect("accepted");
    assert_eq!(
        bench.request(),
        Request::VelocityAcceleration {
            motor: 0,
            amax: 318,
            vmax: 100
        }
    );
    // Manual 7.2: $26 motor, target LSB first (10000 = $2710), then $23 likewise.
    let (_, w26) = bench.next(20).expect("$26");
    assert_eq!(w26, [0x01, 0x26, 0x00, 0x10, 0x27, 0, 0, 0, 0]);
    let (_, w23) = bench.next(20).expect("$23");
    assert_eq!(w23, [0x01, 0x23, 0x00, 0x10, 0x27, 0, 0, 0, 0]);
    // Arrival: a poll sent after the $23 shows the target, inactive.
    bench.serve(60, |motor| position(motor, 10_000, Action::Inactive));
    assert!(bench.driver.channel(0).arrived);
}

#[test]
fn stop_decelerates_with_rotation_zero_then_ends_the_rotation_at_rest() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 16_000.0,
                accel: 160_000.0,
            },
        )
        .expect("accepted");
    let mut pos = 0;
    bench.serve(60, |motor| {
        pos += 100;
        position(motor, pos, Action::Rotation)
    });
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop is always taken");
    assert_eq!(
        bench.request(),
        Request::Rotate {
            motor: 0,
            velocity: 0
        }
    );
    // The motor comes to rest at 5000 and stays in rotation mode until $23.
    let sent = bench.serve(400, |motor| position(motor, 5000, Action::Rotation));
    assert!(
        sent.contains(&Request::StartRamp {
            motor: 0,
            target: 5000
        }),
        "{sent:?}"
    );
    assert!(!bench.driver.goals_pending());
}

#[test]
fn off_cuts_the_current_and_the_next_motion_restores_it() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.driver.set_goal(bench.now, 0, Goal::Off).expect("off");
    let sent = bench.serve(400, |motor| position(motor, 0, Action::Inactive));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::CurrentControl {
            motor: 0,
            i3: tmcpack::CurrentLevel::Off,
            ..
        }
    )));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 10.0 })
        .expect("position");
    let sent = bench.serve(50, |motor| position(motor, 0, Action::Inactive));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::CurrentControl {
            motor: 0,
            i3: tmcpack::CurrentLevel::P100,
            ..
        }
    )));
}

#[test]
fn home_writes_vrefmax_and_starts_the_search_then_reports_homed() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(20, |motor| position(motor, 300, Action::Inactive));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    assert!(!bench.driver.channel(0).homed);
    let sent = bench.serve(20, |motor| position(motor, 300, Action::ReferenceSearch(1)));
    assert!(sent.contains(&Request::ReferenceParameters {
        motor: 0,
        vrefmax: 100,
        debounce_mask: 0x0FFF,
        flags: tmcpack::ReferenceFlags::STOP_AFTER_SEARCH,
    }));
    assert!(sent.contains(&Request::ReferenceSearch { motor: 0 }));
    assert!(!bench.driver.channel(0).homed);
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    assert!(bench.driver.channel(0).homed);
}

#[test]
fn unsupported_and_unrepresentable_goals_are_refused() {
    let mut bench = Bench::new(config());
    bench.online();
    let d = &mut bench.driver;
    assert_eq!(
        d.set_goal(Duration::ZERO, 0, Goal::Power { fraction: 0.5 }),
        Err(GoalError::Unsupported(GoalKind::Power))
    );
    assert_eq!(
        d.set_goal(Duration::ZERO, 1, Goal::Stop { decel: 1.0 }),
        Err(GoalError::Unsupported(GoalKind::Stop))
    );
    assert_eq!(
        d.set_goal(Duration::ZERO, 6, Goal::Off),
        Err(GoalError::NoSuchChannel(6))
    );
    assert_eq!(
        d.set_goal(Duration::ZERO, 0, Goal::Position { counts: 1e12 }),
        Err(GoalError::OutOfBoardRange(GoalKind::Position))
    );
    assert_eq!(
        d.set_goal(
            Duration::ZERO,
            0,
            Goal::Velocity {
                velocity: 300_000.0,
                accel: 1.0
            }
        ),
        Err(GoalError::OutOfBoardRange(GoalKind::Velocity))
    );
    // 8.2: one velocity unit at clkdiv 18, div 0 is 64.25 µsteps/s.
    assert_eq!(
        d.set_goal(
            Duration::ZERO,
            0,
            Goal::Velocity {
                velocity: 30.0,
                accel: 1000.0
            }
        ),
        Err(GoalError::OutOfBoardRange(GoalKind::Velocity))
    );
    assert_eq!(
        d.set_goal(Duration::ZERO, 0, Goal::Home { velocity: 10.0 }),
        Err(GoalError::OutOfBoardRange(GoalKind::Home))
    );
    assert!(d.capabilities(0).contains(GoalKind::Home));
    assert!(!d.capabilities(0).contains(GoalKind::Power));
    assert_eq!(d.capabilities(1), GoalKinds::NONE);
}

#[test]
fn a_set_reset_flag_after_start_up_is_a_reset_fault_and_the_pack_is_reconfigured() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(30, |motor| position(motor, 7, Action::Inactive));
    // Run until the periodic $43, answer it with the reset flag set.
    let mut reconfigured = false;
    let mut first = true;
    for _ in 0..2000 {
        if let Some(w) = bench.tick() {
            match RequestFrame::decode(&w).expect("decodes").request {
                Request::UnitInfo { .. } if !first => {
                    bench.now += 10 * MS;
                    let mut info = UNIT_INFO;
                    info[3] = 0;
                    bench.rx(&info);
                }
                Request::UnitInfo { .. } => {
                    first = false;
                    bench.now += 10 * MS;
                    bench.rx(&UNIT_INFO);
                    assert_eq!(bench.driver.status().fault, Some(DeviceFault::Reset));
                    assert_eq!(bench.driver.status().resets, 1);
                    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::Reset));
                }
                Request::QueryActions { .. } => {
                    bench.now += 10 * MS;
                    bench.rx(&word(Reply::Actions {
                        actions: [Action::Inactive; 6],
                    }));
                }
                Request::QueryPosition { motor, .. } => {
                    bench.now += 10 * MS;
                    bench.rx(&position(motor, 0, Action::Inactive));
                }
                Request::VelocitySetting { .. } => reconfigured = true,
                _ => {}
            }
        }
    }
    assert!(reconfigured);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.channel(0).fault, None);
}

#[test]
fn link_down_faults_channels_and_link_up_restarts() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(30, |motor| position(motor, 7, Action::Inactive));
    bench.driver.link_down(bench.now);
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, Some(DeviceFault::LinkDown));
    assert_eq!(state.position, 7.0, "last known state kept");
    assert_eq!(bench.driver.wants_transmit(bench.now), None);
    bench.driver.link_up(bench.now);
    let (_, w) = bench.next(5).expect("$43 again");
    assert_eq!(w[1], 0x43);
}

#[test]
fn a_motor_found_running_after_start_up_is_stopped() {
    let mut bench = Bench::new(config());
    bench.online();
    let sent = bench.serve(30, |motor| position(motor, 7, Action::Rotation));
    assert!(sent.contains(&Request::Rotate {
        motor: 0,
        velocity: 0
    }));
}

#[test]
fn the_refresh_budget_covers_a_round_of_polls_on_the_bus() {
    let driver = TmcpackDriver::new(TmcpackDriverConfig {
        bus_motors: 10,
        ..config()
    });
    // 10 motors · (2 · 4.69 ms + 2 · 2 ms + 2 ms) ≈ 154 ms a round.
    assert!(driver.refresh_budget() > Duration::from_millis(300));
    assert!(driver.refresh_budget() < Duration::from_secs(1));
}

#[test]
fn the_reply_address_never_equals_the_pack_address() {
    let driver = TmcpackDriver::new(TmcpackDriverConfig {
        address: 0xFE,
        ..config()
    });
    assert_eq!(driver.reply_address(), 0xFF);
}

#[test]
fn a_position_goal_on_a_rotating_motor_stops_the_rotation_first() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 8000.0,
                accel: 160_000.0,
            },
        )
        .expect("jog");
    let mut pos = 0;
    bench.serve(60, |motor| {
        pos += 50;
        position(motor, pos, Action::Rotation)
    });
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 0.0 })
        .expect("position");
    // The motor decelerates to rest at 4000, then $23 ends the rotation, then the ramp.
    let sent = bench.serve(500, |motor| position(motor, 4000, Action::Rotation));
    let rotate = sent.iter().position(|r| {
        *r == Request::Rotate {
            motor: 0,
            velocity: 0,
        }
    });
    let end = sent.iter().position(|r| {
        *r == Request::StartRamp {
            motor: 0,
            target: 4000,
        }
    });
    let target = sent.iter().position(|r| {
        *r == Request::SetTarget {
            motor: 0,
            target: 0,
        }
    });
    let start = sent.iter().position(|r| {
        *r == Request::StartRamp {
            motor: 0,
            target: 0,
        }
    });
    assert!(rotate < end && end < target && target < start, "{sent:?}");
    assert!(rotate.is_some());
    // The ramp ran and ended at 0.
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    // An inactive motor needs no stop before the next ramp.
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Position { counts: 10.0 })
        .expect("position");
    let sent = bench.serve(50, |motor| position(motor, 0, Action::Ramp));
    assert!(!sent.contains(&Request::Rotate {
        motor: 0,
        velocity: 0
    }));
    assert!(sent.contains(&Request::StartRamp {
        motor: 0,
        target: 10
    }));
}

/// Bytes that come while nothing is awaited (a late answer, noise) are someone driving the
/// line (manual 6.1): nothing goes out before the word they belong to can have ended and
/// the pack's switch-over hold after it has passed.
#[test]
fn bytes_nobody_asked_for_hold_the_line_until_their_word_and_the_hold_passed() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(60, |motor| position(motor, 0, Action::Inactive));
    // Let the last exchange end.
    for _ in 0..30 {
        bench.driver.handle_timeout(bench.now);
        if !bench.driver.awaiting_reply() {
            break;
        }
        bench.now += MS;
    }
    assert!(!bench.driver.awaiting_reply());
    // Three bytes of a word: six more to come (6 × 0.52 ms), then the 2 ms hold.
    let at = bench.now;
    bench.rx(&[0xFE, 0x20, 0x00]);
    assert!(bench.driver.awaiting_reply());
    let byte = word_time(19_200) / 9;
    let free = at + byte * 6 + 2 * MS;
    bench.driver.handle_timeout(free - Duration::from_micros(1));
    assert!(bench.driver.awaiting_reply());
    bench.driver.handle_timeout(free);
    assert!(!bench.driver.awaiting_reply());
    assert!(bench.driver.status().bad_replies >= 1);
}

/// Ticks, answering `$20` polls at rest, until the `$43` reset check goes out; returns
/// when it was written.
fn until_reset_check(bench: &mut Bench) -> Duration {
    for _ in 0..3000 {
        let at = bench.now;
        if let Some(w) = bench.tick() {
            match RequestFrame::decode(&w).expect("decodes").request {
                Request::UnitInfo { .. } => return at,
                Request::QueryPosition { motor, .. } => {
                    bench.now += 10 * MS;
                    bench.rx(&position(motor, 0, Action::Inactive));
                }
                _ => {}
            }
        }
    }
    panic!("no $43 reset check");
}

/// Manual 8.6 `$43`: "reset flag: during first read out 1, afterwards 0". An online pack
/// whose `$43` answers with the flag set rebooted: a reset verdict naming that answer.
#[test]
fn a_reset_flag_is_a_reset_verdict_naming_its_answer() {
    let mut bench = Bench::new(config());
    bench.online();
    let asked = until_reset_check(&mut bench);
    bench.now += 11 * MS;
    let mut rebooted = UNIT_INFO;
    rebooted[3] = 1;
    bench.rx(&rebooted);
    let status = bench.driver.status();
    assert_eq!(status.resets, 1);
    assert_eq!(status.fault, Some(DeviceFault::Reset));
    assert_eq!(status.verdicts, 1);
    let verdict = status.verdict.expect("a verdict");
    assert_eq!(verdict.fault, DeviceFault::Reset);
    let evidence = verdict.evidence.as_str();
    let written = format!("written at {}", motion_drivers::Seconds(asked));
    assert!(
        evidence.contains("the `$43` answer at")
            && evidence.contains(&written)
            && evidence.contains("reset flag set"),
        "{evidence}"
    );
}

/// A `$43` answer that comes after its window is dropped and never paired — but a reset
/// flag in it is still the reboot it proves (the flag reads 0 from then on): a reset.
#[test]
fn a_late_43_with_the_reset_flag_set_is_still_a_reset() {
    let mut bench = Bench::new(config());
    bench.online();
    until_reset_check(&mut bench);
    // Unanswered: its window ends, the driver counts a timeout.
    for _ in 0..25 {
        bench.driver.handle_timeout(bench.now);
        bench.now += MS;
    }
    assert_eq!(bench.driver.status().timeouts, 1);
    let mut rebooted = UNIT_INFO;
    rebooted[3] = 1;
    bench.rx(&rebooted);
    assert_eq!(bench.driver.late_replies(), 1);
    let status = bench.driver.status();
    assert_eq!(status.resets, 1);
    assert_eq!(status.fault, Some(DeviceFault::Reset));
    let evidence = status.verdict.expect("a verdict").evidence;
    assert!(
        evidence.as_str().contains("the late `$43` answer"),
        "{}",
        evidence.as_str()
    );
    // A late `$43` without the flag is just dropped.
    let mut bench = Bench::new(config());
    bench.online();
    until_reset_check(&mut bench);
    for _ in 0..25 {
        bench.driver.handle_timeout(bench.now);
        bench.now += MS;
    }
    bench.rx(&UNIT_INFO.map(|b| if b == 1 { 0 } else { b }));
    assert_eq!(bench.driver.late_replies(), 1);
    let status = bench.driver.status();
    assert_eq!((status.resets, status.verdicts), (0, 0));
    assert!(status.online);
}
