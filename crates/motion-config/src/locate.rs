//! Which config file `motiond` runs when none is named: `--config FILE`, else
//! `$MOTIOND_CONFIG`, else the installed `/etc/motiond/motiond.toml`, else the source tree's
//! simulated robot `config/sim.toml` when run from the tree's root (the README's `cargo run
//! --release`).
//!
//! The search reads no environment and touches no file itself: the caller passes what it
//! found ([`Places`]), so the order is tested without a machine's `/etc`.

use std::fmt;
use std::path::{Path, PathBuf};

/// The environment variable naming the config file.
pub const CONFIG_ENV: &str = "MOTIOND_CONFIG";
/// The installed config (deploy/README.md).
pub const INSTALLED_CONFIG: &str = "/etc/motiond/motiond.toml";
/// The source tree's simulated robot, relative to the tree's root.
pub const SOURCE_TREE_CONFIG: &str = "config/sim.toml";

/// Where the config file came from (said in motiond's first log line).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfigSource {
    /// `--config FILE` (or `--check-config FILE`).
    Flag,
    /// `$MOTIOND_CONFIG`.
    Environment,
    /// `/etc/motiond/motiond.toml`.
    Installed,
    /// `config/sim.toml` below the working directory (the source tree).
    SourceTree,
}

impl fmt::Display for ConfigSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Flag => "given with --config",
            Self::Environment => "named by $MOTIOND_CONFIG",
            Self::Installed => "the installed config",
            Self::SourceTree => "the source tree's simulated robot",
        })
    }
}

/// What the search may choose from.
#[derive(Debug, Clone, Default)]
pub struct Places {
    /// `--config FILE`.
    pub flag: Option<PathBuf>,
    /// The value of `$MOTIOND_CONFIG` (an empty value counts as unset).
    pub environment: Option<PathBuf>,
    /// Whether `/etc/motiond/motiond.toml` exists.
    pub installed_exists: bool,
    /// Whether `config/sim.toml` exists below the working directory.
    pub source_tree_exists: bool,
}

impl Places {
    /// The places of this process: its flag, its environment and its file system.
    pub fn of_process(flag: Option<PathBuf>) -> Self {
        Self {
            flag,
            environment: std::env::var_os(CONFIG_ENV).map(PathBuf::from),
            installed_exists: Path::new(INSTALLED_CONFIG).is_file(),
            source_tree_exists: Path::new(SOURCE_TREE_CONFIG).is_file(),
        }
    }
}

/// No config was named and none was found.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "motiond: no config file: pass --config FILE, set {CONFIG_ENV}=FILE, or install \
     {INSTALLED_CONFIG} (from a checkout, run in its root: {SOURCE_TREE_CONFIG} is the \
     simulated robot)"
)]
pub struct NoConfig;

/// The file to run and where it came from: the first of the flag, the environment, the
/// installed config and the source tree's. A named file (flag or environment) is taken as
/// named even when it does not exist, so that loading it says so.
pub fn locate(places: &Places) -> Result<(PathBuf, ConfigSource), NoConfig> {
    if let Some(path) = &places.flag {
        return Ok((path.clone(), ConfigSource::Flag));
    }
    if let Some(path) = places
        .environment
        .as_ref()
        .filter(|p| !p.as_os_str().is_empty())
    {
        return Ok((path.clone(), ConfigSource::Environment));
    }
    if places.installed_exists {
        return Ok((PathBuf::from(INSTALLED_CONFIG), ConfigSource::Installed));
    }
    if places.source_tree_exists {
        return Ok((PathBuf::from(SOURCE_TREE_CONFIG), ConfigSource::SourceTree));
    }
    Err(NoConfig)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn places(flag: bool, environment: &str, installed: bool, tree: bool) -> Places {
        Places {
            flag: flag.then(|| PathBuf::from("given.toml")),
            environment: Some(PathBuf::from(environment)),
            installed_exists: installed,
            source_tree_exists: tree,
        }
    }

    #[test]
    fn the_flag_comes_first_then_the_environment_then_etc_then_the_tree() {
        let found = |p: &Places| locate(p);
        assert_eq!(
            found(&places(true, "env.toml", true, true)),
            Ok((PathBuf::from("given.toml"), ConfigSource::Flag))
        );
        assert_eq!(
            found(&places(false, "env.toml", true, true)),
            Ok((PathBuf::from("env.toml"), ConfigSource::Environment))
        );
        assert_eq!(
            found(&places(false, "", true, true)),
            Ok((PathBuf::from(INSTALLED_CONFIG), ConfigSource::Installed))
        );
        assert_eq!(
            found(&places(false, "", false, true)),
            Ok((PathBuf::from(SOURCE_TREE_CONFIG), ConfigSource::SourceTree))
        );
        assert_eq!(found(&places(false, "", false, false)), Err(NoConfig));
    }

    #[test]
    fn the_no_config_line_names_every_way_to_pass_one() {
        let line = NoConfig.to_string();
        for words in [
            "--config FILE",
            "MOTIOND_CONFIG",
            INSTALLED_CONFIG,
            "config/sim.toml",
        ] {
            assert!(line.contains(words), "{line}");
        }
        assert!(!line.contains('\n'), "one line: {line}");
    }
}
