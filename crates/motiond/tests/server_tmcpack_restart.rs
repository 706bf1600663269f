//! References across a restart of motiond (issue 29; docs/keys/tmcpack.md "References
//! across a server restart"), run as a user would: motiond drives a simulated SIXpack on a
//! pseudo-terminal (the pack lives in this test process, so its EEPROM and its position
//! registers outlive each motiond) with `power_down = "restore"`. x is referenced and moved
//! to 20 mm; motiond is stopped (SIGTERM, and SIGKILL), the pack's supply fails (it saves
//! its positions, "SIXpack / QUADpack manual" V2.43 8.6 "Power-Down modus") and comes back,
//! motiond starts again: x is referenced at 20 mm without a search. Refused: the motor moved
//! while motiond was down, and a file whose axis keys no longer match the config, and a
//! corrupt file (no panic, a log line).
//!
//! And the attacks of issue 40 on the file: a record edited to the counts the pack now
//! reports, and one planted as referenced for an axis never homed, are refused (each record
//! carries the server's MAC) and the axes need a reference; a state directory of another
//! user, or a black box directory that is a link, and the server does not start.

mod support;

use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, DeviceState, MotionFrame};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;
use tmcpack::Request;

fn homed(frame: &MotionFrame, axis: usize) -> bool {
    frame.axes[axis].flags & AxisFlags::HOMED.0 != 0
}

/// The config: x (channel 0, 100 µsteps/mm, its switch 32 mm to the right) and y (channel
/// 1, never referenced); `max_velocity` of x as given.
fn config(name: &str, tty: &Path, state_dir: &Path, x_max_velocity: f64) -> PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"
state_dir = "{}"
blackbox_dir = "{}"
blackbox_on_exit = true

[[link]]
name = "rs485"
type = "serial"
path = "{}"
baud = 19200

[[device]]
name = "pack"
link = "rs485"
model = "tmcpack"
address = 1
power_down = "restore"

[[axis]]
name = "x"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = {x_max_velocity:.1}
max_accel = 250.0
reference = {{ side = "right" }}

[[axis]]
name = "y"
device = "pack"
channel = 1
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 50.0
max_accel = 250.0
"#,
            state_dir.display(),
            state_dir.join("blackbox").display(),
            tty.display()
        ),
    )
}

/// x's record in the references file: (referenced, counts), or `None` without one.
fn saved_x(file: &Path) -> Option<(bool, i64)> {
    let text = std::fs::read_to_string(file).ok()?;
    let value: toml::Value = toml::from_str(&text).ok()?;
    let x = value
        .get("axis")?
        .as_array()?
        .iter()
        .find(|a| a.get("axis").and_then(toml::Value::as_str) == Some("x"))?;
    Some((
        x.get("referenced")?.as_bool()?,
        x.get("counts")?.as_integer()?,
    ))
}

/// Sets `referenced` and `counts` of axis `axis`'s record in the references file, as
/// someone with write access to it would by hand (the file keeps its owner and mode).
fn edit_record(file: &Path, axis: &str, referenced: bool, counts: i64) {
    let text = std::fs::read_to_string(file).expect("the references file");
    let mut value: toml::Value = toml::from_str(&text).expect("toml");
    let record = value
        .get_mut("axis")
        .and_then(toml::Value::as_array_mut)
        .and_then(|axes| {
            axes.iter_mut()
                .find(|a| a.get("axis").and_then(toml::Value::as_str) == Some(axis))
        })
        .and_then(toml::Value::as_table_mut)
        .unwrap_or_else(|| panic!("a record of {axis} in {text}"));
    record.insert("referenced".into(), toml::Value::Boolean(referenced));
    record.insert("counts".into(), toml::Value::Integer(counts));
    std::fs::write(file, toml::to_string(&value).expect("toml")).expect("edited");
}

/// Waits up to 10 s for x's record to be `want` (a loaded machine writes it later).
fn saved_becomes(file: &Path, want: (bool, i64)) -> Option<(bool, i64)> {
    let end = Instant::now() + Duration::from_secs(10);
    let mut last = saved_x(file);
    while Instant::now() < end && last != Some(want) {
        std::thread::sleep(Duration::from_millis(20));
        last = saved_x(file);
    }
    last
}

/// motiond started on `config`, with its client, once the pack is online and x's data
/// fresh: the first such frame.
fn start(config: &Path, name: &str) -> (Server, RawClient, MotionFrame) {
    let server = Server::start(config);
    let client = RawClient::connect(name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(15), |f| {
        f.device_state(0) == DeviceState::Online
            && f.axes[0].flags & AxisFlags::STALE.0 == 0
            && f.axes[0].last_refresh_tick > 0
    });
    assert!(ready, "{:?}", frame.axes()[0]);
    (server, client, frame)
}

/// Waits up to 5 s after the pack came online for x to be referenced (a poll confirms
/// the saved position); the last frame.
fn x_referenced(client: &RawClient) -> (MotionFrame, bool) {
    client.wait_frame(Duration::from_secs(5), |f| {
        homed(f, 0) && f.axes[0].flags & AxisFlags::STALE.0 == 0
    })
}

#[test]
fn a_referenced_axis_stays_referenced_across_motiond_restarts_and_pack_outages() {
    let name = unique_name("tmcrestart");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let state_dir = std::env::temp_dir().join(format!("{name}-state"));
    let file = state_dir.join(format!("{name}.references.toml"));
    let _served = PtyBoard::start(&tty, Arc::clone(&pack), epoch, 19_200);
    let cfg = config(&name, &tty, &state_dir, 50.0);

    // First run: no file (a log line says so); home x, move it to 20 mm.
    let (mut server, mut client, _) = start(&cfg, &name);
    assert!(server.wait_for_log("no saved references", Duration::from_secs(2)));
    let reply = client.command(0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, done) = client.wait_frame(Duration::from_secs(15), |f| {
        homed(f, 0) && f.axes[0].mode == AxisMode::Hold as u8
    });
    assert!(done, "homed: {:?}", frame.axes()[0]);
    let reply = client.command(0, CommandKind::Position, [20.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    // Moving: written as not referenced.
    assert_eq!(saved_becomes(&file, (false, 0)), Some((false, 0)));
    let (frame, there) = client.wait_frame(Duration::from_secs(10), |f| {
        f.axes[0].flags & AxisFlags::ARRIVED.0 != 0 && f.axes[0].flags & AxisFlags::MOVING.0 == 0
    });
    assert!(there, "{:?}", frame.axes()[0]);
    assert_eq!(saved_becomes(&file, (true, 2000)), Some((true, 2000)));
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert_eq!(saved_x(&file), Some((true, 2000)), "after a clean stop");
    let physical = pack.lock().expect("pack").motor(0).expect("m0").physical;

    // The supply fails (the pack saves 2000) and comes back; motiond starts again.
    pack.lock().expect("pack").power_outage(epoch.elapsed());
    let (mut server, client, _) = start(&cfg, &name);
    let (frame, referenced) = x_referenced(&client);
    assert!(referenced, "no search needed: {:?}", frame.axes()[0]);
    assert!(
        (frame.axes[0].position - 20.0).abs() < 1e-9,
        "{:?}",
        frame.axes()[0]
    );
    assert!(!homed(&frame, 1), "y never had a reference");
    assert_eq!(
        pack.lock().expect("pack").motor(0).expect("m0").physical,
        physical,
        "no search: the rotor stayed"
    );
    // This run's black box (checked at the end: it replays with the reference start-up
    // handed the driver, journaled).
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(server.pid() as i32),
        Signal::SIGUSR2,
    )
    .expect("SIGUSR2");
    assert!(server.wait_for_log("black box saved (sigusr2)", Duration::from_secs(5)));

    // SIGKILL, the pack kept running (no boot): referenced from its registers.
    assert_eq!(saved_becomes(&file, (true, 2000)), Some((true, 2000)));
    drop(client);
    server.signal_and_wait(Signal::SIGKILL, Duration::from_secs(5));
    let (mut server, client, _) = start(&cfg, &name);
    let (frame, referenced) = x_referenced(&client);
    assert!(referenced, "kept: {:?}", frame.axes()[0]);
    assert!((frame.axes[0].position - 20.0).abs() < 1e-9);

    // SIGKILL, then an outage: referenced from the loaded positions.
    assert_eq!(saved_becomes(&file, (true, 2000)), Some((true, 2000)));
    drop(client);
    server.signal_and_wait(Signal::SIGKILL, Duration::from_secs(5));
    pack.lock().expect("pack").power_outage(epoch.elapsed());
    let (mut server, client, _) = start(&cfg, &name);
    let (frame, referenced) = x_referenced(&client);
    assert!(referenced, "loaded: {:?}", frame.axes()[0]);
    assert!((frame.axes[0].position - 20.0).abs() < 1e-9);

    // Refused: the motor moved (another master ran it to 25 mm) while motiond was down;
    // then the outage saved that position.
    assert_eq!(saved_becomes(&file, (true, 2000)), Some((true, 2000)));
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    {
        let mut pack = pack.lock().expect("pack");
        let now = epoch.elapsed();
        pack.act_behind_the_back(
            now,
            Request::SetTarget {
                motor: 0,
                target: 2500,
            },
        );
        pack.act_behind_the_back(
            now,
            Request::StartRamp {
                motor: 0,
                target: 2500,
            },
        );
        // Long enough for the ramp (5 mm at up to 50 mm/s).
        pack.power_outage(now + Duration::from_secs(2));
        assert_eq!(pack.motor(0).expect("m0").position, 0, "booted");
    }
    let (mut server, mut client, _) = start(&cfg, &name);
    let (frame, referenced) = x_referenced(&client);
    assert!(!referenced, "moved while down: {:?}", frame.axes()[0]);
    assert!(
        (frame.axes[0].position - 25.0).abs() < 1e-9,
        "{:?}",
        frame.axes()[0]
    );

    // Refused: the axis's keys changed (x's max_velocity), though the position matches.
    let reply = client.command(0, CommandKind::SetPosition, [25.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    assert_eq!(saved_becomes(&file, (true, 2500)), Some((true, 2500)));
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    let changed = config(&name, &tty, &state_dir, 40.0);
    let (mut server, client, _) = start(&changed, &name);
    assert!(server.wait_for_log("keys changed", Duration::from_secs(2)));
    let (frame, referenced) = x_referenced(&client);
    assert!(!referenced, "another config: {:?}", frame.axes()[0]);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );

    // Refused: a corrupt file. motiond starts, says so, references nothing.
    std::fs::write(&file, "server = \"not toml").expect("corrupt");
    let (mut server, client, _) = start(&cfg, &name);
    assert!(server.wait_for_log("is not a references file", Duration::from_secs(2)));
    let (frame, referenced) = x_referenced(&client);
    assert!(!referenced, "corrupt file: {:?}", frame.axes()[0]);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    // Every run's black box replays frame for frame: the runs whose driver was handed a
    // saved reference at start-up, and the others.
    let saved: Vec<PathBuf> = std::fs::read_dir(state_dir.join("blackbox"))
        .expect("the black box files")
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "mcap"))
        .collect();
    assert!(saved.len() >= 5, "{saved:?}");
    for file in &saved {
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_motiond"))
            .arg("--replay")
            .arg(file)
            .output()
            .expect("motiond --replay runs");
        let text = String::from_utf8_lossy(&output.stdout);
        assert!(
            output.status.success() && text.contains("frames identical"),
            "{}: {text}{}",
            file.display(),
            String::from_utf8_lossy(&output.stderr)
        );
    }
    let _ = std::fs::remove_dir_all(&state_dir);
}

/// Issue 40, same user: x referenced at 20 mm, then moved to 25 mm while motiond was down
/// (the pack saved 2500 at its outage); the record edited to 2500 made x `homed` at 25 mm
/// after a restart. And a record planted as `referenced = true` for y, never homed, made
/// y `homed` at 0 mm. Both are refused now: neither record is the server's (its MAC), the
/// log says so, and both axes need a reference.
#[test]
fn an_edited_or_planted_record_is_refused_and_the_axes_need_a_reference() {
    let name = unique_name("tmcforge");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let state_dir = std::env::temp_dir().join(format!("{name}-state"));
    let file = state_dir.join(format!("{name}.references.toml"));
    let _served = PtyBoard::start(&tty, Arc::clone(&pack), epoch, 19_200);
    let cfg = config(&name, &tty, &state_dir, 50.0);

    let (mut server, mut client, _) = start(&cfg, &name);
    let reply = client.command(0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, done) = client.wait_frame(Duration::from_secs(15), |f| {
        homed(f, 0) && f.axes[0].mode == AxisMode::Hold as u8
    });
    assert!(done, "homed: {:?}", frame.axes()[0]);
    let reply = client.command(0, CommandKind::Position, [20.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    assert_eq!(saved_becomes(&file, (true, 2000)), Some((true, 2000)));
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    // Only the server's user may read the file and the key beside it.
    for private in [file.clone(), state_dir.join("motiond.key")] {
        let mode = std::fs::metadata(&private)
            .expect("made")
            .permissions()
            .mode();
        assert_eq!(mode & 0o777, 0o600, "{}", private.display());
    }
    {
        let mut pack = pack.lock().expect("pack");
        let now = epoch.elapsed();
        for request in [
            Request::SetTarget {
                motor: 0,
                target: 2500,
            },
            Request::StartRamp {
                motor: 0,
                target: 2500,
            },
        ] {
            pack.act_behind_the_back(now, request);
        }
        pack.power_outage(now + Duration::from_secs(2));
    }
    edit_record(&file, "x", true, 2500);
    edit_record(&file, "y", true, 0);

    let (mut server, client, _) = start(&cfg, &name);
    for axis in ["x", "y"] {
        assert!(
            server.wait_for_log(
                &format!(
                    "axis `{axis}` is not referenced from {}: its record is not authenticated",
                    file.display()
                ),
                Duration::from_secs(2)
            ),
            "{axis}: {:#?}",
            server.log
        );
    }
    let (frame, referenced) = x_referenced(&client);
    assert!(!referenced, "an edited record: {:?}", frame.axes()[0]);
    assert!(
        (frame.axes[0].position - 25.0).abs() < 1e-9,
        "{:?}",
        frame.axes()[0]
    );
    assert!(!homed(&frame, 1), "a planted record: {:?}", frame.axes()[1]);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    let _ = std::fs::remove_dir_all(&state_dir);
}

/// Issue 40: another user pre-created the state directory (here one chowned to uid 65534),
/// and the server wrote its references into it; `blackbox_dir` a link to a directory
/// elsewhere, and the server wrote there. Now the server does not start, and says which
/// directory, what it found and what to do.
#[test]
fn a_state_or_black_box_directory_not_the_server_s_own_is_refused_at_start() {
    if !nix::unistd::geteuid().is_root() {
        eprintln!("not root: a directory of another user cannot be made here");
        return;
    }
    let name = unique_name("tmcdirs");
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let state_dir = std::env::temp_dir().join(format!("{name}-state"));
    let _ = std::fs::remove_dir_all(&state_dir);
    std::fs::create_dir(&state_dir).expect("made");
    std::fs::set_permissions(&state_dir, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    nix::unistd::chown(&state_dir, Some(65_534.into()), Some(65_534.into())).expect("chown");
    let cfg = config(&name, &tty, &state_dir, 50.0);
    let mut server = Server::start(&cfg);
    assert_eq!(server.wait(Duration::from_secs(10)), Some(1), "refused");
    let log = server.log_text();
    for needle in [
        format!(
            "[server] state_dir {} is not the server's own",
            state_dir.display()
        ),
        "uid 65534, mode 755".to_owned(),
        "this server runs as uid 0".to_owned(),
    ] {
        assert!(log.contains(&needle), "{needle:?} in {log}");
    }
    assert_eq!(
        std::fs::read_dir(&state_dir).expect("listed").count(),
        0,
        "nothing written there"
    );
    std::fs::remove_dir_all(&state_dir).expect("removed");

    // The state directory the server's own; the black box's a link to another directory.
    std::fs::create_dir(&state_dir).expect("made");
    let elsewhere = std::env::temp_dir().join(format!("{name}-elsewhere"));
    std::fs::create_dir_all(&elsewhere).expect("made");
    std::os::unix::fs::symlink(&elsewhere, state_dir.join("blackbox")).expect("link");
    let mut server = Server::start(&cfg);
    assert_eq!(server.wait(Duration::from_secs(10)), Some(1), "refused");
    let log = server.log_text();
    assert!(
        log.contains(&format!(
            "[server] blackbox_dir {} is not the server's own: it is a symbolic link (to {})",
            state_dir.join("blackbox").display(),
            elsewhere.display()
        )),
        "{log}"
    );
    assert_eq!(std::fs::read_dir(&elsewhere).expect("listed").count(), 0);
    let _ = std::fs::remove_dir_all(&state_dir);
    let _ = std::fs::remove_dir_all(&elsewhere);
}
