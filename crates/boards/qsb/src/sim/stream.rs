//! Streaming reads (`S` commands): which registers stream, the data output timer
//! (INTERVAL RATE), THRESHOLD, and cancellation.

use core::time::Duration;

use qsb::{AnalogSample, EncoderMode, Register, Response, ResponseType, StreamTrigger};

use super::QsbSim;

/// The streamable registers, in the order their lines go out at a tick.
pub(crate) const STREAMABLE: [Register; 5] = [
    Register::DigIo,
    Register::Capture,
    Register::Str,
    Register::ReadEncoder,
    Register::MdStatus,
];

fn slot(register: Register) -> Option<usize> {
    STREAMABLE.iter().position(|r| *r == register)
}

/// Stream state.
#[derive(Debug, Clone, Default)]
pub(crate) struct Streams {
    /// Active streams, by [`STREAMABLE`] slot, with the last value sent (the threshold
    /// reference for READ ENCODER).
    pub active: [Option<u32>; 5],
    /// Next data output tick.
    pub next_tick: Option<Duration>,
}

impl Streams {
    pub(crate) fn any(&self) -> bool {
        self.active.iter().any(Option::is_some)
    }

    pub(crate) fn start(&mut self, register: Register, value: u32) {
        if let Some(s) = slot(register).and_then(|i| self.active.get_mut(i)) {
            *s = Some(value);
        }
    }

    /// A read of a streamed register cancels its stream.
    pub(crate) fn cancel(&mut self, register: Register) {
        if let Some(s) = slot(register).and_then(|i| self.active.get_mut(i)) {
            *s = None;
        }
        if !self.any() {
            self.next_tick = None;
        }
    }

    pub(crate) fn cancel_all(&mut self) {
        self.active = [None; 5];
        self.next_tick = None;
    }
}

impl QsbSim {
    /// The measurement time of one value in the current MODE.
    pub(super) fn measurement_delay(&self) -> Duration {
        if self.regs.mode.encoder == EncoderMode::Analog {
            self.config
                .processing_delay
                .max(qsb::ANALOG_PROCESSING_DELAY)
        } else {
            self.config.processing_delay
        }
    }

    /// The data output period, `None` when INTERVAL RATE disables output.
    pub(super) fn stream_period(&self) -> Option<Duration> {
        self.regs
            .interval
            .period()
            .map(|p| p.max(self.measurement_delay()))
    }

    /// (Re)starts the data output timer at `now` when something streams.
    pub(super) fn restart_stream_timer(&mut self, now: Duration) {
        self.streams.next_tick = if self.streams.any() {
            self.stream_period().map(|p| now.saturating_add(p))
        } else {
            None
        };
    }

    /// The value a stream line carries for `register` at the model time.
    pub(super) fn stream_value(&mut self, register: Register) -> u32 {
        if register == Register::ReadEncoder && self.regs.mode.encoder == EncoderMode::Analog {
            let sample = AnalogSample {
                time_stamp: self.analog_time_stamp(self.t),
                digital: self.dio.pins(),
                analog: self.analog_value(),
            };
            return sample.data();
        }
        self.read_register(register)
    }

    /// One data output tick at the model time.
    pub(super) fn stream_tick(&mut self) {
        let now = self.t;
        let delay = self.measurement_delay();
        // The firmware cannot get ahead of its UART: a sample the line has no room for
        // is not taken.
        let busy = self.output.uart_free > now.saturating_add(delay);
        for (i, register) in STREAMABLE.into_iter().enumerate() {
            let Some(last) = self.streams.active.get(i).copied().flatten() else {
                continue;
            };
            if busy {
                continue;
            }
            let value = self.stream_value(register);
            let send = match register.stream_trigger() {
                Some(StreamTrigger::OnChange) => value != last,
                Some(StreamTrigger::IntervalThreshold) => {
                    let threshold = u32::from(self.regs.threshold);
                    let (a, b) = if self.regs.mode.encoder == EncoderMode::Analog {
                        (value & 0x3FF, last & 0x3FF)
                    } else {
                        (value, last)
                    };
                    threshold == 0 || (a.wrapping_sub(b) as i32).unsigned_abs() >= threshold
                }
                None => false,
            };
            if send {
                if let Some(s) = self.streams.active.get_mut(i) {
                    *s = Some(value);
                }
                let response = Response::new(ResponseType::Stream, register.number(), value);
                self.send(response, now.saturating_add(delay));
            }
        }
        self.streams.next_tick = self.stream_period().map(|p| now.saturating_add(p));
    }
}
