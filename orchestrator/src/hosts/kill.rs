//! `orchestrator kill` (and the viewer's kill button) for a robot that runs on another host:
//! there is no local process to signal, and the world's segment of the barrier, where the
//! kill-order words are, is sealed against every mapping but the world's and its
//! orchestrator's (docs/protocol.md sections 4, 9). So the order goes to the orchestrator that
//! owns the run: its gateway serves the run's `hosts/kill` iceoryx2 request-response service
//! ([`KillServer`]), writes the kill order through its own mapping, and forwards it to the
//! robot's host as it forwards the world's, whose proxy SIGKILLs that agent.

use super::HostsError;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::request_response::PortFactory;
use std::time::{Duration, Instant};
use swarm::transport;

/// The run's kill service (under the run's iceoryx2 prefix, so only that run's): a request
/// is a robot's index, the answer the attach number of the agent ordered killed, or
/// [`NO_LIVE_AGENT`].
const KILL_SERVICE: &str = "hosts/kill";

/// The answer when the robot has no live agent (none attached yet, or its last one is
/// dead), or is not a remote robot of the run.
pub const NO_LIVE_AGENT: u64 = 0;

/// How long `orchestrator kill` waits for the gateway's answer. [chosen] The gateway looks
/// at the service every 2 ms (its idle poll and while it waits for a tick's batches).
const ANSWER_WITHIN: Duration = Duration::from_secs(5);

/// At most this many `orchestrator kill`s (and viewers) at once on one run. [chosen]
const MAX_CLIENTS: usize = 16;

type KillPorts = PortFactory<ipc::Service, u32, (), u64, ()>;

fn service_name() -> Result<ServiceName, HostsError> {
    ServiceName::new(KILL_SERVICE)
        .map_err(|e| HostsError::Other(format!("service name {KILL_SERVICE}: {e:?}")))
}

/// The gateway's side: the run's kill service.
pub struct KillServer {
    server: Server<ipc::Service, u32, (), u64, ()>,
    _service: KillPorts,
}

impl KillServer {
    /// Makes the run's kill service (the gateway, once a run).
    pub fn create(node: &Node<ipc::Service>) -> Result<KillServer, HostsError> {
        let service = node
            .service_builder(&service_name()?)
            .request_response::<u32, u64>()
            .max_clients(MAX_CLIENTS)
            .max_servers(1)
            .create()
            .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} service: {e:?}")))?;
        let server = service
            .server_builder()
            .create()
            .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} server: {e:?}")))?;
        Ok(KillServer {
            server,
            _service: service,
        })
    }

    /// Answers every pending request: `order(robot)` orders that robot's live agent killed
    /// and returns its attach number ([`NO_LIVE_AGENT`]: none).
    pub fn serve(&self, mut order: impl FnMut(u32) -> u64) -> Result<(), HostsError> {
        while let Some(request) = self
            .server
            .receive()
            .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} receive: {e:?}")))?
        {
            let attach = order(*request.payload());
            // A client that gave up meanwhile misses the answer; the order stands.
            let _ = request.send_copy(attach);
        }
        Ok(())
    }
}

/// Asks the gateway of the run with prefix `prefix` to kill robot `robot`'s agent: the
/// attach number it ordered killed, or [`NO_LIVE_AGENT`].
fn ask(prefix: &str, robot: u32) -> Result<u64, HostsError> {
    let config = transport::run_config(prefix)?;
    let node = transport::node(&config, "kill")?;
    let service = node
        .service_builder(&service_name()?)
        .request_response::<u32, u64>()
        .open()
        .map_err(|e| {
            HostsError::Other(format!(
                "the run's {KILL_SERVICE} service (its gateway serves it once its hosts \
                 joined): {e:?}"
            ))
        })?;
    let client = service
        .client_builder()
        .create()
        .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} client: {e:?}")))?;
    let pending = client
        .send_copy(robot)
        .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} request: {e:?}")))?;
    let until = Instant::now() + ANSWER_WITHIN;
    loop {
        if let Some(answer) = pending
            .receive()
            .map_err(|e| HostsError::Other(format!("{KILL_SERVICE} answer: {e:?}")))?
        {
            return Ok(*answer.payload());
        }
        if !pending.is_connected() || Instant::now() >= until {
            return Err(HostsError::Unanswered {
                service: KILL_SERVICE,
                seconds: ANSWER_WITHIN.as_secs(),
            });
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Orders robot `robot`'s current agent on its host killed; the line to print ("killed ..."
/// as for a local agent: its proxy SIGKILLs it within milliseconds).
pub fn kill_remote(prefix: &str, run_id: &str, robot: u32) -> String {
    match ask(prefix, robot) {
        Ok(NO_LIVE_AGENT) => format!("robot {robot}: no live agent on its host (already dead?)"),
        Ok(attach) => format!(
            "killed robot {robot} of run {run_id} (on its host: its agent of attach {attach}, \
             ordered through the run's gateway)"
        ),
        Err(e) => format!("robot {robot}: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kill request reaches the gateway's server through real iceoryx2 services, from
    /// another thread of the same process as the viewer's button sends it (and from another
    /// process as `orchestrator kill` does, the same calls), and its answer comes back; no
    /// server: a clear error, no hang.
    #[test]
    fn a_kill_request_is_answered_by_the_runs_server() {
        let prefix = transport::prefix_for(&format!("unit-kill-{}", std::process::id()));
        let config = transport::run_config(&prefix).unwrap();
        let node = transport::node(&config, "gateway").unwrap();
        let no_server = kill_remote(&prefix, "r1", 3);
        assert!(no_server.contains("hosts/kill"), "{no_server}");
        let server = KillServer::create(&node).unwrap();
        let p = prefix.clone();
        let asks = std::thread::spawn(move || (kill_remote(&p, "r1", 3), kill_remote(&p, "r1", 4)));
        let mut seen = Vec::new();
        while !asks.is_finished() {
            server
                .serve(|robot| {
                    seen.push(robot);
                    if robot == 3 {
                        7
                    } else {
                        NO_LIVE_AGENT
                    }
                })
                .unwrap();
            std::thread::sleep(Duration::from_millis(1));
        }
        let (killed, dead) = asks.join().unwrap();
        assert_eq!(seen, vec![3, 4]);
        assert!(killed.starts_with("killed robot 3 of run r1"), "{killed}");
        assert!(killed.contains("attach 7"), "{killed}");
        assert!(dead.contains("no live agent"), "{dead}");
        drop(server);
        drop(node);
        swarm::cleanup::remove_run(&prefix);
    }
}
