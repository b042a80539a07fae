//! The multi-process executor: one world process and one agent process per robot.

use crate::agent_spawn::{self, Launcher};
use crate::registry::{self, RegistryError, RunEntry};
use crate::signals;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use swarm::barrier::TickBarrier;
use swarm::frames::{Control, WorldStatus, CONTROL_ROBOT_DIED, CONTROL_STOP};
use swarm::scenario::{FaultPolicy, Scenario};
use swarm::{cleanup, transport};

/// How long the world gets to finish after a stop request before everything is killed.
const STOP_GRACE: Duration = Duration::from_secs(10);
/// How long agents get to exit after the world shut the run down (agents waiting for a tick
/// exit within a few ms of the shutdown word; the rest, still starting, are killed: the
/// run's outputs are written and its /dev/shm is removed after them anyway).
const AGENT_EXIT_GRACE: Duration = Duration::from_millis(500);
/// How long the end of a run waits for its SIGKILLed processes to be gone before it removes
/// their files.
const PROCESS_GONE_WAIT: Duration = Duration::from_secs(5);
/// How often the orchestrator reaps children and refreshes the progress bar.
const SUPERVISE_PERIOD: Duration = Duration::from_millis(5);
/// How long the world may take to create the run's services.
const READY_TIMEOUT: Duration = Duration::from_secs(60);
/// The error of a run interrupted before its world was ready (up prints it, exit 130).
pub const INTERRUPTED_AT_START: &str = "interrupted during start-up, before any tick";
/// How often the run registry (read by `orchestrator status`) is refreshed.
const REGISTRY_PERIOD: Duration = Duration::from_millis(50);
/// How many agents of one robot in a row may exit before attaching to the run, under
/// `faults.on_fault = "restart"`, before the robot counts as failed and the run ends (a
/// program that exits at once is not restarted for ever, and never waited on for the whole
/// `runtime.startup_timeout_s`). Under "drop" one such exit fails the robot. [chosen] Enough
/// for a replacement that lost a race with the run's end; a broken program fails in ~0.1 s.
pub const START_FAILURES: u32 = 3;

pub struct ProcessRun<'a> {
    pub sc: &'a Scenario,
    pub run_id: &'a str,
    pub run_dir: &'a Path,
    pub on_status: &'a mut dyn FnMut(&WorldStatus),
    /// The world flushes recording.bin after every tick (`up --view` reads it as it grows).
    pub live: bool,
}

#[derive(Debug)]
pub struct ProcessOutcome {
    /// Exit status of the world: Ok(code) or Err(signal).
    pub world_exit: Result<i32, i32>,
    pub shm_removed: usize,
    /// A robot whose agent kept exiting before it attached: the run was stopped for it.
    pub failed_robot: Option<RobotFailure>,
}

/// A robot none of whose agents got as far as attaching to the run.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "robot {robot} failed: its agent exited before attaching to the run {times} time(s) in a \
     row (last: {status}); command: {command}{log}"
)]
pub struct RobotFailure {
    pub robot: u32,
    pub times: u32,
    /// How the last one ended ("exit code 3", "signal 9", "did not attach within 2 s").
    pub status: String,
    pub command: String,
    /// The last one's exit code, if it exited (2: it refused its input, e.g. its params).
    pub exit_code: Option<i32>,
    /// The robot's log and its last lines ("" when empty), shown under the message.
    pub log: String,
}

/// Why a run of processes could not be run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("{INTERRUPTED_AT_START}")]
    InterruptedAtStart,
    #[error(transparent)]
    Registry(#[from] RegistryError),
    #[error("{0}")]
    Other(String),
}

impl From<String> for RunError {
    fn from(s: String) -> RunError {
        if s == INTERRUPTED_AT_START {
            RunError::InterruptedAtStart
        } else {
            RunError::Other(s)
        }
    }
}

pub(crate) fn bin(name: &str) -> PathBuf {
    registry::binary(name)
}

/// "exit code C" or "signal S" of a waitpid status.
pub(crate) fn describe(status: i32) -> String {
    match exit_of(status) {
        Ok(c) => format!("exit code {c}"),
        Err(s) => format!("signal {s}"),
    }
}

/// One agent process of the run.
struct Agent {
    robot: u32,
    /// The robot's attach count when this agent was started.
    base: u64,
    /// When it was started, and how long it may take to attach (`[[agents]]` programs).
    started: Instant,
    attach_timeout: Option<Duration>,
}

/// Decoded waitpid status.
pub(crate) fn exit_of(status: i32) -> Result<i32, i32> {
    if libc::WIFEXITED(status) {
        Ok(libc::WEXITSTATUS(status))
    } else {
        Err(libc::WTERMSIG(status))
    }
}

pub(crate) fn kill(pid: u32) {
    // SAFETY: plain kill of our own child.
    unsafe {
        libc::kill(pid as i32, libc::SIGKILL);
    }
}

/// Whether process `pid` has exited (gone, or a zombie not reaped yet).
fn exited(pid: u32) -> bool {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    match stat
        .rfind(')')
        .and_then(|i| stat[i + 1..].split_whitespace().next())
    {
        Some(state) => state == "Z" || state == "X",
        None => true,
    }
}

/// Reaps one exited child, if any.
pub(crate) fn reap() -> Option<(u32, i32)> {
    let mut status = 0;
    // SAFETY: waitpid on our own children with a valid status pointer.
    let pid = unsafe { libc::waitpid(-1, &mut status, libc::WNOHANG) };
    (pid > 0).then_some((pid as u32, status))
}

/// Runs the scenario; a robot that failed (its agents never attached) is an error here, for
/// callers that only read the summary (experiments, benchmarks).
pub fn run(p: ProcessRun) -> Result<ProcessOutcome, String> {
    let o = run_typed(p).map_err(|e| e.to_string())?;
    match &o.failed_robot {
        Some(f) => Err(f.to_string()),
        None => Ok(o),
    }
}

/// [`run`] with its errors typed: `up` tells a run id in use (bad input) from a failure.
pub fn run_typed(mut p: ProcessRun) -> Result<ProcessOutcome, RunError> {
    let sc = p.sc;
    let prefix = transport::prefix_for(p.run_id);
    let scenario_path = p.run_dir.join("scenario.toml");
    let me = std::process::id();
    let mut entry = RunEntry {
        run_id: p.run_id.to_string(),
        prefix: prefix.clone(),
        orchestrator_pid: me,
        orchestrator_start: registry::start_time(me).unwrap_or(0),
        world_pid: 0,
        world_start: 0,
        agent_pids: vec![],
        agent_starts: vec![],
        tick: 0,
        alive: 0,
        dead: 0,
        restarted: 0,
        run_dir: p.run_dir.display().to_string(),
    };
    // First: a run id held by a live run is refused before anything of this run exists (the
    // cleanup below would otherwise remove the other run's files).
    registry::create(&entry)?;
    if let Err(e) = std::fs::create_dir_all(p.run_dir)
        .map_err(|e| format!("{}: {e}", p.run_dir.display()))
        .and_then(|_| {
            world::output::write_atomic(&scenario_path, sc.to_toml().as_bytes())
                .map_err(|e| e.to_string())
        })
    {
        registry::remove(p.run_id);
        return Err(RunError::Other(e));
    }
    let result = supervise(&mut p, &prefix, &scenario_path, &mut entry).map_err(RunError::from);
    // Whatever happened: no process and nothing in /dev/shm of this run stays.
    for &pid in std::iter::once(&entry.world_pid).chain(entry.agent_pids.iter()) {
        if pid != 0 && registry::pid_alive(pid) {
            kill(pid);
        }
    }
    // Wait until every process of the run is gone (a SIGKILLed agent can still be finishing a
    // system call that makes a link's files), then remove what they left.
    let deadline = Instant::now() + PROCESS_GONE_WAIT;
    for &pid in std::iter::once(&entry.world_pid).chain(entry.agent_pids.iter()) {
        while pid != 0 && registry::pid_alive(pid) && Instant::now() < deadline {
            let mut status = 0;
            // SAFETY: waitpid on a child of ours (or a pid already reaped: ECHILD).
            let r = unsafe { libc::waitpid(pid as i32, &mut status, libc::WNOHANG) };
            if r != 0 {
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
    while reap().is_some() {}
    let removed = cleanup::remove_run(&prefix);
    registry::remove(p.run_id);
    result.map(|mut o| {
        o.shm_removed = removed;
        o
    })
}

/// The barrier of the run this process supervises, while it runs (`bench restart` watches
/// it: the segments have no name another thread could open).
static SUPERVISED: std::sync::Mutex<Option<std::sync::Arc<TickBarrier>>> =
    std::sync::Mutex::new(None);

/// The tick barrier of the run this process supervises, if one runs.
pub fn supervised_barrier() -> Option<std::sync::Arc<TickBarrier>> {
    SUPERVISED.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// Clears [`SUPERVISED`] when the supervision ends, however it ends.
struct Supervised;

impl Drop for Supervised {
    fn drop(&mut self) {
        *SUPERVISED.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}

fn supervise(
    p: &mut ProcessRun,
    prefix: &str,
    scenario_path: &Path,
    entry: &mut RunEntry,
) -> Result<ProcessOutcome, String> {
    let sc = p.sc;
    let n = sc.run.robots;
    // The tick barrier: two sealed memfds, handed to the world and every agent (nothing of
    // it in /dev/shm for an agent to open by name or truncate; docs/protocol.md section 4).
    let (barrier, barrier_fds) =
        TickBarrier::create(prefix, n).map_err(|e| format!("tick barrier: {e}"))?;
    let barrier = std::sync::Arc::new(barrier);
    *SUPERVISED.lock().unwrap_or_else(|e| e.into_inner()) = Some(barrier.clone());
    let _supervised = Supervised;
    // A run across hosts (`[[hosts]]`): the declared hosts join before anything starts.
    let mut hosts = crate::hosts::Hosts::wait(sc).map_err(|e| e.to_string())?;
    let remote = swarm::sections::hosts::placement(sc);
    let mut world = Command::new(bin("world"));
    // The world and every agent inherit the barrier's descriptors (SWARM_BARRIER_FDS).
    barrier_fds.pass_to(&mut world);
    let mut world = world
        .args(["--run-id", p.run_id, "--prefix", prefix, "--run-dir"])
        .arg(p.run_dir)
        .args(p.live.then_some("--live"))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .process_group(0)
        .spawn()
        .map_err(|e| format!("cannot start {}: {e}", bin("world").display()))?;
    entry.world_pid = world.id();
    entry.world_start = registry::start_time(world.id()).unwrap_or(0);
    registry::write(entry).map_err(|e| e.to_string())?;
    // Wait for READY: every service exists.
    let stdout = world.stdout.take().expect("piped");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    // Wait in short slices: Ctrl-C / SIGTERM while the world builds its services (a large or
    // slow scenario) ends the run at once instead of after the world is ready (issue 14
    // items 6, 8). Nothing has ticked yet: the world is killed, no summary is written.
    let ready_by = Instant::now() + READY_TIMEOUT;
    loop {
        match rx.recv_timeout(SUPERVISE_PERIOD) {
            Ok(l) if l.trim() == "READY" => break,
            Err(std::sync::mpsc::RecvTimeoutError::Timeout)
                if Instant::now() < ready_by && !signals::interrupted() => {}
            _ if signals::interrupted() => {
                kill(world.id());
                let _ = world.wait();
                return Err(INTERRUPTED_AT_START.to_string());
            }
            _ => {
                kill(world.id());
                let code = world.wait().ok().and_then(|s| s.code());
                return Err(format!(
                    "the world process did not get ready (exit: {code:?}); see its messages above"
                ));
            }
        }
    }
    let config = transport::run_config(prefix).map_err(|e| e.to_string())?;
    let node = transport::node(&config, "orchestrator").map_err(|e| e.to_string())?;
    let control_svc = transport::control_service(&node, false).map_err(|e| e.to_string())?;
    let control = control_svc
        .publisher_builder()
        .create()
        .map_err(|e| format!("control publisher: {e:?}"))?;
    let status_svc = transport::status_service(&node, false).map_err(|e| e.to_string())?;
    let status = status_svc
        .subscriber_builder()
        .create()
        .map_err(|e| format!("status subscriber: {e:?}"))?;
    // Its segment shrank under a read (section 4 of docs/protocol.md).
    let mut status_lost = false;
    // The world mapped the barrier (it does before READY): from now on nobody maps the
    // world's segment writable, before any agent exists.
    barrier_fds
        .seal_worlds_segment()
        .map_err(|e| e.to_string())?;
    if let Some(h) = hosts.as_mut() {
        h.start(sc, p.run_id, prefix, barrier.clone())
            .map_err(|e| e.to_string())?;
    }
    let launcher = Launcher {
        sc,
        prefix,
        run_id: p.run_id,
        scenario_path,
        run_dir: p.run_dir,
        barrier_fds: &barrier_fds,
    };
    // Agents started per robot (the marks in its log count them).
    let mut starts = vec![0u32; n as usize];
    // (pid, start time) of a new agent of `robot`.
    let mut spawn_agent = |robot: u32, tick: u64| -> Result<(u32, u64), String> {
        starts[robot as usize] += 1;
        launcher.spawn(robot, starts[robot as usize], tick)
    };
    let new_agent = |robot: u32, base: u64| Agent {
        robot,
        base,
        started: Instant::now(),
        attach_timeout: launcher.attach_timeout(robot),
    };
    // pid -> (robot, the robot's attach count when it was spawned): only one agent of a
    // robot lives at a time (a replacement starts after its predecessor is reaped), so the
    // next attach of its robot is this agent's, with attach number base + 1.
    let mut agents: BTreeMap<u32, Agent> = BTreeMap::new();
    for i in 0..n {
        if signals::interrupted() {
            // Ctrl-C while the agents start: the loop below stops the world at once.
            break;
        }
        if remote[i as usize].is_some() {
            // Its host's proxy runs its agent (crate::hosts).
            entry.agent_pids.push(0);
            entry.agent_starts.push(0);
            continue;
        }
        let (pid, start) = spawn_agent(i, 0)?;
        agents.insert(pid, new_agent(i, 0));
        entry.agent_pids.push(pid);
        entry.agent_starts.push(start);
    }
    registry::write(entry).map_err(|e| e.to_string())?;
    // Writes and reads of the run's own segments are guarded: one truncated by a process of
    // the user is read as zeros (no message) rather than SIGBUS the orchestrator, which left
    // the run's files behind (world::shrink_guard).
    world::shrink_guard::install().map_err(|e| e.to_string())?;
    let send_control = |kind: u32, robot: u32, value: u64, tick: u64, status: i32| {
        if world::shrink_guard::control_is_lost() {
            // Its segment shrank: nothing is sent on it any more (the world finds a dead
            // robot by its ack deadline, and a stop is the SIGKILL after STOP_GRACE).
            barrier.nudge_world();
            return;
        }
        let sent = guarded(|| {
            if let Ok(s) = control.loan_uninit() {
                let _ = s
                    .write_payload(Control {
                        kind,
                        robot,
                        value,
                        tick,
                        status,
                        reserved: 0,
                    })
                    .send();
            }
        });
        if sent.is_none() {
            world::shrink_guard::control_lost();
        }
        barrier.nudge_world();
    };
    let restart = sc.faults.on_fault == FaultPolicy::Restart;
    // Deaths of agents that had attached, per robot: the k-th is restarted while
    // k <= max_restarts (the world counts the same deaths as faults and waits for the restart
    // rather than end the run "all robots dead", world::World::end_reason).
    let mut restarts = vec![0u32; n as usize];
    // Agents of each robot in a row that exited before attaching (reset by an attach).
    let mut start_failures = vec![0u32; n as usize];
    // How the last of them ended.
    let mut last_failure = vec![String::new(); n as usize];
    // A robot none of whose agents attached: the report names its command and quotes its log.
    let failure = |robot: u32, times: u32, status: String, exit_code: Option<i32>| {
        let tail = launcher.log_tail(robot);
        let log = agent_spawn::log_path(p.run_dir, robot);
        RobotFailure {
            robot,
            times,
            status,
            command: launcher.describe(robot),
            exit_code,
            log: if tail.is_empty() {
                format!("; its log: {} (empty)", log.display())
            } else {
                format!("; its log: {}, ending:\n{tail}", log.display())
            },
        }
    };
    // Agents killed for not attaching within their attach timeout (pid -> the timeout).
    let mut timed_out: BTreeMap<u32, Duration> = BTreeMap::new();
    let start_failure_limit = if restart { START_FAILURES } else { 1 };
    let mut failed_robot: Option<RobotFailure> = None;
    // The last kill order of each robot acted on (see TickBarrier::order_kill).
    let mut kill_done = vec![0u64; n as usize];
    let mut last = WorldStatus::default();
    let mut last_registry = Instant::now();
    let mut stop_sent: Option<Instant> = None;
    let world_pid = entry.world_pid;
    let world_exit;
    'outer: loop {
        while let Some((pid, st)) = reap() {
            if pid == world_pid {
                world_exit = exit_of(st);
                break 'outer;
            }
            let Some(Agent { robot, base, .. }) = agents.remove(&pid) else {
                continue;
            };
            let timeout = timed_out.remove(&pid);
            let attached = barrier.attach_count(robot) > base;
            // It can attach no more and no other agent of the robot lives: every attach so
            // far is of a dead agent. Written before the report, which the world checks
            // against it (a report of a replacement that never took over is no fault).
            barrier.set_dead_upto(robot, barrier.attach_count(robot));
            if barrier.is_shutdown() || (attached && exit_of(st) == Ok(0)) || exited(world_pid) {
                // Ended with the run (the world's shutdown word, or the world is gone: the
                // agent left because of it), not a fault.
                continue;
            }
            let r = robot as usize;
            if attached {
                start_failures[r] = 0;
            } else if stop_sent.is_none() {
                // Exited before it attached, however it exited (exit code 0 included: the
                // world would wait for it until runtime.startup_timeout_s).
                start_failures[r] += 1;
                last_failure[r] = match timeout {
                    Some(t) => format!(
                        "did not attach within {} s ([[agents]] attach_timeout_s), killed",
                        t.as_secs_f64()
                    ),
                    None => describe(st),
                };
                // One that never attaches is not waited for again.
                if start_failures[r] >= start_failure_limit || timeout.is_some() {
                    let code = exit_of(st).ok().filter(|_| timeout.is_none());
                    failed_robot = Some(failure(
                        robot,
                        start_failures[r],
                        last_failure[r].clone(),
                        code,
                    ));
                    send_control(CONTROL_STOP, 0, 0, last.tick, 0);
                    stop_sent = Some(Instant::now());
                    continue;
                }
            }
            send_control(
                CONTROL_ROBOT_DIED,
                robot,
                monotonic_us(),
                barrier.current_tick(),
                st,
            );
            // A start failure under the limit is retried without using up a restart.
            let budget = !attached || restarts[r] < sc.faults.max_restarts;
            if restart && stop_sent.is_none() && budget {
                // The replacement starts first and the dead agent's ports are cleaned while
                // it starts up: each service has room for one dead agent's ports beside the
                // live one's (transport's RESTART_SLACK), and the cleanup (~0.3-0.6 s at
                // N = 50: iceoryx2 lists /dev/shm for every port it removes) was almost all
                // of a restart's latency (`bench restart`, issue 14 item 3). The cleanup ends
                // before the next death is reaped, so at most one dead agent's ports per
                // robot are ever left.
                let base = barrier.attach_count(robot);
                let (pid, start) = spawn_agent(robot, barrier.current_tick())?;
                if attached {
                    restarts[r] += 1;
                }
                agents.insert(pid, new_agent(robot, base));
                entry.agent_pids[r] = pid;
                entry.agent_starts[r] = start;
                registry::write(entry).map_err(|e| e.to_string())?;
                cleanup_dead_agents(&node, prefix);
            }
        }
        // The world declared these agents dead (a scheduled kill at its tick, an ack
        // deadline): SIGKILL exactly that incarnation, never a replacement that has not taken
        // over. A kill scheduled while the robot is already dead (its restart under way) is
        // void: the world orders nothing.
        for (&pid, a) in &agents {
            // An `[[agents]]` program alive but not attached after its attach timeout.
            if let Some(t) = a.attach_timeout {
                let waiting = barrier.attach_count(a.robot) == a.base;
                if waiting && a.started.elapsed() > t && !timed_out.contains_key(&pid) {
                    timed_out.insert(pid, t);
                    kill(pid);
                }
            }
            let r = a.robot as usize;
            let order = barrier.kill_order(a.robot);
            if order > kill_done[r] {
                kill_done[r] = order;
                if barrier.attach_count(a.robot) > a.base && a.base + 1 == order {
                    kill(pid);
                }
            }
        }
        // A status read from a shrunk `world/state` segment (zeros) is not believed, and the
        // subscriber is not touched again (iceoryx2 panics on the zeros it would read next;
        // docs/protocol.md section 4): the run goes on without status.
        if !status_lost {
            let newest = guarded(|| {
                let mut newest = None;
                while let Ok(Some(s)) = status.receive() {
                    newest = Some(*s);
                }
                newest
            });
            match newest {
                Some(Some(s)) => last = s,
                Some(None) => {}
                None => status_lost = true,
            }
        }
        (p.on_status)(&last);
        if last_registry.elapsed() > REGISTRY_PERIOD {
            entry.tick = last.tick;
            entry.alive = last.alive;
            entry.dead = last.dead;
            entry.restarted = last.restarted;
            let _ = registry::write(entry);
            last_registry = Instant::now();
        }
        if signals::interrupted() && stop_sent.is_none() {
            send_control(CONTROL_STOP, 0, 0, last.tick, 0);
            stop_sent = Some(Instant::now());
        }
        if let Some(t) = stop_sent {
            if t.elapsed() > STOP_GRACE {
                kill(world_pid);
            }
        }
        std::thread::sleep(SUPERVISE_PERIOD);
    }
    // The world is gone: agents exit on its shutdown word (or notice it died).
    // Interrupted (Ctrl-C, SIGTERM): the world has written the outputs, so the agents are
    // killed at once rather than given AGENT_EXIT_GRACE; 500 agents leaving gracefully on 2
    // cores took ~1 s, and their files are removed by the run's prefix either way.
    let grace = if signals::interrupted() {
        Duration::ZERO
    } else {
        AGENT_EXIT_GRACE
    };
    let t = Instant::now();
    while !agents.is_empty() && t.elapsed() < grace {
        while let Some((pid, _)) = reap() {
            agents.remove(&pid);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    for &pid in agents.keys() {
        kill(pid);
    }
    // A run that ended (an unpaced one can reach max_ticks within milliseconds) before the
    // limit was reached: a robot none of whose agents ever attached still failed.
    if failed_robot.is_none() {
        failed_robot = (0..n)
            .find(|&i| start_failures[i as usize] > 0 && barrier.attach_count(i) == 0)
            .map(|robot| {
                failure(
                    robot,
                    start_failures[robot as usize],
                    last_failure[robot as usize].clone(),
                    None,
                )
            });
    }
    if let Some(h) = hosts.as_mut() {
        h.finish();
        if let Some(e) = h.failure() {
            return Err(e);
        }
    }
    // Closing the ports touches their segments: one that shrank is let go without closing
    // (its zeros make iceoryx2 panic, and a panic while unwinding aborts the orchestrator
    // before it removed the run's files); the others under the guard.
    if status_lost {
        std::mem::forget((status, status_svc));
    } else {
        let _ = guarded(|| drop(status));
    }
    if world::shrink_guard::control_is_lost() {
        std::mem::forget((control, control_svc));
    } else {
        let _ = guarded(|| drop(control));
    }
    drop(barrier);
    drop(node);
    Ok(ProcessOutcome {
        world_exit,
        shm_removed: 0,
        failed_robot,
    })
}

/// Runs `f`, which touches the run's own shared segments, under the SIGBUS guard: None when
/// one shrank under it.
fn guarded<T>(f: impl FnOnce() -> T) -> Option<T> {
    world::shrink_guard::reading(world::shrink_guard::RUN_SEGMENTS, f)
}

/// An empty /dev/shm segment of the run older than this has lost its creator (one that lives
/// sizes it within microseconds of creating it).
const EMPTY_SEGMENT_AGE: Duration = Duration::from_millis(50);

/// `try_cleanup_dead_nodes`, unblocked when it would wait for ever. iceoryx2 0.10's cleanup
/// of a dead node opens each of its connection segments and, for a segment that was created
/// but never sized (an agent SIGKILLed between `shm_open` and `ftruncate`, i.e. killed while
/// making a link), waits without a timeout (`MappingSizeIsZero` loops in
/// `posix_shared_memory::open_impl`): the orchestrator hung there with the whole run
/// defunct, seen under dense kills during restarts. A watchdog thread removes the run's empty
/// segments older than `EMPTY_SEGMENT_AGE` while the cleanup runs; the open then finds
/// nothing and the cleanup goes on.
pub(crate) fn cleanup_dead_agents(
    node: &iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    prefix: &str,
) {
    let t = Instant::now();
    let done = std::sync::atomic::AtomicBool::new(false);
    std::thread::scope(|s| {
        s.spawn(|| {
            while !done.load(std::sync::atomic::Ordering::Acquire) {
                std::thread::sleep(Duration::from_millis(10));
                remove_empty_segments(prefix, EMPTY_SEGMENT_AGE);
            }
        });
        node.try_cleanup_dead_nodes();
        done.store(true, std::sync::atomic::Ordering::Release);
    });
    LAST_CLEANUP_US.store(
        t.elapsed().as_micros() as u64,
        std::sync::atomic::Ordering::Relaxed,
    );
}

static LAST_CLEANUP_US: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// How long the last restart's port cleanup took, in microseconds (`bench restart`).
pub fn last_cleanup_us() -> u64 {
    LAST_CLEANUP_US.load(std::sync::atomic::Ordering::Relaxed)
}

/// Removes the run's empty /dev/shm files older than `age`; returns how many.
fn remove_empty_segments(prefix: &str, age: Duration) -> usize {
    let mut removed = 0;
    for name in cleanup::shm_files(prefix) {
        let p = Path::new("/dev/shm").join(&name);
        let Ok(m) = std::fs::metadata(&p) else {
            continue;
        };
        let old = m
            .modified()
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|e| e > age);
        if m.is_file() && m.len() == 0 && old && std::fs::remove_file(&p).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// CLOCK_MONOTONIC in microseconds (the world compares it with its own clock).
pub fn monotonic_us() -> u64 {
    world::process::monotonic_us()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_old_empty_segments_of_the_run_are_removed() {
        let prefix = format!("swtest{}_", std::process::id());
        let shm = Path::new("/dev/shm");
        std::fs::write(shm.join(format!("{prefix}empty-old")), b"").unwrap();
        std::fs::write(shm.join(format!("{prefix}full")), b"x").unwrap();
        std::thread::sleep(Duration::from_millis(60));
        std::fs::write(shm.join(format!("{prefix}empty-new")), b"").unwrap();
        assert_eq!(remove_empty_segments(&prefix, EMPTY_SEGMENT_AGE), 1);
        assert_eq!(
            cleanup::shm_files(&prefix),
            vec![format!("{prefix}empty-new"), format!("{prefix}full")]
        );
        cleanup::remove_run(&prefix);
        assert!(cleanup::shm_files(&prefix).is_empty());
    }
}
