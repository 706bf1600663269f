//! One motor channel: its firmware state (mode, position counter, velocity) and the rotor it
//! drives (physical position, reference switch, end stops).

use tmcpack::convert::{AmaxDivisor, StepClock};
use tmcpack::{Action, MotorOptions, MotorType};

use super::config::MotorConfig;
use super::params::MotorParams;
use super::ramp::{self, Limits, Q};
use super::reference::{self, Outcome, RefSearch, Resume, SearchDrive};

/// What a motor does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    Inactive,
    /// Trapezoidal ramp to an internal (unwrapped) target.
    Ramp {
        target: i64,
    },
    /// PI controller ($24).
    Pi {
        target: i64,
        integral: i64,
    },
    /// Rotation ($25).
    Rotation {
        velocity: i16,
    },
    /// Decelerating with amax to standstill, then inactive (a soft stop, or $23 on a
    /// rotating motor: "the motor is only stopped by this command"). Reports `action`.
    Halt {
        action: Action,
    },
    /// Reference search.
    Reference(RefSearch),
    /// Part of a $50 interpolation, moved by the pack.
    Interp,
}

/// What the pack gives a motor for one tick.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TickCtx {
    pub clkdiv: u8,
    /// Peak coil current of this motor, A ($10 pair value, QUADpack DIP).
    pub peak_amps: f64,
}

/// A motor in its reference search, with the tick's context: what the search module drives.
struct Searching<'a> {
    motor: &'a mut Motor,
    ctx: &'a TickCtx,
}

impl SearchDrive for Searching<'_> {
    fn params(&self) -> &MotorParams {
        &self.motor.p
    }
    fn clkdiv(&self) -> u8 {
        self.ctx.clkdiv
    }
    fn position(&self) -> i64 {
        self.motor.pos
    }
    fn switch_active(&self) -> bool {
        self.motor.switch_active
    }
    fn at_rest(&self) -> bool {
        self.motor.vq == 0
    }
    fn current_div(&self) -> u8 {
        self.motor.vdiv
    }
    fn drive(&mut self, velocity: i64, div: u8) -> i64 {
        self.motor.drive(velocity, div, self.ctx)
    }
    fn halt_now(&mut self) {
        self.motor.halt_now();
    }
    fn ramp_step(&mut self, target: i64, vmax: u16) -> bool {
        self.motor.ramp_step(target, vmax, self.ctx)
    }
    fn rezero(&mut self, zero: i64) {
        self.motor.rezero(zero);
    }
}

/// One motor channel.
#[derive(Debug, Clone)]
pub(crate) struct Motor {
    pub p: MotorParams,
    pub mode: Mode,
    /// Position counter (unwrapped; cyclic axes report it wrapped).
    pub pos: i64,
    /// Phase of the step generator towards the next microstep in direction `phase_dir`,
    /// in 1/denominator units (0..denominator): like the hardware's accumulator it counts
    /// magnitude, so both directions step alike.
    frac: i128,
    phase_dir: i64,
    denom: i128,
    /// Velocity · 64 in units of `vdiv`.
    pub vq: i64,
    pub vdiv: u8,
    /// The rotor, microsteps.
    pub phys: i64,
    /// Target programmed by $26 (and $23/$24).
    pub target: i32,
    pub stop_flag: bool,
    pub standstill_ticks: u32,
    pub accelerating: bool,
    hist: u16,
    pub switch_active: bool,
    pub testnull_timer: Option<u32>,
    pub hw: MotorConfig,
    /// Coil current in A after the last tick.
    pub current_amps: f64,
    /// How the firmware reads `$14`: amax / divisor per 2 ms tick.
    pub divisor: AmaxDivisor,
}

impl Motor {
    pub fn new(hw: MotorConfig, phys: i64, divisor: AmaxDivisor) -> Self {
        let p = MotorParams::default();
        let mut m = Self {
            p,
            mode: Mode::Inactive,
            pos: 0,
            frac: 0,
            phase_dir: 1,
            denom: StepClock::DEFAULT.denominator().into(),
            vq: 0,
            vdiv: p.div,
            phys,
            target: 0,
            stop_flag: false,
            standstill_ticks: u32::MAX,
            accelerating: false,
            hist: 0,
            switch_active: false,
            testnull_timer: None,
            hw,
            current_amps: 0.0,
            divisor,
        };
        let raw = m.raw_switch();
        m.hist = if raw { u16::MAX } else { 0 };
        m.switch_active = raw;
        m
    }

    /// The position as the 32-bit register reports it; cyclic axes wrap into
    /// 0..poslimit (NullLeft) or −poslimit..0.
    pub fn reported(&self) -> i32 {
        if self.p.cyclic() {
            let l = i64::from(self.p.poslimit);
            let w = if self.p.motor_type.contains(MotorType::NULL_LEFT) {
                self.pos.rem_euclid(l)
            } else {
                -(-self.pos).rem_euclid(l)
            };
            w as i32
        } else {
            self.pos as i32
        }
    }

    /// The internal target for a 32-bit target from the host: on cyclic axes the nearest
    /// copy in the direction that is shorter with way optimisation, the direct one otherwise.
    pub fn internal_target(&self, target: i32) -> i64 {
        if !self.p.cyclic() {
            return i64::from(target);
        }
        let l = i64::from(self.p.poslimit);
        let mut delta = i64::from(target) - i64::from(self.reported());
        if self.p.options.contains(MotorOptions::WAY_OPTIMIZATION) {
            delta = delta.rem_euclid(l);
            if delta > l / 2 {
                delta -= l;
            }
        }
        self.pos + delta
    }

    pub fn action(&self) -> Action {
        match self.mode {
            Mode::Inactive => Action::Inactive,
            Mode::Ramp { .. } | Mode::Interp => Action::Ramp,
            Mode::Pi { .. } => Action::PiController,
            Mode::Rotation { .. } => Action::Rotation,
            Mode::Halt { action } => action,
            Mode::Reference(r) => r.action(),
        }
    }

    /// The velocity register (vact) in the units of the divider in use.
    pub fn vact(&self) -> i16 {
        (self.vq / Q) as i16
    }

    pub fn microstep_hz(&self, clkdiv: u8) -> f64 {
        StepClock::new(clkdiv, self.vdiv)
            .map(|c| c.hz_per_unit() * f64::from(self.vact()))
            .unwrap_or(0.0)
    }

    pub fn limits(&self, vmax: u16) -> Limits {
        let vmax = i64::from(vmax.max(1));
        Limits {
            vs: i64::from(self.p.vstart).min(vmax) * Q,
            vmax: vmax * Q,
            // amax / divisor per tick, in 1/64 units (Q): amax at /64, 4 · amax at /16.
            d: i64::from(self.p.amax.max(1)) * (Q / i64::from(self.divisor.get())),
        }
    }

    fn raw_switch(&self) -> bool {
        let level = self.hw.ref_switch.is_none_or(|s| s.level(self.phys));
        level == self.p.options.contains(MotorOptions::NULL_POSITIVE)
    }

    /// Electrical level at Ref_In (`true` = high; nothing connected floats high).
    pub fn ref_level(&self) -> bool {
        self.hw.ref_switch.is_none_or(|s| s.level(self.phys))
    }

    fn sample_switch(&mut self) {
        let raw = self.raw_switch();
        self.hist = (self.hist << 1) | u16::from(raw);
        if self.p.motor_type.contains(MotorType::FILTER_SWITCH) {
            let mask = self.p.debounce_mask.max(1);
            if self.hist & mask == mask {
                self.switch_active = true;
            } else if self.hist & mask == 0 {
                self.switch_active = false;
            }
        } else {
            self.switch_active = raw;
        }
    }

    /// Makes `div` the divider of the step generator, keeping the fraction's share.
    pub fn set_div(&mut self, clkdiv: u8, div: u8) {
        let denom: i128 = StepClock::new(clkdiv, div)
            .map(StepClock::denominator)
            .unwrap_or(StepClock::DEFAULT.denominator())
            .into();
        if denom != self.denom {
            self.frac = self.frac * denom / self.denom.max(1);
            self.denom = denom;
        }
        self.vdiv = div;
    }

    /// Moves by `fine` units of the current divider.
    fn advance(&mut self, fine: i128, ctx: &TickCtx) {
        if fine == 0 {
            return;
        }
        self.phase_dir = if fine > 0 { 1 } else { -1 };
        let acc = self.frac + fine.abs();
        let steps = i64::try_from(acc / self.denom).unwrap_or(0) * self.phase_dir;
        self.frac = acc % self.denom;
        self.pos = self.pos.saturating_add(steps);
        self.move_rotor(steps, ctx);
    }

    /// The position in fine units.
    fn fine_pos(&self) -> i128 {
        i128::from(self.pos) * self.denom + i128::from(self.phase_dir) * self.frac
    }

    fn move_rotor(&mut self, steps: i64, ctx: &TickCtx) {
        let level = if self.accelerating {
            self.p.i3
        } else {
            self.p.i2
        };
        if ctx.peak_amps * f64::from(level.percent()) <= 0.0 {
            return; // no current: the rotor does not follow
        }
        let mut phys = self.phys.saturating_add(steps);
        if let Some((lo, hi)) = self.hw.travel {
            phys = phys.clamp(lo.min(hi), hi.max(lo));
        }
        self.phys = phys;
    }

    /// Jumps the counter to `pos` while driving (the last microsteps of a ramp).
    fn land(&mut self, pos: i64, ctx: &TickCtx) {
        let delta = pos - self.pos;
        self.pos = pos;
        self.frac = 0;
        self.move_rotor(delta, ctx);
    }

    /// `$27`: the counter jumps, the rotor stays.
    pub fn set_position(&mut self, pos: i64) {
        self.pos = pos;
        self.frac = 0;
    }

    /// Shifts the coordinate system so that counter value `zero` becomes 0.
    pub fn rezero(&mut self, zero: i64) {
        self.pos -= zero;
    }

    /// One ramp tick to `target` with velocity limit `vmax`; `true` on arrival.
    pub fn ramp_step(&mut self, target: i64, vmax: u16, ctx: &TickCtx) -> bool {
        if self.vq == 0 || self.vdiv == self.p.div {
            self.set_div(ctx.clkdiv, self.p.div);
        }
        let rem = i128::from(target) * self.denom - self.fine_pos();
        if rem == 0 && self.vq == 0 {
            return true;
        }
        let lim = self.limits(vmax);
        let nv = ramp::ramp_velocity(self.vq, rem, lim);
        self.accelerating = nv.abs() > self.vq.abs();
        let s = ramp::step(nv);
        if nv.abs() <= lim.vs && s.signum() == rem.signum() && s.abs() >= rem.abs() {
            self.vq = 0;
            self.land(target, ctx);
            return true;
        }
        self.vq = nv;
        self.advance(s, ctx);
        false
    }

    /// One tick heading for velocity `want` (units of `div`); returns the microsteps moved.
    pub fn drive(&mut self, want: i64, div: u8, ctx: &TickCtx) -> i64 {
        if self.vdiv != div && self.vq != 0 {
            // Stop in the old divider before changing it.
            return self.drive(0, self.vdiv, ctx);
        }
        self.set_div(ctx.clkdiv, div);
        let lim = self.limits(self.p.vmax.max(self.p.vstart));
        let nv = ramp::slew(self.vq, want * Q, lim);
        self.accelerating = nv.abs() > self.vq.abs();
        self.vq = nv;
        let before = self.pos;
        self.advance(ramp::step(nv), ctx);
        self.pos - before
    }

    /// Stops at once (abrupt stop, or a reference phase that found its edge).
    pub fn halt_now(&mut self) {
        self.vq = 0;
        self.accelerating = false;
    }

    /// Starts a reference search (from $22, AutoNullCmd, or a stop condition).
    pub fn start_reference(&mut self) {
        let resume = match self.mode {
            Mode::Reference(r) => r.resume,
            Mode::Ramp { target } => Resume::Ramp(target),
            Mode::Rotation { velocity } => Resume::Rotation(velocity),
            Mode::Pi { target, .. } => Resume::Pi(target),
            Mode::Inactive | Mode::Halt { .. } | Mode::Interp => Resume::Ramp(self.pos),
        };
        self.testnull_timer = None;
        self.mode = Mode::Reference(RefSearch::new(resume));
    }

    fn pi_step(&mut self, target: i64, integral: i64, ctx: &TickCtx) -> i64 {
        let diff = (target - self.pos).clamp(i64::from(i32::MIN), i64::from(i32::MAX));
        let clip = i64::from(self.p.intinpclip);
        let lim = i64::from(self.p.intclip.max(1));
        let integral = (integral + diff.clamp(-clip, clip)).clamp(-lim, lim);
        let want = 64 * diff / i64::from(self.p.propdiv.max(1))
            + 64 * integral / i64::from(self.p.intdiv.max(1));
        let vmax = i64::from(self.p.vmax) * Q;
        let want = want.clamp(-vmax, vmax);
        self.set_div(ctx.clkdiv, self.p.div);
        let lim = self.limits(self.p.vmax);
        let nv = ramp::slew(self.vq, want, lim);
        self.accelerating = nv.abs() > self.vq.abs();
        self.vq = nv;
        self.advance(ramp::step(nv), ctx);
        integral
    }

    /// One 2 ms tick of everything but a $50 interpolation.
    pub fn tick(&mut self, ctx: &TickCtx) {
        self.sample_switch();
        let was_active = self.mode != Mode::Inactive;
        match self.mode {
            Mode::Inactive => self.halt_now(),
            Mode::Ramp { target } => {
                if self.ramp_step(target, self.p.vmax, ctx) {
                    self.mode = Mode::Inactive;
                }
            }
            Mode::Pi { target, integral } => {
                let integral = self.pi_step(target, integral, ctx);
                self.mode = Mode::Pi { target, integral };
            }
            Mode::Rotation { velocity } => {
                let v = i64::from(velocity).clamp(-i64::from(self.p.vmax), i64::from(self.p.vmax));
                self.drive(v, self.p.div, ctx);
            }
            Mode::Halt { .. } => {
                self.drive(0, self.vdiv, ctx);
                if self.vq == 0 {
                    self.mode = Mode::Inactive;
                }
            }
            Mode::Reference(r) => {
                let outcome = reference::tick(&mut Searching { motor: self, ctx }, r);
                self.mode = match outcome {
                    Outcome::Searching(r) => Mode::Reference(r),
                    Outcome::Inactive => Mode::Inactive,
                    Outcome::Resume(Resume::Ramp(target)) => Mode::Ramp { target },
                    Outcome::Resume(Resume::Rotation(velocity)) => Mode::Rotation { velocity },
                    Outcome::Resume(Resume::Pi(target)) => Mode::Pi {
                        target,
                        integral: 0,
                    },
                };
            }
            Mode::Interp => {}
        }
        if was_active && self.mode == Mode::Inactive {
            self.on_stopped();
        }
        self.after_motion(ctx);
    }

    /// Called after the motor came to rest: arms the TestNull check.
    pub fn on_stopped(&mut self) {
        if self.p.motor_type.contains(MotorType::TEST_NULL) && self.reported() == 0 {
            let delay = if self.p.options.contains(MotorOptions::DELAY_TEST_NULL) {
                u32::from(self.p.t0)
            } else {
                0
            };
            self.testnull_timer = Some(self.p.filter_ticks() + delay);
        }
    }

    /// Stop conditions, TestNull, currents: the checks after each tick's motion.
    pub fn after_motion(&mut self, ctx: &TickCtx) {
        self.check_stop_conditions();
        self.check_testnull();
        if self.vq == 0 {
            self.standstill_ticks = self.standstill_ticks.saturating_add(1);
            self.accelerating = false;
        } else {
            self.standstill_ticks = 0;
        }
        self.current_amps = self.coil_current(ctx);
    }

    /// The coil current the $15 levels give now: I3 accelerating, I2 at constant speed, I1
    /// for T0 after a stop, I0 at standstill (manual 8.2 $15).
    fn coil_current(&self, ctx: &TickCtx) -> f64 {
        let level = if self.vq != 0 {
            if self.accelerating {
                self.p.i3
            } else {
                self.p.i2
            }
        } else if self.standstill_ticks < u32::from(self.p.t0) {
            self.p.i1
        } else {
            self.p.i0
        };
        ctx.peak_amps * f64::from(level.percent()) / 100.0
    }

    /// `true` when the coil current shown is the one the current levels and peak give
    /// (a `$15` or `$11` changed nothing yet while the pack was quiet otherwise).
    pub fn current_settled(&self, ctx: &TickCtx) -> bool {
        self.current_amps == self.coil_current(ctx)
    }

    fn check_stop_conditions(&mut self) {
        if matches!(self.mode, Mode::Inactive | Mode::Reference(_)) {
            return;
        }
        let dir = self.vq.signum();
        if dir == 0 {
            return;
        }
        let null_hit = self.p.motor_type.contains(MotorType::STOP_NULL)
            && self.switch_active
            && i64::from(self.reported()).abs() > i64::from(self.p.testnullrange)
            && dir == self.p.toward_zero();
        let a = self.hw.analog;
        let analog_hit = (self.p.stop_left_min > 0 && dir < 0 && a < self.p.stop_left_min)
            || (self.p.stop_right_max < 1023 && dir > 0 && a > self.p.stop_right_max);
        if null_hit || analog_hit {
            self.stop_condition();
        }
    }

    /// A stop condition: stop bit, soft or abrupt stop, and a reference search unless
    /// StopNoRef (manual 8.3 $15, 8.5 $31).
    pub fn stop_condition(&mut self) {
        self.stop_flag = true;
        let soft = self.p.options.contains(MotorOptions::STOP_SOFT);
        let action = self.action();
        if !soft {
            self.halt_now();
        }
        if self.p.options.contains(MotorOptions::STOP_NO_REF) {
            self.mode = if soft {
                Mode::Halt { action }
            } else {
                Mode::Inactive
            };
        } else {
            self.start_reference();
        }
    }

    fn check_testnull(&mut self) {
        let Some(left) = self.testnull_timer else {
            return;
        };
        if self.mode != Mode::Inactive {
            self.testnull_timer = None;
            return;
        }
        if left > 0 {
            self.testnull_timer = Some(left - 1);
            return;
        }
        self.testnull_timer = None;
        if !self.switch_active {
            self.stop_flag = true;
            if !self.p.options.contains(MotorOptions::STOP_NO_REF) {
                self.start_reference();
            }
        }
    }

    /// `true` when nothing can change without a command: no motion, no timer, switch filter
    /// settled.
    pub fn idle(&self) -> bool {
        self.mode == Mode::Inactive
            && self.vq == 0
            && self.testnull_timer.is_none()
            && self.standstill_ticks >= u32::from(self.p.t0)
            && {
                let raw = self.raw_switch();
                self.switch_active == raw && self.hist == if raw { u16::MAX } else { 0 }
            }
    }

    /// Sets the position of a $50 slave (the pack computes it from the master's progress).
    pub fn follow(&mut self, pos: i64, vq: i64, ctx: &TickCtx) {
        self.accelerating = vq.abs() > self.vq.abs();
        self.vq = vq;
        self.land(pos, ctx);
    }
}
