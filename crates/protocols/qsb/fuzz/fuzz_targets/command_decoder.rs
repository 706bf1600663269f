//! Command lines (host → board): the incremental decoder and the typed decode of each line.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qsb::{CommandDecoder, ProductType, Request};

fuzz_target!(|data: &[u8]| {
    let mut decoder = CommandDecoder::new();
    for &b in data {
        if let Some(Ok(line)) = decoder.push(b) {
            if let Ok(request) = Request::from_line(&line) {
                let _ = request.check(ProductType::M);
                let mut buf = [0u8; qsb::MAX_COMMAND_LEN];
                let n = request.encode(&mut buf).expect("a typed request always encodes");
                assert_eq!(Request::decode(&buf[..n - qsb::EOC.len()]), Ok(request));
            }
        }
    }
    let _ = Request::decode(data);
});
