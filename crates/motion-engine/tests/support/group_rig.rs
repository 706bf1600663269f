//! The group tests' rig: two links, one ideal board each, one group of all four axes, and
//! the commands and paths a client sends it.

use core::time::Duration;
use std::sync::{Arc, Mutex};

use motion_drivers::{Follow, LinkKind};
use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig, GroupConfig};
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, GroupMotion, GroupPath, MAX_GROUP_AXES,
    PathFlags, PathKind, Target,
};

use super::{ALL_GOALS, BoardControl, Harness, IdealBoard, axis};

/// Two links with one ideal board each (x, y on the first; z, w on the second), `follow`
/// per board, and one group `xyzw` of all four axes (path tolerance `path`, goal
/// tolerance 0.05, goal time 200 ms).
pub fn rig(follow: [Follow; 2], path: f64) -> (Harness, Vec<Arc<Mutex<BoardControl>>>) {
    let group = GroupConfig {
        name: "xyzw".into(),
        axes: vec![0, 1, 2, 3],
        path_tolerance: vec![path; 4],
        goal_tolerance: vec![0.05; 4],
        goal_time_tolerance: Duration::from_millis(200),
        ..GroupConfig::default()
    };
    let mut fast = axis("w", 1, 1);
    fast.max_velocity = 20.0;
    fast.max_accel = 100.0;
    let config = EngineConfig {
        name: "groups".into(),
        links: vec![
            BusConfig {
                name: "bus0".into(),
                kind: LinkKind::Stream,
            },
            BusConfig {
                name: "bus1".into(),
                kind: LinkKind::Spi,
            },
        ],
        devices: vec![
            DeviceConfig {
                name: "board0".into(),
                link: 0,
                address: 1,
            },
            DeviceConfig {
                name: "board1".into(),
                link: 1,
                address: 2,
            },
        ],
        axes: vec![axis("x", 0, 0), axis("y", 0, 1), axis("z", 1, 0), fast],
        groups: vec![group],
        ..EngineConfig::default()
    };
    let mut controls = Vec::new();
    let mut boards = Vec::new();
    for style in follow {
        let (board, control) = IdealBoard::boxed(2, &ALL_GOALS);
        control.lock().expect("control").follow = style;
        boards.push(board);
        controls.push(control);
    }
    let mut h = Harness::new(Engine::new(config, boards).expect("valid config"));
    h.ticks(3);
    (h, controls)
}

pub fn group_command(
    h: &mut Harness,
    client: ClientId,
    kind: CommandKind,
    value: f64,
) -> CommandReply {
    h.sequence += 1;
    let mut request =
        CommandRequest::new(client, h.sequence, 0, kind).with_values([value, 0.0, 0.0]);
    request.target = Target::Group as u32;
    h.port.requests.push_back(request);
    h.tick();
    h.port.replies.pop().expect("answered")
}

pub fn line(id: u64, targets: &[f64]) -> Box<GroupPath> {
    let mut path = Box::new(GroupPath::EMPTY);
    path.set_line(0, id, targets, (0.0, 0.0));
    path
}

/// A trajectory of `points` (time, positions) with optional velocities.
pub fn trajectory(
    id: u64,
    points: &[(f64, [f64; 4])],
    velocities: Option<&[[f64; 4]]>,
) -> Box<GroupPath> {
    let mut path = Box::new(GroupPath::EMPTY);
    path.kind = PathKind::Trajectory as u32;
    path.id = id;
    path.axis_count = 4;
    path.point_count = points.len() as u32;
    for (index, (time, positions)) in points.iter().enumerate() {
        path.times[index] = *time;
        path.positions[index * MAX_GROUP_AXES..][..4].copy_from_slice(positions);
    }
    if let Some(velocities) = velocities {
        path.flags = PathFlags::VELOCITIES.0;
        for (index, velocity) in velocities.iter().enumerate() {
            path.velocities[index * MAX_GROUP_AXES..][..4].copy_from_slice(velocity);
        }
    }
    path
}

pub fn run(h: &mut Harness, client: ClientId, path: Box<GroupPath>) -> CommandReply {
    let id = path.id;
    h.port.paths.push((client, path));
    group_command(h, client, CommandKind::Run, id as f64)
}

pub fn desired(h: &Harness) -> [f64; 4] {
    core::array::from_fn(|axis| h.frame.axes[axis].desired_position)
}

pub fn motion(h: &Harness) -> GroupMotion {
    h.frame.groups[0].motion().expect("known")
}

/// Ticks until the group's motion is no longer active, recording the desired positions;
/// at most `limit` ticks.
pub fn run_out(h: &mut Harness, limit: usize) -> Vec<[f64; 4]> {
    let mut seen = Vec::new();
    for _ in 0..limit {
        h.tick();
        seen.push(desired(h));
        if !motion(h).active() {
            break;
        }
    }
    seen
}
