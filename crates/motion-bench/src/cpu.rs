//! A process's CPU use as the kernel counts it (the sum over its threads of
//! `/proc/<pid>/task/*/schedstat`, time on a CPU): % of one core per [`WINDOW`] and the
//! mean per thread name ([`measure_cpu`]), printed largest first ([`threads_line`]). The
//! I/O phase measures motiond, the plain peer and the bare poller with it.

use core::time::Duration;
use std::collections::BTreeMap;
use std::time::Instant;

use crate::dist::Dist;

/// CPU windows.
pub const WINDOW: Duration = Duration::from_millis(500);
/// Every task of `pid`: its name and its time on a CPU so far, ns.
fn task_times(pid: u32) -> Vec<(String, u64)> {
    let Ok(tasks) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return Vec::new();
    };
    tasks
        .flatten()
        .filter_map(|task| {
            let dir = task.path();
            let name = std::fs::read_to_string(dir.join("comm")).ok()?;
            let stat = std::fs::read_to_string(dir.join("schedstat")).ok()?;
            let ns = stat.split_whitespace().next()?.parse().ok()?;
            Some((name.trim().to_owned(), ns))
        })
        .collect()
}

/// CPU of `pid` in [`WINDOW`]s for `duration`: the distribution per window (hundredths of a
/// percent of one core) and the mean per thread name.
pub fn measure_cpu(pid: u32, duration: Duration) -> (Dist, BTreeMap<String, f64>) {
    let mut dist = Dist::new();
    let first = task_times(pid);
    let started = Instant::now();
    let mut previous: u64 = first.iter().map(|(_, ns)| ns).sum();
    let mut window_start = Instant::now();
    while started.elapsed() < duration {
        std::thread::sleep(WINDOW);
        let total: u64 = task_times(pid).iter().map(|(_, ns)| ns).sum();
        let elapsed = window_start.elapsed().as_nanos().max(1);
        window_start = Instant::now();
        let busy = u128::from(total.saturating_sub(previous));
        previous = total;
        dist.record(
            u64::try_from(busy * 10_000 / elapsed)
                .unwrap_or(u64::MAX)
                .max(1),
        );
    }
    let span = started.elapsed().as_secs_f64().max(1e-9);
    let mut threads: BTreeMap<String, f64> = BTreeMap::new();
    let before: BTreeMap<String, u64> = first.into_iter().fold(BTreeMap::new(), |mut m, (n, v)| {
        *m.entry(n).or_default() += v;
        m
    });
    for (name, ns) in task_times(pid) {
        *threads.entry(name).or_default() += ns as f64;
    }
    for (name, ns) in &mut threads {
        let start = before.get(name).copied().unwrap_or(0) as f64;
        *ns = (*ns - start).max(0.0) / 1e9 / span * 100.0;
    }
    (dist, threads)
}

/// `tick 2.1%, io-qsb 0.4%, …`, largest first.
pub fn threads_line(threads: &BTreeMap<String, f64>) -> String {
    let mut list: Vec<(&String, &f64)> = threads.iter().collect();
    list.sort_by(|a, b| b.1.total_cmp(a.1));
    list.iter()
        .map(|(name, percent)| format!("{name} {percent:.2}%"))
        .collect::<Vec<_>>()
        .join(", ")
}
