//! The workspace as the README's commands name it: its packages with their binaries,
//! examples, benches and features (read from the `Cargo.toml` files), the package
//! `cargo run` runs without `-p`, the top-level directories paths start with, and where
//! the binaries cargo built for this test are (and whether they are older than their
//! sources).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// One package of the workspace.
#[derive(Debug, Clone, Default)]
pub struct Package {
    pub bins: BTreeSet<String>,
    pub examples: BTreeSet<String>,
    pub benches: BTreeSet<String>,
    pub features: BTreeSet<String>,
}

/// The workspace at `root`.
#[derive(Debug, Clone)]
pub struct Workspace {
    pub root: PathBuf,
    /// By package name.
    pub packages: BTreeMap<String, Package>,
    /// The packages `cargo run` in the root chooses from (`default-members`).
    pub default_run: Vec<String>,
}

type Result<T> = core::result::Result<T, String>;

impl Workspace {
    /// Reads the root `Cargo.toml` and every member's.
    pub fn read(root: &Path) -> Result<Self> {
        let manifest = table(&root.join("Cargo.toml"))?;
        let workspace = manifest
            .get("workspace")
            .and_then(toml::Value::as_table)
            .ok_or("the root Cargo.toml has no [workspace]")?;
        let mut packages = BTreeMap::new();
        let mut dir_names = BTreeMap::new();
        for member in strings(workspace.get("members")) {
            for dir in expand(root, &member)? {
                let (name, package) = package(&dir)?;
                dir_names.insert(dir.clone(), name.clone());
                packages.insert(name, package);
            }
        }
        let default_run = strings(workspace.get("default-members"))
            .iter()
            .filter_map(|member| dir_names.get(&root.join(member)).cloned())
            .collect();
        Ok(Self {
            root: root.to_owned(),
            packages,
            default_run,
        })
    }

    /// The package that has binary `bin`.
    pub fn package_of_bin(&self, bin: &str) -> Option<&str> {
        self.packages
            .iter()
            .find(|(_, package)| package.bins.contains(bin))
            .map(|(name, _)| name.as_str())
    }

    /// The top-level directories of the repository a path may start with (not `target`,
    /// not `.git`).
    pub fn top_dirs(&self) -> Result<BTreeSet<String>> {
        let entries = std::fs::read_dir(&self.root).map_err(|e| format!("{e}"))?;
        Ok(entries
            .filter_map(core::result::Result::ok)
            .filter(|entry| entry.path().is_dir())
            .filter_map(|entry| entry.file_name().into_string().ok())
            .filter(|name| !matches!(name.as_str(), "target" | ".git" | ".venv"))
            .collect())
    }
}

/// `crates/boards/*` → every directory under `crates/boards` with a `Cargo.toml`.
fn expand(root: &Path, member: &str) -> Result<Vec<PathBuf>> {
    let Some(parent) = member.strip_suffix("/*") else {
        return Ok(vec![root.join(member)]);
    };
    let entries = std::fs::read_dir(root.join(parent)).map_err(|e| format!("{member}: {e}"))?;
    let mut dirs: Vec<PathBuf> = entries
        .filter_map(core::result::Result::ok)
        .map(|entry| entry.path())
        .filter(|dir| dir.join("Cargo.toml").is_file())
        .collect();
    dirs.sort();
    Ok(dirs)
}

/// The package in `dir`: its name and targets (cargo's auto-discovery included).
fn package(dir: &Path) -> Result<(String, Package)> {
    let manifest = table(&dir.join("Cargo.toml"))?;
    let name = manifest
        .get("package")
        .and_then(|package| package.get("name"))
        .and_then(toml::Value::as_str)
        .ok_or_else(|| format!("{}: no [package] name", dir.display()))?
        .to_owned();
    let named = |key: &str| -> BTreeSet<String> {
        manifest
            .get(key)
            .and_then(toml::Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(|target| target.get("name")?.as_str().map(str::to_owned))
            .collect()
    };
    let mut bins = named("bin");
    if dir.join("src/main.rs").is_file() {
        bins.insert(name.clone());
    }
    bins.extend(stems(&dir.join("src/bin")));
    let mut examples = named("example");
    examples.extend(stems(&dir.join("examples")));
    let mut benches = named("bench");
    benches.extend(stems(&dir.join("benches")));
    let features = manifest
        .get("features")
        .and_then(toml::Value::as_table)
        .map(|features| features.keys().cloned().collect())
        .unwrap_or_default();
    let package = Package {
        bins,
        examples,
        benches,
        features,
    };
    Ok((name, package))
}

/// The targets cargo finds in `dir`: `x.rs` and `x/main.rs` are `x`.
fn stems(dir: &Path) -> BTreeSet<String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return BTreeSet::new();
    };
    entries
        .filter_map(core::result::Result::ok)
        .map(|entry| entry.path())
        .filter_map(|path| {
            if path.extension().is_some_and(|ext| ext == "rs") {
                path.file_stem()?.to_str().map(str::to_owned)
            } else if path.join("main.rs").is_file() {
                path.file_name()?.to_str().map(str::to_owned)
            } else {
                None
            }
        })
        .collect()
}

fn table(path: &Path) -> Result<toml::Table> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.parse().map_err(|e| format!("{}: {e}", path.display()))
}

fn strings(value: Option<&toml::Value>) -> Vec<String> {
    value
        .and_then(toml::Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(|value| value.as_str().map(str::to_owned))
        .collect()
}

/// The binary `bin` of package `package` as cargo built it for this test: motionctl is
/// this package's own (`CARGO_BIN_EXE_motionctl`); another package's is looked for beside
/// it, and must be newer than every source file it was built from (the files cargo lists
/// in the `<bin>.d` beside it, its path dependencies' included), or its help could
/// describe a command line the sources no longer have.
pub fn built_binary(package: &str, bin: &str) -> Result<PathBuf> {
    let own = PathBuf::from(env!("CARGO_BIN_EXE_motionctl"));
    if bin == "motionctl" {
        return Ok(own);
    }
    let path = own.with_file_name(bin);
    let build = format!("build it first: `cargo build -p {package}` (same target directory)");
    let built =
        modified(&path).map_err(|_| format!("no `{bin}` at {}: {build}", path.display()))?;
    let Ok(dep_info) = std::fs::read_to_string(path.with_extension("d")) else {
        return Ok(path); // nothing says what it was built from
    };
    for source in sources(&dep_info) {
        if modified(Path::new(&source)).is_ok_and(|changed| changed > built) {
            return Err(format!(
                "`{}` is older than {source}, one of its sources: {build}",
                path.display()
            ));
        }
    }
    Ok(path)
}

/// The files a cargo dep-info file (`target: source source …`, spaces in names escaped)
/// lists.
fn sources(dep_info: &str) -> Vec<String> {
    let Some((_, list)) = dep_info
        .lines()
        .next()
        .and_then(|line| line.split_once(": "))
    else {
        return Vec::new();
    };
    let mut sources = Vec::new();
    let mut current = String::new();
    let mut chars = list.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => current.extend(chars.next()),
            ' ' if !current.is_empty() => sources.push(core::mem::take(&mut current)),
            ' ' => {}
            c => current.push(c),
        }
    }
    if !current.is_empty() {
        sources.push(current);
    }
    sources
}

fn modified(path: &Path) -> Result<SystemTime> {
    std::fs::metadata(path)
        .and_then(|meta| meta.modified())
        .map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dep_info_lists_its_sources() {
        let dep_info = "/t/debug/motiond: /r/a.rs /r/with\\ space.rs  /r/b.rs\n";
        assert_eq!(
            sources(dep_info),
            ["/r/a.rs", "/r/with space.rs", "/r/b.rs"]
        );
    }
}
