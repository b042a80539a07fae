//! One instance, every method: CBCA (with grouping, and without it as the ablation) over the
//! round radio of rounds.rs, and the three baselines of sec. 4.3, all scored alike by
//! `baselines::evaluate` (the realised joint schedule, (4.1) with (4.12) at each task's start,
//! less (4.14)). This is what the comparative sweeps of Figs. 4.6-4.7 run per seed.

use std::collections::BTreeSet;

use serde::Serialize;
use swarm::geometry::Vec2;

use super::baselines::eta;
use super::baselines::{self, Allocation, Evaluation};
use super::consensus::CbcaRobot;
use super::grouping::{comm_graph, components, robot_knowledge, PriorInfo};
use super::model::{Robot, RobotId, Task, TaskBook, TaskId};
use super::params::CbcaParams;
use super::rounds::{run, run_from, Radio, RunStats};

/// The methods of the comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Method {
    /// CBCA with grouping by local prior information (sec. 4.2.2): the 1.5 km radio graph,
    /// each robot knowing its detections plus the undetected targets it is nearest to.
    CbcaGrouped,
    /// The ablation: CBCA without grouping (every robot hears every other and knows every
    /// target).
    CbcaGlobal,
    /// Sujit, Manathara, Ghose & de Sousa 2014 (baselines/sujit.rs).
    Sujit,
    /// Kim, Baik & Lee 2015 (baselines/welfare.rs).
    ResourceWelfare,
    /// Li, Liu & Zhang 2016 (baselines/contract_net.rs).
    ContractNet,
}

impl Method {
    pub const ALL: [Method; 5] = [
        Method::CbcaGrouped,
        Method::CbcaGlobal,
        Method::Sujit,
        Method::ResourceWelfare,
        Method::ContractNet,
    ];
    pub fn label(self) -> &'static str {
        match self {
            Method::CbcaGrouped => "CBCA",
            Method::CbcaGlobal => "CBCA without grouping",
            Method::Sujit => "Sujit et al. 2014",
            Method::ResourceWelfare => "Kim-Baik-Lee 2015",
            Method::ContractNet => "improved contract net",
        }
    }
}

/// What every method of the fair comparison is given (issue 18: "every method under the same
/// information").
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Information {
    /// Grouping by local prior information (sec. 4.2.2): the 1.5 km temporary groups, each
    /// knowing its detections plus the undetected targets it is nearest to; groups that claim
    /// a common target merge and plan again (CBCA: `merge_on_conflict`; the baselines:
    /// baselines/local.rs).
    Local,
    /// Every robot hears every other and knows every target.
    Global,
}

impl Information {
    pub const ALL: [Information; 2] = [Information::Local, Information::Global];
    pub fn label(self) -> &'static str {
        match self {
            Information::Local => "local (1.5 km groups)",
            Information::Global => "global",
        }
    }
}

/// The four algorithms of Figs. 4.6-4.7, each runnable under either [`Information`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub enum Algorithm {
    Cbca,
    Sujit,
    ResourceWelfare,
    ContractNet,
}

impl Algorithm {
    pub const ALL: [Algorithm; 4] = [
        Algorithm::Cbca,
        Algorithm::Sujit,
        Algorithm::ResourceWelfare,
        Algorithm::ContractNet,
    ];
    pub fn label(self) -> &'static str {
        match self {
            Algorithm::Cbca => "CBCA",
            Algorithm::Sujit => "Sujit et al. 2014",
            Algorithm::ResourceWelfare => "Kim-Baik-Lee 2015",
            Algorithm::ContractNet => "improved contract net",
        }
    }
}

/// Runs `algorithm` under `info` (and (2.6) as `params.enforce_coverage` says, for every
/// algorithm alike) and scores it. CBCA under [`Information::Local`] is [`Method::CbcaGrouped`],
/// under [`Information::Global`] [`Method::CbcaGlobal`]; a baseline under `Global` sees every
/// robot and target (Sujit et al. with its range limit lifted), under `Local` it runs group by
/// group (baselines/local.rs).
pub fn run_fair(
    algorithm: Algorithm,
    info: Information,
    robots: &[Robot],
    tasks: &[Task],
    radio: &Radio,
    params: &CbcaParams,
) -> MethodRun {
    let method = match algorithm {
        Algorithm::Cbca if info == Information::Local => Method::CbcaGrouped,
        Algorithm::Cbca => Method::CbcaGlobal,
        Algorithm::Sujit => Method::Sujit,
        Algorithm::ResourceWelfare => Method::ResourceWelfare,
        Algorithm::ContractNet => Method::ContractNet,
    };
    if algorithm == Algorithm::Cbca {
        return run_method(method, robots, tasks, radio, params);
    }
    let allocate: baselines::local::Allocator = match algorithm {
        Algorithm::Sujit => baselines::sujit::allocate,
        Algorithm::ResourceWelfare => baselines::welfare::allocate,
        _ => baselines::contract_net::allocate,
    };
    let allocation = match info {
        Information::Local => baselines::local::allocate_local(allocate, robots, tasks, params).0,
        Information::Global => {
            let book = tasks.iter().map(|t| (t.id, t.clone())).collect();
            let all = CbcaParams {
                comm_radius_km: f64::INFINITY,
                ..params.clone()
            };
            allocate(robots, &book, &all)
        }
    };
    let book = tasks.iter().map(|t| (t.id, t.clone())).collect();
    let evaluation = baselines::evaluate(robots, &book, &allocation, params).ok();
    MethodRun {
        method,
        allocation,
        evaluation,
        consensus: None,
        merges: Vec::new(),
    }
}

/// A method's result on one instance.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodRun {
    pub method: Method,
    pub allocation: Allocation,
    /// None when the paths deadlock (4.6 fails), which only an unconverged CBCA run can give.
    pub evaluation: Option<Evaluation>,
    /// CBCA only: rounds, broadcasts, bytes, copies, and whether every detector converged
    /// before the cap (a run that did not is *censored*: reported, not dropped).
    pub consensus: Option<RunStats>,
    /// Grouped CBCA only: the conflict merges, in order (empty for the others).
    pub merges: Vec<ConflictMerge>,
}

/// One conflict merge of a grouped run: after the groups converged, targets claimed by robots
/// of more than one temporary group. Those robots are all heading for the target, so the
/// groups meet there and merge (sec. 4.2.5 case 2.2): consensus runs again with radio links
/// between the claimers of each shared target.
#[derive(Clone, Debug, PartialEq)]
pub struct ConflictMerge {
    /// Each shared target with the groups (their members) that claim it.
    pub shared: Vec<(TaskId, Vec<Vec<RobotId>>)>,
    /// Every robot's path before the merge.
    pub paths_before: Vec<Vec<TaskId>>,
    /// When the groups meet: the earliest time at which members of two claiming groups have
    /// both reached a shared target (own travel and holds along the paths before the merge).
    pub meet_time: f64,
}

/// CBCA on `robots` / `tasks`: grouped (radio graph of `params.comm_radius_km`, knowledge
/// `prior`) or, with `prior = PriorInfo::Global`, on the complete graph. With
/// `params.merge_on_conflict` a grouped run merges the groups that claim a common target
/// ([`ConflictMerge`]) and runs consensus again until no target is claimed by two groups: the
/// thesis's groups move and merge when they meet, while the round runs do not move, and
/// without the merge groups that never talk share targets (over-full coalitions, and paths
/// that deadlock when scored together since (4.6) is checked inside a group only). The
/// round counts of the phases add up in the returned stats.
pub fn run_cbca(
    robots: &[Robot],
    tasks: &[Task],
    prior: PriorInfo,
    radio: &Radio,
    params: &CbcaParams,
) -> (Vec<CbcaRobot>, RunStats, Vec<ConflictMerge>) {
    let pos: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let n = robots.len();
    let knowledge = robot_knowledge(&pos, tasks, params.detection_radius_km, prior);
    let mut neighbours: Vec<Vec<RobotId>> = if prior == PriorInfo::Global {
        complete_graph(n)
    } else {
        comm_graph(&pos, params.comm_radius_km)
    };
    let mut cbca = cbca_robots(robots, tasks, &knowledge, params);
    let mut stats = run(&mut cbca, &neighbours, radio, params.max_iterations);
    let mut merges = Vec::new();
    while params.merge_on_conflict && stats.converged {
        let paths: Vec<Vec<TaskId>> = cbca.iter().map(|r| r.plan().path.clone()).collect();
        let Some(merge) = conflict(robots, tasks, &paths, &components(&neighbours)) else {
            break;
        };
        for (j, _) in &merge.shared {
            let claimers: Vec<RobotId> = (0..n).filter(|&i| paths[i].contains(j)).collect();
            for &a in &claimers {
                for &b in &claimers {
                    if a != b && !neighbours[a].contains(&b) {
                        neighbours[a].push(b);
                    }
                }
            }
        }
        merges.push(merge);
        let later = run_from(
            &mut cbca,
            &neighbours,
            radio,
            stats.rounds,
            params.max_iterations,
        );
        stats.add(&later);
    }
    (cbca, stats, merges)
}

/// Every robot hears every other (CBCA without grouping).
pub fn complete_graph(n: usize) -> Vec<Vec<RobotId>> {
    (0..n)
        .map(|i| (0..n).filter(|&j| j != i).collect())
        .collect()
}

/// One CBCA robot per row, each with the tasks of `knowledge[i]` in its book.
pub fn cbca_robots(
    robots: &[Robot],
    tasks: &[Task],
    knowledge: &[BTreeSet<TaskId>],
    params: &CbcaParams,
) -> Vec<CbcaRobot> {
    robots
        .iter()
        .map(|r| {
            let book = tasks
                .iter()
                .filter(|t| knowledge[r.id].contains(&t.id))
                .map(|t| (t.id, t.clone()))
                .collect();
            CbcaRobot::new(r.clone(), robots.len(), tasks.len(), book, params.clone())
        })
        .collect()
}

/// The targets claimed by more than one of `groups` under `paths`, with the groups' meeting
/// time; None when every target's claimers are in one group.
pub fn conflict(
    robots: &[Robot],
    tasks: &[Task],
    paths: &[Vec<TaskId>],
    groups: &[Vec<RobotId>],
) -> Option<ConflictMerge> {
    let book: TaskBook = tasks.iter().map(|t| (t.id, t.clone())).collect();
    let mut shared = Vec::new();
    let mut meet_time = f64::INFINITY;
    for t in tasks {
        let claiming: Vec<&Vec<RobotId>> = groups
            .iter()
            .filter(|g| g.iter().any(|&i| paths[i].contains(&t.id)))
            .collect();
        if claiming.len() < 2 {
            continue;
        }
        // Each group's first arrival at the target; the groups meet at the second earliest.
        let mut firsts: Vec<f64> = claiming
            .iter()
            .map(|g| {
                g.iter()
                    .filter_map(|&i| {
                        let k = paths[i].iter().position(|&j| j == t.id)?;
                        Some(eta(&robots[i], &paths[i][..k], t.id, &book))
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        firsts.sort_by(f64::total_cmp);
        meet_time = meet_time.min(firsts[1]);
        shared.push((t.id, claiming.into_iter().cloned().collect()));
    }
    (!shared.is_empty()).then(|| ConflictMerge {
        shared,
        paths_before: paths.to_vec(),
        meet_time,
    })
}

/// Runs `method` on the instance and scores it.
pub fn run_method(
    method: Method,
    robots: &[Robot],
    tasks: &[Task],
    radio: &Radio,
    params: &CbcaParams,
) -> MethodRun {
    let book = tasks.iter().map(|t| (t.id, t.clone())).collect();
    let mut merges = Vec::new();
    let (allocation, consensus) = match method {
        Method::CbcaGrouped | Method::CbcaGlobal => {
            let prior = if method == Method::CbcaGrouped {
                PriorInfo::DetectionPlusNearest
            } else {
                PriorInfo::Global
            };
            let (cbca, stats, m) = run_cbca(robots, tasks, prior, radio, params);
            merges = m;
            let alloc = Allocation {
                paths: cbca.iter().map(|r| r.plan().path.clone()).collect(),
                messages: stats.broadcasts,
            };
            (alloc, Some(stats))
        }
        Method::Sujit => (baselines::sujit::allocate(robots, &book, params), None),
        Method::ResourceWelfare => (baselines::welfare::allocate(robots, &book, params), None),
        Method::ContractNet => (
            baselines::contract_net::allocate(robots, &book, params),
            None,
        ),
    };
    let evaluation = baselines::evaluate(robots, &book, &allocation, params).ok();
    MethodRun {
        method,
        allocation,
        evaluation,
        consensus,
        merges,
    }
}

/// Robot i's utility at time t under the realised joint schedule of `paths` (Figs. 4.3, 4.5:
/// "each robot's utility against time"): Σ over its path of w1 V_aj e^(-beta_j min(t, start_j))
/// minus w2 gamma_i d_ij, the reward of a task frozen once the task starts (its coalition has
/// caught it), so a flat curve means the robot's targets are done. An idle robot's utility is
/// 0. Tasks without a full coalition earn nothing (as in `baselines::evaluate`).
pub fn utility_curve(
    robots: &[Robot],
    tasks: &[Task],
    paths: &[Vec<usize>],
    params: &CbcaParams,
    times: &[f64],
) -> Option<Vec<Vec<f64>>> {
    let book = tasks.iter().map(|t| (t.id, t.clone())).collect();
    let schedule = super::dag::joint_schedule(robots, paths, &book).ok()?;
    let mut count = std::collections::BTreeMap::new();
    for p in paths {
        for &j in p {
            *count.entry(j).or_insert(0usize) += 1;
        }
    }
    Some(
        robots
            .iter()
            .zip(paths)
            .map(|(r, p)| {
                times
                    .iter()
                    .map(|&t| {
                        let mut at = r.position;
                        let mut u = 0.0;
                        for &j in p {
                            let task = &tasks[j];
                            let d = (task.pos() - at).norm();
                            at = task.pos();
                            let full = count[&j] >= task.robots_needed;
                            let reward = if full {
                                task.value * (-task.beta * t.min(schedule.start[&j])).exp()
                            } else {
                                0.0
                            };
                            u += params.w1 * reward - params.w2 * r.gamma * d;
                        }
                        u
                    })
                    .collect()
            })
            .collect(),
    )
}

/// Figs. 4.5's reading with re-planning: robot i's utility against time when the plan changes
/// at the conflict merges. Before the first merge's `meet_time` the curve is that of the paths
/// before it, between merges that of the next paths, after the last merge that of `final_paths`
/// (each by [`utility_curve`]), so a robot whose path changes at a merge jumps there. The round
/// runs do not move: every plan's schedule is counted from the start positions. None if some
/// plan deadlocks.
pub fn replanned_utility_curve(
    robots: &[Robot],
    tasks: &[Task],
    merges: &[ConflictMerge],
    final_paths: &[Vec<TaskId>],
    params: &CbcaParams,
    times: &[f64],
) -> Option<Vec<Vec<f64>>> {
    let mut phases: Vec<(f64, Vec<Vec<f64>>)> = Vec::new();
    let mut from = f64::NEG_INFINITY;
    for m in merges {
        phases.push((
            from,
            utility_curve(robots, tasks, &m.paths_before, params, times)?,
        ));
        from = from.max(m.meet_time);
    }
    phases.push((
        from,
        utility_curve(robots, tasks, final_paths, params, times)?,
    ));
    Some(
        (0..robots.len())
            .map(|i| {
                times
                    .iter()
                    .enumerate()
                    .map(|(k, &t)| {
                        let (_, c) = phases
                            .iter()
                            .rev()
                            .find(|(start, _)| *start <= t)
                            .expect("the first phase starts at -inf");
                        c[i][k]
                    })
                    .collect()
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::instance::{random_instance, InstanceParams};
    use crate::cbca::model::tests::{robot, task};

    #[test]
    fn every_method_respects_l_j_and_cbca_converges_on_a_small_instance() {
        let p = CbcaParams::default();
        let inst = random_instance(8, 4, 3, &InstanceParams::default(), &p);
        for m in Method::ALL {
            let r = run_method(m, &inst.robots, &inst.tasks, &Radio::perfect(), &p);
            for (j, ms) in r.allocation.coalitions() {
                assert!(ms.len() <= inst.tasks[j].robots_needed, "{m:?} over L_j");
            }
            assert!(r.evaluation.is_some(), "{m:?} deadlocked");
            if let Some(s) = &r.consensus {
                assert!(s.converged, "{m:?}: {s:?}");
            }
        }
    }

    #[test]
    fn fair_runs_respect_l_j_and_with_2_6_every_full_coalition_covers() {
        // Seeds 1..=6 of a 13-robot, 8-target instance (the loss sweep's point), every
        // algorithm under both informations, (2.6) on and off.
        for seed in 1..=6 {
            for cover in [false, true] {
                let p = CbcaParams {
                    enforce_coverage: cover,
                    ..CbcaParams::default()
                };
                let inst = random_instance(13, 8, seed, &InstanceParams::default(), &p);
                for a in Algorithm::ALL {
                    for info in Information::ALL {
                        let r = run_fair(a, info, &inst.robots, &inst.tasks, &Radio::perfect(), &p);
                        let e = r.evaluation.as_ref().expect("no deadlock");
                        assert!(e.hunted + e.shelved == 8);
                        for (j, ms) in r.allocation.coalitions() {
                            let t = &inst.tasks[j];
                            assert!(ms.len() <= t.robots_needed, "{a:?} {info:?} over L_j");
                            if cover && ms.len() == t.robots_needed {
                                let res: Vec<_> =
                                    ms.iter().map(|&m| &inst.robots[m].resources).collect();
                                assert!(
                                    crate::cbca::model::covers(&res, t),
                                    "seed {seed} {a:?} {info:?}: T{} uncovered",
                                    j + 1
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn replanned_curve_switches_plans_at_the_meeting() {
        // The by-hand case below: before the merge at t = 2 only R1 is on T1 (incomplete: no
        // reward, cost 1.5 -> -1.5); after it both are (98.5 at 0 decaying to 12.0335 at 4),
        // so R1's curve is -1.5, -1.5, then 35.2879 at t = 2 (a jump), 12.0335 at t = 4.
        let tasks = vec![task(0, [0.0, 3.0], [1.0; 6], 2)];
        let robots = vec![
            robot(0, [0.0, 0.0], [1.0; 6]),
            robot(1, [4.0, 3.0], [1.0; 6]),
        ];
        let merge = ConflictMerge {
            shared: vec![],
            paths_before: vec![vec![0], vec![]],
            meet_time: 2.0,
        };
        let c = replanned_utility_curve(
            &robots,
            &tasks,
            &[merge],
            &[vec![0], vec![0]],
            &CbcaParams::default(),
            &[0.0, 1.0, 2.0, 4.0],
        )
        .unwrap();
        let want = [-1.5, -1.5, 35.2879, 12.0335];
        for (got, w) in c[0].iter().zip(want) {
            assert!((got - w).abs() < 1e-4, "{got} vs {w}");
        }
        assert_eq!(c[1][..2], [0.0, 0.0]);
    }

    #[test]
    fn utility_curve_by_hand() {
        // T1 at (0, 3), V_a 100, beta 0.5, L 2; R1 at (0, 0) gamma 0.5, R2 at (4, 3) gamma 0.5.
        // Start 4 (R2's arrival). R1: 100 e^(-0.5 min(t, 4)) - 1.5: t = 0 -> 98.5,
        // t = 2 -> 100 e^-1 - 1.5 = 35.2879, t >= 4 -> 100 e^-2 - 1.5 = 12.0335 (flat).
        let tasks = vec![task(0, [0.0, 3.0], [1.0; 6], 2)];
        let robots = vec![
            robot(0, [0.0, 0.0], [1.0; 6]),
            robot(1, [4.0, 3.0], [1.0; 6]),
        ];
        let c = utility_curve(
            &robots,
            &tasks,
            &[vec![0], vec![0]],
            &CbcaParams::default(),
            &[0.0, 2.0, 4.0, 9.0],
        )
        .unwrap();
        let want = [98.5, 35.2879, 12.0335, 12.0335];
        for (got, w) in c[0].iter().zip(want) {
            assert!((got - w).abs() < 1e-4, "{got} vs {w}");
        }
        // R2 pays 2.0 instead of 1.5.
        assert!((c[1][3] - (100.0 * (-2.0f64).exp() - 2.0)).abs() < 1e-9);
    }
}

#[cfg(test)]
mod deadlock_across_groups {
    use super::*;
    use crate::cbca::grouping::temporary_groups;
    use crate::cbca::instance::{random_instance, InstanceParams};

    /// Seed 13 of the Fig. 4.6 sweep at n_r = 40, n_e = 30 (traced, docs/hunting.md 14.3):
    /// with the groups fixed at the start, R24 and R30 (one group) go T20 -> T5 -> T16 and R39
    /// (another group, out of radio range) goes T16 -> T20; each group's task graph is a DAG,
    /// their union has the cycle T5 -> T16 -> T20 -> T5, and joint arrival deadlocks. Merging
    /// the groups that claim a common target removes it.
    #[test]
    fn groups_that_never_talk_deadlock_and_the_conflict_merge_resolves_it() {
        let fixed = CbcaParams {
            merge_on_conflict: false,
            ..CbcaParams::default()
        };
        let inst = random_instance(40, 30, 13, &InstanceParams::default(), &fixed);
        let pos: Vec<Vec2> = inst.robots.iter().map(|r| r.position).collect();
        let groups = temporary_groups(&pos, fixed.comm_radius_km);
        let group_of = |i: usize| groups.iter().position(|g| g.contains(&i));
        let r = run_method(
            Method::CbcaGrouped,
            &inst.robots,
            &inst.tasks,
            &Radio::perfect(),
            &fixed,
        );
        assert!(r.evaluation.is_none(), "the fixed groups deadlock");
        let paths = &r.allocation.paths;
        assert!(paths[23].windows(2).any(|w| w == [19, 4]));
        assert!(paths[23].windows(2).any(|w| w == [4, 15]));
        assert!(paths[38].windows(2).any(|w| w == [15, 19]));
        assert_ne!(group_of(23), group_of(38));
        assert!(conflict(&inst.robots, &inst.tasks, paths, &groups).is_some());

        let p = CbcaParams::default();
        assert!(p.merge_on_conflict);
        let (cbca, stats, merges) = run_cbca(
            &inst.robots,
            &inst.tasks,
            PriorInfo::DetectionPlusNearest,
            &Radio::perfect(),
            &p,
        );
        assert!(stats.converged && !merges.is_empty());
        let r = run_method(
            Method::CbcaGrouped,
            &inst.robots,
            &inst.tasks,
            &Radio::perfect(),
            &p,
        );
        assert!(r.evaluation.is_some(), "no deadlock after the merges");
        for (j, ms) in r.allocation.coalitions() {
            assert!(ms.len() <= inst.tasks[j].robots_needed);
        }
        let final_paths: Vec<Vec<TaskId>> = cbca.iter().map(|r| r.plan().path.clone()).collect();
        assert_eq!(final_paths, r.allocation.paths);
    }
}
