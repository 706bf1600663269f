//! Unit-level functions: power-down, hardware reset, the QUADpack variant, service functions.

use super::host::*;

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

/// Random words (commands of the section 9 table with random parameters, some garbage) at
/// random times: the model never panics and its registers stay in their documented ranges.
#[test]
fn random_traffic_never_breaks_the_model() {
    let mut rng = motion_sim::rng::SimRng::new(42);
    for variant in [Variant::SixPack, Variant::QuadPack] {
        let mut h = Host::new(TmcpackSim::new(TmcpackSimConfig {
            variant,
            ..TmcpackSimConfig::default()
        }));
        for _ in 0..4000 {
            let mut w = [0u8; 9];
            for b in &mut w {
                *b = rng.next_u64() as u8;
            }
            let commands = tmcpack::Command::ALL;
            let pick = (rng.next_u64() % commands.len() as u64) as usize;
            w[1] = commands[pick].code();
            if (w[1] == 0xCC && !rng.next_u64().is_multiple_of(8)) || (0x40..=0x42).contains(&w[1])
            {
                // Keep resets rare (each deafens the pack for a second) and the line
                // settings (address, baud, switch-over, timeout) as they are.
                w[1] = 0x20;
            }
            w[0] = if rng.next_u64().is_multiple_of(10) {
                2
            } else {
                1
            };
            w[2] %= 6; // mostly valid motor numbers
            let len = if rng.next_u64().is_multiple_of(20) {
                4
            } else {
                9
            };
            h.send_raw(&w[..len]);
            h.wait(Duration::from_micros(rng.next_u64() % 30_000));
            for m in 0..6 {
                if let Some(v) = h.dev.motor(m) {
                    assert!(v.velocity.unsigned_abs() <= 511, "{v:?}");
                    assert!(v.microstep_hz.is_finite());
                    assert!(v.coil_current_amps >= 0.0);
                }
            }
        }
        let s = h.dev.stats();
        assert!(s.executed > 1000 && s.invalid > 0 && s.foreign > 0, "{s:?}");
    }
}
