//! Golden vectors of the instructions behind the power-down mode, the starting velocity,
//! the motor characteristics table and the PI controller (issue 29 items 1, 7, 8), from the
//! SIXpack/QUADpack manual (V2.43), quoting it.

use tmcpack::table::{self, FULL_STEP_TABLE, SINE_TABLE};
use tmcpack::{
    Error, PowerDownRequest, PowerDownStatus, Reply, ReplyFrame, Request, RequestFrame,
    power_down_supported,
};

const PACK: u8 = 1;
const HOST: u8 = 0xFE;

fn word(request: Request) -> [u8; 9] {
    RequestFrame::new(PACK, request)
        .to_word()
        .expect("valid request")
}

fn round_trip(request: Request) -> [u8; 9] {
    let w = word(request);
    assert_eq!(
        RequestFrame::decode(&w),
        Ok(RequestFrame::new(PACK, request))
    );
    w
}

/// 8.6 `$45` "Power-Down modus": "P0 response address", "P1 Bit 0: 1 = Read positions from
/// EEprom, and copy them to the motor position registers, if they contain valid values;
/// Bit 1: 1 = set positions in EEprom as invalid; Bit 2: 1 = activate Power down (stop
/// motors & autosave position on undervoltage); Bit 3: 1 = Reset powerdown state and
/// re-enable the motors".
#[test]
fn manual_8_6_power_down_request_bits() {
    let cases = [
        (PowerDownRequest::EMPTY, 0b0000),
        (PowerDownRequest::LOAD_POSITIONS, 0b0001),
        (PowerDownRequest::INVALIDATE_POSITIONS, 0b0010),
        (PowerDownRequest::ACTIVATE, 0b0100),
        (PowerDownRequest::RESET_STATE, 0b1000),
        (
            PowerDownRequest::ACTIVATE | PowerDownRequest::RESET_STATE,
            0b1100,
        ),
    ];
    for (flags, bits) in cases {
        let w = round_trip(Request::PowerDown {
            reply_to: HOST,
            flags,
        });
        assert_eq!(w, [PACK, 0x45, HOST, bits, 0, 0, 0, 0, 0]);
    }
}

/// 8.6 `$45` response: "P0 Bit 0: 1 = loaded valid position from EEprom; Bit 1: 1 = located
/// valid position in EEprom; Bit 2: 1 = Power down – status before Command; Bit 3: 1 = Power
/// down – status after Command".
#[test]
fn manual_8_6_power_down_status_bits() {
    let cases = [
        (0b0001, PowerDownStatus::LOADED),
        (0b0010, PowerDownStatus::VALID_IN_EEPROM),
        (0b0100, PowerDownStatus::DOWN_BEFORE),
        (0b1000, PowerDownStatus::DOWN_AFTER),
        (
            0b0011,
            PowerDownStatus::LOADED | PowerDownStatus::VALID_IN_EEPROM,
        ),
    ];
    for (bits, status) in cases {
        let frame = ReplyFrame::decode(&[HOST, 0x45, bits, 0, 0, 0, 0, 0, 0]).expect("decodes");
        assert_eq!(frame, ReplyFrame::new(HOST, Reply::PowerDown { status }));
        assert_eq!(
            ReplyFrame::new(HOST, Reply::PowerDown { status }).to_word(),
            Ok([HOST, 0x45, bits, 0, 0, 0, 0, 0, 0])
        );
    }
}

/// 8.6 `$45`: "(Version 1.46 and since Version 1.49)"; `$43` "firmware-revision (e.g.
/// 148=V1.4.8)".
#[test]
fn manual_8_6_power_down_firmware_versions() {
    assert!(!power_down_supported(145));
    assert!(power_down_supported(146));
    assert!(!power_down_supported(147));
    assert!(!power_down_supported(148));
    assert!(power_down_supported(149));
    assert!(power_down_supported(160));
}

/// 8.3 `$13` "Starting velocity": "P0 motnr, P1,2 # vmin (0..511), P3,4 # vstart (1..511),
/// P5 div_i (0..3)", LSB first.
#[test]
fn manual_8_3_starting_velocity_13() {
    let w = round_trip(Request::StartingVelocity {
        motor: 2,
        vmin: 0,
        vstart: 300,
        div: 1,
    });
    assert_eq!(w, [PACK, 0x13, 2, 0, 0, 0x2C, 0x01, 1, 0]);
    for (vmin, vstart, div, field) in [
        (0, 0, 0, "vstart"),
        (0, 512, 0, "vstart"),
        (512, 5, 0, "vmin"),
        (0, 5, 4, "div"),
    ] {
        let bad = Request::StartingVelocity {
            motor: 0,
            vmin,
            vstart,
            div,
        };
        assert_eq!(bad.validate(), Err(Error::OutOfRange { field }));
    }
}

/// 8.3 `$17` "Write motor characteristics Table": "P0 pointer to the table (start = 0,4,8
/// or 12), P1..P4 # 4 table entries (0..255) starting from the given position", with the
/// "Default-table: 255 * SIN([0.5..15.5]/32*PI)".
#[test]
fn manual_8_3_motor_characteristics_table_17() {
    let words: Vec<[u8; 9]> = table::table_requests(&SINE_TABLE)
        .into_iter()
        .map(round_trip)
        .collect();
    assert_eq!(
        words,
        [
            [PACK, 0x17, 0, 13, 37, 62, 86, 0, 0],
            [PACK, 0x17, 4, 109, 131, 152, 171, 0, 0],
            [PACK, 0x17, 8, 189, 205, 219, 231, 0, 0],
            [PACK, 0x17, 12, 240, 247, 252, 255, 0, 0],
        ]
    );
    // "e.g. table=255, 255,…, 255 -> full step".
    assert!(
        table::table_requests(&FULL_STEP_TABLE)
            .iter()
            .all(|r| matches!(r, Request::MicrostepTable { entries, .. } if *entries == [255; 4]))
    );
    // Only the four starts the manual names.
    let bad = Request::MicrostepTable {
        pointer: 2,
        entries: [0; 4],
    };
    assert_eq!(bad.validate(), Err(Error::OutOfRange { field: "pointer" }));
    assert!(RequestFrame::decode(&[PACK, 0x17, 16, 1, 2, 3, 4, 0, 0]).is_err());
}

/// 8.3 `$19` "PI-Parameter": "P0 motnr, P1 propdiv (1..255), P2,3 # intdiv (1..32767),
/// P4,5 # intclip (1..32767), P6 intinpclip (0..255)"; 7.1 defaults "propdiv=8;
/// intdiv=129; intclip=129; intinpclip=1".
#[test]
fn manual_8_3_pi_parameters_19() {
    let w = round_trip(Request::PiParameters {
        motor: 5,
        propdiv: 255,
        intdiv: 32767,
        intclip: 1,
        intinpclip: 0,
    });
    assert_eq!(w, [PACK, 0x19, 5, 255, 0xFF, 0x7F, 1, 0, 0]);
    for (propdiv, intdiv, intclip, field) in [
        (0, 129, 129, "propdiv"),
        (8, 0, 129, "intdiv"),
        (8, 32768, 129, "intdiv"),
        (8, 129, 0, "intclip"),
        (8, 129, 32768, "intclip"),
    ] {
        let bad = Request::PiParameters {
            motor: 0,
            propdiv,
            intdiv,
            intclip,
            intinpclip: 1,
        };
        assert_eq!(bad.validate(), Err(Error::OutOfRange { field }));
    }
}

/// 8.4 `$24` "Activate PI-Controller on Target Position (on-the-fly target position
/// change)": "P0 motnr, P1,2,3,4 # Target position (32 bit signed long)".
#[test]
fn manual_8_4_pi_target_24() {
    assert_eq!(
        round_trip(Request::PiTarget {
            motor: 3,
            target: 10_000
        }),
        [PACK, 0x24, 3, 0x10, 0x27, 0, 0, 0, 0]
    );
    assert_eq!(
        round_trip(Request::PiTarget {
            motor: 0,
            target: -1
        }),
        [PACK, 0x24, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0, 0]
    );
}
