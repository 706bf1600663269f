//! Typed replies (pack → host): the responses tabled in manual section 8.

use crate::params::{PARAMS, bit0, byte, i16_at, i32_at, put, u16_at};
use crate::request::MAX_CHANNEL;
use crate::types::{Action, PowerDownStatus, RefInputs, check_motor};
use crate::{Command, Error};

/// Highest analogue value ($30: "unsigned 0..1023").
pub const MAX_ANALOG: u16 = 1023;

/// A response, without its address byte. See [`ReplyFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reply {
    /// $20: position and activity.
    Position {
        /// Motor number.
        motor: u8,
        /// posact.
        position: i32,
        /// Current action.
        action: Action,
        /// P6 bit 0: a stop condition has occurred (cleared by the read).
        stopped: bool,
    },
    /// $21: velocity and activity.
    Velocity {
        /// Motor number.
        motor: u8,
        /// vact.
        velocity: i16,
        /// Current action.
        action: Action,
    },
    /// $28: the actions of all six motors.
    Actions {
        /// P0..P5: motor 0..5.
        actions: [Action; 6],
    },
    /// $30: an analogue channel and the inputs.
    Input {
        /// Channel 0..=7.
        channel: u8,
        /// Analogue value 0..=1023.
        value: u16,
        /// P3 bit 0: the channel's reference input (inverted, as the pack reports it).
        reference: bool,
        /// P4: all reference inputs and the jumpers.
        inputs: RefInputs,
        /// P5 bit 0: logic state at TTLIO1.
        ttlio1: bool,
    },
    /// $43: unit information.
    UnitInfo {
        /// Firmware revision (148 = V1.4.8).
        firmware: u8,
        /// Reset flag: 1 at the first read-out after a reset.
        reset: bool,
        /// Temperature in °C.
        temperature: i8,
        /// Serial number.
        serial: u16,
    },
    /// $44: RS-232 via CAN status.
    CanRs232 {
        /// Bytes in the RS-232 send buffer.
        tx_pending: u8,
        /// P1 bit 0: state of the CTS line (inverted).
        cts: bool,
    },
    /// $45: power-down status.
    PowerDown {
        /// P0 bits.
        status: PowerDownStatus,
    },
    /// $F2: P0 = 1 when erasing went well.
    FlashEnable {
        /// Erase OK.
        ok: bool,
    },
    /// $F4: flash checksum.
    FlashChecksum {
        /// Checksum.
        checksum: u16,
    },
    /// $F5: seven flash bytes.
    FlashData {
        /// Data.
        data: [u8; 7],
    },
    /// $F6: P0 = 1 when writing went well.
    EepromWrite {
        /// Write OK.
        ok: bool,
    },
    /// $F7: P0 as tabled ("1=writing successful"; the manual tables no value for the read).
    EepromRead {
        /// P0 = 1.
        ok: bool,
    },
}

impl Reply {
    /// The instruction code this reply answers.
    pub const fn command(&self) -> Command {
        match self {
            Self::Position { .. } => Command::QueryPosition,
            Self::Velocity { .. } => Command::QueryVelocity,
            Self::Actions { .. } => Command::QueryActions,
            Self::Input { .. } => Command::ReadInput,
            Self::UnitInfo { .. } => Command::UnitInfo,
            Self::CanRs232 { .. } => Command::CanRs232,
            Self::PowerDown { .. } => Command::PowerDown,
            Self::FlashEnable { .. } => Command::FlashEnable,
            Self::FlashChecksum { .. } => Command::FlashChecksum,
            Self::FlashData { .. } => Command::FlashRead,
            Self::EepromWrite { .. } => Command::EepromWrite,
            Self::EepromRead { .. } => Command::EepromRead,
        }
    }

    /// Checks the parameters against their tabled ranges.
    pub fn validate(&self) -> Result<(), Error> {
        match *self {
            Self::Position { motor, .. } | Self::Velocity { motor, .. } => {
                check_motor(motor).map(|_| ())
            }
            Self::Input { channel, value, .. } => {
                if channel > MAX_CHANNEL {
                    Err(Error::OutOfRange { field: "channel" })
                } else if value > MAX_ANALOG {
                    Err(Error::OutOfRange {
                        field: "analogue value",
                    })
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }

    /// Writes P0..P6 (unused bytes zero). Validates first.
    pub fn encode_params(&self) -> Result<[u8; PARAMS], Error> {
        self.validate()?;
        let mut p = [0u8; PARAMS];
        match *self {
            Self::Position {
                motor,
                position,
                action,
                stopped,
            } => {
                p[0] = motor;
                put(&mut p, 1, &position.to_le_bytes());
                p[5] = action.to_u8();
                p[6] = u8::from(stopped);
            }
            Self::Velocity {
                motor,
                velocity,
                action,
            } => {
                p[0] = motor;
                put(&mut p, 1, &velocity.to_le_bytes());
                p[3] = action.to_u8();
            }
            Self::Actions { actions } => {
                for (slot, a) in p.iter_mut().zip(actions) {
                    *slot = a.to_u8();
                }
            }
            Self::Input {
                channel,
                value,
                reference,
                inputs,
                ttlio1,
            } => {
                p[0] = channel;
                put(&mut p, 1, &value.to_le_bytes());
                p[3] = u8::from(reference);
                p[4] = inputs.bits();
                p[5] = u8::from(ttlio1);
            }
            Self::UnitInfo {
                firmware,
                reset,
                temperature,
                serial,
            } => {
                p[0] = firmware;
                p[1] = u8::from(reset);
                p[2] = temperature.to_le_bytes()[0];
                put(&mut p, 3, &serial.to_le_bytes());
            }
            Self::CanRs232 { tx_pending, cts } => {
                p[0] = tx_pending;
                p[1] = u8::from(cts);
            }
            Self::PowerDown { status } => p[0] = status.bits(),
            Self::FlashEnable { ok } | Self::EepromWrite { ok } | Self::EepromRead { ok } => {
                p[0] = u8::from(ok);
            }
            Self::FlashChecksum { checksum } => put(&mut p, 0, &checksum.to_le_bytes()),
            Self::FlashData { data } => p = data,
        }
        Ok(p)
    }

    /// Parses P0..P6 of a reply to `command`.
    pub fn decode_params(command: Command, p: &[u8; PARAMS]) -> Result<Self, Error> {
        let action = |i| Action::from_u8(byte(p, i));
        let reply = match command {
            Command::QueryPosition => Self::Position {
                motor: byte(p, 0),
                position: i32_at(p, 1),
                action: action(5),
                stopped: bit0(p, 6),
            },
            Command::QueryVelocity => Self::Velocity {
                motor: byte(p, 0),
                velocity: i16_at(p, 1),
                action: action(3),
            },
            Command::QueryActions => Self::Actions {
                actions: [
                    action(0),
                    action(1),
                    action(2),
                    action(3),
                    action(4),
                    action(5),
                ],
            },
            Command::ReadInput => Self::Input {
                channel: byte(p, 0),
                value: u16_at(p, 1),
                reference: bit0(p, 3),
                inputs: RefInputs::from_bits_retain(byte(p, 4)),
                ttlio1: bit0(p, 5),
            },
            Command::UnitInfo => Self::UnitInfo {
                firmware: byte(p, 0),
                reset: bit0(p, 1),
                temperature: i8::from_le_bytes([byte(p, 2)]),
                serial: u16_at(p, 3),
            },
            Command::CanRs232 => Self::CanRs232 {
                tx_pending: byte(p, 0),
                cts: bit0(p, 1),
            },
            Command::PowerDown => Self::PowerDown {
                status: PowerDownStatus::from_bits_retain(byte(p, 0)),
            },
            Command::FlashEnable => Self::FlashEnable {
                ok: byte(p, 0) == 1,
            },
            Command::FlashChecksum => Self::FlashChecksum {
                checksum: u16_at(p, 0),
            },
            Command::FlashRead => Self::FlashData { data: *p },
            Command::EepromWrite => Self::EepromWrite {
                ok: byte(p, 0) == 1,
            },
            Command::EepromRead => Self::EepromRead {
                ok: byte(p, 0) == 1,
            },
            other => return Err(Error::NoReply(other.code())),
        };
        reply.validate()?;
        Ok(reply)
    }
}

word_frame! {
    /// A whole reply word: the response address given in the request, the command, P0..P6.
    ReplyFrame {
        /// The response address the request carried.
        address,
        /// The reply.
        reply: Reply,
    }
    /// A reply sent to `address`.
    new
}
