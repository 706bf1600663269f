//! Motion: ramp limits, on-the-fly targets, rotation, PI, parallel start, synchronous stop, delayed answer.

use super::host::*;

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

/// $15 P5 bit 0 "PiMode: 0=trapezoidal ramp, 1=PI-controller": $23 then positions with
/// the PI controller.
#[test]
fn manual_8_3_pi_mode_bit_makes_23_use_the_pi_controller() {
    let mut h = pack();
    h.send(
        1,
        Request::MotorParameters {
            motor: 4,
            poslimit: 6400,
            motor_type: MotorType::PI_MODE,
            options: MotorOptions::EMPTY,
        },
    );
    h.send(
        1,
        Request::StartRamp {
            motor: 4,
            target: 2000,
        },
    );
    h.wait(4 * MS);
    assert_eq!(h.dev.motor(4).expect("m4").action, Action::PiController);
    h.wait(3000 * MS);
    assert!((h.dev.motor(4).expect("m4").position - 2000).abs() <= 8);
}

/// Rotary axis (8.3 $15 P5 bit 1): rotation wraps the position into 0..poslimit (NullLeft);
/// with way optimisation (P6 bit 0) a ramp takes the shorter way round.
#[test]
fn manual_8_3_rotary_axis_wraps_and_optimises_the_way() {
    let mut h = pack();
    h.send(
        1,
        Request::MotorParameters {
            motor: 0,
            poslimit: 6400,
            motor_type: MotorType::ROTARY | MotorType::NULL_LEFT,
            options: MotorOptions::WAY_OPTIMIZATION,
        },
    );
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: -300,
        },
    );
    for _ in 0..300 {
        h.wait(10 * MS);
        let p = h.dev.motor(0).expect("m0").position;
        assert!((0..6400).contains(&p), "wrapped: {p}");
    }
    assert!(
        h.dev.motor(0).expect("m0").physical < -6400,
        "more than a turn"
    );
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: 0,
        },
    );
    h.wait(1000 * MS);
    h.send(
        1,
        Request::SetPosition {
            motor: 0,
            position: 100,
        },
    );
    let before = h.dev.motor(0).expect("m0").physical;
    h.send(
        1,
        Request::StartRamp {
            motor: 0,
            target: 6300,
        },
    );
    h.wait(2000 * MS);
    let v = h.dev.motor(0).expect("m0");
    assert_eq!((v.position, v.action), (6300, Action::Inactive));
    assert_eq!(
        v.physical - before,
        -200,
        "the short way, backwards through 0"
    );
}

/// $32/$33: TTLOUT1 as ready output goes low while a motor of the mask is active; the
/// display shows the number of active motors (manual 2, 8.5).
#[test]
fn manual_8_5_ready_output_32_33() {
    let mut h = pack();
    h.send(
        1,
        Request::Outputs {
            ttlout1: false,
            ttlio1_input: true,
            ttlio1: false,
            ttlout1_ready: true,
        },
    );
    h.send(
        1,
        Request::ReadyOutput {
            active_mask: MotorMask::M2,
            reference_mask: MotorMask::EMPTY,
        },
    );
    h.wait(4 * MS);
    assert!(h.dev.ttlout1(), "ready");
    h.send(
        1,
        Request::Rotate {
            motor: 1,
            velocity: 50,
        },
    );
    h.wait(4 * MS);
    assert!(h.dev.ttlout1(), "motor 1 is not in the mask");
    h.send(
        1,
        Request::Rotate {
            motor: 2,
            velocity: 50,
        },
    );
    h.wait(4 * MS);
    assert!(!h.dev.ttlout1(), "active");
    assert_eq!(h.dev.display(), (2, false));
}
