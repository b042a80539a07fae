//! One CBCA robot over the behaviour API (thesis 003 chapter 4): the kernels' consensus state
//! machine (`cbca::consensus::CbcaRobot`) driven by ticks, the radio and the Sense frame.
//!
//! Every tick: (1) robots that vanished from the link list while surely in range are dead
//! (their process died) and forgotten; (2) targets within the detection radius are learnt
//! (grouping's prior information, sec. 4.2.2: a group is whoever hears whom, so groups are the
//! communication components and merge when they come into range); (3) the inbox runs
//! Algorithm 2; (4) Algorithm 1 runs; (5) the convergence detector decides: the first time it
//! says "settled" the robot commits to its path (its bids are pinned) and starts moving; every
//! later time, after something changed, it reviews its path with the loyalty test (4.22) and
//! switches (paying compensation) only if the gain beats sigma_i; (6) it broadcasts its full
//! state while unsettled or while a neighbour disagrees, else a beacon; (7) it moves: to the
//! waiting ring of its first target, then, once the coalition is assembled, onto the capture
//! ring; after the capture it holds for the target's hold time, then the target is done.

use std::collections::{BTreeMap, BTreeSet};

use swarm::geometry::Vec2;
use swarm::{Command, Outbox, Received, Sense};

use super::liveness::{Change, Liveness};
use super::messages::{CbcaRadio, Paid, Sighting};
use super::motion::{ring_point, Mover};
use super::params::BehaviourParams;
use super::Section;
use crate::cbca::consensus::CbcaRobot;
use crate::cbca::loyalty::{compensation, switches, threshold, LoyaltyState};
use crate::cbca::model::{Task, TaskBook, TaskId};
use crate::cbca::score::path_score;

/// The robot's phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Consensus not yet settled: the robot waits.
    Planning,
    /// Committed to a path (possibly empty: idle).
    Executing,
}

/// What the robot last heard from a neighbour.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Heard {
    tick: u64,
    pos: [f64; 2],
    digest: u64,
}

/// Counters for the experiments (reported in `Command.report` and by the tests).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counters {
    /// Messages carrying the full consensus state.
    pub full_sent: u64,
    pub beacons_sent: u64,
    /// The tick the detector first said "settled" (consensus rounds to convergence).
    pub first_settled: Option<u64>,
    /// Loyalty decisions: switches made, and switches refused by (4.22).
    pub switches: u64,
    pub loyal: u64,
}

/// An event worth printing (examples, tests).
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    Committed { tick: u64, path: Vec<TaskId> },
    Switched { tick: u64, from: Vec<TaskId>, to: Vec<TaskId>, gain: f64, sigma: f64 },
    StayedLoyal { tick: u64, kept: Vec<TaskId>, offered: Vec<TaskId>, gain: f64, sigma: f64 },
    RobotGone { tick: u64, robot: u32 },
    /// A member of `task` not heard at the capture ring for `presume_lost_ticks`: taken for dead.
    PresumedLost { tick: u64, robot: u32, task: TaskId },
    /// A robot taken for dead (sensed or presumed) heard of again after its death record at
    /// `dead_at`: directly, or through a relayed later alive stamp (liveness.rs).
    Revived { tick: u64, robot: u32, dead_at: u64 },
    Captured { tick: u64, task: TaskId },
    Finished { tick: u64, task: TaskId, utility: f64 },
}

/// How the mission marks a target entity: its kind, and the flag of a captured one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetSensing {
    pub kind: u32,
    pub captured_flag: u32,
}

pub struct Cbca {
    id: u32,
    kernel: CbcaRobot,
    /// Every target's attributes (the scenario's rows): a robot knows what a target needs once
    /// it detects it or hears of it.
    tasks: Vec<Task>,
    p: BehaviourParams,
    detection_radius: f64,
    comm_reach: f64,
    v_max: f64,
    sensing: TargetSensing,
    mover: Mover,
    phase: Phase,
    heard: BTreeMap<u32, Heard>,
    prev_links: Vec<u32>,
    /// Who is alive, time-stamped (liveness.rs): deaths sensed or presumed, revocable.
    live: Liveness,
    sightings: BTreeMap<u32, Sighting>,
    ready: BTreeSet<(u32, u32)>,
    paid: BTreeMap<(u32, u32, u32), (f64, u64)>,
    paid_cap: usize,
    was_settled: bool,
    dirty: bool,
    commit_tick: u64,
    /// The target being held after its capture, and the tick the hold ends.
    hold: Option<(TaskId, u64)>,
    /// Since when the robot waits at the ring of which target.
    waiting: Option<(TaskId, u64)>,
    /// It is closing on its capture point (after the joint arrival, or holding).
    closing: bool,
    /// Since when it closes on the capture point of which target (the presumed-loss clock).
    closing_since: Option<(TaskId, u64)>,
    /// The target at whose waiting ring this robot itself has arrived (cleared when its first
    /// target changes). The `ready` gossip cannot serve: it is never withdrawn, so a robot that
    /// left j's ring for an earlier target would, back on j, skip the ring and close alone.
    arrived: Option<TaskId>,
    /// Realised utility: finished tasks' scores, plus compensation received, less paid.
    utility: f64,
    /// Distance travelled since the last finished task (km) and the tick it finished.
    leg: f64,
    last_pos: Option<[f64; 2]>,
    pub counters: Counters,
    pub events: Vec<Event>,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

impl Cbca {
    pub fn new(sec: &Section, sc: &swarm::scenario::Scenario, robot: u32) -> Cbca {
        let robots = sec.kernels.robots().expect("validated");
        let tasks = sec.kernels.tasks().expect("validated");
        let mut params = sec.kernels.params.clone();
        // The detector's quiet period is counted in ticks here (BehaviourParams::quiet_ticks).
        params.quiet_iterations = sec.behaviour.quiet_ticks;
        let me = robots[robot as usize].clone();
        let known: TaskBook = initial_knowledge(robot as usize, &robots, &tasks, sec)
            .into_iter()
            .map(|j| (j, tasks[j].clone()))
            .collect();
        let paid_cap = super::messages::paid_cap(&tasks, params.max_tasks);
        let kernel = CbcaRobot::new(me, robots.len(), tasks.len(), known, params.clone());
        Cbca {
            id: robot,
            kernel,
            tasks,
            p: {
                let mut p = sec.behaviour.clone();
                if !sc.hunt().robots.is_empty() {
                    // The mission judges capture on its circle r_s and its tolerance.
                    p.ring_radius_km = sc.hunt().params.r_s;
                    p.arrive_tolerance_km = sc.hunt().params.capture_tolerance;
                }
                p
            },
            detection_radius: params.detection_radius_km,
            comm_reach: sc.robot.neighbour_sensing_radius,
            v_max: sc.robot.v_max,
            sensing: sec.sensing,
            mover: Mover::new(sc, robot, &sec.behaviour),
            phase: Phase::Planning,
            heard: BTreeMap::new(),
            prev_links: Vec::new(),
            live: Liveness::default(),
            sightings: BTreeMap::new(),
            ready: BTreeSet::new(),
            paid: BTreeMap::new(),
            paid_cap,
            was_settled: false,
            dirty: false,
            commit_tick: 0,
            hold: None,
            waiting: None,
            closing: false,
            closing_since: None,
            arrived: None,
            utility: 0.0,
            leg: 0.0,
            last_pos: None,
            counters: Counters::default(),
            events: Vec::new(),
        }
    }

    pub fn kernel(&self) -> &CbcaRobot {
        &self.kernel
    }
    pub fn phase(&self) -> Phase {
        self.phase
    }
    /// The convergence detector's verdict at the last tick.
    pub fn is_settled(&self) -> bool {
        self.was_settled
    }
    pub fn utility(&self) -> f64 {
        self.utility
    }
    pub fn path(&self) -> &[TaskId] {
        &self.kernel.plan().path
    }

    fn settled(&self, now: u64) -> bool {
        let neighbours: Vec<usize> = self
            .heard
            .iter()
            .filter(|(m, h)| now.saturating_sub(h.tick) <= self.p.neighbour_window && !self.live.is_gone(**m))
            .map(|(&m, _)| m as usize)
            .collect();
        self.kernel.converged(&neighbours)
    }

    /// (1) A robot that the proximity sensor saw last tick (Sense `nearby`: live robots within
    /// `robot.neighbour_sensing_radius`), does not see now, and was last heard where it could
    /// not have left that range in the time since, has died. (The link design's list of
    /// robots in radio reach is gone with the shared medium; a radio gives no such oracle.)
    fn detect_deaths(&mut self, s: &Sense, now: u64) {
        let mut links: Vec<u32> = s.nearby().iter().map(|n| n.robot).collect();
        links.sort_unstable();
        for m in std::mem::take(&mut self.prev_links) {
            if links.binary_search(&m).is_ok() || self.live.is_gone(m) {
                continue;
            }
            if let Some(h) = self.heard.get(&m) {
                let age = now.saturating_sub(h.tick) as f64;
                if dist(s.pos, h.pos) + self.v_max * (age + 1.0) < self.comm_reach {
                    self.forget(m, now);
                }
            }
        }
        self.prev_links = links;
    }

    /// m is taken for dead at tick `now` (sensed or presumed).
    fn forget(&mut self, m: u32, now: u64) {
        if m != self.id {
            let c = self.live.dead(m, now);
            self.apply(m, c, now);
        }
    }

    /// What a liveness record's change means: a death forgets m (its bids and facts, and the
    /// kernel refuses news of it); a revival takes m's news again from its death record on,
    /// so its next message (or a relay of a later one) brings its bids back.
    fn apply(&mut self, m: u32, change: Option<Change>, now: u64) {
        match change {
            Some(Change::Died) => {
                self.kernel.forget_robot(m as usize);
                self.ready.retain(|&(_, r)| r != m);
                self.events.push(Event::RobotGone { tick: now, robot: m });
                self.dirty = true;
            }
            Some(Change::Revived { dead_at }) => {
                self.kernel.revive_robot(m as usize, dead_at as f64);
                self.events.push(Event::Revived { tick: now, robot: m, dead_at });
                self.dirty = true;
            }
            None => {}
        }
    }

    /// (2) Targets this robot sees.
    fn sense_targets(&mut self, s: &Sense, now: u64) -> BTreeSet<TaskId> {
        let mut captured = BTreeSet::new();
        for e in s.entities() {
            if e.kind != self.sensing.kind || e.flags & swarm::frames::ENTITY_HAS_POS == 0 {
                continue;
            }
            // Entity ids are the thesis's 1-based T_j.
            let Some(j) = (e.id as usize).checked_sub(1).filter(|&j| j < self.tasks.len()) else {
                continue;
            };
            if e.flags & self.sensing.captured_flag != 0 {
                captured.insert(j);
            }
            self.sightings.insert(
                j as u32,
                Sighting {
                    task: j as u32,
                    pos: e.pos,
                    tick: now,
                },
            );
            // Tracked wherever sensed; learnt as a task within the detection radius (sec. 4.3).
            if dist(s.pos, e.pos) > self.detection_radius {
                continue;
            }
            let mut t = self.tasks[j].clone();
            t.position = e.pos;
            if self.kernel.learn_task(t) {
                self.dirty = true;
            }
        }
        captured
    }

    /// (3) One received message.
    fn take(&mut self, r: &Received<CbcaRadio>, now: u64) {
        let m = &r.msg;
        // A message is proof of life at its send tick: a robot taken for dead comes back if
        // it sent this after its death record (a stale, delayed one changes nothing).
        let c = self.live.alive(r.from, r.tick);
        self.apply(r.from, c, now);
        if self.live.is_gone(r.from) {
            return;
        }
        self.heard.insert(
            r.from,
            Heard {
                tick: now,
                pos: r.sender_pos,
                digest: m.digest,
            },
        );
        for o in &m.gone {
            // Its own record is refuted by its own messages.
            if o.robot != self.id {
                let c = self.live.merge(o);
                self.apply(o.robot, c, now);
            }
        }
        for &j in &m.done {
            if self.kernel.complete(j as usize) {
                self.ready.retain(|&(t, _)| t != j);
                self.dirty = true;
            }
        }
        for s in &m.sightings {
            let newer = self.sightings.get(&s.task).is_none_or(|o| o.tick < s.tick);
            if newer && (s.task as usize) < self.tasks.len() {
                self.sightings.insert(s.task, *s);
            }
        }
        for &(j, robot) in &m.ready {
            if !self.live.is_gone(robot) && !self.kernel.done().contains(&(j as usize)) {
                self.ready.insert((j, robot));
            }
        }
        for p in &m.paid {
            if let std::collections::btree_map::Entry::Vacant(v) = self.paid.entry((p.from, p.to, p.task)) {
                v.insert((p.amount, now));
                if p.to == self.id {
                    self.utility += p.amount;
                }
            }
        }
        match &m.state {
            Some(state) => {
                let got = match self.unforgotten(state) {
                    Some(clean) => self.kernel.receive(&clean),
                    None => self.kernel.receive(state),
                };
                if got.changed_entries > 0 || !got.new_tasks.is_empty() || !got.released.is_empty() {
                    self.dirty = true;
                }
            }
            None => self.kernel.hear_digest(r.from as usize, m.digest),
        }
    }

    /// The sender's state with its refusals of robots this robot knows alive removed, or None
    /// if there are none. `CbcaRobot::forget_robot` marks a forgotten robot's stamp +inf, and
    /// stamps merge by the maximum, so a sender that has not yet heard of m's revival would
    /// otherwise make the receiver forget m again (and clear its bids, rule A). Such a stamp
    /// becomes -inf: the sender's news of m is taken as none.
    fn unforgotten(&self, state: &crate::cbca::consensus::CbcaMessage) -> Option<crate::cbca::consensus::CbcaMessage> {
        let stale = |m: usize| state.stamps[m] == f64::INFINITY && !self.live.is_gone(m as u32) && m != state.sender;
        if !(0..state.stamps.len()).any(stale) {
            return None;
        }
        let mut clean = state.clone();
        for m in 0..clean.stamps.len() {
            if stale(m) {
                clean.stamps[m] = f64::NEG_INFINITY;
            }
        }
        Some(clean)
    }

    /// (5) Settled again after a change, while executing: the loyalty review (4.18)-(4.22).
    fn review(&mut self, now: u64) {
        let (offered, new_score) = self.kernel.proposal();
        let kept = self.kernel.plan().path.clone();
        if offered == kept || kept.is_empty() {
            return;
        }
        let old_score = self.kernel.path_score();
        let sigma = if self.p.loyalty {
            let first = kept[0];
            let mut coalition = [0.0; crate::cbca::RESOURCE_TYPES];
            for (m, _) in self.kernel.winners().winners_of(first) {
                let r = if m == self.id as usize {
                    Some(self.kernel.robot().resources)
                } else {
                    self.kernel.known_resources(m)
                };
                if let Some(r) = r {
                    for (c, x) in coalition.iter_mut().zip(r) {
                        *c += x;
                    }
                }
            }
            let st = LoyaltyState {
                resources: self.kernel.robot().resources,
                coalition_resources: coalition,
                travelled_time: now.saturating_sub(self.commit_tick) as f64 / self.p.ticks_per_time_unit,
                gamma: self.kernel.robot().gamma,
                unexecuted_score: old_score,
            };
            threshold(&st, &self.kernel.params().loyalty).sigma
        } else {
            0.0
        };
        let gain = new_score - old_score;
        if !switches(old_score, new_score, sigma) {
            self.counters.loyal += 1;
            self.events.push(Event::StayedLoyal {
                tick: now,
                kept,
                offered,
                gain,
                sigma,
            });
            return;
        }
        // Compensation to the coalitions it leaves (the tasks of p_i not in p_i').
        let scores = path_score(
            self.kernel.robot(),
            &kept,
            self.kernel.book(),
            self.kernel.params(),
        );
        let abandoned: Vec<(TaskId, f64, Vec<usize>)> = scores
            .tasks
            .iter()
            .filter(|t| !offered.contains(&t.task))
            .map(|t| {
                let stay = self
                    .kernel
                    .winners()
                    .winners_of(t.task)
                    .into_iter()
                    .map(|(m, _)| m)
                    .filter(|&m| m != self.id as usize)
                    .collect();
                (t.task, t.score, stay)
            })
            .collect();
        let rate = self.kernel.params().loyalty.compensation_rate;
        for pay in compensation(self.id as usize, &abandoned, rate) {
            self.utility -= pay.amount;
            self.paid.insert(
                (pay.from as u32, pay.to as u32, pay.task as u32),
                (pay.amount, now),
            );
        }
        self.counters.switches += 1;
        self.events.push(Event::Switched {
            tick: now,
            from: kept,
            to: offered,
            gain,
            sigma,
        });
        self.kernel.release_all();
        self.waiting = None;
        self.dirty = true;
    }

    /// (6) The message of this tick, if any.
    fn message(&mut self, now: u64, settled: bool) -> Option<CbcaRadio> {
        let digest = self.kernel.digest();
        let disagree = self.heard.values().any(|h| {
            now.saturating_sub(h.tick) <= self.p.neighbour_window && h.digest != digest
        });
        let full = !settled || disagree;
        if !full && now % self.p.beacon_period != u64::from(self.id) % self.p.beacon_period {
            return None;
        }
        let window = self.p.neighbour_window;
        let msg = CbcaRadio {
            digest,
            state: full.then(|| self.kernel.message(now as f64)),
            gone: self.live.obits(),
            done: self.kernel.done().iter().map(|&j| j as u32).collect(),
            sightings: self.sightings.values().copied().collect(),
            ready: self.ready.iter().copied().collect(),
            paid: {
                // The most recent first, capped (messages::paid_cap).
                let mut recent: Vec<(u64, Paid)> = self
                    .paid
                    .iter()
                    .filter(|(_, (_, at))| now.saturating_sub(*at) <= window)
                    .map(|(&(from, to, task), &(amount, at))| {
                        (at, Paid { from, to, task, amount })
                    })
                    .collect();
                recent.sort_by_key(|(at, p)| (std::cmp::Reverse(*at), p.from, p.to, p.task));
                recent.truncate(self.paid_cap);
                recent.into_iter().map(|(_, p)| p).collect()
            },
        };
        if full {
            self.counters.full_sent += 1;
        } else {
            self.counters.beacons_sent += 1;
        }
        Some(msg)
    }

    /// Where target j is believed to be.
    fn target_pos(&self, j: TaskId) -> Option<[f64; 2]> {
        self.sightings
            .get(&(j as u32))
            .map(|s| s.pos)
            .or_else(|| self.kernel.book().get(&j).map(|t| t.position))
    }

    /// (7) Motion and the hunt of the first target of the path.
    fn act(&mut self, s: &Sense, now: u64, captured: &BTreeSet<TaskId>) -> [f64; 2] {
        self.closing = self.hold.is_some();
        if self.phase != Phase::Executing {
            return self.mover.stop();
        }
        if let Some((j, until)) = self.hold {
            if now >= until {
                self.finish(j, now);
            } else {
                let goal = self.capture_goal(j, s.pos).unwrap_or(s.pos);
                return self.mover.go(s, goal);
            }
        }
        let Some(&j) = self.kernel.plan().path.first() else {
            self.closing_since = None;
            return self.seek(s);
        };
        let Some(target) = self.target_pos(j) else {
            return self.mover.stop();
        };
        if captured.contains(&j) {
            let ticks = (self.tasks[j].hold_time * self.p.ticks_per_time_unit).ceil() as u64;
            self.hold = Some((j, now + ticks));
            self.closing = true;
            self.events.push(Event::Captured { tick: now, task: j });
            return self.mover.go(s, self.capture_goal(j, s.pos).unwrap_or(s.pos));
        }
        if self.arrived.is_some_and(|a| a != j) {
            self.arrived = None;
        }
        let d = dist(s.pos, target);
        let members: Vec<u32> = self
            .kernel
            .winners()
            .winners_of(j)
            .into_iter()
            .map(|(m, _)| m as u32)
            .collect();
        // A member counts as assembled only while j is the first target of its path as this
        // robot knows it: the `ready` gossip is never withdrawn, so a member that reached j's
        // ring and then put another target first (a task learnt at a merge, a switch) would
        // otherwise still count, the others would close on j without it, and
        // `presume_lost` would then take it for dead (the trace of docs/hunting.md 14.4).
        let assembled = members
            .iter()
            .all(|&m| self.ready.contains(&(j as u32, m)) && self.heads_for(m, j));
        let since = match self.waiting {
            Some((w, t)) if w == j => t,
            _ => {
                self.waiting = Some((j, now));
                now
            }
        };
        if d > self.p.wait_radius_km + self.p.arrive_tolerance_km
            && self.arrived != Some(j)
        {
            // Towards the waiting ring.
            let k = (d - self.p.wait_radius_km) / d;
            let goal = [s.pos[0] + (target[0] - s.pos[0]) * k, s.pos[1] + (target[1] - s.pos[1]) * k];
            self.waiting = Some((j, now));
            return self.mover.go(s, goal);
        }
        self.ready.insert((j as u32, self.id));
        self.arrived = Some(j);
        // A coalition short of L_j (a member died and was forgotten) waits for a replacement.
        let full = members.len() >= self.tasks[j].robots_needed;
        if full && (assembled || now.saturating_sub(since) >= self.p.max_wait_ticks) {
            self.closing = true;
            // The presumed-loss clock runs only near the target (`presume_within_km`), where
            // every live member closing on it is in radio range.
            let started = match self.closing_since {
                Some((c, t)) if c == j => Some(t),
                _ if d <= self.p.presume_within_km => {
                    self.closing_since = Some((j, now));
                    Some(now)
                }
                _ => None,
            };
            if started.is_some_and(|t| now.saturating_sub(t) >= self.p.presume_lost_ticks) {
                self.presume_lost(j, &members, now);
            }
            let goal = self.capture_goal(j, s.pos).unwrap_or(target);
            self.mover.go(s, goal)
        } else {
            self.closing_since = None;
            self.mover.stop()
        }
    }

    /// Members of j not heard directly for `presume_lost_ticks` while this robot has closed on
    /// j that long are dead (BehaviourParams::presume_lost_ticks).
    fn presume_lost(&mut self, j: TaskId, members: &[u32], now: u64) {
        let window = self.p.presume_lost_ticks;
        let silent: Vec<u32> = members
            .iter()
            .copied()
            .filter(|&m| m != self.id && self.heads_for(m, j))
            .filter(|m| {
                // Heard directly, or a later send tick relayed in a death record's alive stamp
                // (a member revived by another member's hearing is not presumed lost again).
                let last = self.heard.get(m).map(|h| h.tick).max(self.live.alive_at(*m));
                last.is_none_or(|t| now.saturating_sub(t) >= window)
            })
            .collect();
        for m in silent {
            self.events.push(Event::PresumedLost { tick: now, robot: m, task: j });
            self.forget(m, now);
        }
    }

    /// Whether robot m's path, as this robot knows it, starts with target j (m is on its way
    /// to j, or there). A member busy with an earlier target is neither assembled at j nor
    /// missing from it.
    fn heads_for(&self, m: u32, j: TaskId) -> bool {
        m == self.id || self.kernel.known_path(m as usize).first() == Some(&j)
    }

    /// An idle robot goes to `seek_radius_km` of the nearest unfinished target it knows of
    /// (BehaviourParams::seek_when_idle), or stands still.
    fn seek(&mut self, s: &Sense) -> [f64; 2] {
        if !self.p.seek_when_idle {
            return self.mover.stop();
        }
        let nearest = self
            .kernel
            .book()
            .keys()
            .filter_map(|&j| self.target_pos(j))
            .min_by(|a, b| dist(s.pos, *a).total_cmp(&dist(s.pos, *b)));
        let Some(target) = nearest else {
            return self.mover.stop();
        };
        let d = dist(s.pos, target);
        if d <= self.p.seek_radius_km + self.p.arrive_tolerance_km {
            return self.mover.stop();
        }
        let k = (d - self.p.seek_radius_km) / d;
        let goal = [s.pos[0] + (target[0] - s.pos[0]) * k, s.pos[1] + (target[1] - s.pos[1]) * k];
        self.mover.go(s, goal)
    }

    /// The robot's place on the capture ring of target j: members in id order, evenly around.
    fn capture_goal(&self, j: TaskId, _me: [f64; 2]) -> Option<[f64; 2]> {
        let target = self.target_pos(j)?;
        let members: Vec<usize> = self
            .kernel
            .winners()
            .winners_of(j)
            .into_iter()
            .map(|(m, _)| m)
            .collect();
        let rank = members.iter().position(|&m| m == self.id as usize).unwrap_or(0);
        let n = members.len().max(1);
        Some(ring_point(target, self.p.ring_radius_km, rank, n))
    }

    /// The hold after the capture of j is over: j is done, its score is earned.
    fn finish(&mut self, j: TaskId, now: u64) {
        self.hold = None;
        let t = &self.tasks[j];
        // t_(p_i) - t_o of (4.12): t_o is the tick the robot committed to its plan.
        let elapsed = now.saturating_sub(self.commit_tick) as f64 / self.p.ticks_per_time_unit;
        let prm = self.kernel.params();
        let earned = prm.w1 * t.value * (-t.beta * elapsed).exp() - prm.w2 * self.kernel.robot().gamma * self.leg;
        self.utility += earned;
        self.leg = 0.0;
        self.kernel.complete(j);
        self.ready.retain(|&(t, _)| t as usize != j);
        self.waiting = None;
        self.dirty = true;
        self.events.push(Event::Finished {
            tick: now,
            task: j,
            utility: self.utility,
        });
    }

    pub fn step_msgs(&mut self, s: &Sense, inbox: &[&Received<CbcaRadio>], out: &mut Outbox<CbcaRadio>) -> Command {
        let now = s.tick;
        let events_before = self.events.len();
        if let Some(p) = self.last_pos {
            self.leg += dist(p, s.pos);
        }
        self.last_pos = Some(s.pos);
        self.detect_deaths(s, now);
        let captured = self.sense_targets(s, now);
        for r in inbox {
            self.take(r, now);
        }
        if self.phase == Phase::Executing && self.hold.is_none() {
            // New bids start where the robot is now.
            self.kernel.set_position(Vec2::new(s.pos[0], s.pos[1]));
        }
        self.kernel.iterate(now as f64);
        let settled = self.settled(now);
        if settled && !self.was_settled {
            self.counters.first_settled.get_or_insert(now);
            match self.phase {
                Phase::Planning => {
                    self.phase = Phase::Executing;
                    self.commit_tick = now;
                    self.events.push(Event::Committed {
                        tick: now,
                        path: self.kernel.plan().path.clone(),
                    });
                }
                // Every new settlement while executing: something changed (a merge, a
                // death, a target learnt or finished), so the path is reviewed.
                Phase::Executing if self.hold.is_none() => self.review(now),
                Phase::Executing => {}
            }
            self.kernel.pin(self.p.commit_bonus);
            self.dirty = false;
        }
        self.was_settled = settled;
        if let Some(m) = self.message(now, settled) {
            out.broadcast(m);
        }
        let cmd = self.act(s, now, &captured);
        self.trace(now, s.pos, events_before);
        // The hunt mission's report contract (swarm::sections::hunt): [T_j hunted, the point
        // it heads for (x, y; NaN before the ring), REPORT_AT_POINT when there]; the display
        // state is the task.
        let task = match self.phase {
            Phase::Executing => self.hold.map(|(j, _)| j).or(self.kernel.plan().path.first().copied()),
            Phase::Planning => None,
        };
        let point = task.filter(|_| self.closing).and_then(|j| self.capture_goal(j, s.pos));
        let at = point.is_some_and(|q| dist(q, s.pos) <= self.p.arrive_tolerance_km);
        Command {
            cmd,
            events: task.map_or(0, |j| (j as u32 + 1).min(254)),
            report: [
                task.map_or(0.0, |j| j as f64 + 1.0),
                point.map_or(f64::NAN, |q| q[0]),
                point.map_or(f64::NAN, |q| q[1]),
                if at { swarm::sections::hunt::REPORT_AT_POINT } else { 0.0 },
            ],
        }
    }
}

impl Cbca {
    /// Debug trace (`CBCA_TRACE=<thesis target id>` in the agent's environment, every
    /// `CBCA_TRACE_EVERY` ticks, default 10): what this robot believes about that target's
    /// coalition, the members' resources it has heard, and why it does not bid.
    fn trace(&self, now: u64, pos: [f64; 2], events_before: usize) {
        thread_local! {
            static TRACE: Option<(usize, u64)> = std::env::var("CBCA_TRACE").ok().and_then(|v| {
                let every = std::env::var("CBCA_TRACE_EVERY").ok().and_then(|e| e.parse().ok()).unwrap_or(10);
                v.parse::<usize>().ok().and_then(|t| t.checked_sub(1)).map(|t| (t, every))
            });
        }
        let Some((j, every)) = TRACE.with(|t| *t) else { return };
        for e in &self.events[events_before..] {
            eprintln!("event t={now} R{}: {e:?}", self.id + 1);
        }
        if !now.is_multiple_of(every) {
            return;
        }
        let k = &self.kernel;
        let members: Vec<String> = k
            .winners()
            .winners_of(j)
            .into_iter()
            .map(|(m, b)| {
                let r = k.known_resources(m).map_or("?".to_string(), |r| format!("{r:?}"));
                format!("R{}({b:.1},{r})", m + 1)
            })
            .collect();
        let why = if k.book().contains_key(&j) {
            let c = crate::cbca::bundle::evaluate(k.robot(), k.plan(), j, k.winners(), k.book(), &k.peers(), k.params());
            format!("{c:?}")
        } else {
            "unknown".into()
        };
        eprintln!(
            "trace t={now} R{} pos=({:.2},{:.2}) {:?} settled={} path={:?} gone={:?} T{}: [{}] why={why}",
            self.id + 1,
            pos[0],
            pos[1],
            self.phase,
            self.was_settled,
            k.plan().path.iter().map(|t| t + 1).collect::<Vec<_>>(),
            self.live.gone().map(|g| g + 1).collect::<Vec<_>>(),
            j + 1,
            members.join(" "),
        );
    }
}

impl swarm::Behaviour for Cbca {
    type Msg = CbcaRadio;
    fn step_refs(&mut self, s: &Sense, inbox: &[&Received<CbcaRadio>], out: &mut Outbox<CbcaRadio>) -> Command {
        self.step_msgs(s, inbox, out)
    }
}

/// The targets robot `me` knows at the start (sec. 4.2.2's prior information).
pub fn initial_knowledge(
    me: usize,
    robots: &[crate::cbca::Robot],
    tasks: &[Task],
    sec: &Section,
) -> BTreeSet<TaskId> {
    use super::params::Prior;
    let r = sec.kernels.params.detection_radius_km;
    let sees = |i: usize, t: &Task| (robots[i].position - t.pos()).norm() <= r;
    let mut known = BTreeSet::new();
    for t in tasks {
        let mine = match sec.behaviour.prior {
            Prior::All => true,
            Prior::Detection => sees(me, t),
            Prior::DetectionPlusNearest => {
                sees(me, t)
                    || (!(0..robots.len()).any(|i| sees(i, t))
                        && (0..robots.len())
                            .min_by(|&a, &b| {
                                (robots[a].position - t.pos())
                                    .norm()
                                    .total_cmp(&(robots[b].position - t.pos()).norm())
                                    .then(a.cmp(&b))
                            })
                            == Some(me))
            }
        };
        if mine {
            known.insert(t.id);
        }
    }
    known
}
