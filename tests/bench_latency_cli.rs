//! Smoke test of the latency bench's command line (benches/latency/cli.rs), which
//! `cargo test` does not otherwise build: the documented invocations parse, bad ones fail.

#[allow(dead_code)] // the bench reads the fields; this test only parses
#[path = "../benches/latency/cli.rs"]
mod cli;

use core::time::Duration;

use clap::Parser;
use clap::error::ErrorKind;
use cli::{Cli, CommandProbe, parse_duration};

#[test]
fn documented_invocation_parses() {
    let cli = Cli::try_parse_from([
        "latency",
        "--bench", // cargo bench passes it
        "--server",
        "demo",
        "--duration",
        "10s",
        "--json",
        "--out",
        "/tmp/latency",
        "--rt-priority",
        "80",
        "--cpu",
        "1",
        "--axes-sweep",
    ])
    .expect("the README's command line parses");
    assert_eq!(cli.server, "demo");
    assert_eq!(cli.duration, Duration::from_secs(10));
    assert!(cli.json && cli.axes_sweep);
    assert_eq!(cli.rt_priority, Some(80));
    assert_eq!(cli.cpu, Some(1));
    assert_eq!(cli.command, CommandProbe::UnknownAxis);
    assert!(
        cli.command_to_wire,
        "the command-to-wire phase runs by default"
    );
    assert!(cli.peer.is_none());
}

#[test]
fn command_to_wire_is_on_by_default_and_can_be_switched_off() {
    let parse = |args: &[&str]| {
        Cli::try_parse_from(args)
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
            .command_to_wire
    };
    assert!(parse(&["latency"]));
    assert!(parse(&["latency", "--command-to-wire"]));
    assert!(parse(&["latency", "--command-to-wire=true"]));
    assert!(!parse(&["latency", "--command-to-wire=false"]));
    assert!(!parse(&["latency", "--command-to-wire", "false", "--json"]));
    assert!(Cli::try_parse_from(["latency", "--command-to-wire=maybe"]).is_err());
}

#[test]
fn help_lists_the_options_but_not_the_peer_flags() {
    let error = Cli::try_parse_from(["latency", "--help"]).expect_err("--help exits");
    assert_eq!(error.kind(), ErrorKind::DisplayHelp);
    let help = error.render().to_string();
    for option in [
        "--server",
        "--duration",
        "--json",
        "--out",
        "--rt-priority",
        "--cpu",
        "--axes-sweep",
        "--command-to-wire",
        "--motiond",
    ] {
        assert!(
            help.contains(option),
            "{option} missing from --help:\n{help}"
        );
    }
    assert!(!help.contains("--peer"), "internal flag shown:\n{help}");
}

#[test]
fn bad_values_are_refused() {
    for args in [
        &["latency", "--rt-priority", "0"][..],
        &["latency", "--rt-priority", "100"],
        &["latency", "--duration", "0s"],
        &["latency", "--duration", "10 parsecs"],
        &["latency", "--command", "move"],
    ] {
        assert!(Cli::try_parse_from(args).is_err(), "{args:?} accepted");
    }
}

#[test]
fn durations_take_units() {
    assert_eq!(parse_duration("10s"), Ok(Duration::from_secs(10)));
    assert_eq!(parse_duration("250ms"), Ok(Duration::from_millis(250)));
    assert_eq!(parse_duration("2m"), Ok(Duration::from_secs(120)));
    assert_eq!(parse_duration("1.5"), Ok(Duration::from_millis(1500)));
    assert_eq!(parse_duration("500us"), Ok(Duration::from_micros(500)));
    assert!(parse_duration("").is_err());
    assert!(parse_duration("-1s").is_err());
    assert!(parse_duration("2h").is_err());
}
