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
    /// A file that is not UTF-8: the first bad byte, located.
    pub fn not_utf8(path: &Path, bytes: &[u8], error: &core::str::Utf8Error) -> Self {
        let good = &bytes[..error.valid_up_to()];
        let text = core::str::from_utf8(good).unwrap_or_default();
        let (line, column) = line_column(text, text.len());
        let byte = bytes.get(error.valid_up_to()).copied().unwrap_or(0);
        Self {
            path: path.to_owned(),
            issues: vec![ConfigIssue {
                line,
                column,
                key: "(file)".into(),
                message: format!(
                    "byte 0x{byte:02X} is not UTF-8: a config file is UTF-8 text (save it as UTF-8)"
                ),
            }],
        }
    }

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
    /// Indices into `list` of issues about dangling names (reported first).
    pub references: Vec<usize>,
    /// Things that work but are probably not what the user wants.
    pub warnings: Vec<ConfigIssue>,
}

impl<'a> Issues<'a> {
    pub fn new(source: &'a str) -> Self {
        Self {
            source,
            list: Vec::new(),
            references: Vec::new(),
            warnings: Vec::new(),
        }
    }

    /// Records `message` about `key` at byte range `span`.
    pub fn push(&mut self, span: Range<usize>, key: impl Into<String>, message: impl Into<String>) {
        let issue = self.at(span, key, message);
        self.list.push(issue);
    }

    /// Records an issue about a name that refers to nothing (listed before other issues:
    /// it often explains them).
    pub fn push_reference(
        &mut self,
        span: Range<usize>,
        key: impl Into<String>,
        message: impl Into<String>,
    ) {
        self.references.push(self.list.len());
        self.push(span, key, message);
    }

    /// The issues, dangling references first, then in file order.
    pub fn sorted(mut self) -> Vec<ConfigIssue> {
        let mut keyed: Vec<(bool, ConfigIssue)> = self
            .list
            .drain(..)
            .enumerate()
            .map(|(index, issue)| (!self.references.contains(&index), issue))
            .collect();
        keyed.sort_by_key(|(later, issue)| (*later, issue.line, issue.column));
        keyed.into_iter().map(|(_, issue)| issue).collect()
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

    /// The dotted key of the line holding byte `offset` (`server.tick_hz`, `axis[2].max`,
    /// the table itself for a header line), for errors serde reports with only a span.
    pub fn key_at(&self, offset: usize) -> String {
        let offset = offset.min(self.source.len());
        let mut table = String::new();
        let mut counts: Vec<(String, usize)> = Vec::new();
        let mut line_start = 0;
        for line in self.source.split_inclusive('\n') {
            let trimmed = line.trim();
            let header = if let Some(name) = trimmed.strip_prefix("[[") {
                let name = name.split("]]").next().unwrap_or("").trim().to_owned();
                let index = match counts.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, count)) => {
                        *count += 1;
                        *count - 1
                    }
                    None => {
                        counts.push((name.clone(), 1));
                        0
                    }
                };
                Some(format!("{name}[{index}]"))
            } else {
                trimmed
                    .strip_prefix('[')
                    .map(|name| name.split(']').next().unwrap_or("").trim().to_owned())
            };
            let is_header = header.is_some();
            if let Some(header) = header {
                table = header;
            }
            if offset < line_start + line.len() || line_start + line.len() == self.source.len() {
                if is_header {
                    return table;
                }
                let key = line.split_once('=').map(|(key, value)| {
                    let key = key.trim().trim_matches('"').to_owned();
                    // Inside an inline table: down to the key the offset is in.
                    let before = (offset - line_start).saturating_sub(key_len(line, value));
                    let inner = inline_path(value.get(..before).unwrap_or(value));
                    inner
                        .into_iter()
                        .fold(key, |path, part| format!("{path}.{part}"))
                });
                return match (key, table.is_empty()) {
                    (Some(key), true) => key,
                    (Some(key), false) => format!("{table}.{key}"),
                    (None, false) => table,
                    (None, true) => "(file)".to_owned(),
                };
            }
            line_start += line.len();
        }
        "(file)".to_owned()
    }
}

/// Bytes of `line` before its value (`value` is the part after the first `=`).
fn key_len(line: &str, value: &str) -> usize {
    line.len() - value.len()
}

/// The keys of the inline tables that are open at the end of `value` (a line's text after
/// its first `=`, cut at an offset), outermost first, with the key being given there:
/// `{ a = 1, b = { c = ` gives `[b, c]`. Strings are skipped.
fn inline_path(value: &str) -> Vec<String> {
    let mut open: Vec<Option<String>> = Vec::new();
    let mut current: Option<String> = None;
    let mut token = String::new();
    let mut quote: Option<char> = None;
    for c in value.chars() {
        if let Some(q) = quote {
            if c == q {
                quote = None;
            }
            token.push(c);
            continue;
        }
        match c {
            '"' | '\'' => {
                quote = Some(c);
                token.push(c);
            }
            '{' => {
                open.push(current.take());
                token.clear();
            }
            '}' => {
                current = open.pop().flatten();
                token.clear();
            }
            '=' => {
                current = Some(token.trim().trim_matches('"').to_owned());
                token.clear();
            }
            ',' => {
                if !open.is_empty() {
                    current = None;
                }
                token.clear();
            }
            '#' => break,
            _ => token.push(c),
        }
    }
    if open.is_empty() {
        return Vec::new();
    }
    open.into_iter().flatten().chain(current).collect()
}

/// 1-based line and column (characters) of byte `offset` in `source`.
pub(crate) fn line_column(source: &str, offset: usize) -> (usize, usize) {
    let offset = motion_base::floor_char_boundary(source, offset);
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
    fn key_at_finds_the_dotted_key_or_table_of_a_line() {
        let source = "[server]\ntick_hz = \"fast\"\n[[axis]]\nname = \"a\"\n[[axis]]\nmax = \"x\"\nhome = { input = 5 }";
        let issues = Issues::new(source);
        assert_eq!(
            issues.key_at(source.find("fast").unwrap()),
            "server.tick_hz"
        );
        assert_eq!(issues.key_at(2), "server");
        assert_eq!(
            issues.key_at(source.find("[[axis]]").unwrap() + 3),
            "axis[0]"
        );
        assert_eq!(issues.key_at(source.find("\"x\"").unwrap()), "axis[1].max");
        assert_eq!(
            issues.key_at(source.find("5 }").unwrap()),
            "axis[1].home.input"
        );
        let source =
            "[[axis]]\ncurrent = { peak = \"a, b = {\", limit = { low = 1, high = 2.5 }, t = 3 }\n";
        let issues = Issues::new(source);
        let at = |needle: &str| issues.key_at(source.find(needle).unwrap());
        assert_eq!(at("\"a,"), "axis[0].current.peak");
        assert_eq!(at("1,"), "axis[0].current.limit.low");
        assert_eq!(at("2.5"), "axis[0].current.limit.high");
        assert_eq!(at("3 }"), "axis[0].current.t");
        assert_eq!(at("{ peak"), "axis[0].current");
    }

    #[test]
    fn a_non_utf8_byte_is_located() {
        let mut bytes = b"[server]\nname = \"d_mo\"\n".to_vec();
        bytes[18] = 0xE9; // a Latin-1 é in place of the `_`
        let error = core::str::from_utf8(&bytes).unwrap_err();
        let config = ConfigError::not_utf8(Path::new("x.toml"), &bytes, &error);
        assert_eq!((config.issues[0].line, config.issues[0].column), (2, 10));
        assert!(config.issues[0].message.contains("0xE9"));
    }
}
