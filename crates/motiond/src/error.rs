//! The shell's typed errors: what went wrong setting up the server, each with the text an
//! operator reads (and what to do about it).

use std::io;

use iceoryx2::node::NodeCreationFailure;
use iceoryx2::port::listener::ListenerCreateError;
use iceoryx2::port::notifier::NotifierCreateError;
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::prelude::SemanticStringError;
use iceoryx2::service::builder::event::{EventOpenError, EventOpenOrCreateError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
};
use iceoryx2::service::builder::request_response::{
    RequestResponseOpenError, RequestResponseOpenOrCreateError,
};
use iceoryx2::service::port_factory::server::ServerCreateError;
use iceoryx2::service::service_name::ServiceNameError;
use motion_engine::EngineConfigError;
use motion_ipc::PidFileError;
use motion_link::LinkError;

use motion_config::boards::BuildError;
use motion_config::private_dir::PrivateDirError;

/// A real-time set-up step that could not be done (the server may go on without it).
pub use motion_rt::RtError;

/// The iceoryx2 services of an instance could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// A node or service name iceoryx2 refuses.
    #[error("{what} name {name:?}")]
    Name {
        /// "node" or "service".
        what: &'static str,
        /// The name.
        name: String,
        /// iceoryx2's reason.
        #[source]
        source: Iceoryx2ServiceError,
    },
    /// The iceoryx2 node could not be created.
    #[error("iceoryx2 node")]
    Node(#[source] NodeCreationFailure),
    /// Another live motiond serves the instance.
    #[error(
        "another motiond (process {pid}) is serving instance `{instance}`; stop it or pick another [server] name"
    )]
    AnotherServer {
        /// Its process.
        pid: u32,
        /// The instance name.
        instance: String,
    },
    /// A service or one of its ports could not be made.
    #[error("service {service} could not be set up{}", source.hint().text())]
    Service {
        /// The service name.
        service: String,
        /// iceoryx2's reason.
        #[source]
        source: Iceoryx2ServiceError,
    },
}

impl ServiceError {
    /// Why `service` could not be made.
    pub fn service(service: &str, error: impl Into<Iceoryx2ServiceError>) -> Self {
        Self::Service {
            service: service.to_owned(),
            source: error.into(),
        }
    }
}

/// What iceoryx2 answered when a name, a service or a port of the instance could not be
/// made, in iceoryx2's own error types (its text is iceoryx2's).
#[derive(Debug, thiserror::Error)]
pub enum Iceoryx2ServiceError {
    /// A node name iceoryx2 refuses.
    #[error(transparent)]
    NodeName(#[from] SemanticStringError),
    /// A service name iceoryx2 refuses.
    #[error(transparent)]
    ServiceName(#[from] ServiceNameError),
    /// An event service could not be opened or created.
    #[error(transparent)]
    Event(#[from] EventOpenOrCreateError),
    /// A publish-subscribe service could not be opened or created.
    #[error(transparent)]
    PublishSubscribe(#[from] PublishSubscribeOpenOrCreateError),
    /// A request-response service could not be opened or created.
    #[error(transparent)]
    RequestResponse(#[from] RequestResponseOpenOrCreateError),
    /// A notifier could not be created.
    #[error(transparent)]
    Notifier(#[from] NotifierCreateError),
    /// A listener could not be created.
    #[error(transparent)]
    Listener(#[from] ListenerCreateError),
    /// A publisher could not be created.
    #[error(transparent)]
    Publisher(#[from] PublisherCreateError),
    /// A request-response server port could not be created.
    #[error(transparent)]
    Server(#[from] ServerCreateError),
    /// A subscriber could not be created.
    #[error(transparent)]
    Subscriber(#[from] SubscriberCreateError),
}

/// What an operator can do about a service that could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServiceHint {
    /// The service exists with other settings than this server asks for.
    OtherSettings,
    /// Every port slot of its kind is taken.
    SlotsTaken,
    /// Nothing specific is known.
    None,
}

impl ServiceHint {
    /// The words appended to the error ("" for [`ServiceHint::None`]).
    pub const fn text(self) -> &'static str {
        match self {
            Self::OtherSettings => {
                " (it exists with other settings: clients of a previous server still hold it, and this config changed max_clients or a payload; stop those clients, or keep the previous settings)"
            }
            Self::SlotsTaken => " (its port slots are all taken, by clients of a previous server?)",
            Self::None => "",
        }
    }
}

impl Iceoryx2ServiceError {
    /// What to do about it, from which of iceoryx2's errors it is.
    pub fn hint(&self) -> ServiceHint {
        use EventOpenError as Event;
        use PublishSubscribeOpenError as PubSub;
        use RequestResponseOpenError as ReqRes;
        match self {
            Self::Event(EventOpenOrCreateError::EventOpenError(open)) => match open {
                Event::IncompatibleMessagingPattern
                | Event::IncompatibleAttributes
                | Event::IncompatibleDeadline
                | Event::IncompatibleNotifierCreatedEvent
                | Event::IncompatibleNotifierDroppedEvent
                | Event::IncompatibleNotifierDeadEvent
                | Event::DoesNotSupportRequestedAmountOfNotifiers
                | Event::DoesNotSupportRequestedAmountOfListeners
                | Event::DoesNotSupportRequestedMaxEventId
                | Event::DoesNotSupportRequestedAmountOfNodes => ServiceHint::OtherSettings,
                Event::ExceedsMaxNumberOfNodes => ServiceHint::SlotsTaken,
                _ => ServiceHint::None,
            },
            Self::PublishSubscribe(
                PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(open),
            ) => match open {
                PubSub::IncompatibleTypes
                | PubSub::IncompatibleMessagingPattern
                | PubSub::IncompatibleAttributes
                | PubSub::IncompatibleOverflowBehavior
                | PubSub::DoesNotSupportRequestedMinBufferSize
                | PubSub::DoesNotSupportRequestedMinHistorySize
                | PubSub::DoesNotSupportRequestedMinSubscriberBorrowedSamples
                | PubSub::DoesNotSupportRequestedAmountOfPublishers
                | PubSub::DoesNotSupportRequestedAmountOfSubscribers
                | PubSub::DoesNotSupportRequestedAmountOfNodes => ServiceHint::OtherSettings,
                PubSub::ExceedsMaxNumberOfNodes => ServiceHint::SlotsTaken,
                _ => ServiceHint::None,
            },
            Self::RequestResponse(RequestResponseOpenOrCreateError::RequestResponseOpenError(
                open,
            )) => match open {
                ReqRes::IncompatibleRequestOrResponseType
                | ReqRes::IncompatibleAttributes
                | ReqRes::IncompatibleMessagingPattern
                | ReqRes::IncompatibleOverflowBehaviorForRequests
                | ReqRes::IncompatibleOverflowBehaviorForResponses
                | ReqRes::IncompatibleBehaviorForFireAndForgetRequests
                | ReqRes::DoesNotSupportRequestedAmountOfClientRequestLoans
                | ReqRes::DoesNotSupportRequestedAmountOfActiveRequestsPerClient
                | ReqRes::DoesNotSupportRequestedResponseBufferSize
                | ReqRes::DoesNotSupportRequestedAmountOfServers
                | ReqRes::DoesNotSupportRequestedAmountOfClients
                | ReqRes::DoesNotSupportRequestedAmountOfNodes
                | ReqRes::DoesNotSupportRequestedAmountOfBorrowedResponsesPerPendingResponse => {
                    ServiceHint::OtherSettings
                }
                ReqRes::ExceedsMaxNumberOfNodes => ServiceHint::SlotsTaken,
                _ => ServiceHint::None,
            },
            Self::Notifier(NotifierCreateError::ExceedsMaxSupportedNotifiers)
            | Self::Listener(ListenerCreateError::ExceedsMaxSupportedListeners)
            | Self::Publisher(PublisherCreateError::ExceedsMaxSupportedPublishers)
            | Self::Server(ServerCreateError::ExceedsMaxSupportedServers)
            | Self::Subscriber(SubscriberCreateError::ExceedsMaxSupportedSubscribers) => {
                ServiceHint::SlotsTaken
            }
            _ => ServiceHint::None,
        }
    }
}

/// `$NOTIFY_SOCKET` is set but unusable.
#[derive(Debug, thiserror::Error)]
pub enum NotifyError {
    /// Not valid UTF-8.
    #[error("NOTIFY_SOCKET is not UTF-8")]
    NotUtf8,
    /// Neither `/path` nor `@name`.
    #[error("NOTIFY_SOCKET={0:?}: neither an absolute path nor an @abstract name")]
    BadTarget(String),
    /// The address could not be made.
    #[error("NOTIFY_SOCKET={target:?}: {source}")]
    Address {
        /// The value.
        target: String,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// No socket could be created.
    #[error("NOTIFY_SOCKET: cannot create a socket: {0}")]
    Socket(#[source] io::Error),
}

/// The tick thread could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The services could not be made.
    #[error(transparent)]
    Services(#[from] ServiceError),
    /// `--require-rt` and the real-time set-up is incomplete.
    #[error("--require-rt: real-time set-up incomplete ({summary}); {missing}")]
    RtIncomplete {
        /// What was achieved.
        summary: String,
        /// What is missing: the config key to set, or the steps that failed.
        missing: String,
    },
}

/// Why [`run`](crate::app::run) could not start the server, or why it ended with an error.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// A signal handler could not be installed.
    #[error("installing signal handlers")]
    SignalHandlers(#[source] io::Error),
    /// A device's board refused its config ([`boards::build`](motion_config::boards::build): which
    /// device, which key, why).
    #[error(transparent)]
    Drivers(#[from] BuildError),
    /// The engine refused the config.
    #[error("building the engine")]
    Engine(#[source] EngineConfigError),
    /// A link could not be opened.
    #[error("link `{link}`")]
    Link {
        /// The link's name.
        link: String,
        /// Why.
        #[source]
        source: LinkError,
    },
    /// A link's I/O thread could not be started.
    #[error("starting the I/O thread of link `{link}`")]
    IoThread {
        /// The link's name.
        link: String,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// The tick thread could not be started.
    #[error("starting the tick thread")]
    TickThread(#[source] io::Error),
    /// The black box's recorder thread could not be started.
    #[error("starting the black box recorder thread")]
    RecorderThread(#[source] io::Error),
    /// The tick thread could not set up its services or its real-time settings.
    #[error(transparent)]
    Start(#[from] StartError),
    /// The pid file could not be written; every axis was stopped before exiting.
    #[error(transparent)]
    PidFile(#[from] PidFileError),
    /// `state_dir` or `blackbox_dir` (or the server's key in it) is not the server's own,
    /// or could not be made (motion_config::private_dir: what was found and what to do).
    #[error(transparent)]
    PrivateDir(#[from] PrivateDirError),
}

#[cfg(test)]
mod tests {
    use std::error::Error as _;

    use iceoryx2::port::publisher::PublisherCreateError;
    use iceoryx2::service::builder::event::EventOpenOrCreateError;
    use iceoryx2::service::builder::publish_subscribe::{
        PublishSubscribeOpenError, PublishSubscribeOpenOrCreateError,
    };

    use super::{BuildError, Iceoryx2ServiceError, ServerError, ServiceError, ServiceHint};

    fn hint_of(error: &ServiceError) -> ServiceHint {
        match error {
            ServiceError::Service { source, .. } => source.hint(),
            other => panic!("not a service error: {other:?}"),
        }
    }

    #[test]
    fn a_service_with_other_settings_says_so() {
        let error = ServiceError::service(
            "motiond/demo/frame",
            PublishSubscribeOpenOrCreateError::PublishSubscribeOpenError(
                PublishSubscribeOpenError::DoesNotSupportRequestedAmountOfSubscribers,
            ),
        );
        assert_eq!(hint_of(&error), ServiceHint::OtherSettings);
        assert!(
            error.to_string().starts_with(
                "service motiond/demo/frame could not be set up (it exists with other settings:"
            ),
            "{error}"
        );
        let source = error.source().expect("iceoryx2's error is the source");
        assert!(
            source
                .to_string()
                .contains("DoesNotSupportRequestedAmountOfSubscribers"),
            "{source}"
        );
    }

    #[test]
    fn taken_port_slots_and_unknown_failures_are_told_apart() {
        let taken = ServiceError::service(
            "motiond/demo/frame",
            PublisherCreateError::ExceedsMaxSupportedPublishers,
        );
        assert_eq!(hint_of(&taken), ServiceHint::SlotsTaken);
        assert!(
            taken.to_string().contains("port slots are all taken"),
            "{taken}"
        );
        let in_flux =
            ServiceError::service("motiond/demo/tick", EventOpenOrCreateError::SystemInFlux);
        assert_eq!(hint_of(&in_flux), ServiceHint::None);
        assert_eq!(
            in_flux.to_string(),
            "service motiond/demo/tick could not be set up"
        );
        assert!(matches!(
            in_flux
                .source()
                .and_then(|s| s.downcast_ref::<Iceoryx2ServiceError>()),
            Some(Iceoryx2ServiceError::Event(
                EventOpenOrCreateError::SystemInFlux
            ))
        ));
    }

    #[test]
    fn a_board_that_refuses_its_config_is_named_with_the_key() {
        let error = ServerError::from(BuildError {
            device: "six".to_owned(),
            key: "device[1].address".to_owned(),
            message: "300 is above 255".to_owned(),
        });
        assert!(matches!(error, ServerError::Drivers(_)));
        assert_eq!(
            error.to_string(),
            "device `six`: device[1].address: 300 is above 255"
        );
    }
}
