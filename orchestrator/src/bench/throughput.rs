//! `orchestrator bench throughput`: radio messages and bytes delivered per second with N robots
//! all broadcasting every tick.
//!
//! The runtime rows carry the traffic through the shared medium, as a run does: N child
//! processes (`__bench-child tput`) each run the agent's radio loop (wait for the tick on the
//! runtime's futex barrier, read the tick's air through `transport::AirSource` and decode its
//! list, `AgentRuntime::step` a behaviour that broadcasts one payload-sized message into its
//! act sample, send it, acknowledge); the parent is the world's radio (publish the air through
//! `transport::AirSink::publish`, release the tick, take every act sample's messages as the
//! world process does, `Medium::transmit` them). The air is the run's (`radio.air`): the
//! world's ring (the default, column `air` = ring) or the iceoryx2 air service (iceoryx2), so
//! both are measured in one run. Every robot is within range of every other one, so a tick
//! delivers N (N - 1) messages. No physics, no Sense frames: the numbers are the radio's.
//!
//! The `raw` rows move the same traffic with raw iceoryx2 and one service per robot (the link
//! design's wiring, without its runtime): loan the payload's bytes, copy them in, send; take
//! one sample off each other robot's service and drop it unread. They are what carrying this
//! traffic over iceoryx2 sender by sender costs on this machine.

use super::{check_no_leftovers, spawn_child, tick, BenchError, BenchResult, ByteBuf, ChildArgs};
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::Read;
use std::sync::atomic::AtomicUsize;
use std::sync::Arc;
use std::time::{Duration, Instant};
use swarm::air::ActTx;
use swarm::barrier::{TickBarrier, Wake};
use swarm::frames::RadioHeader;
use swarm::mailbox::Air;
use swarm::scenario::Scenario;
use swarm::transport::{PubSubCapacity, Reach, ServiceId, TransportError};
use swarm::{cleanup, transport, AgentRuntime, Behaviour, Blob, Command, Outbox, Received, Sense};
use world::medium::{Medium, MediumParams};
use world::output::percentile;

/// Most robots a throughput run takes (the raw rows subscribe every robot to every other).
const MAX_ROBOTS: u32 = 129;

/// How the parent (the world) carries the payloads from the act samples to the air.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WorldCopy {
    /// As the world process does: act sample -> the tick's buffer, and the medium lends the
    /// air (`Medium::transmit_lent`): the buffer -> the air sample (`write_air_from`). Two
    /// copies of each payload in the world.
    Lent,
    /// The path before `World::lend_air` (3dad5d7), kept to measure beside it: act sample ->
    /// the tick's buffer -> the medium's air (`Medium::transmit`) -> the air sample. Three.
    Copy,
}

impl WorldCopy {
    fn name(self) -> &'static str {
        match self {
            WorldCopy::Lent => "lent",
            WorldCopy::Copy => "copy",
        }
    }
}

/// (payload bytes, encoding, air, the world's copies): `seq` is a `Vec<u8>` as serde encodes
/// it (element by element), `bytes` the same bytes as one byte string, `blob` the same wire
/// bytes received in place (`swarm::Blob`, zero-copy), `raw` raw iceoryx2 without the runtime
/// (no air, no world), `raw-copy` the same with each received payload copied into an owned
/// buffer (what a `bytes` receiver gets: the counterpart the raw rows, which drop their samples
/// unread, do not make). The air is the runtime's iceoryx2 air service (`radio/air`). The
/// `copy` rows are the world's old three-copy path (`WorldCopy`).
pub const CASES: [(usize, &str, Option<AirTransport>, WorldCopy); 12] = [
    (64, "seq", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (4096, "seq", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (64, "bytes", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (4096, "bytes", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (64, "bytes", Some(AirTransport::Iceoryx2), WorldCopy::Copy),
    (4096, "bytes", Some(AirTransport::Iceoryx2), WorldCopy::Copy),
    (64, "blob", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (4096, "blob", Some(AirTransport::Iceoryx2), WorldCopy::Lent),
    (64, "raw", None, WorldCopy::Lent),
    (4096, "raw", None, WorldCopy::Lent),
    (64, "raw-copy", None, WorldCopy::Lent),
    (4096, "raw-copy", None, WorldCopy::Lent),
];

/// The air of a row: the runtime's iceoryx2 air service (the raw rows have none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AirTransport {
    #[default]
    Iceoryx2,
}

/// The air's name in the table and in a child's `--mode` (`enc:air`).
fn air_name(air: Option<AirTransport>) -> &'static str {
    match air {
        Some(AirTransport::Iceoryx2) => "iceoryx2",
        None => "-",
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub robots: u32,
    pub payload_bytes: usize,
    pub encoding: String,
    /// The air's transport: ring, iceoryx2, or - (raw rows: no air).
    pub air: String,
    /// The world's payload copies: lent (2), copy (3), or - (raw rows: no world).
    pub world: String,
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

fn scenario(robots: u32, size: usize, _air: AirTransport) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = robots;
    sc.radio.max_message_bytes = size.max(64) as u32;
    sc.radio.max_messages_per_tick = 1;
    sc.radio.loss = 0.0;
    sc.radio.delay_ticks = 0;
    // The blob rows' receivers hold the air sample they read in place.
    sc.radio.zero_copy_held = 1;
    sc
}

pub fn run(robots: u32, quick: bool) -> BenchResult<Vec<Row>> {
    let (min, max) = (2, MAX_ROBOTS);
    if !(min..=max).contains(&robots) {
        return Err(BenchError::Robots { robots, min, max });
    }
    // `SWARM_TPUT_ONLY=enc:air[:world]` (e.g. `bytes:ring`, `bytes:ring:copy`, `raw:-`) runs
    // only those rows (no world part: the lent rows): to profile one path (`perf record`
    // over the run), not for the tables.
    let only = std::env::var("SWARM_TPUT_ONLY").ok();
    CASES
        .iter()
        .filter(|&&(_, enc, air, world)| {
            only.as_deref().is_none_or(|o| {
                o.split(',').any(|c| {
                    let name = format!("{enc}:{}", air_name(air));
                    c == format!("{name}:{}", world.name())
                        || (c == name && world == WorldCopy::Lent)
                })
            })
        })
        .map(|&(size, enc, air, world)| {
            let ticks = match (quick, size > 1024 && enc == "seq") {
                (true, true) => 100,
                (true, false) => 300,
                (false, true) => 500,
                (false, false) => 2000,
            };
            one(robots, size, enc, air, world, ticks)
        })
        .collect()
}

pub fn print(rows: &[Row]) {
    println!("radio throughput: every robot broadcasts one message every tick, all robots in range (runtime: through the shared medium)");
    println!(
        "{:>6} {:>8} {:>6} {:>8} {:>5} {:>6} | {:>8} {:>8} {:>8} | {:>12} {:>10} | {:>9} {:>9}",
        "robots",
        "payload",
        "enc",
        "air",
        "world",
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
            "{:>6} {:>8} {:>6} {:>8} {:>5} {:>6} | {:>8.0} {:>8.0} {:>8.0} | {:>12.0} {:>10.1} | {:>9} {:>8.2}%",
            r.robots,
            format!("{} B", r.payload_bytes),
            r.encoding,
            r.air,
            r.world,
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
        for base in ["raw", "raw-copy"] {
            if let Some(raw) = rows
                .iter()
                .find(|x| x.encoding == base && x.payload_bytes == r.payload_bytes)
            {
                println!(
                    "runtime ({}, {} air, world {}) ticks/s / {base} iceoryx2 ticks/s at {} B: {:.2}x",
                    r.encoding,
                    r.air,
                    r.world,
                    r.payload_bytes,
                    r.ticks_per_s / raw.ticks_per_s.max(1e-9)
                );
            }
        }
    }
    println!("messages/s counts (message, receiver) pairs decoded by the receivers' runtimes (raw: taken off the services); MiB/s = messages/s x payload.");
    println!("enc: seq = the payload is a Vec<u8> (serde encodes it byte by byte), bytes = the same bytes as one byte string,");
    println!("     blob = the same wire bytes as a swarm::Blob, received in place (zero-copy: no decode copy),");
    println!("     raw = raw iceoryx2, one service per robot, the same barrier: loan, copy in, send; receive one per sender, drop unread;");
    println!("     raw-copy = the same, each received payload copied into an owned Vec<u8> (what a bytes receiver holds).");
    println!("world: lent = the world copies each payload twice (act sample -> tick buffer -> air, Medium::transmit_lent), as the world process does;");
    println!("       copy = three times (-> the medium's own air too, Medium::transmit), the path before World::lend_air.");
}

/// Seconds the children have to get ready, and to acknowledge one tick.
const READY_S: u64 = 120;
const ACK_S: u64 = 10;

fn one(
    n: u32,
    size: usize,
    enc: &str,
    air: Option<AirTransport>,
    world: WorldCopy,
    ticks: u64,
) -> BenchResult<Row> {
    let prefix = tick::bench_prefix(&format!(
        "tput-{n}-{size}-{enc}-{}-{}",
        air_name(air),
        world.name()
    ));
    let r = (|| -> BenchResult<Row> {
        let sc = scenario(n, size, air.unwrap_or_default());
        let (barrier, fds) = TickBarrier::create(&prefix, n)?;
        let config = transport::run_config(&prefix)?;
        let node = transport::node(&config, "bench-tput")?;
        let radio = if enc.starts_with("raw") {
            Radio::Raw(
                (0..n)
                    .map(|i| raw_service(&node, i, &sc, true))
                    .collect::<Result<Vec<_>, _>>()?,
            )
        } else {
            Radio::Medium(Box::new(WorldRadio::create(&node, &sc, world)?))
        };
        let mut radio = radio;
        let extra = [
            "--size".to_string(),
            size.to_string(),
            "--rounds".to_string(),
            ticks.to_string(),
            "--robots".to_string(),
            n.to_string(),
            "--mode".to_string(),
            format!("{enc}:{}", air_name(air)),
        ];
        let mut children = Vec::new();
        for i in 0..n {
            children.push(spawn_child("tput", (&prefix, &fds), i, &extra, true)?);
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
                if let Radio::Medium(w) = &mut radio {
                    w.publish(k)?;
                }
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
                if let Radio::Medium(w) = &mut radio {
                    w.transmit(k);
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
                air: air_name(air).to_string(),
                world: if air.is_some() { world.name() } else { "-" }.to_string(),
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
    cleanup::remove_run(&prefix);
    check_no_leftovers(&prefix)?;
    r
}

/// How the parent carries the traffic: the world's medium, or nothing but raw services.
enum Radio {
    Medium(Box<WorldRadio>),
    /// The per-robot services, held open while the children use them.
    Raw(#[allow(dead_code)] Vec<RawService>),
}

/// A robot's act service and the world's subscription to it.
type ActPort = (
    transport::ActService,
    Subscriber<ipc::Service, [u8], swarm::Action>,
);

/// The world's side of the medium: every robot's act service, the run's air (`AirSink`, as
/// the world process has it), the medium.
struct WorldRadio {
    acts: Vec<ActPort>,
    air: transport::AirSink,
    medium: Medium,
    poses: Vec<[f64; 3]>,
    alive: Vec<bool>,
    sent: Air,
    copy: WorldCopy,
}

impl WorldRadio {
    fn create(
        node: &Node<ipc::Service>,
        sc: &Scenario,
        copy: WorldCopy,
    ) -> BenchResult<WorldRadio> {
        let n = sc.run.robots;
        let mut acts = Vec::new();
        for i in 0..n {
            let svc = transport::act_service(node, i, true)?;
            let sub = transport::act_subscriber(&svc)?;
            acts.push((svc, sub));
        }
        Ok(WorldRadio {
            acts,
            air: transport::AirSink::create(node, sc)?,
            medium: Medium::new(sc, MediumParams::from_scenario(sc)),
            poses: (0..n)
                .map(|i| {
                    let p = position(i, n);
                    [p[0], p[1], 0.0]
                })
                .collect(),
            alive: vec![true; n as usize],
            sent: Air::default(),
            copy,
        })
    }

    /// The air of tick k, as the world process publishes it before the release
    /// (`AirSink::publish` of `write_air_from`, from the last tick's buffer `sent`, untouched
    /// since `transmit`); the spent air goes back to the medium, as `World::apply` hands it
    /// back.
    fn publish(&mut self, k: u64) -> BenchResult<()> {
        let due = self.medium.due(k);
        let n = self.poses.len();
        let len = swarm::air::air_len(due.as_ref(), n);
        let sent = self.sent.bytes();
        self.air.publish(len, |out| {
            swarm::air::write_air_from(due.as_ref(), sent, n, k, out)
        })?;
        if let Some(a) = due {
            self.medium.recycle(a);
        }
        Ok(())
    }

    /// Every robot's messages of tick k into the medium, as `World::apply` takes them (lent,
    /// as the world process has it, or copied: `WorldCopy`).
    fn transmit(&mut self, k: u64) {
        use swarm::wire::RadioTx;
        self.sent.clear();
        for (_, sub) in &self.acts {
            let mut latest = None;
            while let Ok(Some(s)) = sub.receive() {
                latest = Some(s);
            }
            if let Some(s) = latest {
                let used = (s.user_header().radio_bytes as usize).min(s.payload().len());
                for (h, p) in swarm::air::act_messages(&s.payload()[..used]).unwrap_or_default() {
                    self.sent.transmit(&h, &mut |b| b.copy_from_slice(p));
                }
            }
        }
        let (sent, bytes) = (self.sent.entries(), self.sent.bytes());
        match self.copy {
            WorldCopy::Lent => self
                .medium
                .transmit_lent(k, sent, bytes, &self.poses, &self.alive),
            WorldCopy::Copy => self
                .medium
                .transmit(k, sent, bytes, &self.poses, &self.alive),
        };
    }
}

/// Robot i of n on a circle of radius 100: every robot within range of every other.
fn position(i: u32, n: u32) -> [f64; 2] {
    let angle = std::f64::consts::TAU * i as f64 / n as f64;
    [500.0 + 100.0 * angle.cos(), 500.0 + 100.0 * angle.sin()]
}

/// A raw row's per-robot service.
type RawService = transport::PubSubService<[u8], RadioHeader>;

fn raw_service(
    node: &Node<ipc::Service>,
    robot: u32,
    sc: &Scenario,
    create: bool,
) -> BenchResult<RawService> {
    let n = sc.run.robots as usize;
    Ok(transport::pub_sub(
        node,
        ServiceId::from(format!("bench/raw/{robot}").as_str()),
        Reach::create_if(create, || PubSubCapacity {
            publishers: 1,
            subscribers: n,
            nodes: n + 2,
            buffer: 2,
            borrowed: Some(1),
            history: Some(0),
            safe_overflow: None,
        }),
    )?)
}

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
    let enc = a.mode.split_once(':').map_or(a.mode.as_str(), |m| m.0);
    let air = AirTransport::Iceoryx2;
    let r = match enc {
        "bytes" => child_run::<BytesBlob>(a, air),
        "blob" => child_run::<BlobMsg>(a, air),
        "raw" => child_raw(a, false),
        "raw-copy" => child_raw(a, true),
        _ => child_run::<SeqBlob>(a, air),
    };
    match r {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("bench child tput {}: {e}", a.index);
            1
        }
    }
}

fn child_run<M: Make>(a: &ChildArgs, air: AirTransport) -> BenchResult<()> {
    let (n, me) = (a.robots, a.index);
    let sc = scenario(n, a.size, air);
    let barrier = TickBarrier::open_inherited()?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, &format!("bench-tput-{me}"))?;
    let act_svc = transport::act_service(&node, me, false)?;
    let act = transport::act_publisher(&act_svc, &sc)?;
    let mut air = transport::AirSource::open(&node, &sc)?;
    let mut rt = AgentRuntime::new(
        &sc,
        me,
        Flood::<M> {
            data: vec![0xa5; data_len::<M>(a.size)],
            _m: std::marker::PhantomData,
        },
    );
    let mut sense = Sense::zeroed();
    sense.robot = me;
    sense.pos = position(me, n);
    sense.alive_robots = n;
    let warm = warm_for(a.rounds);
    let held = transport::air_held(&sc);
    let live: Arc<AtomicUsize> = Arc::default();
    let area = transport::act_slice_len(&sc);
    let mut inbox = Vec::new();
    let (mut delivered, mut malformed, mut failures) = (0u64, 0u64, 0u64);
    let mut done = 0;
    barrier.mark_ready(me);
    while let Some(k) = next_tick(&barrier, done) {
        sense.tick = k;
        inbox.clear();
        let mut bad = 0;
        if let Some(got) = air.receive()?.filter(|g| g.tick() == k) {
            bad = got.inbox(me, rt.zero_copy(), &live, held, &mut inbox);
        }
        let sample = act
            .loan_slice_uninit(area)
            .map_err(|source| TransportError::Loan {
                service: ServiceId::Act(me),
                source,
            })?;
        // SAFETY: shared memory is always initialised bytes; the parent reads only what
        // ActTx writes.
        let mut sample = unsafe { sample.assume_init() };
        let mut tx = ActTx::new(sample.payload_mut());
        let mut action = rt.step_owned(&sense, &inbox, bad, &mut tx);
        action.radio_bytes = tx.used as u32;
        failures += tx.failures;
        inbox.clear();
        *sample.user_header_mut() = action;
        sample.send().map_err(|source| TransportError::Send {
            service: ServiceId::Act(me),
            source,
        })?;
        if k >= warm {
            delivered += action.radio_delivered as u64;
            malformed += action.radio_malformed as u64;
        }
        barrier.ack(me, k);
        done = k + 1;
    }
    println!("delivered {delivered} lost 0 malformed {malformed} failed_sends {failures}");
    Ok(())
}

/// The raw iceoryx2 child: one service per robot, every robot subscribed to every other's,
/// no runtime (no encode, no range / loss decision, no decode). Every robot sends one message
/// a tick, so a receiver takes exactly one off each other robot's service. `copy`: each payload
/// is copied into an owned buffer (the `raw-copy` rows).
fn child_raw(a: &ChildArgs, copy: bool) -> BenchResult<()> {
    let (n, me) = (a.robots, a.index);
    let sc = scenario(n, a.size, AirTransport::Iceoryx2);
    let barrier = TickBarrier::open_inherited()?;
    let config = transport::run_config(&a.prefix)?;
    let node = transport::node(&config, &format!("bench-tput-{me}"))?;
    let own = raw_service(&node, me, &sc, false)?;
    let publisher = own
        .publisher_builder()
        .initial_max_slice_len(a.size.max(1))
        .allocation_strategy(AllocationStrategy::Static)
        .max_loaned_samples(1)
        .create()
        .map_err(|source| TransportError::Publisher {
            service: ServiceId::of(&own),
            source,
        })?;
    let mut links = Vec::new();
    for j in (0..n).filter(|&j| j != me) {
        let svc = raw_service(&node, j, &sc, false)?;
        let sub = svc
            .subscriber_builder()
            .buffer_size(2)
            .create()
            .map_err(|source| TransportError::Subscriber {
                service: ServiceId::of(&svc),
                source,
            })?;
        links.push((svc, sub));
    }
    let data = vec![0xa5u8; a.size];
    let warm = warm_for(a.rounds);
    let (mut delivered, mut failures) = (0u64, 0u64);
    let mut done = 0;
    barrier.mark_ready(me);
    while let Some(k) = next_tick(&barrier, done) {
        let mut got = 0u64;
        if k > 0 {
            for (_, sub) in links.iter() {
                if let Ok(Some(m)) = sub.receive() {
                    std::hint::black_box(m.user_header().seq);
                    if copy {
                        std::hint::black_box(m.payload().to_vec());
                    }
                    got += 1;
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
        if k >= warm {
            delivered += got;
        }
        barrier.ack(me, k);
        done = k + 1;
    }
    println!("delivered {delivered} lost 0 malformed 0 failed_sends {failures}");
    Ok(())
}
