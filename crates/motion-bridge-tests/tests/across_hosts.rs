//! motiond and a bridge on one side, `motionctl --remote` on the other: over loopback on
//! this host (always), and across two network namespaces joined by a veth pair (when the
//! test runs as root; skipped with a message otherwise). List, move and arrive, jog and
//! kill the remote client, a command not on the allow-list, and — across the namespaces —
//! the network dropping under a jog.

use core::time::Duration;
use std::time::Instant;

use motion_bridge_tests::real::{Netns, Rig, binaries, finish};
use motion_bridge_tests::{DEADLINE, Result};
use nix::sys::signal::{Signal, kill};
use nix::unistd::{Pid, geteuid};
use serde_json::Value;

/// Polls the server's own status until `check` holds for axis `name`.
fn until_axis(rig: &Rig, name: &str, what: &str, check: impl Fn(&Value) -> bool) -> Result<Value> {
    let until = Instant::now() + DEADLINE;
    loop {
        let axis = Rig::axis(&rig.status()?, name)?;
        if check(&axis) {
            return Ok(axis);
        }
        if Instant::now() > until {
            return Err(format!("{name} never {what}: {axis}\n{}", rig.logs()).into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn jogging(axis: &Value) -> bool {
    axis["mode"] == "ramp-velocity" || axis["mode"] == "velocity"
}

fn has_flag(axis: &Value, flag: &str) -> bool {
    axis["flags"]
        .as_array()
        .is_some_and(|flags| flags.iter().any(|f| f == flag))
}

fn names(list: &Value, key: &str) -> Vec<String> {
    list[key]
        .as_array()
        .map(|items| {
            items
                .iter()
                .filter_map(|item| item["name"].as_str().map(str::to_owned))
                .collect()
        })
        .unwrap_or_default()
}

/// Starts a remote jog of `axis` and waits until the server runs it.
fn start_jog(rig: &Rig, axis: &str, velocity: &str) -> Result<std::process::Child> {
    let jog = rig
        .remote_command("operator", &["jog", axis, velocity])
        .spawn()?;
    until_axis(rig, axis, "jogged", jogging)?;
    Ok(jog)
}

fn kill_now(child: std::process::Child) -> Result {
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGKILL)?;
    finish(child, DEADLINE)?;
    Ok(())
}

/// What every remote session must be able to do, and not do.
fn list_move_jog_kill_refuse(rig: &Rig) -> Result {
    // list: the remote sees what the server has.
    let listed = rig.remote("operator", &["list", "--json"])?;
    assert!(listed.status.success(), "{listed:?}\n{}", rig.logs());
    let list: Value = serde_json::from_slice(&listed.stdout)?;
    let status = rig.status()?;
    assert_eq!(names(&list, "axes"), names(&status, "axes"));
    assert!(names(&list, "axes").contains(&"conveyor".to_owned()));

    // move and arrive.
    let moved = rig.remote(
        "operator",
        &["move", "x", "10", "--wait", "--timeout", "30s"],
    )?;
    assert!(moved.status.success(), "{moved:?}\n{}", rig.logs());
    let x = Rig::axis(&rig.status()?, "x")?;
    let reached = x["position"].as_f64().ok_or("position")?;
    assert!((reached - 10.0).abs() < 0.1, "x at {reached}");
    assert!(has_flag(&x, "arrived"), "{x}");

    // jog, renewed across the network for longer than the deadman (250 ms)...
    let jog = start_jog(rig, "conveyor", "50")?;
    std::thread::sleep(Duration::from_millis(800));
    let conveyor = Rig::axis(&rig.status()?, "conveyor")?;
    assert!(
        jogging(&conveyor),
        "the jog lapsed while its client ran: {conveyor}"
    );
    // ...then the remote client is killed: the axis stops.
    kill_now(jog)?;
    until_axis(rig, "conveyor", "stopped", |axis| !jogging(axis))?;

    // Not on the allow-list: refused by the bridge, exit status 4, nothing moves.
    let refused = rig.remote("viewer", &["move", "y", "5"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert!(
        stderr.contains("not-allowed") && stderr.contains("viewer"),
        "{stderr}"
    );
    let y = Rig::axis(&rig.status()?, "y")?;
    assert_ne!(y["mode"], "ramp-position", "{y}");
    // What the viewer may do, it can.
    let stopped = rig.remote("viewer", &["stop", "y"])?;
    assert!(stopped.status.success(), "{stopped:?}");
    Ok(())
}

#[test]
fn over_loopback_a_remote_motionctl_lists_moves_jogs_and_is_refused() -> Result {
    let Some(binaries) = binaries() else {
        return Ok(());
    };
    let rig = Rig::start(&binaries, None)?;
    list_move_jog_kill_refuse(&rig)
}

#[test]
fn across_network_namespaces_and_when_the_network_drops() -> Result {
    if !geteuid().is_root() {
        eprintln!(
            "SKIPPED across_network_namespaces_and_when_the_network_drops: creating network \
             namespaces needs root (run ./scripts/test as root)"
        );
        return Ok(());
    }
    let Some(binaries) = binaries() else {
        return Ok(());
    };
    let netns = match Netns::create() {
        Ok(netns) => netns,
        Err(error) => {
            eprintln!(
                "SKIPPED across_network_namespaces_and_when_the_network_drops: this machine \
                 cannot make network namespaces: {error}"
            );
            return Ok(());
        }
    };
    let rig = Rig::start(&binaries, Some(&netns))?;
    // The bridge is reachable only across the veth pair, not through the remote's loopback.
    assert!(
        rig.endpoint
            .starts_with(&format!("tcp/{}:", netns.server_addr))
    );
    list_move_jog_kill_refuse(&rig)?;

    // The network drops under a running jog (nothing is closed: zenoh on the bridge's side
    // still believes in the session for its lease of 10 s): the renewals stop arriving and
    // the server's deadman stops the axis.
    let jog = start_jog(&rig, "conveyor", "-50")?;
    netns.set_remote_link(false)?;
    let stopped = until_axis(&rig, "conveyor", "stopped by its deadman", |axis| {
        !jogging(axis) && has_flag(axis, "deadman-expired")
    });
    netns.set_remote_link(true)?;
    kill_now(jog)?;
    stopped?;
    Ok(())
}
