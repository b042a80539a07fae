//! What can go wrong between a process and iceoryx2, with the service it happened on.
//!
//! Each variant names the service (and through it the robot: `robot/7/radio`) and keeps
//! iceoryx2's own error as its `source()`. The message also ends with that error's text
//! (`open service robot/7/radio: PublishSubscribeOpenError::DoesNotExist`), because the
//! binaries print an error with `{e}` alone at their edge: nothing is lost when a caller only
//! keeps `to_string()`.

use super::ServiceId;
use iceoryx2::node::NodeCreationFailure;
use iceoryx2::port::listener::{ListenerCreateError, ListenerWaitError};
use iceoryx2::port::notifier::{NotifierCreateError, NotifierNotifyError};
use iceoryx2::port::publisher::PublisherCreateError;
use iceoryx2::port::reader::{EntryHandleError, ReaderCreateError};
use iceoryx2::port::subscriber::SubscriberCreateError;
use iceoryx2::port::writer::{EntryHandleMutError, WriterCreateError};
use iceoryx2::port::{LoanError, ReceiveError, SendError};
use iceoryx2::prelude::SemanticStringError;
use iceoryx2::service::builder::blackboard::{BlackboardCreateError, BlackboardOpenError};
use iceoryx2::service::builder::event::{EventCreateError, EventOpenError};
use iceoryx2::service::builder::publish_subscribe::{
    PublishSubscribeCreateError, PublishSubscribeOpenError,
};
use iceoryx2::service::service_name::ServiceNameError;
use std::fmt;

/// The port of a service an error happened on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Port {
    Publisher,
    Subscriber,
    Notifier,
    Listener,
}

impl fmt::Display for Port {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Port::Publisher => "publisher",
            Port::Subscriber => "subscriber",
            Port::Notifier => "notifier",
            Port::Listener => "listener",
        })
    }
}

/// A failed iceoryx2 call of the runtime or a benchmark.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The run's prefix is not a valid iceoryx2 file name.
    #[error("iceoryx2 prefix {prefix:?}: {source}")]
    Prefix {
        prefix: String,
        source: SemanticStringError,
    },
    /// The run's iceoryx2 root folder is not a valid iceoryx2 path.
    #[error("iceoryx2 root path {path:?}: {source}")]
    RootPath {
        path: String,
        source: SemanticStringError,
    },
    #[error("iceoryx2 node name {name:?}: {source}")]
    NodeName {
        name: String,
        source: SemanticStringError,
    },
    #[error("create iceoryx2 node {name:?}: {source}")]
    Node {
        name: String,
        source: NodeCreationFailure,
    },
    #[error("service name {service}: {source}")]
    ServiceName {
        service: ServiceId,
        source: ServiceNameError,
    },
    /// The world (or a benchmark's parent) could not create a publish-subscribe service.
    #[error("create service {service}: {source}")]
    Create {
        service: ServiceId,
        source: PublishSubscribeCreateError,
    },
    /// An agent (or the orchestrator) could not open a publish-subscribe service.
    #[error("open service {service}: {source}")]
    Open {
        service: ServiceId,
        source: PublishSubscribeOpenError,
    },
    /// The world could not create a robot's act blackboard.
    #[error("create blackboard {service}: {source}")]
    CreateBoard {
        service: ServiceId,
        source: BlackboardCreateError,
    },
    /// An agent could not open its robot's act blackboard.
    #[error("open blackboard {service}: {source}")]
    OpenBoard {
        service: ServiceId,
        source: BlackboardOpenError,
    },
    #[error("{service} reader: {source}")]
    Reader {
        service: ServiceId,
        source: ReaderCreateError,
    },
    #[error("{service} writer: {source}")]
    Writer {
        service: ServiceId,
        source: WriterCreateError,
    },
    #[error("{service} reader's entry: {source}")]
    Entry {
        service: ServiceId,
        source: EntryHandleError,
    },
    #[error("{service} writer's entry: {source}")]
    EntryMut {
        service: ServiceId,
        source: EntryHandleMutError,
    },
    #[error("create event service {service}: {source}")]
    CreateEvent {
        service: ServiceId,
        source: EventCreateError,
    },
    #[error("open event service {service}: {source}")]
    OpenEvent {
        service: ServiceId,
        source: EventOpenError,
    },
    #[error("{service} publisher: {source}")]
    Publisher {
        service: ServiceId,
        source: PublisherCreateError,
    },
    #[error("{service} subscriber: {source}")]
    Subscriber {
        service: ServiceId,
        source: SubscriberCreateError,
    },
    #[error("{service} notifier: {source}")]
    Notifier {
        service: ServiceId,
        source: NotifierCreateError,
    },
    #[error("{service} listener: {source}")]
    Listener {
        service: ServiceId,
        source: ListenerCreateError,
    },
    #[error("{service}: loan a sample: {source}")]
    Loan {
        service: ServiceId,
        source: LoanError,
    },
    #[error("{service}: send: {source}")]
    Send {
        service: ServiceId,
        source: SendError,
    },
    #[error("{service}: receive: {source}")]
    Receive {
        service: ServiceId,
        source: ReceiveError,
    },
    #[error("{service}: notify: {source}")]
    Notify {
        service: ServiceId,
        source: NotifierNotifyError,
    },
    #[error("{service}: wait: {source}")]
    Wait {
        service: ServiceId,
        source: ListenerWaitError,
    },
    /// An air longer than the air service's slots (the scenario's worst case,
    /// `transport::air_max_len`): refused, never written past the slot.
    #[error("radio/air: an air of {len} bytes exceeds the slot of {max} bytes")]
    AirTooLong { len: usize, max: usize },
}

impl TransportError {
    /// The service the error happened on (None for the run's configuration and node).
    pub fn service(&self) -> Option<&ServiceId> {
        use TransportError::*;
        match self {
            Prefix { .. } | RootPath { .. } | NodeName { .. } | Node { .. } => None,
            ServiceName { service, .. }
            | Create { service, .. }
            | Open { service, .. }
            | CreateBoard { service, .. }
            | OpenBoard { service, .. }
            | Reader { service, .. }
            | Writer { service, .. }
            | Entry { service, .. }
            | EntryMut { service, .. }
            | CreateEvent { service, .. }
            | OpenEvent { service, .. }
            | Publisher { service, .. }
            | Subscriber { service, .. }
            | Notifier { service, .. }
            | Listener { service, .. }
            | Loan { service, .. }
            | Send { service, .. }
            | Receive { service, .. }
            | Notify { service, .. }
            | Wait { service, .. } => Some(service),
            AirTooLong { .. } => {
                static AIR: ServiceId = ServiceId::Air { generation: 0 };
                Some(&AIR)
            }
        }
    }

    /// The robot whose service it happened on.
    pub fn robot(&self) -> Option<u32> {
        self.service().and_then(ServiceId::robot)
    }

    /// The port it happened on, for a port's creation.
    pub fn port(&self) -> Option<Port> {
        match self {
            TransportError::Publisher { .. } => Some(Port::Publisher),
            TransportError::Subscriber { .. } => Some(Port::Subscriber),
            TransportError::Notifier { .. } => Some(Port::Notifier),
            TransportError::Listener { .. } => Some(Port::Listener),
            _ => None,
        }
    }
}

/// A transport call's result.
pub type TransportResult<T> = std::result::Result<T, TransportError>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error;

    #[test]
    fn names_the_service_robot_and_cause() {
        let e = TransportError::Open {
            service: ServiceId::Act(7),
            source: PublishSubscribeOpenError::DoesNotExist,
        };
        assert_eq!(
            e.to_string(),
            "open service robot/7/act: PublishSubscribeOpenError::DoesNotExist"
        );
        assert_eq!(e.robot(), Some(7));
        let cause = e.source().expect("iceoryx2's error is the source");
        assert_eq!(cause.to_string(), "PublishSubscribeOpenError::DoesNotExist");
    }
}
