//! A host proxy's agents: started as the orchestrator starts them ([`Launcher`]: the built-in
//! agent or the robot's `[[agents]]` program, the barrier's descriptors inherited, output
//! appended to the robot's log in the proxy's run folder), reaped, restarted under the run's
//! fault policy (`faults.on_fault`, `faults.max_restarts`, `processes::START_FAILURES` for
//! agents that exit before attaching; an `[[agents]]` program that does not attach within its
//! attach timeout is killed), SIGKILLed on the world's kill orders. An agent has attached when
//! a new attach notice came through its robot's act service (one agent of a robot lives at a
//! time, and only it can publish there). Every attach and every death is told to the world's
//! host (`Up::Attached`, `Up::Died`), which mirrors them into the world's barrier, act services
//! and control channel: the k-th attach told of a robot is its attach number k on the world's
//! side, which the world's kill orders name. The proxy keeps that number per agent, never
//! reading it back from the barrier's attach words, which every agent can write.

use super::proxy_io::LocalWorld;
use super::wire::Up;
use super::HostsError;
use crate::agent_spawn::Launcher;
use crate::processes::{self, describe, exit_of, kill, reap};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use swarm::scenario::{FaultPolicy, Scenario};

/// One agent process: its robot, its attach number on the world's side once it attached,
/// when it started and how long it may take to attach.
struct Agent {
    robot: u32,
    attach: Option<u64>,
    started: Instant,
    attach_timeout: Option<Duration>,
}

pub struct Agents {
    sc: Scenario,
    prefix: String,
    run_id: String,
    /// The run's scenario as the proxy wrote it (what every agent reads).
    scenario: PathBuf,
    /// The proxy's run folder: the robots' logs are in its `logs/`.
    run_dir: PathBuf,
    restart: bool,
    max_restarts: u32,
    agents: BTreeMap<u32, Agent>,
    restarts: Vec<u32>,
    start_failures: Vec<u32>,
    /// Agents started per robot (the marks in its log count them).
    starts: Vec<u32>,
    /// Each robot's attaches told to the world's host (its last attach number there).
    told: Vec<u64>,
    /// Each robot's highest attach notice already taken as an agent's attach.
    noticed: Vec<u64>,
    /// Agents killed for not attaching within their attach timeout.
    timed_out: BTreeMap<u32, Duration>,
    /// The last tick the world's host released (for the start marks in the logs).
    pub tick: u64,
    /// Set once the run ends: deaths are no faults any more.
    pub ending: bool,
}

impl Agents {
    pub fn new(
        sc: &Scenario,
        prefix: &str,
        run_id: &str,
        scenario: PathBuf,
        run_dir: PathBuf,
    ) -> Agents {
        let n = sc.run.robots as usize;
        Agents {
            sc: sc.clone(),
            prefix: prefix.to_string(),
            run_id: run_id.to_string(),
            scenario,
            run_dir,
            restart: sc.faults.on_fault == FaultPolicy::Restart,
            max_restarts: sc.faults.max_restarts,
            agents: BTreeMap::new(),
            restarts: vec![0; n],
            start_failures: vec![0; n],
            starts: vec![0; n],
            told: vec![0; n],
            noticed: vec![0; n],
            timed_out: BTreeMap::new(),
            tick: 0,
            ending: false,
        }
    }

    fn launcher<'a>(&'a self, world: &'a LocalWorld) -> Launcher<'a> {
        Launcher {
            sc: &self.sc,
            prefix: &self.prefix,
            run_id: &self.run_id,
            scenario_path: &self.scenario,
            run_dir: &self.run_dir,
            barrier_fds: &world.barrier_fds,
        }
    }

    /// Starts an agent of `robot`.
    /// The pid of each robot's attached agent process, now (a tick's drivers at its release).
    pub fn drivers(&self) -> BTreeMap<u32, u32> {
        self.agents
            .iter()
            .filter(|(_, a)| a.attach.is_some())
            .map(|(&pid, a)| (a.robot, pid))
            .collect()
    }

    /// Whether agent process `pid` has not been reaped.
    pub fn runs(&self, pid: u32) -> bool {
        self.agents.contains_key(&pid)
    }

    pub fn spawn(&mut self, robot: u32, world: &LocalWorld) -> Result<(), HostsError> {
        let r = robot as usize;
        self.starts[r] += 1;
        let launcher = self.launcher(world);
        let (pid, _) = launcher
            .spawn(robot, self.starts[r], self.tick)
            .map_err(HostsError::Other)?;
        let agent = Agent {
            robot,
            attach: None,
            started: Instant::now(),
            attach_timeout: launcher.attach_timeout(robot),
        };
        self.agents.insert(pid, agent);
        Ok(())
    }

    /// Tells new attaches, kills agents that did not attach in time, reaps dead agents (told
    /// as deaths, restarted under the policy). Returns the robots whose agent died; `tell`
    /// sends to the world's host.
    pub fn supervise(
        &mut self,
        world: &mut LocalWorld,
        tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    ) -> Result<Vec<u32>, HostsError> {
        self.tell_attaches(world, tell)?;
        self.kill_unattached();
        let mut dead = Vec::new();
        while let Some((pid, st)) = reap() {
            let Some(mut agent) = self.agents.remove(&pid) else {
                continue;
            };
            // Its notice may have come after the last look.
            self.note_attach(&mut agent, world, tell)?;
            let (robot, attached) = (agent.robot, agent.attach.is_some());
            let timeout = self.timed_out.remove(&pid);
            if self.ending || world.barrier.is_shutdown() || (attached && exit_of(st) == Ok(0)) {
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
                    let how = match timeout {
                        Some(t) => format!(
                            "did not attach within its attach timeout of {} s and was killed",
                            t.as_secs_f64()
                        ),
                        None => format!("exited before attaching ({})", describe(st)),
                    };
                    let launcher = self.launcher(world);
                    tell(Up::Failed(format!(
                        "robot {robot} failed: its agent {how}, {} time(s) in a row; command: \
                         {}; its log on the host: {}, ending:\n{}",
                        self.start_failures[r],
                        launcher.describe(robot),
                        crate::agent_spawn::log_path(&self.run_dir, robot).display(),
                        launcher.log_tail(robot)
                    )))?;
                    continue;
                }
            }
            tell(Up::Died {
                robot,
                attached,
                status: st,
            })?;
            // A blackboard is made anew for the replacement (its dead writer's entries stay
            // taken): the proxy lets go of it now and makes it once the cleanup removed it.
            world.retire(robot);
            let budget = !attached || self.restarts[r] < self.max_restarts;
            if self.restart && budget {
                self.spawn(robot, world)?;
                if attached {
                    self.restarts[r] += 1;
                }
                processes::cleanup_dead_agents(&world.node, &self.prefix);
            }
        }
        Ok(dead)
    }

    /// Tells the attach of every agent whose notice came.
    fn tell_attaches(
        &mut self,
        world: &mut LocalWorld,
        tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    ) -> Result<(), HostsError> {
        let mut agents = std::mem::take(&mut self.agents);
        let result = agents
            .values_mut()
            .try_for_each(|a| self.note_attach(a, world, tell));
        self.agents = agents;
        result
    }

    /// If `a` has not attached yet and its robot's act service brought a new attach notice,
    /// `a` attached (it is its robot's only agent): it gets the robot's next attach number
    /// on the world's side, told to the world's host.
    fn note_attach(
        &mut self,
        a: &mut Agent,
        world: &mut LocalWorld,
        tell: &mut dyn FnMut(Up) -> Result<(), HostsError>,
    ) -> Result<(), HostsError> {
        let r = a.robot as usize;
        if a.attach.is_some() {
            return Ok(());
        }
        let notice = world.attached(a.robot);
        if notice <= self.noticed[r] {
            return Ok(());
        }
        self.noticed[r] = notice;
        self.told[r] += 1;
        a.attach = Some(self.told[r]);
        tell(Up::Attached { robot: a.robot })
    }

    /// SIGKILLs each agent with an attach timeout (an `[[agents]]` program) that has not
    /// attached within it (reaped as a start failure).
    fn kill_unattached(&mut self) {
        for (&pid, a) in &self.agents {
            let Some(t) = a.attach_timeout else { continue };
            if self.timed_out.contains_key(&pid) || a.started.elapsed() < t {
                continue;
            }
            if a.attach.is_none() {
                kill(pid);
                self.timed_out.insert(pid, t);
            }
        }
    }

    /// The world ordered robot `robot`'s agent with attach number `attach` killed: SIGKILL
    /// that incarnation if it still runs (never a replacement that has not taken over).
    pub fn kill(&self, robot: u32, attach: u64) {
        for (&pid, a) in &self.agents {
            if a.robot == robot && a.attach == Some(attach) {
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
        let t = Instant::now();
        while !self.agents.is_empty() && t.elapsed() < AGENTS_GONE_WAIT {
            while let Some((pid, _)) = reap() {
                self.agents.remove(&pid);
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

/// How long the proxy's end waits for its SIGKILLed agents before it removes their files.
const AGENTS_GONE_WAIT: Duration = Duration::from_secs(5);
