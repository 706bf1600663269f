//! Property round trips for every request and reply type, over the 9-byte and CAN forms.

mod common;

use proptest::prelude::*;
use tmcpack::{ReplyFrame, RequestFrame};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        // scripts/fuzz without a nightly toolchain asks for more.
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(2000)
    ))]

    #[test]
    fn request_round_trip(address in any::<u8>(), req in common::request()) {
        let frame = RequestFrame::new(address, req);
        let mut buf = [0u8; 12];
        prop_assert_eq!(frame.encode(&mut buf), Ok(9));
        prop_assert_eq!(buf[1], req.command().code());
        prop_assert_eq!(RequestFrame::decode(&buf[..9]), Ok(frame));
        prop_assert_eq!(&buf[9..], &[0u8; 3]);
        if address != 0 {
            let can = frame.to_can().expect("address is valid on CAN");
            prop_assert_eq!(can.id, u16::from(address) << 3);
            prop_assert_eq!(RequestFrame::from_can(&can), Ok(frame));
        }
    }

    #[test]
    fn reply_round_trip(address in any::<u8>(), rep in common::reply()) {
        let frame = ReplyFrame::new(address, rep);
        let mut buf = [0u8; 9];
        prop_assert_eq!(frame.encode(&mut buf), Ok(9));
        prop_assert_eq!(ReplyFrame::decode(&buf), Ok(frame));
        if address != 0 {
            let can = frame.to_can().expect("address is valid on CAN");
            prop_assert_eq!(ReplyFrame::from_can(&can), Ok(frame));
        }
    }

    /// A decoded word re-encodes to the same bytes except the unused ones, which the pack
    /// ignores and we send as zero.
    #[test]
    fn decode_then_encode_is_stable(w in any::<[u8; 9]>()) {
        if let Ok(f) = RequestFrame::decode(&w) {
            let again = f.to_word().expect("decoded requests are valid");
            prop_assert_eq!(RequestFrame::decode(&again), Ok(f));
        }
        if let Ok(f) = ReplyFrame::decode(&w) {
            let again = f.to_word().expect("decoded replies are valid");
            prop_assert_eq!(ReplyFrame::decode(&again), Ok(f));
        }
    }
}
