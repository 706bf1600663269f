//! What a clap `--help` says a command line may hold: its subcommands, its options (and
//! whether each takes a value), its positional arguments and the options it requires, and
//! the check of one command line's words against it, subcommand by subcommand.

use std::collections::{BTreeMap, BTreeSet};

/// Whether an option takes a value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Takes {
    /// A switch (`--wait`).
    Nothing,
    /// `--velocity <VELOCITY>`: the next word (or `=value`).
    Value,
    /// `--groups [<BOOL>]`: only as `--groups=value`.
    OptionalValue,
}

/// A positional argument of the usage line (`<AXIS>`, `[AXES]...`, `<on|off>`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Positional {
    pub name: String,
    pub required: bool,
    pub repeated: bool,
    /// `<on|off>`: the words allowed.
    pub choices: Vec<String>,
}

/// One `--help` page.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Help {
    pub subcommands: BTreeSet<String>,
    /// `--server`, `-h`, … with what each takes.
    pub options: BTreeMap<String, Takes>,
    pub positionals: Vec<Positional>,
    /// Options the usage line lists outside brackets (`--duration <DURATION>`).
    pub required: Vec<String>,
    /// The usage line asks for a subcommand (`<COMMAND>`).
    pub needs_command: bool,
}

/// Reads a clap help page. `depth` is the number of words before the usage line's own
/// arguments (the program and its subcommands: `Usage: motionctl group move …` has 3).
pub fn parse(text: &str, depth: usize) -> Help {
    let mut help = Help::default();
    let mut section = "";
    for line in text.lines() {
        if let Some(usage) = line.strip_prefix("Usage: ") {
            usage_line(usage, depth, &mut help);
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        if !line.starts_with(' ') {
            section = line.trim_end();
            continue;
        }
        let indent = line.len() - line.trim_start().len();
        let body = line.trim_start();
        match section {
            "Commands:" if indent == 2 => {
                if let Some(name) = body.split_whitespace().next() {
                    help.subcommands.insert(name.to_owned());
                }
            }
            "Options:" if indent <= 6 && body.starts_with('-') => option_line(body, &mut help),
            _ => {}
        }
    }
    help
}

/// `-h, --help`, `--velocity <VELOCITY>  Ramp velocity…`, `--groups [<BOOL>]`.
fn option_line(body: &str, help: &mut Help) {
    let mut names = Vec::new();
    let mut takes = Takes::Nothing;
    let mut after_comma = false;
    for word in body.split_whitespace() {
        if let Some(name) = word.strip_suffix(',').filter(|name| name.starts_with('-')) {
            names.push(name.to_owned());
            after_comma = true;
        } else if word.starts_with('-') && (names.is_empty() || after_comma) {
            names.push(word.to_owned());
            after_comma = false;
        } else if word.starts_with("[<") {
            takes = Takes::OptionalValue;
            break;
        } else if word.starts_with('<') {
            takes = Takes::Value;
            break;
        } else {
            break;
        }
    }
    for name in names {
        help.options.insert(name, takes);
    }
}

/// The usage line's arguments after its first `depth` words.
fn usage_line(usage: &str, depth: usize, help: &mut Help) {
    let words: Vec<&str> = usage.split_whitespace().skip(depth).collect();
    let mut index = 0;
    while index < words.len() {
        let word = words[index];
        index += 1;
        if word == "<COMMAND>" {
            help.needs_command = true;
            continue;
        }
        if word == "[OPTIONS]" || word == "[COMMAND]" {
            continue;
        }
        if word.starts_with("[-") {
            // An optional option group, `[--flag <V>]`: to its closing bracket.
            while index < words.len() && !words[index - 1].ends_with(']') {
                index += 1;
            }
            continue;
        }
        if word.starts_with("--") {
            help.required.push(word.to_owned());
            if words.get(index).is_some_and(|value| value.starts_with('<')) {
                index += 1;
            }
            continue;
        }
        let repeated = word.ends_with("...");
        let bare = word.trim_end_matches("...");
        let required = bare.starts_with('<');
        let name = bare.trim_matches(['<', '>', '[', ']']).to_owned();
        let choices = if name.contains('|') {
            name.split('|').map(str::to_owned).collect()
        } else {
            Vec::new()
        };
        help.positionals.push(Positional {
            name,
            required,
            repeated,
            choices,
        });
    }
}

/// Where a command line's words lead: the subcommands it names, in order, and what is
/// wrong with it (empty when every word parses).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Walk {
    pub path: Vec<String>,
    pub problems: Vec<String>,
}

/// Checks `args` against the help pages `help_of` returns for each subcommand path (`[]`
/// for the program itself): each subcommand exists, each option exists at the level it is
/// given, a value follows an option that takes one, the positional arguments fit the usage
/// line and its choices, and the options it requires are given.
pub fn walk(
    program: &str,
    args: &[String],
    mut help_of: impl FnMut(&[String]) -> Result<Help, String>,
) -> Walk {
    let mut walk = Walk::default();
    let mut help = match help_of(&[]) {
        Ok(help) => help,
        Err(problem) => {
            walk.problems.push(problem);
            return walk;
        }
    };
    let mut positionals: Vec<&str> = Vec::new();
    let mut given: BTreeSet<String> = BTreeSet::new();
    let mut index = 0;
    while index < args.len() {
        let word = args[index].as_str();
        index += 1;
        let shown = || format!("`{program} {}`", walk.path.join(" ")).replace(" `", "`");
        if word == "--" {
            positionals.extend(args[index..].iter().map(String::as_str));
            break;
        }
        if word.starts_with('-') && word.len() > 1 && !is_number(word) {
            let (name, value) = match word.split_once('=') {
                Some((name, _)) => (name, true),
                None => (word, false),
            };
            match help.options.get(name) {
                None => walk.problems.push(format!(
                    "{} has no option `{name}` (its --help lists: {})",
                    shown(),
                    help.options.keys().cloned().collect::<Vec<_>>().join(" ")
                )),
                Some(Takes::Value) if !value => {
                    if index < args.len() {
                        index += 1;
                    } else {
                        walk.problems
                            .push(format!("{}: `{name}` needs a value", shown()));
                    }
                }
                Some(Takes::Nothing) if value => walk
                    .problems
                    .push(format!("{}: `{name}` takes no value", shown())),
                Some(_) => {}
            }
            given.insert(name.to_owned());
            continue;
        }
        if positionals.is_empty() && !help.subcommands.is_empty() {
            if !help.subcommands.contains(word) {
                walk.problems.push(format!(
                    "{} has no subcommand `{word}` (its --help lists: {})",
                    shown(),
                    help.subcommands
                        .iter()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(" ")
                ));
                return walk;
            }
            walk.path.push(word.to_owned());
            help = match help_of(&walk.path) {
                Ok(help) => help,
                Err(problem) => {
                    walk.problems.push(problem);
                    return walk;
                }
            };
            continue;
        }
        positionals.push(word);
    }
    let shown = format!("`{program} {}`", walk.path.join(" ")).replace(" `", "`");
    if ["--help", "-h", "--version", "-V"]
        .iter()
        .any(|&word| given.contains(word))
    {
        // clap answers these before it looks at anything else.
        return walk;
    }
    if help.needs_command {
        walk.problems.push(format!("{shown} needs a subcommand"));
    }
    fit_positionals(&shown, &help, &positionals, &mut walk.problems);
    for option in &help.required {
        if !given.contains(option) {
            walk.problems.push(format!("{shown} requires `{option}`"));
        }
    }
    walk
}

/// The positional words against the usage line: none missing, none too many, each of a
/// choice among its choices.
fn fit_positionals(shown: &str, help: &Help, words: &[&str], problems: &mut Vec<String>) {
    let mut words = words.iter();
    for positional in &help.positionals {
        let taken: Vec<&&str> = if positional.repeated {
            words.by_ref().collect()
        } else {
            words.next().into_iter().collect()
        };
        if taken.is_empty() && positional.required {
            problems.push(format!("{shown} misses its argument <{}>", positional.name));
        }
        for word in taken {
            if !positional.choices.is_empty() && !positional.choices.iter().any(|c| c == word) {
                problems.push(format!(
                    "{shown}: `{word}` is not one of <{}>",
                    positional.name
                ));
            }
        }
    }
    let extra: Vec<&&str> = words.collect();
    if !extra.is_empty() && help.subcommands.is_empty() {
        problems.push(format!("{shown} takes no further argument: {extra:?}"));
    }
}

/// `-2.5`, `-10`: a negative number, not an option.
fn is_number(word: &str) -> bool {
    word[1..].starts_with(|c: char| c.is_ascii_digit() || c == '.')
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOP: &str = "Usage: motionctl [OPTIONS] <COMMAND>\n\nCommands:\n  move  Move an axis\n  io    Board I/O\n  help  Print this message\n\nOptions:\n      --server <NAME>  Instance name [default: demo]\n  -h, --help  Print help\n";
    const MOVE: &str = "Usage: motionctl move [OPTIONS] <AXIS> <POSITION>\n\nArguments:\n  <AXIS>  Axis name\n\nOptions:\n      --server <NAME>\n          Instance\n\n      --wait  Wait\n      --groups [<BOOL>]\n          Measure:\n          - csv:  One row\n  -h, --help  Print help\n";
    const SET: &str = "Usage: motionctl io set [OPTIONS] --duration <DURATION> <NAME> <on|off>\n\nOptions:\n      --duration <DURATION>\n";

    fn pages(path: &[String]) -> Result<Help, String> {
        match path.iter().map(String::as_str).collect::<Vec<_>>()[..] {
            [] => Ok(parse(TOP, 1)),
            ["move"] => Ok(parse(MOVE, 2)),
            ["io"] => Ok(parse(&TOP.replace("move", "set"), 2)),
            ["io", "set"] => Ok(parse(SET, 3)),
            _ => Err(format!("no page for {path:?}")),
        }
    }

    fn problems(line: &str) -> Vec<String> {
        let args: Vec<String> = line.split_whitespace().map(str::to_owned).collect();
        walk("motionctl", &args, pages).problems
    }

    #[test]
    fn a_help_page_is_read() {
        let help = parse(MOVE, 2);
        assert_eq!(help.options.get("--server"), Some(&Takes::Value));
        assert_eq!(help.options.get("--wait"), Some(&Takes::Nothing));
        assert_eq!(help.options.get("--groups"), Some(&Takes::OptionalValue));
        assert_eq!(help.options.get("-h"), Some(&Takes::Nothing));
        assert!(
            !help.options.contains_key("-"),
            "a description's list is no option"
        );
        assert_eq!(help.positionals.len(), 2);
        assert!(help.positionals.iter().all(|p| p.required && !p.repeated));
        assert_eq!(parse(SET, 3).required, ["--duration"]);
        assert_eq!(
            parse(TOP, 1).subcommands,
            ["help", "io", "move"].map(String::from).into()
        );
    }

    #[test]
    fn good_lines_pass() {
        assert_eq!(
            problems("--server demo move x -2.5 --wait"),
            Vec::<String>::new()
        );
        assert_eq!(problems("move x 10 --groups=false"), Vec::<String>::new());
        assert_eq!(
            problems("io set --duration 5s lamp on"),
            Vec::<String>::new()
        );
    }

    #[test]
    fn bad_lines_are_named() {
        let expect = |line: &str, part: &str| {
            let found = problems(line);
            assert!(found.iter().any(|p| p.contains(part)), "{line}: {found:?}");
        };
        expect("mvoe x 10", "no subcommand `mvoe`");
        expect("move x 10 --velocityy 2", "no option `--velocityy`");
        expect("move x 10 --wait=yes", "takes no value");
        expect("move x", "misses its argument <POSITION>");
        expect("move x 1 2", "takes no further argument");
        expect("io set --duration 1s lamp maybe", "not one of <on|off>");
        expect("io set lamp on", "requires `--duration`");
        expect("io", "needs a subcommand");
        expect("move x 10 --server", "needs a value");
        assert_eq!(problems("io --help"), Vec::<String>::new());
    }
}
