//! One hunting robot (thesis sec. 3.2.3-3.2.5): the Bidder of the improved auction over the
//! radio, then the pursuit by the artificial potential field (2.11-2.16) turned into unicycle
//! commands (v, w), the hunting-point phase (3.17-3.20) led by the first member inside r_e,
//! and the re-planning the auctioneer sends (new coalitions, swaps, assistance, replacements).
//!
//! Per tick:
//! 1. the inbox: statuses of the others (positions, for the leader's assignment), the
//!    auction's messages (the `Bidder` kernel), assignments (newest epoch wins), the leader's
//!    points;
//! 2. the evaders it senses (Sense entities of kind `ENTITY_EVADER`);
//! 3. the goal: its target while pursuing, its hunting point once its coalition's leader has
//!    placed them; a member inside r_e that hears no leader for `LEADER_SILENCE_TICKS` leads
//!    itself (ties: the lower id keeps the lead);
//! 4. the APF force with the robots its own sensors see (Sense `nearby`) as repulsors, turned
//!    into (v, w) within its own speed and turn rate;
//! 5. its status (every `status_period_ticks`, every tick in the hunting-point phase), its bid,
//!    its points if it leads; its report to the world (task, point, flags).

use super::messages::{HuntMsg, Status};
use crate::hunt::apf::{to_command, total_force};
use crate::hunt::auction::{Announcement, Bidder, BidderState};
use crate::hunt::parallel_auction::parallel_bids;
use crate::hunt::cost::bid_value;
use crate::hunt::hunting_points::{assign, leader_angle};
use crate::hunt::ring_by_wall::{ring_points, Walls};
use crate::hunt::model::{Robot, RobotId, Task, TaskId};
use crate::hunt::params::HuntParams;
use crate::hunt::scenario::robot_of;
use std::collections::BTreeMap;
use swarm::frames::ENTITY_HAS_POS;
use swarm::geometry::Vec2;
use swarm::scenario::Scenario;
use swarm::sections::hunt::{
    AuctionKind, ENTITY_EVADER, EVADER_CAPTURED, REPORT_AT_POINT, REPORT_LEADER, STATE_FREE,
};
use swarm::{Command, Outbox, Received, Sense};

/// A member inside r_e takes the lead when it has heard no leader's points for this long.
const LEADER_SILENCE_TICKS: u64 = 3;

/// The robot's current assignment.
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    pub task: TaskId,
    pub members: Vec<RobotId>,
    pub reward: f64,
    pub epoch: u32,
}

/// The leader's plan of hunting points, as last heard (or made).
#[derive(Clone, Debug)]
struct Plan {
    leader: RobotId,
    anchor: f64,
    order: Vec<RobotId>,
    heard: u64,
}

pub struct HuntRobot {
    id: RobotId,
    station: u32,
    p: HuntParams,
    /// The arena's walls for hunting points by a wall (None: `hunting_points_inside_arena`
    /// off).
    walls: Option<Walls>,
    robot: Robot,
    /// The auction it takes part in and its Bidder.
    auction: Option<(u32, Bidder)>,
    /// An announcement to answer this tick (the newest heard).
    pending: Option<(u32, Vec<TaskId>, Announcement)>,
    pub assignment: Option<Assignment>,
    /// Peers' last statuses: position and tick heard.
    peers: BTreeMap<RobotId, ([f64; 2], u64)>,
    plan: Option<Plan>,
    /// The tick it first entered r_e of its current target (None: not yet).
    entered: Option<u64>,
    /// Every task announced so far, positions as last sensed.
    tasks: BTreeMap<TaskId, Task>,
    /// Evaders sensed this tick: position, captured.
    seen: BTreeMap<TaskId, (Vec2, bool)>,
}

impl HuntRobot {
    pub fn new(sc: &Scenario, index: u32) -> HuntRobot {
        let spec = &sc.hunt().robots[index as usize];
        let robot = robot_of(spec);
        HuntRobot {
            id: spec.id,
            station: sc.bodies(),
            walls: sc.hunt().params.hunting_points_inside_arena.then_some(Walls {
                width: sc.arena.width,
                height: sc.arena.height,
                clearance: sc.hunt().params.hunting_point_wall_clearance,
            }),
            p: sc.hunt().params.clone(),
            auction: None,
            pending: None,
            assignment: None,
            peers: BTreeMap::new(),
            plan: None,
            entered: None,
            tasks: BTreeMap::new(),
            seen: BTreeMap::new(),
            robot,
        }
    }

    fn take_assignment(&mut self, a: Assignment) {
        if self.assignment.as_ref().map(|x| x.task) != Some(a.task) {
            self.plan = None;
            self.entered = None;
        }
        self.assignment = Some(a);
    }

    fn epoch(&self) -> u32 {
        self.assignment.as_ref().map_or(0, |a| a.epoch)
    }

    fn listen(&mut self, s: &Sense, inbox: &[&Received<HuntMsg>]) {
        // The auctioneer's radio range (`hunt.auctioneer.radio_range`) is the medium's
        // per-sender range of the station: what arrives here was in range.
        for r in inbox {
            match &r.msg {
                HuntMsg::Status(st) => {
                    self.peers.insert(st.robot, (st.pos, s.tick));
                }
                HuntMsg::Announce {
                    auction,
                    replan_of,
                    a,
                } => {
                    let fresh = self.auction.as_ref().is_none_or(|(n, _)| n != auction);
                    if fresh {
                        self.auction = Some((*auction, Bidder::new(self.robot.clone(), &self.p)));
                    }
                    for t in &a.tasks {
                        self.tasks.entry(t.id).or_insert_with(|| t.task());
                    }
                    self.pending = Some((*auction, replan_of.clone(), a.clone()));
                }
                HuntMsg::Award {
                    auction,
                    epoch,
                    award,
                } => {
                    if let Some((n, b)) = self.auction.as_mut() {
                        if n == auction {
                            b.on_award(award);
                        }
                    }
                    if award.members.contains(&self.id) && *epoch > self.epoch() {
                        self.take_assignment(Assignment {
                            task: award.task,
                            members: award.members.clone(),
                            reward: award.reward,
                            epoch: *epoch,
                        });
                    }
                }
                HuntMsg::Closed { auction, closed } => {
                    if let Some((n, b)) = self.auction.as_mut() {
                        if n == auction {
                            b.on_closed(closed);
                        }
                    }
                }
                HuntMsg::Assign {
                    epoch,
                    task,
                    members,
                    reward,
                } => {
                    if *epoch <= self.epoch() {
                        continue;
                    }
                    if members.contains(&self.id) {
                        self.take_assignment(Assignment {
                            task: *task,
                            members: members.clone(),
                            reward: *reward,
                            epoch: *epoch,
                        });
                    } else if self.assignment.as_ref().is_some_and(|a| a.task == *task) {
                        self.assignment = None;
                        self.plan = None;
                        self.entered = None;
                    }
                }
                HuntMsg::Points {
                    task,
                    leader,
                    anchor,
                    order,
                } => {
                    if self.assignment.as_ref().is_some_and(|a| a.task == *task) {
                        // Two leaders: the lower id keeps the lead.
                        let take = match &self.plan {
                            Some(p) if p.leader == self.id => *leader < self.id,
                            Some(p) => *leader <= p.leader || s.tick > p.heard + 1,
                            None => true,
                        };
                        if take {
                            self.plan = Some(Plan {
                                leader: *leader,
                                anchor: *anchor,
                                order: order.clone(),
                                heard: s.tick,
                            });
                        }
                    }
                }
                HuntMsg::Bid { .. } => {}
            }
        }
    }

    /// The bid for the pending announcement, if any (Bidder kernel; a re-planning auction
    /// also asks that a hunting member gain by moving, and that its coalition be one of those
    /// re-planned).
    fn bid(&mut self, out: &mut Outbox<HuntMsg>) {
        let Some((auction, replan_of, a)) = self.pending.take() else {
            return;
        };
        let Some((n, bidder)) = self.auction.as_mut() else {
            return;
        };
        if *n != auction {
            return;
        }
        bidder.set_position(self.robot.position);
        let bids = match self.p.auction {
            // Its single best task (sec. 3.2.3).
            AuctionKind::Improved => bidder.on_announcement(&a).into_iter().collect(),
            // Every task it can take (spec 11), while it is still in the auction.
            AuctionKind::Parallel if *bidder.state() == BidderState::Bidding => {
                parallel_bids(bidder.robot(), &a, &self.p)
            }
            AuctionKind::Parallel => Vec::new(),
        };
        for bid in bids {
            // A robot hunting an uncaptured target bids only in a re-planning auction that
            // names its coalition, and only if it gains by moving (sec. 3.2.5 step 3).
            if let Some(cur) = &self.assignment {
                let done = self.seen.get(&cur.task).is_some_and(|(_, c)| *c);
                if !done {
                    let gains = replan_of.contains(&cur.task)
                        && a.tasks.iter().all(|t| t.id != cur.task)
                        && self.utility_now(cur).is_none_or(|y| bid.utility > y);
                    if !gains {
                        continue;
                    }
                }
            }
            out.send(self.station, HuntMsg::Bid { auction, bid });
        }
    }

    /// y_ij (3.16) on its current task at its reward, from where it and the target are now.
    fn utility_now(&self, a: &Assignment) -> Option<f64> {
        bid_value(&self.robot, self.tasks.get(&a.task)?, a.reward, &self.p)
    }

    /// The evaders it senses; known tasks follow them.
    fn sense_evaders(&mut self, s: &Sense) {
        self.seen.clear();
        for e in s.entities() {
            if e.kind == ENTITY_EVADER && e.flags & ENTITY_HAS_POS != 0 {
                let at = Vec2::new(e.pos[0], e.pos[1]);
                self.seen
                    .insert(e.id, (at, e.flags & EVADER_CAPTURED != 0));
                if let Some(t) = self.tasks.get_mut(&e.id) {
                    t.position = at;
                }
            }
        }
    }

    /// The members it knows to be alive (heard within `silent_dead_ticks`, itself always),
    /// with positions.
    fn live_members(&self, a: &Assignment, tick: u64, own: Vec2) -> Vec<(RobotId, Vec2)> {
        a.members
            .iter()
            .filter_map(|m| {
                if *m == self.id {
                    return Some((*m, own));
                }
                let (pos, heard) = self.peers.get(m)?;
                (tick.saturating_sub(*heard) <= self.p.silent_dead_ticks)
                    .then(|| (*m, Vec2::new(pos[0], pos[1])))
            })
            .collect()
    }

    /// Its goal this tick and whether it leads: the target, or its hunting point once the
    /// coalition has a plan (sec. 3.2.4). Returns (goal, point, leads, messages to send).
    fn goal(&mut self, s: &Sense, own: Vec2) -> (Option<Vec2>, Option<Vec2>, bool, Option<HuntMsg>) {
        let Some(a) = self.assignment.clone() else {
            return (None, None, false, None);
        };
        let Some(&(target, captured)) = self.seen.get(&a.task) else {
            return (None, None, false, None);
        };
        if captured {
            return (None, None, false, None);
        }
        let r_e = self.p.effective_range(a.members.len().max(1));
        let inside = (own - target).norm() <= r_e;
        if inside {
            self.entered.get_or_insert(s.tick);
        }
        let stale = self
            .plan
            .as_ref()
            .is_none_or(|p| s.tick > p.heard + LEADER_SILENCE_TICKS);
        let mut msg = None;
        let leads = self.plan.as_ref().is_some_and(|p| p.leader == self.id);
        if (stale && inside) || leads {
            // Lead: keep the ring's bearing from when it took the lead (hunting_points.rs).
            let anchor = match &self.plan {
                Some(p) if p.leader == self.id => p.anchor,
                _ => leader_angle(&target, &own),
            };
            let members = self.live_members(&a, s.tick, own);
            let points = ring_points(
                &target,
                members.len(),
                self.p.r_s,
                anchor,
                self.walls.as_ref(),
            );
            let got = assign(&members, &points, self.p.contested_point_to_farthest);
            let mut order = vec![0; points.len()];
            for (robot, k) in &got {
                order[*k] = *robot;
            }
            self.plan = Some(Plan {
                leader: self.id,
                anchor,
                order: order.clone(),
                heard: s.tick,
            });
            msg = Some(HuntMsg::Points {
                task: a.task,
                leader: self.id,
                anchor,
                order,
            });
        }
        let Some(plan) = self.plan.as_ref().filter(|p| s.tick <= p.heard + LEADER_SILENCE_TICKS)
        else {
            return (Some(target), None, false, msg);
        };
        let Some(k) = plan.order.iter().position(|r| *r == self.id) else {
            return (Some(target), None, false, msg);
        };
        let point = ring_points(
            &target,
            plan.order.len(),
            self.p.r_s,
            plan.anchor,
            self.walls.as_ref(),
        )[k];
        (Some(point), Some(point), plan.leader == self.id, msg)
    }

    /// One tick of the robot.
    pub fn step(
        &mut self,
        s: &Sense,
        inbox: &[&Received<HuntMsg>],
        out: &mut Outbox<HuntMsg>,
    ) -> Command {
        let own = Vec2::new(s.pos[0], s.pos[1]);
        self.robot.position = own;
        self.robot.heading = s.heading;
        self.listen(s, inbox);
        self.sense_evaders(s);
        self.bid(out);
        let (goal, point, leads, points_msg) = self.goal(s, own);
        if let Some(m) = points_msg {
            out.broadcast(m);
        }
        let dt = self.p.minutes_per_tick;
        let cmd = match goal {
            None => [0.0, 0.0],
            Some(g) => {
                let others: Vec<Vec2> = s
                    .nearby()
                    .iter()
                    .map(|q| Vec2::new(q.pos[0], q.pos[1]))
                    .collect();
                let f = total_force(&own, &g, &others, &self.p);
                let c = to_command(
                    &f,
                    s.heading,
                    self.robot.speed,
                    self.robot.turn_rate,
                    dt,
                    &self.p,
                );
                // km/min and rad/min to the world's per-tick units.
                [c.v.max(0.0) * dt, c.w * dt]
            }
        };
        let at_point = point.is_some_and(|q| (q - own).norm() <= self.p.capture_tolerance);
        let a = self.assignment.as_ref();
        let task = a.map_or(0, |a| a.task);
        let target = self.seen.get(&task).map(|(x, _)| *x);
        let captured = self.seen.get(&task).is_some_and(|(_, c)| *c);
        // Every tick in the hunting-point phase (the leader needs fresh positions).
        let hunting = point.is_some() && !captured;
        if hunting || s.tick.is_multiple_of(self.p.status_period_ticks.max(1)) {
            let nan = [f64::NAN; 2];
            out.broadcast(HuntMsg::Status(Status {
                robot: self.id,
                pos: s.pos,
                task,
                epoch: self.epoch(),
                target: target.map_or(nan, |t| [t.x, t.y]),
                point: point.map_or(nan, |q| [q.x, q.y]),
                captured,
            }));
        }
        let mut flags = 0.0;
        if leads {
            flags += REPORT_LEADER;
        }
        if at_point {
            flags += REPORT_AT_POINT;
        }
        let state = if task == 0 { STATE_FREE } else { task.min(254) };
        Command {
            cmd,
            events: state,
            report: [
                task as f64,
                point.map_or(f64::NAN, |q| q.x),
                point.map_or(f64::NAN, |q| q.y),
                flags,
            ],
        }
    }
}
