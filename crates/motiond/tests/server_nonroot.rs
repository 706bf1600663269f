//! motiond as a non-root user (issue 14), the way deploy/motiond.service runs it: without
//! privileges its real-time set-up is refused and the log says what and why (and
//! `--require-rt` refuses to run); with the unit's ambient capabilities (CAP_SYS_NICE,
//! CAP_IPC_LOCK, nothing else) or its limits (LimitRTPRIO, LimitMEMLOCK) it gets SCHED_FIFO
//! and locked memory. Run as root, the test creates a throwaway system user (`useradd`; else
//! `nobody`) and drops to it with util-linux's `setpriv`, limits set with `prlimit`; run as
//! another user, it runs motiond as that user and checks the log explains what it got.
//!
//! iceoryx2 keeps node and service records under its root path (`/tmp/iceoryx2`, created
//! 0750 by whoever came first): each motiond here gets a root path of its own through a
//! project-local `config/iceoryx2.toml` in its working directory.

mod deploy_support;

use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use deploy_support::{FakeManager, Motiond, Scratch, config_text};
use nix::sys::signal::Signal;

/// A system user made for this test and removed after it (or `nobody` when `useradd` is
/// missing).
struct TestUser {
    name: Option<String>,
    uid: u32,
    gid: u32,
}

impl TestUser {
    fn create() -> Self {
        let name = format!("motiond-t{}", std::process::id());
        let made = Command::new("useradd")
            .args([
                "--system",
                "--no-create-home",
                "--shell",
                "/usr/sbin/nologin",
                "--user-group",
                &name,
            ])
            .status()
            .is_ok_and(|s| s.success());
        if made && let Some((uid, gid)) = ids_of(&name) {
            return Self {
                name: Some(name),
                uid,
                gid,
            };
        }
        eprintln!("useradd failed: running motiond as nobody");
        Self {
            name: None,
            uid: 65_534,
            gid: 65_534,
        }
    }
}

impl Drop for TestUser {
    fn drop(&mut self) {
        if let Some(name) = &self.name {
            let _ = Command::new("userdel").arg(name).status();
        }
    }
}

/// uid and gid from /etc/passwd.
fn ids_of(name: &str) -> Option<(u32, u32)> {
    let passwd = std::fs::read_to_string("/etc/passwd").ok()?;
    passwd.lines().find_map(|line| {
        let fields: Vec<&str> = line.split(':').collect();
        (fields.first() == Some(&name))
            .then(|| Some((fields.get(2)?.parse().ok()?, fields.get(3)?.parse().ok()?)))?
    })
}

/// A working directory for one motiond run as `owner`: the config, a copy of the binary
/// (the build directory may not be readable by others), and iceoryx2's root path.
struct Stage {
    scratch: Scratch,
    config: PathBuf,
    motiond: PathBuf,
    name: String,
}

impl Stage {
    fn new(tag: &str, owner: Option<(u32, u32)>) -> Self {
        let scratch = Scratch::new(tag);
        let name = format!("t{}-{tag}", std::process::id());
        let config = scratch.file(
            "motiond.toml",
            &config_text(&name, "rt_priority = 50\nlock_memory = true\n"),
        );
        let iox = scratch.dir.join("iceoryx2");
        std::fs::create_dir_all(&iox).expect("iceoryx2 root");
        if let Some((uid, gid)) = owner {
            nix::unistd::chown(&iox, Some(uid.into()), Some(gid.into())).expect("chown");
        }
        scratch.file(
            "config/iceoryx2.toml",
            &format!("[global]\nroot-path = \"{}/\"\n", iox.display()),
        );
        let motiond = scratch.dir.join("motiond");
        std::fs::copy(env!("CARGO_BIN_EXE_motiond"), &motiond).expect("copy motiond");
        std::fs::set_permissions(&motiond, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        Self {
            scratch,
            config,
            motiond,
            name,
        }
    }

    fn dir(&self) -> &Path {
        &self.scratch.dir
    }
}

/// `prlimit LIMITS -- setpriv --reuid U --regid G --clear-groups [CAPS] -- motiond …`.
fn as_user(stage: &Stage, user: &TestUser, limits: &[&str], caps: bool, extra: &[&str]) -> Command {
    let mut command = Command::new("prlimit");
    command.args(limits).arg("--").arg("setpriv");
    command.arg(format!("--reuid={}", user.uid));
    command.arg(format!("--regid={}", user.gid));
    command.arg("--clear-groups");
    if caps {
        // AmbientCapabilities=CAP_SYS_NICE CAP_IPC_LOCK, as deploy/motiond.service.
        command.args([
            "--inh-caps=+sys_nice,+ipc_lock",
            "--ambient-caps=+sys_nice,+ipc_lock",
        ]);
    }
    command
        .arg("--")
        .arg(&stage.motiond)
        .arg("--config")
        .arg(&stage.config)
        .args(extra)
        .current_dir(stage.dir());
    command
}

/// Runs to READY (every device online) under a fake notify socket, checks the process's
/// identity, stops it with SIGTERM; returns its log.
fn run_until_ready(
    stage: &Stage,
    mut command: Command,
    expect_uid: u32,
    expect_caps: Option<u64>,
) -> String {
    let mut manager = FakeManager::new(stage.dir());
    command.env("NOTIFY_SOCKET", &manager.path);
    let mut server = Motiond::spawn_command(command).expect("start motiond");
    let ready = manager.wait_for(Duration::from_secs(30), |m| m.contains("READY=1"));
    let log = server.log_text();
    assert!(
        ready.is_some(),
        "instance {}: no READY=1 ({:?}); log:\n{log}",
        stage.name,
        manager.messages
    );
    let status =
        std::fs::read_to_string(format!("/proc/{}/status", server.child.id())).expect("status");
    let field = |name: &str| {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .map(|v| v.split_whitespace().map(str::to_owned).collect::<Vec<_>>())
            .unwrap_or_default()
    };
    assert_eq!(
        field("Uid:").get(1),
        Some(&expect_uid.to_string()),
        "{status}"
    );
    if let Some(caps) = expect_caps {
        assert_eq!(
            field("CapEff:").first(),
            Some(&format!("{caps:016x}")),
            "{status}"
        );
    }
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    server.log_text()
}

const CAPS: u64 = (1 << 23) | (1 << 14); // CAP_SYS_NICE, CAP_IPC_LOCK

#[test]
fn a_non_root_server_gets_real_time_with_the_unit_s_capabilities_or_limits_and_says_why_not_without()
 {
    if !nix::unistd::Uid::effective().is_root() {
        return as_this_user();
    }
    for tool in ["prlimit", "setpriv"] {
        assert!(
            Command::new(tool).arg("--version").output().is_ok(),
            "{tool} (util-linux) is needed to drop to another user with given limits"
        );
    }
    let user = TestUser::create();
    let owner = Some((user.uid, user.gid));

    // No privileges: refused, and the log says which and why; the server still serves.
    let stage = Stage::new("bare", owner);
    let bare = ["--rtprio=0", "--memlock=65536"];
    let log = run_until_ready(
        &stage,
        as_user(&stage, &user, &bare, false, &[]),
        user.uid,
        Some(0),
    );
    for needed in [
        "real-time: SCHED_FIFO priority 50: Operation not permitted",
        "(needs CAP_SYS_NICE or `ulimit -r 50`); continuing without it",
        "(raise RLIMIT_MEMLOCK",
        "real-time: SCHED_FIFO off",
        "memory not locked",
        "device `pumps` online",
    ] {
        assert!(log.contains(needed), "`{needed}` not in:\n{log}");
    }
    drop(stage);

    // The same with --require-rt: it refuses to run, saying why.
    let stage = Stage::new("require", owner);
    let mut server =
        Motiond::spawn_command(as_user(&stage, &user, &bare, false, &["--require-rt"]))
            .expect("start motiond");
    assert_eq!(server.wait(Duration::from_secs(20)), Some(1));
    let log = server.log_text();
    assert!(
        log.contains("--require-rt: real-time set-up incomplete"),
        "{log}"
    );
    assert!(log.contains("Operation not permitted"), "{log}");
    drop(stage);

    // The unit's ambient capabilities, limits still at nothing: SCHED_FIFO and locked memory.
    let stage = Stage::new("caps", owner);
    let log = run_until_ready(
        &stage,
        as_user(&stage, &user, &bare, true, &[]),
        user.uid,
        Some(CAPS),
    );
    assert!(log.contains("real-time: SCHED_FIFO prio 50"), "{log}");
    assert!(log.contains("memory locked"), "{log}");
    assert!(!log.contains("SCHED_FIFO priority 50:"), "{log}");
    assert!(!log.contains("mlockall"), "{log}");
    drop(stage);

    // The unit's limits (LimitRTPRIO=50, LimitMEMLOCK=infinity) without capabilities. Raising
    // a hard limit needs CAP_SYS_RESOURCE, which a container may withhold even from root.
    let limits = ["--rtprio=50", "--memlock=unlimited"];
    if Command::new("prlimit")
        .args(limits)
        .arg("true")
        .status()
        .is_ok_and(|s| s.success())
    {
        let stage = Stage::new("limits", owner);
        let log = run_until_ready(
            &stage,
            as_user(&stage, &user, &limits, false, &[]),
            user.uid,
            Some(0),
        );
        assert!(log.contains("real-time: SCHED_FIFO prio 50"), "{log}");
        assert!(log.contains("memory locked"), "{log}");
    } else {
        eprintln!(
            "limits case not run: this root may not raise RLIMIT_RTPRIO (no CAP_SYS_RESOURCE)"
        );
    }
}

/// Not root: motiond runs as this user; whatever it gets, the log says which and why.
fn as_this_user() {
    let stage = Stage::new("self", None);
    let mut command = Command::new(&stage.motiond);
    command
        .arg("--config")
        .arg(&stage.config)
        .current_dir(stage.dir());
    let uid = nix::unistd::Uid::effective().as_raw();
    let log = run_until_ready(&stage, command, uid, None);
    assert!(
        log.contains("real-time: SCHED_FIFO prio 50")
            || (log.contains("SCHED_FIFO priority 50: Operation not permitted")
                && log.contains("(needs CAP_SYS_NICE")),
        "{log}"
    );
    assert!(
        log.contains("memory locked") || log.contains("(raise RLIMIT_MEMLOCK"),
        "{log}"
    );
}
