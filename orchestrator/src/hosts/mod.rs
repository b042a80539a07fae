//! Runs across hosts (issue 41, DESIGN section 12, docs/protocol.md section 9).
//!
//! The world process does not change: on the world's host a **gateway** (a thread of the
//! orchestrator, [`gateway`]) is, to the world, the agents of every remote host's robots (it
//! publishes their actions on their `robot/<i>/act` services and speaks the barrier for them);
//! on each remote host a **host proxy** (`orchestrator host`, [`proxy`]) is, to that host's
//! agents, a local world (its own iceoryx2 services and barrier; it starts and supervises
//! them). Once a tick each remote host gets one Zenoh message and sends one back
//! ([`wire`]), so a run across hosts gives the recording of the same run on one host.

pub mod gateway;
mod gateway_tick;
pub mod kill;
pub mod link;
pub mod proxy;
mod proxy_agents;
mod proxy_io;
pub mod wire;

pub use gateway::Hosts;

/// Why a run across hosts could not start or go on.
#[derive(Debug, thiserror::Error)]
pub enum HostsError {
    #[error("zenoh: {what}: {message}")]
    Zenoh { what: String, message: String },
    #[error(
        "host(s) {missing} did not join within runtime.startup_timeout_s = {seconds} s (start \
         `orchestrator host --join ENDPOINT --name NAME` on each, ENDPOINT the world host's \
         listen endpoint {endpoint})"
    )]
    Missing {
        missing: String,
        seconds: u64,
        endpoint: String,
    },
    #[error("host {host}: {message}")]
    Host { host: String, message: String },
    #[error(transparent)]
    Transport(#[from] swarm::transport::TransportError),
    #[error(transparent)]
    Barrier(#[from] swarm::barrier::BarrierError),
    #[error(
        "the run's {service} service did not answer within {seconds} s (is its orchestrator \
         still running?)"
    )]
    Unanswered { service: &'static str, seconds: u64 },
    #[error("{0}")]
    Other(String),
}
