//! `orchestrator experiment FILE`: a grid of runs (modes x swarm sizes x seeds) and the
//! paper-style table (min / mean / max steps and energy) beside the paper's Table 5.

use crate::up::Executor;
use crate::{inprocess, processes, runid};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use swarm::scenario::Scenario;

#[derive(Args, Debug)]
pub struct ExperimentArgs {
    /// Experiment file (TOML), e.g. configs/search-table5.toml.
    pub file: PathBuf,
    /// Seeds per cell (overrides the file's `seeds`; the same seeds for every mode and size).
    #[arg(long)]
    pub runs: Option<u32>,
    #[arg(long, value_enum, default_value_t = Executor::Inprocess)]
    pub executor: Executor,
    /// Where results.md and results.json go (default runs/experiment-<id>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Runs at once (in-process executor); default: the number of cores.
    #[arg(long)]
    pub jobs: Option<usize>,
    #[arg(long)]
    pub quiet: bool,
}

/// The experiment file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Base scenario, relative to the experiment file.
    pub scenario: PathBuf,
    pub modes: Vec<String>,
    pub robots: Vec<u32>,
    /// Seeds first_seed .. first_seed + seeds.
    pub seeds: u32,
    pub first_seed: u64,
    pub max_ticks: u64,
    /// The paper's rows to print beside ours: [robots, mode, steps min, mean, max, energy
    /// min, mean, max (x 10^4)].
    #[serde(default)]
    pub paper: Vec<PaperRow>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PaperRow {
    pub robots: u32,
    pub mode: String,
    pub steps: [f64; 3],
    pub energy: [f64; 3],
}

#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    pub mode: String,
    pub robots: u32,
    pub seed: u64,
    /// None: censored (max_ticks reached before every target was found).
    pub steps: Option<u64>,
    pub found: u32,
    pub targets: u32,
    pub energy: f64,
    pub ticks: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    pub mode: String,
    pub robots: u32,
    pub runs: usize,
    pub censored: usize,
    /// Over the completed runs.
    pub steps: Option<[f64; 3]>,
    pub energy_e4: Option<[f64; 3]>,
    /// Mean energy / (robots x mean steps): must be <= v_max.
    pub energy_per_robot_step: Option<f64>,
    pub paper: Option<PaperRow>,
}

fn min_mean_max(v: &[f64]) -> Option<[f64; 3]> {
    if v.is_empty() {
        return None;
    }
    let min = v.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = v.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    Some([min, v.iter().sum::<f64>() / v.len() as f64, max])
}

fn load(path: &Path) -> Result<Experiment, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let mut x: Experiment =
        toml::from_str(&text).map_err(|e| format!("{}: {}", path.display(), e.message()))?;
    if x.modes.is_empty() || x.robots.is_empty() || x.seeds == 0 {
        return Err(format!(
            "{}: `modes`, `robots` and `seeds` must be non-empty",
            path.display()
        ));
    }
    x.scenario = path.parent().unwrap_or(Path::new(".")).join(&x.scenario);
    Ok(x)
}

pub fn experiment(a: ExperimentArgs) -> i32 {
    match run(a) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}

fn run(a: ExperimentArgs) -> Result<i32, String> {
    let x = load(&a.file)?;
    let base = Scenario::load(&x.scenario).map_err(|e| e.to_string())?;
    let seeds = a.runs.unwrap_or(x.seeds);
    // Every cell's scenario, validated before anything runs.
    let mut jobs: Vec<(String, u32, u64, Scenario)> = Vec::new();
    let mut unavailable: Vec<(String, String)> = Vec::new();
    for mode in &x.modes {
        let mut ok = true;
        for &n in &x.robots {
            for s in 0..seeds as u64 {
                let mut sc = base.clone();
                sc.search.mode = mode.clone();
                sc.run.robots = n;
                sc.run.seed = x.first_seed + s;
                sc.run.max_ticks = x.max_ticks;
                let file = a.file.display().to_string();
                if let Err(e) = sc
                    .validate(&|_| file.clone())
                    .map_err(|e| e.to_string())
                    .and_then(|_| agent::behaviours::validate(&sc))
                {
                    if s == 0 && n == x.robots[0] {
                        unavailable.push((mode.clone(), e));
                    }
                    ok = false;
                    break;
                }
                jobs.push((mode.clone(), n, sc.run.seed, sc));
            }
            if !ok {
                break;
            }
        }
        if !ok {
            jobs.retain(|j| &j.0 != mode);
        }
    }
    for (m, e) in &unavailable {
        eprintln!("mode {m}: not run: {e}");
    }
    let id = runid::new_run_id();
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| Path::new("runs").join(format!("experiment-{id}")));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let pb = if a.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(jobs.len() as u64)
    };
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} runs {pos}/{len} [{bar:30}] {elapsed} eta {eta} | {msg}",
        )
        .expect("template")
        .progress_chars("=> "),
    );
    let results: Mutex<Vec<RunResult>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let threads = match a.executor {
        Executor::Inprocess => a
            .jobs
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
        Executor::Processes => 1,
    };
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some((mode, n, seed, sc)) = jobs.get(i) else {
                    break;
                };
                let run_id = format!("{id}-{mode}-{n}-{seed}");
                let summary: Result<serde_json::Value, String> = match a.executor {
                    Executor::Inprocess => inprocess::run(sc, None, &run_id, &mut |_| {})
                        .map_err(|e| e.to_string())
                        .and_then(|s| serde_json::to_value(&s).map_err(|e| e.to_string())),
                    Executor::Processes => {
                        let dir = std::env::temp_dir().join(format!("swarm-exp-{run_id}"));
                        let r = processes::run(processes::ProcessRun {
                            sc,
                            run_id: &run_id,
                            run_dir: &dir,
                            on_status: &mut |_| {},
                        })
                        .and_then(|_| {
                            std::fs::read_to_string(dir.join("summary.json"))
                                .map_err(|e| e.to_string())
                        })
                        .and_then(|t| serde_json::from_str(&t).map_err(|e| e.to_string()));
                        let _ = std::fs::remove_dir_all(&dir);
                        r
                    }
                };
                match summary {
                    Ok(s) => {
                        let m = &s["mission"]["search"];
                        results.lock().expect("lock").push(RunResult {
                            mode: mode.clone(),
                            robots: *n,
                            seed: *seed,
                            steps: m["steps"].as_u64(),
                            found: m["found"].as_u64().unwrap_or(0) as u32,
                            targets: m["targets"].as_u64().unwrap_or(0) as u32,
                            energy: m["energy"].as_f64().unwrap_or(0.0),
                            ticks: s["ticks"].as_u64().unwrap_or(0),
                        });
                    }
                    Err(e) => failures
                        .lock()
                        .expect("lock")
                        .push(format!("{mode} N={n} seed {seed}: {e}")),
                }
                pb.inc(1);
                pb.set_message(format!("{mode} N={n} seed {seed}"));
            });
        }
    });
    pb.finish_and_clear();
    let failures = failures.into_inner().expect("lock");
    for f in &failures {
        eprintln!("run failed: {f}");
    }
    let mut results = results.into_inner().expect("lock");
    results.sort_by(|a, b| (a.robots, &a.mode, a.seed).cmp(&(b.robots, &b.mode, b.seed)));
    let cells = tabulate(&x, &results);
    let md = report(&x, &cells, seeds, &unavailable);
    print!("{md}");
    std::fs::write(out.join("results.md"), &md).map_err(|e| e.to_string())?;
    let json = serde_json::json!({ "experiment": x, "seeds": seeds, "runs": results, "cells": cells,
        "unavailable": unavailable, "failures": failures });
    std::fs::write(
        out.join("results.json"),
        serde_json::to_string_pretty(&json).expect("json"),
    )
    .map_err(|e| e.to_string())?;
    println!("\nwritten: {}/results.md, results.json", out.display());
    Ok(if failures.is_empty() { 0 } else { 1 })
}

fn tabulate(x: &Experiment, results: &[RunResult]) -> Vec<Cell> {
    let mut cells = Vec::new();
    for &n in &x.robots {
        for mode in &x.modes {
            let rs: Vec<&RunResult> = results
                .iter()
                .filter(|r| r.robots == n && &r.mode == mode)
                .collect();
            if rs.is_empty() {
                continue;
            }
            let done: Vec<&&RunResult> = rs.iter().filter(|r| r.steps.is_some()).collect();
            let steps = min_mean_max(
                &done
                    .iter()
                    .map(|r| r.steps.unwrap() as f64)
                    .collect::<Vec<_>>(),
            );
            let energy = min_mean_max(&done.iter().map(|r| r.energy / 1e4).collect::<Vec<_>>());
            let eprs = match (steps, energy) {
                (Some(s), Some(e)) => Some(e[1] * 1e4 / (n as f64 * s[1])),
                _ => None,
            };
            cells.push(Cell {
                mode: mode.clone(),
                robots: n,
                runs: rs.len(),
                censored: rs.len() - done.len(),
                steps,
                energy_e4: energy,
                energy_per_robot_step: eprs,
                paper: x
                    .paper
                    .iter()
                    .find(|p| p.robots == n && &p.mode == mode)
                    .cloned(),
            });
        }
    }
    cells
}

/// Improvement of `ours` over `other` the paper's way (spec/search.md 4.6): relative reduction
/// of the mean values summed over the swarm sizes (pooled over the modes of each group).
fn improvement(
    cells: &[Cell],
    ours: &[&str],
    other: &[&str],
    energy: bool,
    paper: bool,
) -> Option<f64> {
    let total = |modes: &[&str]| -> Option<f64> {
        let mut sum = 0.0;
        for m in modes {
            for c in cells.iter().filter(|c| c.mode == *m) {
                let v = if paper {
                    let p = c.paper.as_ref()?;
                    if energy {
                        p.energy[1]
                    } else {
                        p.steps[1]
                    }
                } else if energy {
                    c.energy_e4?[1]
                } else {
                    c.steps?[1]
                };
                sum += v;
            }
        }
        (sum > 0.0).then_some(sum)
    };
    let (o, t) = (total(ours)?, total(other)?);
    Some((t - o) / t * 100.0)
}

fn fmt3(v: Option<[f64; 3]>, prec: usize) -> String {
    match v {
        Some([a, b, c]) => format!("{a:.prec$} / {b:.prec$} / {c:.prec$}"),
        None => "n/a".into(),
    }
}

fn report(x: &Experiment, cells: &[Cell], seeds: u32, unavailable: &[(String, String)]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Multi-target search: steps and energy (min / mean / max over {seeds} seeds)\n"
    );
    let _ = writeln!(s, "Energy is the total path length of all robots, x 10^4. Steps are counted over completed runs; censored runs (max_ticks = {} reached) are counted apart, never dropped silently.\n", x.max_ticks);
    let _ = writeln!(s, "| N | mode | runs | censored | steps (ours) | steps (paper) | energy (ours) | energy (paper) | energy / robot-step |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
    for c in cells {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.robots,
            c.mode,
            c.runs,
            c.censored,
            fmt3(c.steps, 0),
            c.paper
                .as_ref()
                .map_or("".into(), |p| fmt3(Some(p.steps), 0)),
            fmt3(c.energy_e4, 3),
            c.paper
                .as_ref()
                .map_or("".into(), |p| fmt3(Some(p.energy), 3)),
            c.energy_per_robot_step
                .map_or("n/a".into(), |v| format!("{v:.2}")),
        );
    }
    for (m, e) in unavailable {
        let _ = writeln!(s, "\nMode {m} was not run: {e}");
    }
    let _ = writeln!(
        s,
        "\n## Headline comparisons (spec/search.md 4.6: relative reduction of the summed means)\n"
    );
    let _ = writeln!(s, "| comparison | steps: ours | steps: paper's table | energy: ours | energy: paper's table |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    let pct = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{v:.2} %"));
    let mut rows: Vec<(String, Vec<&str>, Vec<&str>)> = ["BE", "BA", "ST", "SE", "SA"]
        .iter()
        .map(|m| (format!("BT vs {m}"), vec!["BT"], vec![*m]))
        .collect();
    rows.push((
        "BSOA vs SVF (B** vs S**)".into(),
        vec!["BT", "BE", "BA"],
        vec!["ST", "SE", "SA"],
    ));
    rows.push((
        "TPEPSO vs EPSO (*T vs *E)".into(),
        vec!["BT", "ST"],
        vec!["BE", "SE"],
    ));
    rows.push((
        "TPEPSO vs ARBA (*T vs *A)".into(),
        vec!["BT", "ST"],
        vec!["BA", "SA"],
    ));
    for (name, ours, other) in rows {
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} |",
            pct(improvement(cells, &ours, &other, false, false)),
            pct(improvement(cells, &ours, &other, false, true)),
            pct(improvement(cells, &ours, &other, true, false)),
            pct(improvement(cells, &ours, &other, true, true)),
        );
    }
    // Does BT have the fewest mean steps at every N?
    let mut verdicts = Vec::new();
    for &n in &x.robots {
        let at: Vec<&Cell> = cells
            .iter()
            .filter(|c| c.robots == n && c.steps.is_some())
            .collect();
        if let Some(best) = at
            .iter()
            .min_by(|a, b| a.steps.unwrap()[1].total_cmp(&b.steps.unwrap()[1]))
        {
            verdicts.push(format!("N={n}: fewest mean steps {}", best.mode));
        }
    }
    let _ = writeln!(s, "\n{}", verdicts.join("; "));
    s
}
