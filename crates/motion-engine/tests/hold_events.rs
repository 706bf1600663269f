//! An axis's own hold and resume (`Hold` / `Resume` with `Target::Axis`), and the events
//! of capture and trigger signals, tick by tick on ideal boards with a fake clock.

mod support;

use std::sync::{Arc, Mutex};

use motion_drivers::{GoalKind, LinkKind, Pin, SignalKind};
use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig, SignalConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, CommandRequest, Reason, SignalFlags};
use support::*;

/// One ideal board with two axes (`x`, `y`, 100 counts/mm), taking `goals`, and `signals`.
fn rig(goals: &[GoalKind], signals: Vec<SignalConfig>) -> (Harness, Arc<Mutex<BoardControl>>) {
    let config = EngineConfig {
        name: "hold".into(),
        links: vec![BusConfig {
            name: "bus".into(),
            kind: LinkKind::Stream,
        }],
        devices: vec![DeviceConfig {
            name: "board".into(),
            link: 0,
            address: 1,
        }],
        axes: vec![axis("x", 0, 0), axis("y", 0, 1)],
        signals,
        ..EngineConfig::default()
    };
    let (board, control) = IdealBoard::boxed(2, goals);
    let engine = Engine::new(config, vec![board]).expect("valid config");
    let mut harness = Harness::new(engine);
    harness.ticks(3);
    (harness, control)
}

fn hold(h: &mut Harness, axis: u32) -> Result<(), Reason> {
    h.command(CLIENT_A, axis, CommandKind::Hold, [0.0; 3])
        .result()
}

fn resume(h: &mut Harness, axis: u32) -> Result<(), Reason> {
    h.command(CLIENT_A, axis, CommandKind::Resume, [0.0; 3])
        .result()
}

/// Ticks until axis 0 stands still; the ticks it took.
fn until_still(h: &mut Harness) -> usize {
    for tick in 0..5000 {
        h.tick();
        if h.axis(0).velocity == 0.0 && !h.axis(0).flags().contains(AxisFlags::MOVING) {
            return tick;
        }
    }
    panic!("never came to rest: {:?}", h.axis(0));
}

#[test]
fn a_ramp_held_by_the_engine_stops_at_its_acceleration_and_resumes_to_its_target() {
    // A board without a pause of its own: the engine stops the ramp and sends it again.
    let (mut h, board) = rig(&ALL_GOALS, Vec::new());
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::RampPosition, [60.0, 20.0, 100.0])
            .result(),
        Ok(())
    );
    h.ticks(400);
    let before = h.axis(0);
    assert!(before.velocity > 19.0, "at speed: {before:?}");
    assert_eq!(hold(&mut h, 0), Ok(()));
    let state = h.axis(0);
    assert_eq!(state.mode(), Ok(AxisMode::Stopping));
    assert!(state.flags().contains(AxisFlags::HELD), "{state:?}");
    // At the ramp's 100 mm/s² (not max_accel's 500): 20 mm/s takes 200 ms.
    let ticks = until_still(&mut h);
    assert!((180..=220).contains(&ticks), "stopped in {ticks} ticks");
    h.ticks(5);
    let held = h.axis(0);
    assert_eq!(held.mode(), Ok(AxisMode::Hold));
    assert!(held.flags().contains(AxisFlags::HELD));
    assert!(held.position < 60.0 - 1.0, "short of the target: {held:?}");
    assert_eq!(held.target, held.position, "holds where it came to rest");
    assert_eq!(hold(&mut h, 0), Ok(()), "a second hold changes nothing");
    h.ticks(50);
    assert_eq!(h.axis(0).position, held.position);
    assert_eq!(resume(&mut h, 0), Ok(()));
    let state = h.axis(0);
    assert_eq!(state.mode(), Ok(AxisMode::RampPosition));
    assert_eq!(state.target, 60.0);
    assert!(!state.flags().contains(AxisFlags::HELD));
    h.ticks(3000);
    let state = h.axis(0);
    assert!(state.flags().contains(AxisFlags::ARRIVED), "{state:?}");
    assert!((state.position - 60.0).abs() < 0.01);
    assert_eq!(resume(&mut h, 0), Err(Reason::NotMoving), "nothing held");
    assert_eq!(board.lock().unwrap().paused, 0, "the board never paused");
}

#[test]
fn a_board_that_pauses_its_own_move_is_asked_to_and_resumes_it() {
    let (mut h, board) = rig(&ALL_GOALS, Vec::new());
    board.lock().unwrap().pauses = true;
    h.command(CLIENT_A, 0, CommandKind::RampPosition, [60.0, 20.0, 100.0]);
    h.ticks(400);
    let wire_before = board.lock().unwrap().wire.len();
    assert_eq!(hold(&mut h, 0), Ok(()));
    until_still(&mut h);
    h.ticks(5);
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Hold));
    assert_eq!(resume(&mut h, 0), Ok(()));
    h.ticks(3000);
    let state = h.axis(0);
    assert!((state.position - 60.0).abs() < 0.01, "{state:?}");
    let control = board.lock().unwrap();
    assert_eq!((control.paused, control.resumed), (1, 1));
    assert_eq!(
        control.wire.len(),
        wire_before,
        "no goal went out: the board's own"
    );
}

#[test]
fn what_is_not_a_position_move_on_its_way_is_not_held() {
    let (mut h, _) = rig(&ALL_GOALS, Vec::new());
    assert_eq!(hold(&mut h, 0), Err(Reason::NotMoving), "holding");
    h.command(CLIENT_A, 0, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    h.tick();
    assert_eq!(hold(&mut h, 0), Err(Reason::NotMoving), "a jog: stop it");
    h.command(CLIENT_A, 0, CommandKind::Stop, [0.0; 3]);
    h.ticks(100);
    // A move held, then stopped: the stop forgets it.
    h.command(CLIENT_A, 0, CommandKind::RampPosition, [50.0, 0.0, 0.0]);
    h.ticks(100);
    assert_eq!(hold(&mut h, 0), Ok(()));
    h.command(CLIENT_A, 0, CommandKind::Stop, [0.0; 3]);
    assert!(!h.axis(0).flags().contains(AxisFlags::HELD));
    h.ticks(200);
    assert_eq!(resume(&mut h, 0), Err(Reason::NotMoving));
    // Held, then a new goal: forgotten too.
    h.command(CLIENT_A, 0, CommandKind::RampPosition, [-20.0, 0.0, 0.0]);
    h.ticks(50);
    assert_eq!(hold(&mut h, 0), Ok(()));
    h.command(CLIENT_A, 0, CommandKind::RampPosition, [0.0, 0.0, 0.0]);
    assert_eq!(resume(&mut h, 0), Err(Reason::NotMoving));
    // Held, then an e-stop and a reset: nothing resumes.
    h.ticks(500);
    h.command(CLIENT_A, 0, CommandKind::RampPosition, [40.0, 0.0, 0.0]);
    h.ticks(50);
    assert_eq!(hold(&mut h, 0), Ok(()));
    h.command(CLIENT_A, u32::MAX, CommandKind::EStop, [0.0; 3]);
    assert_eq!(resume(&mut h, 0), Err(Reason::EstopLatched));
    h.command(CLIENT_A, u32::MAX, CommandKind::Reset, [0.0; 3]);
    assert_eq!(resume(&mut h, 0), Err(Reason::NotMoving));
    // Another client's claim refuses both.
    h.command(CLIENT_B, 1, CommandKind::Claim, [0.0; 3]);
    assert_eq!(hold(&mut h, 1), Err(Reason::ClaimedByOther));
}

#[test]
fn a_position_goal_that_arrived_is_not_held() {
    let (mut h, _) = rig(&ALL_GOALS, Vec::new());
    // The ideal board's controller is at a Position target in the tick it gets it.
    h.command(CLIENT_A, 0, CommandKind::Position, [30.0, 0.0, 0.0]);
    h.tick();
    assert_eq!(hold(&mut h, 0), Err(Reason::NotMoving));
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Position));
}

#[test]
fn an_axis_without_a_position_move_cannot_hold() {
    let (mut h, _) = rig(
        &[GoalKind::Stop, GoalKind::Velocity, GoalKind::SetPosition],
        Vec::new(),
    );
    assert_eq!(hold(&mut h, 0), Err(Reason::Unsupported));
    let info = {
        let mut info = Box::new(motion_ipc::ServerInfo::EMPTY);
        h.engine.fill_info(&mut info);
        info.axes[0]
    };
    let caps = motion_ipc::Capabilities(info.capabilities);
    assert!(!caps.supports(CommandKind::Hold) && !caps.supports(CommandKind::Resume));
}

fn event_signals() -> Vec<SignalConfig> {
    let signal = |name: &str, pin: u16, kind: SignalKind| SignalConfig {
        name: name.into(),
        unit: "mm".into(),
        device: 0,
        pin: Pin(pin),
        pin_name: format!("p{pin}"),
        kind,
        invert: false,
        scale: 0.01,
        offset: 0.0,
        full_scale: 2_147_483_647.0,
        safe: None,
    };
    vec![
        signal("probe", 3, SignalKind::Capture),
        signal("camera", 4, SignalKind::Trigger),
    ]
}

fn set_value(h: &mut Harness, signal: u32, value: f64) -> Result<(), Reason> {
    h.sequence += 1;
    let request = CommandRequest::for_signal(CLIENT_A, h.sequence, signal, CommandKind::SetOutput)
        .with_values([value, 0.0, 0.0]);
    h.port.requests.push_back(request);
    h.tick();
    h.port.replies.pop().expect("answered").result()
}

#[test]
fn captures_show_with_their_tick_and_a_sequence_that_counts_missed_ones() {
    let (mut h, board) = rig(&ALL_GOALS, event_signals());
    let probe = h.frame.signals[0];
    assert_eq!((probe.sequence, probe.event_tick), (0, 0));
    assert_eq!(probe.kind, SignalKind::Capture as u8);
    // A capture reported between ticks: the next tick takes it in.
    {
        let mut control = board.lock().unwrap();
        control.inputs[3] = 1234.0;
        control.events[3] = 1;
    }
    h.tick();
    let probe = h.frame.signals[0];
    let tick = h.frame.tick;
    assert_eq!((probe.sequence, probe.event_tick), (1, tick));
    assert!(
        (probe.value - 12.34).abs() < 1e-12,
        "counts × scale: {probe:?}"
    );
    assert_eq!(probe.raw, 1234.0);
    h.ticks(5);
    assert_eq!(h.frame.signals[0].event_tick, tick, "no new event");
    // Two captures before the engine looks: one step of two, the newer value.
    {
        let mut control = board.lock().unwrap();
        control.inputs[3] = -50.0;
        control.events[3] = 3;
    }
    h.tick();
    let probe = h.frame.signals[0];
    assert_eq!(probe.events_since(1), 2, "a client that saw 1 missed one");
    assert_eq!((probe.sequence, probe.event_tick), (3, h.frame.tick));
    assert_eq!(probe.value, -0.5);
    // The driver's count wraps at 2^32: the sequence goes on.
    board.lock().unwrap().events[3] = 2;
    h.tick();
    assert_eq!(h.frame.signals[0].sequence, 2, "u32::MAX more: wraps to 2");
}

#[test]
fn a_trigger_s_compare_position_is_set_in_its_unit_and_its_pulses_are_events() {
    let (mut h, board) = rig(&ALL_GOALS, event_signals());
    board.lock().unwrap().values[4] = Some(5000.0);
    h.tick();
    assert_eq!(h.frame.signals[1].value, 50.0, "5000 counts at 0.01 mm");
    assert_eq!(set_value(&mut h, 1, 62.5), Ok(()));
    assert_eq!(board.lock().unwrap().values[4], Some(6250.0));
    h.tick();
    let camera = h.frame.signals[1];
    assert_eq!(camera.value, 62.5);
    assert!(!camera.flags().contains(SignalFlags::PENDING));
    assert_eq!(set_value(&mut h, 1, 1e12), Err(Reason::OutOfRange));
    assert_eq!(
        set_value(&mut h, 0, 1.0),
        Err(Reason::NotAnOutput),
        "a capture"
    );
    board.lock().unwrap().events[4] = 1;
    h.tick();
    let camera = h.frame.signals[1];
    assert_eq!((camera.sequence, camera.event_tick), (1, h.frame.tick));
}
