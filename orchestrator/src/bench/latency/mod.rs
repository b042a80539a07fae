//! `orchestrator bench latency`: one-hop latency between two processes.
//!
//! Paths (each cell is a parent process and one `__bench-child lat-*` process, ping-pong; the
//! parent is the measured receiver of the child's messages):
//! - `runtime radio`: the robot's radio as it really travels: `AgentRuntime::step` -> the
//!   behaviour's message bincode-encoded straight into a slot loaned from the sender's radio
//!   service (the same steps as the agent's `ShmTx`) -> subscriber `receive` ->
//!   `AgentRuntime::ingest` decodes it out of shared memory. Message: `{ stamp: u64, data:
//!   Vec<u8> }` (serde encodes a `Vec<u8>` element by element);
//! - `runtime radio, bytes`: the same, with the data field serialised as one byte string;
//! - `runtime radio, blob`: the same wire bytes, the data field a `swarm::Blob` and the
//!   behaviour's `zero_copy()`: the receiver decodes in place and holds a view into the sample;
//! - `runtime Sense`: a whole Sense frame, `loan_uninit`, written in place, sent, read in place;
//! - `raw iceoryx2`: `[u8]` publish-subscribe, loan, copy the payload in, send, receive;
//! - `UDS + bincode`: the bytes variant of the radio's message encoded into a buffer, written
//!   to a Unix domain socket, read and decoded (the payload copied four times: encode, write,
//!   read, decode).
//!
//! One hop = from the sender's time stamp (taken right before it encodes / loans) to the
//! receiver holding the decoded message (or the sample), both read from CLOCK_MONOTONIC.
//! Busy-poll: the receiver spins on receive. Blocking-wake: the receiver sleeps and the sender
//! wakes it once per message: the runtime paths through the tick barrier's futex words (as
//! the runtime does), raw iceoryx2 through an iceoryx2 event, UDS in a blocking read.
//!
//! One file per path (`radio.rs`, `sense.rs`, `iox2.rs`, `uds.rs`), each with its parent
//! (measuring) and child (echoing) side; all of them wait through `wait::wait_for`. The table
//! and its ratios are in `table.rs`.

mod iox2;
mod radio;
mod sense;
mod table;
mod uds;
mod wait;

pub use table::{print, Report, Row};

use super::error::Peer;
use super::{check_no_leftovers, spawn_child, tick, BenchError, BenchResult, ChildArgs};
use std::process::Child;
use std::time::{Duration, Instant};
use swarm::barrier::{TickBarrier, Wake};
use swarm::{cleanup, Sense};
use wait::NAP;
use world::output::percentile;

/// The radio payload sizes of the issue.
pub const SIZES: [usize; 4] = [64, 4096, 65536, 1 << 20];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Poll,
    Block,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Poll => "poll",
            Mode::Block => "block",
        }
    }
    fn parse(s: &str) -> Mode {
        if s == "poll" {
            Mode::Poll
        } else {
            Mode::Block
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Path {
    Radio,
    RadioBytes,
    RadioBlob,
    Sense,
    Iox2,
    Uds,
}

impl Path {
    fn kind(self) -> &'static str {
        match self {
            Path::Radio => "lat-radio",
            Path::RadioBytes => "lat-radio-bytes",
            Path::RadioBlob => "lat-radio-blob",
            Path::Sense => "lat-sense",
            Path::Iox2 => "lat-iox2",
            Path::Uds => "lat-uds",
        }
    }
    fn label(self) -> &'static str {
        match self {
            Path::Radio => "runtime radio",
            Path::RadioBytes => "runtime radio, bytes",
            Path::RadioBlob => "runtime radio, blob",
            Path::Sense => "runtime Sense",
            Path::Iox2 => "raw iceoryx2",
            Path::Uds => "UDS + bincode",
        }
    }
}

fn rounds_for(size: usize, quick: bool) -> u64 {
    match (size, quick) {
        (s, false) if s <= 16384 => 5000,
        (s, false) if s <= 65536 => 2000,
        (_, false) => 300,
        (s, true) if s <= 16384 => 600,
        (s, true) if s <= 65536 => 300,
        (_, true) => 40,
    }
}

pub fn run(quick: bool) -> BenchResult<Report> {
    let sense_bytes = std::mem::size_of::<Sense>();
    let mut cells: Vec<(Path, usize)> = Vec::new();
    for &s in &SIZES {
        cells.push((Path::Radio, s));
    }
    for &s in &SIZES {
        cells.push((Path::RadioBytes, s));
    }
    for &s in &SIZES {
        cells.push((Path::RadioBlob, s));
    }
    cells.push((Path::Sense, sense_bytes));
    let mut iox_sizes = SIZES.to_vec();
    iox_sizes.insert(2, sense_bytes);
    for &s in &iox_sizes {
        cells.push((Path::Iox2, s));
    }
    for &s in &SIZES {
        cells.push((Path::Uds, s));
    }
    let mut rows = Vec::new();
    for (path, size) in cells {
        let rounds = rounds_for(size, quick);
        let mut q = [0.0; 4];
        for (j, mode) in [Mode::Poll, Mode::Block].into_iter().enumerate() {
            let mut ns = cell(path, size, mode, rounds)
                .map_err(|e| e.in_cell(path.label(), size, mode.name()))?;
            ns.sort_unstable();
            q[2 * j] = percentile(&ns, 0.5) / 1e3;
            q[2 * j + 1] = percentile(&ns, 0.99) / 1e3;
        }
        rows.push(Row {
            path: path.label().to_string(),
            payload_bytes: size,
            rounds,
            poll_p50_us: q[0],
            poll_p99_us: q[1],
            block_p50_us: q[2],
            block_p99_us: q[3],
        });
    }
    let ratios = table::ratios(&rows, sense_bytes);
    Ok(Report { rows, ratios })
}

/// One cell: the samples in nanoseconds, warm-up dropped.
fn cell(path: Path, size: usize, mode: Mode, rounds: u64) -> BenchResult<Vec<u64>> {
    let prefix = tick::bench_prefix(&format!("{}-{size}-{}", path.kind(), mode.name()));
    let warm = (rounds / 10).max(5);
    let total = rounds + warm;
    let r = (|| -> BenchResult<Vec<u64>> {
        let (barrier, fds) = TickBarrier::create(&prefix, 2)?;
        // Round 0 is "released" by the parent itself; expected = 1 arms the child's ack wait.
        barrier.release(0, 1);
        let extra = [
            "--size".to_string(),
            size.to_string(),
            "--mode".to_string(),
            mode.name().to_string(),
            "--rounds".to_string(),
            total.to_string(),
        ];
        let p = Parent {
            prefix: &prefix,
            barrier: &barrier,
            fds: &fds,
            extra: &extra,
            kind: path.kind(),
            mode,
            size,
            total,
        };
        let ns = match path {
            Path::Radio => radio::parent::<radio::SeqPing>(&p)?,
            Path::RadioBytes => radio::parent::<radio::BytesPing>(&p)?,
            Path::RadioBlob => radio::parent::<radio::BlobPing>(&p)?,
            Path::Sense => sense::parent(&p)?,
            Path::Iox2 => iox2::parent(&p)?,
            Path::Uds => uds::parent(&p)?,
        };
        Ok(ns.into_iter().skip(warm as usize).collect())
    })();
    cleanup::remove_run(&prefix);
    check_no_leftovers(&prefix)?;
    r
}

/// The measuring side of one cell.
struct Parent<'a> {
    prefix: &'a str,
    barrier: &'a TickBarrier,
    /// The barrier's descriptors, for the child.
    fds: &'a swarm::barrier::BarrierFds,
    extra: &'a [String],
    kind: &'a str,
    mode: Mode,
    size: usize,
    total: u64,
}

/// Seconds a bench child has to get ready (or connect).
const READY_S: u64 = 30;

impl Parent<'_> {
    /// Starts the child and waits until it is ready (it marks itself in the barrier).
    fn spawn(&self) -> BenchResult<Child> {
        let mut c = spawn_child(self.kind, (self.prefix, self.fds), 1, self.extra, false)?;
        let t = Instant::now();
        while self.barrier.ready_count() < 1 {
            if let Ok(Some(status)) = c.try_wait() {
                return Err(BenchError::ChildExited {
                    kind: self.kind.to_string(),
                    status,
                });
            }
            if t.elapsed() > Duration::from_secs(READY_S) {
                let _ = c.kill();
                let _ = c.wait();
                return Err(self.not_ready());
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        Ok(c)
    }

    fn not_ready(&self) -> BenchError {
        BenchError::ChildNotReady {
            kind: self.kind.to_string(),
            seconds: READY_S,
        }
    }

    /// Waits for the child's message: `take` it, sleeping on the barrier's release word
    /// between tries when blocking (the child releases a round per message; `done` is the
    /// next round the parent waits for).
    fn wait<T>(
        &self,
        done: &mut u64,
        take: impl FnMut() -> BenchResult<Option<T>>,
    ) -> BenchResult<T> {
        wait::wait_for(self.mode, Peer::Child, take, || {
            if let Wake::Tick(k) = self.barrier.wait_release(*done, NAP) {
                *done = k + 1;
            }
            Ok(())
        })
    }
}

/// The child's wait for the parent's message: `take` it, sleeping on the barrier's ack word
/// between tries when blocking (the parent acknowledges a round per message).
fn wait_parent<T>(
    b: &TickBarrier,
    mode: Mode,
    take: impl FnMut() -> BenchResult<Option<T>>,
) -> BenchResult<T> {
    wait::wait_for(mode, Peer::Parent, take, || {
        b.wait_acks(NAP);
        Ok(())
    })
}

/// The child's end of the barrier.
fn open_barrier() -> BenchResult<TickBarrier> {
    TickBarrier::open_inherited().map_err(BenchError::from)
}

// ---- the child side ----

pub fn child(a: &ChildArgs) -> i32 {
    let mode = Mode::parse(&a.mode);
    let r = match a.kind.as_str() {
        "lat-radio" => radio::child::<radio::SeqPing>(a, mode),
        "lat-radio-bytes" => radio::child::<radio::BytesPing>(a, mode),
        "lat-radio-blob" => radio::child::<radio::BlobPing>(a, mode),
        "lat-sense" => sense::child(a, mode),
        "lat-iox2" => iox2::child(a, mode),
        "lat-uds" => uds::child(a, mode),
        other => Err(BenchError::UnknownChild {
            kind: other.to_string(),
        }),
    };
    match r {
        Ok(()) => 0,
        Err(x) => {
            eprintln!("bench child {}: {x}", a.kind);
            1
        }
    }
}
