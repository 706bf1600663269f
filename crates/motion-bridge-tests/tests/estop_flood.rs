//! An e-stop through the bridge under a flood of stops (issue 40, item 1), with real
//! `motiond`, `motion-bridge` and `motionctl` processes: the e-stop has its own path
//! through the bridge, so no bound it shares with stops can refuse it.
//!
//! - Two anonymous peers (the `*` entry may send `stop`) send `stop` for one axis as fast
//!   as they can (paced to about 10 000 queries a second each) while the panel's e-stop is
//!   sent 20 times through the Rust remote client and 20 times with `motionctl --remote …
//!   --identity panel estop`: every one is accepted and latches.
//! - One peer sends 1500 stops at once, the e-stop right behind them, 20 times: the same.
//!
//! The delay is measured in server time: the tick of the newest frame the server had
//! published when the e-stop left (read over shared memory) against the tick its reply says
//! it latched in. The figures are printed, not asserted (a loaded test machine is no
//! measure); what is asserted is that every e-stop was accepted and latched.

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use iceoryx2::prelude::ipc;
use motion_bridge_tests::raw::{self, Z as _};
use motion_bridge_tests::real::{Rig, binaries};
use motion_bridge_tests::{DEADLINE, Result};
use motion_client::ipc::{ClientId, CommandKind, CommandRequest, FrameFlags};
use motion_client::{Client, ClientBuilder};
use motion_wire::keys::{ANONYMOUS, Keys, Refusal};
use motion_wire::wire;
use zenoh::Wait as _;

/// The panel may do anything; any other identity may only stop (no e-stop).
const RULES: &str = r#"
[[remote]]
identity = "panel"
allow = ["all"]

[[remote]]
identity = "*"
allow = ["stop"]
"#;

/// How many e-stops each way.
const ROUNDS: usize = 20;

/// The answers a flooder got, by kind.
#[derive(Debug, Default)]
struct Counts {
    sent: AtomicU64,
    accepted: AtomicU64,
    busy: AtomicU64,
    rate_limited: AtomicU64,
    other: AtomicU64,
}

impl Counts {
    fn answered(&self) -> u64 {
        self.accepted.load(Ordering::Relaxed)
            + self.busy.load(Ordering::Relaxed)
            + self.rate_limited.load(Ordering::Relaxed)
            + self.other.load(Ordering::Relaxed)
    }
}

/// Sends an anonymous stop of `axis` without waiting for its answer (counted in `counts`
/// when it comes).
fn send_stop(
    session: &zenoh::Session,
    keys: &Keys,
    axis: u32,
    sequence: u64,
    counts: &Arc<Counts>,
) -> Result {
    let stop = CommandRequest::new(ClientId::NONE, sequence, axis, CommandKind::Stop);
    let counted = Arc::clone(counts);
    session
        .get(keys.command(ANONYMOUS))
        .payload(wire::encode(&stop))
        .timeout(Duration::from_secs(5))
        .callback(move |reply| {
            let slot = match reply.result() {
                Ok(_) => &counted.accepted,
                Err(error) => {
                    let text = String::from_utf8_lossy(&error.payload().to_bytes()).into_owned();
                    match Refusal::parse(&text).map(|(refusal, _)| refusal) {
                        Some(Refusal::Busy) => &counted.busy,
                        Some(Refusal::RateLimited) => &counted.rate_limited,
                        _ => {
                            if counted.other.load(Ordering::Relaxed) == 0 {
                                eprintln!("peer: a stop answered `{text}`");
                            }
                            &counted.other
                        }
                    }
                }
            };
            slot.fetch_add(1, Ordering::Relaxed);
        })
        .wait()
        .z()?;
    counts.sent.fetch_add(1, Ordering::Relaxed);
    Ok(())
}

/// How a flooding peer runs: a process of its own (this test binary again, running
/// [`peer`]), so that its zenoh runtime is not the remote client's — as two peers on the
/// network are.
const PEER_ENV: &str = "MOTION_BRIDGE_TEST_PEER";

/// A flooding peer: this test binary running [`peer`] with `mode` (`flood <axis>
/// <per_second>`: stops of `axis` at that rate until its stdin closes; `burst <axes>`:
/// on each line `burst N` from stdin, N stops over `axes` axes, then `sent` on stdout).
/// On its stdin's end it prints its [`Counts`] as `counts sent accepted busy rate_limited
/// other` and exits.
struct Peer {
    child: std::process::Child,
    lines: std::io::Lines<std::io::BufReader<std::process::ChildStdout>>,
}

impl Peer {
    fn start(rig: &Rig, mode: &str) -> Result<Self> {
        let mut child = std::process::Command::new(std::env::current_exe()?)
            .args([
                "--exact",
                "peer",
                "--ignored",
                "--nocapture",
                "--test-threads",
                "1",
            ])
            .env(PEER_ENV, format!("{} {} {mode}", rig.endpoint, rig.name))
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::inherit())
            .spawn()?;
        let stdout = child.stdout.take().ok_or("the peer's stdout")?;
        let mut peer = Self {
            child,
            lines: std::io::BufRead::lines(std::io::BufReader::new(stdout)),
        };
        peer.expect("ready")?;
        Ok(peer)
    }

    /// Reads lines until one starts with `word`; that line.
    fn expect(&mut self, word: &str) -> Result<String> {
        for line in self.lines.by_ref() {
            // The harness writes `test peer ... ` before the peer's first line.
            let line = line?;
            if let Some((_, said)) = line.split_once("peer: ")
                && said.starts_with(word)
            {
                return Ok(said.to_owned());
            }
        }
        Err(format!("the peer ended before saying `{word}`").into())
    }

    fn say(&mut self, line: &str) -> Result {
        use std::io::Write as _;
        let stdin = self.child.stdin.as_mut().ok_or("the peer's stdin")?;
        writeln!(stdin, "{line}")?;
        stdin.flush()?;
        Ok(())
    }

    /// Ends the peer (its stdin closed) and returns its counts.
    fn finish(mut self) -> Result<[u64; 5]> {
        drop(self.child.stdin.take());
        let line = self.expect("counts")?;
        let _ = self.child.wait();
        let numbers: Vec<u64> = line
            .split_whitespace()
            .skip(1)
            .map(str::parse)
            .collect::<core::result::Result<_, _>>()?;
        numbers
            .try_into()
            .map_err(|_| format!("not five counts: {line}").into())
    }
}

fn summary([sent, accepted, busy, rate_limited, other]: [u64; 5]) -> String {
    format!(
        "{sent} sent: {accepted} answered by the server, {busy} busy, {rate_limited} \
         rate-limited, {other} other (no answer within 5 s)"
    )
}

/// The flooding peer's side (see [`Peer`]); runs only as a child of the tests below.
#[test]
#[ignore = "a flooding peer: run by the tests of this file as a process of its own"]
fn peer() -> Result {
    let Ok(what) = std::env::var(PEER_ENV) else {
        return Ok(());
    };
    let words: Vec<&str> = what.split_whitespace().collect();
    let [endpoint, name, mode, rest @ ..] = &words[..] else {
        return Err(format!("{PEER_ENV}: {what}").into());
    };
    let keys = Keys::new(name)?;
    let session = raw::session(endpoint)?;
    raw::wait_for_server(&session, &keys)?;
    let counts = Arc::new(Counts::default());
    let done = Arc::new(AtomicBool::new(false));
    let stdin_done = Arc::clone(&done);
    let (lines_tx, lines_rx) = std::sync::mpsc::channel::<String>();
    std::thread::spawn(move || {
        for line in std::io::BufRead::lines(std::io::stdin().lock()) {
            match line {
                Ok(line) => {
                    if lines_tx.send(line).is_err() {
                        break;
                    }
                }
                Err(_) => break,
            }
        }
        stdin_done.store(true, Ordering::Relaxed);
    });
    println!("\npeer: ready");
    let mut sequence = 0;
    match (*mode, rest) {
        ("flood", [axis, per_second]) => {
            let axis: u32 = axis.parse()?;
            let per_period = (per_second.parse::<u64>()? / 100).max(1);
            let period = Duration::from_millis(10);
            let mut next = Instant::now();
            while !done.load(Ordering::Relaxed) {
                for _ in 0..per_period {
                    sequence += 1;
                    send_stop(&session, &keys, axis, sequence, &counts)?;
                }
                next += period;
                if let Some(left) = next.checked_duration_since(Instant::now()) {
                    std::thread::sleep(left);
                }
            }
        }
        ("burst", [axes]) => {
            let axes: u32 = axes.parse()?;
            while let Ok(line) = lines_rx.recv() {
                let n: u32 = line.strip_prefix("burst ").ok_or("burst N")?.parse()?;
                for i in 0..n {
                    sequence += 1;
                    // Every third for axis 0, the rest over every axis.
                    let axis = if i % 3 == 0 { 0 } else { i % axes };
                    send_stop(&session, &keys, axis, sequence, &counts)?;
                }
                println!("peer: sent");
            }
        }
        _ => return Err(format!("{PEER_ENV}: {what}").into()),
    }
    let until = Instant::now() + DEADLINE;
    while counts.answered() < counts.sent.load(Ordering::Relaxed) && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(20));
    }
    println!(
        "peer: counts {} {} {} {} {}",
        counts.sent.load(Ordering::Relaxed),
        counts.accepted.load(Ordering::Relaxed),
        counts.busy.load(Ordering::Relaxed),
        counts.rate_limited.load(Ordering::Relaxed),
        counts.other.load(Ordering::Relaxed)
    );
    Ok(())
}

/// The server's own client, over shared memory.
fn local(rig: &Rig) -> Result<Client<ipc::Service>> {
    Ok(ClientBuilder::new(&rig.name)
        .node_name("estop-flood-test")
        .connect_timeout(DEADLINE)
        .connect::<ipc::Service>()?)
}

/// Waits until the server's frames show the e-stop latched (`true`) or cleared; the tick
/// of that frame.
fn until_latched(local: &Client<ipc::Service>, latched: bool, from_tick: u64) -> Result<u64> {
    let until = Instant::now() + DEADLINE;
    loop {
        let frame = local.next_frame(Duration::from_millis(100));
        if let Ok(frame) = frame
            && frame.tick >= from_tick
            && frame.flags().contains(FrameFlags::ESTOP_LATCHED) == latched
        {
            return Ok(frame.tick);
        }
        if Instant::now() > until {
            return Err(format!(
                "the e-stop never {}",
                if latched { "latched" } else { "cleared" }
            )
            .into());
        }
    }
}

/// Clears the e-stop from the server's host and waits until the frames say so.
fn reset(local: &Client<ipc::Service>) -> Result {
    let accepted = local.reset()?;
    until_latched(local, false, accepted.tick)?;
    Ok(())
}

/// The newest tick the server published.
fn now_tick(local: &Client<ipc::Service>) -> Result<u64> {
    Ok(local.latest()?.tick)
}

/// What the e-stops of one way got: the delays in ticks of those latched, the failures.
#[derive(Debug, Default)]
struct Latches {
    ticks: Vec<u64>,
    failures: Vec<String>,
    /// Latched, but the sender said otherwise (it could not see the latch in time).
    complaints: Vec<String>,
}

impl Latches {
    fn report(&self, what: &str, tick_hz: f64) -> String {
        let mut ticks = self.ticks.clone();
        ticks.sort_unstable();
        let ms = |ticks: u64| ticks as f64 * 1000.0 / tick_hz;
        match (ticks.first(), ticks.last()) {
            (Some(least), Some(most)) => format!(
                "{what}: {} of {ROUNDS} latched ({} within 100 ms), {}–{} ms of server time from \
                 the newest frame at sending to the latch (median {} ms); failures: {:?}; \
                 latched, but the sender could not tell: {:?}",
                ticks.len(),
                ticks.iter().filter(|&&t| ms(t) <= 100.0).count(),
                ms(*least),
                ms(*most),
                ms(ticks[ticks.len() / 2]),
                self.failures,
                self.complaints
            ),
            _ => format!("{what}: none latched; failures: {:?}", self.failures),
        }
    }
}

/// The Rust remote client's e-stop as `panel`, `ROUNDS` times, `before` run before each.
fn estops_by_client(
    rig: &Rig,
    local: &Client<ipc::Service>,
    mut before: impl FnMut() -> Result,
) -> Result<Latches> {
    // A reply timeout long enough for a loaded machine: what is asserted is the latch.
    let panel = ClientBuilder::new(&rig.name)
        .node_name("estop-flood-panel")
        .connect_timeout(Duration::from_secs(10))
        .reply_timeout(Duration::from_secs(5))
        .remote(&rig.endpoint)
        .identity("panel")
        .connect::<ipc::Service>()?;
    let mut latches = Latches::default();
    for _ in 0..ROUNDS {
        before()?;
        let sent_at = now_tick(local)?;
        match panel.estop() {
            Ok(accepted) => {
                until_latched(local, true, accepted.tick)?;
                latches.ticks.push(accepted.tick.saturating_sub(sent_at));
            }
            Err(error) => latches.failures.push(error.to_string()),
        }
        reset(local)?;
    }
    Ok(latches)
}

/// `motionctl --remote … --identity panel estop`, `ROUNDS` times (the delay here includes
/// the process's start and its connection to the bridge). Latched is what the server's own
/// frames say; a run that latched the e-stop but could not see it in the bridge's frames in
/// time (motionctl's exit 5 under the flood) is listed in `complaints`.
fn estops_by_motionctl(rig: &Rig, local: &Client<ipc::Service>) -> Result<Latches> {
    let mut latches = Latches::default();
    for _ in 0..ROUNDS {
        let started_at = now_tick(local)?;
        let output = rig.remote("panel", &["estop"])?;
        let latched = until_latched_within(local, started_at, Duration::from_secs(2))?;
        let said = format!(
            "exit {:?}: {}{}",
            output.status.code(),
            String::from_utf8_lossy(&output.stdout).trim(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
        match latched {
            Some(tick) => {
                latches.ticks.push(tick.saturating_sub(started_at));
                if !output.status.success() {
                    latches.complaints.push(said);
                }
                reset(local)?;
            }
            None => latches.failures.push(said),
        }
    }
    Ok(latches)
}

/// The tick of the first frame at or after `from_tick` showing the e-stop latched, if one
/// does within `within`.
fn until_latched_within(
    local: &Client<ipc::Service>,
    from_tick: u64,
    within: Duration,
) -> Result<Option<u64>> {
    let until = Instant::now() + within;
    while Instant::now() < until {
        if let Ok(frame) = local.next_frame(Duration::from_millis(100))
            && frame.tick >= from_tick
            && frame.flags().contains(FrameFlags::ESTOP_LATCHED)
        {
            return Ok(Some(frame.tick));
        }
    }
    Ok(None)
}

#[test]
fn two_stop_floods_do_not_crowd_out_an_estop() -> Result {
    let Some(binaries) = binaries() else {
        return Ok(());
    };
    let rig = Rig::start_with(&binaries, None, RULES, "panel")?;
    let local = local(&rig)?;
    let tick_hz = f64::from(local.info()?.tick_hz);
    let x = local.axis("x")?.index();
    // The same e-stops without a flood, for comparison.
    let quiet = estops_by_client(&rig, &local, || Ok(()))?;
    let flooders = [
        Peer::start(&rig, &format!("flood {x} 10000"))?,
        Peer::start(&rig, &format!("flood {x} 10000"))?,
    ];
    // The flood in full swing first.
    std::thread::sleep(Duration::from_millis(500));
    let flood_start = Instant::now();
    let by_client = estops_by_client(&rig, &local, || Ok(()));
    let by_motionctl = estops_by_motionctl(&rig, &local);
    let flood_time = flood_start.elapsed().as_secs_f64() + 0.5;
    let mut total = [0; 5];
    for flooder in flooders {
        for (sum, count) in total.iter_mut().zip(flooder.finish()?) {
            *sum += count;
        }
    }
    let (by_client, by_motionctl) = (by_client?, by_motionctl?);
    eprintln!(
        "{}\ntwo anonymous peers flooding `stop x` at {:.0} queries/s together ({})\n{}\n{}",
        quiet.report("without a flood, the remote client's e-stop", tick_hz),
        total[0] as f64 / flood_time,
        summary(total),
        by_client.report("the remote client's e-stop", tick_hz),
        by_motionctl.report(
            "motionctl --remote --identity panel estop (with its start and connection)",
            tick_hz
        ),
    );
    assert!(
        by_client.failures.is_empty() && by_client.ticks.len() == ROUNDS,
        "{}\n{}",
        by_client.report("the remote client's e-stop", tick_hz),
        rig.logs()
    );
    assert!(
        by_motionctl.failures.is_empty() && by_motionctl.ticks.len() == ROUNDS,
        "{}\n{}",
        by_motionctl.report("motionctl's e-stop", tick_hz),
        rig.logs()
    );
    Ok(())
}

#[test]
fn an_estop_behind_1500_queued_stops_latches() -> Result {
    let Some(binaries) = binaries() else {
        return Ok(());
    };
    let rig = Rig::start_with(&binaries, None, RULES, "panel")?;
    let local = local(&rig)?;
    let tick_hz = f64::from(local.info()?.tick_hz);
    let mut flooder = Peer::start(&rig, &format!("burst {}", local.axes().len()))?;
    // 1500 stops at once, the e-stop right behind them.
    let latches = estops_by_client(&rig, &local, || {
        flooder.say("burst 1500")?;
        flooder.expect("sent")?;
        Ok(())
    })?;
    let counts = flooder.finish()?;
    eprintln!(
        "{ROUNDS} rounds of 1500 stops at once ({}), the e-stop right behind:\n{}",
        summary(counts),
        latches.report("the remote client's e-stop", tick_hz)
    );
    assert!(
        latches.failures.is_empty() && latches.ticks.len() == ROUNDS,
        "{}\n{}",
        latches.report("the remote client's e-stop", tick_hz),
        rig.logs()
    );
    Ok(())
}
