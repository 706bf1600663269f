//! The references file's records, their MACs, the file's reading and writing, and the
//! tick's watch.

use std::os::unix::fs::{MetadataExt as _, PermissionsExt as _};

use super::*;

fn record(axis: &str) -> Record {
    Record {
        axis: axis.into(),
        device: "pack".into(),
        model: "tmcpack".into(),
        address: 1,
        link: "rs485".into(),
        channel: 0,
        keys: fingerprint("x"),
        referenced: true,
        counts: 1234,
        mac: String::new(),
    }
}

/// A fresh directory of this user's, mode 0700.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-refs-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn key(byte: u8) -> ServerKey {
    ServerKey::from_bytes(&[byte; 32]).expect("a key")
}

#[test]
fn a_record_is_refused_for_any_identity_change_or_when_not_referenced() {
    let now = record("x");
    assert_eq!(refusal(&record("x"), &now), None);
    for change in [
        |r: &mut Record| r.device = "other".into(),
        |r: &mut Record| r.address = 2,
        |r: &mut Record| r.model = "qsb".into(),
        |r: &mut Record| r.link = "bus".into(),
        |r: &mut Record| r.channel = 1,
        |r: &mut Record| r.keys = fingerprint("y"),
        |r: &mut Record| r.referenced = false,
    ] {
        let mut saved = record("x");
        change(&mut saved);
        assert!(refusal(&saved, &now).is_some(), "{saved:?}");
    }
}

#[test]
fn the_file_is_written_atomically_and_read_back() {
    let path = scratch("rw");
    let dir = PrivateDir::open(&path, KEY, STATE_DIR_MODE).expect("made");
    let name = file_name("demo");
    let file = File {
        server: "demo".into(),
        axis: vec![record("x")],
    };
    write_atomically(&dir, &name, &file).expect("written");
    assert_eq!(read(&dir, &name, "demo"), Some(file));
    let meta = std::fs::metadata(dir.file_path(&name)).expect("written");
    assert_eq!(
        meta.mode() & 0o777,
        FILE_MODE,
        "only the server's user reads it"
    );
    assert_eq!(read(&dir, &name, "other"), None, "another server's file");
    std::fs::write(
        dir.file_path(&name),
        "server = \"demo\"\n[[axis]]\naxis = 3\n",
    )
    .expect("garbage");
    assert_eq!(read(&dir, &name, "demo"), None, "a corrupt file");
    std::fs::remove_file(dir.file_path(&name)).expect("removed");
    assert_eq!(read(&dir, &name, "demo"), None, "no file");
    let _ = std::fs::remove_dir_all(&path);
}

/// Issue 40: a record edited by hand (its counts, `referenced`), moved to another server
/// or axis, or planted without the server's key is not authentic; one the server signed is.
#[test]
fn only_a_record_the_server_signed_unchanged_is_authentic() {
    let key = key(1);
    let mut signed = record("x");
    signed.sign("demo", &key);
    assert_eq!(signed.mac.len(), 64);
    assert!(signed.authentic("demo", &key));
    assert!(!signed.authentic("other", &key), "another server's name");
    assert!(!signed.authentic("demo", &self::key(2)), "another key");
    for edit in [
        |r: &mut Record| r.counts = 1221,
        |r: &mut Record| r.referenced = false,
        |r: &mut Record| r.axis = "y".into(),
        |r: &mut Record| r.device = "other".into(),
        |r: &mut Record| r.model = "qsb".into(),
        |r: &mut Record| r.address = 2,
        |r: &mut Record| r.link = "bus".into(),
        |r: &mut Record| r.channel = 1,
        |r: &mut Record| r.keys = fingerprint("y"),
        |r: &mut Record| r.mac = String::new(),
        |r: &mut Record| r.mac.replace_range(0..1, "0"),
    ] {
        let mut edited = signed.clone();
        edit(&mut edited);
        if edited != signed {
            assert!(!edited.authentic("demo", &key), "{edited:?}");
        }
    }
    // Planted: `referenced = true, counts = 0` for an axis never homed, with any MAC.
    let mut planted = record("y");
    planted.counts = 0;
    assert!(!planted.authentic("demo", &key), "no MAC");
    planted.mac = signed.mac.clone();
    assert!(!planted.authentic("demo", &key), "another record's MAC");
}

/// Issue 40: a symbolic link planted at `<name>.references.toml.tmp` made a root server
/// overwrite the file it pointed to. Now the link is removed, never followed: the file it
/// points to is untouched, and the references file is written.
#[test]
fn a_link_planted_at_the_temporary_name_is_never_followed() {
    let path = scratch("link");
    let dir = PrivateDir::open(&path, KEY, STATE_DIR_MODE).expect("made");
    let victim = std::env::temp_dir().join(format!("motiond-refs-victim-{}", std::process::id()));
    std::fs::write(&victim, "root's own file\n").expect("victim");
    let name = file_name("demo");
    std::os::unix::fs::symlink(&victim, dir.file_path(&format!("{name}.tmp"))).expect("planted");
    let file = File {
        server: "demo".into(),
        axis: vec![record("x")],
    };
    write_atomically(&dir, &name, &file).expect("written");
    assert_eq!(
        std::fs::read_to_string(&victim).expect("victim"),
        "root's own file\n",
        "the link's target is untouched"
    );
    assert_eq!(read(&dir, &name, "demo"), Some(file));
    assert!(
        std::fs::symlink_metadata(dir.file_path(&format!("{name}.tmp"))).is_err(),
        "no temporary file left"
    );
    let _ = std::fs::remove_file(&victim);
    let _ = std::fs::remove_dir_all(&path);
}

/// A references file others may write, a link to one, or another user's file is not read
/// (the reason is logged).
#[test]
fn a_file_others_may_write_a_link_or_another_user_s_file_is_not_read() {
    let path = scratch("own");
    let dir = PrivateDir::open(&path, KEY, STATE_DIR_MODE).expect("made");
    let name = file_name("demo");
    let file = File {
        server: "demo".into(),
        axis: vec![record("x")],
    };
    write_atomically(&dir, &name, &file).expect("written");
    let at = dir.file_path(&name);
    std::fs::set_permissions(&at, std::fs::Permissions::from_mode(0o666)).expect("chmod");
    assert!(matches!(
        dir.read_own(&name, Privacy::Unwritable, MAX_FILE_BYTES),
        Err(PrivateDirError::Untrusted { .. })
    ));
    assert_eq!(read(&dir, &name, "demo"), None);
    std::fs::set_permissions(&at, std::fs::Permissions::from_mode(0o600)).expect("chmod");
    assert_eq!(read(&dir, &name, "demo"), Some(file.clone()));

    let elsewhere = path.join("elsewhere.toml");
    std::fs::rename(&at, &elsewhere).expect("moved");
    std::os::unix::fs::symlink(&elsewhere, &at).expect("link");
    let error = dir
        .read_own(&name, Privacy::Unwritable, MAX_FILE_BYTES)
        .expect_err("a link");
    assert!(error.to_string().contains("symbolic link"), "{error}");
    assert_eq!(read(&dir, &name, "demo"), None);
    std::fs::remove_file(&at).expect("unlinked");
    std::fs::rename(&elsewhere, &at).expect("back");

    if nix::unistd::geteuid().is_root() {
        nix::unistd::chown(&at, Some(65_534.into()), None).expect("chown");
        let error = dir
            .read_own(&name, Privacy::Unwritable, MAX_FILE_BYTES)
            .expect_err("another user's");
        assert!(error.to_string().contains("uid 65534"), "{error}");
        assert_eq!(read(&dir, &name, "demo"), None);
    } else {
        eprintln!("not root: another user's file is not tried");
    }
    let _ = std::fs::remove_dir_all(&path);
}

/// A frame whose axis 1 is `mode` with `flags`, online, at `counts`.
fn frame(mode: AxisMode, flags: AxisFlags, counts: i64) -> Box<MotionFrame> {
    let mut frame = Box::new(MotionFrame::EMPTY);
    let axis = &mut frame.axes[1];
    axis.mode = mode as u8;
    axis.flags = flags.0;
    axis.raw_counts = counts;
    axis.device_state = DeviceState::Online as u8;
    frame
}

/// What the tick sends for a watched axis (index 1): referenced only while HOMED, not
/// MOVING, no fault, holding (or arrived); nothing while the device is not online or
/// the data stale; a change of position while referenced; a full ring retried.
#[test]
fn the_watch_sends_referenced_only_at_rest_and_only_changes() {
    let (tx, mut rx) = rtrb::RingBuffer::new(2);
    let mut watch = Watch {
        axes: vec![(1, None)],
        tx,
        restored: Vec::new(),
    };
    let mut seen = |watch: &mut Watch, frame: &MotionFrame| {
        watch.observe(frame);
        let mut out = Vec::new();
        while let Ok(s) = rx.pop() {
            out.push((s.referenced, s.counts));
        }
        out
    };
    let homed = AxisFlags::HOMED;
    let rest = frame(AxisMode::Hold, homed, 2000);
    assert_eq!(seen(&mut watch, &rest), [(true, 2000)]);
    assert_eq!(seen(&mut watch, &rest), [], "no change, nothing sent");
    // A move taken: the mode changes before the board reports motion.
    let taken = frame(AxisMode::RampPosition, homed, 2000);
    assert_eq!(seen(&mut watch, &taken), [(false, 2000)]);
    let moving = frame(
        AxisMode::RampPosition,
        homed.with(AxisFlags::MOVING, true),
        2300,
    );
    assert_eq!(seen(&mut watch, &moving), [], "still not referenced");
    let arrived = frame(
        AxisMode::RampPosition,
        homed.with(AxisFlags::ARRIVED, true),
        2500,
    );
    assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
    // Moving in hold (pushed, a board's own motion), a fault, no reference: not.
    for flags in [
        homed.with(AxisFlags::MOVING, true),
        homed.with(AxisFlags::FAULT, true),
        AxisFlags::default(),
    ] {
        assert_eq!(
            seen(&mut watch, &frame(AxisMode::Hold, flags, 2500)),
            [(false, 2500)]
        );
        assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
    }
    // Stopping, homing: not at rest.
    for mode in [AxisMode::Stopping, AxisMode::Homing, AxisMode::Velocity] {
        assert_eq!(seen(&mut watch, &frame(mode, homed, 2500)), [(false, 2500)]);
        assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
    }
    // The device not online, or the data stale: the record stays as it was.
    let mut offline = frame(AxisMode::Stopping, AxisFlags::default(), 0);
    offline.axes[1].device_state = DeviceState::Faulted as u8;
    assert_eq!(seen(&mut watch, &offline), []);
    let stale = frame(AxisMode::Off, AxisFlags::STALE, 0);
    assert_eq!(seen(&mut watch, &stale), []);
    // Referenced elsewhere (a set-position): sent.
    assert_eq!(
        seen(&mut watch, &frame(AxisMode::Hold, homed, 100)),
        [(true, 100)]
    );
    // A full ring: the change is sent at the next frame that finds room.
    let mut full = Watch {
        axes: vec![(1, None)],
        tx: rtrb::RingBuffer::new(1).0,
        restored: Vec::new(),
    };
    full.observe(&rest);
    full.observe(&taken);
    assert_eq!(
        full.axes[0].1.map(|s| s.referenced),
        Some(true),
        "not sent: not taken"
    );
}

#[test]
fn fingerprints_are_fnv1a_64() {
    // FNV-1a 64 of "" and "a" (the published test vectors).
    assert_eq!(fingerprint(""), "cbf29ce484222325");
    assert_eq!(fingerprint("a"), "af63dc4c8601ec8c");
}
