//! One row per campaign: its figures, its invariants (checked) and its timing targets
//! (reported, flagged when missed, never failing the run).

use std::fmt::Write as _;

use serde_json::{Value, json};

/// An invariant of a campaign: it holds or the run fails.
#[derive(Debug, Clone)]
pub struct Check {
    /// What must hold ("0 axes left moving").
    pub name: String,
    /// Whether it held.
    pub ok: bool,
    /// The figure behind it.
    pub detail: String,
}

/// A timing target ("within 10 % of the quiet run"): reported, flagged when missed.
#[derive(Debug, Clone)]
pub struct Target {
    /// What is compared.
    pub name: String,
    /// Loaded ÷ quiet.
    pub ratio: f64,
    /// The ratio it should stay under.
    pub limit: f64,
}

/// The outcome of one campaign.
#[derive(Debug, Clone, Default)]
pub struct Row {
    /// Campaign number and name ("1 dead clients").
    pub campaign: String,
    /// How much was done ("1000 × SIGKILL, 1000 × SIGSTOP").
    pub runs: String,
    /// Measured figures, in order.
    pub figures: Vec<(String, String)>,
    /// Invariants.
    pub checks: Vec<Check>,
    /// Timing targets.
    pub targets: Vec<Target>,
    /// Notes: what was done instead of what was asked, and why.
    pub notes: Vec<String>,
    /// Wall time of the campaign, seconds.
    pub seconds: f64,
}

impl Row {
    /// A row for `campaign`.
    pub fn new(campaign: &str) -> Self {
        Self {
            campaign: campaign.to_owned(),
            ..Self::default()
        }
    }

    /// Adds a figure.
    pub fn figure(&mut self, name: &str, value: impl Into<String>) {
        self.figures.push((name.to_owned(), value.into()));
    }

    /// Adds an invariant.
    pub fn check(&mut self, name: &str, ok: bool, detail: impl Into<String>) {
        self.checks.push(Check {
            name: name.to_owned(),
            ok,
            detail: detail.into(),
        });
    }

    /// Adds a timing target (skipped when the quiet figure is 0).
    pub fn target(&mut self, name: &str, loaded: f64, quiet: f64, limit: f64) {
        if quiet > 0.0 && loaded.is_finite() {
            self.targets.push(Target {
                name: name.to_owned(),
                ratio: loaded / quiet,
                limit,
            });
        }
    }

    /// Adds a note.
    pub fn note(&mut self, text: impl Into<String>) {
        self.notes.push(text.into());
    }

    /// Whether every invariant held.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|check| check.ok)
    }

    /// A row that could not run at all.
    pub fn failed(campaign: &str, error: &anyhow::Error) -> Self {
        let mut row = Self::new(campaign);
        row.check("the campaign ran", false, format!("{error:#}"));
        row
    }

    fn verdict(&self) -> String {
        let failed: Vec<&str> = self
            .checks
            .iter()
            .filter(|c| !c.ok)
            .map(|c| c.name.as_str())
            .collect();
        let flagged: Vec<String> = self
            .targets
            .iter()
            .filter(|t| t.ratio > t.limit)
            .map(|t| format!("{} ×{:.2} > ×{:.2}", t.name, t.ratio, t.limit))
            .collect();
        let mut text = if failed.is_empty() {
            format!("PASS ({} invariants)", self.checks.len())
        } else {
            format!("FAIL: {}", failed.join("; "))
        };
        if !flagged.is_empty() {
            let _ = write!(text, "; FLAG: {}", flagged.join("; "));
        }
        text
    }

    /// The row as JSON.
    pub fn json(&self) -> Value {
        json!({
            "campaign": self.campaign,
            "runs": self.runs,
            "seconds": (self.seconds * 10.0).round() / 10.0,
            "passed": self.passed(),
            "figures": self.figures.iter().map(|(k, v)| json!({"name": k, "value": v})).collect::<Vec<_>>(),
            "invariants": self.checks.iter().map(|c| json!({"name": c.name, "ok": c.ok, "detail": c.detail})).collect::<Vec<_>>(),
            "targets": self.targets.iter().map(|t| json!({
                "name": t.name,
                "ratio": (t.ratio * 1000.0).round() / 1000.0,
                "limit": t.limit,
                "flagged": t.ratio > t.limit,
            })).collect::<Vec<_>>(),
            "notes": self.notes,
        })
    }
}

/// The Markdown table of every row, then each row's invariants and notes.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::new();
    out.push_str("| campaign | runs | figures | targets (loaded ÷ quiet) | verdict |\n");
    out.push_str("|---|---|---|---|---|\n");
    for row in rows {
        let figures: Vec<String> = row
            .figures
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        let targets: Vec<String> = row
            .targets
            .iter()
            .map(|t| {
                format!(
                    "{} ×{:.2}{}",
                    t.name,
                    t.ratio,
                    if t.ratio > t.limit { " (flag)" } else { "" }
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            row.campaign,
            row.runs,
            figures.join("; "),
            if targets.is_empty() {
                "–".to_owned()
            } else {
                targets.join("; ")
            },
            row.verdict()
        );
    }
    out.push('\n');
    for row in rows {
        let _ = writeln!(out, "{} ({:.0} s):", row.campaign, row.seconds);
        for check in &row.checks {
            let _ = writeln!(
                out,
                "  [{}] {}: {}",
                if check.ok { "ok" } else { "FAIL" },
                check.name,
                check.detail
            );
        }
        for note in &row.notes {
            let _ = writeln!(out, "  note: {note}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_invariant_fails_the_row_and_a_missed_target_only_flags_it() {
        let mut row = Row::new("9 test");
        row.check("server alive", true, "yes");
        row.target("tick p99", 1.5, 1.0, 1.1);
        assert!(row.passed());
        assert!(row.verdict().starts_with("PASS"));
        assert!(row.verdict().contains("FLAG: tick p99 ×1.50"));
        row.check("0 left moving", false, "2 left moving");
        assert!(!row.passed());
        assert!(row.verdict().starts_with("FAIL: 0 left moving"));
        let text = table(&[row.clone()]);
        assert!(text.contains("| 9 test |"), "{text}");
        assert!(
            text.contains("[FAIL] 0 left moving: 2 left moving"),
            "{text}"
        );
        assert_eq!(row.json()["passed"], false);
        assert_eq!(row.json()["targets"][0]["flagged"], true);
        // A quiet figure of 0 gives no ratio.
        row.target("empty", 1.0, 0.0, 1.1);
        assert_eq!(row.targets.len(), 1);
    }
}
