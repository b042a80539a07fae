//! `bench tick`'s rows of agent programs of one's own (issue 38): the roam scenario with every
//! robot run by an `[[agents]]` program (the rust-boids example) beside the same size run by
//! the built-in roam behaviour. Both broadcast a position every tick; the boid's own work is a
//! few dozen flops a neighbour heard, so the difference is mostly the program's.

use super::tick::{ticks_for, Stats};
use super::BenchResult;
use serde::Serialize;
use swarm::scenario::{AgentEntry, RobotSet, Scenario};

/// Sizes the rows are measured at (of those `bench tick` was given).
const OWN_MAX_ROBOTS: u32 = 100;

/// The weights of examples/rust-boids/boids.toml.
const BOIDS_PARAMS: &str = "cohesion = 0.01\nalignment = 0.125\nseparation = 20.0\n\
                            separation_radius = 25.0\navoid = 40.0\ncruise = 0.6\n";

/// A program of one's own measured by the table.
pub struct Program {
    /// Its name in the table.
    pub name: &'static str,
    /// Its binary, beside the orchestrator's (built by its own `cargo build --release`).
    pub binary: &'static str,
    pub params: &'static str,
}

/// The programs measured (another language's example adds its line).
pub const PROGRAMS: &[Program] = &[Program {
    name: "rust-boids",
    binary: "rust-boids",
    params: BOIDS_PARAMS,
}];

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub program: String,
    pub robots: u32,
    pub ticks: u64,
    pub builtin_ticks_per_s: f64,
    pub builtin_p50_us: f64,
    pub program_ticks_per_s: f64,
    pub program_p50_us: f64,
}

/// The rows at the sizes of `sizes` up to OWN_MAX_ROBOTS, for each program that is built
/// (one that is not is named and skipped).
pub fn run(sizes: &[u32], ticks: u64) -> BenchResult<Vec<Row>> {
    let mut rows = Vec::new();
    for p in PROGRAMS {
        let bin = crate::registry::binary(p.binary);
        if !bin.exists() {
            println!(
                "{}: not built ({} missing: cargo build --release in examples/{}), no rows",
                p.name,
                bin.display(),
                p.name
            );
            continue;
        }
        for &n in sizes.iter().filter(|&&n| n <= OWN_MAX_ROBOTS) {
            let ticks = ticks_for(n, ticks);
            let builtin = measure(n, ticks, None)?;
            let own = measure(n, ticks, Some((bin.display().to_string(), p.params)))?;
            rows.push(Row {
                program: p.name.to_string(),
                robots: n,
                ticks,
                builtin_ticks_per_s: builtin.per_s,
                builtin_p50_us: builtin.p50_us,
                program_ticks_per_s: own.per_s,
                program_p50_us: own.p50_us,
            });
        }
    }
    Ok(rows)
}

/// The roam scenario at `n` robots, all run by `program` (path, params) or the built-in roam.
fn measure(n: u32, ticks: u64, program: Option<(String, &str)>) -> BenchResult<Stats> {
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    let warmup = (ticks / 20).max(10);
    sc.run.max_ticks = ticks + warmup;
    if let Some((path, params)) = program {
        sc.agents = vec![AgentEntry {
            robots: RobotSet::Range { start: 0, end: n },
            command: vec![path],
            cwd: None,
            attach_timeout_s: None,
            params: params.parse().expect("the bench's params are TOML"),
            source: None,
        }];
    }
    super::tick::run_stats(&sc).map(|(_, s)| s)
}

pub fn print(rows: &[Row]) {
    if rows.is_empty() {
        return;
    }
    println!(
        "agent programs of one's own ([[agents]], roam scenario; every robot run by the program)"
    );
    println!(
        "{:>12} {:>6} {:>6} | {:>10} {:>8} | {:>10} {:>8} | {:>8}",
        "program", "robots", "ticks", "built-in/s", "p50 us", "program/s", "p50 us", "ratio"
    );
    for r in rows {
        println!(
            "{:>12} {:>6} {:>6} | {:>10.0} {:>8.0} | {:>10.0} {:>8.0} | {:>7.2}x",
            r.program,
            r.robots,
            r.ticks,
            r.builtin_ticks_per_s,
            r.builtin_p50_us,
            r.program_ticks_per_s,
            r.program_p50_us,
            r.builtin_ticks_per_s / r.program_ticks_per_s
        );
    }
    println!("built-in = the built-in roam behaviour at the same size; ratio = built-in ticks/s / program ticks/s.");
}
