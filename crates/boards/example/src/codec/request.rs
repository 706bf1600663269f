//! Host → board: [`Request`].

use super::line::{SliceWriter, channel, int, rate, tokens};
use super::{CHANNELS, CodecError, MAX_ACCEL, MAX_SPEED};

/// One request of the host (README "Commands"). Positions in steps, speeds in steps/s,
/// accelerations in steps/s².
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Request {
    /// `?` → `AS2 <version>`.
    Identify,
    /// `P<ch>?` → `P<ch> <position> <velocity> <I|M|O>`.
    Position {
        /// Channel.
        channel: u8,
    },
    /// `M<ch> <target> <speed> <accel>`: go to `target` along a trapezoid → `OK`.
    Move {
        /// Channel.
        channel: u8,
        /// Target, steps.
        target: i32,
        /// Cruise speed, 1..=[`MAX_SPEED`].
        speed: u32,
        /// Acceleration and deceleration, 1..=[`MAX_ACCEL`].
        accel: u32,
    },
    /// `V<ch> <velocity> <accel>`: run at `velocity` (0 ramps to a stop) → `OK`.
    Jog {
        /// Channel.
        channel: u8,
        /// Velocity, |v| ≤ [`MAX_SPEED`].
        velocity: i32,
        /// Acceleration, 1..=[`MAX_ACCEL`].
        accel: u32,
    },
    /// `S<ch> <decel>`: ramp down to standstill and hold → `OK`.
    Stop {
        /// Channel.
        channel: u8,
        /// Deceleration, 1..=[`MAX_ACCEL`].
        decel: u32,
    },
    /// `Z<ch> <position>`: the position counter becomes `position` (no motion) → `OK`.
    SetPosition {
        /// Channel.
        channel: u8,
        /// The new position, steps.
        position: i32,
    },
    /// `O<ch>`: coils off at once, the motor is free → `OK`.
    Off {
        /// Channel.
        channel: u8,
    },
}

impl Request {
    /// The channel the request is for (`None`: the board).
    #[must_use]
    pub const fn channel(&self) -> Option<u8> {
        match *self {
            Self::Identify => None,
            Self::Position { channel }
            | Self::Move { channel, .. }
            | Self::Jog { channel, .. }
            | Self::Stop { channel, .. }
            | Self::SetPosition { channel, .. }
            | Self::Off { channel } => Some(channel),
        }
    }

    /// Whether every value is one the board takes.
    fn in_range(&self) -> bool {
        let speed = |s: u32| (1..=MAX_SPEED).contains(&s);
        let accel = |a: u32| (1..=MAX_ACCEL).contains(&a);
        let channel_ok = self
            .channel()
            .is_none_or(|channel| usize::from(channel) < CHANNELS);
        channel_ok
            && match *self {
                Self::Move {
                    speed: s, accel: a, ..
                } => speed(s) && accel(a),
                Self::Jog {
                    velocity, accel: a, ..
                } => velocity.unsigned_abs() <= MAX_SPEED && accel(a),
                Self::Stop { decel, .. } => accel(decel),
                _ => true,
            }
    }

    /// Writes the request, terminator included, at the start of `buf`; the bytes written.
    ///
    /// # Errors
    /// [`CodecError::OutOfRange`] for a value the board does not take,
    /// [`CodecError::BufferTooSmall`] when `buf` cannot hold the line (40 bytes always do).
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, CodecError> {
        if !self.in_range() {
            return Err(CodecError::OutOfRange);
        }
        let out = SliceWriter::new(buf);
        match *self {
            Self::Identify => out.line(format_args!("?")),
            Self::Position { channel } => out.line(format_args!("P{channel}?")),
            Self::Move {
                channel,
                target,
                speed,
                accel,
            } => out.line(format_args!("M{channel} {target} {speed} {accel}")),
            Self::Jog {
                channel,
                velocity,
                accel,
            } => out.line(format_args!("V{channel} {velocity} {accel}")),
            Self::Stop { channel, decel } => out.line(format_args!("S{channel} {decel}")),
            Self::SetPosition { channel, position } => {
                out.line(format_args!("Z{channel} {position}"))
            }
            Self::Off { channel } => out.line(format_args!("O{channel}")),
        }
    }

    /// The request on `line` (without its terminator), as the board reads it.
    ///
    /// # Errors
    /// [`CodecError::Malformed`] for a line that is no request (the board answers `E1`),
    /// [`CodecError::OutOfRange`] for a value it does not take (`E3`; a channel it does
    /// not have is `E2`, which the board tells apart with [`Request::channel`]).
    pub fn parse(line: &[u8]) -> Result<Self, CodecError> {
        if line == b"?" {
            return Ok(Self::Identify);
        }
        let (&letter, rest) = line.split_first().ok_or(CodecError::Malformed)?;
        let (&digit, rest) = rest.split_first().ok_or(CodecError::Malformed)?;
        let channel = channel(core::str::from_utf8(&[digit]).map_err(|_| CodecError::Malformed)?)?;
        if letter == b'P' {
            return if rest == b"?" {
                Ok(Self::Position { channel })
            } else {
                Err(CodecError::Malformed)
            };
        }
        let mut args = tokens(rest)?;
        // After the channel digit: nothing (O), or a space and the arguments.
        if args.next() != Some("") {
            return Err(CodecError::Malformed);
        }
        let mut next = || args.next().ok_or(CodecError::Malformed);
        let request = match letter {
            b'M' => Self::Move {
                channel,
                target: int(next()?)?,
                speed: rate(next()?, MAX_SPEED)?,
                accel: rate(next()?, MAX_ACCEL)?,
            },
            b'V' => {
                let velocity = int(next()?)?;
                if velocity.unsigned_abs() > MAX_SPEED {
                    return Err(CodecError::OutOfRange);
                }
                Self::Jog {
                    channel,
                    velocity,
                    accel: rate(next()?, MAX_ACCEL)?,
                }
            }
            b'S' => Self::Stop {
                channel,
                decel: rate(next()?, MAX_ACCEL)?,
            },
            b'Z' => Self::SetPosition {
                channel,
                position: int(next()?)?,
            },
            b'O' if rest.is_empty() => return Ok(Self::Off { channel }),
            _ => return Err(CodecError::Malformed),
        };
        if args.next().is_some() {
            return Err(CodecError::Malformed);
        }
        Ok(request)
    }
}
