//! The agent loop: attach to the run, then each released tick read the Sense frame and the
//! inbox in place, step the behaviour, send the action, ack (moved here from the built-in
//! agent binary so that any program runs the same loop: issue 38).

use super::{AgentError, EXIT_OK, EXIT_WORLD_GONE};
use crate::air::ActTx;
use crate::barrier::{TickBarrier, Wake};
use crate::frames::Action;
use crate::scenario::Scenario;
use crate::shrink_guard::{self, AGENT_FRAMES};
use crate::transport;
use crate::{AgentRuntime, Behaviour, Received};
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;

fn world_alive(pid: u32) -> bool {
    // SAFETY: signal 0 only checks for existence.
    pid != 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}

pub(super) fn run_loop<B: Behaviour>(
    prefix: &str,
    sc: &Scenario,
    robot: u32,
    mut rt: AgentRuntime<B>,
) -> Result<i32, AgentError> {
    // The world's data services are files any process of the user can truncate: this
    // agent's reads of them are guarded (a SIGBUS there holds the robot still for the tick,
    // instead of killing the agent; docs/protocol.md section 4), and so are the mappings of
    // their data segments, which zero-copy views the behaviour keeps read at any time
    // (registered by the transport as the first sample of each arrives).
    shrink_guard::install()?;
    let config = transport::run_config(prefix)?;
    let node = transport::node(&config, &format!("agent-{robot}"))?;
    let barrier = TickBarrier::open_agent(prefix)?;
    let world_pid = barrier.world_pid();
    // The generation of the world's data services: the world makes them anew when a segment
    // of theirs shrinks under it (docs/protocol.md section 4), and says so in the barrier.
    let mut generation = barrier.data_generation();
    // Sense frames: this robot's record in the world's `world/sense` sample, copied into
    // `frame`.
    let mut sense_in = transport::SenseSource::open_generation(&node, robot, generation)?;
    let mut frame = crate::frames::Sense::zeroed();
    // Actions: this robot's own `robot/<i>/act` service (or its board `robot/<i>/board`,
    // `runtime.acts = "blackboard"`). A replacement waits for the world to make its board
    // anew, as long as the world is there and running.
    let world_running = || world_alive(world_pid) && !barrier.is_shutdown();
    let mut act_out = transport::ActSink::open(&node, sc, robot, &world_running)?;
    // The air: the `radio/air` service (a sample held while a read or a zero-copy view
    // lasts).
    let mut air_in = transport::AirSource::open_generation(&node, sc, generation)?;
    let bell = match sc.runtime.barrier {
        crate::scenario::BarrierKind::Futex => None,
        crate::scenario::BarrierKind::Iox2Event => {
            Some(crate::bell::EventBell::agent(&node, barrier.robots())?)
        }
    };
    let bell = bell.as_ref();
    let poll = Duration::from_millis(sc.runtime.poll_ms);
    let held_limit = transport::air_held(sc);
    // Air samples held by zero-copy views.
    let live: Arc<AtomicUsize> = Arc::default();
    let mut inbox: Vec<Received<B::Msg>> = Vec::new();
    // Real-time mode (the world does not wait past a tick's deadline): a slow agent can find
    // the Sense frame or the air of a later tick than the one it woke for. It keeps them for
    // that tick (a copy of the Sense, the decoded list of the air) rather than losing them
    // when it reads the next time. In lock-step the world publishes tick k + 1 only after
    // every ack of tick k, so none of this ever happens.
    let mut ahead_sense: Option<Box<crate::frames::Sense>> = None;
    let mut ahead_inbox: Vec<Received<B::Msg>> = Vec::new();
    let mut ahead_air: Option<(u64, u32)> = None;
    // Whether this agent said that views it held read zeros (a truncated segment of the
    // world's, absorbed by the shrink guard: docs/protocol.md section 4).
    let mut said_lost = false;
    // The first tick to answer is the first released after the attach: a replacement
    // finds the tick its robot is dead in released already, without its Sense record, and
    // waits for the next (the ack words, which any agent can write, are not read).
    let mut done = 0;
    let attach = barrier.mark_ready(robot);
    // The attach notice: the world counts the robot attached when its act service
    // delivers it (docs/protocol.md section 6).
    act_out.attach(attach)?;
    loop {
        let k = match barrier.wait_release_with(done, poll, bell) {
            Wake::Shutdown => return Ok(EXIT_OK),
            Wake::Timeout => {
                if !world_alive(world_pid) {
                    return Ok(EXIT_WORLD_GONE);
                }
                continue;
            }
            Wake::Tick(k) => k,
        };
        // The world made its data services anew: open them and wait for tick k's frames,
        // which the world sends again once every agent opened them.
        let remade = barrier.data_generation();
        if remade != generation {
            generation = remade;
            // The old services are let go unclosed: a segment of theirs shrank, and closing
            // a port reads its service's shared state (a SIGBUS, or zeros iceoryx2 panics
            // on). The orchestrator removes their files with the run's.
            std::mem::forget(std::mem::replace(
                &mut sense_in,
                transport::SenseSource::open_generation(&node, robot, generation)?,
            ));
            std::mem::forget(std::mem::replace(
                &mut air_in,
                transport::AirSource::open_generation(&node, sc, generation)?,
            ));
            if !sense_in.wait_for(&world_running)? || !air_in.wait_for(&world_running)? {
                continue;
            }
        }
        // The world published Sense_k and the air of tick k before releasing tick k: read
        // them in place.
        // One receive: the subscriber's buffer holds 1 (the newest frame replaces an unread
        // one). Draining in a loop could hold two samples at once when the world publishes
        // the next tick's in between (real-time mode), beyond the air's borrow limit.
        let Some(got) = shrink_guard::reading(AGENT_FRAMES, || sense_in.receive(&mut frame)) else {
            hold_still(&mut act_out, robot, k)?;
            barrier.ack_with(robot, k, bell);
            done = k + 1;
            continue;
        };
        let got = got?;
        let latest: Option<&crate::frames::Sense> = got.map(|_| &*frame);
        if let Some(s) = latest.filter(|s| s.robot == robot && s.tick > k) {
            // The world is past tick k already: keep this Sense for its own tick.
            let mut copy = ahead_sense
                .take()
                .unwrap_or_else(crate::frames::Sense::zeroed);
            copy.as_mut().clone_from(s);
            ahead_sense = Some(copy);
            done = k + 1;
            continue;
        }
        let kept = ahead_sense.take();
        let sense: &crate::frames::Sense = match (latest, &kept) {
            (Some(s), _) => s,
            // Not for us yet (a restarted agent attaching mid-tick): wait for the next one.
            (None, None) => {
                done = k + 1;
                continue;
            }
            (None, Some(s)) => s,
        };
        if sense.tick != k || sense.robot != robot {
            done = k + 1;
            continue;
        }
        // This tick's inbox: our list in the air (the latest sample; the world sent it
        // before the release, so it is there unless we attached after).
        inbox.clear();
        let mut malformed = 0;
        // One receive, as for the Sense frame (buffer 1, borrowed 1 + radio.zero_copy_held:
        // the sample is held until decoded or until its views go).
        let zero_copy = rt.zero_copy();
        let decoded = shrink_guard::reading(AGENT_FRAMES, || -> Result<_, AgentError> {
            Ok(match air_in.receive()? {
                Some(a) if a.tick() == k => {
                    let bad = a.inbox(robot, zero_copy, &live, held_limit, &mut inbox);
                    Some((k, bad))
                }
                Some(a) if a.tick() > k => {
                    // Past tick k's deadline already (real-time mode): the list is for a
                    // later tick, decoded now and kept for it.
                    let t = a.tick();
                    ahead_inbox.clear();
                    let bad = a.inbox(robot, zero_copy, &live, held_limit, &mut ahead_inbox);
                    Some((t, bad))
                }
                _ => None,
            })
        });
        let Some(decoded) = decoded else {
            inbox.clear();
            drop(kept);
            hold_still(&mut act_out, robot, k)?;
            barrier.ack_with(robot, k, bell);
            done = k + 1;
            continue;
        };
        match decoded? {
            Some((t, bad)) if t == k => {
                ahead_air = None;
                malformed = bad;
            }
            Some((t, bad)) => ahead_air = Some((t, bad)),
            _ => match ahead_air {
                Some((t, bad)) if t == k => {
                    ahead_air = None;
                    std::mem::swap(&mut inbox, &mut ahead_inbox);
                    malformed = bad;
                }
                Some((t, _)) if t < k => ahead_air = None,
                _ => {}
            },
        }
        // The messages are written in place into the loaned sample's message area; the
        // world reads only the `radio_bytes` that ActTx writes.
        act_out.send(|area| {
            let mut tx = ActTx::new(area);
            let mut action = rt.step_owned(sense, &inbox, malformed, &mut tx);
            action.radio_bytes = tx.used as u32;
            action
        })?;
        // Zero-copy views the behaviour keeps (Blobs into an air) are read outside the
        // guarded reads: a fault there, in a world's data segment that a process of the user
        // truncated, read zeros (garbage messages for the tick) instead of killing the agent.
        if !said_lost && shrink_guard::absorbed() > 0 {
            said_lost = true;
            eprintln!(
                "agent {robot}: messages it held were lost to a truncated segment of the world's \
                 (read as zeros; docs/protocol.md section 4)"
            );
        }
        inbox.clear();
        drop(kept);
        barrier.ack_with(robot, k, bell);
        done = k + 1;
    }
}

/// Robot `robot`'s action of tick `k` when its frames could not be read (a segment of the
/// world's data services shrank under the read): no motion, no message. The world remakes the
/// services at its next write of them, and the agent follows (docs/protocol.md section 4).
fn hold_still(act_out: &mut transport::ActSink, robot: u32, k: u64) -> Result<(), AgentError> {
    act_out.send(|_area| Action {
        tick: k,
        robot,
        ..Action::default()
    })?;
    Ok(())
}
