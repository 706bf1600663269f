//! A Linux spidev device (`/dev/spidevB.C`) through the `spidev` crate.

use core::time::Duration;
use std::collections::VecDeque;
use std::sync::Arc;

use ::spidev::{SpiModeFlags, Spidev, SpidevOptions, SpidevTransfer};

use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// The most parts [`Link::write_parts`] batches into one `transfer_multiple` call.
pub const MAX_PARTS: usize = 8;

/// How to open a spidev link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SpidevConfig {
    /// Device path, e.g. `/dev/spidev0.0`.
    pub path: String,
    /// SPI mode 0..=3 (CPOL << 1 | CPHA). The QuadQuad2Drv uses mode 1.
    pub mode: u8,
    /// Clock rate in Hz (the QuadQuad2Drv allows at most 500 kHz).
    pub speed_hz: u32,
    /// Bits per word; byte links support 8 only.
    pub bits_per_word: u8,
    /// Longest transaction accepted, in bytes (MISO scratch is sized from it at start-up).
    pub max_transaction: usize,
    /// Capacity of the queue of MISO bytes waiting for [`Link::read`].
    pub miso_capacity: usize,
}

impl SpidevConfig {
    /// Mode 0, 8 bits, 4096-byte transactions, a 16 KiB MISO queue.
    pub fn new(path: impl Into<String>, mode: u8, speed_hz: u32) -> Self {
        Self {
            path: path.into(),
            mode,
            speed_hz,
            bits_per_word: 8,
            max_transaction: 4096,
            miso_capacity: 16 * 1024,
        }
    }

    /// Checks every field; `link` names the link in the error.
    fn validate(&self, link: &Arc<str>) -> Result<(), LinkError> {
        let bad = |reason: String| {
            Err(LinkError::Config {
                link: link.clone(),
                reason,
            })
        };
        if self.path.is_empty() {
            return bad("empty spidev path; give e.g. /dev/spidev0.0".into());
        }
        if self.mode > 3 {
            return bad(format!("SPI mode {} out of range 0..=3", self.mode));
        }
        if self.speed_hz == 0 || self.speed_hz > 100_000_000 {
            return bad(format!(
                "speed_hz {} out of range 1..=100000000",
                self.speed_hz
            ));
        }
        if self.bits_per_word != 8 {
            return bad(format!(
                "bits_per_word {} unsupported; byte links use 8",
                self.bits_per_word
            ));
        }
        if self.max_transaction == 0 || self.max_transaction > usize::from(u16::MAX) {
            return bad(format!(
                "max_transaction {} out of range 1..=65535",
                self.max_transaction
            ));
        }
        if self.miso_capacity < self.max_transaction {
            return bad(format!(
                "miso_capacity {} smaller than max_transaction {}",
                self.miso_capacity, self.max_transaction
            ));
        }
        Ok(())
    }

    fn options(&self) -> SpidevOptions {
        let mode = match self.mode {
            0 => SpiModeFlags::SPI_MODE_0,
            1 => SpiModeFlags::SPI_MODE_1,
            2 => SpiModeFlags::SPI_MODE_2,
            _ => SpiModeFlags::SPI_MODE_3,
        };
        SpidevOptions::new()
            .bits_per_word(self.bits_per_word)
            .max_speed_hz(self.speed_hz)
            .mode(mode)
            .build()
    }
}

/// A spidev device behind the [`Link`] trait.
///
/// [`write`](Link::write) performs one full-duplex transaction (the ioctl blocks for the
/// transaction's wire time, ~0.6 ms for 40 bytes at 500 kHz: run this link on its own I/O
/// thread) and queues the MISO bytes for [`read`](Link::read). Buffers are allocated once,
/// at creation.
#[derive(Debug)]
pub struct SpidevLink {
    config: SpidevConfig,
    name: Arc<str>,
    dev: Option<Spidev>,
    scratch: Vec<u8>,
    miso: VecDeque<u8>,
    stats: LinkStats,
}

impl SpidevLink {
    /// Validates `config` without opening the device (closed until [`reopen`](Link::reopen)).
    pub fn new(config: SpidevConfig) -> Result<Self, LinkError> {
        let name: Arc<str> = format!(
            "spidev {} mode {} @ {} Hz",
            config.path, config.mode, config.speed_hz
        )
        .into();
        config.validate(&name)?;
        Ok(Self {
            scratch: vec![0; config.max_transaction],
            miso: VecDeque::with_capacity(config.miso_capacity),
            config,
            name,
            dev: None,
            stats: LinkStats::default(),
        })
    }

    /// Validates `config`, opens and configures the device.
    pub fn open(config: SpidevConfig) -> Result<Self, LinkError> {
        let mut link = Self::new(config)?;
        link.open_dev()?;
        Ok(link)
    }

    fn open_dev(&mut self) -> Result<(), LinkError> {
        self.dev = None;
        self.miso.clear();
        let mut dev = Spidev::open(&self.config.path)
            .map_err(|e| LinkError::from_io(&self.name, "open", &e))?;
        dev.configure(&self.config.options())
            .map_err(|e| LinkError::from_io(&self.name, "configure", &e))?;
        self.dev = Some(dev);
        Ok(())
    }

    fn fail(&mut self, err: LinkError) -> LinkError {
        self.stats.errors += 1;
        if matches!(err, LinkError::Disconnected { .. }) {
            self.dev = None;
        }
        err
    }

    /// Checks that a transaction of `len` bytes fits, returning the error otherwise.
    fn check_room(&self, len: usize) -> Result<(), LinkError> {
        if len > self.config.max_transaction {
            return Err(LinkError::Unsupported {
                link: self.name.clone(),
                what: "transaction longer than max_transaction",
            });
        }
        if self.miso.len() + len > self.config.miso_capacity {
            return Err(LinkError::Overflow {
                link: self.name.clone(),
                what: "MISO queue",
                capacity: self.config.miso_capacity,
            });
        }
        Ok(())
    }

    fn transact(&mut self, parts: &[&[u8]]) -> Result<usize, LinkError> {
        let len: usize = parts.iter().map(|p| p.len()).sum();
        if parts.len() > MAX_PARTS {
            return Err(self.fail(LinkError::Unsupported {
                link: self.name.clone(),
                what: "more than MAX_PARTS parts in one transaction",
            }));
        }
        if let Err(e) = self.check_room(len) {
            return Err(self.fail(e));
        }
        let Some(dev) = self.dev.as_ref() else {
            return Err(self.fail(LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the device is closed after an earlier failure; reopen it",
            }));
        };
        if len == 0 {
            return Ok(0);
        }
        let result = {
            let mut transfers: [SpidevTransfer<'_, '_>; MAX_PARTS] = Default::default();
            let mut rest = self.scratch.get_mut(..len).unwrap_or_default();
            let mut used = 0;
            for (slot, part) in transfers.iter_mut().zip(parts.iter()) {
                let (rx, tail) = rest.split_at_mut(part.len().min(rest.len()));
                rest = tail;
                *slot = SpidevTransfer::read_write(part, rx);
                used += 1;
            }
            let batch = transfers.get_mut(..used).unwrap_or_default();
            if let [single] = batch {
                dev.transfer(single)
            } else {
                dev.transfer_multiple(batch)
            }
        };
        if let Err(e) = result {
            let err = LinkError::from_io(&self.name, "transfer", &e);
            return Err(self.fail(err));
        }
        self.miso
            .extend(self.scratch.get(..len).unwrap_or_default().iter().copied());
        self.stats.bytes_out += len as u64;
        self.stats.transactions += 1;
        Ok(len)
    }
}

impl Link for SpidevLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Spi
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn write(&mut self, _now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        self.transact(&[bytes])
    }

    fn write_parts(&mut self, _now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        self.transact(parts)
    }

    fn read(&mut self, _now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        if self.dev.is_none() && self.miso.is_empty() {
            return Err(self.fail(LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the device is closed after an earlier failure; reopen it",
            }));
        }
        let n = buf.len().min(self.miso.len());
        for (slot, byte) in buf.iter_mut().zip(self.miso.drain(..n)) {
            *slot = byte;
        }
        self.stats.bytes_in += n as u64;
        Ok(n)
    }

    fn flush(&mut self, _now: Duration) -> Result<(), LinkError> {
        // Transactions complete inside `write`; nothing is ever queued outward.
        Ok(())
    }

    fn reopen(&mut self, _now: Duration) -> Result<(), LinkError> {
        match self.open_dev() {
            Ok(()) => {
                self.stats.reconnects += 1;
                Ok(())
            }
            Err(e) => Err(self.fail(e)),
        }
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LinkErrorKind;

    #[test]
    fn configuration_is_validated() {
        let ok = SpidevConfig::new("/dev/spidev0.0", 1, 500_000);
        assert!(SpidevLink::new(ok.clone()).is_ok());
        for bad in [
            SpidevConfig {
                mode: 4,
                ..ok.clone()
            },
            SpidevConfig {
                speed_hz: 0,
                ..ok.clone()
            },
            SpidevConfig {
                bits_per_word: 9,
                ..ok.clone()
            },
            SpidevConfig {
                max_transaction: 0,
                ..ok.clone()
            },
            SpidevConfig {
                max_transaction: 70_000,
                ..ok.clone()
            },
            SpidevConfig {
                miso_capacity: 10,
                ..ok.clone()
            },
            SpidevConfig {
                path: String::new(),
                ..ok.clone()
            },
        ] {
            let err = SpidevLink::new(bad.clone()).unwrap_err();
            assert_eq!(err.kind(), LinkErrorKind::Config, "{bad:?}");
        }
    }

    #[test]
    fn a_closed_device_reports_disconnected_and_oversized_transactions_are_refused() {
        let mut cfg = SpidevConfig::new("/dev/motiond-no-such-spidev", 0, 1_000_000);
        cfg.max_transaction = 4;
        cfg.miso_capacity = 4;
        let err = SpidevLink::open(cfg.clone()).unwrap_err();
        assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
        let mut link = SpidevLink::new(cfg).unwrap();
        let t = Duration::ZERO;
        assert_eq!(
            link.write(t, &[1, 2]).unwrap_err().kind(),
            LinkErrorKind::Disconnected
        );
        assert_eq!(
            link.write(t, &[0; 5]).unwrap_err().kind(),
            LinkErrorKind::Unsupported
        );
        let parts: [&[u8]; 9] = [&[1]; 9];
        assert_eq!(
            link.write_parts(t, &parts).unwrap_err().kind(),
            LinkErrorKind::Unsupported
        );
        assert_eq!(
            link.read(t, &mut [0; 4]).unwrap_err().kind(),
            LinkErrorKind::Disconnected
        );
        assert_eq!(link.stats().errors, 4);
    }
}
