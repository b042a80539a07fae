//! The agent process: one robot, one behaviour, over iceoryx2 and the tick barrier.

use crate::behaviours::{dispatch, BehaviourVisitor};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::Duration;
use swarm::barrier::{BarrierError, TickBarrier, Wake};
use swarm::frames::RadioHeader;
use swarm::scenario::Scenario;
use swarm::transport::{self, ServiceId, ShmTx, TransportError};
use swarm::{AgentRuntime, Behaviour};

/// Why an agent process stopped before the run ended.
#[derive(Debug, thiserror::Error)]
pub enum AgentError {
    /// An iceoryx2 call failed (which service, and iceoryx2's error, are in it).
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// The run's tick barrier segment could not be opened.
    #[error(transparent)]
    Barrier(#[from] BarrierError),
}

pub type Result<T> = std::result::Result<T, AgentError>;

pub struct AgentArgs {
    pub robot: u32,
    pub prefix: String,
    pub scenario: Scenario,
}

/// Exit codes of the agent process.
pub const EXIT_OK: i32 = 0;
pub const EXIT_WORLD_GONE: i32 = 3;
pub const EXIT_SETUP: i32 = 4;

struct Link {
    _service: transport::RadioService,
    sub: Subscriber<ipc::Service, [u8], RadioHeader>,
    /// Samples of this link held by zero-copy views.
    live: Arc<AtomicUsize>,
}

fn world_alive(pid: u32) -> bool {
    // SAFETY: signal 0 only checks for existence.
    pid != 0 && unsafe { libc::kill(pid as i32, 0) } == 0
}

struct Run<'a>(&'a AgentArgs);

impl BehaviourVisitor for Run<'_> {
    type Out = Result<i32>;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Result<i32>
    where
        B::Msg: Send + Sync,
    {
        run_loop(
            self.0,
            AgentRuntime::new(&self.0.scenario, self.0.robot, make(self.0.robot)),
        )
    }
}

pub fn run(args: &AgentArgs) -> Result<i32> {
    dispatch(&args.scenario, Run(args))
}

fn run_loop<B: Behaviour>(args: &AgentArgs, mut rt: AgentRuntime<B>) -> Result<i32> {
    let sc = &args.scenario;
    let robot = args.robot;
    let config = transport::run_config(&args.prefix)?;
    let node = transport::node(&config, &format!("agent-{robot}"))?;
    let sense_svc = transport::sense_service(&node, robot, false)?;
    let sense_sub = sense_svc
        .subscriber_builder()
        .buffer_size(1)
        .create()
        .map_err(|source| TransportError::Subscriber {
            service: ServiceId::Sense(robot),
            source,
        })?;
    let act_svc = transport::act_service(&node, robot, false)?;
    let act_pub =
        act_svc
            .publisher_builder()
            .create()
            .map_err(|source| TransportError::Publisher {
                service: ServiceId::Act(robot),
                source,
            })?;
    let radio_svc = transport::radio_service(&node, robot, sc, false)?;
    let radio_pub = transport::radio_publisher(&radio_svc, sc)?;
    let barrier = TickBarrier::open(&args.prefix)?;
    let world_pid = barrier.world_pid();
    let bell = match sc.runtime.barrier {
        swarm::scenario::BarrierKind::Futex => None,
        swarm::scenario::BarrierKind::Iox2Event => {
            Some(swarm::bell::EventBell::agent(&node, barrier.robots())?)
        }
    };
    let bell = bell.as_ref();
    let poll = Duration::from_millis(sc.runtime.poll_ms);
    let held_limit = transport::radio_held_per_link(sc);
    let mut links: BTreeMap<u32, Link> = BTreeMap::new();
    let mut tx = ShmTx {
        publisher: &radio_pub,
        failures: 0,
    };
    let mut done = barrier.acked_up_to(robot);
    barrier.mark_ready(robot);
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
        // The world published Sense_k before releasing tick k: read it in place.
        let mut latest = None;
        while let Some(s) = sense_sub
            .receive()
            .map_err(|source| TransportError::Receive {
                service: ServiceId::Sense(robot),
                source,
            })?
        {
            latest = Some(s);
        }
        let Some(sense) = latest else {
            // Not for us yet (a restarted agent attaching mid-tick): wait for the next one.
            done = k + 1;
            continue;
        };
        if sense.tick != k || sense.robot != robot {
            done = k + 1;
            continue;
        }
        rt.begin(&sense);
        // Take off each link exactly the messages its sender sent at k-1 (FIFO per link; any of
        // tick k that a faster sender already sent stay for the next tick, or are taken early
        // in their place: the runtime orders and times delivery by header, not by arrival).
        //
        // A link whose robot was beyond comm_radius + link_margin at k-1 carries nothing in
        // range: its messages are left on the link (not even touched), where the sender's next
        // messages overwrite the oldest (iceoryx2's safe overflow). When the robot comes back
        // within reach, what is older than k-1 is taken off and dropped before its k-1 messages.
        if k > 0 {
            for (&s, link) in links.iter() {
                if !rt.links().reaches(s, k - 1) {
                    continue;
                }
                let mut taken = 0;
                while taken < barrier.sent_count(s, k - 1) {
                    match link.sub.receive() {
                        Ok(Some(m)) if m.user_header().tick + 1 < k => rt.stats.skipped += 1,
                        Ok(Some(m)) => {
                            transport::take_radio(&mut rt, m, &link.live, held_limit);
                            taken += 1;
                        }
                        _ => break,
                    }
                }
            }
        }
        let action = rt.step(&sense, &mut tx);
        barrier.record_sent(robot, k, action.n_sent);
        let (added, removed) = rt.update_links(&sense);
        for r in removed {
            links.remove(r);
        }
        for &r in added {
            match transport::radio_service(&node, r, sc, false).and_then(|svc| {
                let sub = svc
                    .subscriber_builder()
                    .buffer_size(transport::radio_buffer(sc))
                    .create()
                    .map_err(|source| TransportError::Subscriber {
                        service: ServiceId::Radio(r),
                        source,
                    })?;
                Ok(Link {
                    _service: svc,
                    sub,
                    live: Arc::default(),
                })
            }) {
                Ok(l) => {
                    links.insert(r, l);
                }
                Err(e) => eprintln!("agent {robot}: no link to robot {r}: {e}"),
            }
        }
        let sample = act_pub
            .loan_uninit()
            .map_err(|source| TransportError::Loan {
                service: ServiceId::Act(robot),
                source,
            })?;
        sample
            .write_payload(action)
            .send()
            .map_err(|source| TransportError::Send {
                service: ServiceId::Act(robot),
                source,
            })?;
        drop(sense);
        barrier.ack_with(robot, k, bell);
        done = k + 1;
    }
}
