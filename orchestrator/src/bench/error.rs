//! What can make a benchmark fail, with what it was measuring.

use std::path::PathBuf;
use std::process::ExitStatus;
use swarm::barrier::BarrierError;
use swarm::scenario::ConfigError;
use swarm::transport::TransportError;

/// The other side of a benchmark's ping-pong.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Peer {
    /// The bench child process (seen from the parent).
    Child,
    /// The bench parent (seen from a child).
    Parent,
}

impl std::fmt::Display for Peer {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Peer::Child => "child",
            Peer::Parent => "parent",
        })
    }
}

/// A failed benchmark (or bench child).
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// An iceoryx2 call failed: the service and iceoryx2's error are in it.
    #[error(transparent)]
    Transport(#[from] TransportError),
    /// One latency cell (path, payload, variant) failed.
    #[error("{path} {size} B {mode}: {source}")]
    Cell {
        path: &'static str,
        size: usize,
        mode: &'static str,
        source: Box<BenchError>,
    },
    #[error(transparent)]
    Barrier(#[from] BarrierError),
    #[error("spawn bench child {kind}: {source}")]
    Spawn {
        kind: String,
        source: std::io::Error,
    },
    #[error("bench child {kind} exited early: {status}")]
    ChildExited { kind: String, status: ExitStatus },
    #[error("bench child {kind} did not get ready within {seconds} s")]
    ChildNotReady { kind: String, seconds: u64 },
    #[error("unknown bench child kind {kind:?}")]
    UnknownChild { kind: String },
    /// A throughput child's last line is not its count of deliveries.
    #[error("bench child said {output:?}, not its deliveries")]
    ChildOutput { output: String },
    #[error("timed out waiting for the {0}")]
    Timeout(Peer),
    #[error("tick {tick}: a bench child did not acknowledge within {seconds} s")]
    NoAck { tick: u64, seconds: u64 },
    /// The runtime's radio lost messages in a latency cell (there is no loss there).
    #[error("{failed} failed sends, {oversize} oversize")]
    SendFailures { failed: u64, oversize: u64 },
    #[error("{delivered} of {expected} echoes delivered")]
    Lost { delivered: u64, expected: u64 },
    #[error("round {round}: {sent} messages echoed, not 1")]
    Echo { round: u64, sent: u32 },
    #[error("UDS {what}: {source}")]
    Uds {
        what: &'static str,
        source: std::io::Error,
    },
    #[error("UDS: the peer closed the socket")]
    UdsClosed,
    #[error("bincode encode: {0}")]
    Encode(#[from] bincode::error::EncodeError),
    #[error("bincode decode: {0}")]
    Decode(#[from] bincode::error::DecodeError),
    #[error("--robots {robots} is out of range: allowed {min}..={max}")]
    Robots { robots: u32, min: u32, max: u32 },
    #[error(transparent)]
    Scenario(#[from] ConfigError),
    /// The behaviour of the scenario did not validate (agent::behaviours, whose errors are text).
    #[error("behaviour: {0}")]
    Behaviour(String),
    /// `processes::run` could not run the scenario (its errors are text).
    #[error("runtime run: {0}")]
    Run(String),
    /// The world process of a runtime run did not exit with 0 (`Err`: killed by that signal).
    #[error("runtime run failed: world exit {0:?}")]
    WorldExit(Result<i32, i32>),
    #[error("in-process run: {0}")]
    InProcess(std::io::Error),
    #[error("{}: {source}", path.display())]
    File {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {source}", path.display())]
    Json {
        path: PathBuf,
        source: serde_json::Error,
    },
    /// What a benchmark left in /dev/shm (it must leave nothing).
    #[error("left in /dev/shm: {files:?}")]
    Leftovers { files: Vec<String> },
    /// The rows across hosts failed (hosts/error.rs).
    #[error("tick across hosts: {0}")]
    Hosts(#[from] super::hosts::HostsBenchError),
    /// Ctrl-C (or SIGTERM) stopped the benchmark; what it had started was stopped and removed.
    #[error("interrupted")]
    Interrupted,
    /// `bench memory` failed (memory.rs's errors are text).
    #[error("{0}")]
    Memory(String),
}

impl BenchError {
    /// This error, as it happened in one latency cell.
    pub fn in_cell(self, path: &'static str, size: usize, mode: &'static str) -> BenchError {
        BenchError::Cell {
            path,
            size,
            mode,
            source: Box::new(self),
        }
    }
}

/// For the benchmarks whose own errors are still text (memory.rs): `?` on a typed error.
impl From<BenchError> for String {
    fn from(e: BenchError) -> String {
        e.to_string()
    }
}

pub type BenchResult<T> = std::result::Result<T, BenchError>;
