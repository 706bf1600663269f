//! What the server must do for late clients: an iceoryx2 publisher hands its history sample
//! (the `ServerInfo` published once at start) to a subscriber that joined later only when
//! the publisher next updates its connections (any send or loan, or `update_connections`).
//! So motiond must call `update_connections()` on its info publisher regularly, or clients
//! that connect after start-up never learn the axis names. This pins that iceoryx2 fact.

use iceoryx2::port::update_connections::UpdateConnections as _;
use iceoryx2::prelude::*;
use motion_client::ipc::{ServerInfo, ServiceNames};
use motion_client::testing::unique_name;

#[test]
fn late_subscriber_gets_history_only_after_the_publisher_updates_connections()
-> Result<(), Box<dyn core::error::Error>> {
    let node = NodeBuilder::new().create::<local::Service>()?;
    let names = ServiceNames::new(&unique_name("history"));
    let service = node
        .service_builder(&names.info().as_str().try_into()?)
        .publish_subscribe::<ServerInfo>()
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .open_or_create()?;
    let publisher = service.publisher_builder().create()?;
    let mut info = ServerInfo::EMPTY;
    info.tick_hz = 1234;
    publisher.send_copy(info)?;

    let late = service.subscriber_builder().create()?;
    assert!(
        late.receive()?.is_none(),
        "history arrives before the publisher acts?"
    );
    publisher.update_connections()?;
    let received = late
        .receive()?
        .ok_or("no history after update_connections")?;
    assert_eq!(received.tick_hz, 1234);
    Ok(())
}
