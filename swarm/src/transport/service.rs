//! The run's iceoryx2 services: their names, their capacities, and one builder that creates
//! (the world, a benchmark's parent) or opens (everyone else) any of them.

use super::{TransportError, TransportResult};
use iceoryx2::prelude::*;
use iceoryx2::service::builder::publish_subscribe::{
    Builder, PublishSubscribeCreateError, PublishSubscribeOpenError,
};
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use std::fmt;
use std::fmt::Debug;

/// A publish-subscribe service's port factory.
pub type PubSubService<P, H> = PortFactory<ipc::Service, P, H>;
/// An event service's port factory.
pub type EventService = iceoryx2::service::port_factory::event::PortFactory<ipc::Service>;

pub const STATUS_NAME: &str = "world/state";
pub const CONTROL_NAME: &str = "run/control";
pub const AIR_NAME: &str = "radio/air";
pub const SENSES_NAME: &str = "world/sense";

/// The generation of the world's data services (`world/sense`, `radio/air`): 0 at the start
/// of a run; the world makes both anew under the next generation when one of their segments
/// shrinks under it (a process of the user truncated it: docs/protocol.md section 4), and
/// says so in the tick barrier ([`crate::barrier::TickBarrier::data_generation`]).
pub type Generation = u32;

/// The name of a world data service of generation `generation`: `base` for 0 (every run
/// that nobody tampered with), `<base>/g<generation>` after.
fn generation_name(base: &str, generation: Generation) -> String {
    if generation == 0 {
        base.to_string()
    } else {
        format!("{base}/g{generation}")
    }
}

/// The generation a name of `base`'s services carries, if it is one of them.
fn generation_of(name: &str, base: &str) -> Option<Generation> {
    if name == base {
        return Some(0);
    }
    name.strip_prefix(base)?
        .strip_prefix("/g")?
        .parse()
        .ok()
        .filter(|&g| g > 0)
}

/// One iceoryx2 service of a run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ServiceId {
    /// `world/sense` (`world/sense/g<generation>` after the world made it anew): every
    /// robot's Sense record of a tick, in one sample.
    Senses { generation: Generation },
    /// `robot/<i>/sense`: one robot's Sense frame (the latency benchmark's one hop).
    Sense(u32),
    /// `robot/<i>/act`: robot i's Action frames (pub-sub).
    Act(u32),
    /// `robot/<i>/board`: robot i's Action frames (blackboard, `runtime.acts`).
    Board(u32),
    /// `radio/air` (`radio/air/g<generation>`): the world's one publication a tick of the
    /// messages due.
    Air { generation: Generation },
    /// `world/state`: the world's status for the orchestrator.
    Status,
    /// `run/control`: the orchestrator's commands to the world.
    Control,
    /// Any other service (the iceoryx2-event bell, the benchmarks' raw services).
    Named(String),
}

impl ServiceId {
    /// The iceoryx2 service name.
    pub fn name(&self) -> String {
        match self {
            ServiceId::Sense(r) => format!("robot/{r}/sense"),
            ServiceId::Act(r) => format!("robot/{r}/act"),
            ServiceId::Board(r) => format!("robot/{r}/board"),
            ServiceId::Air { generation } => generation_name(AIR_NAME, *generation),
            ServiceId::Senses { generation } => generation_name(SENSES_NAME, *generation),
            ServiceId::Status => STATUS_NAME.to_string(),
            ServiceId::Control => CONTROL_NAME.to_string(),
            ServiceId::Named(n) => n.clone(),
        }
    }

    /// The robot the service belongs to, if it is one robot's.
    pub fn robot(&self) -> Option<u32> {
        match self {
            ServiceId::Sense(r) | ServiceId::Act(r) | ServiceId::Board(r) => Some(*r),
            _ => None,
        }
    }

    /// The service a port factory is for.
    pub fn of<F: iceoryx2::service::port_factory::PortFactory>(factory: &F) -> ServiceId {
        ServiceId::from(factory.name().as_str())
    }
}

impl fmt::Display for ServiceId {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl From<&str> for ServiceId {
    /// The service of this name: a robot's or the run's own when the name is one of theirs.
    fn from(name: &str) -> ServiceId {
        let robots = |kind: &str| -> Option<u32> {
            name.strip_prefix("robot/")?
                .strip_suffix(kind)?
                .strip_suffix('/')?
                .parse()
                .ok()
        };
        if let Some(r) = robots("sense") {
            ServiceId::Sense(r)
        } else if let Some(r) = robots("act") {
            ServiceId::Act(r)
        } else if let Some(r) = robots("board") {
            ServiceId::Board(r)
        } else if let Some(generation) = generation_of(name, AIR_NAME) {
            ServiceId::Air { generation }
        } else if let Some(generation) = generation_of(name, SENSES_NAME) {
            ServiceId::Senses { generation }
        } else if name == STATUS_NAME {
            ServiceId::Status
        } else if name == CONTROL_NAME {
            ServiceId::Control
        } else {
            ServiceId::Named(name.to_string())
        }
    }
}

/// The iceoryx2 name of a service.
pub fn service_name(service: &ServiceId) -> TransportResult<ServiceName> {
    ServiceName::new(&service.name()).map_err(|source| TransportError::ServiceName {
        service: service.clone(),
        source,
    })
}

/// How a process reaches a service: it creates it, with these capacities, or opens it as its
/// creator made it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reach<C> {
    Create(C),
    Open,
}

impl<C> Reach<C> {
    /// `Create(capacity())` when `create`, else `Open`.
    pub fn create_if(create: bool, capacity: impl FnOnce() -> C) -> Reach<C> {
        if create {
            Reach::Create(capacity())
        } else {
            Reach::Open
        }
    }
}

/// What a publish-subscribe service admits, fixed when it is created. `None`: iceoryx2's
/// default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PubSubCapacity {
    pub publishers: usize,
    pub subscribers: usize,
    pub nodes: usize,
    /// Samples one subscriber's buffer holds.
    pub buffer: usize,
    /// Samples one subscriber may hold at once.
    pub borrowed: Option<usize>,
    /// Samples kept for subscribers that connect later.
    pub history: Option<usize>,
    /// Whether a full subscriber buffer drops its oldest sample for a new one (true) or the
    /// publisher's send fails (false).
    pub safe_overflow: Option<bool>,
}

/// What an event service admits, fixed when it is created.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EventCapacity {
    pub listeners: usize,
    pub notifiers: usize,
    pub nodes: usize,
}

/// A payload type a publish-subscribe service of the run carries. iceoryx2 creates and opens
/// services of fixed-size payloads and of slices with separate methods; this picks the one.
pub trait ShmPayload: Debug + ZeroCopySend + IceoryxSend {
    fn create<H: Debug + ZeroCopySend>(
        b: Builder<Self, H, ipc::Service>,
    ) -> Result<PubSubService<Self, H>, PublishSubscribeCreateError>;
    fn open<H: Debug + ZeroCopySend>(
        b: Builder<Self, H, ipc::Service>,
    ) -> Result<PubSubService<Self, H>, PublishSubscribeOpenError>;
}

impl<T: Debug + ZeroCopySend + IceoryxSend> ShmPayload for T {
    fn create<H: Debug + ZeroCopySend>(
        b: Builder<T, H, ipc::Service>,
    ) -> Result<PubSubService<T, H>, PublishSubscribeCreateError> {
        b.create()
    }
    fn open<H: Debug + ZeroCopySend>(
        b: Builder<T, H, ipc::Service>,
    ) -> Result<PubSubService<T, H>, PublishSubscribeOpenError> {
        b.open()
    }
}

impl ShmPayload for [u8] {
    fn create<H: Debug + ZeroCopySend>(
        b: Builder<[u8], H, ipc::Service>,
    ) -> Result<PubSubService<[u8], H>, PublishSubscribeCreateError> {
        b.create()
    }
    fn open<H: Debug + ZeroCopySend>(
        b: Builder<[u8], H, ipc::Service>,
    ) -> Result<PubSubService<[u8], H>, PublishSubscribeOpenError> {
        b.open()
    }
}

/// Creates or opens the publish-subscribe service `service` with payload `P` and user header
/// `H` (`()` for none).
pub fn pub_sub<P: ShmPayload + ?Sized, H: Debug + ZeroCopySend>(
    node: &Node<ipc::Service>,
    service: ServiceId,
    reach: Reach<PubSubCapacity>,
) -> TransportResult<PubSubService<P, H>> {
    let b = node
        .service_builder(&service_name(&service)?)
        .publish_subscribe::<P>()
        .user_header::<H>();
    match reach {
        Reach::Create(c) => {
            let mut b = b
                .max_publishers(c.publishers)
                .max_subscribers(c.subscribers)
                .max_nodes(c.nodes)
                .subscriber_max_buffer_size(c.buffer);
            if let Some(v) = c.borrowed {
                b = b.subscriber_max_borrowed_samples(v);
            }
            if let Some(v) = c.history {
                b = b.history_size(v);
            }
            if let Some(v) = c.safe_overflow {
                b = b.enable_safe_overflow(v);
            }
            P::create(b).map_err(|source| TransportError::Create { service, source })
        }
        Reach::Open => P::open(b).map_err(|source| TransportError::Open { service, source }),
    }
}

/// Creates or opens the event service `service`.
pub fn event(
    node: &Node<ipc::Service>,
    service: ServiceId,
    reach: Reach<EventCapacity>,
) -> TransportResult<EventService> {
    let b = node.service_builder(&service_name(&service)?).event();
    match reach {
        Reach::Create(c) => b
            .max_listeners(c.listeners)
            .max_notifiers(c.notifiers)
            .max_nodes(c.nodes)
            .create()
            .map_err(|source| TransportError::CreateEvent { service, source }),
        Reach::Open => b
            .open()
            .map_err(|source| TransportError::OpenEvent { service, source }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn service_names_are_the_runs_names() {
        assert_eq!(ServiceId::Sense(3).name(), "robot/3/sense");
        assert_eq!(ServiceId::Act(0).name(), "robot/0/act");
        assert_eq!(ServiceId::Status.name(), "world/state");
        assert_eq!(ServiceId::Control.name(), "run/control");
        assert_eq!(ServiceId::Senses { generation: 0 }.name(), "world/sense");
        assert_eq!(ServiceId::Air { generation: 2 }.name(), "radio/air/g2");
        assert_eq!(
            ServiceId::from("radio/air/g0"),
            ServiceId::Named("radio/air/g0".into())
        );
        assert_eq!(ServiceId::from("tick/down").robot(), None);
        // A name read back from iceoryx2 is the service it names.
        for id in [
            ServiceId::Sense(3),
            ServiceId::Act(12),
            ServiceId::Air { generation: 0 },
            ServiceId::Senses { generation: 0 },
            ServiceId::Air { generation: 3 },
            ServiceId::Senses { generation: 1 },
            ServiceId::Status,
            ServiceId::Control,
            ServiceId::from("lat/down"),
        ] {
            assert_eq!(ServiceId::from(id.name().as_str()), id);
        }
        assert_eq!(
            ServiceId::from("robot/x/radio"),
            ServiceId::Named("robot/x/radio".into())
        );
    }
}
