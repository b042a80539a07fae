//! The gateway's tick: on the world's release of tick k it sends each remote host that has
//! live robots one message (their Sense records, the air once) and waits for one batch back
//! (their Actions), which it publishes on the robots' act services and acknowledges on the
//! barrier, as each robot's agent would. Between ticks it mirrors the hosts' attaches (an
//! attach notice on the robot's act service, as an agent sends) and deaths into the world's
//! barrier and control channel, and forwards the world's kill orders and those of
//! `orchestrator kill` ([`KillServer`]) to the robots' hosts.

use super::kill::{KillServer, NO_LIVE_AGENT};
use super::link;
use super::wire::{Down, Up};
use super::{gateway::Remote, HostsError};
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::Duration;
use swarm::barrier::{TickBarrier, Wake};
use swarm::frames::{AirHeader, Control, Sense, SenseHeader, CONTROL_ROBOT_DIED, CONTROL_STOP};
use swarm::scenario::Scenario;
use swarm::sense_pack::{unpack_into, SensePacker};
use swarm::transport::{self, ActSink};

/// What reaches the gateway from the hosts (Zenoh callbacks feed one channel).
pub enum Event {
    /// Host `name`'s proxy joined (its liveliness token appeared).
    Came(String),
    /// Host `name`'s proxy is gone (its token went: died, or its host or link did).
    Gone(String),
    /// A message of host `name`.
    Up(String, Up),
}

/// How long the gateway sleeps at most between looks at the hosts' messages and the world's
/// kill orders while no tick is under way. [chosen] Short against a tick's cost; the world
/// waits for attaches in 2 ms slices too.
const IDLE_POLL: Duration = Duration::from_millis(2);

type Zpub = zenoh::pubsub::Publisher<'static>;

/// The wait status reported to the world for the robots of a host that left the run (its
/// proxy's liveliness token went): as if SIGKILLed, which is how a proxy's end stops its
/// agents; the gateway says on stderr which host left.
const LINK_LOST_STATUS: i32 = libc::SIGKILL;

/// How often the gateway looks for the first frames of data services the world made anew.
const REMADE_POLL: Duration = Duration::from_micros(200);

/// The world's `world/sense` and `radio/air` of one generation, as the gateway reads them.
struct WorldData {
    generation: transport::Generation,
    senses: Subscriber<ipc::Service, [u8], SenseHeader>,
    air: Subscriber<ipc::Service, [u8], AirHeader>,
    _senses_svc: transport::SensesService,
    _air_svc: transport::AirService,
}

impl WorldData {
    fn open(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        generation: transport::Generation,
    ) -> Result<WorldData, HostsError> {
        let senses_svc = transport::senses_service(node, sc, generation, false)?;
        let senses = senses_svc
            .subscriber_builder()
            .buffer_size(1)
            .create()
            .map_err(|e| HostsError::Other(format!("world/sense subscriber: {e:?}")))?;
        let air_svc = transport::air_service(node, sc, generation, false)?;
        let air = air_svc
            .subscriber_builder()
            .buffer_size(1)
            .create()
            .map_err(|e| HostsError::Other(format!("radio/air subscriber: {e:?}")))?;
        Ok(WorldData {
            generation,
            senses,
            air,
            _senses_svc: senses_svc,
            _air_svc: air_svc,
        })
    }
}

struct Host {
    remote: Remote,
    down: Zpub,
    /// Its proxy left: its robots are faults, nothing more is sent to it.
    gone: bool,
}

pub struct Gateway {
    node: Node<ipc::Service>,
    /// The run's scenario (a remote robot's act service is opened anew for a replacement).
    sc: Box<Scenario>,
    /// Per robot: the attach number of a remote agent that attached, while its act service
    /// is not open (the gateway keeps every remote robot's act service for the whole run, so
    /// this only guards a sink that failed to open: the notice waits for it).
    pending: Vec<Option<u64>>,
    hosts: Vec<Host>,
    /// Which host runs each robot (None: the world's host).
    at: Vec<Option<usize>>,
    /// The orchestrator's own mapping of the run's barrier (the world's segment is sealed
    /// against any other writable one).
    barrier: Arc<TickBarrier>,
    /// The world's data services, of the generation the barrier names.
    data: WorldData,
    /// Each remote robot's act service, written as its agent would.
    acts: Vec<Option<ActSink>>,
    control: Publisher<ipc::Service, Control, ()>,
    kills: KillServer,
    /// The last kill order of each robot forwarded.
    kill_done: Vec<u64>,
    packer: SensePacker,
    scratch: Box<Sense>,
    _services: Vec<Box<dyn std::any::Any>>,
}

impl Gateway {
    /// Opens the world's services for the remote robots; `barrier` is the run's, as the
    /// orchestrator mapped it.
    pub fn open(
        sc: &Scenario,
        prefix: &str,
        barrier: Arc<TickBarrier>,
        remotes: Vec<Remote>,
        downs: Vec<Zpub>,
    ) -> Result<Gateway, HostsError> {
        let n = sc.run.robots;
        let config = transport::run_config(prefix)?;
        let node = transport::node(&config, "gateway")?;
        let mut services: Vec<Box<dyn std::any::Any>> = Vec::new();
        let data = WorldData::open(&node, sc, barrier.data_generation())?;
        let control_svc = transport::control_service(&node, false)?;
        let control = control_svc
            .publisher_builder()
            .create()
            .map_err(|e| HostsError::Other(format!("run/control publisher: {e:?}")))?;
        let mut at = vec![None; n as usize];
        let mut acts: Vec<Option<_>> = (0..n).map(|_| None).collect();
        for (h, r) in remotes.iter().enumerate() {
            for &i in &r.robots {
                at[i as usize] = Some(h);
                acts[i as usize] = Some(ActSink::open(&node, sc, i, &|| true)?);
            }
        }
        services.push(Box::new(control_svc));
        let hosts = remotes
            .into_iter()
            .zip(downs)
            .map(|(remote, down)| Host {
                remote,
                down,
                gone: false,
            })
            .collect();
        Ok(Gateway {
            kills: KillServer::create(&node)?,
            node,
            sc: Box::new(sc.clone()),
            pending: vec![None; n as usize],
            hosts,
            at,
            barrier,
            data,
            acts,
            control,
            kill_done: vec![0; n as usize],
            packer: SensePacker::default(),
            scratch: Sense::zeroed(),
            _services: services,
        })
    }

    /// Serves the run until the world shuts it down or `stop` is set; then tells every host
    /// the run is over.
    pub fn run(&mut self, events: &Receiver<Event>, stop: &AtomicBool) -> Result<(), HostsError> {
        let result = self.serve(events, stop);
        for h in self.hosts.iter().filter(|h| !h.gone) {
            let _ = link::put(&h.down, Down::Stop.encode());
        }
        result
    }

    fn serve(&mut self, events: &Receiver<Event>, stop: &AtomicBool) -> Result<(), HostsError> {
        let mut done = 0;
        loop {
            if stop.load(Ordering::Acquire) {
                return Ok(());
            }
            while let Ok(ev) = events.try_recv() {
                self.handle(ev, None)?;
            }
            self.attach_pending()?;
            self.forward_kills()?;
            let k = match self.barrier.wait_release(done, IDLE_POLL) {
                Wake::Shutdown => return Ok(()),
                Wake::Timeout => continue,
                Wake::Tick(k) => k,
            };
            self.tick(k, events, stop)?;
            done = k + 1;
        }
    }

    /// Tick `k`: one message to each host with live robots, one batch back from each.
    fn tick(
        &mut self,
        k: u64,
        events: &Receiver<Event>,
        stop: &AtomicBool,
    ) -> Result<(), HostsError> {
        let g = self.barrier.data_generation();
        if g != self.data.generation {
            // The world made its data services anew (docs/protocol.md section 4): open them
            // and wait for the tick's frames, which it sends again once they are opened.
            // The old ones are let go unclosed (their shrunk segments: see the agent loop).
            std::mem::forget(std::mem::replace(
                &mut self.data,
                WorldData::open(&self.node, &self.sc, g)?,
            ));
            let barrier = &self.barrier;
            let running = || !barrier.is_shutdown() && !stop.load(Ordering::Relaxed);
            while running()
                && !(self.data.senses.has_samples().unwrap_or(false)
                    && self.data.air.has_samples().unwrap_or(false))
            {
                std::thread::sleep(REMADE_POLL);
            }
        }
        // The tick's frames, copied out under the shrink guard (issue 37): a segment of the
        // world's that another process truncated reads zeros here, not a SIGBUS that would end
        // the whole run; the tick is then skipped (the world makes its data services anew at
        // its next write, and this gateway follows the generation word above).
        let data = &self.data;
        let frames = swarm::shrink_guard::reading(swarm::shrink_guard::AGENT_FRAMES, || {
            let mut sense = None;
            while let Ok(Some(s)) = data.senses.receive() {
                sense = Some(s);
            }
            let mut air = None;
            while let Ok(Some(s)) = data.air.receive() {
                air = Some(s);
            }
            let sense = sense.filter(|s| s.user_header().tick == k)?;
            let air = match &air {
                Some(a) if a.user_header().tick == k => (*a.user_header(), a.payload().to_vec()),
                _ => (
                    AirHeader {
                        tick: k,
                        ..AirHeader::default()
                    },
                    Vec::new(),
                ),
            };
            Some((sense.payload().to_vec(), air))
        });
        let Some(Some((sense, (air_header, air_bytes)))) = frames else {
            return Ok(());
        };
        let n = self.at.len() as u32;
        let mut waiting = vec![false; self.hosts.len()];
        for (h, host) in self.hosts.iter().enumerate() {
            if host.gone {
                continue;
            }
            self.packer.begin(n);
            let mut any = false;
            for &r in &host.remote.robots {
                if let Ok(true) = unpack_into(&sense, r, &mut self.scratch) {
                    self.packer.push(r, &self.scratch);
                    any = true;
                }
            }
            if !any {
                continue;
            }
            let msg = Down::Tick {
                tick: k,
                sense: self.packer.bytes().to_vec(),
                air_header,
                air: air_bytes.clone(),
            };
            link::put(&host.down, msg.encode())?;
            waiting[h] = true;
        }
        while waiting.iter().any(|w| *w) {
            if stop.load(Ordering::Acquire)
                || self.barrier.is_shutdown()
                || self.barrier.current_tick() > k
            {
                // The world went on without them (its ack deadline) or ended the run.
                return Ok(());
            }
            match events.recv_timeout(IDLE_POLL) {
                Ok(ev) => self.handle(ev, Some((k, &mut waiting)))?,
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
            self.forward_kills()?;
        }
        Ok(())
    }

    fn host_index(&self, name: &str) -> Option<usize> {
        self.hosts.iter().position(|h| h.remote.name == name)
    }

    /// One event; `tick`: the tick under way and which hosts' batches it still waits for.
    fn handle(&mut self, ev: Event, tick: Option<(u64, &mut Vec<bool>)>) -> Result<(), HostsError> {
        match ev {
            Event::Came(_) => {}
            Event::Gone(name) => {
                let Some(h) = self.host_index(&name) else {
                    return Ok(());
                };
                if self.hosts[h].gone {
                    return Ok(());
                }
                self.hosts[h].gone = true;
                if let Some((_, waiting)) = tick {
                    waiting[h] = false;
                }
                if !self.barrier.is_shutdown() {
                    eprintln!(
                        "host {name} left the run (its proxy's liveliness token went): its \
                         robots {:?} are faults",
                        self.hosts[h].remote.robots
                    );
                    for r in self.hosts[h].remote.robots.clone() {
                        self.died(r, LINK_LOST_STATUS);
                    }
                }
            }
            Event::Up(name, up) => {
                let Some(h) = self.host_index(&name) else {
                    return Ok(());
                };
                match up {
                    Up::Ready => {}
                    Up::Attached { robot } if self.at.get(robot as usize) == Some(&Some(h)) => {
                        // The world believes only the notice on the robot's act service.
                        let attach = self.barrier.mark_ready(robot);
                        self.pending[robot as usize] = Some(attach);
                        self.attach_pending()?;
                    }
                    Up::Died { robot, status, .. }
                        if self.at.get(robot as usize) == Some(&Some(h)) =>
                    {
                        self.died(robot, status);
                    }
                    Up::Batch { tick: t, acts } => {
                        if let Some((k, waiting)) = tick {
                            if t == k && waiting[h] {
                                waiting[h] = false;
                                self.deliver(h, k, acts)?;
                            }
                        }
                    }
                    Up::Failed(message) => {
                        self.send_control(CONTROL_STOP, 0, 0);
                        return Err(HostsError::Host {
                            host: name,
                            message,
                        });
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// Publishes host `h`'s actions of tick `k` and acknowledges them, robot by robot.
    fn deliver(&mut self, h: usize, k: u64, acts: Vec<super::wire::Act>) -> Result<(), HostsError> {
        for a in acts {
            let r = a.robot as usize;
            if self.at.get(r) != Some(&Some(h)) {
                continue;
            }
            let Some(sink) = self.acts[r].as_mut() else {
                continue;
            };
            // Never an attach notice: those cross as `Up::Attached` only.
            if transport::attach_of(&a.action).is_some() {
                continue;
            }
            let (bytes, mut action) = (&a.area, a.action);
            sink.send(|area| {
                let used = bytes.len().min(area.len());
                area[..used].copy_from_slice(&bytes[..used]);
                action.radio_bytes = action.radio_bytes.min(used as u32);
                action
            })?;
            self.barrier.ack(a.robot, k);
        }
        Ok(())
    }

    /// Robot `r`'s agent on its host is dead (wait status `status`): reported to the world as
    /// the orchestrator reports a local agent's death (every attach so far dead, then a
    /// ROBOT_DIED).
    fn died(&mut self, r: u32, status: i32) {
        if self.barrier.is_shutdown() {
            return;
        }
        self.barrier.set_dead_upto(r, self.barrier.attach_count(r));
        self.send_control(CONTROL_ROBOT_DIED, r, status);
    }

    /// Gives the attach notice of every remote agent that attached, once its robot's act
    /// service can be opened (one try each call: the gateway never waits here).
    fn attach_pending(&mut self) -> Result<(), HostsError> {
        for r in 0..self.pending.len() {
            let Some(attach) = self.pending[r] else {
                continue;
            };
            if self.acts[r].is_none() {
                self.acts[r] = ActSink::try_open(&self.node, &self.sc, r as u32).ok();
            }
            if let Some(sink) = self.acts[r].as_mut() {
                sink.attach(attach)?;
                self.pending[r] = None;
            }
        }
        Ok(())
    }

    fn send_control(&self, kind: u32, robot: u32, status: i32) {
        if let Ok(s) = self.control.loan_uninit() {
            let _ = s
                .write_payload(Control {
                    kind,
                    robot,
                    value: crate::processes::monotonic_us(),
                    tick: self.barrier.current_tick(),
                    status,
                    reserved: 0,
                })
                .send();
        }
        self.barrier.nudge_world();
    }

    /// `orchestrator kill`'s orders for remote robots: each robot's live agent (its latest
    /// attach, not known dead) is ordered killed in the barrier, as the world orders it, and
    /// so forwarded by [`Gateway::forward_kills`].
    fn take_kill_requests(&self) -> Result<(), HostsError> {
        self.kills.serve(|r| {
            if !matches!(self.at.get(r as usize), Some(Some(_))) {
                return NO_LIVE_AGENT;
            }
            let attach = self.barrier.attach_count(r);
            if attach == 0 || attach <= self.barrier.dead_upto(r) {
                return NO_LIVE_AGENT;
            }
            self.barrier.order_kill(r, attach);
            attach
        })
    }

    /// The world's (and `orchestrator kill`'s) new kill orders of remote robots, to their
    /// hosts.
    fn forward_kills(&mut self) -> Result<(), HostsError> {
        self.take_kill_requests()?;
        for (r, at) in self.at.iter().enumerate() {
            let Some(h) = *at else { continue };
            let order = self.barrier.kill_order(r as u32);
            if order > self.kill_done[r] {
                self.kill_done[r] = order;
                let host = &self.hosts[h];
                if !host.gone {
                    let kill = Down::Kill {
                        robot: r as u32,
                        attach: order,
                    };
                    link::put(&host.down, kill.encode())?;
                }
            }
        }
        Ok(())
    }
}
