//! Start-up: the probe (what the board is and streams now) and the configuration.

use core::fmt::Write as _;
use core::time::Duration;

use qq2drv::limits::{ACCELERATION_MAX, POWER_LIMIT_MAX, VELOCITY_LIMIT_MAX, WINDUP_MAX, to_fixed};
use qq2drv::{
    AccelerationLimitEntry, CHANNELS, ChannelMask, DataMask, DataMaskEntry, Entries,
    InputModeEntry, MotionLayout, PositionPidEntry, PowerLimitEntry, Request, StreamConfig,
    VelocityLimitEntry, VelocityPidEntry,
};

use super::wire::{Packet, Sent, Tag};
use super::{CONFIGURE_REQUESTS, Phase, Qq2drvDriver, STATUS_MASK, STREAM_CONFIG, STREAM_MASK};

/// A channel's acceleration limit (packet 28) for an axis's `max_accel`: shl 12, clipped to
/// the board's range, never 0 (which would disable limiting).
pub(super) fn accel_limit(max_accel: f64) -> u32 {
    to_fixed(max_accel)
        .unwrap_or(ACCELERATION_MAX)
        .clamp(1, ACCELERATION_MAX)
}

/// A channel's velocity limit (packet 26) for an axis's `max_velocity`: shl 12, clipped to
/// the board's range, never 0.
pub(super) fn velocity_limit(max_velocity: f64) -> u32 {
    to_fixed(max_velocity)
        .unwrap_or(VELOCITY_LIMIT_MAX)
        .clamp(1, VELOCITY_LIMIT_MAX)
}
use motion_drivers::{DeviceFault, FIRMWARE_LEN, Seconds, Verdict};

/// Four data masks as hex bytes (`23 23 00 00`).
struct Masks([DataMask; CHANNELS]);

impl core::fmt::Display for Masks {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for (i, mask) in self.0.iter().enumerate() {
            let sep = if i == 0 { "" } else { " " };
            write!(f, "{sep}{:02X}", mask.0)?;
        }
        Ok(())
    }
}

/// What the probe has learnt so far.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct ProbeReplies {
    pub(super) version: Option<(u8, u8, u8)>,
    pub(super) masks: Option<[DataMask; CHANNELS]>,
    pub(super) config: Option<StreamConfig>,
    pub(super) period: Option<u16>,
}

impl Qq2drvDriver {
    /// Writes the probe requests.
    pub(super) fn write_probe(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        let requests = [
            Request::GetVersion,
            Request::GetDataMask,
            Request::GetStreamConfig,
            Request::GetStreamPeriod,
        ];
        // All of it fits, or nothing is in flight.
        let mut len = 0;
        for request in &requests {
            len += request.encode(buf.get_mut(len..)?).ok()?;
        }
        for request in requests {
            self.in_flight.push(Sent {
                id: request.id(),
                at: now,
                number: self.io_stamps.next_number(),
                tag: Tag::Probe,
                heard_after: None,
            });
        }
        self.probe_number = self.io_stamps.next_number();
        self.probe_due = false;
        Some(len)
    }

    /// Writes the configuration (start-up step 3).
    pub(super) fn write_configure(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        // One Data Mask entry per distinct mask (at most three: stream, status, none).
        let wanted = self.stream_masks();
        let mut masks = [DataMaskEntry {
            channels: ChannelMask(0),
            mask: DataMask(0),
        }; CHANNELS];
        let mut masks_len = 0;
        for (index, mask) in wanted.iter().enumerate() {
            let bit = ChannelMask::single(index).0;
            match masks.iter_mut().take(masks_len).find(|e| e.mask == *mask) {
                Some(entry) => entry.channels.0 |= bit,
                None => {
                    if let Some(slot) = masks.get_mut(masks_len) {
                        *slot = DataMaskEntry {
                            channels: ChannelMask(bit),
                            mask: *mask,
                        };
                        masks_len += 1;
                    }
                }
            }
        }
        let masks = masks.get(..masks_len)?;
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
        let mut position_pid = [PositionPidEntry {
            channels: ChannelMask(0),
            p: 0,
            i: 0,
            d: 0,
            windup: 0,
        }; CHANNELS];
        let mut velocity_pid = [VelocityPidEntry {
            channels: ChannelMask(0),
            p: 0,
            i: 0,
            d: 0,
        }; CHANNELS];
        let (mut limits_len, mut inputs_len) = (0, 0);
        for (index, channel) in self.channels.iter().enumerate() {
            if !channel.config.enabled {
                continue;
            }
            let channels = ChannelMask::single(index);
            let limits = channel.config.limits;
            if let (Some(p), Some(v), Some(a), Some(pp), Some(vp)) = (
                power.get_mut(limits_len),
                velocity.get_mut(limits_len),
                accel.get_mut(limits_len),
                position_pid.get_mut(limits_len),
                velocity_pid.get_mut(limits_len),
            ) {
                *p = PowerLimitEntry {
                    channels,
                    limit: channel.config.power_limit.min(POWER_LIMIT_MAX),
                };
                *v = VelocityLimitEntry {
                    channels,
                    limit: velocity_limit(limits.max_velocity),
                };
                *a = AccelerationLimitEntry {
                    channels,
                    limit: accel_limit(limits.max_accel),
                };
                let pid = channel.config.position_pid;
                *pp = PositionPidEntry {
                    channels,
                    p: pid.p,
                    i: pid.i,
                    d: pid.d,
                    windup: pid.windup.min(WINDUP_MAX),
                };
                let pid = channel.config.velocity_pid;
                *vp = VelocityPidEntry {
                    channels,
                    p: pid.p,
                    i: pid.i,
                    d: pid.d,
                };
                limits_len += 1;
            }
            if channel.home().is_some()
                && let (
                    Some(slot),
                    Packet::Input {
                        config, spacing, ..
                    },
                ) = (inputs.get_mut(inputs_len), channel.input(false))
            {
                *slot = InputModeEntry {
                    channels,
                    config,
                    spacing,
                    position: 0,
                };
                inputs_len += 1;
            }
        }
        let mut requests = [None; CONFIGURE_REQUESTS];
        let some = limits_len > 0;
        let list = [
            Some(Request::SetHistoryDimensions(self.config.history)),
            Some(Request::SetDataMask(Entries::new(masks))),
            Some(Request::SetStreamConfig(STREAM_CONFIG)),
            some.then(|| Request::SetPowerLimit(Entries::new(&power[..limits_len]))),
            some.then(|| Request::SetVelocityLimit(Entries::new(&velocity[..limits_len]))),
            some.then(|| Request::SetAccelerationLimit(Entries::new(&accel[..limits_len]))),
            some.then(|| Request::SetPositionPid(Entries::new(&position_pid[..limits_len]))),
            some.then(|| Request::SetVelocityPid(Entries::new(&velocity_pid[..limits_len]))),
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
                number: self.io_stamps.next_number(),
                tag: Tag::Setup,
                heard_after: None,
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
        let mut text = motion_base::FixedText::<FIRMWARE_LEN>::new();
        let _ = write!(text, "fw {major}.{minor} protocol {protocol}");
        self.status.set_firmware(text.as_str());
        let ours = masks == self.stream_masks()
            && config == STREAM_CONFIG
            && period == self.config.stream_period_units();
        if self.configured_once && !ours {
            let ours_masks = self.stream_masks();
            self.status.declare(Verdict::new(
                DeviceFault::Reset,
                now,
                format_args!(
                    "the probe at {} read stream period {period}, stream config {:02X}, data \
                     masks {}; start-up wrote {}, {:02X}, {}: the board lost its \
                     configuration (at power-up the period is 0)",
                    Seconds(now),
                    config.0,
                    Masks(masks),
                    self.config.stream_period_units(),
                    STREAM_CONFIG.0,
                    Masks(ours_masks),
                ),
            ));
            self.status.resets = self.status.resets.saturating_add(1);
            self.raise(DeviceFault::Reset);
            for channel in &mut self.channels {
                channel.board_reset();
            }
            for inputs in &mut self.inputs {
                inputs.forget();
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

    /// The data masks start-up writes: position, velocity and status for a channel with
    /// an axis, status alone for one whose pins a signal reads, nothing otherwise.
    pub fn stream_masks(&self) -> [DataMask; CHANNELS] {
        self.config.channels.map(|c| {
            if c.enabled {
                STREAM_MASK
            } else if c.pins != 0 {
                STATUS_MASK
            } else {
                DataMask(0)
            }
        })
    }

    /// Starts again from the probe; unanswered requests are void (goals go again).
    pub(super) fn restart(&mut self, now: Duration) {
        self.phase = Phase::Probe {
            attempts: 0,
            next_at: now,
        };
        self.in_flight.clear();
        for channel in &mut self.channels {
            channel.void_in_flight();
        }
        for channel in &mut self.channels {
            // The stop and the hold wait for data measured after the restart.
            channel.data_valid = false;
        }
        self.probe = ProbeReplies::default();
        self.probe_due = false;
        self.check_due = false;
        self.configure_due = false;
        self.setup_unanswered = 0;
        self.decoder.clear();
    }
}
