//! `orchestrator experiment FILE` for a file with `kind = "cbca"` (configs/cbca-experiment.toml;
//! docs/hunting.md sections 8 and 14): the thesis's chapter 4 experiments.
//!
//! 1. **Examples 1 and 2 under the round radio** (the kernels, static targets, as the thesis's
//!    MATLAB runs): the temporary groups, the coalitions beside the thesis's, the idle robots,
//!    consensus rounds, messages and bytes, every method scored alike, and each robot's utility
//!    against time (Figs. 4.3, 4.5) as `utility-example1.svg` / `utility-example2.svg`.
//! 2. **Examples 1 and 2 in the hunt world** (the `cbca` behaviour, with `--executor`: the same
//!    recording as the processes): who captured what, when, and the coalition changes.
//! 3. **Figs. 4.6-4.7 as tables** (and `fig-4.6a.svg` ... `fig-4.7b.svg`): average system
//!    utility and average completion time, CBCA against the three baselines and the ablation
//!    without grouping, on seeded random instances (`agent::cbca::instance`); consensus rounds,
//!    messages and bytes with and without grouping; runs that did not converge are *censored*
//!    and counted.
//! 4. **What the thesis claims but never measured**: the kernels' convergence under radio loss
//!    (one sweep point, every level), and the hunt world under loss, with 20 % of the robots
//!    killed, and the ablations (loyalty off, grouping off), `variant_seeds` seeds a variant.

use crate::experiment::runner::{
    parse_file, tag_of, Context, Report, Row, SeedSpec, DEFAULT_FIRST_SEED,
};
use agent::behaviours::cbca::Section;
use agent::cbca::compare::{replanned_utility_curve, run_cbca, run_method, Method, MethodRun};
use agent::cbca::grouping::{temporary_groups, PriorInfo};
use agent::cbca::instance::{random_instance, InstanceParams};
use agent::cbca::model::{Robot, Task};
use agent::cbca::rounds::Radio;
use agent::cbca::CbcaParams;
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use swarm::scenario::{Check, Scenario};

/// The experiment file of CBCA.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CbcaExperiment {
    /// "cbca".
    pub kind: String,
    /// Example 1 as a runnable hunt (configs/hunt-cbca.toml), relative to the file.
    pub example1: PathBuf,
    /// Example 2 as a runnable hunt (configs/hunt-cbca-example2-hunt.toml).
    pub example2: PathBuf,
    /// The seeds of a point of the sweeps (the issue: 30): a count (from `first_seed`), a
    /// range "A..B" or a list. `--seeds` / `--runs` override it and `variant_seeds`.
    pub seeds: SeedSpec,
    /// The first seed of a count.
    #[serde(default = "first_seed")]
    pub first_seed: u64,
    /// Fig. 4.6: n_e fixed, n_r varied (the thesis gives no values).
    pub sweep_robots: Vec<usize>,
    pub sweep_robots_evaders: usize,
    /// Fig. 4.7: n_r fixed (13), n_e varied.
    pub sweep_evaders: Vec<usize>,
    pub sweep_evaders_robots: usize,
    /// The random instances' ranges (agent::cbca::instance; defaults from Tables 4.1-4.4).
    #[serde(default)]
    pub instance: InstanceParams,
    /// The kernels' loss sweep: radio loss levels, at the sweep point (n_r, n_e) below, with
    /// delays of up to `loss_max_delay` rounds when lossy.
    pub losses: Vec<f64>,
    pub loss_point: [usize; 2],
    pub loss_max_delay: u64,
    /// Utility curves (Figs. 4.3, 4.5): sampled every `utility_step` time units up to
    /// `utility_horizon`.
    pub utility_horizon: f64,
    pub utility_step: f64,
    /// The seeds of the hunt-world runs of Example 1 per variant (a count from `first_seed`,
    /// a range or a list).
    pub variant_seeds: SeedSpec,
    pub variants: Vec<crate::experiment::Variant>,
    /// Run the hunt-world sections (Examples 1 and 2 in the hunt world, the variants). Default
    /// true; configs/cbca-rounds.toml (round runs only) sets false.
    #[serde(default = "yes")]
    pub hunt_world: bool,
    /// Run the first sweeps (grouped CBCA against globally informed baselines, the SVGs of
    /// Figs. 4.6-4.7). Default true.
    #[serde(default = "yes")]
    pub legacy_sweeps: bool,
    /// Run the fair comparison (experiment_cbca_fair.rs: every algorithm under local and
    /// global information, (2.6) off and on). Default false.
    #[serde(default)]
    pub fair: bool,
    /// Kill this fraction of the robots after convergence in the round runs at `loss_point`
    /// (0: skip).
    #[serde(default)]
    pub kill_fraction: f64,
    /// Example 2 re-planned with motion (Fig. 4.5) at these radio radii (km); empty: skip.
    #[serde(default)]
    pub moving_radii: Vec<f64>,
}

fn yes() -> bool {
    true
}

fn first_seed() -> u64 {
    DEFAULT_FIRST_SEED
}

#[path = "experiment_cbca_fair.rs"]
mod fair;
#[path = "experiment_cbca_narrative.rs"]
mod narrative;

use crate::experiment::mean_sd;

fn set(v: &[usize]) -> String {
    let names: Vec<String> = v.iter().map(|i| format!("R{}", i + 1)).collect();
    format!("{{{}}}", names.join(", "))
}

/// The thesis's coalitions (Figs. 4.2b, 4.4b; spec 8.1, 8.2), by 1-based target.
const THESIS_EXAMPLE1: [(usize, &str); 4] = [
    (1, "{R3, R6, R5} (Phi1)"),
    (2, "{R1, R2, R4} (Phi2)"),
    (3, "{R7, R11, R12} (Phi3)"),
    (4, "{R8, R9, R14, R15} (Phi4)"),
];
const THESIS_EXAMPLE2: [(usize, &str); 4] = [
    (1, "{R1, R15, R5} (Phi1)"),
    (2, "{R2, R4, R6} (Phi2)"),
    (3, "{R7, R8, R9} (Phi3)"),
    (4, "{R13, R12, R11, R10} (Phi4)"),
];

/// The `[cbca]` rows of a runnable scenario.
fn kernels_of(sc: &Scenario) -> Result<(Vec<Robot>, Vec<Task>, CbcaParams), String> {
    let key = |k: &str| k.to_string();
    let c = Check { key_source: &key };
    let s = Section::of(sc, &c).map_err(|e| e.to_string())?;
    let robots = s.kernels.robots().map_err(|e| e.to_string())?;
    let tasks = s.kernels.tasks().map_err(|e| e.to_string())?;
    Ok((robots, tasks, s.kernels.params))
}

fn example_rounds(
    n: u32,
    sc: &Scenario,
    x: &CbcaExperiment,
    out: &Path,
    md: &mut String,
) -> Result<(), String> {
    let (robots, tasks, params) = kernels_of(sc)?;
    let thesis: &[(usize, &str)] = if n == 1 {
        &THESIS_EXAMPLE1
    } else {
        &THESIS_EXAMPLE2
    };
    let pos: Vec<_> = robots.iter().map(|r| r.position).collect();
    let groups = temporary_groups(&pos, params.comm_radius_km);
    let _ = writeln!(
        md,
        "## Example {n} under the round radio (kernels, static targets, perfect radio)\n"
    );
    let _ = writeln!(
        md,
        "Temporary groups at {} km: {} ({}); the thesis draws two.\n",
        params.comm_radius_km,
        groups.len(),
        groups.iter().map(|g| set(g)).collect::<Vec<_>>().join(" ")
    );
    let runs: Vec<MethodRun> = Method::ALL
        .iter()
        .map(|&m| run_method(m, &robots, &tasks, &Radio::perfect(), &params))
        .collect();
    let _ = writeln!(
        md,
        "| target | L_j | thesis | CBCA | CBCA without grouping | Sujit et al. | Kim-Baik-Lee | contract net |\n|---|---|---|---|---|---|---|---|"
    );
    for t in &tasks {
        let th = thesis.iter().find(|x| x.0 == t.id + 1).map_or("-", |x| x.1);
        let cells: Vec<String> = runs
            .iter()
            .map(|r| {
                r.allocation
                    .coalitions()
                    .get(&t.id)
                    .map_or("-".into(), |v| set(v))
            })
            .collect();
        let _ = writeln!(
            md,
            "| T{} | {} | {th} | {} |",
            t.id + 1,
            t.robots_needed,
            cells.join(" | ")
        );
    }
    let idle: Vec<usize> = runs[0]
        .allocation
        .paths
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_empty())
        .map(|(i, _)| i)
        .collect();
    let _ = writeln!(
        md,
        "\nCBCA's idle robots: {}{}.\n",
        set(&idle),
        if n == 1 { " (thesis: R10, R13)" } else { "" }
    );
    // Why: Algorithm 1's verdict on each target for each idle robot, against the winner lists
    // it converged on (the grouped run again, to hold its robots' states).
    let (grouped, _, _) = agent::cbca::compare::run_cbca(
        &robots,
        &tasks,
        agent::cbca::grouping::PriorInfo::DetectionPlusNearest,
        &Radio::perfect(),
        &params,
    );
    for r in grouped.iter().filter(|r| r.plan().path.is_empty()) {
        let why: Vec<String> = agent::cbca::idle::why_idle(r, &tasks)
            .iter()
            .map(|(j, reason)| format!("T{}: {}", j + 1, agent::cbca::idle::describe(reason)))
            .collect();
        let _ = writeln!(md, "- why R{} is idle: {}", r.id() + 1, why.join("; "));
    }
    let _ = writeln!(md);
    let _ = writeln!(
        md,
        "| method | system utility | mean completion (time units) | hunted / shelved | messages | consensus rounds | bytes broadcast |\n|---|---|---|---|---|---|---|"
    );
    for r in &runs {
        let (u, c, h) =
            r.evaluation
                .as_ref()
                .map_or(("deadlock".into(), "-".into(), "-".into()), |e| {
                    (
                        format!("{:.1}", e.system_utility),
                        format!("{:.2}", e.mean_completion),
                        format!("{} / {}", e.hunted, e.shelved),
                    )
                });
        let (rounds, bytes) = r.consensus.as_ref().map_or(("-".into(), "-".into()), |s| {
            (
                format!(
                    "{}{}",
                    s.rounds,
                    if s.converged { "" } else { " (censored)" }
                ),
                format!("{}", s.bytes),
            )
        });
        let _ = writeln!(
            md,
            "| {} | {u} | {c} | {h} | {} | {rounds} | {bytes} |",
            r.method.label(),
            r.allocation.messages
        );
    }
    // Utility against time (Figs. 4.3 / 4.5), CBCA with grouping.
    let times: Vec<f64> = (0..=((x.utility_horizon / x.utility_step).round() as usize))
        .map(|k| k as f64 * x.utility_step)
        .collect();
    let grouped = &runs[0];
    for (k, m) in grouped.merges.iter().enumerate() {
        let after = grouped
            .merges
            .get(k + 1)
            .map_or(&grouped.allocation.paths, |n| &n.paths_before);
        let shared: Vec<String> = m
            .shared
            .iter()
            .map(|(j, gs)| {
                format!(
                    "T{} ({})",
                    j + 1,
                    gs.iter().map(|g| set(g)).collect::<Vec<_>>().join(" and ")
                )
            })
            .collect();
        let switched: Vec<String> = m
            .paths_before
            .iter()
            .zip(after)
            .enumerate()
            .filter(|(_, (a, b))| a != b)
            .map(|(i, (a, b))| {
                let names = |p: &Vec<usize>| {
                    p.iter()
                        .map(|j| format!("T{}", j + 1))
                        .collect::<Vec<_>>()
                        .join(" ")
                };
                format!("R{}: [{}] -> [{}]", i + 1, names(a), names(b))
            })
            .collect();
        let _ = writeln!(
            md,
            "
Conflict merge {} (CBCA, `merge_on_conflict`): shared {}; the groups meet at t = {:.2}; paths changed: {}.",
            k + 1,
            shared.join(", "),
            m.meet_time,
            if switched.is_empty() { "none".into() } else { switched.join("; ") }
        );
    }
    if let Some(curves) = replanned_utility_curve(
        &robots,
        &tasks,
        &grouped.merges,
        &grouped.allocation.paths,
        &params,
        &times,
    ) {
        let file = format!("utility-example{n}.svg");
        let series: Vec<(String, Vec<f64>)> = curves
            .into_iter()
            .enumerate()
            .filter(|(i, _)| !runs[0].allocation.paths[*i].is_empty())
            .map(|(i, c)| (format!("R{}", i + 1), c))
            .collect();
        write_curves_svg(
            &format!("Example {n}: each robot's utility against time (CBCA)"),
            &times,
            &series,
            &out.join(&file),
        )?;
        let _ = writeln!(
            md,
            "\n![utility against time]({file})\n\nEach busy robot's utility against time (idle robots stay at 0): the reward of (4.12) decays until the task's coalition has assembled (the realised joint schedule), then stays; travel costs are counted from the start. Static targets; where the groups merge (a conflict merge above) each curve switches at the meeting time from the plan before to the plan after, so a robot whose path changed jumps there (both plans' schedules are counted from the start positions: the round runs do not move).\n"
        );
    }
    Ok(())
}

/// Utility curves as a chart (`charts::write`): one line per robot against time.
fn write_curves_svg(
    title: &str,
    times: &[f64],
    series: &[(String, Vec<f64>)],
    path: &Path,
) -> Result<(), String> {
    use crate::export::charts::{write, Chart, Point, Series};
    let chart = Chart {
        title: title.to_string(),
        x_label: "time (CBCA time units)".into(),
        y_label: "utility".into(),
        series: series
            .iter()
            .map(|(label, us)| Series {
                label: label.clone(),
                points: times
                    .iter()
                    .zip(us)
                    .map(|(&x, &u)| Point {
                        x,
                        mean: u,
                        lo: u,
                        hi: u,
                    })
                    .collect(),
                reference: false,
            })
            .collect(),
    };
    write(&chart, path)
}

/// A hunt-world run as results.csv has it (the capture time empty when not every evader was
/// captured: censored).
fn hunt_row(variant: &str, sc: &Scenario, s: &serde_json::Value) -> Row {
    let m = &s["mission"]["hunt"];
    let first = m["coalition_changes"]
        .as_array()
        .and_then(|c| c.iter().filter_map(|c| c["tick"].as_u64()).min());
    Row::new(variant, "cbca (hunt world)", sc.run.robots, sc.run.seed)
        .with("evaders", sc.hunt().evaders.len())
        .with("captured", m["captured"].as_f64())
        .with("all_captured", m["all_captured_minutes"].is_number())
        .with("all_captured_minutes", m["all_captured_minutes"].as_f64())
        .with("ticks", s["ticks"].as_u64())
        .with("first_commitment_tick", first)
        .with("messages_offered", s["messages"]["offered"].as_u64())
        .with("messages_delivered", s["messages"]["delivered"].as_u64())
        .with("bytes_delivered", s["message_bytes"]["delivered"].as_u64())
        .with(
            "robots_killed",
            s["faults"].as_array().map_or(0, |f| f.len()),
        )
}

fn ids(v: &serde_json::Value) -> String {
    let names: Vec<String> = v
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_u64())
                .map(|i| format!("R{i}"))
                .collect()
        })
        .unwrap_or_default();
    format!("{{{}}}", names.join(", "))
}

fn example_hunt(
    n: u32,
    sc: &Scenario,
    ctx: &Context,
    md: &mut String,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let s = ctx.run(sc, &format!("cbca-example{n}"))?;
    rows.push(hunt_row(&format!("example {n} (hunt world)"), sc, &s));
    let m = &s["mission"]["hunt"];
    let dt = sc.hunt().params.minutes_per_tick;
    let _ = writeln!(
        md,
        "## Example {n} in the hunt world (the `cbca` behaviour, {}, seed {})\n",
        match ctx.executor {
            crate::up::Executor::Inprocess => "in-process",
            crate::up::Executor::Processes => "with real processes",
        },
        sc.run.seed
    );
    let _ = writeln!(
        md,
        "End: {}, {} ticks ({:.1} min); captured {} of {}. Messages offered {}, delivered {}; payload bytes delivered {} ({:.0} kB).\n",
        s["end"],
        s["ticks"],
        s["ticks"].as_f64().unwrap_or(0.0) * dt,
        m["captured"],
        m["evaders"],
        s["messages"]["offered"],
        s["messages"]["delivered"],
        s["message_bytes"]["delivered"],
        s["message_bytes"]["delivered"].as_f64().unwrap_or(0.0) / 1000.0
    );
    let _ = writeln!(
        md,
        "| target | captured at (min) | by | distance it ran (km) |\n|---|---|---|---|"
    );
    for e in m["per_evader"].as_array().cloned().unwrap_or_default() {
        let _ = writeln!(
            md,
            "| T{} | {} | {} | {:.1} |",
            e["id"],
            e["capture_minutes"]
                .as_f64()
                .map_or("not captured".into(), |t| format!("{t:.2}")),
            ids(&e["captured_by"]),
            e["distance_run_km"].as_f64().unwrap_or(0.0)
        );
    }
    let changes = m["coalition_changes"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    let first = changes.iter().filter_map(|c| c["tick"].as_u64()).min();
    let _ = writeln!(
        md,
        "\nFirst commitment (a robot reports a target) at tick {}; {} changes of the reported coalitions in all (a robot reports the FIRST target of its path; the members' reports are what the mission counts).\n",
        first.map_or("-".into(), |t| t.to_string()),
        changes.len()
    );
    Ok(())
}

/// One sweep point: every method on `seeds` instances.
struct PointResult {
    /// Per method (Method::ALL order): utilities, completions, hunted, of the evaluated runs.
    utility: Vec<Vec<f64>>,
    completion: Vec<Vec<f64>>,
    hunted: Vec<Vec<f64>>,
    /// CBCA grouped / global: rounds, bytes, broadcasts, converged count, deadlocked count.
    rounds: [Vec<f64>; 2],
    bytes: [Vec<f64>; 2],
    delivered: [Vec<f64>; 2],
    censored: [usize; 2],
    deadlocked: [usize; 2],
}

fn sweep_point(
    n_r: usize,
    n_e: usize,
    seeds: &[u64],
    ip: &InstanceParams,
    params: &CbcaParams,
    figure: &str,
    rows: &mut Vec<Row>,
) -> PointResult {
    let k = Method::ALL.len();
    let mut p = PointResult {
        utility: vec![Vec::new(); k],
        completion: vec![Vec::new(); k],
        hunted: vec![Vec::new(); k],
        rounds: Default::default(),
        bytes: Default::default(),
        delivered: Default::default(),
        censored: [0; 2],
        deadlocked: [0; 2],
    };
    for &seed in seeds {
        let inst = random_instance(n_r, n_e, seed, ip, params);
        for (mi, &m) in Method::ALL.iter().enumerate() {
            let r = run_method(m, &inst.robots, &inst.tasks, &Radio::perfect(), params);
            let (e, c) = (r.evaluation.as_ref(), r.consensus.as_ref());
            rows.push(
                Row::new(figure, m.label(), n_r as u32, seed)
                    .with("targets", n_e)
                    .with("deadlocked", e.is_none())
                    .with("system_utility", e.map(|e| e.system_utility))
                    .with("mean_completion", e.map(|e| e.mean_completion))
                    .with("hunted", e.map(|e| e.hunted as f64))
                    .with("consensus_rounds", c.map(|c| c.rounds as f64))
                    .with("converged", c.map(|c| f64::from(u8::from(c.converged))))
                    .with("bytes", c.map(|c| c.bytes as f64))
                    .with("delivered", c.map(|c| c.delivered as f64)),
            );
            if let Some(s) = &r.consensus {
                p.rounds[mi].push(s.rounds as f64);
                p.bytes[mi].push(s.bytes as f64);
                p.delivered[mi].push(s.delivered as f64);
                if !s.converged {
                    p.censored[mi] += 1;
                }
            }
            match &r.evaluation {
                Some(e) => {
                    p.utility[mi].push(e.system_utility);
                    p.completion[mi].push(e.mean_completion);
                    p.hunted[mi].push(e.hunted as f64);
                }
                None if mi < 2 => p.deadlocked[mi] += 1,
                None => {}
            }
        }
    }
    p
}

fn fmt_ms(v: &[f64], digits: usize) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let (m, s) = mean_sd(v);
    format!("{m:.digits$} ± {s:.digits$}")
}

/// A figure: its number, its (n_r, n_e) points, whether n_r is the varied one.
type Fig<'a> = (&'a str, Vec<(usize, usize)>, bool);

fn sweeps(
    x: &CbcaExperiment,
    seeds: &[u64],
    params: &CbcaParams,
    ctx: &Context,
    md: &mut String,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let _ = writeln!(
        md,
        "## Figs. 4.6-4.7 as tables ({} seeds a point, mean ± sd; random instances of `agent::cbca::instance`, perfect radio)\n",
        seeds.len()
    );
    let _ = writeln!(md, "System utility: (4.1) with (4.12) taken at each task's realised start (the joint schedule: a task starts when its last member arrives), less the path costs (4.14); a target without L_j members earns nothing. Completion: the mean start time over the hunted targets (time units, 1 km of travel each). A CBCA run whose detectors did not all converge within `max_iterations` is censored: counted in its column, scored as it stood.\n");
    let figs: [Fig; 2] = [
        (
            "4.6",
            x.sweep_robots
                .iter()
                .map(|&n_r| (n_r, x.sweep_robots_evaders))
                .collect(),
            true,
        ),
        (
            "4.7",
            x.sweep_evaders
                .iter()
                .map(|&n_e| (x.sweep_evaders_robots, n_e))
                .collect(),
            false,
        ),
    ];
    use crate::export::charts::{write, Chart, Point, Series};
    for (fig, points, by_robots) in figs {
        let results: Vec<PointResult> = points
            .iter()
            .map(|&(n_r, n_e)| {
                sweep_point(
                    n_r,
                    n_e,
                    seeds,
                    &x.instance,
                    params,
                    &format!("fig {fig}"),
                    rows,
                )
            })
            .collect();
        let header: Vec<&str> = Method::ALL.iter().map(|m| m.label()).collect();
        let xs = |i: usize| -> f64 {
            if by_robots {
                points[i].0 as f64
            } else {
                points[i].1 as f64
            }
        };
        for (what, pick, digits) in [
            ("(a) average system utility", 0usize, 0usize),
            ("(b) average completion time", 1, 2),
            ("targets hunted (of n_e)", 2, 1),
        ] {
            let _ = writeln!(
                md,
                "### Fig. {fig} {what}: {}\n",
                if by_robots {
                    format!("n_e = {}, n_r varied", x.sweep_robots_evaders)
                } else {
                    format!("n_r = {}, n_e varied", x.sweep_evaders_robots)
                }
            );
            let _ = writeln!(
                md,
                "| n_r | n_e | {} |\n|---|---|{}",
                header.join(" | "),
                "---|".repeat(header.len())
            );
            for (i, r) in results.iter().enumerate() {
                let v = match pick {
                    0 => &r.utility,
                    1 => &r.completion,
                    _ => &r.hunted,
                };
                let cells: Vec<String> = v.iter().map(|s| fmt_ms(s, digits)).collect();
                let _ = writeln!(
                    md,
                    "| {} | {} | {} |",
                    points[i].0,
                    points[i].1,
                    cells.join(" | ")
                );
            }
            if pick < 2 {
                let series: Vec<Series> = Method::ALL
                    .iter()
                    .enumerate()
                    .map(|(mi, m)| Series {
                        label: m.label().to_string(),
                        points: results
                            .iter()
                            .enumerate()
                            .filter_map(|(i, r)| {
                                let v = if pick == 0 {
                                    &r.utility[mi]
                                } else {
                                    &r.completion[mi]
                                };
                                (!v.is_empty()).then(|| {
                                    let (mean, _) = mean_sd(v);
                                    Point {
                                        x: xs(i),
                                        mean,
                                        lo: v.iter().copied().fold(f64::INFINITY, f64::min),
                                        hi: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                                    }
                                })
                            })
                            .collect(),
                        reference: false,
                    })
                    .collect();
                let file = format!("fig-{fig}{}.svg", if pick == 0 { "a" } else { "b" });
                write(
                    &Chart {
                        title: format!("Fig. {fig}{}: {}", &what[..3], &what[4..]),
                        x_label: if by_robots { "n_r" } else { "n_e" }.into(),
                        y_label: if pick == 0 {
                            "system utility"
                        } else {
                            "completion time"
                        }
                        .into(),
                        series,
                    },
                    &ctx.out_file(&file)?,
                )?;
                let _ = writeln!(md, "\n![Fig. {fig}{}]({file})\n", &what[..3]);
            } else {
                let _ = writeln!(md);
            }
        }
        // Orderings.
        let means = |r: &PointResult, mi: usize, pick: usize| -> f64 {
            let v = if pick == 0 {
                &r.utility[mi]
            } else {
                &r.completion[mi]
            };
            mean_sd(v).0
        };
        let n = results.len();
        let mut lines = Vec::new();
        for (mi, m) in Method::ALL.iter().enumerate().skip(2) {
            let higher = results
                .iter()
                .filter(|r| means(r, 0, 0) > means(r, mi, 0))
                .count();
            let faster = results
                .iter()
                .filter(|r| means(r, 0, 1) < means(r, mi, 1))
                .count();
            lines.push(format!(
                "CBCA's utility above {}'s at {higher} of {n} points, its completion time below at {faster} of {n}",
                m.label()
            ));
        }
        let gaps: Vec<f64> = results
            .iter()
            .map(|r| {
                means(r, 0, 0)
                    - (2..Method::ALL.len())
                        .map(|mi| means(r, mi, 0))
                        .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect();
        let growing = gaps.windows(2).filter(|w| w[1] > w[0]).count();
        let falling_time = results
            .windows(2)
            .filter(|w| means(&w[1], 0, 1) < means(&w[0], 0, 1))
            .count();
        let _ = writeln!(
            md,
            "Orderings (Fig. {fig}): {}. CBCA's lead over the best baseline (utility): {}; it grows from one point to the next {growing} of {} times{}. CBCA's completion time falls from one point to the next {falling_time} of {} times{}.\n",
            lines.join("; "),
            gaps.iter().map(|g| format!("{g:.0}")).collect::<Vec<_>>().join(", "),
            n.saturating_sub(1),
            if by_robots { "" } else { " (thesis: the advantage grows with n_e)" },
            n.saturating_sub(1),
            if by_robots {
                " (thesis: it decreases with n_r)"
            } else {
                " (thesis: first rises slightly, then falls)"
            }
        );
        // Messages, bytes, rounds: with and without grouping.
        let _ = writeln!(
            md,
            "### Fig. {fig}: consensus cost, with and without grouping (what the thesis claims, never measured)\n"
        );
        let _ = writeln!(md, "| n_r | n_e | rounds, grouped | rounds, global | kB broadcast, grouped | kB, global | copies delivered, grouped | copies, global | censored (grouped / global) | deadlocked (grouped / global) |\n|---|---|---|---|---|---|---|---|---|---|");
        for (i, r) in results.iter().enumerate() {
            let kb = |v: &[f64]| -> Vec<f64> { v.iter().map(|b| b / 1000.0).collect() };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {} / {} |",
                points[i].0,
                points[i].1,
                fmt_ms(&r.rounds[0], 1),
                fmt_ms(&r.rounds[1], 1),
                fmt_ms(&kb(&r.bytes[0]), 0),
                fmt_ms(&kb(&r.bytes[1]), 0),
                fmt_ms(&r.delivered[0], 0),
                fmt_ms(&r.delivered[1], 0),
                r.censored[0],
                r.censored[1],
                r.deadlocked[0],
                r.deadlocked[1]
            );
        }
        let _ = writeln!(md);
    }
    Ok(())
}

fn loss_sweep(
    x: &CbcaExperiment,
    seeds: &[u64],
    params: &CbcaParams,
    md: &mut String,
    rows: &mut Vec<Row>,
) {
    let [n_r, n_e] = x.loss_point;
    let _ = writeln!(
        md,
        "## Consensus under radio loss (kernels; n_r = {n_r}, n_e = {n_e}, {} seeds a level, delays of up to {} rounds when lossy)\n",
        seeds.len(), x.loss_max_delay
    );
    let _ = writeln!(md, "| setup | loss | converged | rounds | kB broadcast | system utility | targets hunted |\n|---|---|---|---|---|---|---|");
    for (name, prior) in [
        ("grouped", PriorInfo::DetectionPlusNearest),
        ("without grouping", PriorInfo::Global),
    ] {
        for &loss in &x.losses {
            let mut conv = 0;
            let mut rounds = Vec::new();
            let mut kb = Vec::new();
            let mut util = Vec::new();
            let mut hunted = Vec::new();
            for &seed in seeds {
                let inst = random_instance(n_r, n_e, seed, &x.instance, params);
                let radio = Radio {
                    loss,
                    max_delay: if loss > 0.0 { x.loss_max_delay } else { 0 },
                    seed,
                };
                let (cbca, s, _) = run_cbca(&inst.robots, &inst.tasks, prior, &radio, params);
                conv += s.converged as usize;
                rounds.push(s.rounds as f64);
                kb.push(s.bytes as f64 / 1000.0);
                let alloc = agent::cbca::baselines::Allocation {
                    paths: cbca.iter().map(|r| r.plan().path.clone()).collect(),
                    messages: s.broadcasts,
                };
                let book = inst.tasks.iter().map(|t| (t.id, t.clone())).collect();
                let e = agent::cbca::baselines::evaluate(&inst.robots, &book, &alloc, params).ok();
                if let Some(e) = &e {
                    util.push(e.system_utility);
                    hunted.push(e.hunted as f64);
                }
                rows.push(
                    Row::new(
                        format!(
                            "radio loss, (2.6) {}",
                            if params.enforce_coverage { "on" } else { "off" }
                        ),
                        format!("CBCA, {name}"),
                        n_r as u32,
                        seed,
                    )
                    .with("targets", n_e)
                    .with("loss", loss)
                    .with("converged", s.converged)
                    .with("consensus_rounds", s.rounds as f64)
                    .with("bytes", s.bytes as f64)
                    .with("deadlocked", e.is_none())
                    .with("system_utility", e.as_ref().map(|e| e.system_utility))
                    .with("hunted", e.map(|e| e.hunted as f64)),
                );
            }
            let _ = writeln!(
                md,
                "| {name} | {loss} | {conv} of {} | {} | {} | {} | {} |",
                seeds.len(),
                fmt_ms(&rounds, 1),
                fmt_ms(&kb, 0),
                fmt_ms(&util, 0),
                fmt_ms(&hunted, 1)
            );
        }
    }
    let _ = writeln!(md);
}

fn variants(
    x: &CbcaExperiment,
    base: &Scenario,
    seeds: &[u64],
    ctx: &Context,
    md: &mut String,
    rows: &mut Vec<Row>,
) -> Result<(), String> {
    let _ = writeln!(
        md,
        "## `example1` ({}) in the hunt world under each variant ({} seeds a variant)\n",
        x.example1.display(),
        seeds.len()
    );
    let _ = writeln!(md, "A run that does not capture every evader by `run.max_ticks` ({}) is censored: it counts in 'runs capturing all' and its time is left out of the mean (the column says how many runs the mean has).\n", base.run.max_ticks);
    let _ = writeln!(md, "| variant | runs | captured (mean of {}) | runs capturing all | time to the last capture, min (mean ± sd, n) | first commitment, tick (mean) | messages offered | delivered | kB delivered | robots killed |\n|---|---|---|---|---|---|---|---|---|---|", base.hunt().evaders.len());
    // Every run's scenario first (all validated before any runs), then `--jobs` at a time.
    let mut jobs = Vec::new();
    for v in &x.variants {
        for &seed in seeds {
            let mut sc = v.scenario(base, &ctx.dir)?;
            sc.run.seed = seed;
            v.apply(&mut sc);
            crate::prepare::prepare_from(&mut sc, &ctx.name()).map_err(|e| e.to_string())?;
            jobs.push((sc, tag_of(&format!("cbca-{}-{seed}", v.name))));
        }
    }
    let mut summaries = ctx.run_all(&jobs).into_iter().zip(&jobs);
    for v in &x.variants {
        let mut captured = Vec::new();
        let mut all = 0;
        let mut times = Vec::new();
        let mut first = Vec::new();
        let mut offered = Vec::new();
        let mut delivered = Vec::new();
        let mut kb = Vec::new();
        let mut killed = Vec::new();
        for _ in seeds {
            let (s, (sc, _)) = summaries.next().expect("a summary a job");
            let s = s?;
            rows.push(hunt_row(&v.name, sc, &s));
            let m = &s["mission"]["hunt"];
            captured.push(m["captured"].as_f64().unwrap_or(0.0));
            if let Some(t) = m["all_captured_minutes"].as_f64() {
                all += 1;
                times.push(t);
            }
            if let Some(t) = m["coalition_changes"]
                .as_array()
                .and_then(|c| c.iter().filter_map(|c| c["tick"].as_u64()).min())
            {
                first.push(t as f64);
            }
            offered.push(s["messages"]["offered"].as_f64().unwrap_or(0.0));
            delivered.push(s["messages"]["delivered"].as_f64().unwrap_or(0.0));
            kb.push(s["message_bytes"]["delivered"].as_f64().unwrap_or(0.0) / 1000.0);
            killed.push(s["faults"].as_array().map_or(0, |f| f.len()) as f64);
        }
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} | {all} | {} | {:.1} | {:.0} | {:.0} | {:.0} | {:.1} |",
            v.name,
            seeds.len(),
            mean_sd(&captured).0,
            if times.is_empty() {
                "-".to_string()
            } else {
                format!(
                    "{:.1} ± {:.1} ({})",
                    mean_sd(&times).0,
                    mean_sd(&times).1,
                    times.len()
                )
            },
            mean_sd(&first).0,
            mean_sd(&offered).0,
            mean_sd(&delivered).0,
            mean_sd(&kb).0,
            mean_sd(&killed).0
        );
    }
    let _ = writeln!(
        md,
        "\nMessages are (message, receiver) pairs offered to / delivered by the shared medium (a broadcast counts once per other live agent; most are out of the 1.5 km range). kB delivered = the medium's payload bytes of the delivered pairs (summary `message_bytes.delivered`; the 40-byte header of each is not counted), so it compares with the round radio's 'copies delivered', not with its 'bytes broadcast'.\n"
    );
    Ok(())
}

pub fn run(ctx: &Context) -> Result<Report, String> {
    let x: CbcaExperiment = parse_file(&ctx.file)?;
    if x.kind != "cbca" {
        return Err(format!("{}: kind = {:?}, not \"cbca\"", ctx.name(), x.kind));
    }
    let seeds = ctx.seeds(&x.seeds, x.first_seed)?;
    let variant_seeds = ctx.seeds(&x.variant_seeds, x.first_seed)?;
    let name = ctx.name();
    let load = |p: &Path| -> Result<Scenario, String> {
        let mut sc = Scenario::load(&ctx.dir.join(p)).map_err(|e| e.to_string())?;
        crate::prepare::prepare_from(&mut sc, &name).map_err(|e| e.to_string())?;
        Ok(sc)
    };
    let ex1 = load(&x.example1)?;
    let ex2 = load(&x.example2)?;
    let out = ctx.out_dir()?;
    let mut md = format!("# CBCA, thesis 003 chapter 4 (`orchestrator experiment {name}`)\n\n");
    let mut rows = Vec::new();
    example_rounds(1, &ex1, &x, out, &mut md)?;
    example_rounds(2, &ex2, &x, out, &mut md)?;
    if !x.moving_radii.is_empty() {
        let (robots, tasks, params) = kernels_of(&ex2)?;
        // Our CBCA's start, then the thesis's first allocation (experiment_cbca_narrative.rs).
        for section in [fair::example2_moving, narrative::example2_narrative] {
            section(
                &robots,
                &tasks,
                &params,
                &x.moving_radii,
                out,
                &mut md,
                &write_curves_svg,
            )?;
        }
    }
    if x.hunt_world {
        example_hunt(1, &ex1, ctx, &mut md, &mut rows)?;
        example_hunt(2, &ex2, ctx, &mut md, &mut rows)?;
    }
    let (_, _, params) = kernels_of(&ex1)?;
    if x.legacy_sweeps {
        sweeps(&x, &seeds, &params, ctx, &mut md, &mut rows)?;
    }
    if x.fair {
        let robots_points: Vec<(usize, usize)> = x
            .sweep_robots
            .iter()
            .map(|&n_r| (n_r, x.sweep_robots_evaders))
            .collect();
        let evaders_points: Vec<(usize, usize)> = x
            .sweep_evaders
            .iter()
            .map(|&n_e| (x.sweep_evaders_robots, n_e))
            .collect();
        fair::fair_sweeps(
            &seeds,
            &robots_points,
            &evaders_points,
            &x.instance,
            &params,
            &mut md,
            &mut rows,
        );
    }
    for cover in [false, true] {
        let p = CbcaParams {
            enforce_coverage: cover,
            ..params.clone()
        };
        let _ = writeln!(
            md,
            "(The next section with (2.6) {}.)\n",
            if cover { "on" } else { "off" }
        );
        loss_sweep(&x, &seeds, &p, &mut md, &mut rows);
        if x.kill_fraction > 0.0 {
            fair::kill_sweep(
                &seeds,
                x.loss_point,
                &x.losses,
                x.loss_max_delay,
                x.kill_fraction,
                &x.instance,
                &p,
                &mut md,
                &mut rows,
            );
        }
        if !x.fair {
            break;
        }
    }
    if x.hunt_world {
        variants(&x, &ex1, &variant_seeds, ctx, &mut md, &mut rows)?;
    }
    Ok(Report {
        md,
        rows,
        ..Report::default()
    })
}
