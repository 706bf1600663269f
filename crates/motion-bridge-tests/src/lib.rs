//! The end-to-end tests of `motion-bridge` and its latency bench: the bridge driven through
//! `motion-client` (a remote `Client`, `motionctl --remote`) or raw zenoh, against the fake
//! motiond of `motion-client` or a real one. They live in their own crate because
//! `motion-client` sits above the bridge: neither the bridge nor the client depends on the
//! other, and this crate may depend on both (`publish = false`, nothing here ships).
//!
//! The tests are in `tests/` (`cargo test -p motion-bridge-tests`, `--features tls` for the
//! TLS one), the bench in `benches/bridge_latency.rs`; this library is what they share: a
//! bridge on a thread of the test, a fake or real motiond, remote clients, free ports
//! ([`raw`]: a foreign peer's raw zenoh; [`real`]: real processes).

pub mod raw;
pub mod real;

use core::time::Duration;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Instant;

use iceoryx2::prelude::ipc;
use motion_bridge::Bridge;
use motion_bridge::config::{BridgeConfig, Overrides};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientBuilder};

pub type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

/// Long enough for anything on a loaded 2-core machine; never a timing assertion.
pub const DEADLINE: Duration = Duration::from_secs(20);

/// A TCP port of 127.0.0.1 nobody listens on now.
pub fn free_port() -> Result<u16> {
    let listener = std::net::TcpListener::bind("127.0.0.1:0")?;
    Ok(listener.local_addr()?.port())
}

/// A directory of its own under the temp dir.
pub fn scratch(prefix: &str) -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(unique_name(prefix));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}

/// The demo fake motiond (500 Hz, deadman 250 ms, axes x, y, a).
pub fn fake(prefix: &str) -> Result<FakeServer> {
    Ok(FakeServer::start::<ipc::Service>(FakeConfig::demo(
        &unique_name(prefix),
    ))?)
}

/// A bridge running on a thread of the test; stops (and joins) when dropped.
#[derive(Debug)]
pub struct BridgeThread {
    pub endpoint: String,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
}

impl BridgeThread {
    /// A bridge of `server` on a free loopback port with `config_toml` (the `[[remote]]`
    /// tables and other keys; `server` and `listen` are set here), `--insecure` (the tests'
    /// rules are wide, zenoh authenticates nobody, and only loopback reaches it).
    pub fn start(server: &str, config_toml: &str) -> Result<Self> {
        Self::start_with(server, config_toml, None)
    }

    /// [`BridgeThread::start`] with zenoh's own config file.
    pub fn start_with(
        server: &str,
        config_toml: &str,
        zenoh_config: Option<PathBuf>,
    ) -> Result<Self> {
        let endpoint = format!("tcp/127.0.0.1:{}", free_port()?);
        Self::start_on(server, config_toml, zenoh_config, &endpoint)
    }

    /// [`BridgeThread::start_with`] listening on `endpoint`.
    pub fn start_on(
        server: &str,
        config_toml: &str,
        zenoh_config: Option<PathBuf>,
        endpoint: &str,
    ) -> Result<Self> {
        let endpoint = endpoint.to_owned();
        let overrides = Overrides {
            server: Some(server.to_owned()),
            listen: vec![endpoint.clone()],
            zenoh_config,
            insecure: true,
            ..Overrides::default()
        };
        let config =
            BridgeConfig::parse(config_toml, std::path::Path::new("test.toml"), overrides)?;
        Self::start_config(config, endpoint)
    }

    /// A bridge of exactly `config` (listening on `endpoint`).
    pub fn start_config(config: BridgeConfig, endpoint: String) -> Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let flag = Arc::clone(&stop);
        let handle = std::thread::Builder::new()
            .name("bridge".to_owned())
            .spawn(move || match Bridge::start(config) {
                Ok(mut bridge) => {
                    let _ = ready_tx.send(Ok(()));
                    bridge.run(&flag);
                }
                Err(error) => {
                    let _ = ready_tx.send(Err(error.to_string()));
                }
            })?;
        ready_rx.recv_timeout(DEADLINE)??;
        Ok(Self {
            endpoint,
            stop,
            handle: Some(handle),
        })
    }
}

impl Drop for BridgeThread {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }
}

/// A remote client of `server` through the bridge at `endpoint`, as `identity`.
pub fn remote(server: &str, endpoint: &str, identity: &str) -> Result<Client<ipc::Service>> {
    Ok(ClientBuilder::new(server)
        .node_name("bridge-test")
        .connect_timeout(Duration::from_secs(10))
        .remote(endpoint)
        .identity(identity)
        .connect::<ipc::Service>()?)
}

/// Polls `check` until it holds or [`DEADLINE`] passes.
pub fn eventually(what: &str, mut check: impl FnMut() -> Result<bool>) -> Result {
    let until = Instant::now() + DEADLINE;
    loop {
        if check()? {
            return Ok(());
        }
        if Instant::now() > until {
            return Err(format!("never happened: {what}").into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}
