//! The world process: drives `World` over iceoryx2 and the tick barrier.

use crate::data_plane::{DataPlane, TooManyRemakes};
use crate::output::{RunOutputs, Timing};
use crate::shrink_guard::GuardedActs;
use crate::world::World;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use swarm::barrier::TickBarrier;
use swarm::frames::{Action, Control, CONTROL_ROBOT_DIED, CONTROL_STOP};
use swarm::mailbox::Air;
use swarm::scenario::Scenario;
use swarm::transport::{self, Result};

pub struct WorldArgs {
    pub run_id: String,
    pub prefix: String,
    pub run_dir: PathBuf,
    pub scenario: Scenario,
    /// Flush recording.bin after every tick: a live viewer reads it as it grows
    /// (`orchestrator up --view`). Off, the world does nothing for viewers.
    pub live: bool,
}

/// Real-time mode's clock and each robot's progress: when the world last received an action
/// of each robot through its act service (the ack-deadline rule is per robot here, since the
/// world never waits for anyone past a tick's deadline) and from which tick its current agent
/// drives it.
struct RealtimeClock {
    /// When each robot's act service last delivered an action (or the robot started or was
    /// revived).
    last_ack: Vec<Instant>,
    since: Vec<u64>,
    late_releases: u64,
}

impl RealtimeClock {
    fn new(n: usize, now: Instant) -> RealtimeClock {
        RealtimeClock {
            last_ack: vec![now; n],
            since: vec![0; n],
            late_releases: 0,
        }
    }

    /// A (re)started agent drives robot i from tick k: its deadline clock starts now.
    fn start(&mut self, i: usize, k: u64) {
        self.last_ack[i] = Instant::now();
        self.since[i] = k;
    }

    /// Receives what the live robots sent since the last look; true if every live robot's
    /// action of tick k arrived.
    fn all_acked(
        &mut self,
        world: &World,
        acts: &mut crate::shrink_guard::GuardedActs,
        k: u64,
    ) -> bool {
        let now = Instant::now();
        let mut all = true;
        for i in world.live_robots() {
            let r = i as usize;
            if acts.poll_realtime(i, k, self.since[r]) {
                self.last_ack[r] = now;
            }
            all &= acts.holds(i, k);
        }
        all
    }

    /// The live robots silent for longer than `deadline` (runtime.ack_deadline_ms).
    fn silent(&self, world: &World, deadline: Duration) -> Vec<u32> {
        world
            .live_robots()
            .filter(|&i| self.last_ack[i as usize].elapsed() > deadline)
            .collect()
    }
}

/// What the control channel said.
#[derive(Default)]
struct ControlState {
    stop: bool,
}

/// Which agent process drives each robot, by attach number (the number in the attach notice
/// that came through the robot's own act service, `ActSource::attached`; 0 = the robot's
/// first agent has not attached yet).
///
/// Deaths, attaches and kills all name an incarnation, never just a robot: a death report
/// about an agent that is not the driver (a replacement killed before it attached, reported
/// after the next one took over) is stale and ignored; an attach by an agent already known
/// dead revives nothing. Before, both were anonymous events and a replacement that attached
/// before the report of its predecessor's death was consumed by that report: the robot stayed
/// dead with a live agent waiting for ever (issue 14 item 1).
struct Drivers {
    attached: Vec<u64>,
    /// Faults already turned into kill orders.
    ordered: usize,
}

impl Drivers {
    /// Orders the SIGKILL of every agent the world declared dead since the last call (a
    /// scheduled kill, an ack deadline): a robot the world holds dead keeps no process, and
    /// under `restart` the orchestrator then starts its replacement (issue 14 item 2).
    fn order_kills(&mut self, world: &World, barrier: &TickBarrier) {
        for f in &world.faults[self.ordered..] {
            let a = self.attached[f.robot as usize];
            if a > 0 {
                barrier.order_kill(f.robot, a);
            }
        }
        self.ordered = world.faults.len();
    }
}

fn drain_control(
    sub: &Subscriber<ipc::Service, Control, ()>,
    world: &mut World,
    state: &mut ControlState,
    barrier: &TickBarrier,
    drivers: &Drivers,
) {
    // `run/control` is the orchestrator's segment: truncated, the world stops reading it
    // rather than die of SIGBUS (shrink_guard; docs/protocol.md section 4).
    while !crate::shrink_guard::control_is_lost() {
        let c = crate::shrink_guard::reading(crate::shrink_guard::RUN_SEGMENTS, || {
            sub.receive().ok().flatten().map(|c| *c)
        });
        let Some(c) = c else {
            crate::shrink_guard::control_lost();
            break;
        };
        let Some(c) = c else {
            break;
        };
        match c.kind {
            // A scheduled kill reaped before the world began its tick: begin_tick records it
            // (same tick, same cause) so the run stays reproducible.
            CONTROL_ROBOT_DIED if world.kill_scheduled_now(c.robot) => {}
            // The agent that died is not the robot's driver (a replacement that had not taken
            // over yet): nothing happened to the robot.
            CONTROL_ROBOT_DIED
                if c.robot < barrier.robots()
                    && drivers.attached[c.robot as usize] > barrier.dead_upto(c.robot) => {}
            CONTROL_ROBOT_DIED => {
                // value: CLOCK_MONOTONIC microseconds when the orchestrator reaped the process
                // (the same clock here: it is system-wide).
                let detection_ms = monotonic_us().saturating_sub(c.value) as f64 / 1e3;
                world.mark_dead(
                    c.robot,
                    &format!(
                        "process died (reaped by orchestrator): {}",
                        swarm::agent::exit_cause(c.status)
                    ),
                    Some(c.tick),
                    Some(detection_ms),
                );
            }
            CONTROL_STOP => state.stop = true,
            _ => {}
        }
    }
}

/// Sleeps until tick `k` may start (runtime.tick_hz, or real-time mode's clock), in slices
/// of at most `poll`, asking `stopped` after each: a stop request ends a slow pace at once (a
/// pace of `--tick-hz 1e-300` would otherwise sleep for ever). Returns false if stopped.
fn pace(
    rt: &swarm::scenario::RuntimeParams,
    loop_start: Instant,
    k: u64,
    poll: Duration,
    mut stopped: impl FnMut() -> bool,
) -> bool {
    let Some(at) = rt
        .tick_start(k)
        .or_else(|| rt.realtime_window(k).map(|w| w.0))
    else {
        return true;
    };
    loop {
        let now = loop_start.elapsed();
        if at <= now {
            return true;
        }
        std::thread::sleep((at - now).min(poll));
        if stopped() {
            return false;
        }
    }
}

/// CLOCK_MONOTONIC in microseconds: comparable across processes on one machine.
pub fn monotonic_us() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: valid pointer to a timespec.
    unsafe {
        libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts);
    }
    ts.tv_sec as u64 * 1_000_000 + ts.tv_nsec as u64 / 1000
}

/// Real-time mode: waits for tick k's acknowledgements until every live robot has sent its
/// action or tick k's deadline (t0 + (k + 1) / realtime_hz) has passed, whichever comes first,
/// then declares dead every robot silent for longer than `runtime.ack_deadline_ms` (per robot,
/// from its last acknowledgement). Returns false on a stop request.
fn wait_realtime(
    (clock, acts): (&mut RealtimeClock, &mut crate::shrink_guard::GuardedActs),
    world: &mut World,
    barrier: &TickBarrier,
    bell: Option<&swarm::bell::EventBell>,
    (control, ctl, drivers): (
        &Subscriber<ipc::Service, Control, ()>,
        &mut ControlState,
        &mut Drivers,
    ),
    t_loop: Instant,
    k: u64,
) -> bool {
    let sc = &world.sc;
    let poll = Duration::from_millis(sc.runtime.poll_ms);
    let ack_deadline = Duration::from_millis(sc.runtime.ack_deadline_ms);
    let due = t_loop
        + sc.runtime
            .realtime_window(k)
            .expect("real-time mode")
            .1
            .min(Duration::from_secs(u32::MAX as u64));
    if Instant::now() > due {
        clock.late_releases += 1;
    }
    drain_control(control, world, ctl, barrier, drivers);
    loop {
        // The counter first, then what arrived: an ack after the look changes the counter,
        // so the sleep below returns at once. The counter only says when to look.
        let seen = barrier.ack_count();
        if clock.all_acked(world, acts, k) {
            break;
        }
        let now = Instant::now();
        if now >= due {
            break;
        }
        barrier.wait_ack_change_with(seen, (due - now).min(poll), bell);
        drain_control(control, world, ctl, barrier, drivers);
        if ctl.stop {
            return false;
        }
    }
    for i in clock.silent(world, ack_deadline) {
        world.mark_dead(i, "no action within runtime.ack_deadline_ms", None, None);
    }
    drivers.order_kills(world, barrier);
    true
}

pub fn run(args: &WorldArgs) -> Result<i32> {
    let t_start = Instant::now();
    let sc = &args.scenario;
    let n = sc.run.robots;
    let mut world = World::new(sc).map_err(|e| e.to_string())?;
    world.lend_air();
    let config = transport::run_config(&args.prefix)?;
    let node = transport::node(&config, "world")?;
    // Sense frames (every robot's record packed into one `world/sense` sample a tick) and the
    // air (`radio/air`), written under the shrink guard and made anew when a segment of
    // theirs shrinks under the world (data_plane).
    crate::shrink_guard::install()?;
    let mut data = DataPlane::create(&node, sc)?;
    // Actions: one `robot/<i>/act` service (or `robot/<i>/board`, `runtime.acts`) a robot.
    // Every read of robot r's act service is guarded: a segment that shrinks under it makes r
    // a fault, not a SIGBUS of the world (shrink_guard).
    let mut acts = GuardedActs::new(transport::ActSource::create(&node, sc)?);
    // The world's status for the orchestrator (`world/state`), written under the guard.
    let mut status = crate::status_out::StatusOut::create(&node)?;
    let control_svc = transport::control_service(&node, true)?;
    let control = control_svc
        .subscriber_builder()
        .create()
        .map_err(|e| format!("control subscriber: {e:?}"))?;
    // The barrier's segments, inherited from the orchestrator (docs/protocol.md section 4).
    let barrier = std::sync::Arc::new(TickBarrier::open_world()?);
    // A read of a robot's act service that does not end (a writer that keeps moving a
    // blackboard entry's counter) is bounded by a watchdog (read_watchdog).
    crate::read_watchdog::spawn(barrier.clone())?;
    if barrier.robots() != n {
        return Err(format!(
            "the tick barrier has {} robot slots, the scenario {n} robots",
            barrier.robots()
        )
        .into());
    }
    // runtime.barrier = "iox2-event": the barrier's wake-ups go through iceoryx2 events.
    let bell = match sc.runtime.barrier {
        swarm::scenario::BarrierKind::Futex => None,
        swarm::scenario::BarrierKind::Iox2Event => Some(swarm::bell::EventBell::world(&node, n)?),
    };
    let bell = bell.as_ref();
    let mut outputs = RunOutputs::create(&args.run_dir, &world)?;
    if args.live {
        outputs.flush_each_tick();
    }
    // Tell the orchestrator every service exists: agents may start.
    println!("READY");
    std::io::stdout().flush()?;

    let mut ctl = ControlState::default();
    let mut drivers = Drivers {
        attached: vec![0; n as usize],
        ordered: 0,
    };
    let poll = Duration::from_millis(sc.runtime.poll_ms);
    // Wait for every agent (or its death) before the first tick: a robot is attached when
    // its own act service delivered its agent's attach notice (the barrier's ready and attach
    // words, which every agent can write, are not believed).
    let startup_deadline = Instant::now() + Duration::from_secs(sc.runtime.startup_timeout_s);
    let mut unattached: Vec<u32> = (0..n).collect();
    loop {
        unattached.retain(|&i| world.alive[i as usize] && acts.attached(&node, i) == 0);
        if unattached.is_empty() {
            break;
        }
        drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
        if ctl.stop {
            break;
        }
        if Instant::now() > startup_deadline {
            return Err(format!(
                "only {} of {n} agents attached within runtime.startup_timeout_s = {} s",
                n as usize - unattached.len(),
                sc.runtime.startup_timeout_s
            )
            .into());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let startup_seconds = t_start.elapsed().as_secs_f64();
    let restart = sc.faults.on_fault == swarm::scenario::FaultPolicy::Restart;
    for i in 0..n {
        // A robot whose first agent died during start-up is driven by no one yet: any later
        // attach beyond the dead ones takes it over.
        drivers.attached[i as usize] = if world.alive[i as usize] {
            acts.attached(&node, i)
        } else {
            barrier.dead_upto(i)
        };
    }
    let t_loop = Instant::now();
    let realtime = sc.runtime.is_realtime();
    let mut clock = RealtimeClock::new(n as usize, t_loop);
    let mut late: Vec<Option<Action>> = vec![None; n as usize];
    let mut tick_ns = Vec::with_capacity(sc.run.max_ticks.min(10_000_000) as usize);
    let mut actions: Vec<Option<Action>> = vec![None; n as usize];
    let mut sent = Air::default();
    // Who is alive as this tick's frames are written (a copy: sensing needs the world).
    let mut alive_now: Vec<bool> = Vec::with_capacity(n as usize);
    let deadline = Duration::from_millis(sc.runtime.ack_deadline_ms);
    // Who was alive at the last tick's start: a robot found dead since has its act service
    // retired once (`ActSource::retire`: a blackboard is made anew for a replacement). Every
    // robot counts as alive before tick 0, so one that died during start-up is retired too.
    let mut was_alive: Vec<bool> = vec![true; n as usize];
    // Stopped during start-up (Ctrl-C before every agent attached): no tick runs, so no
    // robot that was still starting is declared dead at tick 0 (issue 14 item 8).
    let mut end = if ctl.stop { "interrupted" } else { "completed" }.to_string();
    // The run ended on an error after which its outputs are still written (the world exits 1).
    let mut failed = false;
    'ticks: while world.tick < sc.run.max_ticks && !ctl.stop {
        let k = world.tick;
        if !pace(&sc.runtime, t_loop, k, poll, || {
            drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
            ctl.stop
        }) {
            end = "interrupted".to_string();
            break;
        }
        let t_tick = Instant::now();
        world.begin_tick();
        drivers.order_kills(&world, &barrier);
        for (i, was) in was_alive.iter_mut().enumerate() {
            if *was && !world.alive[i] {
                acts.retire(i as u32);
            }
            *was = world.alive[i];
        }
        if restart {
            // A new agent process attached for a dead robot (its attach notice came through
            // the robot's act service): it drives the robot from now on, unless it is already
            // known dead itself (killed after its attach). An attach while the robot is still
            // alive (the report of the old agent's death not drained yet) is kept pending until
            // the robot is dead, never consumed early.
            for i in 0..n {
                if world.alive[i as usize] {
                    continue;
                }
                let c = acts.attached(&node, i);
                if c > drivers.attached[i as usize] && c > barrier.dead_upto(i) && world.revive(i) {
                    drivers.attached[i as usize] = c;
                    clock.start(i as usize, k);
                    // Alive again: its next death retires the new board (a kill scheduled
                    // at the very next tick included).
                    was_alive[i as usize] = true;
                }
            }
        }
        if ctl.stop || k + 1 == sc.run.max_ticks {
            world.set_stopping();
        }
        // Sense_k of every live robot, packed once into the tick's `world/sense` sample. What
        // a SIGKILLed agent held of the Sense and air samples does not need to be released:
        // the services' static slots count every subscriber's holds (a dead one's too), and
        // iceoryx2 reclaims them when the dead node is cleaned (`orchestrator::processes`).
        alive_now.clear();
        alive_now.extend_from_slice(&world.alive);
        let published = data
            .publish((&node, sc), &barrier, &mut world, &alive_now, &sent, k)
            .and_then(|()| {
                barrier.release_with(k, world.alive_count(), bell);
                let agents = world.alive_count() as usize;
                data.after_release((&node, sc), &barrier, (&world, &sent), k, agents)
            });
        if let Err(e) = published {
            // Remade too often: the run ends here, failed, with its outputs.
            if e.downcast_ref::<TooManyRemakes>().is_none() {
                return Err(e);
            }
            eprintln!("world: {e}");
            end = "failed: the world's data services were truncated again and again".to_string();
            failed = true;
            break;
        }
        if realtime {
            if !wait_realtime(
                (&mut clock, &mut acts),
                &mut world,
                &barrier,
                bell,
                (&control, &mut ctl, &mut drivers),
                t_loop,
                k,
            ) {
                end = "interrupted".to_string();
                break 'ticks;
            }
            sent.clear();
            for i in 0..n as usize {
                (actions[i], late[i]) = (None, None);
                if !world.alive[i] {
                    // Nothing of a dead robot's agent is read later as late.
                    acts.discard(i as u32);
                    continue;
                }
                (actions[i], late[i]) = acts.take_realtime(i as u32, k, clock.since[i], &mut sent);
            }
            if acts.fault_shrunk(&mut world) {
                drivers.order_kills(&world, &barrier);
            }
            let rec = world.apply_with_late(&actions, &late, &sent);
            outputs.push(&rec, &world)?;
            tick_ns.push(t_tick.elapsed().as_nanos() as u64);
            status.publish(world.status(false));
            drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
            if ctl.stop {
                end = "interrupted".to_string();
                break;
            }
            if let Some(why) = world.end_reason() {
                end = why.to_string();
                break;
            }
            continue;
        }
        // The deadline runs from the last ack of any robot, not from the release: when many
        // agents are slow but working (1,000 agents making their first radio links on 2 cores
        // take ~25 s), none is declared dead while acks still come in; a hung agent is
        // declared dead at most ack_deadline_ms after the last progress.
        let mut waited = Instant::now();
        let mut acked = 0usize;
        // A death the orchestrator reported before this release (its nudge of the ack counter
        // was reset by the release): handled now, not after a whole poll_ms.
        drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
        // The ack counter as read before a look that found robots missing: the next sleep
        // lasts until it changes (a forged counter at or above the expected count would
        // otherwise return at once, and the world would spin).
        let mut missing_at: Option<u32> = None;
        // A robot declared dead since the last look (a death report, the deadline): look
        // again at once, as the remaining robots may all be done.
        let mut look_now = false;
        loop {
            match (look_now, missing_at) {
                (true, _) => {}
                (false, None) => barrier.wait_acks_with(poll, bell),
                (false, Some(seen)) => barrier.wait_ack_change_with(seen, poll, bell),
            }
            let seen = barrier.ack_count();
            // A robot is done with tick k when its own act service delivered its action of
            // tick k; the ack counter and words only say when to look (docs/protocol.md
            // section 5): what another agent writes there cannot make the world skip a robot.
            let now_acked = world.live_robots().filter(|&i| acts.arrived(i, k)).count();
            if acts.fault_shrunk(&mut world) {
                drivers.order_kills(&world, &barrier);
                continue;
            }
            if now_acked == world.alive_count() as usize {
                break;
            }
            missing_at = Some(seen);
            if now_acked > acked {
                acked = now_acked;
                waited = Instant::now();
            }
            let alive = world.alive_count();
            drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
            if ctl.stop {
                // Ctrl-C while agents are slow (the first ticks make every radio link, which
                // takes seconds at 50 robots on 2 cores): the unfinished tick is dropped, the
                // outputs hold the ticks that completed.
                end = "interrupted".to_string();
                break 'ticks;
            }
            if waited.elapsed() > deadline {
                let silent: Vec<u32> = world
                    .live_robots()
                    .filter(|&i| !acts.arrived(i, k))
                    .collect();
                for i in silent {
                    world.mark_dead(i, "no action within runtime.ack_deadline_ms", None, None);
                }
                drivers.order_kills(&world, &barrier);
            }
            look_now = world.alive_count() != alive;
        }
        sent.clear();
        for (i, a) in actions.iter_mut().enumerate() {
            *a = None;
            if world.alive[i] {
                *a = acts.take(i as u32, k, &mut sent);
            }
        }
        if acts.fault_shrunk(&mut world) {
            drivers.order_kills(&world, &barrier);
        }
        let rec = world.apply(&actions, &sent);
        outputs.push(&rec, &world)?;
        tick_ns.push(t_tick.elapsed().as_nanos() as u64);
        status.publish(world.status(false));
        drain_control(&control, &mut world, &mut ctl, &barrier, &drivers);
        if ctl.stop {
            end = "interrupted".to_string();
            break;
        }
        if let Some(why) = world.end_reason() {
            end = why.to_string();
            break;
        }
    }
    let loop_seconds = t_loop.elapsed().as_secs_f64();
    let late_releases = clock.late_releases;
    barrier.shutdown_with(bell);
    let timing = Timing {
        wall_seconds: t_start.elapsed().as_secs_f64(),
        loop_seconds,
        startup_seconds,
        tick_ns,
        late_releases,
    };
    outputs.finish(&mut world, &timing, &args.run_id, "processes", &end)?;
    status.publish(world.status(true));
    status.close();
    // The control subscriber: let go unclosed when its segment shrank (give_up).
    if crate::shrink_guard::control_is_lost() {
        crate::shrink_guard::give_up((control, control_svc));
    }
    Ok(if failed { 1 } else { 0 })
}
