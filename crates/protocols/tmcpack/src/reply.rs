//! Typed replies (pack → host): the responses tabled in manual section 8.

use crate::request::MAX_CHANNEL;
use crate::types::{Action, PowerDownStatus, RefInputs, check_motor};

use crate::{Command, Error};

/// Highest analogue value ($30: "unsigned 0..1023").
pub const MAX_ANALOG: u16 = 1023;

message_table! {
/// A response, without its address byte. See [`ReplyFrame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Reply {
    /// $20: position and activity.
    Position => QueryPosition {
        /// Motor number.
        motor: u8 = 0,
        /// posact.
        position: i32 = 1,
        /// Current action.
        action: Action = 5,
        /// P6 bit 0: a stop condition has occurred (cleared by the read).
        stopped: bool = 6,
    },
    /// $21: velocity and activity.
    Velocity => QueryVelocity {
        /// Motor number.
        motor: u8 = 0,
        /// vact.
        velocity: i16 = 1,
        /// Current action.
        action: Action = 3,
    },
    /// $28: the actions of all six motors.
    Actions => QueryActions {
        /// P0..P5: motor 0..5.
        actions: [Action; 6] = 0,
    },
    /// $30: an analogue channel and the inputs.
    Input => ReadInput {
        /// Channel 0..=7.
        channel: u8 = 0,
        /// Analogue value 0..=1023.
        value: u16 = 1,
        /// P3 bit 0: the channel's reference input (inverted, as the pack reports it).
        reference: bool = 3,
        /// P4: all reference inputs and the jumpers.
        inputs: RefInputs = 4,
        /// P5 bit 0: logic state at TTLIO1.
        ttlio1: bool = 5,
    },
    /// $43: unit information.
    UnitInfo => UnitInfo {
        /// Firmware revision (148 = V1.4.8).
        firmware: u8 = 0,
        /// Reset flag: 1 at the first read-out after a reset.
        reset: bool = 1,
        /// Temperature in °C.
        temperature: i8 = 2,
        /// Serial number.
        serial: u16 = 3,
    },
    /// $44: RS-232 via CAN status.
    CanRs232 => CanRs232 {
        /// Bytes in the RS-232 send buffer.
        tx_pending: u8 = 0,
        /// P1 bit 0: state of the CTS line (inverted).
        cts: bool = 1,
    },
    /// $45: power-down status.
    PowerDown => PowerDown {
        /// P0 bits.
        status: PowerDownStatus = 0,
    },
    /// $F2: P0 = 1 when erasing went well.
    FlashEnable => FlashEnable {
        /// Erase OK.
        ok: bool = 0 via exact_one,
    },
    /// $F4: flash checksum.
    FlashChecksum => FlashChecksum {
        /// Checksum.
        checksum: u16 = 0,
    },
    /// $F5: seven flash bytes.
    FlashData => FlashRead {
        /// Data.
        data: [u8; 7] = 0,
    },
    /// $F6: P0 = 1 when writing went well.
    EepromWrite => EepromWrite {
        /// Write OK.
        ok: bool = 0 via exact_one,
    },
    /// $F7: P0 as tabled ("1=writing successful"; the manual tables no value for the read).
    EepromRead => EepromRead {
        /// P0 = 1.
        ok: bool = 0 via exact_one,
    },
}
unmatched: |other: Command| Error::NoReply(other.code())
}

impl Reply {
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
