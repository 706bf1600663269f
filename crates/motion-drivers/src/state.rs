//! What a driver knows about its board and channels.

use core::time::Duration;

/// A fault a driver reports for its board or one channel.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceFault {
    /// The link is down.
    LinkDown,
    /// The board did not answer within its reply budget (several times in a row).
    NotResponding,
    /// The board rebooted (reset flag, version re-read, unexpected start-up state): goals
    /// were lost and need a new command.
    Reset,
    /// The board answered a request with an error status.
    BoardError,
    /// Replies could not be decoded for too long.
    Protocol,
    /// The board reported overspeed or an encoder glitch.
    Overspeed,
    /// A limit or reference switch stopped the channel.
    LimitSwitch,
    /// A reference search ended without finding its switch or index (travel limit
    /// reached, the board reported a search error).
    HomeFailed,
}

/// The state of one channel, in counts, as last reported by the board.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct ChannelState {
    /// Measured (or, for open-loop steppers, commanded) position, counts.
    pub position: f64,
    /// Velocity, counts/s.
    pub velocity: f64,
    /// The board's own position register, counts.
    pub raw_counts: i64,
    /// When fresh data last arrived from the board for this channel (`None`: never).
    pub refreshed_at: Option<Duration>,
    /// The channel is moving.
    pub moving: bool,
    /// The channel has a reference (homed or position set).
    pub homed: bool,
    /// A limit or reference switch is active.
    pub at_limit: bool,
    /// The last position goal has been reached (board's own criterion or the driver's).
    pub arrived: bool,
    /// A fault on this channel (or its board).
    pub fault: Option<DeviceFault>,
}

impl ChannelState {
    /// A channel never heard from.
    pub const UNKNOWN: Self = Self {
        position: 0.0,
        velocity: 0.0,
        raw_counts: 0,
        refreshed_at: None,
        moving: false,
        homed: false,
        at_limit: false,
        arrived: false,
        fault: None,
    };
}

impl Default for ChannelState {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

/// Capacity of a verdict's evidence, bytes.
pub const EVIDENCE_LEN: usize = 200;

/// Why a driver declared its board not answering ([`DeviceFault::NotResponding`]) or reset
/// ([`DeviceFault::Reset`]): the proof, in words, for the server's log. A verdict drops the
/// board's goals and starts it again, so it is reached only on evidence a user can check —
/// which request went unanswered, when it was written, when its answer was due and how far
/// the link had been heard past that; or which field of which answer showed the reboot.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct Verdict {
    /// `NotResponding` or `Reset`.
    pub fault: DeviceFault,
    /// When the driver reached it (the `now` it was given).
    pub at: Duration,
    /// The evidence, e.g. "3 requests unanswered in a row since 1.250 s; the last, `$20`
    /// motor 2, written at 1.302 s, due by 1.323 s, the link heard until 1.341 s (18 ms past
    /// due)". Formatted in place (no allocation).
    pub evidence: motion_base::FixedText<EVIDENCE_LEN>,
}

impl Verdict {
    /// A verdict reached at `at`, with its evidence formatted from `args`.
    pub fn new(fault: DeviceFault, at: Duration, args: core::fmt::Arguments<'_>) -> Self {
        let mut evidence = motion_base::FixedText::new();
        let _ = core::fmt::Write::write_fmt(&mut evidence, args);
        Self {
            fault,
            at,
            evidence,
        }
    }
}

/// A duration as seconds with milliseconds (`1.302 s`), for verdicts' evidence.
#[derive(Debug, Clone, Copy)]
pub struct Seconds(pub Duration);

impl core::fmt::Display for Seconds {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}.{:03} s", self.0.as_secs(), self.0.subsec_millis())
    }
}

/// Capacity of a board's firmware description.
pub const FIRMWARE_LEN: usize = 32;

/// What the driver knows about its board as a whole.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceStatus {
    /// The board answered its start-up sequence and has not been declared dead since.
    pub online: bool,
    /// Firmware version as the board reported it, UTF-8, `firmware_len` bytes valid.
    pub firmware: [u8; FIRMWARE_LEN],
    /// Valid bytes in `firmware`.
    pub firmware_len: u8,
    /// A board-level fault.
    pub fault: Option<DeviceFault>,
    /// Replies decoded and accepted, since creation.
    pub replies: u64,
    /// Requests that got no reply in time, since creation.
    pub timeouts: u32,
    /// Replies that could not be decoded or did not match, since creation.
    pub bad_replies: u32,
    /// Times the board was seen to reboot, since creation.
    pub resets: u32,
    /// Verdicts reached since creation (not answering, reset): the server logs each new
    /// one with its evidence.
    pub verdicts: u32,
    /// The newest verdict and its evidence.
    pub verdict: Option<Verdict>,
}

impl DeviceStatus {
    /// Nothing known yet.
    pub const UNKNOWN: Self = Self {
        online: false,
        firmware: [0; FIRMWARE_LEN],
        firmware_len: 0,
        fault: None,
        replies: 0,
        timeouts: 0,
        bad_replies: 0,
        resets: 0,
        verdicts: 0,
        verdict: None,
    };

    /// Records `verdict` (counted; the newest is kept for the log).
    pub fn declare(&mut self, verdict: Verdict) {
        self.verdicts = self.verdicts.saturating_add(1);
        self.verdict = Some(verdict);
    }

    /// The firmware description ("" until known).
    pub fn firmware(&self) -> &str {
        let len = usize::from(self.firmware_len).min(FIRMWARE_LEN);
        core::str::from_utf8(&self.firmware[..len]).unwrap_or("")
    }

    /// Records `text` as the firmware description (cut to [`FIRMWARE_LEN`] bytes on a
    /// character boundary).
    pub fn set_firmware(&mut self, text: &str) {
        let end = motion_base::floor_char_boundary(text, FIRMWARE_LEN);
        motion_base::write_text(&mut self.firmware, &text[..end]);
        self.firmware_len = end as u8;
    }
}

impl Default for DeviceStatus {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

#[cfg(test)]
mod tests {
    use super::{DeviceFault, DeviceStatus, Seconds, Verdict};
    use core::time::Duration;

    #[test]
    fn firmware_text_is_cut_on_char_boundaries() {
        let mut status = DeviceStatus::UNKNOWN;
        status.set_firmware("TMC v1.23");
        assert_eq!(status.firmware(), "TMC v1.23");
        status.set_firmware(&"é".repeat(40));
        assert_eq!(status.firmware(), "é".repeat(16));
    }

    #[test]
    fn a_verdict_carries_its_evidence_and_is_counted() {
        let mut status = DeviceStatus::UNKNOWN;
        let at = Duration::from_millis(1302);
        status.declare(Verdict::new(
            DeviceFault::NotResponding,
            at,
            format_args!(
                "`$20` written at {}, due by {}",
                Seconds(at),
                Seconds(at * 2)
            ),
        ));
        assert_eq!(status.verdicts, 1);
        let verdict = status.verdict.expect("kept");
        assert_eq!(
            verdict.evidence.as_str(),
            "`$20` written at 1.302 s, due by 2.604 s"
        );
        assert_eq!(verdict.fault, DeviceFault::NotResponding);
    }
}
