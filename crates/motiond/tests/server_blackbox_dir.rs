//! The black box's directory under the attacks of issue 40, run as a user would: motiond
//! started on a simulated stepper, saves asked for with SIGUSR2.
//!
//! Before: `blackbox_keep` pruned every `*.mcap` of the directory by modification time, so
//! two servers sharing a directory deleted each other's saves, another user's files went
//! too, and 20 files dated 2030 made every save delete itself; a directory of another user
//! was written into; saves were 0644. Now a save removes only its own server's oldest saves
//! (by the time in their name, never the file just saved), is made 0640, and a directory
//! that is not the server's own stops the server at start with the reason.

mod support;

use core::time::Duration;
use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
use std::path::{Path, PathBuf};
use std::time::Instant;

use nix::sys::signal::Signal;
use support::*;

/// How many "black box saved (sigusr2)" lines the server logged so far.
fn saves(server: &mut Server) -> usize {
    server.drain_log();
    server
        .log
        .iter()
        .filter(|line| line.contains("black box saved (sigusr2)"))
        .count()
}

/// SIGUSR2, then waits for its save to be logged; the path saved.
fn save(server: &mut Server) -> PathBuf {
    let before = saves(server);
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(server.pid() as i32),
        Signal::SIGUSR2,
    )
    .expect("SIGUSR2");
    let end = Instant::now() + Duration::from_secs(10);
    while saves(server) == before {
        assert!(Instant::now() < end, "no save: {:#?}", server.log);
        std::thread::sleep(Duration::from_millis(20));
    }
    let line = server
        .log
        .iter()
        .rev()
        .find(|line| line.contains("black box saved (sigusr2)"))
        .expect("the line");
    let path = line
        .split("): ")
        .nth(1)
        .and_then(|rest| rest.split(" (").next())
        .expect("a path");
    // The next save's name is a later millisecond.
    std::thread::sleep(Duration::from_millis(5));
    PathBuf::from(path)
}

/// The names of `dir`'s files, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("listed")
        .filter_map(Result::ok)
        .filter_map(|entry| entry.file_name().into_string().ok())
        .collect();
    names.sort();
    names
}

/// The saves of server `name` among `names` (`<name>-<digits>-<word>.mcap`).
fn saves_of<'a>(names: &'a [String], name: &str) -> Vec<&'a String> {
    names
        .iter()
        .filter(|file| {
            file.strip_prefix(&format!("{name}-"))
                .and_then(|rest| rest.strip_suffix(".mcap"))
                .and_then(|rest| rest.split_once('-'))
                .is_some_and(|(millis, word)| {
                    millis.bytes().all(|b| b.is_ascii_digit()) && !word.contains('-')
                })
        })
        .collect()
}

fn start(name: &str, dir: &Path, keep: u32) -> Server {
    let config = stepper_config(
        name,
        &format!(
            "blackbox_seconds = 1\nblackbox_keep = {keep}\nblackbox_dir = \"{}\"",
            dir.display()
        ),
    );
    let server = Server::start(&config);
    let client = RawClient::connect(name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(15), axis0_online);
    assert!(online, "{:?}", frame.axes()[0]);
    server
}

fn stop(mut server: Server) {
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// Two servers (`<a>` and `<a>-1`, whose name starts with the other's) share a directory
/// with `blackbox_keep = 2`, beside another program's `.mcap` files and, as root, a file of
/// another user named as `<a>`'s oldest save: each keeps its own two newest saves, and
/// nothing else is removed.
#[test]
fn two_servers_sharing_a_directory_keep_their_own_saves() {
    let a = unique_name("bbshare");
    let b = format!("{a}-1");
    let dir = std::env::temp_dir().join(format!("{a}-dir"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("made");
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o750)).expect("chmod");
    let others = ["other-1-fault.mcap", "other-2-fault.mcap", "recording.mcap"];
    for file in others {
        std::fs::write(dir.join(file), "not ours").expect("written");
    }
    let root = nix::unistd::geteuid().is_root();
    let foreign = format!("{a}-1-fault.mcap");
    if root {
        std::fs::write(dir.join(&foreign), "another user's").expect("written");
        nix::unistd::chown(&dir.join(&foreign), Some(65_534.into()), None).expect("chown");
    }
    let mut server_a = start(&a, &dir, 2);
    let mut server_b = start(&b, &dir, 2);
    let mut kept_a = Vec::new();
    let mut kept_b = Vec::new();
    for _ in 0..3 {
        kept_a.push(save(&mut server_a));
        kept_b.push(save(&mut server_b));
    }
    let left = names(&dir);
    let name_of = |path: &PathBuf| path.file_name().and_then(|n| n.to_str()).map(str::to_owned);
    for kept in [&kept_a, &kept_b] {
        assert!(
            !left.contains(&name_of(&kept[0]).expect("name")),
            "{left:?}"
        );
        for path in &kept[1..] {
            assert!(
                left.contains(&name_of(path).expect("name")),
                "{path:?}: {left:?}"
            );
            let meta = std::fs::metadata(path).expect("saved");
            assert_eq!(meta.mode() & 0o7777, 0o640, "{}", path.display());
        }
    }
    for file in others {
        assert!(left.contains(&file.to_owned()), "{file}: {left:?}");
    }
    if root {
        assert!(
            left.contains(&foreign),
            "another user's file stays: {left:?}"
        );
    }
    assert_eq!(saves_of(&left, &b).len(), 2, "{left:?}");
    stop(server_a);
    stop(server_b);
    let _ = std::fs::remove_dir_all(&dir);
}

/// 20 saves whose names say 2030 (a clock that was wrong) and 20 whose modification time
/// says 2030: a save is never the file its own pruning removes; the ones named oldest go
/// first, whatever their modification time.
#[test]
fn files_dated_2030_do_not_make_a_save_remove_itself() {
    let name = unique_name("bb2030");
    let dir = std::env::temp_dir().join(format!("{name}-dir"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("made");
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o750)).expect("chmod");
    let y2030 = std::time::UNIX_EPOCH + Duration::from_secs(1_900_000_000);
    for n in 0..20u64 {
        // Named in 2030.
        std::fs::write(
            dir.join(format!("{name}-{}-fault.mcap", 1_900_000_000_000 + n)),
            "",
        )
        .expect("written");
        // Named in 2001, touched in 2030.
        let old = dir.join(format!("{name}-{}-fault.mcap", 1_000_000_000_000 + n));
        std::fs::write(&old, "").expect("written");
        std::fs::File::options()
            .write(true)
            .open(&old)
            .and_then(|file| file.set_modified(y2030))
            .expect("mtime 2030");
    }
    let mut server = start(&name, &dir, 20);
    // 41 saves of this server, 20 kept: the 20 named in 2001 and the oldest named in 2030
    // go; the save stays.
    let first = save(&mut server);
    let left = names(&dir);
    assert!(
        first.exists(),
        "{} removed itself: {left:?}",
        first.display()
    );
    assert_eq!(saves_of(&left, &name).len(), 20, "{left:?}");
    assert!(
        !left.iter().any(|file| file.contains("-1000000000")),
        "{left:?}"
    );
    let future = left
        .iter()
        .filter(|file| file.contains("-19000000000"))
        .count();
    assert_eq!(future, 19, "{left:?}");
    // The next: the first save is now the oldest name, and goes; this one stays.
    let second = save(&mut server);
    let left = names(&dir);
    assert!(
        second.exists(),
        "{} removed itself: {left:?}",
        second.display()
    );
    assert!(!first.exists(), "{left:?}");
    assert_eq!(saves_of(&left, &name).len(), 20, "{left:?}");
    stop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A black box directory of another user (here one chowned to uid 65534): the server does
/// not start, and says which directory, what it found and what to do.
#[test]
fn a_black_box_directory_of_another_user_is_refused_at_start() {
    if !nix::unistd::geteuid().is_root() {
        eprintln!("not root: a directory of another user cannot be made here");
        return;
    }
    let name = unique_name("bbother");
    let dir = std::env::temp_dir().join(format!("{name}-dir"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("made");
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    nix::unistd::chown(&dir, Some(65_534.into()), Some(65_534.into())).expect("chown");
    let config = stepper_config(&name, &format!("blackbox_dir = \"{}\"", dir.display()));
    let mut server = Server::start(&config);
    assert_eq!(server.wait(Duration::from_secs(10)), Some(1), "refused");
    let log = server.log_text();
    for needle in [
        format!(
            "[server] blackbox_dir {} is not the server's own",
            dir.display()
        ),
        "uid 65534, mode 755".to_owned(),
        "give `[server] blackbox_dir` a directory of uid 0's".to_owned(),
    ] {
        assert!(log.contains(&needle), "{needle:?} in {log}");
    }
    assert!(names(&dir).is_empty(), "nothing written there");
    let _ = std::fs::remove_dir_all(&dir);
}
