//! `orchestrator experiment FILE`: a grid of runs (modes x swarm sizes x seeds) and the
//! paper-style table (min / mean / max steps and energy) beside the paper's Table 5.

use super::runner::{parse_file, Context, Report, Row, SeedSpec, DEFAULT_FIRST_SEED};
use super::Variant;
use crate::up::Executor;
use indicatif::{ProgressBar, ProgressStyle};
use search::SearchScenario;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use swarm::scenario::{FaultPolicy, Scenario};

/// The experiment file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// "search", or no `kind` at all.
    #[serde(default, skip_serializing)]
    pub kind: Option<String>,
    /// Base scenario, relative to the experiment file.
    pub scenario: PathBuf,
    pub modes: Vec<String>,
    pub robots: Vec<u32>,
    /// The seeds of every (mode, N, variant): a count (from `first_seed`), a range "A..B"
    /// (both ends included) or a list; `--seeds` / `--runs` override it.
    pub seeds: SeedSpec,
    #[serde(default = "first_seed")]
    pub first_seed: u64,
    pub max_ticks: u64,
    /// The paper's rows to print beside ours: [robots, mode, steps min, mean, max, energy
    /// min, mean, max (x 10^4)].
    #[serde(default)]
    pub paper: Vec<PaperRow>,
    /// Conditions every (mode, N, seed) also runs under: radio loss, agents killed. The first
    /// is the reference the others' slowdown is measured against, seed by seed. None: one
    /// unnamed variant, the scenario as it is.
    #[serde(default)]
    pub variants: Vec<Variant>,
}

fn first_seed() -> u64 {
    DEFAULT_FIRST_SEED
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
    pub variant: String,
    pub robots: u32,
    pub seed: u64,
    /// None: censored (max_ticks reached before every target was found).
    pub steps: Option<u64>,
    pub found: u32,
    pub targets: u32,
    pub energy: f64,
    pub ticks: u64,
    /// Robots killed (faults in the summary) and restarted.
    pub faults: u64,
    pub restarted: u64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    pub mode: String,
    pub variant: String,
    pub robots: u32,
    pub runs: usize,
    pub censored: usize,
    /// Over the completed runs.
    pub steps: Option<[f64; 3]>,
    /// Completed runs / runs.
    pub completion_rate: f64,
    /// Mean steps over every run, each censored run counted at the cap (`max_ticks`): a
    /// lower bound on the true mean when `censored > 0` (a censored run would have needed
    /// more). The mean of the completed runs alone drops the hardest runs and flatters the
    /// method that fails most (issue 14 item 11).
    pub steps_mean_censored_at_cap: f64,
    /// Whether `steps_mean_censored_at_cap` is only a lower bound (some run was censored).
    pub steps_mean_is_lower_bound: bool,
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
    let mut x: Experiment = parse_file(path)?;
    if x.kind.as_deref().is_some_and(|k| k != "search") {
        return Err(format!(
            "{}: kind = {:?}, not \"search\"",
            path.display(),
            x.kind
        ));
    }
    if x.modes.is_empty() || x.robots.is_empty() {
        return Err(format!(
            "{}: `modes` and `robots` must be non-empty",
            path.display()
        ));
    }
    x.scenario = path.parent().unwrap_or(Path::new(".")).join(&x.scenario);
    if x.variants.is_empty() {
        x.variants.push(Variant::default());
    }
    let mut names: Vec<&str> = x.variants.iter().map(|v| v.name.as_str()).collect();
    names.sort_unstable();
    if names.windows(2).any(|w| w[0] == w[1]) {
        return Err(format!(
            "{}: every [[variants]] needs its own `name`",
            path.display()
        ));
    }
    Ok(x)
}

/// The grid: every (mode, N, variant) over the seeds, then the paper-style tables.
pub fn run(ctx: &Context) -> Result<Report, String> {
    let x = load(&ctx.file)?;
    let base = Scenario::load(&x.scenario).map_err(|e| e.to_string())?;
    let dir = ctx.dir.clone();
    let bases: Vec<Scenario> = x
        .variants
        .iter()
        .map(|v| v.scenario(&base, &dir))
        .collect::<Result<_, _>>()?;
    let seed_list = ctx.seeds(&x.seeds, x.first_seed)?;
    let seeds = seed_list.len() as u32;
    // Every cell's scenario, validated before anything runs.
    let mut jobs: Vec<(String, String, u32, u64, Scenario)> = Vec::new();
    let mut unavailable: Vec<(String, String)> = Vec::new();
    for mode in &x.modes {
        let mut ok = true;
        for &n in &x.robots {
            for (s, seed, (v, vbase)) in seed_list
                .iter()
                .enumerate()
                .flat_map(|(s, &seed)| x.variants.iter().zip(&bases).map(move |v| (s, seed, v)))
            {
                let mut sc = vbase.clone();
                sc.search_mut().mode = mode.clone();
                sc.run.robots = n;
                sc.run.seed = seed;
                sc.run.max_ticks = x.max_ticks;
                v.apply(&mut sc);
                if sc.faults.on_fault == FaultPolicy::Restart
                    && sc.faults.kill_fraction > 0.0
                    && ctx.executor == Executor::Inprocess
                {
                    return Err(format!(
                        "variant {:?}: on_fault = \"restart\" needs real agent processes: run with --executor processes",
                        v.name
                    ));
                }
                let file = ctx.name();
                if let Err(e) =
                    crate::prepare::prepare_from(&mut sc, &file).map_err(|e| e.to_string())
                {
                    if s == 0 && n == x.robots[0] {
                        unavailable.push((mode.clone(), e));
                    }
                    ok = false;
                    break;
                }
                jobs.push((mode.clone(), v.name.clone(), n, sc.run.seed, sc));
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
    let id = &ctx.id;
    let pb = if ctx.quiet {
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
    std::thread::scope(|scope| {
        for _ in 0..ctx.jobs {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some((mode, variant, n, seed, sc)) = jobs.get(i) else {
                    break;
                };
                let run_id = format!("{id}-{mode}-{n}-{seed}-{i}");
                let summary = super::runner::run_scenario(sc, ctx.executor, &run_id);
                match summary {
                    Ok(s) => {
                        let m = &s["mission"]["search"];
                        let faults = s["faults"].as_array().map_or(&[][..], |f| f.as_slice());
                        results.lock().expect("lock").push(RunResult {
                            mode: mode.clone(),
                            variant: variant.clone(),
                            robots: *n,
                            seed: *seed,
                            steps: m["steps"].as_u64(),
                            found: m["found"].as_u64().unwrap_or(0) as u32,
                            targets: m["targets"].as_u64().unwrap_or(0) as u32,
                            energy: m["energy"].as_f64().unwrap_or(0.0),
                            ticks: s["ticks"].as_u64().unwrap_or(0),
                            faults: faults.len() as u64,
                            restarted: faults
                                .iter()
                                .filter(|f| f["restarted_tick"].is_u64())
                                .count() as u64,
                        });
                    }
                    Err(e) => failures
                        .lock()
                        .expect("lock")
                        .push(format!("{mode} {variant} N={n} seed {seed}: {e}")),
                }
                pb.inc(1);
                pb.set_message(format!("{mode} {variant} N={n} seed {seed}"));
            });
        }
    });
    pb.finish_and_clear();
    let failures = failures.into_inner().expect("lock");
    for f in &failures {
        eprintln!("run failed: {f}");
    }
    let mut results = results.into_inner().expect("lock");
    let order = |v: &str| x.variants.iter().position(|w| w.name == v);
    results.sort_by(|a, b| {
        (a.robots, &a.mode, order(&a.variant), a.seed).cmp(&(
            b.robots,
            &b.mode,
            order(&b.variant),
            b.seed,
        ))
    });
    let cells = tabulate(&x, &results);
    let mut md = report(&x, &cells, seeds, &unavailable);
    if x.variants.len() > 1 {
        if x.variants
            .iter()
            .any(|v| v.overlay.is_some() || v.set.is_some())
        {
            md += &sensitivity_report(&x, &cells);
        }
        md += &variants_report(&x, &results);
    }
    write_charts(&x, &cells, seeds, ctx)?;
    let rows = results.iter().map(row_of).collect();
    let mut json = serde_json::Map::new();
    json.insert("experiment".into(), serde_json::json!(x));
    json.insert("runs".into(), serde_json::json!(results));
    json.insert("cells".into(), serde_json::json!(cells));
    json.insert("unavailable".into(), serde_json::json!(unavailable));
    json.insert("failures".into(), serde_json::json!(failures));
    let _ = writeln!(md, "\nCharts: steps.svg, energy.svg.");
    Ok(Report {
        md,
        rows,
        json,
        failed: !failures.is_empty(),
    })
}

/// A run as results.csv has it: steps empty when censored.
fn row_of(r: &RunResult) -> Row {
    Row::new(&r.variant, &r.mode, r.robots, r.seed)
        .with("completed", r.steps.is_some())
        .with("steps", r.steps)
        .with("found", r.found as u64)
        .with("targets", r.targets as u64)
        .with("energy", r.energy)
        .with("ticks", r.ticks)
        .with("faults", r.faults)
        .with("restarted", r.restarted)
}

/// `steps.svg` and `energy.svg` beside results.md: the mean and the spread (min to max) over
/// the completed runs against the swarm size, one line per mode (and variant), with the
/// paper's means as crosses where the experiment gives them.
fn write_charts(x: &Experiment, cells: &[Cell], seeds: u32, ctx: &Context) -> Result<(), String> {
    use crate::export::charts::{write, Chart, Point, Series};
    let many = x.variants.len() > 1;
    for (file, what, pick, paper) in [
        (
            "steps.svg",
            "steps",
            (|c: &Cell| c.steps) as fn(&Cell) -> Option<[f64; 3]>,
            (|p: &PaperRow| p.steps[1]) as fn(&PaperRow) -> f64,
        ),
        (
            "energy.svg",
            "energy (x 10^4)",
            |c: &Cell| c.energy_e4,
            |p: &PaperRow| p.energy[1],
        ),
    ] {
        let mut series = Vec::new();
        for mode in &x.modes {
            for v in &x.variants {
                let points: Vec<Point> = cells
                    .iter()
                    .filter(|c| &c.mode == mode && c.variant == v.name)
                    .filter_map(|c| {
                        pick(c).map(|[lo, mean, hi]| Point {
                            x: c.robots as f64,
                            mean,
                            lo,
                            hi,
                        })
                    })
                    .collect();
                series.push(Series {
                    label: if many {
                        format!("{mode} {}", v.name)
                    } else {
                        mode.clone()
                    },
                    points,
                    reference: false,
                });
            }
            let theirs: Vec<Point> = x
                .paper
                .iter()
                .filter(|p| &p.mode == mode)
                .map(|p| {
                    let m = paper(p);
                    Point {
                        x: p.robots as f64,
                        mean: m,
                        lo: m,
                        hi: m,
                    }
                })
                .collect();
            if !theirs.is_empty() {
                series.push(Series {
                    label: format!("{mode} (paper)"),
                    points: theirs,
                    reference: true,
                });
            }
        }
        let chart = Chart {
            title: format!("{what}: mean and min-max over the completed runs of {seeds} seeds"),
            x_label: "robots (N)".into(),
            y_label: what.into(),
            series,
        };
        write(&chart, &ctx.out_file(file)?)?;
    }
    Ok(())
}

fn tabulate(x: &Experiment, results: &[RunResult]) -> Vec<Cell> {
    let mut cells = Vec::new();
    for &n in &x.robots {
        for (mode, variant) in x
            .modes
            .iter()
            .flat_map(|m| x.variants.iter().map(move |v| (m, &v.name)))
        {
            let rs: Vec<&RunResult> = results
                .iter()
                .filter(|r| r.robots == n && &r.mode == mode && &r.variant == variant)
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
            let at_cap: f64 = rs
                .iter()
                .map(|r| r.steps.unwrap_or(x.max_ticks) as f64)
                .sum::<f64>()
                / rs.len() as f64;
            cells.push(Cell {
                mode: mode.clone(),
                variant: variant.clone(),
                robots: n,
                runs: rs.len(),
                censored: rs.len() - done.len(),
                steps,
                completion_rate: done.len() as f64 / rs.len() as f64,
                steps_mean_censored_at_cap: at_cap,
                steps_mean_is_lower_bound: done.len() < rs.len(),
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

/// Improvement of `ours` over `other` the paper's way (docs/search.md 4.6): relative reduction
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

/// The mean with censored runs at the cap; ">= m" when it is a lower bound.
fn fmt_at_cap(c: &Cell) -> String {
    let lb = if c.steps_mean_is_lower_bound {
        ">= "
    } else {
        ""
    };
    format!("{lb}{:.0}", c.steps_mean_censored_at_cap)
}

fn fmt3(v: Option<[f64; 3]>, prec: usize) -> String {
    match v {
        Some([a, b, c]) => format!("{a:.prec$} / {b:.prec$} / {c:.prec$}"),
        None => "n/a".into(),
    }
}

fn report(x: &Experiment, cells: &[Cell], seeds: u32, unavailable: &[(String, String)]) -> String {
    // The headline comparisons are between modes under the reference (first) variant.
    let head: Vec<Cell> = cells
        .iter()
        .filter(|c| c.variant == x.variants[0].name)
        .cloned()
        .collect();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Multi-target search: steps and energy (min / mean / max over {seeds} seeds)\n"
    );
    let _ = writeln!(s, "Energy is the total path length of all robots, x 10^4. Steps are counted over completed runs; censored runs (max_ticks = {} reached) are counted apart, never dropped silently.\n", x.max_ticks);
    let _ = writeln!(s, "\"mean steps, censored at cap\" counts every run, a censored one at the cap ({}): marked >= it is a lower bound on the true mean whenever a run was censored; \"completed\" is the share of runs that found every target.\n", x.max_ticks);
    let _ = writeln!(s, "| N | mode | runs | censored | completed | steps (ours) | mean steps, censored at cap | steps (paper) | energy (ours) | energy (paper) | energy / robot-step |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|");
    for c in cells {
        let completed = format!("{:.0} %", 100.0 * c.completion_rate);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.robots,
            if c.variant.is_empty() {
                c.mode.clone()
            } else {
                format!("{} ({})", c.mode, c.variant)
            },
            c.runs,
            c.censored,
            completed,
            fmt3(c.steps, 0),
            fmt_at_cap(c),
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
    if x.modes.len() < 2 {
        return s;
    }
    let _ = writeln!(
        s,
        "\n## Headline comparisons (docs/search.md 4.6: relative reduction of the summed means)\n"
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
            pct(improvement(&head, &ours, &other, false, false)),
            pct(improvement(&head, &ours, &other, false, true)),
            pct(improvement(&head, &ours, &other, true, false)),
            pct(improvement(&head, &ours, &other, true, true)),
        );
    }
    // Does BT have the fewest mean steps at every N?
    let mut verdicts = Vec::new();
    for &n in &x.robots {
        let at: Vec<&Cell> = head
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

/// Improvement of `ours` over `other` (docs/search.md 4.6) with the per-cell mean `value`.
fn improvement_by(
    cells: &[&Cell],
    ours: &[&str],
    other: &[&str],
    value: &dyn Fn(&Cell) -> Option<f64>,
) -> Option<f64> {
    let total = |modes: &[&str]| -> Option<f64> {
        let mut sum = 0.0;
        for c in cells.iter().filter(|c| modes.contains(&c.mode.as_str())) {
            sum += value(c)?;
        }
        (sum > 0.0).then_some(sum)
    };
    let (o, t) = (total(ours)?, total(other)?);
    Some((t - o) / t * 100.0)
}

/// One row per variant (a sensitivity table): censored runs, BT's mean steps and energy summed
/// over the swarm sizes, and the three headline gaps (BSOA vs SVF, TPEPSO vs EPSO, BT vs BE)
/// the paper's way. Steps count every run, a censored one at the cap (a lower bound then);
/// energy is over the completed runs.
fn sensitivity_report(x: &Experiment, cells: &[Cell]) -> String {
    let mut s = String::new();
    let ns: Vec<String> = x.robots.iter().map(|n| n.to_string()).collect();
    let _ = writeln!(
        s,
        "\n## Sensitivity: each variant against {:?} (sums over N = {})\n\n\
         Steps: mean over every run, a censored run counted at the cap ({}); energy (x 10^4): \
         mean over the completed runs. Gaps: relative reduction of the summed means \
         (docs/search.md 4.6), steps / energy.\n\n\
         | variant | runs | censored | BT steps | vs ref | BT energy | vs ref | BSOA vs SVF | TPEPSO vs EPSO | BT vs BE |\n\
         |---|---|---|---|---|---|---|---|---|---|",
        x.variants[0].name,
        ns.join(" / "),
        x.max_ticks
    );
    let steps = |c: &Cell| Some(c.steps_mean_censored_at_cap);
    let energy = |c: &Cell| c.energy_e4.map(|e| e[1]);
    let paper_steps = |c: &Cell| c.paper.as_ref().map(|p| p.steps[1]);
    let paper_energy = |c: &Cell| c.paper.as_ref().map(|p| p.energy[1]);
    let pct = |v: Option<f64>| v.map_or("n/a".to_string(), |v| format!("{v:.1}"));
    let gaps =
        |of: &[&Cell], st: &dyn Fn(&Cell) -> Option<f64>, en: &dyn Fn(&Cell) -> Option<f64>| {
            [
                (vec!["BT", "BE", "BA"], vec!["ST", "SE", "SA"]),
                (vec!["BT", "ST"], vec!["BE", "SE"]),
                (vec!["BT"], vec!["BE"]),
            ]
            .iter()
            .map(|(o, t)| {
                format!(
                    "{} / {} %",
                    pct(improvement_by(of, o, t, st)),
                    pct(improvement_by(of, o, t, en))
                )
            })
            .collect::<Vec<_>>()
        };
    let bt = |of: &[&Cell], f: &dyn Fn(&Cell) -> Option<f64>| -> Option<f64> {
        let v: Option<Vec<f64>> = of.iter().filter(|c| c.mode == "BT").map(|c| f(c)).collect();
        v.filter(|v| !v.is_empty()).map(|v| v.iter().sum())
    };
    let of_variant =
        |name: &str| -> Vec<&Cell> { cells.iter().filter(|c| c.variant == name).collect() };
    let reference = of_variant(&x.variants[0].name);
    let (ref_steps, ref_energy) = (bt(&reference, &steps), bt(&reference, &energy));
    let rel = |v: Option<f64>, r: Option<f64>| match (v, r) {
        (Some(v), Some(r)) if r > 0.0 => format!("{:+.1} %", (v / r - 1.0) * 100.0),
        _ => "n/a".into(),
    };
    for v in &x.variants {
        let of = of_variant(&v.name);
        if of.is_empty() {
            continue;
        }
        let runs: usize = of.iter().map(|c| c.runs).sum();
        let censored: usize = of.iter().map(|c| c.censored).sum();
        let (st, en) = (bt(&of, &steps), bt(&of, &energy));
        let g = gaps(&of, &steps, &energy);
        let lb = if of
            .iter()
            .any(|c| c.mode == "BT" && c.steps_mean_is_lower_bound)
        {
            ">= "
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "| {} | {runs} | {censored} | {lb}{} | {} | {} | {} | {} | {} | {} |",
            v.name,
            st.map_or("n/a".into(), |v| format!("{v:.0}")),
            rel(st, ref_steps),
            en.map_or("n/a".into(), |v| format!("{v:.2}")),
            rel(en, ref_energy),
            g[0],
            g[1],
            g[2],
        );
    }
    if reference.iter().any(|c| c.paper.is_some()) {
        let g = gaps(&reference, &paper_steps, &paper_energy);
        let _ = writeln!(
            s,
            "| paper's Table 5 (same N) | | | {} | | {} | | {} | {} | {} |",
            bt(&reference, &paper_steps).map_or("n/a".into(), |v| format!("{v:.0}")),
            bt(&reference, &paper_energy).map_or("n/a".into(), |v| format!("{v:.2}")),
            g[0],
            g[1],
            g[2],
        );
    }
    s
}

/// Per (N, mode): each variant's completed runs and its slowdown against the first variant,
/// seed by seed (only seeds both completed), so layouts are compared with themselves.
fn variants_report(x: &Experiment, results: &[RunResult]) -> String {
    let mut s = String::new();
    let reference = &x.variants[0].name;
    let _ = writeln!(
        s,
        "\n## Variants against {reference:?} (same seeds)\n\n\
         | N | mode | variant | all targets found | robots killed / restarted (mean) | mean steps | slowdown vs {reference:?} (paired seeds) |\n\
         |---|---|---|---|---|---|---|"
    );
    for &n in &x.robots {
        for mode in &x.modes {
            let of = |v: &str| -> Vec<&RunResult> {
                results
                    .iter()
                    .filter(|r| r.robots == n && &r.mode == mode && r.variant == v)
                    .collect()
            };
            let base = of(reference);
            for v in &x.variants {
                let rs = of(&v.name);
                if rs.is_empty() {
                    continue;
                }
                let done: Vec<&&RunResult> = rs.iter().filter(|r| r.steps.is_some()).collect();
                let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
                let steps: Vec<f64> = done.iter().map(|r| r.steps.unwrap() as f64).collect();
                let paired: Vec<(f64, f64)> = done
                    .iter()
                    .filter_map(|r| {
                        let b = base.iter().find(|b| b.seed == r.seed)?.steps?;
                        Some((b as f64, r.steps.unwrap() as f64))
                    })
                    .collect();
                let slowdown = if paired.is_empty() {
                    "n/a".to_string()
                } else {
                    let b: f64 = paired.iter().map(|p| p.0).sum();
                    let o: f64 = paired.iter().map(|p| p.1).sum();
                    format!(
                        "{:+.1} % over {} seeds",
                        (o / b - 1.0) * 100.0,
                        paired.len()
                    )
                };
                let killed = mean(&rs.iter().map(|r| r.faults as f64).collect::<Vec<_>>());
                let restarted = mean(&rs.iter().map(|r| r.restarted as f64).collect::<Vec<_>>());
                let _ = writeln!(
                    s,
                    "| {n} | {mode} | {} | {} / {} ({:.0} %) | {killed:.1} / {restarted:.1} | {} | {slowdown} |",
                    v.name,
                    done.len(),
                    rs.len(),
                    100.0 * done.len() as f64 / rs.len() as f64,
                    if steps.is_empty() { "n/a".into() } else { format!("{:.0}", mean(&steps)) },
                );
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(seed: u64, steps: Option<u64>) -> RunResult {
        RunResult {
            mode: "BA".into(),
            variant: String::new(),
            robots: 20,
            seed,
            steps,
            found: if steps.is_some() { 10 } else { 9 },
            targets: 10,
            energy: 1e4,
            ticks: steps.unwrap_or(3000),
            faults: 0,
            restarted: 0,
        }
    }

    /// Issue 14 item 11's case by hand: completed runs 500 and 640 (mean 570), one censored
    /// at the 3,000 cap: (500 + 640 + 3000) / 3 = 1380, a lower bound; 2 of 3 completed.
    #[test]
    fn censored_runs_count_at_the_cap_as_a_lower_bound() {
        let x = Experiment {
            scenario: "s.toml".into(),
            modes: vec!["BA".into()],
            robots: vec![20],
            kind: None,
            seeds: SeedSpec::Count(3),
            first_seed: 1,
            max_ticks: 3000,
            paper: vec![],
            variants: vec![Variant::default()],
        };
        let cells = tabulate(&x, &[run(1, Some(500)), run(2, Some(640)), run(3, None)]);
        let c = &cells[0];
        assert_eq!(c.censored, 1);
        assert_eq!(c.steps.unwrap()[1], 570.0);
        assert_eq!(c.steps_mean_censored_at_cap, 1380.0);
        assert!(c.steps_mean_is_lower_bound);
        assert!((c.completion_rate - 2.0 / 3.0).abs() < 1e-12);
        let md = report(&x, &cells, 3, &[]);
        assert!(
            md.contains("| 20 | BA | 3 | 1 | 67 % | 500 / 570 / 640 | >= 1380 |"),
            "{md}"
        );
        // No censored run: the two means agree and neither is a bound.
        let cells = tabulate(&x, &[run(1, Some(500)), run(2, Some(640))]);
        assert_eq!(cells[0].steps_mean_censored_at_cap, 570.0);
        assert!(!cells[0].steps_mean_is_lower_bound);
        assert_eq!(fmt_at_cap(&cells[0]), "570");
    }
}
