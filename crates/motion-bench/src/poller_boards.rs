//! What the bare poller ([`crate::poller`]) sends to each of the I/O phase's four idle
//! boards: the transactions motiond's drivers send while no axis moves, at their rates, and
//! the least start-up that makes each board's idle answers the same as under motiond. Time
//! is an argument (the tick's instant), as in the drivers, so that a test steps these
//! schedules and the drivers side by side on the same simulated boards
//! (`tests/poller_traffic.rs`).
//!
//! - QSB-M (230400 baud): start-up `W161` (quiet old streams), EOR, INTERVAL RATE (the
//!   driver's automatic choice for the line rate), COMMAND 2 (motor drive, whose MD STATUS
//!   is streamed), `S13`, `S0E`; one request in flight. Idle: nothing — the board streams
//!   MD STATUS and the counter every interval, and the poller reads them.
//! - SIXpack (19200 baud): start-up `$40` (the link's baud divisor, the driver's default
//!   switch-over, which sets the pack's answer delay). Idle: `$20` position polls of motor
//!   0, the next in the first tick after the answer plus the switch-over time, and a `$43`
//!   reset check every [`RESET_CHECK_PERIOD`] after the last one's answer.
//! - QuadQuad2Drv (SPI): start-up one transaction of Data Mask (channel 0: the driver's
//!   `STREAM_MASK`), Stream Config and Stream Period (the driver's for its poll period).
//!   Idle: a filler transaction as long as one stream packet plus `POLL_SLACK` every poll
//!   period (three quarters of it at least apart, as the driver).
//! - SPI_motor stepper at 0x90: idle reads of position, target and step delay every poll
//!   period, each its own transaction, and the identification every
//!   [`PRESENCE_EVERY`]-th poll.
//!
//! Replies are read back whole; a schedule looks only at what it needs to go on (the
//! answer that ends a QSB or pack exchange, the length of the SPI_motor's identification).

use core::time::Duration;
use std::collections::VecDeque;

use board_qq2drv::driver::{POLL_SLACK, Qq2drvDriverConfig, STREAM_CONFIG, STREAM_MASK};
use board_qsb::driver::QsbDriverConfig;
use board_spimotor::driver::{PRESENCE_EVERY, SpimotorDriverConfig};
use board_tmcpack::driver::{
    DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS, RESET_CHECK_PERIOD, word_time,
};
use qq2drv::{ChannelMask, DataMask, DataMaskEntry, Entries, MotionLayout};
use qsb::{Eor, QsbCommand, Register, ResponseDecoder};
use spimotor::{Address, ReadPort, Reply, Transaction};
use tmcpack::{FRAME_LEN, RequestFrame};

use crate::pty::BAUD;
pub use crate::wire_board::{PACK_BAUD, SPIM_ADDRESS};

/// A QSB or pack request unanswered this long is sent again.
const RETRY_AFTER: Duration = Duration::from_millis(100);

/// One board's idle schedule.
#[derive(Debug)]
pub enum IdleBoard {
    /// The QSB-M.
    Qsb(QsbIdle),
    /// The SIXpack.
    Pack(PackIdle),
    /// The QuadQuad2Drv.
    Quad(QuadIdle),
    /// The SPI_motor stepper.
    Spim(SpimIdle),
}

impl IdleBoard {
    /// The I/O phase's four boards, in its config's order (QSB, pack, QuadQuad2Drv,
    /// SPI_motor).
    pub fn all() -> [Self; 4] {
        [
            Self::Qsb(QsbIdle::new()),
            Self::Pack(PackIdle::new()),
            Self::Quad(QuadIdle::new()),
            Self::Spim(SpimIdle::new()),
        ]
    }

    /// Bytes read from the board's link since the last tick, handed over at tick `now`.
    pub fn receive(&mut self, now: Duration, bytes: &[u8]) {
        match self {
            Self::Qsb(board) => board.receive(bytes),
            Self::Pack(board) => board.receive(now, bytes),
            Self::Quad(_) => {}
            Self::Spim(board) => board.receive(bytes),
        }
    }

    /// The next message due at tick `now`, written into `buf`: its length. Called until
    /// `None` in every tick.
    pub fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        match self {
            Self::Qsb(board) => board.transmit(now, buf),
            Self::Pack(board) => board.transmit(now, buf),
            Self::Quad(board) => board.transmit(now, buf),
            Self::Spim(board) => board.transmit(now, buf),
        }
    }

    /// Whether a board command may go out at `now` (as the drivers: after the exchange in
    /// flight on the QSB and the pack's half-duplex line; at once on SPI).
    pub fn line_free(&self, now: Duration) -> bool {
        match self {
            Self::Qsb(board) => board.awaiting.is_none(),
            Self::Pack(board) => board.awaiting.is_none() && now >= board.quiet_until,
            Self::Quad(_) | Self::Spim(_) => true,
        }
    }

    /// A board command of `len` bytes went out at `now`: what its answer (or its silence)
    /// means for the line.
    pub fn commanded(&mut self, now: Duration, len: usize) {
        match self {
            // Its answer echoes the register written (`W12…` → `w 12 …`).
            Self::Qsb(board) => board.awaiting = Some((Register::MdJogRate.number(), now)),
            // No answer: the word's wire time and the pack's packet timeout.
            Self::Pack(board) => {
                board.quiet_until = now + word_time(PACK_BAUD) + tmcpack::DEFAULT_PACKET_TIMEOUT;
            }
            Self::Quad(_) => {}
            Self::Spim(board) => board.pending.push_back((None, len)),
        }
    }

    /// Whether the start-up is over (the idle traffic runs).
    pub fn started(&self) -> bool {
        match self {
            Self::Qsb(board) => board.next >= QSB_STARTUP.len() && board.awaiting.is_none(),
            Self::Pack(board) => board.started,
            Self::Quad(board) => board.started,
            Self::Spim(_) => true,
        }
    }
}

/// The QSB start-up, in order.
const QSB_STARTUP: [QsbStep; 6] = [
    QsbStep::Command(QsbCommand::StopStreaming),
    QsbStep::Eor,
    QsbStep::Interval,
    QsbStep::Command(QsbCommand::EnableMotorDrive),
    QsbStep::Stream(Register::MdStatus),
    QsbStep::Stream(Register::ReadEncoder),
];

#[derive(Debug, Clone, Copy)]
enum QsbStep {
    Command(QsbCommand),
    Eor,
    Interval,
    Stream(Register),
}

impl QsbStep {
    fn request(self) -> qsb::Request {
        match self {
            Self::Command(command) => qsb::Request::Write(qsb::Write::Command(command)),
            // The driver's: LF and the time stamp (`s0E00001234000ABCDE!\n`).
            Self::Eor => qsb::Request::Write(qsb::Write::Eor(Eor {
                line_feed: true,
                carriage_return: false,
                time_stamp: true,
                spaces: false,
            })),
            Self::Interval => qsb::Request::Write(qsb::Write::IntervalRate(
                QsbDriverConfig {
                    baud: BAUD,
                    ..QsbDriverConfig::default()
                }
                .interval(),
            )),
            Self::Stream(register) => qsb::Request::Stream(register),
        }
    }
}

/// The QSB's schedule.
#[derive(Debug)]
pub struct QsbIdle {
    decoder: ResponseDecoder,
    next: usize,
    /// The register whose answer is awaited, and when its request was sent.
    awaiting: Option<(u8, Duration)>,
}

impl QsbIdle {
    fn new() -> Self {
        Self {
            decoder: ResponseDecoder::new(),
            next: 0,
            awaiting: None,
        }
    }

    fn receive(&mut self, mut bytes: &[u8]) {
        while !bytes.is_empty() {
            let (used, response) = self.decoder.decode(bytes);
            if used == 0 {
                return;
            }
            if let (Some(response), Some((register, _))) = (response, self.awaiting)
                && response.register == register
            {
                self.awaiting = None;
            }
            bytes = bytes.get(used..).unwrap_or(&[]);
        }
    }

    fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        let step = match self.awaiting {
            None => {
                let step = QSB_STARTUP.get(self.next)?;
                self.next += 1;
                step
            }
            // A command's answer lost after the start-up: the line is free again.
            Some((_, sent))
                if now.saturating_sub(sent) >= RETRY_AFTER && self.next >= QSB_STARTUP.len() =>
            {
                self.awaiting = None;
                return None;
            }
            // A start-up step unanswered: once more (the index already moved on).
            Some((_, sent)) if now.saturating_sub(sent) >= RETRY_AFTER => {
                QSB_STARTUP.get(self.next.checked_sub(1)?)?
            }
            Some(_) => return None,
        };
        let request = step.request();
        self.awaiting = Some((request.register().number(), now));
        request.encode(buf).ok()
    }
}

/// The pack's schedule.
#[derive(Debug)]
pub struct PackIdle {
    started: bool,
    /// Reply bytes still expected, and the instant the exchange is given up.
    awaiting: Option<(usize, Duration)>,
    /// The last request was a `$43`.
    checking: bool,
    /// The line is the pack's until then (its switch-over after an answer).
    quiet_until: Duration,
    next_check: Option<Duration>,
}

impl PackIdle {
    fn new() -> Self {
        Self {
            started: false,
            awaiting: None,
            checking: false,
            quiet_until: Duration::ZERO,
            next_check: None,
        }
    }

    fn switchover() -> Duration {
        tmcpack::convert::units(DEFAULT_SWITCHOVER_UNITS)
    }

    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        let Some((left, deadline)) = self.awaiting else {
            return;
        };
        let left = left.saturating_sub(bytes.len());
        if left > 0 {
            self.awaiting = Some((left, deadline));
            return;
        }
        self.awaiting = None;
        self.quiet_until = now + Self::switchover();
        if self.checking {
            self.next_check = Some(now + RESET_CHECK_PERIOD);
        }
    }

    fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        if let Some((_, deadline)) = self.awaiting {
            if now < deadline {
                return None;
            }
            self.awaiting = None;
        }
        if now < self.quiet_until {
            return None;
        }
        let request = if self.started {
            let check_due = self.next_check.is_none_or(|at| now >= at);
            self.checking = check_due;
            if check_due {
                tmcpack::Request::UnitInfo {
                    reply_to: DEFAULT_REPLY_ADDRESS,
                }
            } else {
                tmcpack::Request::QueryPosition {
                    motor: 0,
                    reply_to: DEFAULT_REPLY_ADDRESS,
                }
            }
        } else {
            // $40 has no answer: the line is free again after its word and the pack's
            // packet timeout.
            self.started = true;
            self.next_check = Some(now + RESET_CHECK_PERIOD);
            self.quiet_until = now + word_time(PACK_BAUD) + tmcpack::DEFAULT_PACKET_TIMEOUT;
            tmcpack::Request::SetBaud {
                divisor: tmcpack::convert::baud_divisor(PACK_BAUD).ok()?,
                switchover: DEFAULT_SWITCHOVER_UNITS,
            }
        };
        let len = RequestFrame::new(1, request).encode(buf).ok()?;
        if !matches!(request, tmcpack::Request::SetBaud { .. }) {
            self.awaiting = Some((FRAME_LEN, now + RETRY_AFTER));
        }
        Some(len)
    }
}

/// The QuadQuad2Drv's schedule.
#[derive(Debug)]
pub struct QuadIdle {
    started: bool,
    config: Qq2drvDriverConfig,
    next_poll_at: Duration,
}

impl QuadIdle {
    fn new() -> Self {
        Self {
            started: false,
            config: Qq2drvDriverConfig::default(),
            next_poll_at: Duration::ZERO,
        }
    }

    /// Channel 0 streams what the driver has it stream for an axis; the others nothing.
    fn masks() -> [DataMask; qq2drv::CHANNELS] {
        let mut masks = [DataMask(0); qq2drv::CHANNELS];
        masks[0] = STREAM_MASK;
        masks
    }

    /// A poll: one stream packet in that layout plus the driver's slack.
    pub fn poll_len() -> usize {
        let layout = MotionLayout {
            data_masks: Self::masks(),
            stream_config: STREAM_CONFIG,
        };
        (qq2drv::MIN_PACKET_LEN + layout.stream_payload_len() + POLL_SLACK).clamp(16, 255)
    }

    fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        if !self.started {
            self.started = true;
            let entry = [DataMaskEntry {
                channels: ChannelMask::single(0),
                mask: STREAM_MASK,
            }];
            let mut len = 0;
            for request in [
                qq2drv::Request::SetDataMask(Entries::new(&entry)),
                qq2drv::Request::SetStreamConfig(STREAM_CONFIG),
                qq2drv::Request::SetStreamPeriod(self.config.stream_period_units()),
            ] {
                len += request.encode(buf.get_mut(len..)?).ok()?;
            }
            return Some(len);
        }
        if now < self.next_poll_at {
            return None;
        }
        let period = self.config.poll_period;
        self.next_poll_at = now + (period - period / 4);
        let len = Self::poll_len();
        buf.get_mut(..len)?.fill(0x00);
        Some(len)
    }
}

/// The SPI_motor's schedule.
#[derive(Debug)]
pub struct SpimIdle {
    poll_period: Duration,
    next_poll_at: Duration,
    polls: u32,
    /// Reads of the poll in progress sent so far (0: none in progress).
    in_poll: usize,
    /// The identification's length on the wire, once read.
    identification_len: Option<u16>,
    /// The transactions sent whose MISO bytes have not all come back: the port read (none
    /// for a write) and the length.
    pending: VecDeque<(Option<ReadPort>, usize)>,
    miso: Vec<u8>,
}

impl SpimIdle {
    fn new() -> Self {
        Self {
            poll_period: SpimotorDriverConfig::default().poll_period,
            next_poll_at: Duration::ZERO,
            polls: 0,
            in_poll: 0,
            identification_len: None,
            pending: VecDeque::with_capacity(8),
            miso: Vec::with_capacity(64),
        }
    }

    fn receive(&mut self, bytes: &[u8]) {
        self.miso.extend_from_slice(bytes);
        while let Some(&(port, len)) = self.pending.front() {
            let Some(transaction) = self.miso.get(..len) else {
                return;
            };
            if let Some(port) = port
                && let Ok(Reply::Identification(id)) = Reply::decode(port, transaction)
            {
                self.identification_len = u16::try_from(id.wire_len()).ok();
            }
            self.pending.pop_front();
            self.miso.drain(..len);
        }
    }

    fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        // A poll starts when due and once the last one's reads are all back (the driver
        // waits for its step-delay read).
        if self.in_poll == 0 && (now < self.next_poll_at || !self.pending.is_empty()) {
            return None;
        }
        // Position, target and step delay go out in the same tick, each its own
        // transaction; the identification before them every PRESENCE_EVERY-th poll.
        const PLAIN: [ReadPort; 3] = [
            ReadPort::CurrentPosition,
            ReadPort::TargetPosition,
            ReadPort::StepDelay,
        ];
        const PRESENCE: [ReadPort; 4] = [
            ReadPort::Identification,
            ReadPort::CurrentPosition,
            ReadPort::TargetPosition,
            ReadPort::StepDelay,
        ];
        let reads: &[ReadPort] = if self.polls % PRESENCE_EVERY == PRESENCE_EVERY - 1 {
            &PRESENCE
        } else {
            &PLAIN
        };
        let port = *reads.get(self.in_poll)?;
        let read = match port {
            ReadPort::Identification => spimotor::Read {
                port,
                len: self
                    .identification_len
                    .unwrap_or(spimotor::IDENTIFICATION_READ_LEN),
            },
            _ => spimotor::Read::new(port),
        };
        let transaction = Transaction {
            address: Address::new(SPIM_ADDRESS).ok()?,
            request: spimotor::Request::Read(read),
        };
        let len = transaction.encode(buf).ok()?;
        self.pending.push_back((Some(port), len));
        self.in_poll += 1;
        if self.in_poll == reads.len() {
            self.in_poll = 0;
            self.polls = self.polls.wrapping_add(1);
            self.next_poll_at = now + self.poll_period;
        }
        Some(len)
    }
}

/// The four schedules with the bytes each board's link delivered since the last tick: the
/// bare poller's whole state, stepped by its process on the real links and by the test on
/// simulated ones.
#[derive(Debug)]
pub struct Idle {
    boards: [IdleBoard; 4],
    rx: [Vec<u8>; 4],
}

impl Default for Idle {
    fn default() -> Self {
        Self::new()
    }
}

impl Idle {
    /// The I/O phase's four boards, nothing received yet.
    pub fn new() -> Self {
        Self {
            boards: IdleBoard::all(),
            rx: core::array::from_fn(|_| Vec::with_capacity(4096)),
        }
    }

    /// Bytes read from link `index` (kept for the next tick, as motiond's receive rings).
    pub fn take(&mut self, index: usize, bytes: &[u8]) {
        if let Some(rx) = self.rx.get_mut(index) {
            rx.extend_from_slice(bytes);
        }
    }

    /// Whether every board's start-up is over.
    pub fn started(&self) -> bool {
        self.boards.iter().all(IdleBoard::started)
    }

    /// At tick `now`: board `index` gets `message` (a command, written whole) if its line
    /// is free; whether it did.
    ///
    /// # Errors
    /// The link refused the write.
    pub fn command(
        &mut self,
        index: usize,
        now: Duration,
        link: &mut dyn motion_link::Link,
        message: &[u8],
    ) -> Result<bool, motion_link::LinkError> {
        let Some(board) = self.boards.get_mut(index) else {
            return Ok(false);
        };
        if !board.started() || !board.line_free(now) {
            return Ok(false);
        }
        link.write(now, message)?;
        board.commanded(now, message.len());
        Ok(true)
    }

    /// One tick at `now`: each board takes what its link delivered, then its due messages
    /// are written to its link (`links` in the same order), each reported to `sent` with
    /// its link's index.
    ///
    /// # Errors
    /// The first write a link refused (the rest of the tick is not done).
    pub fn tick(
        &mut self,
        now: Duration,
        links: &mut [Box<dyn motion_link::Link>],
        mut sent: impl FnMut(usize, &[u8]),
    ) -> Result<(), motion_link::LinkError> {
        let mut buf = [0u8; 256];
        for (index, (board, link)) in self.boards.iter_mut().zip(links.iter_mut()).enumerate() {
            if let Some(rx) = self.rx.get_mut(index) {
                board.receive(now, rx);
                rx.clear();
            }
            while let Some(len) = board.transmit(now, &mut buf) {
                let bytes = buf.get(..len).unwrap_or(&[]);
                link.write(now, bytes)?;
                sent(index, bytes);
            }
        }
        Ok(())
    }
}
