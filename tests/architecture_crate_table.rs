//! docs/ARCHITECTURE.md's crate table says the truth about the `Cargo.toml` files: every
//! workspace crate has a row, every row names crates that exist, and each row's `depends on`
//! column names exactly the crates of ours that its crates list under `[dependencies]`
//! (optional ones too; dev-dependencies are not the architecture). Third-party crates may be
//! named there too, but only ones the crate depends on.
//!
//! A cell may group crates with braces (`crates/protocols/{qq2drv,qsb}`) or a `*`
//! (`crates/boards/*`, `board-*`: every crate of ours that matches), so that adding a board
//! crate under `crates/boards/` needs no new row.
//!
//! The manifests are read through `cargo metadata --no-deps` (workspace globs, inherited
//! dependencies and renames are cargo's business).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

/// One workspace crate as its manifest says.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Manifest {
    /// Its directory relative to the workspace root (`.` for the root package).
    dir: String,
    /// The workspace crates among its `[dependencies]`.
    ours: BTreeSet<String>,
    /// Its other `[dependencies]`.
    third_party: BTreeSet<String>,
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Row {
    /// Its line in the file (1-based).
    line: usize,
    /// The crate directories of its first column, braces expanded.
    dirs: Vec<String>,
    /// The crate names of its `depends on` column, braces expanded.
    depends_on: BTreeSet<String>,
}

/// Expands `a/{x,y}` into `a/x` and `a/y` (one pair of braces at most).
fn expand(item: &str) -> Vec<String> {
    match (item.find('{'), item.find('}')) {
        (Some(open), Some(close)) if open < close => item[open + 1..close]
            .split(',')
            .map(|part| format!("{}{}{}", &item[..open], part.trim(), &item[close + 1..]))
            .collect(),
        _ => vec![item.to_owned()],
    }
}

/// The backticked items of a cell.
fn backticked(cell: &str) -> Vec<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

/// Whether a backticked item of the `depends on` column names crates (not code such as
/// `motion_drivers::spec`).
fn names_crates(item: &str) -> bool {
    !item.is_empty()
        && item
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_{},*".contains(c))
}

/// Whether `text` matches `pattern`, where one `*` stands for any run of characters but `/`.
fn matches(pattern: &str, text: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == text,
        Some((head, tail)) => {
            text.len() >= head.len() + tail.len()
                && text.starts_with(head)
                && text.ends_with(tail)
                && !text[head.len()..text.len() - tail.len()].contains('/')
        }
    }
}

/// The items of `stated` with each `*` pattern replaced by the `known` names it matches.
fn resolve<'a>(stated: impl IntoIterator<Item = &'a String>, known: &[&str]) -> Vec<String> {
    stated
        .into_iter()
        .flat_map(|item| {
            if item.contains('*') {
                known
                    .iter()
                    .filter(|name| matches(item, name))
                    .map(|name| (*name).to_owned())
                    .collect()
            } else {
                vec![item.clone()]
            }
        })
        .collect()
}

/// The rows of the table whose header is `| crate | owns | depends on | …`.
fn crate_table(markdown: &str) -> Result<Vec<Row>, String> {
    let lines: Vec<&str> = markdown.lines().collect();
    let header = lines
        .iter()
        .position(|line| line.starts_with("| crate | owns | depends on |"))
        .ok_or("no table with the header `| crate | owns | depends on | …`")?;
    let mut rows = Vec::new();
    for (index, line) in lines.iter().enumerate().skip(header + 2) {
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // "| a | b | c | d |" splits into "", a, b, c, d, "".
        if cells.len() < 5 {
            return Err(format!("line {}: not four cells: {line}", index + 1));
        }
        let dirs: Vec<String> = backticked(cells[1]).into_iter().flat_map(expand).collect();
        if dirs.is_empty() {
            return Err(format!(
                "line {}: the first cell names no crate directory in backticks",
                index + 1
            ));
        }
        let depends_on = backticked(cells[3])
            .into_iter()
            .filter(|item| names_crates(item))
            .flat_map(expand)
            .collect();
        rows.push(Row {
            line: index + 1,
            dirs,
            depends_on,
        });
    }
    Ok(rows)
}

/// What the table gets wrong about `manifests` (crate name → manifest); empty when nothing.
fn disagreements(rows: &[Row], manifests: &BTreeMap<String, Manifest>) -> Vec<String> {
    let by_dir: BTreeMap<&str, (&String, &Manifest)> = manifests
        .iter()
        .map(|(name, manifest)| (manifest.dir.as_str(), (name, manifest)))
        .collect();
    let dirs: Vec<&str> = by_dir.keys().copied().collect();
    let names: Vec<&str> = manifests.keys().map(String::as_str).collect();
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    // Rows that name their crates come first; a row with a `*` then covers the crates no
    // other row names, and states the dependencies such a crate may have (a new board
    // needs no row of its own).
    let (named, globbed): (Vec<&Row>, Vec<&Row>) = rows
        .iter()
        .partition(|row| !row.dirs.iter().any(|dir| dir.contains('*')));
    for (row, glob) in named
        .into_iter()
        .map(|row| (row, false))
        .chain(globbed.into_iter().map(|row| (row, true)))
    {
        for pattern in row.dirs.iter().filter(|dir| dir.contains('*')) {
            if !dirs.iter().any(|dir| matches(pattern, dir)) {
                problems.push(format!(
                    "line {}: `{pattern}` matches no workspace crate's directory",
                    row.line
                ));
            }
        }
        let depends_on: BTreeSet<String> = resolve(&row.depends_on, &names).into_iter().collect();
        for dir in &resolve(&row.dirs, &dirs) {
            let Some((name, manifest)) = by_dir.get(dir.as_str()) else {
                problems.push(format!(
                    "line {}: `{dir}` is not a workspace crate's directory",
                    row.line
                ));
                continue;
            };
            if glob && seen.contains(dir) {
                continue;
            }
            if !seen.insert(dir.clone()) {
                problems.push(format!("line {}: `{dir}` has a row already", row.line));
            }
            let stated_ours: BTreeSet<String> = depends_on
                .iter()
                .filter(|dep| manifests.contains_key(*dep))
                .cloned()
                .collect();
            for missing in manifest.ours.difference(&stated_ours) {
                problems.push(format!(
                    "line {}: {name} depends on `{missing}`, which its row does not name",
                    row.line
                ));
            }
            if glob {
                continue;
            }
            for extra in stated_ours.difference(&manifest.ours) {
                problems.push(format!(
                    "line {}: the row says {name} depends on `{extra}`; its [dependencies] do not",
                    row.line
                ));
            }
            for other in depends_on
                .iter()
                .filter(|dep| !manifests.contains_key(*dep))
            {
                if !manifest.third_party.contains(other) {
                    problems.push(format!(
                        "line {}: `{other}` is neither a crate of ours nor a dependency of {name}",
                        row.line
                    ));
                }
            }
        }
    }
    for (name, manifest) in manifests {
        if !seen.contains(&manifest.dir) {
            problems.push(format!(
                "{name} (`{}`) has no row in the crate table",
                manifest.dir
            ));
        }
    }
    problems
}

/// The workspace root (this package's directory).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every workspace crate's manifest, by name, from `cargo metadata --no-deps`.
fn manifests(root: &Path) -> BTreeMap<String, Manifest> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(cargo)
        .args([
            "metadata",
            "--no-deps",
            "--offline",
            "--format-version",
            "1",
        ])
        .current_dir(root)
        .output()
        .expect("cargo metadata runs");
    assert!(
        output.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let metadata: serde_json::Value =
        serde_json::from_slice(&output.stdout).expect("cargo metadata prints JSON");
    let packages = metadata["packages"].as_array().expect("a package list");
    let names: BTreeSet<String> = packages
        .iter()
        .filter_map(|package| package["name"].as_str().map(str::to_owned))
        .collect();
    packages
        .iter()
        .map(|package| {
            let name = package["name"].as_str().expect("a name").to_owned();
            let manifest_path = PathBuf::from(package["manifest_path"].as_str().expect("a path"));
            let dir = manifest_path
                .parent()
                .and_then(|dir| dir.strip_prefix(root).ok())
                .map(|dir| {
                    let text = dir.to_string_lossy().into_owned();
                    if text.is_empty() {
                        ".".to_owned()
                    } else {
                        text
                    }
                })
                .expect("a manifest inside the workspace");
            let mut ours = BTreeSet::new();
            let mut third_party = BTreeSet::new();
            for dependency in package["dependencies"].as_array().expect("dependencies") {
                // `kind` is null for [dependencies], "dev" or "build" otherwise.
                if !dependency["kind"].is_null() {
                    continue;
                }
                let dep = dependency["name"].as_str().expect("a name").to_owned();
                if names.contains(&dep) {
                    ours.insert(dep);
                } else {
                    third_party.insert(dep);
                }
            }
            (
                name,
                Manifest {
                    dir,
                    ours,
                    third_party,
                },
            )
        })
        .collect()
}

#[test]
fn the_crate_table_matches_the_manifests() {
    let root = root();
    let markdown = std::fs::read_to_string(root.join("docs/ARCHITECTURE.md"))
        .expect("docs/ARCHITECTURE.md is readable");
    let rows = crate_table(&markdown).unwrap_or_else(|error| panic!("{error}"));
    let problems = disagreements(&rows, &manifests(&root));
    assert!(
        problems.is_empty(),
        "docs/ARCHITECTURE.md's crate table disagrees with the Cargo.toml files:\n{}",
        problems.join("\n")
    );
}

fn manifest(dir: &str, ours: &[&str], third_party: &[&str]) -> Manifest {
    Manifest {
        dir: dir.to_owned(),
        ours: ours.iter().map(|name| (*name).to_owned()).collect(),
        third_party: third_party.iter().map(|name| (*name).to_owned()).collect(),
    }
}

/// Two codec crates and a driver crate over them.
fn small_workspace() -> BTreeMap<String, Manifest> {
    BTreeMap::from([
        ("aa".to_owned(), manifest("crates/codecs/aa", &[], &[])),
        ("bb".to_owned(), manifest("crates/codecs/bb", &[], &[])),
        (
            "drivers".to_owned(),
            manifest("crates/drivers", &["aa", "bb"], &["thiserror"]),
        ),
    ])
}

const TABLE_HEAD: &str = "| crate | owns | depends on | why |\n|---|---|---|---|\n";

fn problems_of(body: &str) -> Vec<String> {
    let rows = crate_table(&format!("{TABLE_HEAD}{body}")).expect("a table");
    disagreements(&rows, &small_workspace())
}

#[test]
fn a_true_table_with_groups_code_and_third_party_names_passes() {
    let problems = problems_of(
        "| `crates/codecs/{aa,bb}` | codecs | nothing of ours | x |\n\
         | `crates/drivers` | drivers | the codecs `{aa,bb}`, `thiserror`; see `drivers::spec` | x |\n",
    );
    assert_eq!(problems, Vec::<String>::new());
}

#[test]
fn a_star_covers_every_crate_it_matches_and_nothing_else() {
    let mut workspace = small_workspace();
    workspace.insert("cc".to_owned(), manifest("crates/codecs/cc", &[], &[]));
    let rows = crate_table(&format!(
        "{TABLE_HEAD}| `crates/codecs/*` | codecs | nothing of ours | x |\n\
         | `crates/drivers` | drivers | every codec `{{aa,bb}}` | x |\n\
         | `crates/boards/*` | boards | nothing | x |\n"
    ))
    .expect("a table");
    assert_eq!(
        disagreements(&rows, &workspace),
        vec!["line 5: `crates/boards/*` matches no workspace crate's directory".to_owned()]
    );
    let all = crate_table(&format!(
        "{TABLE_HEAD}| `crates/codecs/*` | codecs | nothing of ours | x |\n\
         | `crates/drivers` | drivers | every codec `*` | x |\n"
    ))
    .expect("a table");
    // `*` names cc and drivers too, which drivers does not depend on.
    assert_eq!(
        disagreements(&all, &workspace),
        vec![
            "line 4: the row says drivers depends on `cc`; its [dependencies] do not".to_owned(),
            "line 4: the row says drivers depends on `drivers`; its [dependencies] do not"
                .to_owned(),
        ]
    );
    assert!(matches("board-*", "board-qsb") && !matches("crates/*", "crates/boards/qsb"));
}

#[test]
fn a_star_row_states_what_the_crates_no_other_row_names_may_depend_on() {
    let mut workspace = small_workspace();
    workspace.insert("cc".to_owned(), manifest("crates/codecs/cc", &["aa"], &[]));
    // aa and bb depend on nothing, cc on aa: all within the star row's `aa`, `bb`.
    let fits = crate_table(&format!(
        "{TABLE_HEAD}| `crates/codecs/*` | codecs | at most `aa`, `bb` | x |\n\
         | `crates/drivers` | drivers | `aa`, `bb` | x |\n"
    ))
    .expect("a table");
    assert_eq!(disagreements(&fits, &workspace), Vec::<String>::new());
    // A dependency outside the star row is still reported.
    let narrow = crate_table(&format!(
        "{TABLE_HEAD}| `crates/codecs/*` | codecs | at most `bb` | x |\n\
         | `crates/drivers` | drivers | `aa`, `bb` | x |\n"
    ))
    .expect("a table");
    assert_eq!(
        disagreements(&narrow, &workspace),
        vec!["line 3: cc depends on `aa`, which its row does not name".to_owned()]
    );
    // A crate with a row of its own is held to that row, not to the star's.
    let own = crate_table(&format!(
        "{TABLE_HEAD}| `crates/codecs/*` | codecs | at most `bb` | x |\n\
         | `crates/codecs/cc` | the odd one | `aa` | x |\n\
         | `crates/drivers` | drivers | `aa`, `bb` | x |\n"
    ))
    .expect("a table");
    assert_eq!(disagreements(&own, &workspace), Vec::<String>::new());
}

#[test]
fn a_missing_row_an_unknown_crate_and_wrong_dependencies_are_each_reported() {
    let problems = problems_of(
        "| `crates/codecs/{aa,cc}` | codecs | nothing of ours | x |\n\
         | `crates/drivers` | drivers | `aa`, `serde` | x |\n",
    );
    assert_eq!(
        problems,
        vec![
            "line 3: `crates/codecs/cc` is not a workspace crate's directory".to_owned(),
            "line 4: drivers depends on `bb`, which its row does not name".to_owned(),
            "line 4: `serde` is neither a crate of ours nor a dependency of drivers".to_owned(),
            "bb (`crates/codecs/bb`) has no row in the crate table".to_owned(),
        ]
    );
    let claimed = problems_of(
        "| `crates/codecs/{aa,bb}` | codecs | `drivers` | x |\n\
         | `crates/drivers` | drivers | `aa`, `bb` | x |\n",
    );
    assert_eq!(
        claimed,
        vec![
            "line 3: the row says aa depends on `drivers`; its [dependencies] do not".to_owned(),
            "line 3: the row says bb depends on `drivers`; its [dependencies] do not".to_owned(),
        ]
    );
}
