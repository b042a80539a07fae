//! The auctioneer (task initiator, thesis sec. 3.1-3.2.5) as an agent of its own: a station
//! with no body that knows what the scenario gives it (the targets of Table 3.1 with their
//! appearance times, the robots of Table 3.2) and what it hears (bids, statuses), and acts
//! only by radio.
//!
//! - **Auctions** (the `Auctioneer` kernel): round r is announced, bids are taken for
//!   `bid_window_ticks`, the round is closed (awards broadcast), until the kernel finishes;
//!   then `Closed`. A bid from a robot already awarded gets its award again.
//! - **A new target** (sec. 3.2.5 steps 2-3) at its appearance tick: the coalitions whose
//!   total utility (3.21) is higher on it are named in a re-planning auction of that target
//!   over the radio; the winners leave their coalitions. If no coalition is interested, the
//!   target becomes a hunt with no members, which assistance fills from the free robots.
//! - **Every `replan_period_ticks`**: robots silent for `silent_dead_ticks` are taken for dead
//!   and replaced (`replace_dead`), hunts whose members report their target captured are
//!   finished (their members free), swaps (`apply_swaps`, with the members' reported
//!   hunting points), then assistance (`assist`) to hunts short of L_j or E_j or past the
//!   timeout. Every change is broadcast as an `Assign` with a new epoch.
//! - Each hunt's `Assign` is resent every `award_resend_ticks` (one hunt a tick, in turn), so
//!   a robot that missed its award or a change learns it.
//! - Its report to the world: one awarded task a tick, in turn: [task, z_j, rounds, 0], then
//!   the totals row [0, C, rounds, Y] (3.13, 3.14 over every auction finished so far).
//! - `hunt.params.auction` = "parallel" runs the baseline instead (spec 11): one round at a
//!   fixed reward, every robot bids on every task; a robot that wins several keeps the one it
//!   bid most on (`one_task_each`), and assistance fills the coalitions it leaves short.

use super::messages::{HuntMsg, Status};
use crate::hunt::auction::{
    Announcement, AuctionError, Auctioneer, Award, Bid, Closed, Finish, RoundRecord,
};
use crate::hunt::parallel_auction::{one_task_each, ParallelAuctioneer};
use crate::hunt::model::{Robot, RobotId, Task, TaskId};
use crate::hunt::params::HuntParams;
use crate::hunt::replan::{self, Hunt};
use crate::hunt::scenario::{robot_of, task_of};
use serde::Serialize;
use std::collections::BTreeMap;
use swarm::geometry::Vec2;
use swarm::scenario::Scenario;
use swarm::sections::hunt::{AuctionKind, AuctioneerSpec, STATE_AUCTIONEER};
use swarm::{Command, Outbox, Received, Sense};

/// The auction kernel the station runs (`hunt.params.auction`): the same calls on either.
enum Kernel {
    Improved(Auctioneer),
    Parallel(ParallelAuctioneer),
}

impl Kernel {
    fn new(tasks: &[Task], n_r: usize, p: &HuntParams) -> Kernel {
        match p.auction {
            AuctionKind::Improved => Kernel::Improved(Auctioneer::new(tasks, n_r, p)),
            AuctionKind::Parallel => Kernel::Parallel(ParallelAuctioneer::new(tasks, p)),
        }
    }
    fn announce(&mut self) -> Option<Announcement> {
        match self {
            Kernel::Improved(k) => k.announce(),
            Kernel::Parallel(k) => k.announce(),
        }
    }
    fn receive(&mut self, bid: Bid) -> Result<(), AuctionError> {
        match self {
            Kernel::Improved(k) => k.receive(bid),
            Kernel::Parallel(k) => k.receive(bid),
        }
    }
    /// The awards of the round closed. A parallel auction's robot that won several tasks
    /// keeps the one it bid most on (`one_task_each`): it can hunt one target at a time.
    fn close_round(&mut self) -> Vec<Award> {
        match self {
            Kernel::Improved(k) => k.close_round(),
            Kernel::Parallel(k) => {
                let awards = k.close_round();
                let c = k.coalitions();
                let utility = |r: RobotId, j: TaskId| {
                    let c = &c[&j];
                    let i = c.award.members.iter().position(|m| *m == r);
                    i.map_or(f64::NEG_INFINITY, |i| c.utilities[i])
                };
                one_task_each(&awards, &utility)
            }
        }
    }
    fn finish(&self) -> Option<Finish> {
        match self {
            Kernel::Improved(k) => k.finish(),
            Kernel::Parallel(k) => k.finish(),
        }
    }
    fn closed(&self) -> Option<Closed> {
        match self {
            Kernel::Improved(k) => k.closed(),
            Kernel::Parallel(k) => k.closed(),
        }
    }
    fn award_of(&self, robot: RobotId) -> Option<&Award> {
        match self {
            Kernel::Improved(k) => k.award_of(robot),
            Kernel::Parallel(k) => k.award_of(robot),
        }
    }
    fn round(&self) -> u32 {
        match self {
            Kernel::Improved(k) => k.round(),
            Kernel::Parallel(k) => k.round(),
        }
    }
    fn history(&self) -> &[RoundRecord] {
        match self {
            Kernel::Improved(k) => k.history(),
            Kernel::Parallel(k) => k.history(),
        }
    }
    /// C (3.13) and Y (3.14) of the awards as the kernel made them.
    fn totals(&self) -> (f64, f64) {
        match self {
            Kernel::Improved(k) => (k.total_cost(), k.total_utility()),
            Kernel::Parallel(k) => (k.total_cost(), k.total_utility()),
        }
    }
}

/// One auction under way.
struct Running {
    id: u32,
    kernel: Kernel,
    replan_of: Vec<TaskId>,
    /// The tick the open round was announced (None: announce next).
    opened: Option<u64>,
}

/// What the auctioneer did, for the experiments (Example 3-A's events).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Log {
    /// (auction id, its round records).
    pub auctions: Vec<(u32, Vec<RoundRecord>)>,
    /// (tick, what happened).
    pub events: Vec<(u64, String)>,
}

pub struct Station {
    p: HuntParams,
    spec: AuctioneerSpec,
    /// The robots of the scenario (thesis id -> robot), positions as last heard.
    robots: BTreeMap<RobotId, Robot>,
    /// Every target of the scenario, positions as last heard.
    tasks: BTreeMap<TaskId, Task>,
    appear: BTreeMap<TaskId, u64>,
    /// Targets whose appearance has been handled.
    published: Vec<TaskId>,
    last_heard: BTreeMap<RobotId, u64>,
    statuses: BTreeMap<RobotId, Status>,
    dead: Vec<RobotId>,
    pub hunts: Vec<Hunt>,
    running: Option<Running>,
    next_auction: u32,
    epoch: u32,
    rounds: u32,
    /// C (3.13) and Y (3.14) summed over the awards of every auction finished so far, as the
    /// kernel made them (a parallel robot's several wins all count, as in the sweeps).
    totals: (f64, f64),
    resend_turn: usize,
    report_turn: usize,
    pub log: Log,
}

impl Station {
    pub fn new(sc: &Scenario) -> Station {
        let h = &sc.hunt();
        let p = h.params.clone();
        Station {
            robots: h.robots.iter().map(|r| (r.id, robot_of(r))).collect(),
            tasks: h.evaders.iter().map(|e| (e.id, task_of(e))).collect(),
            appear: h.evaders.iter().map(|e| (e.id, e.appear_tick(&p))).collect(),
            published: Vec::new(),
            last_heard: BTreeMap::new(),
            statuses: BTreeMap::new(),
            dead: Vec::new(),
            hunts: Vec::new(),
            running: None,
            next_auction: 1,
            epoch: 0,
            rounds: 0,
            totals: (0.0, 0.0),
            resend_turn: 0,
            report_turn: 0,
            log: Log::default(),
            spec: h.auctioneer.clone(),
            p,
        }
    }

    fn minutes(&self, tick: u64) -> f64 {
        tick as f64 * self.p.minutes_per_tick
    }

    fn live_robots(&self) -> BTreeMap<RobotId, Robot> {
        self.robots
            .iter()
            .filter(|(id, _)| !self.dead.contains(id))
            .map(|(id, r)| (*id, r.clone()))
            .collect()
    }

    fn listen(&mut self, s: &Sense, inbox: &[&Received<HuntMsg>], out: &mut Outbox<HuntMsg>) {
        for r in inbox {
            if !self.spec.reaches(r.sender_pos) {
                continue;
            }
            match &r.msg {
                HuntMsg::Status(st) => {
                    if let Some(rb) = self.robots.get_mut(&st.robot) {
                        rb.position = Vec2::new(st.pos[0], st.pos[1]);
                    }
                    if st.task != 0 && st.target[0].is_finite() {
                        if let Some(t) = self.tasks.get_mut(&st.task) {
                            t.position = Vec2::new(st.target[0], st.target[1]);
                        }
                    }
                    self.last_heard.insert(st.robot, s.tick);
                    self.statuses.insert(st.robot, st.clone());
                }
                HuntMsg::Bid { auction, bid } => {
                    self.last_heard.insert(bid.robot, s.tick);
                    if let Some(rb) = self.robots.get_mut(&bid.robot) {
                        rb.position = Vec2::new(bid.position[0], bid.position[1]);
                    }
                    self.take_bid(*auction, bid.clone(), out);
                }
                _ => {}
            }
        }
    }

    fn take_bid(&mut self, auction: u32, bid: Bid, out: &mut Outbox<HuntMsg>) {
        let Some(run) = self.running.as_mut().filter(|r| r.id == auction) else {
            return;
        };
        match run.kernel.receive(bid) {
            Ok(()) => {}
            Err(AuctionError::AlreadyAwarded { robot, .. }) => {
                if let Some(award) = run.kernel.award_of(robot).cloned() {
                    let epoch = self
                        .hunts
                        .iter()
                        .find(|h| h.task == award.task)
                        .map_or(self.epoch, |_| self.epoch);
                    out.broadcast(HuntMsg::Award {
                        auction,
                        epoch,
                        award,
                    });
                }
            }
            Err(_) => {} // a late or duplicate bid: no bid
        }
    }

    fn start_auction(&mut self, tasks: &[Task], replan_of: Vec<TaskId>, tick: u64) {
        let n_r = self.live_robots().len();
        let id = self.next_auction;
        self.next_auction += 1;
        let names: Vec<String> = tasks.iter().map(|t| format!("T{}", t.id)).collect();
        self.log.events.push((
            tick,
            format!(
                "auction {id} of {} ({} robots){}",
                names.join(", "),
                n_r,
                if replan_of.is_empty() {
                    String::new()
                } else {
                    format!(", re-planning coalitions of {replan_of:?}")
                }
            ),
        ));
        self.running = Some(Running {
            id,
            kernel: Kernel::new(tasks, n_r, &self.p),
            replan_of,
            opened: None,
        });
    }

    /// Runs the auction under way one tick.
    fn auction_tick(&mut self, tick: u64, out: &mut Outbox<HuntMsg>) {
        let Some(run) = self.running.as_mut() else {
            return;
        };
        match run.opened {
            None => {
                if let Some(a) = run.kernel.announce() {
                    self.rounds += 1;
                    run.opened = Some(tick);
                    out.broadcast(HuntMsg::Announce {
                        auction: run.id,
                        replan_of: run.replan_of.clone(),
                        a,
                    });
                    return;
                }
            }
            Some(at) if tick < at + self.p.bid_window_ticks => return,
            Some(_) => {
                let awards = run.kernel.close_round();
                run.opened = None;
                let id = run.id;
                for award in awards {
                    self.epoch += 1;
                    let epoch = self.epoch;
                    // Winners leave the coalitions they had (re-planning).
                    for h in self.hunts.iter_mut() {
                        h.members.retain(|m| !award.members.contains(m));
                    }
                    self.hunts.retain(|h| h.task != award.task);
                    self.hunts.push(Hunt {
                        task: award.task,
                        members: award.members.clone(),
                        reward: award.reward,
                        captured: false,
                        since: tick as f64 * self.p.minutes_per_tick,
                    });
                    self.log.events.push((
                        tick,
                        format!(
                            "award T{} to {:?} at z = {:.1}",
                            award.task, award.members, award.reward
                        ),
                    ));
                    out.broadcast(HuntMsg::Award {
                        auction: id,
                        epoch,
                        award,
                    });
                }
                let run = self.running.as_mut().expect("running");
                if run.kernel.finish().is_none() {
                    return;
                }
            }
        }
        // Finished.
        let run = self.running.take().expect("running");
        if let Some(closed) = run.kernel.closed() {
            out.broadcast(HuntMsg::Closed {
                auction: run.id,
                closed,
            });
        }
        self.log
            .auctions
            .push((run.id, run.kernel.history().to_vec()));
        let (c, y) = run.kernel.totals();
        self.totals.0 += c;
        self.totals.1 += y;
        self.log.events.push((
            tick,
            format!(
                "auction {} ends after {} rounds ({:?}); C = {c:.1}, Y = {y:.1}",
                run.id,
                run.kernel.round(),
                run.kernel.finish()
            ),
        ));
        // Re-planned coalitions that lost members: tell their remaining members.
        if !run.replan_of.is_empty() {
            for task in run.replan_of {
                self.send_assign(task, out);
            }
        }
    }

    fn send_assign(&mut self, task: TaskId, out: &mut Outbox<HuntMsg>) {
        if let Some(h) = self.hunts.iter().find(|h| h.task == task) {
            self.epoch += 1;
            out.broadcast(HuntMsg::Assign {
                epoch: self.epoch,
                task,
                members: h.members.clone(),
                reward: h.reward,
            });
        }
    }

    /// A target appears: sec. 3.2.5 steps 2-3.
    fn new_target(&mut self, task: TaskId, tick: u64) {
        self.published.push(task);
        let robots = self.live_robots();
        let w = replan::World {
            robots: &robots,
            tasks: &self.tasks,
        };
        let t = &self.tasks[&task];
        let z0 = self.p.alpha * t.reward_cap;
        let interested: Vec<TaskId> = self
            .hunts
            .iter()
            .filter(|h| !h.captured)
            .filter(|h| {
                replan::coalition_utility(&w, &h.members, task, z0, &self.p)
                    > replan::coalition_utility(&w, &h.members, h.task, h.reward, &self.p)
            })
            .map(|h| h.task)
            .collect();
        self.log.events.push((
            tick,
            format!("T{task} appears; coalitions interested (3.21): {interested:?}"),
        ));
        let free = replan::free_robots(&w, &self.hunts);
        if interested.is_empty() && free.is_empty() {
            // Nobody gains by moving: a hunt with no members, for assistance to fill.
            self.hunts.push(Hunt {
                task,
                members: Vec::new(),
                reward: z0,
                captured: false,
                since: self.minutes(tick),
            });
            return;
        }
        let t = t.clone();
        self.start_auction(&[t], interested, tick);
    }

    /// The periodic re-planning pass (sec. 3.2.5 and future-work item 4).
    fn replan(&mut self, tick: u64, out: &mut Outbox<HuntMsg>) {
        let now = self.minutes(tick);
        let mut changed: Vec<TaskId> = Vec::new();
        // Captures, as the members report them.
        for h in self.hunts.iter_mut().filter(|h| !h.captured) {
            if h.members.iter().any(|m| {
                self.statuses
                    .get(m)
                    .is_some_and(|s| s.task == h.task && s.captured)
            }) {
                h.captured = true;
                self.log.events.push((tick, format!("T{} captured by {:?}", h.task, h.members)));
            }
        }
        // Members gone silent: dead (their agent process died), replaced.
        let silent: Vec<RobotId> = self
            .robots
            .keys()
            .copied()
            .filter(|id| !self.dead.contains(id))
            .filter(|id| {
                tick.saturating_sub(self.last_heard.get(id).copied().unwrap_or(0))
                    > self.p.silent_dead_ticks
            })
            .collect();
        for d in silent {
            self.dead.push(d);
            let robots = self.live_robots();
            let w = replan::World {
                robots: &robots,
                tasks: &self.tasks,
            };
            if let Some(k) = self
                .hunts
                .iter()
                .position(|h| !h.captured && h.members.contains(&d))
            {
                let free = replan::free_robots(&w, &self.hunts);
                let (h, help) =
                    replan::replace_dead(&w, &self.hunts[k], d, &free, robots.len(), &self.p);
                self.log.events.push((
                    tick,
                    format!(
                        "R{d} silent for {} ticks: taken for dead; T{} recruits {:?}",
                        self.p.silent_dead_ticks, h.task, help.recruits
                    ),
                ));
                self.hunts[k] = h;
                // Recruits leave captured hunts they were listed in.
                for (j, other) in self.hunts.iter_mut().enumerate() {
                    if j != k {
                        other.members.retain(|m| !help.recruits.contains(m));
                    }
                }
                changed.push(self.hunts[k].task);
            } else {
                self.log
                    .events
                    .push((tick, format!("R{d} silent: taken for dead")));
            }
        }
        let robots = self.live_robots();
        let w = replan::World {
            robots: &robots,
            tasks: &self.tasks,
        };
        // Swaps (step 4), with the members' reported hunting points.
        let points: BTreeMap<RobotId, Vec2> = self
            .statuses
            .iter()
            .filter(|(_, s)| s.point[0].is_finite())
            .map(|(id, s)| (*id, Vec2::new(s.point[0], s.point[1])))
            .collect();
        for s in replan::apply_swaps(&w, &mut self.hunts, &points, &self.p) {
            self.log.events.push((
                tick,
                format!(
                    "swap R{} (T{}) with R{} (T{}), gain {:.2}",
                    s.i, s.from_task, s.k, s.to_task, s.gain
                ),
            ));
            changed.push(s.from_task);
            changed.push(s.to_task);
        }
        // Assistance (step 5).
        for k in 0..self.hunts.len() {
            if !replan::needs_assistance(&w, &self.hunts[k], now, &self.p) {
                continue;
            }
            let free = replan::free_robots(&w, &self.hunts);
            if free.is_empty() {
                continue;
            }
            let help = replan::assist(&w, &self.hunts[k], &free, robots.len(), &self.p);
            // The auctioneer "keeps raising that target's reward" (3.15) until someone joins.
            self.hunts[k].reward = help.reward;
            if help.recruits.is_empty() {
                continue;
            }
            let h = &mut self.hunts[k];
            h.members.extend(&help.recruits);
            h.members.sort();
            h.reward = help.reward;
            h.since = now;
            let task = h.task;
            self.log.events.push((
                tick,
                format!(
                    "assistance to T{task}: {:?} join at z = {:.1}",
                    help.recruits, help.reward
                ),
            ));
            for (j, other) in self.hunts.iter_mut().enumerate() {
                if j != k {
                    other.members.retain(|m| !help.recruits.contains(m));
                }
            }
            changed.push(task);
        }
        changed.sort_unstable();
        changed.dedup();
        for task in changed {
            self.send_assign(task, out);
        }
    }

    /// One tick of the auctioneer.
    pub fn step(
        &mut self,
        s: &Sense,
        inbox: &[&Received<HuntMsg>],
        out: &mut Outbox<HuntMsg>,
    ) -> Command {
        let k = s.tick;
        self.listen(s, inbox, out);
        if k == 0 {
            let first: Vec<Task> = self
                .tasks
                .values()
                .filter(|t| self.appear[&t.id] == 0)
                .cloned()
                .collect();
            self.published.extend(first.iter().map(|t| t.id));
            self.start_auction(&first, Vec::new(), k);
        }
        if self.running.is_some() {
            self.auction_tick(k, out);
        } else {
            let due: Option<TaskId> = self
                .appear
                .iter()
                .find(|(t, at)| **at <= k && !self.published.contains(t))
                .map(|(t, _)| *t);
            if let Some(t) = due {
                self.new_target(t, k);
            } else if k > 0 && k.is_multiple_of(self.p.replan_period_ticks.max(1)) {
                self.replan(k, out);
            } else if k.is_multiple_of(self.p.award_resend_ticks.max(1)) && !self.hunts.is_empty()
            {
                // Resend one hunt's coalition, in turn (same epoch: a repeat, not a change).
                let h = &self.hunts[self.resend_turn % self.hunts.len()];
                self.resend_turn += 1;
                if !h.captured {
                    out.broadcast(HuntMsg::Assign {
                        epoch: self.epoch,
                        task: h.task,
                        members: h.members.clone(),
                        reward: h.reward,
                    });
                }
            }
        }
        // One awarded task a tick in turn, then the totals row [0, C, rounds, Y].
        let turn = self.report_turn % (self.hunts.len() + 1);
        self.report_turn += 1;
        let report = match self.hunts.get(turn) {
            Some(h) => [h.task as f64, h.reward, self.rounds as f64, 0.0],
            None => [0.0, self.totals.0, self.rounds as f64, self.totals.1],
        };
        Command {
            cmd: [0.0, 0.0],
            events: STATE_AUCTIONEER,
            report,
        }
    }
}
