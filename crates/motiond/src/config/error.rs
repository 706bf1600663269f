//! Config errors that point at the file, line, column and key.

use core::fmt;
use core::ops::Range;
use std::path::{Path, PathBuf};

/// One problem in a config file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigIssue {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub column: usize,
    /// The key (dotted where useful, e.g. `axis[2].max`), or the table.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// A config file that cannot be used: every problem found, each with its location.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct ConfigError {
    /// The file.
    pub path: PathBuf,
    /// The problems, in file order.
    pub issues: Vec<ConfigIssue>,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (index, issue) in self.issues.iter().enumerate() {
            if index > 0 {
                writeln!(f)?;
            }
            write!(
                f,
                "{}:{}:{}: `{}`: {}",
                self.path.display(),
                issue.line,
                issue.column,
                issue.key,
                issue.message
            )?;
        }
        Ok(())
    }
}

impl ConfigIssue {
    /// `file:line:column: warning: `key`: message`, for a warning about `path`.
    pub fn warning_line(&self, path: &Path) -> String {
        format!(
            "{}:{}:{}: warning: `{}`: {}",
            path.display(),
            self.line,
            self.column,
            self.key,
            self.message
        )
    }
}

impl ConfigError {
    /// A file that could not be read at all.
    pub fn unreadable(path: &Path, error: &std::io::Error) -> Self {
        Self {
            path: path.to_owned(),
            issues: vec![ConfigIssue {
                line: 1,
                column: 1,
                key: "(file)".into(),
                message: format!("cannot read the config file: {error}"),
            }],
        }
    }
}

/// Collects issues against one source text.
pub(crate) struct Issues<'a> {
    source: &'a str,
    pub list: Vec<ConfigIssue>,
    /// Things that work but are probably not what the user wants.
    pub warnings: Vec<ConfigIssue>,
}

impl<'a> Issues<'a> {
    pub fn new(source: &'a str) -> Self {
        Self {
            source,
            list: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// Records `message` about `key` at byte range `span`.
    pub fn push(&mut self, span: Range<usize>, key: impl Into<String>, message: impl Into<String>) {
        let issue = self.at(span, key, message);
        self.list.push(issue);
    }

    /// Records a warning (the config is used anyway).
    pub fn warn(&mut self, span: Range<usize>, key: impl Into<String>, message: impl Into<String>) {
        let issue = self.at(span, key, message);
        self.warnings.push(issue);
    }

    fn at(
        &self,
        span: Range<usize>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> ConfigIssue {
        let (line, column) = line_column(self.source, span.start);
        ConfigIssue {
            line,
            column,
            key: key.into(),
            message: message.into(),
        }
    }

    /// The key written at the start of the line holding byte `offset` (`key = value`), for
    /// errors serde reports with only a span.
    pub fn key_at(&self, offset: usize) -> String {
        let start = self.source[..offset.min(self.source.len())]
            .rfind('\n')
            .map_or(0, |newline| newline + 1);
        let line = self.source[start..].lines().next().unwrap_or("");
        let trimmed = line.trim();
        if let Some(table) = trimmed.strip_prefix('[') {
            return table
                .trim_matches(|c| c == '[' || c == ']')
                .trim()
                .to_owned();
        }
        match trimmed.split_once('=') {
            Some((key, _)) => key.trim().to_owned(),
            None => "(file)".to_owned(),
        }
    }
}

/// 1-based line and column (characters) of byte `offset` in `source`.
pub(crate) fn line_column(source: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(source.len());
    let mut offset = offset;
    while !source.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &source[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |newline| newline + 1);
    let column = source[line_start..offset].chars().count() + 1;
    (line, column)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based_and_count_characters() {
        let source = "a = 1\nb = \"é\" x\n";
        assert_eq!(line_column(source, 0), (1, 1));
        assert_eq!(line_column(source, 6), (2, 1));
        let x = source.find('x').unwrap();
        assert_eq!(line_column(source, x), (2, 9));
        assert_eq!(line_column(source, 10_000), (3, 1));
    }

    #[test]
    fn key_at_finds_the_key_or_table_of_a_line() {
        let source = "[server]\ntick_hz = \"fast\"\n[[axis]]\n";
        let issues = Issues::new(source);
        assert_eq!(issues.key_at(source.find("fast").unwrap()), "tick_hz");
        assert_eq!(issues.key_at(2), "server");
        assert_eq!(issues.key_at(source.rfind("axis").unwrap()), "axis");
    }
}
