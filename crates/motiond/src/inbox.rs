//! What the `paths` and `setpoints` services share: a publish-subscribe service clients
//! publish into and only the server subscribes to, and the node each sample came from —
//! read from the service's dynamic config (written by iceoryx2 when the publisher
//! connected), never from the payload.

use core::fmt::Debug;

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use motion_ipc::ClientId;

use crate::Ipc;
use crate::error::ServiceError;

/// The server's end of an inbox service: its subscriber and the service's port factory.
pub type Inbox<T> = (Subscriber<Ipc, T, ()>, PortFactory<Ipc, T, ()>);

/// Creates (or opens) `name` for payload `T`: no history, `buffer` samples a publisher
/// may have queued, `borrowed` samples the server may hold, `max_clients` publishers and
/// the server's one subscriber.
pub fn create<T: Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    name: &str,
    max_clients: usize,
    buffer: usize,
    borrowed: usize,
) -> Result<Inbox<T>, ServiceError> {
    let service_name = ServiceName::new(name).map_err(|e| ServiceError::Name {
        what: "service",
        source: e.into(),
        name: name.to_owned(),
    })?;
    let factory = node
        .service_builder(&service_name)
        .publish_subscribe::<T>()
        .history_size(0)
        .subscriber_max_buffer_size(buffer)
        .subscriber_max_borrowed_samples(borrowed)
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
    Ok((subscriber, factory))
}

/// The node of the publisher `publisher` (a sample header's `publisher_id().value()`);
/// `None` when it left before we looked.
pub fn publisher_node<T: Debug + ZeroCopySend>(
    factory: &PortFactory<Ipc, T, ()>,
    publisher: u128,
) -> Option<ClientId> {
    let mut node = None;
    factory.dynamic_config().list_publishers(|details| {
        if details.publisher_id.value() == publisher {
            node = Some(ClientId::from_u128(details.node_id.value()));
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    node
}
