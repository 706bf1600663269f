//! `motionctl blackbox save FILE.mcap` against a real `motiond` on `config/sim.toml`: the
//! server saves its black box, motionctl copies it and says where both are, and the copy
//! replays frame for frame (`motiond --replay`); the server's stats count no black-box
//! record lost.

mod common;

use std::process::Command;

use common::real::{RealServer, motiond_binary};
use common::*;

#[test]
fn blackbox_save_copies_the_servers_file_and_the_copy_replays() -> Result {
    let server = RealServer::start()?;
    let out = std::env::temp_dir().join(format!("{}-saved.mcap", server.name));
    let output = run(
        &server.name,
        &["blackbox", "save", &out.display().to_string()],
    )?;
    let text = String::from_utf8_lossy(&output.stdout).into_owned();
    assert!(output.status.success(), "{output:?}");
    assert!(
        text.contains(&format!("black box saved: {}", out.display())),
        "{text}"
    );
    let servers = text
        .split("the server's copy: ")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .ok_or_else(|| format!("the server's copy is named: {text}"))?;
    assert!(std::path::Path::new(servers).exists(), "{servers}");
    assert!(text.contains("motiond --replay"), "{text}");
    let bytes = std::fs::read(&out)?;
    assert!(bytes.starts_with(b"\x89MCAP0\r\n"), "an MCAP file");
    let replay = Command::new(motiond_binary()?)
        .arg("--replay")
        .arg(&out)
        .output()?;
    let said = String::from_utf8_lossy(&replay.stdout);
    assert!(replay.status.success(), "{said} {replay:?}");
    assert!(said.contains("frames identical"), "{said}");
    // A replay that went through crossed no hole: the server says it dropped no record.
    let status = poll_json(&server.name, &["status", "--json"], |status| {
        status["stats"]["blackbox_lost"].as_u64().is_some()
    })?;
    assert_eq!(status["stats"]["blackbox_lost"], 0, "{status}");
    let _ = std::fs::remove_file(&out);
    Ok(())
}
