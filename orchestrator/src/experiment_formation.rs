//! `orchestrator experiment FILE` for the formation paper (docs/formation.md 4): a file with
//! `kind = "formation"` names one of its tables, whose runs are made here (in-process, in
//! parallel) and printed beside the paper's numbers:
//!
//! - `table1`: scenario 1 (the same starts, the template given in `placements` orientations:
//!   "different desired pattern positions") and scenario 2 (the same pattern, `seeds` random
//!   starts), the proposed model (with rotation) against ref. \[10\] (theta = 0): mean K, T, L
//!   and the reductions.
//! - `table2`: in `groups` start groups, the optimum against 3 perturbed feasible parameter sets.
//! - `table3`: the letters n and r with theta restricted: theta* (and the run's K, L).
//! - `one-shot`: section 3.2, the assignment once against every step: L, K, reassignments;
//!   and Fig. 9 (each robot's distance to its slot against k) as an SVG of the first seed.
//!
//! T is reported as simulated time K tau (the paper's T is unexplained wall time, spec 4.6).

use crate::inprocess;
use agent::behaviours::formation::parse_params;
use agent::formation::constraints::PatternConstraints;
use agent::formation::optimise::optimise_in;
use agent::formation::{Template, Transform};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use swarm::geometry::Vec2;
use swarm::scenario::Scenario;
use swarm::sections::formation::{PatternChoice, Reassignment};

/// A formation experiment file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FormationExperiment {
    /// Must be "formation".
    pub kind: String,
    /// "table1", "table2", "table3" or "one-shot".
    pub table: String,
    /// Base scenario, relative to the experiment file.
    pub scenario: PathBuf,
    /// Scenario 2 / one-shot / table 2: seeds first_seed .. first_seed + seeds.
    #[serde(default = "ten")]
    pub seeds: u32,
    #[serde(default = "one")]
    pub first_seed: u64,
    /// Scenario 1: the template turned by k * 360 / placements degrees, k = 0 .. placements.
    #[serde(default = "ten")]
    pub placements: u32,
    /// Table 3: the scenarios of the letters (relative to the file).
    #[serde(default)]
    pub letters: Vec<PathBuf>,
    /// Where results go (relative to the working directory): results/formation-<table>.md.
    #[serde(default = "results")]
    pub results: PathBuf,
}

fn ten() -> u32 {
    10
}
fn one() -> u64 {
    1
}
fn results() -> PathBuf {
    PathBuf::from("results")
}

/// Whether `path` is a formation experiment file (`kind = "formation"`).
/// One run's figures.
#[derive(Debug, Clone, Serialize)]
pub struct FormationRun {
    pub label: String,
    pub group: String,
    pub seed: u64,
    pub formed: bool,
    pub k: Option<u64>,
    pub t: Option<f64>,
    pub l: f64,
    pub reassignments: u64,
    pub overlapping_pairs: u64,
    pub min_robot_clearance: f64,
    pub min_obstacle_clearance: f64,
    pub optimiser_seconds: f64,
    pub optimiser_gap: f64,
    #[serde(skip)]
    pub series: Option<Vec<Vec<f64>>>,
}

struct Job {
    label: String,
    group: String,
    sc: Scenario,
}

fn run_all(jobs: Vec<Job>, quiet: bool) -> Result<Vec<FormationRun>, String> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<(usize, Result<FormationRun, String>)>> = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let id = crate::runid::new_run_id();
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(job) = jobs.get(i) else { break };
                let r = inprocess::run(&job.sc, None, &format!("{id}-f{i}"), 1, &mut |_| {})
                    .map_err(|e| e.to_string())
                    .and_then(|s| serde_json::to_value(&s).map_err(|e| e.to_string()))
                    .map(|s| figures(job, &s));
                if !quiet {
                    eprintln!("run {}/{}: {} {}", i + 1, jobs.len(), job.group, job.label);
                }
                out.lock().expect("lock").push((i, r));
            });
        }
    });
    let mut v = out.into_inner().expect("lock");
    v.sort_by_key(|x| x.0);
    v.into_iter().map(|x| x.1).collect()
}

fn figures(job: &Job, s: &serde_json::Value) -> FormationRun {
    let f = &s["mission"]["formation"];
    let plan = &f["plans"][0];
    FormationRun {
        label: job.label.clone(),
        group: job.group.clone(),
        seed: job.sc.run.seed,
        formed: f["formed"].as_bool().unwrap_or(false),
        k: f["iterations"].as_u64(),
        t: f["simulated_time"].as_f64(),
        l: f["path_length"].as_f64().unwrap_or(f64::NAN),
        reassignments: f["reassignments"].as_u64().unwrap_or(0),
        overlapping_pairs: f["overlapping_pairs"].as_u64().unwrap_or(0),
        min_robot_clearance: f["min_robot_clearance"].as_f64().unwrap_or(f64::NAN),
        min_obstacle_clearance: f["min_obstacle_clearance"].as_f64().unwrap_or(f64::NAN),
        optimiser_seconds: plan["seconds"].as_f64().unwrap_or(0.0),
        optimiser_gap: plan["gap"].as_f64().unwrap_or(0.0),
        series: series_of(&f["distance_to_slot"]),
    }
}

/// summary.json's `distance_to_slot` (per robot, per tick; null where the robot had no slot
/// yet: the world's NaN), with the nulls as NaN. Read as plain numbers, the first null failed
/// the whole series and no Fig. 9 was written.
fn series_of(v: &serde_json::Value) -> Option<Vec<Vec<f64>>> {
    let rows: Vec<Vec<Option<f64>>> = serde_json::from_value(v.clone()).ok()?;
    Some(
        rows.into_iter()
            .map(|r| r.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect())
            .collect(),
    )
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = v.collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Mean K, T, L over the formed runs, and how many formed.
fn kt_l(runs: &[&FormationRun]) -> (f64, f64, f64, usize) {
    let done: Vec<&&FormationRun> = runs.iter().filter(|r| r.formed).collect();
    (
        mean(done.iter().filter_map(|r| r.k.map(|k| k as f64))),
        mean(done.iter().filter_map(|r| r.t)),
        mean(done.iter().map(|r| r.l)),
        done.len(),
    )
}

fn pct(ours: f64, base: f64) -> f64 {
    100.0 * (base - ours) / base
}

fn with(sc: &Scenario, edit: impl Fn(&mut Scenario)) -> Result<Scenario, String> {
    let mut s = sc.clone();
    edit(&mut s);
    crate::prepare::prepare_from(&mut s, "formation experiment").map_err(|e| e.to_string())?;
    Ok(s)
}

fn section(sc: &mut Scenario) -> &mut swarm::sections::formation::FormationSection {
    sc.formation.get_or_insert_with(Default::default)
}

/// The world's seeded start positions for `sc`.
fn starts(sc: &Scenario) -> Result<Vec<Vec2>, String> {
    let w = world::World::new(sc).map_err(|e| e.to_string())?;
    Ok(w.start.iter().map(|p| Vec2::new(p[0], p[1])).collect())
}

pub fn run(file: &Path, quiet: bool) -> Result<i32, String> {
    let text = std::fs::read_to_string(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let mut x: FormationExperiment =
        toml::from_str(&text).map_err(|e| format!("{}: {}", file.display(), e.message()))?;
    let dir = file.parent().unwrap_or(Path::new(".")).to_path_buf();
    x.scenario = dir.join(&x.scenario);
    let base = Scenario::load(&x.scenario).map_err(|e| e.to_string())?;
    let (md, runs) = match x.table.as_str() {
        "table1" => table1(&x, &base, quiet)?,
        "table2" => table2(&x, &base, quiet)?,
        "table3" => table3(&x, &dir, quiet)?,
        "one-shot" => one_shot(&x, &base, quiet)?,
        t => return Err(format!("{}: table = {t:?} is unknown: allowed \"table1\", \"table2\", \"table3\", \"one-shot\"", file.display())),
    };
    let bad: u64 = runs.iter().map(|r| r.overlapping_pairs).sum();
    let md = format!(
        "{md}\nRuns: {}, formed: {}, overlapping robot pairs summed over every run and tick: {bad}.\nMade by `orchestrator experiment {}`.\n",
        runs.len(),
        runs.iter().filter(|r| r.formed).count(),
        file.display()
    );
    print!("{md}");
    std::fs::create_dir_all(&x.results).map_err(|e| e.to_string())?;
    let stem = format!("formation-{}", x.table);
    std::fs::write(x.results.join(format!("{stem}.md")), &md).map_err(|e| e.to_string())?;
    std::fs::write(
        x.results.join(format!("{stem}.json")),
        serde_json::to_string_pretty(&runs).map_err(|e| e.to_string())?,
    )
    .map_err(|e| e.to_string())?;
    println!("written: {}/{stem}.md, {stem}.json", x.results.display());
    Ok(0)
}

fn rotated(points: &[[f64; 2]], angle: f64) -> Vec<[f64; 2]> {
    let (s, c) = angle.sin_cos();
    points
        .iter()
        .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
        .collect()
}

fn table1(
    x: &FormationExperiment,
    base: &Scenario,
    quiet: bool,
) -> Result<(String, Vec<FormationRun>), String> {
    let n = base.run.robots as usize;
    let template = base
        .formation
        .clone()
        .unwrap_or_default()
        .template_points(n)?;
    let mut jobs = Vec::new();
    for (method, pattern) in [
        ("ours", PatternChoice::Optimise),
        ("baseline [10]", PatternChoice::NoRotation),
    ] {
        for k in 0..x.placements {
            let angle = std::f64::consts::TAU * k as f64 / x.placements as f64;
            let t = rotated(&template, angle);
            jobs.push(Job {
                label: method.into(),
                group: "scenario 1".into(),
                sc: with(base, |s| {
                    s.run.seed = x.first_seed;
                    let f = section(s);
                    f.pattern = pattern;
                    f.template = t.clone();
                })?,
            });
        }
        for seed in 0..x.seeds as u64 {
            jobs.push(Job {
                label: method.into(),
                group: "scenario 2".into(),
                sc: with(base, |s| {
                    s.run.seed = x.first_seed + seed;
                    section(s).pattern = pattern;
                })?,
            });
        }
    }
    let runs = run_all(jobs, quiet)?;
    let pick = |g: &str, l: &str| -> Vec<&FormationRun> {
        runs.iter()
            .filter(|r| r.group == g && r.label == l)
            .collect()
    };
    let mut md = String::from(
        "# Formation, Table 1: ours (with rotation) vs ref. [10] (no rotation)\n\n\
         Scenario 1: the same starts (seed first_seed), the template given in 10 orientations \
         (\"different desired pattern positions\"). Scenario 2: the same template, 10 seeded starts. \
         K = ticks to completion (2 of them gathering the starts over the radio), T = K tau \
         (simulated, tau = 0.25 s), L = sum of path lengths. Means over the formed runs.\n\n\
         | scenario | algorithm | formed | K | T (s) | L | paper K | paper T | paper L |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let paper = [
        ("scenario 1", "ours", [41.3, 12.73, 35.02]),
        ("scenario 1", "baseline [10]", [45.7, 15.34, 37.89]),
        ("scenario 2", "ours", [39.5, 11.35, 33.72]),
        ("scenario 2", "baseline [10]", [43.2, 13.63, 36.30]),
    ];
    for (g, l, p) in paper {
        let rs = pick(g, l);
        let (k, t, len, done) = kt_l(&rs);
        let _ = writeln!(
            md,
            "| {g} | {l} | {done}/{} | {k:.1} | {t:.2} | {len:.2} | {} | {} | {} |",
            rs.len(),
            p[0],
            p[1],
            p[2]
        );
    }
    md.push_str("\n| scenario | K reduction | T reduction | L reduction | paper K | paper T | paper L |\n|---|---|---|---|---|---|---|\n");
    for (g, pk, pt, pl) in [
        ("scenario 1", 9.6, 17.0, 7.6),
        ("scenario 2", 8.6, 16.7, 7.1),
    ] {
        let (k1, t1, l1, _) = kt_l(&pick(g, "ours"));
        let (k0, t0, l0, _) = kt_l(&pick(g, "baseline [10]"));
        let _ = writeln!(
            md,
            "| {g} | {:.1} % | {:.1} % | {:.1} % | {pk} % | {pt} % | {pl} % |",
            pct(k1, k0),
            pct(t1, t0),
            pct(l1, l0)
        );
    }
    Ok((md, runs))
}

/// Table 2's perturbations of the optimum (alpha, d_1, d_2, theta), after the paper's rows
/// (alpha by 0.03-0.13, d by 0.03-0.2, theta by 0.04-0.07): tried in this order, kept when the
/// pattern is feasible and inside the search domain, the first 3 kept are run.
const PERTURBATIONS: [[f64; 4]; 16] = [
    [-0.03, 0.03, 0.1, 0.07],
    [-0.03, 0.13, 0.2, 0.07],
    [-0.13, 0.13, 0.2, 0.04],
    [0.03, 0.03, 0.1, 0.07],
    [0.03, 0.13, 0.2, 0.07],
    [0.13, 0.13, 0.2, 0.04],
    [-0.05, -0.1, 0.1, -0.05],
    [0.05, -0.1, 0.1, -0.05],
    [-0.1, 0.2, -0.2, 0.1],
    [0.1, 0.2, -0.2, 0.1],
    [-0.02, -0.2, -0.2, -0.1],
    [0.02, -0.2, -0.2, -0.1],
    [-0.03, 0.0, 0.0, 0.0],
    [0.0, 0.1, 0.0, 0.0],
    [0.0, 0.0, 0.1, 0.0],
    [0.0, 0.0, 0.0, 0.05],
];

/// The objective of eq. (1) at the parameters: the least sum of squared distances over sigma.
fn objective(starts: &[Vec2], targets: &[Vec2]) -> f64 {
    let mut sigma = Vec::new();
    let mut h = agent::formation::hungarian::Hungarian::new();
    if agent::formation::hungarian::assign_targets(starts, targets, &mut h, &mut sigma).is_err() {
        return f64::NAN;
    }
    sigma
        .iter()
        .enumerate()
        .map(|(i, j)| (starts[i] - targets[*j]).norm_squared())
        .sum()
}

fn table2(
    x: &FormationExperiment,
    base: &Scenario,
    quiet: bool,
) -> Result<(String, Vec<FormationRun>), String> {
    let mut jobs = Vec::new();
    let mut rows: Vec<(String, String, [f64; 4], f64)> = Vec::new();
    for g in 0..3u64 {
        let seed = x.first_seed + g;
        let sc = with(base, |s| s.run.seed = seed)?;
        let p = parse_params(&sc)?.kernels;
        let f = sc.formation.clone().unwrap_or_default();
        let template = Template {
            name: f.template_name.clone(),
            points: f.template_points(sc.run.robots as usize)?,
        };
        let starts = starts(&sc)?;
        let o = &p.optimiser;
        let best = optimise_in(&starts, &template, &p, o.alpha_range, o.theta_range)
            .map_err(|e| e.to_string())?;
        let t = best.transform;
        let opt = [t.alpha, t.d[0], t.d[1], t.theta];
        let constraints = PatternConstraints::new(&p);
        let reading = p.transform_reading;
        let cost_of = |q: [f64; 4]| {
            let tf = Transform {
                alpha: q[0],
                d: [q[1], q[2]],
                theta: q[3],
            };
            objective(&starts, &tf.targets(reading, &template))
        };
        let mut sets = vec![("optimum".to_string(), opt)];
        for d in PERTURBATIONS {
            if sets.len() == 4 {
                break;
            }
            let sign = if opt[3] < 0.0 { -1.0 } else { 1.0 };
            let q = [
                opt[0] + d[0],
                opt[1] + d[1],
                opt[2] + d[2],
                opt[3] + sign * d[3],
            ];
            let tf = Transform {
                alpha: q[0],
                d: [q[1], q[2]],
                theta: q[3],
            };
            let inside = (o.alpha_range[0]..=o.alpha_range[1]).contains(&q[0])
                && (o.theta_range[0]..=o.theta_range[1]).contains(&q[3]);
            if inside && constraints.satisfied(&tf.targets(p.transform_reading, &template)) {
                sets.push((format!("perturbed {}", sets.len()), q));
            }
        }
        for (label, q) in sets {
            rows.push((format!("group {}", g + 1), label.clone(), q, cost_of(q)));
            jobs.push(Job {
                label,
                group: format!("group {}", g + 1),
                sc: with(&sc, |s| {
                    let f = section(s);
                    f.pattern = PatternChoice::Fixed;
                    f.transform = q;
                })?,
            });
        }
    }
    let runs = run_all(jobs, quiet)?;
    let mut md = String::from(
        "# Formation, Table 2: the optimum against perturbed feasible parameters\n\n\
         Three start groups (seeds first_seed ..); in each, the optimal (alpha, d, theta) of eq. (14) \
         and up to 3 feasible perturbations of it (the paper's rows perturb alpha by 0.03-0.13, d by \
         0.03-0.2, theta by 0.04-0.07), each run with its Hungarian assignment and per-step \
         reassignment. The paper's groups have other starts, obstacles and template, so only the \
         ordering compares.\n\n\
         The objective is eq. (1) at the start positions (sum of squared distances, the \
         Hungarian assignment): the optimum's is the least, by construction.\n\n\
         | group | parameters | alpha | d | theta | objective | K | T (s) | L |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for (r, (_, _, q, cost)) in runs.iter().zip(&rows) {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} | [{:.4}, {:.4}] | {:.4} | {cost:.2} | {} | {} | {:.2} |",
            r.group,
            r.label,
            q[0],
            q[1],
            q[2],
            q[3],
            r.k.map_or("-".into(), |k| k.to_string()),
            r.t.map_or("-".into(), |t| format!("{t:.2}")),
            r.l
        );
    }
    md.push_str("\nThe paper (Table 2): group 1 optimum K 35, T 13.53, L 33.22 vs 37-42, 13.78-15.23, 33.36-34.60; group 2 optimum 46, 14.02, 41.07 vs 49-53, 14.23-14.42, 42.10-42.71; group 3 optimum 42, 10.81, 35.89 vs 47-55, 12.16-13.03, 36.33-40.14.\n");
    Ok((md, runs))
}

fn table3(
    x: &FormationExperiment,
    dir: &Path,
    quiet: bool,
) -> Result<(String, Vec<FormationRun>), String> {
    let mut md = String::from(
        "# Formation, Table 3: letters n and r with theta restricted\n\n\
         | experiment | letter | theta range | theta* (ours) | alpha* | gap | K | L | paper theta* |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let paper = [0.65, 0.26];
    let mut jobs = Vec::new();
    let mut solved = Vec::new();
    for path in &x.letters {
        let sc = Scenario::load(&dir.join(path)).map_err(|e| e.to_string())?;
        let sc = with(&sc, |s| s.run.seed = x.first_seed)?;
        let p = parse_params(&sc)?.kernels;
        let f = sc.formation.clone().unwrap_or_default();
        let template = Template {
            name: f.template_name.clone(),
            points: f.template_points(sc.run.robots as usize)?,
        };
        let o = &p.optimiser;
        let best = optimise_in(&starts(&sc)?, &template, &p, o.alpha_range, o.theta_range)
            .map_err(|e| e.to_string())?;
        solved.push((f.template_name.clone(), o.theta_range, best));
        jobs.push(Job {
            label: f.template_name.clone(),
            group: "table 3".into(),
            sc,
        });
    }
    let runs = run_all(jobs, quiet)?;
    for (i, ((name, range, best), r)) in solved.iter().zip(&runs).enumerate() {
        let _ = writeln!(
            md,
            "| {} | {name} | [{}, {}] | {:.4} | {:.4} | {:.4} | {} | {:.2} | {} |",
            i + 1,
            range[0],
            range[1],
            best.transform.theta,
            best.transform.alpha,
            best.gap,
            r.k.map_or("-".into(), |k| k.to_string()),
            r.l,
            paper.get(i).map_or("-".into(), |p| p.to_string())
        );
    }
    md.push_str("\nOur letters are our own drawings (the paper's are unpublished), so theta* need not match; a theta* on the range's edge means the unrestricted optimum lies outside it.\n");
    Ok((md, runs))
}

fn one_shot(
    x: &FormationExperiment,
    base: &Scenario,
    quiet: bool,
) -> Result<(String, Vec<FormationRun>), String> {
    let mut jobs = Vec::new();
    for (label, mode) in [
        ("per-step", Reassignment::PerStep),
        ("one-shot", Reassignment::OneShot),
    ] {
        for seed in 0..x.seeds as u64 {
            jobs.push(Job {
                label: label.into(),
                group: "section 3.2".into(),
                sc: with(base, |s| {
                    s.run.seed = x.first_seed + seed;
                    section(s).reassignment = mode;
                })?,
            });
        }
    }
    let runs = run_all(jobs, quiet)?;
    let mut md = String::from(
        "# Formation, section 3.2: the assignment every step against once\n\n\
         | assignment | formed | mean K | mean L | reassignments (total) | least robot clearance |\n|---|---|---|---|---|---|\n",
    );
    for label in ["per-step", "one-shot"] {
        let rs: Vec<&FormationRun> = runs.iter().filter(|r| r.label == label).collect();
        let (k, _, l, done) = kt_l(&rs);
        let _ = writeln!(
            md,
            "| {label} | {done}/{} | {k:.1} | {l:.2} | {} | {:.4} |",
            rs.len(),
            rs.iter().map(|r| r.reassignments).sum::<u64>(),
            rs.iter()
                .map(|r| r.min_robot_clearance)
                .fold(f64::INFINITY, f64::min)
        );
    }
    md.push_str("\nThe paper shows this only qualitatively (Figs. 8-9: shorter paths with per-step reassignment; no numbers).\n");
    // Fig. 9: the per-step run of the first seed.
    if let Some(series) = runs
        .iter()
        .find(|r| r.label == "per-step")
        .and_then(|r| r.series.clone())
    {
        std::fs::create_dir_all(&x.results).map_err(|e| e.to_string())?;
        let path = x.results.join("formation-fig9.svg");
        std::fs::write(&path, fig9(&series)).map_err(|e| e.to_string())?;
        let _ = writeln!(
            md,
            "\nFig. 9 analogue: {} (seed {}).",
            path.display(),
            x.first_seed
        );
    }
    Ok((md, runs))
}

/// Each robot's distance to its slot against k, as a plain SVG.
fn fig9(series: &[Vec<f64>]) -> String {
    let (w, h, m) = (640.0, 400.0, 50.0);
    let kmax = series.iter().map(|s| s.len()).max().unwrap_or(1).max(2) as f64;
    let ymax = series
        .iter()
        .flatten()
        .filter(|v| v.is_finite())
        .fold(1e-9f64, |a, b| a.max(*b));
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
         <text x=\"{}\" y=\"20\" text-anchor=\"middle\">Fig. 9 analogue: distance of each robot to its slot</text>\n\
         <line x1=\"{m}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n<line x1=\"{m}\" y1=\"{m}\" x2=\"{m}\" y2=\"{}\" stroke=\"black\"/>\n\
         <text x=\"{}\" y=\"{}\" text-anchor=\"middle\">k (ticks, 0 .. {})</text>\n<text x=\"12\" y=\"{}\" transform=\"rotate(-90 12 {})\" text-anchor=\"middle\">distance (0 .. {ymax:.1})</text>\n",
        w / 2.0,
        h - m,
        w - m,
        h - m,
        h - m,
        w / 2.0,
        h - 15.0,
        kmax as u64 - 1,
        h / 2.0,
        h / 2.0
    );
    for (i, robot) in series.iter().enumerate() {
        let hue = 360.0 * i as f64 / series.len().max(1) as f64;
        let pts: Vec<String> = robot
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(k, v)| {
                format!(
                    "{:.1},{:.1}",
                    m + (w - 2.0 * m) * k as f64 / (kmax - 1.0),
                    h - m - (h - 2.0 * m) * v / ymax
                )
            })
            .collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"hsl({hue:.0},70%,45%)\" stroke-width=\"1.5\" points=\"{}\"/>",
            pts.join(" ")
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fig9_series_keeps_the_ticks_before_a_slot_as_gaps_and_draws_every_robot() {
        let v = serde_json::json!([[null, 3.0, 2.0, 1.0], [null, null, 4.0, 0.5]]);
        let s = series_of(&v).expect("a series with nulls is read");
        assert!(s[0][0].is_nan() && s[1][1].is_nan());
        assert_eq!((s[0][3], s[1][2]), (1.0, 4.0));
        let svg = fig9(&s);
        assert_eq!(svg.matches("<polyline").count(), 2);
        // Robot 0 has 3 points, robot 1 has 2 (the nulls left out).
        let points: Vec<usize> = svg
            .lines()
            .filter(|l| l.starts_with("<polyline"))
            .map(|l| l.split("points=\"").nth(1).unwrap().split(' ').count())
            .collect();
        assert_eq!(points, vec![3, 2]);
        assert!(series_of(&serde_json::json!("not a series")).is_none());
    }
}
