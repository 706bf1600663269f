//! One quadrature channel: motor, encoder counter, control loop, input and status latches.

use qq2drv::limits::RATED_MAX_TRANSITIONS_PER_S;
use qq2drv::{ControlMode, Status};

use super::config::{InputPin, MotorConfig};
use super::control::Controller;
use super::inputs::{Input, InputAction, pin_level};
use super::physics::Motor;

/// Channel state.
#[derive(Debug, Clone)]
pub(crate) struct Channel {
    pub(crate) motor: Motor,
    pub(crate) control: Controller,
    pub(crate) input: Input,
    pub(crate) pin: InputPin,
    /// Test hook: force the pin's electrical level.
    pub(crate) pin_override: Option<bool>,
    transitions_per_rev: u32,
    /// Position counter = encoder count + offset (wrapping to 32 bits on the wire).
    offset: i64,
    /// Counter value at the last packet-2/3 position read (relative mode).
    pub(crate) last_read: i64,
    glitch: bool,
    overspeed: bool,
}

impl Channel {
    pub(crate) fn new(motor: MotorConfig, gain: f64, pin: InputPin) -> Self {
        Self {
            motor: Motor::new(motor, gain),
            control: Controller::new(),
            input: Input::default(),
            pin,
            pin_override: None,
            transitions_per_rev: motor.transitions_per_rev,
            offset: 0,
            last_read: 0,
            glitch: false,
            overspeed: false,
        }
    }

    /// The position counter (full width).
    pub(crate) fn counter(&self) -> i64 {
        self.motor.count() + self.offset
    }

    /// The position counter as the firmware's 32-bit register.
    pub(crate) fn counter_i32(&self) -> i32 {
        self.counter() as i32
    }

    /// Overwrites the whole 32-bit counter (packet 10, input triggers); the control loop's
    /// frame moves with it.
    pub(crate) fn set_counter(&mut self, value: i32) {
        let before = self.counter();
        self.offset = i64::from(value) - self.motor.count();
        let delta = self.counter() - before;
        self.control.shift(delta as f64);
        self.last_read += delta;
    }

    /// Power cycle: loop, input, status and counter back to start-up; the shaft keeps its
    /// position and coasts.
    pub(crate) fn power_cycle(&mut self) {
        self.control = Controller::new();
        self.input = Input::default();
        self.motor.set_power(0);
        self.motor.clear_captures();
        self.offset = -self.motor.count();
        self.last_read = 0;
        self.glitch = false;
        self.overspeed = false;
    }

    /// Latches a glitch (an invalid A/B transition).
    pub(crate) fn latch_glitch(&mut self) {
        self.glitch = true;
    }

    /// Advances the shaft by `dt` seconds ending at `t_end`, then evaluates the input.
    pub(crate) fn step(&mut self, dt: f64, t_end: f64, glitch_velocity: f64) {
        self.motor.step(dt, t_end);
        let v = self.motor.velocity().abs();
        if v > f64::from(RATED_MAX_TRANSITIONS_PER_S) {
            self.overspeed = true;
        }
        if v > glitch_velocity {
            self.glitch = true;
        }
        self.evaluate_input();
    }

    /// Evaluates the IN pin against the current shaft position.
    pub(crate) fn evaluate_input(&mut self) {
        let level = self.pin_override.unwrap_or_else(|| {
            pin_level(&self.pin, self.motor.position(), self.transitions_per_rev)
        });
        let forward = self.motor.velocity() >= 0.0;
        match self
            .input
            .evaluate(level, self.counter(), self.motor.ab_zero(), forward)
        {
            InputAction::None => {}
            InputAction::SetCounter(v) => self.set_counter(v),
        }
    }

    /// One control period; applies the loop's output to the motor.
    pub(crate) fn control_tick(&mut self, dt: f64) {
        let count = self.counter() as f64;
        let power = self.control.tick(count, dt);
        self.motor.set_power(power);
    }

    /// Packet 16.
    pub(crate) fn set_mode(&mut self, mode: ControlMode) {
        let count = self.counter() as f64;
        self.control.set_mode(mode, count);
        if mode == ControlMode::Off {
            self.motor.set_power(0);
        }
    }

    /// The Status byte; transmitting it clears the accumulated bits.
    pub(crate) fn take_status(&mut self) -> Status {
        let mut bits = self.input.take_status_bits();
        if self.glitch {
            bits |= Status::GLITCH;
        }
        if self.overspeed {
            bits |= Status::OVERSPEED;
        }
        self.glitch = false;
        self.overspeed = false;
        Status(bits)
    }

    /// Position as reported in packets 2/3: absolute, or the change since the last read.
    pub(crate) fn read_position(&mut self, relative: bool) -> i32 {
        let now = self.counter();
        let value = if relative { now - self.last_read } else { now };
        self.last_read = now;
        value as i32
    }
}
