//! The configuration a pack gets after it answered `$43` (manual 7.1 "Strategy for
//! Parameter Setting"): switch-over delay, clkdiv, peak currents, and per motor current
//! control, starting velocity/divider, vmax/amax, motor parameters, reference search
//! parameters and null offset.

use tmcpack::convert::baud_divisor;
use tmcpack::{MotorType, ReferenceFlags, Request};

use super::channel::Channel;
use super::config::TmcpackDriverConfig;

/// $16 P5 the driver always sets: "1=Stop after reference search", so that a `Home` goal
/// ends at the new zero point with the motor inactive (0 would resume the previous action,
/// e.g. drive back to where the search started).
pub(crate) const REFERENCE_FLAGS: ReferenceFlags = ReferenceFlags::STOP_AFTER_SEARCH;

/// Most requests a start-up can need: $40, $12, three $10, six motors × six.
pub(crate) const MAX_STARTUP: usize = 48;

/// The configuration requests, in the order they are sent.
#[derive(Debug, Clone)]
pub(crate) struct StartupPlan {
    requests: [Option<Request>; MAX_STARTUP],
}

impl StartupPlan {
    pub fn new(config: &TmcpackDriverConfig, clkdiv: u8, channels: &[Option<Channel>]) -> Self {
        let mut requests = [None; MAX_STARTUP];
        let mut len = 0;
        let mut push = |request: Request| {
            if let Some(slot) = requests.get_mut(len)
                && request.validate().is_ok()
            {
                *slot = Some(request);
                len += 1;
            }
        };
        if let (Some(switchover), Ok(divisor)) =
            (config.switchover_units, baud_divisor(config.baud))
        {
            // The divisor of the link's own rate: the baud rate stays what it is.
            push(Request::SetBaud {
                divisor,
                switchover,
            });
        }
        // "$12 … change only with stopped motors": sent before any motor is started.
        push(Request::VelocitySetting { clkdiv });
        for pair in 0..3u8 {
            let value = [2 * pair, 2 * pair + 1].into_iter().find_map(|motor| {
                channels
                    .get(usize::from(motor))
                    .and_then(Option::as_ref)
                    .and_then(|c| c.cfg.peak_current)
            });
            if let Some(value) = value {
                // "Only the values set for motor-numbers 0,2 and 4 are valid."
                push(Request::PeakCurrent {
                    motor: 2 * pair,
                    value,
                });
            }
        }
        for channel in channels.iter().flatten() {
            let motor = channel.motor;
            let (cfg, scale) = (channel.cfg, channel.scale);
            let c = cfg.currents;
            push(Request::CurrentControl {
                motor,
                i0: c.i0,
                i1: c.i1,
                i2: c.i2,
                i3: c.i3,
                t0: c.t0.max(1),
            });
            push(Request::StartingVelocity {
                motor,
                // "The fastest possible vmin will be calculated automatically when its
                // value is set to 0" (≤ 250 Hz at divider 3).
                vmin: 0,
                vstart: scale.vstart,
                div: scale.clock.div(),
            });
            push(Request::VelocityAcceleration {
                motor,
                amax: scale.amax,
                vmax: scale.vmax,
            });
            push(Request::MotorParameters {
                motor,
                poslimit: cfg.poslimit,
                motor_type: cfg
                    .motor_type
                    .with(MotorType::PI_MODE, false)
                    .with(MotorType::AUTO_NULL_CMD, false),
                options: cfg.options,
            });
            push(Request::ReferenceParameters {
                motor,
                vrefmax: scale.vrefmax,
                debounce_mask: cfg.debounce_mask,
                flags: REFERENCE_FLAGS,
            });
            push(Request::NullOffset {
                motor,
                nulloffset: cfg.nulloffset,
                testnullrange: cfg.testnullrange,
            });
        }
        Self { requests }
    }

    /// Request `index` of the plan.
    pub fn get(&self, index: usize) -> Option<Request> {
        self.requests.get(index).copied().flatten()
    }
}
