//! The results: a human table (figure, baseline, ratio), JSON, and distribution files.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Value, json};

use crate::dist::{Dist, Summary, format_ns};
use crate::sweep::SweepPoint;

/// One figure beside its baseline.
#[derive(Debug, Clone)]
pub struct Row {
    /// What is measured.
    pub figure: String,
    /// Unit of the numbers: `ns` (printed as time) or `ticks`.
    pub unit: Unit,
    /// Our figure.
    pub ours: Summary,
    /// The same-run baseline, if this figure has one.
    pub baseline: Option<Summary>,
    /// What the baseline is.
    pub baseline_label: String,
    /// Anything the reader must know (sample window, method).
    pub note: String,
}

/// Unit of a row.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Nanoseconds.
    Ns,
    /// Ticks.
    Ticks,
    /// Hundredths of a percent of one core (CPU use), or of anything counted.
    CentiPercent,
    /// Millionths of an axis's unit (a position error), printed in that unit.
    MicroUnit(UnitName),
}

/// The name of an axis's unit (`mm`, `deg`), kept in a `Copy` value (at most 15 bytes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnitName {
    bytes: [u8; 15],
    len: u8,
}

impl UnitName {
    /// `name`, cut at 15 bytes (on a character boundary).
    pub fn new(name: &str) -> Self {
        let mut end = name.len().min(15);
        while !name.is_char_boundary(end) {
            end -= 1;
        }
        let mut bytes = [0; 15];
        bytes[..end].copy_from_slice(&name.as_bytes()[..end]);
        Self {
            bytes,
            len: end as u8,
        }
    }

    /// The name.
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl Row {
    /// ours / baseline at p50 and p99 (None without a usable baseline).
    pub fn ratios(&self) -> Option<(f64, f64)> {
        let base = self
            .baseline
            .filter(|b| !b.is_empty() && b.p50 > 0 && b.p99 > 0)?;
        if self.ours.is_empty() {
            return None;
        }
        Some((
            self.ours.p50 as f64 / base.p50 as f64,
            self.ours.p99 as f64 / base.p99 as f64,
        ))
    }
}

/// Everything the bench found.
#[derive(Debug, Default)]
pub struct Report {
    /// Context lines (server, rate, thread set-up).
    pub context: Vec<(String, String)>,
    /// The figures.
    pub rows: Vec<Row>,
    /// Tick work versus axes, when swept.
    pub sweep: Vec<SweepPoint>,
    /// Baseline of the sweep (the peer's per-tick work).
    pub sweep_baseline: Option<Summary>,
    /// What could not be measured, and why.
    pub notes: Vec<String>,
}

/// One value of a row in its unit, as the table prints it.
pub(crate) fn value(unit: Unit, v: u64) -> String {
    match unit {
        Unit::Ns => format_ns(v),
        Unit::Ticks => format!("{v}t"),
        Unit::CentiPercent => format!("{:.2}%", v as f64 / 100.0),
        Unit::MicroUnit(name) => format!("{:.4} {}", v as f64 / 1e6, name.as_str()),
    }
}

fn cell(unit: Unit, s: Summary) -> String {
    if s.is_empty() {
        return "no samples".to_owned();
    }
    format!(
        "{} / {} / {} / {} (n={})",
        value(unit, s.p50),
        value(unit, s.p99),
        value(unit, s.p999),
        value(unit, s.max),
        s.samples
    )
}

impl Report {
    /// The human table.
    pub fn table(&self) -> String {
        let mut out = String::new();
        for (key, value) in &self.context {
            let _ = writeln!(out, "{key:<22} {value}");
        }
        let _ = writeln!(
            out,
            "\nEach cell: p50 / p99 / p99.9 / max (samples). Ratio = ours ÷ baseline at p50 and p99."
        );
        for (index, row) in self.rows.iter().enumerate() {
            let _ = writeln!(out, "\n{}. {}", index + 1, row.figure);
            let _ = writeln!(out, "   ours      {}", cell(row.unit, row.ours));
            match row.baseline {
                Some(base) => {
                    let _ = writeln!(out, "   baseline  {}", cell(row.unit, base));
                    let _ = writeln!(out, "             ({})", row.baseline_label);
                }
                None => {
                    let _ = writeln!(out, "   baseline  none ({})", row.baseline_label);
                }
            }
            if let Some((p50, p99)) = row.ratios() {
                let _ = writeln!(out, "   ratio     ×{p50:.2} at p50, ×{p99:.2} at p99");
            }
            if !row.note.is_empty() {
                let _ = writeln!(out, "   note      {}", row.note);
            }
        }
        if !self.sweep.is_empty() {
            let _ = writeln!(
                out,
                "\nTick work versus axes (ServerStats.work since start of a motiond started per point on generated QUADpack configs; start-up included):"
            );
            if let Some(base) = self.sweep_baseline {
                let _ = writeln!(
                    out,
                    "   baseline  {} (plain peer's per-tick work, no engine)",
                    cell(Unit::Ns, base)
                );
            }
            for point in &self.sweep {
                match point {
                    SweepPoint::Ran {
                        axes,
                        work,
                        wakeup,
                        overruns,
                        fresh,
                        all_fresh_after,
                    } => {
                        let ratio = self
                            .sweep_baseline
                            .filter(|b| b.p50 > 0)
                            .map(|b| format!("  ×{:.2} at p50", work.p50 as f64 / b.p50 as f64))
                            .unwrap_or_default();
                        let _ = writeln!(
                            out,
                            "   {axes:>3} axes  work {}{ratio}; wake-up p99 {}; overruns {overruns}; {fresh}/{axes} axes fresh at the end, {}",
                            cell(Unit::Ns, *work),
                            format_ns(wakeup.p99),
                            all_fresh_after.map_or(
                                "not all fresh within 10 s".to_owned(),
                                |d| format!("all fresh after {:.1} s", d.as_secs_f64())
                            )
                        );
                    }
                    SweepPoint::Skipped { axes, reason } => {
                        let _ = writeln!(out, "   {axes:>3} axes  skipped: {reason}");
                    }
                }
            }
        }
        if !self.notes.is_empty() {
            let _ = writeln!(out, "\nNot measured, or measured differently:");
            for note in &self.notes {
                let _ = writeln!(out, " - {note}");
            }
        }
        out
    }

    /// The JSON document.
    pub fn json(&self) -> Value {
        let summary = |s: Summary| json!({"samples": s.samples, "p50": s.p50, "p99": s.p99, "p999": s.p999, "max": s.max});
        let rows: Vec<Value> = self
            .rows
            .iter()
            .map(|row| {
                let (p50, p99) = row
                    .ratios()
                    .map_or((Value::Null, Value::Null), |(a, b)| (json!(a), json!(b)));
                json!({
                    "figure": row.figure,
                    "unit": match row.unit {
                        Unit::Ns => "ns".to_owned(),
                        Unit::Ticks => "ticks".to_owned(),
                        Unit::CentiPercent => "centi-percent".to_owned(),
                        Unit::MicroUnit(name) => format!("millionths of {}", name.as_str()),
                    },
                    "ours": summary(row.ours),
                    "baseline": row.baseline.map(summary),
                    "baseline_label": row.baseline_label,
                    "ratio_p50": p50,
                    "ratio_p99": p99,
                    "note": row.note,
                })
            })
            .collect();
        let sweep: Vec<Value> = self
            .sweep
            .iter()
            .map(|point| match point {
                SweepPoint::Ran {
                    axes,
                    work,
                    wakeup,
                    overruns,
                    fresh,
                    all_fresh_after,
                } => json!({
                    "axes": axes, "work_ns": summary(*work), "wakeup_ns": summary(*wakeup),
                    "overruns": overruns, "fresh_axes_at_end": fresh,
                    "all_fresh_after_s": all_fresh_after.map(|d| d.as_secs_f64()),
                }),
                SweepPoint::Skipped { axes, reason } => json!({"axes": axes, "skipped": reason}),
            })
            .collect();
        let context: serde_json::Map<String, Value> = self
            .context
            .iter()
            .map(|(k, v)| (k.clone(), json!(v)))
            .collect();
        json!({
            "context": context,
            "rows": rows,
            "axes_sweep": sweep,
            "axes_sweep_baseline_ns": self.sweep_baseline.map(summary),
            "notes": self.notes,
        })
    }
}

/// Writes `dist` to `dir/<slug>.txt` when `dir` is given; returns the error text if any.
pub fn write_dist(dir: Option<&Path>, slug: &str, title: &str, dist: &Dist) -> Option<String> {
    let dir = dir?;
    let path = dir.join(format!("{slug}.txt"));
    dist.write_percentiles(&path, title)
        .err()
        .map(|e| format!("{}: {e}", path.display()))
}
