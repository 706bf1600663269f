//! The engine's commissioning rules (`CommandKind::Commission` with `Target::Device`,
//! `crates/motion-engine/src/commission.rs`), stepped tick by tick with ideal boards and a
//! fake clock: refused for an unknown device, unless the client holds every claim of the
//! device, and while any of its axes moves; accepted otherwise, the device `Starting` in
//! that tick's frame and the change handed to its driver exactly once. And (issue 40 item
//! 8) refused while the e-stop is latched, and a line-rate change on a link other devices
//! share refused while one of them is in use, the reply naming it.

mod support;

use motion_drivers::{Commission, GoalKind, Pin, SignalKind};
use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig, SignalConfig};
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, CommissionWhat, DeviceState, Reason,
    Target,
};
use std::sync::{Arc, Mutex};
use support::*;

/// Sends a commission of device `device` from `client` in the next tick: a new address.
fn commission(h: &mut Harness, client: ClientId, device: u32, address: u32) -> CommandReply {
    commission_of(h, client, device, CommissionWhat::Address, address)
}

/// Sends a commission of `what` (to `value`) of device `device` from `client` in the next
/// tick.
fn commission_of(
    h: &mut Harness,
    client: ClientId,
    device: u32,
    what: CommissionWhat,
    value: u32,
) -> CommandReply {
    h.sequence += 1;
    let mut request = CommandRequest::new(client, h.sequence, device, CommandKind::Commission)
        .with_values([f64::from(what as u32), f64::from(value), 0.0]);
    request.target = Target::Device as u32;
    h.port.requests.push_back(request);
    h.tick();
    let reply = h.port.replies.pop().expect("every request is answered");
    assert_eq!(reply.sequence, h.sequence);
    reply
}

fn claim(h: &mut Harness, client: ClientId, axis: u32) {
    let reply = h.command(client, axis, CommandKind::Claim, [0.0; 3]);
    assert_eq!(reply.result(), Ok(()), "claim of axis {axis}");
}

#[test]
fn an_unknown_device_is_refused() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    for device in [2, 7, u32::MAX - 1] {
        let reply = commission(&mut h, CLIENT_A, device, 5);
        assert_eq!(
            reply.result(),
            Err(Reason::UnknownDevice),
            "device {device}"
        );
    }
    assert!(
        controls
            .iter()
            .all(|c| c.lock().unwrap().commissions.is_empty())
    );
}

#[test]
fn a_client_must_hold_every_claim_of_the_device() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    // Nothing claimed.
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Err(Reason::NotClaimed));
    // x claimed, y not: y is named.
    claim(&mut h, CLIENT_A, 0);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Err(Reason::NotClaimed));
    assert_eq!(reply.at_axis, 1);
    // y held by another client: it is named with its holder.
    claim(&mut h, CLIENT_B, 1);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!((reply.at_axis, reply.holder), (1, CLIENT_B));
    // Nor does the holder of only y.
    let reply = commission(&mut h, CLIENT_B, 0, 5);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!((reply.at_axis, reply.holder), (0, CLIENT_A));
    // Without a client id at all.
    let reply = commission(&mut h, ClientId::NONE, 0, 5);
    assert_eq!(reply.result(), Err(Reason::NoClientId));
    // Claims of the other device's axes do not count for this one.
    claim(&mut h, CLIENT_A, 2);
    claim(&mut h, CLIENT_A, 3);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert!(controls[0].lock().unwrap().commissions.is_empty());
    assert_eq!(h.frame.device_state(0), DeviceState::Online);
}

#[test]
fn a_commission_is_refused_while_an_axis_of_the_device_moves() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    claim(&mut h, CLIENT_A, 0);
    claim(&mut h, CLIENT_A, 1);
    // y ramps (50 mm at 50 mm/s, 500 mm/s²: over a second).
    let reply = h.command(CLIENT_A, 1, CommandKind::RampPosition, [50.0, 50.0, 500.0]);
    assert_eq!(reply.result(), Ok(()));
    h.ticks(100);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Err(Reason::GroupBusy));
    assert_eq!(reply.at_axis, 1, "the moving axis is named");
    assert!(h.axis(1).position > 1.0 && h.axis(1).position < 49.0);
    // Once y has arrived (and with `following_error` 0, supervision off, as these axes
    // have: the frame's ARRIVED, not supervision's, decides) it is accepted.
    h.ticks(1500);
    assert!((h.axis(1).position - 50.0).abs() < 0.01, "{:?}", h.axis(1));
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(
        controls[0].lock().unwrap().commissions,
        [Commission::Address(5)]
    );
}

#[test]
fn the_holder_of_every_claim_is_accepted_and_the_device_is_found_again() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    claim(&mut h, CLIENT_A, 0);
    claim(&mut h, CLIENT_A, 1);
    // z of the other board moves meanwhile: no matter.
    claim(&mut h, CLIENT_B, 2);
    let reply = h.command(CLIENT_B, 2, CommandKind::Position, [50.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    h.ticks(10);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Ok(()));
    // Starting in the frame of the tick that took it; the other device is untouched.
    assert_eq!(h.frame.device_state(0), DeviceState::Starting);
    assert_eq!(h.frame.device_state(1), DeviceState::Online);
    assert_eq!(
        controls[0].lock().unwrap().commissions,
        [Commission::Address(5)]
    );
    assert!(controls[1].lock().unwrap().commissions.is_empty());
    // The ideal board answers at once: online again at the next tick.
    h.ticks(2);
    assert_eq!(h.frame.device_state(0), DeviceState::Online);
}

/// Issue 40 item 8: a `$CC` (or any commission) re-parameterises a pack that is meant to
/// hold while the e-stop is latched. Refused with `EstopLatched` whatever the change, even
/// to the holder of every claim; accepted again after a reset.
#[test]
fn a_commission_is_refused_while_the_estop_is_latched() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    claim(&mut h, CLIENT_A, 0);
    claim(&mut h, CLIENT_A, 1);
    let estop = h.command(
        CLIENT_B,
        CommandRequest::ALL_AXES,
        CommandKind::EStop,
        [0.0; 3],
    );
    assert_eq!(estop.result(), Ok(()));
    h.ticks(5);
    for (what, value) in [
        (CommissionWhat::Address, 5),
        (CommissionWhat::Baud, 115_200),
        (CommissionWhat::FactoryReset, 0),
    ] {
        let reply = commission_of(&mut h, CLIENT_A, 0, what, value);
        assert_eq!(reply.result(), Err(Reason::EstopLatched), "{what:?}");
    }
    assert!(controls[0].lock().unwrap().commissions.is_empty());
    assert_eq!(h.frame.device_state(0), DeviceState::Online);
    let reset = h.command(
        CLIENT_A,
        CommandRequest::ALL_AXES,
        CommandKind::Reset,
        [0.0; 3],
    );
    assert_eq!(reset.result(), Ok(()));
    let reply = commission_of(&mut h, CLIENT_A, 0, CommissionWhat::FactoryReset, 0);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(
        controls[0].lock().unwrap().commissions,
        [Commission::FactoryReset]
    );
}

/// One link `bus0` shared by `board0` (x, y) and `board1` (z, w, and output `lamp`), and
/// `board2` (v) alone on `bus1`.
fn shared_link_engine() -> (Engine, Vec<Arc<Mutex<BoardControl>>>) {
    let config = EngineConfig {
        name: "test".into(),
        tick_hz: 1000,
        command_timeout: core::time::Duration::from_millis(250),
        links: vec![
            BusConfig {
                name: "bus0".into(),
                kind: motion_drivers::LinkKind::Stream,
            },
            BusConfig {
                name: "bus1".into(),
                kind: motion_drivers::LinkKind::Stream,
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
                link: 0,
                address: 2,
            },
            DeviceConfig {
                name: "board2".into(),
                link: 1,
                address: 1,
            },
        ],
        axes: vec![
            axis("x", 0, 0),
            axis("y", 0, 1),
            axis("z", 1, 0),
            axis("w", 1, 1),
            axis("v", 2, 0),
        ],
        signals: vec![SignalConfig {
            name: "lamp".into(),
            unit: String::new(),
            device: 1,
            pin: Pin(1),
            pin_name: "p1".into(),
            kind: SignalKind::DigitalOut,
            invert: false,
            scale: 1.0,
            offset: 0.0,
            full_scale: 1.0,
            safe: None,
        }],
        ..EngineConfig::default()
    };
    let goals: [GoalKind; 8] = ALL_GOALS;
    let (board0, control0) = IdealBoard::boxed(2, &goals);
    let (board1, control1) = IdealBoard::boxed(2, &goals);
    let (board2, control2) = IdealBoard::boxed(1, &goals);
    let engine = Engine::new(config, vec![board0, board1, board2]).expect("valid config");
    (engine, vec![control0, control1, control2])
}

fn signal_claim(h: &mut Harness, client: ClientId, signal: u32, kind: CommandKind) {
    h.sequence += 1;
    let request = CommandRequest::for_signal(client, h.sequence, signal, kind);
    h.port.requests.push_back(request);
    h.tick();
    let reply = h.port.replies.pop().expect("answered");
    assert_eq!(reply.result(), Ok(()), "{kind:?} of signal {signal}");
}

/// Issue 40 item 8: a line-rate change leaves the other boards of its link at the old rate
/// (unreachable until they are changed too: the datasheet issue's item 1). Until then it is
/// refused while another device on the link is in use, the reply naming the axis, the
/// claimant and the device (`value`): another client's claim on an axis or a signal of it,
/// a goal (a jog, a move not done — even the sender's own — or held), a moving axis. Idle
/// claims of the sender there, and anything on another link, do not hold it back.
#[test]
fn a_line_rate_change_on_a_shared_link_is_refused_while_a_neighbour_is_in_use() {
    let (engine, controls) = shared_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    claim(&mut h, CLIENT_A, 0);
    claim(&mut h, CLIENT_A, 1);
    let baud = |h: &mut Harness| commission_of(h, CLIENT_A, 0, CommissionWhat::Baud, 115_200);

    // Another client's claim on z of board1.
    claim(&mut h, CLIENT_B, 2);
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!(
        (reply.at_axis, reply.holder, reply.value),
        (2, CLIENT_B, 1.0)
    );
    // B's jog on z: a goal.
    let jog = h.command(CLIENT_B, 2, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    assert_eq!(jog.result(), Ok(()));
    h.ticks(20);
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Err(Reason::GroupBusy));
    assert_eq!(
        (reply.at_axis, reply.holder, reply.value),
        (2, CLIENT_B, 1.0)
    );
    let stop = h.command(CLIENT_B, 2, CommandKind::Stop, [0.0; 3]);
    assert_eq!(stop.result(), Ok(()));
    h.ticks(200);
    let release = h.command(CLIENT_B, 2, CommandKind::Release, [0.0; 3]);
    assert_eq!(release.result(), Ok(()));

    // Another client's claim on board1's output.
    signal_claim(&mut h, CLIENT_B, 0, CommandKind::Claim);
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!(
        (reply.at_axis, reply.holder, reply.value),
        (u32::MAX, CLIENT_B, 1.0)
    );
    signal_claim(&mut h, CLIENT_B, 0, CommandKind::Release);

    // The sender's own move on w, not done: refused too (w would be cut off mid-move).
    claim(&mut h, CLIENT_A, 3);
    let reply = h.command(CLIENT_A, 3, CommandKind::RampPosition, [50.0, 50.0, 500.0]);
    assert_eq!(reply.result(), Ok(()));
    h.ticks(100);
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Err(Reason::GroupBusy));
    assert_eq!((reply.at_axis, reply.value), (3, 1.0));
    assert!(controls[0].lock().unwrap().commissions.is_empty());

    // Held mid-move, at rest: a move to resume is a goal still.
    let hold = h.command(CLIENT_A, 3, CommandKind::Hold, [0.0; 3]);
    assert_eq!(hold.result(), Ok(()));
    h.ticks(500);
    assert!(
        h.axis(3).velocity == 0.0 && h.axis(3).position < 49.0,
        "{:?}",
        h.axis(3)
    );
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Err(Reason::GroupBusy));
    assert_eq!((reply.at_axis, reply.value), (3, 1.0));
    let resume = h.command(CLIENT_A, 3, CommandKind::Resume, [0.0; 3]);
    assert_eq!(resume.result(), Ok(()));

    // w arrived; the sender's idle claim on it, and v moving on the other link for
    // another client, do not hold the change back.
    h.ticks(1500);
    assert!((h.axis(3).position - 50.0).abs() < 0.01, "{:?}", h.axis(3));
    claim(&mut h, CLIENT_B, 4);
    let jog = h.command(CLIENT_B, 4, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    assert_eq!(jog.result(), Ok(()));
    h.ticks(20);
    let reply = baud(&mut h);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(
        controls[0].lock().unwrap().commissions,
        [Commission::Baud(115_200)]
    );
    assert!(controls[1].lock().unwrap().commissions.is_empty());
}

/// Only a line-rate change waits for the neighbours: a new address keeps them reachable.
#[test]
fn an_address_change_on_a_shared_link_does_not_wait_for_the_neighbours() {
    let (engine, controls) = shared_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    claim(&mut h, CLIENT_A, 0);
    claim(&mut h, CLIENT_A, 1);
    claim(&mut h, CLIENT_B, 2);
    let jog = h.command(CLIENT_B, 2, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    assert_eq!(jog.result(), Ok(()));
    h.ticks(20);
    let reply = commission(&mut h, CLIENT_A, 0, 5);
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(
        controls[0].lock().unwrap().commissions,
        [Commission::Address(5)]
    );
}
