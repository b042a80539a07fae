//! On-line task re-planning (thesis sec. 3.2.5, spec 3.8), as decision rules on the current
//! hunts: a new target appearing (coalitions whose total utility (3.21) is higher there release
//! the members who gain by moving, through an auction of the new task with reward feedback), swaps
//! of two robots between coalitions, assistance to a coalition that has not captured its target,
//! and recruiting a replacement when a member dies (the thesis's future-work item 4).
//!
//! Utilities are y_ij = z_j g_ij - C_ij (3.16) at the robots' current positions and the hunts'
//! rewards; U_jo of (3.21) is read as z_jo g_ijo (spec 3.8 [INFERRED]).

use crate::hunt::auction::{Auctioneer, Award, Bid, Finish, RoundRecord};
use crate::hunt::cost::bid_value;
use crate::hunt::model::{coalition_covers, feasible, sum_resources, Robot, RobotId, Task, TaskId};
use crate::hunt::params::HuntParams;
use std::collections::BTreeMap;
use swarm::geometry::Vec2;

/// One coalition hunting one target.
#[derive(Clone, Debug, PartialEq)]
pub struct Hunt {
    pub task: TaskId,
    /// Phi_j, ascending ids.
    pub members: Vec<RobotId>,
    /// z_j paid to each member.
    pub reward: f64,
    /// The target is encircled: the coalition is finished and its members free to assist.
    pub captured: bool,
    /// When the hunt (re)started, minutes.
    pub since: f64,
}

/// The robots and targets as the re-planner sees them (ids to current state).
pub struct World<'a> {
    pub robots: &'a BTreeMap<RobotId, Robot>,
    pub tasks: &'a BTreeMap<TaskId, Task>,
}

/// y_ij for robot `i` on task `j` at reward `z`; `None` if q_ij = 0.
pub fn utility(w: &World, i: RobotId, j: TaskId, z: f64, p: &HuntParams) -> Option<f64> {
    bid_value(&w.robots[&i], &w.tasks[&j], z, p)
}

/// U^Phi_j = sum_{i in Phi} (z_j g_ij - C_ij), eq. (3.21); -infinity if a member cannot take j.
pub fn coalition_utility(w: &World, members: &[RobotId], j: TaskId, z: f64, p: &HuntParams) -> f64 {
    members
        .iter()
        .map(|i| utility(w, *i, j, z, p).unwrap_or(f64::NEG_INFINITY))
        .sum()
}

/// The robots that hunt nothing or whose hunt is captured (free to join another).
pub fn free_robots(w: &World, hunts: &[Hunt]) -> Vec<RobotId> {
    w.robots
        .keys()
        .copied()
        .filter(|i| !hunts.iter().any(|h| !h.captured && h.members.contains(i)))
        .collect()
}

/// What the re-planner did about a new target.
#[derive(Clone, Debug, PartialEq)]
pub struct NewTargetOutcome {
    /// Tasks of the coalitions with U^Phi_new > U^Phi_old (3.21), which publish the new target.
    pub interested: Vec<TaskId>,
    /// The coalition formed for the new target, if the auction filled it.
    pub award: Option<Award>,
    /// The re-auction's rounds (rewards and bid counts).
    pub rounds: Vec<RoundRecord>,
    pub finish: Option<Finish>,
    /// The hunts after the split: winners moved to the new task, the others keep theirs.
    pub hunts: Vec<Hunt>,
}

/// Sec. 3.2.5 step 2-3: a new target `new` (already in `w.tasks`) appears at time `now`. Every
/// uncaptured coalition compares (3.21) on its target and on `new` at the new reward alpha
/// z_max. If none prefers `new`, everyone keeps its target. Otherwise the auctioneer publishes
/// `new` and runs the reward feedback (3.15): each member of an interested coalition bids when its
/// own utility on `new` beats its utility on its current target, each free robot when it is
/// positive; the winners split off (case 1, or the L lowest-cost of case 2), the losers keep their
/// target; with too few bidders the reward keeps rising (case 3) until it settles.
pub fn new_target(
    w: &World,
    hunts: &[Hunt],
    new: TaskId,
    now: f64,
    p: &HuntParams,
) -> NewTargetOutcome {
    let task = &w.tasks[&new];
    let z0 = p.alpha * task.reward_cap;
    let interested: Vec<TaskId> = hunts
        .iter()
        .filter(|h| !h.captured)
        .filter(|h| {
            coalition_utility(w, &h.members, new, z0, p)
                > coalition_utility(w, &h.members, h.task, h.reward, p)
        })
        .map(|h| h.task)
        .collect();
    if interested.is_empty() {
        return NewTargetOutcome {
            interested,
            award: None,
            rounds: Vec::new(),
            finish: None,
            hunts: hunts.to_vec(),
        };
    }
    // Who may bid, and what each gives up by moving.
    let mut current: BTreeMap<RobotId, f64> = BTreeMap::new();
    for h in hunts.iter().filter(|h| interested.contains(&h.task)) {
        for i in &h.members {
            current.insert(*i, utility(w, *i, h.task, h.reward, p).unwrap_or(0.0));
        }
    }
    for i in free_robots(w, hunts) {
        current.insert(i, 0.0);
    }
    let mut auctioneer = Auctioneer::new(std::slice::from_ref(task), w.robots.len(), p);
    let mut award = None;
    while let Some(a) = auctioneer.announce() {
        let z = a.tasks[0].reward;
        for (i, keep) in &current {
            if let Some(y) = utility(w, *i, new, z, p).filter(|y| *y > 0.0 && y > keep) {
                let r = &w.robots[i];
                let bid = Bid {
                    round: a.round,
                    robot: *i,
                    task: new,
                    utility: y,
                    position: [r.position.x, r.position.y],
                    resources: r.resources,
                };
                auctioneer.receive(bid).expect("valid bid");
            }
        }
        if let Some(x) = auctioneer.close_round().into_iter().next() {
            award = Some(x);
        }
        if auctioneer.finish().is_some() {
            break;
        }
    }
    let mut out_hunts: Vec<Hunt> = hunts.to_vec();
    if let Some(a) = &award {
        for h in &mut out_hunts {
            h.members.retain(|i| !a.members.contains(i));
        }
        out_hunts.push(Hunt {
            task: new,
            members: a.members.clone(),
            reward: a.reward,
            captured: false,
            since: now,
        });
    }
    NewTargetOutcome {
        interested,
        award,
        rounds: auctioneer.history().to_vec(),
        finish: auctioneer.finish(),
        hunts: out_hunts,
    }
}

/// A swap of robot `i` (hunting `from_task`) with robot `k` (hunting `to_task`).
#[derive(Clone, Debug, PartialEq)]
pub struct Swap {
    pub i: RobotId,
    pub from_task: TaskId,
    pub k: RobotId,
    pub to_task: TaskId,
    /// (U_i,j2 + U_k,j1) - (U_i,j1 + U_k,j2) > 0.
    pub gain: f64,
}

/// The swap gain of sec. 3.2.5 step 4: (U_i,j2 + U_k,j1) - (U_i,j1 + U_k,j2) for i on hunt `a`
/// (target j1) and k on hunt `b` (j2), each at its hunt's reward; `None` if either cannot take the
/// other's target.
pub fn swap_gain(
    w: &World,
    i: RobotId,
    a: &Hunt,
    k: RobotId,
    b: &Hunt,
    p: &HuntParams,
) -> Option<f64> {
    let after = utility(w, i, b.task, b.reward, p)? + utility(w, k, a.task, a.reward, p)?;
    let before = utility(w, i, a.task, a.reward, p)? + utility(w, k, b.task, b.reward, p)?;
    Some(after - before)
}

/// Sec. 3.2.5 step 4, repeated to a fixed point: a robot k of another uncaptured coalition that is
/// closer to member i's hunting point (its target if it has no point yet, `points`) than i is,
/// swaps with i when both can take the other's target, both coalitions still cover their E_j
/// (2.6), and the swap gain is positive. The best-gain swap is applied first; every swap raises
/// the total utility, so this ends. Returns the swaps in order and updates `hunts`.
pub fn apply_swaps(
    w: &World,
    hunts: &mut [Hunt],
    points: &BTreeMap<RobotId, Vec2>,
    p: &HuntParams,
) -> Vec<Swap> {
    let mut done = Vec::new();
    loop {
        let mut best: Option<(usize, usize, Swap)> = None;
        for a in 0..hunts.len() {
            for b in 0..hunts.len() {
                if a == b || hunts[a].captured || hunts[b].captured {
                    continue;
                }
                for &i in &hunts[a].members {
                    let goal = points
                        .get(&i)
                        .copied()
                        .unwrap_or(w.tasks[&hunts[a].task].position);
                    for &k in &hunts[b].members {
                        let (xi, xk) = (w.robots[&i].position, w.robots[&k].position);
                        if (xk - goal).norm() >= (xi - goal).norm() {
                            continue;
                        }
                        let Some(gain) = swap_gain(w, i, &hunts[a], k, &hunts[b], p) else {
                            continue;
                        };
                        if gain <= 1e-9
                            || !covers_after(w, &hunts[a], i, k)
                            || !covers_after(w, &hunts[b], k, i)
                        {
                            continue;
                        }
                        if best.as_ref().is_none_or(|(_, _, s)| gain > s.gain) {
                            let s = Swap {
                                i,
                                from_task: hunts[a].task,
                                k,
                                to_task: hunts[b].task,
                                gain,
                            };
                            best = Some((a, b, s));
                        }
                    }
                }
            }
        }
        let Some((a, b, s)) = best else {
            return done;
        };
        replace(&mut hunts[a].members, s.i, s.k);
        replace(&mut hunts[b].members, s.k, s.i);
        done.push(s);
    }
}

fn replace(members: &mut Vec<RobotId>, out: RobotId, inn: RobotId) {
    members.retain(|m| *m != out);
    members.push(inn);
    members.sort();
}

fn covers_after(w: &World, h: &Hunt, out: RobotId, inn: RobotId) -> bool {
    let members = h
        .members
        .iter()
        .filter(|m| **m != out)
        .chain(std::iter::once(&inn));
    coalition_covers(
        members.map(|m| &w.robots[m].resources),
        &w.tasks[&h.task].resources,
    )
}

/// Sec. 3.2.5 (a) and step 5: an uncaptured hunt needs help when it is short of L_j robots or of
/// E_j (2.6), or has run `assistance_timeout` minutes without capture.
pub fn needs_assistance(w: &World, h: &Hunt, now: f64, p: &HuntParams) -> bool {
    if h.captured {
        return false;
    }
    let t = &w.tasks[&h.task];
    h.members.len() < t.required_robots
        || !coalition_covers(
            h.members.iter().map(|m| &w.robots[m].resources),
            &t.resources,
        )
        || now - h.since >= p.assistance_timeout
}

/// Help for a hunt: the robots recruited and the raised reward.
#[derive(Clone, Debug, PartialEq)]
pub struct Assistance {
    pub recruits: Vec<RobotId>,
    /// z_j after the raise (3.15 with the missing robots as the deficit).
    pub reward: f64,
    /// The coalition is still short of L_j or E_j after recruiting everyone available.
    pub still_short: bool,
}

/// Recruit among `candidates` (free robots: finished coalitions, unassigned) for hunt `h`: the
/// auctioneer raises z_j by (3.15) with the deficit max(L_j - |Phi|, 1) (it "keeps raising that
/// target's reward"), then the feasible candidates with a positive utility at that reward join in
/// decreasing utility (ties: nearer, lower id) until the coalition has L_j robots and covers E_j.
/// When it has L_j but still misses resources, the candidate that most reduces the missing
/// resources joins next (the coalition may then exceed L_j: the thesis's assisted T4 has 4).
pub fn assist(
    w: &World,
    h: &Hunt,
    candidates: &[RobotId],
    n_r: usize,
    p: &HuntParams,
) -> Assistance {
    let t = &w.tasks[&h.task];
    let deficit = (t.required_robots as i64 - h.members.len() as i64).max(1);
    let reward = crate::hunt::auction::feedback(h.reward, t.reward_cap, -deficit, n_r, p);
    let mut pool: Vec<(RobotId, f64, f64)> = candidates
        .iter()
        .filter(|i| !h.members.contains(i) && feasible(&w.robots[i], t))
        .filter_map(|i| {
            let y = utility(w, *i, h.task, reward, p)?;
            let d = (w.robots[i].position - t.position).norm();
            (y > 0.0).then_some((*i, y, d))
        })
        .collect();
    pool.sort_by(|a, b| {
        b.1.total_cmp(&a.1)
            .then(a.2.total_cmp(&b.2))
            .then(a.0.cmp(&b.0))
    });
    let mut members = h.members.clone();
    let mut recruits = Vec::new();
    let covered =
        |m: &[RobotId]| coalition_covers(m.iter().map(|i| &w.robots[i].resources), &t.resources);
    while !pool.is_empty() && (members.len() < t.required_robots || !covered(&members)) {
        let pick = if members.len() < t.required_robots {
            0
        } else {
            // Most reduction of the missing resources, ties by the utility order.
            let missing = |m: &[RobotId]| -> f64 {
                let have = sum_resources(m.iter().map(|i| &w.robots[i].resources));
                have.iter()
                    .zip(&t.resources)
                    .map(|(h, n)| (n - h).max(0.0))
                    .sum()
            };
            let base = missing(&members);
            let (k, gain) = pool
                .iter()
                .enumerate()
                .map(|(k, (i, _, _))| {
                    let mut m = members.clone();
                    m.push(*i);
                    (k, base - missing(&m))
                })
                .fold(
                    (0, f64::NEG_INFINITY),
                    |acc, x| if x.1 > acc.1 { x } else { acc },
                );
            if gain <= 0.0 {
                break;
            }
            k
        };
        let (i, _, _) = pool.remove(pick);
        members.push(i);
        recruits.push(i);
    }
    let still_short = members.len() < t.required_robots || !covered(&members);
    Assistance {
        recruits,
        reward,
        still_short,
    }
}

/// A member died (its agent process stopped, future-work item 4): drop it and recruit a
/// replacement among the free robots with [`assist`]. Returns the updated hunt and what was done.
pub fn replace_dead(
    w: &World,
    h: &Hunt,
    dead: RobotId,
    free: &[RobotId],
    n_r: usize,
    p: &HuntParams,
) -> (Hunt, Assistance) {
    let mut h = h.clone();
    h.members.retain(|m| *m != dead);
    let candidates: Vec<RobotId> = free.iter().copied().filter(|i| *i != dead).collect();
    let help = assist(w, &h, &candidates, n_r, p);
    h.members.extend(&help.recruits);
    h.members.sort();
    h.reward = help.reward;
    (h, help)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hunt::model::tests::{robot, task};

    fn world(
        robots: Vec<Robot>,
        tasks: Vec<Task>,
    ) -> (BTreeMap<RobotId, Robot>, BTreeMap<TaskId, Task>) {
        (
            robots.into_iter().map(|r| (r.id, r)).collect(),
            tasks.into_iter().map(|t| (t.id, t)).collect(),
        )
    }

    fn with_g(mut r: Robot, g: &[f64]) -> Robot {
        r.matching = g.to_vec();
        r
    }

    #[test]
    fn new_target_splits_the_members_who_gain() {
        // T1 (L 3) hunted by R1-R3 at z = 400; T2 (L 2, cap 1000) appears beside them.
        // g on T1 = 0.3 for all; on T2: R1, R2 0.4, R3 0.05. At z_2 = 800: R1, R2 gain
        // (320 - C vs 120 - C), R3 does not (40 - C < 120 - C), so exactly 2 bids: case 1.
        let t1 = task(1, 5.0, 5.0, [1.0; 6], 3);
        let mut t2 = task(2, 5.5, 5.0, [1.0; 6], 2);
        t2.reward_cap = 1000.0;
        let robots = vec![
            with_g(robot(1, 4.0, 5.0, [1.0; 6]), &[0.3, 0.4]),
            with_g(robot(2, 4.0, 5.5, [1.0; 6]), &[0.3, 0.4]),
            with_g(robot(3, 4.0, 4.5, [1.0; 6]), &[0.3, 0.05]),
        ];
        let (robots, tasks) = world(robots, vec![t1, t2]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let hunts = vec![Hunt {
            task: 1,
            members: vec![1, 2, 3],
            reward: 400.0,
            captured: false,
            since: 0.0,
        }];
        let p = HuntParams::default();
        // (3.21): U on T1 = 3 * 120 - sum C; on T2 = 2 * 320 + 40 - sum C': higher.
        assert!(
            coalition_utility(&w, &[1, 2, 3], 2, 800.0, &p)
                > coalition_utility(&w, &[1, 2, 3], 1, 400.0, &p)
        );
        let out = new_target(&w, &hunts, 2, 7.0, &p);
        assert_eq!(out.interested, vec![1]);
        let a = out.award.unwrap();
        assert_eq!(a.members, vec![1, 2]);
        assert_eq!(out.rounds.len(), 1);
        assert_eq!(
            out.hunts[0].members,
            vec![3],
            "the loser keeps the original target"
        );
        assert_eq!(out.hunts[1].members, vec![1, 2]);
        assert_eq!(out.hunts[1].since, 7.0);
    }

    #[test]
    fn new_target_ignored_when_no_coalition_prefers_it() {
        let t1 = task(1, 5.0, 5.0, [1.0; 6], 2);
        let t2 = task(2, 9.0, 9.0, [1.0; 6], 2);
        let robots = vec![
            with_g(robot(1, 5.0, 4.0, [1.0; 6]), &[0.5, 0.1]),
            with_g(robot(2, 5.0, 6.0, [1.0; 6]), &[0.5, 0.1]),
        ];
        let (robots, tasks) = world(robots, vec![t1, t2]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let hunts = vec![Hunt {
            task: 1,
            members: vec![1, 2],
            reward: 400.0,
            captured: false,
            since: 0.0,
        }];
        let out = new_target(&w, &hunts, 2, 1.0, &HuntParams::default());
        assert!(out.interested.is_empty() && out.award.is_none());
        assert_eq!(out.hunts, hunts);
    }

    #[test]
    fn crossed_robots_swap_when_it_pays() {
        // R1 hunts T1 at (0,0) but stands at (9,0) next to T2; R2 hunts T2 at (10,0) but stands
        // at (1,0). Same g: the swap shortens both pursuits, gain
        // = 0.5 * (d_11 + d_22 - d_12 - d_21) / 0.2 = 0.5 * (9 + 9 - 1 - 1) / 0.2 = 40.
        let t1 = task(1, 0.0, 0.0, [1.0; 6], 1);
        let t2 = task(2, 10.0, 0.0, [1.0; 6], 1);
        let robots = vec![
            with_g(robot(1, 9.0, 0.0, [1.0; 6]), &[0.3, 0.3]),
            with_g(robot(2, 1.0, 0.0, [1.0; 6]), &[0.3, 0.3]),
        ];
        let (robots, tasks) = world(robots, vec![t1, t2]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let h = |task, m| Hunt {
            task,
            members: vec![m],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let mut hunts = vec![h(1, 1), h(2, 2)];
        let p = HuntParams::default();
        assert!((swap_gain(&w, 1, &hunts[0], 2, &hunts[1], &p).unwrap() - 40.0).abs() < 1e-9);
        let swaps = apply_swaps(&w, &mut hunts, &BTreeMap::new(), &p);
        assert_eq!(swaps.len(), 1);
        assert_eq!(hunts[0].members, vec![2]);
        assert_eq!(hunts[1].members, vec![1]);
        // A fixed point: nothing more to swap.
        assert!(apply_swaps(&w, &mut hunts, &BTreeMap::new(), &p).is_empty());
    }

    #[test]
    fn no_swap_when_matching_outweighs_distance() {
        // Same geometry, but R1's g on T1 is 0.9 and on T2 0.1: moving loses 0.8*400 = 320 of
        // benefit against 40 of cost.
        let t1 = task(1, 0.0, 0.0, [1.0; 6], 1);
        let t2 = task(2, 10.0, 0.0, [1.0; 6], 1);
        let robots = vec![
            with_g(robot(1, 9.0, 0.0, [1.0; 6]), &[0.9, 0.1]),
            with_g(robot(2, 1.0, 0.0, [1.0; 6]), &[0.3, 0.3]),
        ];
        let (robots, tasks) = world(robots, vec![t1, t2]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let h = |task, m| Hunt {
            task,
            members: vec![m],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let mut hunts = vec![h(1, 1), h(2, 2)];
        assert!(apply_swaps(&w, &mut hunts, &BTreeMap::new(), &HuntParams::default()).is_empty());
    }

    #[test]
    fn assistance_recruits_the_best_free_robots_and_raises_the_reward() {
        // T1 needs 3 and 3 units of type 1; its coalition has R1 (1 unit). Free: R2 (far, 2
        // units), R3 (near, 1 unit), R4 (near but too slow for T1), R5 (near, 1 unit).
        let mut t1 = task(1, 5.0, 5.0, [3.0, 1.0, 1.0, 1.0, 1.0, 1.0], 3);
        t1.min_robot_speed = 0.7;
        let mut slow = robot(4, 5.2, 5.0, [5.0; 6]);
        slow.speed = 0.5;
        let robots = vec![
            robot(1, 5.0, 4.0, [1.0; 6]),
            robot(2, 9.0, 9.0, [2.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
            robot(3, 5.0, 5.5, [1.0; 6]),
            slow,
            robot(5, 5.0, 6.0, [1.0; 6]),
        ];
        let (robots, tasks) = world(robots, vec![t1]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let h = Hunt {
            task: 1,
            members: vec![1],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let p = HuntParams::default();
        assert!(needs_assistance(&w, &h, 1.0, &p), "short of L_j");
        let help = assist(&w, &h, &[2, 3, 4, 5], 5, &p);
        // Raise (3.15) with deficit 2 of n_r = 5: 400 + 0.4 * 100 = 440.
        assert!((help.reward - 440.0).abs() < 1e-9);
        // By utility (same g): R3 and R5 (nearest) fill L_j = 3, but type 1 is then 3 units:
        // covered. R4 is never taken (speed), R2 not needed.
        assert_eq!(help.recruits, vec![3, 5]);
        assert!(!help.still_short);
    }

    #[test]
    fn assistance_exceeds_l_j_only_to_cover_resources() {
        let t1 = task(1, 5.0, 5.0, [4.0, 1.0, 1.0, 1.0, 1.0, 1.0], 2);
        let robots = vec![
            robot(1, 5.0, 4.0, [1.0; 6]),
            robot(2, 5.0, 5.5, [1.0; 6]),
            robot(3, 9.0, 9.0, [3.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
        ];
        let (robots, tasks) = world(robots, vec![t1]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let h = Hunt {
            task: 1,
            members: vec![1],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let help = assist(&w, &h, &[2, 3], 3, &HuntParams::default());
        // R2 first (nearer, same g): 2 robots, 2 units < 4: R3 joins for its 3 units.
        assert_eq!(help.recruits, vec![2, 3]);
        assert!(!help.still_short);
    }

    #[test]
    fn timeout_triggers_assistance_for_a_full_coalition() {
        let t1 = task(1, 5.0, 5.0, [1.0; 6], 1);
        let (robots, tasks) = world(vec![robot(1, 5.0, 4.0, [1.0; 6])], vec![t1]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let mut h = Hunt {
            task: 1,
            members: vec![1],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let p = HuntParams::default();
        assert!(!needs_assistance(&w, &h, p.assistance_timeout - 0.1, &p));
        assert!(needs_assistance(&w, &h, p.assistance_timeout, &p));
        h.captured = true;
        assert!(!needs_assistance(&w, &h, 1e9, &p));
    }

    #[test]
    fn dead_member_is_replaced_by_a_free_robot() {
        let t1 = task(1, 5.0, 5.0, [2.0, 1.0, 1.0, 1.0, 1.0, 1.0], 2);
        let robots = vec![
            robot(1, 5.0, 4.0, [1.0; 6]),
            robot(2, 5.0, 6.0, [1.0; 6]),
            robot(3, 7.0, 5.0, [1.0; 6]),
        ];
        let (robots, tasks) = world(robots, vec![t1]);
        let w = World {
            robots: &robots,
            tasks: &tasks,
        };
        let h = Hunt {
            task: 1,
            members: vec![1, 2],
            reward: 400.0,
            captured: false,
            since: 0.0,
        };
        let hunts = [h.clone()];
        let free = free_robots(&w, &hunts);
        assert_eq!(free, vec![3]);
        let (after, help) = replace_dead(&w, &h, 2, &free, 3, &HuntParams::default());
        assert_eq!(after.members, vec![1, 3]);
        assert!(!help.still_short);
        // Nobody free: the hunt is left short, and says so.
        let (after, help) = replace_dead(&w, &h, 2, &[], 3, &HuntParams::default());
        assert_eq!(after.members, vec![1]);
        assert!(help.still_short && help.recruits.is_empty());
    }
}
