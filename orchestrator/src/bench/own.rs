//! `bench tick`'s rows of agent programs of one's own (issue 38): the roam scenario with every
//! robot run by an `[[agents]]` program beside the same size run by the built-in roam
//! behaviour. The programs: an empty behaviour in Rust (`swarm/examples/empty_agent.rs`) and in
//! Python (`python/bench/empty.py`): their difference is the Python runtime's own cost per
//! robot-tick; and the boids examples in both languages (`examples/rust-boids`,
//! `examples/python-boids/boids.py`). Python programs run on the repository's `.venv` (made by
//! scripts/test.sh) or `$SWARM_PYTHON`; a program that is not built is named and skipped.

use super::tick::{ticks_for, Stats};
use super::BenchResult;
use serde::Serialize;
use swarm::scenario::{AgentEntry, RobotSet, Scenario};

/// Sizes the rows are measured at (of those `bench tick` was given).
const OWN_MAX_ROBOTS: u32 = 100;

/// The weights of examples/rust-boids/boids.toml.
const BOIDS_PARAMS: &str = "cohesion = 0.01\nalignment = 0.125\nseparation = 20.0\n\
                            separation_radius = 25.0\navoid = 40.0\ncruise = 0.6\n";

/// How a program of the table is started.
pub enum Launch {
    /// A binary under the orchestrator's folder (target/release), built as `how` says.
    Binary {
        path: &'static str,
        how: &'static str,
    },
    /// A Python script of the repository, run by its `.venv`'s interpreter (or `$SWARM_PYTHON`).
    Python { script: &'static str },
}

/// A program of one's own measured by the table.
pub struct Program {
    /// Its name in the table.
    pub name: &'static str,
    pub launch: Launch,
    pub params: &'static str,
}

/// The programs measured (another language's example adds its line).
pub const PROGRAMS: &[Program] = &[
    Program {
        name: "rust-empty",
        launch: Launch::Binary {
            path: "examples/empty_agent",
            how: "cargo build --release -p swarm --example empty_agent",
        },
        params: "",
    },
    Program {
        name: "python-empty",
        launch: Launch::Python {
            script: "python/bench/empty.py",
        },
        params: "",
    },
    Program {
        name: "rust-boids",
        launch: Launch::Binary {
            path: "rust-boids",
            how: "cargo build --release in examples/rust-boids",
        },
        params: BOIDS_PARAMS,
    },
    Program {
        name: "python-boids",
        launch: Launch::Python {
            script: "examples/python-boids/boids.py",
        },
        params: "",
    },
];

/// The environment variable naming the Python interpreter of the Python rows (default: the
/// repository's `.venv/bin/python`).
pub const PYTHON_ENV: &str = "SWARM_PYTHON";

/// The repository: two folders above the orchestrator's binary (target/release).
fn repo() -> std::path::PathBuf {
    crate::registry::binary("../..")
}

/// The command that starts `p`, or why it cannot be started here.
fn command_of(p: &Program) -> Result<Vec<String>, String> {
    match p.launch {
        Launch::Binary { path, how } => {
            let bin = crate::registry::binary(path);
            if bin.exists() {
                Ok(vec![bin.display().to_string()])
            } else {
                Err(format!("{} missing: {how}", bin.display()))
            }
        }
        Launch::Python { script } => {
            let python = std::env::var(PYTHON_ENV)
                .map(std::path::PathBuf::from)
                .unwrap_or_else(|_| repo().join(".venv/bin/python"));
            let script = repo().join(script);
            if !python.exists() {
                return Err(format!(
                    "no Python at {} (scripts/test.sh makes .venv; or set {PYTHON_ENV})",
                    python.display()
                ));
            }
            let imports = std::process::Command::new(&python)
                .args(["-c", "import swarm"])
                .output()
                .is_ok_and(|o| o.status.success());
            if !imports {
                return Err(format!(
                    "{} cannot import swarm (pip install ./python)",
                    python.display()
                ));
            }
            Ok(vec![
                python.display().to_string(),
                script.display().to_string(),
            ])
        }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub program: String,
    pub robots: u32,
    pub ticks: u64,
    pub builtin_ticks_per_s: f64,
    pub builtin_p50_us: f64,
    pub program_ticks_per_s: f64,
    pub program_p50_us: f64,
    /// Spawn to every agent attached (summary.json's `startup_seconds`).
    pub program_startup_s: f64,
}

impl Row {
    /// The program run's time per robot-tick (us): 1e6 / (ticks/s x robots).
    pub fn us_per_robot_tick(&self) -> f64 {
        1e6 / (self.program_ticks_per_s * self.robots as f64)
    }
}

/// The rows at the sizes of `sizes` up to OWN_MAX_ROBOTS, for each program that is built
/// (one that is not is named and skipped).
pub fn run(sizes: &[u32], ticks: u64) -> BenchResult<Vec<Row>> {
    let mut rows = Vec::new();
    for p in PROGRAMS {
        let command = match command_of(p) {
            Ok(c) => c,
            Err(why) => {
                println!("{}: not measured ({why}), no rows", p.name);
                continue;
            }
        };
        for &n in sizes.iter().filter(|&&n| n <= OWN_MAX_ROBOTS) {
            let ticks = ticks_for(n, ticks);
            let builtin = measure(n, ticks, None)?;
            let own = measure(n, ticks, Some((command.clone(), p.params)))?;
            rows.push(Row {
                program: p.name.to_string(),
                robots: n,
                ticks,
                builtin_ticks_per_s: builtin.per_s,
                builtin_p50_us: builtin.p50_us,
                program_ticks_per_s: own.per_s,
                program_p50_us: own.p50_us,
                program_startup_s: own.startup_s,
            });
        }
    }
    Ok(rows)
}

/// The roam scenario at `n` robots, all run by `program` (path, params) or the built-in roam.
fn measure(n: u32, ticks: u64, program: Option<(Vec<String>, &str)>) -> BenchResult<Stats> {
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    let warmup = (ticks / 20).max(10);
    sc.run.max_ticks = ticks + warmup;
    if let Some((command, params)) = program {
        sc.agents = vec![AgentEntry {
            robots: RobotSet::Range { start: 0, end: n },
            command,
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
        "{:>12} {:>6} {:>6} | {:>10} {:>8} | {:>10} {:>8} {:>11} {:>9} | {:>8}",
        "program",
        "robots",
        "ticks",
        "built-in/s",
        "p50 us",
        "program/s",
        "p50 us",
        "us/robot-tk",
        "start s",
        "ratio"
    );
    for r in rows {
        println!(
            "{:>12} {:>6} {:>6} | {:>10.0} {:>8.0} | {:>10.0} {:>8.0} {:>11.1} {:>9.2} | {:>7.2}x",
            r.program,
            r.robots,
            r.ticks,
            r.builtin_ticks_per_s,
            r.builtin_p50_us,
            r.program_ticks_per_s,
            r.program_p50_us,
            r.us_per_robot_tick(),
            r.program_startup_s,
            r.builtin_ticks_per_s / r.program_ticks_per_s
        );
    }
    println!("built-in = the built-in roam behaviour at the same size; ratio = built-in ticks/s / program ticks/s.");
    for r in rows.iter().filter(|r| r.program == "python-empty") {
        if let Some(rust) = rows
            .iter()
            .find(|q| q.program == "rust-empty" && q.robots == r.robots)
        {
            println!(
                "N = {}: the Python runtime's own cost per robot-tick beyond the Rust one (empty behaviours): {:.1} us",
                r.robots,
                r.us_per_robot_tick() - rust.us_per_robot_tick()
            );
        }
    }
}
