//! Every black box in `tests/recordings/` replays frame for frame on today's drivers and
//! engine (docs/BLACKBOX.md; `scripts/record-fixture` records them): a change that
//! makes the server answer the same inputs differently fails here, with the first tick
//! and region or byte that differs. Re-record only for a change meant to do that.

use std::path::PathBuf;

#[test]
fn every_recording_in_tests_recordings_replays_frame_for_frame() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/recordings");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/recordings")
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "mcap"))
        .collect();
    files.sort();
    assert!(!files.is_empty(), "no recordings in {}", dir.display());
    for file in files {
        let recording = motion_blackbox::read(&file).expect("a black box");
        let config = motion_config::ServerConfig::parse(&file, recording.config_text())
            .expect("its recorded config is valid");
        let replayed = motion_blackbox::replay(&config, &recording)
            .unwrap_or_else(|error| panic!("{}: {error}", file.display()));
        assert_eq!(replayed.ticks as usize, recording.ticks.len());
        assert!(
            replayed.ticks > 100,
            "{}: {} ticks",
            file.display(),
            replayed.ticks
        );
    }
}
