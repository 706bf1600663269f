//! The few keys of a motiond config the doctor needs: the tick rate and real-time settings
//! of `[server]` and the links' types and paths, read from the config motiond itself would
//! run (`motion_config`: the same validation, every mistake located), so the doctor never
//! checks a machine against a config the server would refuse.

use std::path::{Path, PathBuf};

use motion_config::{ServerConfig, Transport};
#[cfg(test)]
use serde::Deserialize;

/// Where the deployed server's config lives (deploy/README.md): the one motiond runs
/// without `--config`.
pub const DEPLOYED_CONFIG: &str = motion_config::locate::INSTALLED_CONFIG;

/// What the doctor reads of a config.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(test, derive(Deserialize), serde(default))]
pub struct DoctorConfig {
    /// `[server]`.
    pub server: ServerKeys,
    /// `[[link]]`.
    pub link: Vec<LinkKeys>,
}

/// `[server]` keys of interest.
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(test, derive(Deserialize), serde(default))]
pub struct ServerKeys {
    /// Instance name.
    pub name: String,
    /// Tick rate (motiond's default 1000).
    pub tick_hz: u32,
    /// SCHED_FIFO priority of the tick thread.
    pub rt_priority: Option<u8>,
    /// Core of the tick thread.
    pub cpu: Option<usize>,
    /// mlockall once the shared memory exists.
    pub lock_memory: bool,
}

impl Default for ServerKeys {
    fn default() -> Self {
        Self {
            name: String::new(),
            tick_hz: 1000,
            rt_priority: None,
            cpu: None,
            lock_memory: false,
        }
    }
}

/// `[[link]]` keys of interest.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[cfg_attr(test, derive(Deserialize), serde(default))]
pub struct LinkKeys {
    /// Link name.
    pub name: String,
    /// Its config `type`: `serial`, `spidev`, `spi-socket`, `sim`, `socketcan`, `sim-can`.
    #[cfg_attr(test, serde(rename = "type"))]
    pub kind: String,
    /// Device path.
    pub path: Option<PathBuf>,
}

impl LinkKeys {
    /// A tty (`type = "serial"`).
    pub fn is_serial(&self) -> bool {
        self.kind == "serial"
    }

    /// A spidev node.
    pub fn is_spidev(&self) -> bool {
        self.kind == "spidev"
    }
}

impl DoctorConfig {
    /// What the doctor needs of a validated config.
    pub fn of(config: &ServerConfig) -> Self {
        let server = &config.server;
        Self {
            server: ServerKeys {
                name: server.name.clone(),
                tick_hz: server.tick_hz,
                rt_priority: server.rt_priority,
                cpu: server.cpu,
                lock_memory: server.lock_memory,
            },
            link: config
                .links
                .iter()
                .map(|link| {
                    let (kind, path) = match &link.transport {
                        Transport::Serial { path, .. } => ("serial", Some(path.clone())),
                        Transport::Spidev { path, .. } => ("spidev", Some(path.clone())),
                        Transport::SpiSocket { path } => ("spi-socket", Some(path.clone())),
                        Transport::Sim { .. } => ("sim", None),
                        Transport::SocketCan { .. } => ("socketcan", None),
                        Transport::SimCan { .. } => ("sim-can", None),
                    };
                    LinkKeys {
                        name: link.name.clone(),
                        kind: kind.to_owned(),
                        path,
                    }
                })
                .collect(),
        }
    }

    /// Reads and validates `path` as motiond does (`motion_config::ServerConfig::load`):
    /// a config the server would refuse is refused with the same located reasons.
    pub fn load(path: &Path) -> Result<Self, String> {
        ServerConfig::load(path)
            .map(|config| Self::of(&config))
            .map_err(|error| {
                format!(
                    "{error}\n{}: not a config motiond would run",
                    path.display()
                )
            })
    }

    /// The doctor's keys read straight from `text` (the unit tests' fake hosts: a few
    /// keys, no machine).
    #[cfg(test)]
    pub fn parse(text: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    /// The serial and spidev links with their paths.
    pub fn device_links(&self) -> impl Iterator<Item = (&LinkKeys, &Path)> {
        self.link
            .iter()
            .filter(|l| l.is_serial() || l.is_spidev())
            .filter_map(|l| l.path.as_deref().map(|p| (l, p)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("motionctl-doctor-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("a temporary directory");
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write the config");
        path
    }

    #[test]
    fn the_shipped_config_reads_as_motiond_reads_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
        let server = ServerConfig::load(&path).expect("config/sim.toml is valid");
        let config = DoctorConfig::load(&path).expect("the doctor reads it");
        assert_eq!(config.server.name, server.server.name);
        assert_eq!(config.server.tick_hz, server.server.tick_hz);
        assert_eq!(config.link.len(), server.links.len());
        assert!(
            config.link.iter().all(|link| link.kind == "sim"),
            "{config:?}"
        );
        assert_eq!(
            config.device_links().count(),
            0,
            "simulated links have no device node"
        );
    }

    #[test]
    fn serial_and_spidev_links_are_the_device_links() {
        let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/examples");
        let mut seen = Vec::new();
        for entry in std::fs::read_dir(&example).expect("config/examples") {
            let path = entry.expect("an entry").path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let Ok(server) = ServerConfig::load(&path) else {
                continue;
            };
            let config = DoctorConfig::of(&server);
            for (link, device) in config.device_links() {
                assert!(link.is_serial() || link.is_spidev(), "{link:?}");
                seen.push((link.kind.clone(), device.to_path_buf()));
            }
        }
        assert!(seen.iter().any(|(kind, _)| kind == "serial"), "{seen:?}");
    }

    #[test]
    fn a_config_motiond_would_refuse_is_refused_with_its_reasons() {
        let shipped = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml"),
        )
        .expect("config/sim.toml");
        let bad = shipped.replacen("[server]", "[server]\ntick_hz = 0", 1);
        let path = write("tick0.toml", &bad);
        let why = DoctorConfig::load(&path).expect_err("tick_hz = 0 is refused");
        assert!(why.contains("tick0.toml:"), "{why}");
        assert!(why.contains("`server.tick_hz`"), "{why}");
        assert!(why.contains("not a config motiond would run"), "{why}");
        let why = DoctorConfig::load(&write("syntax.toml", "[server\n")).expect_err("syntax");
        assert!(why.contains("syntax.toml:1:"), "{why}");
    }

    #[test]
    fn defaults_are_motiond_s() {
        let config = DoctorConfig::parse("[server]\nname = \"x\"\n").expect("parses");
        assert_eq!(config.server.tick_hz, 1000);
        assert_eq!(config.server.rt_priority, None);
        assert!(!config.server.lock_memory);
    }
}
