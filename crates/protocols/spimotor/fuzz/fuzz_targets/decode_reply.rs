//! Any MISO bytes for any read port (chosen by the first input byte): the reply decoder
//! must not panic, and whatever it accepts must encode back to an equal reply.
#![no_main]

use libfuzzer_sys::fuzz_target;
use spimotor::{REPLY_OFFSET, ReadPort, Reply};

fuzz_target!(|input: &[u8]| {
    let Some((&selector, miso)) = input.split_first() else {
        return;
    };
    let port = ReadPort::ALL[usize::from(selector) % ReadPort::ALL.len()];
    if let Ok(reply) = Reply::decode(port, miso) {
        let mut out = vec![0u8; REPLY_OFFSET + reply.len()];
        reply.encode_miso(&mut out);
        assert_eq!(Reply::decode(port, &out), Ok(reply));
    }
});
