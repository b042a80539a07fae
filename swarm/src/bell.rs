//! The iceoryx2-event alternative to the futex wake-ups of the tick barrier
//! (`runtime.barrier = "iox2-event"`), kept selectable for comparison (issue 5): the barrier's
//! state (released tick, acknowledgements, per-robot slots) stays in its shared-memory segment;
//! only sleeping and waking go through two iceoryx2 event services:
//!
//! - `tick/down`: the world's notifier wakes every agent's listener (release, shutdown);
//! - `tick/up`: each agent's notifier wakes the world's listener (the last acknowledgement).
//!
//! Waits re-check the shared words after every wake-up, and an event sent before the wait
//! began is kept by iceoryx2 until taken, so no wake-up is lost. Costs: one event per agent and
//! tick to release (iceoryx2 signals each listener), about 37 us each on this VM (see
//! spec/iceoryx2-and-peers.md), against one FUTEX_WAKE for all.

use crate::transport::{
    event, EventCapacity, EventService, Reach, ServiceId, TransportError, TransportResult,
};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use std::time::Duration;

/// Extra ports beyond one per robot: restarted agents open new ones before the dead ones'
/// are cleaned, and the world needs its own.
const SLACK: usize = 8;

/// The bell's two event services: the world rings agents down, agents ring the world up.
const DOWN: &str = "tick/down";
const UP: &str = "tick/up";

/// One process's end of the two event services.
pub struct EventBell {
    notifier: Notifier<ipc::Service>,
    listener: Listener<ipc::Service>,
}

fn services(
    node: &Node<ipc::Service>,
    robots: u32,
    create: bool,
) -> TransportResult<(EventService, EventService)> {
    let n = robots as usize + SLACK;
    let down = Reach::create_if(create, || EventCapacity {
        listeners: n,
        notifiers: 2,
        nodes: n + 2,
    });
    let up = Reach::create_if(create, || EventCapacity {
        listeners: 2,
        notifiers: n,
        nodes: n + 2,
    });
    Ok((
        event(node, ServiceId::from(DOWN), down)?,
        event(node, ServiceId::from(UP), up)?,
    ))
}

fn notifier(svc: &EventService) -> TransportResult<Notifier<ipc::Service>> {
    svc.notifier_builder()
        .create()
        .map_err(|source| TransportError::Notifier {
            service: ServiceId::of(svc),
            source,
        })
}

fn listener(svc: &EventService) -> TransportResult<Listener<ipc::Service>> {
    svc.listener_builder()
        .create()
        .map_err(|source| TransportError::Listener {
            service: ServiceId::of(svc),
            source,
        })
}

impl EventBell {
    /// The world's end: creates both services (before any agent starts).
    pub fn world(node: &Node<ipc::Service>, robots: u32) -> TransportResult<EventBell> {
        let (down, up) = services(node, robots, true)?;
        Ok(EventBell {
            notifier: notifier(&down)?,
            listener: listener(&up)?,
        })
    }

    /// An agent's end.
    pub fn agent(node: &Node<ipc::Service>, robots: u32) -> TransportResult<EventBell> {
        let (down, up) = services(node, robots, false)?;
        Ok(EventBell {
            listener: listener(&down)?,
            notifier: notifier(&up)?,
        })
    }

    /// Wakes the other side (every listener of our notifier's service).
    pub fn ring(&self) {
        // A failed notify only delays the other side to its next poll.
        let _ = self.notifier.notify();
    }

    /// Sleeps until rung or `timeout` passes (spurious wake-ups allowed).
    pub fn wait(&self, timeout: Duration) {
        let _ = self.listener.timed_wait(|_| {}, timeout);
    }
}
