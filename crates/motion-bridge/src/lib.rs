//! Bridges one motiond instance beyond its host: its frames, description and statistics go
//! out on zenoh key expressions in the same binary layout as in shared memory (plus a JSON
//! state for tools), and commands come back through a zenoh queryable, judged by an
//! allow-list per remote identity, rate-limited, and forwarded to the server's iceoryx2
//! command service. motiond itself stays free of network code: the bridge is its own
//! process, an ordinary client of the server.
//!
//! The network contract (key expressions, attachments, refusals, the payloads as bytes and
//! the JSON state) is the `motion-wire` crate, shared with `motion-client`'s `zenoh`
//! transport. Here:
//! - [`policy`]: allow-lists, the sessions the bridge issues, rate limits (one bucket per
//!   `[[remote]]` entry), lateness, claims per remote.
//! - [`config`]: the bridge's config file and command line.
//! - [`Bridge`] and the `motion-bridge` binary.
//!
//! `crates/motion-bridge/README.md` has the two-terminal example, the config file, the
//! security model (identities, zenoh access control and TLS) and measured latencies; the
//! tests that drive a bridge through `motion-client` are in `crates/motion-bridge-tests`.
//!
//! ```
//! use std::path::Path;
//!
//! use motion_bridge::config::{BridgeConfig, Overrides};
//!
//! let text = "server = \"demo\"\nlisten = [\"tcp/127.0.0.1:7447\"]\n";
//! let config = BridgeConfig::parse(text, Path::new("bridge.toml"), Overrides::default())
//!     .expect("a valid config");
//! assert_eq!(config.server, "demo");
//! assert_eq!(config.listen, ["tcp/127.0.0.1:7447"]);
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod bridge;
pub mod config;
pub mod policy;

pub use bridge::{Bridge, BridgeError, zenoh_config};
