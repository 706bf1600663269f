//! `motionctl bench`: the latency suite of `crates/motion-bench` against the running
//! server (docs/PERFORMANCE.md), the same figures and baselines as `cargo bench --bench
//! latency`. Progress goes to stderr, the table or JSON to stdout.

use motion_bench::BenchArgs;

/// Runs the suite against instance `server` and prints the report.
pub fn run(server: &str, args: &BenchArgs) -> anyhow::Result<()> {
    let report = motion_bench::run(server, args)?;
    if args.json {
        out!("{:#}", report.json());
    } else {
        use std::io::Write as _;
        write!(std::io::stdout().lock(), "{}", report.table())?;
    }
    Ok(())
}
