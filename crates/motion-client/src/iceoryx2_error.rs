//! What iceoryx2 answered when a call of this client failed, kept as iceoryx2's own error
//! types: [`ConnectError::Ipc`](crate::ConnectError::Ipc) and
//! [`ClientError::Ipc`](crate::ClientError::Ipc) carry it as their source, beside the words
//! of what the client was doing.

use iceoryx2::node::{NodeCreationFailure, NodeListFailure};
use iceoryx2::port::client::RequestSendError;
use iceoryx2::port::listener::{ListenerCreateError, ListenerWaitError};
use iceoryx2::port::notifier::{NotifierCreateError, NotifierNotifyError};
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::port::update_connections::ConnectionFailure;
use iceoryx2::port::{LoanError, ReceiveError, SendError};
use iceoryx2::prelude::SemanticStringError;
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::builder::request_response::RequestResponseOpenError;
use iceoryx2::service::port_factory::client::ClientCreateError;
use iceoryx2::service::service_name::ServiceNameError;
use iceoryx2::waitset::{WaitSetAttachmentError, WaitSetCreateError, WaitSetRunError};

/// An error iceoryx2 returned, one variant per iceoryx2 error type this client can meet
/// (match on it to tell, say, a closed connection from a full buffer). Its text is
/// iceoryx2's.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Iceoryx2Error {
    /// A node name iceoryx2 refuses.
    #[error(transparent)]
    NodeName(#[from] SemanticStringError),
    /// A service name iceoryx2 refuses.
    #[error(transparent)]
    ServiceName(#[from] ServiceNameError),
    /// The node could not be created.
    #[error(transparent)]
    NodeCreation(#[from] NodeCreationFailure),
    /// The nodes could not be listed.
    #[error(transparent)]
    NodeList(#[from] NodeListFailure),
    /// A publish-subscribe service could not be opened.
    #[error(transparent)]
    PublishSubscribeOpen(#[from] PublishSubscribeOpenError),
    /// A subscriber could not be created.
    #[error(transparent)]
    SubscriberCreate(#[from] SubscriberCreateError),
    /// An event service could not be opened.
    #[error(transparent)]
    EventOpen(#[from] EventOpenError),
    /// A publisher could not be created.
    #[error(transparent)]
    PublisherCreate(#[from] PublisherCreateError),
    /// A sample could not be loaned.
    #[error(transparent)]
    Loan(#[from] LoanError),
    /// A sample could not be sent.
    #[error(transparent)]
    Send(#[from] SendError),
    /// A listener could not be created.
    #[error(transparent)]
    ListenerCreate(#[from] ListenerCreateError),
    /// A notifier could not be created.
    #[error(transparent)]
    NotifierCreate(#[from] NotifierCreateError),
    /// A request-response service could not be opened.
    #[error(transparent)]
    RequestResponseOpen(#[from] RequestResponseOpenError),
    /// A request-response client port could not be created.
    #[error(transparent)]
    ClientCreate(#[from] ClientCreateError),
    /// A request could not be sent.
    #[error(transparent)]
    RequestSend(#[from] RequestSendError),
    /// A sample or a response could not be received.
    #[error(transparent)]
    Receive(#[from] ReceiveError),
    /// A subscriber could not update its connections.
    #[error(transparent)]
    Connection(#[from] ConnectionFailure),
    /// A listener's wait failed.
    #[error(transparent)]
    ListenerWait(#[from] ListenerWaitError),
    /// A notification could not be sent.
    #[error(transparent)]
    NotifierNotify(#[from] NotifierNotifyError),
    /// A wait set could not be created.
    #[error(transparent)]
    WaitSetCreate(#[from] WaitSetCreateError),
    /// Something could not be attached to a wait set.
    #[error(transparent)]
    WaitSetAttachment(#[from] WaitSetAttachmentError),
    /// A wait set's wait failed.
    #[error(transparent)]
    WaitSetRun(#[from] WaitSetRunError),
}

#[cfg(test)]
mod tests {
    use std::error::Error as _;

    use iceoryx2::service::service_name::ServiceNameError;

    use super::Iceoryx2Error;
    use crate::error::with_causes;
    use crate::{ClientError, ConnectError};

    #[test]
    fn a_refused_service_name_keeps_iceoryx2s_error() {
        // An empty service name is iceoryx2's `InvalidContent`.
        let error = crate::ports::service_name("", "demo").expect_err("empty name");
        let ConnectError::InvalidName { name, kind, source } = &error else {
            panic!("not InvalidName: {error:?}");
        };
        assert_eq!((name.as_str(), *kind), ("demo", "service"));
        assert!(matches!(
            source,
            Iceoryx2Error::ServiceName(ServiceNameError::InvalidContent)
        ));
        assert_eq!(
            with_causes(&error),
            "\"demo\" is not a valid iceoryx2 service name: ServiceNameError::InvalidContent"
        );
    }

    #[test]
    fn a_failed_call_names_the_operation_and_keeps_the_source() {
        let error = ClientError::ipc(
            "receive a sample",
            iceoryx2::port::ReceiveError::ExceedsMaxBorrows,
        );
        assert_eq!(error.to_string(), "iceoryx2 could not receive a sample");
        let source = error
            .source()
            .and_then(|source| source.downcast_ref::<Iceoryx2Error>())
            .expect("the iceoryx2 error is the source");
        assert!(matches!(
            source,
            Iceoryx2Error::Receive(iceoryx2::port::ReceiveError::ExceedsMaxBorrows)
        ));
        assert_eq!(
            with_causes(&error),
            "iceoryx2 could not receive a sample: ReceiveError::ExceedsMaxBorrows"
        );
    }
}
