//! `orchestrator bench search`: robot-steps per second of the in-process executor running the
//! search scenario (issue 3's speed figure), one run at a time, over several seeds, on one
//! thread and on all cores (the in-process executor splits each tick's agents over threads).
//!
//! A robot-step is one robot's tick: the world's sensing for it, its radio inbox, its
//! behaviour's step and its move. The loop time excludes start-up (world and behaviour
//! construction, the per-robot offline calibration).

use crate::inprocess;
use serde::Serialize;
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

pub fn run(robots: u32, mode: &str, seeds: u64, threads: usize) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for seed in 1..=seeds {
        let mut sc = Scenario::default();
        sc.run.robots = robots;
        sc.run.seed = seed;
        sc.search.mode = mode.to_string();
        sc.validate(&|_| "bench search".into())
            .map_err(|e| e.to_string())?;
        agent::behaviours::validate(&sc)?;
        let s = inprocess::run(
            &sc,
            None,
            &format!("bench-search-{seed}"),
            threads,
            &mut |_| {},
        )
        .map_err(|e| e.to_string())?;
        let v = serde_json::to_value(&s).map_err(|e| e.to_string())?;
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
