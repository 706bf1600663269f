//! The simulated SIXpack / QUADpack against the manual: golden exchanges, wire timing,
//! ramp physics, every mode, two packs on one RS-485 pair, and the CAN interface.

#[path = "sim/can.rs"]
mod can;
#[path = "sim/features.rs"]
mod features;
#[path = "sim/host.rs"]
mod host;
#[path = "sim/io.rs"]
mod io;
#[path = "sim/motion.rs"]
mod motion;
#[path = "sim/readings.rs"]
mod readings;
#[path = "sim/reference.rs"]
mod reference;
#[path = "sim/unit.rs"]
mod unit;
#[path = "sim/wire.rs"]
mod wire;

use host::*;

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
