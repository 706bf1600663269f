//! Campaign 6, malformed configs: a corpus made by mutating config/sim.toml — every value
//! of the wrong type, every required key missing, keys, tables and names duplicated,
//! references to links, devices, pins and channels that do not exist, values out of range —
//! each given to `motiond --config` (the real start, not `--check-config`). Each must be
//! refused with exit status 1, an issue `file:line:column: `key`` on the mutated line naming
//! the mutated key (the table's first line for a missing key), no Rust type names, "nothing
//! was opened", and no iceoryx2 file made.

use core::time::Duration;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::Context;

use crate::harness::Harness;
use crate::report::Row;

/// One `key = value` line of the source config.
#[derive(Debug, Clone)]
struct Entry {
    /// 0-based line.
    line: usize,
    /// `server`, `link`, `device`, `axis`, `signal`.
    table: String,
    /// Index of its table among those of its kind.
    index: usize,
    /// 0-based line of its table's header.
    header: usize,
    key: String,
    value: String,
}

/// A malformed config and where its issue must be.
#[derive(Debug, Clone)]
pub struct Mutant {
    /// The kind of mutation.
    pub kind: &'static str,
    /// What was done, for a report.
    pub what: String,
    /// The config.
    pub text: String,
    /// Acceptable (1-based line, key) of the issue; the key matches its last component.
    pub sites: Vec<(usize, String)>,
}

const REQUIRED: [(&str, &[&str]); 5] = [
    ("server", &["name"]),
    ("link", &["name", "type"]),
    ("device", &["name", "link", "model"]),
    (
        "axis",
        &[
            "name",
            "device",
            "channel",
            "unit",
            "counts_per_unit",
            "min",
            "max",
            "max_velocity",
            "max_accel",
        ],
    ),
    ("signal", &["name", "device", "pin", "kind"]),
];

/// The code of a line: up to a `#` outside a string.
fn code(line: &str) -> &str {
    let mut in_string = false;
    for (at, c) in line.char_indices() {
        match c {
            '"' => in_string = !in_string,
            '#' if !in_string => return &line[..at],
            _ => {}
        }
    }
    line
}

fn entries(lines: &[&str]) -> Vec<Entry> {
    let mut found = Vec::new();
    let mut table = String::new();
    let mut header = 0;
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (number, line) in lines.iter().enumerate() {
        let text = code(line).trim();
        if let Some(name) = text.strip_prefix('[') {
            table = name.trim_matches(|c| c == '[' || c == ']').to_owned();
            header = number;
            *counts.entry(table.clone()).or_default() += 1;
            continue;
        }
        if let Some((key, value)) = text.split_once('=')
            && !table.is_empty()
        {
            found.push(Entry {
                line: number,
                table: table.clone(),
                index: counts.get(&table).copied().unwrap_or(1) - 1,
                header,
                key: key.trim().to_owned(),
                value: value.trim().to_owned(),
            });
        }
    }
    found
}

fn replace_line(lines: &[&str], at: usize, with: &str) -> String {
    let mut out: Vec<&str> = lines.to_vec();
    out[at] = with;
    out.join("\n") + "\n"
}

fn insert_line(lines: &[&str], at: usize, with: &str) -> String {
    let mut out: Vec<&str> = lines.to_vec();
    out.insert(at, with);
    out.join("\n") + "\n"
}

fn wrong_type(value: &str) -> &'static str {
    if value.starts_with('"') {
        "42"
    } else if value.starts_with('{') || value.starts_with('[') {
        "7"
    } else if value == "true" || value == "false" {
        "\"yes\""
    } else {
        "\"seven\""
    }
}

/// Out-of-range values per key (docs/CONFIG.md's ranges and rules).
const OUT_OF_RANGE: [(&str, &str, &[&str]); 14] = [
    ("server", "tick_hz", &["0", "20001", "-5"]),
    ("server", "command_timeout_ms", &["60001", "-1"]),
    ("link", "baud", &["299", "4000001"]),
    ("link", "speed_hz", &["0"]),
    ("device", "address", &["256", "0x91", "-1"]),
    ("device", "intensity", &["256"]),
    ("device", "coils", &["3", "0"]),
    ("axis", "counts_per_unit", &["0.0"]),
    ("axis", "max_velocity", &["0.0", "-10.0"]),
    ("axis", "max_accel", &["0.0", "-1.0"]),
    ("axis", "power_limit", &["1.5", "-0.1"]),
    ("axis", "estop", &["\"sideways\""]),
    ("axis", "unit", &["\"\""]),
    ("signal", "kind", &["\"digital-sideways\""]),
];

/// The corpus.
pub fn corpus(source: &str) -> Vec<Mutant> {
    let lines: Vec<&str> = source.lines().collect();
    let all = entries(&lines);
    let mut out = Vec::new();
    // The entry's key given `value` instead, found at its line.
    let set_to = |kind: &'static str, e: &Entry, value: &str| Mutant {
        kind,
        what: format!("{}[{}].{} = {value}", e.table, e.index, e.key),
        text: replace_line(&lines, e.line, &format!("{} = {value}", e.key)),
        sites: vec![(e.line + 1, e.key.clone())],
    };
    for e in &all {
        out.push(set_to("wrong type", e, wrong_type(&e.value)));
    }
    for e in &all {
        if REQUIRED
            .iter()
            .any(|(table, keys)| *table == e.table && keys.contains(&e.key.as_str()))
        {
            let mut text: Vec<&str> = lines.clone();
            text.remove(e.line);
            out.push(Mutant {
                kind: "missing key",
                what: format!("{}[{}].{} removed", e.table, e.index, e.key),
                text: text.join("\n") + "\n",
                sites: vec![(e.header + 1, e.key.clone())],
            });
        }
    }
    // Every key of the first table of each kind, twice.
    for e in all.iter().filter(|e| e.index == 0) {
        out.push(Mutant {
            kind: "duplicate",
            what: format!("{}[0].{} twice", e.table, e.key),
            text: insert_line(&lines, e.line + 1, lines[e.line]),
            sites: vec![(e.line + 2, e.key.clone())],
        });
    }
    // The second table of each kind named as the first.
    for table in ["link", "device", "axis", "signal"] {
        let names: Vec<&Entry> = all
            .iter()
            .filter(|e| e.table == table && e.key == "name")
            .collect();
        if let [first, second, ..] = names.as_slice() {
            out.push(Mutant {
                kind: "duplicate",
                what: format!("{table}[1] named as {table}[0]"),
                text: replace_line(&lines, second.line, &format!("name = {}", first.value)),
                sites: vec![(second.line + 1, second.key.clone())],
            });
        }
    }
    let server_at = lines
        .iter()
        .position(|l| l.trim() == "[server]")
        .unwrap_or(0);
    out.push(Mutant {
        kind: "duplicate",
        what: "[server] twice".to_owned(),
        text: format!("{source}\n[server]\nname = \"again\"\n"),
        sites: vec![
            (lines.len() + 2, "server".to_owned()),
            (server_at + 1, "server".to_owned()),
        ],
    });
    for e in &all {
        let bad = match (e.table.as_str(), e.key.as_str()) {
            ("device", "link") | ("axis" | "signal", "device") => "\"nowhere\"",
            ("signal", "pin") => "\"nopin\"",
            ("axis", "channel") => "99",
            _ => continue,
        };
        out.push(set_to("dangling reference", e, bad));
    }
    for e in &all {
        let Some((_, _, values)) = OUT_OF_RANGE
            .iter()
            .find(|(table, key, _)| *table == e.table && *key == e.key)
        else {
            continue;
        };
        for value in *values {
            // An odd address is out of range for an SPI_motor (written in hex in sim.toml),
            // not for a pack.
            if value.starts_with("0x") && !e.value.starts_with("0x") {
                continue;
            }
            out.push(set_to("out of range", e, value));
        }
    }
    // Soft limits the wrong way round, on every axis.
    for e in all.iter().filter(|e| e.table == "axis" && e.key == "min") {
        if let Some(max) = all
            .iter()
            .find(|m| m.table == "axis" && m.index == e.index && m.key == "max")
        {
            out.push(Mutant {
                kind: "out of range",
                what: format!("axis[{}].min = max", e.index),
                text: replace_line(&lines, e.line, &format!("min = {}", max.value)),
                sites: vec![(e.line + 1, "min".into()), (max.line + 1, "max".into())],
            });
        }
    }
    // Keys absent from sim.toml, given out of range.
    for (key, value) in [
        ("max_clients", "0"),
        ("max_clients", "1025"),
        ("liveness_check_ms", "9"),
        ("rt_priority", "100"),
    ] {
        out.push(Mutant {
            kind: "out of range",
            what: format!("server.{key} = {value}"),
            text: insert_line(&lines, server_at + 1, &format!("{key} = {value}")),
            sites: vec![(server_at + 2, key.to_owned())],
        });
    }
    out
}

/// A `file:line:column: `key`: message` line of `stderr` for `file`.
fn issues<'a>(stderr: &'a str, file: &str) -> Vec<(usize, usize, &'a str, &'a str)> {
    stderr
        .lines()
        .filter_map(|line| {
            let rest = line.strip_prefix(file)?.strip_prefix(':')?;
            let (number, rest) = rest.split_once(':')?;
            let (column, rest) = rest.split_once(": `")?;
            let (key, message) = rest.split_once("`: ")?;
            Some((number.parse().ok()?, column.parse().ok()?, key, message))
        })
        .collect()
}

fn key_matches(key: &str, expected: &str) -> bool {
    key == expected
        || key.ends_with(&format!(".{expected}"))
        || key.starts_with(&format!("{expected}["))
}

/// Judges one mutant: `None` when refused as it must be, else what was wrong.
fn judge(h: &Harness, file: &Path, mutant: &Mutant) -> anyhow::Result<Option<String>> {
    std::fs::write(file, &mutant.text)?;
    let before = h.iox_files();
    let mut child = Command::new(&h.motiond)
        .arg("--config")
        .arg(file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .context("start motiond")?;
    let end = Instant::now() + Duration::from_secs(10);
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break Some(status);
        }
        if Instant::now() > end {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(2));
    };
    let mut stderr = String::new();
    if let Some(mut pipe) = child.stderr.take() {
        use std::io::Read as _;
        let _ = pipe.read_to_string(&mut stderr);
    }
    let after = h.iox_files();
    let Some(status) = status else {
        return Ok(Some("accepted: motiond ran".to_owned()));
    };
    let name = file.display().to_string();
    let found = issues(&stderr, &name);
    let located = found.iter().any(|(line, column, key, _)| {
        *column >= 1
            && mutant
                .sites
                .iter()
                .any(|(l, k)| line == l && key_matches(key, k))
    });
    let rust_names = ["i128", "u64", "i64", "f64", "struct ", "Raw"];
    let leaked = found
        .iter()
        .find(|(_, _, _, message)| rust_names.iter().any(|r| message.contains(r)));
    let problem = if status.code() != Some(1) {
        Some(format!("exit {status}"))
    } else if !located {
        Some(format!("no issue at {:?}", mutant.sites))
    } else if let Some(issue) = leaked {
        Some(format!("a Rust type name in {issue:?}"))
    } else if !stderr.contains("nothing was opened") {
        Some("no \"nothing was opened\"".to_owned())
    } else if after > before {
        Some(format!("{} iceoryx2 files made", after - before))
    } else {
        None
    };
    Ok(problem.map(|p| format!("{p}; stderr: {}", stderr.trim().replace('\n', " | "))))
}

/// Runs the campaign (`--quick`: every fourth mutant).
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let source = std::fs::read_to_string(&h.sim_config)?;
    let mut mutants = corpus(&source);
    if h.quick {
        // Every fourth: each kind stays represented.
        mutants = mutants.into_iter().step_by(4).collect();
    }
    let mut row = Row::new("6 malformed configs");
    row.runs = format!(
        "{} mutants of config/sim.toml through `motiond --config`",
        mutants.len()
    );
    let dir = h.path("c6");
    std::fs::create_dir_all(&dir)?;
    let mut by_kind: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    let mut failures = Vec::new();
    for (number, mutant) in mutants.iter().enumerate() {
        let file = dir.join(format!("m{number:04}.toml"));
        let verdict = judge(h, &file, mutant)?;
        let entry = by_kind.entry(mutant.kind).or_default();
        entry.1 += 1;
        match verdict {
            None => entry.0 += 1,
            Some(problem) => failures.push(format!("{} ({}): {problem}", mutant.what, mutant.kind)),
        }
    }
    row.figure(
        "refused as required, by kind",
        by_kind
            .iter()
            .map(|(kind, (ok, all))| format!("{kind} {ok}/{all}"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    row.check(
        "a corpus of at least 50",
        mutants.len() >= 50,
        format!("{} mutants", mutants.len()),
    );
    row.check(
        "every mutant refused with file:line:column and key, nothing opened",
        failures.is_empty(),
        format!("{} of {} mishandled", failures.len(), mutants.len()),
    );
    for failure in failures.iter().take(8) {
        row.note(failure.clone());
    }
    Ok(row)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "[server]\nname = \"a\" # the name\n\n[[link]]\nname = \"l\"\ntype = \"sim\"\n\n[[link]]\nname = \"m\"\ntype = \"sim\"\n";

    #[test]
    fn the_corpus_locates_each_mutation() {
        let corpus = corpus(SMALL);
        let wrong: Vec<&Mutant> = corpus.iter().filter(|m| m.kind == "wrong type").collect();
        assert_eq!(wrong.len(), 5);
        assert!(wrong[0].text.contains("name = 42\n"), "{}", wrong[0].text);
        assert_eq!(wrong[0].sites, vec![(2, "name".to_owned())]);
        let missing: Vec<&Mutant> = corpus.iter().filter(|m| m.kind == "missing key").collect();
        assert_eq!(missing.len(), 5, "every key here is required");
        // A missing key is reported at its table's first line.
        assert_eq!(missing[2].sites, vec![(4, "type".to_owned())]);
        let renamed = corpus
            .iter()
            .find(|m| m.what == "link[1] named as link[0]")
            .expect("renamed");
        assert!(
            renamed
                .text
                .contains("[[link]]\nname = \"l\"\ntype = \"sim\"\n\n[[link]]\nname = \"l\"")
        );
        assert_eq!(renamed.sites, vec![(9, "name".to_owned())]);
    }

    #[test]
    fn issues_are_parsed_from_the_log() {
        let log = "/x/m.toml:3:11: `server.tick_hz`: invalid type\nmotiond: /x/m.toml is not a usable config; nothing was opened\n";
        let found = issues(log, "/x/m.toml");
        assert_eq!(found, vec![(3, 11, "server.tick_hz", "invalid type")]);
        assert!(key_matches("axis[2].max", "max"));
        assert!(!key_matches("axis[2].max_accel", "max"));
        assert!(key_matches("server", "server"));
    }
}
