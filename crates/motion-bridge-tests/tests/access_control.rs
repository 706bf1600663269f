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
use zenoh::Wait as _;

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
/// read (subscribe and query: never put, never answer queries) and command only as itself;
/// `reader` may only read.
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
        flows: ["ingress"],
        messages: ["declare_subscriber", "query", "declare_liveliness_subscriber",
                   "liveliness_query"],
        key_exprs: ["motiond/{server}/frame", "motiond/{server}/info", "motiond/{server}/stats",
                    "motiond/{server}/params", "motiond/{server}/state/json",
                    "motiond/{server}/bridge"],
      }},
      {{
        id: "read-delivered",
        permission: "allow",
        flows: ["egress"],
        messages: ["put", "reply", "liveliness_token"],
        key_exprs: ["motiond/{server}/frame", "motiond/{server}/info", "motiond/{server}/stats",
                    "motiond/{server}/params", "motiond/{server}/state/json",
                    "motiond/{server}/bridge"],
      }},
      {{
        id: "as-panel",
        permission: "allow",
        flows: ["ingress"],
        messages: ["query", "liveliness_token"],
        key_exprs: ["motiond/{server}/command/panel", "motiond/{server}/session/panel",
                    "motiond/{server}/remote/panel/*"],
      }},
      {{
        id: "as-visitor",
        permission: "allow",
        flows: ["ingress"],
        messages: ["query", "liveliness_token"],
        key_exprs: ["motiond/{server}/command/visitor", "motiond/{server}/session/visitor",
                    "motiond/{server}/remote/visitor/*"],
      }},
      {{
        id: "answers",
        permission: "allow",
        flows: ["egress"],
        messages: ["reply"],
        key_exprs: ["motiond/{server}/command/*", "motiond/{server}/session/*"],
      }},
    ],
    subjects: [
      {{ id: "panel", usernames: ["panel"] }},
      {{ id: "visitor", usernames: ["visitor"] }},
      {{ id: "reader", usernames: ["reader"] }},
    ],
    policies: [
      {{ rules: ["read", "read-delivered", "as-panel", "answers"], subjects: ["panel"] }},
      {{ rules: ["read", "read-delivered", "as-visitor", "answers"], subjects: ["visitor"] }},
      {{ rules: ["read", "read-delivered"], subjects: ["reader"] }},
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

/// A raw zenoh session logged in as `user` (a foreign peer), connected to `endpoint`.
fn raw_session(dir: &Path, endpoint: &str, user: &str, password: &str) -> Result<zenoh::Session> {
    let login = client_zenoh_config(dir, user, password)?;
    let mut config = zenoh::Config::from_file(&login).map_err(|error| error.to_string())?;
    for (key, value) in [
        ("mode", "\"client\"".to_owned()),
        ("scouting/multicast/enabled", "false".to_owned()),
        ("connect/endpoints", format!("[\"{endpoint}\"]")),
    ] {
        config
            .insert_json5(key, &value)
            .map_err(|error| error.to_string())?;
    }
    Ok(zenoh::open(config)
        .wait()
        .map_err(|error| error.to_string())?)
}

/// The README's access control for a user who may only read: it subscribes and queries,
/// but a frame it puts on the frame key, or an answer it offers on the description's key,
/// never reaches another remote (zenoh's access control drops them at the bridge).
#[test]
fn a_reader_may_subscribe_and_query_but_not_put_or_answer() -> Result {
    let server = fake("bridge-acl-reader")?;
    let dir = scratch("bridge-acl-reader")?;
    std::fs::write(
        dir.join("credentials.txt"),
        "panel:panel-secret\nvisitor:visitor-secret\nreader:reader-secret\n",
    )?;
    let zenoh = dir.join("bridge-zenoh.json5");
    std::fs::write(&zenoh, bridge_zenoh_config(server.name(), &dir))?;
    let bridge = BridgeThread::start_with(server.name(), RULES, Some(zenoh))?;
    let endpoint = bridge.endpoint.as_str();
    let keys = motion_wire::keys::Keys::new(server.name())?;

    // The panel, reading frames as a foreign peer would.
    let panel = raw_session(&dir, endpoint, "panel", "panel-secret")?;
    let frames = panel
        .declare_subscriber(keys.frame())
        .with(zenoh::handlers::FifoChannel::new(4096))
        .wait()
        .map_err(|error| error.to_string())?;

    // The reader reads: the description through the bridge.
    let reader = raw_session(&dir, endpoint, "reader", "reader-secret")?;
    motion_bridge_tests::raw::wait_for_server(&reader, &keys)?;
    // ... and tries to write: a forged frame on the frame key, an answer on the
    // description's key.
    let forged = b"forged: estop latched".to_vec();
    let forged_reply = forged.clone();
    let info_key = keys.info();
    let _queryable = reader
        .declare_queryable(&info_key)
        .callback(move |query| {
            let _ = query
                .reply(query.key_expr().clone(), forged_reply.clone())
                .wait();
        })
        .wait()
        .map_err(|error| error.to_string())?;
    for _ in 0..20 {
        reader
            .put(keys.frame(), forged.clone())
            .wait()
            .map_err(|error| error.to_string())?;
        std::thread::sleep(Duration::from_millis(25));
    }
    std::thread::sleep(Duration::from_millis(300));
    let mut real = 0;
    let mut fakes = 0;
    while let Ok(Some(sample)) = frames.try_recv() {
        if sample.payload().to_bytes() == forged.as_slice() {
            fakes += 1;
        } else {
            real += 1;
        }
    }
    let replies = panel
        .get(&info_key)
        .timeout(Duration::from_secs(2))
        .wait()
        .map_err(|error| error.to_string())?;
    let mut answers = Vec::new();
    while let Ok(reply) = replies.recv() {
        if let Ok(sample) = reply.result() {
            answers.push(sample.payload().to_bytes().into_owned());
        }
    }
    eprintln!(
        "the panel got {real} frames of the bridge and {fakes} of the reader's 20 puts; {} \
         answers on the description's key, {} of them the reader's",
        answers.len(),
        answers.iter().filter(|answer| **answer == forged).count()
    );
    assert!(real > 0, "the panel reads the bridge's frames");
    assert_eq!(fakes, 0, "a reader's put reached another remote");
    assert!(!answers.is_empty(), "the bridge answers the description");
    assert!(
        answers.iter().all(|answer| *answer != forged),
        "a reader's queryable answered another remote"
    );
    drop(bridge);
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
