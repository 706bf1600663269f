//! The deadman's bound per board, computed from a validated config the way
//! docs/ARCHITECTURE.md "The deadman's bound per board" derives it:
//!
//! ```text
//! bound = lease + one bus exchange + |v| / max_accel + the board's refresh (+ margin)
//! lease = command_timeout + 1 tick
//! ```

use core::fmt;
use core::time::Duration;
use motion_drivers::spec::FromSpec as _;

use board_qq2drv::driver::Qq2drvDriverConfig;
use board_qsb::driver::QsbDriverConfig;
use board_spimotor::driver::SpimotorDriverConfig;
use board_tmcpack::driver::TmcpackDriverConfig;
use motion_config::boards::driver_spec;
use motion_config::{ServerConfig, Transport};
use motion_drivers::Model;

/// The margin for scheduling on a loaded machine: the tick, the link's I/O thread and the
/// simulated board each woken late by a few milliseconds (cyclictest on the 2-vCPU
/// development guests without real-time priority: p99.9 wake-up ~0.55 ms, a few ms under
/// a parallel build), each of the ~3 hand-overs of a stop (tick → I/O thread → board →
/// I/O thread → tick) once, with room for a 10 ms stall. It does not cover a host stall of
/// tens of ms (seen with the load average near 10): a stop during which the server's own
/// frames were published more than this late after their deadline is measured again (at
/// most twice) rather than hidden in the bound; a machine that stalls every time fails.
pub const MARGIN: Duration = Duration::from_millis(25);

/// 8N1: ten bits a byte.
fn bytes_at(baud: u32, bytes: u32) -> Duration {
    Duration::from_secs_f64(f64::from(bytes) * 10.0 / f64::from(baud))
}

/// SPI: eight clocks a byte.
fn spi_bytes(hz: u32, bytes: u32) -> Duration {
    Duration::from_secs_f64(f64::from(bytes) * 8.0 / f64::from(hz))
}

/// The board an axis is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Board {
    Qq2drv,
    Tmcpack,
    Spimotor,
    Qsb,
}

impl Board {
    pub fn of(config: &ServerConfig, axis: usize) -> Self {
        match config.devices[config.axes[axis].device].model {
            Model::QQ2DRV => Self::Qq2drv,
            Model::TMCPACK => Self::Tmcpack,
            Model::SPIMOTOR => Self::Spimotor,
            Model::QSB => Self::Qsb,
            other => panic!("no deadman bound is written down for {other}"),
        }
    }
}

/// The terms of one axis's bound.
#[derive(Debug, Clone, Copy)]
pub struct Bound {
    pub lease: Duration,
    pub exchange: Duration,
    pub decel: Duration,
    pub refresh: Duration,
    pub margin: Duration,
}

impl Bound {
    /// The bound of axis `axis` (on `board`) jogging at `speed` units/s.
    pub fn new(config: &ServerConfig, axis: usize, board: Board, speed: f64) -> Self {
        let tick = Duration::from_secs(1) / config.server.tick_hz;
        let spec = &config.axes[axis];
        let device = &config.devices[spec.device];
        let rate = match config.links[device.link].transport {
            Transport::Serial { baud, .. } => baud,
            Transport::Spidev { speed_hz, .. } => speed_hz,
            Transport::Sim { rate } => rate,
            Transport::SocketCan { bitrate, .. } | Transport::SimCan { bitrate } => bitrate,
            Transport::SpiSocket { .. } => panic!("the bound needs the link's rate"),
        };
        let driver = driver_spec(config, spec.device, device);
        let (exchange, refresh) = match board {
            Board::Tmcpack => {
                // "SIXpack / QUADpack manual" V2.43, 7.1 "Interlacing of Requests":
                // "Requests must not be interlaced. Each request should wait for the
                // response of the PACK before transmitting a new command." 6.1: "an
                // instruction will be transmitted only after an adjustable transmitter
                // switchover time (s. CMD $40 ...) has passed ... The PACK continues to drive
                // the line for a pre-set time after transmitting a message." 8.3 $14: "1/64
                // amax is accumulated with 500Hz during acceleration to vact".
                let cfg = TmcpackDriverConfig::from_spec(&driver).expect("tmcpack spec");
                let word = bytes_at(rate, 9);
                let switchover = tmcpack::convert::units(
                    cfg.switchover_units
                        .unwrap_or(tmcpack::convert::DEFAULT_SWITCHOVER_UNITS),
                );
                let cycle = Duration::from_millis(2);
                // 6.2 "internal processing time is approx. 2 ms per command", read for the
                // serial line too: the word is acted on in the pack's next 2 ms cycle.
                let query = 2 * word + 2 * switchover + cycle;
                // The query in flight, the tick that takes its answer in, the `$25` word,
                // and two of the pack's 2 ms cycles (acted on at the next one; its ramp
                // ends rounded up to one).
                let exchange = query + tick + word + 2 * cycle;
                // The `$14` after the `$25`, then three polls of the motor (the one in
                // flight at rest, the first after it, the one showing the same position),
                // each possibly after one overdue poll of another motor of its pack and one
                // message of every other pack on the bus, and the tick.
                let packs = config
                    .devices
                    .iter()
                    .filter(|d| d.link == device.link && d.model == Model::TMCPACK)
                    .count() as u32;
                let refresh = word + 3 * (packs + 1) * (query + tick) + tick;
                (exchange, refresh)
            }
            Board::Qq2drv => {
                // "QuadQuad2Drv PCB Datasheet", packet 12 Set History Dimensions: "Maximum
                // Averaging Time in Microseconds = Maximum Averaging Time x 0.64" and "the
                // slower average velocity will wind down when motion is significantly
                // slowed down or stopped"; features: "Loop rate of 500Hz".
                let cfg = Qq2drvDriverConfig::from_spec(&driver).expect("qq2drv spec");
                let loop_period = board_qq2drv::driver::LOOP_PERIOD;
                // The transaction in progress, the stop's first transaction (the setpoint
                // reset to the measured speed), its answer in the next poll, one loop
                // period before the ramp goes out, the tick.
                let transaction = spi_bytes(rate, 64);
                let exchange = 2 * transaction + cfg.poll_period + loop_period + tick;
                // One loop period for the board to follow; the shaft settling behind the
                // setpoint (three mechanical time constants of the motor: a property of
                // the motor, here the simulated gearmotor's); the velocity average winding
                // down over its window after the last capture event (packet 12's
                // averaging time); the next stream packet; the tick.
                let averaging = Duration::from_nanos((1u64 << cfg.history.averaging_bits) * 640);
                let settle = 3 * board_qq2drv::sim::MotorConfig::default().time_constant;
                let refresh = loop_period + settle + averaging + cfg.poll_period + tick;
                (exchange, refresh)
            }
            Board::Spimotor => {
                // SPI_motor "Motor protocol", port 0x43: "set stepdelay. (in tenths of a
                // millisecond ...)": one byte, so the slowest step is 25.5 ms.
                let cfg = SpimotorDriverConfig::from_spec(&driver).expect("spimotor spec");
                // The transaction in progress and the stop's step delay, the tick.
                let transaction = spi_bytes(rate, 8);
                let exchange = 2 * transaction + tick;
                // The last step at the board's slowest rate (the ramp's end), the next
                // position read, the tick.
                let slowest = board_spimotor::driver::ramp::SLOWEST_DELAY.duration();
                let refresh = slowest + cfg.poll_period + tick;
                (exchange, refresh)
            }
            Board::Qsb => {
                // "QSB Command List" 1.28: "At the conclusion of the command response, the
                // QSB is ready to accept another command."
                let cfg = QsbDriverConfig::from_spec(&driver).expect("qsb spec");
                let usb = Duration::from_millis(1);
                // One command at a time: the line in flight (command, answer, the USB
                // frame that hands it over), the tick, the stop's MD ACCEL write and its
                // answer, then MOTOR STOP.
                let line = bytes_at(rate, 13) + bytes_at(rate, 26) + usb;
                let exchange = 2 * (line + tick) + bytes_at(rate, 13);
                let refresh = cfg.stream_period() + usb + tick;
                (exchange, refresh)
            }
        };
        Self {
            lease: config.server.command_timeout + tick,
            exchange,
            decel: Duration::from_secs_f64(speed.abs() / spec.max_accel),
            refresh,
            margin: MARGIN,
        }
    }

    pub fn total(&self) -> Duration {
        self.lease + self.exchange + self.decel + self.refresh + self.margin
    }
}

impl fmt::Display for Bound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:?} = lease {:?} + exchange {:?} + deceleration {:?} + refresh {:?} + margin {:?}",
            self.total(),
            self.lease,
            self.exchange,
            self.decel,
            self.refresh,
            self.margin
        )
    }
}
