//! Smoke test of the latency bench's command line (benches/latency/cli.rs), which
//! `cargo test` does not otherwise build: the documented invocations parse, bad ones fail,
//! and the baseline peer's hidden command line round-trips.

#[allow(dead_code)] // the bench reads the fields; this test only parses
#[path = "../benches/latency/cli.rs"]
mod cli;

use core::time::Duration;

use clap::Parser;
use clap::error::ErrorKind;
use cli::Cli;
use motion_bench::peer::{PEER_FLAG, PeerArgs};
use motion_bench::{CommandProbe, PeerMode, parse_duration};

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
        "--plot",
        "/tmp/latency-plots",
        "--rt-priority",
        "80",
        "--cpu",
        "1",
        "--axes-sweep",
        "--python",
        "target/py-venv/bin/python",
    ])
    .expect("the command line of docs/PERFORMANCE.md parses");
    assert_eq!(cli.server, "demo");
    assert!(cli.cargo_bench);
    let bench = &cli.bench;
    assert_eq!(bench.duration, Duration::from_secs(10));
    assert!(bench.json && bench.axes_sweep);
    assert_eq!(bench.rt_priority, Some(80));
    assert_eq!(bench.cpu, Some(1));
    assert_eq!(
        bench.plot.as_deref(),
        Some(std::path::Path::new("/tmp/latency-plots"))
    );
    assert_eq!(bench.command, CommandProbe::UnknownAxis);
    assert_eq!(
        bench.python.as_deref(),
        Some(std::path::Path::new("target/py-venv/bin/python"))
    );
    assert!(
        bench.command_to_wire,
        "the command-to-wire phase runs by default"
    );
}

#[test]
fn the_peer_command_line_round_trips_and_refuses_garbage() {
    let peer = PeerArgs {
        mode: PeerMode::Ticking,
        name: "bench-peer-1".to_owned(),
        hz: 1000,
        rt_priority: Some(80),
        cpu: Some(1),
    };
    assert_eq!(PeerArgs::parse(&peer.to_words()), Ok(peer.clone()));
    let plain = PeerArgs {
        mode: PeerMode::BusyRr,
        rt_priority: None,
        cpu: None,
        ..peer
    };
    assert_eq!(PeerArgs::parse(&plain.to_words()), Ok(plain));
    let words = |w: &[&str]| w.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
    for bad in [
        &[][..],
        &["ticking", "x"],
        &["spinning", "x", "1000"],
        &["ticking", "x", "0"],
        &["ticking", "", "1000"],
        &["ticking", "x", "1000", "--cpu"],
        &["ticking", "x", "1000", "--nice", "3"],
    ] {
        assert!(PeerArgs::parse(&words(bad)).is_err(), "{bad:?} accepted");
    }
    // The flag is not an option of the bench's own command line (the binary's main
    // handles it before parsing).
    assert!(Cli::try_parse_from(["latency", PEER_FLAG, "ticking", "x", "1000"]).is_err());
}

#[test]
fn command_to_wire_is_on_by_default_and_can_be_switched_off() {
    let parse = |args: &[&str]| {
        Cli::try_parse_from(args)
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
            .bench
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
        "--python",
    ] {
        assert!(
            help.contains(option),
            "{option} missing from --help:\n{help}"
        );
    }
    assert!(!help.contains("--peer"), "internal flag shown:\n{help}");
    assert!(
        !help.contains("--motion-bench-peer"),
        "internal flag shown:\n{help}"
    );
    assert!(!help.contains("--bench "), "cargo's flag shown:\n{help}");
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
    assert_eq!(parse_duration("2h"), Ok(Duration::from_secs(7200)));
    assert!(parse_duration("2d").is_err());
}
