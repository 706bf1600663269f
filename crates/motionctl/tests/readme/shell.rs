//! Shell lines as a reader types them: a block's logical lines (a line ending in `\`
//! continued on the next; in a ```console block only the lines after a prompt), and each
//! line's simple commands as words, the way sh splits them.

use super::markdown::Block;

/// The command lines of `block`, each with the number of the line it starts on.
pub fn command_lines(block: &Block) -> Vec<(usize, String)> {
    let console = block.info.starts_with("console");
    let mut lines = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (number, line) in &block.lines {
        let text = match pending.take() {
            Some((start, head)) => Some((start, head + " " + line.trim_start())),
            None if console => prompt_stripped(line).map(|rest| (*number, rest.to_owned())),
            None => Some((*number, line.clone())),
        };
        let Some((start, text)) = text else {
            continue;
        };
        match text.strip_suffix('\\') {
            Some(head) => pending = Some((start, head.trim_end().to_owned())),
            None => lines.push((start, text)),
        }
    }
    lines.extend(pending);
    lines
}

/// The command after a console prompt (`$ `, `host-a$ `, `user@host:~$ `), or `None` for a
/// line of output.
fn prompt_stripped(line: &str) -> Option<&str> {
    let (prompt, rest) = line.split_once("$ ")?;
    (!prompt.contains(char::is_whitespace)).then_some(rest)
}

/// The simple commands of `line`: words with their quotes removed, split at `;`, `&&`,
/// `||`, `|` and `&`; a `#` that starts a word ends the line (a comment).
pub fn commands(line: &str) -> Vec<Vec<String>> {
    let mut commands = Vec::new();
    let mut words: Vec<String> = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                for quoted in chars.by_ref() {
                    if quoted == '\'' {
                        break;
                    }
                    word.push(quoted);
                }
            }
            '"' => {
                in_word = true;
                while let Some(quoted) = chars.next() {
                    match quoted {
                        '"' => break,
                        '\\' if matches!(chars.peek(), Some('"' | '\\' | '$' | '`')) => {
                            word.extend(chars.next());
                        }
                        _ => word.push(quoted),
                    }
                }
            }
            '\\' => {
                in_word = true;
                word.extend(chars.next());
            }
            '#' if !in_word => break,
            ';' | '&' | '|' => {
                end_word(&mut words, &mut word, &mut in_word);
                end_command(&mut commands, &mut words);
            }
            c if c.is_whitespace() => end_word(&mut words, &mut word, &mut in_word),
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    end_word(&mut words, &mut word, &mut in_word);
    end_command(&mut commands, &mut words);
    commands
}

fn end_word(words: &mut Vec<String>, word: &mut String, in_word: &mut bool) {
    if *in_word {
        words.push(core::mem::take(word));
        *in_word = false;
    }
}

fn end_command(commands: &mut Vec<Vec<String>>, words: &mut Vec<String>) {
    if !words.is_empty() {
        commands.push(core::mem::take(words));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn owned(words: &[&[&str]]) -> Vec<Vec<String>> {
        words
            .iter()
            .map(|command| command.iter().map(|&word| word.to_owned()).collect())
            .collect()
    }

    #[test]
    fn words_quotes_separators_and_comments() {
        assert_eq!(
            commands(r#"python3 -m venv .venv && . .venv/bin/activate   # a "comment""#),
            owned(&[
                &["python3", "-m", "venv", ".venv"],
                &[".", ".venv/bin/activate"]
            ])
        );
        assert_eq!(
            commands(r#"pip install './python[numpy]' x\ y "a \"b\" #c" ; cargo run &"#),
            owned(&[
                &["pip", "install", "./python[numpy]", "x y", r#"a "b" #c"#],
                &["cargo", "run"],
            ])
        );
        assert_eq!(
            commands("motionctl group feed arm 50%#1"),
            owned(&[&["motionctl", "group", "feed", "arm", "50%#1"]])
        );
    }

    #[test]
    fn console_lines_keep_only_commands_and_continuations_join() {
        let block = Block {
            info: "console".to_owned(),
            lines: vec![
                (10, "host-a$ cargo run --release \\".to_owned()),
                (11, "    -p motiond".to_owned()),
                (12, "INFO motion_bridge: bridge up".to_owned()),
                (13, "motiond \"demo\": 1000 Hz $ not a prompt".to_owned()),
                (14, "$ motionctl list".to_owned()),
            ],
        };
        assert_eq!(
            command_lines(&block),
            [
                (10, "cargo run --release -p motiond".to_owned()),
                (14, "motionctl list".to_owned()),
            ]
        );
    }
}
