//! Simulated **US Digital QSB** (-S, -D, -M): the firmware's behaviour on the serial wire,
//! byte for byte, the quadrature counter, and the -M's stepper drive with an encoder on
//! its shaft.
//!
//! [`QsbSim`] implements [`motion_link::sim::StreamDevice`] (USB virtual COM port, 230400
//! baud 8N1 by default). The model never reads a clock: it is deterministic under the
//! times it is given and [`QsbSimConfig::seed`]. Every line it decodes or encodes goes
//! through the `qsb` protocol crate.
//!
//! ```
//! use std::time::Duration;
//! use motion_link::sim::StreamDevice;
//! use board_qsb::sim::{QsbSim, QsbSimConfig};
//!
//! let mut board = QsbSim::new(QsbSimConfig::default()); // a QSB-M, serial 00001
//! board.receive(Duration::ZERO, b"R14\r\n");
//! let mut out = [0u8; 64];
//! // The answer starts after the 100 µs processing time.
//! assert_eq!(board.transmit(Duration::from_micros(99), &mut out), 0);
//! let n = board.transmit(Duration::from_micros(100), &mut out);
//! assert_eq!(&out[..n], b"r 14 00001113 !\r\n");
//! ```
//!
//! # Timing
//!
//! - A command is executed when its end-of-command byte arrives; its answer starts
//!   [`QsbSimConfig::processing_delay`] (100 µs) later, after the previous answer's
//!   processing (200 µs for READ ENCODER in analog mode). Lines are handed out whole when
//!   they start; the link charges their wire time. A command whose first byte begins
//!   before the previous command's answer has left the UART ("At the conclusion of the
//!   command response, the QSB is ready to accept another command") is counted
//!   ([`QsbSimStats::interlaced`]) and executed in turn.
//! - The time stamp counts 1/512 s ticks (1.953125 ms) from power-up; the data output timer
//!   runs in the same ticks (INTERVAL RATE, "1.95ms steps (1/512 Hz clock)"; the command
//!   list's "1.95ms (1/256 Hz)" under Time Stamp names the same 1.95 ms period with another
//!   frequency, read as a slip). Behind USB the host gets the bytes at the end of each 1 ms
//!   frame (`Board::link`'s `host_frame`, `SimLink::with_host_frames`).
//! - Streams (`S01`, `S05`, `S06`, `S0E`, `S13`) are answered at once with an `s` line,
//!   then paced by the data output timer: every INTERVAL RATE × 1/512 s (never faster than
//!   the processing delay; 0xFFFF, the factory value, disables output). The timer starts
//!   with the first stream and restarts when INTERVAL RATE is written. At each tick READ
//!   ENCODER is sent if THRESHOLD is 0 or it moved by at least THRESHOLD since the last
//!   value sent; the other registers are sent when they changed. A sample the UART has no
//!   room for (the previous lines still being sent) is skipped.
//! - A read (`R`) of a streamed register cancels that register's stream; COMMAND 0 and 1
//!   cancel every stream.
//! - `W16X0A` answers at the old rate; [`baud`](StreamDevice::baud) reports the new rate
//!   once that answer has left the UART. The rate is saved across power cycles.
//!
//! # Answers
//!
//! `r`/`w`/`s` as documented (a write echoes the data sent); `x` for unknown registers,
//! command types a register does not take, registers the variant lacks, unparseable lines
//! (register 00, data 0) and the baud command on firmware before 13; `e` (echoing the
//! data, nothing written) for data outside a register's range and COMMAND functions the
//! variant lacks. Motor commands are accepted without the drive enabled (COMMAND 2) but
//! move nothing.
//!
//! # Signals
//!
//! - -M: the encoder is on the stepper shaft ([`QsbSimConfig::cycles_per_step`], negative
//!   reverses it); -S/-D: it follows [`QsbSimConfig::motion`]. [`QsbSim::nudge_encoder`]
//!   moves it by hand. With [`QsbSimConfig::drive_enable`] the external stepper driver
//!   follows the step pulses only while its enable line (a DIG I/O bit) is active.
//! - Index: one pulse per [`QsbSimConfig::cycles_per_rev`], a quarter cycle wide, acting
//!   on its leading edge in the direction of motion (trailing edge with MDR1 B3).
//! - Triggers: an index, a match (CNTR passing through DTR), an underflow or an overflow
//!   enabled in MDR1 B4–B7 pulses DIG I/O bit 0 for INTERVAL RATE when DIG I/O CONFIG B12
//!   is set (bit 0 toggles, and back; an event during a pulse lengthens it); MDR1 B4 also
//!   captures at the index. STR latches CY, BW, CMP and IDX until CLEAR REG 3.
//! - Digital I/O: open-drain outputs with pull-ups; [`QsbSim::set_digital_inputs`] pulls
//!   pins low from outside. With the drive enabled, bit 1 is the step line (reads high)
//!   and bit 2 the direction (1 = positive). The -D has bit 0 only, the -S none; missing
//!   pins read 0.
//! - STR powers up as the factory table says (0x0A: counting enabled, up).
mod config;
mod counter;
mod dio;
mod firmware;
mod output;
mod physics;
mod ramp;
mod stream;

use core::time::Duration;

use motion_link::sim::StreamDevice;
use qsb::{
    BACKSPACE, BaudRate, CommandDecoder, DigIo, DigIoConfig, Eor, IntervalRate, Mdr0, Mdr1, Mode,
    Str, defaults,
};

use motion_sim::rng::SimRng;

pub use config::{AnalogInput, DriveEnable, EncoderMotion, QsbSimConfig, Variant};
pub use dio::{DIRECTION_BIT, STEP_BIT};

use counter::Counter;
use dio::DigitalIo;
use output::Output;
use ramp::Stepper;
use stream::Streams;

/// Registers that are neither the counter's nor the digital I/O's.
#[derive(Debug, Clone)]
struct Registers {
    mode: Mode,
    threshold: u16,
    interval: IntervalRate,
    eor: Eor,
    step_rate: u32,
    accel: u32,
    move_steps: i32,
    jog_rate: i32,
}

/// What COMMAND 3 saves (and the baud rate, saved by its own command).
#[derive(Debug, Clone)]
struct Saved {
    regs: Registers,
    mdr0: Mdr0,
    mdr1: Mdr1,
    dtr: u32,
    dig_io: u8,
    dig_io_config: DigIoConfig,
    motor_enabled: bool,
    baud: BaudRate,
}

impl Saved {
    fn factory(config: &QsbSimConfig) -> Self {
        Self {
            regs: Registers {
                mode: Mode::from_data(defaults::MODE).unwrap_or_default(),
                threshold: defaults::THRESHOLD as u16,
                interval: IntervalRate::from_data(defaults::INTERVAL_RATE).unwrap_or_default(),
                eor: Eor::from_data(defaults::EOR).unwrap_or_default(),
                step_rate: defaults::MD_STEP_RATE,
                accel: defaults::MD_ACCEL,
                move_steps: defaults::MD_MOVE_STEPS as i32,
                jog_rate: defaults::MD_JOG_RATE as i32,
            },
            mdr0: Mdr0::from_data(defaults::MDR0).unwrap_or_default(),
            mdr1: Mdr1::from_data(defaults::MDR1).unwrap_or_default(),
            dtr: defaults::DTR,
            dig_io: DigIo::from_data(defaults::DIG_IO).unwrap_or_default().0,
            dig_io_config: DigIoConfig::from_data(defaults::DIG_IO_CONFIG).unwrap_or_default(),
            motor_enabled: config.motor_drive_enabled && config.variant == Variant::M,
            baud: config.baud,
        }
    }
}

/// Counters of what the model did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct QsbSimStats {
    /// Command lines executed (including bad ones).
    pub commands: u64,
    /// Lines that could not be parsed.
    pub bad_lines: u64,
    /// `e` answers.
    pub errors: u64,
    /// `x` answers.
    pub unsupported: u64,
    /// Lines queued for transmission.
    pub lines: u64,
    /// Lines lost because the transmit queue was full.
    pub dropped_lines: u64,
    /// Commands whose first byte began before the answer to the previous command had left
    /// the UART: "At the conclusion of the command response, the QSB is ready to accept
    /// another command" (Command Acknowledgement Format). A host that keeps one command at
    /// a time never makes one.
    pub interlaced: u64,
}

/// A simulated QSB-S, -D or -M.
#[derive(Debug, Clone)]
pub struct QsbSim {
    config: QsbSimConfig,
    rng: SimRng,
    rx: CommandDecoder,
    /// Whether the first call has fixed the power-up instant.
    started: bool,
    t: Duration,
    ts_epoch: Duration,
    regs: Registers,
    counter: Counter,
    dio: DigitalIo,
    motor: Stepper,
    motor_enabled: bool,
    saved: Saved,
    encoder_offset: f64,
    streams: Streams,
    output: Output,
    cpu_free: Duration,
    baud: u32,
    baud_change: Option<u32>,
    pending_baud: Option<(Duration, u32)>,
    pulse_end: Option<Duration>,
    /// When the answer to the last command will have left the UART.
    answer_end: Duration,
    /// Trigger events that pulsed bit 0 since power-up (for observation).
    trigger_pulses: u64,
    stats: QsbSimStats,
}

impl QsbSim {
    /// A board just powered up with its saved (initially factory) parameters.
    pub fn new(config: QsbSimConfig) -> Self {
        let saved = Saved::factory(&config);
        let mut sim = Self {
            rng: SimRng::new(config.seed),
            rx: CommandDecoder::new(),
            started: false,
            t: Duration::ZERO,
            ts_epoch: Duration::ZERO,
            regs: saved.regs.clone(),
            counter: Counter::new(saved.mdr0, saved.mdr1, saved.dtr, Str::default()),
            dio: DigitalIo::new(0, 0, DigIoConfig::default(), 0),
            motor: Stepper::new(),
            motor_enabled: false,
            encoder_offset: 0.0,
            streams: Streams::default(),
            output: Output::new(config.tx_capacity),
            cpu_free: Duration::ZERO,
            baud: saved.baud.bits_per_second(),
            baud_change: None,
            pending_baud: None,
            pulse_end: None,
            answer_end: Duration::ZERO,
            trigger_pulses: 0,
            stats: QsbSimStats::default(),
            saved,
            config,
        };
        sim.power_up(Duration::ZERO);
        sim.started = false;
        sim
    }

    /// Restores the power-up state at `now`: saved parameters, volatile registers at their
    /// factory values, no streams, motor at rest, time stamp 0, nothing in flight.
    fn power_up(&mut self, now: Duration) {
        let s = self.saved.clone();
        self.started = true;
        self.t = now;
        self.ts_epoch = now;
        self.cpu_free = now;
        self.regs = s.regs.clone();
        let status = Str::from_data(defaults::STR).unwrap_or_default();
        self.counter = Counter::new(s.mdr0, s.mdr1, s.dtr, status);
        self.dio = DigitalIo::new(
            self.config.variant.digital_io_bits(),
            s.dig_io,
            s.dig_io_config,
            self.config.digital_inputs,
        );
        self.motor = Stepper::new();
        self.motor_enabled = s.motor_enabled;
        if s.motor_enabled {
            self.dio.drive = Some(true);
        }
        self.streams = Streams::default();
        self.output.clear(now);
        self.rx.clear();
        self.baud = s.baud.bits_per_second();
        self.baud_change = None;
        self.pending_baud = None;
        self.pulse_end = None;
        self.answer_end = now;
        self.trigger_pulses = 0;
    }

    /// Power-cycles the board at `now` (USB unplugged and plugged back).
    pub fn power_cycle(&mut self, now: Duration) {
        self.advance(now);
        let t = self.t;
        self.power_up(t);
    }

    /// Resets the board at `now` (a high-low-high transition on DTR): the same as a power
    /// cycle.
    pub fn reset(&mut self, now: Duration) {
        self.power_cycle(now);
    }

    /// Runs the model to `now`: physics, data output ticks, pulse ends, baud change.
    fn advance(&mut self, now: Duration) {
        if !self.started {
            self.power_up(now);
        }
        let now = now.max(self.t);
        loop {
            let next = [
                self.streams.next_tick,
                self.pulse_end,
                self.pending_baud.map(|(t, _)| t),
            ]
            .into_iter()
            .flatten()
            .filter(|t| *t <= now)
            .min();
            let Some(t) = next else { break };
            let t = t.max(self.t);
            self.advance_physics(t);
            if self.pulse_end.is_some_and(|p| p <= t) {
                self.pulse_end = None;
                self.toggle_bit0();
            }
            if let Some((_, rate)) = self.pending_baud.filter(|(p, _)| *p <= t) {
                self.baud = rate;
                self.pending_baud = None;
            }
            if self.streams.next_tick.is_some_and(|p| p <= t) {
                self.stream_tick();
            }
        }
        self.advance_physics(now);
        self.stats.lines = self.output.lines;
        self.stats.dropped_lines = self.output.dropped_lines;
        self.stats.bad_lines = self.rx.bad_lines();
    }

    /// The TIME STAMP register at model time `t`: 1/512 s ticks since power-up or the last
    /// clear, rolling over at 32 bits.
    fn time_stamp(&self, t: Duration) -> u32 {
        (t.saturating_sub(self.ts_epoch).as_nanos() / qsb::TICK.as_nanos()) as u32
    }

    /// The 16-bit 500 µs time stamp of the analog data format.
    fn analog_time_stamp(&self, t: Duration) -> u16 {
        (t.saturating_sub(self.ts_epoch).as_nanos() / qsb::ANALOG_TICK.as_nanos()) as u16
    }

    // ----- observation -----

    /// The configuration.
    pub fn config(&self) -> &QsbSimConfig {
        &self.config
    }

    /// The true encoder position at the model time, quadrature cycles.
    pub fn encoder_position(&self) -> f64 {
        self.encoder_at(self.t)
    }

    /// The stepper's true position, steps (-M).
    pub fn motor_position(&self) -> f64 {
        self.motor.position
    }

    /// The stepper's true velocity, steps/s (-M).
    pub fn motor_velocity(&self) -> f64 {
        self.motor.velocity
    }

    /// The stepper's acceleration in the current motion phase, steps/s² (-M).
    pub fn motor_acceleration(&self) -> f64 {
        self.motor.acceleration
    }

    /// The move rate and acceleration in force (MD STEP RATE and MD ACCEL in 16-step
    /// increments), steps/s and steps/s².
    pub fn motor_limits(&self) -> (f64, f64) {
        self.motor_limits_internal()
    }

    /// The quadrature counter (CNTR).
    pub fn counter(&self) -> u32 {
        self.counter.cntr
    }

    /// Levels at the digital I/O pins.
    pub fn digital_pins(&self) -> u8 {
        self.dio.pins()
    }

    /// Captures made since power-up (an enabled input edge, an index with MDR1 B4),
    /// whether or not they changed CAPTURE.
    pub fn captures(&self) -> u64 {
        self.counter.captures
    }

    /// The CAPTURE register.
    pub fn capture(&self) -> u32 {
        self.counter.capture
    }

    /// Trigger events that pulsed DIG I/O bit 0 since power-up (MDR1 B4–B7 with DIG I/O
    /// CONFIG B12; events during a pulse lengthen it and count too).
    pub fn trigger_pulses(&self) -> u64 {
        self.trigger_pulses
    }

    /// Whether the trigger pulse is on now (bit 0 away from its resting level).
    pub fn trigger_pulse_active(&self) -> bool {
        self.pulse_end.is_some()
    }

    /// DIG I/O bits configured as outputs (DIG I/O CONFIG B11–B8) and the output states
    /// written (DIG I/O), as `(outputs, latch)`.
    pub fn digital_outputs(&self) -> (u8, u8) {
        (self.dio.config.output & 0xF, self.dio.latch & 0xF)
    }

    /// Whether the external stepper driver is enabled (always without
    /// [`QsbSimConfig::drive_enable`]).
    pub fn drive_energised(&self) -> bool {
        self.config
            .drive_enable
            .is_none_or(|line| (self.dio.pins() >> line.bit) & 1 == u8::from(line.active_high))
    }

    /// The line rate the board is listening at.
    pub fn line_rate(&self) -> u32 {
        self.baud
    }

    /// Counters of what the model did.
    pub fn stats(&self) -> QsbSimStats {
        self.stats
    }

    /// The model time (the latest `now` it was given).
    pub fn now(&self) -> Duration {
        self.t
    }

    // ----- injection -----

    /// Advances to `now`, then moves the encoder by `cycles` quadrature cycles (a hand on
    /// the shaft), counting the edges and index pulses on the way.
    pub fn nudge_encoder(&mut self, now: Duration, cycles: f64) {
        self.advance(now);
        let p0 = self.encoder_at(self.t);
        self.encoder_offset += cycles;
        let p1 = self.encoder_at(self.t);
        self.encoder_moved(p0, p1);
    }

    /// Advances to `now`, then sets the levels the outside world leaves on digital I/O
    /// bits 3–0 (1 = not pulled low); an enabled edge loads CAPTURE.
    pub fn set_digital_inputs(&mut self, now: Duration, levels: u8) {
        self.advance(now);
        let before = self.dio.pins();
        self.dio.external = levels & 0xF;
        if self.dio.interrupt(before) {
            self.counter.capture_now();
        }
    }
}

impl StreamDevice for QsbSim {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.advance(now);
        for &b in bytes {
            let starts_command = self.rx.is_idle() && !matches!(b, b'\r' | b'\n' | BACKSPACE);
            // The byte began one byte time before it arrived.
            let began = now.saturating_sub(output::byte_time(self.baud));
            if starts_command && began < self.answer_end {
                self.stats.interlaced += 1;
            }
            if let Some(line) = self.rx.push(b) {
                self.execute(line, now);
            }
        }
        self.stats.bad_lines = self.rx.bad_lines();
        self.stats.lines = self.output.lines;
        self.stats.dropped_lines = self.output.dropped_lines;
    }

    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.advance(now);
        self.output.take(now, out)
    }

    fn next_event(&self, _now: Duration) -> Option<Duration> {
        [
            self.output.next_ready(),
            self.streams.next_tick,
            self.pulse_end,
            self.pending_baud.map(|(t, _)| t),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn baud(&self) -> Option<u32> {
        Some(self.baud)
    }
}
