//! One instance, every method: CBCA (with grouping, and without it as the ablation) over the
//! round radio of rounds.rs, and the three baselines of sec. 4.3, all scored alike by
//! `baselines::evaluate` (the realised joint schedule, (4.1) with (4.12) at each task's start,
//! less (4.14)). This is what the comparative sweeps of Figs. 4.6-4.7 run per seed.

use serde::Serialize;
use swarm::geometry::Vec2;

use super::baselines::{self, Allocation, Evaluation};
use super::consensus::CbcaRobot;
use super::grouping::{comm_graph, robot_knowledge, PriorInfo};
use super::model::{Robot, RobotId, Task};
use super::params::CbcaParams;
use super::rounds::{run, Radio, RunStats};

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
}

/// CBCA on `robots` / `tasks`: grouped (radio graph of `params.comm_radius_km`, knowledge
/// `prior`) or, with `prior = PriorInfo::Global`, on the complete graph.
pub fn run_cbca(
    robots: &[Robot],
    tasks: &[Task],
    prior: PriorInfo,
    radio: &Radio,
    params: &CbcaParams,
) -> (Vec<CbcaRobot>, RunStats) {
    let pos: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let n = robots.len();
    let knowledge = robot_knowledge(&pos, tasks, params.detection_radius_km, prior);
    let neighbours: Vec<Vec<RobotId>> = if prior == PriorInfo::Global {
        (0..n)
            .map(|i| (0..n).filter(|&j| j != i).collect())
            .collect()
    } else {
        comm_graph(&pos, params.comm_radius_km)
    };
    let mut cbca: Vec<CbcaRobot> = robots
        .iter()
        .map(|r| {
            let book = tasks
                .iter()
                .filter(|t| knowledge[r.id].contains(&t.id))
                .map(|t| (t.id, t.clone()))
                .collect();
            CbcaRobot::new(r.clone(), n, tasks.len(), book, params.clone())
        })
        .collect();
    let stats = run(&mut cbca, &neighbours, radio, params.max_iterations);
    (cbca, stats)
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
    let (allocation, consensus) = match method {
        Method::CbcaGrouped | Method::CbcaGlobal => {
            let prior = if method == Method::CbcaGrouped {
                PriorInfo::DetectionPlusNearest
            } else {
                PriorInfo::Global
            };
            let (cbca, stats) = run_cbca(robots, tasks, prior, radio, params);
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
