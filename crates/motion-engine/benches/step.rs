//! `Engine::step` cost versus axis count (4, 32, 128), with ideal boards so that the figure
//! is the engine's own work: command intake, safety, driver polling and frame writing.
//! Board drivers with real protocols are measured end to end by the root benches.

use core::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use motion_drivers::{Driver, LinkKind};
use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig};
use motion_ipc::{CommandKind, CommandRequest, MotionFrame};

#[path = "../tests/support/mod.rs"]
#[allow(unused_imports)]
mod support;

use support::{ALL_GOALS, CLIENT_A, IdealBoard, Queue, axis};

/// `axes` axes on ideal boards of 8 channels, 4 boards per link.
fn engine_with(axes: usize) -> Engine {
    let boards = axes.div_ceil(8);
    let links = boards.div_ceil(4);
    let config = EngineConfig {
        name: "bench".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: (0..links)
            .map(|l| BusConfig {
                name: format!("l{l}"),
                kind: LinkKind::Stream,
            })
            .collect(),
        devices: (0..boards)
            .map(|b| DeviceConfig {
                name: format!("b{b}"),
                link: b / 4,
                address: b as u32,
            })
            .collect(),
        axes: (0..axes)
            .map(|a| axis(&format!("a{a}"), a / 8, a % 8))
            .collect(),
        ..EngineConfig::default()
    };
    let drivers: Vec<Box<dyn Driver>> = (0..boards)
        .map(|_| IdealBoard::boxed(8, &ALL_GOALS).0)
        .collect();
    Engine::new(config, drivers).expect("valid bench config")
}

fn bench_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("engine_step");
    for axes in [4usize, 32, 128] {
        group.bench_with_input(BenchmarkId::from_parameter(axes), &axes, |b, &axes| {
            let mut engine = engine_with(axes);
            let mut frame = Box::new(MotionFrame::EMPTY);
            let mut port = Queue::default();
            let mut buf = [0u8; 256];
            let mut now = Duration::ZERO;
            let mut tick = 0u64;
            b.iter(|| {
                // One jog command per tick keeps command intake and driver traffic busy.
                let axis = (tick % axes as u64) as u32;
                let velocity = if tick.is_multiple_of(2) { 5.0 } else { -5.0 };
                port.requests.push_back(
                    CommandRequest::new(CLIENT_A, tick, axis, CommandKind::Velocity)
                        .with_values([velocity, 0.0, 0.0]),
                );
                engine.step(now, &mut port, &mut frame);
                for link in 0..engine.config().links.len() {
                    while engine.poll_link_transmit(link, now, &mut buf).is_some() {}
                }
                port.replies.clear();
                now += Duration::from_millis(1);
                tick += 1;
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
