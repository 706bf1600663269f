//! The few keys of a motiond config the doctor needs: the tick rate and real-time settings
//! of `[server]` and the links' types and paths. motionctl does not depend on motiond, so
//! this is a small read of its own: other keys are ignored, and motiond itself validates the
//! file (`motiond --check-config FILE`).

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// Where the deployed server's config lives (deploy/README.md).
pub const DEPLOYED_CONFIG: &str = "/etc/motiond/motiond.toml";

/// What the doctor reads of a config.
#[derive(Debug, Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(default)]
pub struct DoctorConfig {
    /// `[server]`.
    pub server: ServerKeys,
    /// `[[link]]`.
    pub link: Vec<LinkKeys>,
}

/// `[server]` keys of interest.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(default)]
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
#[derive(Debug, Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(default)]
pub struct LinkKeys {
    /// Link name.
    pub name: String,
    /// `serial`, `spidev`, `spi-socket`, `sim`.
    #[serde(rename = "type")]
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
    /// Parses config text.
    pub fn parse(text: &str) -> Result<Self, String> {
        let config: Self = toml::from_str(text).map_err(|e| e.to_string())?;
        if config.server.tick_hz == 0 {
            return Err("`server.tick_hz` must be at least 1".to_owned());
        }
        if config
            .server
            .rt_priority
            .is_some_and(|p| !(1..=99).contains(&p))
        {
            return Err("`server.rt_priority` must be within 1..=99".to_owned());
        }
        Ok(config)
    }

    /// Reads and parses `path`.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
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

    #[test]
    fn reads_the_keys_it_needs_and_ignores_the_rest() {
        let config = DoctorConfig::parse(
            r#"
            [server]
            name = "cell"
            tick_hz = 500
            rt_priority = 80
            cpu = 3
            lock_memory = true
            command_timeout_ms = 250

            [[link]]
            name = "rs485"
            type = "serial"
            path = "/dev/serial/by-id/usb-FTDI-if00-port0"
            baud = 19200

            [[link]]
            name = "spi"
            type = "spidev"
            path = "/dev/spidev0.0"

            [[link]]
            name = "sim"
            type = "sim"

            [[device]]
            name = "pack"
            link = "rs485"
            model = "tmcpack"
            "#,
        )
        .expect("parses");
        assert_eq!(config.server.tick_hz, 500);
        assert_eq!(config.server.rt_priority, Some(80));
        assert_eq!(config.server.cpu, Some(3));
        assert!(config.server.lock_memory);
        let links: Vec<&str> = config
            .device_links()
            .map(|(l, _)| l.name.as_str())
            .collect();
        assert_eq!(links, ["rs485", "spi"]);
    }

    #[test]
    fn defaults_are_motiond_s() {
        let config = DoctorConfig::parse("[server]\nname = \"x\"\n").expect("parses");
        assert_eq!(config.server.tick_hz, 1000);
        assert_eq!(config.server.rt_priority, None);
        assert!(!config.server.lock_memory);
    }

    #[test]
    fn bad_values_are_errors() {
        assert!(DoctorConfig::parse("[server]\ntick_hz = 0\n").is_err());
        assert!(DoctorConfig::parse("[server]\nrt_priority = 0\n").is_err());
        assert!(DoctorConfig::parse("[server]\nrt_priority = 300\n").is_err());
        assert!(DoctorConfig::parse("[server]\ncpu = \"one\"\n").is_err());
        assert!(DoctorConfig::parse("[server\n").is_err());
    }
}
