//! The simulated SIXpack / QUADpack against the manual: golden exchanges, wire timing,
//! ramp physics, every mode, and two packs on one RS-485 pair.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use motion_link::sim::{StreamBus, StreamDevice};
use motion_sim::tmcpack::{RefSwitch, TmcpackSim, TmcpackSimConfig};
use tmcpack::convert::byte_time;
use tmcpack::{
    Action, MotorMask, MotorOptions, MotorType, PowerDownRequest, PowerDownStatus, Reply,
    ReplyFrame, Request, RequestFrame, Variant,
};

const HOST: u8 = 0xFE;
const MS: Duration = Duration::from_millis(1);

fn bt() -> Duration {
    byte_time(19_200)
}

/// A host on the line: sends words byte by byte with real wire time, collects replies.
struct Host<D: StreamDevice> {
    dev: D,
    now: Duration,
    bt: Duration,
}

impl<D: StreamDevice> Host<D> {
    fn new(dev: D) -> Self {
        Self {
            dev,
            now: Duration::from_secs(10),
            bt: bt(),
        }
    }

    /// Sends a raw word starting now; returns when its last byte arrived.
    fn send_raw(&mut self, bytes: &[u8]) -> Duration {
        for b in bytes {
            self.now += self.bt;
            self.dev.receive(self.now, &[*b]);
        }
        self.now
    }

    fn send(&mut self, address: u8, req: Request) -> Duration {
        let w = RequestFrame::new(address, req)
            .to_word()
            .expect("valid request");
        self.send_raw(&w)
    }

    /// Follows the device's events until `until`; returns each byte with the instant its
    /// transmission started.
    fn collect_until(&mut self, until: Duration) -> Vec<(Duration, u8)> {
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        while let Some(e) = self.dev.next_event(self.now) {
            if e > until {
                break;
            }
            let t = e.max(self.now);
            let n = self.dev.transmit(t, &mut buf);
            got.extend(buf.iter().take(n).map(|b| (t, *b)));
            self.now = if n == 0 && t == self.now {
                t + Duration::from_nanos(1)
            } else {
                t
            };
        }
        self.now = self.now.max(until);
        self.dev.transmit(self.now, &mut buf);
        got
    }

    /// Sends a query and returns the decoded reply and the instant its first byte started.
    fn query(&mut self, address: u8, req: Request) -> Option<(Duration, ReplyFrame)> {
        self.send(address, req);
        let got = self.collect_until(self.now + 40 * MS);
        let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
        let first = got.first()?.0;
        Some((first, ReplyFrame::decode(&bytes).expect("one reply word")))
    }

    /// Lets time pass with nothing on the line.
    fn wait(&mut self, d: Duration) -> Vec<(Duration, u8)> {
        self.collect_until(self.now + d)
    }
}

fn pack() -> Host<TmcpackSim> {
    Host::new(TmcpackSim::new(TmcpackSimConfig::default()))
}

fn position(h: &mut Host<TmcpackSim>, motor: u8) -> (i32, Action, bool) {
    match h.query(
        1,
        Request::QueryPosition {
            motor,
            reply_to: HOST,
        },
    ) {
        Some((
            _,
            ReplyFrame {
                reply:
                    Reply::Position {
                        position,
                        action,
                        stopped,
                        ..
                    },
                ..
            },
        )) => (position, action, stopped),
        other => panic!("no position reply: {other:?}"),
    }
}

/// Manual 7.2 "Starting a two axis interpolated movement": $26 motor 0 to $03E8 (1000),
/// $26 motor 1 to $07D0 (2000), $50 mask 3. Both arrive together; the $20 answer has the
/// 9-byte layout of 8.4 at the response address.
#[test]
fn manual_7_2_interpolated_movement_golden_exchange() {
    let mut h = pack();
    h.send_raw(&[1, 0x26, 0, 0xE8, 0x03, 0, 0, 0, 0]);
    h.send_raw(&[1, 0x26, 1, 0xD0, 0x07, 0, 0, 0, 0]);
    h.send_raw(&[1, 0x50, 0x03, 0, 0, 0, 0, 0, 0]);
    assert!(
        h.wait(2 * MS).is_empty(),
        "set-target and $50 have no answer"
    );
    let mut done = [None, None];
    for step in 0..2000u32 {
        h.wait(2 * MS);
        for (m, slot) in done.iter_mut().enumerate() {
            let v = h.dev.motor(m as u8).expect("motor");
            if slot.is_none() && v.action == Action::Inactive {
                *slot = Some(step);
            }
            if v.action == Action::Ramp {
                // Linear interpolation: motor 1 is always at twice motor 0's distance.
                let p0 = h.dev.motor(0).expect("m0").position;
                let p1 = h.dev.motor(1).expect("m1").position;
                assert!((i64::from(p1) - 2 * i64::from(p0)).abs() <= 2, "{p0} {p1}");
            }
        }
        if done.iter().all(Option::is_some) {
            break;
        }
    }
    assert_eq!(
        done[0], done[1],
        "both axes reach their targets at the same time"
    );
    h.send_raw(&[1, 0x20, 0, HOST, 0, 0, 0, 0, 0]);
    let reply: Vec<u8> = h.wait(30 * MS).iter().map(|(_, b)| *b).collect();
    assert_eq!(reply, [HOST, 0x20, 0, 0xE8, 0x03, 0, 0, 0, 0]);
    h.send_raw(&[1, 0x20, 1, HOST, 0, 0, 0, 0, 0]);
    let reply: Vec<u8> = h.wait(30 * MS).iter().map(|(_, b)| *b).collect();
    assert_eq!(reply, [HOST, 0x20, 1, 0xD0, 0x07, 0, 0, 0, 0]);
}

/// Manual 6.1: "an instruction will be transmitted only after an adjustable transmitter
/// switchover time (s. CMD $40; pre-set to 6ms) has passed"; bytes follow back to back.
#[test]
fn manual_6_1_reply_starts_after_switchover_delay() {
    let mut h = pack();
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    let got = h.wait(40 * MS);
    assert_eq!(got.len(), 9);
    for (k, (t, _)) in got.iter().enumerate() {
        assert_eq!(*t, end + 6 * MS + bt() * k as u32, "byte {k}");
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
    assert_eq!(got.first().map(|g| g.0), Some(end + 20 * MS));
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
    assert_eq!(got[0].0, end + 2 * MS);
    assert_eq!(got[8].0 - got[0].0, byte_time(115_200) * 8);
}

/// Sample the true state every tick of a ramp: never above vmax, velocity changes by at
/// most amax/64 per 2 ms outside the vstart band (8.3 $13/$14), exact arrival.
#[test]
fn ramp_arrives_without_exceeding_vmax_or_amax() {
    for (amax, vmax, target) in [
        (128u16, 511u16, 60_000i32),
        (40, 300, -25_000),
        (300, 200, 123),
    ] {
        let mut h = pack();
        h.send(
            1,
            Request::StartingVelocity {
                motor: 2,
                vmin: 4,
                vstart: 5,
                div: 2,
            },
        );
        h.send(
            1,
            Request::VelocityAcceleration {
                motor: 2,
                amax,
                vmax,
            },
        );
        h.send(1, Request::StartRamp { motor: 2, target });
        let (vs, vmax_q) = (5 * 64, i64::from(vmax) * 64);
        let mut prev = h.dev.motor(2).expect("m2").velocity_q;
        let mut peak = 0i64;
        for _ in 0..100_000 {
            h.wait(2 * MS);
            let v = h.dev.motor(2).expect("m2");
            assert!(v.velocity_q.abs() <= vmax_q, "above vmax: {}", v.velocity_q);
            if prev.abs() > vs || v.velocity_q.abs() > vs {
                assert!(
                    (v.velocity_q - prev).abs() <= i64::from(amax),
                    "Δv {} > amax",
                    v.velocity_q - prev
                );
            }
            assert!(v.microstep_hz.abs() <= 200_000.0);
            peak = peak.max(v.velocity_q.abs());
            prev = v.velocity_q;
            if v.action == Action::Inactive {
                break;
            }
        }
        let v = h.dev.motor(2).expect("m2");
        assert_eq!(
            (v.position, v.action, v.velocity),
            (target, Action::Inactive, 0)
        );
        assert_eq!(v.physical, i64::from(target));
        if target.abs() > 20_000 {
            assert_eq!(peak, vmax_q, "long ramp reaches vmax");
        }
    }
}

/// $26 on the fly: a target behind a fast motor makes it decelerate with amax, overshoot
/// and drive back (8.4); $23 while active is ignored.
#[test]
fn manual_8_4_on_the_fly_target_change_26() {
    let mut h = pack();
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: 100_000,
        },
    );
    h.wait(400 * MS);
    let p = h.dev.motor(0).expect("m0").position;
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: -5,
        },
    );
    assert_eq!(h.dev.motor(0).expect("m0").action, Action::Ramp);
    h.send(
        1,
        Request::SetTarget {
            motor: 0,
            target: p,
        },
    );
    let mut max = p;
    for _ in 0..5000 {
        h.wait(2 * MS);
        let v = h.dev.motor(0).expect("m0");
        max = max.max(v.position);
        if v.action == Action::Inactive {
            break;
        }
    }
    assert!(max > p, "overshoots");
    assert_eq!(h.dev.motor(0).expect("m0").position, p);
}

/// $25 rotation with amax, then $23 only stops a rotating motor (8.4).
#[test]
fn manual_8_4_rotation_25_and_stop_by_23() {
    let mut h = pack();
    h.send(
        1,
        Request::Rotate {
            motor: 1,
            velocity: -200,
        },
    );
    h.wait(10 * MS);
    let early = h.dev.motor(1).expect("m1").velocity;
    assert!(early < 0 && early > -200, "accelerates: {early}");
    h.wait(300 * MS);
    let v = h.dev.motor(1).expect("m1");
    assert_eq!((v.velocity, v.action), (-200, Action::Rotation));
    let reply = h
        .query(
            1,
            Request::QueryVelocity {
                motor: 1,
                reply_to: HOST,
            },
        )
        .expect("reply")
        .1;
    assert_eq!(
        reply.reply,
        Reply::Velocity {
            motor: 1,
            velocity: -200,
            action: Action::Rotation
        }
    );
    h.send(
        1,
        Request::StartRamp {
            motor: 1,
            target: 0,
        },
    );
    h.wait(500 * MS);
    let v = h.dev.motor(1).expect("m1");
    assert_eq!((v.velocity, v.action), (0, Action::Inactive));
    assert!(v.position < -1000, "stopped where it was, not driven to 0");
}

/// $24 PI controller: switches at once, follows the target.
#[test]
fn manual_8_4_pi_controller_24() {
    let mut h = pack();
    h.send(
        1,
        Request::PiTarget {
            motor: 3,
            target: 5000,
        },
    );
    h.wait(4 * MS);
    assert_eq!(h.dev.motor(3).expect("m3").action, Action::PiController);
    h.wait(3000 * MS);
    let v = h.dev.motor(3).expect("m3");
    assert!(
        (v.position - 5000).abs() <= 8,
        "PI settles near target: {}",
        v.position
    );
    h.send(
        1,
        Request::PiTarget {
            motor: 3,
            target: 0,
        },
    );
    h.wait(3000 * MS);
    assert!(h.dev.motor(3).expect("m3").position.abs() <= 8);
}

/// $29 parallel start of targets set with $26; $2A stops synchronously, returning to the
/// stop point (8.4).
#[test]
fn manual_8_4_parallel_start_29_and_sync_stop_2a() {
    let mut h = pack();
    h.send(
        1,
        Request::SetTarget {
            motor: 0,
            target: 50_000,
        },
    );
    h.send(
        1,
        Request::SetTarget {
            motor: 5,
            target: -50_000,
        },
    );
    h.wait(10 * MS);
    assert_eq!(
        h.dev.motor(0).expect("m0").action,
        Action::Inactive,
        "$26 alone does not start"
    );
    h.send(
        1,
        Request::StartRampParallel {
            mask: MotorMask::M0 | MotorMask::M5,
        },
    );
    h.wait(2 * MS);
    let (a, b) = (h.dev.motor(0).expect("m0"), h.dev.motor(5).expect("m5"));
    assert_eq!((a.action, b.action), (Action::Ramp, Action::Ramp));
    assert_eq!(a.position, -b.position, "started in the same tick");
    h.wait(300 * MS);
    h.send(
        1,
        Request::Stop {
            mask: MotorMask::M0 | MotorMask::M5,
        },
    );
    let stop_at = h.dev.motor(0).expect("m0").target;
    h.wait(2000 * MS);
    let (a, b) = (h.dev.motor(0).expect("m0"), h.dev.motor(5).expect("m5"));
    assert_eq!((a.action, b.action), (Action::Inactive, Action::Inactive));
    assert_eq!(a.position, stop_at);
    assert_eq!(a.position, -b.position);
}

/// $28 with a mask answers only once the masked motors are inactive; a query in between is
/// served ("a delayed response with RS 232 may be outstanding in parallel", 7.1).
#[test]
fn manual_8_4_delayed_response_28() {
    let mut h = pack();
    h.send(
        1,
        Request::StartRamp {
            motor: 4,
            target: 20_000,
        },
    );
    h.send(
        1,
        Request::QueryActions {
            reply_to: HOST,
            delay_mask: MotorMask::M4,
        },
    );
    assert!(
        h.wait(100 * MS).is_empty(),
        "no answer while motor 4 drives"
    );
    let (_, pos) = h
        .query(
            1,
            Request::QueryPosition {
                motor: 4,
                reply_to: HOST,
            },
        )
        .expect("served");
    assert!(matches!(
        pos.reply,
        Reply::Position {
            action: Action::Ramp,
            ..
        }
    ));
    let got = h.wait(3000 * MS);
    let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
    assert_eq!(bytes, [HOST, 0x28, 0, 0, 0, 0, 0, 0, 0]);
    assert_eq!(h.dev.motor(4).expect("m4").position, 20_000);
    let done = got[0].0;
    // Immediate when nothing is masked.
    let (_, f) = h
        .query(
            1,
            Request::QueryActions {
                reply_to: 7,
                delay_mask: MotorMask::EMPTY,
            },
        )
        .expect("reply");
    assert_eq!(f.address, 7);
    assert!(done > Duration::ZERO);
}

/// $22 reference search with the default flags (NullCenter, FastRef, zero point right):
/// the pack finds the switch, sets zero at its centre and drives back (8.4, 7.1).
#[test]
fn manual_8_4_reference_search_22_null_center() {
    let mut h = pack();
    h.send(1, Request::ReferenceSearch { motor: 0 });
    let mut saw = [false; 6];
    let mut dp = false;
    for _ in 0..20_000 {
        h.wait(2 * MS);
        let v = h.dev.motor(0).expect("m0");
        if let Action::ReferenceSearch(p) = v.action {
            saw[usize::from(p).min(5)] = true;
            dp |= h.dev.display().1;
        }
        if v.action == Action::Inactive {
            break;
        }
    }
    // Phase 0 (stopping) ends in the first tick for a motor at rest.
    assert!(saw[1] && saw[2] && saw[3] && saw[4], "phases {saw:?}");
    assert!(dp, "decimal point during the search");
    let v = h.dev.motor(0).expect("m0");
    assert_eq!(v.action, Action::Inactive);
    assert_eq!(v.position, 0);
    // Switch actuated 3200..=3519: the centre, within the slow approach's resolution.
    assert!(
        (v.physical - 3360).abs() <= 4,
        "zero at the centre: {}",
        v.physical
    );
}

/// $18 nulloffset with NullLeft (no NullCenter): zero lies nulloffset beyond the switch
/// edge; "stop after reference search" ($16 P5 bit 0) drives there.
#[test]
fn manual_8_3_nulloffset_18_null_left() {
    let mut h = pack();
    h.dev.set_ref_switch(
        1,
        Some(RefSwitch {
            from: -10_000,
            to: -2000,
            opener: true,
        }),
    );
    h.send(
        1,
        Request::MotorParameters {
            motor: 1,
            poslimit: 6400,
            motor_type: MotorType::NULL_LEFT | MotorType::FILTER_SWITCH,
            options: MotorOptions::FAST_REF | MotorOptions::NULL_POSITIVE,
        },
    );
    h.send(
        1,
        Request::NullOffset {
            motor: 1,
            nulloffset: 100,
            testnullrange: 240,
        },
    );
    h.send(
        1,
        Request::ReferenceParameters {
            motor: 1,
            vrefmax: 100,
            debounce_mask: 0x0FFF,
            flags: tmcpack::ReferenceFlags::STOP_AFTER_SEARCH,
        },
    );
    h.send(1, Request::ReferenceSearch { motor: 1 });
    h.wait(20_000 * MS);
    let v = h.dev.motor(1).expect("m1");
    assert_eq!((v.action, v.position), (Action::Inactive, 0));
    assert!(
        (v.physical - (-2000 - 100)).abs() <= 3,
        "zero 100 beyond the edge: {}",
        v.physical
    );
}

/// No switch within 125 % of poslimit: the search repeats (8.4).
#[test]
fn manual_8_4_reference_search_without_switch_repeats() {
    let mut h = pack();
    h.dev.set_ref_switch(2, None);
    h.send(1, Request::ReferenceSearch { motor: 2 });
    h.wait(10_000 * MS);
    let v = h.dev.motor(2).expect("m2");
    assert!(v.action.is_referencing());
    assert!(v.physical > 8000 * 2, "kept searching: {}", v.physical);
}

/// StopNull + testnullrange: the switch seen far from zero while driving towards it stops
/// the motor (abruptly, or with amax when StopSoft) and sets the stop bit, read once by $20
/// (8.3); without StopNoRef a reference search follows.
#[test]
fn manual_8_3_stop_null_outside_testnullrange() {
    let mut h = pack();
    for (motor, options) in [
        (0u8, MotorOptions::STOP_NO_REF),
        (1, MotorOptions::STOP_NO_REF | MotorOptions::STOP_SOFT),
        (2, MotorOptions::EMPTY),
    ] {
        h.send(
            1,
            Request::MotorParameters {
                motor,
                poslimit: 6400,
                motor_type: MotorType::STOP_NULL,
                options,
            },
        );
        h.send(
            1,
            Request::StartRamp {
                motor,
                target: 10_000,
            },
        );
    }
    h.wait(3000 * MS);
    let (hard, action, stopped) = position(&mut h, 0);
    assert_eq!(action, Action::Inactive);
    assert!(stopped, "stop bit");
    assert!(
        (3200..3260).contains(&hard),
        "stopped at the switch: {hard}"
    );
    assert!(!position(&mut h, 0).2, "cleared after read");
    let (soft, action, stopped) = position(&mut h, 1);
    assert_eq!((action, stopped), (Action::Inactive, true));
    assert!(
        soft > hard + 100 && soft < 10_000,
        "decelerated with amax: {soft}"
    );
    // Motor 2 (no StopNoRef) referenced itself, then resumed its ramp to 10000, which lies
    // beyond the new zero point: the switch stops it again, as the real pack would
    // ("The reference search requires proper poslimit settings", 7.1).
    let (_, action, stopped) = position(&mut h, 2);
    assert!(
        (stopped && action.is_referencing()) || action == Action::Ramp,
        "{action:?}"
    );
    h.send(
        1,
        Request::ReferenceParameters {
            motor: 2,
            vrefmax: 100,
            debounce_mask: 0x0FFF,
            flags: tmcpack::ReferenceFlags::STOP_AFTER_SEARCH,
        },
    );
    h.send(1, Request::ReferenceSearch { motor: 2 });
    h.wait(10_000 * MS);
    let v = h.dev.motor(2).expect("m2");
    assert_eq!((v.position, v.action), (0, Action::Inactive));
    assert!(
        (v.physical - 3200).abs() <= 2,
        "homed to the switch edge: {}",
        v.physical
    );
}

/// $30 analogue channels (ch 7 = supply, 1 V = 22) and the inverted reference inputs; $31
/// stop limit stops a motor running right.
#[test]
fn manual_8_5_analogue_inputs_30_31() {
    let mut h = pack();
    let (_, f) = h
        .query(
            1,
            Request::ReadInput {
                channel: 7,
                reply_to: HOST,
            },
        )
        .expect("reply");
    let Reply::Input { value, inputs, .. } = f.reply else {
        panic!("{f:?}")
    };
    assert!((527..=529).contains(&value), "24 V: {value}");
    assert_eq!(
        inputs.bits() & 0x3F,
        0,
        "no switch actuated, inputs inverted"
    );
    h.dev.set_analog(3, 800);
    let (_, f) = h
        .query(
            1,
            Request::ReadInput {
                channel: 3,
                reply_to: HOST,
            },
        )
        .expect("reply");
    assert!(matches!(
        f.reply,
        Reply::Input {
            channel: 3,
            value: 799..=801,
            reference: false,
            ..
        }
    ));
    h.send(
        1,
        Request::StopLimits {
            channel: 3,
            left_min: 0,
            right_max: 700,
        },
    );
    h.send(
        1,
        Request::MotorParameters {
            motor: 3,
            poslimit: 6400,
            motor_type: MotorType::EMPTY,
            options: MotorOptions::STOP_NO_REF,
        },
    );
    h.send(
        1,
        Request::Rotate {
            motor: 3,
            velocity: 100,
        },
    );
    h.wait(50 * MS);
    let (_, action, stopped) = position(&mut h, 3);
    assert_eq!((action, stopped), (Action::Inactive, true));
    h.send(
        1,
        Request::Rotate {
            motor: 3,
            velocity: -100,
        },
    );
    h.wait(50 * MS);
    assert_eq!(
        h.dev.motor(3).expect("m3").action,
        Action::Rotation,
        "left is allowed"
    );
}

/// $45 power-down: activated, undervoltage stops the motors and saves the positions;
/// bit 3 resets the state, bit 0 loads the saved positions (8.6).
#[test]
fn manual_8_6_power_down_45() {
    let mut h = pack();
    let (_, f) = h
        .query(
            1,
            Request::PowerDown {
                reply_to: HOST,
                flags: PowerDownRequest::ACTIVATE,
            },
        )
        .expect("reply");
    assert_eq!(
        f.reply,
        Reply::PowerDown {
            status: PowerDownStatus::EMPTY
        }
    );
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: 300,
        },
    );
    h.wait(500 * MS);
    let now = h.now;
    h.dev.set_supply_volts(now, 12.0);
    let saved = h.dev.saved_positions().expect("saved on undervoltage");
    assert_eq!(h.dev.motor(0).expect("m0").action, Action::Inactive);
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: 300,
        },
    );
    h.wait(20 * MS);
    assert_eq!(
        h.dev.motor(0).expect("m0").action,
        Action::Inactive,
        "motors held"
    );
    h.send(
        1,
        Request::SetPosition {
            motor: 0,
            position: 0,
        },
    );
    let now = h.now;
    h.dev.set_supply_volts(now, 24.0);
    let flags = PowerDownRequest::RESET_STATE | PowerDownRequest::LOAD_POSITIONS;
    let (_, f) = h
        .query(
            1,
            Request::PowerDown {
                reply_to: HOST,
                flags,
            },
        )
        .expect("reply");
    assert_eq!(
        f.reply,
        Reply::PowerDown {
            status: PowerDownStatus::LOADED
                | PowerDownStatus::VALID_IN_EEPROM
                | PowerDownStatus::DOWN_BEFORE
        }
    );
    assert_eq!(h.dev.motor(0).expect("m0").position, saved[0]);
    assert!(saved[0] > 1000);
}

/// $CC: a 0 byte, about a second deaf, defaults back (address from the rotary switch);
/// the reset flag of $43 is 1 again; positions cleared, rotors where they were (8.6).
#[test]
fn manual_8_6_hardware_reset_cc() {
    let mut h = pack();
    h.send(1, Request::SetAddress { address: 9 });
    h.send(9, Request::UnitInfo { reply_to: HOST });
    h.wait(40 * MS);
    h.send(
        9,
        Request::StartRamp {
            motor: 0,
            target: 400,
        },
    );
    h.wait(1000 * MS);
    assert!(
        h.query(1, Request::UnitInfo { reply_to: HOST }).is_none(),
        "address 1 no longer"
    );
    let end = h.send(9, Request::HardwareReset);
    let got = h.wait(1100 * MS);
    assert_eq!(got, [(end, 0u8)]);
    let (_, f) = h
        .query(1, Request::UnitInfo { reply_to: HOST })
        .expect("back at address 1");
    assert!(matches!(f.reply, Reply::UnitInfo { reset: true, .. }));
    let v = h.dev.motor(0).expect("m0");
    assert_eq!((v.position, v.physical), (0, 400));
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
    assert_eq!(got[0].0, end + 6 * MS);
    assert_eq!(h.dev.stats().replaced_replies, 1);
    // A request sent into the answer: the pack does not hear it.
    let end = h.send(1, Request::UnitInfo { reply_to: HOST });
    h.now = end + 6 * MS + 2 * bt();
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

/// QUADpack: four motors; a query for motor 4 gets no answer; $28 reports 4 and 5 idle.
#[test]
fn quadpack_has_four_motors() {
    let mut h = Host::new(TmcpackSim::new(TmcpackSimConfig {
        variant: Variant::QuadPack,
        ..TmcpackSimConfig::default()
    }));
    assert!(h.dev.motor(4).is_none());
    assert!(
        h.query(
            1,
            Request::QueryPosition {
                motor: 4,
                reply_to: HOST
            }
        )
        .is_none()
    );
    assert!(
        h.query(
            1,
            Request::QueryPosition {
                motor: 3,
                reply_to: HOST
            }
        )
        .is_some()
    );
    h.send(
        1,
        Request::Rotate {
            motor: 3,
            velocity: 50,
        },
    );
    let (_, f) = h
        .query(
            1,
            Request::QueryActions {
                reply_to: HOST,
                delay_mask: MotorMask::EMPTY,
            },
        )
        .expect("reply");
    let Reply::Actions { actions } = f.reply else {
        panic!()
    };
    assert_eq!(actions[3], Action::Rotation);
    assert_eq!(actions[4], Action::Inactive);
    // QUADpack peak: 1.5 A · 128/256 · 100 % DIP, I3 = 100 % while accelerating.
    h.wait(2 * MS);
    assert!((h.dev.motor(3).expect("m3").coil_current_amps - 0.75).abs() < 1e-9);
}

/// Service functions $F2–$F7: wrong magic refused; erase, program, checksum, read back.
#[test]
fn manual_8_8_service_functions() {
    let cfg = TmcpackSimConfig {
        flash_size: 14,
        ..TmcpackSimConfig::default()
    };
    let (fm, em) = (cfg.flash_magic, cfg.eeprom_magic);
    let mut h = Host::new(TmcpackSim::new(cfg));
    let r = |h: &mut Host<TmcpackSim>, req| h.query(1, req).expect("reply").1.reply;
    assert_eq!(
        r(
            &mut h,
            Request::FlashEnable {
                reply_to: HOST,
                magic: 1
            }
        ),
        Reply::FlashEnable { ok: false }
    );
    assert_eq!(
        r(
            &mut h,
            Request::FlashEnable {
                reply_to: HOST,
                magic: fm
            }
        ),
        Reply::FlashEnable { ok: true }
    );
    h.send(
        1,
        Request::FlashProgram {
            data: [1, 2, 3, 4, 5, 6, 7],
        },
    );
    h.send(1, Request::FlashProgram { data: [8; 7] });
    let sum = (1..=7u16).sum::<u16>() + 56;
    assert_eq!(
        r(&mut h, Request::FlashChecksum { reply_to: HOST }),
        Reply::FlashChecksum { checksum: sum }
    );
    assert_eq!(
        r(&mut h, Request::FlashRead { reply_to: HOST }),
        Reply::FlashData {
            data: [1, 2, 3, 4, 5, 6, 7]
        }
    );
    assert_eq!(
        r(&mut h, Request::FlashRead { reply_to: HOST }),
        Reply::FlashData { data: [8; 7] }
    );
    let w = Request::EepromWrite {
        reply_to: HOST,
        magic: em,
        address: 3,
        value: 77,
    };
    assert_eq!(r(&mut h, w), Reply::EepromWrite { ok: true });
    let rd = Request::EepromRead {
        reply_to: HOST,
        magic: 0,
        address: 3,
        value: 0,
    };
    assert_eq!(r(&mut h, rd), Reply::EepromRead { ok: false });
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
