//! The payloads travel through real iceoryx2 services (the in-process service type, so the
//! test needs no shared memory of its own): what a client reads is what the server wrote.

use iceoryx2::prelude::*;
use motion_ipc::*;

#[test]
fn frame_written_in_place_is_received_intact() -> Result<(), Box<dyn core::error::Error>> {
    let node = NodeBuilder::new().create::<local::Service>()?;
    let names = ServiceNames::new("layout-roundtrip");
    let service = node
        .service_builder(&names.frame().as_str().try_into()?)
        .publish_subscribe::<MotionFrame>()
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .open_or_create()?;
    let publisher = service.publisher_builder().create()?;
    let subscriber = service.subscriber_builder().create()?;

    let mut sample = publisher.loan_uninit()?.write_payload(MotionFrame::EMPTY);
    let frame = sample.payload_mut();
    frame.tick = 41;
    frame.axis_count = 2;
    frame.axes[1].position = 12.5;
    frame.axes[1].flags = AxisFlags::MOVING.with(AxisFlags::HOMED, true).0;
    frame.axes[1].claimed_by = ClientId::from_u128(77);
    sample.send()?;

    let received = subscriber.receive()?.ok_or("no frame received")?;
    assert_eq!(received.tick, 41);
    assert_eq!(received.axes().len(), 2);
    assert_eq!(received.axes[1].position, 12.5);
    assert!(received.axes[1].flags().contains(AxisFlags::HOMED));
    assert_eq!(received.axes[1].claimed_by.as_u128(), 77);
    Ok(())
}

#[test]
fn command_request_response_round_trip() -> Result<(), Box<dyn core::error::Error>> {
    let node = NodeBuilder::new().create::<local::Service>()?;
    let names = ServiceNames::new("layout-roundtrip");
    let service = node
        .service_builder(&names.command().as_str().try_into()?)
        .request_response::<CommandRequest, CommandReply>()
        .open_or_create()?;
    let server = service.server_builder().create()?;
    let client = service.client_builder().create()?;

    let request = CommandRequest::new(ClientId::from_u128(5), 9, 0, CommandKind::Velocity)
        .with_values([1.0, 0.0, 0.0]);
    let pending = client.send_copy(request)?;
    let active = server.receive()?.ok_or("no request received")?;
    assert_eq!(*active.payload(), request);
    active.send_copy(CommandReply::to(active.payload(), Reason::VelocityLimit, 3))?;
    let reply = pending.receive()?.ok_or("no reply received")?;
    assert_eq!(reply.sequence, 9);
    assert_eq!(reply.result(), Err(Reason::VelocityLimit));
    Ok(())
}
