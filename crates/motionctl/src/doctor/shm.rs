//! iceoryx2's shared memory (`/dev/shm`) and state directory (`/tmp/iceoryx2`), and
//! systemd-logind's `RemoveIPC`, which deletes a logged-out user's shared memory.

use std::path::Path;

use super::check::{Check, Context, Status};
use super::host::format_bytes;

/// Below this much free space in `/dev/shm` the server's services may not fit (the
/// simulated robot's take about 35 MiB with the default 32 clients).
pub const SHM_FAIL_BELOW: u64 = 64 << 20;
/// Below this, a few clients more or `max_clients` raised may not fit.
pub const SHM_WARN_BELOW: u64 = 256 << 20;

const SHM: &str = "iceoryx2-shm";
const SHM_T: &str = "iceoryx2 shared memory (/dev/shm) and state (/tmp/iceoryx2)";

/// `/dev/shm` exists, this user can create segments there, and enough is free;
/// `/tmp/iceoryx2` (iceoryx2 0.10's node and service records) is this user's or can be
/// created. Records of other users there warn: their programs and ours cannot see each
/// other's services.
pub fn iceoryx2(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let id = match &cx.identity {
        Ok(id) => id,
        Err(e) => {
            return Check::warn(
                SHM,
                SHM_T,
                format!("unknown user: {e}"),
                "run the doctor on the machine itself, with /proc mounted",
            );
        }
    };
    let user = host.user_name(id.uid);
    let mut status = Status::Pass;
    let mut values = Vec::new();
    let mut fixes: Vec<String> = Vec::new();
    match host.owner(Path::new("/dev/shm")) {
        None => {
            status = Status::Fail;
            values.push("/dev/shm is missing".to_owned());
            fixes.push("mount a tmpfs on /dev/shm (`mount -t tmpfs -o mode=1777 tmpfs /dev/shm`, or the fstab entry)".to_owned());
        }
        Some(owner) => {
            let free = host.probe.free_bytes(&host.path("/dev/shm"));
            let described = owner.describe(host);
            if !id.can_create_in(owner.mode, owner.uid, owner.gid) {
                status = Status::Fail;
                values.push(format!(
                    "/dev/shm is {described}: {user} cannot create segments"
                ));
                fixes.push("sudo chmod 1777 /dev/shm".to_owned());
            } else {
                match free {
                    Err(e) => {
                        status = status.max(Status::Warn);
                        values.push(format!("/dev/shm {described}, free space unknown ({e})"));
                    }
                    Ok(bytes) => {
                        let verdict = if bytes < SHM_FAIL_BELOW {
                            Status::Fail
                        } else if bytes < SHM_WARN_BELOW {
                            Status::Warn
                        } else {
                            Status::Pass
                        };
                        status = status.max(verdict);
                        values.push(format!(
                            "/dev/shm {described}, {} free",
                            format_bytes(bytes)
                        ));
                        if verdict != Status::Pass {
                            fixes.push(format!(
                                "give /dev/shm at least {} (`sudo mount -o remount,size=512M /dev/shm`, \
                                 and the size= option in /etc/fstab), or remove leftovers of dead \
                                 programs (`ls -l /dev/shm/iox2_*`)",
                                format_bytes(SHM_WARN_BELOW)
                            ));
                        }
                    }
                }
            }
        }
    }
    let state = Path::new("/tmp/iceoryx2");
    match host.owner(state) {
        None => match host.owner(Path::new("/tmp")) {
            Some(tmp) if id.can_create_in(tmp.mode, tmp.uid, tmp.gid) => {
                values.push("/tmp/iceoryx2 not created yet (/tmp is writable)".to_owned());
            }
            _ => {
                status = Status::Fail;
                values.push(format!(
                    "/tmp/iceoryx2 is missing and {user} cannot create it in /tmp"
                ));
                fixes.push("sudo chmod 1777 /tmp, or install deploy/tmpfiles.d/motiond.conf (`sudo systemd-tmpfiles --create`)".to_owned());
            }
        },
        Some(owner) => {
            let described = owner.describe(host);
            let blocked: Vec<String> = ["", "nodes", "services"]
                .iter()
                .map(|sub| state.join(sub))
                .filter(|dir| {
                    host.owner(dir)
                        .is_some_and(|o| !id.can_create_in(o.mode, o.uid, o.gid))
                })
                .map(|dir| dir.display().to_string())
                .collect();
            if !blocked.is_empty() {
                status = Status::Fail;
                values.push(format!(
                    "/tmp/iceoryx2 is {described}: {user} cannot create its records in {}",
                    blocked.join(", ")
                ));
                fixes.push(format!(
                    "stop every iceoryx2 program, `sudo rm -rf /tmp/iceoryx2`, and run the server and \
                     its clients as {user} only (deploy/tmpfiles.d/motiond.conf creates it for the \
                     `motion` user at boot)"
                ));
            } else {
                let foreign = foreign_owners(cx, id.uid);
                if foreign.is_empty() {
                    values.push(format!("/tmp/iceoryx2 {described}"));
                } else {
                    status = status.max(Status::Warn);
                    values.push(format!(
                        "/tmp/iceoryx2 {described} holds records of other users ({}): programs of \
                         different users cannot open each other's services (mode 0600)",
                        foreign.join(", ")
                    ));
                    fixes.push(
                        "run motiond and every client as one user (`sudo -u motion motionctl …`); \
                         records of stopped programs of other users go with `sudo rm -rf \
                         /tmp/iceoryx2` while no iceoryx2 program runs"
                            .to_owned(),
                    );
                }
            }
        }
    }
    Check::with(SHM, SHM_T, status, values.join("; "), fixes.join("; "))
}

/// Users other than `uid` owning node records (`/tmp/iceoryx2/nodes/*`) or segments
/// (`/dev/shm/iox2_*`).
fn foreign_owners(cx: &Context<'_>, uid: u32) -> Vec<String> {
    use std::os::unix::fs::MetadataExt as _;
    let mut owners = std::collections::BTreeSet::new();
    for (dir, prefix) in [("/tmp/iceoryx2/nodes", ""), ("/dev/shm", "iox2_")] {
        let Ok(entries) = std::fs::read_dir(cx.host.path(dir)) else {
            continue;
        };
        for entry in entries.flatten() {
            if !entry.file_name().to_string_lossy().starts_with(prefix) {
                continue;
            }
            if let Ok(meta) = entry.metadata()
                && meta.uid() != uid
            {
                owners.insert(meta.uid());
            }
        }
    }
    owners.into_iter().map(|u| cx.host.user_name(u)).collect()
}

const LOGIND: &str = "logind-removeipc";
const LOGIND_T: &str = "systemd-logind RemoveIPC";

/// `RemoveIPC=yes` (logind's default) deletes a user's shared memory when their last
/// session ends — under a running server, if it runs as a regular (login) user. Root and
/// system users are exempt (logind.conf(5)); systemd fixes that boundary when it is built,
/// from the build machine's /etc/login.defs, so this machine's `SYS_UID_MAX` (999 when
/// absent) is the best guess at run time.
pub fn remove_ipc(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let logind = [
        "/usr/lib/systemd/systemd-logind",
        "/lib/systemd/systemd-logind",
    ]
    .iter()
    .any(|p| host.path(p).exists());
    if !logind {
        return Check::pass(
            LOGIND,
            LOGIND_T,
            "systemd-logind is not installed: nothing removes IPC at logout",
        );
    }
    let remove_ipc = remove_ipc_setting(cx);
    let setting = format!("RemoveIPC={}", if remove_ipc { "yes" } else { "no" });
    let id = match &cx.identity {
        Ok(id) => id,
        Err(e) => {
            return Check::warn(
                LOGIND,
                LOGIND_T,
                format!("{setting}; unknown user: {e}"),
                "run the doctor as the server's user",
            );
        }
    };
    let sys_uid_max = host
        .read("/etc/login.defs")
        .and_then(|text| {
            text.lines().find_map(|line| {
                let mut words = line.split_whitespace();
                (words.next() == Some("SYS_UID_MAX")).then(|| words.next()?.parse::<u32>().ok())?
            })
        })
        .unwrap_or(999);
    let user = host.user_name(id.uid);
    if id.uid == 0 {
        return Check::pass(LOGIND, LOGIND_T, format!("{setting}; root is exempt"));
    }
    if id.uid <= sys_uid_max {
        return Check::pass(
            LOGIND,
            LOGIND_T,
            format!(
                "{setting}; {user} (uid {}) is a system user (≤ SYS_UID_MAX {sys_uid_max}): exempt",
                id.uid
            ),
        );
    }
    let fix = "run the server as a system user (`sudo useradd --system --no-create-home --shell \
               /usr/sbin/nologin motion`, deploy/README.md), or set RemoveIPC=no in \
               /etc/systemd/logind.conf.d/motiond.conf and `sudo systemctl restart systemd-logind`";
    if remove_ipc {
        Check::fail(
            LOGIND,
            LOGIND_T,
            format!(
                "{setting}; {user} (uid {}) is a regular user: logging out removes the server's shared memory under it",
                id.uid
            ),
            fix,
        )
    } else {
        Check::warn(
            LOGIND,
            LOGIND_T,
            format!(
                "{setting}; {user} (uid {}) is a regular user: safe only while RemoveIPC stays off",
                id.uid
            ),
            fix,
        )
    }
}

/// logind.conf, then its drop-ins in name order (a drop-in in /etc hides the same name in
/// /run and /usr/lib); the last `RemoveIPC=` of a `[Login]` section wins; default yes.
fn remove_ipc_setting(cx: &Context<'_>) -> bool {
    let host = &cx.host;
    let mut files = vec![host.path("/etc/systemd/logind.conf")];
    let mut dropins: std::collections::BTreeMap<String, std::path::PathBuf> = Default::default();
    for dir in [
        "/usr/lib/systemd/logind.conf.d",
        "/run/systemd/logind.conf.d",
        "/etc/systemd/logind.conf.d",
    ] {
        if let Ok(entries) = std::fs::read_dir(host.path(dir)) {
            for entry in entries.flatten() {
                let name = entry.file_name().to_string_lossy().into_owned();
                if name.ends_with(".conf") {
                    dropins.insert(name, entry.path());
                }
            }
        }
    }
    files.extend(dropins.into_values());
    let mut value = true;
    for file in files {
        let Some(text) = host.read_path(&file) else {
            continue;
        };
        let mut in_login = false;
        for line in text.lines().map(str::trim) {
            if line.starts_with('[') {
                in_login = line == "[Login]";
            } else if in_login && let Some(v) = line.strip_prefix("RemoveIPC=") {
                match v.trim().to_ascii_lowercase().as_str() {
                    "yes" | "true" | "on" | "1" => value = true,
                    "no" | "false" | "off" | "0" => value = false,
                    _ => {}
                }
            }
        }
    }
    value
}

#[cfg(test)]
mod tests {
    use super::super::fake::{FakeRoot, UID};
    use super::*;

    fn dirs(fake: &FakeRoot) {
        fake.dir("/dev/shm");
        fake.chmod("/dev/shm", 0o1777);
        fake.dir("/tmp");
        fake.chmod("/tmp", 0o1777);
        fake.file(
            "/etc/passwd",
            &format!("motion:x:{UID}:{UID}::/:/usr/sbin/nologin\n"),
        );
    }

    #[test]
    fn iceoryx2_pass_warn_fail() {
        let fake = FakeRoot::new();
        dirs(&fake);
        let check = fake.check(iceoryx2);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("1024 MiB free"), "{check:?}");
        assert!(check.value.contains("not created yet"), "{check:?}");
        *fake.probe.free.borrow_mut() = 100 << 20;
        assert_eq!(fake.check(iceoryx2).status, Status::Warn);
        *fake.probe.free.borrow_mut() = 10 << 20;
        let check = fake.check(iceoryx2);
        assert_eq!(check.status, Status::Fail);
        assert!(check.fix.contains("remount,size="), "{check:?}");
        *fake.probe.free.borrow_mut() = 1 << 30;
        // Another user (the test runner) created /tmp/iceoryx2 with iceoryx2's 0750.
        fake.dir("/tmp/iceoryx2/nodes");
        fake.chmod("/tmp/iceoryx2", 0o750);
        let check = fake.check(iceoryx2);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(
            check
                .value
                .contains("cannot create its records in /tmp/iceoryx2"),
            "{check:?}"
        );
        assert!(check.fix.contains("rm -rf /tmp/iceoryx2"));
        // Writable, but with another user's records in it.
        fake.chmod("/tmp/iceoryx2", 0o777);
        fake.chmod("/tmp/iceoryx2/nodes", 0o777);
        fake.dir("/tmp/iceoryx2/nodes/iox2_1234");
        let check = fake.check(iceoryx2);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(check.value.contains("records of other users"), "{check:?}");
        // /dev/shm not writable.
        fake.chmod("/dev/shm", 0o755);
        assert_eq!(fake.check(iceoryx2).status, Status::Fail);
        fake.remove("/dev/shm");
        let check = fake.check(iceoryx2);
        assert_eq!(check.status, Status::Fail);
        assert!(check.value.contains("/dev/shm is missing"));
    }

    #[test]
    fn remove_ipc_pass_warn_fail() {
        let fake = FakeRoot::new();
        assert_eq!(fake.check(remove_ipc).status, Status::Pass, "no logind");
        fake.file("/usr/lib/systemd/systemd-logind", "");
        fake.file("/etc/login.defs", "SYS_UID_MIN 101\nSYS_UID_MAX 999\n");
        // uid 4242 is a regular user; RemoveIPC defaults to yes.
        let check = fake.check(remove_ipc);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.value.contains("RemoveIPC=yes"), "{check:?}");
        assert!(check.fix.contains("useradd --system"));
        fake.file(
            "/etc/systemd/logind.conf",
            "[Login]\n#RemoveIPC=yes\nRemoveIPC=no\n",
        );
        assert_eq!(fake.check(remove_ipc).status, Status::Warn);
        // A drop-in wins over the main file.
        fake.file(
            "/etc/systemd/logind.conf.d/10-ipc.conf",
            "[Login]\nRemoveIPC=yes\n",
        );
        assert_eq!(fake.check(remove_ipc).status, Status::Fail);
        // A key outside [Login] does not count.
        fake.file(
            "/etc/systemd/logind.conf.d/10-ipc.conf",
            "[Other]\nRemoveIPC=yes\n",
        );
        assert_eq!(fake.check(remove_ipc).status, Status::Warn);
        // A system user is exempt.
        fake.identity(998, &[], 0);
        let check = fake.check(remove_ipc);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("system user"));
    }
}
