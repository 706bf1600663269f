//! Writes the files generated from the contract's description (`motion_ipc::schema`):
//! `include/motiond.h` and `python/src/motiond/_layout.py`.
//!
//! ```text
//! cargo run -p motion-ipc --example gen              # rewrite the stale ones
//! cargo run -p motion-ipc --example gen -- --check   # only say which are stale (exit 1)
//! ```
//!
//! `scripts/gen` runs the first form. Run it after changing a payload, an enumeration, a
//! constant or a service name; `tests/generated.rs` fails until the files are refreshed.

use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let check = std::env::args().skip(1).any(|arg| arg == "--check");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut stale = 0;
    for file in motion_ipc::schema::contract().generated_files() {
        let path = root.join(file.path);
        if std::fs::read_to_string(&path).is_ok_and(|now| now == file.contents) {
            println!("{}: up to date", file.path);
            continue;
        }
        stale += 1;
        if check {
            println!("{}: stale", file.path);
        } else if let Err(error) = std::fs::write(&path, &file.contents) {
            eprintln!("gen: could not write {}: {error}", path.display());
            return ExitCode::FAILURE;
        } else {
            println!("{}: written", file.path);
        }
    }
    if check && stale > 0 {
        eprintln!("gen: {stale} stale file(s): run `cargo run -p motion-ipc --example gen`");
        return ExitCode::FAILURE;
    }
    ExitCode::SUCCESS
}
