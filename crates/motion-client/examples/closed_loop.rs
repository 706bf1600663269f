//! A controller that closes its loop through motiond every tick: it streams a sine in
//! velocity mode to the group `base` (wheel_left, wheel_right: ±20 deg/s, period 1.5 s;
//! the right wheel mirrored, so the base turns on the spot), reading each frame and sending
//! the setpoint for the tick the stream's lead ahead (`DEFAULT_STREAM_LEAD`). At the end it
//! compares what it sent with what the server counted, and exits non-zero unless every
//! setpoint was applied exactly once or dropped as `late` (it reached the server more than
//! `stream_buffer` ticks after its tick: this client was descheduled that long), none before
//! its tick, none clamped; one applied after its tick made the stream run that much behind
//! (`delay`), which the check reports.
//!
//! Run the server first (`cargo run --release`: config/sim.toml, server name `demo`), then
//! `cargo run --release -p motion-client --example closed_loop -- [SERVER] [SECONDS]`
//! (defaults: `demo`, 5 s).

use core::f64::consts::TAU;
use core::ops::ControlFlow;
use core::time::Duration;
use std::process::ExitCode;

use iceoryx2::prelude::ipc;
use motion_client::Client;
use motion_client::ipc::{StreamFlags, StreamMode};

/// Velocity amplitude, deg/s.
const AMPLITUDE: f64 = 20.0;
/// Period of the sine, s.
const PERIOD: f64 = 1.5;
/// How many recent setpoints the check remembers (by sequence number).
const REMEMBERED: usize = 256;

/// What the frames the client read said about the setpoints applied in their ticks.
#[derive(Debug, Default)]
struct Seen {
    frames: u64,
    /// Setpoints applied in the tick they were for.
    on_time: u64,
    /// Applied in a later tick (the stream's delay: one of them arrived after its tick).
    after: u64,
    /// Applied before their tick: must never happen.
    before: u64,
    /// The tick of the last frame read, and the longest gap between two frames read.
    last_frame: u64,
    longest_gap: u64,
}

fn main() -> ExitCode {
    match run() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(error) => {
            eprintln!("closed_loop: {error}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<bool, Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let server = args.next().unwrap_or_else(|| "demo".to_owned());
    let seconds: f64 = match args.next() {
        Some(text) => text.parse()?,
        None => 5.0,
    };
    let client = Client::<ipc::Service>::connect(&server)?;
    let base = client.group("base")?;
    for axis in base.axis_handles() {
        axis.wait_ready(Duration::from_secs(30))?;
    }
    let axes = base.axes();
    if axes.len() != 2 {
        return Err(format!("group base has {} axes, not 2: {axes:?}", axes.len()).into());
    }
    let tick_hz = f64::from(client.info()?.tick_hz.max(1));
    let index = base.index() as usize;

    let mut stream = base.stream(StreamMode::Velocity)?;
    let start = stream.started_tick();
    println!(
        "streaming velocities to base ({}) from tick {start} for {seconds} s at {tick_hz} Hz",
        axes.join(", ")
    );
    // for_tick of each setpoint, by sequence number (the n-th call of the closure sends
    // sequence n, for its frame's tick + lead).
    let lead = stream.lead();
    let mut for_ticks = [0u64; REMEMBERED];
    let mut calls = 0u64;
    let mut seen = Seen::default();
    let run = stream.run_each_tick(
        Some(Duration::from_secs_f64(seconds)),
        |frame, velocities| {
            seen.frames += 1;
            if seen.last_frame > 0 {
                seen.longest_gap = seen.longest_gap.max(frame.tick - seen.last_frame);
            }
            seen.last_frame = frame.tick;
            if let Some(state) = frame.groups().get(index)
                && state.stream_flags().contains(StreamFlags::APPLIED)
                && state.last_sequence > calls.saturating_sub(REMEMBERED as u64)
            {
                let for_tick = for_ticks[(state.last_sequence % REMEMBERED as u64) as usize];
                match for_tick.cmp(&frame.tick) {
                    core::cmp::Ordering::Equal => seen.on_time += 1,
                    core::cmp::Ordering::Less => seen.after += 1,
                    core::cmp::Ordering::Greater => seen.before += 1,
                }
            }
            calls += 1;
            let for_tick = frame.tick + lead;
            for_ticks[(calls % REMEMBERED as u64) as usize] = for_tick;
            let t = (for_tick - start) as f64 / tick_hz;
            let v = AMPLITUDE * (TAU * t / PERIOD).sin();
            velocities[0] = v;
            velocities[1] = -v;
            ControlFlow::Continue(())
        },
    );
    let run = match run {
        Ok(run) => run,
        Err(error) => {
            println!(
                "stopped after {} frames read (longest gap {} ticks, last frame {}): {error}",
                seen.frames, seen.longest_gap, seen.last_frame
            );
            return Err(error.into());
        }
    };
    let status = stream.wait_caught_up(Duration::from_secs(2))?;
    let last_tick = run.last_tick.unwrap_or(start);
    println!(
        "sent {} setpoints for ticks {}..={last_tick} ({} ticks skipped by the client, {} seen \
         to miss their tick)",
        run.sent,
        run.first_tick.unwrap_or(start),
        run.skipped,
        run.behind
    );
    println!(
        "server: applied {}, late {}, early {}, refused {}, clamped {}; delay {} ticks; last \
         sequence {} applied in tick {} (stream {})",
        status.applied,
        status.late,
        status.early,
        status.refused,
        status.clamped,
        status.delay,
        status.last_sequence,
        status.last_applied_tick,
        status.state.name()
    );
    println!(
        "frames read: {} (longest gap {} ticks); setpoints applied in their own tick {}, \
         after it {}, before it {}",
        seen.frames, seen.longest_gap, seen.on_time, seen.after, seen.before
    );
    let mut failures = Vec::new();
    if status.applied + status.late != run.sent {
        failures.push(format!(
            "applied {} + late {} is not the {} setpoints sent",
            status.applied, status.late, run.sent
        ));
    }
    if status.early + status.refused + status.clamped > 0 {
        failures.push(format!(
            "early {}, refused {}, clamped {}: none expected",
            status.early, status.refused, status.clamped
        ));
    }
    if status.last_sequence != run.last_sequence {
        failures.push(format!(
            "the last setpoint applied is sequence {}, the last sent {}",
            status.last_sequence, run.last_sequence
        ));
    }
    if seen.before > 0 || status.last_applied_tick < last_tick {
        failures.push(format!(
            "applied before its tick: {} seen; the last one (for tick {last_tick}) in tick {}",
            seen.before, status.last_applied_tick
        ));
    }
    if status.last_applied_tick > last_tick {
        println!(
            "the last setpoint (for tick {last_tick}) was applied in tick {}: published after \
             the server had taken its tick's",
            status.last_applied_tick
        );
    }
    stream.cancel()?;
    if failures.is_empty() {
        if status.late == 0 {
            println!("ok: every setpoint sent was applied exactly once, none before its tick");
        } else {
            println!(
                "ok: every setpoint was applied once or dropped as late (more than stream_buffer \
                 ticks after its tick), none before its tick"
            );
        }
        Ok(true)
    } else {
        for failure in &failures {
            println!("FAILED: {failure}");
        }
        Ok(false)
    }
}
