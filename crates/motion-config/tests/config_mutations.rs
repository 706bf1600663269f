//! Mutated configs, as an attacker or a typo makes them: every number of every shipped
//! config (`config/sim.toml` and each `config/examples/*.toml`), at top level and inside
//! inline tables, is replaced in turn by values of the wrong size, type or kind. Each
//! mutant either still loads or is refused with an issue on the mutated line that names the
//! mutated key (dotted, down into inline tables) — never a panic, never an issue without a
//! key, never serde's internal type names (`i128`, `u64`).

use std::path::{Path, PathBuf};

use motion_config::ServerConfig;

/// The configs the project ships.
fn shipped() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = vec![root.join("config/sim.toml")];
    let mut examples: Vec<PathBuf> = std::fs::read_dir(root.join("config/examples"))
        .expect("config/examples")
        .map(|entry| entry.expect("entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "toml"))
        .collect();
    examples.sort();
    files.extend(examples);
    files
}

/// A number given to a key on a line: (byte range of the number, key, is it an integer).
struct Site {
    range: core::ops::Range<usize>,
    key: String,
    integer: bool,
}

/// Every `key = number` of `text` outside comments and strings, inline tables included.
fn sites(text: &str) -> Vec<Site> {
    let mut found = Vec::new();
    let mut line_start = 0;
    for line in text.split_inclusive('\n') {
        let code = line.split('#').next().unwrap_or("");
        let bytes = code.as_bytes();
        let mut in_string = false;
        let mut i = 0;
        while i < bytes.len() {
            let c = bytes[i];
            if c == b'"' {
                in_string = !in_string;
            }
            if !in_string && c == b'=' {
                let key_end = code[..i].trim_end().len();
                let key_start = code[..key_end]
                    .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .map_or(0, |p| p + 1);
                let key = code[key_start..key_end].to_owned();
                let rest = &code[i + 1..];
                let start = i + 1 + (rest.len() - rest.trim_start().len());
                let len = code[start..]
                    .find(|c: char| !(c.is_ascii_digit() || "+-.eE_".contains(c)))
                    .unwrap_or(code.len() - start);
                let number = &code[start..start + len];
                if !key.is_empty() && number.bytes().any(|b| b.is_ascii_digit()) {
                    found.push(Site {
                        range: line_start + start..line_start + start + len,
                        key,
                        integer: !number.contains(['.', 'e', 'E']),
                    });
                }
            }
            i += 1;
        }
        line_start += line.len();
    }
    found
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset].matches('\n').count() + 1
}

/// The mutant either loads, or is refused with a located issue naming `site.key`.
fn judge(file: &Path, text: &str, site: &Site, value: &str, must_fail: bool) -> Result<(), String> {
    let mut mutant = text.to_owned();
    mutant.replace_range(site.range.clone(), value);
    let what = format!(
        "{}:{}: `{}` = {value}",
        file.display(),
        line_of(text, site.range.start),
        site.key
    );
    let result = std::panic::catch_unwind(|| ServerConfig::parse(file, &mutant));
    let Ok(result) = result else {
        return Err(format!("{what}: the parser panicked"));
    };
    let error = match result {
        Ok(_) if must_fail => return Err(format!("{what}: accepted")),
        Ok(_) => return Ok(()),
        Err(error) => error,
    };
    for issue in &error.issues {
        if issue.key.is_empty() || issue.message.contains("i128") || issue.message.contains("u64") {
            return Err(format!("{what}: {issue:?}"));
        }
    }
    let line = line_of(text, site.range.start);
    let named = error.issues.iter().any(|issue| {
        issue.line == line
            && (issue.key == site.key || issue.key.ends_with(&format!(".{}", site.key)))
    });
    if named {
        Ok(())
    } else {
        Err(format!(
            "{what}: no issue on line {line} names the key: {error}"
        ))
    }
}

#[test]
fn every_number_of_every_shipped_config_survives_mutation() {
    let mut failures = Vec::new();
    let mut mutants = 0;
    for file in shipped() {
        let text = std::fs::read_to_string(&file).expect("read config");
        assert!(
            ServerConfig::parse(&file, &text).is_ok(),
            "{} loads as shipped",
            file.display()
        );
        let found = sites(&text);
        assert!(!found.is_empty(), "{}: no numbers found", file.display());
        for site in &found {
            // Too large for any integer type, in either direction: refused (no key takes it).
            let mut cases = vec![
                ("99999999999999999999", site.integer),
                ("-99999999999999999999", site.integer),
                ("\"7\"", true),
                ("true", true),
                ("nan", true),
                ("inf", true),
                ("-inf", true),
            ];
            if site.integer {
                cases.push(("1.5", false));
            } else {
                cases.push(("1e400", true));
            }
            for (value, must_fail) in cases {
                mutants += 1;
                if let Err(failure) = judge(&file, &text, site, value, must_fail) {
                    failures.push(failure);
                }
            }
        }
    }
    assert!(mutants > 500, "only {mutants} mutants");
    assert!(
        failures.is_empty(),
        "{} of {mutants} mutants mishandled:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
