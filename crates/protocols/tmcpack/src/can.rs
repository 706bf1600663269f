//! The CAN 2.0A form of the protocol (manual 6.2, 6.3).
//!
//! Telegrams have a fixed length of 8 bytes: the command and P0..P6 (the 9-byte word without
//! its address). The 11-bit identifier is the 8-bit address shifted left by 3; the lower three
//! bits are `000` for commands and responses (a response goes to the response address shifted
//! the same way) and `001` for bytes to forward to the pack's RS-232 port. Address 0 is not
//! valid on CAN, so identifiers run from $008 to $7F8.
//!
//! The manual's words (6.2): "Telegrams with a fixed length of 8 bytes are used. The address
//! of the unit (upper 8 address bits) can be set via rotary switches (scanned on reset). The
//! lower 3 address bits are fixed to "000". Take care: According to the CAN standard 0 is no
//! valid address! Address range: $008 to $7F8 (in increments of 8)." and "The CAN response
//! address is transferred to PACK in a 8 bit format, like at RS 232 / 485. For responding
//! the address is shifted to the left by 3 bits, resulting in the same address range as
//! defined above." So a query's P0 is the same 8-bit response address as on RS-232, and
//! the answer comes with the identifier `response address << 3`; a telegram's 8 data bytes
//! are the RS-232 word without its address byte (command, P0..P6).
//!
//! The pack "has an internal cache for 16 CAN-commands, internal processing time is approx.
//! 2 ms per command" ([`CAN_CACHE_COMMANDS`], [`CAN_COMMAND_TIME`]): a host that sends
//! faster than that fills the cache, and a 17th command has nowhere to go.

use core::time::Duration;

use crate::{CanBitrate, Error, FRAME_LEN, ReplyFrame, RequestFrame, Word};

/// Length of a command or response telegram.
pub const CAN_LEN: usize = 8;

/// The lowest identifier of a pack (address 1): "Address range: $008 to $7F8".
pub const CAN_ID_MIN: u16 = 0x008;

/// The highest identifier of a pack (address 255).
pub const CAN_ID_MAX: u16 = 0x7F8;

/// Commands the pack's CAN cache holds (manual 6.2: "an internal cache for 16
/// CAN-commands").
pub const CAN_CACHE_COMMANDS: usize = 16;

/// The pack's processing time per CAN command (manual 6.2: "approx. 2 ms per command").
pub const CAN_COMMAND_TIME: Duration = Duration::from_millis(2);

/// The bit rate with no jumper set: "250 kbit/s (default)" ([`CanBitrate`] has the table).
pub const CAN_DEFAULT_BITRATE: u32 = CanBitrate::Kbit250.bits_per_second();

/// One CAN 2.0A data frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    /// 11-bit identifier.
    pub id: u16,
    /// Data length 0..=8.
    pub len: u8,
    /// Data bytes (only `len` are meaningful).
    pub data: [u8; 8],
}

/// What the lower three identifier bits say a telegram is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CanChannel {
    /// `000`: a command (or a response, when sent by a pack).
    Command,
    /// `001`: bytes to forward to the RS-232 port.
    Rs232,
}

/// The identifier for an 8-bit address and channel.
pub const fn can_id(address: u8, channel: CanChannel) -> Result<u16, Error> {
    if address == 0 {
        return Err(Error::InvalidCanId(0));
    }
    let low = match channel {
        CanChannel::Command => 0,
        CanChannel::Rs232 => 1,
    };
    Ok(((address as u16) << 3) | low)
}

/// The command identifier of the pack (or the response identifier of the host) at the 8-bit
/// `address`: `address << 3`, in $008..=$7F8. Address 0 is refused ("According to the CAN
/// standard 0 is no valid address!").
pub const fn can_command_id(address: u8) -> Result<u16, Error> {
    can_id(address, CanChannel::Command)
}

/// The 8-bit address and channel of an identifier.
pub const fn split_can_id(id: u16) -> Result<(u8, CanChannel), Error> {
    let address = (id >> 3) as u8;
    if id > 0x7FF || address == 0 {
        return Err(Error::InvalidCanId(id));
    }
    match id & 7 {
        0 => Ok((address, CanChannel::Command)),
        1 => Ok((address, CanChannel::Rs232)),
        _ => Err(Error::InvalidCanId(id)),
    }
}

impl CanFrame {
    /// The payload bytes.
    pub fn payload(&self) -> &[u8] {
        self.data.get(..usize::from(self.len)).unwrap_or(&self.data)
    }

    /// 1..=8 bytes for the RS-232 port of the pack at `address` (manual 6.3).
    pub fn rs232_forward(address: u8, bytes: &[u8]) -> Result<Self, Error> {
        if bytes.is_empty() || bytes.len() > CAN_LEN {
            return Err(Error::WrongLength {
                expected: CAN_LEN,
                got: bytes.len(),
            });
        }
        let mut data = [0u8; 8];
        data.get_mut(..bytes.len())
            .unwrap_or(&mut [])
            .copy_from_slice(bytes);
        Ok(Self {
            id: can_id(address, CanChannel::Rs232)?,
            len: bytes.len() as u8,
            data,
        })
    }

    fn from_word(w: &Word) -> Result<Self, Error> {
        let mut data = [0u8; 8];
        data.copy_from_slice(&w[1..]);
        Ok(Self {
            id: can_id(w[0], CanChannel::Command)?,
            len: CAN_LEN as u8,
            data,
        })
    }

    fn to_word(self) -> Result<Word, Error> {
        if usize::from(self.len) != CAN_LEN {
            return Err(Error::WrongLength {
                expected: CAN_LEN,
                got: usize::from(self.len),
            });
        }
        let (address, channel) = split_can_id(self.id)?;
        if channel != CanChannel::Command {
            return Err(Error::InvalidCanId(self.id));
        }
        let mut w = [0u8; FRAME_LEN];
        w[0] = address;
        w[1..].copy_from_slice(&self.data);
        Ok(w)
    }
}

impl RequestFrame {
    /// The CAN telegram for this request (identifier = address << 3).
    pub fn to_can(&self) -> Result<CanFrame, Error> {
        CanFrame::from_word(&self.to_word()?)
    }

    /// The request a CAN command telegram carries.
    pub fn from_can(frame: &CanFrame) -> Result<Self, Error> {
        Self::decode(&frame.to_word()?)
    }
}

impl ReplyFrame {
    /// The CAN telegram for this reply (identifier = response address << 3).
    pub fn to_can(&self) -> Result<CanFrame, Error> {
        CanFrame::from_word(&self.to_word()?)
    }

    /// The reply a CAN response telegram carries.
    pub fn from_can(frame: &CanFrame) -> Result<Self, Error> {
        Self::decode(&frame.to_word()?)
    }
}

/// The pack's cache of CAN commands (manual 6.2: "an internal cache for 16 CAN-commands,
/// internal processing time is approx. 2 ms per command"), as a timing model both sides
/// use: the simulator holds the telegrams in it and executes each when its processing ends;
/// the driver mirrors it with `T = ()` to know how full the pack's cache is and when an
/// answer can come.
///
/// Our reading: the cache holds every command not yet processed, the one in process
/// included; the pack takes them in arrival order, each [`CAN_COMMAND_TIME`] from the end
/// of the previous one (or from its own arrival, when the pack was idle); a telegram that
/// arrives while 16 wait has nowhere to go and is lost. A command's effect, and its answer,
/// come at the end of its processing.
///
/// ```
/// use core::time::Duration;
/// use tmcpack::{CAN_CACHE_COMMANDS, CanCache};
///
/// let mut cache = CanCache::<u32>::new();
/// let t0 = Duration::from_millis(10);
/// for n in 0..CAN_CACHE_COMMANDS as u32 {
///     assert_eq!(cache.push(t0, n), Ok(t0 + Duration::from_millis(2 * u64::from(n) + 2)));
/// }
/// assert_eq!(cache.push(t0, 99), Err(99), "the 17th has nowhere to go");
/// assert_eq!(cache.pop_done(t0 + Duration::from_millis(2)), Some((t0 + Duration::from_millis(2), 0)));
/// assert_eq!(cache.pop_done(t0 + Duration::from_millis(3)), None);
/// assert_eq!(cache.waiting(t0 + Duration::from_millis(3)), 15);
/// ```
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct CanCache<T: Copy> {
    slots: [Option<(Duration, T)>; CAN_CACHE_COMMANDS],
    head: usize,
    len: usize,
    /// When the newest command's processing ends.
    last_done: Duration,
    command_time: Duration,
    dropped: u64,
}

impl<T: Copy> Default for CanCache<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Copy> CanCache<T> {
    /// An empty cache processing a command in [`CAN_COMMAND_TIME`].
    pub const fn new() -> Self {
        Self::with_command_time(CAN_COMMAND_TIME)
    }

    /// An empty cache with another processing time per command (a slower firmware).
    pub const fn with_command_time(command_time: Duration) -> Self {
        Self {
            slots: [None; CAN_CACHE_COMMANDS],
            head: 0,
            len: 0,
            last_done: Duration::ZERO,
            command_time,
            dropped: 0,
        }
    }

    /// The processing time per command.
    pub const fn command_time(&self) -> Duration {
        self.command_time
    }

    /// Commands taken in and not yet popped.
    pub const fn len(&self) -> usize {
        self.len
    }

    /// `true` when nothing is cached.
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Telegrams lost because the cache was full.
    pub const fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Commands whose processing has not ended at `now`: how full the cache is.
    pub fn waiting(&self, now: Duration) -> usize {
        self.iter().filter(|(done, _)| *done > now).count()
    }

    /// When the processing of everything cached ends (`now` when nothing waits).
    pub fn idle_at(&self, now: Duration) -> Duration {
        if self.waiting(now) == 0 {
            now
        } else {
            self.last_done
        }
    }

    /// When a command arriving at `now` would be processed: its end of processing.
    pub fn done_if_pushed(&self, now: Duration) -> Duration {
        self.idle_at(now).max(now).saturating_add(self.command_time)
    }

    /// When the cache has room again for one more command, if it is full at `now`: the end
    /// of processing of the oldest command that waits.
    pub fn room_at(&self, now: Duration) -> Duration {
        self.fewer_than_at(now, CAN_CACHE_COMMANDS)
    }

    /// The earliest instant from `now` on at which fewer than `n` commands wait (`now` when
    /// that is already so; `n` of 0 is taken as 1).
    pub fn fewer_than_at(&self, now: Duration, n: usize) -> Duration {
        let n = n.max(1);
        let waiting = self.waiting(now);
        if waiting < n {
            return now;
        }
        // The commands wait in order of their ends: once `waiting - n + 1` of them are
        // done, `n - 1` are left.
        self.iter()
            .map(|(done, _)| done)
            .filter(|done| *done > now)
            .nth(waiting - n)
            .unwrap_or(now)
    }

    fn iter(&self) -> impl Iterator<Item = (Duration, T)> + '_ {
        (0..self.len).filter_map(move |i| {
            self.slots
                .get((self.head + i) % CAN_CACHE_COMMANDS)
                .copied()
                .flatten()
        })
    }

    /// A command arrived at `at`: returns when its processing ends, or gives it back when
    /// the cache is full (16 commands still in process at `at`). Commands done by `at` but
    /// not popped yet leave room: the caller pops them before it acts on this one.
    pub fn push(&mut self, at: Duration, item: T) -> Result<Duration, T> {
        if self.waiting(at) >= CAN_CACHE_COMMANDS {
            self.dropped += 1;
            return Err(item);
        }
        if self.len == CAN_CACHE_COMMANDS {
            // Full of commands already done: the oldest is forgotten unpopped (a caller that
            // mirrors the timing only never pops).
            self.head = (self.head + 1) % CAN_CACHE_COMMANDS;
            self.len -= 1;
        }
        let done = self.done_if_pushed(at);
        self.last_done = done;
        if let Some(slot) = self
            .slots
            .get_mut((self.head + self.len) % CAN_CACHE_COMMANDS)
        {
            *slot = Some((done, item));
        }
        self.len += 1;
        Ok(done)
    }

    /// The oldest command whose processing ended at or before `now`, with that instant.
    pub fn pop_done(&mut self, now: Duration) -> Option<(Duration, T)> {
        let slot = self.slots.get_mut(self.head)?;
        match *slot {
            Some((done, item)) if self.len > 0 && done <= now => {
                *slot = None;
                self.head = (self.head + 1) % CAN_CACHE_COMMANDS;
                self.len -= 1;
                Some((done, item))
            }
            _ => None,
        }
    }

    /// When the oldest command's processing ends, if one is cached.
    pub fn next_done(&self) -> Option<Duration> {
        self.iter().next().map(|(done, _)| done)
    }

    /// Forgets everything (a reset of the pack, or of the driver's view of it).
    pub fn clear(&mut self) {
        self.slots = [None; CAN_CACHE_COMMANDS];
        self.head = 0;
        self.len = 0;
        self.last_done = Duration::ZERO;
    }
}
