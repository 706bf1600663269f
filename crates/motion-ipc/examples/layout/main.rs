//! Prints the shared-memory contract of this build as JSON (`motion_ipc::schema`): every
//! payload's size, alignment, iceoryx2 type name and fields, every enumeration, the flag
//! bits, the constants and the service name formats.
//!
//! ```text
//! cargo run -p motion-ipc --example layout > layout.json
//! ```
//!
//! The Python package's tests (`python/tests/test_layout.py`) compare its ctypes mirrors
//! with this output; `tests/c_header.rs` checks `include/motiond.h` against the same data.

fn main() {
    print!("{}", motion_ipc::schema::contract().to_json());
}
