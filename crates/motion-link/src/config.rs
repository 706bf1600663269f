//! Opening any real transport from its configuration.

use crate::error::LinkError;
use crate::link::Link;
use crate::serial::{SerialConfig, SerialLink};
use crate::socketcan::{SocketCanConfig, SocketCanLink};
use crate::spi_socket::{SpiSocketConfig, SpiSocketLink};
use crate::spidev::{SpidevConfig, SpidevLink};

/// The configuration of one real transport (a `[[link]]` of type `serial`, `spidev`,
/// `spi-socket` or `socketcan`). Simulated links are built with [`SimLink`](crate::sim::SimLink) around
/// their device models.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LinkConfig {
    /// A tty.
    Serial(SerialConfig),
    /// A Linux spidev device.
    Spidev(SpidevConfig),
    /// An SPI-socket peer.
    SpiSocket(SpiSocketConfig),
    /// A SocketCAN interface.
    SocketCan(SocketCanConfig),
}

impl LinkConfig {
    /// Validates the configuration and opens the transport now.
    pub fn open(&self) -> Result<Box<dyn Link>, LinkError> {
        Ok(match self {
            Self::Serial(c) => Box::new(SerialLink::open(c.clone())?),
            Self::Spidev(c) => Box::new(SpidevLink::open(c.clone())?),
            Self::SpiSocket(c) => Box::new(SpiSocketLink::connect(c.clone())?),
            Self::SocketCan(c) => Box::new(SocketCanLink::open(c.clone())?),
        })
    }

    /// Validates the configuration without opening anything: the link reports
    /// `Disconnected` until its first successful [`Link::reopen`], so a server can start
    /// while a device is still unplugged.
    pub fn create(&self) -> Result<Box<dyn Link>, LinkError> {
        Ok(match self {
            Self::Serial(c) => Box::new(SerialLink::new(c.clone())?),
            Self::Spidev(c) => Box::new(SpidevLink::new(c.clone())?),
            Self::SpiSocket(c) => Box::new(SpiSocketLink::new(c.clone())?),
            Self::SocketCan(c) => Box::new(SocketCanLink::new(c.clone())?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LinkErrorKind, LinkKind};
    use core::time::Duration;

    #[test]
    fn create_validates_and_leaves_the_link_closed() {
        let configs = [
            LinkConfig::Serial(SerialConfig::new("/dev/motiond-absent", 19_200)),
            LinkConfig::Spidev(SpidevConfig::new("/dev/motiond-absent", 1, 500_000)),
            LinkConfig::SpiSocket(SpiSocketConfig::new("/tmp/motiond-absent.sock")),
            LinkConfig::SocketCan(SocketCanConfig::new("motiondcan9", 250_000)),
        ];
        let kinds = [
            LinkKind::Stream,
            LinkKind::Spi,
            LinkKind::Spi,
            LinkKind::Stream,
        ];
        for (config, kind) in configs.iter().zip(kinds) {
            let mut link = config.create().expect("valid");
            assert_eq!(link.kind(), kind);
            let err = link.read(Duration::ZERO, &mut [0; 4]).unwrap_err();
            assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
            let err = link.reopen(Duration::ZERO).unwrap_err();
            assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
            assert_eq!(
                config.open().unwrap_err().kind(),
                LinkErrorKind::Disconnected
            );
        }
        let bad = LinkConfig::Serial(SerialConfig::new("/dev/ttyS0", 0));
        assert_eq!(bad.create().unwrap_err().kind(), LinkErrorKind::Config);
    }
}
