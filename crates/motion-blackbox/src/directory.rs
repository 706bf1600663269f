//! The black box's directory (`[server] blackbox_dir`): a directory of the server's own
//! (motion_config::private_dir, checked at start-up and at every save), the files this server saves
//! in it, and which of them a save removes (`blackbox_keep`).
//!
//! A save is `<server>-<ms since 1970>-<reason>.mcap`, created `O_CREAT | O_EXCL |
//! O_NOFOLLOW`, mode 0640. After it the server removes its own oldest saves beyond
//! `blackbox_keep`, and nothing else: only regular files of the server's user whose name is
//! exactly this server's name, a time and a reason (another server's name, even one that
//! starts with this one's, never matches: the time and the reason hold no `-`), ordered by
//! the time in their name (not their modification time, which anyone who can write a file
//! can set), and never the file just saved.

use std::fs::File;
use std::io;

use motion_config::private_dir::PrivateDir;

/// The config key naming the directory, for messages.
pub const KEY: &str = "[server] blackbox_dir";

/// The directory's mode when the server makes it: its group may read the saves.
pub const DIR_MODE: u32 = 0o750;

/// A save's mode: its group may read it (it holds every command and the config).
pub const FILE_MODE: u32 = 0o640;

/// The name of server `server`'s save at `millis` for `reason`.
pub fn file_name(server: &str, millis: u64, reason: &str) -> String {
    format!("{server}-{millis}-{reason}.mcap")
}

/// The time in the name of one of server `server`'s saves; `None` for any other name.
pub fn saved_at(server: &str, name: &str) -> Option<u64> {
    let stem = name.strip_suffix(".mcap")?;
    let (rest, reason) = stem.rsplit_once('-')?;
    let (owner, millis) = rest.rsplit_once('-')?;
    let word = !reason.is_empty()
        && reason
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit());
    let time = !millis.is_empty() && millis.bytes().all(|b| b.is_ascii_digit());
    (owner == server && word && time)
        .then(|| millis.parse().ok())
        .flatten()
}

/// Creates server `server`'s save for `reason` at `millis` (a later millisecond when that
/// name is taken): its name and the file, empty, mode 0640.
pub fn create(
    dir: &PrivateDir,
    server: &str,
    millis: u64,
    reason: &str,
) -> io::Result<(String, File)> {
    let mut last = None;
    for at in millis..millis + 100 {
        let name = file_name(server, at, reason);
        match dir.create_new(&name, FILE_MODE) {
            Ok(file) => return Ok((name, file)),
            Err(error) if error.kind() == io::ErrorKind::AlreadyExists => last = Some(error),
            Err(error) => return Err(error),
        }
    }
    Err(last.unwrap_or_else(|| io::Error::other("no free name")))
}

/// Removes server `server`'s oldest saves in `dir` beyond the newest `keep` (by the time
/// in their names), never `just_saved`; returns the names removed (a file removed meanwhile
/// by someone else is no error).
pub fn remove_oldest(dir: &PrivateDir, server: &str, keep: usize, just_saved: &str) -> Vec<String> {
    let Ok(files) = dir.own_files() else {
        return Vec::new();
    };
    let mut saves: Vec<(u64, String)> = files
        .into_iter()
        .filter_map(|(name, _)| Some((saved_at(server, &name)?, name)))
        .collect();
    let excess = saves.len().saturating_sub(keep);
    saves.retain(|(_, name)| name != just_saved);
    saves.sort();
    let mut removed = Vec::new();
    for (_, name) in saves.into_iter().take(excess) {
        if dir.remove(&name).is_ok() {
            removed.push(name);
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};
    use std::path::PathBuf;

    use super::*;

    /// A fresh black box directory of this user's.
    fn scratch(tag: &str) -> (PathBuf, PrivateDir) {
        let path = std::env::temp_dir().join(format!("motiond-bbdir-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        let dir = PrivateDir::open(&path, KEY, DIR_MODE).expect("made");
        (path, dir)
    }

    fn touch(path: &std::path::Path, name: &str) {
        std::fs::write(path.join(name), "x").expect("written");
    }

    fn names(path: &std::path::Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(path)
            .expect("listed")
            .filter_map(Result::ok)
            .filter_map(|e| e.file_name().into_string().ok())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn only_this_server_s_names_are_its_saves() {
        assert_eq!(
            saved_at("demo", "demo-1795784106767-fault.mcap"),
            Some(1_795_784_106_767)
        );
        assert_eq!(saved_at("demo", "demo-5-sigusr2.mcap"), Some(5));
        assert_eq!(saved_at("a-b", "a-b-17-exit.mcap"), Some(17));
        for other in [
            "demo-1-1795784106767-fault.mcap", // server `demo-1`
            "demox-1795784106767-fault.mcap",
            "other-1795784106767-fault.mcap",
            "demo-1795784106767-fault.mcap.tmp",
            "demo-1795784106767.mcap",
            "demo--fault.mcap",
            "demo-17a-fault.mcap",
            "demo-17-Fault.mcap",
            "demo-17-.mcap",
            "1795784106767-fault.mcap",
            "notes.txt",
        ] {
            assert_eq!(saved_at("demo", other), None, "{other}");
        }
        // Server `demo-1`'s own, not `demo`'s.
        assert_eq!(
            saved_at("demo-1", "demo-1-1795784106767-fault.mcap"),
            Some(1_795_784_106_767)
        );
    }

    /// Issue 40: `blackbox_keep` pruned every `*.mcap` by mtime, and two servers sharing
    /// the directory deleted each other's files. Now: this server's names only.
    #[test]
    fn a_save_removes_only_this_server_s_oldest_files() {
        let (path, dir) = scratch("two");
        for t in 1..=5 {
            touch(&path, &file_name("demo", t, "fault"));
            touch(&path, &file_name("demo-1", t, "fault"));
            touch(&path, &file_name("demox", t, "estop"));
        }
        touch(&path, "other.mcap");
        touch(&path, "notes.txt");
        let (name, _) = create(&dir, "demo", 6, "sigusr2").expect("saved");
        let removed = remove_oldest(&dir, "demo", 3, &name);
        assert_eq!(
            removed,
            [
                "demo-1-fault.mcap",
                "demo-2-fault.mcap",
                "demo-3-fault.mcap"
            ]
        );
        let left = names(&path);
        for t in 1..=5 {
            assert!(left.contains(&file_name("demo-1", t, "fault")), "{left:?}");
            assert!(left.contains(&file_name("demox", t, "estop")), "{left:?}");
        }
        assert!(left.contains(&"other.mcap".to_owned()));
        assert!(left.contains(&"notes.txt".to_owned()));
        assert!(left.contains(&name));
        let _ = std::fs::remove_dir_all(&path);
    }

    /// By the time in the name: files whose modification time says 2030 but whose names
    /// are old are the oldest; 20 files named in 2030 do not make the save remove itself
    /// (it removes the oldest of them instead).
    #[test]
    fn the_time_in_the_name_orders_them_and_the_new_save_stays() {
        let (path, dir) = scratch("time");
        let y2030 = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_900_000_000);
        for t in 1..=3 {
            touch(&path, &file_name("demo", t, "fault"));
            let file = File::options()
                .write(true)
                .open(path.join(file_name("demo", t, "fault")))
                .expect("open");
            file.set_modified(y2030).expect("mtime 2030");
        }
        let (name, _) = create(&dir, "demo", 1_000, "estop").expect("saved");
        assert_eq!(
            remove_oldest(&dir, "demo", 2, &name),
            ["demo-1-fault.mcap", "demo-2-fault.mcap"]
        );
        let _ = std::fs::remove_dir_all(&path);

        let (path, dir) = scratch("future");
        let future = 1_900_000_000_000;
        for t in 0..20 {
            touch(&path, &file_name("demo", future + t, "fault"));
        }
        let (name, _) = create(&dir, "demo", 1_800_000_000_000, "sigusr2").expect("saved");
        assert_eq!(
            remove_oldest(&dir, "demo", 20, &name),
            [file_name("demo", future, "fault")]
        );
        assert!(names(&path).contains(&name), "the new save stays");
        let _ = std::fs::remove_dir_all(&path);
    }

    /// Another user's file with this server's name is not removed; a save is made 0640,
    /// never through a link, and a taken name moves it to the next millisecond.
    #[test]
    fn another_user_s_files_stay_and_saves_are_new_files() {
        let (path, dir) = scratch("user");
        let (first, _) = create(&dir, "demo", 7, "fault").expect("saved");
        assert_eq!(first, "demo-7-fault.mcap");
        let meta = std::fs::metadata(path.join(&first)).expect("saved");
        assert_eq!(meta.mode() & 0o7777, FILE_MODE);
        let victim =
            std::env::temp_dir().join(format!("motiond-bbdir-victim-{}", std::process::id()));
        std::fs::write(&victim, "kept").expect("victim");
        std::os::unix::fs::symlink(&victim, path.join("demo-8-fault.mcap")).expect("link");
        let (second, _) = create(&dir, "demo", 7, "fault").expect("saved");
        assert_eq!(second, "demo-9-fault.mcap", "7 taken, 8 a link");
        assert_eq!(std::fs::read_to_string(&victim).expect("victim"), "kept");
        if nix::unistd::geteuid().is_root() {
            touch(&path, "demo-1-fault.mcap");
            std::fs::set_permissions(
                path.join("demo-1-fault.mcap"),
                std::fs::Permissions::from_mode(0o644),
            )
            .expect("chmod");
            nix::unistd::chown(&path.join("demo-1-fault.mcap"), Some(65_534.into()), None)
                .expect("chown");
            let removed = remove_oldest(&dir, "demo", 1, &second);
            assert_eq!(removed, [first], "another user's file stays");
            assert!(names(&path).contains(&"demo-1-fault.mcap".to_owned()));
        }
        let _ = std::fs::remove_file(&victim);
        let _ = std::fs::remove_dir_all(&path);
    }
}
