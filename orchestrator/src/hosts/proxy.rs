//! `orchestrator host --join ENDPOINT --name NAME`: a remote host's proxy. It joins the world
//! host's Zenoh endpoint, waits for a run that places robots on it (`[[hosts]]`), and is to
//! those robots' agents a local world: its own iceoryx2 prefix, services and barrier, the
//! agents started and supervised here. Each tick it publishes what the world's host sent,
//! releases the tick, waits for its agents' actions and sends them back as one batch. It
//! serves one run, then exits.

use super::proxy_agents::Agents;
use super::proxy_io::{robots_in, LocalWorld};
use super::wire::{self, Down, Up};
use super::{link, HostsError};
use crate::{exit, signals};
use clap::Args;
use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};
use swarm::scenario::Scenario;

#[derive(Args, Debug, Clone)]
pub struct HostArgs {
    /// The world host's Zenoh endpoint (its `up --listen`, or the scenario's `hosts_listen`),
    /// e.g. tcp/10.7.0.1:7447.
    #[arg(long, value_name = "ENDPOINT")]
    pub join: String,
    /// This host's name, as the scenario's `[[hosts]]` gives it.
    #[arg(long)]
    pub name: String,
    /// Seconds to keep trying to reach the world's host and to wait for a run.
    #[arg(long, value_name = "SECONDS", default_value_t = JOIN_PATIENCE_S)]
    pub wait: u64,
    /// The folder in which the run's folder (`swarm-host-NAME-RUN`: the run's scenario and
    /// its robots' logs, `logs/robot-<i>.log`) is made; it stays after the run. Default: the
    /// system's temporary folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// How long a proxy waits for the world's host and its run by default. [chosen] Long enough
/// to start the proxies first and `up` after, by hand.
const JOIN_PATIENCE_S: u64 = 600;

/// How long the proxy sleeps at most between looks at its agents and at the link.
const POLL: Duration = Duration::from_millis(2);

/// What reaches the proxy's loop from the link.
enum Msg {
    Down(Down),
    Bad(String),
    WorldGone,
}

pub fn host(a: HostArgs) -> i32 {
    signals::install();
    if let Err(m) = swarm::sections::hosts::check_endpoint(&a.join) {
        eprintln!("error: --join {m}");
        return exit::BAD_INPUT;
    }
    let ok_name = !a.name.is_empty()
        && a.name.len() <= swarm::sections::hosts::MAX_HOST_NAME
        && a.name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_');
    if !ok_name {
        eprintln!(
            "error: --name {:?} is not a host name: allowed 1 to {} letters, digits, `-` and `_`",
            a.name,
            swarm::sections::hosts::MAX_HOST_NAME
        );
        return exit::BAD_INPUT;
    }
    match serve(&a) {
        Ok(()) => exit::COMPLETE,
        Err(e) => {
            eprintln!("error: host {}: {e}", a.name);
            exit::FAILED
        }
    }
}

fn serve(a: &HostArgs) -> Result<(), HostsError> {
    let patience = Duration::from_secs(a.wait);
    let session = link::join(&a.join, patience)?;
    let (tx, rx) = mpsc::channel();
    let down_tx = tx.clone();
    // The subscriber first, the token after: the world's host sends the run's start when it
    // sees the token.
    let _down = link::subscribe(&session, &wire::down_key(&a.name), move |_, bytes| {
        let _ = down_tx.send(match Down::decode(&bytes) {
            Ok(d) => Msg::Down(d),
            Err(e) => Msg::Bad(e.to_string()),
        });
    })?;
    let _world = link::watch(&session, wire::WORLD_TOKEN, move |_, alive| {
        if !alive {
            let _ = tx.send(Msg::WorldGone);
        }
    })?;
    let up = link::publisher(&session, wire::up_key(&a.name))?;
    let _token = link::token(&session, &wire::token_key(&a.name))?;
    eprintln!("host {}: joined {}, waiting for a run", a.name, a.join);
    let until = Instant::now() + patience;
    let (run_id, scenario, robots) = loop {
        if signals::interrupted() {
            return Ok(());
        }
        if Instant::now() > until {
            return Err(HostsError::Other(format!(
                "no run placed robots on this host within --wait {} s",
                a.wait
            )));
        }
        match rx.recv_timeout(POLL * 50) {
            Ok(Msg::Down(Down::Start {
                run_id,
                scenario,
                robots,
            })) => break (run_id, scenario, robots),
            Ok(Msg::Bad(m)) => return Err(HostsError::Other(m)),
            _ => {}
        }
    };
    let mut tell = |u: Up| link::put(&up, u.encode());
    let result = run(a, &run_id, &scenario, &robots, &rx, &mut tell);
    if let Err(e) = &result {
        let _ = tell(Up::Failed(e.to_string()));
    }
    result
}

fn run(
    a: &HostArgs,
    run_id: &str,
    text: &str,
    robots: &[u32],
    rx: &Receiver<Msg>,
    tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
) -> Result<(), HostsError> {
    let sc = Scenario::parse(text, "the run's scenario from the world's host")
        .map_err(|e| HostsError::Other(e.to_string()))?;
    // Its own prefix: on one machine (the tests' namespaces share /dev/shm) the world's
    // host's files and each proxy's never meet.
    let prefix = swarm::transport::prefix_for(&format!("{run_id}@{}", a.name));
    let dir = a
        .out
        .clone()
        .unwrap_or_else(std::env::temp_dir)
        .join(format!("swarm-host-{}-{run_id}", a.name));
    let scenario_path: PathBuf = dir.join("scenario.toml");
    std::fs::create_dir_all(&dir)
        .and_then(|_| std::fs::write(&scenario_path, text))
        .map_err(|e| HostsError::Other(format!("{}: {e}", scenario_path.display())))?;
    let mut agents = Agents::new(&sc, &prefix, run_id, scenario_path, dir.clone());
    let result = LocalWorld::create(&sc, &prefix, robots)
        .and_then(|mut world| serve_run(&sc, robots, &mut world, &mut agents, rx, tell));
    agents.kill_all();
    swarm::cleanup::remove_run(&prefix);
    eprintln!(
        "host {}: run {run_id} over; its robots' logs: {}",
        a.name,
        dir.join(crate::agent_spawn::LOGS_DIR).display()
    );
    result
}

fn serve_run(
    sc: &Scenario,
    robots: &[u32],
    world: &mut LocalWorld,
    agents: &mut Agents,
    rx: &Receiver<Msg>,
    tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
) -> Result<(), HostsError> {
    for &r in robots {
        agents.spawn(r, world)?;
    }
    tell(Up::Ready)?;
    let deadline = Duration::from_millis(sc.runtime.ack_deadline_ms);
    loop {
        if signals::interrupted() {
            break;
        }
        agents.supervise(world, tell)?;
        let msg = match rx.recv_timeout(POLL) {
            Ok(m) => m,
            Err(RecvTimeoutError::Timeout) => continue,
            Err(RecvTimeoutError::Disconnected) => break,
        };
        match msg {
            Msg::Down(Down::Tick {
                tick,
                sense,
                air_header,
                air,
            }) => {
                agents.tick = tick;
                world.publish(tick, sc.run.robots, &sense, air_header, &air)?;
                let live: Vec<u32> = robots_in(&sense)
                    .into_iter()
                    .filter(|r| robots.contains(r))
                    .collect();
                world.barrier.release(tick, live.len() as u32);
                if !wait_tick(world, agents, rx, tell, tick, live.clone(), deadline)? {
                    break;
                }
                let acts = live.iter().filter_map(|&r| world.take(r, tick)).collect();
                tell(Up::Batch { tick, acts })?;
            }
            Msg::Down(Down::Kill { robot, attach }) => agents.kill(robot, attach),
            Msg::Down(Down::Stop) | Msg::WorldGone => break,
            Msg::Down(Down::Start { .. }) => {}
            Msg::Bad(m) => return Err(HostsError::Other(m)),
        }
    }
    agents.ending = true;
    world.barrier.shutdown();
    Ok(())
}

/// Waits until each of `wait` (the tick's live robots here) has acknowledged tick `k` with
/// its action on its act service, died, or been silent for `deadline` since the last
/// progress (then the world's own deadline judges it). False: the run ended meanwhile.
fn wait_tick(
    world: &mut LocalWorld,
    agents: &mut Agents,
    rx: &Receiver<Msg>,
    tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    k: u64,
    mut wait: Vec<u32>,
    deadline: Duration,
) -> Result<bool, HostsError> {
    let mut progress = Instant::now();
    // Who drives each robot as the tick is released: a robot whose agent is reaped before it
    // answered is not waited for (it may have died, and been reaped by an earlier look,
    // before the world's host released the tick with its record: its death is told, and the
    // world does not wait for it either); a replacement answers from the next tick.
    let drivers = agents.drivers();
    wait.retain(|r| drivers.get(r).is_some_and(|&pid| agents.runs(pid)));
    loop {
        let before = wait.len();
        wait.retain(|&r| !(world.barrier.acked(r, k) && world.arrived(r, k)));
        if wait.is_empty() {
            return Ok(true);
        }
        if wait.len() < before {
            progress = Instant::now();
        }
        if progress.elapsed() > deadline {
            return Ok(true);
        }
        world.barrier.wait_acks(POLL);
        let dead = agents.supervise(world, tell)?;
        wait.retain(|r| !dead.contains(r) && drivers.get(r).is_some_and(|&pid| agents.runs(pid)));
        while let Ok(m) = rx.try_recv() {
            match m {
                Msg::Down(Down::Kill { robot, attach }) => agents.kill(robot, attach),
                Msg::Down(Down::Stop) | Msg::WorldGone => return Ok(false),
                Msg::Bad(m) => return Err(HostsError::Other(m)),
                Msg::Down(_) => {}
            }
        }
        if signals::interrupted() {
            return Ok(false);
        }
    }
}
