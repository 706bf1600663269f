//! The Trinamic pack's drive functions as a user sees them through motionctl, against a
//! real `motiond` on the simulated robot (`config/sim.toml`; see `real_server.rs` for where
//! the binary comes from): the QUADpack `pack_aux` has `power_down = "restore"` and its
//! `camera_pan` axis the PI position mode. `list --json` shows the power-down mode among the
//! device's parameters (from the config) and its state in the description (the pack armed,
//! nothing loaded on a fresh start), the axis's position mode and `$19` parameters.

mod common;

use common::real::RealServer;
use common::*;
use serde_json::Value;

/// The parameter `key` of `list`'s `owner` (`devices` or `axes`) named `name`: (value,
/// from_config).
fn param(list: &Value, owner: &str, name: &str, key: &str) -> Result<(String, bool)> {
    let entry = list[owner]
        .as_array()
        .and_then(|all| all.iter().find(|e| e["name"] == name))
        .ok_or_else(|| format!("no {owner} {name} in {list}"))?;
    let row = entry["params"]
        .as_array()
        .and_then(|rows| rows.iter().find(|p| p["key"] == key))
        .ok_or_else(|| format!("no {key} in {entry}"))?;
    Ok((
        row["value"].as_str().unwrap_or_default().to_owned(),
        row["from_config"] == true,
    ))
}

#[test]
fn real_list_shows_the_power_down_mode_its_state_and_the_pi_axis() -> Result {
    let server = RealServer::start()?;
    let list = poll_json(&server.name, &["list", "--json"], |list| {
        list["devices"]
            .as_array()
            .and_then(|all| all.iter().find(|d| d["name"] == "pack_aux"))
            .is_some_and(|d| {
                d["firmware"]
                    .as_str()
                    .is_some_and(|f| f.ends_with("PD armed"))
            })
    })?;
    let aux = list["devices"]
        .as_array()
        .and_then(|all| all.iter().find(|d| d["name"] == "pack_aux"))
        .ok_or("no pack_aux")?;
    assert_eq!(aux["firmware"], "QUADpack V1.4.9 #1001 PD armed");
    assert_eq!(
        param(&list, "devices", "pack_aux", "power_down")?,
        ("restore (save; loaded after a boot)".to_owned(), true)
    );
    assert_eq!(
        param(&list, "devices", "pack_xyz", "power_down")?,
        ("off (no $45)".to_owned(), false)
    );
    // Without the key the description is as it always was.
    let xyz = list["devices"]
        .as_array()
        .and_then(|all| all.iter().find(|d| d["name"] == "pack_xyz"))
        .ok_or("no pack_xyz")?;
    assert_eq!(xyz["firmware"], "SIXpack V1.4.9 s/n 1001");
    assert_eq!(
        param(&list, "axes", "camera_pan", "position_mode")?,
        ("pi ($24 PI controller)".to_owned(), true)
    );
    assert_eq!(
        param(&list, "axes", "camera_pan", "pi.propdiv")?,
        ("8 ($19)".to_owned(), false)
    );
    assert_eq!(
        param(&list, "axes", "camera_tilt", "position_mode")?,
        ("ramp ($14, $26, $23)".to_owned(), false)
    );
    // A ramp move keeps the trapezoid on the PI axis too, and arrives.
    let moved = run(&server.name, &["move", "camera_pan", "20", "--wait"])?;
    assert!(moved.status.success(), "{}", stderr(&moved));
    let status = status_json(&server.name)?;
    let pan = status["axes"]
        .as_array()
        .and_then(|all| all.iter().position(|a| a["name"] == "camera_pan"))
        .ok_or("no camera_pan")?;
    let at = axis_field(&status, pan, "position")
        .as_f64()
        .ok_or("position is not a number")?;
    assert!((at - 20.0).abs() < 0.2, "{status}");
    Ok(())
}
