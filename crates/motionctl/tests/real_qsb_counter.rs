//! A QSB counter mode as a user sees it through motionctl, against a real `motiond` (see
//! `real_server.rs` for where the binary comes from): a simulated QSB-D read as a wheel in
//! x1, modulo-n (count_limit 499), the index resetting the count. `list --json` shows the
//! mode among the device's machine parameters (from the config), `status --json` the
//! wheel's angle within one revolution.

mod common;

use common::real::RealServer;
use common::*;
use serde_json::Value;

const WHEEL: &str = r#"[server]
name = "demo"

[[link]]
name = "usb"
type = "sim"

[[device]]
name = "wheel_qsb"
link = "usb"
model = "qsb"
variant = "qsb-d"
count_mode = "x1"
count_range = "modulo-n"
count_limit = 499
index_action = "reset"

[[axis]]
name = "wheel"
device = "wheel_qsb"
channel = 0
unit = "deg"
counts_per_unit = 1.3888888888888888
min = 0.0
max = 360.0
max_velocity = 720.0
max_accel = 7200.0
following_error = 0.0
"#;

/// The device parameter `key` of `list`: (value, from_config).
fn param(list: &Value, key: &str) -> Result<(String, bool)> {
    let params = list["devices"][0]["params"]
        .as_array()
        .ok_or_else(|| format!("no device params in {list}"))?;
    let row = params
        .iter()
        .find(|p| p["key"] == key)
        .ok_or_else(|| format!("no {key} in {params:?}"))?;
    Ok((
        row["value"].as_str().unwrap_or_default().to_owned(),
        row["from_config"] == true,
    ))
}

#[test]
fn real_list_shows_the_counter_mode_and_status_the_wrapped_angle() -> Result {
    let server = RealServer::start_with(WHEEL)?;
    let list = json_of(&run(&server.name, &["list", "--json"])?)?;
    assert_eq!(param(&list, "count_mode")?, ("x1".to_owned(), true));
    assert_eq!(
        param(&list, "count_range")?,
        ("modulo-n 0..=499".to_owned(), true)
    );
    assert_eq!(param(&list, "index_action")?, ("reset".to_owned(), true));
    assert_eq!(
        param(&list, "index_sync")?,
        ("synchronous".to_owned(), false)
    );
    // The simulated -D's encoder swings ±250 cycles: the angle stays within one turn.
    for _ in 0..20 {
        let status = status_json(&server.name)?;
        let angle = axis_field(&status, 0, "position")
            .as_f64()
            .ok_or("position is not a number")?;
        assert!((0.0..360.0).contains(&angle), "{status}");
        std::thread::sleep(core::time::Duration::from_millis(50));
    }
    Ok(())
}
