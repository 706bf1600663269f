//! Bridges one motiond instance beyond its host: its frames, description and statistics go
//! out on zenoh key expressions in the same binary layout as in shared memory (plus a JSON
//! state for tools), and commands come back through a zenoh queryable, judged by an
//! allow-list per remote identity, rate-limited, and forwarded to the server's iceoryx2
//! command service. motiond itself stays free of network code: the bridge is its own
//! process, an ordinary client of the server.
//!
//! - [`wire`]: the payloads as bytes (C layout, little-endian) — the network contract,
//!   shared with `motion-client`'s `zenoh` transport.
//! - [`keys`]: key expressions, attachments and the bridge's own refusals.
//! - `policy` (feature `server`): allow-lists, the sessions the bridge issues, rate limits
//!   (one bucket per `[[remote]]` entry), lateness, claims per remote.
//! - `Bridge` (feature `server`) and the `motion-bridge` binary.
//!
//! `crates/motion-bridge/README.md` has the two-terminal example, the config file, the
//! security model (identities, zenoh access control and TLS) and measured latencies.
//!
//! ```
//! use motion_bridge::keys::Keys;
//!
//! let keys = Keys::new("demo").expect("a plain name");
//! assert_eq!(keys.frame(), "motiond/demo/frame");
//! assert_eq!(keys.command("panel"), "motiond/demo/command/panel");
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod keys;
pub mod wire;

#[cfg(feature = "server")]
mod bridge;
#[cfg(feature = "server")]
pub mod config;
#[cfg(feature = "server")]
mod json;
#[cfg(feature = "server")]
pub mod policy;

#[cfg(feature = "server")]
pub use bridge::{Bridge, BridgeError, zenoh_config};
