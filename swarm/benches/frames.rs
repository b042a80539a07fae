//! Criterion benches of the frame encode / decode on the runtime's hot path: a radio message
//! through `AgentRuntime::step` (bincode sized, then encoded into the transmit buffer), its
//! decode as an agent decodes its list of the air (`wire::decode`, or `decode_in` in place)
//! followed by the delivering step, and a whole Sense frame written in place.
//!
//! `cargo bench -p swarm --bench frames`

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use serde::{Deserialize, Serialize};
use swarm::behaviour::RadioTx;
use swarm::{AgentRuntime, Behaviour, Command, Outbox, RadioHeader, Received, Scenario, Sense};

#[derive(Serialize, Deserialize, Clone)]
struct Beacon {
    pos: [f64; 2],
}

#[derive(Serialize, Deserialize, Clone)]
struct Blob(Vec<u8>);

/// Broadcasts a clone of `msg` every tick.
struct Talker<M> {
    msg: M,
}

impl<M: Serialize + for<'de> Deserialize<'de> + Clone> Behaviour for Talker<M> {
    type Msg = M;
    fn step_refs(&mut self, _s: &Sense, _i: &[&Received<M>], out: &mut Outbox<M>) -> Command {
        out.broadcast(self.msg.clone());
        Command::default()
    }
}

/// Says nothing; only receives.
struct Quiet<M>(std::marker::PhantomData<M>);

impl<M: Serialize + for<'de> Deserialize<'de> + Clone> Behaviour for Quiet<M> {
    type Msg = M;
    fn step_refs(&mut self, _s: &Sense, _i: &[&Received<M>], _out: &mut Outbox<M>) -> Command {
        Command::default()
    }
}

/// Encodes into one reused buffer, as a loaned shared-memory slot would be filled.
struct Buf {
    header: RadioHeader,
    bytes: Vec<u8>,
}

impl RadioTx for Buf {
    fn transmit(&mut self, h: &RadioHeader, fill: &mut dyn FnMut(&mut [u8])) {
        self.header = *h;
        self.bytes.clear();
        self.bytes.resize(h.len as usize, 0);
        fill(&mut self.bytes);
    }
}

fn sense(robot: u32, tick: u64, x: f64) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.tick = tick;
    s.pos = [x, 0.0];
    s
}

/// Robot 0 running `b`, and a buffer for what it sends.
fn receiver<B: Behaviour>(sc: &Scenario, b: B) -> (AgentRuntime<B>, Buf) {
    let sink = Buf {
        header: RadioHeader::default(),
        bytes: Vec::new(),
    };
    (AgentRuntime::new(sc, 0, b), sink)
}

fn bench_radio<M>(c: &mut Criterion, name: &str, msg: M, bytes: u64)
where
    M: Serialize + for<'de> Deserialize<'de> + Clone + 'static,
{
    let mut sc = Scenario::roam();
    sc.radio.max_message_bytes = 65_536;
    let mut g = c.benchmark_group("radio");
    g.throughput(Throughput::Bytes(bytes));
    // Encode: one step of a talker (the message clone included).
    let mut tx = AgentRuntime::new(&sc, 1, Talker { msg: msg.clone() });
    let mut buf = Buf {
        header: RadioHeader::default(),
        bytes: Vec::new(),
    };
    let s1 = sense(1, 1, 10.0);
    g.bench_function(BenchmarkId::new("step-encode", name), |b| {
        b.iter(|| tx.step(black_box(&s1), &[], 0, &mut buf))
    });
    // Decode: the encoded message decoded as from the air, then the step that delivers it.
    drop(msg);
    let (mut rx, mut sink) = receiver(&sc, Quiet::<M>(std::marker::PhantomData));
    let h = buf.header;
    let payload = buf.bytes.clone();
    let s = sense(0, 2, 0.0);
    g.bench_function(BenchmarkId::new("decode-step", name), |b| {
        b.iter(|| {
            let m: M = swarm::wire::decode(black_box(&h), black_box(&payload)).expect("decodes");
            let r = Received::new(&h, m);
            rx.step(&s, &[&r], 0, &mut sink)
        })
    });
    g.finish();
}

/// Receives in place (`zero_copy()`); only receives.
struct InPlace;

impl Behaviour for InPlace {
    type Msg = swarm::Blob;
    fn zero_copy(&self) -> bool {
        true
    }
    fn step_refs(
        &mut self,
        _s: &Sense,
        _i: &[&Received<swarm::Blob>],
        _out: &mut Outbox<swarm::Blob>,
    ) -> Command {
        Command::default()
    }
}

/// Bytes shared without copying, standing in for a held iceoryx2 sample.
struct Shared(std::sync::Arc<Vec<u8>>);

impl swarm::blob::AsBytes for Shared {
    fn as_bytes(&self) -> &[u8] {
        &self.0
    }
}

/// Zero-copy receive of a `swarm::Blob` message: `decode_in` decodes in place (the Blob is a
/// view), then the delivering step; against `decode-step` of the same wire bytes.
fn bench_in_place(c: &mut Criterion, name: &str, data: usize) {
    let mut sc = Scenario::roam();
    sc.radio.max_message_bytes = 65_536;
    let wire = bincode::serde::encode_to_vec(
        swarm::Blob::from(vec![7u8; data]),
        bincode::config::standard(),
    )
    .expect("encodable");
    let mut g = c.benchmark_group("radio");
    g.throughput(Throughput::Bytes(wire.len() as u64));
    let (mut rx, mut sink) = receiver(&sc, InPlace);
    let h = RadioHeader {
        sender: 1,
        len: wire.len() as u32,
        sender_pos: [10.0, 0.0],
        ..Default::default()
    };
    let wire = std::sync::Arc::new(wire);
    let s = sense(0, 2, 0.0);
    g.bench_function(BenchmarkId::new("decode-in-place-step", name), |b| {
        b.iter(|| {
            let owner: std::sync::Arc<dyn swarm::blob::AsBytes> =
                std::sync::Arc::new(Shared(wire.clone()));
            let m: swarm::Blob = swarm::wire::decode_in(black_box(&h), &owner, 0).expect("decodes");
            let r = Received::new(&h, m);
            rx.step(&s, &[&r], 0, &mut sink)
        })
    });
    g.finish();
}

fn bench_radio_all(c: &mut Criterion) {
    bench_radio(c, "beacon-16B", Beacon { pos: [1.5, -2.0] }, 16);
    bench_radio(c, "blob-64B", Blob(vec![7; 62]), 64);
    bench_radio(c, "blob-4KiB", Blob(vec![7; 4093]), 4096);
    bench_radio(c, "bytes-4KiB", swarm::Blob::from(vec![7; 4093]), 4096);
    bench_in_place(c, "bytes-4KiB", 4093);
    bench_radio(c, "bytes-64KiB", swarm::Blob::from(vec![7; 65_530]), 65_536);
    bench_in_place(c, "bytes-64KiB", 65_530);
}

fn bench_sense(c: &mut Criterion) {
    let mut g = c.benchmark_group("sense");
    g.throughput(Throughput::Bytes(std::mem::size_of::<Sense>() as u64));
    let mut frame = Sense::zeroed();
    g.bench_function("write-in-place-full", |b| {
        b.iter(|| {
            let s = black_box(&mut *frame);
            // As the world does: zero the fixed part, then write every list in full.
            // SAFETY: Sense is plain old data; its first SENSE_FIXED_BYTES are its fixed fields.
            unsafe {
                std::ptr::write_bytes(
                    s as *mut Sense as *mut u8,
                    0,
                    swarm::frames::SENSE_FIXED_BYTES,
                )
            };
            s.tick = 7;
            s.fill_every_list(1.0);
        })
    });
    g.bench_function("read-in-place-lists", |b| {
        b.iter(|| {
            let s = black_box(&*frame);
            let mut acc = 0.0;
            for q in s.obstacle_points() {
                acc += q[0] - q[1];
            }
            acc + s.nearby().len() as f64
        })
    });
    g.finish();
}

criterion_group!(benches, bench_radio_all, bench_sense);
criterion_main!(benches);
