//! What the firmware does with a command line: the register file, `e` and `x` answers,
//! the COMMAND functions, and the reply.

use core::time::Duration;

use qsb::{
    CommandLine, EncoderMode, Error, LoadTarget, MdStatus, Mode, QsbCommand, Register, Request,
    Response, ResponseType, TIME_STAMP_CLEAR, Version, Write,
};

use super::ramp::Goal;
use super::{QsbSim, Saved};

impl QsbSim {
    /// Executes one decoded command line received at `now` and queues its answer.
    pub(super) fn execute(&mut self, line: Result<CommandLine, Error>, now: Duration) {
        self.stats.commands += 1;
        let start = self.cpu_free.max(now);
        let (response, register) = match line {
            Ok(line) => (self.apply(&line, now), Register::from_u8(line.register)),
            Err(_) => (Response::new(ResponseType::Unsupported, 0, 0), None),
        };
        match response.ty {
            ResponseType::Error => self.stats.errors += 1,
            ResponseType::Unsupported => self.stats.unsupported += 1,
            _ => {}
        }
        let delay = if register == Some(Register::ReadEncoder) {
            self.measurement_delay()
        } else {
            self.config.processing_delay
        };
        self.cpu_free = start.saturating_add(delay);
        let end = self.send(response, self.cpu_free);
        if let Some(end) = end {
            self.answer_end = end;
        }
        if let (Some(rate), Some(end)) = (self.baud_change.take(), end) {
            self.pending_baud = Some((end, rate));
        }
    }

    /// Queues `response` to start at `ready`, with the time stamp if EOR asks for it.
    /// Returns when it will have left the UART.
    pub(super) fn send(&mut self, mut response: Response, ready: Duration) -> Option<Duration> {
        if self.regs.eor.time_stamp {
            response.time_stamp = Some(self.time_stamp(self.t));
        }
        self.output.send(response, self.regs.eor, ready, self.baud)
    }

    fn apply(&mut self, line: &CommandLine, now: Duration) -> Response {
        let data = line.data.unwrap_or(0);
        let refuse = |ty| Response::new(ty, line.register, data);
        let request =
            match Request::from_line(line).and_then(|r| r.check(self.config.variant).map(|()| r)) {
                Ok(r) => r,
                Err(Error::UnknownRegister | Error::NotPermitted) => {
                    return refuse(ResponseType::Unsupported);
                }
                Err(_) => return refuse(ResponseType::Error),
            };
        match request {
            Request::Read(register) => {
                self.streams.cancel(register);
                Response::new(
                    ResponseType::Read,
                    line.register,
                    self.read_register(register),
                )
            }
            Request::Stream(register) => {
                let value = self.stream_value(register);
                let was_streaming = self.streams.next_tick.is_some();
                self.streams.start(register, value);
                if !was_streaming {
                    self.restart_stream_timer(now);
                }
                Response::new(ResponseType::Stream, line.register, value)
            }
            Request::Write(write) => match self.write(write, now) {
                Ok(()) => Response::new(ResponseType::Write, line.register, data),
                Err(ty) => refuse(ty),
            },
        }
    }

    /// The value a read returns at the model time.
    pub(super) fn read_register(&mut self, register: Register) -> u32 {
        match register {
            Register::Mode => Mode {
                encoder: self.regs.mode.encoder,
                pwm_12bit: self.regs.mode.encoder == EncoderMode::Pwm && self.config.pwm_12bit,
            }
            .data(),
            Register::DigIo => u32::from(self.dio.pins()),
            Register::DigIoConfig => self.dio.config.data(),
            Register::Mdr0 => self.counter.mdr0.data(),
            Register::Mdr1 => self.counter.mdr1.data(),
            Register::Capture => self.counter.capture,
            Register::Str => self.counter.status().data(),
            Register::Otr => {
                self.counter.load(LoadTarget::CntrToOtr);
                self.counter.otr
            }
            Register::Dtr => self.counter.dtr,
            Register::Threshold => u32::from(self.regs.threshold),
            Register::IntervalRate => self.regs.interval.data(),
            Register::TimeStamp => self.time_stamp(self.t),
            Register::ReadEncoder => match self.regs.mode.encoder {
                EncoderMode::Quadrature => {
                    self.counter.load(LoadTarget::CntrToOtr);
                    self.counter.otr
                }
                EncoderMode::Pwm => self.pwm_value(),
                EncoderMode::Analog => u32::from(self.analog_value()),
            },
            Register::MdStepRate => self.regs.step_rate,
            Register::MdAccel => self.regs.accel,
            Register::MdMoveSteps => self.regs.move_steps as u32,
            Register::MdJogRate => self.regs.jog_rate as u32,
            Register::MdStatus => self.md_status().data(),
            Register::Version => Version {
                serial: self.config.serial_number,
                product: self.config.variant,
                firmware: self.config.firmware_version,
            }
            .data(),
            Register::Eor => self.regs.eor.data(),
            Register::ClearReg | Register::LoadReg | Register::Command => 0,
        }
    }

    /// MD STATUS.
    pub fn md_status(&self) -> MdStatus {
        let moving = self.motor.moving();
        MdStatus {
            done: !moving && self.motor.paused.is_none(),
            moving,
            paused: self.motor.paused.is_some(),
            jogging: matches!(self.motor.goal, Goal::Jog { .. }),
            enabled: self.motor_enabled,
        }
    }

    /// Changes the digital I/O and fires the capture interrupt on an enabled edge.
    fn with_dio(&mut self, change: impl FnOnce(&mut super::dio::DigitalIo)) {
        let before = self.dio.pins();
        change(&mut self.dio);
        if self.dio.interrupt(before) {
            self.counter.capture_now();
        }
    }

    fn write(&mut self, write: Write, now: Duration) -> Result<(), ResponseType> {
        match write {
            Write::Mode(m) => {
                self.regs.mode = Mode {
                    encoder: m.encoder,
                    pwm_12bit: false,
                }
            }
            Write::DigIo(v) => self.with_dio(|d| d.latch = v.0),
            Write::DigIoConfig(c) => self.with_dio(|d| {
                d.config = c;
                d.latch = 0xF;
            }),
            Write::Mdr0(v) => self.counter.mdr0 = v,
            Write::Mdr1(v) => self.counter.mdr1 = v,
            Write::Dtr(v) => self.counter.dtr = v,
            Write::Clear(target) => self.counter.clear(target),
            Write::Load(target) => self.counter.load(target),
            Write::Threshold(v) => self.regs.threshold = v,
            Write::IntervalRate(v) => {
                self.regs.interval = v;
                self.restart_stream_timer(now);
            }
            Write::TimeStamp(v) => {
                if v == TIME_STAMP_CLEAR {
                    self.ts_epoch = now;
                }
            }
            Write::StepRate(v) => self.regs.step_rate = v,
            Write::Accel(v) => self.regs.accel = v,
            Write::MoveSteps(v) => self.regs.move_steps = v,
            Write::JogRate(v) => self.regs.jog_rate = v,
            Write::Eor(v) => self.regs.eor = v,
            Write::Command(c) => return self.command(c),
        }
        Ok(())
    }

    fn command(&mut self, command: QsbCommand) -> Result<(), ResponseType> {
        match command {
            QsbCommand::StopAll => {
                self.motor.quit();
                self.streams.cancel_all();
                self.motor_enabled = false;
                let latch = self.saved.dig_io;
                self.with_dio(|d| {
                    d.drive = None;
                    d.latch = latch;
                });
            }
            QsbCommand::StopStreaming => self.streams.cancel_all(),
            QsbCommand::EnableMotorDrive => {
                self.motor_enabled = true;
                self.with_dio(|d| d.drive = Some(d.drive.unwrap_or(true)));
            }
            QsbCommand::SaveParameters => {
                self.saved = Saved {
                    regs: self.regs.clone(),
                    mdr0: self.counter.mdr0,
                    mdr1: self.counter.mdr1,
                    dtr: self.counter.dtr,
                    dig_io: self.dio.latch,
                    dig_io_config: self.dio.config,
                    motor_enabled: self.motor_enabled,
                    baud: self.saved.baud,
                };
            }
            QsbCommand::MotorStop => self.motor.stop(),
            QsbCommand::MotorQuit => self.motor.quit(),
            QsbCommand::MotorPause => self.motor.pause(),
            QsbCommand::MotorResume => self.motor.resume(),
            QsbCommand::MotorMove => {
                if self.motor_enabled {
                    self.motor.start_move(self.regs.move_steps);
                }
            }
            QsbCommand::MotorJog => {
                if self.motor_enabled {
                    let rate = qsb::effective_rate(self.regs.jog_rate.unsigned_abs());
                    let rate = f64::from(rate) * f64::from(self.regs.jog_rate.signum());
                    self.motor.start_jog(rate);
                }
            }
            QsbCommand::SetBaud(rate) => {
                if self.config.firmware_version < Version::BAUD_SELECTION_FIRMWARE {
                    return Err(ResponseType::Unsupported);
                }
                self.saved.baud = rate;
                self.baud_change = Some(rate.bits_per_second());
            }
        }
        Ok(())
    }
}
