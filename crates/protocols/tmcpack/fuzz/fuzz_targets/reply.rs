#![no_main]
//! Any bytes through the reply decoder; a decoded reply must re-encode and decode equal.

use libfuzzer_sys::fuzz_target;
use tmcpack::ReplyFrame;

fuzz_target!(|data: &[u8]| {
    if let Ok(f) = ReplyFrame::decode(data) {
        let w = f.to_word().expect("a decoded reply is valid");
        assert_eq!(ReplyFrame::decode(&w), Ok(f));
    }
});
