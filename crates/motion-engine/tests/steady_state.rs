//! Determinism and zero allocation of `Engine::step` in steady state (ideal boards).
//!
//! The counting allocator counts allocations on the test's own thread only, so the test
//! harness and other tests running in parallel do not disturb the count.
mod support;

#[path = "../../../tests/support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CountingAllocator, allocations};
use motion_ipc::{CommandKind, CommandRequest};
use support::*;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// A scripted session: jogs, moves, a claim, an e-stop and a reset at fixed ticks.
fn script(tick: u64) -> Option<(u32, CommandKind, [f64; 3])> {
    match tick % 1000 {
        10 => Some((0, CommandKind::Velocity, [10.0, 0.0, 0.0])),
        20 => Some((
            2,
            CommandKind::RampPosition,
            [(tick % 7) as f64, 20.0, 100.0],
        )),
        100 => Some((1, CommandKind::Claim, [0.0; 3])),
        150 => Some((1, CommandKind::Power, [0.1, 0.0, 0.0])),
        300 => Some((0, CommandKind::Velocity, [f64::NAN, 0.0, 0.0])),
        400 => Some((u32::MAX, CommandKind::EStop, [0.0; 3])),
        500 => Some((u32::MAX, CommandKind::Reset, [0.0; 3])),
        600 => Some((1, CommandKind::Release, [0.0; 3])),
        700 => Some((3, CommandKind::RampVelocity, [-3.0, 50.0, 0.0])),
        _ => None,
    }
}

fn run(ticks: u64, harness: &mut Harness) {
    for tick in 0..ticks {
        if let Some((axis, kind, values)) = script(tick) {
            let request = CommandRequest::new(CLIENT_A, tick, axis, kind).with_values(values);
            harness.port.requests.push_back(request);
        }
        harness.tick();
    }
}

#[test]
fn step_allocates_nothing_in_steady_state() {
    let (engine, controls) = two_link_engine();
    for control in &controls {
        let mut control = control.lock().unwrap();
        control.wire.reserve(100_000);
        control.goals.reserve(100_000);
    }
    let mut harness = Harness::new(engine);
    harness.port.replies.reserve(100_000);
    harness.port.requests.reserve(16);
    // Warm-up: first ticks may touch lazily initialised state.
    run(1000, &mut harness);
    let before = allocations();
    run(10_000, &mut harness);
    let after = allocations();
    assert_eq!(
        after - before,
        0,
        "Engine::step allocated {} times",
        after - before
    );
    assert!(
        harness.port.replies.len() >= 90,
        "the script really ran commands"
    );
}

#[test]
fn same_inputs_give_byte_identical_frames() {
    let record = || {
        let (engine, _) = two_link_engine();
        let mut harness = Harness::new(engine);
        let mut frames = Vec::new();
        for tick in 0..3000u64 {
            if let Some((axis, kind, values)) = script(tick) {
                let request = CommandRequest::new(CLIENT_A, tick, axis, kind).with_values(values);
                harness.port.requests.push_back(request);
            }
            harness.tick();
            frames.push(format!("{:?}", harness.frame.axes()));
        }
        (frames, format!("{:?}", harness.port.replies))
    };
    let first = record();
    let second = record();
    assert_eq!(first.1, second.1);
    assert_eq!(first.0.len(), second.0.len());
    for (tick, (a, b)) in first.0.iter().zip(&second.0).enumerate() {
        assert_eq!(a, b, "frames differ at tick {tick}");
    }
}
