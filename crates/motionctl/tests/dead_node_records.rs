//! Clients killed while they start leave no node record behind (issue 30, item 6): 200
//! `motionctl list` SIGKILLed 0–60 ms after their start against a live motiond; soon after
//! (about 2 s on a quiet machine; the test waits while their count falls) every record on the iceoryx2
//! service root belongs to a live node, and the server's stats count what it removed. One test in its own binary: nothing else here makes nodes.

mod common;

use core::time::Duration;
use std::collections::HashSet;
use std::path::PathBuf;
use std::process::Stdio;
use std::time::{Instant, SystemTime};

use iceoryx2::node::{Node, NodeState, NodeView as _};
use iceoryx2::prelude::{CallbackProgression, Config, ipc};

use common::real::RealServer;
use common::*;

/// The ids of the live nodes.
fn live_nodes() -> Result<HashSet<u128>> {
    let mut live = HashSet::new();
    Node::<ipc::Service>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state {
            live.insert(view.id().value());
        }
        CallbackProgression::Continue
    })
    .map_err(|error| format!("{error:?}"))?;
    Ok(live)
}

/// Every listed node's id and state as iceoryx2 names it (for a failure's message).
fn node_states() -> Vec<String> {
    let mut states = Vec::new();
    let listed = Node::<ipc::Service>::list(Config::global_config(), |state| {
        let kind = match &state {
            NodeState::Alive(_) => "alive",
            NodeState::Dead(_) => "dead",
            NodeState::Inaccessible(_) => "inaccessible",
            NodeState::Undefined(_) => "undefined",
        };
        states.push(format!("{} {kind}", state.node_id().value()));
        CallbackProgression::Continue
    });
    if let Err(error) = listed {
        states.push(format!("listing failed: {error:?}"));
    }
    states
}

/// Records in the node directory whose node is not alive and that are older than `age`
/// (younger ones may be a node another process is creating right now).
fn dead_records(age: Duration) -> Result<Vec<PathBuf>> {
    let dir = PathBuf::from(Config::global_config().global.node_dir().as_str());
    let live = live_nodes()?;
    let prefix = Config::global_config().global.prefix.as_str().to_owned();
    let mut dead = Vec::new();
    for entry in std::fs::read_dir(&dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let id = name
            .strip_prefix(&prefix)
            .unwrap_or(&name)
            .split('.')
            .next()
            .and_then(|id| id.parse::<u128>().ok());
        let Some(id) = id else { continue };
        let old = entry
            .metadata()?
            .modified()
            .map(|at| SystemTime::now().duration_since(at).unwrap_or_default() >= age)?;
        if old && !live.contains(&id) {
            dead.push(entry.path());
        }
    }
    Ok(dead)
}

#[test]
#[ignore = "open bug: under a full CI run the server's sweep has stalled (43 -> 70 records, none \
            removed in 15 s; cause not found); passes alone and under 4 parallel builds. Run \
            with `cargo test -p motionctl --test dead_node_records -- --ignored`"]
fn clients_killed_while_they_start_leave_no_node_record() -> Result {
    let server = RealServer::start()?;
    // Records already there belong to processes of other tests (a CI run kills servers and
    // clients in other test binaries too); the claim is about the clients killed here.
    let before: HashSet<PathBuf> = dead_records(Duration::ZERO)?.into_iter().collect();
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    for _ in 0..200 {
        let mut child = command(&server.name, &["list"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()?;
        // xorshift: 0–60 ms, the same every run.
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        std::thread::sleep(Duration::from_millis(seed % 61));
        child.kill()?;
        child.wait()?;
    }
    // The server's sweep removes them within a couple of seconds on a quiet machine; a
    // loaded one (a CI run building and testing on two cores, a debug server cleaning each
    // dead node's services) takes longer. The test asserts that they go, not how fast:
    // it waits while the count keeps falling, and fails when it stops falling for
    // `STALL` (or past a generous bound), printing the counts it saw.
    const STALL: Duration = Duration::from_secs(15);
    const BOUND: Duration = Duration::from_secs(120);
    let killed = Instant::now();
    let mut left = Vec::new();
    let mut fewest = usize::MAX;
    let mut progress = Instant::now();
    let mut seen = Vec::new();
    while killed.elapsed() < BOUND && progress.elapsed() < STALL {
        std::thread::sleep(Duration::from_millis(250));
        left = dead_records(Duration::from_millis(1500))?;
        left.retain(|record| !before.contains(record));
        if left.len() < fewest {
            fewest = left.len();
            progress = Instant::now();
            seen.push((killed.elapsed().as_millis(), left.len()));
        }
        if left.is_empty() && killed.elapsed() >= Duration::from_secs(2) {
            break;
        }
    }
    assert!(
        left.is_empty(),
        "{} records of dead nodes left {:?} after the kills (ms, records, each time fewer: \
         {seen:?}): {left:#?}\niceoryx2 lists: {:#?}",
        left.len(),
        killed.elapsed(),
        node_states()
    );
    // The server counts what it removed (the clients killed before their node existed
    // leave nothing to remove; most get one).
    let status = poll_json(&server.name, &["status", "--json"], |status| {
        status["stats"]["nodes_cleaned"].as_u64().is_some()
    })?;
    let cleaned = status["stats"]["nodes_cleaned"].as_u64().unwrap_or(0);
    assert!(cleaned > 0, "{status}");
    Ok(())
}
