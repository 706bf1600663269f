//! The checked-in files generated from the contract (`include/motiond.h`,
//! `python/src/motiond/_layout.py`) are exactly what the generator writes now.

use std::path::Path;

#[test]
fn generated_files_are_up_to_date() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut stale = Vec::new();
    for file in motion_ipc::schema::contract().generated_files() {
        let now = std::fs::read_to_string(root.join(file.path)).unwrap_or_default();
        if now != file.contents {
            let line = now
                .lines()
                .zip(file.contents.lines())
                .position(|(have, want)| have != want)
                .unwrap_or_else(|| now.lines().count().min(file.contents.lines().count()));
            stale.push(format!(
                "{} (first difference at line {})",
                file.path,
                line + 1
            ));
        }
    }
    assert!(
        stale.is_empty(),
        "stale generated files: {}\nrefresh them with `cargo run -p motion-ipc --example gen` \
         (or scripts/gen) and commit the result",
        stale.join(", ")
    );
}
