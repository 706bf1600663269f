//! Typed register values: every register with arbitrary data.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qsb::{Register, Value, Write};

fuzz_target!(|data: &[u8]| {
    if let [r, a, b, c, d, ..] = *data {
        let word = u32::from_le_bytes([a, b, c, d]);
        if let Some(register) = Register::from_u8(r) {
            if let Ok(value) = Value::decode(register, word) {
                assert_eq!(Value::decode(register, value.data()), Ok(value));
            }
            if let Ok(write) = Write::from_data(register, word) {
                assert_eq!(Write::from_data(register, write.data()), Ok(write));
            }
        }
    }
});
