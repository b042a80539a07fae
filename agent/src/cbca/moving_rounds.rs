//! Round runs in which the robots MOVE along their plans between re-planning instants (thesis
//! sec. 4.2.5, Example 2, Figs. 4.4-4.5; issue 18's "Fig. 4.5"): the kernels' stand-in for the
//! thesis's MATLAB re-planning runs, without the hunt world's evaders (targets stand still).
//!
//! At t = 0 the temporary groups (components of the `radius_km` radio graph) run CBCA
//! (Algorithms 1 + 2 over the round radio, rounds.rs), each robot knowing its detections plus
//! the undetected targets it is nearest to (`PriorInfo::DetectionPlusNearest`). Then, every
//! `dt` time units:
//! - **motion**: a robot goes straight, at its speed, to the first task of its path whose
//!   coalition (the robots whose paths hold it) has L_j members; it skips a task short of members
//!   (shelved: "until another coalition discovers it");
//! - **capture and hold** (principle 4): when every member of a full coalition is at the target,
//!   the target is captured (each member earns w1 V_aj e^(-beta_j t), (4.12) at the capture
//!   time), the members hold it for its hold time, then it is done for everyone;
//! - **local vision** (sec. 4.2.5 case 1): a target a robot comes within the detection radius of
//!   joins its group's knowledge, without re-planning;
//! - **groups meet** (case 2): two planning groups with members within `radius_km` of each other
//!   merge. Robots in their hold time are left out (principle 4; case 2.1, a coalition that has
//!   captured, does not re-plan). For the others (case 2.2): CBCA runs afresh on the merged group
//!   from where each robot is, on the targets the merged group knows and nobody has captured,
//!   their values decayed to now (t_o = now in (4.12)); each robot adopts its new path p_i' only
//!   if S_i(p_i') > S_i(p_i) + sigma_i (4.22, replan::decide), and a robot that switches pays
//!   compensation to the coalitions it abandons (loyalty.rs). A **consistency pass** follows:
//!   consensus runs again with every robot seeded with its decided plan
//!   (`CbcaRobot::seed_plan`), so a loyal robot and a switcher that both claim the last place of
//!   a coalition are settled by Algorithm 2 (the smaller score gives way and is left with what
//!   Algorithm 1 still finds for it: the thesis's R10, whose place R6 takes).
//!
//! Robot i's utility at time t (Fig. 4.5): (4.13) over its path, the tasks it has captured at
//! their realised reward and leg, the tasks still ahead at the reward and legs it expects from
//! where it is now (travel and holds, no waiting), plus the compensation it received less what
//! it paid. The partial leg travelled towards a task it then drops stays sunk (it is in no
//! task's leg), so a robot left without tasks reads 0, as the thesis's R10.
//!
//! Choices (the thesis gives none of this): the merged group's consensus runs on a complete
//! graph (the thesis's group shares its information; relays inside it are assumed); resources
//! left after the captured tasks (4.5) and l_i less the captured tasks bound the new plans;
//! holding robots keep their paths; an idle robot's Ē_i is 0 (it leaves no coalition, so
//! (4.22) holds it back by nothing but its sunk cost).

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

use super::compare::{cbca_robots, complete_graph};
use super::consensus::CbcaRobot;
use super::grouping::{comm_graph, components, robot_knowledge, PriorInfo};
use super::loyalty::{LoyaltyState, Payment, Threshold};
use super::model::{consumption, Robot, RobotId, Task, TaskBook, TaskId};
use super::params::CbcaParams;
use super::replan::{decide, Proposal, Verdict};
use super::rounds::{run, Radio, RunStats};
use super::score::path_score;

/// The moving run's own parameters (`[cbca.moving]` if it becomes a scenario section).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MovingParams {
    /// Time step (time units): 0.05, i.e. 50 m of travel at the kernels' 1 km per time unit.
    pub dt: f64,
    /// The run stops here at the latest (time units): 15.
    pub horizon: f64,
    /// The radio radius (km) of the temporary groups and of the meetings: the thesis's 1.5 km;
    /// 2.0 gives Example 2 the narrative's two groups (spec 10.3).
    pub radius_km: f64,
    /// Added to every bid of a decided plan in the consistency pass (it must exceed any fresh
    /// marginal gain: the tables' V_a are at most 600): 10,000.
    pub decided_bonus: f64,
}

impl Default for MovingParams {
    fn default() -> Self {
        Self {
            dt: 0.05,
            horizon: 15.0,
            radius_km: 1.5,
            decided_bonus: 10_000.0,
        }
    }
}

/// One robot's decision at a re-planning instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    pub robot: RobotId,
    pub old_path: Vec<TaskId>,
    pub old_score: f64,
    /// p_i' of the fresh CBCA run and S_i(p_i').
    pub proposed: Vec<TaskId>,
    pub new_score: f64,
    pub verdict: Verdict,
    /// sigma_i (4.18) when the proposal differed.
    pub sigma: Option<f64>,
    /// Its terms (Ē_i, d_ic, mu_i) when the proposal differed.
    pub threshold: Option<Threshold>,
    /// The path after the consistency pass.
    pub final_path: Vec<TaskId>,
}

/// A meeting of planning groups and its re-planning (sec. 4.2.5 case 2).
#[derive(Clone, Debug, PartialEq)]
pub struct Replanning {
    pub time: f64,
    /// The planning groups that met (members).
    pub groups: Vec<Vec<RobotId>>,
    /// Members in their hold time, left out.
    pub holding: Vec<RobotId>,
    pub decisions: Vec<Decision>,
    pub payments: Vec<Payment>,
    /// Consensus cost of the fresh run plus the consistency pass.
    pub stats: RunStats,
    /// Every robot as it was when the groups met (position, resources and l_i left), and the
    /// old coalitions (task -> members of the merged group): what the decisions were taken on.
    pub robots_now: Vec<Robot>,
    pub old_coalitions: BTreeMap<TaskId, Vec<RobotId>>,
}

/// A captured target.
#[derive(Clone, Debug, PartialEq)]
pub struct Capture {
    pub task: TaskId,
    pub time: f64,
    pub members: Vec<RobotId>,
}

/// The whole run.
#[derive(Clone, Debug, PartialEq)]
pub struct MovingRun {
    pub initial_groups: Vec<Vec<RobotId>>,
    pub initial_paths: Vec<Vec<TaskId>>,
    pub initial_stats: RunStats,
    pub replannings: Vec<Replanning>,
    pub captures: Vec<Capture>,
    /// Sample times and each robot's utility at them.
    pub times: Vec<f64>,
    pub utility: Vec<Vec<f64>>,
    pub final_paths: Vec<Vec<TaskId>>,
}

#[derive(Clone, Debug)]
struct Mover {
    pos: Vec2,
    path: Vec<TaskId>,
    /// Distance travelled in all, and when the current leg began (at the last capture).
    travelled: f64,
    leg_from: f64,
    /// Captured tasks' (4.13) terms, summed.
    banked: f64,
    compensation: f64,
    hold_until: Option<(TaskId, f64)>,
    captured: usize,
    left: super::model::Resources,
    group: usize,
}

/// The targets of `path` that robot `i` would actually go for: those whose coalition (robots
/// whose path holds them) has L_j members.
fn live(paths: &[&[TaskId]], j: TaskId, tasks: &[Task]) -> bool {
    paths.iter().filter(|p| p.contains(&j)).count() >= tasks[j].robots_needed
}

/// How a moving run starts. The default: the temporary groups are the components of the
/// `radius_km` graph and CBCA plans in them at t = 0. The narrative run of Example 2
/// (narrative.rs) imposes the thesis's groups and coalitions instead.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Start {
    /// Imposed temporary groups (every robot in exactly one); None: the radio components.
    pub groups: Option<Vec<Vec<RobotId>>>,
    /// Imposed initial paths, one per robot (the decided plans of the first allocation; no
    /// CBCA at t = 0); None: CBCA in each group.
    pub paths: Option<Vec<Vec<TaskId>>>,
    /// Targets nobody knows or sees until the first meeting of groups, at which they join the
    /// meeting groups' knowledge (the narrative's T5, unallocated at first).
    pub hidden_until_meeting: Vec<TaskId>,
}

/// Runs Example-like instances with motion (see the module doc).
pub fn run_moving(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    mp: &MovingParams,
) -> MovingRun {
    run_moving_from(robots, tasks, params, mp, &Start::default())
}

/// [`run_moving`] from a given [`Start`].
pub fn run_moving_from(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    mp: &MovingParams,
    start: &Start,
) -> MovingRun {
    let n = robots.len();
    let pos0: Vec<Vec2> = robots.iter().map(|r| r.position).collect();
    let mut hidden: BTreeSet<TaskId> = start.hidden_until_meeting.iter().copied().collect();
    let mut knowledge = robot_knowledge(
        &pos0,
        tasks,
        params.detection_radius_km,
        PriorInfo::DetectionPlusNearest,
    );
    for k in knowledge.iter_mut() {
        k.retain(|j| !hidden.contains(j));
    }
    let graph = comm_graph(&pos0, mp.radius_km);
    let initial_groups = start.groups.clone().unwrap_or_else(|| components(&graph));
    let (initial_paths, initial_stats) = match &start.paths {
        Some(p) => {
            // The imposed coalitions' targets are known to their members.
            for (i, path) in p.iter().enumerate() {
                knowledge[i].extend(path.iter().copied());
            }
            (p.clone(), RunStats::default())
        }
        None => {
            let mut cb = cbca_robots(robots, tasks, &knowledge, params);
            let stats = run(&mut cb, &graph, &Radio::perfect(), params.max_iterations);
            (cb.iter().map(|r| r.plan().path.clone()).collect(), stats)
        }
    };
    let mut group_known: Vec<BTreeSet<TaskId>> = initial_groups
        .iter()
        .map(|g| g.iter().flat_map(|&i| knowledge[i].clone()).collect())
        .collect();
    let mut movers: Vec<Mover> = robots
        .iter()
        .map(|r| Mover {
            pos: r.position,
            path: initial_paths[r.id].clone(),
            travelled: 0.0,
            leg_from: 0.0,
            banked: 0.0,
            compensation: 0.0,
            hold_until: None,
            captured: 0,
            left: r.resources,
            group: initial_groups
                .iter()
                .position(|g| g.contains(&r.id))
                .expect("every robot is in a group"),
        })
        .collect();
    let mut done: BTreeSet<TaskId> = BTreeSet::new();
    let mut held: BTreeSet<TaskId> = BTreeSet::new();
    let mut captures = Vec::new();
    let mut replannings = Vec::new();
    let mut times = Vec::new();
    let mut utility = vec![Vec::new(); n];
    let steps = (mp.horizon / mp.dt).round() as usize;
    for step in 0..=steps {
        let t = step as f64 * mp.dt;
        // Utility samples (before this step's motion).
        times.push(t);
        for (i, m) in movers.iter().enumerate() {
            utility[i].push(robot_utility(&robots[i], m, tasks, params, t));
        }
        if step == steps || done.len() == tasks.len() {
            break;
        }
        // Motion.
        let paths: Vec<Vec<TaskId>> = movers.iter().map(|m| m.path.clone()).collect();
        let refs: Vec<&[TaskId]> = paths.iter().map(|p| p.as_slice()).collect();
        for (i, m) in movers.iter_mut().enumerate() {
            if m.hold_until.is_some() {
                continue;
            }
            let Some(&j) = m.path.iter().find(|&&j| live(&refs, j, tasks)) else {
                continue;
            };
            let to = tasks[j].pos() - m.pos;
            let step_len = robots[i].speed * mp.dt;
            let d = to.norm();
            if d <= step_len {
                m.pos = tasks[j].pos();
                m.travelled += d;
            } else {
                m.pos += to * (step_len / d);
                m.travelled += step_len;
            }
        }
        let t_next = t + mp.dt;
        // Holds that end.
        for m in movers.iter_mut() {
            if let Some((j, until)) = m.hold_until {
                if until <= t_next + 1e-9 {
                    m.hold_until = None;
                    m.path.retain(|&k| k != j);
                    held.remove(&j);
                    done.insert(j);
                }
            }
        }
        // Captures: every member of a full coalition at the target (and not holding another).
        let paths: Vec<Vec<TaskId>> = movers.iter().map(|m| m.path.clone()).collect();
        let refs: Vec<&[TaskId]> = paths.iter().map(|p| p.as_slice()).collect();
        for task in tasks {
            let j = task.id;
            if done.contains(&j) || held.contains(&j) || !live(&refs, j, tasks) {
                continue;
            }
            let members: Vec<RobotId> = (0..n).filter(|&i| paths[i].contains(&j)).collect();
            let here = members.iter().all(|&i| {
                movers[i].hold_until.is_none() && (movers[i].pos - task.pos()).norm() < 1e-9
            });
            if !here {
                continue;
            }
            held.insert(j);
            for &i in &members {
                let m = &mut movers[i];
                let leg = m.travelled - m.leg_from;
                m.leg_from = m.travelled;
                m.banked += params.w1 * task.value * (-task.beta * t_next).exp()
                    - params.w2 * robots[i].gamma * leg;
                m.captured += 1;
                let used = consumption(&m.left, task, params.consumption);
                for (l, u) in m.left.iter_mut().zip(used) {
                    *l -= u;
                }
                m.hold_until = Some((j, t_next + task.hold_time));
            }
            captures.push(Capture {
                task: j,
                time: t_next,
                members,
            });
        }
        // Local vision (case 1): no re-planning, the group learns the target.
        for m in &movers {
            for task in tasks.iter().filter(|k| !hidden.contains(&k.id)) {
                if (m.pos - task.pos()).norm() <= params.detection_radius_km {
                    group_known[m.group].insert(task.id);
                }
            }
        }
        // Meetings (case 2).
        let pos: Vec<Vec2> = movers.iter().map(|m| m.pos).collect();
        let g = comm_graph(&pos, mp.radius_km);
        let mut meet: BTreeSet<(usize, usize)> = BTreeSet::new();
        for (i, ns) in g.iter().enumerate() {
            for &k in ns {
                let (a, b) = (movers[i].group, movers[k].group);
                if a != b {
                    meet.insert((a.min(b), a.max(b)));
                }
            }
        }
        if meet.is_empty() {
            continue;
        }
        // The hidden targets appear at the first meeting, to the groups that meet.
        for j in std::mem::take(&mut hidden) {
            for &(a, b) in &meet {
                group_known[a].insert(j);
                group_known[b].insert(j);
            }
        }
        // Union of the meeting groups (transitively), each union re-plans once.
        let mut parent: Vec<usize> = (0..group_known.len()).collect();
        fn root(p: &mut [usize], g: usize) -> usize {
            let mut r = g;
            while p[r] != r {
                r = p[r];
            }
            p[g] = r;
            r
        }
        for &(a, b) in &meet {
            let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
        let mut unions: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
        for gi in 0..group_known.len() {
            if movers.iter().any(|m| m.group == gi) {
                unions.entry(root(&mut parent, gi)).or_default().push(gi);
            }
        }
        for (new_group, parts) in unions.into_iter().filter(|(_, p)| p.len() > 1) {
            let members: Vec<RobotId> = (0..n)
                .filter(|&i| parts.contains(&movers[i].group))
                .collect();
            let known: BTreeSet<TaskId> = parts
                .iter()
                .flat_map(|&gi| group_known[gi].clone())
                .collect();
            let met: Vec<Vec<RobotId>> = parts
                .iter()
                .map(|&gi| (0..n).filter(|&i| movers[i].group == gi).collect())
                .collect();
            let mut r = replan(
                robots,
                tasks,
                params,
                mp,
                &mut movers,
                &members,
                &known,
                &done,
                &held,
                t_next,
            );
            r.groups = met;
            for &gi in &parts {
                let k = group_known[gi].clone();
                group_known[new_group].extend(k);
            }
            for &i in &members {
                movers[i].group = new_group;
            }
            replannings.push(r);
        }
    }
    let final_paths = movers.iter().map(|m| m.path.clone()).collect();
    MovingRun {
        initial_groups,
        initial_paths,
        initial_stats,
        replannings,
        captures,
        times,
        utility,
        final_paths,
    }
}

/// Robot i now: its position, l_i less the captured tasks, the resources left.
fn robot_now(r: &Robot, m: &Mover) -> Robot {
    Robot {
        position: m.pos,
        max_tasks: r.max_tasks.saturating_sub(m.captured),
        resources: m.left,
        mileage_budget: (r.mileage_budget - m.travelled).max(0.0),
        ..r.clone()
    }
}

/// The tasks with their values decayed to time t (t_o = t in (4.12)).
pub(crate) fn decayed(tasks: &[Task], t: f64) -> Vec<Task> {
    tasks
        .iter()
        .map(|k| Task {
            value: k.value * (-k.beta * t).exp(),
            ..k.clone()
        })
        .collect()
}

/// Fig. 4.5's utility of robot i at time t (module doc).
fn robot_utility(r: &Robot, m: &Mover, tasks: &[Task], params: &CbcaParams, t: f64) -> f64 {
    let ahead: Vec<TaskId> = match m.hold_until {
        Some((j, _)) => m.path.iter().copied().filter(|&k| k != j).collect(),
        None => m.path.clone(),
    };
    let mut u = m.banked + m.compensation;
    if ahead.is_empty() {
        return u;
    }
    let book: TaskBook = decayed(tasks, t).into_iter().map(|k| (k.id, k)).collect();
    let mut now = robot_now(r, m);
    if let Some((j, until)) = m.hold_until {
        // Still holding j: the next legs start from j after the hold.
        now.position = tasks[j].pos();
        let wait = until - t;
        let s = path_score(&now, &ahead, &book, params);
        let mut total = 0.0;
        for ts in &s.tasks {
            let task = &tasks[ts.task];
            total += params.w1 * ts.reward * (-task.beta * wait).exp() - params.w2 * ts.cost;
        }
        return u + total;
    }
    let s = path_score(&now, &ahead, &book, params);
    u += s.total;
    // The sunk part of the current leg belongs to its first task's leg.
    u -= params.w2 * r.gamma * (m.travelled - m.leg_from);
    u
}

#[allow(clippy::too_many_arguments)]
fn replan(
    robots: &[Robot],
    tasks: &[Task],
    params: &CbcaParams,
    mp: &MovingParams,
    movers: &mut [Mover],
    members: &[RobotId],
    known: &BTreeSet<TaskId>,
    done: &BTreeSet<TaskId>,
    held: &BTreeSet<TaskId>,
    t: f64,
) -> Replanning {
    let n = robots.len();
    let holding: Vec<RobotId> = members
        .iter()
        .copied()
        .filter(|&i| movers[i].hold_until.is_some())
        .collect();
    let active: Vec<RobotId> = members
        .iter()
        .copied()
        .filter(|i| !holding.contains(i))
        .collect();
    let now_tasks = decayed(tasks, t);
    let open: BTreeSet<TaskId> = known
        .iter()
        .copied()
        .filter(|j| !done.contains(j) && !held.contains(j))
        .collect();
    let book: TaskBook = now_tasks
        .iter()
        .filter(|k| open.contains(&k.id))
        .map(|k| (k.id, k.clone()))
        .collect();
    // The robots as they are now, indexed as in `robots` (the others take no part: they are
    // given no tasks and no links).
    let now: Vec<Robot> = (0..n).map(|i| robot_now(&robots[i], &movers[i])).collect();
    let knows: Vec<BTreeSet<TaskId>> = (0..n)
        .map(|i| {
            if active.contains(&i) {
                open.clone()
            } else {
                BTreeSet::new()
            }
        })
        .collect();
    let mut links = complete_graph(n);
    for (i, l) in links.iter_mut().enumerate() {
        if active.contains(&i) {
            l.retain(|k| active.contains(k));
        } else {
            l.clear();
        }
    }
    let no_tasks = CbcaParams {
        max_tasks: 0,
        ..params.clone()
    };
    let fresh_robots = || -> Vec<CbcaRobot> {
        let mut cb = cbca_robots(&now, &now_tasks, &knows, params);
        for i in 0..n {
            if !active.contains(&i) {
                cb[i] = CbcaRobot::new(
                    Robot {
                        max_tasks: 0,
                        ..now[i].clone()
                    },
                    n,
                    tasks.len(),
                    TaskBook::new(),
                    no_tasks.clone(),
                );
            }
        }
        cb
    };
    // 1. Fresh CBCA on the merged group.
    let mut cb = fresh_robots();
    let mut stats = run(&mut cb, &links, &Radio::perfect(), params.max_iterations);
    // 2. Loyalty (4.22) and compensation.
    let old_coalitions: BTreeMap<TaskId, Vec<RobotId>> = {
        let mut c: BTreeMap<TaskId, Vec<RobotId>> = BTreeMap::new();
        for &i in members {
            for &j in &movers[i].path {
                c.entry(j).or_default().push(i);
            }
        }
        c
    };
    let proposals: Vec<Proposal> = active
        .iter()
        .map(|&i| {
            let old_path: Vec<TaskId> = movers[i]
                .path
                .iter()
                .copied()
                .filter(|j| book.contains_key(j))
                .collect();
            let old = path_score(&now[i], &old_path, &book, params);
            let new_path = cb[i].plan().path.clone();
            let new_score = path_score(&now[i], &new_path, &book, params).total;
            let mut coalition = [0.0; super::model::RESOURCE_TYPES];
            // An idle robot leaves no coalition: Ē_i = 0 (4.19 over no type), so only its
            // sunk cost and mu_i (both 0 here) hold it back.
            if let Some(j) = old_path.first() {
                for &m in &old_coalitions[j] {
                    for (w, c) in coalition.iter_mut().enumerate() {
                        *c += robots[m].resources[w];
                    }
                }
            }
            Proposal {
                robot: i,
                holding: false,
                old: old.tasks.iter().map(|s| (s.task, s.score)).collect(),
                new_path,
                new_score,
                loyalty: LoyaltyState {
                    resources: robots[i].resources,
                    coalition_resources: coalition,
                    travelled_time: movers[i].travelled / robots[i].speed,
                    gamma: robots[i].gamma,
                    unexecuted_score: old.total,
                },
            }
        })
        .collect();
    let (outcomes, payments) = decide(&proposals, &old_coalitions, &params.loyalty);
    for pay in &payments {
        movers[pay.from].compensation -= pay.amount;
        movers[pay.to].compensation += pay.amount;
    }
    // 3. Consistency pass: consensus with every robot seeded with its decided plan.
    let mut cb = fresh_robots();
    for o in &outcomes {
        let scores: Vec<f64> = path_score(&now[o.robot], &o.path, &book, params)
            .tasks
            .iter()
            .map(|s| s.score)
            .collect();
        cb[o.robot].seed_plan(&o.path, &scores, mp.decided_bonus);
    }
    let later = super::rounds::run_from(
        &mut cb,
        &links,
        &Radio::perfect(),
        stats.rounds,
        params.max_iterations,
    );
    stats.add(&later);
    let mut decisions = Vec::new();
    for (p, o) in proposals.iter().zip(&outcomes) {
        let i = o.robot;
        let final_path = cb[i].plan().path.clone();
        // Tasks it keeps being held by others are not in the book: keep nothing of them.
        movers[i].path = final_path.clone();
        if final_path.first().copied() != p.old.first().map(|(j, _)| *j) {
            // A new first leg: the partial leg travelled so far stays sunk.
            movers[i].leg_from = movers[i].travelled;
        }
        decisions.push(Decision {
            robot: i,
            old_path: p.old.iter().map(|(j, _)| *j).collect(),
            old_score: p.old_score(),
            proposed: p.new_path.clone(),
            new_score: p.new_score,
            verdict: o.verdict,
            sigma: o.threshold.as_ref().map(|t| t.sigma),
            threshold: o.threshold.clone(),
            final_path,
        });
    }
    Replanning {
        time: t,
        groups: vec![members.to_vec()],
        holding,
        decisions,
        payments,
        stats,
        robots_now: now,
        old_coalitions,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{unit_robots, unit_tasks};

    #[test]
    fn robots_move_capture_and_bank_their_utility() {
        // T1 at (0, 0), L 2, V 100; T2 at (4, 0), L 1, V 300, 1 a type. Group A = {R1 (0, 0.7),
        // R2 (0, -0.7)} (1.4 km apart) detects T1 and takes it. R3 at (6, 1.5), alone (group B),
        // detects nothing but is the robot nearest to T2 (2.5 km): it knows T2 and takes it.
        // R1 and R2 reach T1 at t = 0.7 and capture it; R3 captures T2 at t = 2.5; the groups
        // never come within 1.5 km: no re-planning.
        let tasks = unit_tasks(&[([0.0, 0.0], 2, 100.0), ([4.0, 0.0], 1, 300.0)]);
        let robots = unit_robots(&[[0.0, 0.7], [0.0, -0.7], [6.0, 1.5]]);
        let p = CbcaParams::default();
        let mp = MovingParams::default();
        let r = run_moving(&robots, &tasks, &p, &mp);
        assert_eq!(r.initial_groups, vec![vec![0, 1], vec![2]]);
        assert_eq!(r.initial_paths, vec![vec![0], vec![0], vec![1]]);
        assert!(r.replannings.is_empty());
        assert_eq!(r.captures.len(), 2);
        assert_eq!(r.captures[0].task, 0);
        assert!((r.captures[0].time - 0.7).abs() < 1e-6);
        assert_eq!(r.captures[1].task, 1);
        assert!((r.captures[1].time - 2.5).abs() < 1e-6);
        // R1's utility once T1 is captured: 100 e^(-beta 0.7) - gamma 0.7 ...
        let (b, g) = (tasks[0].beta, robots[0].gamma);
        let want = 100.0 * (-b * 0.7f64).exp() - g * 0.7;
        assert!((r.utility[0].last().unwrap() - want).abs() < 1e-6);
        // ... and at t = 0 the same plan, expected: the identical value (no waiting).
        assert!((r.utility[0][0] - want).abs() < 1e-6);
    }
}

#[cfg(test)]
mod example2_tests {
    use super::*;
    use crate::cbca::params::LoyaltyParams;
    use crate::cbca::scenario::tests::example;

    /// Example 2 at 1.5 km without loyalty (r1 = r2 = r3 = 0): coalition members switch to a
    /// better path (3 here; none leaves a coalition that others stay in, so nobody is paid);
    /// with loyalty on (the defaults) none does. Payments, if any, sum to zero.
    #[test]
    fn loyalty_blocks_the_switches_a_free_run_makes() {
        let s = example(2);
        let robots = s.robots().unwrap();
        let tasks = s.tasks().unwrap();
        let mp = MovingParams::default();
        let free = CbcaParams {
            loyalty: LoyaltyParams {
                r1: 0.0,
                r2: 0.0,
                r3: 0.0,
                ..LoyaltyParams::default()
            },
            ..s.params.clone()
        };
        let count = |p: &CbcaParams| {
            let r = run_moving(&robots, &tasks, p, &mp);
            let switches: usize = r
                .replannings
                .iter()
                .flat_map(|x| &x.decisions)
                .filter(|d| d.verdict == Verdict::Switches && !d.old_path.is_empty())
                .count();
            let (n, amount) = r
                .replannings
                .iter()
                .flat_map(|x| &x.payments)
                .fold((0, 0.0), |(n, a), p| (n + 1, a + p.amount));
            (r, switches, n, amount)
        };
        let (r, switches, payments, amount) = count(&free);
        eprintln!("without loyalty: {switches} member switches, {payments} payments, {amount:.2}");
        assert!(switches > 0);
        assert_eq!((payments, amount), (0, 0.0));
        let (_, loyal_switches, _, _) = count(&s.params);
        eprintln!("with loyalty: {loyal_switches} member switches");
        assert!(loyal_switches < switches);
        // Every payment leaves one robot and reaches another.
        let mut balance = vec![0.0; robots.len()];
        for p in r.replannings.iter().flat_map(|x| &x.payments) {
            balance[p.from] -= p.amount;
            balance[p.to] += p.amount;
        }
        assert!(balance.iter().sum::<f64>().abs() < 1e-9);
    }
}
