//! The instruction codes of the manual's section 9 table.

use crate::Error;

macro_rules! commands {
    ($($(#[$doc:meta])* $name:ident = $code:literal, reply: $reply:literal;)*) => {
        /// An instruction code of the section 9 instruction table.
        #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum Command {
            $($(#[$doc])* $name = $code,)*
        }

        impl Command {
            /// Every instruction of the table, in table order.
            pub const ALL: &'static [Command] = &[$(Command::$name,)*];

            /// The instruction for a command byte.
            pub const fn from_u8(code: u8) -> Result<Self, Error> {
                match code {
                    $($code => Ok(Self::$name),)*
                    other => Err(Error::UnknownCommand(other)),
                }
            }

            /// `true` when the manual tables a response for this instruction.
            pub const fn has_reply(self) -> bool {
                match self {
                    $(Self::$name => $reply,)*
                }
            }
        }
    };
}

commands! {
    /// $10 Peak current.
    PeakCurrent = 0x10, reply: false;
    /// $11 Current control.
    CurrentControl = 0x11, reply: false;
    /// $12 Velocity setting (clkdiv).
    VelocitySetting = 0x12, reply: false;
    /// $13 Starting velocity.
    StartingVelocity = 0x13, reply: false;
    /// $14 Velocity, acceleration.
    VelocityAcceleration = 0x14, reply: false;
    /// $15 Motor parameters.
    MotorParameters = 0x15, reply: false;
    /// $16 Reference search parameters.
    ReferenceParameters = 0x16, reply: false;
    /// $17 Write motor characteristics table.
    MicrostepTable = 0x17, reply: false;
    /// $18 Null point offset and range.
    NullOffset = 0x18, reply: false;
    /// $19 PI parameters.
    PiParameters = 0x19, reply: false;
    /// $20 Query position and activity.
    QueryPosition = 0x20, reply: true;
    /// $21 Query velocity and activity.
    QueryVelocity = 0x21, reply: true;
    /// $22 Start search of reference.
    ReferenceSearch = 0x22, reply: false;
    /// $23 Start trapezoidal ramp.
    StartRamp = 0x23, reply: false;
    /// $24 Activate PI controller on target position.
    PiTarget = 0x24, reply: false;
    /// $25 Start rotation / change rotation velocity.
    Rotate = 0x25, reply: false;
    /// $26 Set target position.
    SetTarget = 0x26, reply: false;
    /// $27 Set actual position.
    SetPosition = 0x27, reply: false;
    /// $28 Query all motor activities, request delayed response.
    QueryActions = 0x28, reply: true;
    /// $29 Start trapezoidal ramp in parallel.
    StartRampParallel = 0x29, reply: false;
    /// $2A Stop motors selectively or synchronously.
    Stop = 0x2A, reply: false;
    /// $30 Read motor input channels and additional inputs.
    ReadInput = 0x30, reply: true;
    /// $31 Setting the limits for the stop function left/right.
    StopLimits = 0x31, reply: false;
    /// $32 Setting of additional outputs.
    Outputs = 0x32, reply: false;
    /// $33 Function of the ready output.
    ReadyOutput = 0x33, reply: false;
    /// $40 Adjust RS-232 / RS-485 baud rate.
    SetBaud = 0x40, reply: false;
    /// $41 Setting of timeout for abort of packet.
    PacketTimeout = 0x41, reply: false;
    /// $42 Change address of unit.
    SetAddress = 0x42, reply: false;
    /// $43 Read out information about unit.
    UnitInfo = 0x43, reply: true;
    /// $44 Configure / query RS-232 operating mode via CAN.
    CanRs232 = 0x44, reply: true;
    /// $45 Power-down mode.
    PowerDown = 0x45, reply: true;
    /// $CC Complete hardware reset.
    HardwareReset = 0xCC, reply: false;
    /// $50 Start multi-dimensional linear interpolation.
    Interpolate = 0x50, reply: false;
    /// $F2 Enable erasing and writing the flash memory.
    FlashEnable = 0xF2, reply: true;
    /// $F3 Program flash memory.
    FlashProgram = 0xF3, reply: false;
    /// $F4 Query flash memory checksum and abort programming.
    FlashChecksum = 0xF4, reply: true;
    /// $F5 Read out flash memory.
    FlashRead = 0xF5, reply: true;
    /// $F6 Write EEPROM.
    EepromWrite = 0xF6, reply: true;
    /// $F7 Read EEPROM.
    EepromRead = 0xF7, reply: true;
}

impl Command {
    /// The command byte.
    pub const fn code(self) -> u8 {
        self as u8
    }
}
