//! Client library for motiond: connect to a running server, read its per-tick
//! [`MotionFrame`](motion_ipc::MotionFrame)s straight from shared memory, command its axes
//! and signals, and wait for them.
//!
//! Everything goes through the iceoryx2 services of docs/ARCHITECTURE.md's shared-memory contract
//! (`motiond/<name>/{frame,tick,command,info,stats,params,estop}`, types from [`motion_ipc`],
//! re-exported here as [`ipc`]). The client is generic over the iceoryx2 service type: use
//! `iceoryx2::prelude::ipc::Service` to talk to a real server, `local::Service` in tests.
//!
//! - Connect: [`Client::connect`] (retries for a while, then says clearly that no server
//!   runs), or [`ClientBuilder`] for timeouts and signal handling. Connecting opens only the
//!   info service; frames, commands, stats and machine parameters are opened by their first
//!   use, so a client that only commands works while the frame service's subscriber slots
//!   are all taken.
//! - Describe: [`Client::info`] (axes, units, limits, capabilities, supervision, devices,
//!   signals), [`Client::axis`] / [`Client::signal`] for handles by name, [`Client::stats`],
//!   [`Client::machine_params`] (every device's and axis's effective machine parameter,
//!   marked config or default).
//! - Read: [`Client::latest`] (the newest frame, zero-copy), [`Client::next_frame`] and
//!   [`Client::frames`] (every frame in order, sleeping on the tick event),
//!   [`Client::for_each_frame`] (a callback driven by an iceoryx2 `WaitSet`), or attach
//!   [`Client::tick_listener`] to your own `WaitSet`; [`Client::devices`] for device states.
//! - Command: typed methods on [`Axis`] (`position`, `ramp_to`, `velocity`, `ramp_velocity`,
//!   `power`, `stop`, `off`, `home`, `set_position`, `claim`, `release`), on [`Signal`]
//!   (`set`, `claim`, `release`) and on [`Client`] (`estop`, `reset`, `stop_all`,
//!   `off_all`); each returns [`Accepted`] or [`ClientError::Refused`] with the server's
//!   typed [`Reason`](motion_ipc::Reason) and, where it helps, the case in words ("device
//!   `six` is starting: …", the fault sentence of a faulted axis). Requests carry this
//!   client's iceoryx2 node id; the server takes identity from the transport (zero is
//!   allowed, a borrowed id is refused).
//! - Wait: [`Client::wait_ready`] / [`Axis::wait_ready`] (devices online),
//!   [`Axis::wait_until_arrived`], [`Axis::wait_until_homed`] (a faulted axis ends them with
//!   [`ClientError::AxisFaulted`] carrying [`FaultCode::explain`](motion_ipc::FaultCode::explain)'s
//!   sentence), [`Signal::wait_for`] / [`Signal::wait_until`].
//! - Coordinated motion: [`Client::group`] finds an axis group (`[[group]]`); [`Group`]
//!   moves its axes together along a synchronized line ([`Group::move_to`]) or a
//!   [`Trajectory`] ([`Group::follow`]), holds, resumes, sets the feed, cancels, claims every
//!   member at once, and [`Group::wait_done`] ends with the motion (an abort is
//!   [`ClientError::GroupAborted`] naming the reason, the axis and the figures; a refused
//!   path [`ClientError::GroupRefused`] naming the point and the axis). Shared memory only
//!   for now (not through a bridge).
//! - Streaming: [`Group::stream`] claims a group and starts a [`SetpointStream`]: a
//!   controller sends a setpoint (positions, velocities or powers) per tick
//!   ([`SetpointStream::send`]) or closes its loop with
//!   [`SetpointStream::run_each_tick`] (read the frame, write the next tick's values);
//!   the frames count what the server applied ([`SetpointStream::state`]); dropping the
//!   stream stops the axes and releases the claim. `examples/closed_loop.rs` streams a
//!   sine to a real server.
//! - Jog: [`Axis::jog`] returns a [`JogGuard`] that renews the server's deadman while your
//!   program keeps calling into the client, and stops the axis when dropped;
//!   [`Axis::claim_guard`] a [`ClaimGuard`].
//! - Emergency: [`estop`] latches the e-stop with no connected client (command service,
//!   else the estop event, else SIGUSR1 to the process the server's pid file names), says
//!   which path worked, and succeeds only when the server said so (a frame showing the
//!   latch, or the command service's reply when no frame slot is free); [`stop_all`] needs
//!   only the command service.
//! - Restarts: a server that restarts under the client (a new process on the same name) is
//!   noticed from its description, its frames or its replies ([`Client::restart`],
//!   [`ClientError::ServerRestarted`]). Guards fail safe: nothing is renewed or released on
//!   the new server; other goals wait for [`Client::acknowledge_restart`]; stops, e-stops
//!   and offs always go out.
//!
//! ```no_run
//! use core::time::Duration;
//! use iceoryx2::prelude::ipc;
//! use motion_client::{Client, ClientError};
//!
//! fn main() -> Result<(), Box<dyn std::error::Error>> {
//!     let client = Client::<ipc::Service>::connect("demo")?;
//!     client.wait_ready(Duration::from_secs(10))?; // every board answered
//!     let x = client.axis("x")?;
//!     println!("x is at {} {}", x.state()?.position, x.info().unit());
//!
//!     x.ramp_to(10.0, 0.0, 0.0)?; // 0.0: the axis's max velocity and acceleration
//!     x.wait_until_arrived(Duration::from_secs(10))?;
//!
//!     match x.position(1e9) {
//!         Err(ClientError::Refused { reason, .. }) => println!("refused: {reason}"),
//!         other => println!("unexpected: {other:?}"),
//!     }
//!
//!     let jog = x.jog(-2.0, 0.0)?; // stops when `jog` is dropped
//!     for frame in client.frames(Duration::from_secs(1)).take(500) {
//!         let frame = frame?;
//!         println!("tick {} x {:.3}", frame.tick, frame.axes()[0].position);
//!     }
//!     jog.stop()?;
//!
//!     if let Ok(lamp) = client.signal("lamp") {
//!         lamp.set(true)?;
//!     }
//!     Ok(())
//! }
//! ```
//!
//! `examples/jog_and_move.rs` is a complete program doing the same against a running
//! server.
//!
//! Across hosts (feature `zenoh`): the same API through a `motion-bridge` running beside
//! the server, `ClientBuilder::new("demo").remote("tcp/HOST:7447").identity("panel")`;
//! see the [`remote`] module (with the feature) and `crates/motion-bridge/README.md`.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod axis;
mod claim;
mod client;
mod command;
mod commission;
mod emergency;
mod error;
#[cfg(feature = "zenoh")]
mod feed;
mod frames;
mod group;
mod group_error;
mod group_state;
mod iceoryx2_error;
mod jog;
#[cfg(feature = "zenoh")]
mod link;
mod ports;
mod ready;
mod received;
#[cfg(feature = "zenoh")]
pub mod remote;
mod remote_error;
mod session;
mod signal;
mod stream;
mod stream_status;
#[cfg(feature = "testing")]
pub mod testing;
mod trajectory;
mod unanswered;

pub use axis::Axis;
pub use claim::ClaimGuard;
pub use client::{
    Client, ClientBuilder, DEFAULT_CONNECT_TIMEOUT, DEFAULT_REPLY_TIMEOUT, Frame, Info, Params,
    Stats, TickListener,
};
pub use command::Accepted;
pub use commission::Commissioned;
pub use emergency::{Estop, EstopPath, estop, stop_all};
pub use error::{ClientError, ConnectError, DeviceStatus, EstopError, Restart};
pub use frames::{FIRST_FRAME_TIMEOUT, Frames};
pub use group::{Group, GroupRun};
pub use group_error::{GroupAborted, GroupRefusal};
pub use group_state::{GroupOutcome, GroupStatus};
pub use iceoryx2_error::Iceoryx2Error;
pub use jog::JogGuard;
pub use motion_ipc as ipc;
pub use received::Received;
pub use remote_error::{RemoteError, RemoteSource};
pub use signal::{Signal, SignalEvent, signal_value_text};
pub use stream::{DEFAULT_STREAM_LEAD, STREAM_FRAME_TIMEOUT, SetpointStream};
pub use stream_status::{StreamError, StreamRun, StreamStatus};
pub use trajectory::{PointKind, Trajectory, TrajectoryError};
pub use unanswered::Unanswered;
