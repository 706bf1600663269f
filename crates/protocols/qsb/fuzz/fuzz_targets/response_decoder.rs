//! Response lines (board → host): the incremental decoder, re-encoding what it accepts.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qsb::{Eor, Response, ResponseDecoder};

fuzz_target!(|data: &[u8]| {
    let mut decoder = ResponseDecoder::new();
    for &b in data {
        if let Some(response) = decoder.push(b) {
            let _ = response.value();
            let mut buf = [0u8; qsb::MAX_RESPONSE_LEN];
            let n = response
                .encode(Eor::FACTORY, &mut buf)
                .expect("a decoded response always encodes");
            assert_eq!(Response::decode(&buf[..n]), Ok(response));
        }
    }
    let _ = Response::decode(data);
});
