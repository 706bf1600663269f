//! The checks of the server's own directories and the files made in them (issue 40: another
//! user's pre-created directory, a link planted in place of the directory or of a file).

use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};

use super::*;

const KEY: &str = "[server] state_dir";

/// A path under the temp directory that does not exist yet.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-pdir-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn root() -> bool {
    nix::unistd::geteuid().is_root()
}

#[test]
fn a_missing_directory_is_made_this_user_s_with_the_mode_asked_for() {
    let base = scratch("made");
    let path = base.join("deeper/state");
    let dir = PrivateDir::open(&path, KEY, 0o750).expect("made");
    assert_eq!(dir.path(), path);
    let meta = std::fs::metadata(&path).expect("exists");
    assert!(meta.is_dir());
    assert_eq!(meta.uid(), nix::unistd::geteuid().as_raw());
    // The umask may take bits off, never add: at most 0750, never writable by others.
    assert_eq!(meta.mode() & 0o7777 & !0o750, 0, "{:o}", meta.mode());
    let parent = std::fs::metadata(base.join("deeper")).expect("parent");
    assert_eq!(parent.mode() & 0o077, 0, "missing parents are made 0700");
    // Opened again as it is.
    PrivateDir::open(&path, KEY, 0o700).expect("the same directory");
    let _ = std::fs::remove_dir_all(&base);
}

/// Issue 40: another user pre-created the directory; the server wrote into it. Refused,
/// with the path, what was found and what to do.
#[test]
fn another_user_s_directory_is_refused_with_its_owner_and_mode() {
    if !root() {
        eprintln!("not root: a directory of another user cannot be made here");
        return;
    }
    let path = scratch("other");
    std::fs::create_dir(&path).expect("made");
    std::fs::set_permissions(&path, Permissions::from_mode(0o755)).expect("chmod");
    nix::unistd::chown(&path, Some(65_534.into()), Some(65_534.into())).expect("chown");
    let error = PrivateDir::open(&path, KEY, 0o700).expect_err("another user's");
    let text = error.to_string();
    assert!(matches!(error, PrivateDirError::Untrusted { .. }), "{text}");
    for needle in [
        path.to_str().expect("utf-8"),
        "[server] state_dir",
        "uid 65534, mode 755",
        "this server runs as uid 0",
        "remove it",
    ] {
        assert!(text.contains(needle), "{needle:?} in {text}");
    }
    // Nothing was written there.
    assert_eq!(std::fs::read_dir(&path).expect("listed").count(), 0);
    let _ = std::fs::remove_dir_all(&path);
}

/// Issue 40: `blackbox_dir` a symbolic link to a root-only directory. Refused whatever it
/// points to; so is a file where the directory should be.
#[test]
fn a_link_or_a_file_in_place_of_the_directory_is_refused() {
    let base = scratch("link");
    let target = base.join("target");
    std::fs::create_dir_all(&target).expect("target");
    let link = base.join("blackbox");
    std::os::unix::fs::symlink(&target, &link).expect("link");
    let error = PrivateDir::open(&link, "[server] blackbox_dir", 0o750).expect_err("a link");
    let text = error.to_string();
    assert!(
        text.contains("symbolic link") && text.contains(target.to_str().expect("utf-8")),
        "{text}"
    );
    let file = base.join("file");
    std::fs::write(&file, "").expect("file");
    let error = PrivateDir::open(&file, KEY, 0o700).expect_err("a file");
    assert!(error.to_string().contains("not a directory"), "{error}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_directory_its_group_or_others_may_write_is_refused() {
    let base = scratch("mode");
    std::fs::create_dir_all(&base).expect("made");
    for mode in [0o777, 0o775, 0o1777, 0o722] {
        std::fs::set_permissions(&base, Permissions::from_mode(mode)).expect("chmod");
        let error = PrivateDir::open(&base, KEY, 0o700).expect_err("writable");
        let text = error.to_string();
        assert!(
            text.contains("group or others may write") && text.contains("chmod go-w"),
            "{mode:o}: {text}"
        );
    }
    for mode in [0o700, 0o750, 0o755] {
        std::fs::set_permissions(&base, Permissions::from_mode(mode)).expect("chmod");
        PrivateDir::open(&base, KEY, 0o700).unwrap_or_else(|e| panic!("{mode:o}: {e}"));
    }
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_parent_anyone_may_write_without_the_sticky_bit_is_refused() {
    let base = scratch("parent");
    let path = base.join("state");
    std::fs::create_dir_all(&path).expect("made");
    std::fs::set_permissions(&base, Permissions::from_mode(0o777)).expect("chmod");
    let error = PrivateDir::open(&path, KEY, 0o700).expect_err("parent");
    assert!(error.to_string().contains("no sticky bit"), "{error}");
    std::fs::set_permissions(&base, Permissions::from_mode(0o1777)).expect("chmod");
    PrivateDir::open(&path, KEY, 0o700).expect("sticky, as /tmp");
    let _ = std::fs::remove_dir_all(&base);
}

/// New files: `O_CREAT | O_EXCL | O_NOFOLLOW`, their mode exactly as asked.
#[test]
fn a_new_file_is_never_made_through_a_link_or_over_a_file() {
    let base = scratch("new");
    let dir = PrivateDir::open(&base, KEY, 0o700).expect("made");
    let victim = std::env::temp_dir().join(format!("motiond-pdir-victim-{}", std::process::id()));
    std::fs::write(&victim, "kept").expect("victim");
    std::os::unix::fs::symlink(&victim, base.join("planted")).expect("link");
    assert!(dir.create_new("planted", 0o640).is_err(), "a link");
    std::fs::write(base.join("there"), "kept").expect("file");
    assert!(dir.create_new("there", 0o640).is_err(), "a file");
    assert_eq!(std::fs::read_to_string(&victim).expect("victim"), "kept");
    assert_eq!(
        std::fs::read_to_string(base.join("there")).expect("file"),
        "kept"
    );
    let mut made = dir.create_new("made", 0o640).expect("new");
    made.write_all(b"x").expect("written");
    assert_eq!(
        std::fs::metadata(base.join("made")).expect("made").mode() & 0o7777,
        0o640
    );
    // Made whole once; never replaced.
    assert!(dir.create_whole("key", b"first", 0o600).expect("made"));
    assert!(!dir.create_whole("key", b"second", 0o600).expect("exists"));
    assert_eq!(
        dir.read_own("key", Privacy::Secret, 64).expect("read"),
        Some(b"first".to_vec())
    );
    std::fs::set_permissions(base.join("key"), Permissions::from_mode(0o640)).expect("chmod");
    let error = dir
        .read_own("key", Privacy::Secret, 64)
        .expect_err("others may read");
    assert!(error.to_string().contains("may read or write"), "{error}");
    // Only this user's regular files are listed (not the link).
    let mut names: Vec<String> = dir
        .own_files()
        .expect("listed")
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    names.sort();
    assert_eq!(names, ["key", "made", "there"]);
    if root() {
        nix::unistd::chown(&base.join("there"), Some(65_534.into()), None).expect("chown");
        let names: Vec<String> = dir
            .own_files()
            .expect("listed")
            .into_iter()
            .map(|(name, _)| name)
            .collect();
        assert!(!names.contains(&"there".to_owned()), "{names:?}");
    }
    let _ = std::fs::remove_file(&victim);
    let _ = std::fs::remove_dir_all(&base);
}

/// The default state directory: systemd's, the system's for root or its owner, the user's
/// XDG state directory, and `/tmp/motiond-state-<uid>` last.
#[test]
fn the_default_state_dir_resolves_from_the_environment() {
    let user = StateEnv {
        euid: 1000,
        home: Some("/home/ann".into()),
        home_owner: Some(1000),
        ..StateEnv::default()
    };
    assert_eq!(
        state_dir_from(&user),
        PathBuf::from("/home/ann/.local/state/motiond")
    );
    let xdg = StateEnv {
        xdg_state_home: Some("/srv/ann/state".into()),
        ..user.clone()
    };
    assert_eq!(
        state_dir_from(&xdg),
        PathBuf::from("/srv/ann/state/motiond")
    );
    let relative_xdg = StateEnv {
        xdg_state_home: Some("state".into()),
        ..user.clone()
    };
    assert_eq!(
        state_dir_from(&relative_xdg),
        PathBuf::from("/home/ann/.local/state/motiond"),
        "a relative XDG_STATE_HOME is ignored (the spec)"
    );
    let systemd = StateEnv {
        state_directory: Some("/var/lib/motiond:/var/lib/other".into()),
        ..user.clone()
    };
    assert_eq!(state_dir_from(&systemd), PathBuf::from("/var/lib/motiond"));
    let root = StateEnv {
        euid: 0,
        home: Some("/root".into()),
        home_owner: Some(0),
        ..StateEnv::default()
    };
    assert_eq!(state_dir_from(&root), PathBuf::from(VAR_LIB));
    let service_user = StateEnv {
        euid: 998,
        var_lib_owner: Some(998),
        home: Some("/nonexistent".into()),
        ..StateEnv::default()
    };
    assert_eq!(state_dir_from(&service_user), PathBuf::from(VAR_LIB));
    // Another user's /var/lib/motiond and a HOME not this user's (setpriv keeps root's).
    let stranger = StateEnv {
        euid: 4242,
        var_lib_owner: Some(998),
        home: Some("/root".into()),
        home_owner: Some(0),
        ..StateEnv::default()
    };
    assert_eq!(
        state_dir_from(&stranger),
        PathBuf::from("/tmp/motiond-state-4242")
    );
    let homeless = StateEnv {
        euid: 4242,
        home: Some("/".into()),
        home_owner: Some(4242),
        ..StateEnv::default()
    };
    assert_eq!(
        state_dir_from(&homeless),
        PathBuf::from("/tmp/motiond-state-4242")
    );
}
