//! `orchestrator bench memory`: what a run costs in memory, file descriptors and /dev/shm
//! files, against N.
//!
//! Each size is a real `up` run (processes executor): the roam scenario (configs/roam.toml), except that the
//! robots start spread over the whole arena (in the default 100 x 100 start square every robot
//! is within radio range of every other, which would make the neighbour count N - 1). At tick
//! 50 of the run the agent and world processes (children of this process) are measured from
//! /proc, the run's /dev/shm entries are counted, and the radio links are counted as the
//! subscribers of every robot's radio service.

use super::{check_no_leftovers, count_files};
use crate::processes;
use iceoryx2::prelude::*;
use serde::Serialize;
use std::path::Path;
use swarm::frames::WorldStatus;
use swarm::scenario::Scenario;
use swarm::{cleanup, transport};

#[derive(Debug, Clone, Serialize, Default)]
pub struct Row {
    pub robots: u32,
    pub tick_sampled: u64,
    pub agents_measured: usize,
    /// Radio links (subscriptions) per agent, mean.
    pub links_per_agent: f64,
    pub agent_rss_mib_mean: f64,
    pub agent_rss_mib_max: f64,
    /// Proportional set size: shared pages divided among the processes that map them.
    pub agent_pss_mib_mean: f64,
    /// Pages only this agent maps (heap, stacks, private data).
    pub agent_private_mib_mean: f64,
    pub agent_fds_mean: f64,
    pub agent_fds_max: usize,
    pub world_rss_mib: f64,
    pub world_fds: usize,
    /// Entries directly in /dev/shm with the run's prefix (iceoryx2 segments, tick barrier,
    /// the iceoryx2 root folder).
    pub shm_entries: usize,
    /// Files in the run's iceoryx2 root folder /dev/shm/<prefix>iox2/ (node and service files).
    pub iox2_root_files: usize,
    /// Bytes of the /dev/shm entries (apparent size).
    pub shm_mib: f64,
    /// (shm entries + root files) / (N x links per agent).
    pub files_per_link: f64,
    /// /dev/shm pages actually allocated (tmpfs blocks, not the apparent size).
    pub shm_resident_mib: f64,
    /// The whole run's memory: the anonymous pages (heap, stacks) of the world and of every
    /// agent, plus the run's /dev/shm pages (shared, counted once); shared code left out.
    pub run_mib: f64,
    /// `run_mib / robots`: what each robot costs the machine (issue 14 item 5).
    pub run_mib_per_robot: f64,
    /// World file descriptors per robot: (world fds - WORLD_FDS_BASE) / robots.
    pub world_fds_per_robot: f64,
}

/// The tick at which a run is measured.
const SAMPLE_TICK: u64 = 50;

pub fn run(sizes: &[u32], quick: bool) -> Result<Vec<Row>, String> {
    // Long enough that the run is still going well after the measurement (which takes up to
    // ~0.1 s), short enough for --quick: small swarms tick thousands of times a second.
    let budget = if quick { 20_000 } else { 60_000 };
    sizes
        .iter()
        .map(|&n| one(n, (budget / n.max(1) as u64).max(4 * SAMPLE_TICK)))
        .collect()
}

pub fn print(rows: &[Row]) {
    println!("memory and files of a real run (processes executor, robots spread over the arena), measured at tick {SAMPLE_TICK}");
    println!(
        "{:>6} {:>6} | {:>9} {:>9} {:>9} {:>9} {:>9} | {:>6} {:>6} | {:>9} {:>5} | {:>7} {:>8} {:>8} {:>10}",
        "robots", "links",
        "RSS MiB", "RSS max", "PSS MiB", "priv MiB", "world RSS",
        "fds", "fd max",
        "world fds", "",
        "shm", "iox2 dir", "shm MiB", "files/link"
    );
    for r in rows {
        println!(
            "{:>6} {:>6.1} | {:>9.2} {:>9.2} {:>9.2} {:>9.2} {:>9.1} | {:>6.1} {:>6} | {:>9} {:>5} | {:>7} {:>8} {:>8.1} {:>10.2}",
            r.robots,
            r.links_per_agent,
            r.agent_rss_mib_mean,
            r.agent_rss_mib_max,
            r.agent_pss_mib_mean,
            r.agent_private_mib_mean,
            r.world_rss_mib,
            r.agent_fds_mean,
            r.agent_fds_max,
            r.world_fds,
            "",
            r.shm_entries,
            r.iox2_root_files,
            r.shm_mib,
            r.files_per_link
        );
    }
    println!("links = radio subscriptions per agent (its neighbour count); RSS/PSS/private per agent process; fds = open file descriptors per agent;");
    println!("shm = /dev/shm entries of the run, iox2 dir = files in its iceoryx2 root folder; files/link = (shm + iox2 dir) / (robots x links).");
    println!();
    println!("whole run (world + agents + /dev/shm): anonymous pages of every process plus the run's /dev/shm pages");
    println!(
        "{:>6} | {:>12} {:>10} {:>12} | {:>14}",
        "robots", "shm res MiB", "run MiB", "MiB / robot", "world fds/robot"
    );
    for r in rows {
        println!(
            "{:>6} | {:>12.1} {:>10.1} {:>12.2} | {:>14.2}",
            r.robots, r.shm_resident_mib, r.run_mib, r.run_mib_per_robot, r.world_fds_per_robot
        );
    }
}

fn one(n: u32, ticks: u64) -> Result<Row, String> {
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    sc.run.max_ticks = ticks;
    sc.arena.start_region = [0.0, 0.0, sc.arena.width, sc.arena.height];
    sc.validate(&|_| "bench".into())
        .map_err(|e| e.to_string())?;
    let run_id = crate::runid::new_run_id();
    let prefix = transport::prefix_for(&run_id);
    let dir = std::env::temp_dir().join(format!("swarm-bench-mem-{run_id}"));
    let mut row: Option<Result<Row, String>> = None;
    let out = processes::run(processes::ProcessRun {
        sc: &sc,
        run_id: &run_id,
        run_dir: &dir,
        live: false,
        on_status: &mut |st: &WorldStatus| {
            if row.is_none() && st.tick >= SAMPLE_TICK {
                row = Some(measure(&sc, &prefix, st.tick));
            }
        },
    });
    let _ = std::fs::remove_dir_all(&dir);
    cleanup::remove_run(&prefix);
    check_no_leftovers(&prefix)?;
    let out = out?;
    if out.world_exit != Ok(0) {
        return Err(format!("run failed: world exit {:?}", out.world_exit));
    }
    let row = row.unwrap_or_else(|| Err("the run ended before it was measured".into()))?;
    if row.agents_measured != n as usize || row.shm_entries == 0 {
        return Err(format!(
            "N = {n}: measured {} agents, {} /dev/shm entries: the run was not fully up",
            row.agents_measured, row.shm_entries
        ));
    }
    Ok(row)
}

struct Proc {
    comm: String,
    rss_kib: u64,
    pss_kib: u64,
    private_kib: u64,
    /// Anonymous pages (heap, stacks): private memory that is not a /dev/shm mapping.
    anon_kib: u64,
    fds: usize,
}

/// The children of this process, from /proc.
fn children() -> Vec<Proc> {
    let me = std::process::id();
    let mut v = Vec::new();
    let Ok(rd) = std::fs::read_dir("/proc") else {
        return v;
    };
    for e in rd.filter_map(|e| e.ok()) {
        let name = e.file_name().to_string_lossy().into_owned();
        if !name.bytes().all(|b| b.is_ascii_digit()) {
            continue;
        }
        let base = e.path();
        let Ok(stat) = std::fs::read_to_string(base.join("stat")) else {
            continue;
        };
        // pid (comm) state ppid ...
        let (Some(l), Some(r)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let comm = stat[l + 1..r].to_string();
        let ppid: u32 = stat[r + 1..]
            .split_whitespace()
            .nth(1)
            .and_then(|x| x.parse().ok())
            .unwrap_or(0);
        if ppid != me {
            continue;
        }
        let field = |file: &str, key: &str| -> u64 {
            std::fs::read_to_string(base.join(file))
                .ok()
                .and_then(|s| {
                    s.lines()
                        .find(|l| l.starts_with(key))
                        .and_then(|l| l.split_whitespace().nth(1))
                        .and_then(|x| x.parse().ok())
                })
                .unwrap_or(0)
        };
        v.push(Proc {
            comm,
            rss_kib: field("status", "VmRSS:"),
            pss_kib: field("smaps_rollup", "Pss:"),
            private_kib: field("smaps_rollup", "Private_Clean:")
                + field("smaps_rollup", "Private_Dirty:"),
            anon_kib: field("smaps_rollup", "Anonymous:"),
            fds: std::fs::read_dir(base.join("fd"))
                .map(|d| d.count())
                .unwrap_or(0),
        });
    }
    v
}

fn mib(kib: f64) -> f64 {
    kib / 1024.0
}

fn measure(sc: &Scenario, prefix: &str, tick: u64) -> Result<Row, String> {
    let n = sc.run.robots;
    // Files and links first (the run is certainly still up), then the processes.
    let shm = cleanup::shm_files(prefix);
    let metas: Vec<std::fs::Metadata> = shm
        .iter()
        .filter_map(|f| std::fs::metadata(Path::new("/dev/shm").join(f)).ok())
        .filter(|m| m.is_file())
        .collect();
    let shm_bytes: u64 = metas.iter().map(|m| m.len()).sum();
    let shm_resident: u64 = {
        use std::os::unix::fs::MetadataExt;
        metas.iter().map(|m| m.blocks() * 512).sum()
    };
    let root_files = count_files(&transport::root_for(prefix));
    let procs = children();
    let agents: Vec<&Proc> = procs.iter().filter(|p| p.comm == "agent").collect();
    let world = procs.iter().find(|p| p.comm == "world");
    if agents.is_empty() {
        return Err("no agent process found".into());
    }
    let k = agents.len() as f64;
    let mean = |f: &dyn Fn(&Proc) -> u64| agents.iter().map(|p| f(p) as f64).sum::<f64>() / k;
    // Subscriptions per agent: the iceoryx2 air service's subscribers (one per agent with
    // radio.air = "iceoryx2"; none with the world's air ring, the default, which has no
    // service; the link design had one per radio link).
    let config = transport::run_config(prefix).map_err(|e| e.to_string())?;
    let node = transport::node(&config, "bench-memory").map_err(|e| e.to_string())?;
    let subs = transport::air_service(&node, sc, 0, false)
        .map(|svc| svc.dynamic_config().number_of_subscribers())
        .unwrap_or(0);
    drop(node);
    let links = subs as f64 / n as f64;
    Ok(Row {
        robots: n,
        tick_sampled: tick,
        agents_measured: agents.len(),
        links_per_agent: links,
        agent_rss_mib_mean: mib(mean(&|p| p.rss_kib)),
        agent_rss_mib_max: mib(agents.iter().map(|p| p.rss_kib).max().unwrap_or(0) as f64),
        agent_pss_mib_mean: mib(mean(&|p| p.pss_kib)),
        agent_private_mib_mean: mib(mean(&|p| p.private_kib)),
        agent_fds_mean: mean(&|p| p.fds as u64),
        agent_fds_max: agents.iter().map(|p| p.fds).max().unwrap_or(0),
        world_rss_mib: world.map(|w| mib(w.rss_kib as f64)).unwrap_or(0.0),
        world_fds: world.map(|w| w.fds).unwrap_or(0),
        shm_entries: shm.len(),
        iox2_root_files: root_files,
        shm_mib: shm_bytes as f64 / (1024.0 * 1024.0),
        files_per_link: (shm.len() + root_files) as f64 / (n as f64 * links).max(1.0),
        shm_resident_mib: shm_resident as f64 / (1024.0 * 1024.0),
        run_mib: run_mib(&procs, shm_resident),
        run_mib_per_robot: run_mib(&procs, shm_resident) / n as f64,
        world_fds_per_robot: world.map_or(0.0, |w| {
            w.fds.saturating_sub(swarm::limits::WORLD_FDS_BASE as usize) as f64 / n as f64
        }),
    })
}

/// Anonymous pages (heap, stacks) of every process of the run plus its /dev/shm pages (each
/// counted once however many processes map it), in MiB.
fn run_mib(procs: &[Proc], shm_resident: u64) -> f64 {
    let anon: u64 = procs.iter().map(|p| p.anon_kib).sum();
    mib(anon as f64) + shm_resident as f64 / (1024.0 * 1024.0)
}
