//! The configuration a pack gets after it answered `$43` (manual 7.1 "Strategy for
//! Parameter Setting"): switch-over delay, packet timeout, clkdiv, peak currents, and per
//! motor current control, starting velocity/divider, vmax/amax, motor parameters, reference
//! search parameters, null offset and analogue stop limits; then the ready output and the
//! outputs. With `microstep_table` the four `$17` follow the peak currents, and a motor
//! with `position_mode = "pi"` (or `pi` keys) gets its `$19` after its `$31`. The same plan
//! is sent again whenever the pack is seen to have reset; the `$45` power-down steps
//! follow it (the `power_down` module).
//!
//! Before it, the [`Quiesce`] step: `$12` ("change only with stopped motors!"), `$13` and
//! `$16` ("change only with motors standing still") must not reach a motor that is still
//! running (left so by a previous server). So the driver first asks `$28` for every
//! motor's action; configured motors found active get `$14` (this axis's amax) and `$25`
//! velocity 0, and are polled with `$21` until their velocity reads 0 (or an upper bound of
//! their stop time has passed) before the configuration goes out.
//!
//! Also here: going online once the plan is sent, and what a restart (reset, silence,
//! link) voids.

use core::time::Duration;

use motion_base::FixedQueue;
use tmcpack::convert::{DEFAULT_SWITCHOVER_UNITS as FACTORY_SWITCHOVER, baud_divisor, units};
use tmcpack::{
    Action, Command, DEFAULT_PACKET_TIMEOUT, MAX_VELOCITY, MotorMask, MotorOptions, MotorType,
    OptionsLayout, Request,
};

use super::channel::Channel;
use super::config::{REFERENCE_FLAGS, TmcpackDriverConfig};
use super::io::IoState;
use super::wire::{Pick, Purpose};
use super::{Phase, RESET_CHECK_PERIOD, TmcpackDriver};
use motion_drivers::DeviceFault;

/// Most requests a start-up can need: $40, $41, $12, three $10, four $17, six motors ×
/// eight ($19 with the PI controller), $33, $32; and room to spare.
pub(crate) const MAX_STARTUP: usize = 64;

/// The $15 motor type the driver writes: PiMode cleared (positions use the trapezoidal
/// ramp), AutoNullCmd cleared (a search starts only with a `Home` goal).
pub(crate) fn motor_type(configured: MotorType) -> MotorType {
    configured
        .with(MotorType::PI_MODE, false)
        .with(MotorType::AUTO_NULL_CMD, false)
}

/// The $15 options the driver writes: StopNoRef set, so that a stop condition (the switch
/// outside its tolerance with StopNull, an analogue limit) just stops the motor and reports
/// it ($20 P6) instead of starting a reference search the host did not ask for; the engine
/// stops the axis and reports the limit. `layout` puts StopNoRef and NullPositive where the
/// pack's firmware reads them (bit 5 and 6 as the manual's table has them, or swapped as
/// its prose says: key `stop_no_ref_bit`).
pub(crate) fn motor_options(configured: MotorOptions, layout: OptionsLayout) -> MotorOptions {
    layout.wire(configured.with(MotorOptions::STOP_NO_REF, true))
}

/// The configuration requests, in the order they are sent. The `$32` in it is a
/// placeholder: the driver sends its current output levels in its place.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct StartupPlan {
    requests: FixedQueue<Request, MAX_STARTUP>,
}

impl StartupPlan {
    pub fn new(
        config: &TmcpackDriverConfig,
        clkdiv: u8,
        channels: &[Option<Channel>],
        io: &IoState,
    ) -> Self {
        let mut requests = FixedQueue::new();
        let mut push = |request: Request| {
            // $40 and $41 set up the RS-232 / RS-485 line, which a CAN link does not use.
            let serial_only = matches!(
                request,
                Request::SetBaud { .. } | Request::PacketTimeout { .. }
            );
            if serial_only && config.can_bitrate.is_some() {
                return;
            }
            if request.validate().is_ok() {
                requests.push(request);
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
        push(Request::PacketTimeout {
            timeout: config.packet_timeout(),
        });
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
        if let Some(table) = &config.microstep_table {
            // $17: "can be modified for all motors in common", four entries at a time.
            for request in tmcpack::table::table_requests(table) {
                push(request);
            }
        }
        for channel in channels.iter().flatten() {
            let motor = channel.motor;
            let (cfg, scale) = (channel.cfg, channel.scale);
            push(cfg.currents.request(motor));
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
                motor_type: motor_type(cfg.motor_type),
                options: motor_options(cfg.options, config.options_layout),
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
            push(Request::StopLimits {
                channel: motor,
                left_min: cfg.analog_stop.0,
                right_max: cfg.analog_stop.1,
            });
            if let Some(pi) = cfg.written_pi() {
                push(pi.request(motor));
            }
        }
        if let Some(ready) = io.ready_request() {
            push(ready);
        }
        if io.writes_outputs() {
            push(io.outputs_request());
        }
        Self { requests }
    }

    /// Request `index` of the plan.
    pub fn get(&self, index: usize) -> Option<Request> {
        self.requests.get(index)
    }
}

/// Requests the quiesce step can send: `$14` and `$25` for six motors.
const MAX_QUIESCE: usize = 12;

/// Margin on top of the computed stop time before the driver configures anyway.
const QUIESCE_MARGIN: Duration = Duration::from_millis(250);

/// Stopping the configured motors that the `$28` survey found active.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Quiesce {
    requests: FixedQueue<Request, MAX_QUIESCE>,
    /// Motors not yet seen at rest.
    pub moving: MotorMask,
    next_motor: u8,
    /// Configure anyway after this (a motor that never reads 0 must not keep the pack
    /// unconfigured forever).
    pub deadline: Duration,
}

impl Quiesce {
    /// The step for the `$28` answer `actions` at `now`; `None` when no configured motor
    /// is active.
    pub fn new(now: Duration, actions: [Action; 6], channels: &[Option<Channel>]) -> Option<Self> {
        let mut requests = FixedQueue::new();
        let mut moving = MotorMask::EMPTY;
        let mut longest = Duration::ZERO;
        for channel in channels.iter().flatten() {
            let motor = channel.motor;
            if !actions
                .get(usize::from(motor))
                .is_some_and(|a| a.is_active())
            {
                continue;
            }
            let amax = channel
                .scale
                .stop_amax(channel.cfg.max_accel)
                .unwrap_or(channel.scale.amax);
            for request in [
                Request::VelocityAcceleration {
                    motor,
                    amax,
                    vmax: channel.scale.vmax,
                },
                Request::Rotate { motor, velocity: 0 },
            ] {
                requests.push(request);
            }
            moving = moving | MotorMask::single(motor);
            // From any velocity the pack allows (its divider may not be ours yet).
            longest = longest.max(channel.scale.stop_time(MAX_VELOCITY, amax));
        }
        if moving.bits() == 0 {
            return None;
        }
        let words = Duration::from_millis(10) * requests.len() as u32;
        Some(Self {
            requests,
            moving,
            next_motor: 0,
            deadline: now + words + longest + QUIESCE_MARGIN,
        })
    }

    /// The stop command to send next, if any.
    pub fn command(&self) -> Option<Request> {
        self.requests.front()
    }

    /// The command returned by [`command`](Self::command) was sent.
    pub fn sent(&mut self) {
        self.requests.pop();
    }

    /// The next motor to ask `$21`, round-robin over those still moving.
    #[must_use]
    pub fn poll_motor(&mut self) -> Option<u8> {
        let motor = (0..6u8)
            .map(|offset| (self.next_motor + offset) % 6)
            .find(|&m| self.moving.has(m))?;
        self.next_motor = (motor + 1) % 6;
        Some(motor)
    }

    /// A `$21` answer: `motor` runs at `velocity`.
    pub fn on_velocity(&mut self, motor: u8, velocity: i16) {
        if velocity == 0 {
            self.moving = self.moving.with(MotorMask::single(motor), false);
        }
    }

    /// Whether the configuration may go out at `now`.
    pub fn done(&self, now: Duration) -> bool {
        self.command().is_none() && (self.moving.bits() == 0 || now >= self.deadline)
    }
}

impl TmcpackDriver {
    /// The requests the start-up writes after the survey, in order (with the outputs as
    /// they are now).
    pub fn startup_requests(&self) -> impl Iterator<Item = Request> + '_ {
        (0..MAX_STARTUP)
            .map_while(|index| self.plan.get(index))
            .map(|request| self.resolve(request))
    }

    /// A plan entry as it goes on the wire: the `$32` placeholder carries the current
    /// output levels.
    pub(super) fn resolve(&self, request: Request) -> Request {
        match request {
            Request::Outputs { .. } => self.io.outputs_request(),
            // The divisor of the rate the driver talks at (module `rate`: the link's own
            // without a `baud`).
            Request::SetBaud { switchover, .. } => Request::SetBaud {
                divisor: baud_divisor(self.rate.now()).unwrap_or(65),
                switchover,
            },
            other => other,
        }
    }

    pub(super) fn pick_quiesce(&mut self, now: Duration) -> Option<Pick> {
        let quiesce = self.quiesce.as_mut()?;
        if let Some(request) = quiesce.command() {
            return Some(Pick {
                request,
                expect: None,
                channel: None,
            });
        }
        if quiesce.done(now) {
            self.quiesce = None;
            self.phase = Phase::Configure(0);
            return self.pick(now);
        }
        let motor = quiesce.poll_motor()?;
        Some(self.query(
            Request::QueryVelocity {
                motor,
                reply_to: self.reply_address,
            },
            Command::QueryVelocity,
            Some(motor),
            Purpose::Quiesce,
        ))
    }

    pub(super) fn go_online(&mut self, now: Duration) {
        self.phase = Phase::Online;
        self.rate.online();
        self.status.online = true;
        self.status.fault = None;
        self.ever_online = true;
        self.reset_check_at = now + RESET_CHECK_PERIOD;
        // The start-up wrote the outputs as they are now.
        self.io.outputs_pending = false;
    }

    /// The pack lost what it was told (reboot, silence, link): channels keep their last
    /// state but are faulted until fresh data, and their goals are void.
    pub(super) fn restart(&mut self, fault: DeviceFault) {
        self.status.online = false;
        self.status.fault = Some(fault);
        self.quiesce = None;
        self.line = None;
        self.power.forget();
        self.describe();
        for channel in self.channels.iter_mut().flatten() {
            channel.restart(fault);
        }
    }

    /// Whatever the pack may have now, before this start-up programs it: the factory
    /// settings (after a reboot, manual 6.1 "pre-set to 6ms") or the configured ones (a
    /// previous run programmed them) — the longer of each, so that no answer is cut short
    /// and no torn word outlives the quiet time. No switch-over on CAN.
    pub(super) fn assume_unknown_line(&mut self) {
        let configured = self.switchover_units.map_or(Duration::ZERO, units);
        self.switchover = match self.can {
            Some(_) => Duration::ZERO,
            None => units(FACTORY_SWITCHOVER).max(configured),
        };
        self.pack_timeout = DEFAULT_PACKET_TIMEOUT.max(self.configured_timeout);
    }
}
