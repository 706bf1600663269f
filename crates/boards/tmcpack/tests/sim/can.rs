//! The pack's CAN interface (manual 6.2) with the telegrams given straight to the model:
//! identifiers, the 16-command cache at 2 ms a command, answers to the response address
//! shifted by 3, and CAN taking over from RS-232.

use super::host::*;
use motion_drivers::CanRecord;
use motion_link::sim::CanDevice;
use tmcpack::{CAN_COMMAND_TIME, CanFrame};

/// The telegram of `request` to the pack at `address`, as a link carries it.
fn telegram(address: u8, request: Request) -> CanRecord {
    let frame: CanFrame = RequestFrame::new(address, request)
        .to_can()
        .expect("valid on CAN");
    CanRecord::standard(frame.id, &frame.data).expect("11-bit id, 8 bytes")
}

/// Every frame the pack sends up to `until`, with the instant each was ready.
fn answers(pack: &mut TmcpackSim, from: Duration, until: Duration) -> Vec<(Duration, CanRecord)> {
    let mut out = Vec::new();
    let mut now = from;
    while let Some(at) = CanDevice::next_event(pack, now) {
        if at > until {
            break;
        }
        now = at.max(now);
        while let Some(sent) = CanDevice::transmit(pack, now) {
            out.push(sent);
        }
        if CanDevice::next_event(pack, now).is_some_and(|next| next <= now) {
            now += Duration::from_micros(1);
        }
    }
    out
}

/// "The CAN response address is transferred to PACK in a 8 bit format, like at RS 232 /
/// 485. For responding the address is shifted to the left by 3 bits": a `$43` to the pack
/// at address 2 ($010) with response address $FE is answered on $7F0, 2 ms after it
/// arrived.
#[test]
fn a_query_is_answered_on_the_response_address_shifted_by_3_after_2_ms() {
    let mut sim = TmcpackSim::new(TmcpackSimConfig {
        address: 2,
        ..TmcpackSimConfig::default()
    });
    let t0 = Duration::from_secs(1);
    let query = telegram(2, Request::UnitInfo { reply_to: HOST });
    assert_eq!(query.standard_id(), Some(0x010));
    CanDevice::receive(&mut sim, t0, &query);
    let got = answers(&mut sim, t0, t0 + 50 * MS);
    assert_eq!(got.len(), 1, "{got:?}");
    let (at, answer) = got[0];
    assert_eq!(at, t0 + CAN_COMMAND_TIME);
    assert_eq!(answer.standard_id(), Some(0x7F0));
    // $43 response: CMD, firmware 149, reset flag 1 (first read), temperature, serial.
    assert_eq!(answer.payload(), [0x43, 149, 1, 35, 0xE9, 0x03, 0, 0]);
    assert!(sim.can_active());
    // Another pack's telegram ($008) is not this pack's.
    CanDevice::receive(
        &mut sim,
        t0 + 60 * MS,
        &telegram(1, Request::UnitInfo { reply_to: HOST }),
    );
    assert!(answers(&mut sim, t0 + 60 * MS, t0 + 100 * MS).is_empty());
    assert_eq!(sim.can_stats().foreign, 1);
}

/// "The PACK has an internal cache for 16 CAN-commands, internal processing time is approx.
/// 2 ms per command": twenty `$20` queries at once — sixteen are cached and answered 2 ms
/// apart, four are lost.
#[test]
fn the_cache_takes_16_commands_and_processes_one_every_2_ms() {
    let mut sim = TmcpackSim::new(TmcpackSimConfig::default());
    let t0 = Duration::from_secs(1);
    for n in 0..20u8 {
        let query = telegram(
            1,
            Request::QueryPosition {
                motor: n % 6,
                reply_to: HOST,
            },
        );
        CanDevice::receive(&mut sim, t0, &query);
    }
    assert_eq!(sim.can_cached(t0), 16);
    let stats = sim.can_stats();
    assert_eq!((stats.cached, stats.overflowed, stats.deepest), (16, 4, 16));
    let got = answers(&mut sim, t0, t0 + 100 * MS);
    assert_eq!(got.len(), 16);
    for (k, (at, answer)) in got.iter().enumerate() {
        assert_eq!(*at, t0 + CAN_COMMAND_TIME * (k as u32 + 1), "answer {k}");
        assert_eq!(answer.payload()[..2], [0x20, k as u8 % 6]);
    }
    assert_eq!(sim.can_cached(t0 + 100 * MS), 0);
}

/// A command acts at the end of its processing: `$26` + `$23` queued behind a `$20` start
/// the ramp 6 ms after they all arrived, not before.
#[test]
fn commands_act_at_the_end_of_their_processing() {
    let mut sim = TmcpackSim::new(TmcpackSimConfig::default());
    let t0 = Duration::from_secs(1);
    for request in [
        Request::QueryPosition {
            motor: 0,
            reply_to: HOST,
        },
        Request::SetTarget {
            motor: 0,
            target: 5000,
        },
        Request::StartRamp {
            motor: 0,
            target: 5000,
        },
    ] {
        CanDevice::receive(&mut sim, t0, &telegram(1, request));
    }
    let _ = CanDevice::transmit(&mut sim, t0 + 5 * MS);
    assert_eq!(sim.motor(0).expect("motor").action, Action::Inactive);
    let _ = CanDevice::transmit(&mut sim, t0 + 6 * MS);
    assert_eq!(sim.motor(0).expect("motor").action, Action::Ramp);
}

/// "After receiving the first valid instruction via CAN, control via RS 232 or RS 485 will
/// be terminated": serial words are ignored from then on, until a reset ($CC) initialises
/// both interfaces again.
#[test]
fn the_first_can_instruction_ends_serial_control_until_a_reset() {
    let mut h = pack();
    // Serial works before.
    h.send(1, Request::UnitInfo { reply_to: HOST });
    assert_eq!(h.wait(30 * MS).len(), 9);
    let t = h.now;
    CanDevice::receive(
        &mut h.dev,
        t,
        &telegram(1, Request::UnitInfo { reply_to: HOST }),
    );
    assert_eq!(answers(&mut h.dev, t, t + 10 * MS).len(), 1);
    h.now = t + 10 * MS;
    h.send(1, Request::UnitInfo { reply_to: HOST });
    assert!(h.wait(30 * MS).is_empty(), "serial no longer answers");
    assert_eq!(h.dev.can_stats().serial_ignored, 1);
    // $CC over CAN: both interfaces are initialised again (and the pack boots for 1 s).
    let t = h.now;
    CanDevice::receive(&mut h.dev, t, &telegram(1, Request::HardwareReset));
    let _ = CanDevice::transmit(&mut h.dev, t + 3 * MS);
    assert!(!h.dev.can_active());
    h.now = t + Duration::from_millis(1500);
    h.wait(MS);
    h.send(1, Request::UnitInfo { reply_to: HOST });
    assert_eq!(
        h.wait(30 * MS).len(),
        9,
        "serial answers again after the reset"
    );
}

/// A response address 0 has no CAN identifier ("According to the CAN standard 0 is no
/// valid address!"): the pack executes the query and cannot answer it. A telegram shorter
/// than 8 bytes is invalid; one on `…001` is for the RS-232 port.
#[test]
fn telegrams_the_pack_cannot_use() {
    let mut sim = TmcpackSim::new(TmcpackSimConfig::default());
    let t0 = Duration::from_secs(1);
    CanDevice::receive(
        &mut sim,
        t0,
        &telegram(1, Request::UnitInfo { reply_to: 0 }),
    );
    let short = CanRecord::standard(0x008, &[0x43, HOST]).expect("valid frame");
    CanDevice::receive(&mut sim, t0, &short);
    let forward = CanRecord::standard(0x009, b"hello").expect("valid frame");
    CanDevice::receive(&mut sim, t0, &forward);
    assert!(answers(&mut sim, t0, t0 + 20 * MS).is_empty());
    let stats = sim.can_stats();
    assert_eq!(
        (
            stats.executed,
            stats.unanswerable,
            stats.invalid,
            stats.rs232
        ),
        (1, 1, 1, 1),
        "{stats:?}"
    );
}
