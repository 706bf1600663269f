//! The simulated AS-2 ([`ExampleSim`]): the firmware's answers on the serial wire, byte
//! for byte through [`crate::codec`], and two steppers with constant-acceleration
//! profiles. It implements [`StreamDevice`]; the simulated link charges the wire time of
//! every byte both ways. The model reads no clock: it is deterministic under the times it
//! is given and [`ExampleSimConfig::seed`].
//!
//! ```
//! use core::time::Duration;
//! use motion_link::sim::StreamDevice;
//! use board_example::sim::{ExampleSim, ExampleSimConfig};
//!
//! let mut board = ExampleSim::new(ExampleSimConfig::default());
//! board.receive(Duration::ZERO, b"?\r");
//! let mut out = [0u8; 64];
//! // The answer starts after the 200 µs processing time.
//! assert_eq!(board.transmit(Duration::from_micros(199), &mut out), 0);
//! let n = board.transmit(Duration::from_micros(200), &mut out);
//! assert_eq!(&out[..n], b"AS2 1.4\r");
//! ```
//!
//! A request is executed when its `\r` arrives; its reply starts
//! [`ExampleSimConfig::processing_delay`] later (plus up to
//! [`ExampleSimConfig::jitter`], drawn from the seed), after the previous reply has left.
//! A line that is no request answers `E1`, a channel other than 0 and 1 `E2`, a value out
//! of range `E3`. A request begun before the previous reply had left the board ("One
//! request at a time") is counted ([`ExampleSimStats::interlaced`]).

mod stepper;

use core::time::Duration;
use std::collections::VecDeque;

use motion_link::sim::StreamDevice;

use crate::codec::{
    BoardError, CHANNELS, CodecError, LineDecoder, MAX_LINE, Reply, Request, Version,
};

use stepper::Stepper;

/// How the simulated board behaves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExampleSimConfig {
    /// From a request's `\r` to the start of its reply.
    pub processing_delay: Duration,
    /// Up to this much more, drawn per request from `seed`.
    pub jitter: Duration,
    /// The seed of the jitter.
    pub seed: u64,
    /// The firmware version `?` reports.
    pub version: &'static str,
}

impl Default for ExampleSimConfig {
    fn default() -> Self {
        Self {
            processing_delay: Duration::from_micros(200),
            jitter: Duration::ZERO,
            seed: 0,
            version: "1.4",
        }
    }
}

/// Counters of what the model did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExampleSimStats {
    /// Lines received (requests and bad lines).
    pub lines: u64,
    /// `E<n>` answers.
    pub errors: u64,
    /// Requests whose first byte began before the reply to the previous one had left the
    /// board: "One request at a time: the host waits for the reply before it sends the
    /// next" (README "Commands"). Counted, and executed in turn.
    pub interlaced: u64,
}

/// A reply waiting for its processing time.
#[derive(Debug, Clone, Copy)]
struct Scheduled {
    at: Duration,
    bytes: [u8; MAX_LINE],
    len: usize,
}

/// A simulated AS-2 two-channel stepper controller. See the module docs.
#[derive(Debug, Clone)]
pub struct ExampleSim {
    config: ExampleSimConfig,
    version: Version,
    rng: u64,
    lines: LineDecoder,
    /// The model's time (`None` until the first call).
    t: Option<Duration>,
    steppers: [Stepper; CHANNELS],
    scheduled: VecDeque<Scheduled>,
    /// Bytes of replies whose transmission has started, not yet handed to the link.
    started: VecDeque<u8>,
    /// The line's rate, as the link says ([`StreamDevice::line_rate`]).
    baud: u32,
    /// When the last reply will have left the board.
    reply_end: Duration,
    stats: ExampleSimStats,
}

impl ExampleSim {
    /// A board just powered up: both channels at step 0, holding.
    ///
    /// # Panics
    /// When `config.version` is no valid version (1..=16 printable ASCII bytes).
    #[must_use]
    pub fn new(config: ExampleSimConfig) -> Self {
        let version = Version::new(config.version)
            .unwrap_or_else(|_| panic!("firmware version {:?} is invalid", config.version));
        Self {
            config,
            version,
            rng: config.seed | 1,
            lines: LineDecoder::new(),
            t: None,
            steppers: [Stepper::new(); CHANNELS],
            scheduled: VecDeque::new(),
            started: VecDeque::new(),
            baud: crate::driver::DEFAULT_BAUD,
            reply_end: Duration::ZERO,
            stats: ExampleSimStats::default(),
        }
    }

    /// What the model did so far.
    #[must_use]
    pub fn stats(&self) -> ExampleSimStats {
        self.stats
    }

    /// Channel `channel`'s position counter, steps (a test's view of the shaft).
    #[must_use]
    pub fn position(&self, channel: usize) -> Option<i32> {
        self.steppers.get(channel).map(|s| s.position())
    }

    /// One 8N1 byte at the line's rate.
    fn byte_time(&self) -> Duration {
        Duration::from_nanos(10_000_000_000 / u64::from(self.baud.max(1)))
    }

    fn advance(&mut self, now: Duration) {
        let from = *self.t.get_or_insert(now);
        if now > from {
            let seconds = (now - from).as_secs_f64();
            for stepper in &mut self.steppers {
                stepper.advance(seconds);
            }
            self.t = Some(now);
        }
    }

    /// The next jitter, xorshift64 on the seed.
    fn jitter(&mut self) -> Duration {
        self.rng ^= self.rng << 13;
        self.rng ^= self.rng >> 7;
        self.rng ^= self.rng << 17;
        let nanos = self.config.jitter.as_nanos() as u64;
        Duration::from_nanos(if nanos == 0 {
            0
        } else {
            self.rng % (nanos + 1)
        })
    }

    /// Executes one received line; its reply.
    fn execute(&mut self, parsed: Result<Request, CodecError>) -> Reply {
        let request = match parsed {
            Ok(request) => request,
            Err(CodecError::OutOfRange) => return Reply::Error(BoardError::OutOfRange),
            Err(_) => return Reply::Error(BoardError::Syntax),
        };
        let Some(channel) = request.channel() else {
            return Reply::Identity(self.version);
        };
        let Some(stepper) = self.steppers.get_mut(usize::from(channel)) else {
            return Reply::Error(BoardError::NoSuchChannel);
        };
        match request {
            Request::Identify => Reply::Identity(self.version),
            Request::Position { channel } => Reply::Position {
                channel,
                position: stepper.position(),
                velocity: stepper.velocity(),
                motion: stepper.motion(),
            },
            Request::Move {
                target,
                speed,
                accel,
                ..
            } => {
                stepper.go_to(target, speed, accel);
                Reply::Done
            }
            Request::Jog {
                velocity, accel, ..
            } => {
                stepper.jog(velocity, accel);
                Reply::Done
            }
            Request::Stop { decel, .. } => {
                stepper.stop(decel);
                Reply::Done
            }
            Request::SetPosition { position, .. } => {
                stepper.set_position(position);
                Reply::Done
            }
            Request::Off { .. } => {
                stepper.off();
                Reply::Done
            }
        }
    }
}

impl StreamDevice for ExampleSim {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.advance(now);
        for &byte in bytes {
            let starts = self.lines.is_idle() && !matches!(byte, b'\n' | 0 | crate::codec::END);
            // The byte began one byte time (10 bits) before it arrived.
            if starts && now.saturating_sub(self.byte_time()) < self.reply_end {
                self.stats.interlaced += 1;
            }
            let parsed = match self.lines.push(byte) {
                None => continue,
                Some(line) => line.and_then(Request::parse),
            };
            self.stats.lines += 1;
            let reply = self.execute(parsed);
            if matches!(reply, Reply::Error(_)) {
                self.stats.errors += 1;
            }
            let mut bytes = [0u8; MAX_LINE];
            // Every reply fits a line (MAX_LINE).
            let len = reply.encode(&mut bytes).unwrap_or(0);
            // Replies leave in request order, whatever the jitter drew.
            let earliest = self.scheduled.back().map_or(Duration::ZERO, |s| s.at);
            let at = (now + self.config.processing_delay + self.jitter()).max(earliest);
            // Its bytes leave after the previous reply's (the link charges the wire time).
            self.reply_end =
                at.max(self.reply_end) + self.byte_time() * u32::try_from(len).unwrap_or(u32::MAX);
            self.scheduled.push_back(Scheduled { at, bytes, len });
        }
    }

    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.advance(now);
        while let Some(next) = self.scheduled.front().filter(|s| s.at <= now).copied() {
            self.scheduled.pop_front();
            self.started.extend(&next.bytes[..next.len]);
        }
        let count = out.len().min(self.started.len());
        for (slot, byte) in out.iter_mut().zip(self.started.drain(..count)) {
            *slot = byte;
        }
        count
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        if self.started.is_empty() {
            self.scheduled.front().map(|s| s.at.max(now))
        } else {
            Some(now)
        }
    }

    fn line_rate(&mut self, baud: u32) {
        self.baud = baud.max(1);
    }
}

#[cfg(test)]
mod tests;
