//! Start-up: the probe (what the board is and streams now) and the configuration.

use core::fmt::{self, Write as _};
use core::time::Duration;

use qq2drv::limits::{ACCELERATION_MAX, POWER_LIMIT_MAX, VELOCITY_LIMIT_MAX, to_fixed};
use qq2drv::{
    AccelerationLimitEntry, CHANNELS, ChannelMask, DataMask, DataMaskEntry, Entries,
    InputModeEntry, MotionLayout, PowerLimitEntry, Request, StreamConfig, VelocityLimitEntry,
};

use super::in_flight::{Sent, Tag};
use super::packet::Packet;
use super::{Phase, Qq2drvDriver, STREAM_CONFIG, STREAM_MASK};
use crate::state::{DeviceFault, FIRMWARE_LEN};

/// What the probe has learnt so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct ProbeReplies {
    pub(super) version: Option<(u8, u8, u8)>,
    pub(super) masks: Option<[DataMask; CHANNELS]>,
    pub(super) config: Option<StreamConfig>,
    pub(super) period: Option<u16>,
}

impl Qq2drvDriver {
    /// Writes the probe requests.
    pub(super) fn write_probe(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        let mut len = 0;
        for request in [
            Request::GetVersion,
            Request::GetDataMask,
            Request::GetStreamConfig,
            Request::GetStreamPeriod,
        ] {
            len += request.encode(buf.get_mut(len..)?).ok()?;
            self.in_flight.push(Sent {
                id: request.id(),
                at: now,
                tag: Tag::Probe,
            });
        }
        self.probe_due = false;
        Some(len)
    }

    /// Writes the configuration (start-up step 3).
    pub(super) fn write_configure(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        let enabled = self
            .config
            .channels
            .iter()
            .enumerate()
            .filter(|(_, c)| c.enabled)
            .fold(0u8, |mask, (i, _)| mask | ChannelMask::single(i).0);
        let masks = [
            DataMaskEntry {
                channels: ChannelMask(enabled),
                mask: STREAM_MASK,
            },
            DataMaskEntry {
                channels: ChannelMask(!enabled & 0x0F),
                mask: DataMask(0),
            },
        ];
        let masks = match (enabled, enabled == 0x0F) {
            (0, _) => masks.get(1..),
            (_, true) => masks.get(..1),
            _ => masks.get(..),
        }?;
        let mut power = [PowerLimitEntry {
            channels: ChannelMask(0),
            limit: 0,
        }; CHANNELS];
        let mut velocity = [VelocityLimitEntry {
            channels: ChannelMask(0),
            limit: 0,
        }; CHANNELS];
        let mut accel = [AccelerationLimitEntry {
            channels: ChannelMask(0),
            limit: 0,
        }; CHANNELS];
        let mut inputs = [InputModeEntry {
            channels: ChannelMask(0),
            config: qq2drv::InputConfig(0),
            spacing: 0,
            position: 0,
        }; CHANNELS];
        let (mut limits_len, mut inputs_len) = (0, 0);
        for (index, channel) in self.channels.iter().enumerate() {
            if !channel.config.enabled {
                continue;
            }
            let channels = ChannelMask::single(index);
            let limits = channel.config.limits;
            if let (Some(p), Some(v), Some(a)) = (
                power.get_mut(limits_len),
                velocity.get_mut(limits_len),
                accel.get_mut(limits_len),
            ) {
                *p = PowerLimitEntry {
                    channels,
                    limit: channel.config.power_limit.min(POWER_LIMIT_MAX),
                };
                *v = VelocityLimitEntry {
                    channels,
                    limit: to_fixed(limits.max_velocity)
                        .unwrap_or(VELOCITY_LIMIT_MAX)
                        .clamp(1, VELOCITY_LIMIT_MAX),
                };
                *a = AccelerationLimitEntry {
                    channels,
                    limit: to_fixed(limits.max_accel)
                        .unwrap_or(ACCELERATION_MAX)
                        .clamp(1, ACCELERATION_MAX),
                };
                limits_len += 1;
            }
            if channel.home().is_some()
                && let (Some(slot), Packet::Input { config, .. }) =
                    (inputs.get_mut(inputs_len), channel.input(false))
            {
                *slot = InputModeEntry {
                    channels,
                    config,
                    spacing: 0,
                    position: 0,
                };
                inputs_len += 1;
            }
        }
        let mut requests = [None; 8];
        let list = [
            Some(Request::SetHistoryDimensions(self.config.history)),
            Some(Request::SetDataMask(Entries::new(masks))),
            Some(Request::SetStreamConfig(STREAM_CONFIG)),
            (limits_len > 0).then(|| Request::SetPowerLimit(Entries::new(&power[..limits_len]))),
            (limits_len > 0)
                .then(|| Request::SetVelocityLimit(Entries::new(&velocity[..limits_len]))),
            (limits_len > 0)
                .then(|| Request::SetAccelerationLimit(Entries::new(&accel[..limits_len]))),
            (inputs_len > 0).then(|| Request::SetInputMode(Entries::new(&inputs[..inputs_len]))),
            Some(Request::SetStreamPeriod(self.config.stream_period_units())),
        ];
        for (slot, request) in requests.iter_mut().zip(list) {
            *slot = request;
        }
        let mut len = 0;
        for request in requests.iter().flatten() {
            len += request.encode(buf.get_mut(len..)?).ok()?;
        }
        let mut count = 0;
        for request in requests.iter().flatten() {
            self.in_flight.push(Sent {
                id: request.id(),
                at: now,
                tag: Tag::Setup,
            });
            count += 1;
        }
        self.setup_unanswered = count;
        self.configure_due = false;
        Some(len)
    }

    /// Start-up step 2, once the probe is complete.
    pub(super) fn evaluate_probe(&mut self, now: Duration) {
        let ProbeReplies {
            version: Some((major, minor, protocol)),
            masks: Some(masks),
            config: Some(config),
            period: Some(period),
        } = self.probe
        else {
            return;
        };
        if !matches!(self.phase, Phase::Probe { .. }) {
            return;
        }
        let mut text = Text::default();
        let _ = write!(text, "fw {major}.{minor} protocol {protocol}");
        self.status.set_firmware(text.as_str());
        let ours = masks == self.stream_masks()
            && config == STREAM_CONFIG
            && period == self.config.stream_period_units();
        if self.configured_once && !ours {
            self.status.resets = self.status.resets.saturating_add(1);
            self.raise(DeviceFault::Reset);
            for channel in &mut self.channels {
                channel.board_reset();
            }
        }
        self.layout = MotionLayout {
            data_masks: masks,
            stream_config: config,
        };
        self.phase = Phase::Configure;
        self.configure_due = true;
        self.next_poll_at = now;
    }
}

/// A string in a fixed buffer (no allocation), cut at [`FIRMWARE_LEN`] bytes.
#[derive(Debug, Clone, Copy, Default)]
struct Text {
    bytes: [u8; FIRMWARE_LEN],
    len: usize,
}

impl Text {
    fn as_str(&self) -> &str {
        core::str::from_utf8(self.bytes.get(..self.len).unwrap_or(&[])).unwrap_or("")
    }
}

impl fmt::Write for Text {
    fn write_str(&mut self, text: &str) -> fmt::Result {
        for byte in text.bytes() {
            match self.bytes.get_mut(self.len) {
                Some(slot) => {
                    *slot = byte;
                    self.len += 1;
                }
                None => break,
            }
        }
        Ok(())
    }
}
