//! The network contract of motiond: what a remote peer (motion-client's `zenoh` transport,
//! a tool in another language) and `motion-bridge` agree on, and nothing that does I/O.
//!
//! - [`keys`]: the zenoh key expressions of an instance (built on `motion-ipc`'s service
//!   names), the attachments beside the payloads, the bridge's refusals.
//! - [`wire`]: the `motion-ipc` payloads as bytes (C layout, little-endian), walked through
//!   `motion-ipc`'s schema: no field list here.
//! - [`json`] (feature `json`): the JSON state published for tools, and the axis, signal
//!   and device views `motionctl status --json` shares with it.
//!
//! Both the client and the bridge depend on this crate; it depends on `motion-ipc` only.
//!
//! ```
//! use motion_ipc::{ClientId, CommandKind, CommandRequest};
//! use motion_wire::keys::Keys;
//! use motion_wire::wire;
//!
//! let keys = Keys::new("demo").expect("a plain name");
//! assert_eq!(keys.frame(), "motiond/demo/frame");
//! assert_eq!(keys.command("panel"), "motiond/demo/command/panel");
//!
//! let request = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Stop);
//! let bytes = wire::encode(&request);
//! assert_eq!(wire::decode::<CommandRequest>(&bytes), Ok(request));
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(feature = "json")]
pub mod json;
pub mod keys;
pub mod wire;
