//! Arrival skew of a group move: three lines of the gantry (x on the SIXpack, feeder on
//! the QSB-M, lift on the QuadQuad2Drv) back and forth; per move the tick at which each
//! axis's measurement came within its goal tolerance of its target and stayed (as `motionctl
//! group move --json` reports `arrived_tick`), spread max − min. Baseline: the same axes
//! between the same ends by single-axis `RampPosition` at their own limits, sent back to
//! back (unsynchronised).

use core::time::Duration;

use motion_ipc::{CommandKind, Target};

use crate::dist::Dist;
use crate::group_client::{FrameRec, GroupClient, GroupDesc, Watch};
use crate::report::{Row, Unit};

/// Ticks watched after a move ended, for the "and stayed" of an arrival.
const SETTLE_TICKS: u64 = 200;

/// The arrivals of one move.
#[derive(Debug, Clone)]
pub struct Move {
    /// The tick the move began in (the `Run`, or the first `RampPosition`, applied).
    pub start: u64,
    /// Per axis, the group's order: the tick its measurement came within its goal
    /// tolerance and stayed.
    pub arrived: Vec<u64>,
    /// Ticks between the first and the last command applied (0 for a group's line).
    pub start_spread: u64,
}

impl Move {
    fn spread(&self) -> u64 {
        let max = self.arrived.iter().max().copied().unwrap_or(0);
        let min = self.arrived.iter().min().copied().unwrap_or(0);
        max - min
    }
}

/// The arrival figures of the gantry's lines and of their baseline.
#[derive(Debug, Clone)]
pub struct SkewRun {
    /// The gantry's lines.
    pub lines: Vec<Move>,
    /// The same ends by single-axis ramps.
    pub ramps: Vec<Move>,
    /// The gantry's axes, the group's order.
    pub axes: Vec<String>,
    /// Their moves' lengths, their units.
    pub deltas: Vec<f64>,
}

/// How far the gantry's lines go, per axis by name (its unit), at full length. The lift
/// (10 mm/s) sets the line's pace; x then peaks near 10 mm/s, where the pack follows well
/// within its path tolerance (5 mm: at 20 mm/s, a 30 mm line, it came within 0.4 mm of
/// aborting, and once aborted at 5.1 mm).
fn delta(axis: &str) -> f64 {
    match axis {
        "feeder" => 30.0,
        "x" | "lift" => 15.0,
        _ => 10.0,
    }
}

/// The arrival tick of each axis: the refresh tick at which its measurement came within
/// `tolerance` of `targets` and stayed, over `frames`.
fn arrivals(frames: &[FrameRec], targets: &[f64], tolerance: &[f64]) -> Vec<Option<u64>> {
    let mut arrived = vec![None; targets.len()];
    for frame in frames {
        for (slot, value) in arrived.iter_mut().enumerate() {
            let axis = frame.axes[slot];
            if (axis.position - targets[slot]).abs() <= tolerance[slot] {
                value.get_or_insert(axis.refresh);
            } else {
                *value = None;
            }
        }
    }
    arrived
}

/// Three gantry lines back and forth, then the same ends by single-axis ramps.
pub fn run(
    client: &mut GroupClient,
    gantry: &GroupDesc,
    duration: Duration,
) -> Result<SkewRun, String> {
    let scale = (duration.as_secs_f64() / 10.0).clamp(0.25, 1.0);
    let deltas: Vec<f64> = gantry.axes.iter().map(|a| delta(&a.name) * scale).collect();
    let watch = Watch {
        axes: gantry.axes.iter().map(|a| a.index).collect(),
        groups: vec![gantry.index],
    };
    let mut frames = Vec::new();
    client.frames_for(&watch, &mut frames, 20)?;
    let start: Vec<f64> = frames
        .last()
        .ok_or("no frame")?
        .axes
        .iter()
        .map(|a| a.position)
        .collect();
    let away: Vec<f64> = start.iter().zip(&deltas).map(|(s, d)| s + d).collect();
    let tolerance = &gantry.goal_tolerance;
    let mut lines = Vec::new();
    for (n, targets) in [&away, &start, &away].into_iter().enumerate() {
        let mut frames = Vec::new();
        let index = gantry.index;
        let (id, tick) = client.run_path(index, &|path, id| {
            path.set_line(
                u32::try_from(index).unwrap_or(u32::MAX),
                id,
                targets,
                (1.0, 1.0),
            );
        })?;
        let what = format!("gantry line {}", n + 1);
        let ids = [(0, id, gantry)];
        client.wait_done(&watch, &mut frames, &ids, Duration::from_secs(15), &what)?;
        client.frames_for(&watch, &mut frames, SETTLE_TICKS)?;
        let from = frames.partition_point(|f| f.tick < tick);
        lines.push(arrived(
            &what,
            gantry,
            tick,
            0,
            &arrivals(&frames[from..], targets, tolerance),
        )?);
    }
    let mut ramps = Vec::new();
    for (n, targets) in [&start, &away, &start].into_iter().enumerate() {
        let mut frames = Vec::new();
        let mut ticks = Vec::new();
        for (slot, axis) in gantry.axes.iter().enumerate() {
            let index = u32::try_from(axis.index).unwrap_or(u32::MAX);
            let values = [targets[slot], 0.0, 0.0];
            let reply = client.accepted(Target::Axis, index, CommandKind::RampPosition, values)?;
            ticks.push(reply.tick_applied);
        }
        let what = format!("single-axis ramps {}", n + 1);
        let mut last = String::new();
        client
            .pump(
                &watch,
                &mut frames,
                Duration::from_secs(15),
                &what,
                |frame| {
                    if let Some(axis) = frame.axes.iter().find(|a| a.fault != 0) {
                        return Err(format!("{what}: an axis faulted (fault {})", axis.fault));
                    }
                    let waiting: Vec<String> = frame
                        .axes
                        .iter()
                        .enumerate()
                        .filter(|(slot, a)| (a.position - targets[*slot]).abs() > tolerance[*slot])
                        .map(|(slot, a)| {
                            format!(
                                "{} at {} (target {}, mode {})",
                                gantry.axes[slot].name, a.position, targets[slot], a.mode
                            )
                        })
                        .collect();
                    last = waiting.join(", ");
                    Ok(waiting.is_empty())
                },
            )
            .map_err(|e| format!("{e}: {last}"))?;
        client.frames_for(&watch, &mut frames, SETTLE_TICKS)?;
        let first = ticks.iter().min().copied().unwrap_or(0);
        let last = ticks.iter().max().copied().unwrap_or(0);
        let from = frames.partition_point(|f| f.tick < first);
        ramps.push(arrived(
            &what,
            gantry,
            first,
            last - first,
            &arrivals(&frames[from..], targets, tolerance),
        )?);
    }
    Ok(SkewRun {
        lines,
        ramps,
        axes: gantry.axes.iter().map(|a| a.name.clone()).collect(),
        deltas,
    })
}

fn arrived(
    what: &str,
    gantry: &GroupDesc,
    start: u64,
    start_spread: u64,
    arrivals: &[Option<u64>],
) -> Result<Move, String> {
    let arrived = arrivals
        .iter()
        .zip(&gantry.axes)
        .map(|(tick, axis)| {
            tick.ok_or_else(|| {
                format!(
                    "{what}: axis `{}` did not stay within its goal tolerance",
                    axis.name
                )
            })
        })
        .collect::<Result<Vec<u64>, String>>()?;
    Ok(Move {
        start,
        arrived,
        start_spread,
    })
}

fn spreads(moves: &[Move]) -> Dist {
    let mut dist = Dist::new();
    for m in moves {
        dist.record_count(m.spread());
    }
    dist
}

fn describe_moves(moves: &[Move], axes: &[String]) -> String {
    moves
        .iter()
        .map(|m| {
            let each: Vec<String> = axes
                .iter()
                .zip(&m.arrived)
                .map(|(name, tick)| format!("{name} +{}", tick.saturating_sub(m.start)))
                .collect();
            format!("{} t ({})", m.spread(), each.join(", "))
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The row: arrival spread per move beside the single-axis ramps'.
pub fn row(run: &SkewRun, server: &str) -> Row {
    let deltas: Vec<String> = run
        .axes
        .iter()
        .zip(&run.deltas)
        .map(|(name, d)| format!("{name} {d:.1}"))
        .collect();
    let start_spreads: Vec<String> = run
        .ramps
        .iter()
        .map(|m| m.start_spread.to_string())
        .collect();
    Row {
        figure: format!(
            "arrival skew of a gantry line ({}): max − min over the axes of the tick each came \
             within its goal tolerance and stayed, per move",
            run.axes.join(", ")
        ),
        unit: Unit::Ticks,
        ours: spreads(&run.lines).summary(),
        baseline: Some(spreads(&run.ramps).summary()),
        baseline_label: "the same axes between the same ends by single-axis RampPosition at \
                         their own max_velocity and max_accel, sent back to back (unsynchronised)"
            .to_owned(),
        note: format!(
            "{} moves each way, back and forth by {} (the group's goal_tolerance; arrival = the \
             refresh tick of the measurement); {server}; lines: {}; ramps: {} (commands applied \
             {} ticks apart)",
            run.lines.len(),
            deltas.join(", "),
            describe_moves(&run.lines, &run.axes),
            describe_moves(&run.ramps, &run.axes),
            start_spreads.join("/"),
        ),
    }
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
    fn an_arrival_is_the_last_entry_within_tolerance() {
        let frames: Vec<FrameRec> = [(0, 5.0), (1, 0.05), (2, 0.5), (3, 0.02), (4, 0.0)]
            .iter()
            .map(|&(tick, position)| frame(tick, 0.0, position, tick))
            .collect();
        assert_eq!(arrivals(&frames, &[0.0], &[0.1]), vec![Some(3)]);
        assert_eq!(arrivals(&frames[..3], &[0.0], &[0.1]), vec![None]);
    }
}
