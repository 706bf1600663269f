//! The bare poller's part of the I/O phase ([`crate::poller`]): its CPU on the same four
//! idle boards, in the same 500 ms windows as motiond's and the plain peer's, and then its
//! own write latency per board — its board command decided (a stamp just before the write)
//! → the command's first byte read by the board's thread, the way the command → wire phase
//! times motiond ([`crate::wire`]).

use core::time::Duration;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::mpsc::{Receiver, channel};

use crate::cpu::{WINDOW, measure_cpu, threads_line};
use crate::dist::Dist;
use crate::io_links::Links;
use crate::poller::Poller;
use crate::pty::LineSeen;
use crate::report::{Row, Unit};
use crate::sweep::ServerRt;
use crate::wire::WireRun;
use crate::wire_board::{Served, WireBoard};

/// A decided command whose first byte the board has not read within this is lost.
const LOST_AFTER_NS: u64 = 50_000_000;

/// What the poller's run measured.
#[derive(Debug)]
pub struct PollerRun {
    /// % of one core per window, in hundredths of a percent.
    pub cpu: Dist,
    /// Mean % of one core per thread name.
    pub threads: BTreeMap<String, f64>,
    /// Per board ([`WireBoard::ALL`] order): command decided → first byte at the board, ns.
    pub write: [Dist; 4],
    /// Per board: commands whose first byte did not arrive.
    pub lost: [u64; 4],
    /// Per board: idle polls the poller wrote after its start-up (board commands not
    /// counted).
    pub sent: [u64; 4],
}

/// Pairs each decided instant with the first arrival at or after it (both in order, one
/// arrival per decision): the distribution of the waits, and how many decisions found no
/// arrival within [`LOST_AFTER_NS`]. Arrivals before a decision (the start-up's messages)
/// are skipped.
pub fn pair(decided: &[u64], arrived: &[u64]) -> (Dist, u64) {
    let mut dist = Dist::new();
    let mut lost = 0;
    let mut next = arrived.iter().peekable();
    for &at in decided {
        while next.next_if(|&&t| t < at).is_some() {}
        match next.next_if(|&&t| t - at <= LOST_AFTER_NS) {
            Some(&t) => dist.record((t - at).max(1)),
            None => lost += 1,
        }
    }
    (dist, lost)
}

fn arrivals(seen: &Receiver<LineSeen>) -> Vec<u64> {
    let mut stamps: Vec<u64> = seen.try_iter().map(|line| line.first_byte_ns).collect();
    stamps.sort_unstable();
    stamps
}

/// Serves the four boards (as the command → wire phase does, reporting the host's
/// command messages), runs the poller on them at `tick_hz`: its CPU for `duration` after
/// a second of settling, then board commands for `span`.
///
/// # Errors
/// A board or the poller could not be started, or the poller failed.
pub fn run(
    tick_hz: u32,
    rt: ServerRt,
    duration: Duration,
    span: Duration,
    dir: &Path,
) -> Result<PollerRun, String> {
    let pid = std::process::id();
    let path = |slug: &str, ext: &str| dir.join(format!("io-poller-{slug}-{pid}.{ext}"));
    let links = Links {
        qsb: path("qsb", "tty"),
        pack: path("pack", "tty"),
        quad: path("quad", "sock"),
        spim: path("spim", "sock"),
    };
    let mut served: Vec<(Served, Receiver<LineSeen>)> = Vec::new();
    for (board, link) in
        WireBoard::ALL
            .into_iter()
            .zip([&links.qsb, &links.pack, &links.quad, &links.spim])
    {
        let (sender, seen) = channel();
        served.push((board.serve(link, sender)?, seen));
    }
    let outcome = (|| {
        let mut poller = Poller::start(tick_hz, rt, &links)?;
        std::thread::sleep(Duration::from_secs(1));
        let (cpu, threads) = measure_cpu(poller.pid(), duration);
        // The start-up's messages are not commands.
        for (_, seen) in &served {
            let _ = arrivals(seen);
        }
        poller.start_commands()?;
        std::thread::sleep(span);
        let figures = poller.stop()?;
        // The boards' threads have read everything the poller wrote by now.
        std::thread::sleep(Duration::from_millis(100));
        let mut write: [Dist; 4] = core::array::from_fn(|_| Dist::new());
        let mut lost = [0; 4];
        for (index, (_, seen)) in served.iter().enumerate() {
            let decided = figures.decided.get(index).map_or(&[][..], Vec::as_slice);
            let (dist, missing) = pair(decided, &arrivals(seen));
            write[index] = dist;
            lost[index] = missing;
        }
        Ok(PollerRun {
            cpu,
            threads,
            write,
            lost,
            sent: figures.sent,
        })
    })();
    for (board, _) in &mut served {
        board.stop();
    }
    outcome
}

/// The rows of the poller's figures: motiond's CPU against the poller's, the poller's
/// against the plain peer's (`peer`), and per board motiond's command → wire (of `wire`,
/// when that phase ran) against the poller's own write.
pub fn rows(
    run: &PollerRun,
    motiond_cpu: &Dist,
    peer: &Dist,
    wire: Option<&WireRun>,
    notes: &mut Vec<String>,
) -> Vec<Row> {
    let window = WINDOW.as_millis();
    let sent: Vec<String> = WireBoard::ALL
        .iter()
        .zip(run.sent)
        .map(|(board, count)| format!("{} {count}", board.name()))
        .collect();
    let mut rows = vec![
        Row {
            figure: format!(
                "motiond CPU, four idle external links, against the bare poller, % of one core \
                 per {window} ms window"
            ),
            unit: Unit::CentiPercent,
            ours: motiond_cpu.summary(),
            baseline: Some(run.cpu.summary()),
            baseline_label: "the bare poller: the same transactions on the same four links at \
                             the same rates (the drivers' idle polls), every reply read back, a \
                             frame-sized sample published every tick, nothing else"
                .to_owned(),
            note: "the ratio is motiond's own cost over the links' (engine, drivers, decoding, \
                   its threads); the poller's boards are served as motiond's are"
                .to_owned(),
        },
        Row {
            figure: format!(
                "the bare poller's CPU against the plain peer, % of one core per {window} ms \
                 window"
            ),
            unit: Unit::CentiPercent,
            ours: run.cpu.summary(),
            baseline: Some(peer.summary()),
            baseline_label: "the plain peer ticking at the same rate (no links)".to_owned(),
            note: format!(
                "the links' own cost; one thread: {}; idle polls written after the start-up \
                 (settling, CPU and command windows; the board commands not counted): {}",
                threads_line(&run.threads),
                sent.join(", ")
            ),
        },
    ];
    for (index, board) in WireBoard::ALL.into_iter().enumerate() {
        let (Some(write), Some(lost)) = (run.write.get(index), run.lost.get(index)) else {
            continue;
        };
        let ours = wire.and_then(|w| w.boards.iter().find(|b| b.board == board));
        let label = format!(
            "the bare poller's own write: its board command decided (a stamp just before the \
             write, in its tick, with the four links' idle traffic running) → the first byte \
             read by the board's thread; {lost} lost"
        );
        match ours {
            Some(ours) => rows.push(Row {
                figure: format!(
                    "command → first byte at the link, {} ({}), against the bare poller",
                    board.name(),
                    board.transport()
                ),
                unit: Unit::Ns,
                ours: ours.ours.summary(),
                baseline: Some(write.summary()),
                baseline_label: label,
                note: "ours as in the command → wire row of this board; the poller decides at \
                       its tick, so its figure has no wait for a tick in it: the ratio includes \
                       motiond's by-design wait for its next tick"
                    .to_owned(),
            }),
            None => notes.push(format!(
                "{}: the bare poller's own write (decided → first byte) {} (n={}), {lost} lost; \
                 motiond's command → wire not measured this run",
                board.name(),
                crate::dist::format_ns(write.summary().p50),
                write.summary().samples
            )),
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::{LOST_AFTER_NS, pair};

    #[test]
    fn each_decision_takes_the_first_arrival_after_it() {
        // An arrival from before (the start-up), two paired, one decision never arrives.
        let decided = [1_000, 5_000, 10_000];
        let arrived = [500, 1_200, 5_030, 10_000 + LOST_AFTER_NS + 1];
        let (dist, lost) = pair(&decided, &arrived);
        assert_eq!(lost, 1);
        let summary = dist.summary();
        assert_eq!(summary.samples, 2);
        assert_eq!(summary.max, 200);
    }

    #[test]
    fn an_arrival_is_paired_once() {
        let (dist, lost) = pair(&[1_000, 1_001], &[1_500]);
        assert_eq!((dist.summary().samples, lost), (1, 1));
    }
}
