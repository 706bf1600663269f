//! `motionctl record --out x.mcap` against the fake server of `motion_client::testing`: the
//! file reads back with the `mcap` crate's reader (chunked, with a summary), one JointState
//! message per recorded tick (the same ticks as the CSV written in the same run, by
//! sequence), the channels' topics and schemas, and the metadata records. `--plot` writes
//! an SVG. The CDR bytes themselves are pinned by the unit tests of
//! `src/joint_state_cdr.rs`.

mod common;

use std::collections::BTreeMap;

use common::*;
use motion_client::ipc::FaultCode;
use motion_client::testing::unique_name;

#[test]
fn record_to_mcap_reads_back_with_the_mcap_crate() -> Result {
    let server = fake("record-mcap")?;
    let dir = std::env::temp_dir().join(unique_name("motionctl-record-mcap"));
    std::fs::create_dir_all(&dir)?;
    let (mcap_path, csv_path, svg_path) = (
        dir.join("run.mcap"),
        dir.join("run.csv"),
        dir.join("run.svg"),
    );
    let arg = |path: &std::path::Path| path.to_str().map(str::to_owned).ok_or("path");
    let (mcap_arg, csv_arg, svg_arg) = (arg(&mcap_path)?, arg(&csv_path)?, arg(&svg_path)?);
    let output = run(
        server.name(),
        &[
            "record",
            "--duration",
            "1s",
            "--out",
            &mcap_arg,
            "--out",
            &csv_arg,
            "--plot",
            &svg_arg,
        ],
    )?;
    assert!(output.status.success(), "{output:?}");
    let bytes = std::fs::read(&mcap_path)?;
    let csv = std::fs::read_to_string(&csv_path)?;
    let svg = std::fs::read_to_string(&svg_path)?;
    std::fs::remove_dir_all(&dir)?;

    let csv_ticks: Vec<u32> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap_or("").parse::<u64>())
        .map(|tick| tick.map(|t| t as u32))
        .collect::<core::result::Result<_, _>>()?;
    assert!(!csv_ticks.is_empty());

    // The summary section is there, with chunk indexes (what Foxglove seeks by).
    let summary = mcap::Summary::read(&bytes)?.ok_or("no summary section")?;
    assert!(!summary.chunk_indexes.is_empty(), "not chunked");
    let stats = summary.stats.as_ref().ok_or("no statistics")?;
    assert_eq!(stats.metadata_count, 4);

    let topic = |what: &str| format!("/motiond/{}/{what}", server.name());
    let mut per_topic: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    let mut joint_schema = None;
    let mut first_joint_bytes = None;
    for message in mcap::MessageStream::new(&bytes)? {
        let message = message?;
        let channel = &message.channel;
        if channel.topic == topic("joint_states") {
            assert_eq!(channel.message_encoding, "cdr");
            let schema = channel.schema.as_ref().ok_or("no schema")?;
            joint_schema = Some((
                schema.name.clone(),
                schema.encoding.clone(),
                schema.data.to_vec(),
            ));
            first_joint_bytes.get_or_insert_with(|| message.data.to_vec());
            // log time = publish time = the tick's stamp, wall-clock-like (after 2020).
            assert_eq!(message.log_time, message.publish_time);
            assert!(
                message.log_time > 1_577_836_800_000_000_000,
                "{}",
                message.log_time
            );
        } else {
            assert_eq!(channel.message_encoding, "json", "{}", channel.topic);
            let schema = channel.schema.as_ref().ok_or("no schema")?;
            assert_eq!(schema.encoding, "jsonschema");
            serde_json::from_slice::<serde_json::Value>(&message.data)?;
        }
        per_topic
            .entry(channel.topic.clone())
            .or_default()
            .push(message.sequence);
    }
    // One JointState per recorded tick: the CSV's ticks, in order.
    assert_eq!(per_topic.get(&topic("joint_states")), Some(&csv_ticks));
    assert_eq!(per_topic.get(&topic("axes")), Some(&csv_ticks));
    assert!(
        per_topic.keys().all(|t| t.starts_with(&topic(""))),
        "{per_topic:?}"
    );

    let (name, encoding, definition) = joint_schema.ok_or("no JointState message")?;
    assert_eq!(name, "sensor_msgs/msg/JointState");
    assert_eq!(encoding, "ros2msg");
    let definition = String::from_utf8(definition)?;
    assert!(
        definition.contains("\nMSG: std_msgs/Header\n"),
        "{definition}"
    );
    assert!(
        definition.contains("\nMSG: builtin_interfaces/Time\n"),
        "{definition}"
    );
    let first = first_joint_bytes.ok_or("no message")?;
    assert_eq!(first[..4], [0, 1, 0, 0], "CDR little-endian encapsulation");

    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
    assert_eq!(svg.matches("<polyline").count(), 4 * count_axes(&csv));
    Ok(())
}

/// Axes in the CSV header (one `.position[` column each).
fn count_axes(csv: &str) -> usize {
    csv.lines()
        .next()
        .unwrap_or("")
        .matches(".position[")
        .count()
}

#[test]
fn an_unknown_extension_is_refused_before_recording() -> Result {
    let server = fake("record-ext")?;
    let output = run(
        server.name(),
        &[
            "record",
            "--duration",
            "1s",
            "--out",
            "/nonexistent-dir/run.bag",
        ],
    )?;
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    assert!(stderr(&output).contains("--format csv|mcap"), "{output:?}");
    Ok(())
}

#[test]
fn a_fault_is_one_message_on_the_faults_channel() -> Result {
    let server = fake("record-fault")?;
    let dir = std::env::temp_dir().join(unique_name("motionctl-record-fault"));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join("fault.mcap");
    let path_arg = path.to_str().ok_or("path")?;
    let child = command(
        server.name(),
        &["record", "--duration", "1s", "--out", path_arg, "x"],
    )
    .stdin(std::process::Stdio::null())
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped())
    .spawn()?;
    // During the recording or, on a slow machine, before its first tick: either way the
    // fault is one change from none.
    std::thread::sleep(core::time::Duration::from_millis(300));
    server.fault_axis(0, FaultCode::BoardError, 0.0, 0.0);
    let output = finish(child, core::time::Duration::from_secs(30))?;
    assert!(output.status.success(), "{output:?}");
    let bytes = std::fs::read(&path)?;
    std::fs::remove_dir_all(&dir)?;
    let topic = format!("/motiond/{}/faults", server.name());
    let mut faults = Vec::new();
    for message in mcap::MessageStream::new(&bytes)? {
        let message = message?;
        if message.channel.topic == topic {
            faults.push(serde_json::from_slice::<serde_json::Value>(&message.data)?);
        }
    }
    assert_eq!(faults.len(), 1, "{faults:?}");
    let fault = &faults[0];
    assert_eq!(fault["axis"], "x", "{fault}");
    assert_eq!(fault["code"], FaultCode::BoardError as u16, "{fault}");
    assert_eq!(fault["fault"], "board-error", "{fault}");
    assert_eq!(fault["previous"], "none", "{fault}");
    assert!(
        fault["text"].as_str().is_some_and(|text| !text.is_empty()),
        "{fault}"
    );
    Ok(())
}
