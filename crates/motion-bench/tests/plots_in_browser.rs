//! `--plot DIR` seen in a real browser: fixture distributions (three figures, each with
//! its baselines, as a bench run writes them) become SVGs and index.html through
//! `motion_bench::plots::write`, and `scripts/check-plots` opens the page in headless
//! Chromium: every picture loaded, the screenshot not blank. Skipped, saying why, when no
//! Chromium can be had (the script exits 77); a failure of the check fails the test.

use std::path::PathBuf;
use std::process::Command;

use motion_bench::{Dist, Report};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A long-tailed latency: `base` ns for most samples, a tail up to 20 × that.
fn latency(base: u64, samples: u64) -> Dist {
    let mut dist = Dist::new();
    for i in 0..samples {
        let tail = if i % 100 == 0 { 1 + (i / 100) % 20 } else { 1 };
        dist.record(base * tail + (i * 7919) % (base / 2));
    }
    dist
}

#[test]
fn the_plot_page_renders_in_headless_chromium() -> Result {
    let dir = std::env::temp_dir().join(format!("motion-bench-plot-check-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    for (slug, base) in [
        ("frame-waitset-motiond", 9_000),
        ("frame-waitset-baseline", 6_000),
        ("command-rtt-motiond", 500_000),
        ("command-rtt-baseline-ticking", 480_000),
        ("command-rtt-baseline-busy", 4_000),
        ("deadline-to-publish-motiond", 20_000),
        ("deadline-to-publish-baseline", 8_000),
    ] {
        latency(base, 20_000).write_percentiles(&dir.join(format!("{slug}.txt")), slug)?;
    }
    let mut report = Report::default();
    report
        .context
        .push(("server".to_owned(), "fixture distributions".to_owned()));
    let names = motion_bench::plots::write(
        &dir,
        &dir,
        &report,
        &[
            "machine: fixture".to_owned(),
            "command: cargo test".to_owned(),
        ],
    )?;
    assert_eq!(names.len(), 3, "{names:?}");
    let output = Command::new(repo().join("scripts/check-plots"))
        .arg(&dir)
        .output()?;
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    eprintln!("{text}");
    if output.status.code() == Some(77) {
        eprintln!("skipped: scripts/check-plots could not run Chromium (above)");
        return Ok(());
    }
    assert!(
        output.status.success(),
        "scripts/check-plots failed:\n{text}"
    );
    assert!(text.contains("3 of 3 images loaded"), "{text}");
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
