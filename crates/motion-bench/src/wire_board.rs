//! The four boards of figure 9 (command → first byte at the link): how each is served by
//! the bench, which of the host's messages carries the first request of a `Velocity`
//! goal, and how the bench writes that message itself for its transport baseline.
//!
//! | board | transport | the goal's first request (driver, `motion-drivers`) |
//! |---|---|---|
//! | QSB-M | pty, 230400 baud, ASCII lines | `W12…` MD JOG RATE (the jog plan: MD ACCEL when it differs, MD JOG RATE, COMMAND 9) |
//! | SIXpack | pty, 19200 baud, 9-byte words | `$25` rotation (`$11` only for a motor switched off, `$14` only when amax/vmax differ) |
//! | QuadQuad2Drv | SPI socket | the transaction carrying packet 36 (velocity ramp), after 16 (control mode) |
//! | SPI_motor stepper | SPI socket | the first write transaction to the board (0x90): the ramp's step delay (0x43), target (0x41) or stop-here (0x42) |

use std::io::{Read as _, Write as _};
use std::os::unix::net::UnixStream;
use std::path::Path;
use std::sync::mpsc::Sender;

use motion_base::Model;

use crate::pty::{BAUD, Framing, LineSeen, PtyBoard, Wire};
use crate::sim_boards::{serial_board, spi_board};
use crate::spi_board::{SpiBoard, Watch};
use crate::sweep::ServerRt;

/// The SIXpack's factory line rate.
pub const PACK_BAUD: u32 = 19_200;
/// The pack's bus address in the generated config.
const PACK_ADDRESS: u8 = 1;
/// The host's messages the SIXpack's pty reports: `$25` (rotation) to the pack (the word
/// starts with the address and the command byte, manual 6.1).
const PACK_ROTATE: &[u8] = &[PACK_ADDRESS, tmcpack::Command::Rotate.code()];
/// The SPI_motor's address (write transactions start with it; reads with it + 1).
pub const SPIM_ADDRESS: u8 = 0x90;

/// One board of figure 9.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireBoard {
    /// US Digital QSB-M on a pty.
    Qsb,
    /// Trinamic SIXpack on a pty.
    Tmcpack,
    /// QuadQuad2Drv on an SPI socket.
    Qq2drv,
    /// SPI_motor stepper on an SPI socket.
    Spimotor,
}

/// The served board of one [`WireBoard`].
#[derive(Debug)]
pub enum Served {
    /// On a pty.
    Pty(PtyBoard),
    /// On an SPI socket.
    Spi(SpiBoard),
}

impl Served {
    /// Stops the serving thread.
    pub fn stop(&mut self) {
        match self {
            Self::Pty(board) => board.stop(),
            Self::Spi(board) => board.stop(),
        }
    }

    /// What went wrong in the serving thread, if anything.
    pub fn failure(&self) -> Option<String> {
        let failure = match self {
            Self::Pty(board) => &board.failure,
            Self::Spi(board) => &board.failure,
        };
        failure.lock().ok().and_then(|f| f.clone())
    }
}

/// The bench's own end of a baseline transport: the pty's slave side, or a connection to
/// the SPI socket.
#[derive(Debug)]
pub enum Host {
    /// A pty slave, non-blocking.
    Pty(std::fs::File),
    /// An SPI socket connection, blocking.
    Spi(UnixStream),
}

impl WireBoard {
    /// Every board, in the order of the rows.
    pub const ALL: [Self; 4] = [Self::Qsb, Self::Tmcpack, Self::Qq2drv, Self::Spimotor];

    /// Name in the rows.
    pub fn name(self) -> &'static str {
        match self {
            Self::Qsb => "QSB-M",
            Self::Tmcpack => "SIXpack",
            Self::Qq2drv => "QuadQuad2Drv",
            Self::Spimotor => "SPI_motor stepper",
        }
    }

    /// File-name part of the `--out` files.
    pub fn slug(self) -> &'static str {
        match self {
            Self::Qsb => "qsb",
            Self::Tmcpack => "tmcpack",
            Self::Qq2drv => "qq2drv",
            Self::Spimotor => "spimotor",
        }
    }

    /// The transport, for the rows.
    pub fn transport(self) -> &'static str {
        match self {
            Self::Qsb => "pty, 230400 baud",
            Self::Tmcpack => "pty, 19200 baud",
            Self::Qq2drv | Self::Spimotor => "SPI socket",
        }
    }

    /// The message the rows name.
    pub fn message(self) -> &'static str {
        match self {
            Self::Qsb => "`W12…` line (MD JOG RATE)",
            Self::Tmcpack => "`$25` word (rotation)",
            Self::Qq2drv => "transaction with packet 36 (velocity ramp)",
            Self::Spimotor => "first write transaction to 0x90",
        }
    }

    /// The axis index of the board in [`config_text`].
    pub fn axis(self) -> u32 {
        match self {
            Self::Qsb => 0,
            Self::Tmcpack => 1,
            Self::Qq2drv => 2,
            Self::Spimotor => 3,
        }
    }

    /// The jog velocity of the requests, in the axis's units/s.
    pub fn velocity(self) -> f64 {
        match self {
            // 1000 counts/s at 100 counts/mm: MD JOG RATE ±96.
            Self::Qsb => 10.0,
            // 6400 µsteps/s at 640 µsteps/mm.
            Self::Tmcpack => 10.0,
            // 3183 transitions/s.
            Self::Qq2drv => 0.1,
            // 100 steps/s: a 20 ms ramp at 5000 steps/s².
            Self::Spimotor => 100.0,
        }
    }

    /// Pause before each request: 1 ms plus up to this, so that requests land at every
    /// phase of the tick and of the board's own traffic (the pack's ~12 ms query round
    /// trip), and each one refreshes the 250 ms deadman.
    pub fn pace_ns(self) -> u64 {
        match self {
            Self::Tmcpack => 30_000_000,
            Self::Qsb | Self::Qq2drv | Self::Spimotor => 5_000_000,
        }
    }

    /// The one-axis group of this board's axis in [`config_text`] (the SPI boards': the
    /// setpoint → wire stream, [`crate::stream_wire`]).
    pub fn stream_group(self) -> u32 {
        match self {
            Self::Spimotor => 1,
            Self::Qsb | Self::Tmcpack | Self::Qq2drv => 0,
        }
    }

    /// The position stream's swing, `A (1 − cos 2π t / T)`: (A in the axis's unit, T in s),
    /// within the axis's limits (peak velocity A · 2π / T, acceleration A (2π / T)²).
    pub fn stream_swing(self) -> (f64, f64) {
        match self {
            // 126 steps/s, 790 steps/s² (max 500, 5000).
            Self::Spimotor => (20.0, 1.0),
            // 0.31 m/s, 2.0 m/s² (max 1.5, 3).
            Self::Qsb | Self::Tmcpack | Self::Qq2drv => (0.05, 1.0),
        }
    }

    /// Counts per unit of the board's axis in [`config_text`].
    pub fn counts_per_unit(self) -> f64 {
        match self {
            Self::Qsb => 100.0,
            Self::Tmcpack => 640.0,
            Self::Qq2drv => 31831.0,
            Self::Spimotor => 1.0,
        }
    }

    /// How the board follows a stream, for the rows.
    pub fn stream_follows(self) -> &'static str {
        match self {
            Self::Spimotor => {
                "the SPI_motor follows by setpoints: a position goal in the tick each \
                 setpoint applies (writes to 0x90)"
            }
            Self::Qsb | Self::Tmcpack | Self::Qq2drv => {
                "the QuadQuad2Drv follows by segments: a packet 34 (position ramp) once the \
                 last is acknowledged and as long again, so most setpoints wait for the next \
                 segment"
            }
        }
    }

    /// Whether `message` (a line, word or transaction the board side reported) carries
    /// the goal's first request: `Some(Some(positive))` with the sign of the velocity it
    /// sets, `Some(None)` when its bytes carry no sign (the SPI_motor's step delay), `None`
    /// when it is another message.
    pub fn goal_sign(self, message: &[u8]) -> Option<Option<bool>> {
        match self {
            Self::Qsb => {
                let digits = std::str::from_utf8(message.strip_prefix(b"W12")?).ok()?;
                let value = u32::from_str_radix(digits, 16).ok()? as i32;
                (value != 0).then_some(Some(value > 0))
            }
            Self::Tmcpack => match tmcpack::RequestFrame::decode(message) {
                Ok(tmcpack::RequestFrame {
                    address: PACK_ADDRESS,
                    request: tmcpack::Request::Rotate { velocity, .. },
                }) if velocity != 0 => Some(Some(velocity > 0)),
                _ => None,
            },
            Self::Qq2drv => velocity_ramp(message).map(|v| Some(v > 0)),
            Self::Spimotor => spim_write(message).then_some(None),
        }
    }

    /// Starts the simulated board at `link` (a pty symlink or a socket path), reporting
    /// the host's messages that may carry a goal to `seen`.
    pub fn serve(self, link: &Path, seen: Sender<LineSeen>) -> Result<Served, String> {
        Ok(match self {
            Self::Qsb => Served::Pty(PtyBoard::start_with(
                link,
                serial_board(Model::QSB)?,
                Wire::QSB,
                b"W1",
                seen,
            )?),
            Self::Tmcpack => Served::Pty(PtyBoard::start_framed(
                link,
                serial_board(Model::TMCPACK)?,
                Wire::uart(PACK_BAUD),
                Framing::Words {
                    len: 9,
                    gap_ns: 2_000_000,
                },
                PACK_ROTATE,
                seen,
            )?),
            Self::Qq2drv => Served::Spi(SpiBoard::start_watched(
                link,
                spi_board(Model::QQ2DRV, None, None)?,
                Some(Watch {
                    // Figure 9's velocity ramps, and the position stream's segments.
                    select: |mosi| velocity_ramp(mosi).is_some() || position_ramp(mosi),
                    seen,
                }),
            )?),
            Self::Spimotor => Served::Spi(SpiBoard::start_watched(
                link,
                spi_board(Model::SPIMOTOR, Some(SPIM_ADDRESS), Some("stepper"))?,
                Some(Watch {
                    select: spim_write,
                    seen,
                }),
            )?),
        })
    }

    /// The bench's own end of the transport at `link`, for the baseline.
    pub fn open_host(self, link: &Path) -> Result<Host, String> {
        match self {
            Self::Qsb | Self::Tmcpack => {
                use std::os::unix::fs::OpenOptionsExt as _;
                std::fs::OpenOptions::new()
                    .read(true)
                    .write(true)
                    .custom_flags(libc::O_NOCTTY | libc::O_NONBLOCK | libc::O_CLOEXEC)
                    .open(link)
                    .map(Host::Pty)
                    .map_err(|e| format!("open {}: {e}", link.display()))
            }
            Self::Qq2drv | Self::Spimotor => {
                // The board thread accepts every 20 ms.
                let mut tries = 0;
                loop {
                    match UnixStream::connect(link) {
                        Ok(stream) => return Ok(Host::Spi(stream)),
                        Err(_) if tries < 50 => {
                            tries += 1;
                            std::thread::sleep(core::time::Duration::from_millis(20));
                        }
                        Err(e) => return Err(format!("connect {}: {e}", link.display())),
                    }
                }
            }
        }
    }

    /// A message that sets a velocity of the sign asked for, for a baseline whose motiond
    /// part saw none (the bytes motiond sends, from the driver's encoding).
    pub fn fallback_message(self, positive: bool) -> Vec<u8> {
        match self {
            Self::Qsb => {
                let rate: i32 = if positive { 96 } else { -96 };
                format!("W12{:X}", rate as u32).into_bytes()
            }
            Self::Tmcpack => {
                let velocity: i16 = if positive { 100 } else { -100 };
                let frame = tmcpack::RequestFrame::new(
                    PACK_ADDRESS,
                    tmcpack::Request::Rotate { motor: 0, velocity },
                );
                let mut word = [0u8; tmcpack::FRAME_LEN];
                let len = frame.encode(&mut word).unwrap_or(0);
                word.get(..len).unwrap_or_default().to_vec()
            }
            Self::Qq2drv => {
                let entry = qq2drv::VelocityRampEntry {
                    channels: qq2drv::ChannelMask::single(0),
                    velocity: if positive { 3183 } else { -3183 },
                    acceleration: 0,
                };
                let entries = [entry];
                let request = qq2drv::Request::VelocityRamp(qq2drv::Entries::new(&entries));
                let mut packet = [0u8; qq2drv::MAX_PACKET_LEN];
                let len = request.encode(&mut packet).unwrap_or(0);
                packet.get(..len).unwrap_or_default().to_vec()
            }
            // 0x43 ← 100: 10 ms per step.
            Self::Spimotor => vec![SPIM_ADDRESS, 0x43, 100],
        }
    }

    /// The bytes a host writes for `message`: a QSB line with its CR LF, anything else as
    /// it is (an SPI link frames its transactions itself).
    pub fn on_the_wire(self, message: &[u8]) -> Vec<u8> {
        if self == Self::Qsb {
            [message, b"\r\n"].concat()
        } else {
            message.to_vec()
        }
    }

    /// Writes `message` through the host end as the driver's link would (a QSB line with
    /// its CR LF; an SPI transaction as its length and MOSI bytes, then its MISO bytes read
    /// back). Returns whether the transport took it whole.
    pub fn write(self, host: &mut Host, message: &[u8]) -> bool {
        match host {
            Host::Pty(tty) => {
                let bytes = self.on_the_wire(message);
                matches!(tty.write(&bytes), Ok(n) if n == bytes.len())
            }
            Host::Spi(stream) => {
                let Ok(len) = u16::try_from(message.len()) else {
                    return false;
                };
                let mut framed = len.to_le_bytes().to_vec();
                framed.extend_from_slice(message);
                if stream.write_all(&framed).is_err() {
                    return false;
                }
                let mut miso = vec![0u8; message.len()];
                stream.read_exact(&mut miso).is_ok()
            }
        }
    }

    /// Reads and drops what the board sent the host end (the model's answers), as a host
    /// would; SPI answers are read by [`write`](Self::write).
    pub fn drain(host: &mut Host) {
        if let Host::Pty(tty) = host {
            let mut drain = [0u8; 256];
            while matches!(tty.read(&mut drain), Ok(n) if n > 0) {}
        }
    }
}

/// The velocity of the first packet 36 (velocity ramp) in an SPI transaction's MOSI bytes
/// (any number of packets, filler between them), if it has one.
fn velocity_ramp(mosi: &[u8]) -> Option<i32> {
    first_packet(mosi, |request| match request {
        qq2drv::Request::VelocityRamp(entries) => entries.iter().next().map(|e| e.velocity),
        _ => None,
    })
}

/// Whether an SPI transaction's MOSI bytes carry a packet 34 (position ramp: the segments
/// a position stream or a path hands the QuadQuad2Drv).
fn position_ramp(mosi: &[u8]) -> bool {
    first_packet(mosi, |request| {
        matches!(request, qq2drv::Request::PositionRamp(_)).then_some(())
    })
    .is_some()
}

/// The first packet in `mosi` for which `pick` says something.
fn first_packet<T>(mosi: &[u8], pick: impl Fn(qq2drv::Request<'_>) -> Option<T>) -> Option<T> {
    let mut start = 0;
    while let Some(offset) = mosi.get(start..)?.iter().position(|&b| b == qq2drv::STX) {
        let at = start + offset;
        let size = usize::from(*mosi.get(at + 1)?);
        match mosi.get(at..at + size).map(qq2drv::Request::parse) {
            Some(Ok(request)) => match pick(request) {
                Some(found) => return Some(found),
                None => start = at + size,
            },
            _ => start = at + 1,
        }
    }
    None
}

/// Whether an SPI transaction writes to the SPI_motor (address byte 0x90, read bit clear).
fn spim_write(mosi: &[u8]) -> bool {
    mosi.first() == Some(&SPIM_ADDRESS) && mosi.len() > 2
}

/// The generated config: the four boards, one axis each (in [`WireBoard::axis`] order),
/// limits far from where the jogs go.
pub fn config_text(
    name: &str,
    tick_hz: u32,
    rt: ServerRt,
    links: &[(WireBoard, &Path); 4],
) -> String {
    use std::fmt::Write as _;
    let mut text = format!(
        "# generated by the latency bench's --command-to-wire\n\
         [server]\nname = \"{name}\"\ntick_hz = {tick_hz}\ncommand_timeout_ms = 250\n{}",
        rt.keys()
    );
    for (board, link) in links {
        let link = link.display();
        let _ = match board {
            WireBoard::Qsb => write!(
                text,
                "\n[[link]]\nname = \"qsb\"\ntype = \"serial\"\npath = \"{link}\"\nbaud = {BAUD}\n\n\
                 [[device]]\nname = \"feeder_qsb\"\nlink = \"qsb\"\nmodel = \"qsb\"\n"
            ),
            WireBoard::Tmcpack => write!(
                text,
                "\n[[link]]\nname = \"rs485\"\ntype = \"serial\"\npath = \"{link}\"\nbaud = {PACK_BAUD}\n\n\
                 [[device]]\nname = \"pack\"\nlink = \"rs485\"\nmodel = \"tmcpack\"\naddress = {PACK_ADDRESS}\n\
                 variant = \"sixpack\"\n"
            ),
            WireBoard::Qq2drv => write!(
                text,
                "\n[[link]]\nname = \"quad\"\ntype = \"spi-socket\"\npath = \"{link}\"\n\n\
                 [[device]]\nname = \"quad\"\nlink = \"quad\"\nmodel = \"qq2drv\"\n"
            ),
            WireBoard::Spimotor => write!(
                text,
                "\n[[link]]\nname = \"spim\"\ntype = \"spi-socket\"\npath = \"{link}\"\n\n\
                 [[device]]\nname = \"focus_drv\"\nlink = \"spim\"\nmodel = \"spimotor\"\n\
                 address = {SPIM_ADDRESS:#x}\ndrive = \"stepper\"\n"
            ),
        };
    }
    text.push_str(
        "\n[[axis]]\nname = \"feeder\"\ndevice = \"feeder_qsb\"\nchannel = 0\nunit = \"mm\"\n\
         counts_per_unit = 100.0\nmin = -1000.0\nmax = 1000.0\nmax_velocity = 100.0\n\
         max_accel = 1000.0\n\n\
         [[axis]]\nname = \"x\"\ndevice = \"pack\"\nchannel = 0\nunit = \"mm\"\n\
         counts_per_unit = 640.0\nmin = -1000.0\nmax = 1000.0\nmax_velocity = 50.0\n\
         max_accel = 250.0\n\n\
         [[axis]]\nname = \"wheel\"\ndevice = \"quad\"\nchannel = 0\nunit = \"m\"\n\
         counts_per_unit = 31831.0\nmin = -1000.0\nmax = 1000.0\nmax_velocity = 1.5\n\
         max_accel = 3.0\n\n\
         [[axis]]\nname = \"focus\"\ndevice = \"focus_drv\"\nchannel = 0\nunit = \"step\"\n\
         counts_per_unit = 1.0\nmin = -100000.0\nmax = 100000.0\nmax_velocity = 500.0\n\
         max_accel = 5000.0\n\n\
         [[group]]\nname = \"wheel\"\naxes = [\"wheel\"]\nstream_limit = \"clamp\"\n\
         stream_timeout = 50\n\n\
         [[group]]\nname = \"focus\"\naxes = [\"focus\"]\nstream_limit = \"clamp\"\n\
         stream_timeout = 50\n",
    );
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_boards_fallback_message_is_its_own_goal_message_with_the_sign_asked_for() {
        for board in WireBoard::ALL {
            for positive in [false, true] {
                let sign = board.goal_sign(&board.fallback_message(positive));
                let expected = if board == WireBoard::Spimotor {
                    Some(None)
                } else {
                    Some(Some(positive))
                };
                assert_eq!(sign, expected, "{board:?} {positive}");
            }
        }
    }

    #[test]
    fn other_messages_are_not_taken_for_the_goal() {
        assert_eq!(WireBoard::Qsb.goal_sign(b"W169"), None);
        assert_eq!(
            WireBoard::Qsb.goal_sign(b"W120"),
            None,
            "a zero rate has no sign"
        );
        assert_eq!(
            WireBoard::Tmcpack.goal_sign(&[1, 0x20, 0, 0, 0, 0, 0, 0, 0]),
            None,
            "a status query"
        );
        // Filler, then packet 16 alone (control mode), then a torn packet 36.
        let mut mosi = vec![0u8; 8];
        let mode = [qq2drv::ControlModeEntry {
            channels: qq2drv::ChannelMask::single(0),
            mode: qq2drv::ControlMode::VelocityPid,
        }];
        let mut packet = [0u8; qq2drv::MAX_PACKET_LEN];
        let len = qq2drv::Request::SetControlMode(qq2drv::Entries::new(&mode))
            .encode(&mut packet)
            .expect("fits");
        mosi.extend_from_slice(&packet[..len]);
        assert_eq!(WireBoard::Qq2drv.goal_sign(&mosi), None);
        let ramp = WireBoard::Qq2drv.fallback_message(false);
        mosi.extend_from_slice(ramp.get(..ramp.len() - 1).unwrap_or_default());
        assert_eq!(WireBoard::Qq2drv.goal_sign(&mosi), None, "torn");
        mosi.extend_from_slice(&ramp);
        assert_eq!(WireBoard::Qq2drv.goal_sign(&mosi), Some(Some(false)));
        assert_eq!(
            WireBoard::Spimotor.goal_sign(&[0x91, 0x40, 0, 0, 0, 0]),
            None,
            "a read"
        );
    }

    #[test]
    fn the_config_names_every_link_once() {
        let paths = ["/tmp/q", "/tmp/p", "/tmp/d", "/tmp/s"];
        let links = [
            (WireBoard::Qsb, Path::new(paths[0])),
            (WireBoard::Tmcpack, Path::new(paths[1])),
            (WireBoard::Qq2drv, Path::new(paths[2])),
            (WireBoard::Spimotor, Path::new(paths[3])),
        ];
        let text = config_text("n", 1000, ServerRt::default(), &links);
        for path in paths {
            assert_eq!(text.matches(path).count(), 1, "{path}");
        }
        assert_eq!(text.matches("[[axis]]").count(), 4);
        assert_eq!(text.matches("[[group]]").count(), 2);
    }
}
