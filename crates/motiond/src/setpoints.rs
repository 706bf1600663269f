//! The `setpoints` service: setpoints clients stream to their groups (`Setpoint`, 288
//! bytes), handed to the engine each tick with the node that sent each — from the
//! service's dynamic config, written by iceoryx2 when the port connected, never from the
//! payload — and the instant the tick took each from the service (CLOCK_MONOTONIC, the
//! clock of the frame's `publish_ns`: the frame's `GroupState::last_received_ns`). Nothing
//! is allocated after start-up.

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use motion_engine::Engine;
use motion_ipc::Setpoint;

use crate::boards::AnyDriver;
use crate::error::ServiceError;
use crate::rt::monotonic_now;
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
    let (subscriber, factory) = crate::inbox::create(node, name, max_clients, SETPOINTS_BUFFER, 2)?;
    let inbox = SetpointInbox {
        subscriber,
        orphans: 0,
    };
    Ok((inbox, factory))
}

impl SetpointInbox {
    /// Hands every setpoint that arrived since the last tick to `engine`, each with its
    /// sender's node and the instant it was taken from the service.
    pub fn deliver(
        &mut self,
        factory: &SetpointsFactory,
        engine: &mut Engine<AnyDriver>,
        journal: &mut crate::blackbox::Journal,
    ) {
        for _ in 0..SETPOINTS_PER_TICK {
            let Ok(Some(sample)) = self.subscriber.receive() else {
                return;
            };
            let received_ns = crate::io::duration_ns(monotonic_now());
            let publisher = sample.header().publisher_id().value();
            match crate::inbox::publisher_node(factory, publisher) {
                Some(node) => {
                    journal.setpoint(node, received_ns, sample.payload());
                    engine.handle_setpoint_at(node, sample.payload(), received_ns);
                }
                None => self.orphans += 1,
            }
        }
    }
}
