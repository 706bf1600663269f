//! The test host: sends words with real wire time and follows the device's events.

pub use std::time::Duration;

pub use board_tmcpack::sim::{RefSwitch, TmcpackSim, TmcpackSimConfig};
pub use motion_link::sim::{StreamBus, StreamDevice};
pub use tmcpack::convert::byte_time;
pub use tmcpack::{
    Action, MotorMask, MotorOptions, MotorType, PowerDownRequest, PowerDownStatus, Reply,
    ReplyFrame, Request, RequestFrame, Variant,
};

pub const HOST: u8 = 0xFE;
pub const MS: Duration = Duration::from_millis(1);

/// The pack's first 2 ms firmware cycle at or after `t`: it acts on a word there (its
/// answer starts the switch-over after it).
pub fn cycle(t: Duration) -> Duration {
    let tick = Duration::from_millis(2).as_nanos();
    Duration::from_nanos((t.as_nanos().div_ceil(tick) * tick) as u64)
}

pub fn bt() -> Duration {
    byte_time(19_200)
}

/// A host on the line: sends words byte by byte with real wire time, collects replies.
pub struct Host<D: StreamDevice> {
    pub dev: D,
    pub now: Duration,
    pub bt: Duration,
}

impl<D: StreamDevice> Host<D> {
    pub fn new(dev: D) -> Self {
        Self {
            dev,
            now: Duration::from_secs(10),
            bt: bt(),
        }
    }

    /// Sends a raw word starting now; returns when its last byte arrived.
    pub fn send_raw(&mut self, bytes: &[u8]) -> Duration {
        for b in bytes {
            self.now += self.bt;
            self.dev.receive(self.now, &[*b]);
        }
        self.now
    }

    pub fn send(&mut self, address: u8, req: Request) -> Duration {
        let w = RequestFrame::new(address, req)
            .to_word()
            .expect("valid request");
        self.send_raw(&w)
    }

    /// Follows the device's events until `until`; returns each byte with the instant its
    /// transmission started.
    pub fn collect_until(&mut self, until: Duration) -> Vec<(Duration, u8)> {
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        while let Some(e) = self.dev.next_event(self.now) {
            if e > until {
                break;
            }
            let t = e.max(self.now);
            let n = self.dev.transmit(t, &mut buf);
            got.extend(buf.iter().take(n).map(|b| (t, *b)));
            self.now = if n == 0 && t == self.now {
                t + Duration::from_nanos(1)
            } else {
                t
            };
        }
        self.now = self.now.max(until);
        self.dev.transmit(self.now, &mut buf);
        got
    }

    /// Sends a query and returns the decoded reply and the instant its first byte started.
    pub fn query(&mut self, address: u8, req: Request) -> Option<(Duration, ReplyFrame)> {
        self.send(address, req);
        let got = self.collect_until(self.now + 40 * MS);
        let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
        let first = got.first()?.0;
        Some((first, ReplyFrame::decode(&bytes).expect("one reply word")))
    }

    /// Lets time pass with nothing on the line.
    pub fn wait(&mut self, d: Duration) -> Vec<(Duration, u8)> {
        self.collect_until(self.now + d)
    }
}

pub fn pack() -> Host<TmcpackSim> {
    Host::new(TmcpackSim::new(TmcpackSimConfig::default()))
}

pub fn position(h: &mut Host<TmcpackSim>, motor: u8) -> (i32, Action, bool) {
    match h.query(
        1,
        Request::QueryPosition {
            motor,
            reply_to: HOST,
        },
    ) {
        Some((
            _,
            ReplyFrame {
                reply:
                    Reply::Position {
                        position,
                        action,
                        stopped,
                        ..
                    },
                ..
            },
        )) => (position, action, stopped),
        other => panic!("no position reply: {other:?}"),
    }
}
