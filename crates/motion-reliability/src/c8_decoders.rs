//! Campaign 8, the decoders: `scripts/fuzz` runs every cargo-fuzz target of the protocol
//! crates (libFuzzer, nightly) for `--fuzz-seconds` each, or without a nightly toolchain
//! their property tests at 10⁶ cases; every target must finish without a crashing input.
//! Full runs only: `--quick` leaves it to `./scripts/test`, whose `cargo test` runs the
//! decoders' property tests at their usual counts.

use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::Context;

use crate::harness::Harness;
use crate::report::Row;

/// One line of `scripts/fuzz`: `fuzz <board>/<target>: <runs> runs in <s> s, corpus <n>: ok`.
#[derive(Debug, PartialEq, Eq)]
pub struct Target {
    /// `board/target`.
    pub name: String,
    /// Inputs tried.
    pub runs: u64,
    /// Ran and finished without a crashing input (`CRASH`: one found; `FAILED`: the
    /// target never ran, e.g. its build failed).
    pub ok: bool,
}

/// Parses `scripts/fuzz`'s target lines.
pub fn targets(stdout: &str) -> Vec<Target> {
    stdout
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix("fuzz ")?;
            let (name, rest) = rest.split_once(": ")?;
            let runs = rest.split_whitespace().next()?.parse().ok()?;
            Some(Target {
                name: name.to_owned(),
                runs,
                ok: rest.ends_with(": ok"),
            })
        })
        .collect()
}

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let mut row = Row::new("8 decoders");
    if h.quick || h.fuzz_seconds == 0 {
        row.runs = "skipped (full run only)".to_owned();
        row.note(
            "--quick (or --fuzz-seconds 0): no fuzzing; ./scripts/test's cargo test runs the \
             decoders' property tests",
        );
        return Ok(row);
    }
    let script = h.source.join("scripts/fuzz");
    let started = Instant::now();
    let output = Command::new(&script)
        .arg(h.fuzz_seconds.to_string())
        .current_dir(&h.source)
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .with_context(|| format!("run {}", script.display()))?;
    let stdout = String::from_utf8_lossy(&output.stdout);
    let found = targets(&stdout);
    if stdout.contains("no nightly toolchain") {
        row.runs = "proptest fallback (no nightly toolchain)".to_owned();
        row.figure("proptest", stdout.lines().last().unwrap_or("").to_owned());
        row.check(
            "every property holds",
            output.status.success(),
            format!("exit {}", output.status),
        );
        return Ok(row);
    }
    let total: u64 = found.iter().map(|t| t.runs).sum();
    row.runs = format!(
        "{} cargo-fuzz targets × {} s (libFuzzer, nightly, -O)",
        found.len(),
        h.fuzz_seconds
    );
    row.figure(
        "inputs",
        format!(
            "{total} in all ({:.0} s with the builds): {}",
            started.elapsed().as_secs_f64(),
            found
                .iter()
                .map(|t| format!("{} {:.1} M", t.name, t.runs as f64 / 1e6))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let not_ok: Vec<&str> = found
        .iter()
        .filter(|t| !t.ok)
        .map(|t| t.name.as_str())
        .collect();
    row.check(
        "every target ran, no crashing input",
        !found.is_empty() && not_ok.is_empty() && output.status.success(),
        format!(
            "{} targets, crashed or never ran: {not_ok:?}, exit {}",
            found.len(),
            output.status
        ),
    );
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        row.note(stderr.lines().rev().take(5).collect::<Vec<_>>().join(" | "));
    }
    Ok(row)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_script_lines_are_parsed() {
        let out = "fuzz qsb/typed: 123456 runs in 60 s, corpus 80: ok\nnoise\nfuzz tmcpack/can: 7 runs in 60 s, corpus 1: CRASH\n\
                   fuzz: installing cargo-fuzz\nfuzz spimotor/reply: 0 runs in 60 s, corpus 0: FAILED\n";
        assert_eq!(
            targets(out),
            vec![
                Target {
                    name: "qsb/typed".into(),
                    runs: 123_456,
                    ok: true
                },
                Target {
                    name: "tmcpack/can".into(),
                    runs: 7,
                    ok: false
                },
                Target {
                    name: "spimotor/reply".into(),
                    runs: 0,
                    ok: false
                },
            ]
        );
    }
}
