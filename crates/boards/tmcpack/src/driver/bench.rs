//! The unit tests' bench: one driver, a fake clock, and a hand-played pack.

use core::time::Duration;

use tmcpack::{Action, Reply, ReplyFrame, Request, RequestFrame};

use super::*;

pub(super) const MS: Duration = Duration::from_millis(1);

pub(super) struct Bench {
    pub driver: TmcpackDriver,
    pub now: Duration,
    /// How `serve` answers `$30` (its channel is replaced by the one asked for).
    pub input: Reply,
}

pub(super) fn channel() -> TmcpackChannel {
    TmcpackChannel {
        max_velocity: 32_000.0,
        max_accel: 160_000.0,
        ..TmcpackChannel::default()
    }
}

pub(super) fn config() -> TmcpackDriverConfig {
    let mut channels = [None; 6];
    channels[0] = Some(channel());
    channels[2] = Some(TmcpackChannel {
        max_velocity: 1600.0,
        max_accel: 6400.0,
        ..TmcpackChannel::default()
    });
    TmcpackDriverConfig {
        channels,
        ..TmcpackDriverConfig::default()
    }
}

pub(super) fn word(reply: Reply) -> [u8; 9] {
    ReplyFrame::new(0xFE, reply).to_word().expect("valid reply")
}

pub(super) fn position(motor: u8, position: i32, action: Action) -> [u8; 9] {
    word(Reply::Position {
        motor,
        position,
        action,
        stopped: false,
    })
}

pub(super) const UNIT_INFO: [u8; 9] = [0xFE, 0x43, 149, 1, 35, 0xE9, 0x03, 0, 0];

impl Bench {
    pub fn new(config: TmcpackDriverConfig) -> Self {
        Self {
            driver: TmcpackDriver::new(config),
            now: Duration::ZERO,
            input: Reply::Input {
                channel: 0,
                value: 0,
                reference: false,
                inputs: tmcpack::RefInputs::EMPTY,
                ttlio1: false,
            },
        }
    }

    /// One tick: timeouts, then at most one message.
    pub fn tick(&mut self) -> Option<[u8; 9]> {
        self.driver.handle_timeout(self.now);
        let mut buf = [0u8; 256];
        let out = if self.driver.wants_transmit(self.now).is_some()
            && let Some(t) = self.driver.poll_transmit(self.now, &mut buf)
        {
            assert_eq!(t.len, 9);
            assert!(t.expects_reply, "every request reserves the bus");
            let mut w = [0u8; 9];
            w.copy_from_slice(&buf[..9]);
            Some(w)
        } else {
            None
        };
        self.now += MS;
        out
    }

    /// Ticks until the driver sends something (at most `limit` ticks).
    pub fn next(&mut self, limit: u32) -> Option<(Duration, [u8; 9])> {
        for _ in 0..limit {
            let at = self.now;
            if let Some(w) = self.tick() {
                return Some((at, w));
            }
        }
        None
    }

    pub fn request(&mut self) -> Request {
        let (_, w) = self.next(1000).expect("a request");
        RequestFrame::decode(&w).expect("decodes").request
    }

    pub fn rx(&mut self, bytes: &[u8]) {
        self.driver.handle_rx(self.now, bytes);
    }

    /// Answers `$43` and the `$28` survey (every motor inactive) and lets the start-up
    /// run; returns the configuration requests.
    pub fn online(&mut self) -> Vec<Request> {
        let (_, w) = self.next(10).expect("$43");
        assert_eq!(w, [0x01, 0x43, 0xFE, 0, 0, 0, 0, 0, 0]);
        self.now += 11 * MS;
        self.rx(&UNIT_INFO);
        self.survey([Action::Inactive; 6]);
        self.configure()
    }

    /// Lets the configuration run until the driver is online; returns its requests.
    pub fn configure(&mut self) -> Vec<Request> {
        let mut sent = Vec::new();
        for _ in 0..100 {
            if self.driver.status().online {
                return sent;
            }
            sent.push(self.request());
        }
        panic!("not online after {sent:?}");
    }

    /// Answers the `$28` survey with `actions`.
    pub fn survey(&mut self, actions: [Action; 6]) {
        let (_, w) = self.next(20).expect("$28");
        // Manual 8.4 $28: P0 response address, P1 mask for delayed response (none).
        assert_eq!(w, [0x01, 0x28, 0xFE, 0, 0, 0, 0, 0, 0]);
        self.now += 11 * MS;
        self.rx(&word(Reply::Actions { actions }));
    }

    /// Answers every `$20` poll with `answer(motor)` until `done`, at most `limit` ticks.
    pub fn serve(&mut self, limit: u32, mut answer: impl FnMut(u8) -> [u8; 9]) -> Vec<Request> {
        let mut sent = Vec::new();
        for _ in 0..limit {
            if let Some(w) = self.tick() {
                let request = RequestFrame::decode(&w).expect("decodes").request;
                match request {
                    Request::QueryActions { .. } => {
                        self.now += 10 * MS;
                        self.rx(&word(Reply::Actions {
                            actions: [Action::Inactive; 6],
                        }));
                    }
                    Request::QueryPosition { motor, .. } => {
                        self.now += 10 * MS;
                        let reply = answer(motor);
                        self.rx(&reply);
                    }
                    Request::ReadInput { channel: asked, .. } => {
                        self.now += 10 * MS;
                        let mut reply = self.input;
                        if let Reply::Input { channel, .. } = &mut reply {
                            *channel = asked;
                        }
                        self.rx(&word(reply));
                    }
                    Request::UnitInfo { .. } => {
                        self.now += 10 * MS;
                        let mut info = UNIT_INFO;
                        info[3] = 0;
                        self.rx(&info);
                    }
                    _ => {}
                }
                sent.push(request);
            }
        }
        sent
    }
}
