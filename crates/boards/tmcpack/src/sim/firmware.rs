//! What the pack does with each instruction of the section 9 table.

use core::time::Duration;

use tmcpack::convert::{TICK, byte_time, nominal_baud, units};
use tmcpack::{
    Action, MotorMask, MotorOptions, MotorType, PowerDownRequest, PowerDownStatus, RefInputs,
    Reply, ReplyFrame, Request,
};

use super::TmcpackSim;
use super::motor::{Mode, Motor};
use super::pack::{Delayed, Interp, PackState};
use super::wire::Kind;

impl TmcpackSim {
    /// Executes a request that completed at `t`.
    pub(super) fn execute(&mut self, t: Duration, req: Request) {
        let motors = self.cfg.variant.motors();
        let idx = req.motor().map_or(0, usize::from);
        let enabled = self.motors_enabled();
        match req {
            Request::PeakCurrent { motor, value } => {
                // "Only the values set for motor-numbers 0,2 and 4 are valid."
                if motor % 2 == 0
                    && let Some(p) = self.st.peak.get_mut(usize::from(motor / 2))
                {
                    *p = value;
                }
            }
            Request::CurrentControl {
                i0, i1, i2, i3, t0, ..
            } => self.with_motor(idx, |m| {
                (m.p.i0, m.p.i1, m.p.i2, m.p.i3, m.p.t0) = (i0, i1, i2, i3, t0);
            }),
            Request::VelocitySetting { clkdiv } => self.st.clkdiv = clkdiv,
            Request::StartingVelocity {
                vmin, vstart, div, ..
            } => self.with_motor(idx, |m| {
                (m.p.vmin, m.p.vstart, m.p.div) = (vmin, vstart, div);
            }),
            Request::VelocityAcceleration { amax, vmax, .. } => {
                self.with_motor(idx, |m| (m.p.amax, m.p.vmax) = (amax, vmax));
            }
            Request::MotorParameters {
                poslimit,
                motor_type,
                options,
                ..
            } => {
                // P6 as this firmware reads it: StopNoRef bit 5 or 6.
                let layout = self.cfg.options_layout;
                self.with_motor(idx, |m| {
                    m.p.poslimit = poslimit;
                    m.p.motor_type = motor_type.with(MotorType::AUTO_NULL_CMD, false);
                    m.p.options = layout.wire(options);
                    if motor_type.contains(MotorType::AUTO_NULL_CMD) && enabled {
                        m.start_reference();
                    }
                });
            }
            Request::ReferenceParameters {
                vrefmax,
                debounce_mask,
                flags,
                ..
            } => {
                self.with_motor(idx, |m| {
                    (m.p.vrefmax, m.p.debounce_mask, m.p.ref_flags) =
                        (vrefmax, debounce_mask, flags);
                });
            }
            Request::MicrostepTable { pointer, entries } => {
                let p = usize::from(pointer);
                if let Some(slots) = self.st.table.get_mut(p..p + 4) {
                    slots.copy_from_slice(&entries);
                }
            }
            Request::NullOffset {
                nulloffset,
                testnullrange,
                ..
            } => {
                self.with_motor(idx, |m| {
                    (m.p.nulloffset, m.p.testnullrange) = (nulloffset, testnullrange)
                });
            }
            Request::PiParameters {
                propdiv,
                intdiv,
                intclip,
                intinpclip,
                ..
            } => {
                self.with_motor(idx, |m| {
                    (m.p.propdiv, m.p.intdiv, m.p.intclip, m.p.intinpclip) =
                        (propdiv, intdiv, intclip, intinpclip);
                });
            }
            Request::QueryPosition { motor, reply_to } => {
                if let Some(m) = self.motors.get_mut(idx) {
                    let stopped = core::mem::take(&mut m.stop_flag);
                    let reply = Reply::Position {
                        motor,
                        position: m.reported(),
                        action: m.action(),
                        stopped,
                    };
                    self.send(t, reply_to, reply, Kind::Immediate);
                }
            }
            Request::QueryVelocity { motor, reply_to } => {
                if let Some(m) = self.motors.get(idx) {
                    let reply = Reply::Velocity {
                        motor,
                        velocity: m.vact(),
                        action: m.action(),
                    };
                    self.send(t, reply_to, reply, Kind::Immediate);
                }
            }
            Request::ReferenceSearch { .. } if enabled => {
                self.with_motor(idx, Motor::start_reference)
            }
            Request::StartRamp { target, .. } if enabled => self.start_ramp(idx, target),
            Request::PiTarget { target, .. } if enabled => self.with_motor(idx, |m| {
                m.target = target;
                let t = m.internal_target(target);
                m.mode = match m.mode {
                    Mode::Pi { integral, .. } => Mode::Pi {
                        target: t,
                        integral,
                    },
                    _ => Mode::Pi {
                        target: t,
                        integral: 0,
                    },
                };
            }),
            Request::Rotate { velocity, .. } if enabled => {
                self.with_motor(idx, |m| m.mode = Mode::Rotation { velocity });
            }
            Request::SetTarget { target, .. } => self.with_motor(idx, |m| {
                m.target = target;
                let t = m.internal_target(target);
                match m.mode {
                    Mode::Ramp { .. } => m.mode = Mode::Ramp { target: t },
                    Mode::Pi { integral, .. } => {
                        m.mode = Mode::Pi {
                            target: t,
                            integral,
                        }
                    }
                    _ => {}
                }
            }),
            Request::SetPosition { position, .. } => {
                self.with_motor(idx, |m| m.set_position(i64::from(position)));
            }
            Request::QueryActions {
                reply_to,
                delay_mask,
            } => {
                self.st.delayed = None;
                if delay_mask.bits() == 0 {
                    let reply = self.actions_reply();
                    self.send(t, reply_to, reply, Kind::Immediate);
                } else {
                    self.st.delayed = Some(Delayed {
                        reply_to,
                        mask: delay_mask,
                    });
                    self.check_delayed(t);
                }
            }
            Request::StartRampParallel { mask } if enabled => {
                for i in (0..motors).filter(|&i| mask.has(i)) {
                    let target = self.motors.get(usize::from(i)).map_or(0, |m| m.target);
                    self.start_ramp(usize::from(i), target);
                }
            }
            Request::Stop { mask } => self.stop(mask),
            Request::ReadInput { channel, reply_to } => {
                let reply = self.input_reply(channel);
                self.send(t, reply_to, reply, Kind::Immediate);
            }
            Request::StopLimits {
                channel,
                left_min,
                right_max,
            } => match channel {
                0..=5 => self.with_motor(usize::from(channel), |m| {
                    (m.p.stop_left_min, m.p.stop_right_max) = (left_min, right_max);
                }),
                _ => {
                    if let Some(l) = self.st.extra_limits.get_mut(usize::from(channel - 6)) {
                        *l = (left_min, right_max);
                    }
                }
            },
            Request::Outputs {
                ttlout1,
                ttlio1_input,
                ttlio1,
                ttlout1_ready,
            } => {
                self.st.ttlout1 = ttlout1;
                self.st.ttlio1_is_input = ttlio1_input;
                self.st.ttlio1_out = ttlio1;
                self.st.ttlout1_ready = ttlout1_ready;
            }
            Request::ReadyOutput {
                active_mask,
                reference_mask,
            } => {
                self.st.ready_active = active_mask;
                self.st.ready_ref = reference_mask;
            }
            Request::SetBaud {
                divisor,
                switchover,
            } => {
                self.st.divisor = divisor;
                self.st.switchover_units = switchover;
                self.decoder.set_byte_time(byte_time(nominal_baud(divisor)));
            }
            Request::PacketTimeout { timeout } => {
                self.st.timeout_units = timeout;
                self.decoder.set_timeout(units(timeout));
            }
            Request::SetAddress { address } => self.st.address = address,
            Request::UnitInfo { reply_to } => {
                let reply = Reply::UnitInfo {
                    firmware: self.cfg.firmware_revision,
                    reset: core::mem::take(&mut self.st.reset_flag),
                    temperature: self.cfg.temperature_c,
                    serial: self.cfg.serial_number,
                };
                self.send(t, reply_to, reply, Kind::Immediate);
            }
            Request::CanRs232 {
                reply_to,
                rs232_reply_to,
                forward_count,
            } => {
                self.st.can_rs232 = (rs232_reply_to, forward_count);
                let reply = Reply::CanRs232 {
                    tx_pending: 0,
                    cts: self.cfg.cts,
                };
                self.send(t, reply_to, reply, Kind::Immediate);
            }
            Request::PowerDown { reply_to, flags } => {
                let status = self.power_down(flags);
                self.send(t, reply_to, Reply::PowerDown { status }, Kind::Immediate);
            }
            Request::HardwareReset => self.hardware_reset(t),
            Request::Interpolate { mask } if enabled => self.interpolate_start(mask),
            Request::FlashEnable { reply_to, magic } => {
                let ok = magic == self.cfg.flash_magic;
                if ok {
                    self.nv.flash.fill(0xFF);
                    self.st.flash_enabled = true;
                    self.st.flash_write = 0;
                }
                self.send(t, reply_to, Reply::FlashEnable { ok }, Kind::Immediate);
            }
            Request::FlashProgram { data } => {
                if self.st.flash_enabled {
                    let at = self.st.flash_write;
                    for (k, b) in data.iter().enumerate() {
                        if let Some(slot) = self.nv.flash.get_mut(at + k) {
                            *slot = *b;
                        }
                    }
                    self.st.flash_write = at + data.len();
                }
            }
            Request::FlashChecksum { reply_to } => {
                self.st.flash_enabled = false;
                self.st.flash_read = 0;
                let reply = Reply::FlashChecksum {
                    checksum: self.nv.checksum(),
                };
                self.send(t, reply_to, reply, Kind::Immediate);
            }
            Request::FlashRead { reply_to } => {
                let at = self.st.flash_read;
                let mut data = [0xFFu8; 7];
                for (k, slot) in data.iter_mut().enumerate() {
                    *slot = self.nv.flash.get(at + k).copied().unwrap_or(0xFF);
                }
                self.st.flash_read = at + data.len();
                self.send(t, reply_to, Reply::FlashData { data }, Kind::Immediate);
            }
            Request::EepromWrite {
                reply_to,
                magic,
                address,
                value,
            } => {
                let slot = self.nv.eeprom.get_mut(usize::from(address));
                let ok = magic == self.cfg.eeprom_magic && slot.is_some();
                if let (true, Some(slot)) = (ok, slot) {
                    *slot = value;
                }
                self.send(t, reply_to, Reply::EepromWrite { ok }, Kind::Immediate);
            }
            Request::EepromRead {
                reply_to,
                magic,
                address,
                ..
            } => {
                let ok =
                    magic == self.cfg.eeprom_magic && usize::from(address) < self.nv.eeprom.len();
                self.send(t, reply_to, Reply::EepromRead { ok }, Kind::Immediate);
            }
            // Motion commands while the power-down mode holds the motors.
            Request::ReferenceSearch { .. }
            | Request::StartRamp { .. }
            | Request::PiTarget { .. }
            | Request::Rotate { .. }
            | Request::StartRampParallel { .. }
            | Request::Interpolate { .. } => {}
        }
    }

    fn with_motor(&mut self, i: usize, f: impl FnOnce(&mut Motor)) {
        if let Some(m) = self.motors.get_mut(i) {
            f(m);
        }
    }

    /// Queues `reply` to `reply_to`: the firmware acts on a word in its next 2 ms cycle
    /// (the driver's reading of "internal processing time is approx. 2 ms per command",
    /// manual 6.2, for the serial line too), then `processing_time` more, then the
    /// switch-over delay (6.1).
    pub(super) fn send(&mut self, t: Duration, reply_to: u8, reply: Reply, kind: Kind) {
        if self.can.active {
            // CAN has taken over: every answer goes out there (the `can` module).
            self.send_can(t, reply_to, reply);
            return;
        }
        let Ok(word) = ReplyFrame::new(reply_to, reply).to_word() else {
            return;
        };
        let ready = next_cycle(t)
            .saturating_add(self.cfg.processing_time)
            .saturating_add(self.switchover());
        let replaced = self
            .tx
            .schedule(ready, &word, self.byte_time(), self.switchover(), kind);
        self.stats.replaced_replies += u64::from(replaced);
        self.stats.replies += 1;
    }

    /// $23 (and $29 per motor): "does not influence the motor, if the motor is still active";
    /// "If rotation has been active, the motor is only stopped by this command." A motor
    /// whose $15 type has PiMode ("1=PI-controller") positions with the PI controller.
    fn start_ramp(&mut self, i: usize, target: i32) {
        self.with_motor(i, |m| match m.mode {
            Mode::Inactive => {
                m.target = target;
                let t = m.internal_target(target);
                m.mode = if m.p.motor_type.contains(MotorType::PI_MODE) {
                    Mode::Pi {
                        target: t,
                        integral: 0,
                    }
                } else {
                    Mode::Ramp { target: t }
                };
            }
            Mode::Rotation { .. } => {
                m.mode = Mode::Halt {
                    action: Action::Rotation,
                }
            }
            _ => {}
        });
    }

    /// $2A: target := actual position (to the nearest full step with StopAtFullsteps).
    fn stop(&mut self, mask: MotorMask) {
        for i in 0..usize::from(self.cfg.variant.motors()) {
            if !mask.has(i as u8) {
                continue;
            }
            if let (Some(ip), Some(m)) = (self.st.interp, self.motors.get(i))
                && ip.mask.has(i as u8)
                && m.mode == Mode::Interp
            {
                // Stopping any axis of an interpolation stops the master; the others
                // follow its progress and stop with it.
                let master = ip.master;
                self.with_motor(master, |mm| mm.target = mm.pos as i32);
                continue;
            }
            self.with_motor(i, |m| {
                let mut pos = m.pos;
                if m.p.options.contains(MotorOptions::STOP_AT_FULLSTEPS) {
                    pos = (pos + 8).div_euclid(16) * 16;
                }
                m.target = pos as i32;
                match m.mode {
                    Mode::Ramp { .. } | Mode::Rotation { .. } | Mode::Halt { .. } => {
                        m.mode = Mode::Ramp { target: pos };
                    }
                    Mode::Pi { integral, .. } => {
                        m.mode = Mode::Pi {
                            target: pos,
                            integral,
                        }
                    }
                    Mode::Inactive | Mode::Reference(_) | Mode::Interp => {}
                }
            });
        }
    }

    /// $50: every masked motor must stand still; the axis that needs longest at its vmax is
    /// the master, the others follow in proportion so that all arrive together.
    fn interpolate_start(&mut self, mask: MotorMask) {
        let n = usize::from(self.cfg.variant.motors());
        let used: Vec<usize> = (0..n).filter(|&i| mask.has(i as u8)).collect();
        if used.is_empty()
            || used
                .iter()
                .any(|&i| self.motors.get(i).is_some_and(|m| m.mode != Mode::Inactive))
        {
            return;
        }
        let mut ip = Interp {
            master: 0,
            start: [0; 6],
            dist: [0; 6],
            mask,
        };
        let mut longest = -1.0f64;
        for &i in &used {
            let clkdiv = self.st.clkdiv;
            let Some(m) = self.motors.get(i) else {
                continue;
            };
            let start = m.pos;
            let dist = m.internal_target(m.target) - start;
            let hz = m.limits(m.p.vmax).vmax as f64
                * tmcpack::StepClock::new(clkdiv, m.p.div)
                    .map(tmcpack::StepClock::hz_per_unit)
                    .unwrap_or(1.0);
            let time = dist.unsigned_abs() as f64 / hz.max(1e-9);
            if time > longest {
                longest = time;
                ip.master = i;
            }
            if let (Some(s), Some(d)) = (ip.start.get_mut(i), ip.dist.get_mut(i)) {
                (*s, *d) = (start, dist);
            }
        }
        let m_dist = ip.dist.get(ip.master).copied().unwrap_or(0);
        if m_dist == 0 {
            return;
        }
        for &i in &used {
            self.with_motor(i, |m| m.mode = Mode::Interp);
        }
        self.st.interp = Some(ip);
    }

    /// The $28 answer: actions of all six motors (missing motors of a QUADpack: inactive).
    pub(super) fn actions_reply(&self) -> Reply {
        let mut actions = [Action::Inactive; 6];
        for (slot, m) in actions.iter_mut().zip(self.active_motors()) {
            *slot = m.action();
        }
        Reply::Actions { actions }
    }

    /// The $30 answer. Reference inputs are reported inverted (8.5).
    fn input_reply(&mut self, channel: u8) -> Reply {
        let raw = match channel {
            0..=5 => self
                .motors
                .get(usize::from(channel))
                .map_or(0, |m| m.hw.analog),
            6 => self.cfg.external_analog,
            _ => (self.supply_volts * tmcpack::convert::SUPPLY_COUNTS_PER_VOLT)
                .round()
                .clamp(0.0, 1023.0) as u16,
        };
        let value = (i32::from(raw) + self.noise()).clamp(0, i32::from(tmcpack::MAX_ANALOG)) as u16;
        let mut inputs = RefInputs::EMPTY;
        for (i, m) in self.active_motors().enumerate() {
            inputs = inputs.with(RefInputs::from_bits_retain(1 << i), !m.ref_level());
        }
        let (jp1, jp2) = self.cfg.can_bitrate.jumpers();
        inputs = inputs
            .with(RefInputs::JUMPER1, jp1)
            .with(RefInputs::JUMPER2, jp2);
        let reference = channel < 6 && inputs.contains(RefInputs::from_bits_retain(1 << channel));
        let ttlio1 = if self.st.ttlio1_is_input {
            self.ttlio1_in
        } else {
            self.st.ttlio1_out
        };
        Reply::Input {
            channel,
            value,
            reference,
            inputs,
            ttlio1,
        }
    }

    /// $45, bits handled in the order load, invalidate, activate, reset.
    fn power_down(&mut self, flags: PowerDownRequest) -> PowerDownStatus {
        let mut status =
            PowerDownStatus::EMPTY.with(PowerDownStatus::DOWN_BEFORE, self.power_down_state);
        if flags.contains(PowerDownRequest::LOAD_POSITIONS)
            && let Some(saved) = self.nv.saved_positions
        {
            for (m, p) in self.motors.iter_mut().zip(saved) {
                m.set_position(i64::from(p));
            }
            status = status.with(PowerDownStatus::LOADED, true);
        }
        if flags.contains(PowerDownRequest::INVALIDATE_POSITIONS) {
            self.nv.saved_positions = None;
        }
        if flags.contains(PowerDownRequest::ACTIVATE) {
            self.st.power_down_enabled = true;
        }
        if flags.contains(PowerDownRequest::RESET_STATE)
            && self.supply_volts >= self.cfg.power_down_volts
        {
            self.power_down_state = false;
        }
        status
            .with(
                PowerDownStatus::VALID_IN_EEPROM,
                self.nv.saved_positions.is_some(),
            )
            .with(PowerDownStatus::DOWN_AFTER, self.power_down_state)
    }

    /// $CC or a power cycle at `t`.
    pub(super) fn hardware_reset(&mut self, t: Duration) {
        self.st = PackState::new(self.cfg.address);
        // Parameters back to defaults; the rotors and what is wired to them stay.
        for m in &mut self.motors {
            *m = Motor::new(m.hw, m.phys, m.divisor);
        }
        self.tx.clear();
        self.can.reset();
        self.decoder.clear();
        self.decoder.set_timeout(units(self.st.timeout_units));
        self.decoder.set_byte_time(self.byte_time());
        self.power_down_state = false;
        // "The RS232 usually receives a 0-byte during execution."
        self.tx
            .schedule(t, &[0], self.byte_time(), Duration::ZERO, Kind::Glitch);
        self.deaf_until = Some(t.saturating_add(self.cfg.boot_time));
        self.check_supply();
    }
}

/// The firmware's first 2 ms cycle at or after `t` (cycles fall on multiples of [`TICK`],
/// as the motors' ticks do).
fn next_cycle(t: Duration) -> Duration {
    let tick = TICK.as_nanos();
    let cycles = t.as_nanos().div_ceil(tick);
    u64::try_from(cycles.saturating_mul(tick)).map_or(t, Duration::from_nanos)
}
