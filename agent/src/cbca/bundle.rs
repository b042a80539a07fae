//! Algorithm 1 of thesis sec. 4.2.2 (spec 4.5): bundle construction by marginal gain. While
//! |b_i| < l_i, robot i computes c_ij (4.15) for every task it knows; a task is open to it
//! (h_ij = 1) if its believed coalition is not full (N_j^sum < L_j), or if the bid beats the
//! weakest winner's (4.16), who is then displaced; it adds the best open task at its best
//! insertion position and records itself as a winner with its bid.
//!
//! What the pseudo-code leaves out and we add (spec 4.5 [INFERRED]):
//! - a task is a candidate only if the new path meets the constraints of sec. 4.1: l_i (4.2),
//!   mileage (2.5), compatibility (2.7) and resources (4.5) (model::check_path), and the task
//!   graph of the new path with the other robots' known paths stays a DAG (4.6);
//! - the loop ends when no candidate has a positive bid;
//! - displacing the weakest winner k* clears z_k*j and y_k*j, so N_j^sum never exceeds L_j;
//! - the minimum runs over the current winners only; ties go to the smaller id;
//! - with `params.cap_bids` the bid is min(c_ij, the bids already in the bundle);
//! - with `params.substitution_check` a displacement also needs E_i ∩ E_k* != ∅, the test
//!   Algorithm 2 applies to the same situation;
//! - with `params.enforce_coverage` a bid that completes a coalition (its L_j-th member) or
//!   displaces a member needs the resulting coalition to cover E_j (2.6).

use std::cell::{Cell, RefCell};

use super::dag;
use super::model::{
    check_path, coverage_shortfall, overlaps, Infeasible, Resources, Robot, RobotId, TaskBook,
    TaskId,
};
use super::params::CbcaParams;
use super::score::{marginal_gain, Insertion};
use super::winners::{outbids, Winners};

/// What robot i needs to know about the others: their resources (for the substitution test)
/// and their paths (for the DAG test), as it last heard them.
pub trait Peers {
    fn resources(&self, m: RobotId) -> Option<Resources>;
    /// Robot m's path as known (empty when unknown). Robot i's own entry is not used.
    fn path(&self, m: RobotId) -> &[TaskId];
    fn count(&self) -> usize;
}

/// Peers given as plain lists (tests, benches, centralised baselines).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StaticPeers {
    pub resources: Vec<Resources>,
    pub paths: Vec<Vec<TaskId>>,
}

impl Peers for StaticPeers {
    fn resources(&self, m: RobotId) -> Option<Resources> {
        self.resources.get(m).copied()
    }
    fn path(&self, m: RobotId) -> &[TaskId] {
        self.paths.get(m).map(|p| p.as_slice()).unwrap_or(&[])
    }
    fn count(&self) -> usize {
        self.paths.len()
    }
}

/// A robot's plan: b_i (4.10), tasks in the order they were added, and p_i (4.9), in the
/// order they will be executed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Plan {
    pub bundle: Vec<TaskId>,
    pub path: Vec<TaskId>,
    /// The tasks the robot has committed to (`CbcaRobot::pin`, the runtime's first
    /// settlement). They keep the head of p_i: Algorithm 1 inserts a new task only after them,
    /// so a committed robot is never drawn away from the coalition it is executing by a task
    /// learnt later (only the loyalty review (4.22) may do that). Empty in the round runs.
    pub committed: std::collections::BTreeSet<TaskId>,
}

impl Plan {
    /// How many leading entries of p_i are committed (insertions go at or after this index).
    pub fn committed_head(&self) -> usize {
        self.path
            .iter()
            .take_while(|j| self.committed.contains(j))
            .count()
    }
}

/// How a task looks to robot i at one step of Algorithm 1.
#[derive(Clone, Debug, PartialEq)]
pub enum Candidate {
    /// Already in b_i (c = 0 in (4.15)).
    InBundle,
    /// No insertion position meets sec. 4.1's constraints alone (the first position's reason).
    Infeasible(Infeasible),
    /// Every position that meets them alone would make the task graph cyclic (4.6).
    Deadlock,
    /// The best bid is not positive.
    NoGain { bid: f64 },
    /// Full, and the bid does not beat the weakest winner (4.16): h_ij = 0.
    Outbid {
        bid: f64,
        weakest: RobotId,
        weakest_bid: f64,
    },
    /// Full; the bid beats the weakest, but it carries no type the weakest carries.
    NoSubstitute { bid: f64, weakest: RobotId },
    /// The bid would complete the coalition (or replace `displaces` in it), but the members'
    /// resources would not cover E_j (2.6, `params.enforce_coverage`): short by `shortfall`.
    Uncovered {
        bid: f64,
        displaces: Option<RobotId>,
        shortfall: Resources,
    },
    /// Open: h_ij = 1 with this bid, displacing `displaces` if the coalition is full.
    Open {
        bid: f64,
        insertion: Insertion,
        displaces: Option<RobotId>,
    },
}

/// One task added by Algorithm 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Added {
    pub task: TaskId,
    pub position: usize,
    pub bid: f64,
    pub displaced: Option<RobotId>,
}

/// The candidate status of task j for robot `me` with plan `plan` and beliefs `winners`.
pub fn evaluate(
    me: &Robot,
    plan: &Plan,
    j: TaskId,
    winners: &Winners,
    book: &TaskBook,
    peers: &dyn Peers,
    params: &CbcaParams,
) -> Candidate {
    if plan.bundle.contains(&j) {
        return Candidate::InBundle;
    }
    let Some(task) = book.get(&j) else {
        return Candidate::Infeasible(Infeasible::UnknownTask { task: j });
    };
    let first_reason: RefCell<Option<Infeasible>> = RefCell::new(None);
    let any_alone = Cell::new(false);
    let head = plan.committed_head();
    let allowed = |p: &[TaskId]| -> bool {
        if p[..head] != plan.path[..head] {
            return false;
        }
        match check_path(me, p, book, params) {
            Err(e) => {
                first_reason.borrow_mut().get_or_insert(e);
                false
            }
            Ok(_) => {
                any_alone.set(true);
                deadlock_free(me.id, p, peers)
            }
        }
    };
    let Some(insertion) = marginal_gain(me, &plan.path, j, book, params, allowed) else {
        return if any_alone.get() {
            Candidate::Deadlock
        } else {
            Candidate::Infeasible(
                first_reason
                    .into_inner()
                    .unwrap_or(Infeasible::UnknownTask { task: j }),
            )
        };
    };
    let mut bid = insertion.gain;
    if params.cap_bids {
        for &b in &plan.bundle {
            bid = bid.min(winners.bid(me.id, b));
        }
    }
    if bid <= 0.0 {
        return Candidate::NoGain { bid };
    }
    let others = winners.count(j) - usize::from(winners.is_winner(me.id, j));
    if others < task.robots_needed {
        if others + 1 == task.robots_needed {
            if let Some(shortfall) = uncovered(me, j, None, winners, book, peers, params) {
                return Candidate::Uncovered {
                    bid,
                    displaces: None,
                    shortfall,
                };
            }
        }
        return Candidate::Open {
            bid,
            insertion,
            displaces: None,
        };
    }
    let (weakest, weakest_bid) = winners.weakest(j).expect("a full coalition has a member");
    if !outbids((bid, me.id), (weakest_bid, weakest)) {
        return Candidate::Outbid {
            bid,
            weakest,
            weakest_bid,
        };
    }
    if params.substitution_check {
        if let Some(res) = peers.resources(weakest) {
            if !overlaps(&me.resources, &res) {
                return Candidate::NoSubstitute { bid, weakest };
            }
        }
    }
    if let Some(shortfall) = uncovered(me, j, Some(weakest), winners, book, peers, params) {
        return Candidate::Uncovered {
            bid,
            displaces: Some(weakest),
            shortfall,
        };
    }
    Candidate::Open {
        bid,
        insertion,
        displaces: Some(weakest),
    }
}

/// (2.6) for the coalition robot `me` would complete on task j (replacing `displaced` if
/// given): None when it covers E_j or `params.enforce_coverage` is off, else the shortfall per
/// type. Members contribute their carried resources E_i' as (2.6) writes it; a member whose
/// resources robot i has not heard yet counts as carrying nothing (i cannot vouch for it).
fn uncovered(
    me: &Robot,
    j: TaskId,
    displaced: Option<RobotId>,
    winners: &Winners,
    book: &TaskBook,
    peers: &dyn Peers,
    params: &CbcaParams,
) -> Option<Resources> {
    if !params.enforce_coverage {
        return None;
    }
    let mut members: Vec<Resources> = winners
        .winners_of(j)
        .into_iter()
        .filter(|&(m, _)| m != me.id && Some(m) != displaced)
        .map(|(m, _)| peers.resources(m).unwrap_or_default())
        .collect();
    members.push(me.resources);
    let refs: Vec<&Resources> = members.iter().collect();
    let short = coverage_shortfall(&refs, &book[&j]);
    short.iter().any(|s| *s > 0.0).then_some(short)
}

/// (4.6) for robot `me` taking path `p`, against the other robots' known paths.
pub fn deadlock_free(me: RobotId, p: &[TaskId], peers: &dyn Peers) -> bool {
    let mut paths: Vec<&[TaskId]> = (0..peers.count())
        .filter(|&m| m != me)
        .map(|m| peers.path(m))
        .collect();
    paths.push(p);
    dag::is_dag(paths)
}

/// Algorithm 1: extends `plan` while |b_i| < l_i and some task is open with a positive bid;
/// records the new bids in `winners` (and clears the displaced). Returns what it added.
pub fn build_bundle(
    me: &Robot,
    plan: &mut Plan,
    winners: &mut Winners,
    book: &TaskBook,
    peers: &dyn Peers,
    params: &CbcaParams,
) -> Vec<Added> {
    let mut added = Vec::new();
    while plan.bundle.len() < me.max_tasks {
        // T_i = argmax_j c_ij h_ij (ties: the smaller task id, the first in book order).
        let mut best: Option<(TaskId, f64, Insertion, Option<RobotId>)> = None;
        for &j in book.keys() {
            if let Candidate::Open {
                bid,
                insertion,
                displaces,
            } = evaluate(me, plan, j, winners, book, peers, params)
            {
                if best.as_ref().is_none_or(|b| bid > b.1) {
                    best = Some((j, bid, insertion, displaces));
                }
            }
        }
        let Some((j, bid, insertion, displaces)) = best else {
            break;
        };
        if let Some(k) = displaces {
            winners.clear(k, j);
        }
        plan.bundle.push(j);
        plan.path.insert(insertion.position, j);
        winners.set(me.id, j, bid);
        added.push(Added {
            task: j,
            position: insertion.position,
            bid,
            displaced: displaces,
        });
    }
    added
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    /// T1 at (0, 0): V_a 100, L 2. T2 at (4, 0): V_a 60, L 1. beta 0 (no decay), w1 = w2 = 1,
    /// so S_ij = V_a - gamma d and the hand computation is exact. Resources never bind here.
    fn case() -> (Vec<Robot>, TaskBook, CbcaParams) {
        let mut t1 = task(0, [0.0, 0.0], [1.0; 6], 2);
        let mut t2 = task(1, [4.0, 0.0], [1.0; 6], 1);
        t1.beta = 0.0;
        t2.beta = 0.0;
        t2.value = 60.0;
        let book = [(0, t1), (1, t2)].into_iter().collect();
        let mut robots = vec![
            robot(0, [0.0, 1.0], [5.0; 6]),
            robot(1, [0.0, 2.0], [5.0; 6]),
            robot(2, [0.0, 3.0], [5.0; 6]),
        ];
        robots[0].gamma = 1.0;
        robots[1].gamma = 1.0;
        robots[2].gamma = 0.5;
        for r in &mut robots {
            r.max_tasks = 2;
        }
        (robots, book, CbcaParams::default())
    }

    #[test]
    fn three_robots_two_tasks_by_hand() {
        let (robots, book, params) = case();
        let mut winners = Winners::new(3, 2);
        let mut plans = vec![Plan::default(); 3];
        let mut known = StaticPeers {
            resources: robots.iter().map(|r| r.resources).collect(),
            paths: vec![vec![]; 3],
        };
        // Each robot runs Algorithm 1 in turn on the same beliefs (as after a perfect exchange).
        // R1 (0, 1), gamma 1: T1 d = 1 -> 99; T2 d = sqrt(17) = 4.1231 -> 55.8769. Takes T1 (99).
        // Then T2 after T1 (leg 4): 155 - 99 = 56; before T1: (60 - 4.1231) + (100 - 4) - 99
        // = 52.8769. Appends T2 with bid min(56, 99) = 56.
        let a = build_bundle(
            &robots[0],
            &mut plans[0],
            &mut winners,
            &book,
            &known,
            &params,
        );
        assert_eq!(
            a,
            vec![
                Added {
                    task: 0,
                    position: 0,
                    bid: 99.0,
                    displaced: None
                },
                Added {
                    task: 1,
                    position: 1,
                    bid: 56.0,
                    displaced: None
                },
            ]
        );
        assert_eq!(plans[0].path, vec![0, 1]);
        known.paths[0] = plans[0].path.clone();
        // R2 (0, 2), gamma 1: T1 -> 98 (room: 1 < 2), T2 alone 60 - sqrt(20) = 55.5279 < 56
        // (T2 full, h = 0). Takes T1 (98). Then T2 after T1: 154 - 98 = 56 = R1's 56: the tie
        // goes to the smaller id, R1, so h = 0 and the bundle stops at [T1].
        let b = build_bundle(
            &robots[1],
            &mut plans[1],
            &mut winners,
            &book,
            &known,
            &params,
        );
        assert_eq!(
            b,
            vec![Added {
                task: 0,
                position: 0,
                bid: 98.0,
                displaced: None
            }]
        );
        assert_eq!(
            evaluate(&robots[1], &plans[1], 1, &winners, &book, &known, &params),
            Candidate::Outbid {
                bid: 56.0,
                weakest: 0,
                weakest_bid: 56.0
            }
        );
        known.paths[1] = plans[1].path.clone();
        // R3 (0, 3), gamma 0.5: T1 -> 100 - 1.5 = 98.5 > the weakest winner R2's 98: displaces
        // R2. T2 alone 60 - 2.5 = 57.5. Takes T1 (98.5 > 57.5), displacing R2. Then T2 after T1:
        // 60 - 0.5 * 4 = 58; before: (60 - 2.5) + (100 - 2) - 98.5 = 57. Bid min(58, 98.5) = 58
        // > R1's 56 on the full T2: displaces R1.
        let c = build_bundle(
            &robots[2],
            &mut plans[2],
            &mut winners,
            &book,
            &known,
            &params,
        );
        assert_eq!(
            c,
            vec![
                Added {
                    task: 0,
                    position: 0,
                    bid: 98.5,
                    displaced: Some(1)
                },
                Added {
                    task: 1,
                    position: 1,
                    bid: 58.0,
                    displaced: Some(0)
                },
            ]
        );
        // R3's beliefs: T1 = {R1 99, R3 98.5}, T2 = {R3 58}; never more than L_j.
        assert_eq!(winners.winners_of(0), vec![(0, 99.0), (2, 98.5)]);
        assert_eq!(winners.winners_of(1), vec![(2, 58.0)]);
    }

    #[test]
    fn l_i_and_non_positive_gains_stop_the_bundle() {
        let (mut robots, mut book, params) = case();
        robots[0].max_tasks = 1;
        let known = StaticPeers {
            resources: robots.iter().map(|r| r.resources).collect(),
            paths: vec![vec![]; 3],
        };
        let mut winners = Winners::new(3, 2);
        let mut plan = Plan::default();
        let a = build_bundle(&robots[0], &mut plan, &mut winners, &book, &known, &params);
        assert_eq!(a.len(), 1);
        // A task worth less than the trip: V_a 3 at 4.1231 km, gamma 1 -> negative, not taken.
        book.get_mut(&1).unwrap().value = 3.0;
        robots[0].max_tasks = 2;
        let mut plan = Plan::default();
        let mut winners = Winners::new(3, 2);
        build_bundle(&robots[0], &mut plan, &mut winners, &book, &known, &params);
        assert_eq!(plan.bundle, vec![0]);
        assert!(matches!(
            evaluate(&robots[0], &plan, 1, &winners, &book, &known, &params),
            Candidate::NoGain { bid } if bid < 0.0
        ));
    }

    #[test]
    fn a_task_that_would_close_a_cycle_is_refused() {
        let (mut robots, book, params) = case();
        // R2 is known to do T2 then T1. R1 holding T1 must not append T2 after it (T1 -> T2 and
        // T2 -> T1); it may put T2 first.
        robots[0].max_tasks = 2;
        let known = StaticPeers {
            resources: robots.iter().map(|r| r.resources).collect(),
            paths: vec![vec![], vec![1, 0], vec![]],
        };
        let mut winners = Winners::new(3, 2);
        let plan = Plan {
            committed: Default::default(),
            bundle: vec![0],
            path: vec![0],
        };
        winners.set(0, 0, 99.0);
        match evaluate(&robots[0], &plan, 1, &winners, &book, &known, &params) {
            Candidate::Open { insertion, .. } => assert_eq!(insertion.position, 0),
            other => panic!("{other:?}"),
        }
        // With R2 at T2 -> T1 and R3 at T1 -> T2 known, both orders close a cycle for R1.
        let both = StaticPeers {
            resources: known.resources.clone(),
            paths: vec![vec![], vec![1, 0], vec![0, 1]],
        };
        let plan = Plan {
            committed: Default::default(),
            bundle: vec![0],
            path: vec![0],
        };
        assert_eq!(
            evaluate(&robots[0], &plan, 1, &winners, &book, &both, &params),
            Candidate::Deadlock
        );
    }

    #[test]
    fn displacement_needs_a_common_resource_type() {
        let (mut robots, book, params) = case();
        robots[2].resources = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let mut resources: Vec<Resources> = robots.iter().map(|r| r.resources).collect();
        resources[1] = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let known = StaticPeers {
            resources,
            paths: vec![vec![]; 3],
        };
        let mut winners = Winners::new(3, 2);
        winners.set(0, 0, 99.0);
        winners.set(1, 0, 98.0);
        // R3 outbids R2 on T1 (98.5 > 98) but shares no type with R2's {1,0,0,0,0,0}.
        assert_eq!(
            evaluate(
                &robots[2],
                &Plan::default(),
                0,
                &winners,
                &book,
                &known,
                &params
            ),
            Candidate::NoSubstitute {
                bid: 98.5,
                weakest: 1
            }
        );
    }

    /// (2.6) enforced: T1 at (0, 0) needs E = {4, 4, 0, 0, 0, 0} from L = 2 robots (beta 0).
    /// R1 holds T1 with {2, 2, ...} (bid 90). R2 carries {1, 1, ...} and is close (d 1, gamma 1:
    /// bid 99 > 90): completing with R1 gives {3, 3} < {4, 4}, so h = 0 (shortfall 1 in types 1
    /// and 2), although without the rule it would join. R3 carries {2, 2, ...} and is farther
    /// (d 3, gamma 1: bid 97): {4, 4} covers, so it completes the coalition. With T1 full of R1
    /// and R3, R2 (99) beats the weakest R1 (90) but R3's {2,2} + {1,1} fails again: h = 0;
    /// R4 ({3, 3, ...}, d 2, bid 98 > 90) displaces R1 because {2,2} + {3,3} covers.
    #[test]
    fn coverage_rule_blocks_a_completing_or_displacing_bid_that_leaves_e_j_uncovered() {
        let mut t1 = task(0, [0.0, 0.0], [4.0, 4.0, 0.0, 0.0, 0.0, 0.0], 2);
        t1.beta = 0.0;
        let book: TaskBook = [(0, t1)].into_iter().collect();
        let mut robots = vec![
            robot(0, [0.0, 10.0], [2.0; 6]),
            robot(1, [0.0, 1.0], [1.0; 6]),
            robot(2, [0.0, 3.0], [2.0; 6]),
            robot(3, [0.0, 2.0], [3.0; 6]),
        ];
        for r in &mut robots {
            r.gamma = 1.0;
        }
        let known = StaticPeers {
            resources: robots.iter().map(|r| r.resources).collect(),
            paths: vec![vec![0], vec![], vec![], vec![]],
        };
        let params = CbcaParams::default();
        let mut winners = Winners::new(4, 1);
        winners.set(0, 0, 90.0);
        let empty = Plan::default();
        assert_eq!(
            evaluate(&robots[1], &empty, 0, &winners, &book, &known, &params),
            Candidate::Uncovered {
                bid: 99.0,
                displaces: None,
                shortfall: [1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
        let lax = CbcaParams {
            enforce_coverage: false,
            ..params.clone()
        };
        assert!(matches!(
            evaluate(&robots[1], &empty, 0, &winners, &book, &known, &lax),
            Candidate::Open {
                displaces: None,
                ..
            }
        ));
        let mut plan = Plan::default();
        let added = build_bundle(&robots[2], &mut plan, &mut winners, &book, &known, &params);
        assert_eq!(added.len(), 1);
        assert_eq!((added[0].task, added[0].bid), (0, 97.0));
        assert_eq!(
            evaluate(&robots[1], &empty, 0, &winners, &book, &known, &params),
            Candidate::Uncovered {
                bid: 99.0,
                displaces: Some(0),
                shortfall: [1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
            }
        );
        assert!(matches!(
            evaluate(&robots[3], &empty, 0, &winners, &book, &known, &params),
            Candidate::Open {
                displaces: Some(0),
                ..
            }
        ));
    }
}
