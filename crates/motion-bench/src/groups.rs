//! Coordinated motion, measured on a motiond the bench starts itself on `config/sim.toml`
//! (the simulated robot, its groups `gantry` and `base`; never the server under test, whose
//! axes may be a real machine's):
//!
//! - **trajectory tracking per board**: one trajectory on `gantry` (x on the SIXpack, feeder
//!   on the QSB-M, lift on the QuadQuad2Drv: the three ways a board follows) and one on
//!   `base` (the QuadQuad2Drv's wheels) at the same time. Per axis, on every frame with a
//!   fresh measurement of it (`last_refresh_tick` changed) while its group moves:
//!   |`desired_position` − `position`|; and the lag: the shift `s` in 0..=300 ticks that
//!   minimises the mean of (measured(t) − desired(t − s))² over those fresh samples, desired
//!   taken from every frame. The lag's baseline is the axis's own refresh interval (ticks
//!   between fresh measurements) in the same run: how much of the lag is the board's
//!   refresh;
//! - **arrival skew of a group move**: three gantry lines back and forth; per move, the
//!   ticks at which each axis's measurement came within its goal tolerance of its target and
//!   stayed, spread max − min; baseline: the same three axes sent single-axis `RampPosition`
//!   commands at their own limits in the same tick, between the same ends (unsynchronised);
//! - **streaming** ([`crate::stream`]).
//!
//! A motion that does not end `done` is an error of the phase, not a figure.

use core::time::Duration;
use std::path::Path;
use std::time::Instant;

use motion_ipc::{
    GroupMotion, GroupPath, MAX_GROUP_AXES, PathFlags, PathKind, SCHEMA_VERSION, ServiceNames,
};

use crate::arrival::SkewRun;
use crate::dist::Dist;
use crate::group_client::{FrameRec, GroupClient, GroupDesc, Watch};
use crate::report::{Row, Unit, UnitName};
use crate::sweep::{Server, ServerRt, last_line};

/// The simulated robot the phase runs (its `[server]` name and rate are replaced).
const SIM_TOML: &str = include_str!("../../../config/sim.toml");

/// The largest shift tried when aligning measured with desired, ticks.
pub const MAX_LAG: u64 = 300;

/// Points of the trajectory (quintic: positions, velocities, accelerations).
const POINTS: usize = 201;

/// The lead-in before the trajectory's first point, s.
const LEAD_IN: f64 = 0.2;

/// One axis's tracking of its group's trajectory.
#[derive(Debug, Clone)]
pub struct AxisTracking {
    /// Its group.
    pub group: String,
    /// The axis.
    pub axis: String,
    /// Its unit.
    pub unit: String,
    /// Its board: `device (model)`.
    pub board: String,
    /// |desired − measured| on fresh frames while the group moved, millionths of the unit.
    pub errors: Dist,
    /// Ticks between fresh measurements while the group moved.
    pub refresh: Dist,
    /// The best-aligning shift, ticks (`None`: no fresh sample).
    pub lag: Option<u64>,
    /// The RMS error at that shift, the axis's unit.
    pub lag_rms: f64,
    /// The trajectory's peak velocity, unit/s.
    pub peak_velocity: f64,
}

/// Everything the group phase measured.
#[derive(Debug)]
pub struct GroupsRun {
    /// Per axis of both trajectories.
    pub tracking: Vec<AxisTracking>,
    /// The trajectories' length, s.
    pub trajectory_s: f64,
    /// The gantry's lines and their single-axis baseline.
    pub skew: SkewRun,
    /// The streaming figures, or why there are none.
    pub stream: Result<crate::stream::StreamRun, String>,
    /// What the bench's motiond ran with.
    pub rt: ServerRt,
    /// How long until every member axis was ready.
    pub online_after: Duration,
    /// Frames the phase's client never saw.
    pub lost_frames: u64,
    /// `Run`s the server answered `NoPath` for a path published just before (sent again).
    pub no_path_retries: u64,
}

/// `config/sim.toml` as server `name` at `tick_hz`, with `rt`'s keys.
pub fn config_text(name: &str, tick_hz: u32, rt: ServerRt) -> Result<String, String> {
    let keys = [
        "[server]\n",
        "name = \"demo\"",
        "tick_hz = 1000",
        "name = \"gantry\"",
        "name = \"base\"",
    ];
    if let Some(missing) = keys.iter().find(|key| !SIM_TOML.contains(*key)) {
        return Err(format!(
            "config/sim.toml as built in has no `{}`: the group phase needs its [server] name \
             and tick_hz and the groups gantry and base",
            missing.trim()
        ));
    }
    Ok(SIM_TOML
        .replacen("name = \"demo\"", &format!("name = \"{name}\""), 1)
        .replacen("tick_hz = 1000", &format!("tick_hz = {tick_hz}"), 1)
        .replacen("[server]\n", &format!("[server]\n{}", rt.keys()), 1))
}

/// Runs the phase: motiond `motiond` on `config/sim.toml` at `tick_hz` with `rt`, files in
/// `dir`; `client_priority` for the streaming client (as the WaitSet clients get it);
/// `python`, the interpreter of the Python closed-loop client, if any, and how many busy
/// loops spin beside it.
pub fn run(
    motiond: &Path,
    tick_hz: u32,
    rt: ServerRt,
    client_priority: Option<u8>,
    duration: Duration,
    dir: &Path,
    python: Option<(&Path, u32)>,
) -> Result<GroupsRun, String> {
    let motiond = motiond.to_path_buf();
    let dir = dir.to_path_buf();
    let python = python.map(|(path, loops)| (path.to_path_buf(), loops));
    // A path is a ≈400 KB sample written in place: room for an unoptimised build too.
    std::thread::Builder::new()
        .name("bench-groups".to_owned())
        .stack_size(16 << 20)
        .spawn(move || {
            run_here(
                &motiond,
                tick_hz,
                rt,
                client_priority,
                duration,
                &dir,
                python
                    .as_ref()
                    .map(|(path, loops)| (path.as_path(), *loops)),
            )
        })
        .map_err(|e| format!("group phase thread: {e}"))?
        .join()
        .map_err(|_| "the group phase thread panicked".to_owned())?
}

fn run_here(
    motiond: &Path,
    tick_hz: u32,
    rt: ServerRt,
    client_priority: Option<u8>,
    duration: Duration,
    dir: &Path,
    python: Option<(&Path, u32)>,
) -> Result<GroupsRun, String> {
    let name = format!("bench-groups-{}", std::process::id());
    let config = dir.join("groups-sim.toml");
    let log = dir.join("groups-sim.log");
    std::fs::write(&config, config_text(&name, tick_hz, rt)?)
        .map_err(|e| format!("{}: {e}", config.display()))?;
    let mut server = Server::start(motiond, &config, &log)?;
    let started = Instant::now();
    let names = ServiceNames::new(&name);
    let mut client = loop {
        if let Some(status) = server.child.try_wait().map_err(|e| e.to_string())? {
            return Err(format!("motiond exited ({status}): {}", last_line(&log)));
        }
        match GroupClient::open(&names, "groups") {
            Ok(client) => break client,
            Err(e) if started.elapsed() > Duration::from_secs(15) => {
                return Err(format!("{e} ({})", last_line(&log)));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(100)),
        }
    };
    let groups = client.describe(&["gantry", "base"])?;
    let (gantry, base) = (&groups[0], &groups[1]);
    let watch = Watch {
        axes: gantry
            .axes
            .iter()
            .chain(&base.axes)
            .map(|a| a.index)
            .collect(),
        groups: vec![gantry.index, base.index],
    };
    client
        .wait_ready(&watch, Duration::from_secs(20))
        .map_err(|e| format!("{e} ({})", last_line(&log)))?;
    let online_after = started.elapsed();
    let with_log = |e: String| format!("{e} (motiond: {})", last_line(&log));
    let (tracking, trajectory_s) =
        tracking(&mut client, gantry, base, duration).map_err(with_log)?;
    let skew = crate::arrival::run(&mut client, gantry, duration).map_err(with_log)?;
    let lost_frames = client.lost_frames;
    let no_path_retries = client.no_path_retries;
    let mut stream = crate::stream::run(&mut client, base, tick_hz, client_priority, duration)
        .map_err(|e| format!("{e} (motiond: {})", last_line(&log)));
    // The Python closed-loop client on the same group, once the Rust one let it go.
    if let (Ok(streamed), Some((python, busy_loops))) = (&mut stream, python) {
        streamed.python =
            crate::python_stream::measure_leads(python, &name, "base", streamed.length, busy_loops)
                .into_iter()
                .map(|run| run.map_err(|e| format!("{e} (motiond: {})", last_line(&log))))
                .collect();
    }
    drop(client);
    server.stop();
    Ok(GroupsRun {
        tracking,
        trajectory_s,
        skew,
        stream,
        rt,
        online_after,
        lost_frames,
        no_path_retries,
    })
}

/// The peak velocity the trajectory asks of an axis, by name (unit/s).
fn peak_velocity(axis: &str) -> f64 {
    match axis {
        "x" => 12.0,
        "feeder" => 20.0,
        "lift" => 6.0,
        "wheel_left" | "wheel_right" => 40.0,
        _ => 5.0,
    }
}

/// There and back from `start`, `length` s after a lead-in: `A (1 − cos ωt)² / 4` with
/// ω = 2π / `length`, at rest with no acceleration at both ends (a path must end at rest:
/// velocity and acceleration exactly 0), peak velocity `peaks[axis]` (0.6495 A ω at
/// ωt = 2π/3); positions, velocities and accelerations exact (quintic segments).
fn write_wave(
    path: &mut GroupPath,
    group: usize,
    id: u64,
    start: &[f64],
    peaks: &[f64],
    length: f64,
) {
    let axes = start.len().min(MAX_GROUP_AXES);
    path.schema_version = SCHEMA_VERSION;
    path.kind = PathKind::Trajectory as u32;
    path.id = id;
    path.group = u32::try_from(group).unwrap_or(u32::MAX);
    path.point_count = POINTS as u32;
    path.axis_count = axes as u32;
    path.flags = PathFlags::VELOCITIES.0 | PathFlags::ACCELERATIONS.0;
    let omega = core::f64::consts::TAU / length;
    // max over θ of (1 − cos θ) sin θ / 2: at θ = 2π/3, 1.5 · (√3/2) / 2
    let shape_peak = 0.75 * 3.0_f64.sqrt() / 2.0;
    for point in 0..POINTS {
        let t = point as f64 / (POINTS - 1) as f64 * length;
        let (sin, cos) = (omega * t).sin_cos();
        let ends = point == 0 || point == POINTS - 1;
        path.times[point] = LEAD_IN + t;
        for axis in 0..axes {
            let amplitude = peaks[axis] / (shape_peak * omega);
            let slot = point * MAX_GROUP_AXES + axis;
            path.positions[slot] = start[axis] + amplitude * (1.0 - cos).powi(2) / 4.0;
            let velocity = amplitude / 2.0 * (1.0 - cos) * sin * omega;
            let accel = amplitude / 2.0 * (sin * sin + cos - cos * cos) * omega * omega;
            path.velocities[slot] = if ends { 0.0 } else { velocity };
            path.accelerations[slot] = if ends { 0.0 } else { accel };
        }
    }
}

/// Moves `group` by a line (when needed) to where each axis is at least 5 % of its range
/// from its limits, the wave of `length` s included; returns where that is.
fn clear_of_limits(
    client: &mut GroupClient,
    group: &GroupDesc,
    length: f64,
) -> Result<Vec<f64>, String> {
    let watch = Watch {
        axes: group.axes.iter().map(|a| a.index).collect(),
        groups: vec![group.index],
    };
    let mut frames = Vec::new();
    client.frames_for(&watch, &mut frames, 20)?;
    let now = frames.last().ok_or("no frame")?.clone();
    let targets: Vec<f64> = group
        .axes
        .iter()
        .zip(&now.axes)
        .map(|(axis, state)| {
            let margin = (axis.max - axis.min) * 0.05;
            let excursion = peak_velocity(&axis.name) * length / 4.0;
            let high = (axis.max - margin - excursion).max(axis.min + margin);
            state.position.clamp(axis.min + margin, high)
        })
        .collect();
    let moved = targets.iter().zip(&now.axes).any(|(t, a)| *t != a.position);
    if moved {
        let index = group.index;
        let (id, _) = client.run_path(index, &|path, id| {
            path.set_line(
                u32::try_from(index).unwrap_or(u32::MAX),
                id,
                &targets,
                (1.0, 1.0),
            );
        })?;
        let ids = [(0, id, group)];
        client.wait_done(
            &watch,
            &mut frames,
            &ids,
            Duration::from_secs(20),
            "line clear of the limits",
        )?;
    }
    Ok(targets)
}

fn tracking(
    client: &mut GroupClient,
    gantry: &GroupDesc,
    base: &GroupDesc,
    duration: Duration,
) -> Result<(Vec<AxisTracking>, f64), String> {
    let length = duration.as_secs_f64().clamp(2.0, 10.0);
    let watch = Watch {
        axes: gantry
            .axes
            .iter()
            .chain(&base.axes)
            .map(|a| a.index)
            .collect(),
        groups: vec![gantry.index, base.index],
    };
    // Clear of the soft limits first (the simulated robot starts at x's and the lift's
    // min): a path that touches a limit may be refused for an excursion of 1e-23.
    let gantry_clear = clear_of_limits(client, gantry, length)?;
    let base_clear = clear_of_limits(client, base, length)?;
    let mut frames = Vec::new();
    client.frames_for(&watch, &mut frames, 50)?;
    let now = frames.last().ok_or("no frame")?.clone();
    for (column, target) in gantry_clear.iter().chain(&base_clear).enumerate() {
        if (now.axes[column].position - target).abs() > 1.0 {
            return Err(format!(
                "axis #{} is not where the line put it",
                watch.axes[column]
            ));
        }
    }
    let mut ids = Vec::new();
    let mut first = 0;
    for (slot, group) in [gantry, base].into_iter().enumerate() {
        let count = group.axes.len();
        let start: Vec<f64> = now.axes[first..first + count]
            .iter()
            .map(|a| a.position)
            .collect();
        let peaks: Vec<f64> = group.axes.iter().map(|a| peak_velocity(&a.name)).collect();
        let index = group.index;
        let (id, _) = client.run_path(index, &|path, id| {
            write_wave(path, index, id, &start, &peaks, length);
        })?;
        ids.push((slot, id, group));
        first += count;
    }
    let timeout = Duration::from_secs_f64(length + LEAD_IN + 10.0);
    client.wait_done(&watch, &mut frames, &ids, timeout, "trajectory")?;
    client.frames_for(&watch, &mut frames, 20)?;
    let mut out = Vec::new();
    let mut column = 0;
    for &(slot, id, group) in &ids {
        for axis in &group.axes {
            let mut track = track_axis(&frames, column, slot, id);
            track.group = if slot == 0 { "gantry" } else { "base" }.to_owned();
            track.axis.clone_from(&axis.name);
            track.unit.clone_from(&axis.unit);
            track.board.clone_from(&axis.board);
            track.peak_velocity = peak_velocity(&axis.name);
            out.push(track);
            column += 1;
        }
    }
    Ok((out, length))
}

/// The figures of watched axis `column` over the frames in which group slot `slot` ran
/// path `id`.
fn track_axis(frames: &[FrameRec], column: usize, slot: usize, id: u64) -> AxisTracking {
    let mut errors = Dist::new();
    let mut refresh = Dist::new();
    let mut samples: Vec<(u64, f64)> = Vec::new();
    let mut previous: Option<u64> = None;
    let mut last_fresh: Option<u64> = None;
    for frame in frames {
        let axis = frame.axes[column];
        let fresh = previous.is_some_and(|p| p != axis.refresh);
        previous = Some(axis.refresh);
        let group = frame.groups[slot];
        let moving = group.path_id == id
            && GroupMotion::try_from(group.motion).is_ok_and(GroupMotion::active);
        if !(moving && fresh) {
            continue;
        }
        let error = (axis.desired - axis.position).abs();
        errors.record_count((error * 1e6).round() as u64);
        if let Some(last) = last_fresh {
            refresh.record_count(axis.refresh - last);
        }
        last_fresh = Some(axis.refresh);
        samples.push((axis.refresh, axis.position));
    }
    let (lag, lag_rms) = best_shift(frames, column, &samples);
    AxisTracking {
        group: String::new(),
        axis: String::new(),
        unit: String::new(),
        board: String::new(),
        errors,
        refresh,
        lag,
        lag_rms,
        peak_velocity: 0.0,
    }
}

/// The shift s in 0..=[`MAX_LAG`] minimising the mean of (measured(t) − desired(t − s))²
/// over `samples` (tick of the measurement, measured position); desired(τ) from the frame
/// of tick τ (the newest frame at or before τ; the first frame's before it). With the RMS
/// error at that shift.
pub fn best_shift(
    frames: &[FrameRec],
    column: usize,
    samples: &[(u64, f64)],
) -> (Option<u64>, f64) {
    if samples.is_empty() || frames.is_empty() {
        return (None, 0.0);
    }
    let desired = |tick: u64| {
        let at = frames.partition_point(|f| f.tick <= tick);
        frames[at.saturating_sub(1)].axes[column].desired
    };
    let mut best = (0, f64::INFINITY);
    for shift in 0..=MAX_LAG {
        let sum: f64 = samples
            .iter()
            .map(|&(tick, measured)| {
                let d = measured - desired(tick.saturating_sub(shift));
                d * d
            })
            .sum();
        let mean = sum / samples.len() as f64;
        if mean < best.1 {
            best = (shift, mean);
        }
    }
    (Some(best.0), best.1.sqrt())
}

/// The rows of the phase (the streaming rows from [`crate::stream::rows`]).
pub fn rows(run: &GroupsRun) -> Vec<Row> {
    let mut rows = Vec::new();
    let server = format!(
        "a motiond started by the bench on config/sim.toml ({}; ready after {:.1} s)",
        run.rt.describe(),
        run.online_after.as_secs_f64()
    );
    for track in &run.tracking {
        let errors = track.errors.summary();
        rows.push(Row {
            figure: format!(
                "trajectory tracking, {} {} on {}: |desired − measured| at each fresh measurement",
                track.group, track.axis, track.board
            ),
            unit: Unit::MicroUnit(UnitName::new(&track.unit)),
            ours: errors,
            baseline: None,
            baseline_label: "no baseline for an error in the axis's unit: the lag row below \
                             puts the lag beside the board's refresh"
                .to_owned(),
            note: format!(
                "a {:.1} s (1 − cos)² there and back (peak {} {}/s; gantry and base at the same time), {server}; \
                 frames with last_refresh_tick changed while the group moved; includes the \
                 measurement's age (the server's own path check compares with where the path was \
                 when the board measured)",
                run.trajectory_s, track.peak_velocity, track.unit
            ),
        });
        let lag = track.lag.unwrap_or(0);
        rows.push(Row {
            figure: format!("trajectory lag, {} {}, ticks", track.group, track.axis),
            unit: Unit::Ticks,
            ours: crate::dist::Summary {
                samples: u64::from(track.lag.is_some()),
                p50: lag,
                p99: lag,
                p999: lag,
                max: lag,
            },
            baseline: Some(track.refresh.summary()),
            baseline_label: format!(
                "the axis's own refresh interval in the same run: ticks between fresh \
                 measurements of {} while it moved",
                track.axis
            ),
            note: format!(
                "one figure per run: the shift s in 0..={MAX_LAG} ticks minimising the mean of \
                 (measured(t) − desired(t − s))² over the fresh measurements (desired from every \
                 frame); RMS error at that shift {:.4} {}; a lag near the refresh interval is \
                 mostly the board's refresh",
                track.lag_rms, track.unit
            ),
        });
    }
    rows.push(crate::arrival::row(&run.skew, &server));
    rows
}

/// What the reader must know about the phase beyond its rows.
pub fn notes(run: &GroupsRun) -> Vec<String> {
    let mut notes = vec![format!(
        "coordinated motion: the phase's client missed {} frames inside its measured windows \
         (between two frames it kept: an axis refreshed more than once in such a gap counts \
         once, and the desired series the lag is aligned with holds the frame before the gap)",
        run.lost_frames
    )];
    if run.no_path_retries > 0 {
        notes.push(format!(
            "coordinated motion: {} Run command(s) were answered NoPath although their path was \
             published just before; sent again, they ran (motiond takes in the paths at the \
             start of a tick, before its commands: a Run that arrives between the two misses \
             its path)",
            run.no_path_retries
        ));
    }
    notes
}

/// The distribution files of the phase: (slug, title, distribution).
pub fn files(run: &GroupsRun) -> Vec<(String, String, &Dist)> {
    let mut files = Vec::new();
    for track in &run.tracking {
        files.push((
            format!("tracking-error-{}-{}", track.group, track.axis),
            format!(
                "|desired − measured|, millionths of {}, {} {}",
                track.unit, track.group, track.axis
            ),
            &track.errors,
        ));
        files.push((
            format!("refresh-interval-{}-{}", track.group, track.axis),
            format!(
                "ticks between fresh measurements, {} {}",
                track.group, track.axis
            ),
            &track.refresh,
        ));
    }
    files
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::group_client::AxisRec;
    use motion_ipc::GroupState;

    fn frame(tick: u64, desired: f64, position: f64, refresh: u64) -> FrameRec {
        FrameRec {
            tick,
            time_ns: 0,
            publish_ns: 0,
            axes: vec![AxisRec {
                position,
                desired,
                refresh,
                ..AxisRec::default()
            }],
            groups: vec![GroupState::IDLE],
        }
    }

    #[test]
    fn the_best_shift_finds_a_measurement_that_follows_late() {
        // desired: a ramp from tick 100; measured: the same ramp 40 ticks later, sampled
        // every 10 ticks.
        let ramp = |tick: u64| tick.saturating_sub(100) as f64 * 0.01;
        let frames: Vec<FrameRec> = (0..1000)
            .map(|t| frame(t, ramp(t), ramp(t.saturating_sub(40)), t - t % 10))
            .collect();
        let samples: Vec<(u64, f64)> = (0..100_u64)
            .map(|n| (n * 10, ramp((n * 10).saturating_sub(40))))
            .collect();
        let (lag, rms) = best_shift(&frames, 0, &samples);
        assert_eq!(lag, Some(40));
        assert!(rms < 1e-9, "{rms}");
        assert_eq!(best_shift(&frames, 0, &[]), (None, 0.0));
    }

    #[test]
    fn the_sim_config_is_renamed_and_keeps_its_groups() {
        let rt = ServerRt {
            priority: Some(80),
            cpu: Some(1),
        };
        let text = config_text("bench-x", 500, rt).expect("sim.toml has its keys");
        assert!(text.contains("name = \"bench-x\""));
        assert!(text.contains("tick_hz = 500"));
        assert!(text.contains("[server]\nrt_priority = 80\ncpu = 1\n"));
        assert!(text.contains("name = \"base\""));
        assert!(!text.contains("name = \"demo\""));
    }
}
