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

use crate::transport::{err, Result};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use std::time::Duration;

/// Extra ports beyond one per robot: restarted agents open new ones before the dead ones'
/// are cleaned, and the world needs its own.
const SLACK: usize = 8;

/// One process's end of the two event services.
pub struct EventBell {
    notifier: Notifier<ipc::Service>,
    listener: Listener<ipc::Service>,
}

fn services(
    node: &Node<ipc::Service>,
    robots: u32,
    create: bool,
) -> Result<(
    iceoryx2::service::port_factory::event::PortFactory<ipc::Service>,
    iceoryx2::service::port_factory::event::PortFactory<ipc::Service>,
)> {
    let n = robots as usize + SLACK;
    let name = |s: &str| ServiceName::new(s).map_err(|e| err("service name", e));
    let down = node.service_builder(&name("tick/down")?).event();
    let up = node.service_builder(&name("tick/up")?).event();
    if create {
        let down = down
            .max_listeners(n)
            .max_notifiers(2)
            .max_nodes(n + 2)
            .create()
            .map_err(|e| err("create tick/down", e))?;
        let up = up
            .max_listeners(2)
            .max_notifiers(n)
            .max_nodes(n + 2)
            .create()
            .map_err(|e| err("create tick/up", e))?;
        Ok((down, up))
    } else {
        let down = down.open().map_err(|e| err("open tick/down", e))?;
        let up = up.open().map_err(|e| err("open tick/up", e))?;
        Ok((down, up))
    }
}

impl EventBell {
    /// The world's end: creates both services (before any agent starts).
    pub fn world(node: &Node<ipc::Service>, robots: u32) -> Result<EventBell> {
        let (down, up) = services(node, robots, true)?;
        Ok(EventBell {
            notifier: down
                .notifier_builder()
                .create()
                .map_err(|e| err("tick/down notifier", e))?,
            listener: up
                .listener_builder()
                .create()
                .map_err(|e| err("tick/up listener", e))?,
        })
    }

    /// An agent's end.
    pub fn agent(node: &Node<ipc::Service>, robots: u32) -> Result<EventBell> {
        let (down, up) = services(node, robots, false)?;
        Ok(EventBell {
            listener: down
                .listener_builder()
                .create()
                .map_err(|e| err("tick/down listener", e))?,
            notifier: up
                .notifier_builder()
                .create()
                .map_err(|e| err("tick/up notifier", e))?,
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
