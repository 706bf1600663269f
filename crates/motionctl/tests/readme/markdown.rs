//! The README as markdown: its fenced blocks, its headings (and their GitHub anchors), its
//! links, and the repository paths its text names.

use std::collections::BTreeSet;

/// A fenced code block: its info string (`sh`, `console`, `rust,no_run`, …) and its lines,
/// numbered from 1 as in the file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Block {
    pub info: String,
    pub lines: Vec<(usize, String)>,
}

impl Block {
    /// Whether the block holds shell commands: ```sh, ```bash, ```shell or ```console.
    pub fn is_shell(&self) -> bool {
        let language = self.info.split([',', ' ']).next().unwrap_or("");
        matches!(language, "sh" | "bash" | "shell" | "console")
    }
}

/// Every fenced block of `text`, in order. An unclosed fence runs to the end of the text.
pub fn blocks(text: &str) -> Vec<Block> {
    let mut blocks = Vec::new();
    let mut open: Option<Block> = None;
    for (index, line) in text.lines().enumerate() {
        let fence = line.trim_start().strip_prefix("```");
        match (&mut open, fence) {
            (None, Some(info)) => {
                open = Some(Block {
                    info: info.trim().to_owned(),
                    lines: Vec::new(),
                });
            }
            (Some(_), Some(_)) => blocks.extend(open.take()),
            (Some(block), None) => block.lines.push((index + 1, line.to_owned())),
            (None, None) => {}
        }
    }
    blocks.extend(open);
    blocks
}

/// The text of every heading of `text` outside fenced blocks, without its `#`s and with
/// backticks removed (`## From another host: through \`motion-bridge\`` →
/// `From another host: through motion-bridge`).
pub fn headings(text: &str) -> Vec<String> {
    let mut inside = false;
    let mut found = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            inside = !inside;
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if inside || hashes == 0 || hashes > 6 {
            continue;
        }
        if let Some(rest) = line[hashes..].strip_prefix(' ') {
            found.push(rest.trim().trim_end_matches('#').trim().replace('`', ""));
        }
    }
    found
}

/// The anchor GitHub gives a heading: lower case, spaces to `-`, every character that is
/// not a letter, a digit, `-` or `_` dropped.
pub fn slug(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// A markdown link `[text](target)`: its line, its target, and the section it names right
/// after it, if any (`[docs/X.md](docs/X.md) "Section"` or `…(docs/X.md), "Section"`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Link {
    pub line: usize,
    pub target: String,
    pub section: Option<String>,
}

/// Every inline link of `text` outside fenced blocks.
pub fn links(text: &str) -> Vec<Link> {
    let prose = without_blocks(text);
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(at) = prose[from..].find("](") {
        let start = from + at + 2;
        let Some(length) = prose[start..].find(')') else {
            break;
        };
        let target = &prose[start..start + length];
        let after = &prose[start + length + 1..];
        from = start + length + 1;
        if target.contains(char::is_whitespace) {
            continue;
        }
        let line = prose[..start].matches('\n').count() + 1;
        found.push(Link {
            line,
            target: target.to_owned(),
            section: quoted_section(after),
        });
    }
    found
}

/// The `"Section"` that opens `after` (an optional comma and white space first), its white
/// space collapsed.
fn quoted_section(after: &str) -> Option<String> {
    let rest = after.strip_prefix(',').unwrap_or(after).trim_start();
    let rest = rest.strip_prefix('"')?;
    let end = rest.find('"')?;
    let words: Vec<&str> = rest[..end].split_whitespace().collect();
    (!words.is_empty()).then(|| words.join(" "))
}

/// `text` with the lines of its fenced blocks emptied (line numbers kept).
fn without_blocks(text: &str) -> String {
    let mut inside = false;
    let mut kept = String::with_capacity(text.len());
    for line in text.lines() {
        let fence = line.trim_start().starts_with("```");
        if fence {
            inside = !inside;
        }
        if !inside && !fence {
            kept.push_str(line);
        }
        kept.push('\n');
    }
    kept
}

/// Every path into the repository that `text` names (prose and blocks alike), with its
/// line: a word that starts with one of the top-level directories `top` (`docs/…`,
/// `./scripts/test`, `crates/…`), braces expanded (`docs/keys/{qsb,qq2drv}.md` is two
/// paths). Words with a placeholder (`<board>`, `*`, `…`) name no single path and are left
/// out.
pub fn paths(text: &str, top: &BTreeSet<String>) -> Vec<(usize, String)> {
    let mut found = Vec::new();
    for (index, line) in text.lines().enumerate() {
        for word in path_words(line) {
            let path = word.strip_prefix("./").unwrap_or(word);
            let Some((first, _)) = path.split_once('/') else {
                continue;
            };
            if !top.contains(first) || path.contains(['<', '>', '*', '…', '$']) {
                continue;
            }
            for expanded in expand_braces(path) {
                found.push((index + 1, expanded));
            }
        }
    }
    found
}

/// The words of `line` that may be paths: runs of path characters (and `{…}` groups), not
/// preceded by one (so `/tmp/run.csv` yields nothing that starts inside it), with a
/// sentence's final `.` removed.
fn path_words(line: &str) -> Vec<&str> {
    let is_path = |c: char| c.is_alphanumeric() || "_-./<>*…$".contains(c);
    let mut words = Vec::new();
    let mut chars = line.char_indices().peekable();
    while let Some((start, c)) = chars.next() {
        if !is_path(c) && c != '{' {
            continue;
        }
        let mut end = start + c.len_utf8();
        let mut depth = usize::from(c == '{');
        while let Some(&(at, next)) = chars.peek() {
            if next == '{' {
                depth += 1;
            } else if next == '}' && depth > 0 {
                depth -= 1;
            } else if depth == 0 && !is_path(next) {
                break;
            }
            end = at + next.len_utf8();
            chars.next();
        }
        let word = line[start..end].trim_end_matches('.');
        if !word.starts_with('/') && !word.is_empty() {
            words.push(word);
        }
    }
    words
}

/// `a/{b,c}/d` → `a/b/d`, `a/c/d` (nested groups too).
fn expand_braces(path: &str) -> Vec<String> {
    let Some(open) = path.find('{') else {
        return vec![path.to_owned()];
    };
    let mut depth = 0;
    let mut close = None;
    for (at, c) in path[open..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    close = Some(open + at);
                    break;
                }
            }
            _ => {}
        }
    }
    let Some(close) = close else {
        return vec![path.to_owned()];
    };
    let (head, tail) = (&path[..open], &path[close + 1..]);
    path[open + 1..close]
        .split(',')
        .flat_map(|choice| expand_braces(&format!("{head}{choice}{tail}")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = "# Title\n\nSee [docs/X.md](docs/X.md) \"The\nsection\" and `docs/keys/{a,b}.md`.\n\n```sh\n./scripts/test   # /tmp/run.csv\n# ## not a heading\n```\n\n## From `here`\n";

    #[test]
    fn blocks_headings_links_and_paths_are_found() {
        let blocks = blocks(SAMPLE);
        assert_eq!(blocks.len(), 1);
        assert!(blocks[0].is_shell());
        assert_eq!(
            blocks[0].lines[0],
            (7, "./scripts/test   # /tmp/run.csv".to_owned())
        );
        assert_eq!(headings(SAMPLE), ["Title", "From here"]);
        assert_eq!(
            links(SAMPLE),
            [Link {
                line: 3,
                target: "docs/X.md".to_owned(),
                section: Some("The section".to_owned()),
            }]
        );
        let top: BTreeSet<String> = ["docs", "scripts"].map(String::from).into();
        assert_eq!(
            paths(SAMPLE, &top),
            [
                (3, "docs/X.md".to_owned()),
                (3, "docs/X.md".to_owned()),
                (4, "docs/keys/a.md".to_owned()),
                (4, "docs/keys/b.md".to_owned()),
                (7, "scripts/test".to_owned()),
            ]
        );
    }

    #[test]
    fn slugs_are_githubs() {
        assert_eq!(
            slug("Command → wire: the links' stamps"),
            "command--wire-the-links-stamps"
        );
        assert_eq!(slug("From Python"), "from-python");
    }

    #[test]
    fn placeholders_name_no_path() {
        let top: BTreeSet<String> = ["crates"].map(String::from).into();
        assert!(paths("`crates/boards/<board>/src` and crates/*/README.md", &top).is_empty());
    }
}
