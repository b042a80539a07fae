//! The Parallel auction baseline of chapter 3's comparison (Otte, Kuhlman & Sofge 2020, the
//! thesis's Ref. [68]; spec 7.2 and 11): the auctioneer announces every task once at a fixed
//! reward, every robot bids on every task it can take (q_ij = 1) with a positive utility (3.7),
//! and each task is awarded independently to its L_j lowest-cost bidders covering E_j (3.12,
//! 2.6), exactly as the improved auction picks winners. One round, no reward feedback. A robot may
//! win several tasks (`parallel_multiple_wins`, Otte et al.); with it off, tasks are awarded in
//! id order among the robots not yet awarded.

use crate::hunt::auction::{
    award_naming, select_winners, totals, Announcement, AuctionError, Award, Bid, Closed,
    Coalition, Finish, RoundRecord, TaskInfo,
};
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

/// The auctioneer of the parallel auction as a state machine, the twin of
/// [`crate::hunt::auction::Auctioneer`] so that the live auctioneer can run either: one
/// announcement of every task at its fixed reward, the bids of that round (several a robot,
/// one a task), then one close that awards each task on its own.
#[derive(Clone, Debug)]
pub struct ParallelAuctioneer {
    params: HuntParams,
    /// In id order.
    tasks: Vec<Task>,
    round_open: bool,
    announced: bool,
    bids: BTreeMap<TaskId, Vec<Bid>>,
    coalitions: BTreeMap<TaskId, Coalition>,
    history: Vec<RoundRecord>,
    finish: Option<Finish>,
}

impl ParallelAuctioneer {
    pub fn new(tasks: &[Task], params: &HuntParams) -> Self {
        let mut tasks = tasks.to_vec();
        tasks.sort_by_key(|t| t.id);
        Self {
            params: params.clone(),
            bids: tasks.iter().map(|t| (t.id, Vec::new())).collect(),
            tasks,
            round_open: false,
            announced: false,
            coalitions: BTreeMap::new(),
            history: Vec::new(),
            finish: None,
        }
    }

    /// z_j = `parallel_reward_fraction` z_jmax, fixed (no feedback).
    pub fn reward(&self, t: &Task) -> f64 {
        self.params.parallel_reward_fraction * t.reward_cap
    }

    /// The one announcement (round 1), then `None`.
    pub fn announce(&mut self) -> Option<Announcement> {
        if self.announced {
            return None;
        }
        self.announced = true;
        self.round_open = true;
        Some(Announcement {
            round: 1,
            tasks: self
                .tasks
                .iter()
                .map(|t| TaskInfo::of(t, self.reward(t)))
                .collect(),
        })
    }

    /// One bid of the round: a robot may bid on every task, once each.
    pub fn receive(&mut self, bid: Bid) -> Result<(), AuctionError> {
        if !self.round_open {
            return Err(AuctionError::NoOpenRound);
        }
        if bid.round != 1 {
            return Err(AuctionError::WrongRound {
                got: bid.round,
                current: 1,
            });
        }
        let Some(list) = self.bids.get_mut(&bid.task) else {
            return Err(AuctionError::UnknownTask(bid.task));
        };
        if list.iter().any(|b| b.robot == bid.robot) {
            return Err(AuctionError::DuplicateBid(bid.robot));
        }
        list.push(bid);
        Ok(())
    }

    /// Closes the round: each task, in id order, goes to its L_j lowest-cost bidders covering
    /// E_j (`select_winners`, as the improved auction picks them); without
    /// `parallel_multiple_wins`, only among robots not awarded a task before. Returns the
    /// awards; the auction is then over.
    pub fn close_round(&mut self) -> Vec<Award> {
        if !self.round_open {
            return Vec::new();
        }
        self.round_open = false;
        let mut taken: BTreeSet<RobotId> = BTreeSet::new();
        let mut awarded = Vec::new();
        for t in &self.tasks {
            let z = self.reward(t);
            let eligible: Vec<&Bid> = self.bids[&t.id]
                .iter()
                .filter(|b| self.params.parallel_multiple_wins || !taken.contains(&b.robot))
                .collect();
            if let Some(mut w) = select_winners(t, &eligible, z, &self.params) {
                w.sort_by_key(|b| b.robot);
                taken.extend(w.iter().map(|b| b.robot));
                let costs = w
                    .iter()
                    .map(|b| {
                        auctioneer_cost(z, (t.position - swarm::geometry::v2(b.position)).norm())
                    })
                    .collect();
                self.coalitions.insert(
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
                awarded.push(t.id);
            }
        }
        self.history.push(RoundRecord {
            round: 1,
            rewards: self.tasks.iter().map(|t| (t.id, self.reward(t))).collect(),
            bids: self.bids.iter().map(|(j, b)| (*j, b.len())).collect(),
            awarded: awarded.clone(),
        });
        self.finish = Some(if awarded.len() == self.tasks.len() {
            Finish::AllAwarded
        } else {
            Finish::OneRound
        });
        awarded
            .iter()
            .map(|j| self.coalitions[j].award.clone())
            .collect()
    }

    pub fn closed(&self) -> Option<Closed> {
        self.finish.map(|finish| Closed { round: 1, finish })
    }
    pub fn finish(&self) -> Option<Finish> {
        self.finish
    }
    /// The first award (in task order) naming `robot`.
    pub fn award_of(&self, robot: RobotId) -> Option<&Award> {
        award_naming(&self.coalitions, robot)
    }
    pub fn round(&self) -> u32 {
        self.announced as u32
    }
    pub fn history(&self) -> &[RoundRecord] {
        &self.history
    }
    pub fn coalitions(&self) -> &BTreeMap<TaskId, Coalition> {
        &self.coalitions
    }
    /// Tasks not awarded (all of them before the close).
    pub fn unassigned(&self) -> Vec<TaskId> {
        self.tasks
            .iter()
            .map(|t| t.id)
            .filter(|j| !self.coalitions.contains_key(j))
            .collect()
    }
    /// C (3.13) over the awards as made.
    pub fn total_cost(&self) -> f64 {
        totals(&self.coalitions).0
    }
    /// Y (3.14) over the awards as made.
    pub fn total_utility(&self) -> f64 {
        totals(&self.coalitions).1
    }
}

/// A robot's bids in the parallel auction: one on every announced task it can take (q_ij = 1)
/// with a positive utility (3.7, 3.16), in task order.
pub fn parallel_bids(robot: &Robot, a: &Announcement, p: &HuntParams) -> Vec<Bid> {
    a.tasks
        .iter()
        .filter_map(|info| {
            let y = bid_value(robot, &info.task(), info.reward, p).filter(|y| *y > 0.0)?;
            Some(Bid {
                round: a.round,
                robot: robot.id,
                task: info.id,
                utility: y,
                position: [robot.position.x, robot.position.y],
                resources: robot.resources,
            })
        })
        .collect()
}

/// A robot hunts one target at a time: of several parallel wins it keeps the one it bid the
/// highest utility on (ties: the lower task id) and leaves the other coalitions, which are then
/// short of it (the live auctioneer's assistance fills them). `utility(robot, task)` is the bid.
pub fn one_task_each(awards: &[Award], utility: &dyn Fn(RobotId, TaskId) -> f64) -> Vec<Award> {
    let mut keep: BTreeMap<RobotId, (TaskId, f64)> = BTreeMap::new();
    for a in awards {
        for &r in &a.members {
            let y = utility(r, a.task);
            let better = keep
                .get(&r)
                .is_none_or(|&(j, by)| y > by || (y == by && a.task < j));
            if better {
                keep.insert(r, (a.task, y));
            }
        }
    }
    awards
        .iter()
        .map(|a| Award {
            members: a
                .members
                .iter()
                .copied()
                .filter(|r| keep[r].0 == a.task)
                .collect(),
            ..a.clone()
        })
        .collect()
}

/// Run the parallel auction of `tasks` among `robots` at z_j = `parallel_reward_fraction` z_jmax.
pub fn run_parallel_auction(tasks: &[Task], robots: &[Robot], p: &HuntParams) -> ParallelOutcome {
    let mut auctioneer = ParallelAuctioneer::new(tasks, p);
    let a = auctioneer.announce().expect("the one announcement");
    let mut messages = 1;
    // Every robot bids on every task it can take with a positive utility.
    for r in robots {
        for bid in parallel_bids(r, &a, p) {
            messages += 1;
            auctioneer.receive(bid).expect("a valid bid");
        }
    }
    messages += auctioneer.close_round().len();
    ParallelOutcome {
        coalitions: auctioneer.coalitions().clone(),
        unassigned: auctioneer.unassigned(),
        auctioneer_cost: auctioneer.total_cost(),
        total_utility: auctioneer.total_utility(),
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
    fn the_state_machine_takes_several_bids_a_robot_but_one_a_task() {
        let (tasks, robots) = tiny();
        let p = HuntParams::default();
        let mut a = ParallelAuctioneer::new(&tasks, &p);
        // A bid before the announcement (made from a copy that announced) is refused.
        let early = parallel_bids(&robots[0], &a.clone().announce().unwrap(), &p);
        assert_eq!(a.receive(early[0].clone()), Err(AuctionError::NoOpenRound));
        let ann = a.announce().unwrap();
        assert_eq!(ann.tasks[0].reward, 80.0, "0.8 x 100, fixed");
        assert!(a.announce().is_none(), "one round only");
        let bids = parallel_bids(&robots[0], &ann, &p);
        assert_eq!(bids.len(), 2, "R1 bids on both tasks");
        assert!((bids[0].utility - 33.825).abs() < 1e-9);
        assert!((bids[1].utility - 28.825).abs() < 1e-9);
        for b in &bids {
            a.receive(b.clone()).unwrap();
        }
        assert_eq!(
            a.receive(bids[0].clone()),
            Err(AuctionError::DuplicateBid(1))
        );
        let awards = a.close_round();
        assert_eq!(awards.len(), 2);
        assert_eq!(a.finish(), Some(Finish::AllAwarded));
        assert_eq!(a.history()[0].bids[&1], 1);
    }

    #[test]
    fn a_robot_with_several_wins_keeps_its_best_and_leaves_the_others_short() {
        // The multiple-wins outcome of `tiny`: R1 wins T1 (y = 33.825) and T2 (y = 28.825).
        let (tasks, robots) = tiny();
        let out = run_parallel_auction(&tasks, &robots, &HuntParams::default());
        let awards: Vec<Award> = out.coalitions.values().map(|c| c.award.clone()).collect();
        let y = |r: RobotId, j: TaskId| {
            let c = &out.coalitions[&j];
            let k = c.award.members.iter().position(|m| *m == r).unwrap();
            c.utilities[k]
        };
        let kept = one_task_each(&awards, &y);
        assert_eq!(kept[0].members, vec![1], "T1 keeps R1 (33.825 > 28.825)");
        assert!(kept[1].members.is_empty(), "T2 is left short");
        // A tie goes to the lower task id.
        let kept = one_task_each(&awards, &|_, _| 1.0);
        assert_eq!((kept[0].members.len(), kept[1].members.len()), (1, 0));
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
