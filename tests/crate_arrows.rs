//! The crates' arrows run one way, as docs/ARCHITECTURE.md's crate table draws them: read
//! from `cargo metadata`, no workspace crate reaches itself through other crates' normal,
//! dev or build dependencies (a dev-dependency loop is an arrow back up), and neither
//! `motion-client` nor `motion-bridge` reaches the other — both stand on `motion-wire`, the
//! network contract, and the tests that need both live in `motion-bridge-tests`.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

use serde_json::Value;

/// Each workspace crate and the workspace crates it declares as dependencies (of any kind,
/// optional ones included), itself left out (`motion-client` names itself to turn on a
/// feature in its own tests).
fn workspace_arrows() -> BTreeMap<String, BTreeSet<String>> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let output = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        output.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let metadata: Value = serde_json::from_slice(&output.stdout).expect("cargo's JSON");
    let packages = metadata["packages"].as_array().expect("a package list");
    let members: BTreeSet<String> = packages
        .iter()
        .filter_map(|package| package["name"].as_str().map(str::to_owned))
        .collect();
    packages
        .iter()
        .map(|package| {
            let name = package["name"].as_str().unwrap_or_default().to_owned();
            let arrows = package["dependencies"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|dependency| dependency["name"].as_str())
                .filter(|dependency| members.contains(*dependency) && *dependency != name)
                .map(str::to_owned)
                .collect();
            (name, arrows)
        })
        .collect()
}

/// A chain of arrows from `from` to `to`, if there is one.
fn path(arrows: &BTreeMap<String, BTreeSet<String>>, from: &str, to: &str) -> Option<Vec<String>> {
    let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([from]);
    while let Some(at) = queue.pop_front() {
        for next in arrows.get(at).into_iter().flatten() {
            if next == to {
                let mut chain = vec![to.to_owned(), at.to_owned()];
                let mut step = at;
                while let Some(previous) = came_from.get(step) {
                    chain.push((*previous).to_owned());
                    step = previous;
                }
                chain.reverse();
                return Some(chain);
            }
            if next != from && !came_from.contains_key(next.as_str()) {
                came_from.insert(next, at);
                queue.push_back(next);
            }
        }
    }
    None
}

#[test]
fn neither_the_client_nor_the_bridge_depends_on_the_other() {
    let arrows = workspace_arrows();
    for (from, to) in [
        ("motion-client", "motion-bridge"),
        ("motion-bridge", "motion-client"),
    ] {
        assert!(arrows.contains_key(from), "{from} is a workspace crate");
        if let Some(chain) = path(&arrows, from, to) {
            panic!("{from} depends on {to}: {}", chain.join(" → "));
        }
    }
    for crate_name in ["motion-client", "motion-bridge"] {
        assert!(
            arrows[crate_name].contains("motion-wire"),
            "{crate_name} speaks the network contract of motion-wire"
        );
    }
}

#[test]
fn no_crate_reaches_itself_through_others() {
    let arrows = workspace_arrows();
    let loops: Vec<String> = arrows
        .keys()
        .filter_map(|name| path(&arrows, name, name).map(|chain| chain.join(" → ")))
        .collect();
    assert!(loops.is_empty(), "dependency loops: {loops:#?}");
}

#[test]
fn a_chain_is_found_and_shown_in_order() {
    let arrows: BTreeMap<String, BTreeSet<String>> = [
        ("a", vec!["b"]),
        ("b", vec!["c"]),
        ("c", vec!["a"]),
        ("d", vec![]),
    ]
    .into_iter()
    .map(|(name, to)| (name.to_owned(), to.into_iter().map(str::to_owned).collect()))
    .collect();
    assert_eq!(
        path(&arrows, "a", "c"),
        Some(vec!["a".to_owned(), "b".to_owned(), "c".to_owned()])
    );
    assert_eq!(
        path(&arrows, "a", "a").map(|chain| chain.join(" → ")),
        Some("a → b → c → a".to_owned())
    );
    assert_eq!(path(&arrows, "d", "a"), None);
    assert_eq!(path(&arrows, "a", "d"), None);
}
