//! The README a newcomer runs, checked against the repository without starting anything:
//!
//! - it stays short (at most [`MAX_LINES`] lines: the rest lives in `docs/`);
//! - every command of its ```sh / ```bash / ```console blocks that is the project's exists
//!   as written: a binary's subcommands, options, option values and arguments against its
//!   clap `--help` pages (`motionctl`, `motiond`, `motion-bridge`, `motion-sim`, also as
//!   `target/release/…`, an `alias` or `cargo run -p … -- …`), `cargo … -p` packages,
//!   `--example`, `--bin`, `--bench` and `--features`, `scripts/…` (executable, and each
//!   option named in the script), `python -m motiond…` (the module, its options, its
//!   command's choices);
//! - every repository path it names (`docs/…`, `crates/…`, `./scripts/test`) and every link
//!   it makes exists, down to the anchor and to the section a link names in quotes.
//!
//! motionctl is this package's binary; the other binaries are looked for beside it in the
//! same target directory and must be newer than every source file cargo built them from
//! (their `<bin>.d`): `cargo test --workspace` (`./scripts/test`) builds them all first;
//! alone, run `cargo build -p motiond -p motion-bridge -p motion-sim-cli` before `cargo test
//! -p motionctl --test readme_commands`. The test names what to build when one is missing
//! or stale.

mod readme;

use std::path::{Path, PathBuf};

use readme::check::Checker;
use readme::markdown;
use readme::shell;
use readme::workspace::Workspace;

/// The README's longest allowed length, in lines.
const MAX_LINES: usize = 400;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the repository root")
}

fn readme() -> String {
    std::fs::read_to_string(root().join("README.md")).expect("README.md")
}

fn workspace() -> Workspace {
    Workspace::read(&root()).expect("the workspace's Cargo.toml files")
}

/// What is wrong with the commands of `text`'s command blocks, each with its line, and how
/// many of them were the project's.
fn command_problems(text: &str, workspace: &Workspace) -> (Vec<String>, usize) {
    let mut checker = Checker::new(workspace);
    let mut problems = Vec::new();
    for block in markdown::blocks(text)
        .iter()
        .filter(|block| block.is_shell())
    {
        for (line, command_line) in shell::command_lines(block) {
            for words in shell::commands(&command_line) {
                for problem in checker.check(&words) {
                    problems.push(format!(
                        "README.md:{line}: `{}`: {problem}",
                        words.join(" ")
                    ));
                }
            }
        }
    }
    (problems, checker.checked)
}

/// What is wrong with the paths and links of `text` (a markdown file in `root`).
fn path_problems(text: &str, workspace: &Workspace) -> Vec<String> {
    let root = &workspace.root;
    let mut problems = Vec::new();
    let top = workspace.top_dirs().expect("the repository's directories");
    for (line, path) in markdown::paths(text, &top) {
        if !root.join(&path).exists() {
            problems.push(format!("README.md:{line}: no `{path}` in the repository"));
        }
    }
    for link in markdown::links(text) {
        if link.target.contains("://") || link.target.starts_with("mailto:") {
            continue;
        }
        let (file, anchor) = link.target.split_once('#').unwrap_or((&link.target, ""));
        let line = link.line;
        let target = if file.is_empty() {
            text.to_owned()
        } else if root.join(file).exists() {
            std::fs::read_to_string(root.join(file)).unwrap_or_default()
        } else {
            problems.push(format!(
                "README.md:{line}: the link to `{file}` leads nowhere"
            ));
            continue;
        };
        let headings = markdown::headings(&target);
        if !anchor.is_empty() && !headings.iter().any(|h| markdown::slug(h) == anchor) {
            problems.push(format!(
                "README.md:{line}: `{file}` has no anchor `#{anchor}`"
            ));
        }
        if let Some(section) = &link.section {
            let section = section.replace('`', "");
            if !headings.iter().any(|heading| heading.starts_with(&section)) {
                problems.push(format!(
                    "README.md:{line}: `{file}` has no section \"{section}\""
                ));
            }
        }
    }
    problems
}

#[test]
fn the_readme_stays_short() {
    let lines = readme().lines().count();
    assert!(
        lines <= MAX_LINES,
        "README.md has {lines} lines, more than {MAX_LINES}: move the detail into docs/ and link it"
    );
}

#[test]
fn every_readme_command_exists() {
    let workspace = workspace();
    let (problems, checked) = command_problems(&readme(), &workspace);
    assert!(
        problems.is_empty(),
        "README commands that do not parse:\n{}",
        problems.join("\n")
    );
    // The README's tour runs a few dozen of the project's commands; far fewer would mean the
    // blocks were not read.
    assert!(
        checked >= 20,
        "only {checked} of the README's commands were the project's"
    );
}

#[test]
fn every_path_and_link_the_readme_names_exists() {
    let workspace = workspace();
    let problems = path_problems(&readme(), &workspace);
    assert!(
        problems.is_empty(),
        "README paths and links:\n{}",
        problems.join("\n")
    );
}

/// The checks fail on what a rename leaves behind: each line below is a README command or
/// reference gone stale one way, and each is reported (motionctl's help, the workspace's
/// manifests, the scripts and the Python package are the real ones).
#[test]
fn renamed_commands_and_paths_are_reported() {
    let workspace = workspace();
    let stale = [
        ("motionctl wait-readyy", "no subcommand `wait-readyy`"),
        (
            "motionctl move x 100 --velocityy 20 --wait",
            "no option `--velocityy`",
        ),
        ("motionctl group move", "misses its argument <GROUP>"),
        ("motionctl io set lamp dim", "is not one of <on|off>"),
        (
            "motionctl record --out /tmp/run.csv",
            "requires `--duration`",
        ),
        (
            "alias mc=target/release/motionctll",
            "no binary of the workspace",
        ),
        ("./scripts/tset", "no script `scripts/tset`"),
        (
            "cargo build --release -p motionctll",
            "no package `motionctll`",
        ),
        (
            "cargo run -p motion-client --example closed_lop -- demo 5",
            "no --example",
        ),
        ("python -m motiond stats", "is not one of"),
        (
            "python -m motiond status --serve demo",
            "no option `--serve`",
        ),
    ];
    let mut text = String::from("```sh\nmotionctl move x 100 --velocity 20 --wait   # fine\n");
    for (line, _) in &stale {
        text.push_str(line);
        text.push('\n');
    }
    text.push_str("```\n");
    let (problems, _) = command_problems(&text, &workspace);
    assert!(
        !problems.iter().any(|p| p.contains(":2:")),
        "a good line was refused: {problems:#?}"
    );
    for (index, (line, expected)) in stale.iter().enumerate() {
        let at = format!("README.md:{}:", index + 3);
        assert!(
            problems
                .iter()
                .any(|p| p.starts_with(&at) && p.contains(expected)),
            "`{line}` not reported as {expected:?}: {problems:#?}"
        );
    }

    let text = "See `docs/NOPE.md`, [the keys](docs/CONFIG.md) \"No such section\",\n\
                [a file](docs/GONE.md) and [an anchor](README.md#no-such-anchor).\n";
    let problems = path_problems(text, &workspace);
    for expected in [
        "no `docs/NOPE.md`",
        "no section \"No such section\"",
        "`docs/GONE.md` leads nowhere",
        "no anchor `#no-such-anchor`",
    ] {
        assert!(
            problems.iter().any(|p| p.contains(expected)),
            "{expected:?} not reported: {problems:#?}"
        );
    }
}
