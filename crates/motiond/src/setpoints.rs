//! The `setpoints` service: setpoints clients stream to their groups (`Setpoint`, 288
//! bytes), handed to the engine each tick with the node that sent each — from the
//! service's dynamic config, written by iceoryx2 when the port connected, never from the
//! payload. Nothing is allocated after start-up.

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use motion_engine::Engine;
use motion_ipc::{ClientId, Setpoint};

use crate::boards::AnyDriver;
use crate::error::ServiceError;
use crate::services::Ipc;

/// Setpoints a publisher may have queued before the tick takes them: enough for a client
/// that streams for several ticks ahead, and for one tick the server was late.
pub const SETPOINTS_BUFFER: usize = 16;

/// Setpoints taken from the service in one tick at most (the rest wait for the next).
pub const SETPOINTS_PER_TICK: usize = 256;

/// The `setpoints` service's port factory.
pub type SetpointsFactory = PortFactory<Ipc, Setpoint, ()>;

/// The server's subscriber to `setpoints`.
#[derive(Debug)]
pub struct SetpointInbox {
    subscriber: Subscriber<Ipc, Setpoint, ()>,
    /// Samples whose publisher had left before the tick looked (dropped).
    pub orphans: u64,
}

/// Creates (or opens) `name` with room for `max_clients` publishers and the server.
pub fn create(
    node: &Node<Ipc>,
    name: &str,
    max_clients: usize,
) -> Result<(SetpointInbox, SetpointsFactory), ServiceError> {
    let service_name = ServiceName::new(name).map_err(|e| ServiceError::Name {
        what: "service",
        source: e.into(),
        name: name.to_owned(),
    })?;
    let factory = node
        .service_builder(&service_name)
        .publish_subscribe::<Setpoint>()
        .history_size(0)
        .subscriber_max_buffer_size(SETPOINTS_BUFFER)
        .subscriber_max_borrowed_samples(2)
        .max_subscribers(1)
        .max_publishers(max_clients)
        .max_nodes(max_clients + 2)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| ServiceError::service(name, e))?;
    let subscriber = factory
        .subscriber_builder()
        .create()
        .map_err(|e| ServiceError::service(name, e))?;
    Ok((
        SetpointInbox {
            subscriber,
            orphans: 0,
        },
        factory,
    ))
}

impl SetpointInbox {
    /// Hands every setpoint that arrived since the last tick to `engine`, each with its
    /// sender's node.
    pub fn deliver(&mut self, factory: &SetpointsFactory, engine: &mut Engine<AnyDriver>) {
        for _ in 0..SETPOINTS_PER_TICK {
            let Ok(Some(sample)) = self.subscriber.receive() else {
                return;
            };
            let publisher = sample.header().publisher_id().value();
            let mut node = None;
            factory.dynamic_config().list_publishers(|details| {
                if details.publisher_id.value() == publisher {
                    node = Some(details.node_id.value());
                    return CallbackProgression::Stop;
                }
                CallbackProgression::Continue
            });
            match node {
                Some(node) => engine.handle_setpoint(ClientId::from_u128(node), sample.payload()),
                None => self.orphans += 1,
            }
        }
    }
}
