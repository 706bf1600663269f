//! The bridge's configuration: a TOML file (`--config`), command-line options over it, and
//! the defaults. Every problem of a file is reported at once, each naming its key.
//!
//! ```toml
//! server = "demo"                  # the motiond instance ([server] name of its config)
//! listen = ["tcp/0.0.0.0:7447"]    # zenoh endpoints to listen on
//! connect = []                     # zenoh endpoints to connect to (a router, another peer)
//! frame_rate = 100                 # frames per second published (server ticks decimated)
//! json_rate = 10                   # JSON states per second
//! reply_timeout_ms = 1000          # how long a command waits for the server's reply
//! # max_delay_ms = 250             # the window of every request's time stamp (default: the deadman)
//! # zenoh_config = "zenoh.json5"   # zenoh's own config: TLS, user/password, access control
//!
//! [[remote]]
//! identity = "panel"               # the identity a remote connects with (`*`: any other)
//! allow = ["stop", "estop", "move", "jog"]
//! rate = 200                       # requests per second, sustained
//! burst = 100                      # requests at once above that
//! stop_burst = 1000                # stops at once above `rate` (their own bucket)
//! # sessions = 512                 # sessions open at once (default: an equal share of 1024)
//! ```

use core::time::Duration;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::policy::{
    DEFAULT_BURST, DEFAULT_RATE, DEFAULT_STOP_BURST, KindSet, MAX_SESSIONS, RemoteRule,
};
use motion_wire::keys::{DEFAULT_PORT, check_chunk};

/// Default frames per second.
pub const DEFAULT_FRAME_RATE: f64 = 100.0;
/// Default JSON states per second.
pub const DEFAULT_JSON_RATE: f64 = 10.0;
/// Default wait for the server's reply to a command.
pub const DEFAULT_REPLY_TIMEOUT: Duration = Duration::from_secs(1);

/// The default listening endpoint.
pub fn default_listen() -> String {
    format!("tcp/0.0.0.0:{DEFAULT_PORT}")
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    server: Option<String>,
    listen: Option<Vec<String>>,
    connect: Option<Vec<String>>,
    frame_rate: Option<f64>,
    json_rate: Option<f64>,
    reply_timeout_ms: Option<u64>,
    max_delay_ms: Option<u64>,
    zenoh_config: Option<PathBuf>,
    #[serde(default)]
    remote: Vec<RawRemote>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRemote {
    identity: String,
    allow: Vec<String>,
    rate: Option<f64>,
    burst: Option<f64>,
    stop_burst: Option<f64>,
    sessions: Option<usize>,
}

/// What the command line gives (each `None` / empty: the file's value, else the default).
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    /// `--server`.
    pub server: Option<String>,
    /// `--listen`, repeatable.
    pub listen: Vec<String>,
    /// `--connect`, repeatable.
    pub connect: Vec<String>,
    /// `--frame-rate`.
    pub frame_rate: Option<f64>,
    /// `--json-rate`.
    pub json_rate: Option<f64>,
    /// `--zenoh-config`.
    pub zenoh_config: Option<PathBuf>,
    /// `--insecure`: start with an allow-list wider than stop and e-stop although zenoh
    /// authenticates nobody.
    pub insecure: bool,
}

/// A checked configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct BridgeConfig {
    /// The motiond instance.
    pub server: String,
    /// zenoh endpoints to listen on.
    pub listen: Vec<String>,
    /// zenoh endpoints to connect to.
    pub connect: Vec<String>,
    /// Frames per second.
    pub frame_rate: f64,
    /// JSON states per second.
    pub json_rate: f64,
    /// Wait for the server's reply.
    pub reply_timeout: Duration,
    /// Lateness bound of requests (`None`: the server's deadman).
    pub max_delay: Option<Duration>,
    /// zenoh's own config file, merged under the endpoints above.
    pub zenoh_config: Option<PathBuf>,
    /// Whether the bridge may let remotes do more than stop and e-stop without zenoh
    /// authentication (`--insecure` only: never from the file).
    pub insecure: bool,
    /// What each remote identity may do.
    pub remotes: Vec<RemoteRule>,
}

/// Why a configuration was not taken.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read {path}: {error}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file is not valid TOML or has keys the bridge does not know.
    #[error("{path}: {error}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// toml's message (line and column).
        error: Box<toml::de::Error>,
    },
    /// Values out of range; every one of them.
    #[error("{origin}: {}", .issues.join("; "))]
    Invalid {
        /// The file, or "command line".
        origin: String,
        /// One sentence per problem, naming the key.
        issues: Vec<String>,
    },
}

impl BridgeConfig {
    /// The configuration of `file` (if any) under `overrides`.
    pub fn load(file: Option<&Path>, overrides: Overrides) -> Result<Self, ConfigError> {
        match file {
            None => Self::from_parts(RawConfig::default(), overrides, "command line"),
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|error| ConfigError::Read {
                    path: path.to_owned(),
                    error,
                })?;
                Self::parse(&text, path, overrides)
            }
        }
    }

    /// The configuration in `text` (read from `path`, for messages) under `overrides`.
    pub fn parse(text: &str, path: &Path, overrides: Overrides) -> Result<Self, ConfigError> {
        let raw: RawConfig = toml::from_str(text).map_err(|error| ConfigError::Parse {
            path: path.to_owned(),
            error: Box::new(error),
        })?;
        let mut config = Self::from_parts(raw, overrides, &path.display().to_string())?;
        // A relative zenoh config is relative to the bridge's config file.
        if let (Some(zenoh), Some(dir)) = (&config.zenoh_config, path.parent())
            && zenoh.is_relative()
        {
            config.zenoh_config = Some(dir.join(zenoh));
        }
        Ok(config)
    }

    fn from_parts(raw: RawConfig, cli: Overrides, origin: &str) -> Result<Self, ConfigError> {
        let mut issues = Vec::new();
        let server = cli
            .server
            .or(raw.server)
            .unwrap_or_else(|| "demo".to_owned());
        if let Err(error) = check_chunk("server name", &server) {
            issues.push(format!("server: {error}"));
        }
        let listen = match (cli.listen.is_empty(), raw.listen) {
            (false, _) => cli.listen,
            (true, Some(listen)) => listen,
            (true, None) => vec![default_listen()],
        };
        let connect = if cli.connect.is_empty() {
            raw.connect.unwrap_or_default()
        } else {
            cli.connect
        };
        for (key, endpoints) in [("listen", &listen), ("connect", &connect)] {
            for (index, endpoint) in endpoints.iter().enumerate() {
                if !endpoint.contains('/') || endpoint.contains(char::is_whitespace) {
                    issues.push(format!(
                        "{key}[{index}]: `{endpoint}` is not a zenoh endpoint (like \
                         `tcp/0.0.0.0:{DEFAULT_PORT}`)"
                    ));
                }
            }
        }
        let mut rate = |key: &str, value: Option<f64>, default: f64| match value {
            None => default,
            Some(value) if value.is_finite() && value > 0.0 && value <= 100_000.0 => value,
            Some(value) => {
                issues.push(format!(
                    "{key}: {value} is not a rate (a number of Hz above 0, at most 100000)"
                ));
                default
            }
        };
        let frame_rate = rate(
            "frame_rate",
            cli.frame_rate.or(raw.frame_rate),
            DEFAULT_FRAME_RATE,
        );
        let json_rate = rate(
            "json_rate",
            cli.json_rate.or(raw.json_rate),
            DEFAULT_JSON_RATE,
        );
        let reply_timeout = match raw.reply_timeout_ms {
            None => DEFAULT_REPLY_TIMEOUT,
            Some(0) => {
                issues.push("reply_timeout_ms: must be above 0".to_owned());
                DEFAULT_REPLY_TIMEOUT
            }
            Some(ms) => Duration::from_millis(ms),
        };
        let max_delay = match raw.max_delay_ms {
            Some(0) => {
                issues.push(
                    "max_delay_ms: must be above 0 (the window every request's time stamp is \
                     judged in)"
                        .to_owned(),
                );
                None
            }
            ms => ms.map(Duration::from_millis),
        };
        let remotes = remotes(raw.remote, &mut issues);
        if !issues.is_empty() {
            return Err(ConfigError::Invalid {
                origin: origin.to_owned(),
                issues,
            });
        }
        Ok(Self {
            server,
            listen,
            connect,
            frame_rate,
            json_rate,
            reply_timeout,
            max_delay,
            zenoh_config: cli.zenoh_config.or(raw.zenoh_config),
            insecure: cli.insecure,
            remotes,
        })
    }
}

fn remotes(raw: Vec<RawRemote>, issues: &mut Vec<String>) -> Vec<RemoteRule> {
    let mut seen = HashSet::new();
    let mut rules = Vec::new();
    let mut shares = Vec::new();
    for (index, remote) in raw.into_iter().enumerate() {
        let at = format!("remote[{index}]");
        if remote.identity != "*"
            && let Err(error) = check_chunk("remote identity", &remote.identity)
        {
            issues.push(format!("{at}.identity: {error}, or `*` for any"));
        }
        if !seen.insert(remote.identity.clone()) {
            issues.push(format!(
                "{at}.identity: `{}` has a [[remote]] entry already",
                remote.identity
            ));
        }
        let mut allow = KindSet::NONE;
        for (position, name) in remote.allow.iter().enumerate() {
            match KindSet::from_name(name) {
                Some(kinds) => allow = allow.union(kinds),
                None => issues.push(format!(
                    "{at}.allow[{position}]: `{name}` is not a command (use {})",
                    KindSet::known_names()
                )),
            }
        }
        let mut positive = |key: &str, value: Option<f64>, default: f64, least: f64| match value {
            None => default,
            Some(value) if value.is_finite() && value >= least => value,
            Some(value) => {
                issues.push(format!(
                    "{at}.{key}: {value} must be a number of at least {least}"
                ));
                default
            }
        };
        let rate = positive("rate", remote.rate, DEFAULT_RATE, f64::MIN_POSITIVE);
        let burst = positive("burst", remote.burst, DEFAULT_BURST, 1.0);
        let stop_burst = positive("stop_burst", remote.stop_burst, DEFAULT_STOP_BURST, 1.0);
        if let Some(sessions) = remote.sessions
            && !(1..=MAX_SESSIONS).contains(&sessions)
        {
            issues.push(format!(
                "{at}.sessions: {sessions} must be 1 to {MAX_SESSIONS} (the bridge's table)"
            ));
        }
        shares.push(remote.sessions);
        rules.push(RemoteRule {
            identity: remote.identity,
            allow,
            rate,
            burst,
            stop_burst,
            sessions: 0,
        });
    }
    share_sessions(&mut rules, &shares, issues);
    rules
}

/// Each entry's share of the session table: its `sessions`, or an equal part of what the
/// others leave among the entries that get sessions (those that allow more than stop and
/// e-stop) and name none. The shares together fit in [`MAX_SESSIONS`].
fn share_sessions(rules: &mut [RemoteRule], shares: &[Option<usize>], issues: &mut Vec<String>) {
    let given: usize = shares.iter().flatten().sum();
    if given > MAX_SESSIONS {
        issues.push(format!(
            "remote[].sessions: together {given}, more than the bridge's {MAX_SESSIONS}"
        ));
        return;
    }
    let open = rules
        .iter()
        .zip(shares)
        .filter(|(rule, share)| share.is_none() && rule.allows_more_than_safety())
        .count();
    let each = (MAX_SESSIONS - given).checked_div(open).unwrap_or(0);
    if open > 0 && each == 0 {
        issues.push(format!(
            "remote[].sessions: the entries that name one take all {MAX_SESSIONS}, none is left \
             for the {open} that do not"
        ));
    }
    for (rule, share) in rules.iter_mut().zip(shares) {
        rule.sessions = match share {
            Some(share) => *share,
            None if rule.allows_more_than_safety() => each,
            // Stop and e-stop only: no session (it needs none).
            None => 0,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_ipc::CommandKind;

    fn parse(text: &str) -> Result<BridgeConfig, ConfigError> {
        BridgeConfig::parse(text, Path::new("/etc/bridge.toml"), Overrides::default())
    }

    #[test]
    fn a_full_file_and_the_defaults() -> Result<(), ConfigError> {
        let config = parse(
            r#"
            server = "cell-4"
            listen = ["tcp/127.0.0.1:7500"]
            frame_rate = 50
            max_delay_ms = 300
            zenoh_config = "zenoh.json5"

            [[remote]]
            identity = "panel"
            allow = ["stop", "estop", "move"]
            rate = 20
            burst = 5
            stop_burst = 50

            [[remote]]
            identity = "*"
            allow = ["stop"]
            "#,
        )?;
        assert_eq!(config.server, "cell-4");
        assert_eq!(config.listen, ["tcp/127.0.0.1:7500"]);
        assert_eq!(config.frame_rate, 50.0);
        assert_eq!(config.json_rate, DEFAULT_JSON_RATE);
        assert_eq!(config.max_delay, Some(Duration::from_millis(300)));
        assert_eq!(
            config.zenoh_config.as_deref(),
            Some(Path::new("/etc/zenoh.json5"))
        );
        let panel = &config.remotes[0];
        assert!(panel.allow.contains(CommandKind::EStop));
        assert!(panel.allow.contains(CommandKind::RampPosition));
        assert!(!panel.allow.contains(CommandKind::Velocity));
        assert_eq!(
            (panel.rate, panel.burst, panel.stop_burst),
            (20.0, 5.0, 50.0)
        );
        assert_eq!(config.remotes[1].rate, DEFAULT_RATE);
        assert_eq!(config.remotes[1].stop_burst, DEFAULT_STOP_BURST);
        // The panel, the only entry that gets sessions, has the whole table; `*` (stop
        // only) none.
        assert_eq!(
            (panel.sessions, config.remotes[1].sessions),
            (MAX_SESSIONS, 0)
        );

        let defaults = BridgeConfig::load(None, Overrides::default())?;
        assert_eq!(defaults.server, "demo");
        assert_eq!(defaults.listen, [default_listen()]);
        assert!(
            defaults.remotes.is_empty(),
            "no remote may command by default"
        );
        assert_eq!(defaults.reply_timeout, DEFAULT_REPLY_TIMEOUT);
        Ok(())
    }

    #[test]
    fn the_command_line_wins() -> Result<(), ConfigError> {
        let overrides = Overrides {
            server: Some("other".to_owned()),
            listen: vec!["tcp/10.0.0.1:7447".to_owned()],
            frame_rate: Some(25.0),
            ..Overrides::default()
        };
        let config = BridgeConfig::parse(
            "server = \"demo\"\nframe_rate = 50\n",
            Path::new("b.toml"),
            overrides,
        )?;
        assert_eq!(config.server, "other");
        assert_eq!(config.listen, ["tcp/10.0.0.1:7447"]);
        assert_eq!(config.frame_rate, 25.0);
        Ok(())
    }

    #[test]
    fn every_problem_is_reported_at_once() {
        let error = parse(
            r#"
            server = "a/b"
            listen = ["7447"]
            frame_rate = -1
            max_delay_ms = 0
            [[remote]]
            identity = "pa*nel"
            allow = ["stop", "teleport"]
            rate = nan
            [[remote]]
            identity = "pa*nel"
            allow = []
            burst = 0.5
            stop_burst = 0
            "#,
        )
        .expect_err("invalid");
        let text = error.to_string();
        for part in [
            "server:",
            "listen[0]",
            "frame_rate",
            "max_delay_ms: must be above 0",
            "remote[0].identity",
            "remote[0].allow[1]: `teleport`",
            "remote[0].rate",
            "remote[1].identity: `pa*nel` has a [[remote]] entry already",
            "remote[1].burst",
            "remote[1].stop_burst",
        ] {
            assert!(text.contains(part), "missing {part:?} in {text}");
        }
    }

    #[test]
    fn unknown_keys_and_bad_toml_name_the_line() {
        let text = parse("server = \"demo\"\nlisten_on = []\n")
            .expect_err("unknown key")
            .to_string();
        assert!(
            text.contains("listen_on") && text.contains("line 2"),
            "{text}"
        );
        let text = parse("[[remote]]\nidentity = \"x\"\n")
            .expect_err("allow missing")
            .to_string();
        assert!(text.contains("allow"), "{text}");
    }

    #[test]
    fn the_session_table_is_shared_between_entries() -> Result<(), ConfigError> {
        let config = parse(
            r#"
            [[remote]]
            identity = "panel"
            allow = ["all"]
            sessions = 24
            [[remote]]
            identity = "tablet"
            allow = ["move"]
            [[remote]]
            identity = "*"
            allow = ["jog"]
            [[remote]]
            identity = "viewer"
            allow = ["stop"]
            "#,
        )?;
        let shares: Vec<usize> = config.remotes.iter().map(|rule| rule.sessions).collect();
        assert_eq!(shares, [24, 500, 500, 0]);
        let error = parse(
            r#"
            [[remote]]
            identity = "a"
            allow = ["all"]
            sessions = 1000
            [[remote]]
            identity = "b"
            allow = ["all"]
            sessions = 100
            "#,
        )
        .expect_err("more than the table")
        .to_string();
        assert!(error.contains("together 1100"), "{error}");
        let error = parse("[[remote]]\nidentity = \"a\"\nallow = [\"all\"]\nsessions = 0\n")
            .expect_err("no session")
            .to_string();
        assert!(
            error.contains("remote[0].sessions: 0 must be 1 to 1024"),
            "{error}"
        );
        Ok(())
    }
}
