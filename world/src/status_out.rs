//! The world's status (`world/state`), which the orchestrator and the viewer read, written
//! under the shrink guard: a process of the user that truncates its segment makes the world
//! stop publishing it (said once on stderr), never die of SIGBUS (issue 37 item 4).

use crate::shrink_guard::{self, RUN_SEGMENTS};
use iceoryx2::port::publisher::Publisher;
use iceoryx2::prelude::*;
use swarm::frames::WorldStatus;
use swarm::transport::{self, StatusService, TransportResult};

/// The world's status publisher.
pub struct StatusOut {
    publisher: Publisher<ipc::Service, WorldStatus, ()>,
    _service: StatusService,
    /// Its segment shrank: nothing is written any more.
    lost: bool,
}

impl StatusOut {
    /// Makes the run's status service.
    pub fn create(node: &Node<ipc::Service>) -> TransportResult<StatusOut> {
        let service = transport::status_service(node, true)?;
        let publisher = service.publisher_builder().create().map_err(|source| {
            transport::TransportError::Publisher {
                service: transport::ServiceId::Status,
                source,
            }
        })?;
        Ok(StatusOut {
            publisher,
            _service: service,
            lost: false,
        })
    }

    /// Closes the publisher (under the guard), or lets it go unclosed when its segment
    /// shrank ([`shrink_guard::give_up`]).
    pub fn close(self) {
        if self.lost {
            shrink_guard::give_up(self);
        } else {
            let _ = shrink_guard::reading(RUN_SEGMENTS, || drop(self));
        }
    }

    /// Publishes `status` (a full buffer or a lost segment drops it: the status is advisory).
    pub fn publish(&mut self, status: WorldStatus) {
        if self.lost {
            return;
        }
        let publisher = &self.publisher;
        let sent = shrink_guard::reading(RUN_SEGMENTS, || {
            if let Ok(s) = publisher.loan_uninit() {
                let _ = s.write_payload(status).send();
            }
        });
        if sent.is_none() {
            self.lost = true;
            eprintln!(
                "world: the world/state segment shrank under the world (truncated by a process of \
                 the user): the run's status is not published any more (docs/protocol.md \
                 section 4)"
            );
        }
    }
}
