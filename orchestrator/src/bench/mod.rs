//! `orchestrator bench latency|throughput|tick|memory|all`: every table is measured in the same
//! run on the same machine, with the ratios between its rows printed beside it.
//!
//! - `tick` (tick.rs): the runtime's lock-step tick next to a raw iceoryx2 round and the futex
//!   floor; and (hosts/) the tick across hosts, the swarm split over network namespaces
//!   (needs root; skipped with a line saying why otherwise);
//! - `latency` (latency/, one file per path): one-hop p50 / p99 between two processes for the
//!   runtime's own paths (a radio message, a Sense frame), raw iceoryx2 publish-subscribe and a
//!   copying baseline (Unix domain socket + bincode), busy-poll and blocking-wake;
//! - `throughput` (throughput.rs): radio messages and bytes delivered per second with N robots
//!   all broadcasting every tick;
//! - `memory` (memory.rs): RSS and open files per agent and /dev/shm files per run, against N;
//! - `search` (search.rs): robot-steps per second of the in-process executor on the search
//!   scenario.
//!
//! Failures are `BenchError`s (error.rs), printed only here at the edge (`finish`).
//!
//! Cross-process numbers come from real child processes (`orchestrator __bench-child KIND`),
//! each in its own iceoryx2 prefix that is removed afterwards.

mod error;
mod hosts;
mod latency;
mod memory;
mod own;
mod realtime;
mod restart;
mod search;
mod throughput;
mod tick;

pub use error::{BenchError, BenchResult};

use clap::{Args, Subcommand};
use serde::Serialize;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use swarm::barrier::BarrierFds;

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: BenchWhat,
}

#[derive(Subcommand, Debug)]
enum BenchWhat {
    /// Lock-step tick rate: runtime vs raw iceoryx2 round vs futex floor.
    Tick {
        /// Swarm sizes, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "10,50,100,200,500")]
        robots: Vec<u32>,
        /// Ticks (rounds) measured per size up to 100 robots; above, fewer in proportion
        /// (ticks x 100 / N, at least 100).
        #[arg(long, default_value_t = 2000)]
        ticks: u64,
        /// Also write the table as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Sizes 10,50 and 300 ticks (overrides --robots and --ticks), 2 s of clock per
        /// real-time cell.
        #[arg(long)]
        quick: bool,
        /// The real-time column's clock rates, ticks per second: the deadline-miss rate of
        /// each size at each rate (`runtime.realtime_hz`).
        #[arg(long, value_delimiter = ',', default_value = "10,50,100")]
        realtime_hz: Vec<f64>,
        /// Seconds of clock per real-time cell (ticks = rate x seconds, at least 40).
        #[arg(long, default_value_t = 4.0)]
        realtime_seconds: f64,
        /// Only the real-time column (no lock-step table).
        #[arg(long, conflicts_with = "no_realtime")]
        realtime_only: bool,
        /// Only the lock-step table (no real-time column).
        #[arg(long)]
        no_realtime: bool,
        /// Network namespace counts of the rows across hosts (the world's and NS-1 hosts'),
        /// at the sizes of --robots up to 200. Needs root and `ip` (iproute2); skipped with a
        /// line saying why otherwise.
        #[arg(long, value_delimiter = ',', default_value = "2,4",
              value_parser = clap::value_parser!(u32).range(2..=hosts::MAX_NAMESPACES as i64))]
        hosts: Vec<u32>,
        /// `tc netem` delays of the rows across hosts, ms each way on every link (0: none).
        #[arg(long, value_delimiter = ',', default_value = "0,0.5,2",
              value_parser = hosts::parse_delay)]
        netem_ms: Vec<f64>,
        /// Runs per figure of the rows across hosts (the median of their tick p50s; 1 with
        /// --quick).
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        hosts_runs: u32,
        /// Only the rows across hosts.
        #[arg(long, conflicts_with_all = ["no_hosts", "realtime_only"])]
        hosts_only: bool,
        /// No rows across hosts.
        #[arg(long)]
        no_hosts: bool,
    },
    /// One-hop latency p50 / p99: runtime radio and Sense vs raw iceoryx2 vs UDS + bincode.
    Latency {
        /// Also write the table as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Fewer rounds per cell.
        #[arg(long)]
        quick: bool,
    },
    /// Radio messages and bytes delivered per second, N robots all broadcasting every tick.
    Throughput {
        /// Robots.
        #[arg(long, default_value_t = 50)]
        robots: u32,
        /// Also write the table as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Fewer ticks.
        #[arg(long)]
        quick: bool,
    },
    /// RSS and open files per agent, /dev/shm files per run, against N.
    Memory {
        /// Swarm sizes, comma separated (default 10,25,50,100; 10,50 with --quick).
        #[arg(long, value_delimiter = ',')]
        robots: Option<Vec<u32>>,
        /// Also write the table as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Fewer sizes and ticks.
        #[arg(long)]
        quick: bool,
    },
    /// Restart latency: SIGKILL of an agent -> its replacement ticks again.
    Restart(restart::Args),
    /// Robot-steps per second of the in-process executor on the search scenario.
    Search {
        /// Robots.
        #[arg(long, default_value_t = 100)]
        robots: u32,
        /// Search mode (BT, BE, BA, ST, SE, SA).
        #[arg(long, default_value = "BT")]
        mode: String,
        /// Seeds 1..=S, one run each.
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// Also write the table as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// One seed.
        #[arg(long)]
        quick: bool,
        /// Only this many worker threads (default: 1, then all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// latency, throughput, tick and memory, one after the other.
    All {
        /// Also write every table as one JSON file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// The short version of each (about a minute in all on a 2-core VM).
        #[arg(long)]
        quick: bool,
    },
}

/// `orchestrator __bench-child KIND ...`: one process of a cross-process benchmark.
#[derive(Args, Debug)]
pub struct ChildArgs {
    /// iox2, futex (bench tick); lat-radio, lat-radio-bytes, lat-radio-blob, lat-sense,
    /// lat-iox2, lat-uds (bench latency);
    /// tput (bench throughput)
    kind: String,
    #[arg(long)]
    prefix: String,
    #[arg(long)]
    index: u32,
    /// Payload bytes (latency, throughput).
    #[arg(long, default_value_t = 64)]
    size: usize,
    /// poll or block (latency).
    #[arg(long, default_value = "block")]
    mode: String,
    /// Rounds or ticks, warm-up included (latency, throughput).
    #[arg(long, default_value_t = 0)]
    rounds: u64,
    /// Robots of the run (throughput).
    #[arg(long, default_value_t = 2)]
    robots: u32,
}

/// The machine the numbers were measured on.
#[derive(Debug, Clone, Serialize)]
pub struct Machine {
    pub nproc: usize,
    pub cpu: String,
    pub kernel: String,
}

pub fn machine() -> Machine {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|v| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease")
        .map(|s| s.trim().to_string())
        .unwrap_or_default();
    Machine {
        nproc: std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
        cpu,
        kernel,
    }
}

fn print_machine() {
    let m = machine();
    println!("machine: {} CPU(s), {}, Linux {}", m.nproc, m.cpu, m.kernel);
}

#[derive(Serialize, Default)]
struct AllJson {
    machine: Option<Machine>,
    latency: Option<latency::Report>,
    throughput: Option<Vec<throughput::Row>>,
    tick: Option<Vec<tick::Row>>,
    memory: Option<Vec<memory::Row>>,
}

fn write_json<T: Serialize>(path: &Option<PathBuf>, v: &T) -> BenchResult<()> {
    if let Some(p) = path {
        std::fs::write(p, serde_json::to_string_pretty(v).expect("json")).map_err(|source| {
            BenchError::File {
                path: p.clone(),
                source,
            }
        })?;
    }
    Ok(())
}

/// `bench memory`, whose errors are still text, as a typed result.
fn memory_run(sizes: &[u32], quick: bool) -> BenchResult<Vec<memory::Row>> {
    memory::run(sizes, quick).map_err(BenchError::Memory)
}

/// The binary's edge: the error as text, and the exit code (128 + the signal's number after
/// a Ctrl-C or SIGTERM).
fn finish(r: BenchResult<()>, what: &str) -> i32 {
    match r {
        Ok(()) => 0,
        Err(BenchError::Interrupted) => {
            eprintln!("bench {what}: interrupted");
            crate::signals::exit_code()
        }
        Err(e) => {
            eprintln!("error: bench {what}: {e}");
            1
        }
    }
}

pub fn bench(a: BenchArgs) -> i32 {
    let mut out = AllJson {
        machine: Some(machine()),
        ..Default::default()
    };
    match a.what {
        BenchWhat::Restart(r) => restart::bench(r),
        BenchWhat::Tick {
            robots,
            ticks,
            json,
            quick,
            realtime_hz,
            realtime_seconds,
            realtime_only,
            no_realtime,
            hosts,
            netem_ms,
            hosts_runs,
            hosts_only,
            no_hosts,
        } => {
            let (robots, ticks) = if quick {
                (vec![10, 50], 300)
            } else {
                (robots, ticks)
            };
            let rt = realtime::RealtimeBenchParams {
                rates: realtime_hz,
                seconds: if quick { 2.0 } else { realtime_seconds },
            };
            let across_params = hosts::Params {
                namespaces: if no_hosts || realtime_only {
                    Vec::new()
                } else {
                    hosts
                },
                netem_ms,
                runs: if quick { 1 } else { hosts_runs },
            };
            print_machine();
            finish(
                (|| -> BenchResult<()> {
                    let (rows, own_rows) = if realtime_only || hosts_only {
                        (Vec::new(), Vec::new())
                    } else {
                        let rows = tick::bench_tick(&robots, ticks)?;
                        tick::print_table(&rows);
                        println!();
                        let own_rows = own::run(&robots, ticks)?;
                        own::print(&own_rows);
                        (rows, own_rows)
                    };
                    let cells = if no_realtime || hosts_only || rt.rates.is_empty() {
                        Vec::new()
                    } else {
                        if !realtime_only {
                            println!();
                        }
                        let cells = realtime::run(&robots, &rt)?;
                        realtime::print(&cells, &rt);
                        cells
                    };
                    // Last: from here on Ctrl-C is caught (to remove the namespaces).
                    let (across, failed) = if across_params.namespaces.is_empty() {
                        (None, None)
                    } else {
                        if !hosts_only {
                            println!();
                        }
                        match hosts::run(&robots, ticks, &across_params) {
                            Ok(r) => (Some(r), None),
                            Err(e) => (None, Some(e)),
                        }
                    };
                    // The other tables are written even when the rows across hosts failed.
                    write_json(
                        &json,
                        &serde_json::json!({
                            "lockstep": rows,
                            "own_programs": own_rows,
                            "realtime": cells,
                            "hosts": across
                        }),
                    )?;
                    failed.map_or(Ok(()), Err)
                })(),
                "tick",
            )
        }
        BenchWhat::Latency { json, quick } => {
            print_machine();
            finish(
                latency::run(quick).and_then(|r| {
                    latency::print(&r);
                    out.latency = Some(r);
                    write_json(&json, &out)
                }),
                "latency",
            )
        }
        BenchWhat::Throughput {
            robots,
            json,
            quick,
        } => {
            print_machine();
            finish(
                throughput::run(robots, quick).and_then(|r| {
                    throughput::print(&r);
                    out.throughput = Some(r);
                    write_json(&json, &out)
                }),
                "throughput",
            )
        }
        BenchWhat::Memory {
            robots,
            json,
            quick,
        } => {
            print_machine();
            let sizes = robots.unwrap_or(if quick {
                vec![10, 50]
            } else {
                vec![10, 25, 50, 100]
            });
            finish(
                memory_run(&sizes, quick).and_then(|r| {
                    memory::print(&r);
                    out.memory = Some(r);
                    write_json(&json, &out)
                }),
                "memory",
            )
        }
        BenchWhat::Search {
            robots,
            mode,
            seeds,
            json,
            quick,
            threads,
        } => {
            print_machine();
            let seeds = if quick { 1 } else { seeds };
            let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
            let threads = match threads {
                Some(t) => vec![t.max(1)],
                None if cores > 1 => vec![1, cores],
                None => vec![1],
            };
            finish(
                threads
                    .iter()
                    .try_fold(Vec::new(), |mut rows, &t| {
                        rows.extend(search::run(robots, &mode, seeds, t)?);
                        Ok(rows)
                    })
                    .and_then(|rows| {
                        search::print(&rows);
                        // The sweep row: as `orchestrator experiment` runs, one run per core.
                        let sweep = if cores > 1 {
                            // Whole rounds of `cores` runs (seeds 1..), so no core idles at the end.
                            let runs = seeds.div_ceil(cores as u64) * cores as u64;
                            let s = search::sweep(robots, &mode, runs, cores)?;
                            search::print_sweep(&s);
                            Some(s)
                        } else {
                            None
                        };
                        write_json(&json, &serde_json::json!({ "runs": rows, "sweep": sweep }))
                    }),
                "search",
            )
        }
        BenchWhat::All { json, quick } => {
            print_machine();
            let t = std::time::Instant::now();
            let r = (|| -> BenchResult<()> {
                let l = latency::run(quick)?;
                latency::print(&l);
                out.latency = Some(l);
                println!();
                let th = throughput::run(50, quick)?;
                throughput::print(&th);
                out.throughput = Some(th);
                println!();
                let (sizes, ticks) = if quick {
                    (vec![10, 50], 300)
                } else {
                    (vec![10, 50, 100, 200, 500], 2000)
                };
                let tk = tick::bench_tick(&sizes, ticks)?;
                tick::print_table(&tk);
                out.tick = Some(tk);
                println!();
                let msizes = if quick {
                    vec![10, 50]
                } else {
                    vec![10, 25, 50, 100]
                };
                let m = memory_run(&msizes, quick)?;
                memory::print(&m);
                out.memory = Some(m);
                write_json(&json, &out)
            })();
            println!(
                "\nbench all{}: {:.1} s",
                if quick { " --quick" } else { "" },
                t.elapsed().as_secs_f64()
            );
            finish(r, "all")
        }
    }
}

/// A benchmark child process.
pub fn child(a: ChildArgs) -> i32 {
    // SAFETY: prctl with constant arguments: die with the bench parent.
    unsafe {
        libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
    }
    match a.kind.as_str() {
        "iox2" | "futex" => tick::child(&a),
        k if k.starts_with("lat-") => latency::child(&a),
        "tput" => throughput::child(&a),
        other => {
            eprintln!(
                "unknown bench child kind {other:?}: allowed iox2, futex, lat-radio, \
                 lat-radio-bytes, lat-radio-blob, lat-sense, lat-iox2, lat-uds, tput"
            );
            2
        }
    }
}

/// Starts `orchestrator __bench-child KIND --prefix P --index I ARGS...` (its stdout piped
/// when `piped`).
fn spawn_child(
    kind: &str,
    (prefix, barrier): (&str, &BarrierFds),
    index: u32,
    extra: &[String],
    piped: bool,
) -> BenchResult<Child> {
    let spawn_error = |source| BenchError::Spawn {
        kind: kind.to_string(),
        source,
    };
    let exe = std::env::current_exe().map_err(spawn_error)?;
    let mut cmd = Command::new(exe);
    // The child opens the barrier from the descriptors it inherits (SWARM_BARRIER_FDS).
    barrier.pass_to(&mut cmd);
    cmd.args([
        "__bench-child",
        kind,
        "--prefix",
        prefix,
        "--index",
        &index.to_string(),
    ])
    .args(extra)
    .stdin(Stdio::null())
    .stdout(if piped {
        Stdio::piped()
    } else {
        Stdio::inherit()
    })
    .process_group(0)
    .spawn()
    .map_err(spawn_error)
}

/// CLOCK_MONOTONIC in nanoseconds: one clock for every process of the machine, so a time
/// stamped by one process can be compared with one taken by another.
fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime with a valid timespec pointer.
    unsafe {
        libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts);
    }
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

/// Files (not folders) below `dir`, recursively.
fn count_files(dir: &Path) -> usize {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return 0;
    };
    rd.filter_map(|e| e.ok())
        .map(|e| {
            let p = e.path();
            if p.is_dir() {
                count_files(&p)
            } else {
                1
            }
        })
        .sum()
}

/// No `sw*` entry may stay in /dev/shm after a benchmark: says which did.
fn check_no_leftovers(prefix: &str) -> BenchResult<()> {
    let files = swarm::cleanup::shm_files(prefix);
    if files.is_empty() {
        Ok(())
    } else {
        Err(BenchError::Leftovers { files })
    }
}

/// A byte string that serde encodes in one piece (what `serde_bytes` does), where a plain
/// `Vec<u8>` is encoded element by element.
#[derive(Clone)]
pub(super) struct ByteBuf(pub(super) Vec<u8>);

impl serde::Serialize for ByteBuf {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(&self.0)
    }
}

impl<'de> serde::Deserialize<'de> for ByteBuf {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ByteBuf;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("bytes")
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<ByteBuf, E> {
                Ok(ByteBuf(v.to_vec()))
            }
            fn visit_byte_buf<E: serde::de::Error>(self, v: Vec<u8>) -> Result<ByteBuf, E> {
                Ok(ByteBuf(v))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut a: A,
            ) -> Result<ByteBuf, A::Error> {
                let mut v = Vec::new();
                while let Some(b) = a.next_element()? {
                    v.push(b);
                }
                Ok(ByteBuf(v))
            }
        }
        d.deserialize_byte_buf(V)
    }
}
