//! Latency distributions: hdrhistogram, their p50/p99/p99.9/max summary and their files.

use std::fmt::Write as _;
use std::path::Path;

use hdrhistogram::Histogram;
use motion_ipc::LatencySummary;

/// Highest value tracked (10 s); larger samples are clamped and counted as such.
const MAX_NS: u64 = 10_000_000_000;

/// One distribution, in ns.
#[derive(Debug, Clone)]
pub struct Dist {
    histogram: Histogram<u64>,
}

impl Dist {
    /// 1 ns .. 10 s at 3 significant digits (allocated once, before measuring).
    pub fn new() -> Self {
        let histogram = Histogram::new_with_bounds(1, MAX_NS, 3)
            .unwrap_or_else(|_| Histogram::new(3).expect("3 significant digits are valid"));
        Self { histogram }
    }

    /// Records one sample (clamped into 1 ns .. 10 s).
    pub fn record(&mut self, ns: u64) {
        let _ = self.histogram.record(ns.clamp(1, MAX_NS));
    }

    /// Records one count (ticks), 0 included (clamped at 10 s worth of ns like the rest).
    pub fn record_count(&mut self, count: u64) {
        let _ = self.histogram.record(count.min(MAX_NS));
    }

    /// Records `count` samples of `ns` (clamped like [`Dist::record`]).
    pub fn record_n(&mut self, ns: u64, count: u64) {
        let _ = self.histogram.record_n(ns.clamp(1, MAX_NS), count);
    }

    /// p50/p99/p99.9/max and the count.
    pub fn summary(&self) -> Summary {
        let h = &self.histogram;
        if h.is_empty() {
            return Summary::default();
        }
        Summary {
            samples: h.len(),
            p50: h.value_at_quantile(0.5),
            p99: h.value_at_quantile(0.99),
            p999: h.value_at_quantile(0.999),
            max: h.max(),
        }
    }

    /// Writes the full percentile distribution as `value_ns percentile total_count` lines
    /// (HdrHistogram's classic output, 5 ticks per half distance), after a `#` header.
    pub fn write_percentiles(&self, path: &Path, title: &str) -> std::io::Result<()> {
        let mut text = String::new();
        let _ = writeln!(text, "# {title}");
        let _ = writeln!(text, "# value_ns percentile total_count");
        let mut total = 0u64;
        if !self.histogram.is_empty() {
            for step in self.histogram.iter_quantiles(5) {
                total += step.count_since_last_iteration();
                let _ = writeln!(
                    text,
                    "{} {:.6} {}",
                    step.value_iterated_to(),
                    step.percentile(),
                    total
                );
            }
        }
        std::fs::write(path, text)
    }
}

impl Default for Dist {
    fn default() -> Self {
        Self::new()
    }
}

/// p50/p99/p99.9/max of a distribution, ns, and its sample count.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Summary {
    /// Number of samples.
    pub samples: u64,
    /// Median, ns.
    pub p50: u64,
    /// 99th percentile, ns.
    pub p99: u64,
    /// 99.9th percentile, ns.
    pub p999: u64,
    /// Maximum, ns.
    pub max: u64,
}

impl From<LatencySummary> for Summary {
    fn from(s: LatencySummary) -> Self {
        Self {
            samples: s.samples,
            p50: s.p50_ns,
            p99: s.p99_ns,
            p999: s.p999_ns,
            max: s.max_ns,
        }
    }
}

impl Summary {
    /// `samples p50 p99 p999 max` (the peer's stdout line format).
    pub fn to_line(self) -> String {
        format!(
            "{} {} {} {} {}",
            self.samples, self.p50, self.p99, self.p999, self.max
        )
    }

    /// Parses [`Summary::to_line`].
    pub fn from_line(line: &str) -> Option<Self> {
        let mut fields = line.split_whitespace().map(|f| f.parse::<u64>().ok());
        let mut next = || fields.next().flatten();
        Some(Self {
            samples: next()?,
            p50: next()?,
            p99: next()?,
            p999: next()?,
            max: next()?,
        })
    }

    /// Whether there is anything to report.
    pub fn is_empty(self) -> bool {
        self.samples == 0
    }
}

/// `part` of `whole` in hundredths of a percent, as the summary of one figure (every
/// percentile that value, `whole` its samples).
pub(crate) fn percent(part: u64, whole: u64) -> Summary {
    let value = if whole == 0 {
        0
    } else {
        (part as f64 * 10_000.0 / whole as f64).round() as u64
    };
    Summary {
        samples: whole,
        p50: value,
        p99: value,
        p999: value,
        max: value,
    }
}

/// `12.3µs` / `123µs` / `1.23ms` style, for the table.
pub fn format_ns(ns: u64) -> String {
    match ns {
        0..=999 => format!("{ns}ns"),
        1_000..=9_999 => format!("{:.2}µs", ns as f64 / 1e3),
        10_000..=999_999 => format!("{:.1}µs", ns as f64 / 1e3),
        _ => format!("{:.2}ms", ns as f64 / 1e6),
    }
}
