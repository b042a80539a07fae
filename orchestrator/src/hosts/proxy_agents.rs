//! A host proxy's agents: started as the orchestrator starts them (`agent --robot I --prefix
//! P --run-id ID --scenario FILE`), reaped, restarted under the run's fault policy
//! (`faults.on_fault`, `faults.max_restarts`, `processes::START_FAILURES` for agents that exit
//! before attaching), SIGKILLed on the world's kill orders. Every attach and every death is
//! told to the world's host (`Up::Attached`, `Up::Died`), which mirrors them into the world's
//! barrier and control channel.

use super::wire::Up;
use super::HostsError;
use crate::processes::{self, bin, describe, exit_of, kill, reap};
use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use swarm::barrier::TickBarrier;
use swarm::scenario::{FaultPolicy, Scenario};

/// One agent process: its robot and the robot's attach count when it was started.
struct Agent {
    robot: u32,
    base: u64,
}

pub struct Agents {
    prefix: String,
    run_id: String,
    scenario: PathBuf,
    restart: bool,
    max_restarts: u32,
    agents: BTreeMap<u32, Agent>,
    restarts: Vec<u32>,
    start_failures: Vec<u32>,
    /// Each robot's local attaches already told to the world's host.
    told: Vec<u64>,
    /// Set once the run ends: deaths are no faults any more.
    pub ending: bool,
}

impl Agents {
    pub fn new(sc: &Scenario, prefix: &str, run_id: &str, scenario: PathBuf) -> Agents {
        let n = sc.run.robots as usize;
        Agents {
            prefix: prefix.to_string(),
            run_id: run_id.to_string(),
            scenario,
            restart: sc.faults.on_fault == FaultPolicy::Restart,
            max_restarts: sc.faults.max_restarts,
            agents: BTreeMap::new(),
            restarts: vec![0; n],
            start_failures: vec![0; n],
            told: vec![0; n],
            ending: false,
        }
    }

    fn command(&self, robot: u32) -> Command {
        let mut c = Command::new(bin("agent"));
        c.args(["--robot", &robot.to_string(), "--prefix", &self.prefix])
            .args(["--run-id", &self.run_id, "--scenario"])
            .arg(&self.scenario);
        c
    }

    /// Starts an agent of `robot`.
    pub fn spawn(&mut self, robot: u32, barrier: &TickBarrier) -> Result<(), HostsError> {
        let child = self
            .command(robot)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .process_group(0)
            .spawn()
            .map_err(|e| {
                HostsError::Other(format!("cannot start {}: {e}", bin("agent").display()))
            })?;
        let base = barrier.attach_count(robot);
        self.agents.insert(child.id(), Agent { robot, base });
        Ok(())
    }

    /// Tells new attaches, reaps dead agents (told as deaths, restarted under the policy).
    /// Returns the robots whose agent died; `tell` sends to the world's host.
    pub fn supervise(
        &mut self,
        barrier: &TickBarrier,
        node: &iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
        tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    ) -> Result<Vec<u32>, HostsError> {
        self.tell_attaches(barrier, tell)?;
        let mut dead = Vec::new();
        while let Some((pid, st)) = reap() {
            let Some(Agent { robot, base }) = self.agents.remove(&pid) else {
                continue;
            };
            let attached = barrier.attach_count(robot) > base;
            if self.ending || barrier.is_shutdown() || (attached && exit_of(st) == Ok(0)) {
                continue;
            }
            let r = robot as usize;
            dead.push(robot);
            if attached {
                self.start_failures[r] = 0;
            } else {
                self.start_failures[r] += 1;
                let limit = if self.restart {
                    processes::START_FAILURES
                } else {
                    1
                };
                if self.start_failures[r] >= limit {
                    tell(Up::Failed(format!(
                        "robot {robot} failed: its agent exited before attaching to the run {} \
                         time(s) in a row (last: {})",
                        self.start_failures[r],
                        describe(st)
                    )))?;
                    continue;
                }
            }
            tell(Up::Died { robot, attached })?;
            let budget = !attached || self.restarts[r] < self.max_restarts;
            if self.restart && budget {
                self.spawn(robot, barrier)?;
                if attached {
                    self.restarts[r] += 1;
                }
                processes::cleanup_dead_agents(node, &self.prefix);
            }
        }
        Ok(dead)
    }

    fn tell_attaches(
        &mut self,
        barrier: &TickBarrier,
        tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    ) -> Result<(), HostsError> {
        for r in 0..self.told.len() {
            let c = barrier.attach_count(r as u32);
            while self.told[r] < c {
                self.told[r] += 1;
                tell(Up::Attached { robot: r as u32 })?;
            }
        }
        Ok(())
    }

    /// The world ordered robot `robot`'s agent with attach number `attach` killed: SIGKILL
    /// that incarnation if it still runs (never a replacement that has not taken over).
    pub fn kill(&self, robot: u32, attach: u64, barrier: &TickBarrier) {
        for (&pid, a) in &self.agents {
            if a.robot == robot && barrier.attach_count(robot) > a.base && a.base + 1 == attach {
                kill(pid);
            }
        }
    }

    /// SIGKILLs every agent and waits (briefly) until they are reaped.
    pub fn kill_all(&mut self) {
        self.ending = true;
        for &pid in self.agents.keys() {
            kill(pid);
        }
        let t = std::time::Instant::now();
        while !self.agents.is_empty() && t.elapsed() < AGENTS_GONE_WAIT {
            while let Some((pid, _)) = reap() {
                self.agents.remove(&pid);
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
    }
}

/// How long the proxy's end waits for its SIGKILLed agents before it removes their files.
const AGENTS_GONE_WAIT: std::time::Duration = std::time::Duration::from_secs(5);
