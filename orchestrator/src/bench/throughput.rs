//! `orchestrator bench throughput`: radio messages and bytes delivered per second with N robots
//! all broadcasting every tick.
//!
//! N child processes (`__bench-child tput`) each run the agent's radio loop: wait for the tick
//! on the runtime's futex barrier, take off each link exactly the messages its sender recorded
//! for the last tick, `AgentRuntime::ingest` them, `AgentRuntime::step` a behaviour that
//! broadcasts one payload-sized message, encode it into a slot of its own radio service, record
//! the count and acknowledge. Every robot is within range of every other one and linked to it,
//! so a tick delivers N (N - 1) messages. The parent only releases ticks (no physics, no Sense
//! frames): the numbers are the radio's.
//!
//! The `raw` rows move the same traffic over the same services, barrier and link counting with
//! raw iceoryx2 and no runtime: loan the payload's bytes, copy them in, send; receive each
//! link's messages and drop them unread. They are what any runtime that carries this traffic
//! over iceoryx2 pays on this machine, so runtime / raw is what our radio path adds.

use super::{check_no_leftovers, spawn_child, tick, BenchError, BenchResult, ByteBuf, ChildArgs};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Read;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::{Duration, Instant};
use swarm::barrier::{TickBarrier, Wake};
use swarm::frames::{RadioHeader, MAX_NEIGHBOURS};
use swarm::scenario::Scenario;
use swarm::transport::{ServiceId, ShmTx, TransportError};
use swarm::{cleanup, transport, AgentRuntime, Behaviour, Blob, Command, Outbox, Received, Sense};
use world::output::percentile;

/// (payload bytes, encoding): `seq` is a `Vec<u8>` as serde encodes it (element by element),
/// `bytes` the same bytes as one byte string, `blob` the same wire bytes received in place
/// (`swarm::Blob`, zero-copy), `raw` raw iceoryx2 without the runtime.
pub const CASES: [(usize, &str); 8] = [
    (64, "seq"),
    (4096, "seq"),
    (64, "bytes"),
    (4096, "bytes"),
    (64, "blob"),
    (4096, "blob"),
    (64, "raw"),
    (4096, "raw"),
];

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub robots: u32,
    pub payload_bytes: usize,
    pub encoding: String,
    pub ticks: u64,
    pub seconds: f64,
    pub ticks_per_s: f64,
    pub tick_p50_us: f64,
    pub tick_p99_us: f64,
    pub delivered: u64,
    pub expected: u64,
    pub messages_per_s: f64,
    pub mib_per_s: f64,
}

fn warm_for(ticks: u64) -> u64 {
    (ticks / 10).max(10)
}

fn scenario(robots: u32, size: usize) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = robots;
    sc.radio.max_message_bytes = size.max(64) as u32;
    sc.radio.max_messages_per_tick = 1;
    sc.radio.loss = 0.0;
    sc.radio.delay_ticks = 0;
    // The blob rows' receivers hold the samples they read in place.
    sc.radio.zero_copy_held = 1;
    sc
}

pub fn run(robots: u32, quick: bool) -> BenchResult<Vec<Row>> {
    let (min, max) = (2, MAX_NEIGHBOURS as u32 + 1);
    if !(min..=max).contains(&robots) {
        return Err(BenchError::Robots { robots, min, max });
    }
    CASES
        .iter()
        .map(|&(size, enc)| {
            let ticks = match (quick, size > 1024 && enc == "seq") {
                (true, true) => 100,
                (true, false) => 300,
                (false, true) => 500,
                (false, false) => 2000,
            };
            one(robots, size, enc, ticks)
        })
        .collect()
}

pub fn print(rows: &[Row]) {
    println!("radio throughput: every robot broadcasts one message every tick, all robots in range and linked");
    println!(
        "{:>6} {:>8} {:>6} {:>6} | {:>8} {:>8} {:>8} | {:>12} {:>10} | {:>9} {:>9}",
        "robots",
        "payload",
        "enc",
        "ticks",
        "ticks/s",
        "p50 us",
        "p99 us",
        "messages/s",
        "MiB/s",
        "delivered",
        "of sent"
    );
    for r in rows {
        println!(
            "{:>6} {:>8} {:>6} {:>6} | {:>8.0} {:>8.0} {:>8.0} | {:>12.0} {:>10.1} | {:>9} {:>8.2}%",
            r.robots,
            format!("{} B", r.payload_bytes),
            r.encoding,
            r.ticks,
            r.ticks_per_s,
            r.tick_p50_us,
            r.tick_p99_us,
            r.messages_per_s,
            r.mib_per_s,
            r.delivered,
            100.0 * r.delivered as f64 / r.expected.max(1) as f64
        );
    }
    for r in rows
        .iter()
        .filter(|r| r.encoding == "bytes" || r.encoding == "blob")
    {
        if let Some(raw) = rows
            .iter()
            .find(|x| x.encoding == "raw" && x.payload_bytes == r.payload_bytes)
        {
            println!(
                "runtime ({}) / raw iceoryx2 tick time at {} B: {:.2}x",
                r.encoding,
                r.payload_bytes,
                raw.ticks_per_s / r.ticks_per_s.max(1e-9)
            );
        }
    }
    println!("messages/s counts (message, receiver) pairs decoded by the receivers' runtimes (raw: taken off the links); MiB/s = messages/s x payload.");
    println!("enc: seq = the payload is a Vec<u8> (serde encodes it byte by byte), bytes = the same bytes as one byte string,");
    println!("     blob = the same wire bytes as a swarm::Blob, received in place (zero-copy: no decode copy),");
    println!("     raw = raw iceoryx2 on the same services, barrier and link counting: loan, copy in, send; receive, drop unread.");
}

/// Seconds the children have to get ready, and to acknowledge one tick.
const READY_S: u64 = 120;
const ACK_S: u64 = 10;

fn one(n: u32, size: usize, enc: &str, ticks: u64) -> BenchResult<Row> {
    let prefix = tick::bench_prefix(&format!("tput-{n}-{size}-{enc}"));
    let r = (|| -> BenchResult<Row> {
        let sc = scenario(n, size);
        let barrier = TickBarrier::create(&prefix, n)?;
        let config = transport::run_config(&prefix)?;
        let node = transport::node(&config, "bench-tput")?;
        let _services = (0..n)
            .map(|i| transport::radio_service(&node, i, &sc, true))
            .collect::<Result<Vec<_>, _>>()?;
        let extra = [
            "--size".to_string(),
            size.to_string(),
            "--rounds".to_string(),
            ticks.to_string(),
            "--robots".to_string(),
            n.to_string(),
            "--mode".to_string(),
            enc.to_string(),
        ];
        let mut children = Vec::new();
        for i in 0..n {
            children.push(spawn_child("tput", &prefix, i, &extra, true)?);
        }
        let result = (|| -> BenchResult<Row> {
            let t = Instant::now();
            while barrier.ready_count() < n {
                if let Some(status) = children
                    .iter_mut()
                    .find_map(|c| c.try_wait().ok().flatten())
                {
                    return Err(BenchError::ChildExited {
                        kind: "tput".into(),
                        status,
                    });
                }
                if t.elapsed() > Duration::from_secs(READY_S) {
                    return Err(BenchError::ChildNotReady {
                        kind: "tput".into(),
                        seconds: READY_S,
                    });
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            let warm = warm_for(ticks);
            let mut ns = Vec::with_capacity(ticks as usize);
            let mut start = Instant::now();
            for k in 0..ticks + warm {
                if k == warm {
                    start = Instant::now();
                }
                let t = Instant::now();
                barrier.release(k, n);
                while !(0..n).all(|i| barrier.acked(i, k)) {
                    barrier.wait_acks(Duration::from_millis(500));
                    if t.elapsed() > Duration::from_secs(ACK_S) {
                        return Err(BenchError::NoAck {
                            tick: k,
                            seconds: ACK_S,
                        });
                    }
                }
                if k >= warm {
                    ns.push(t.elapsed().as_nanos() as u64);
                }
            }
            let seconds = start.elapsed().as_secs_f64();
            barrier.shutdown();
            let mut delivered = 0u64;
            for c in children.iter_mut() {
                let mut s = String::new();
                if let Some(o) = c.stdout.as_mut() {
                    let _ = o.read_to_string(&mut s);
                }
                let mut it = s.split_whitespace();
                if it.next() != Some("delivered") {
                    return Err(BenchError::ChildOutput { output: s });
                }
                delivered += it.next().and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
            }
            ns.sort_unstable();
            let msgs = delivered as f64 / seconds;
            Ok(Row {
                robots: n,
                payload_bytes: size,
                encoding: enc.to_string(),
                ticks,
                seconds,
                ticks_per_s: ticks as f64 / seconds,
                tick_p50_us: percentile(&ns, 0.5) / 1e3,
                tick_p99_us: percentile(&ns, 0.99) / 1e3,
                delivered,
                expected: n as u64 * (n as u64 - 1) * ticks,
                messages_per_s: msgs,
                mib_per_s: msgs * size as f64 / (1024.0 * 1024.0),
            })
        })();
        barrier.shutdown();
        tick::reap_children(children);
        result
    })();
    swarm::barrier::unlink(&prefix);
    cleanup::remove_run(&prefix);
    check_no_leftovers(&prefix)?;
    r
}

/// A radio link: the sender's service, our subscription to it, its samples held by
/// zero-copy views.
type Link = (
    transport::RadioService,
    Subscriber<ipc::Service, [u8], RadioHeader>,
    Arc<AtomicUsize>,
);

/// The next tick after `done`, or None at shutdown.
fn next_tick(barrier: &TickBarrier, done: u64) -> Option<u64> {
    loop {
        match barrier.wait_release(done, Duration::from_millis(200)) {
            Wake::Shutdown => return None,
            Wake::Timeout => continue,
            Wake::Tick(k) => return Some(k),
        }
    }
}

/// A bench child's barrier, own radio publisher and links to every other robot (by id).
struct Ports {
    barrier: TickBarrier,
    _node: Node<ipc::Service>,
    _own: transport::RadioService,
    publisher: iceoryx2::port::publisher::Publisher<ipc::Service, [u8], RadioHeader>,
    links: BTreeMap<u32, Link>,
}

impl Ports {
    fn open(a: &ChildArgs, sc: &Scenario) -> BenchResult<Ports> {
        let (n, me) = (a.robots, a.index);
        let barrier = TickBarrier::open(&a.prefix)?;
        let config = transport::run_config(&a.prefix)?;
        let node = transport::node(&config, &format!("bench-tput-{me}"))?;
        let own = transport::radio_service(&node, me, sc, false)?;
        let publisher = transport::radio_publisher(&own, sc)?;
        let mut links = BTreeMap::new();
        for j in (0..n).filter(|&j| j != me) {
            let svc = transport::radio_service(&node, j, sc, false)?;
            let sub = svc
                .subscriber_builder()
                .buffer_size(transport::radio_buffer(sc))
                .create()
                .map_err(|source| TransportError::Subscriber {
                    service: ServiceId::Radio(j),
                    source,
                })?;
            links.insert(j, (svc, sub, Arc::default()));
        }
        Ok(Ports {
            barrier,
            _node: node,
            _own: own,
            publisher,
            links,
        })
    }
}

/// The broadcast payload, element by element.
#[derive(Clone, Serialize, Deserialize)]
struct SeqBlob(Vec<u8>);

/// The broadcast payload as one byte string.
#[derive(Clone, Serialize, Deserialize)]
struct BytesBlob(ByteBuf);

trait Make: Serialize + serde::de::DeserializeOwned + Clone + 'static {
    /// Received in place (see `Behaviour::zero_copy`).
    const ZERO_COPY: bool = false;
    fn make(data: Vec<u8>) -> Self;
}

/// The broadcast payload as a Blob, received in place.
#[derive(Clone, Serialize, Deserialize)]
struct BlobMsg(Blob);

impl Make for BlobMsg {
    const ZERO_COPY: bool = true;
    fn make(data: Vec<u8>) -> Self {
        BlobMsg(Blob::from(data))
    }
}

impl Make for SeqBlob {
    fn make(data: Vec<u8>) -> Self {
        SeqBlob(data)
    }
}

impl Make for BytesBlob {
    fn make(data: Vec<u8>) -> Self {
        BytesBlob(ByteBuf(data))
    }
}

/// Broadcasts one message every tick.
struct Flood<M> {
    data: Vec<u8>,
    _m: std::marker::PhantomData<M>,
}

impl<M: Make> Behaviour for Flood<M> {
    type Msg = M;
    fn zero_copy(&self) -> bool {
        M::ZERO_COPY
    }
    fn step_refs(&mut self, _s: &Sense, _inbox: &[&Received<M>], out: &mut Outbox<M>) -> Command {
        out.broadcast(M::make(self.data.clone()));
        Command::default()
    }
}

fn data_len<M: Make>(size: usize) -> usize {
    let lo = size.saturating_sub(8);
    (lo..=size)
        .rev()
        .find(|&l| {
            let mut w = bincode::enc::write::SizeWriter::default();
            bincode::serde::encode_into_writer(
                M::make(vec![0; l]),
                &mut w,
                bincode::config::standard(),
            )
            .is_ok()
                && w.bytes_written <= size
        })
        .unwrap_or(lo)
}

pub fn child(a: &ChildArgs) -> i32 {
    let r = match a.mode.as_str() {
        "bytes" => child_run::<BytesBlob>(a),
        "blob" => child_run::<BlobMsg>(a),
        "raw" => child_raw(a),
        _ => child_run::<SeqBlob>(a),
    };
    match r {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("bench child tput {}: {e}", a.index);
            1
        }
    }
}

fn child_run<M: Make>(a: &ChildArgs) -> BenchResult<()> {
    let (n, me) = (a.robots, a.index);
    let sc = scenario(n, a.size);
    let ports = Ports::open(a, &sc)?;
    let (barrier, publisher, links) = (&ports.barrier, &ports.publisher, &ports.links);
    let mut rt = AgentRuntime::new(
        &sc,
        me,
        Flood::<M> {
            data: vec![0xa5; data_len::<M>(a.size)],
            _m: std::marker::PhantomData,
        },
    );
    let mut tx = ShmTx {
        publisher,
        failures: 0,
    };
    let mut sense = Sense::zeroed();
    sense.robot = me;
    let angle = std::f64::consts::TAU * me as f64 / n as f64;
    sense.pos = [500.0 + 100.0 * angle.cos(), 500.0 + 100.0 * angle.sin()];
    sense.alive_robots = n;
    for (slot, j) in (0..n).filter(|&j| j != me).take(MAX_NEIGHBOURS).enumerate() {
        sense.neighbours[slot] = j;
        sense.n_neighbours = slot as u32 + 1;
    }
    let warm = warm_for(a.rounds);
    let held = transport::radio_held_per_link(&sc);
    let (mut delivered, mut lost, mut malformed) = (0u64, 0u64, 0u64);
    let mut done = 0;
    barrier.mark_ready(me);
    while let Some(k) = next_tick(barrier, done) {
        sense.tick = k;
        rt.begin(&sense);
        if k > 0 {
            for (&s, (_, sub, live)) in links.iter() {
                for _ in 0..barrier.sent_count(s, k - 1) {
                    match sub.receive() {
                        Ok(Some(m)) => transport::take_radio(&mut rt, m, live, held),
                        _ => break,
                    }
                }
            }
        }
        let action = rt.step(&sense, &mut tx);
        barrier.record_sent(me, k, action.n_sent);
        rt.update_links(&sense);
        if k >= warm {
            delivered += action.radio_delivered as u64;
            lost += action.radio_dropped_loss as u64;
            malformed += action.radio_malformed as u64;
        }
        barrier.ack(me, k);
        done = k + 1;
    }
    println!(
        "delivered {delivered} lost {lost} malformed {malformed} failed_sends {}",
        tx.failures
    );
    Ok(())
}

/// The raw iceoryx2 child: the same services, links, barrier and counts as `child_run`, no
/// runtime (no encode, no range / loss decision, no decode).
fn child_raw(a: &ChildArgs) -> BenchResult<()> {
    let me = a.index;
    let sc = scenario(a.robots, a.size);
    let ports = Ports::open(a, &sc)?;
    let (barrier, publisher, links) = (&ports.barrier, &ports.publisher, &ports.links);
    let data = vec![0xa5u8; a.size];
    let warm = warm_for(a.rounds);
    let (mut delivered, mut failures) = (0u64, 0u64);
    let mut done = 0;
    barrier.mark_ready(me);
    while let Some(k) = next_tick(barrier, done) {
        let mut got = 0u64;
        if k > 0 {
            for (&s, (_, sub, _)) in links.iter() {
                for _ in 0..barrier.sent_count(s, k - 1) {
                    match sub.receive() {
                        Ok(Some(m)) => {
                            std::hint::black_box(m.user_header().seq);
                            got += 1;
                        }
                        _ => break,
                    }
                }
            }
        }
        let header = RadioHeader {
            sender: me,
            tick: k,
            len: a.size as u32,
            ..Default::default()
        };
        let sent = match publisher.loan_slice_uninit(a.size) {
            Ok(sample) => {
                let mut sample = sample.write_from_slice(&data);
                *sample.user_header_mut() = header;
                sample.send().is_ok()
            }
            Err(_) => false,
        };
        if !sent {
            failures += 1;
        }
        barrier.record_sent(me, k, sent as u32);
        if k >= warm {
            delivered += got;
        }
        barrier.ack(me, k);
        done = k + 1;
    }
    println!("delivered {delivered} lost 0 malformed 0 failed_sends {failures}");
    Ok(())
}
