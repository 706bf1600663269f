//! One README command against the repository: a project binary's subcommands and options
//! against its `--help`, `cargo run|build|test|bench -p` against the workspace's packages
//! and targets, `scripts/…` against the scripts, `python -m motiond…` against the Python
//! package's modules. Commands of other programs (`pip`, `screen`, `python3 -c`) are not
//! the project's and pass unchecked.

use std::collections::BTreeMap;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use super::help::{self, Help};
use super::workspace::{Workspace, built_binary};

/// Checks commands in README order (an `alias` holds for the commands after it).
#[derive(Debug)]
pub struct Checker<'a> {
    workspace: &'a Workspace,
    aliases: BTreeMap<String, Vec<String>>,
    helps: BTreeMap<(PathBuf, Vec<String>), Result<Help, String>>,
    /// How many commands were the project's (and so checked).
    pub checked: usize,
}

impl<'a> Checker<'a> {
    pub fn new(workspace: &'a Workspace) -> Self {
        Self {
            workspace,
            aliases: BTreeMap::new(),
            helps: BTreeMap::new(),
            checked: 0,
        }
    }

    /// What is wrong with `words` (empty when nothing is, or when it is not a command of
    /// the project's).
    pub fn check(&mut self, words: &[String]) -> Vec<String> {
        let mut words = words;
        // `NAME=value command …`, `sudo -u motion command …`
        while let Some(first) = words.first() {
            let assignment = first.split_once('=').is_some_and(|(name, _)| {
                !name.is_empty() && name.chars().all(|c| c.is_alphanumeric() || c == '_')
            });
            if assignment {
                words = &words[1..];
            } else if first == "sudo" {
                words = &words[1..];
                while let Some(option) = words.first().filter(|word| word.starts_with('-')) {
                    let skip = if matches!(option.as_str(), "-u" | "-g") {
                        2
                    } else {
                        1
                    };
                    words = &words[skip.min(words.len())..];
                }
            } else {
                break;
            }
        }
        let Some(program) = words.first() else {
            return Vec::new();
        };
        let expanded: Vec<String>;
        if let Some(alias) = self.aliases.get(program) {
            expanded = alias.iter().chain(&words[1..]).cloned().collect();
            words = &expanded;
        }
        let program = words[0].as_str();
        let args = &words[1..];
        if program == "alias" {
            return self.alias(args);
        }
        if program == "cargo" {
            return self.cargo(args);
        }
        if program == "python" || program == "python3" {
            return self.python(args);
        }
        let script = program.strip_prefix("./").unwrap_or(program);
        if script.starts_with("scripts/") {
            return self.script(script, args);
        }
        match self.binary_name(program) {
            Some(bin) => self.binary(&bin, args),
            None => Vec::new(),
        }
    }

    /// `motionctl`, `target/release/motionctl`: the name of a workspace binary.
    fn binary_name(&self, program: &str) -> Option<String> {
        let name = match program.strip_prefix("target/") {
            Some(rest) => rest.rsplit('/').next()?,
            None => program,
        };
        self.workspace.package_of_bin(name).map(|_| name.to_owned())
    }

    /// `alias motionctl=target/release/motionctl`: the target must be a workspace binary.
    fn alias(&mut self, args: &[String]) -> Vec<String> {
        let mut problems = Vec::new();
        for definition in args {
            let Some((name, value)) = definition.split_once('=') else {
                continue;
            };
            let words: Vec<String> = value.split_whitespace().map(str::to_owned).collect();
            if let Some(program) = words.first()
                && program.starts_with("target/")
                && self.binary_name(program).is_none()
            {
                problems.push(format!(
                    "alias {name}: `{program}` is no binary of the workspace"
                ));
            }
            self.checked += 1;
            self.aliases.insert(name.to_owned(), words);
        }
        problems
    }

    /// The binary `bin`'s subcommands and options, from its `--help` pages.
    fn binary(&mut self, bin: &str, args: &[String]) -> Vec<String> {
        self.checked += 1;
        self.against_help(bin, args)
    }

    fn against_help(&mut self, bin: &str, args: &[String]) -> Vec<String> {
        let Some(package) = self.workspace.package_of_bin(bin) else {
            return vec![format!("no package of the workspace has a binary `{bin}`")];
        };
        let package = package.to_owned();
        let path = match built_binary(&package, bin) {
            Ok(path) => path,
            Err(problem) => return vec![problem],
        };
        let helps = &mut self.helps;
        help::walk(bin, args, |subcommands| {
            helps
                .entry((path.clone(), subcommands.to_vec()))
                .or_insert_with(|| help_page(&path, subcommands))
                .clone()
        })
        .problems
    }

    /// `cargo run|build|test|bench|install|check|clippy …`: packages, targets and features
    /// exist; the arguments after `--` of a binary `cargo run` runs are that binary's.
    fn cargo(&mut self, args: &[String]) -> Vec<String> {
        let args: Vec<&str> = args
            .iter()
            .map(String::as_str)
            .skip_while(|word| word.starts_with('+'))
            .collect();
        let Some((&command, rest)) = args.split_first() else {
            return Vec::new();
        };
        if !matches!(
            command,
            "run" | "build" | "test" | "bench" | "install" | "check" | "clippy"
        ) {
            return Vec::new();
        }
        self.checked += 1;
        let (own, after) = match rest.iter().position(|&word| word == "--") {
            Some(at) => (&rest[..at], &rest[at + 1..]),
            None => (rest, &[][..]),
        };
        let mut problems = Vec::new();
        let mut packages = Vec::new();
        let (mut bin, mut example) = (None, None);
        let mut index = 0;
        while index < own.len() {
            let (flag, value) = (own[index], own.get(index + 1).copied());
            index += 1;
            let known = &self.workspace.packages;
            match (flag, value) {
                ("-p" | "--package", Some(name)) => {
                    index += 1;
                    if known.contains_key(name) {
                        packages.push(name.to_owned());
                    } else {
                        problems.push(format!("cargo {command}: no package `{name}`"));
                    }
                }
                ("--path", Some(path)) => {
                    index += 1;
                    if !self.workspace.root.join(path).join("Cargo.toml").is_file() {
                        problems.push(format!("cargo {command}: no package at `{path}`"));
                    }
                }
                ("--bin" | "--example" | "--bench" | "--features" | "-F", Some(name)) => {
                    index += 1;
                    match flag {
                        "--bin" => bin = Some(name.to_owned()),
                        "--example" => example = Some(name.to_owned()),
                        _ => {}
                    }
                    let scope = if packages.is_empty() {
                        known.values().collect::<Vec<_>>()
                    } else {
                        packages.iter().map(|name| &known[name]).collect()
                    };
                    for name in name.split(',') {
                        let found = scope.iter().any(|package| match flag {
                            "--bin" => package.bins.contains(name),
                            "--example" => package.examples.contains(name),
                            "--bench" => package.benches.contains(name),
                            _ => package.features.contains(name),
                        });
                        if !found {
                            problems.push(format!("cargo {command}: no {flag} `{name}`"));
                        }
                    }
                }
                _ => {}
            }
        }
        if command != "run" || example.is_some() || !problems.is_empty() {
            return problems;
        }
        // The binary `cargo run` runs, and the arguments it is given.
        let runs: Vec<String> = if packages.is_empty() {
            self.workspace.default_run.clone()
        } else {
            packages
        };
        let bins: Vec<String> = match bin {
            Some(bin) => vec![bin],
            None => runs
                .iter()
                .flat_map(|name| self.workspace.packages[name].bins.iter().cloned())
                .collect(),
        };
        match &bins[..] {
            [_] if after.is_empty() => Vec::new(),
            [bin] => {
                let after: Vec<String> = after.iter().map(|&word| word.to_owned()).collect();
                self.against_help(bin, &after)
            }
            _ => vec![format!(
                "cargo run: {runs:?} has {} binaries ({bins:?}), not one",
                bins.len()
            )],
        }
    }

    /// `python -m motiond[.module] …`: the module exists, its options are ones it
    /// declares (`"--server"` in its source), its first argument one of its `choices`.
    fn python(&mut self, args: &[String]) -> Vec<String> {
        let [flag, module, rest @ ..] = args else {
            return Vec::new();
        };
        if flag != "-m" || !(module == "motiond" || module.starts_with("motiond.")) {
            return Vec::new();
        }
        self.checked += 1;
        let src = self.workspace.root.join("python/src");
        let file = match module.split_once('.') {
            None => src.join("motiond/__main__.py"),
            Some((_, name)) => src.join("motiond").join(format!("{name}.py")),
        };
        let Ok(source) = std::fs::read_to_string(&file) else {
            return vec![format!("python -m {module}: no {}", file.display())];
        };
        let mut problems = Vec::new();
        for word in rest.iter().filter(|word| word.starts_with("--")) {
            let name = word.split('=').next().unwrap_or(word);
            if !source.contains(&format!("\"{name}\"")) {
                problems.push(format!("python -m {module}: no option `{name}`"));
            }
        }
        let choices = choices(&source);
        let first = rest.iter().find(|word| !word.starts_with('-'));
        if let Some(first) = first
            && !choices.is_empty()
            && !choices.contains(first)
        {
            problems.push(format!(
                "python -m {module}: `{first}` is not one of {choices:?}"
            ));
        }
        problems
    }

    /// `scripts/NAME …`: an executable file, and each option one the script's text names.
    fn script(&mut self, script: &str, args: &[String]) -> Vec<String> {
        self.checked += 1;
        let path = self.workspace.root.join(script);
        let Ok(meta) = std::fs::metadata(&path) else {
            return vec![format!("no script `{script}`")];
        };
        let mut problems = Vec::new();
        if meta.permissions().mode() & 0o111 == 0 {
            problems.push(format!("`{script}` is not executable"));
        }
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        for word in args.iter().filter(|word| word.starts_with("--")) {
            let name = word.split('=').next().unwrap_or(word);
            if !text.contains(name) {
                problems.push(format!("`{script}` knows no option `{name}`"));
            }
        }
        problems
    }
}

/// `<path> <subcommands…> --help`.
fn help_page(path: &Path, subcommands: &[String]) -> Result<Help, String> {
    let output = Command::new(path)
        .args(subcommands)
        .arg("--help")
        .output()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    let shown = format!("{} {} --help", path.display(), subcommands.join(" "));
    if !output.status.success() {
        return Err(format!(
            "`{shown}` failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    let text = String::from_utf8(output.stdout).map_err(|e| format!("`{shown}`: {e}"))?;
    Ok(help::parse(&text, 1 + subcommands.len()))
}

/// The words of every `choices=[…]` list of a Python source.
fn choices(source: &str) -> Vec<String> {
    let mut found = Vec::new();
    for (at, opening) in source.match_indices("choices=[") {
        let rest = &source[at + opening.len()..];
        let list = rest.split(']').next().unwrap_or("");
        found.extend(
            list.split(',')
                .map(|item| item.trim().trim_matches(['"', '\'']).to_owned())
                .filter(|item| !item.is_empty()),
        );
    }
    found
}
