//! Port numbers of the SPI_motor board ("write ports" and "read ports" tables).
//!
//! A port is the second byte of every transaction. The same number can mean different
//! things for a write and a read (0x40 sets the current position when written and returns
//! it when read).

/// Write 0x10: drive intensity for stepper mode, one byte (default [`DEFAULT_STEPPER_INTENSITY`]).
pub const STEPPER_INTENSITY: u8 = 0x10;
/// Write 0x20: spin motor A in direction A with intensity `<byte>`.
pub const MOTOR_A_DIRECTION_A: u8 = 0x20;
/// Write 0x21: spin motor A in direction B with intensity `<byte>`.
pub const MOTOR_A_DIRECTION_B: u8 = 0x21;
/// Write 0x22: stop motor A (no data).
pub const MOTOR_A_STOP: u8 = 0x22;
/// Write 0x30: spin motor B in direction A with intensity `<byte>`.
pub const MOTOR_B_DIRECTION_A: u8 = 0x30;
/// Write 0x31: spin motor B in direction B with intensity `<byte>`.
pub const MOTOR_B_DIRECTION_B: u8 = 0x31;
/// Write 0x32: stop motor B (no data).
pub const MOTOR_B_STOP: u8 = 0x32;
/// Write 0x40: set current position, 4 bytes. Read 0x40: current position, 4 bytes.
pub const CURRENT_POSITION: u8 = 0x40;
/// Write 0x41: set target position, 4 bytes. Read 0x41: target position, 4 bytes.
pub const TARGET_POSITION: u8 = 0x41;
/// Write 0x42: set relative position, 4 bytes.
pub const RELATIVE_POSITION: u8 = 0x42;
/// Write 0x43: set step delay, one byte in tenths of a millisecond. Read 0x43: step delay.
pub const STEP_DELAY: u8 = 0x43;
/// Write 0x44: number of driven coils, one byte (0x00: one coil, anything else: two).
pub const COILS: u8 = 0x44;
/// Write 0xf0: change address (after the unlock writes to 0xf1 and 0xf2).
pub const CHANGE_ADDRESS: u8 = 0xf0;
/// Write 0xf1: write [`UNLOCK_KEY_1`] here to start unlocking the change-address register.
pub const UNLOCK_1: u8 = 0xf1;
/// Write 0xf2: write [`UNLOCK_KEY_2`] here to unlock the change-address register (the
/// datasheet's table prints this row as 0xf0 a second time; docs/ARCHITECTURE.md reads it as 0xf2).
pub const UNLOCK_2: u8 = 0xf2;
/// Read 0x01: identification string, terminated with 0.
pub const IDENTIFICATION: u8 = 0x01;
/// Read 0x02: read eeprom (serial number).
pub const SERIAL: u8 = 0x02;

/// The value that starts the address-change unlock (written to [`UNLOCK_1`]).
pub const UNLOCK_KEY_1: u8 = 0x55;
/// The value that completes the address-change unlock (written to [`UNLOCK_2`]).
pub const UNLOCK_KEY_2: u8 = 0xaa;

/// Power-on drive intensity of stepper mode ("default is 0x20").
pub const DEFAULT_STEPPER_INTENSITY: u8 = 0x20;
