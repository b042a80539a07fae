//! The runtime's radio path through the shared medium: the child (robot 1, an agent) encodes
//! its echo with `AgentRuntime::step` into its act sample (`ActTx`, as the agent does) and
//! sends it (hop 1, with the wake-up of the world through the barrier); the parent is the
//! world (it hands the act sample's messages, where they lie in the sample, to
//! `Medium::transmit`, writes the air and publishes it through the run's air, `radio.air`:
//! the world's ring by default) and robot 0, which reads the air and decodes its list out of
//! shared memory (`AirGot::inbox`; `BlobPing` holds a view). Hop 2 is thus a publish and a
//! read without a second process wake-up. The world writes the air straight from the act
//! sample it holds (`Medium::transmit_lent`, `swarm::air::write_air_from`): the payload is
//! copied once on the way (act sample -> air) besides its encoding into the act sample and
//! its decoding (none for the blob). The world process (`world/src/process.rs`) does not do
//! this yet: it copies each act sample's messages into a tick buffer, the medium copies them
//! again, then the air (BENCHMARKS.md section 14). Three message types: the payload as serde
//! encodes a `Vec<u8>`, as one byte string, and as a `swarm::Blob`.

use super::{open_barrier, wait_parent, Mode, Parent};
use crate::bench::{now_ns, tick, BenchError, BenchResult, ByteBuf, ChildArgs};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::cell::{Cell, RefCell};
use std::marker::PhantomData;
use std::rc::Rc;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use swarm::air::ActTx;
use swarm::mailbox::Air;
use swarm::scenario::Scenario;
use swarm::transport::{self, ServiceId, TransportError};
use swarm::{Action, AgentRuntime, Behaviour, Blob, Command, Outbox, Received, Sense};
use world::medium::{Medium, MediumParams};

/// A radio message of the latency bench: the sender's time stamp and the payload.
pub(super) trait Payload: Serialize + DeserializeOwned + Clone + 'static {
    /// Received in place (see `Behaviour::zero_copy`).
    const ZERO_COPY: bool = false;
    fn make(stamp: u64, data: Vec<u8>) -> Self;
    fn stamp(&self) -> u64;
    fn data(&self) -> &[u8];
}

/// `data` as serde serialises a `Vec<u8>`: a sequence, one element at a time.
#[derive(Clone, Serialize, Deserialize)]
pub(super) struct SeqPing {
    stamp: u64,
    data: Vec<u8>,
}

impl Payload for SeqPing {
    fn make(stamp: u64, data: Vec<u8>) -> Self {
        SeqPing { stamp, data }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn data(&self) -> &[u8] {
        &self.data
    }
}

/// `data` as one byte string (what `serde_bytes` does): the same wire bytes, one copy.
#[derive(Clone, Serialize, Deserialize)]
pub(super) struct BytesPing {
    pub(super) stamp: u64,
    pub(super) data: ByteBuf,
}

impl Payload for BytesPing {
    fn make(stamp: u64, data: Vec<u8>) -> Self {
        BytesPing {
            stamp,
            data: ByteBuf(data),
        }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn data(&self) -> &[u8] {
        &self.data.0
    }
}

/// `data` as a `swarm::Blob`: the same wire bytes as `BytesPing`, received in place.
#[derive(Clone, Serialize, Deserialize)]
pub(super) struct BlobPing {
    stamp: u64,
    data: Blob,
}

impl Payload for BlobPing {
    const ZERO_COPY: bool = true;
    fn make(stamp: u64, data: Vec<u8>) -> Self {
        BlobPing {
            stamp,
            data: Blob::from(data),
        }
    }
    fn stamp(&self) -> u64 {
        self.stamp
    }
    fn data(&self) -> &[u8] {
        &self.data
    }
}

fn encoded_len<M: Serialize>(m: &M) -> usize {
    let mut w = bincode::enc::write::SizeWriter::default();
    bincode::serde::encode_into_writer(m, &mut w, bincode::config::standard()).expect("encode");
    w.bytes_written
}

/// Data length whose message encodes to exactly `size` bytes (or as close below as possible).
pub(super) fn data_len_for<M: Payload>(size: usize) -> usize {
    let stamp = now_ns();
    let lo = size.saturating_sub(16);
    (lo..=size)
        .rev()
        .find(|&l| encoded_len(&M::make(stamp, vec![0; l])) <= size)
        .unwrap_or(lo)
}

fn latency_scenario(size: usize) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = 2;
    // Above the validated 64 KiB limit for the 1 MiB cell: set here, never validated.
    sc.radio.max_message_bytes = size.max(64) as u32;
    sc.radio.max_messages_per_tick = 1;
    sc.radio.loss = 0.0;
    sc.radio.delay_ticks = 0;
    // The blob path's receiver holds the sample it reads in place.
    sc.radio.zero_copy_held = 1;
    sc
}

/// The behaviour of both ends: the parent sends when told and records the latency of each
/// delivered message; the child echoes what it got with a fresh stamp.
struct LatBehaviour<M> {
    echo: bool,
    fire: Rc<Cell<bool>>,
    data: Vec<u8>,
    recv_at: Rc<Cell<u64>>,
    samples: Rc<RefCell<Vec<u64>>>,
    _m: PhantomData<M>,
}

impl<M: Payload> Behaviour for LatBehaviour<M> {
    type Msg = M;
    fn zero_copy(&self) -> bool {
        M::ZERO_COPY
    }
    fn step_refs(&mut self, _s: &Sense, inbox: &[&Received<M>], out: &mut Outbox<M>) -> Command {
        if self.echo {
            if let Some(r) = inbox.last() {
                let data = r.msg.data().to_vec();
                out.broadcast(M::make(now_ns(), data));
            }
        } else {
            for r in inbox {
                self.samples
                    .borrow_mut()
                    .push(self.recv_at.get().saturating_sub(r.msg.stamp()));
            }
            if self.fire.get() {
                let data = self.data.clone();
                out.broadcast(M::make(now_ns(), data));
            }
        }
        Command::default()
    }
}

fn sense_for(robot: u32, x: f64) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.pos = [x, 0.0];
    s.alive_robots = 2;
    s
}

/// The world's side of the cell: robot 1's act subscription, the air (`radio.air`: the
/// world's ring by default), the medium.
struct World {
    act: Subscriber<ipc::Service, [u8], Action>,
    air: transport::AirSink,
    medium: Medium,
    poses: Vec<[f64; 3]>,
    /// The messages of an act sample: header and payload offset in the sample.
    entries: Vec<(swarm::RadioHeader, usize)>,
}

impl World {
    /// Puts `sent` (messages of tick k, payloads in `bytes`) on the medium and publishes
    /// what is due at k + 1, writing each payload from `bytes` straight into the air
    /// (`Medium::transmit_lent`, `write_air_from`: one copy in the world).
    fn carry(
        &mut self,
        k: u64,
        sent: &[(swarm::RadioHeader, usize)],
        bytes: &[u8],
    ) -> BenchResult<()> {
        self.medium
            .transmit_lent(k, sent, bytes, &self.poses, &[true, true]);
        let due = self.medium.due(k + 1);
        let len = swarm::air::air_len(due.as_ref(), 2);
        self.air.publish(len, |out| {
            swarm::air::write_air_from(due.as_ref(), bytes, 2, k + 1, out)
        })?;
        if let Some(a) = due {
            self.medium.recycle(a);
        }
        Ok(())
    }

    /// [`World::carry`] of an act sample's messages, read where they lie in the sample
    /// (`act_messages`' payload slices are offsets into it) while the world holds it: the
    /// payload is copied once, from the act sample into the air.
    fn carry_act(&mut self, k: u64, payload: &[u8]) -> BenchResult<()> {
        let mut entries = std::mem::take(&mut self.entries);
        entries.clear();
        for (h, q) in swarm::air::act_messages(payload).unwrap_or_default() {
            entries.push((h, q.as_ptr() as usize - payload.as_ptr() as usize));
        }
        let r = self.carry(k, &entries, payload);
        self.entries = entries;
        r
    }
}

/// The parent: world and robot 0. Each round robot 0 sends a ping through the medium to the
/// child; the child's echo comes back in its act sample, goes through the medium into the
/// air, and robot 0 decodes it from the air sample: the echo's latency is recorded.
pub(super) fn parent<M: Payload>(p: &Parent) -> BenchResult<Vec<u64>> {
    let sc = latency_scenario(p.size);
    let config = transport::run_config(p.prefix)?;
    let node = transport::node(&config, "bench-lat-0")?;
    let _act0 = transport::act_service(&node, 0, true)?;
    let act1 = transport::act_service(&node, 1, true)?;
    let mut world = World {
        act: act1
            .subscriber_builder()
            .buffer_size(2)
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ServiceId::Act(1),
                source,
            })?,
        air: transport::AirSink::create(&node, &sc)?,
        medium: Medium::new(&sc, MediumParams::from_scenario(&sc)),
        poses: vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]],
        entries: Vec::new(),
    };
    let mut sub = transport::AirSource::open(&node, &sc)?;
    let child = p.spawn()?;
    let fire = Rc::new(Cell::new(false));
    let recv_at = Rc::new(Cell::new(0));
    let samples = Rc::new(RefCell::new(Vec::with_capacity(p.total as usize)));
    let mut rt = AgentRuntime::new(
        &sc,
        0,
        LatBehaviour::<M> {
            echo: false,
            fire: fire.clone(),
            data: vec![0xa5; data_len_for::<M>(p.size)],
            recv_at: recv_at.clone(),
            samples: samples.clone(),
            _m: PhantomData,
        },
    );
    let mut sense = sense_for(0, 0.0);
    let (live, held) = (Arc::default(), transport::air_held(&sc));
    let mut inbox: Vec<Received<M>> = Vec::new();
    let mut sent = Air::default();
    let mut done = 1;
    let r = (|| -> BenchResult<()> {
        for r in 0..p.total {
            // Tick 2r: robot 0 pings (delivering the last echo, decoded below).
            let t = 2 * r;
            sense.tick = t;
            sent.clear();
            fire.set(true);
            rt.step_owned(&sense, &inbox, 0, &mut sent);
            fire.set(false);
            inbox.clear();
            world.carry(t, sent.entries(), sent.bytes())?;
            if p.mode == Mode::Block {
                p.barrier.ack(0, r);
            }
            // Tick 2r + 1: the child's echo, through the medium, then robot 0's air.
            p.wait(&mut done, || {
                let Some(a) = world
                    .act
                    .receive()
                    .map_err(|source| TransportError::Receive {
                        service: ServiceId::Act(1),
                        source,
                    })?
                else {
                    return Ok(None);
                };
                let used = (a.user_header().radio_bytes as usize).min(a.payload().len());
                world.carry_act(t + 1, &a.payload()[..used])?;
                drop(a);
                let Some(s) = sub.receive()?.filter(|s| s.tick() == t + 2) else {
                    return Err(BenchError::Lost {
                        delivered: r,
                        expected: p.total,
                    });
                };
                s.inbox(0, rt.zero_copy(), &live, held, &mut inbox);
                recv_at.set(now_ns());
                Ok(Some(()))
            })?;
        }
        sense.tick = 2 * p.total;
        rt.step_owned(&sense, &inbox, 0, &mut Air::default()); // delivers the last echo
        inbox.clear();
        Ok(())
    })();
    tick::reap_children(vec![child]);
    r?;
    if rt.stats.oversize_sends > 0 {
        return Err(BenchError::SendFailures {
            failed: 0,
            oversize: rt.stats.oversize_sends,
        });
    }
    let v = samples.borrow().clone();
    if (v.len() as u64) < p.total {
        return Err(BenchError::Lost {
            delivered: v.len() as u64,
            expected: p.total,
        });
    }
    Ok(v)
}

/// The child, robot 1: takes each ping from the air and echoes it through its runtime, with
/// a fresh stamp, in its act sample.
pub(super) fn child<M: Payload>(a: &ChildArgs, mode: Mode) -> BenchResult<()> {
    let sc = latency_scenario(a.size);
    let barrier = open_barrier()?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, "bench-lat-1")?;
    let act_svc = transport::act_service(&node, 1, false)?;
    let act = transport::act_publisher(&act_svc, &sc)?;
    let mut sub = transport::AirSource::open(&node, &sc)?;
    let mut rt = AgentRuntime::new(
        &sc,
        1,
        LatBehaviour::<M> {
            echo: true,
            fire: Rc::new(Cell::new(false)),
            data: Vec::new(),
            recv_at: Rc::new(Cell::new(0)),
            samples: Rc::new(RefCell::new(Vec::new())),
            _m: PhantomData,
        },
    );
    let mut sense = sense_for(1, 10.0);
    let live: Arc<AtomicUsize> = Arc::default();
    let held = transport::air_held(&sc);
    let area = transport::act_slice_len(&sc);
    let mut inbox: Vec<Received<M>> = Vec::new();
    barrier.mark_ready(1);
    for r in 0..a.rounds {
        let t = 2 * r + 1;
        sense.tick = t;
        wait_parent(&barrier, mode, || {
            let Some(s) = sub.receive()?.filter(|s| s.tick() == t) else {
                return Ok(None);
            };
            s.inbox(1, rt.zero_copy(), &live, held, &mut inbox);
            Ok(Some(()))
        })?;
        let sample = act
            .loan_slice_uninit(area)
            .map_err(|source| TransportError::Loan {
                service: ServiceId::Act(1),
                source,
            })?;
        // SAFETY: shared memory is always initialised bytes; the world reads what ActTx writes.
        let mut sample = unsafe { sample.assume_init() };
        let mut tx = ActTx::new(sample.payload_mut());
        let mut action = rt.step_owned(&sense, &inbox, 0, &mut tx); // the echo
        action.radio_bytes = tx.used as u32;
        inbox.clear();
        if action.n_sent != 1 {
            return Err(BenchError::Echo {
                round: r,
                sent: action.n_sent,
            });
        }
        *sample.user_header_mut() = action;
        sample.send().map_err(|source| TransportError::Send {
            service: ServiceId::Act(1),
            source,
        })?;
        if mode == Mode::Block {
            barrier.release(r + 1, 1);
        }
    }
    Ok(())
}
