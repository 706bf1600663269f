//! Tick latency statistics in preallocated histograms.

use hdrhistogram::Histogram;
use motion_ipc::LatencySummary;

/// Highest latency the histograms track exactly (10 s); larger values are clamped.
const MAX_TRACKED_NS: u64 = 10_000_000_000;

/// A latency histogram that never allocates after construction.
#[derive(Debug)]
pub struct Latency {
    histogram: Histogram<u64>,
}

impl Latency {
    /// 1 ns .. 10 s at 3 significant digits.
    pub fn new() -> Self {
        let histogram = Histogram::new_with_bounds(1, MAX_TRACKED_NS, 3)
            .unwrap_or_else(|_| Histogram::new(3).expect("3 significant digits are valid"));
        Self { histogram }
    }

    /// Records one sample (clamped into the tracked range).
    pub fn record(&mut self, ns: u64) {
        let _ = self.histogram.record(ns.clamp(1, MAX_TRACKED_NS));
    }

    /// p50/p99/p99.9/max.
    pub fn summary(&self) -> LatencySummary {
        let h = &self.histogram;
        LatencySummary {
            samples: h.len(),
            p50_ns: h.value_at_quantile(0.5),
            p99_ns: h.value_at_quantile(0.99),
            p999_ns: h.value_at_quantile(0.999),
            max_ns: h.max(),
        }
    }
}

impl Default for Latency {
    fn default() -> Self {
        Self::new()
    }
}

/// `12.3µs` style.
pub fn format_ns(ns: u64) -> String {
    match ns {
        0..=9_999 => format!("{:.1}µs", ns as f64 / 1e3),
        10_000..=9_999_999 => format!("{}µs", ns / 1000),
        _ => format!("{:.1}ms", ns as f64 / 1e6),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_of_known_samples() {
        let mut latency = Latency::new();
        for ns in 1..=1000u64 {
            latency.record(ns * 1000);
        }
        latency.record(u64::MAX);
        let summary = latency.summary();
        assert_eq!(summary.samples, 1001);
        assert!((495_000..=505_000).contains(&summary.p50_ns), "{summary:?}");
        assert!((985_000..=995_000).contains(&summary.p99_ns), "{summary:?}");
        assert!(summary.max_ns >= MAX_TRACKED_NS);
        assert_eq!(format_ns(12_345), "12µs");
        assert_eq!(format_ns(1_500), "1.5µs");
    }
}
