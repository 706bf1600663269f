//! The CAN 2.0A telegrams of manual 6.2: golden vectors from the manual's words, and
//! properties over every identifier and every telegram.
//!
//! The manual's rules these vectors check, quoted:
//! - "Telegrams with a fixed length of 8 bytes are used." — the RS-232 word without its
//!   address byte (6.1: "Address, command, P0 … P6"), so the data bytes are command, P0..P6.
//! - "The address of the unit (upper 8 address bits) can be set via rotary switches … The
//!   lower 3 address bits are fixed to "000". Take care: According to the CAN standard 0 is
//!   no valid address! Address range: $008 to $7F8 (in increments of 8)."
//! - "The CAN response address is transferred to PACK in a 8 bit format, like at RS 232 /
//!   485. For responding the address is shifted to the left by 3 bits, resulting in the same
//!   address range as defined above."
//! - 6.3: "To forward bytes received via CAN to RS 232, the CAN-address of the PACK is
//!   incremented by 1, i.e. the lower 3 bits are "001"."
//! - "(*) Note: The PACK has an internal cache for 16 CAN-commands, internal processing time
//!   is approx. 2 ms per command."

mod common;

use core::time::Duration;

use proptest::prelude::*;
use tmcpack::{
    Action, CAN_CACHE_COMMANDS, CAN_COMMAND_TIME, CAN_DEFAULT_BITRATE, CAN_ID_MAX, CAN_ID_MIN,
    CAN_LEN, CanBitrate, CanCache, CanChannel, CanFrame, Error, Reply, ReplyFrame, Request,
    RequestFrame, can_command_id, can_id, split_can_id,
};

/// A `$20` query to the pack at rotary address 2 with response address $FE, and its answer.
#[test]
fn a_query_goes_to_address_shl_3_and_its_answer_to_the_response_address_shl_3() {
    let query = RequestFrame::new(
        2,
        Request::QueryPosition {
            motor: 1,
            reply_to: 0xFE,
        },
    );
    let telegram = query.to_can().expect("address 2 is valid on CAN");
    // Identifier $010 = 2 << 3; data: CMD $20, P0 motnr 1, P1 response address $FE.
    assert_eq!(telegram.id, 0x010);
    assert_eq!(usize::from(telegram.len), CAN_LEN);
    assert_eq!(telegram.data, [0x20, 0x01, 0xFE, 0, 0, 0, 0, 0]);
    // The same request on RS-232 is the address byte and the same eight bytes.
    let word = query.to_word().expect("valid");
    assert_eq!(word[0], 2);
    assert_eq!(word[1..], telegram.data);

    // The answer (8.4 $20 response: CMD, motnr, posact LSB first, action, stop) comes with
    // identifier $FE << 3 = $7F0.
    let answer = ReplyFrame::new(
        0xFE,
        Reply::Position {
            motor: 1,
            position: 2000,
            action: Action::Ramp,
            stopped: false,
        },
    );
    let telegram = answer.to_can().expect("valid");
    assert_eq!(telegram.id, 0x7F0);
    assert_eq!(
        telegram.data,
        [0x20, 0x01, 0xD0, 0x07, 0x00, 0x00, 0x05, 0x00]
    );
    assert_eq!(ReplyFrame::from_can(&telegram), Ok(answer));
    assert_eq!(split_can_id(0x7F0), Ok((0xFE, CanChannel::Command)));
}

/// "$008 to $7F8 (in increments of 8)": both ends, and what lies outside.
#[test]
fn the_address_range_is_008_to_7f8() {
    assert_eq!(CAN_ID_MIN, 0x008);
    assert_eq!(CAN_ID_MAX, 0x7F8);
    assert_eq!(can_command_id(1), Ok(0x008));
    assert_eq!(can_command_id(255), Ok(0x7F8));
    assert_eq!(can_command_id(0), Err(Error::InvalidCanId(0)));
    assert_eq!(split_can_id(0x000), Err(Error::InvalidCanId(0)));
    assert_eq!(split_can_id(0x007), Err(Error::InvalidCanId(0x007)));
    assert_eq!(split_can_id(0x800), Err(Error::InvalidCanId(0x800)));
    // Lower bits 010..111 are no pack's.
    assert_eq!(split_can_id(0x00A), Err(Error::InvalidCanId(0x00A)));
    // 001: bytes for the RS-232 port (6.3), never a command.
    assert_eq!(split_can_id(0x7F9), Ok((0xFF, CanChannel::Rs232)));
    assert_eq!(can_id(0xFF, CanChannel::Rs232), Ok(0x7F9));
}

/// "Telegrams with a fixed length of 8 bytes": a shorter command or response is refused,
/// and so is one on a forwarding identifier.
#[test]
fn telegrams_have_eight_bytes() {
    let mut short = RequestFrame::new(1, Request::UnitInfo { reply_to: 0xFE })
        .to_can()
        .expect("valid");
    assert_eq!(short.data, [0x43, 0xFE, 0, 0, 0, 0, 0, 0]);
    short.len = 2;
    assert_eq!(
        RequestFrame::from_can(&short),
        Err(Error::WrongLength {
            expected: 8,
            got: 2
        })
    );
    let forward = CanFrame::rs232_forward(1, &[0x43, 0xFE]).expect("valid");
    assert_eq!(forward.id, 0x009);
    assert_eq!(
        RequestFrame::from_can(&forward),
        Err(Error::WrongLength {
            expected: 8,
            got: 2
        })
    );
}

/// The cache and the timing the note gives, and the jumper table's default.
#[test]
fn the_cache_holds_16_commands_at_2_ms_each() {
    assert_eq!(CAN_CACHE_COMMANDS, 16);
    assert_eq!(CAN_COMMAND_TIME, Duration::from_millis(2));
    // A full cache drains in 32 ms.
    assert_eq!(
        CAN_COMMAND_TIME * CAN_CACHE_COMMANDS as u32,
        Duration::from_millis(32)
    );
    assert_eq!(CAN_DEFAULT_BITRATE, 250_000);
    for rate in CanBitrate::ALL {
        assert_eq!(
            CanBitrate::from_bits_per_second(rate.bits_per_second()),
            Some(rate)
        );
    }
    assert_eq!(CanBitrate::from_bits_per_second(100_000), None);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(2000)
    ))]

    /// Every 11-bit identifier: a command identifier exactly when it is a nonzero address
    /// shifted by 3, and then it round-trips.
    #[test]
    fn identifiers_round_trip_and_nothing_else_is_a_pack(id in 0u16..=0x0FFF) {
        let command = (CAN_ID_MIN..=CAN_ID_MAX).contains(&id) && id % 8 == 0;
        match split_can_id(id) {
            Ok((address, CanChannel::Command)) => {
                prop_assert!(command, "{id:#x}");
                prop_assert_eq!(can_command_id(address), Ok(id));
            }
            Ok((address, CanChannel::Rs232)) => {
                prop_assert_eq!(id & 7, 1);
                prop_assert_eq!(can_id(address, CanChannel::Rs232), Ok(id));
            }
            Err(e) => {
                prop_assert!(!command, "{id:#x}");
                prop_assert_eq!(e, Error::InvalidCanId(id));
            }
        }
    }

    /// A request and its reply travel as the RS-232 word without its address: the same
    /// data bytes, the address in the identifier.
    #[test]
    fn a_telegram_is_the_word_without_its_address(
        address in 1u8..=255,
        req in common::request(),
        rep in common::reply(),
    ) {
        let request = RequestFrame::new(address, req);
        let word = request.to_word().expect("valid");
        let telegram = request.to_can().expect("valid");
        prop_assert_eq!(telegram.id, u16::from(address) << 3);
        prop_assert_eq!(&telegram.data[..], &word[1..]);
        prop_assert_eq!(RequestFrame::from_can(&telegram), Ok(request));
        let reply = ReplyFrame::new(address, rep);
        let telegram = reply.to_can().expect("valid");
        prop_assert_eq!(&telegram.data[..], &reply.to_word().expect("valid")[1..]);
        prop_assert_eq!(ReplyFrame::from_can(&telegram), Ok(reply));
    }

    /// Any telegram, garbage included: decoding never panics, and what decodes re-encodes
    /// to the same identifier and command byte.
    #[test]
    fn garbage_never_panics(id in any::<u16>(), len in any::<u8>(), data in any::<[u8; 8]>()) {
        let frame = CanFrame { id, len, data };
        let _ = frame.payload();
        if let Ok(r) = RequestFrame::from_can(&frame) {
            let again = r.to_can().expect("decoded requests are valid");
            prop_assert_eq!((again.id, again.data[0]), (id, data[0]));
        }
        if let Ok(r) = ReplyFrame::from_can(&frame) {
            let again = r.to_can().expect("decoded replies are valid");
            prop_assert_eq!((again.id, again.data[0]), (id, data[0]));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(2000)
    ))]

    /// Arrivals at any times (steps of 0..=3 ms) with polls in between: at most 16 wait,
    /// a telegram is refused exactly when 16 wait, and the accepted ones come out once each,
    /// in order, 2 ms apart at least.
    #[test]
    fn the_cache_keeps_order_and_its_bound(
        ops in prop::collection::vec((0u64..=3000, any::<bool>()), 0..200),
    ) {
        let mut cache = CanCache::<u32>::new();
        let mut now = Duration::ZERO;
        let mut accepted = std::collections::VecDeque::new();
        let mut last: Option<Duration> = None;
        for (n, (step_us, poll_only)) in ops.into_iter().enumerate() {
            now += Duration::from_micros(step_us);
            while let Some((done, item)) = cache.pop_done(now) {
                prop_assert_eq!(accepted.pop_front(), Some(item));
                if let Some(before) = last {
                    prop_assert!(done >= before + CAN_COMMAND_TIME);
                }
                last = Some(done);
            }
            if poll_only {
                continue;
            }
            let full = cache.waiting(now) >= CAN_CACHE_COMMANDS;
            match cache.push(now, n as u32) {
                Ok(done) => {
                    prop_assert!(!full);
                    prop_assert!(done >= now + CAN_COMMAND_TIME);
                    accepted.push_back(n as u32);
                }
                Err(item) => {
                    prop_assert!(full);
                    prop_assert_eq!(item, n as u32);
                    prop_assert!(cache.room_at(now) > now);
                }
            }
            prop_assert!(cache.waiting(now) <= CAN_CACHE_COMMANDS);
        }
    }
}

/// A burst of 20 telegrams at once: 16 are taken, 4 lost; the 16 finish 2 ms apart.
#[test]
fn a_burst_beyond_16_loses_the_rest() {
    let mut cache = CanCache::<u8>::new();
    let t0 = Duration::from_millis(5);
    let taken = (0..20u8).filter(|&n| cache.push(t0, n).is_ok()).count();
    assert_eq!(taken, 16);
    assert_eq!(cache.dropped(), 4);
    assert_eq!(cache.room_at(t0), t0 + CAN_COMMAND_TIME);
    assert_eq!(cache.idle_at(t0), t0 + CAN_COMMAND_TIME * 16);
    let mut done = Vec::new();
    while let Some((at, n)) = cache.pop_done(t0 + Duration::from_secs(1)) {
        done.push((at, n));
    }
    assert_eq!(done.len(), 16);
    for (k, (at, n)) in done.into_iter().enumerate() {
        assert_eq!(usize::from(n), k);
        assert_eq!(at, t0 + CAN_COMMAND_TIME * (k as u32 + 1));
    }
}
