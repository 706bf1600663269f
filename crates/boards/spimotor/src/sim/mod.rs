//! Simulated **SPI_motor** board: the firmware's behaviour on the SPI wire, byte for byte,
//! and the physics of the motors connected to it (one stepper, or two brushed DC motors).
//!
//! [`SpimotorSim`] implements [`motion_link::sim::SpiDevice`]: one call of
//! [`transfer`](SpiDevice::transfer) is one chip-select assertion, completing at the `now`
//! the caller passes. The model never reads a clock; it is deterministic under the times it
//! is given and its seed. Every byte it decodes or encodes goes through the `spimotor`
//! protocol crate, so a protocol fact lives in one place; this module adds what the
//! firmware *does* with the bytes.
//!
//! # Example
//!
//! ```
//! use std::time::Duration;
//! use motion_link::sim::SpiDevice;
//! use board_spimotor::sim::{SpimotorSim, SpimotorSimConfig};
//! use spimotor::{Address, ReadPort, Reply, Transaction, Write};
//!
//! let mut board = SpimotorSim::new(SpimotorSimConfig::default()); // stepper at 0x90
//!
//! // Datasheet example: move the stepper to step 0x12345678.
//! let mut mosi = [0u8; 8];
//! let mut miso = [0u8; 8];
//! let move_to = Transaction::write(Address::DEFAULT, Write::TargetPosition(0x1234_5678));
//! let n = move_to.encode(&mut mosi)?;
//! assert_eq!(&mosi[..n], &[0x90, 0x41, 0x78, 0x56, 0x34, 0x12]);
//! assert!(board.transfer(Duration::ZERO, &mosi[..n], &mut miso[..n]));
//!
//! // One second later, at the default step delay of 20 ms, it has made 50 steps.
//! let read = Transaction::read(Address::DEFAULT, ReadPort::CurrentPosition);
//! let n = read.encode(&mut mosi)?;
//! assert!(board.transfer(Duration::from_secs(1), &mosi[..n], &mut miso[..n]));
//! assert_eq!(
//!     Reply::decode(ReadPort::CurrentPosition, &miso[..n])?,
//!     Reply::CurrentPosition(50)
//! );
//!
//! // Another address on the shared bus: the board leaves MISO alone and says so.
//! let other = Transaction::read(Address::new(0x92)?, ReadPort::Identification);
//! let mut buf = [0u8; 40];
//! let n = other.encode(&mut buf)?;
//! let mut miso = [0xFFu8; 40];
//! assert!(!board.transfer(Duration::from_secs(1), &buf[..n], &mut miso[..n]));
//! # Ok::<(), spimotor::Error>(())
//! ```
//!
//! Several boards share a bus through [`motion_link::sim::SpiBus`] (shared chip select,
//! undriven MISO reads 0xFF): give each one its own [`SpimotorSimConfig::address`].
//!
//! # On the wire
//!
//! A transaction is address byte, port byte, data (see the `spimotor` crate docs). What
//! the model clocks out on MISO:
//!
//! | MISO offset | selected board (address byte matches) | other address |
//! |---|---|---|
//! | 0 | [`MISO_UNSELECTED`] (0xFF): nobody knows yet who is selected, the line floats | untouched, `transfer` returns `false` |
//! | 1 | [`MISO_IDLE`] (0x00): selected, but the port is not known yet | untouched |
//! | 2… | read of a documented port: the answer, cut short or followed by 0x00 padding as the host clocks fewer or more bytes; anything else: [`MISO_IDLE`] | untouched |
//!
//! The board answers by port alone: it cannot know how many bytes the host will clock.
//! A value is read as it is when the transaction completes (`now`).
//!
//! Address filtering compares the address byte with bit 0 (the read flag) masked off. A
//! board that is not addressed sees nothing of the transaction: no state changes, no
//! abort of an address-change sequence, only [`SpimotorSimStats::transactions`] counts it.
//!
//! A selected transaction the firmware cannot use (shorter than address + port, an
//! undocumented port, a 4-byte port with another number of bytes, a one-byte port without
//! its byte, a wrong unlock key, an odd new address) is ignored: it changes nothing but
//! [`SpimotorSimStats::malformed`], and aborts an address-change sequence in progress. The
//! model never panics, whatever the bytes.
//!
//! # Ports and what the firmware does with them
//!
//! | port | write | read |
//! |---|---|---|
//! | 0x01 | — | identification string and its 0 ([`SpimotorSimConfig::identification`]) |
//! | 0x02 | — | EEPROM serial number, 4 bytes LE ([`SpimotorSimConfig::serial`]) |
//! | 0x10 | stepper drive intensity (power-on 0x20); 0 de-energises the coils | — |
//! | 0x20 / 0x21 | motor A spins in direction A / B at intensity/255 of full speed | — |
//! | 0x22 | motor A stops (brakes); no data byte needed, any is ignored | — |
//! | 0x30–0x32 | the same for motor B | — |
//! | 0x40 | sets the position counter (the rotor does not move; the target stays) | position counter |
//! | 0x41 | sets the target: the stepper steps towards it | target |
//! | 0x42 | target = current position + value (32-bit wrapping) | — |
//! | 0x43 | step delay in tenths of a millisecond (power-on 200 = 20 ms) | step delay |
//! | 0x44 | 0x00: one coil driven, anything else: two | — |
//! | 0xf1, 0xf2, 0xf0 | the address-change sequence (below) | — |
//!
//! One-byte ports written with several bytes take the last one (the datasheet calls the
//! extra bytes "redundant"). Port 0x40 changes only the counter: if it then differs from
//! the target, the stepper steps towards the target, as a firmware that compares the two
//! would; set both to redefine "here" without moving.
//!
//! ## Step timing
//!
//! While the position counter differs from the target the firmware makes one full step
//! towards the target every step delay, updating the counter and the true rotor position
//! together. A move from rest makes its first step one step delay after the command. A
//! new step delay applies from the last step: the next step comes one new delay after it,
//! or at once if that instant has already passed. Therefore no two steps (and no command
//! and the first step of a move) are ever closer than the step delay in force, and a move
//! of *n* steps from rest arrives exactly *n* × delay after the command. A step delay of 0
//! steps every 0.1 ms (one tick of the firmware's timer). Catching up over a long
//! interval is computed in closed form, so a multi-hour move costs nothing.
//!
//! The coil pattern ([`SpimotorSim::coil_drive`]) follows the rotor's step: one coil (wave
//! drive) A+, B+, A−, B−; two coils A+B+, A−B+, A−B−, A+B−; nothing at intensity 0.
//!
//! ## Address change
//!
//! Write 0x55 to 0xf1, then 0xaa to 0xf2, then the new (even) address to 0xf0, as the next
//! three transactions addressed to the board ([`UnlockStage`]). Anything else addressed
//! to the board in between (a read included) aborts the sequence; 0xf1 ← 0x55 always
//! restarts it; 0xf0 outside it is ignored. The new address takes effect with the next
//! transaction: the old one is then ignored like any other board's. The address lives in
//! EEPROM and survives [`SpimotorSim::power_cycle`].
//!
//! # Motor physics
//!
//! **Stepper** ([`Drive::Stepper`], channel 0): the rotor follows every step exactly (no
//! stall or resonance model). [`SpimotorSim::rotor_steps`] is the true position in full
//! steps since the simulation started; it differs from the firmware's counter by whatever
//! was written to port 0x40. Velocity is the step rate, ±1/delay steps per second, while
//! moving.
//!
//! **Brushed** ([`Drive::Brushed`], channel 0 = motor A, 1 = motor B): each shaft's speed
//! follows a first-order lag with [`BrushedMotorConfig::time_constant`] τ towards
//! `v∞ = ±intensity/255 × no_load_speed × k` (direction A positive), and towards 0 after a
//! stop (the bridge brakes). The solution is integrated exactly between transactions:
//! `v(t) = v∞ + (v₀ − v∞)·e^(−t/τ)`, so the result does not depend on how often the model
//! is advanced. `k` is drawn from `1 ± speed_noise` at every spin command from the seeded
//! [`SimRng`]: load and supply spread, reproducible for one seed.
//! Positions are in revolutions, velocities in revolutions per second.
//!
//! The board has no feedback from the brushed motors; their true state is only observable
//! through the model's accessors. Both sections of the firmware always run: stepper ports
//! work (counter, target, timing) in the brushed drive, and brushed ports are recorded in
//! the stepper drive, but the physics only moves what [`SpimotorSimConfig::drive`] says is
//! connected (the real board would drive the same bridges from both sections; that
//! interference is not modelled).
//!
//! # Observing and injecting
//!
//! Read-only: [`SpimotorSim::position`] / [`SpimotorSim::velocity`] per channel, the
//! firmware registers ([`SpimotorSim::current_position`], [`SpimotorSim::target_position`],
//! [`SpimotorSim::step_delay`], [`SpimotorSim::coils`], [`SpimotorSim::stepper_intensity`],
//! [`SpimotorSim::bridge`]), step instants ([`SpimotorSim::last_step_at`],
//! [`SpimotorSim::next_step_at`]), [`SpimotorSim::address`], [`SpimotorSim::unlock_stage`]
//! and [`SpimotorSim::stats`]. Event: [`SpimotorSim::power_cycle`] (RAM cleared, EEPROM and
//! rotor kept). Time never runs backwards: a `now` earlier than the last one is taken as
//! the last one.
//!
//! # Readings where the datasheet is silent
//!
//! Beyond docs/ARCHITECTURE.md ("How we read the datasheets", SPI_motor) and the `spimotor` crate's
//! readings (answer at MISO offset 2, 4-byte LE serial number, stop ports without data,
//! last byte wins), this model assumes: MISO fill bytes as in the table above; the first
//! step one delay after a move starts; step delay 0 = 0.1 ms; power-on coil setting one
//! coil ([`POWER_ON_COILS`], a zero-initialised variable); relative moves count from the
//! current position; writing the current position leaves the target alone; the coil
//! pattern follows the rotor; a stop brakes. Inter-byte timing of a real AVR (it must load
//! the answer between the port byte and the next) is not modelled: the model answers at
//! any SPI clock.

mod brushed;
mod config;
mod firmware;
mod stepper;
mod unlock;

use core::time::Duration;

use motion_link::sim::SpiDevice;
use spimotor::{Address, Coils, Identification, Motor, SerialNumber, StepDelay};

use motion_sim::rng::SimRng;

pub use brushed::Bridge;
pub use config::{BrushedMotorConfig, Drive, SpimotorSimConfig};
pub use firmware::{MISO_IDLE, MISO_UNSELECTED};
pub use stepper::POWER_ON_COILS;
pub use unlock::UnlockStage;

use brushed::DcMotor;
use stepper::Stepper;

/// Counters of what the board saw on the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SpimotorSimStats {
    /// Every transaction on the bus, whatever its address.
    pub transactions: u64,
    /// Transactions addressed to this board.
    pub addressed: u64,
    /// Addressed transactions the firmware could not use: too short, unknown port, wrong
    /// number of data bytes, wrong unlock key, odd new address. They change nothing
    /// (except aborting an address-change sequence).
    pub malformed: u64,
    /// Completed address changes.
    pub address_changes: u64,
}

/// A simulated SPI_motor board: firmware behaviour on the wire and the physics of the
/// motors connected to it. See the module docs.
#[derive(Debug, Clone)]
pub struct SpimotorSim {
    config: SpimotorSimConfig,
    /// Address in EEPROM (survives a power cycle).
    address: Address,
    identification: Identification,
    serial: SerialNumber,
    unlock: UnlockStage,
    stepper: Stepper,
    motors: [DcMotor; 2],
    rng: SimRng,
    /// The instant the model has been advanced to.
    now: Duration,
    stats: SpimotorSimStats,
}

impl SpimotorSim {
    /// A board fresh from power-on at time zero, with `config`'s address in its EEPROM.
    pub fn new(config: SpimotorSimConfig) -> Self {
        Self {
            address: Address::of_byte(config.address),
            identification: config.wire_identification(),
            serial: config.wire_serial(),
            unlock: UnlockStage::Locked,
            stepper: Stepper::power_on(0),
            motors: [DcMotor::new(); 2],
            rng: SimRng::new(config.seed),
            now: Duration::ZERO,
            stats: SpimotorSimStats::default(),
            config,
        }
    }

    /// The configuration the board was built from.
    pub fn config(&self) -> &SpimotorSimConfig {
        &self.config
    }

    /// The address the board answers to now (even byte form).
    pub fn address(&self) -> u8 {
        self.address.get()
    }

    /// What is connected to the bridges.
    pub fn drive(&self) -> Drive {
        self.config.drive
    }

    /// Motor channels of the drive: 1 (stepper) or 2 (brushed A, B).
    pub fn channels(&self) -> usize {
        self.config.drive.channels()
    }

    /// The instant the model has been advanced to.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// Bus counters.
    pub fn stats(&self) -> SpimotorSimStats {
        self.stats
    }

    /// How far an address-change sequence has got.
    pub fn unlock_stage(&self) -> UnlockStage {
        self.unlock
    }

    // --- stepper section -------------------------------------------------------------

    /// Port 0x40: the firmware's position counter, full steps.
    pub fn current_position(&self) -> i32 {
        self.stepper.current
    }

    /// Port 0x41: the target the firmware steps towards.
    pub fn target_position(&self) -> i32 {
        self.stepper.target
    }

    /// Port 0x43.
    pub fn step_delay(&self) -> StepDelay {
        self.stepper.delay
    }

    /// Port 0x44.
    pub fn coils(&self) -> Coils {
        self.stepper.coils
    }

    /// Port 0x10.
    pub fn stepper_intensity(&self) -> u8 {
        self.stepper.intensity
    }

    /// Whether the firmware is stepping (current position ≠ target).
    pub fn is_moving(&self) -> bool {
        self.stepper.is_moving()
    }

    /// When the firmware made its last step.
    pub fn last_step_at(&self) -> Option<Duration> {
        self.stepper.last_step_at
    }

    /// When the next step is due, while moving.
    pub fn next_step_at(&self) -> Option<Duration> {
        self.stepper.next_step_at()
    }

    /// True rotor position: net full steps made since the simulation started (writing the
    /// current position moves the counter, not the rotor).
    pub fn rotor_steps(&self) -> i64 {
        self.stepper.rotor
    }

    /// Drive of the stepper's coils A and B (+1, 0, −1) at the rotor's present step.
    pub fn coil_drive(&self) -> [i8; 2] {
        self.stepper.coil_drive()
    }

    // --- brushed section -------------------------------------------------------------

    /// What the firmware drives a brushed motor's bridge with.
    pub fn bridge(&self, motor: Motor) -> Bridge {
        self.motor(motor).bridge
    }

    /// True shaft speed of a brushed motor, revolutions per second (direction A positive).
    pub fn motor_velocity(&self, motor: Motor) -> f64 {
        self.motor(motor).velocity
    }

    /// True shaft angle of a brushed motor, revolutions since the simulation started.
    pub fn motor_position(&self, motor: Motor) -> f64 {
        self.motor(motor).position
    }

    /// The speed a brushed motor settles at under its present command, rev/s.
    pub fn motor_settled_velocity(&self, motor: Motor) -> f64 {
        self.motor(motor).settled_velocity(&self.config.brushed)
    }

    fn motor(&self, motor: Motor) -> &DcMotor {
        match motor {
            Motor::A => &self.motors[0],
            Motor::B => &self.motors[1],
        }
    }

    // --- per channel -----------------------------------------------------------------

    /// True position of a channel: the stepper rotor in full steps (channel 0 of
    /// [`Drive::Stepper`]) or a brushed shaft in revolutions (channels 0, 1 of
    /// [`Drive::Brushed`]). `None` for a channel the drive does not have.
    pub fn position(&self, channel: usize) -> Option<f64> {
        match (self.config.drive, channel) {
            // Rotor positions stay far below 2^53 steps: exact in an f64.
            (Drive::Stepper, 0) => Some(self.stepper.rotor as f64),
            (Drive::Brushed, 0) => Some(self.motors[0].position),
            (Drive::Brushed, 1) => Some(self.motors[1].position),
            _ => None,
        }
    }

    /// True velocity of a channel: full steps per second for the stepper (the step rate
    /// while moving), revolutions per second for a brushed motor.
    pub fn velocity(&self, channel: usize) -> Option<f64> {
        match (self.config.drive, channel) {
            (Drive::Stepper, 0) => Some(self.stepper.velocity()),
            (Drive::Brushed, 0) => Some(self.motors[0].velocity),
            (Drive::Brushed, 1) => Some(self.motors[1].velocity),
            _ => None,
        }
    }

    // --- events ----------------------------------------------------------------------

    /// Switches the board off and on again at `now`: RAM is cleared (positions 0, step
    /// delay 200, intensity 0x20, [`POWER_ON_COILS`], motors stopped, unlock sequence
    /// aborted); the EEPROM (address, serial) and the motors' true positions survive.
    pub fn power_cycle(&mut self, now: Duration) {
        self.advance_to(now);
        self.stepper = Stepper::power_on(self.stepper.rotor);
        for m in &mut self.motors {
            m.bridge = Bridge::Stopped;
        }
        self.unlock = UnlockStage::Locked;
    }

    /// Advances the physics to `now` (never backwards) and makes every step due by then.
    fn advance_to(&mut self, now: Duration) {
        let now = now.max(self.now);
        let dt = now - self.now;
        for m in &mut self.motors {
            m.advance(dt, &self.config.brushed);
        }
        self.stepper.advance(now);
        self.now = now;
    }
}

impl Default for SpimotorSim {
    fn default() -> Self {
        Self::new(SpimotorSimConfig::default())
    }
}

impl SpiDevice for SpimotorSim {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        self.advance_to(now);
        let drove = self.handle(self.now, mosi, miso);
        // A write can make a step due at once (a shorter step delay mid-move).
        self.stepper.advance(self.now);
        drove
    }

    fn advance(&mut self, now: Duration) {
        self.advance_to(now);
    }
}
