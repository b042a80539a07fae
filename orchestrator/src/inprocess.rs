//! The in-process executor: the same world, behaviours, agent runtime and radio model in one
//! process, with messages passed in memory instead of iceoryx2. For unit tests and sweeps; it
//! gives the same recording as the multi-process executor.

use crate::phase::PhaseBarrier;
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, MutexGuard, RwLock};
use std::time::Instant;
use swarm::frames::{Action, Sense};
use swarm::mailbox::{Air, Mailbox};
use swarm::plugin::BehaviourVisitor;
use swarm::scenario::Scenario;
use swarm::{AgentRuntime, Behaviour};
use world::sensing::SenseScratch;
use world::{RunOutputs, Summary, Timing, World};

/// Robots per worker thread below which a run stays on one thread (thread hand-offs cost more
/// than small ticks).
const MIN_ROBOTS_PER_THREAD: usize = 16;
/// The longest a paced run sleeps before it looks for a stop request again (Ctrl-C, SIGTERM).
const STOP_POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// Sleeps until tick `k` may start (`runtime.tick_hz`), in slices of at most STOP_POLL;
/// false as soon as `stop()` says so.
fn pace(sc: &Scenario, loop_start: Instant, k: u64, stop: &dyn Fn() -> bool) -> bool {
    let Some(at) = sc.runtime.tick_start(k) else {
        return !stop();
    };
    loop {
        if stop() {
            return false;
        }
        let now = loop_start.elapsed();
        if at <= now {
            return true;
        }
        std::thread::sleep((at - now).min(STOP_POLL));
    }
}

/// One robot's agent side of a tick: its inbox (its list in the tick's air, decoded once for
/// all receivers by the mailbox), its step (messages into `air`).
fn agent_tick<B: Behaviour>(
    rt: &mut AgentRuntime<B>,
    s: &Sense,
    mailbox: &Mailbox<B::Msg>,
    air: &mut Air,
) -> Action {
    let mut inbox = Vec::new();
    let malformed = mailbox.inbox(rt.robot, &mut inbox);
    rt.step(s, &inbox, malformed, air)
}

/// The robots of one worker thread (a contiguous id range) and everything their side of a
/// tick writes.
struct Chunk<B: Behaviour> {
    first: usize,
    rts: Vec<AgentRuntime<B>>,
    senses: Vec<Box<Sense>>,
    actions: Vec<Option<Action>>,
    /// Messages sent this tick, in robot order.
    air: Air,
    scratch: SenseScratch,
}

impl<B: Behaviour> Chunk<B> {
    /// The parallel part of a tick: each live robot's neighbours and obstacle points (its
    /// signals are in already), then its agent side.
    fn work(&mut self, world: &World, mailbox: &Mailbox<B::Msg>) {
        for j in 0..self.rts.len() {
            let i = self.first + j;
            self.actions[j] = if world.alive[i] {
                world.sense_geometry(i, &mut self.scratch, &mut self.senses[j]);
                Some(agent_tick(
                    &mut self.rts[j],
                    &self.senses[j],
                    mailbox,
                    &mut self.air,
                ))
            } else {
                None
            };
        }
    }
}

/// A lock nobody can poison for good: a worker that panicked has already been reported.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

pub struct InProcess<'a> {
    pub sc: &'a Scenario,
    /// The run folder; None keeps only the returned Summary (sweeps).
    pub out_dir: Option<&'a Path>,
    pub run_id: &'a str,
    pub on_tick: &'a mut dyn FnMut(&World),
    /// Worker threads for the robots' side of each tick (1: all on the calling thread). The
    /// robots are split into contiguous id ranges, one per thread, and their messages joined
    /// in id order, so the result does not depend on it.
    pub threads: usize,
    /// Flush recording.bin after every tick (a live viewer reads it as it grows).
    pub live: bool,
    /// Asked before every tick: true ends the run "interrupted", its outputs written
    /// (`orchestrator up`: a Ctrl-C or SIGTERM).
    pub stop: &'a dyn Fn() -> bool,
}

impl BehaviourVisitor for InProcess<'_> {
    type Out = std::io::Result<Summary>;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync,
    {
        let t0 = Instant::now();
        let sc = self.sc;
        let world = World::new(sc).map_err(std::io::Error::other)?;
        let mut outputs = match self.out_dir {
            Some(d) => RunOutputs::create(d, &world)?,
            None => RunOutputs::summary_only(),
        };
        if self.live {
            outputs.flush_each_tick();
        }
        let n = world.n;
        let threads = self.threads.clamp(1, (n / MIN_ROBOTS_PER_THREAD).max(1));
        let per = n.div_ceil(threads).max(1);
        let chunks: Vec<Mutex<Chunk<B>>> = (0..n)
            .step_by(per)
            .map(|first| {
                let ids = first..(first + per).min(n);
                Mutex::new(Chunk {
                    first,
                    rts: ids
                        .clone()
                        .map(|i| AgentRuntime::new(sc, i as u32, make(i as u32)))
                        .collect(),
                    senses: ids.clone().map(|_| Sense::zeroed()).collect(),
                    actions: vec![None; ids.len()],
                    air: Air::default(),
                    scratch: SenseScratch::default(),
                })
            })
            .collect();
        let threads = chunks.len();
        // Zero-copy receive if the behaviours ask for it (all robots run the same one).
        let zero_copy = chunks
            .iter()
            .any(|c| c.lock().expect("fresh").rts.iter().any(|r| r.zero_copy()));
        // The tick's due messages, decoded once for all their receivers.
        let mailbox: RwLock<Mailbox<B::Msg>> = RwLock::new(Mailbox::new().zero_copy(zero_copy));
        let mut cur = Air::default();
        let mut actions: Vec<Option<Action>> = vec![None; n];
        let mut tick_ns = Vec::with_capacity(sc.run.max_ticks.min(10_000_000) as usize);
        let startup_seconds = t0.elapsed().as_secs_f64();
        let world = RwLock::new(world);
        // Each tick: the calling thread does the serial parts (signals, whose noise draws
        // follow robot order; the moves; the mailbox), between them every thread runs its
        // chunk. `go` starts a chunk's work (or, with `stop` set, ends the worker), `done`
        // waits for all.
        let (go, done) = (PhaseBarrier::new(threads), PhaseBarrier::new(threads));
        let stop = AtomicBool::new(false);
        let panicked = AtomicBool::new(false);
        let run_chunk = |c: &Mutex<Chunk<B>>| {
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                let (w, m) = (
                    world.read().unwrap_or_else(|e| e.into_inner()),
                    mailbox.read().unwrap_or_else(|e| e.into_inner()),
                );
                lock(c).work(&w, &m);
            }));
            if r.is_err() {
                panicked.store(true, Ordering::SeqCst);
            }
        };
        let t_loop = Instant::now();
        let mut end = "completed";
        let on_tick = self.on_tick;
        let stop_requested = self.stop;
        let result: std::io::Result<()> = std::thread::scope(|scope| {
            for c in &chunks[1..] {
                let (go, done, stop, run_chunk) = (&go, &done, &stop, &run_chunk);
                scope.spawn(move || loop {
                    go.wait();
                    if stop.load(Ordering::SeqCst) {
                        break;
                    }
                    run_chunk(c);
                    done.wait();
                });
            }
            let result = (|| loop {
                let mut w = world.write().unwrap_or_else(|e| e.into_inner());
                if w.tick >= sc.run.max_ticks {
                    return Ok(());
                }
                if !pace(sc, t_loop, w.tick, stop_requested) {
                    end = "interrupted";
                    return Ok(());
                }
                let t_tick = Instant::now();
                w.begin_tick();
                if w.tick + 1 == sc.run.max_ticks {
                    w.set_stopping();
                }
                mailbox
                    .write()
                    .unwrap_or_else(|e| e.into_inner())
                    .post(w.air());
                for c in &chunks {
                    let mut c = lock(c);
                    let c = &mut *c;
                    for (j, sense) in c.senses.iter_mut().enumerate() {
                        if w.alive[c.first + j] {
                            w.sense_mission(c.first + j, sense);
                        }
                    }
                }
                drop(w);
                go.wait();
                run_chunk(&chunks[0]);
                done.wait();
                if panicked.load(Ordering::SeqCst) {
                    return Err(std::io::Error::other("a robot's behaviour panicked"));
                }
                for c in &chunks {
                    let mut c = lock(c);
                    actions[c.first..c.first + c.actions.len()].copy_from_slice(&c.actions);
                    cur.append(&c.air);
                    c.air.clear();
                }
                let mut w = world.write().unwrap_or_else(|e| e.into_inner());
                let rec = w.apply(&actions, &cur);
                outputs.push(&rec, &w)?;
                cur.clear();
                tick_ns.push(t_tick.elapsed().as_nanos() as u64);
                on_tick(&w);
                if let Some(why) = w.end_reason() {
                    end = why;
                    return Ok(());
                }
            })();
            stop.store(true, Ordering::SeqCst);
            go.wait();
            result
        });
        result?;
        let mut world = world.into_inner().unwrap_or_else(|e| e.into_inner());
        let timing = Timing {
            wall_seconds: t0.elapsed().as_secs_f64(),
            loop_seconds: t_loop.elapsed().as_secs_f64(),
            startup_seconds,
            tick_ns,
            late_releases: 0,
        };
        outputs.finish(&mut world, &timing, self.run_id, "inprocess", end)
    }
}

pub fn run(
    sc: &Scenario,
    out_dir: Option<&Path>,
    run_id: &str,
    threads: usize,
    on_tick: &mut dyn FnMut(&World),
) -> std::io::Result<Summary> {
    run_live(sc, out_dir, run_id, threads, on_tick, false, &|| false)
}

/// Why the in-process executor refuses a scenario.
#[derive(Debug, thiserror::Error)]
pub enum InProcessError {
    /// Real-time mode needs agents that can be late: in one process the world's own threads
    /// step every robot inside the tick, so no action can miss a deadline, and a paced
    /// in-process run is what `runtime.tick_hz` already gives.
    #[error(
        "runtime.realtime_hz = {0} (--realtime) needs the processes executor: in-process, \
         the world's own threads step every robot within the tick, so no action can miss its \
         deadline; use --executor processes, or --tick-hz to pace an in-process run"
    )]
    Realtime(f64),
}

/// Refuses what the in-process executor cannot run (real-time mode; `up` refuses
/// `faults.on_fault = "restart"` when it resolves the scenario, naming where it was set).
pub fn check(sc: &Scenario) -> Result<(), InProcessError> {
    if sc.runtime.is_realtime() {
        return Err(InProcessError::Realtime(sc.runtime.realtime_hz));
    }
    Ok(())
}

/// [`run`], recording.bin flushed after every tick when `live` (`orchestrator up --view`),
/// ended "interrupted" when `stop()` says so before a tick.
pub fn run_live(
    sc: &Scenario,
    out_dir: Option<&Path>,
    run_id: &str,
    threads: usize,
    on_tick: &mut dyn FnMut(&World),
    live: bool,
    stop: &dyn Fn() -> bool,
) -> std::io::Result<Summary> {
    check(sc).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
    crate::plugins::run_inprocess(
        sc,
        InProcess {
            sc,
            out_dir,
            run_id,
            on_tick,
            threads,
            live,
            stop,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(sc: &Scenario, threads: usize, tag: &str) -> Vec<u8> {
        let dir = std::env::temp_dir().join(format!("swarm-inproc-{}-{tag}", std::process::id()));
        let s = run(sc, Some(&dir), "threads-test", threads, &mut |_| {}).expect("run");
        assert!(s.ticks > 10, "the run must last a while");
        let bytes = std::fs::read(dir.join("recording.bin")).expect("recording");
        std::fs::remove_dir_all(&dir).ok();
        bytes
    }

    #[test]
    fn the_number_of_worker_threads_does_not_change_the_recording() {
        // Search, 50 robots (3 chunks of 17, 17, 16 with 3 threads), lossy radio with delay.
        let mut sc = Scenario::default();
        sc.run.robots = 50;
        sc.run.max_ticks = 80;
        sc.radio.loss = 0.2;
        sc.radio.delay_ticks = 1;
        let one = recording(&sc, 1, "1");
        assert_eq!(one, recording(&sc, 2, "2"), "2 threads");
        assert_eq!(one, recording(&sc, 3, "3"), "3 threads");
    }
}
