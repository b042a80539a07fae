//! `orchestrator bench tick`'s real-time column: the deadline-miss rate against N at a few
//! clock rates (`--realtime-hz`), so a user sees how many robots this machine runs at 10, 50
//! or 100 Hz. Each cell is a real run of the roam scenario (configs/roam.toml) with the
//! processes executor in real-time mode (`runtime.realtime_hz`).
//!
//! The miss rate is counted from the run's recording after a warm-up (the first
//! max(10, 5 %) ticks, which include every agent's first touch of its memory): missed
//! (robot, tick) pairs / live (robot, tick) pairs. Beside it: the ticks per second the world
//! achieved over the whole loop (at most the rate), and the ticks the world itself released
//! after their deadline (its own work took longer than the period).

use super::tick::run_processes;
use super::{BenchError, BenchResult};
use serde::{Deserialize, Serialize};
use swarm::recording::{read_recording, Event};
use swarm::scenario::Scenario;

/// What the real-time column measures (`bench tick --realtime-hz ... --realtime-seconds ...`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RealtimeBenchParams {
    /// Clock rates, ticks per second.
    pub rates: Vec<f64>,
    /// Seconds of clock per cell (ticks = rate x seconds, at least MIN_TICKS), warm-up
    /// excluded.
    pub seconds: f64,
}

impl Default for RealtimeBenchParams {
    fn default() -> Self {
        RealtimeBenchParams {
            rates: vec![10.0, 50.0, 100.0],
            // Long enough for a few hundred ticks at 100 Hz, short enough for 5 sizes x 3
            // rates in a few minutes.
            seconds: 4.0,
        }
    }
}

/// Fewest ticks measured per cell (a slow rate's few seconds would give too few).
const MIN_TICKS: u64 = 40;

/// One (N, rate) cell.
#[derive(Debug, Clone, Serialize)]
pub struct RtCell {
    pub robots: u32,
    pub hz: f64,
    /// Ticks measured (after the warm-up).
    pub ticks: u64,
    /// Missed (robot, tick) pairs and all live ones, after the warm-up.
    pub misses: u64,
    pub robot_ticks: u64,
    pub miss_rate: f64,
    /// Ticks per second over the whole loop (the clock's rate when the world keeps up).
    pub achieved_ticks_per_s: f64,
    /// Ticks the world released after their own deadline (whole run).
    pub late_releases: u64,
    /// Actions read after their deadline (whole run).
    pub late_actions: u64,
    /// The machine's 1-minute load average when the cell started (/proc/loadavg): the
    /// cores are shared, and the miss rate depends on what else runs.
    pub load_1min: f64,
}

/// The 1-minute load average (0 if /proc/loadavg cannot be read).
fn load_1min() -> f64 {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|x| x.parse().ok()))
        .unwrap_or(0.0)
}

/// Runs every (size, rate) cell.
pub fn run(sizes: &[u32], p: &RealtimeBenchParams) -> BenchResult<Vec<RtCell>> {
    let mut cells = Vec::new();
    for &n in sizes {
        for &hz in &p.rates {
            cells.push(cell(n, hz, p.seconds)?);
        }
    }
    Ok(cells)
}

fn cell(n: u32, hz: f64, seconds: f64) -> BenchResult<RtCell> {
    let load = load_1min();
    let ticks = ((hz * seconds).round() as u64).max(MIN_TICKS);
    let warmup = (ticks / 20).max(10);
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    sc.run.max_ticks = ticks + warmup;
    sc.runtime.realtime_hz = hz;
    let (s, dir) = run_processes(&sc)?;
    let path = dir.join("recording.bin");
    let read = std::fs::File::open(&path)
        .and_then(|f| read_recording(std::io::BufReader::new(f)))
        .map_err(|source| BenchError::File {
            path: path.clone(),
            source,
        });
    let _ = std::fs::remove_dir_all(&dir);
    let (_, recs) = read?;
    let (mut misses, mut robot_ticks) = (0u64, 0u64);
    for t in recs.iter().filter(|t| t.tick >= warmup) {
        misses += t
            .events
            .iter()
            .filter(|e| matches!(e, Event::DeadlineMissed { .. }))
            .count() as u64;
        // Alive after the tick; a robot that died during it was live at its deadline, but
        // deaths are rare here (none in a bench run).
        robot_ticks += t.alive.iter().map(|&a| a as u64).sum::<u64>();
    }
    let rt = &s["realtime"];
    Ok(RtCell {
        robots: n,
        hz,
        ticks: recs.iter().filter(|t| t.tick >= warmup).count() as u64,
        misses,
        robot_ticks,
        miss_rate: if robot_ticks > 0 {
            misses as f64 / robot_ticks as f64
        } else {
            0.0
        },
        achieved_ticks_per_s: s["ticks_per_second"].as_f64().unwrap_or(0.0),
        late_releases: rt["late_releases"].as_u64().unwrap_or(0),
        late_actions: rt["late_actions"].as_u64().unwrap_or(0),
        load_1min: load,
    })
}

/// One row per size, one column group per rate: miss %, ticks/s achieved, late releases.
pub fn print(cells: &[RtCell], p: &RealtimeBenchParams) {
    println!(
        "real-time mode (roam, configs/roam.toml, processes): deadline-miss rate after a warm-up, {} s of clock per cell",
        p.seconds
    );
    let mut head = format!("{:>6}", "robots");
    for hz in &p.rates {
        head += &format!(
            " | {:>8} {:>8} {:>6}",
            format!("{hz} Hz"),
            "ticks/s",
            "late"
        );
    }
    head += &format!(" | {:>5}", "load");
    println!("{head}");
    let mut sizes: Vec<u32> = cells.iter().map(|c| c.robots).collect();
    sizes.dedup();
    for n in sizes {
        let mut line = format!("{n:>6}");
        for hz in &p.rates {
            match cells.iter().find(|c| c.robots == n && c.hz == *hz) {
                Some(c) => {
                    line += &format!(
                        " | {:>7.2}% {:>8.1} {:>6}",
                        100.0 * c.miss_rate,
                        c.achieved_ticks_per_s,
                        c.late_releases
                    )
                }
                None => line += &format!(" | {:>8} {:>8} {:>6}", "-", "-", "-"),
            }
        }
        let loads: Vec<f64> = cells
            .iter()
            .filter(|c| c.robots == n)
            .map(|c| c.load_1min)
            .collect();
        let mean = loads.iter().sum::<f64>() / loads.len().max(1) as f64;
        println!("{line} | {mean:>5.1}");
    }
    println!("miss % = missed (robot, tick) pairs / live (robot, tick) pairs; ticks/s = achieved over the run (at most the rate);");
    println!("late = ticks the world itself released after their deadline (its own work took longer than the period);");
    println!("load = the 1-minute load average when the row's cells started (mean).");
}
