//! The engine's commissioning rules (`CommandKind::Commission` with `Target::Device`,
//! `crates/motion-engine/src/commission.rs`), stepped tick by tick with ideal boards and a
//! fake clock: refused for an unknown device, unless the client holds every claim of the
//! device, and while any of its axes moves; accepted otherwise, the device `Starting` in
//! that tick's frame and the change handed to its driver exactly once.

mod support;

use motion_drivers::Commission;
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, CommissionWhat, DeviceState, Reason,
    Target,
};
use support::*;

/// Sends a commission of device `device` from `client` in the next tick: a new address.
fn commission(h: &mut Harness, client: ClientId, device: u32, address: u32) -> CommandReply {
    h.sequence += 1;
    let mut request = CommandRequest::new(client, h.sequence, device, CommandKind::Commission)
        .with_values([
            f64::from(CommissionWhat::Address as u32),
            f64::from(address),
            0.0,
        ]);
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
