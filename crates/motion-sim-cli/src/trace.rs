//! What the simulator logs on stderr.

use std::fmt::Write as _;
use std::time::Duration;

/// A stderr logger for one endpoint; byte dumps only with `--trace`.
#[derive(Debug)]
pub struct Trace {
    label: String,
    bytes: bool,
}

impl Trace {
    /// A logger whose lines start with `label`; `bytes` enables byte dumps.
    pub fn new(label: impl Into<String>, bytes: bool) -> Self {
        Self {
            label: label.into(),
            bytes,
        }
    }

    /// Logs `bytes` moving in direction `dir` (`<-` from the client, `->` to it).
    pub fn bytes(&mut self, now: Duration, dir: &str, bytes: &[u8]) {
        if self.bytes && !bytes.is_empty() {
            eprintln!(
                "[{:>12.6}] {} {dir} {}",
                now.as_secs_f64(),
                self.label,
                dump(bytes)
            );
        }
    }

    /// Logs a message.
    pub fn note(&mut self, now: Duration, message: &str) {
        eprintln!("[{:>12.6}] {} {message}", now.as_secs_f64(), self.label);
    }
}

/// Hex bytes followed by their printable form: `52 31 34 0d 0a  "R14\r\n"`.
pub fn dump(bytes: &[u8]) -> String {
    let mut out = String::with_capacity(bytes.len() * 4 + 4);
    for (i, b) in bytes.iter().enumerate() {
        if i > 0 {
            out.push(' ');
        }
        let _ = write!(out, "{b:02x}");
    }
    out.push_str("  \"");
    for &b in bytes {
        out.extend(std::ascii::escape_default(b).map(char::from));
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn dump_shows_hex_and_escaped_text() {
        assert_eq!(super::dump(b"R14\r\n"), "52 31 34 0d 0a  \"R14\\r\\n\"");
    }
}
