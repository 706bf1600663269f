//! One finding of the doctor: pass, warn or fail, the value measured, and the exact fix.

use std::path::PathBuf;

use serde_json::{Value, json};

use super::config::DoctorConfig;
use super::host::{Host, Identity};

/// How a check came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// As it should be for a real-time server.
    Pass,
    /// Works, but costs latency or safety margin.
    Warn,
    /// motiond will not get what its config asks for, or will break.
    Fail,
}

impl Status {
    /// `pass`, `warn`, `fail`.
    pub fn word(self) -> &'static str {
        match self {
            Self::Pass => "pass",
            Self::Warn => "warn",
            Self::Fail => "fail",
        }
    }
}

/// One check's result.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Check {
    /// Stable identifier (`kernel-preemption`).
    pub id: &'static str,
    /// What is checked, in words.
    pub title: &'static str,
    /// The verdict.
    pub status: Status,
    /// What was found.
    pub value: String,
    /// What to do about it (empty when it passed).
    pub fix: String,
}

impl Check {
    /// A passed check.
    pub fn pass(id: &'static str, title: &'static str, value: impl Into<String>) -> Self {
        Self {
            id,
            title,
            status: Status::Pass,
            value: value.into(),
            fix: String::new(),
        }
    }

    /// A warning with its fix.
    pub fn warn(
        id: &'static str,
        title: &'static str,
        value: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        Self::with(id, title, Status::Warn, value, fix)
    }

    /// A failure with its fix.
    pub fn fail(
        id: &'static str,
        title: &'static str,
        value: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        Self::with(id, title, Status::Fail, value, fix)
    }

    /// `status` with the value and fix given (the fix is dropped for a pass).
    pub fn with(
        id: &'static str,
        title: &'static str,
        status: Status,
        value: impl Into<String>,
        fix: impl Into<String>,
    ) -> Self {
        let mut check = Self::pass(id, title, value);
        check.status = status;
        if status != Status::Pass {
            check.fix = fix.into();
        }
        check
    }

    /// The JSON object of this check.
    pub fn json(&self) -> Value {
        json!({
            "id": self.id,
            "title": self.title,
            "status": self.status.word(),
            "value": self.value,
            "fix": if self.fix.is_empty() { Value::Null } else { json!(self.fix) },
        })
    }
}

/// Everything a check may look at.
#[derive(Debug)]
pub struct Context<'a> {
    /// The machine.
    pub host: Host<'a>,
    /// The server's config (defaults when none was found).
    pub config: DoctorConfig,
    /// Where the config came from, if anywhere.
    pub config_path: Option<PathBuf>,
    /// This process's identity, or why it is unknown.
    pub identity: Result<Identity, String>,
    /// How long the wake-up measurement runs (zero: skipped).
    pub wakeup: core::time::Duration,
}

impl Context<'_> {
    /// `user motion (uid 998)`.
    pub fn who(&self) -> String {
        match &self.identity {
            Ok(id) => format!("user {} (uid {})", self.host.user_name(id.uid), id.uid),
            Err(e) => format!("unknown user ({e})"),
        }
    }
}
