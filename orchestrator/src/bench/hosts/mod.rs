//! `bench tick`'s rows across hosts (issue 41): the roam scenario split evenly over NS network
//! namespaces on this machine (the world's and NS-1 hosts', each host joined to the world's
//! by a veth pair: net.rs), against the same swarm with every robot on the world's host, with
//! no added delay and with `tc netem` delays on every link; beside each, the link's round trip
//! (rtt.rs) and the target: the tick across hosts within one round trip plus
//! TARGET_OVERHEAD over the tick on one host. Each figure is the median of `runs` runs' tick
//! p50 (runs.rs). Without root or `ip` the rows are skipped with one line saying why; where
//! netem is missing (a kernel without sch_netem) its rows say so with tc's words.
//!
//! Every namespace made is removed at the end, also on error and on Ctrl-C (the bench's
//! stop signals are caught from here on, `signals`: the runs are stopped, then the guards
//! drop); every run's /dev/shm files are removed after it.

mod error;
mod net;
mod rtt;
mod runs;

pub use error::HostsBenchError;

use super::tick::ticks_for;
use super::{BenchError, BenchResult};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;

/// The rows stop at this swarm size (of those `bench tick` was given): the sizes are
/// 50 and 200, and 500 would take many minutes here.
pub const HOSTS_MAX_ROBOTS: u32 = 200;
/// The most namespaces a row may have (a host's link number is a byte of its addresses).
pub const MAX_NAMESPACES: u32 = 16;
/// The allowance over the tick on one host (20 %), before one round trip.
const TARGET_OVERHEAD: f64 = 0.2;

/// The longest netem delay a row may add (ms, each way). [chosen] A second: beyond any link
/// a lock-step swarm would tick over.
const MAX_NETEM_MS: f64 = 1000.0;

/// A `--netem-ms` value: ms, 0..=MAX_NETEM_MS.
pub fn parse_delay(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(ms) if (0.0..=MAX_NETEM_MS).contains(&ms) => Ok(ms),
        _ => Err(format!(
            "{s:?} is not a delay in ms within 0..={MAX_NETEM_MS}"
        )),
    }
}

/// What the rows measure.
pub struct Params {
    /// Namespace counts (the world's included), each at least 2.
    pub namespaces: Vec<u32>,
    /// `tc netem` delays on every link, each way (ms; 0: none).
    pub netem_ms: Vec<f64>,
    /// Runs per figure (the median of their tick p50s).
    pub runs: u32,
}

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub robots: u32,
    pub namespaces: u32,
    /// Delay added by netem on every link, each way (ms).
    pub netem_ms: f64,
    pub ticks: u64,
    pub runs: u32,
    /// The same swarm with every robot on the world's host: median tick p50 (ms).
    pub one_host_ms: f64,
    /// The slowest link's median TCP round trip (ms); None when netem was unavailable.
    pub rtt_ms: Option<f64>,
    pub across_ms: Option<f64>,
    /// one_host_ms x (1 + TARGET_OVERHEAD) + rtt_ms.
    pub target_ms: Option<f64>,
    pub met: Option<bool>,
    /// Whether every run across hosts recorded the one-host run's bytes (recording.bin).
    pub same_recording: Option<bool>,
    /// tc's error when the delay could not be set (no row measured then).
    pub netem_unavailable: Option<String>,
    /// The runs' ids, one host's then across hosts' (a proxy's files in /dev/shm are under
    /// `prefix_for("<run id>@h<H>")`).
    pub run_ids: Vec<String>,
}

/// The rows, or why there are none.
#[derive(Debug, Clone, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Report {
    Skipped(String),
    Rows(Vec<Row>),
}

/// The bench's temporary folder, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn interrupted() -> BenchResult<()> {
    if crate::signals::interrupted() {
        Err(BenchError::Interrupted)
    } else {
        Ok(())
    }
}

/// Measures and prints the rows (each as soon as it is measured) at the sizes of `sizes` up
/// to HOSTS_MAX_ROBOTS.
pub fn run(sizes: &[u32], ticks: u64, p: &Params) -> BenchResult<Report> {
    println!("tick across hosts (roam; N robots split evenly over NS network namespaces joined by veth pairs, against all N on one host)");
    if let Some(why) = net::unavailable() {
        println!("tick across hosts: skipped: {why}");
        return Ok(Report::Skipped(why));
    }
    crate::signals::install();
    net::remove_stale();
    let scratch = Scratch(std::env::temp_dir().join(format!(
        "swarm-bench-hosts-{}-{}",
        std::process::id(),
        crate::runid::new_run_id()
    )));
    std::fs::create_dir_all(&scratch.0).map_err(|source| BenchError::File {
        path: scratch.0.clone(),
        source,
    })?;
    print_header();
    let mut rows = Vec::new();
    for &n in sizes.iter().filter(|&&n| n <= HOSTS_MAX_ROBOTS) {
        for &ns in &p.namespaces {
            if n < ns {
                println!("{n:>6} {ns:>3}  skipped: fewer robots than namespaces");
                continue;
            }
            // A Ctrl-C also reaches the `ip` or `tc` of the moment, whose failure is then
            // the interruption's, not an error of its own.
            let measured = case(n, ns, ticks_for(n, ticks), p, &scratch.0).map_err(|e| {
                if crate::signals::interrupted() {
                    BenchError::Interrupted
                } else {
                    e
                }
            })?;
            rows.extend(measured);
        }
    }
    println!("ns = namespaces (the world's and ns-1 hosts'); netem = delay added on every link, each way; rtt = the slowest link's median TCP round trip (64 B); one host, across = median over runs of each run's tick p50; target = one host x {:.1} + rtt; recording = every run across hosts recorded the one-host run's bytes.", 1.0 + TARGET_OVERHEAD);
    Ok(Report::Rows(rows))
}

/// The rows of `n` robots over `ns` namespaces, one per netem delay.
fn case(
    n: u32,
    ns: u32,
    ticks: u64,
    p: &Params,
    scratch: &std::path::Path,
) -> BenchResult<Vec<Row>> {
    let mut net = net::Net::new(ns as usize - 1)?;
    let dir = |what: &str, k: u32| scratch.join(format!("{what}-{n}-{ns}-{k}"));
    let mut one = Vec::new();
    for k in 0..p.runs {
        interrupted()?;
        one.push(runs::run(&net, n, ticks, false, &dir("one", k))?);
    }
    let one_host_ms = median(one.iter().map(|d| d.p50_ms).collect());
    let reference = std::fs::read(one[0].dir.join("recording.bin")).ok();
    let mut rows = Vec::new();
    for (i, &d) in p.netem_ms.iter().enumerate() {
        interrupted()?;
        let mut row = Row {
            robots: n,
            namespaces: ns,
            netem_ms: d,
            ticks,
            runs: p.runs,
            one_host_ms,
            rtt_ms: None,
            across_ms: None,
            target_ms: None,
            met: None,
            same_recording: None,
            netem_unavailable: None,
            run_ids: one.iter().map(|d| d.run_id.clone()).collect(),
        };
        if let Err(why) = net.set_delay(d) {
            row.netem_unavailable = Some(why);
            print_row(&row);
            rows.push(row);
            continue;
        }
        let world = net::Netns::open(net.world())?;
        let mut rtt: f64 = 0.0;
        for h in 1..=net.hosts() {
            let host = net::Netns::open(net.host(h))?;
            rtt = rtt.max(rtt::measure(&world, &host, net::Net::host_addr(h))?);
        }
        let mut across = Vec::new();
        let mut same = true;
        for k in 0..p.runs {
            interrupted()?;
            let done = runs::run(&net, n, ticks, true, &dir(&format!("across{i}"), k))?;
            let bytes = std::fs::read(done.dir.join("recording.bin")).ok();
            same &= bytes.is_some() && bytes == reference;
            across.push(done.p50_ms);
            row.run_ids.push(done.run_id);
        }
        let across_ms = median(across);
        let target = one_host_ms * (1.0 + TARGET_OVERHEAD) + rtt;
        row.rtt_ms = Some(rtt);
        row.across_ms = Some(across_ms);
        row.target_ms = Some(target);
        row.met = Some(across_ms <= target);
        row.same_recording = Some(same);
        print_row(&row);
        rows.push(row);
    }
    net.set_delay(0.0).ok();
    Ok(rows)
}

fn print_header() {
    println!(
        "{:>6} {:>3} {:>8} {:>6} {:>4} | {:>8} | {:>11} | {:>9} | {:>9} | {:>3} | recording",
        "robots",
        "ns",
        "netem ms",
        "ticks",
        "runs",
        "rtt ms",
        "one host ms",
        "across ms",
        "target ms",
        "met"
    );
}

fn print_row(r: &Row) {
    let head = format!(
        "{:>6} {:>3} {:>8} {:>6} {:>4} |",
        r.robots, r.namespaces, r.netem_ms, r.ticks, r.runs
    );
    match (&r.netem_unavailable, r.rtt_ms, r.across_ms, r.target_ms) {
        (Some(why), ..) => println!(
            "{head} netem unavailable: {why} (one host {:.3} ms)",
            r.one_host_ms
        ),
        (None, Some(rtt), Some(across), Some(target)) => println!(
            "{head} {rtt:>8.3} | {:>11.3} | {across:>9.3} | {target:>9.3} | {:>3} | {}",
            r.one_host_ms,
            if r.met == Some(true) { "yes" } else { "no" },
            if r.same_recording == Some(true) {
                "same"
            } else {
                "DIFFERS"
            }
        ),
        _ => println!("{head} not measured"),
    }
    // Rows come minutes apart: show each at once, also when stdout is a pipe.
    let _ = std::io::stdout().flush();
}
