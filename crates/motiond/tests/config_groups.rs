//! `[[group]]` tables: a group as the engine takes it (axes as indices into the config's
//! axes, one path and one goal tolerance per member in the group's order, defaults from the
//! axes), every kind of mistake reported at once with `file:line:column` and its key, and
//! the groups of `config/sim.toml`.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::Command;

use motion_config::ServerConfig;
use motion_engine::{Engine, GroupConfig, StreamLimit};

/// A QuadQuad2Drv with two axes (`a` in mm, `b` in degrees) and a QSB-M with one
/// (`feeder`), on two sim links; groups are appended.
const AXES: &str = r#"
[server]
name = "groups"

[[link]]
name = "spi"
type = "sim"

[[link]]
name = "usb"
type = "sim"

[[device]]
name = "drive"
link = "spi"
model = "qq2drv"

[[device]]
name = "io_board"
link = "usb"
model = "qsb"

[[axis]]
name = "a"
device = "drive"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -50.0
max = 50.0
max_velocity = 10.0
max_accel = 100.0

[[axis]]
name = "b"
device = "drive"
channel = 1
unit = "deg"
counts_per_unit = 50.0
min = -180.0
max = 180.0
max_velocity = 90.0
max_accel = 360.0
following_error = 4.0
position_tolerance = 0.1

[[axis]]
name = "feeder"
device = "io_board"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -100.0
max = 100.0
max_velocity = 10.0
max_accel = 100.0
"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motiond-groups-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write config");
    path
}

/// Runs `--check-config`: (exit code, stderr).
fn check(name: &str, text: &str) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--check-config")
        .arg(write(name, text))
        .output()
        .expect("run motiond");
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

fn line_of(text: &str, needle: &str) -> usize {
    let offset = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not in the config"));
    text[..offset].matches('\n').count() + 1
}

fn parse(text: &str) -> ServerConfig {
    ServerConfig::parse(Path::new("groups.toml"), text).unwrap_or_else(|error| panic!("{error}"))
}

#[test]
fn a_group_takes_numbers_and_tables_by_axis_in_its_own_order() {
    let text = format!(
        r#"{AXES}
[[group]]
name = "gantry"
axes = ["feeder", "a"]
path_tolerance = {{ feeder = 2.0 }}
goal_tolerance = {{ a = 0.05, feeder = 0.1 }}
goal_time_tolerance_ms = 500
stream_limit = "clamp"
stream_timeout = 10
stream_buffer = 5

[[group]]
name = "pair"
axes = ["a", "b"]
path_tolerance = 0.3
goal_tolerance = 1
"#
    );
    let config = parse(&text);
    let a = &config.axes[0];
    assert_eq!(config.groups.len(), 2);
    assert_eq!(
        config.groups[0],
        GroupConfig {
            name: "gantry".into(),
            axes: vec![2, 0],
            // feeder as given, `a` its following_error
            path_tolerance: vec![2.0, a.following_error],
            goal_tolerance: vec![0.1, 0.05],
            goal_time_tolerance: Duration::from_millis(500),
            stream_limit: StreamLimit::Clamp,
            stream_timeout: 10,
            stream_buffer: 5,
        }
    );
    // `a` is in both groups; one number is every axis's (an integer is a number).
    assert_eq!(
        config.groups[1],
        GroupConfig {
            name: "pair".into(),
            axes: vec![0, 1],
            path_tolerance: vec![0.3, 0.3],
            goal_tolerance: vec![1.0, 1.0],
            ..GroupConfig::default()
        }
    );
    // The engine takes them as they are.
    assert_eq!(config.engine_config().groups, config.groups);
    let (code, stderr) = check("full.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn tolerances_default_to_the_axes_own_and_the_rest_to_the_documented_values() {
    let text = format!("{AXES}\n[[group]]\nname = \"all\"\naxes = [\"b\", \"feeder\", \"a\"]\n");
    let config = parse(&text);
    let [a, b, feeder] = [&config.axes[0], &config.axes[1], &config.axes[2]];
    // `b` sets its own following_error and position_tolerance; the others take theirs.
    assert_eq!((b.following_error, b.position_tolerance), (4.0, 0.1));
    assert_eq!(
        config.groups,
        vec![GroupConfig {
            name: "all".into(),
            axes: vec![1, 2, 0],
            path_tolerance: vec![b.following_error, feeder.following_error, a.following_error],
            goal_tolerance: vec![
                b.position_tolerance,
                feeder.position_tolerance,
                a.position_tolerance
            ],
            goal_time_tolerance: Duration::from_secs(1),
            stream_limit: StreamLimit::Abort,
            stream_timeout: 20,
            stream_buffer: 3,
        }]
    );
    // A table naming some axes: the others keep their defaults. An empty table is all
    // defaults.
    let text = format!(
        "{AXES}\n[[group]]\nname = \"g\"\naxes = [\"a\", \"b\"]\npath_tolerance = {{ b = 3.5 }}\ngoal_tolerance = {{}}\n"
    );
    let group = &parse(&text).groups[0];
    assert_eq!(group.path_tolerance, vec![a.following_error, 3.5]);
    assert_eq!(
        group.goal_tolerance,
        vec![a.position_tolerance, b.position_tolerance]
    );
    // Without groups there are none.
    assert!(parse(AXES).groups.is_empty());
}

/// Seventeen QuadQuad2Drv axes `m0` … `m16` on five sim links, for a group too large.
fn many_axes() -> String {
    let mut text = String::new();
    for board in 0..5 {
        text.push_str(&format!(
            "\n[[link]]\nname = \"spi_m{board}\"\ntype = \"sim\"\n\n[[device]]\nname = \"drive_m{board}\"\nlink = \"spi_m{board}\"\nmodel = \"qq2drv\"\n"
        ));
    }
    for axis in 0..17 {
        text.push_str(&format!(
            "\n[[axis]]\nname = \"m{axis}\"\ndevice = \"drive_m{}\"\nchannel = {}\nunit = \"mm\"\ncounts_per_unit = 100.0\nmin = -50.0\nmax = 50.0\nmax_velocity = 10.0\nmax_accel = 100.0\n",
            axis / 4,
            axis % 4
        ));
    }
    text
}

/// One file with every kind of group mistake: each is reported, on its own line with its
/// key, in one run (none hides another).
#[test]
fn every_group_mistake_is_reported_at_once_with_its_line_and_key() {
    let seventeen: Vec<String> = (0..17).map(|axis| format!("\"m{axis}\"")).collect();
    let text = format!(
        r#"{AXES}{many}
[[group]]
name = "bad"
axes = ["a", "nowhere", "b", "a"]
path_tolerance = {{ a = -1.0, feeder = 2.0, b = nan }}
goal_tolerance = {{ a = 0.0, b = "tight" }}
goal_time_tolerance_ms = 0
stream_limit = "wrap"
stream_timeout = 0
stream_buffer = -3

[[group]]
name = "empty"
axes = []

[[group]]
name = "huge"
axes = [{seventeen}]

[[group]]
name = "bad"
axes = ["feeder"]
path_tolerance = true
goal_tolerance = -0.5

[[group]]
name = "worse"
axes = ["b"]
path_tolerance = "loose"
goal_tolerance = 0
goal_time_tolerance_ms = 60001

[[group]]
name = "no name"
axes = ["a"]

[[group]]
axes = ["a"]
"#,
        many = many_axes(),
        seventeen = seventeen.join(", ")
    );
    let (code, stderr) = check("every.toml", &text);
    assert_eq!(code, Some(1), "{stderr}");
    let expected: &[(&str, &str, &str)] = &[
        (
            "\"nowhere\"",
            "group[0].axes",
            "no axis called `nowhere`; axes defined: a, b, feeder, m0, m1",
        ),
        (
            "\"nowhere\"",
            "group[0].axes",
            "axis `a` is listed twice; each axis once",
        ),
        (
            "a = -1.0",
            "group[0].path_tolerance.a",
            "-1 is not allowed; a finite number >= 0",
        ),
        (
            "feeder = 2.0,",
            "group[0].path_tolerance.feeder",
            "`feeder` is not an axis of group `bad`; its axes: a, nowhere, b",
        ),
        (
            "b = nan",
            "group[0].path_tolerance.b",
            "NaN is not allowed; a finite number >= 0",
        ),
        (
            "a = 0.0",
            "group[0].goal_tolerance.a",
            "0 is not allowed; a finite number > 0",
        ),
        (
            "\"tight\"",
            "group[0].goal_tolerance.b",
            "a string is not allowed; a finite number > 0",
        ),
        (
            "goal_time_tolerance_ms = 0",
            "group[0].goal_time_tolerance_ms",
            "0 is out of range; allowed: 1..=60000",
        ),
        (
            "\"wrap\"",
            "group[0].stream_limit",
            "unknown stream limit \"wrap\"; allowed: \"abort\"",
        ),
        (
            "stream_timeout = 0",
            "group[0].stream_timeout",
            "0 is out of range; allowed: 1..=100000",
        ),
        (
            "stream_buffer = -3",
            "group[0].stream_buffer",
            "-3 is out of range; allowed: 1..=1000",
        ),
        (
            "axes = []",
            "group[1].axes",
            "a group needs at least one axis",
        ),
        (
            "axes = [\"m0\"",
            "group[2].axes",
            "17 axes; a group holds at most 16",
        ),
        (
            "name = \"bad\"\naxes = [\"feeder\"]",
            "group[3].name",
            "a group called `bad` is already defined; names must be unique",
        ),
        (
            "path_tolerance = true",
            "group[3].path_tolerance",
            "a boolean is not allowed; a finite number >= 0, in the axis's unit (0 turns the check off), or a table of them by axis",
        ),
        (
            "goal_tolerance = -0.5",
            "group[3].goal_tolerance",
            "-0.5 is not allowed; a finite number > 0",
        ),
        (
            "\"loose\"",
            "group[4].path_tolerance",
            "a string is not allowed",
        ),
        (
            "goal_tolerance = 0\n",
            "group[4].goal_tolerance",
            "0 is not allowed; a finite number > 0",
        ),
        (
            "= 60001",
            "group[4].goal_time_tolerance_ms",
            "60001 is out of range; allowed: 1..=60000",
        ),
        (
            "\"no name\"",
            "group[5].name",
            "\"no name\" is not a valid name",
        ),
    ];
    // A missing name is reported at its table's first line.
    let last = text.rfind("[[group]]").expect("the last group");
    let unnamed = (
        text[..last].matches('\n').count() + 1,
        "group[6].name",
        "missing; every group needs a name",
    );
    let lines: Vec<&str> = stderr.lines().collect();
    let expected: Vec<(usize, &str, &str)> = expected
        .iter()
        .map(|&(needle, key, says)| (line_of(&text, needle), key, says))
        .chain([unnamed])
        .collect();
    for (line, key, says) in &expected {
        let location = format!("every.toml:{line}:");
        assert!(
            lines.iter().any(|l| l.contains(&location)
                && l.contains(&format!("`{key}`:"))
                && l.contains(says)),
            "expected {location} `{key}` … {says:?} in:\n{stderr}"
        );
    }
    // Nothing else: one line per mistake, and the closing line.
    assert_eq!(lines.len(), expected.len() + 1, "{stderr}");
    // A name that refers to nothing comes first: it often explains the rest.
    assert!(lines[0].contains("no axis called `nowhere`"), "{stderr}");
}

#[test]
fn unknown_keys_and_wrong_types_are_refused_with_their_key() {
    for (name, group, needle, key, says) in [
        (
            "unknown.toml",
            "name = \"g\"\naxes = [\"a\"]\ntolerance = 1.0",
            "tolerance = 1.0",
            "group[0].tolerance",
            "unknown field `tolerance`, expected one of `name`, `axes`, `path_tolerance`",
        ),
        (
            "axes_type.toml",
            "name = \"g\"\naxes = \"a\"",
            "axes = \"a\"",
            "group[0].axes",
            "invalid type: string \"a\", expected a sequence",
        ),
        (
            "timeout_type.toml",
            "name = \"g\"\naxes = [\"a\"]\nstream_timeout = 1.5",
            "stream_timeout = 1.5",
            "group[0].stream_timeout",
            "invalid type: floating point `1.5`, expected an integer",
        ),
    ] {
        let text = format!("{AXES}\n[[group]]\n{group}\n");
        let (code, stderr) = check(name, &text);
        assert_eq!(code, Some(1), "{name}: {stderr}");
        let location = format!("{name}:{}:", line_of(&text, needle));
        assert!(
            stderr.lines().any(|line| line.contains(&location)
                && line.contains(&format!("`{key}`"))
                && line.contains(says)),
            "{name}: expected {location} `{key}` … {says:?} in:\n{stderr}"
        );
    }
}

#[test]
fn a_zero_path_tolerance_turns_the_check_off_with_a_warning() {
    let text = format!(
        "{AXES}\n[[group]]\nname = \"g\"\naxes = [\"a\", \"b\"]\npath_tolerance = {{ b = 0.0 }}\n"
    );
    let config = parse(&text);
    assert_eq!(config.groups[0].path_tolerance[1], 0.0);
    let (code, stderr) = check("zero.toml", &text);
    assert_eq!(code, Some(0), "{stderr}");
    let location = format!("zero.toml:{}:", line_of(&text, "b = 0.0"));
    assert!(
        stderr.lines().any(|line| line.contains(&location)
            && line.contains("warning: `group[0].path_tolerance.b`: 0 turns off")),
        "{stderr}"
    );
}

#[test]
fn more_than_sixteen_groups_are_refused() {
    let mut text = AXES.to_owned();
    for group in 0..17 {
        text.push_str(&format!(
            "\n[[group]]\nname = \"g{group}\"\naxes = [\"a\"]\n"
        ));
    }
    let (code, stderr) = check("seventeen.toml", &text);
    assert_eq!(code, Some(1), "{stderr}");
    let location = format!(
        "seventeen.toml:{}:",
        line_of(&text, "[[group]]\nname = \"g16\"")
    );
    assert!(
        stderr.lines().any(|line| line.contains(&location)
            && line.contains("`group`: 17 [[group]] tables; at most 16 are supported")),
        "{stderr}"
    );
}

/// `config/sim.toml`'s groups: the SIXpack's six axes, a gantry of three boards on three
/// links, the base's wheels, the sight of two SPI boards (a tracker's stream); the engine
/// takes them.
#[test]
fn the_default_config_has_the_arm_the_gantry_the_base_and_the_sight() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
    let config = ServerConfig::load(&path).unwrap_or_else(|error| panic!("{error}"));
    let named = |group: &GroupConfig| -> Vec<&str> {
        group
            .axes
            .iter()
            .map(|&axis| config.axes[axis].name.as_str())
            .collect()
    };
    let groups: Vec<(&str, Vec<&str>)> = config
        .groups
        .iter()
        .map(|group| (group.name.as_str(), named(group)))
        .collect();
    assert_eq!(
        groups,
        vec![
            ("arm", vec!["x", "y", "z", "a", "b", "c"]),
            ("gantry", vec!["x", "feeder", "lift"]),
            ("base", vec!["wheel_left", "wheel_right"]),
            ("aim", vec!["turret", "focus"]),
        ]
    );
    // The sight spans two boards (the QuadQuad2Drv and an SPI_motor), streams with the
    // default `abort` and 20 ticks of buffer.
    let aim = &config.groups[3];
    let models: Vec<&str> = aim
        .axes
        .iter()
        .map(|&axis| config.devices[config.axes[axis].device].model.id())
        .collect();
    assert_eq!(models, ["qq2drv", "spimotor"]);
    assert_eq!(aim.stream_limit, motion_engine::StreamLimit::Abort);
    assert_eq!((aim.stream_buffer, aim.stream_timeout), (20, 100));
    let device_of = |axis: usize| &config.devices[config.axes[axis].device];
    // The arm is one SIXpack.
    let arm = &config.groups[0];
    assert!(
        arm.axes
            .iter()
            .all(|&axis| device_of(axis).name == "pack_xyz")
    );
    assert_eq!(device_of(arm.axes[0]).channel_count(), 6);
    // The gantry: three boards on three links.
    let gantry = &config.groups[1];
    let mut links: Vec<usize> = gantry.axes.iter().map(|&a| device_of(a).link).collect();
    links.sort_unstable();
    links.dedup();
    assert_eq!(links.len(), 3, "{links:?}");
    // Every tolerance is one of the axis's own size: a path tolerance within its
    // following_error — but on the SIXpack, whose axes follow a path about 150 ms behind
    // on their shared 19200-baud bus (docs/ARCHITECTURE.md "Coordinated motion"): within
    // 5 mm or 8° —, a goal tolerance no larger than its path tolerance.
    for group in &config.groups {
        for (member, &axis) in group.axes.iter().enumerate() {
            let (path, goal) = (group.path_tolerance[member], group.goal_tolerance[member]);
            let on_pack = config.devices[config.axes[axis].device].name == "pack_xyz";
            let axis = &config.axes[axis];
            let most = if on_pack {
                if axis.unit == "deg" { 8.0 } else { 5.0 }
            } else {
                axis.following_error
            };
            assert!(
                path > 0.0 && path <= most,
                "{} {}: {path}",
                group.name,
                axis.name
            );
            assert!(
                goal > 0.0 && goal <= path,
                "{} {}: {goal}",
                group.name,
                axis.name
            );
        }
    }
    assert!(config.warnings.is_empty(), "{:?}", config.warnings);
    let drivers = motion_config::boards::build(&config).expect("drivers");
    let engine = Engine::new(config.engine_config(), drivers).expect("the engine takes them");
    assert_eq!(engine.config().groups, config.groups);
}
