//! The runtime's radio path: `AgentRuntime::step` encodes the behaviour's message into a
//! slot loaned from the sender's radio service (`ShmTx`, as the agent does), the receiver takes
//! the sample off its link and `AgentRuntime::ingest` decodes it out of shared memory (or, for
//! `BlobPing`, holds a view into it). Three message types: the payload as serde encodes a
//! `Vec<u8>`, as one byte string, and as a `swarm::Blob`.

use super::{open_barrier, wait_parent, Mode, Parent};
use crate::bench::{now_ns, tick, BenchError, BenchResult, ByteBuf, ChildArgs};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::cell::{Cell, RefCell};
use std::marker::PhantomData;
use std::rc::Rc;
use std::sync::Arc;
use swarm::frames::RadioHeader;
use swarm::scenario::Scenario;
use swarm::transport::{self, RadioSample, RadioService, ServiceId, ShmTx, TransportError};
use swarm::{AgentRuntime, Behaviour, Blob, Command, Outbox, Received, Sense};

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

fn sense_for(robot: u32, other: u32, x: f64) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.pos = [x, 0.0];
    s.alive_robots = 2;
    s.neighbours[0] = other;
    s.n_neighbours = 1;
    s
}

/// The parent: sends a ping through its runtime each round, takes the child's echo off its
/// radio link and records the echo's one-hop latency.
pub(super) fn parent<M: Payload>(p: &Parent) -> BenchResult<Vec<u64>> {
    let sc = latency_scenario(p.size);
    let config = transport::run_config(p.prefix)?;
    let node = transport::node(&config, "bench-lat-0")?;
    let svc0 = transport::radio_service(&node, 0, &sc, true)?;
    let svc1 = transport::radio_service(&node, 1, &sc, true)?;
    let publisher = transport::radio_publisher(&svc0, &sc)?;
    let sub = subscriber(&svc1, &sc, 1)?;
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
    let mut tx = ShmTx {
        publisher: &publisher,
        failures: 0,
    };
    let mut sense = sense_for(0, 1, 0.0);
    let (live, held) = (Arc::default(), transport::radio_held_per_link(&sc));
    // Tick 0: the link to robot 1 (it carries messages sent after tick 0).
    rt.begin(&sense);
    rt.step(&sense, &mut tx);
    rt.update_links(&sense);
    let mut done = 1;
    let r = (|| -> BenchResult<()> {
        for r in 0..p.total {
            let t = 2 * r + 1;
            sense.tick = t;
            rt.begin(&sense);
            fire.set(true);
            rt.step(&sense, &mut tx); // delivers the previous echo, sends the ping
            fire.set(false);
            if p.mode == Mode::Block {
                p.barrier.ack(0, r);
            }
            sense.tick = t + 1;
            rt.begin(&sense);
            p.wait(&mut done, || {
                let Some(m) = receive(&sub, 1)? else {
                    return Ok(None);
                };
                transport::take_radio(&mut rt, m, &live, held);
                recv_at.set(now_ns());
                Ok(Some(()))
            })?;
        }
        sense.tick = 2 * p.total + 1;
        rt.begin(&sense);
        rt.step(&sense, &mut tx); // delivers the last echo
        Ok(())
    })();
    tick::reap_children(vec![child]);
    r?;
    if tx.failures > 0 || rt.stats.oversize_sends > 0 {
        return Err(BenchError::SendFailures {
            failed: tx.failures,
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

/// The child: takes each ping off its link and echoes it through its runtime with a fresh
/// stamp.
pub(super) fn child<M: Payload>(a: &ChildArgs, mode: Mode) -> BenchResult<()> {
    let sc = latency_scenario(a.size);
    let barrier = open_barrier(a)?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, "bench-lat-1")?;
    let svc0 = transport::radio_service(&node, 0, &sc, false)?;
    let svc1 = transport::radio_service(&node, 1, &sc, false)?;
    let sub = subscriber(&svc0, &sc, 0)?;
    let publisher = transport::radio_publisher(&svc1, &sc)?;
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
    let mut tx = ShmTx {
        publisher: &publisher,
        failures: 0,
    };
    let mut sense = sense_for(1, 0, 10.0);
    let (live, held) = (Arc::default(), transport::radio_held_per_link(&sc));
    rt.begin(&sense);
    rt.step(&sense, &mut tx);
    rt.update_links(&sense);
    barrier.mark_ready(1);
    for r in 0..a.rounds {
        let t = 2 * r + 1;
        sense.tick = t;
        rt.begin(&sense);
        wait_parent(&barrier, mode, || {
            let Some(m) = receive(&sub, 0)? else {
                return Ok(None);
            };
            transport::take_radio(&mut rt, m, &live, held);
            Ok(Some(()))
        })?;
        sense.tick = t + 1;
        rt.begin(&sense);
        let act = rt.step(&sense, &mut tx); // the echo
        if act.n_sent != 1 {
            return Err(BenchError::Echo {
                round: r,
                sent: act.n_sent,
            });
        }
        if mode == Mode::Block {
            barrier.release(r + 1, 1);
        }
    }
    Ok(())
}

/// A subscription to `svc`, robot `of`'s radio.
fn subscriber(
    svc: &RadioService,
    sc: &Scenario,
    of: u32,
) -> BenchResult<Subscriber<ipc::Service, [u8], RadioHeader>> {
    Ok(svc
        .subscriber_builder()
        .buffer_size(transport::radio_buffer(sc))
        .create()
        .map_err(|source| TransportError::Subscriber {
            service: ServiceId::Radio(of),
            source,
        })?)
}

/// The next sample on the link to robot `of`'s radio, if there is one.
fn receive(
    sub: &Subscriber<ipc::Service, [u8], RadioHeader>,
    of: u32,
) -> BenchResult<Option<RadioSample>> {
    Ok(sub.receive().map_err(|source| TransportError::Receive {
        service: ServiceId::Radio(of),
        source,
    })?)
}
