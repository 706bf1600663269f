//! Supervision, readiness, stop categories, identity and signals, tick by tick on ideal
//! boards with a fake clock: each rule triggers, does not trigger within its tolerance,
//! latches, and a reset clears it only when its cause is gone.

mod support;

use core::time::Duration;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use motion_drivers::{GoalKind, LinkKind, Pin, SignalKind};
use motion_engine::{
    AxisConfig, BusConfig, CommandPort, DeviceConfig, Engine, EngineConfig, EstopCategory,
    SignalConfig,
};
use motion_ipc::{
    AxisFlags, AxisMode, ClientId, CommandKind, CommandReply, CommandRequest, DeviceState,
    FaultCode, Reason, SignalFlags,
};
use support::*;

/// Counts per unit of the test axes (`support::axis`).
const COUNTS: f64 = 100.0;

/// One ideal board with two channels (axes `x`, `y`) and the given signals.
fn rig(
    x: AxisConfig,
    y: AxisConfig,
    signals: Vec<SignalConfig>,
) -> (Harness, Arc<Mutex<BoardControl>>) {
    let config = EngineConfig {
        name: "supervision".into(),
        links: vec![BusConfig {
            name: "bus".into(),
            kind: LinkKind::Stream,
        }],
        devices: vec![DeviceConfig {
            name: "board".into(),
            link: 0,
            address: 1,
        }],
        axes: vec![x, y],
        signals,
        ..EngineConfig::default()
    };
    let (board, control) = IdealBoard::boxed(2, &ALL_GOALS);
    let engine = Engine::new(config, vec![board]).expect("valid config");
    let mut harness = Harness::new(engine);
    harness.ticks(3);
    (harness, control)
}

fn supervised(name: &str, channel: usize) -> AxisConfig {
    AxisConfig {
        following_error: 0.5,
        overspeed_factor: 1.5,
        ..axis(name, 0, channel)
    }
}

fn fault(h: &Harness, axis: usize) -> Option<FaultCode> {
    let state = h.axis(axis);
    state
        .flags()
        .contains(AxisFlags::FAULT)
        .then(|| state.fault().expect("known code"))
}

fn drift(board: &Arc<Mutex<BoardControl>>, channel: usize, units_per_s: f64) {
    board.lock().unwrap().drift[channel] = units_per_s * COUNTS;
}

/// Goal kinds put on the wire for `channel` since the last call.
fn wire(board: &Arc<Mutex<BoardControl>>, channel: u8) -> Vec<u8> {
    let mut control = board.lock().unwrap();
    let kinds = control
        .wire
        .iter()
        .filter(|(c, _)| *c == channel)
        .map(|(_, kind)| *kind)
        .collect();
    control.wire.retain(|(c, _)| *c != channel);
    kinds
}

const STOP: u8 = GoalKind::Stop as u8;
const OFF: u8 = GoalKind::Off as u8;

#[test]
fn a_held_axis_driven_away_faults_once_beyond_its_following_error_and_stops() {
    let (mut h, board) = rig(supervised("x", 0), axis("y", 0, 1), vec![]);
    assert_eq!(
        h.axis(0).mode(),
        Ok(AxisMode::Hold),
        "held after the start-up stop"
    );
    wire(&board, 0);
    drift(&board, 0, 1.0);
    h.ticks(400); // 0.4 units away: within the 0.5 tolerance
    assert_eq!(fault(&h, 0), None, "{:?}", h.axis(0));
    h.ticks(150);
    assert_eq!(fault(&h, 0), Some(FaultCode::FollowingError));
    let state = h.axis(0);
    assert!(
        state.fault_value > 0.5 && state.fault_value < 0.52,
        "{state:?}"
    );
    assert_eq!(state.fault_limit, 0.5);
    assert_eq!(wire(&board, 0), [STOP], "a stop (category hold) at once");
    assert_eq!(fault(&h, 1), None, "only the driven axis faults");
    // Latched: the cause going away does not clear it, a command is refused...
    drift(&board, 0, 0.0);
    h.ticks(20);
    assert_eq!(fault(&h, 0), Some(FaultCode::FollowingError));
    let refused = h.command(CLIENT_A, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::AxisFaulted));
    // ...until a reset, which holds where the axis is now.
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    h.ticks(50);
    assert_eq!(fault(&h, 0), None);
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Hold));
    assert!((h.axis(0).target - h.axis(0).position).abs() < 1e-9);
}

#[test]
fn a_move_that_leaves_its_segment_faults_and_a_clean_move_does_not() {
    let x = AxisConfig {
        overspeed_factor: 0.0,
        ..supervised("x", 0)
    };
    let (mut h, board) = rig(x, axis("y", 0, 1), vec![]);
    let accepted = h.command(CLIENT_A, 0, CommandKind::RampPosition, [10.0, 0.0, 0.0]);
    assert_eq!(accepted.result(), Ok(()));
    for _ in 0..2000 {
        h.tick();
        assert_eq!(fault(&h, 0), None, "{:?}", h.axis(0));
        if h.axis(0).flags().contains(AxisFlags::ARRIVED) {
            break;
        }
    }
    assert!(
        h.axis(0).flags().contains(AxisFlags::ARRIVED),
        "{:?}",
        h.axis(0)
    );
    h.ticks(500);
    assert_eq!(
        fault(&h, 0),
        None,
        "an arrived axis at rest stays fault free"
    );
    // The next move overshoots: the board pushes on faster than its ramp can brake.
    let accepted = h.command(CLIENT_A, 0, CommandKind::RampPosition, [20.0, 0.0, 0.0]);
    assert_eq!(accepted.result(), Ok(()));
    drift(&board, 0, 60.0);
    let mut faulted = None;
    for _ in 0..3000 {
        h.tick();
        if fault(&h, 0).is_some() {
            faulted = Some(h.axis(0));
            break;
        }
    }
    let state = faulted.expect("faulted");
    assert_eq!(state.fault(), Ok(FaultCode::FollowingError));
    assert!(state.position > 20.5 && state.position < 20.6, "{state:?}");
    assert!(
        state.fault_value > 0.5 && state.fault_value < 0.6,
        "{state:?}"
    );
}

#[test]
fn overspeed_needs_three_fresh_samples_above_the_factor_and_reset_needs_it_gone() {
    let x = AxisConfig {
        following_error: 0.0,
        overspeed_factor: 1.5,
        ..axis("x", 0, 0)
    };
    let (mut h, board) = rig(x, axis("y", 0, 1), vec![]);
    // 70 units/s: below 1.5 × 50.
    drift(&board, 0, 70.0);
    h.ticks(100);
    assert_eq!(fault(&h, 0), None);
    drift(&board, 0, 80.0);
    h.ticks(2);
    assert_eq!(fault(&h, 0), None, "two samples are not enough");
    h.tick();
    assert_eq!(fault(&h, 0), Some(FaultCode::Overspeed));
    assert_eq!((h.axis(0).fault_value, h.axis(0).fault_limit), (80.0, 75.0));
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    assert_eq!(fault(&h, 0), Some(FaultCode::Overspeed), "still too fast");
    drift(&board, 0, 0.0);
    h.ticks(5);
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    assert_eq!(fault(&h, 0), None);
}

#[test]
fn beyond_a_soft_limit_faults_and_only_moves_back_inside_are_taken_until_reset() {
    let (mut h, board) = rig(supervised("x", 0), axis("y", 0, 1), vec![]);
    let accepted = h.command(CLIENT_A, 0, CommandKind::RampPosition, [100.0, 50.0, 500.0]);
    assert_eq!(accepted.result(), Ok(()));
    assert!(h.engine.tick() < 10_000);
    for _ in 0..5000 {
        h.tick();
        if h.axis(0).flags().contains(AxisFlags::ARRIVED) {
            break;
        }
    }
    // Held at the limit (a stop: the board no longer corrects its position), then pushed.
    let stop = h.command(CLIENT_A, 0, CommandKind::Stop, [0.0; 3]);
    assert_eq!(stop.result(), Ok(()));
    h.ticks(5);
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Hold));
    drift(&board, 0, 1.0);
    h.ticks(400);
    assert_eq!(fault(&h, 0), None, "within the tolerance beyond the limit");
    h.ticks(200);
    assert_eq!(fault(&h, 0), Some(FaultCode::LimitExceeded));
    assert_eq!(h.axis(0).fault_limit, 100.0);
    drift(&board, 0, 0.0);
    h.ticks(20);
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    assert_eq!(fault(&h, 0), Some(FaultCode::LimitExceeded), "still beyond");
    let outward = h.command(CLIENT_A, 0, CommandKind::Velocity, [1.0, 0.0, 0.0]);
    assert_eq!(outward.result(), Err(Reason::OutOfRange), "further out");
    let home = h.command(CLIENT_A, 0, CommandKind::Home, [0.0; 3]);
    assert_eq!(
        home.result(),
        Err(Reason::AxisFaulted),
        "not a way back inside"
    );
    let back = h.command(CLIENT_A, 0, CommandKind::RampPosition, [50.0, 0.0, 0.0]);
    assert_eq!(back.result(), Ok(()), "a move back inside is taken");
    for _ in 0..5000 {
        h.tick();
        if (h.axis(0).position - 50.0).abs() < 0.01 && h.axis(0).velocity == 0.0 {
            break;
        }
    }
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    assert_eq!(fault(&h, 0), None);
}

#[test]
fn a_search_that_travels_too_far_fails_and_stops() {
    let x = AxisConfig {
        home_max_travel: 5.0,
        ..supervised("x", 0)
    };
    let (mut h, board) = rig(x, axis("y", 0, 1), vec![]);
    wire(&board, 0);
    let home = h.command(CLIENT_A, 0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert_eq!(home.result(), Ok(()));
    h.ticks(450); // 4.5 units at 10 units/s
    assert_eq!(fault(&h, 0), None);
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Homing));
    h.ticks(100);
    assert_eq!(fault(&h, 0), Some(FaultCode::HomeFailed));
    let state = h.axis(0);
    assert!(
        state.fault_value > 5.0 && state.fault_value < 5.1,
        "{state:?}"
    );
    assert_eq!(state.fault_limit, 5.0);
    assert_eq!(wire(&board, 0), [GoalKind::Home as u8, STOP]);
}

#[test]
fn e_stop_categories_hold_stop_then_off_and_off() {
    let x = AxisConfig {
        estop: EstopCategory::Hold,
        ..axis("x", 0, 0)
    };
    let y = AxisConfig {
        estop: EstopCategory::StopOff,
        ..axis("y", 0, 1)
    };
    let (mut h, board) = rig(x, y, vec![]);
    for axis in [0, 1] {
        let jog = h.command(CLIENT_A, axis, CommandKind::Velocity, [20.0, 0.0, 0.0]);
        assert_eq!(jog.result(), Ok(()));
    }
    h.ticks(100);
    wire(&board, 0);
    wire(&board, 1);
    let estop = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::EStop,
        [0.0; 3],
    );
    assert_eq!(estop.result(), Ok(()));
    h.ticks(200);
    assert_eq!(wire(&board, 0), [STOP], "category 2: decelerate and hold");
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Hold));
    assert_eq!(
        wire(&board, 1),
        [STOP, OFF],
        "category 1: stop, then off at rest"
    );
    assert_eq!(h.axis(1).mode(), Ok(AxisMode::Off));

    let x = AxisConfig {
        estop: EstopCategory::Off,
        ..axis("x", 0, 0)
    };
    let (mut h, board) = rig(x, axis("y", 0, 1), vec![]);
    let jog = h.command(CLIENT_A, 0, CommandKind::Velocity, [20.0, 0.0, 0.0]);
    assert_eq!(jog.result(), Ok(()));
    h.ticks(50);
    wire(&board, 0);
    let estop = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::EStop,
        [0.0; 3],
    );
    assert_eq!(estop.result(), Ok(()));
    assert_eq!(wire(&board, 0), [OFF], "category 0: off at once");
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Off));
}

#[test]
fn off_de_energises_claims_apply_and_shutdown_stops_every_axis() {
    let (mut h, board) = rig(axis("x", 0, 0), axis("y", 0, 1), vec![]);
    wire(&board, 0);
    let off = h.command(CLIENT_A, 0, CommandKind::Off, [0.0; 3]);
    assert_eq!(off.result(), Ok(()));
    assert_eq!(wire(&board, 0), [OFF]);
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Off));
    let claim = h.command(CLIENT_A, 1, CommandKind::Claim, [0.0; 3]);
    assert_eq!(claim.result(), Ok(()));
    let off = h.command(CLIENT_B, 1, CommandKind::Off, [0.0; 3]);
    assert_eq!(off.result(), Err(Reason::ClaimedByOther));
    // Shutdown: the axis believed off is switched off again, the other stopped.
    wire(&board, 0);
    wire(&board, 1);
    h.engine.begin_shutdown();
    h.tick();
    assert_eq!(wire(&board, 0), [OFF]);
    assert_eq!(wire(&board, 1), [STOP]);
}

#[test]
fn goals_wait_for_a_starting_board_and_its_start_up_stop() {
    let config = EngineConfig {
        links: vec![BusConfig {
            name: "bus".into(),
            kind: LinkKind::Stream,
        }],
        devices: vec![DeviceConfig {
            name: "board".into(),
            link: 0,
            address: 1,
        }],
        axes: vec![axis("x", 0, 0)],
        ..EngineConfig::default()
    };
    let (board, control) = IdealBoard::boxed(1, &ALL_GOALS);
    control.lock().unwrap().starting = true;
    let mut h = Harness::new(Engine::new(config, vec![board]).expect("valid"));
    h.ticks(5);
    assert_eq!(h.frame.device_state(0), DeviceState::Starting);
    assert_eq!(h.axis(0).device_state(), Ok(DeviceState::Starting));
    let refused = h.command(CLIENT_A, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::DeviceStarting));
    control.lock().unwrap().starting = false;
    // The step that sees the board online sends the start-up stop and refuses goals.
    let refused = h.command(CLIENT_A, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::DeviceStarting));
    assert_eq!(control.lock().unwrap().wire, [(0, STOP)]);
    let accepted = h.command(CLIENT_A, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    assert_eq!(accepted.result(), Ok(()));
    assert_eq!(h.frame.device_state(0), DeviceState::Online);
}

/// A port whose transport knows the sender (as motiond's iceoryx2 port does).
#[derive(Default)]
struct Transport {
    requests: VecDeque<(CommandRequest, ClientId)>,
    current: ClientId,
    replies: Vec<CommandReply>,
}

impl CommandPort for Transport {
    fn next_request(&mut self) -> Option<CommandRequest> {
        let (request, sender) = self.requests.pop_front()?;
        self.current = sender;
        Some(request)
    }
    fn reply(&mut self, reply: CommandReply) {
        self.replies.push(reply);
    }
    fn sender(&self) -> Option<ClientId> {
        Some(self.current)
    }
}

#[test]
fn identity_comes_from_the_transport_and_claims_end_with_their_owner() {
    let (mut h, _) = rig(axis("x", 0, 0), axis("y", 0, 1), vec![]);
    let mut port = Transport::default();
    let mut send = |h: &mut Harness, sender: ClientId, request: CommandRequest| {
        port.requests.push_back((request, sender));
        h.engine.step(h.now, &mut port, &mut h.frame);
        h.now += PERIOD;
        port.replies.pop().expect("answered").result()
    };
    // A claims x, sending its own id (or none).
    let claim = CommandRequest::new(CLIENT_A, 1, 0, CommandKind::Claim);
    assert_eq!(send(&mut h, CLIENT_A, claim), Ok(()));
    assert_eq!(h.frame.axes[0].claimed_by, CLIENT_A);
    // B borrows A's id: refused, whatever it asks.
    for kind in [
        CommandKind::RampPosition,
        CommandKind::Release,
        CommandKind::Claim,
    ] {
        let forged = CommandRequest::new(CLIENT_A, 2, 0, kind).with_values([1.0, 0.0, 0.0]);
        assert_eq!(
            send(&mut h, CLIENT_B, forged),
            Err(Reason::IdentityMismatch),
            "{kind:?}"
        );
    }
    // An invented id cannot claim anything either.
    let invented = CommandRequest::new(ClientId::from_u128(0xDEAD_BEEF), 3, 1, CommandKind::Claim);
    assert_eq!(
        send(&mut h, CLIENT_B, invented),
        Err(Reason::IdentityMismatch)
    );
    // B with no id in the payload is B: claimed by another.
    let anonymous = CommandRequest::new(ClientId::NONE, 4, 0, CommandKind::RampPosition)
        .with_values([1.0, 0.0, 0.0]);
    assert_eq!(
        send(&mut h, CLIENT_B, anonymous),
        Err(Reason::ClaimedByOther)
    );
    // A leaves (its command port is gone): its claim ends.
    h.engine.release_claims_of(CLIENT_A);
    assert_eq!(send(&mut h, CLIENT_B, anonymous), Ok(()));
    // Another client's reset ends no claim: B keeps y, A's move is still refused, B's
    // running move goes on.
    let claim = CommandRequest::new(ClientId::NONE, 5, 1, CommandKind::Claim);
    assert_eq!(send(&mut h, CLIENT_B, claim), Ok(()));
    let reset = CommandRequest::new(
        ClientId::NONE,
        6,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
    );
    assert_eq!(send(&mut h, CLIENT_A, reset), Ok(()));
    assert_eq!(h.frame.axes[1].claimed_by, CLIENT_B);
    let a_moves = CommandRequest::new(ClientId::NONE, 7, 1, CommandKind::RampPosition)
        .with_values([1.0, 0.0, 0.0]);
    assert_eq!(send(&mut h, CLIENT_A, a_moves), Err(Reason::ClaimedByOther));
    let b_moves = CommandRequest::new(ClientId::NONE, 8, 1, CommandKind::RampPosition)
        .with_values([1.0, 0.0, 0.0]);
    assert_eq!(send(&mut h, CLIENT_B, b_moves), Ok(()));
    let reset = CommandRequest::new(
        ClientId::NONE,
        9,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
    );
    assert_eq!(send(&mut h, CLIENT_A, reset), Ok(()));
    assert_eq!(h.frame.axes[1].claimed_by, CLIENT_B);
    assert_eq!(
        h.frame.axes[1].mode(),
        Ok(motion_ipc::AxisMode::RampPosition),
        "a reset with nothing latched leaves a running goal alone"
    );
}

#[test]
fn claims_lapse_after_their_lease_unless_renewed() {
    let config = EngineConfig {
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
        claim_lease: Duration::from_millis(100),
        ..EngineConfig::default()
    };
    let (board, _) = IdealBoard::boxed(2, &ALL_GOALS);
    let mut h = Harness::new(Engine::new(config, vec![board]).expect("valid"));
    h.ticks(3);
    for axis in [0, 1] {
        assert_eq!(
            h.command(CLIENT_A, axis, CommandKind::Claim, [0.0; 3])
                .result(),
            Ok(())
        );
    }
    for _ in 0..3 {
        h.ticks(60);
        // Any command of the owner renews all of its claims.
        let stop = h.command(CLIENT_A, 0, CommandKind::Stop, [0.0; 3]);
        assert_eq!(stop.result(), Ok(()));
    }
    assert_eq!(h.frame.axes[1].claimed_by, CLIENT_A, "renewed");
    h.ticks(150);
    assert!(h.frame.axes[0].claimed_by.is_none(), "lapsed");
    assert!(h.frame.axes[1].claimed_by.is_none(), "lapsed");
}

fn signals() -> Vec<SignalConfig> {
    let signal = |name: &str, pin: u16, kind: SignalKind| SignalConfig {
        name: name.into(),
        unit: String::new(),
        device: 0,
        pin: Pin(pin),
        pin_name: format!("p{pin}"),
        kind,
        invert: false,
        scale: 1.0,
        offset: 0.0,
        full_scale: 1.0,
        safe: None,
    };
    vec![
        SignalConfig {
            invert: true,
            ..signal("door_closed", 0, SignalKind::DigitalIn)
        },
        SignalConfig {
            safe: Some(false),
            ..signal("gripper", 1, SignalKind::DigitalOut)
        },
        SignalConfig {
            unit: "V".into(),
            scale: 5.0 / 1023.0,
            offset: 0.0,
            full_scale: 1023.0,
            ..signal("pressure", 2, SignalKind::AnalogIn)
        },
    ]
}

fn set_output(h: &mut Harness, client: ClientId, signal: u32, on: bool) -> Result<(), Reason> {
    h.sequence += 1;
    let request = CommandRequest::for_signal(client, h.sequence, signal, CommandKind::SetOutput)
        .with_values([f64::from(u8::from(on)), 0.0, 0.0]);
    h.port.requests.push_back(request);
    h.tick();
    h.port.replies.pop().expect("answered").result()
}

#[test]
fn signals_read_inputs_drive_outputs_take_claims_and_go_safe_on_e_stop() {
    let (mut h, board) = rig(axis("x", 0, 0), axis("y", 0, 1), signals());
    {
        let mut control = board.lock().unwrap();
        control.inputs[0] = 0.0; // the switch pulls the (inverted) input low: closed
        control.inputs[2] = 512.0;
    }
    h.ticks(2);
    let [door, gripper, pressure] = [h.frame.signals[0], h.frame.signals[1], h.frame.signals[2]];
    assert_eq!(h.frame.signal_count, 3);
    assert_eq!((door.value, door.raw), (1.0, 0.0), "inverted");
    assert!(!door.flags().contains(SignalFlags::STALE));
    assert!((pressure.value - 512.0 * 5.0 / 1023.0).abs() < 1e-12);
    assert_eq!(gripper.value, 0.0);

    assert_eq!(set_output(&mut h, CLIENT_A, 1, true), Ok(()));
    assert_eq!(board.lock().unwrap().outputs[1], Some(true));
    h.tick();
    assert_eq!(h.frame.signals[1].value, 1.0);
    assert!(!h.frame.signals[1].flags().contains(SignalFlags::PENDING));
    assert_eq!(
        set_output(&mut h, CLIENT_A, 0, true),
        Err(Reason::NotAnOutput)
    );
    assert_eq!(
        set_output(&mut h, CLIENT_A, 7, true),
        Err(Reason::UnknownSignal)
    );

    // Claims, as for axes.
    h.sequence += 1;
    let claim = CommandRequest::for_signal(CLIENT_A, h.sequence, 1, CommandKind::Claim);
    h.port.requests.push_back(claim);
    h.tick();
    assert_eq!(h.port.replies.pop().unwrap().result(), Ok(()));
    assert_eq!(
        set_output(&mut h, CLIENT_B, 1, false),
        Err(Reason::ClaimedByOther)
    );

    // E-stop: the output takes its safe state; sets are refused until reset.
    let estop = h.command(
        CLIENT_B,
        CommandRequest::ALL_AXES,
        CommandKind::EStop,
        [0.0; 3],
    );
    assert_eq!(estop.result(), Ok(()));
    assert_eq!(board.lock().unwrap().outputs[1], Some(false));
    h.tick();
    assert!(h.frame.signals[1].flags().contains(SignalFlags::SAFE_STATE));
    assert_eq!(h.frame.signals[1].value, 0.0);
    assert_eq!(
        set_output(&mut h, CLIENT_A, 1, true),
        Err(Reason::EstopLatched)
    );
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    assert_eq!(
        set_output(&mut h, CLIENT_B, 1, true),
        Err(Reason::ClaimedByOther),
        "a reset ends no claim"
    );
    assert_eq!(set_output(&mut h, CLIENT_A, 1, true), Ok(()));
}

#[test]
fn a_board_back_online_switches_an_off_axis_off_again_and_stops_the_others() {
    let (mut h, board) = rig(axis("x", 0, 0), axis("y", 0, 1), vec![]);
    let off = h.command(CLIENT_A, 0, CommandKind::Off, [0.0; 3]);
    assert_eq!(off.result(), Ok(()));
    h.ticks(3);
    wire(&board, 0);
    wire(&board, 1);
    // The board drops out and comes back (a reboot, a glitch): it forgot everything.
    board.lock().unwrap().starting = true;
    h.ticks(3);
    board.lock().unwrap().starting = false;
    h.ticks(3);
    assert_eq!(wire(&board, 0), [OFF], "still meant to be off");
    assert_eq!(h.axis(0).mode(), Ok(AxisMode::Off));
    assert_eq!(wire(&board, 1), [STOP], "the start-up stop");
}
