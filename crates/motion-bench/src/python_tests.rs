//! Tests of the Python client phase: the child's document (good, truncated, garbage,
//! inconsistent), the rows, and children that fail, print garbage or hang.

use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::path::PathBuf;
use std::time::Instant;

use serde_json::json;

use super::*;

fn document(frames: Value, rtt: Value) -> Value {
    json!({
        "format": "motiond.bench/1",
        "server": "demo",
        "tick_hz": 1000,
        "axis_count": 18,
        "duration_s": 1.0,
        "python": "CPython 3.11.7",
        "iceoryx2": "0.10.0",
        "motiond_package": "0.1.0",
        "clock": "clock_gettime(CLOCK_MONOTONIC)",
        "frames": {
            "waiting": "for frame in client.frames()",
            "received": frames["count"].as_u64().unwrap_or(0) + 1,
            "lost": 2,
            "negative": 1,
            "latency_ns": frames,
        },
        "commands": {
            "probe": "Stop on axis 18",
            "axis_index": 18,
            "sent": 5,
            "replies": {"UNKNOWN_AXIS": rtt["count"].as_u64().unwrap_or(0)},
            "wrong_reason": 0,
            "no_reply": 1,
            "rtt_ns": rtt,
        },
    })
}

fn good() -> Value {
    document(
        json!({"count": 4, "p50": 20_000, "samples": [10_000, 20_000, 30_000, 40_000]}),
        json!({"count": 4, "histogram": [[500_000, 3], [1_000_000, 1]]}),
    )
}

#[test]
fn a_good_document_becomes_distributions_and_counts() {
    let run = parse(&good().to_string()).expect("good document");
    let frames = run.frames.summary();
    assert_eq!(frames.samples, 4);
    assert!((19_980..=20_020).contains(&frames.p50), "{frames:?}");
    assert!((39_960..=40_040).contains(&frames.max), "{frames:?}");
    let rtt = run.rtt.summary();
    assert_eq!(rtt.samples, 4);
    assert!((499_000..=501_000).contains(&rtt.p50), "{rtt:?}");
    assert!((999_000..=1_001_000).contains(&rtt.max), "{rtt:?}");
    assert_eq!((run.received, run.lost, run.negative), (5, 2, 1));
    assert_eq!((run.sent, run.wrong_reason, run.no_reply), (5, 0, 1));
    assert_eq!(run.replies.get("UNKNOWN_AXIS"), Some(&4));
    assert_eq!(run.python, "CPython 3.11.7");
    assert_eq!(run.iceoryx2, "0.10.0");
    assert_eq!(run.clock, "clock_gettime(CLOCK_MONOTONIC)");
    // A line printed before the document (a stray warning) does not hide it.
    let noisy = format!("warning: something\n{}\n", good());
    assert_eq!(parse(&noisy).expect("last line").frames.summary(), frames);
}

#[test]
fn truncated_garbage_and_empty_output_are_errors_not_panics() {
    let text = good().to_string();
    for cut in [1, text.len() / 3, text.len() / 2, text.len() - 1] {
        let error = parse(&text[..cut]).expect_err("truncated");
        assert!(matches!(error, PythonError::BadOutput(_)), "{error:?}");
    }
    for garbage in [
        "",
        "   \n",
        "Traceback (most recent call last):",
        "\u{0}\u{1}",
        "[1, 2]",
        "null",
        "42",
    ] {
        let error = parse(garbage).expect_err(garbage);
        assert!(
            matches!(error, PythonError::BadOutput(_)),
            "{garbage:?}: {error:?}"
        );
        assert!(!error.to_string().is_empty());
    }
}

#[test]
fn documents_that_do_not_add_up_are_refused_with_the_reason() {
    let mut wrong_format = good();
    wrong_format["format"] = json!("motiond.bench/0");
    let mut negative = good();
    negative["frames"]["latency_ns"]["samples"][0] = json!(-5);
    let mut count = good();
    count["frames"]["latency_ns"]["count"] = json!(7);
    let mut received = good();
    received["frames"]["received"] = json!(100);
    let mut replies = good();
    replies["commands"]["replies"] = json!({"UNKNOWN_AXIS": 1});
    let mut pair = good();
    pair["commands"]["rtt_ns"]["histogram"] = json!([[500_000]]);
    let mut neither = good();
    neither["commands"]["rtt_ns"] = json!({"count": 0});
    let mut missing = good();
    missing.as_object_mut().map(|o| o.remove("python"));
    for (doc, words) in [
        (wrong_format, "format"),
        (negative, "non-negative"),
        (count, "count 7"),
        (received, "received 100"),
        (replies, "round trips"),
        (pair, "[ns, count]"),
        (neither, "neither"),
        (missing, "`python`"),
    ] {
        let error = parse(&doc.to_string()).expect_err(words);
        assert!(error.to_string().contains(words), "{words}: {error}");
    }
}

#[test]
fn the_rows_put_python_beside_the_rust_clients_with_ratios() {
    let run = parse(&good().to_string()).expect("good");
    let rust = |p50, p99| Summary {
        samples: 100,
        p50,
        p99,
        p999: p99,
        max: p99,
    };
    let rows = rows(
        &run,
        rust(10_000, 20_000),
        rust(250_000, 1_000_000),
        CommandProbe::UnknownAxis,
    );
    assert_eq!(rows.len(), 2);
    assert!(
        rows[0].figure.starts_with("frame delivery, Python client"),
        "{}",
        rows[0].figure
    );
    assert!(
        rows[1]
            .figure
            .starts_with("command round trip, Python client"),
        "{}",
        rows[1].figure
    );
    assert!(rows[0].baseline_label.contains("WaitSet"));
    assert_eq!(rows[0].baseline, Some(rust(10_000, 20_000)));
    let (p50, _) = rows[0].ratios().expect("ratio");
    assert!((1.99..=2.01).contains(&p50), "{p50}");
    let (p50, p99) = rows[1].ratios().expect("ratio");
    assert!((1.99..=2.01).contains(&p50), "{p50}");
    assert!((0.99..=1.01).contains(&p99), "{p99}");
    assert!(rows[0].note.contains("lost ticks 2") && rows[0].note.contains("CPython 3.11.7"));
    assert!(rows[1].note.contains("UNKNOWN_AXIS ×4") && rows[1].note.contains("no reply 1"));
    let claim = rows_claim(&run);
    assert!(claim[1].note.contains("claim-release"), "{}", claim[1].note);
    // In the JSON report the two rows carry ratio keys like every other row.
    let report = crate::Report {
        rows,
        ..Default::default()
    };
    let json = report.json();
    for row in json["rows"].as_array().expect("rows") {
        assert!(
            row["ratio_p50"].is_f64() && row["ratio_p99"].is_f64(),
            "{row}"
        );
    }
    // An empty Python distribution gives no ratio, not a division by zero.
    let mut empty = run;
    empty.frames = Dist::new();
    let row = &rows_claim(&empty)[0];
    assert!(row.ratios().is_none());
}

fn rows_claim(run: &PythonRun) -> Vec<Row> {
    let s = Summary {
        samples: 1,
        p50: 1,
        p99: 1,
        p999: 1,
        max: 1,
    };
    rows(run, s, s, CommandProbe::ClaimRelease)
}

/// An executable shell script standing in for the interpreter.
fn fake_python(tag: &str, body: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motion-bench-py-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("python");
    std::fs::write(&path, format!("#!/bin/sh\n{body}\n")).expect("script");
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    path
}

#[test]
fn a_child_that_prints_garbage_or_fails_gives_its_reason() {
    let garbage = fake_python("garbage", "echo 'not json at all'");
    let error = measure(&garbage, "demo", Duration::from_millis(10)).expect_err("garbage");
    assert!(
        matches!(&error, PythonError::BadOutput(t) if t.contains("not json")),
        "{error}"
    );

    let fails = fake_python(
        "fails",
        "echo 'motiond.bench: no motiond server named \"x\"' >&2; exit 3",
    );
    let error = measure(&fails, "x", Duration::from_millis(10)).expect_err("exit 3");
    let text = error.to_string();
    assert!(matches!(error, PythonError::Child(_)), "{text}");
    assert!(
        text.contains("no motiond server named") && text.contains('3'),
        "{text}"
    );

    let error = check(&fails).expect_err("cannot import");
    assert!(matches!(error, PythonError::Unusable { .. }), "{error}");
    let missing = PathBuf::from("/nonexistent/motion-bench/python");
    let error = find_python(Some(&missing)).expect_err("no such file");
    assert!(error.to_string().contains("could not start"), "{error}");

    let ok = fake_python("ok", "exit 0");
    assert_eq!(find_python(Some(&ok)), Ok(ok.clone()));
    for path in [garbage, fails, ok] {
        let _ = std::fs::remove_dir_all(path.parent().expect("dir"));
    }
}

#[test]
fn a_hanging_child_is_killed_with_its_children() {
    let hangs = fake_python("hangs", "echo started >&2; sleep 30 & sleep 30; echo never");
    let started = Instant::now();
    let error =
        run_with_timeout(Command::new(&hangs), Duration::from_millis(300)).expect_err("hang");
    assert!(
        started.elapsed() < Duration::from_secs(10),
        "{:?}",
        started.elapsed()
    );
    assert!(
        error.contains("killed") && error.contains("started"),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(hangs.parent().expect("dir"));
}

#[test]
fn a_flood_on_stdout_is_cut_short() {
    let started = Instant::now();
    let mut command = Command::new("sh");
    command.args(["-c", "yes garbage-line"]);
    let error = run_with_timeout(command, Duration::from_secs(60)).expect_err("flood");
    assert!(error.contains("MiB on stdout"), "{error}");
    assert!(
        started.elapsed() < Duration::from_secs(30),
        "{:?}",
        started.elapsed()
    );
}

#[test]
fn the_default_lookup_names_the_places_it_looked() {
    // The test binary lives in target/debug/deps: the lookup covers target/ itself.
    match find_python(None) {
        Err(PythonError::NotFound(looked)) => {
            assert_eq!(looked.len(), 3);
            assert!(
                looked.iter().all(|p| p.ends_with(VENV_PYTHON)),
                "{looked:?}"
            );
            assert!(
                PythonError::NotFound(looked)
                    .to_string()
                    .contains("py-venv/bin/python")
            );
        }
        Ok(python) => assert!(python.ends_with(VENV_PYTHON), "{python:?}"),
        Err(other) => eprintln!("target/py-venv exists but is not usable: {other}"),
    }
}
