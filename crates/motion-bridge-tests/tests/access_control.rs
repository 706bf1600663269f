//! zenoh's own authentication and access control in front of the bridge's allow-list:
//! users and passwords say who a remote is, and the access-control rules let each user
//! send commands only under its own identity — so the identity the bridge's allow-list
//! reads from the command key is proven, not claimed. (The config files are the ones the
//! README shows.)

use core::time::Duration;
use std::path::Path;

use iceoryx2::prelude::ipc;
use motion_bridge_tests::{BridgeThread, DEADLINE, Result, fake, scratch};
use motion_client::ipc::CommandKind;
use motion_client::{Client, ClientBuilder, ClientError, ConnectError};

/// The bridge's allow-list: both identities may move; zenoh decides who may use which.
const RULES: &str = r#"
[[remote]]
identity = "panel"
allow = ["all"]

[[remote]]
identity = "visitor"
allow = ["all"]
"#;

/// The bridge's zenoh config: users from `credentials.txt`, and rules that let each user
/// read everything and command only as itself.
fn bridge_zenoh_config(server: &str, dir: &Path) -> String {
    let credentials = dir.join("credentials.txt");
    format!(
        r#"{{
  transport: {{
    auth: {{
      usrpwd: {{ user: "bridge", password: "bridge-secret", dictionary_file: "{credentials}" }},
    }},
  }},
  access_control: {{
    enabled: true,
    default_permission: "deny",
    rules: [
      {{
        id: "read",
        permission: "allow",
        flows: ["ingress", "egress"],
        messages: ["put", "declare_subscriber", "query", "reply", "declare_queryable",
                   "liveliness_token", "declare_liveliness_subscriber", "liveliness_query"],
        key_exprs: ["motiond/{server}/frame", "motiond/{server}/info", "motiond/{server}/stats",
                    "motiond/{server}/params", "motiond/{server}/state/json",
                    "motiond/{server}/bridge"],
      }},
      {{
        id: "as-panel",
        permission: "allow",
        flows: ["ingress", "egress"],
        messages: ["query", "reply", "liveliness_token"],
        key_exprs: ["motiond/{server}/command/panel", "motiond/{server}/session/panel",
                    "motiond/{server}/remote/panel/*"],
      }},
      {{
        id: "as-visitor",
        permission: "allow",
        flows: ["ingress", "egress"],
        messages: ["query", "reply", "liveliness_token"],
        key_exprs: ["motiond/{server}/command/visitor", "motiond/{server}/session/visitor",
                    "motiond/{server}/remote/visitor/*"],
      }},
    ],
    subjects: [
      {{ id: "panel", usernames: ["panel"] }},
      {{ id: "visitor", usernames: ["visitor"] }},
    ],
    policies: [
      {{ rules: ["read", "as-panel"], subjects: ["panel"] }},
      {{ rules: ["read", "as-visitor"], subjects: ["visitor"] }},
    ],
  }},
}}"#,
        credentials = credentials.display()
    )
}

/// A remote client's zenoh config: its user and password.
fn client_zenoh_config(dir: &Path, user: &str, password: &str) -> Result<std::path::PathBuf> {
    let path = dir.join(format!("{user}-{password}.json5"));
    std::fs::write(
        &path,
        format!(
            "{{ transport: {{ auth: {{ usrpwd: {{ user: \"{user}\", password: \"{password}\" }} }} }} }}"
        ),
    )?;
    Ok(path)
}

fn connect(
    server: &str,
    endpoint: &str,
    identity: &str,
    config: Option<&Path>,
) -> core::result::Result<Client<ipc::Service>, ConnectError> {
    connect_within(server, endpoint, identity, config, Duration::from_secs(5))
}

fn connect_within(
    server: &str,
    endpoint: &str,
    identity: &str,
    config: Option<&Path>,
    within: Duration,
) -> core::result::Result<Client<ipc::Service>, ConnectError> {
    let mut builder = ClientBuilder::new(server)
        .connect_timeout(within)
        .reply_timeout(Duration::from_secs(2))
        .remote(endpoint)
        .identity(identity);
    if let Some(config) = config {
        builder = builder.zenoh_config(config);
    }
    builder.connect::<ipc::Service>()
}

fn moves(server: &motion_client::testing::FakeServer) -> usize {
    server
        .requests()
        .iter()
        .filter(|r| r.kind == CommandKind::RampPosition as u32)
        .count()
}

#[test]
fn only_the_authenticated_user_commands_under_its_identity() -> Result {
    let server = fake("bridge-acl")?;
    let dir = scratch("bridge-acl")?;
    std::fs::write(
        dir.join("credentials.txt"),
        "panel:panel-secret\nvisitor:visitor-secret\n",
    )?;
    let zenoh = dir.join("bridge-zenoh.json5");
    std::fs::write(&zenoh, bridge_zenoh_config(server.name(), &dir))?;
    let bridge = BridgeThread::start_with(server.name(), RULES, Some(zenoh))?;
    let endpoint = bridge.endpoint.as_str();

    // The panel user, as `panel`: reads and commands.
    let panel_login = client_zenoh_config(&dir, "panel", "panel-secret")?;
    let panel = connect(server.name(), endpoint, "panel", Some(&panel_login))?;
    panel.wait_ready(DEADLINE)?;
    panel.axis("x")?.ramp_to(4.0, 0.0, 0.0)?;
    assert_eq!(moves(&server), 1);

    // The visitor user claiming to be `panel`: it may read, but its command under
    // `panel`'s key is dropped by zenoh before the bridge sees it.
    let visitor_login = client_zenoh_config(&dir, "visitor", "visitor-secret")?;
    let impostor = connect(server.name(), endpoint, "panel", Some(&visitor_login))?;
    assert_eq!(impostor.info()?.axes().len(), 3);
    match impostor.axis("x")?.ramp_to(8.0, 0.0, 0.0) {
        Err(error @ (ClientError::Network { .. } | ClientError::NoReply { .. })) => {
            eprintln!("impostor: {error}");
        }
        other => return Err(format!("the impostor's move went through: {other:?}").into()),
    }
    assert_eq!(
        moves(&server),
        1,
        "the server never saw the impostor's move"
    );

    // As itself, the visitor commands (the bridge's allow-list lets `visitor` move).
    let visitor = connect(server.name(), endpoint, "visitor", Some(&visitor_login))?;
    visitor.axis("y")?.ramp_to(2.0, 0.0, 0.0)?;
    assert_eq!(moves(&server), 2);

    // Without credentials, or with a wrong password, there is no session at all.
    for login in [None, Some(client_zenoh_config(&dir, "panel", "guess")?)] {
        let within = Duration::from_millis(500);
        match connect_within(server.name(), endpoint, "panel", login.as_deref(), within) {
            Err(ConnectError::NoBridge { why, .. }) => eprintln!("refused: {why}"),
            Err(other) => return Err(format!("unexpected error: {other}").into()),
            Ok(_) => return Err(format!("connected with {login:?}").into()),
        }
    }
    drop(bridge);
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
