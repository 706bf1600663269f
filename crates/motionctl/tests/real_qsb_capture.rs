//! Capture, the trigger output and `hold` / `resume` of an axis as a user sees them
//! through motionctl, against a real `motiond` on the simulated robot (`config/sim.toml`,
//! see `real_server.rs` for where the binary comes from) whose feeder QSB-M pulses a
//! camera trigger on io0 at its index and at 25 mm (`trigger_on = ["match", "index"]`,
//! `compare_position`), and so captures the count at every index (MDR1 B4 "Trigger/Capture
//! on Index"): every 20 mm of the feeder's 500-cycle encoder. `io list` and `io get`
//! show both kinds with their events, `io events` prints the captures as they come, `io
//! compare` moves the compare position, `hold` and `resume` pause and continue a move.

mod common;

use core::time::Duration;
use std::process::Stdio;

use common::real::{RealServer, sim_config};
use common::*;
use serde_json::Value;

/// `config/sim.toml` with the feeder's io0 (the jam sensor there) as a camera trigger and
/// its index captures as a probe.
fn sim_config_with_a_camera() -> Result<String> {
    let config = sim_config()?;
    let device = "name = \"feeder_qsb\"\n";
    let jam = config
        .find("[[signal]]\nname = \"feeder_jam\"")
        .ok_or("config/sim.toml has no feeder_jam signal")?;
    let end = config[jam + 1..]
        .find("\n[[")
        .map_or(config.len(), |at| jam + 1 + at + 1);
    let signals = "[[signal]]\nname = \"probe\"\ndevice = \"feeder_qsb\"\npin = \"capture\"\nkind = \"capture\"\n\n\
                   [[signal]]\nname = \"camera\"\ndevice = \"feeder_qsb\"\npin = \"trigger\"\nkind = \"trigger\"\n\n";
    let config = format!("{}{signals}{}", &config[..jam], &config[end..]);
    if !config.contains(device) {
        return Err("config/sim.toml has no feeder_qsb device".into());
    }
    Ok(config.replacen(
        device,
        &format!("{device}trigger_on = [\"match\", \"index\"]\ncompare_position = 25.0\n"),
        1,
    ))
}

fn signal<'a>(list: &'a Value, name: &str) -> &'a Value {
    list["signals"]
        .as_array()
        .and_then(|signals| signals.iter().find(|s| s["name"] == name))
        .unwrap_or(&Value::Null)
}

fn feeder(status: &Value) -> Value {
    status["axes"]
        .as_array()
        .and_then(|axes| axes.iter().find(|axis| axis["name"] == "feeder"))
        .cloned()
        .unwrap_or(Value::Null)
}

fn has_flag(axis: &Value, flag: &str) -> bool {
    axis["flags"]
        .as_array()
        .is_some_and(|flags| flags.iter().any(|f| f == flag))
}

#[test]
fn real_captures_and_trigger_pulses_are_listed_waited_for_and_the_feeder_holds() -> Result {
    let server = RealServer::start_with(&sim_config_with_a_camera()?)?;
    let name = server.name.clone();
    let list = json_of(&run(&name, &["io", "list", "--json"])?)?;
    let (probe, camera) = (signal(&list, "probe"), signal(&list, "camera"));
    assert_eq!(
        (probe["kind"].clone(), probe["unit"].clone()),
        ("capture".into(), "mm".into())
    );
    assert_eq!(probe["sequence"], 0);
    assert_eq!(camera["kind"], "trigger");
    assert_eq!(
        camera["value"], 25.0,
        "the compare position, in the feeder's mm"
    );

    // Two captures as they come: the feeder passes its index at 20 and 40 mm.
    let events = command(
        &name,
        &[
            "io",
            "events",
            "probe",
            "--count",
            "2",
            "--json",
            "--timeout",
            "20s",
        ],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    std::thread::sleep(Duration::from_millis(500));
    let moved = run(&name, &["move", "feeder", "50", "--wait"])?;
    assert!(moved.status.success(), "{moved:?}");
    let events = finish(events, DEADLINE)?;
    assert!(events.status.success(), "{events:?}");
    let lines: Vec<Value> = stdout(&events)
        .lines()
        .map(serde_json::from_str)
        .collect::<core::result::Result<_, _>>()?;
    assert_eq!(lines.len(), 2, "{lines:?}");
    for (line, at) in lines.iter().zip([20.0, 40.0]) {
        let value = line["value"].as_f64().ok_or("a value")?;
        assert!((value - at).abs() < 0.05, "a capture at the index: {line}");
        assert_eq!(line["missed"], 0);
    }
    assert_eq!(lines[1]["sequence"], 2);

    // Three pulses: the index at 20 mm, the match at 25 mm, the index at 40 mm.
    let camera = poll_json(&name, &["io", "get", "camera", "--json"], |c| {
        c["sequence"] == 3
    })?;
    assert!(
        camera["event_tick"].as_u64().is_some_and(|t| t > 0),
        "{camera}"
    );
    let text = stdout(&run(&name, &["io", "get", "camera"])?);
    assert!(text.contains("event 3 at tick"), "{text}");

    // A new compare position, in mm.
    let output = run(&name, &["io", "compare", "camera", "10"])?;
    assert!(output.status.success(), "{output:?}");
    assert!(
        stdout(&output).contains("camera: fires at 10 mm"),
        "{output:?}"
    );
    poll_json(&name, &["io", "get", "camera", "--json"], |c| {
        c["value"] == 10.0 && c["flags"].as_array().is_some_and(Vec::is_empty)
    })?;
    assert_fails(
        &run(&name, &["io", "compare", "probe", "1"])?,
        4,
        "not an output",
    );
    assert_fails(
        &run(&name, &["io", "events", "lamp", "--count", "1"])?,
        1,
        "only capture and trigger signals have events",
    );

    // Hold a slow move on its way (the QSB-M's COMMAND 6), resume it (COMMAND 7).
    assert_fails(&run(&name, &["hold", "feeder"])?, 4, "no position move");
    let output = run(&name, &["move", "feeder", "90", "--velocity", "20"])?;
    assert!(output.status.success(), "{output:?}");
    std::thread::sleep(Duration::from_millis(600));
    let output = run(&name, &["hold", "feeder"])?;
    assert!(output.status.success(), "{output:?}");
    assert!(stdout(&output).contains("feeder: held"), "{output:?}");
    let status = poll_json(&name, &["status", "--json"], |s| {
        let axis = feeder(s);
        axis["mode"] == "hold" && has_flag(&axis, "held")
    })?;
    let at = feeder(&status)["position"].as_f64().ok_or("a position")?;
    assert!(at > 50.0 && at < 85.0, "held on its way: {at}");
    std::thread::sleep(Duration::from_millis(300));
    let still = feeder(&status_json(&name)?)["position"]
        .as_f64()
        .ok_or("position")?;
    assert!((still - at).abs() < 0.05, "stays held: {at} → {still}");
    let output = run(&name, &["resume", "feeder"])?;
    assert!(output.status.success(), "{output:?}");
    poll_json(&name, &["status", "--json"], |s| {
        let axis = feeder(s);
        has_flag(&axis, "arrived")
            && axis["position"]
                .as_f64()
                .is_some_and(|p| (p - 90.0).abs() < 0.05)
    })?;
    assert_fails(
        &run(&name, &["resume", "feeder"])?,
        4,
        "held move to resume",
    );
    Ok(())
}
