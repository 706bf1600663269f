//! What a black box snapshot of the engine's state costs the tick (docs/BLACKBOX.md):
//! `cargo run --release -p motion-blackbox --example snapshot_cost [CONFIG]`. Serializes the
//! engine built from `config/sim.toml` (or CONFIG) into a buffer sized as motiond sizes it,
//! 2000 times, and a group path holding the longest trajectory (1024 points on 3 axes, the
//! gantry's), and prints the bytes and the time per snapshot (p50, p99, max).

use std::path::PathBuf;
use std::time::Instant;

use motion_config::ServerConfig;
use motion_engine::Engine;
use motion_trajectory::{AxisLimits, Path, Points, Tolerances};

fn figures(label: &str, bytes: usize, mut ns: Vec<u64>) {
    ns.sort_unstable();
    let at = |q: f64| ns[((ns.len() - 1) as f64 * q) as usize] as f64 / 1000.0;
    println!(
        "{label}: {bytes} bytes, p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs ({} snapshots)",
        at(0.5),
        at(0.99),
        at(1.0),
        ns.len()
    );
}

fn time_it<T: serde::Serialize>(value: &T, buf: &mut [u8], runs: usize) -> (usize, Vec<u64>) {
    let mut ns = Vec::with_capacity(runs);
    let mut len = 0;
    for _ in 0..runs {
        let start = Instant::now();
        len = postcard::to_slice(value, buf).expect("fits").len();
        ns.push(start.elapsed().as_nanos() as u64);
    }
    (len, ns)
}

fn main() -> anyhow::Result<()> {
    let path = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml"),
        PathBuf::from,
    );
    let config = ServerConfig::load(&path)?;
    let drivers = motion_config::boards::build(&config)?;
    let engine = Engine::new(config.engine_config(), drivers)?;
    let at_rest = postcard::to_allocvec(&engine)?.len();
    let mut buf = vec![0u8; 2 * at_rest + engine.snapshot_growth() + (64 << 10)];
    println!(
        "{}: snapshot buffer {} bytes ({} at start-up, twice, + {} for the groups' longest paths + 64 KiB)",
        path.display(),
        buf.len(),
        at_rest,
        engine.snapshot_growth()
    );
    let (len, ns) = time_it(&engine, &mut buf, 2000);
    figures("the engine at start-up", len, ns);

    let (axes, points) = (3, motion_ipc::MAX_PATH_POINTS);
    let mut longest = Path::new(axes, points);
    let times: Vec<f64> = (1..=points).map(|i| i as f64 * 0.01).collect();
    let positions: Vec<f64> = (0..points * axes)
        .map(|i| ((i / axes) as f64 * 0.01).sin() * (1 + i % axes) as f64)
        .collect();
    let limits = [AxisLimits {
        min: -1e3,
        max: 1e3,
        max_velocity: 1e3,
        max_accel: 1e5,
    }; 3];
    longest.plan_points(
        &[0.0; 3],
        &[0.0; 3],
        &[0.0; 3],
        &Points {
            times: &times,
            positions: &positions,
            velocities: None,
            accelerations: None,
            stride: axes,
        },
        &limits,
        &Tolerances {
            start: &[1e-6; 3],
            path: &[0.0; 3],
        },
    )?;
    let mut buf = vec![0u8; longest.serialized_bound()];
    let (len, ns) = time_it(&longest, &mut buf, 2000);
    figures("one group's path, 1024 points on 3 axes", len, ns);
    Ok(())
}
