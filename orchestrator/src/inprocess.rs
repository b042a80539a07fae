//! The in-process executor: the same world, behaviours, agent runtime and radio model in one
//! process, with messages passed in memory instead of iceoryx2. For unit tests and sweeps; it
//! gives the same recording as the multi-process executor.

use agent::{dispatch, BehaviourVisitor};
use std::path::Path;
use std::time::Instant;
use swarm::frames::{Action, Sense};
use swarm::mailbox::{Air, Mailbox};
use swarm::scenario::Scenario;
use swarm::{AgentRuntime, Behaviour};
use world::{RunOutputs, Summary, Timing, World};

/// Robots per worker thread below which a run stays on one thread (thread hand-offs cost more
/// than small ticks).
const MIN_ROBOTS_PER_THREAD: usize = 16;

/// One robot's agent side of a tick: its inbox from last tick's messages, its step (messages
/// into `air`), its links.
fn agent_tick<B: Behaviour>(
    rt: &mut AgentRuntime<B>,
    s: &Sense,
    mailbox: &Mailbox<B::Msg>,
    air: &mut Air,
) -> Action {
    rt.begin(s);
    // What the robot's links carry: the messages sent last tick by the robots it is linked to,
    // exactly as its subscriptions would.
    rt.ingest_mailbox(mailbox);
    let a = rt.step_mailbox(s, mailbox, air);
    rt.update_links(s);
    a
}

pub struct InProcess<'a> {
    pub sc: &'a Scenario,
    /// The run folder; None keeps only the returned Summary (sweeps).
    pub out_dir: Option<&'a Path>,
    pub run_id: &'a str,
    pub on_tick: &'a mut dyn FnMut(&World),
    /// Worker threads for the agents' side of each tick (1: all on the calling thread). The
    /// robots are split into contiguous id ranges and their messages joined in id order, so
    /// the result does not depend on it.
    pub threads: usize,
}

impl BehaviourVisitor for InProcess<'_> {
    type Out = std::io::Result<Summary>;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync,
    {
        let t0 = Instant::now();
        let sc = self.sc;
        let mut world = World::new(sc).map_err(std::io::Error::other)?;
        let mut outputs = match self.out_dir {
            Some(d) => RunOutputs::create(d, sc)?,
            None => RunOutputs::summary_only(),
        };
        let n = world.n;
        let mut rts: Vec<AgentRuntime<B>> = (0..n as u32)
            .map(|i| AgentRuntime::new(sc, i, make(i)))
            .collect();
        let mut senses: Vec<Box<Sense>> = (0..n).map(|_| Sense::zeroed()).collect();
        // This tick's messages; then, decoded once for all their receivers, the mailbox.
        let mut cur = Air::default();
        let mut mailbox: Mailbox<B::Msg> = Mailbox::new(n, sc.radio.delay_ticks as u64);
        let mut actions: Vec<Option<Action>> = vec![None; n];
        let threads = self.threads.clamp(1, (n / MIN_ROBOTS_PER_THREAD).max(1));
        let chunk = n.div_ceil(threads);
        let mut airs: Vec<Air> = (0..threads).map(|_| Air::default()).collect();
        let mut tick_ns = Vec::with_capacity(sc.run.max_ticks.min(10_000_000) as usize);
        let startup_seconds = t0.elapsed().as_secs_f64();
        let t_loop = Instant::now();
        let mut end = "completed";
        while world.tick < sc.run.max_ticks {
            sc.runtime.pace(t_loop, world.tick);
            let t_tick = Instant::now();
            world.begin_tick();
            if world.tick + 1 == sc.run.max_ticks {
                world.set_stopping();
            }
            // Sensing first, in robot order (the world's noise draws follow it), then each
            // robot's agent side, independent of the others'.
            for (i, sense) in senses.iter_mut().enumerate() {
                if world.alive[i] {
                    world.sense(i, sense);
                }
            }
            let alive = &world.alive;
            let (mailbox_r, senses_r) = (&mailbox, &senses[..]);
            let work = |first: usize,
                        rts: &mut [AgentRuntime<B>],
                        acts: &mut [Option<Action>],
                        air: &mut Air| {
                for (j, (rt, act)) in rts.iter_mut().zip(acts.iter_mut()).enumerate() {
                    let i = first + j;
                    *act = alive[i].then(|| agent_tick(rt, &senses_r[i], mailbox_r, air));
                }
            };
            if threads == 1 {
                work(0, &mut rts, &mut actions, &mut cur);
            } else {
                std::thread::scope(|scope| {
                    for (c, ((rts, acts), air)) in rts
                        .chunks_mut(chunk)
                        .zip(actions.chunks_mut(chunk))
                        .zip(airs.iter_mut())
                        .enumerate()
                    {
                        let work = &work;
                        scope.spawn(move || work(c * chunk, rts, acts, air));
                    }
                });
                for air in airs.iter_mut() {
                    cur.append(air);
                    air.clear();
                }
            }
            let rec = world.apply(&actions);
            outputs.push(&rec)?;
            mailbox.post(rec.tick, &cur);
            cur.clear();
            tick_ns.push(t_tick.elapsed().as_nanos() as u64);
            (self.on_tick)(&world);
            if world.mission_complete() {
                end = "all targets found";
                break;
            }
            if world.alive_count() == 0 {
                end = "all robots dead";
                break;
            }
        }
        let timing = Timing {
            wall_seconds: t0.elapsed().as_secs_f64(),
            loop_seconds: t_loop.elapsed().as_secs_f64(),
            startup_seconds,
            tick_ns,
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
    dispatch(
        sc,
        InProcess {
            sc,
            out_dir,
            run_id,
            on_tick,
            threads,
        },
    )
}
