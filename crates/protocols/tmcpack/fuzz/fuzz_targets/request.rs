#![no_main]
//! Any bytes through the request decoder; a decoded request must re-encode and decode equal.

use libfuzzer_sys::fuzz_target;
use tmcpack::RequestFrame;

fuzz_target!(|data: &[u8]| {
    if let Ok(f) = RequestFrame::decode(data) {
        let w = f.to_word().expect("a decoded request is valid");
        assert_eq!(RequestFrame::decode(&w), Ok(f));
    }
});
