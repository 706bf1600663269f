//! The fake-clock RS-485 line of the window tests: drivers on a `LinkBus`, and packs
//! played by hand from the manual alone (answer after the request's wire time and the
//! switch-over delay programmed with `$40`, manual 6.1), so that one answer can be held to
//! any instant. Every word on the line is recorded, and the line is checked against the
//! manual's rules independently of the driver ([`Line::check_never_interlaced`]).

use core::time::Duration;

use board_tmcpack::driver::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
use motion_drivers::{Driver, LinkBus, LinkKind};
use tmcpack::{Action, Reply, ReplyFrame, Request, RequestFrame, Variant};

pub const MS: Duration = Duration::from_millis(1);
/// The fake clock's step.
pub const STEP: Duration = Duration::from_micros(100);
pub const BAUD: u32 = 19_200;
/// Manual 6.1: a word is 9 bytes; 8N1 is 10 bits a byte: 90 bits at 19200 baud.
pub const WORD: Duration = Duration::from_nanos(90 * 1_000_000_000 / 19_200);
/// Manual 6.2: "internal processing time is approx. 2 ms per command" (read for the serial
/// line too: docs/ARCHITECTURE.md).
pub const PROCESSING: Duration = Duration::from_millis(2);
/// The driver's default `host_latency_ms`.
pub const HOST: Duration = Duration::from_millis(5);
/// The `$41` packet timeout the driver programs at 19200 baud: one word and two byte
/// times, in 2 ms units (docs/keys/tmcpack.md `packet_timeout_ms`): 6 ms.
pub const PACKET_TIMEOUT: Duration = Duration::from_millis(6);
/// Manual 6.1 / 8.6 `$40`: "pre-set to 6ms".
pub const FACTORY_SWITCHOVER: Duration = Duration::from_millis(6);
/// The position a held `$20` answer reports: it must reach the channel only when paired.
pub const HELD_POSITION: i32 = 777_777;

/// Until when the answer to a query written at `at` can arrive, from the manual: the
/// request on the wire, the pack's processing, its switch-over delay, the answer on the
/// wire, the host's latency.
pub fn window_end(at: Duration, switchover: Duration) -> Duration {
    at + WORD + PROCESSING + switchover + WORD + HOST
}

/// One pack as the manual describes it.
#[derive(Debug)]
struct Pack {
    address: u8,
    switchover: Duration,
    reset_flag: bool,
}

/// One answer held to an instant chosen by the test.
#[derive(Debug, Clone, Copy)]
pub struct Hold {
    /// The pack (driver index) whose answer is held.
    pub pack: usize,
    /// The command whose next answer is held.
    pub command: u8,
    /// From the query's write to the arrival of the answer's last byte.
    pub delay: Duration,
}

/// A held query: when it was written and when its answer arrives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Held {
    pub written: Duration,
    pub arrives: Duration,
}

/// One word on the line.
#[derive(Debug, Clone, Copy)]
pub struct Sent {
    pub at: Duration,
    pub driver: usize,
    pub request: Request,
    /// When its answer arrived (queries only; `None` while not, or never).
    pub answered: Option<Duration>,
    /// The switch-over of its pack when it was sent.
    pub switchover: Duration,
}

pub struct Line {
    pub bus: LinkBus<TmcpackDriver>,
    pub now: Duration,
    pub sent: Vec<Sent>,
    packs: Vec<Pack>,
    /// Answers on their way: arrival, index into `sent`, bytes.
    due: Vec<(Duration, usize, [u8; 9])>,
    pub hold: Option<Hold>,
    pub held: Option<Held>,
}

/// A pack's driver config: motors 0 and 2, the given `$40` switch-over (`None`: the pack
/// keeps its factory 6 ms), at 19200 baud on a bus of `packs`.
pub fn config(address: u8, switchover_units: Option<u16>, packs: u8) -> TmcpackDriverConfig {
    let mut channels = [None; 6];
    for motor in [0, 2] {
        channels[motor] = Some(TmcpackChannel {
            max_velocity: 32_000.0,
            max_accel: 160_000.0,
            ..TmcpackChannel::default()
        });
    }
    TmcpackDriverConfig {
        address,
        variant: Variant::SixPack,
        baud: BAUD,
        switchover_units,
        bus_motors: 2 * packs,
        channels,
        ..TmcpackDriverConfig::default()
    }
}

impl Line {
    /// Packs at addresses 1, 2, … with the given switch-over each, online.
    pub fn online(switchovers: &[Option<u16>]) -> Self {
        let packs = switchovers.len() as u8;
        Self::online_with(
            switchovers
                .iter()
                .enumerate()
                .map(|(i, s)| config(i as u8 + 1, *s, packs))
                .collect(),
        )
    }

    /// Packs of these driver configs (at their addresses), just powered on: nothing sent
    /// yet.
    pub fn new(configs: Vec<TmcpackDriverConfig>) -> Self {
        let packs = configs
            .iter()
            .map(|c| Pack {
                address: c.address,
                switchover: FACTORY_SWITCHOVER,
                reset_flag: true,
            })
            .collect();
        let drivers = configs.into_iter().map(TmcpackDriver::new).collect();
        Self {
            bus: LinkBus::new(LinkKind::Stream, drivers),
            now: Duration::ZERO,
            sent: Vec::new(),
            packs,
            due: Vec::new(),
            hold: None,
            held: None,
        }
    }

    /// Packs of these driver configs, online.
    pub fn online_with(configs: Vec<TmcpackDriverConfig>) -> Self {
        let mut line = Self::new(configs);
        line.run_until(2000 * MS, |l| {
            l.bus.drivers().iter().all(|d| d.status().online)
        });
        assert!(
            line.bus.drivers().iter().all(|d| d.status().online),
            "online within 2 s"
        );
        line
    }

    pub fn driver(&self, index: usize) -> &TmcpackDriver {
        &self.bus.drivers()[index]
    }

    /// One step of the fake clock: answers that arrived, timeouts, words sent.
    pub fn step(&mut self) {
        let now = self.now;
        let mut arrived = Vec::new();
        self.due.retain(|d| {
            if d.0 <= now {
                arrived.push(*d);
                false
            } else {
                true
            }
        });
        arrived.sort_by_key(|d| d.0);
        for (at, index, bytes) in arrived {
            if let Some(sent) = self.sent.get_mut(index) {
                sent.answered = Some(at);
            }
            self.bus.handle_rx(now, &bytes);
        }
        self.bus.handle_timeout(now);
        let mut buf = [0u8; 256];
        while let Some((driver, t)) = self.bus.poll_transmit(now, &mut buf) {
            assert_eq!(t.len, 9);
            let frame = RequestFrame::decode(&buf[..9]).expect("a valid word");
            self.on_word(driver, frame.address, frame.request);
        }
        self.now += STEP;
    }

    /// Steps until `done` or `limit`; whether `done` held.
    pub fn run_until(&mut self, limit: Duration, mut done: impl FnMut(&Self) -> bool) -> bool {
        let end = self.now + limit;
        while self.now < end {
            if done(self) {
                return true;
            }
            self.step();
        }
        done(self)
    }

    pub fn run_for(&mut self, span: Duration) {
        let end = self.now + span;
        while self.now < end {
            self.step();
        }
    }

    /// A word from `driver` to the pack at `address`: the pack acts, and answers a query
    /// after its wire time, its switch-over delay and the answer's wire time (manual 6.1).
    fn on_word(&mut self, driver: usize, address: u8, request: Request) {
        let now = self.now;
        let index = self.sent.len();
        let Some(pack) = self.packs.iter().position(|p| p.address == address) else {
            panic!("a word for address {address}, which no pack has");
        };
        let switchover = self.packs[pack].switchover;
        self.sent.push(Sent {
            at: now,
            driver,
            request,
            answered: None,
            switchover,
        });
        let p = &mut self.packs[pack];
        let reply = match request {
            Request::SetBaud { switchover, .. } => {
                // Manual 8.6: "in increments of 2ms"; from the next word on.
                p.switchover = u32::from(switchover) * 2 * MS;
                None
            }
            Request::UnitInfo { reply_to } => Some((
                reply_to,
                Reply::UnitInfo {
                    firmware: 149,
                    reset: core::mem::take(&mut p.reset_flag),
                    temperature: 35,
                    serial: 1000 + u16::from(p.address),
                },
            )),
            Request::QueryActions { reply_to, .. } => Some((
                reply_to,
                Reply::Actions {
                    actions: [Action::Inactive; 6],
                },
            )),
            Request::QueryPosition { motor, reply_to } => Some((
                reply_to,
                Reply::Position {
                    motor,
                    position: 1000 * i32::from(motor),
                    action: Action::Inactive,
                    stopped: false,
                },
            )),
            Request::QueryVelocity { motor, reply_to } => Some((
                reply_to,
                Reply::Velocity {
                    motor,
                    velocity: 0,
                    action: Action::Inactive,
                },
            )),
            Request::ReadInput { channel, reply_to } => Some((
                reply_to,
                Reply::Input {
                    channel,
                    value: 512,
                    reference: false,
                    inputs: tmcpack::RefInputs::EMPTY,
                    ttlio1: false,
                },
            )),
            _ => None,
        };
        let Some((reply_to, mut reply)) = reply else {
            return;
        };
        let mut arrives = now + WORD + switchover + WORD;
        if let Some(hold) = self.hold
            && hold.pack == pack
            && hold.command == request.command().code()
        {
            self.hold = None;
            arrives = now + hold.delay;
            self.held = Some(Held {
                written: now,
                arrives,
            });
            if let Reply::Position { position, .. } = &mut reply {
                *position = HELD_POSITION;
            }
        }
        let word = ReplyFrame::new(reply_to, reply).to_word().expect("valid");
        self.due.push((arrives, index, word));
    }

    /// The pack at `index` has this switch-over already (a previous run programmed it).
    pub fn set_switchover(&mut self, index: usize, switchover: Duration) {
        if let Some(pack) = self.packs.get_mut(index) {
            pack.switchover = switchover;
        }
    }

    /// Holds the next answer of `pack` to `command` for `delay` after its query's write,
    /// and steps until that query is written; returns its write time.
    pub fn hold_next(&mut self, pack: usize, command: u8, delay: Duration) -> Duration {
        self.held = None;
        self.hold = Some(Hold {
            pack,
            command,
            delay,
        });
        assert!(
            self.run_until(3000 * MS, |l| l.held.is_some()),
            "a ${command:02X} went out"
        );
        self.held.expect("held").written
    }

    /// The words sent after `at`, in order.
    pub fn sent_after(&self, at: Duration) -> Vec<Sent> {
        self.sent.iter().filter(|s| s.at > at).copied().collect()
    }

    /// Manual 6.1 and 7.1 checked on every word on the line, independently of the driver:
    /// after a query, no word (of any driver) before its answer arrived and the pack's
    /// switch-over hold after it passed, or — unanswered in its window — before the window
    /// ended and the `$41` packet timeout passed; after a word without an answer, none
    /// before its wire time and the packet timeout passed. `late` lists the queries
    /// (by write time) whose answers came after their window.
    pub fn check_never_interlaced(&self) {
        for pair in self.sent.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let query = a.request.command().has_reply();
            let free = match (query, a.answered) {
                (true, Some(at)) if at <= window_end(a.at, a.switchover) => at + a.switchover,
                (true, _) => window_end(a.at, a.switchover) + PACKET_TIMEOUT.max(a.switchover),
                (false, _) => a.at + WORD.max(PACKET_TIMEOUT),
            };
            assert!(
                b.at >= free,
                "{:?} at {:?} sent before {:?}: the line was not free after {:?} at {:?} (answered {:?})",
                b.request,
                b.at,
                free,
                a.request,
                a.at,
                a.answered
            );
        }
    }
}
