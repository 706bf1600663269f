//! Doc comments of the description as plain text for the generated C and Python files:
//! paragraphs reflowed, rustdoc links reduced to their `code` span, code spans renamed to
//! the target language's names, lines wrapped.

/// The doc lines of a `///` comment as one text: the space after `///` dropped, rustdoc
/// links (`` [`X`] ``, `` [`X`](path) ``) reduced to `` `X` ``.
pub(super) fn text(lines: &[&str]) -> String {
    let joined: Vec<&str> = lines
        .iter()
        .map(|line| line.strip_prefix(' ').unwrap_or(line))
        .collect();
    unlink(&joined.join("\n"))
}

/// `` [`X`](path) `` and `` [`X`] `` → `` `X` ``.
fn unlink(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("[`") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 1..];
        let Some(end) = after.find("`]") else {
            out.push_str(&rest[start..]);
            return out;
        };
        out.push_str(&after[..end + 1]);
        rest = &after[end + 2..];
        if rest.starts_with('(')
            && let Some(close) = rest.find(')')
        {
            rest = &rest[close + 1..];
        }
    }
    out.push_str(rest);
    out
}

/// `text`'s code spans (`` `X` ``) replaced by `rename(X)` (backticks and all).
pub(super) fn rename_code(text: &str, rename: impl Fn(&str) -> String) -> String {
    let mut out = String::with_capacity(text.len());
    let mut parts = text.split('`');
    if let Some(first) = parts.next() {
        out.push_str(first);
    }
    let mut code = true;
    for part in parts {
        if code {
            out.push_str(&rename(part));
        } else {
            out.push_str(part);
        }
        code = !code;
    }
    out
}

/// Paragraphs (split at blank lines), each reflowed into lines of at most `width`
/// characters (a longer word gets a line of its own).
pub(super) fn wrap(text: &str, width: usize) -> Vec<Vec<String>> {
    text.split("\n\n")
        .map(|paragraph| {
            let mut lines = Vec::new();
            let mut line = String::new();
            for word in paragraph.split_whitespace() {
                if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > width {
                    lines.push(std::mem::take(&mut line));
                }
                if !line.is_empty() {
                    line.push(' ');
                }
                line.push_str(word);
            }
            if !line.is_empty() {
                lines.push(line);
            }
            lines
        })
        .filter(|lines| !lines.is_empty())
        .collect()
}

/// `MotionFrame` → `motion_frame`, `OutOfRange` → `out_of_range` (how the C header and
/// its checks spell Rust names).
pub fn snake(name: &str) -> String {
    let mut out = String::new();
    for (index, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && index > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_lowercase());
    }
    out
}

/// `OutOfRange` → `OUT_OF_RANGE`.
pub(super) fn upper_snake(name: &str) -> String {
    snake(name).to_ascii_uppercase()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_become_code_spans() {
        let lines = [
            " [`FaultCode`] value; see",
            " [`ServerInfo::devices`](crate::ServerInfo::devices).",
        ];
        assert_eq!(
            text(&lines),
            "`FaultCode` value; see\n`ServerInfo::devices`."
        );
        assert_eq!(unlink("a [b] c"), "a [b] c");
    }

    #[test]
    fn code_spans_are_renamed() {
        let renamed = rename_code("the `AxisFlags` bits of `x`", |code| format!("<{code}>"));
        assert_eq!(renamed, "the <AxisFlags> bits of <x>");
    }

    #[test]
    fn paragraphs_are_reflowed_and_wrapped() {
        let wrapped = wrap("one two\nthree four five\n\nsix", 9);
        assert_eq!(
            wrapped,
            vec![vec!["one two", "three", "four five"], vec!["six"]]
        );
    }

    #[test]
    fn names_change_case() {
        assert_eq!(snake("MotionFrame"), "motion_frame");
        assert_eq!(upper_snake("EStop"), "E_STOP");
        assert_eq!(upper_snake("Qq2drv"), "QQ2DRV");
    }
}
