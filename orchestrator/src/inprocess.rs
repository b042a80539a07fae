//! The in-process executor: the same world, behaviours, agent runtime and radio model in one
//! process, with messages passed in memory instead of iceoryx2. For unit tests and sweeps; it
//! gives the same recording as the multi-process executor.

use agent::{dispatch, BehaviourVisitor};
use std::path::Path;
use std::time::Instant;
use swarm::behaviour::RadioTx;
use swarm::frames::{Action, RadioHeader, Sense};
use swarm::scenario::Scenario;
use swarm::{AgentRuntime, Behaviour};
use world::{RunOutputs, Summary, Timing, World};

/// Messages of one tick: headers and their encoded payloads in one buffer.
#[derive(Default)]
struct Air {
    headers: Vec<(RadioHeader, usize)>,
    bytes: Vec<u8>,
}

impl RadioTx for Air {
    fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
        let at = self.bytes.len();
        self.bytes.resize(at + h.len as usize, 0);
        fill(&mut self.bytes[at..]);
        self.headers.push((*h, at));
    }
}

impl Air {
    fn clear(&mut self) {
        self.headers.clear();
        self.bytes.clear();
    }
}

pub struct InProcess<'a> {
    pub sc: &'a Scenario,
    /// The run folder; None keeps only the returned Summary (sweeps).
    pub out_dir: Option<&'a Path>,
    pub run_id: &'a str,
    pub on_tick: &'a mut dyn FnMut(&World),
}

impl BehaviourVisitor for InProcess<'_> {
    type Out = std::io::Result<Summary>;
    fn visit<B: Behaviour + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out {
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
        let mut prev = Air::default();
        let mut cur = Air::default();
        let mut actions: Vec<Option<Action>> = vec![None; n];
        let mut tick_ns = Vec::with_capacity(sc.run.max_ticks.min(10_000_000) as usize);
        let startup_seconds = t0.elapsed().as_secs_f64();
        let t_loop = Instant::now();
        let mut end = "completed";
        while world.tick < sc.run.max_ticks {
            let t_tick = Instant::now();
            world.begin_tick();
            if world.tick + 1 == sc.run.max_ticks {
                world.set_stopping();
            }
            for i in 0..n {
                actions[i] = None;
                if !world.alive[i] {
                    continue;
                }
                world.sense(i, &mut senses[i]);
                let rt = &mut rts[i];
                let s = &senses[i];
                rt.begin(s);
                // What robot i's links carry: every message sent last tick (the runtime keeps
                // only those from linked senders, exactly as its subscriptions would).
                for (h, at) in &prev.headers {
                    rt.ingest(h, &prev.bytes[*at..*at + h.len as usize]);
                }
                actions[i] = Some(rt.step(s, &mut cur));
                rt.update_links(s);
            }
            let rec = world.apply(&actions);
            outputs.push(&rec)?;
            std::mem::swap(&mut prev, &mut cur);
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
    on_tick: &mut dyn FnMut(&World),
) -> std::io::Result<Summary> {
    dispatch(
        sc,
        InProcess {
            sc,
            out_dir,
            run_id,
            on_tick,
        },
    )
}
