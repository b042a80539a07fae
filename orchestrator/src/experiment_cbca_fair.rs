//! The round-run parts of `orchestrator experiment` for CBCA added by issue 18's last items
//! (docs/hunting.md 14.4): Figs. 4.6-4.7 with every method under the same information and the
//! same constraints ([`fair_sweeps`]), the consensus cost with and without grouping under each,
//! robots killed after convergence ([`kill_sweep`]), and Example 2 re-planned with motion,
//! loyalty and compensation (Fig. 4.5, [`example2_moving`]).

use agent::cbca::compare::{complete_graph, run_cbca, run_fair, Algorithm, Information};
use agent::cbca::consensus::CbcaRobot;
use agent::cbca::grouping::{comm_graph, PriorInfo};
use agent::cbca::instance::{random_instance, InstanceParams};
use agent::cbca::model::{Robot, RobotId, Task, TaskId};
use agent::cbca::moving_rounds::{run_moving, MovingParams, MovingRun};
use agent::cbca::narrative_thesis::decision_cells;
use agent::cbca::rounds::{run, Radio};
use agent::cbca::CbcaParams;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::fmt::Write as _;
use std::path::Path;

use crate::experiment::mean_sd;
use crate::experiment::runner::Row;

fn fmt_ms(v: &[f64], digits: usize) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let (m, s) = mean_sd(v);
    format!("{m:.digits$} ± {s:.digits$}")
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        mean_sd(v).0
    }
}

/// Per (information, algorithm): the scored runs of one point.
#[derive(Default, Clone)]
struct Cell {
    utility: Vec<f64>,
    completion: Vec<f64>,
    hunted: Vec<f64>,
    deadlocked: usize,
    rounds: Vec<f64>,
    kb: Vec<f64>,
    delivered: Vec<f64>,
    censored: usize,
}

/// The runs of one point; a row each (`figure`: the rows' variant).
fn point(
    n_r: usize,
    n_e: usize,
    seeds: &[u64],
    ip: &InstanceParams,
    p: &CbcaParams,
    figure: &str,
    rows: &mut Vec<Row>,
) -> Vec<Cell> {
    let mut cells = vec![Cell::default(); Information::ALL.len() * Algorithm::ALL.len()];
    for &seed in seeds {
        let inst = random_instance(n_r, n_e, seed, ip, p);
        for (ii, &info) in Information::ALL.iter().enumerate() {
            for (ai, &a) in Algorithm::ALL.iter().enumerate() {
                let r = run_fair(a, info, &inst.robots, &inst.tasks, &Radio::perfect(), p);
                let c = &mut cells[ii * Algorithm::ALL.len() + ai];
                let info_name = if info == Information::Local {
                    "local"
                } else {
                    "global"
                };
                let e = r.evaluation.as_ref();
                let s = r.consensus.as_ref();
                rows.push(
                    Row::new(
                        figure,
                        format!("{}, {info_name}", a.label()),
                        n_r as u32,
                        seed,
                    )
                    .with("targets", n_e)
                    .with("deadlocked", e.is_none())
                    .with("system_utility", e.map(|e| e.system_utility))
                    .with("mean_completion", e.map(|e| e.mean_completion))
                    .with("hunted", e.map(|e| e.hunted as f64))
                    .with("consensus_rounds", s.map(|s| s.rounds as f64))
                    .with("converged", s.map(|s| f64::from(u8::from(s.converged))))
                    .with("bytes", s.map(|s| s.bytes as f64))
                    .with("delivered", s.map(|s| s.delivered as f64)),
                );
                match &r.evaluation {
                    Some(e) => {
                        c.utility.push(e.system_utility);
                        c.completion.push(e.mean_completion);
                        c.hunted.push(e.hunted as f64);
                    }
                    None => c.deadlocked += 1,
                }
                if let Some(s) = &r.consensus {
                    c.rounds.push(s.rounds as f64);
                    c.kb.push(s.bytes as f64 / 1000.0);
                    c.delivered.push(s.delivered as f64);
                    c.censored += usize::from(!s.converged);
                }
            }
        }
    }
    cells
}

/// Figs. 4.6-4.7 as tables, every algorithm under both informations, with (2.6) off and on.
pub fn fair_sweeps(
    seeds: &[u64],
    robots_points: &[(usize, usize)],
    evaders_points: &[(usize, usize)],
    ip: &InstanceParams,
    base: &CbcaParams,
    md: &mut String,
    rows: &mut Vec<Row>,
) {
    let _ = writeln!(
        md,
        "## Figs. 4.6-4.7, the fair comparison ({} seeds a point, mean ± sd, perfect radio)\n",
        seeds.len()
    );
    let _ = writeln!(md, "Every algorithm under the same information and the same constraints. *Local*: the 1.5 km temporary groups, each knowing its members' detections (1.2 km) plus the undetected targets they are nearest to; groups that claim a common target merge and plan again (CBCA: `merge_on_conflict`; baselines: `agent::cbca::baselines::local`). *Global*: every robot hears every other and knows every target (CBCA without grouping; Sujit et al. with its range limit lifted). (2.6) *on*: CBCA enforces it in Algorithms 1 and 2, a baseline's full coalition that does not cover E_j is shelved. Scored alike (`baselines::evaluate`). Instances and seeds as the sweeps above.\n");
    let labels: Vec<String> = Information::ALL
        .iter()
        .flat_map(|i| {
            Algorithm::ALL.iter().map(move |a| {
                format!(
                    "{}, {}",
                    a.label(),
                    if *i == Information::Local {
                        "local"
                    } else {
                        "global"
                    }
                )
            })
        })
        .collect();
    for cover in [false, true] {
        let p = CbcaParams {
            enforce_coverage: cover,
            ..base.clone()
        };
        for (fig, points) in [("4.6", robots_points), ("4.7", evaders_points)] {
            let results: Vec<Vec<Cell>> = points
                .iter()
                .map(|&(n_r, n_e)| {
                    let figure =
                        format!("fair fig {fig}, (2.6) {}", if cover { "on" } else { "off" });
                    point(n_r, n_e, seeds, ip, &p, &figure, rows)
                })
                .collect();
            for (what, pick, digits) in [
                ("(a) average system utility", 0usize, 0usize),
                ("(b) average completion time", 1, 2),
                ("targets hunted (of n_e)", 2, 1),
            ] {
                let _ = writeln!(
                    md,
                    "### Fig. {fig} {what}, (2.6) {}\n",
                    if cover { "on" } else { "off" }
                );
                let _ = writeln!(
                    md,
                    "| n_r | n_e | {} |\n|---|---|{}",
                    labels.join(" | "),
                    "---|".repeat(labels.len())
                );
                for (k, cells) in results.iter().enumerate() {
                    let v: Vec<String> = cells
                        .iter()
                        .map(|c| {
                            fmt_ms(
                                match pick {
                                    0 => &c.utility,
                                    1 => &c.completion,
                                    _ => &c.hunted,
                                },
                                digits,
                            )
                        })
                        .collect();
                    let _ = writeln!(
                        md,
                        "| {} | {} | {} |",
                        points[k].0,
                        points[k].1,
                        v.join(" | ")
                    );
                }
                let _ = writeln!(md);
            }
            // Orderings: CBCA against each baseline under the same information.
            let n = results.len();
            let mut lines = Vec::new();
            for (ii, info) in Information::ALL.iter().enumerate() {
                fn at(cells: &[Cell], ii: usize, ai: usize) -> &Cell {
                    &cells[ii * Algorithm::ALL.len() + ai]
                }
                for (ai, a) in Algorithm::ALL.iter().enumerate().skip(1) {
                    let higher = results
                        .iter()
                        .filter(|c| mean(&at(c, ii, 0).utility) > mean(&at(c, ii, ai).utility))
                        .count();
                    let faster = results
                        .iter()
                        .filter(|c| {
                            mean(&at(c, ii, 0).completion) < mean(&at(c, ii, ai).completion)
                        })
                        .count();
                    lines.push(format!(
                        "{}: CBCA's utility above {}'s at {higher} of {n}, completion below at {faster} of {n}",
                        if *info == Information::Local { "local" } else { "global" },
                        a.label()
                    ));
                }
            }
            let local_above = results
                .iter()
                .filter(|c| mean(&c[0].utility) > mean(&c[Algorithm::ALL.len()].utility))
                .count();
            let dead: Vec<String> = results
                .iter()
                .map(|c| c.iter().map(|x| x.deadlocked).sum::<usize>().to_string())
                .collect();
            let _ = writeln!(
                md,
                "Orderings (Fig. {fig}, (2.6) {}): {}. CBCA with grouping above CBCA without at {local_above} of {n}. Deadlocked runs (all columns) per point: {}.\n",
                if cover { "on" } else { "off" },
                lines.join("; "),
                dead.join(", ")
            );
            // Consensus cost, with and without grouping.
            let _ = writeln!(md, "### Fig. {fig}, (2.6) {}: CBCA's consensus cost with grouping (local) and without (global)\n", if cover { "on" } else { "off" });
            let _ = writeln!(md, "| n_r | n_e | rounds, local | rounds, global | kB broadcast, local | kB, global | copies delivered, local | copies, global | censored (local / global) |\n|---|---|---|---|---|---|---|---|---|");
            for (k, c) in results.iter().enumerate() {
                let (l, g) = (&c[0], &c[Algorithm::ALL.len()]);
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} / {} |",
                    points[k].0,
                    points[k].1,
                    fmt_ms(&l.rounds, 1),
                    fmt_ms(&g.rounds, 1),
                    fmt_ms(&l.kb, 0),
                    fmt_ms(&g.kb, 0),
                    fmt_ms(&l.delivered, 0),
                    fmt_ms(&g.delivered, 0),
                    l.censored,
                    g.censored
                );
            }
            let _ = writeln!(md);
        }
    }
}

/// Round runs with 20 % of the robots killed after convergence: the survivors forget them
/// (`forget_robot`, the runtime's liveness verdict), consensus runs again over the same radio
/// graph without them; convergence and the targets hunted by the survivors.
#[allow(clippy::too_many_arguments)]
pub fn kill_sweep(
    seeds: &[u64],
    point: [usize; 2],
    losses: &[f64],
    max_delay: u64,
    fraction: f64,
    ip: &InstanceParams,
    params: &CbcaParams,
    md: &mut String,
    rows: &mut Vec<Row>,
) {
    let [n_r, n_e] = point;
    let k = ((n_r as f64) * fraction).round() as usize;
    let _ = writeln!(md, "## Round runs with {k} of {n_r} robots ({:.0} %) killed after convergence (n_e = {n_e}, {} seeds a row, delays of up to {max_delay} rounds when lossy)\n", fraction * 100.0, seeds.len());
    let _ = writeln!(md, "The killed robots (a seeded draw) are forgotten by the survivors (`CbcaRobot::forget_robot`) and consensus runs again on the survivors' radio graph (grouped: the 1.5 km graph at the start positions, plus the conflict merges' links; global: complete). Targets hunted = targets whose survivors' coalition is full.\n");
    let _ = writeln!(md, "| setup | loss | converged before / after | rounds after | targets hunted before | after | system utility after |\n|---|---|---|---|---|---|---|");
    for (name, prior) in [
        ("grouped", PriorInfo::DetectionPlusNearest),
        ("without grouping", PriorInfo::Global),
    ] {
        for &loss in losses {
            let mut conv = [0usize; 2];
            let mut rounds = Vec::new();
            let mut hunted = [Vec::new(), Vec::new()];
            let mut util = Vec::new();
            for &seed in seeds {
                let inst = random_instance(n_r, n_e, seed, ip, params);
                let mut row = Row::new(
                    format!(
                        "{k} killed after convergence, (2.6) {}",
                        if params.enforce_coverage { "on" } else { "off" }
                    ),
                    format!("CBCA, {name}"),
                    n_r as u32,
                    seed,
                )
                .with("targets", n_e)
                .with("loss", loss);
                let radio = Radio {
                    loss,
                    max_delay: if loss > 0.0 { max_delay } else { 0 },
                    seed,
                };
                let (cbca, s, merges) = run_cbca(&inst.robots, &inst.tasks, prior, &radio, params);
                conv[0] += usize::from(s.converged);
                let book = inst.tasks.iter().map(|t| (t.id, t.clone())).collect();
                let paths: Vec<Vec<TaskId>> = cbca.iter().map(|r| r.plan().path.clone()).collect();
                let before = evaluate(&inst.robots, &book, paths, params).ok();
                if let Some(e) = &before {
                    hunted[0].push(e.hunted as f64);
                }
                row = row
                    .with("converged_before", s.converged)
                    .with("hunted_before", before.map(|e| e.hunted as f64));
                let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x6b11);
                let mut ids: Vec<RobotId> = (0..n_r).collect();
                ids.shuffle(&mut rng);
                let dead: Vec<RobotId> = ids[..k].to_vec();
                let graph = survivors_graph(&inst.robots, prior, params, &merges);
                let (mut survivors, index): (Vec<CbcaRobot>, Vec<usize>) = {
                    let mut v = Vec::new();
                    let mut index = vec![usize::MAX; n_r];
                    for r in cbca.into_iter().filter(|r| !dead.contains(&r.id())) {
                        index[r.id()] = v.len();
                        v.push(r);
                    }
                    (v, index)
                };
                for r in &mut survivors {
                    for &d in &dead {
                        r.forget_robot(d);
                    }
                }
                let g: Vec<Vec<usize>> = (0..n_r)
                    .filter(|i| !dead.contains(i))
                    .map(|i| {
                        graph[i]
                            .iter()
                            .filter(|n| !dead.contains(n))
                            .map(|&n| index[n])
                            .collect()
                    })
                    .collect();
                let radio2 = Radio {
                    seed: seed ^ 0xdead,
                    ..radio
                };
                let s2 = run(&mut survivors, &g, &radio2, params.max_iterations);
                conv[1] += usize::from(s2.converged);
                rounds.push(s2.rounds as f64);
                let mut paths = vec![Vec::new(); n_r];
                for r in &survivors {
                    paths[r.id()] = r.plan().path.clone();
                }
                let after = evaluate(&inst.robots, &book, paths, params).ok();
                if let Some(e) = &after {
                    hunted[1].push(e.hunted as f64);
                    util.push(e.system_utility);
                }
                rows.push(
                    row.with("converged_after", s2.converged)
                        .with("rounds_after", s2.rounds as f64)
                        .with("hunted_after", after.as_ref().map(|e| e.hunted as f64))
                        .with("system_utility_after", after.map(|e| e.system_utility)),
                );
            }
            let _ = writeln!(
                md,
                "| {name} | {loss} | {} / {} of {} | {} | {} | {} | {} |",
                conv[0],
                conv[1],
                seeds.len(),
                fmt_ms(&rounds, 1),
                fmt_ms(&hunted[0], 1),
                fmt_ms(&hunted[1], 1),
                fmt_ms(&util, 0)
            );
        }
    }
    let _ = writeln!(md);
}

fn evaluate(
    robots: &[Robot],
    book: &agent::cbca::TaskBook,
    paths: Vec<Vec<TaskId>>,
    params: &CbcaParams,
) -> Result<agent::cbca::baselines::Evaluation, agent::cbca::dag::Deadlock> {
    let alloc = agent::cbca::baselines::Allocation { paths, messages: 0 };
    agent::cbca::baselines::evaluate(robots, book, &alloc, params)
}

/// The radio graph the grouped run ended on: the start positions' graph plus every conflict
/// merge's links (claimers of a shared target), or the complete graph.
fn survivors_graph(
    robots: &[Robot],
    prior: PriorInfo,
    params: &CbcaParams,
    merges: &[agent::cbca::compare::ConflictMerge],
) -> Vec<Vec<RobotId>> {
    let n = robots.len();
    if prior == PriorInfo::Global {
        return complete_graph(n);
    }
    let pos: Vec<_> = robots.iter().map(|r| r.position).collect();
    let mut g = comm_graph(&pos, params.comm_radius_km);
    for m in merges {
        for (j, _) in &m.shared {
            let claimers: Vec<RobotId> =
                (0..n).filter(|&i| m.paths_before[i].contains(j)).collect();
            for &a in &claimers {
                for &b in &claimers {
                    if a != b && !g[a].contains(&b) {
                        g[a].push(b);
                    }
                }
            }
        }
    }
    g
}

fn names(p: &[TaskId]) -> String {
    let v: Vec<String> = p.iter().map(|j| format!("T{}", j + 1)).collect();
    format!("[{}]", v.join(" "))
}

fn set(v: &[usize]) -> String {
    let names: Vec<String> = v.iter().map(|i| format!("R{}", i + 1)).collect();
    format!("{{{}}}", names.join(", "))
}

/// The utility-curve SVG writer of experiment_cbca.rs: (title, times, (label, values), file).
pub type CurvesSvg = dyn Fn(&str, &[f64], &[(String, Vec<f64>)], &Path) -> Result<(), String>;

/// Fig. 4.5's curves of a moving run: every robot whose utility is ever non-zero.
pub fn utility_svg(r: &MovingRun, title: &str, file: &Path, svg: &CurvesSvg) -> Result<(), String> {
    let series: Vec<(String, Vec<f64>)> = r
        .utility
        .iter()
        .enumerate()
        .filter(|(_, u)| u.iter().any(|x| x.abs() > 1e-9))
        .map(|(i, u)| (format!("R{}", i + 1), u.clone()))
        .collect();
    svg(title, &r.times, &series, file)
}

/// Example 2 re-planned with motion (Fig. 4.5): see `agent::cbca::moving_rounds`.
pub fn example2_moving(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    radii: &[f64],
    out: &Path,
    md: &mut String,
    svg: &CurvesSvg,
) -> Result<(), String> {
    let _ = writeln!(md, "## Example 2 re-planned with motion, loyalty and compensation (Fig. 4.5; `agent::cbca::moving_rounds`, static targets)\n");
    let _ = writeln!(md, "Robots move at 1 km per time unit along their plans (dt 0.05); a target is captured when its whole full coalition is there, held for its hold time, then done. When two planning groups come within the radio radius they merge: CBCA runs afresh on the merged group from where the robots are (values decayed to now); each robot adopts its new path only if S_i(p_i') > S_i(p_i) + sigma_i (4.22), a switcher pays compensation (rate {}) split among the members it leaves; a consistency pass (consensus with the decided plans seeded) settles contested places. Loyalty r1 = {}, r2 = {}, r3 = {}.\n", params.loyalty.compensation_rate, params.loyalty.r1, params.loyalty.r2, params.loyalty.r3);
    let _ = writeln!(md, "Thesis (spec 8.2): two groups; initial Phi1 = {{R1, R15, R5}} (T1), Phi2 = {{R2, R4, R6}} (T2), Phi3 = {{R7, R8, R9}} (T3), Phi4 = {{R13, R12, R11, R10}} (T4), T5 unallocated; at the merge R9 -> T5 and R15 -> T3 (utilities 204.39 and 104.53 against 110.56 and 36.32 on their old targets), T1 shelved; R6 leaves T2 for T4 (compensating R2 and R4), R10 left with nothing (utility to 0). The printed data contradict the narrative (spec 10.2, 10.3): 1.5 km gives six groups, not two (2.0 km gives two); Phi1, Phi2 and Phi3 violate (2.6) (T1 type 2: 13 < 14; T2 type 1: 11 < 12; T3 type 1: 7 < 9).\n");
    for (cover, &radius) in [false, true]
        .into_iter()
        .flat_map(|c| radii.iter().map(move |r| (c, r)))
    {
        let mp = MovingParams {
            radius_km: radius,
            ..MovingParams::default()
        };
        let params = &CbcaParams {
            enforce_coverage: cover,
            ..params.clone()
        };
        let r = run_moving(robots, tasks, params, &mp);
        let tag = if cover { "-2.6-on" } else { "" };
        let _ = writeln!(
            md,
            "### Radio radius {radius} km, (2.6) {}\n",
            if cover { "on" } else { "off" }
        );
        let _ = writeln!(
            md,
            "Groups at t = 0: {} ({}); consensus {} rounds.\n",
            r.initial_groups.len(),
            r.initial_groups
                .iter()
                .map(|g| set(g))
                .collect::<Vec<_>>()
                .join(" "),
            r.initial_stats.rounds
        );
        let mut coal: std::collections::BTreeMap<TaskId, Vec<usize>> = Default::default();
        for (i, p) in r.initial_paths.iter().enumerate() {
            for &j in p {
                coal.entry(j).or_default().push(i);
            }
        }
        let _ = writeln!(
            md,
            "Initial coalitions: {}.\n",
            tasks
                .iter()
                .map(|t| format!(
                    "T{} {}",
                    t.id + 1,
                    set(coal.get(&t.id).map_or(&[][..], |v| v))
                ))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let _ = writeln!(md, "| t | groups that meet | robot | old path (S) | proposed (S') | sigma | verdict | path after the consistency pass |\n|---|---|---|---|---|---|---|---|");
        for rp in &r.replannings {
            let g = rp
                .groups
                .iter()
                .map(|g| set(g))
                .collect::<Vec<_>>()
                .join(" + ");
            for d in &rp.decisions {
                if d.old_path == d.proposed && d.final_path == d.old_path {
                    continue;
                }
                let _ = writeln!(
                    md,
                    "| {:.2} | {g} | {} | {} | {:?} | {} |",
                    rp.time,
                    decision_cells(d),
                    d.sigma.map_or("-".into(), |s| format!("{s:.2}")),
                    d.verdict,
                    names(&d.final_path)
                );
            }
            for p in &rp.payments {
                let _ = writeln!(
                    md,
                    "| {:.2} | {g} | R{} | compensation to R{} for T{}: {:.2} | | | | |",
                    rp.time,
                    p.from + 1,
                    p.to + 1,
                    p.task + 1,
                    p.amount
                );
            }
        }
        let _ = writeln!(md, "\n{} re-planning(s) (unchanged robots not listed). Captures: {}. Not captured by t = {}: {}.\n",
            r.replannings.len(),
            r.captures.iter().map(|c| format!("T{} at {:.2} by {}", c.task + 1, c.time, set(&c.members))).collect::<Vec<_>>().join("; "),
            mp.horizon,
            {
                let got: Vec<TaskId> = r.captures.iter().map(|c| c.task).collect();
                let v: Vec<String> = tasks.iter().filter(|t| !got.contains(&t.id)).map(|t| format!("T{}", t.id + 1)).collect();
                if v.is_empty() { "none".to_string() } else { v.join(", ") }
            }
        );
        let file = format!("fig-4.5-moving-{radius}km{tag}.svg");
        utility_svg(
            &r,
            &format!(
                "Example 2 re-planned ({radius} km, (2.6) {}): utility against time",
                if cover { "on" } else { "off" }
            ),
            &out.join(&file),
            svg,
        )?;
        let _ = writeln!(md, "![Fig. 4.5, {radius} km]({file})\n");
    }
    Ok(())
}
