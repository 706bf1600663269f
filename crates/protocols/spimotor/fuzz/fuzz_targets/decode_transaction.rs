//! Any MOSI bytes: the transaction decoder must not panic, and whatever it accepts must
//! re-encode to bytes that decode to the same transaction.
#![no_main]

use libfuzzer_sys::fuzz_target;
use spimotor::{Header, Transaction};

fuzz_target!(|mosi: &[u8]| {
    let _ = Header::decode(mosi);
    if let Ok(t) = Transaction::decode(mosi) {
        let mut buf = vec![0u8; t.len()];
        let n = t.encode(&mut buf).expect("sized to fit");
        assert_eq!(Transaction::decode(&buf[..n]), Ok(t));
    }
});
