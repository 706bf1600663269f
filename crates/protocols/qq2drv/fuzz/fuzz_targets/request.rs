//! Request decoder: any bytes must decode or fail cleanly, and what decodes re-encodes to the
//! same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qq2drv::Request;

fuzz_target!(|data: &[u8]| {
    if let Ok(req) = Request::parse(data) {
        let mut buf = [0u8; 255];
        let n = req.encode(&mut buf).expect("a decoded request re-encodes");
        assert_eq!(&buf[..n], data);
    }
});
