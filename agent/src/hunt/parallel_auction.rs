//! The Parallel auction baseline of chapter 3's comparison (Otte, Kuhlman & Sofge 2020, the
//! thesis's Ref. [68]; spec 7.2 and 11): the auctioneer announces every task once at a fixed
//! reward, every robot bids on every task it can take (q_ij = 1) with a positive utility (3.7),
//! and each task is awarded independently to its L_j lowest-cost bidders covering E_j (3.12,
//! 2.6), exactly as the improved auction picks winners. One round, no reward feedback. A robot may
//! win several tasks (`parallel_multiple_wins`, Otte et al.); with it off, tasks are awarded in
//! id order among the robots not yet awarded.

use crate::hunt::auction::{select_winners, Award, Bid, Coalition};
use crate::hunt::cost::{auctioneer_cost, bid_value};
use crate::hunt::model::{Robot, RobotId, Task, TaskId};
use crate::hunt::params::HuntParams;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// The result of one parallel auction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParallelOutcome {
    pub coalitions: BTreeMap<TaskId, Coalition>,
    pub unassigned: Vec<TaskId>,
    /// C (3.13).
    pub auctioneer_cost: f64,
    /// Y (3.14).
    pub total_utility: f64,
    /// One announcement, every bid, every award.
    pub messages: usize,
}

/// Run the parallel auction of `tasks` among `robots` at z_j = `parallel_reward_fraction` z_jmax.
pub fn run_parallel_auction(tasks: &[Task], robots: &[Robot], p: &HuntParams) -> ParallelOutcome {
    let reward = |t: &Task| p.parallel_reward_fraction * t.reward_cap;
    // Every robot bids on every task it can take with a positive utility.
    let mut bids: BTreeMap<TaskId, Vec<Bid>> = tasks.iter().map(|t| (t.id, Vec::new())).collect();
    for r in robots {
        for t in tasks {
            if let Some(y) = bid_value(r, t, reward(t), p).filter(|y| *y > 0.0) {
                bids.get_mut(&t.id).expect("task").push(Bid {
                    round: 1,
                    robot: r.id,
                    task: t.id,
                    utility: y,
                    position: [r.position.x, r.position.y],
                    resources: r.resources,
                });
            }
        }
    }
    let mut messages = 1 + bids.values().map(Vec::len).sum::<usize>();
    let mut taken: BTreeSet<RobotId> = BTreeSet::new();
    let mut coalitions = BTreeMap::new();
    let mut unassigned = Vec::new();
    for t in tasks {
        let z = reward(t);
        let eligible: Vec<&Bid> = bids[&t.id]
            .iter()
            .filter(|b| p.parallel_multiple_wins || !taken.contains(&b.robot))
            .collect();
        match select_winners(t, &eligible, z, p) {
            Some(mut w) => {
                w.sort_by_key(|b| b.robot);
                taken.extend(w.iter().map(|b| b.robot));
                messages += 1;
                let costs = w
                    .iter()
                    .map(|b| {
                        auctioneer_cost(z, (t.position - swarm::geometry::v2(b.position)).norm())
                    })
                    .collect();
                coalitions.insert(
                    t.id,
                    Coalition {
                        award: Award {
                            round: 1,
                            task: t.id,
                            reward: z,
                            members: w.iter().map(|b| b.robot).collect(),
                        },
                        costs,
                        utilities: w.iter().map(|b| b.utility).collect(),
                    },
                );
            }
            None => unassigned.push(t.id),
        }
    }
    let auctioneer_cost = coalitions
        .values()
        .flat_map(|c: &Coalition| c.costs.iter())
        .sum();
    let total_utility = coalitions
        .values()
        .flat_map(|c: &Coalition| c.utilities.iter())
        .sum();
    ParallelOutcome {
        coalitions,
        unassigned,
        auctioneer_cost,
        total_utility,
        messages,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hunt::auction::run_auction;
    use crate::hunt::model::tests::{robot, task};

    /// T1 at (0,0) and T2 at (4,0), L = 1, cap 100 (z = 0.8 * 100 = 80), E = 1 of each type, speed
    /// 1.0; R1 at (1,0) and R2 at (10,0), g = 0.5 on both, speed 0.8, one of each type.
    fn tiny() -> (Vec<Task>, Vec<Robot>) {
        let mut tasks = vec![
            task(1, 0.0, 0.0, [1.0; 6], 1),
            task(2, 4.0, 0.0, [1.0; 6], 1),
        ];
        for t in &mut tasks {
            t.reward_cap = 100.0;
        }
        let robots = [(1, 1.0), (2, 10.0)]
            .iter()
            .map(|&(id, x)| {
                let mut r = robot(id, x, 0.0, [1.0; 6]);
                r.matching = vec![0.5, 0.5];
                r
            })
            .collect();
        (tasks, robots)
    }

    // By hand, (3.9)-(3.10) with m = (0.2, 0.3, 0.5), v_j - v_i = 0.2, L = 1 so r_e = 3.0:
    //   E_ij = 6 * min(1, 1) = 6;  T' = (3.0 + 0.3) / (2 * 0.2 * 1) = 8.25
    //   C = 0.2 * 6 + 0.3 * 8.25 + 0.5 * d / 0.2 = 3.675 + 2.5 d
    //   y = 80 * 0.5 - C = 36.325 - 2.5 d
    //   R1: d(T1) = 1 -> y = 33.825, c = 81;  d(T2) = 3 -> y = 28.825, c = 83
    //   R2: d(T1) = 10 -> y = 11.325, c = 90; d(T2) = 6 -> y = 21.325, c = 86
    // Parallel, multiple wins: T1 -> R1 (81 < 90), T2 -> R1 (83 < 86):
    //   C = 81 + 83 = 164, Y = 33.825 + 28.825 = 62.65
    // Parallel, one task each: T1 -> R1, T2 -> R2: C = 81 + 86 = 167, Y = 33.825 + 21.325 = 55.15
    // Improved: R1 bids T1 (33.825 > 28.825), R2 bids T2 (21.325 > 11.325): the same as the
    // one-task-each parallel outcome, in one round.

    #[test]
    fn tiny_case_by_hand_multiple_wins() {
        let (tasks, robots) = tiny();
        let out = run_parallel_auction(&tasks, &robots, &HuntParams::default());
        assert_eq!(out.coalitions[&1].award.members, vec![1]);
        assert_eq!(out.coalitions[&2].award.members, vec![1]);
        assert!((out.auctioneer_cost - 164.0).abs() < 1e-9);
        assert!(
            (out.total_utility - 62.65).abs() < 1e-9,
            "{}",
            out.total_utility
        );
        assert_eq!(out.messages, 1 + 4 + 2);
    }

    #[test]
    fn tiny_case_by_hand_one_task_per_robot() {
        let (tasks, robots) = tiny();
        let p = HuntParams {
            parallel_multiple_wins: false,
            ..HuntParams::default()
        };
        let out = run_parallel_auction(&tasks, &robots, &p);
        assert_eq!(out.coalitions[&2].award.members, vec![2]);
        assert!((out.auctioneer_cost - 167.0).abs() < 1e-9);
        assert!((out.total_utility - 55.15).abs() < 1e-9);
        let improved = run_auction(&tasks, &robots, &HuntParams::default());
        assert_eq!(improved.rounds.len(), 1);
        assert!((improved.auctioneer_cost - 167.0).abs() < 1e-9);
        assert!((improved.total_utility - 55.15).abs() < 1e-9);
    }

    #[test]
    fn task_without_enough_bidders_is_unassigned() {
        let (mut tasks, robots) = tiny();
        tasks[1].required_robots = 3;
        let out = run_parallel_auction(&tasks, &robots, &HuntParams::default());
        assert_eq!(out.unassigned, vec![2]);
        assert_eq!(out.coalitions.len(), 1);
    }
}
