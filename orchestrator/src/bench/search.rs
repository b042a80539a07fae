//! `orchestrator bench search`: robot-steps per second of the in-process executor running the
//! search scenario (issue 3's speed figure), one run at a time, over several seeds, on one
//! thread and on all cores (the in-process executor splits each tick's agents over threads),
//! then as a sweep runs them: one run per core at once.
//!
//! A robot-step is one robot's tick: the world's sensing for it, its radio inbox, its
//! behaviour's step and its move. The loop time excludes start-up (world and behaviour
//! construction, the per-robot offline calibration).

use super::{BenchError, BenchResult};
use crate::inprocess;
use search::SearchScenario;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;
use swarm::scenario::Scenario;

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub robots: u32,
    pub mode: String,
    pub seed: u64,
    pub threads: usize,
    pub ticks: u64,
    pub loop_seconds: f64,
    pub ticks_per_s: f64,
    pub robot_steps_per_s: f64,
}

/// The bench's scenario: the embedded default with these robots, seed and mode.
fn scenario(robots: u32, mode: &str, seed: u64) -> BenchResult<Scenario> {
    let mut sc = Scenario::default();
    sc.run.robots = robots;
    sc.run.seed = seed;
    sc.search_mut().mode = mode.to_string();
    crate::prepare::prepare_from(&mut sc, "bench search")?;
    Ok(sc)
}

/// The same runs as a sweep does them (`orchestrator experiment`): `jobs` runs at once, one
/// thread each, timed by the wall clock of the whole batch, start-up included.
#[derive(Debug, Clone, Serialize)]
pub struct Sweep {
    pub robots: u32,
    pub mode: String,
    pub runs: u64,
    pub jobs: usize,
    pub robot_steps: u64,
    pub wall_seconds: f64,
    pub robot_steps_per_s: f64,
}

pub fn sweep(robots: u32, mode: &str, seeds: u64, jobs: usize) -> BenchResult<Sweep> {
    let scs: Vec<Scenario> = (1..=seeds)
        .map(|seed| scenario(robots, mode, seed))
        .collect::<Result<_, _>>()?;
    let next = AtomicUsize::new(0);
    let steps = AtomicU64::new(0);
    let failure: Mutex<Option<std::io::Error>> = Mutex::new(None);
    let t0 = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| {
                while let Some(sc) = scs.get(next.fetch_add(1, Ordering::SeqCst)) {
                    match inprocess::run(sc, None, "bench-search-sweep", 1, &mut |_| {}) {
                        Ok(s) => {
                            steps.fetch_add(s.robots as u64 * s.ticks, Ordering::SeqCst);
                        }
                        Err(e) => *failure.lock().unwrap_or_else(|e| e.into_inner()) = Some(e),
                    }
                }
            });
        }
    });
    let wall_seconds = t0.elapsed().as_secs_f64().max(1e-9);
    if let Some(e) = failure.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(BenchError::InProcess(e));
    }
    let robot_steps = steps.into_inner();
    Ok(Sweep {
        robots,
        mode: mode.to_string(),
        runs: seeds,
        jobs: jobs.max(1),
        robot_steps,
        wall_seconds,
        robot_steps_per_s: robot_steps as f64 / wall_seconds,
    })
}

pub fn print_sweep(s: &Sweep) {
    println!(
        "sweep, {} run(s) at once, 1 thread each, wall clock with start-up (calibrations built above): {:.0} robot-steps/s ({} runs, {} robot-steps in {:.2} s)",
        s.jobs, s.robot_steps_per_s, s.runs, s.robot_steps, s.wall_seconds
    );
}

pub fn run(robots: u32, mode: &str, seeds: u64, threads: usize) -> BenchResult<Vec<Row>> {
    let mut rows = Vec::new();
    for seed in 1..=seeds {
        let sc = scenario(robots, mode, seed)?;
        let s = inprocess::run(
            &sc,
            None,
            &format!("bench-search-{seed}"),
            threads,
            &mut |_| {},
        )
        .map_err(BenchError::InProcess)?;
        let v = serde_json::to_value(&s).expect("a summary is plain data");
        let ticks = v["ticks"].as_u64().unwrap_or(0);
        let wall = v["wall_seconds"].as_f64().unwrap_or(0.0);
        let startup = v["startup_seconds"].as_f64().unwrap_or(0.0);
        let loop_seconds = (wall - startup).max(1e-9);
        rows.push(Row {
            robots,
            mode: mode.to_string(),
            seed,
            threads,
            ticks,
            loop_seconds,
            ticks_per_s: ticks as f64 / loop_seconds,
            robot_steps_per_s: robots as f64 * ticks as f64 / loop_seconds,
        });
    }
    Ok(rows)
}

pub fn print(rows: &[Row]) {
    println!("search scenario, in-process executor, one run at a time (robot-steps per second = robots x ticks / loop seconds)");
    println!(
        "{:>6} {:>4} {:>5} {:>7} {:>6} {:>9} {:>8} {:>14}",
        "robots", "mode", "seed", "threads", "ticks", "loop s", "ticks/s", "robot-steps/s"
    );
    for r in rows {
        println!(
            "{:>6} {:>4} {:>5} {:>7} {:>6} {:>9.3} {:>8.0} {:>14.0}",
            r.robots,
            r.mode,
            r.seed,
            r.threads,
            r.ticks,
            r.loop_seconds,
            r.ticks_per_s,
            r.robot_steps_per_s
        );
    }
    let mut threads: Vec<usize> = rows.iter().map(|r| r.threads).collect();
    threads.dedup();
    for t in threads {
        let of: Vec<&Row> = rows.iter().filter(|r| r.threads == t).collect();
        let steps: f64 = of.iter().map(|r| r.robots as f64 * r.ticks as f64).sum();
        let ticks: u64 = of.iter().map(|r| r.ticks).sum();
        let secs: f64 = of.iter().map(|r| r.loop_seconds).sum();
        println!(
            "all seeds, {t} thread(s): {:.0} robot-steps/s, {:.0} ticks/s ({:.0} robot-steps, {ticks} ticks in {:.2} s)",
            steps / secs,
            ticks as f64 / secs,
            steps,
            secs
        );
    }
}
