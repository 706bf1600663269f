//! The `motion-bridge` binary as a user starts it: its help, and a config it refuses
//! before it opens anything. (Having an integration test also makes `cargo test
//! --workspace` build the binary beside the other test executables, where
//! motion-bridge-tests' process tests find it: without one, they would find a stale binary
//! from an earlier build, or none.)

use std::process::Command;

fn bridge() -> Command {
    Command::new(env!("CARGO_BIN_EXE_motion-bridge"))
}

#[test]
fn help_names_the_server_the_config_and_the_zenoh_config() {
    let out = bridge().arg("--help").output().expect("motion-bridge runs");
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    for flag in ["--server", "--config", "--zenoh-config", "--insecure"] {
        assert!(text.contains(flag), "{flag} missing from:\n{text}");
    }
}

#[test]
fn a_config_that_is_not_toml_is_refused_with_exit_status_1() {
    let dir = std::env::temp_dir().join(format!("motion-bridge-binary-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bridge.toml");
    std::fs::write(&path, "[[remote]\nidentity = ").expect("write config");
    let out = bridge()
        .args(["--server", "nonesuch", "--config"])
        .arg(&path)
        .output()
        .expect("motion-bridge runs");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(
        text.contains("bridge.toml"),
        "the error names the file:\n{text}"
    );
}
