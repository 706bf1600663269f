//! systemd integration without libsystemd: `sd_notify` datagrams on `$NOTIFY_SOCKET`
//! (`READY=1`, `WATCHDOG=1`, `STATUS=…`, `STOPPING=1`; sd_notify(3)), and a watchdog fed only
//! while the tick thread keeps completing ticks.
//!
//! The tick thread stamps [`TickHealth`] at the end of every tick (one relaxed atomic store);
//! the main thread's housekeeping asks [`Supervisor::poll`] every few milliseconds, which
//! sends `WATCHDOG=1` every half `$WATCHDOG_USEC` as long as the newest stamp is recent. A
//! stuck tick stops the pings and systemd restarts the service (`WatchdogSec=`,
//! deploy/motiond.service). `READY=1` goes once the services exist and every configured
//! device is online, so `systemctl start` returns when the machine can move.

use core::time::Duration;
use std::io;
use std::os::linux::net::SocketAddrExt as _;
use std::os::unix::net::{SocketAddr, UnixDatagram};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::NotifyError;

/// A connection to the service manager's notification socket.
#[derive(Debug)]
pub struct Notifier {
    socket: UnixDatagram,
    address: SocketAddr,
}

impl Notifier {
    /// From `$NOTIFY_SOCKET`: `Ok(None)` when it is not set (not started by systemd, or not
    /// `Type=notify`), an error when it is set but unusable.
    pub fn from_env() -> Result<Option<Self>, NotifyError> {
        match std::env::var_os("NOTIFY_SOCKET") {
            None => Ok(None),
            Some(value) => {
                let text = value.to_str().ok_or(NotifyError::NotUtf8)?;
                Self::connect(text).map(Some)
            }
        }
    }

    /// A socket path (`/run/systemd/notify`) or an abstract name (`@name`).
    pub fn connect(target: &str) -> Result<Self, NotifyError> {
        let address = if let Some(name) = target.strip_prefix('@') {
            SocketAddr::from_abstract_name(name.as_bytes())
        } else if target.starts_with('/') {
            SocketAddr::from_pathname(target)
        } else {
            return Err(NotifyError::BadTarget(target.to_owned()));
        }
        .map_err(|source| NotifyError::Address {
            target: target.to_owned(),
            source,
        })?;
        let socket = UnixDatagram::unbound().map_err(NotifyError::Socket)?;
        Ok(Self { socket, address })
    }

    /// Sends one notification (`KEY=value` lines).
    pub fn send(&self, state: &str) -> io::Result<()> {
        self.socket.send_to_addr(state.as_bytes(), &self.address)?;
        Ok(())
    }
}

/// The watchdog interval systemd asks for (`$WATCHDOG_USEC`), unless `$WATCHDOG_PID` names
/// another process.
pub fn watchdog_from_env() -> Option<Duration> {
    watchdog_interval(
        std::env::var("WATCHDOG_USEC").ok().as_deref(),
        std::env::var("WATCHDOG_PID").ok().as_deref(),
        std::process::id(),
    )
}

/// [`watchdog_from_env`] on given values.
pub fn watchdog_interval(usec: Option<&str>, pid: Option<&str>, own_pid: u32) -> Option<Duration> {
    if let Some(pid) = pid
        && pid.trim().parse::<u32>().ok() != Some(own_pid)
    {
        return None;
    }
    let usec: u64 = usec?.trim().parse().ok()?;
    (usec > 0).then(|| Duration::from_micros(usec))
}

/// The tick thread's heartbeat: CLOCK_MONOTONIC (ns) at the end of its newest tick.
#[derive(Debug, Default)]
pub struct TickHealth {
    last_tick_ns: AtomicU64,
}

impl TickHealth {
    /// Called by the tick thread at the end of every tick.
    pub fn beat(&self, now: Duration) {
        let ns = u64::try_from(now.as_nanos()).unwrap_or(u64::MAX);
        self.last_tick_ns.store(ns, Ordering::Relaxed);
    }

    /// The newest beat (`None` before the first tick).
    pub fn last(&self) -> Option<Duration> {
        match self.last_tick_ns.load(Ordering::Relaxed) {
            0 => None,
            ns => Some(Duration::from_nanos(ns)),
        }
    }
}

/// What the watchdog decided at one poll.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feed {
    /// Nothing due.
    Wait,
    /// Send `WATCHDOG=1` now.
    Ping,
    /// The tick has not completed a tick for this long: no ping (reported once per stall).
    Stalled(Duration),
}

/// Decides when to ping the watchdog from the tick's heartbeat (pure: time is passed in).
#[derive(Debug, Clone)]
pub struct WatchdogFeeder {
    every: Duration,
    stale_after: Duration,
    next: Duration,
    stalled: bool,
}

impl WatchdogFeeder {
    /// Pings every half `interval` while the newest tick is younger than a quarter of it
    /// (at least 20 tick periods, so a few overruns are not a stall).
    pub fn new(interval: Duration, tick_period: Duration) -> Self {
        Self {
            every: interval / 2,
            stale_after: (interval / 4).max(tick_period * 20),
            next: Duration::ZERO,
            stalled: false,
        }
    }

    /// What to do at `now`, given the tick's newest beat.
    pub fn poll(&mut self, now: Duration, last_tick: Option<Duration>) -> Feed {
        let age = last_tick.map_or(Duration::MAX, |beat| now.saturating_sub(beat));
        if age > self.stale_after {
            if self.stalled {
                return Feed::Wait;
            }
            self.stalled = true;
            return Feed::Stalled(age);
        }
        self.stalled = false;
        if now >= self.next {
            self.next = now + self.every;
            return Feed::Ping;
        }
        Feed::Wait
    }
}

/// The server's conversation with systemd: readiness, status, watchdog, stopping.
#[derive(Debug)]
pub struct Supervisor {
    notifier: Notifier,
    watchdog: Option<WatchdogFeeder>,
    started: bool,
    ready: bool,
    stopping: bool,
    /// The devices not online and the count, as last reported.
    devices_seen: Option<(String, usize)>,
}

impl Supervisor {
    /// With the watchdog when systemd asked for one.
    pub fn new(notifier: Notifier, watchdog: Option<Duration>, tick_period: Duration) -> Self {
        Self {
            notifier,
            watchdog: watchdog.map(|interval| WatchdogFeeder::new(interval, tick_period)),
            started: false,
            ready: false,
            stopping: false,
            devices_seen: None,
        }
    }

    /// From the environment: `None` when systemd is not listening (or the socket is
    /// unusable: logged).
    pub fn from_env(tick_period: Duration) -> Option<Self> {
        match Notifier::from_env() {
            Ok(Some(notifier)) => Some(Self::new(notifier, watchdog_from_env(), tick_period)),
            Ok(None) => None,
            Err(error) => {
                tracing::warn!("systemd notification disabled: {error}");
                None
            }
        }
    }

    fn send(&self, state: &str) {
        if let Err(error) = self.notifier.send(state) {
            tracing::warn!("systemd notification {state:?} not sent: {error}");
        }
    }

    /// The services exist and the tick runs; `waiting` names the devices not online yet.
    pub fn started(&mut self, waiting: &[&str], devices: usize) {
        self.started = true;
        self.devices(waiting, devices);
    }

    /// The devices not online (of `devices`): `READY=1` the first time none is missing
    /// (once started), a `STATUS=` line naming them otherwise.
    pub fn devices(&mut self, waiting: &[&str], devices: usize) {
        let key = (waiting.join(", "), devices);
        if self.devices_seen.as_ref() == Some(&key) || !self.started || self.stopping {
            return;
        }
        let (names, devices) = key.clone();
        self.devices_seen = Some(key);
        let online = devices.saturating_sub(waiting.len());
        if waiting.is_empty() && !self.ready {
            self.ready = true;
            self.send(&format!(
                "READY=1\nSTATUS=ready: {devices} device(s) online, serving"
            ));
        } else if waiting.is_empty() {
            self.send(&format!("STATUS=serving: {devices} device(s) online"));
        } else if self.ready {
            self.send(&format!(
                "STATUS=serving: {online} of {devices} device(s) online; not answering: {names}"
            ));
        } else {
            self.send(&format!(
                "STATUS=starting: services up, waiting for {names} ({online} of {devices} device(s) online)"
            ));
        }
    }

    /// Shutdown began: `STOPPING=1` once.
    pub fn stopping(&mut self) {
        if !self.stopping {
            self.stopping = true;
            self.send("STOPPING=1\nSTATUS=stopping every axis");
        }
    }

    /// Feeds the watchdog from the tick's heartbeat; returns how long the tick has been
    /// stuck when a stall begins (the caller logs it).
    pub fn poll(&mut self, now: Duration, health: &TickHealth) -> Option<Duration> {
        if !self.started {
            return None;
        }
        let feed = self.watchdog.as_mut()?.poll(now, health.last());
        match feed {
            Feed::Wait => None,
            Feed::Ping => {
                self.send("WATCHDOG=1");
                None
            }
            Feed::Stalled(age) => {
                self.send(&format!(
                    "STATUS=tick thread stuck for {} ms: watchdog no longer fed",
                    age.as_millis()
                ));
                Some(age)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fake service manager: a datagram socket at a temp path.
    struct FakeManager {
        socket: UnixDatagram,
        path: std::path::PathBuf,
    }

    impl FakeManager {
        fn new(tag: &str) -> Self {
            let path = std::env::temp_dir()
                .join(format!("motiond-notify-{}-{tag}.sock", std::process::id()));
            let _ = std::fs::remove_file(&path);
            let socket = UnixDatagram::bind(&path).expect("bind the fake notify socket");
            socket.set_nonblocking(true).expect("nonblocking");
            Self { socket, path }
        }

        fn notifier(&self) -> Notifier {
            Notifier::connect(self.path.to_str().expect("utf-8 path")).expect("connect")
        }

        fn messages(&self) -> Vec<String> {
            let mut buf = [0u8; 4096];
            let mut out = Vec::new();
            while let Ok(len) = self.socket.recv(&mut buf) {
                out.push(String::from_utf8_lossy(&buf[..len]).into_owned());
            }
            out
        }
    }

    impl Drop for FakeManager {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.path);
        }
    }

    #[test]
    fn notifications_reach_a_path_socket_and_an_abstract_one() {
        let manager = FakeManager::new("path");
        manager.notifier().send("READY=1\nSTATUS=x").expect("send");
        assert_eq!(manager.messages(), ["READY=1\nSTATUS=x"]);

        let name = format!("motiond-test-{}", std::process::id());
        let address = SocketAddr::from_abstract_name(name.as_bytes()).expect("abstract name");
        let listener = UnixDatagram::bind_addr(&address).expect("bind abstract");
        Notifier::connect(&format!("@{name}"))
            .expect("connect")
            .send("WATCHDOG=1")
            .expect("send");
        let mut buf = [0u8; 64];
        let len = listener.recv(&mut buf).expect("receive");
        assert_eq!(&buf[..len], b"WATCHDOG=1");
    }

    #[test]
    fn bad_notify_sockets_are_errors() {
        assert!(Notifier::connect("relative/path").is_err());
        assert!(Notifier::connect("").is_err());
        let nobody = Notifier::connect("/nonexistent/motiond/notify").expect("connect is lazy");
        assert!(nobody.send("READY=1").is_err(), "nobody listens there");
    }

    #[test]
    fn watchdog_interval_follows_systemd_s_variables() {
        assert_eq!(
            watchdog_interval(Some("2000000"), None, 7),
            Some(Duration::from_secs(2))
        );
        assert_eq!(
            watchdog_interval(Some("2000000"), Some("7"), 7),
            Some(Duration::from_secs(2))
        );
        assert_eq!(watchdog_interval(Some("2000000"), Some("8"), 7), None);
        assert_eq!(watchdog_interval(Some("0"), None, 7), None);
        assert_eq!(watchdog_interval(Some("soon"), None, 7), None);
        assert_eq!(watchdog_interval(None, None, 7), None);
    }

    #[test]
    fn the_feeder_pings_only_while_ticks_complete() {
        let ms = Duration::from_millis;
        // WatchdogSec=2s at 1 kHz: ping every 1 s, stale after 500 ms.
        let mut feeder = WatchdogFeeder::new(ms(2000), ms(1));
        assert_eq!(feeder.poll(ms(0), None), Feed::Stalled(Duration::MAX));
        assert_eq!(
            feeder.poll(ms(5), None),
            Feed::Wait,
            "a stall is reported once"
        );
        assert_eq!(feeder.poll(ms(10), Some(ms(9))), Feed::Ping);
        assert_eq!(feeder.poll(ms(500), Some(ms(499))), Feed::Wait);
        assert_eq!(feeder.poll(ms(1010), Some(ms(1009))), Feed::Ping);
        // The tick stops at 1200 ms: pings stop once its beat is 500 ms old.
        assert_eq!(feeder.poll(ms(1700), Some(ms(1200))), Feed::Wait);
        assert_eq!(
            feeder.poll(ms(1701), Some(ms(1200))),
            Feed::Stalled(ms(501))
        );
        for at in (1800..6000).step_by(100) {
            assert_eq!(
                feeder.poll(ms(at), Some(ms(1200))),
                Feed::Wait,
                "at {at} ms"
            );
        }
        // It recovers: pings again at once.
        assert_eq!(feeder.poll(ms(6000), Some(ms(5999))), Feed::Ping);
    }

    #[test]
    fn the_feeder_tolerates_a_few_overruns_at_slow_ticks() {
        let ms = Duration::from_millis;
        // WatchdogSec=1s at 10 Hz: stale after 20 periods (2 s), not 250 ms.
        let mut feeder = WatchdogFeeder::new(ms(1000), ms(100));
        assert_eq!(feeder.poll(ms(0), Some(ms(0))), Feed::Ping);
        assert_eq!(feeder.poll(ms(1500), Some(ms(0))), Feed::Ping);
        assert_eq!(feeder.poll(ms(2001), Some(ms(0))), Feed::Stalled(ms(2001)));
    }

    #[test]
    fn the_supervisor_says_ready_once_every_device_is_online_and_stops_feeding_a_stuck_tick() {
        let manager = FakeManager::new("supervisor");
        let ms = Duration::from_millis;
        let mut supervisor = Supervisor::new(manager.notifier(), Some(ms(400)), ms(1));
        let health = TickHealth::default();
        // Nothing before the services exist.
        supervisor.devices(&["a", "b"], 2);
        assert_eq!(supervisor.poll(ms(1), &health), None);
        assert!(manager.messages().is_empty());
        supervisor.started(&["a", "b"], 2);
        supervisor.devices(&["b"], 2);
        supervisor.devices(&["b"], 2); // unchanged: not repeated
        assert_eq!(
            manager.messages(),
            [
                "STATUS=starting: services up, waiting for a, b (0 of 2 device(s) online)",
                "STATUS=starting: services up, waiting for b (1 of 2 device(s) online)",
            ]
        );
        supervisor.devices(&[], 2);
        assert_eq!(
            manager.messages(),
            ["READY=1\nSTATUS=ready: 2 device(s) online, serving"]
        );
        supervisor.devices(&["a"], 2);
        supervisor.devices(&[], 2);
        assert_eq!(
            manager.messages(),
            [
                "STATUS=serving: 1 of 2 device(s) online; not answering: a",
                "STATUS=serving: 2 device(s) online",
            ],
            "READY is sent once"
        );
        // Ticks complete: WATCHDOG=1 every 200 ms.
        let mut pings = 0;
        for at in (10..1000).step_by(10) {
            health.beat(ms(at));
            assert_eq!(supervisor.poll(ms(at), &health), None);
            pings += manager
                .messages()
                .iter()
                .filter(|m| *m == "WATCHDOG=1")
                .count();
        }
        assert_eq!(pings, 5);
        // The tick sticks: its newest beat stays at 990 ms. Pings may go on while that beat
        // is fresh (up to 100 ms old)...
        for at in (1000..1100).step_by(10) {
            assert_eq!(supervisor.poll(ms(at), &health), None);
        }
        let _ = manager.messages();
        // ...then never again, and the stall is reported once.
        let mut stalled = Vec::new();
        for at in (1100..3000).step_by(10) {
            stalled.extend(supervisor.poll(ms(at), &health));
        }
        assert_eq!(stalled, [ms(110)]);
        let messages = manager.messages();
        assert!(messages.iter().all(|m| m != "WATCHDOG=1"), "{messages:?}");
        assert_eq!(messages.len(), 1, "{messages:?}");
        assert!(
            messages[0].starts_with("STATUS=tick thread stuck"),
            "{messages:?}"
        );
        supervisor.stopping();
        supervisor.stopping();
        supervisor.devices(&["a", "b"], 2);
        assert_eq!(
            manager.messages(),
            ["STOPPING=1\nSTATUS=stopping every axis"]
        );
    }
}
