//! Simulated SPI_motor board: firmware behaviour on the SPI wire and motor physics.

mod brushed;
mod config;
mod firmware;
mod stepper;
mod unlock;

use core::time::Duration;

use motion_link::sim::SpiDevice;
use spimotor::{Address, Coils, Identification, Motor, SerialNumber, StepDelay};

use crate::rng::SimRng;

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
            identification: config.identification(),
            serial: config.serial(),
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
