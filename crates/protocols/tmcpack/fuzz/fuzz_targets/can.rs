#![no_main]
//! Any CAN telegram (2 bytes identifier, 1 byte length, 8 data bytes) through the decoders.

use libfuzzer_sys::fuzz_target;
use tmcpack::{CanFrame, ReplyFrame, RequestFrame};

fuzz_target!(|data: &[u8]| {
    let mut b = [0u8; 11];
    for (slot, x) in b.iter_mut().zip(data) {
        *slot = *x;
    }
    let mut payload = [0u8; 8];
    payload.copy_from_slice(&b[3..]);
    let frame = CanFrame {
        id: u16::from_le_bytes([b[0], b[1]]),
        len: b[2],
        data: payload,
    };
    let _ = frame.payload();
    if let Ok(r) = RequestFrame::from_can(&frame) {
        assert_eq!(r.to_can().map(|f| f.id), Ok(frame.id));
    }
    if let Ok(r) = ReplyFrame::from_can(&frame) {
        assert_eq!(r.to_can().map(|f| f.id), Ok(frame.id));
    }
});
