//! The improved auction of thesis sec. 3.1-3.2 (spec 3.4-3.6) as two pure state machines, an
//! [`Auctioneer`] and a [`Bidder`], exchanging typed messages (serde, so they can go over the
//! radio), and a synchronous driver [`run_auction`] for tests and experiments.
//!
//! Round r: the auctioneer announces D^r (unassigned tasks, positions, E_j, L_j, v_j, rewards
//! z_j^r); each robot bids on its single best task (3.16) if the utility is positive (3.7); the
//! auctioneer counts the bids. If every open task has at least L_j bids, each gets its L_j
//! lowest-cost bidders (3.12) and the auction ends. Otherwise tasks with exactly L_j bids are
//! awarded (Omega_1), and the others' rewards follow the reward feedback (3.15): down when too
//! many bid (Omega_2), up when too few (Omega_3). It ends when every task is awarded, when the
//! rewards stop changing, or at the round limit.
//!
//! Choices where the thesis is silent (spec 12 item 5): the winners must cover E_j together (2.6;
//! `enforce_coalition_resources`), and a task whose bidders cannot is treated as one bid short;
//! rewards are clamped to [floor, z_jmax]; awarded robots leave the auction; a robot's missing
//! bid is no bid.

use crate::hunt::cost::{auctioneer_cost, bid_value};
use crate::hunt::model::{coalition_covers, Resources, Robot, RobotId, Task, TaskId};
use crate::hunt::params::HuntParams;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use swarm::geometry::Vec2;

/// One task of the announcement D^r = {theta, M, E, W, Z} (sec. 3.2.2), with L_j, v_j and the
/// speed capability the robots also need (spec 3.4 [INFERRED]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskInfo {
    pub id: TaskId,
    /// m_j^r, km.
    pub position: [f64; 2],
    /// e_j^r = E_j.
    pub resources: Resources,
    pub required_robots: usize,
    pub speed: f64,
    pub min_robot_speed: f64,
    pub reward_cap: f64,
    /// z_j^r.
    pub reward: f64,
}

impl TaskInfo {
    pub fn of(task: &Task, reward: f64) -> Self {
        Self {
            id: task.id,
            position: [task.position.x, task.position.y],
            resources: task.resources,
            required_robots: task.required_robots,
            speed: task.speed,
            min_robot_speed: task.min_robot_speed,
            reward_cap: task.reward_cap,
            reward,
        }
    }

    pub fn task(&self) -> Task {
        Task {
            id: self.id,
            position: Vec2::new(self.position[0], self.position[1]),
            resources: self.resources,
            required_robots: self.required_robots,
            reward_cap: self.reward_cap,
            speed: self.speed,
            min_robot_speed: self.min_robot_speed,
        }
    }
}

/// Auctioneer -> all robots, once per round: D^r.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Announcement {
    pub round: u32,
    pub tasks: Vec<TaskInfo>,
}

/// Robot -> auctioneer, at most once per round: d_i^r = (b, y_ib^r), with what the auctioneer
/// needs to rank and check the bidder (its position for f_ij, its resources for 2.6): the
/// auctioneer knows only what it hears.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bid {
    pub round: u32,
    pub robot: RobotId,
    pub task: TaskId,
    /// y_ib^r (3.16).
    pub utility: f64,
    pub position: [f64; 2],
    pub resources: Resources,
}

/// Auctioneer -> winners: confirm and execute (the coalition Phi_j and its reward).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Award {
    pub round: u32,
    pub task: TaskId,
    /// z_j paid to each member.
    pub reward: f64,
    /// Phi_j, ascending ids.
    pub members: Vec<RobotId>,
}

/// Auctioneer -> all robots: the auction is over; robots without an award are free.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Closed {
    pub round: u32,
    pub finish: Finish,
}

/// Every message of the auction, for one radio channel.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum AuctionMessage {
    Announce(Announcement),
    Bid(Bid),
    Award(Award),
    Closed(Closed),
}

/// Why an auction stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Finish {
    /// Every task is awarded.
    AllAwarded,
    /// No reward changed by more than the tolerance and nothing was awarded: the tasks left are
    /// unassigned (e.g. too few robots).
    RewardsSettled,
    /// The round limit was reached.
    RoundLimit,
    /// The parallel auction's single round is over (tasks without enough bidders stay
    /// unassigned).
    OneRound,
}

/// A bid the auctioneer cannot accept.
#[derive(Debug, PartialEq, thiserror::Error)]
pub enum AuctionError {
    #[error("bid for round {got} while round {current} is open")]
    WrongRound { got: u32, current: u32 },
    #[error("bid for task {0}, which is not open")]
    UnknownTask(TaskId),
    #[error("robot {0} already bid this round")]
    DuplicateBid(RobotId),
    #[error("no round is open")]
    NoOpenRound,
    /// The robot already won a task: its award was lost on the radio. The auctioneer ignores the
    /// bid and resends the award ([`Auctioneer::award_of`]).
    #[error("robot {robot} already won task {task}")]
    AlreadyAwarded { robot: RobotId, task: TaskId },
}

/// What happened in one round (for Fig. 3.6 and the reports).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoundRecord {
    pub round: u32,
    /// z_j^r announced this round, every open task.
    pub rewards: BTreeMap<TaskId, f64>,
    /// L_jbid^r.
    pub bids: BTreeMap<TaskId, usize>,
    /// Tasks awarded at the end of the round.
    pub awarded: Vec<TaskId>,
}

/// One awarded coalition with the auctioneer's and the robots' view of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Coalition {
    pub award: Award,
    /// c_ij = z_j + d_ij per member (3.12), same order as `award.members`.
    pub costs: Vec<f64>,
    /// y_ij per member (3.16), same order.
    pub utilities: Vec<f64>,
}

#[derive(Clone, Debug)]
struct OpenTask {
    task: Task,
    reward: f64,
}

/// The auctioneer (task initiator, sec. 3.2.2).
#[derive(Clone, Debug)]
pub struct Auctioneer {
    params: HuntParams,
    n_r: usize,
    open: BTreeMap<TaskId, OpenTask>,
    round: u32,
    round_open: bool,
    bids: Vec<Bid>,
    bidders: BTreeSet<RobotId>,
    coalitions: BTreeMap<TaskId, Coalition>,
    history: Vec<RoundRecord>,
    finish: Option<Finish>,
}

impl Auctioneer {
    /// An auction of `tasks` among `n_r` robots, initial rewards z_j^1 = alpha z_jmax (3.11).
    pub fn new(tasks: &[Task], n_r: usize, params: &HuntParams) -> Self {
        let rewards = tasks
            .iter()
            .map(|t| (t.id, params.alpha * t.reward_cap))
            .collect();
        Self::with_rewards(tasks, &rewards, n_r, params)
    }

    /// An auction starting from given rewards (re-planning, sec. 3.2.5: a re-published task
    /// keeps or raises its reward); tasks missing from `rewards` start at alpha z_jmax.
    pub fn with_rewards(
        tasks: &[Task],
        rewards: &BTreeMap<TaskId, f64>,
        n_r: usize,
        params: &HuntParams,
    ) -> Self {
        let open = tasks
            .iter()
            .map(|t| {
                let z = rewards
                    .get(&t.id)
                    .copied()
                    .unwrap_or(params.alpha * t.reward_cap);
                (
                    t.id,
                    OpenTask {
                        task: t.clone(),
                        reward: z,
                    },
                )
            })
            .collect();
        Self {
            params: params.clone(),
            n_r: n_r.max(1),
            open,
            round: 0,
            round_open: false,
            bids: Vec::new(),
            bidders: BTreeSet::new(),
            coalitions: BTreeMap::new(),
            history: Vec::new(),
            finish: None,
        }
    }

    /// Stage 1: open round r + 1 and return D^r, or `None` once the auction is over.
    pub fn announce(&mut self) -> Option<Announcement> {
        if self.finish.is_some() {
            return None;
        }
        if self.open.is_empty() {
            self.finish = Some(Finish::AllAwarded);
            return None;
        }
        self.round += 1;
        self.round_open = true;
        self.bids.clear();
        self.bidders.clear();
        Some(Announcement {
            round: self.round,
            tasks: self
                .open
                .values()
                .map(|o| TaskInfo::of(&o.task, o.reward))
                .collect(),
        })
    }

    /// Stage 2 input: one bid of the open round.
    pub fn receive(&mut self, bid: Bid) -> Result<(), AuctionError> {
        if !self.round_open {
            return Err(AuctionError::NoOpenRound);
        }
        if let Some(a) = self.award_of(bid.robot) {
            return Err(AuctionError::AlreadyAwarded {
                robot: bid.robot,
                task: a.task,
            });
        }
        if bid.round != self.round {
            return Err(AuctionError::WrongRound {
                got: bid.round,
                current: self.round,
            });
        }
        if !self.open.contains_key(&bid.task) {
            return Err(AuctionError::UnknownTask(bid.task));
        }
        if !self.bidders.insert(bid.robot) {
            return Err(AuctionError::DuplicateBid(bid.robot));
        }
        self.bids.push(bid);
        Ok(())
    }

    /// Stages 2-4: count the bids, award, update the rewards (3.15). Returns the awards of this
    /// round; after it, [`Self::finish`] says whether the auction is over.
    pub fn close_round(&mut self) -> Vec<Award> {
        if !self.round_open {
            return Vec::new();
        }
        self.round_open = false;
        let mut by_task: BTreeMap<TaskId, Vec<&Bid>> =
            self.open.keys().map(|j| (*j, Vec::new())).collect();
        for b in &self.bids {
            by_task.entry(b.task).or_default().push(b);
        }
        let rewards: BTreeMap<TaskId, f64> =
            self.open.iter().map(|(j, o)| (*j, o.reward)).collect();
        // Winners each task would get if awarded now (L_j lowest-cost bidders covering E_j).
        let winners: BTreeMap<TaskId, Option<Vec<&Bid>>> = by_task
            .iter()
            .map(|(j, bids)| {
                let o = &self.open[j];
                (*j, select_winners(&o.task, bids, o.reward, &self.params))
            })
            .collect();
        let counts: BTreeMap<TaskId, usize> = by_task.iter().map(|(j, b)| (*j, b.len())).collect();
        let all_enough = winners.values().all(|w| w.is_some());
        let mut awarded = Vec::new();
        let mut new_coalitions = Vec::new();
        let mut max_change: f64 = 0.0;
        for (j, w) in &winners {
            let o = &self.open[j];
            let (l_bid, l_j) = (counts[j], o.task.required_robots);
            match w {
                // Every task has enough bids: all awarded, the auction ends (L' = |theta|).
                // Otherwise exactly L_j bids: Omega_1.
                Some(w) if all_enough || l_bid == l_j => {
                    new_coalitions.push(coalition_of(&o.task, o.reward, w, self.round));
                    awarded.push(*j);
                }
                _ => {
                    // Omega_2 (too many) or Omega_3 (too few). A task whose bidders cannot cover
                    // E_j counts as one bid short at least.
                    let excess = if w.is_none() {
                        (l_bid as i64 - l_j as i64).min(-1)
                    } else {
                        l_bid as i64 - l_j as i64
                    };
                    let z = feedback(o.reward, o.task.reward_cap, excess, self.n_r, &self.params);
                    max_change = max_change.max((z - o.reward).abs());
                    self.open.get_mut(j).expect("open task").reward = z;
                }
            }
        }
        for c in new_coalitions {
            self.open.remove(&c.award.task);
            self.coalitions.insert(c.award.task, c);
        }
        self.history.push(RoundRecord {
            round: self.round,
            rewards,
            bids: counts,
            awarded: awarded.clone(),
        });
        if self.open.is_empty() {
            self.finish = Some(Finish::AllAwarded);
        } else if awarded.is_empty() && max_change <= self.params.reward_tolerance {
            self.finish = Some(Finish::RewardsSettled);
        } else if self.round >= self.params.max_rounds {
            self.finish = Some(Finish::RoundLimit);
        }
        awarded
            .iter()
            .map(|j| self.coalitions[j].award.clone())
            .collect()
    }

    /// The message closing the auction, once it is over.
    pub fn closed(&self) -> Option<Closed> {
        self.finish.map(|finish| Closed {
            round: self.round,
            finish,
        })
    }

    pub fn finish(&self) -> Option<Finish> {
        self.finish
    }
    /// The award robot `robot` holds, if any (to resend when its award was lost).
    pub fn award_of(&self, robot: RobotId) -> Option<&Award> {
        award_naming(&self.coalitions, robot)
    }
    pub fn round(&self) -> u32 {
        self.round
    }
    /// Current z_j of the tasks still open.
    pub fn rewards(&self) -> BTreeMap<TaskId, f64> {
        self.open.iter().map(|(j, o)| (*j, o.reward)).collect()
    }
    pub fn coalitions(&self) -> &BTreeMap<TaskId, Coalition> {
        &self.coalitions
    }
    pub fn history(&self) -> &[RoundRecord] {
        &self.history
    }
    /// Tasks not (yet) awarded.
    pub fn open_tasks(&self) -> Vec<TaskId> {
        self.open.keys().copied().collect()
    }
    /// C = sum_j sum_i c_ij x_ij, eq. (3.13).
    pub fn total_cost(&self) -> f64 {
        totals(&self.coalitions).0
    }
    /// Y = sum_j sum_i y_ij x_ij, eq. (3.14).
    pub fn total_utility(&self) -> f64 {
        totals(&self.coalitions).1
    }
}

/// The first award (in task order) of `coalitions` naming `robot`.
pub fn award_naming(coalitions: &BTreeMap<TaskId, Coalition>, robot: RobotId) -> Option<&Award> {
    coalitions
        .values()
        .map(|c| &c.award)
        .find(|a| a.members.contains(&robot))
}

/// (C, Y) of `coalitions`: eqs. (3.13) and (3.14) over the awards made.
pub fn totals(coalitions: &BTreeMap<TaskId, Coalition>) -> (f64, f64) {
    let c = coalitions.values().flat_map(|c| c.costs.iter()).sum();
    let y = coalitions.values().flat_map(|c| c.utilities.iter()).sum();
    (c, y)
}

fn coalition_of(task: &Task, reward: f64, winners: &[&Bid], round: u32) -> Coalition {
    let mut w: Vec<&Bid> = winners.to_vec();
    w.sort_by_key(|b| b.robot);
    Coalition {
        award: Award {
            round,
            task: task.id,
            reward,
            members: w.iter().map(|b| b.robot).collect(),
        },
        costs: w
            .iter()
            .map(|b| auctioneer_cost(reward, distance(b, task)))
            .collect(),
        utilities: w.iter().map(|b| b.utility).collect(),
    }
}

fn distance(b: &Bid, task: &Task) -> f64 {
    (Vec2::new(b.position[0], b.position[1]) - task.position).norm()
}

/// The reward feedback rule, eq. (3.15):
/// z^{r+1} = z^r - ((L_bid - L_j) / n_r) (z_max - z^r), times `reward_feedback_step`, clamped to
/// [floor z_max, z_max] (spec 3.4: a decrease could go negative). The ratio is clamped to
/// [-1, 1], which only matters when L_j > n_r; then a raise stays below the cap (3.4).
pub fn feedback(z: f64, z_max: f64, excess: i64, n_r: usize, p: &HuntParams) -> f64 {
    let ratio = (excess as f64 / n_r as f64).clamp(-1.0, 1.0);
    let next = z - p.reward_feedback_step * ratio * (z_max - z);
    next.clamp(p.reward_floor_fraction * z_max, z_max)
}

/// The L_j winners of task j among its bidders: the L_j lowest auctioneer costs c = z + d (3.12),
/// ties by robot id; with `enforce_coalition_resources`, the cheapest L_j-subset whose resources
/// cover E_j (2.6). `None` when there are fewer than L_j bidders or no subset covers E_j (within
/// `max_coalition_combinations` tries).
pub fn select_winners<'a>(
    task: &Task,
    bids: &[&'a Bid],
    reward: f64,
    p: &HuntParams,
) -> Option<Vec<&'a Bid>> {
    let l = task.required_robots;
    if bids.len() < l {
        return None;
    }
    let mut ranked: Vec<(f64, &Bid)> = bids
        .iter()
        .map(|b| (auctioneer_cost(reward, distance(b, task)), *b))
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.robot.cmp(&b.1.robot)));
    let covers = |set: &[usize]| {
        coalition_covers(set.iter().map(|&k| &ranked[k].1.resources), &task.resources)
    };
    let cheapest: Vec<usize> = (0..l).collect();
    if !p.enforce_coalition_resources || covers(&cheapest) {
        return Some(cheapest.iter().map(|&k| ranked[k].1).collect());
    }
    // Exhaustive search over L_j-subsets (lexicographic over the ranking), keeping the cheapest
    // total cost that covers E_j.
    let mut best: Option<(f64, Vec<usize>)> = None;
    let mut idx: Vec<usize> = (0..l).collect();
    let n = ranked.len();
    let mut tries = 0usize;
    loop {
        tries += 1;
        if tries > p.max_coalition_combinations {
            break;
        }
        if covers(&idx) {
            let c: f64 = idx.iter().map(|&k| ranked[k].0).sum();
            if best.as_ref().is_none_or(|(bc, _)| c < *bc) {
                best = Some((c, idx.clone()));
            }
        }
        // Next combination.
        let mut k = l;
        loop {
            if k == 0 {
                return best.map(|(_, s)| s.iter().map(|&k| ranked[k].1).collect());
            }
            k -= 1;
            if idx[k] < n - l + k {
                idx[k] += 1;
                for m in k + 1..l {
                    idx[m] = idx[m - 1] + 1;
                }
                break;
            }
        }
    }
    best.map(|(_, s)| s.iter().map(|&k| ranked[k].1).collect())
}

/// What a bidder is doing.
#[derive(Clone, Debug, PartialEq)]
pub enum BidderState {
    /// Still in the auction.
    Bidding,
    /// Won a task: hunt it with this coalition.
    Awarded(Award),
    /// The auction closed without an award for this robot.
    Free,
}

/// A robot's side of the auction (sec. 3.2.3).
#[derive(Clone, Debug)]
pub struct Bidder {
    robot: Robot,
    params: HuntParams,
    state: BidderState,
}

impl Bidder {
    pub fn new(robot: Robot, params: &HuntParams) -> Self {
        Self {
            robot,
            params: params.clone(),
            state: BidderState::Bidding,
        }
    }

    pub fn robot(&self) -> &Robot {
        &self.robot
    }
    /// The robot moved (its pose comes from the world each tick).
    pub fn set_position(&mut self, position: Vec2) {
        self.robot.position = position;
    }
    pub fn state(&self) -> &BidderState {
        &self.state
    }

    /// The robot's best task of D^r: argmax_j y_ij^r (3.16), ties by task id, if q_ij = 1 and the
    /// utility is positive (3.7).
    pub fn best_task(&self, a: &Announcement) -> Option<(TaskId, f64)> {
        let mut best: Option<(TaskId, f64)> = None;
        for info in &a.tasks {
            if let Some(y) = bid_value(&self.robot, &info.task(), info.reward, &self.params) {
                if y > 0.0 && best.is_none_or(|(_, by)| y > by) {
                    best = Some((info.id, y));
                }
            }
        }
        best
    }

    /// On D^r: the bid d_i^r = (b, y_ib^r), or nothing (awarded, free, or no positive utility).
    pub fn on_announcement(&mut self, a: &Announcement) -> Option<Bid> {
        if self.state != BidderState::Bidding {
            return None;
        }
        self.best_task(a).map(|(task, utility)| Bid {
            round: a.round,
            robot: self.robot.id,
            task,
            utility,
            position: [self.robot.position.x, self.robot.position.y],
            resources: self.robot.resources,
        })
    }

    /// On an award: join the coalition if named in it.
    pub fn on_award(&mut self, a: &Award) {
        if self.state == BidderState::Bidding && a.members.contains(&self.robot.id) {
            self.state = BidderState::Awarded(a.clone());
        }
    }

    /// On the closing message: a robot still bidding is free.
    pub fn on_closed(&mut self, _c: &Closed) {
        if self.state == BidderState::Bidding {
            self.state = BidderState::Free;
        }
    }
}

/// The result of one auction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AuctionOutcome {
    pub coalitions: BTreeMap<TaskId, Coalition>,
    pub rounds: Vec<RoundRecord>,
    pub finish: Finish,
    /// Tasks left unassigned.
    pub unassigned: Vec<TaskId>,
    /// C (3.13).
    pub auctioneer_cost: f64,
    /// Y (3.14).
    pub total_utility: f64,
    /// Messages exchanged (announcements count once per round, as one broadcast).
    pub messages: usize,
}

impl AuctionOutcome {
    /// The task robot `id` won, if any.
    pub fn task_of(&self, id: RobotId) -> Option<TaskId> {
        self.coalitions
            .values()
            .find(|c| c.award.members.contains(&id))
            .map(|c| c.award.task)
    }
}

/// Run an auctioneer and bidders to the end, synchronously, with lossless messages.
pub fn drive(auctioneer: &mut Auctioneer, bidders: &mut [Bidder]) -> AuctionOutcome {
    drive_lossy(auctioneer, bidders, &mut |_| true)
}

/// Run an auctioneer and bidders to the end, synchronously, where `delivered(message)` decides
/// whether each transmission reaches its one receiver (a broadcast is one transmission per
/// receiver). A lost announcement means no bid that round; a lost bid is no bid; a lost award
/// leaves the robot bidding, so the auctioneer rejects its next bid and resends the award.
pub fn drive_lossy(
    auctioneer: &mut Auctioneer,
    bidders: &mut [Bidder],
    delivered: &mut dyn FnMut(&AuctionMessage) -> bool,
) -> AuctionOutcome {
    let mut messages = 0;
    while let Some(a) = auctioneer.announce() {
        messages += 1;
        let announce = AuctionMessage::Announce(a.clone());
        for b in bidders.iter_mut() {
            if !delivered(&announce) {
                continue;
            }
            if let Some(bid) = b.on_announcement(&a) {
                messages += 1;
                if !delivered(&AuctionMessage::Bid(bid.clone())) {
                    continue;
                }
                match auctioneer.receive(bid) {
                    Ok(()) => {}
                    Err(AuctionError::AlreadyAwarded { robot, .. }) => {
                        let award = auctioneer.award_of(robot).expect("awarded").clone();
                        messages += 1;
                        if delivered(&AuctionMessage::Award(award.clone())) {
                            b.on_award(&award);
                        }
                    }
                    Err(e) => panic!("a bidder's bid is invalid: {e}"),
                }
            }
        }
        for award in auctioneer.close_round() {
            messages += 1;
            let msg = AuctionMessage::Award(award.clone());
            for b in bidders.iter_mut() {
                if delivered(&msg) {
                    b.on_award(&award);
                }
            }
        }
        if auctioneer.finish().is_some() {
            break;
        }
    }
    if let Some(c) = auctioneer.closed() {
        messages += 1;
        let msg = AuctionMessage::Closed(c.clone());
        for b in bidders.iter_mut() {
            if delivered(&msg) {
                b.on_closed(&c);
            }
        }
    }
    AuctionOutcome {
        coalitions: auctioneer.coalitions().clone(),
        rounds: auctioneer.history().to_vec(),
        finish: auctioneer.finish().unwrap_or(Finish::RoundLimit),
        unassigned: auctioneer.open_tasks(),
        auctioneer_cost: auctioneer.total_cost(),
        total_utility: auctioneer.total_utility(),
        messages,
    }
}

/// The improved auction of `tasks` among `robots` from alpha z_jmax (3.11).
pub fn run_auction(tasks: &[Task], robots: &[Robot], p: &HuntParams) -> AuctionOutcome {
    let mut auctioneer = Auctioneer::new(tasks, robots.len(), p);
    let mut bidders: Vec<Bidder> = robots.iter().map(|r| Bidder::new(r.clone(), p)).collect();
    drive(&mut auctioneer, &mut bidders)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hunt::model::tests::{robot, task};

    fn p() -> HuntParams {
        HuntParams::default()
    }

    #[test]
    fn reward_feedback_3_15_lowers_oversubscribed_and_raises_undersubscribed() {
        // n_r = 15. T1 (z_max 520) at z = 416 with 5 bids for L = 3:
        //   z' = 416 - (2/15)(520 - 416) = 416 - 13.866667 = 402.133333   (falls, Omega_2)
        // T4 (z_max 1350) at z = 1080 with 2 bids for L = 5:
        //   z' = 1080 - (-3/15)(1350 - 1080) = 1080 + 54 = 1134          (rises, Omega_3)
        // Exactly L bids: unchanged.
        assert!((feedback(416.0, 520.0, 2, 15, &p()) - 402.133333).abs() < 1e-6);
        assert!((feedback(1080.0, 1350.0, -3, 15, &p()) - 1134.0).abs() < 1e-9);
        assert_eq!(feedback(700.0, 820.0, 0, 15, &p()), 700.0);
        // A big excess at a low reward is clamped at the floor (0), never negative.
        assert_eq!(feedback(10.0, 520.0, 14, 15, &p()), 0.0);
        // A raise never passes the cap (3.4).
        assert!(feedback(819.0, 820.0, -4, 15, &p()) < 820.0);
    }

    /// Two tasks far apart, bidders near each.
    fn two_task_world() -> (Vec<Task>, Vec<Robot>) {
        let mut t1 = task(1, 1.0, 1.0, [1.0; 6], 2);
        let mut t2 = task(2, 9.0, 9.0, [1.0; 6], 2);
        t1.reward_cap = 500.0;
        t2.reward_cap = 500.0;
        let mut robots = Vec::new();
        for (id, x, y, g) in [
            (1, 1.2, 1.0, [0.5, 0.5]),
            (2, 1.0, 1.3, [0.5, 0.5]),
            (3, 8.8, 9.0, [0.5, 0.5]),
            (4, 9.0, 8.6, [0.5, 0.5]),
        ] {
            let mut r = robot(id, x, y, [1.0; 6]);
            r.matching = g.to_vec();
            robots.push(r);
        }
        (vec![t1, t2], robots)
    }

    #[test]
    fn exactly_enough_bids_award_in_round_one() {
        let (tasks, robots) = two_task_world();
        let out = run_auction(&tasks, &robots, &p());
        assert_eq!(out.finish, Finish::AllAwarded);
        assert_eq!(out.rounds.len(), 1);
        assert_eq!(out.coalitions[&1].award.members, vec![1, 2]);
        assert_eq!(out.coalitions[&2].award.members, vec![3, 4]);
        // Rewards paid: alpha z_max = 400.
        assert_eq!(out.coalitions[&1].award.reward, 400.0);
        // C (3.13) = sum (400 + d): d = 0.2, 0.3, 0.2, 0.4 -> 1601.1.
        assert!(
            (out.auctioneer_cost - 1601.1).abs() < 1e-9,
            "{}",
            out.auctioneer_cost
        );
        let y: f64 = out
            .coalitions
            .values()
            .flat_map(|c| c.utilities.iter())
            .sum();
        assert!((out.total_utility - y).abs() < 1e-12 && y > 0.0);
    }

    #[test]
    fn each_robot_bids_only_its_single_best_task() {
        let (tasks, robots) = two_task_world();
        let a = Announcement {
            round: 1,
            tasks: tasks.iter().map(|t| TaskInfo::of(t, 400.0)).collect(),
        };
        let mut b = Bidder::new(robots[0].clone(), &p());
        let bid = b.on_announcement(&a).unwrap();
        // Same g on both: the nearer T1 has the lower cost, so the higher utility.
        assert_eq!(bid.task, 1);
        let y2 = bid_value(&robots[0], &tasks[1], 400.0, &p()).unwrap();
        assert!(bid.utility > y2);
        // No bid when every utility is <= 0 (3.7).
        let broke = Announcement {
            round: 1,
            tasks: tasks.iter().map(|t| TaskInfo::of(t, 0.0)).collect(),
        };
        assert_eq!(b.on_announcement(&broke), None);
    }

    #[test]
    fn oversubscribed_task_loses_reward_until_a_robot_moves() {
        // Three robots prefer T1 (g 0.6 vs 0.4); T1 needs 2, T2 needs 1. Round 1: T1 gets 3
        // bids (Omega_2, reward falls), T2 gets 0 (Omega_3, rises); eventually one robot's
        // utility on T2 overtakes T1 and every task is filled.
        let mut t1 = task(1, 2.0, 2.0, [1.0; 6], 2);
        let mut t2 = task(2, 3.0, 2.0, [1.0; 6], 1);
        t1.reward_cap = 500.0;
        t2.reward_cap = 500.0;
        let robots: Vec<Robot> = [(1, 2.1, 2.0), (2, 2.2, 2.0), (3, 2.9, 2.1)]
            .iter()
            .map(|&(id, x, y)| {
                let mut r = robot(id, x, y, [1.0; 6]);
                r.matching = vec![0.6, 0.4];
                r
            })
            .collect();
        let out = run_auction(&[t1, t2], &robots, &p());
        assert_eq!(out.finish, Finish::AllAwarded);
        assert!(out.rounds.len() > 1);
        let r1 = &out.rounds[0];
        assert_eq!(r1.bids[&1], 3);
        assert_eq!(r1.bids[&2], 0);
        let r2 = &out.rounds[1];
        assert!(
            r2.rewards[&1] < r1.rewards[&1],
            "T1 oversubscribed: reward falls"
        );
        assert!(
            r2.rewards[&2] > r1.rewards[&2],
            "T2 undersubscribed: reward rises"
        );
        // R3 is nearest T2, so it is the one that switches.
        assert_eq!(out.coalitions[&1].award.members, vec![1, 2]);
        assert_eq!(out.coalitions[&2].award.members, vec![3]);
    }

    #[test]
    fn winners_are_the_lowest_cost_bidders_that_cover_the_resources() {
        let mut t = task(1, 0.0, 0.0, [4.0, 0.0, 0.0, 0.0, 0.0, 0.0], 2);
        t.reward_cap = 100.0;
        let mk = |id: RobotId, d: f64, r0: f64| Bid {
            round: 1,
            robot: id,
            task: 1,
            utility: 1.0,
            position: [d, 0.0],
            resources: [r0, 1.0, 1.0, 1.0, 1.0, 1.0],
        };
        let bids = [
            mk(1, 1.0, 1.0),
            mk(2, 2.0, 1.0),
            mk(3, 3.0, 3.0),
            mk(4, 4.0, 3.0),
        ];
        let refs: Vec<&Bid> = bids.iter().collect();
        // Cheapest pair {1,2} has 2 < 4 units of type 1; the cheapest covering pair is {1,3}
        // (cost 80+1 + 80+3 = 164) before {2,3} (165), {1,4} (165), {3,4} (167).
        let w = select_winners(&t, &refs, 80.0, &p()).unwrap();
        assert_eq!(w.iter().map(|b| b.robot).collect::<Vec<_>>(), vec![1, 3]);
        // Without the coalition rule: the two nearest.
        let loose = HuntParams {
            enforce_coalition_resources: false,
            ..p()
        };
        let w = select_winners(&t, &refs, 80.0, &loose).unwrap();
        assert_eq!(w.iter().map(|b| b.robot).collect::<Vec<_>>(), vec![1, 2]);
        // Nobody covers 7 units in pairs.
        t.resources[0] = 7.0;
        assert!(select_winners(&t, &refs, 80.0, &p()).is_none());
    }

    #[test]
    fn when_all_tasks_have_enough_bids_the_extra_bidders_lose() {
        // One task for 2, three bidders: all tasks enough -> the two lowest-cost win, auction ends.
        let mut t = task(1, 0.0, 0.0, [1.0; 6], 2);
        t.reward_cap = 500.0;
        let robots: Vec<Robot> = [(1, 0.5), (2, 0.2), (3, 0.9)]
            .iter()
            .map(|&(id, x)| robot(id, x, 0.0, [1.0; 6]))
            .collect();
        let mut a = Auctioneer::new(&[t], 3, &p());
        let mut bidders: Vec<Bidder> = robots.into_iter().map(|r| Bidder::new(r, &p())).collect();
        let out = drive(&mut a, &mut bidders);
        assert_eq!(out.rounds.len(), 1);
        assert_eq!(out.coalitions[&1].award.members, vec![1, 2]);
        assert_eq!(bidders[2].state(), &BidderState::Free);
        assert!(matches!(bidders[0].state(), BidderState::Awarded(a) if a.task == 1));
    }

    #[test]
    fn too_few_robots_settle_with_the_task_unassigned() {
        let mut t = task(1, 0.0, 0.0, [1.0; 6], 3);
        t.reward_cap = 500.0;
        let robots = vec![robot(1, 0.5, 0.0, [1.0; 6]), robot(2, 0.7, 0.0, [1.0; 6])];
        let out = run_auction(&[t], &robots, &p());
        assert_eq!(out.finish, Finish::RewardsSettled);
        assert_eq!(out.unassigned, vec![1]);
        assert!(out.coalitions.is_empty());
        // Two bids for three: z rises by half the headroom a round, 400, 450, 475, ... toward
        // the cap without reaching it (3.4), until a step is below the tolerance (0.01).
        let z: Vec<f64> = out.rounds.iter().map(|r| r.rewards[&1]).collect();
        assert_eq!(&z[..3], &[400.0, 450.0, 475.0]);
        assert!(z.windows(2).all(|w| w[1] > w[0] && w[1] < 500.0));
        // Round k announces 500 - 100 / 2^(k-1) and moves it by 100 / 2^k: the first step <= 0.01
        // is k = 14 (100 / 16384 = 0.006).
        assert_eq!(out.rounds.len(), 14);
        // With L_j > n_r the ratio is clamped: z reaches the cap at most.
        assert_eq!(feedback(400.0, 500.0, -2, 1, &p()), 500.0);
    }

    #[test]
    fn auctioneer_rejects_bad_bids() {
        let (tasks, _) = two_task_world();
        let mut a = Auctioneer::new(&tasks, 4, &p());
        let bid = Bid {
            round: 1,
            robot: 1,
            task: 1,
            utility: 5.0,
            position: [0.0, 0.0],
            resources: [1.0; 6],
        };
        assert_eq!(a.receive(bid.clone()), Err(AuctionError::NoOpenRound));
        a.announce().unwrap();
        assert_eq!(a.receive(bid.clone()), Ok(()));
        assert_eq!(a.receive(bid.clone()), Err(AuctionError::DuplicateBid(1)));
        assert_eq!(
            a.receive(Bid {
                round: 2,
                ..bid.clone()
            }),
            Err(AuctionError::WrongRound { got: 2, current: 1 })
        );
        assert_eq!(
            a.receive(Bid {
                task: 9,
                robot: 2,
                ..bid
            }),
            Err(AuctionError::UnknownTask(9))
        );
    }

    #[test]
    fn lost_award_is_resent_and_nobody_wins_twice() {
        // Example 3-A with 30 % of the transmissions lost (seeded): coalitions stay disjoint,
        // meet L_j and E_j, and every robot the auctioneer counts in a coalition either learned
        // it or never bid again.
        use crate::hunt::scenario::tests::example_3a;
        use crate::hunt::scenario::HuntKernels;
        use rand::{Rng, SeedableRng};
        let h = example_3a();
        let tasks = h.tasks_at(0.0);
        for seed in 0..20 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut a = Auctioneer::new(&tasks, 15, &p());
            let mut bidders: Vec<Bidder> = h
                .robots()
                .into_iter()
                .map(|r| Bidder::new(r, &p()))
                .collect();
            let out = drive_lossy(&mut a, &mut bidders, &mut |_| rng.gen::<f64>() >= 0.3);
            let mut seen = BTreeSet::new();
            for c in out.coalitions.values() {
                let t = tasks.iter().find(|t| t.id == c.award.task).unwrap();
                assert_eq!(c.award.members.len(), t.required_robots);
                let res: Vec<&Resources> = c
                    .award
                    .members
                    .iter()
                    .map(|i| {
                        &bidders
                            .iter()
                            .find(|b| b.robot().id == *i)
                            .unwrap()
                            .robot()
                            .resources
                    })
                    .collect();
                assert!(coalition_covers(res, &t.resources), "seed {seed}: (2.6)");
                for i in &c.award.members {
                    assert!(seen.insert(*i), "seed {seed}: R{i} won twice");
                }
            }
            // A robot that believes it won holds the auctioneer's award.
            for b in &bidders {
                if let BidderState::Awarded(aw) = b.state() {
                    assert_eq!(a.award_of(b.robot().id), Some(aw));
                }
            }
        }
    }

    #[test]
    fn bid_from_an_awarded_robot_is_rejected() {
        let (tasks, robots) = two_task_world();
        let mut a = Auctioneer::new(&tasks, 4, &p());
        let ann = a.announce().unwrap();
        let mut bidders: Vec<Bidder> = robots.into_iter().map(|r| Bidder::new(r, &p())).collect();
        // R1, R2 bid on T1 (L = 2), R3, R4 on T2: both tasks awarded in round 1.
        for b in &mut bidders {
            let bid = b.on_announcement(&ann).unwrap();
            a.receive(bid).unwrap();
        }
        let awards = a.close_round();
        assert_eq!(awards.len(), 2);
        // Had the award been lost, R1's next bid is answered with it.
        let mut again = a.clone();
        again.round_open = true;
        let bid = Bid {
            round: again.round(),
            robot: 1,
            task: 1,
            utility: 1.0,
            position: [0.0, 0.0],
            resources: [1.0; 6],
        };
        assert_eq!(
            again.receive(bid),
            Err(AuctionError::AlreadyAwarded { robot: 1, task: 1 })
        );
        assert_eq!(again.award_of(1).map(|x| x.task), Some(1));
    }

    #[test]
    fn messages_survive_the_wire() {
        let (tasks, _) = two_task_world();
        let msg = AuctionMessage::Announce(Announcement {
            round: 3,
            tasks: tasks.iter().map(|t| TaskInfo::of(t, 321.5)).collect(),
        });
        let cfg = bincode::config::standard();
        let bytes = bincode::serde::encode_to_vec(&msg, cfg).unwrap();
        let (back, _): (AuctionMessage, usize) =
            bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
        assert_eq!(back, msg);
        if let AuctionMessage::Announce(a) = back {
            assert_eq!(a.tasks[1].task(), tasks[1]);
        }
    }
}
