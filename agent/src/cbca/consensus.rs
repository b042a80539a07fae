//! Algorithm 2 of thesis sec. 4.2.3 (spec 4.6): consensus with the neighbours on (Z, Y, s), as
//! a pure per-robot state machine ([`CbcaRobot`]) whose messages ([`CbcaMessage`]) are serde
//! types for a lossy, delayed radio, and a convergence detector ([`ConvergenceDetector`]).
//!
//! One iteration of robot i: [`CbcaRobot::iterate`] (the deadlock repair of dag.rs, then
//! Algorithm 1), [`CbcaRobot::message`] to every neighbour, and [`CbcaRobot::receive`] for each
//! message that arrives. Per task j and robot m != i, with k the sender and s_km its stamp on m
//! (s_kk = the message's send time):
//! - (A) update / reset: i believes m wins j and k's news of m is newer (s_km > s_im): take k's
//!   entry, a new bid (update) or no winner (reset). The thesis prints this for m = k only; the
//!   reset for m != k is the missing case spec 4.6 lists.
//! - (B) learn: k believes m wins j, i does not, and k's news of m is newer: if i's coalition of
//!   j has room (N_j^sum < L_j) m joins it; if full, m replaces the weakest winner n* when m's bid
//!   beats n*'s (ties: the smaller id) and E_m ∩ E_n* != ∅; if n* = i, i loses j and every task
//!   it added to b_i after j (CBBA's release), and Algorithm 1 runs again next iteration.
//! - leave: otherwise nothing changes. Robot i alone writes its own entries (m = i).
//! - (2.6), with `params.enforce_coverage`: at the next bundle pass, a robot that is the weakest
//!   member of a full coalition whose carried resources do not cover E_j releases j (and what
//!   it added after j), as a displaced robot does ([`CbcaRobot::uncovered_weakest`]).
//!
//! Then s_ik <- max(s_ik, send time) and s_im <- max(s_im, s_km) for m != i, k (the stamp
//! propagation spec 4.6 adds). The thesis sets s_ik to the receive time; with delays a late
//! message would then claim to be fresher than it is, so the send time is used. Each robot's
//! resources and path (for rule B's substitution test and the DAG test) travel with the same
//! stamps; so do the task adverts a group shares (sec. 4.2.2).

use serde::{Deserialize, Serialize};

use super::bundle::{build_bundle, Added, Peers, Plan};
use super::dag;
use super::model::{overlaps, Resources, Robot, RobotId, Task, TaskBook, TaskId};
use super::params::CbcaParams;
use super::winners::{outbids, WinnerEntry, Winners};

/// What a robot tells about itself, relayed with its stamp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobotInfo {
    /// E_i' (static).
    pub resources: Resources,
    /// p_i, for the deadlock test (4.6) of the others.
    pub path: Vec<TaskId>,
}

/// One consensus message from robot k to a neighbour: (Z^k, Y^k, s_k) of Algorithm 2 plus what
/// the thesis's groups share (robot facts, known targets) and the state digest the detector
/// compares.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CbcaMessage {
    pub sender: RobotId,
    /// The sender's clock when it sent this (its stamp on itself).
    pub sent_at: f64,
    /// The non-empty entries of Z^k / Y^k.
    pub winners: Vec<WinnerEntry>,
    /// s_k: the sender's stamps on every robot (-inf: never heard).
    pub stamps: Vec<f64>,
    /// What the sender knows of each robot.
    pub infos: Vec<Option<RobotInfo>>,
    /// The targets the sender knows.
    pub tasks: Vec<Task>,
    /// [`CbcaRobot::digest`] of the sender when it sent this.
    pub digest: u64,
}

/// What one received message changed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Received {
    /// Entries of Z/Y that changed.
    pub changed_entries: usize,
    /// Tasks robot i lost (displaced on them, or released after one it lost), in bundle order.
    pub released: Vec<TaskId>,
    /// Targets learnt from the sender.
    pub new_tasks: Vec<TaskId>,
}

/// The convergence detector: a robot declares convergence once its own state digest has not
/// changed for `quiet` of its iterations and the latest message of every current neighbour
/// carried the same digest and arrived after the robot's last change. If every robot of a
/// connected group declares it at once, every edge joins two equal states, so the whole group
/// agrees (up to a 64-bit digest collision): the stopping rule is detected, not a round count.
/// A robot keeps listening afterwards; a later change clears its verdict.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvergenceDetector {
    digest: u64,
    changed_at: u64,
    heard: std::collections::BTreeMap<RobotId, (u64, u64)>,
}

impl ConvergenceDetector {
    /// Records the robot's own digest at its iteration `now`.
    pub fn note_state(&mut self, now: u64, digest: u64) {
        if digest != self.digest {
            self.digest = digest;
            self.changed_at = now;
        }
    }

    /// Records a neighbour's digest, heard at the robot's iteration `now`.
    pub fn note_heard(&mut self, from: RobotId, digest: u64, now: u64) {
        self.heard.insert(from, (digest, now));
    }

    /// The verdict at iteration `now` for the current neighbour set.
    pub fn converged(&self, now: u64, quiet: u64, neighbours: &[RobotId]) -> bool {
        now.saturating_sub(self.changed_at) >= quiet
            && neighbours.iter().all(|n| {
                self.heard
                    .get(n)
                    .is_some_and(|&(d, at)| d == self.digest && at >= self.changed_at)
            })
    }
}

/// FNV-1a, 64 bit: a stable digest (the same in every process and build).
#[derive(Clone, Copy)]
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn u64(&mut self, v: u64) {
        for b in v.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Robot i's CBCA state: its plan (b_i, p_i), Z^i / Y^i, s_i, what it knows of the others and
/// of the targets, and its convergence detector.
#[derive(Clone, Debug)]
pub struct CbcaRobot {
    me: Robot,
    params: CbcaParams,
    plan: Plan,
    winners: Winners,
    stamps: Vec<f64>,
    infos: Vec<Option<RobotInfo>>,
    book: TaskBook,
    detector: ConvergenceDetector,
    iteration: u64,
    /// Targets the group has finished (captured and held): never bid on again.
    done: std::collections::BTreeSet<TaskId>,
}

/// The Peers view of a robot's infos.
struct InfoPeers<'a>(&'a [Option<RobotInfo>]);

impl Peers for InfoPeers<'_> {
    fn resources(&self, m: RobotId) -> Option<Resources> {
        self.0.get(m).and_then(|i| i.as_ref()).map(|i| i.resources)
    }
    fn path(&self, m: RobotId) -> &[TaskId] {
        self.0
            .get(m)
            .and_then(|i| i.as_ref())
            .map(|i| i.path.as_slice())
            .unwrap_or(&[])
    }
    fn count(&self) -> usize {
        self.0.len()
    }
}

/// What the DAG tests (4.6) of robot i see: each other robot's known path restricted to the
/// tasks i believes it wins. A path is relayed with its robot's stamp, but robot i changes Z
/// itself when it outbids m (rule B, or Algorithm 1 displacing m): m's relayed path then
/// still lists the task i took from it. Testing that stale path made two robots take and drop
/// the same task in turn forever (proptest seed 6322006625875567134: R3 outbid R1 on T1, saw
/// R1's old path [T1, T2] against its own [T2, T1], dropped T1, R1 took it back, ...).
struct BelievedPeers<'a> {
    infos: &'a [Option<RobotInfo>],
    paths: Vec<Vec<TaskId>>,
}

impl<'a> BelievedPeers<'a> {
    /// `doomed`: (robot, task) pairs the robot is about to release by the (2.6) rule
    /// ([`CbcaRobot::doomed`]), left out of its believed path. Without this a robot's DAG
    /// repair reacted to a task its peer was releasing at the same time, and both gave way in
    /// turn forever (fixed sweep seed 14405549394120499418: R1 released T3 by (2.6) while R2
    /// dropped T3 and T1 to break the cycle R1's stale path made, then both took them again).
    fn new(
        me: RobotId,
        infos: &'a [Option<RobotInfo>],
        winners: &Winners,
        doomed: &std::collections::BTreeSet<(RobotId, TaskId)>,
    ) -> Self {
        let paths = (0..infos.len())
            .map(|m| {
                let view = InfoPeers(infos);
                let known = view.path(m);
                if m == me {
                    known.to_vec()
                } else {
                    known
                        .iter()
                        .copied()
                        .filter(|&j| winners.is_winner(m, j) && !doomed.contains(&(m, j)))
                        .collect()
                }
            })
            .collect();
        Self { infos, paths }
    }
}

impl Peers for BelievedPeers<'_> {
    fn resources(&self, m: RobotId) -> Option<Resources> {
        InfoPeers(self.infos).resources(m)
    }
    fn path(&self, m: RobotId) -> &[TaskId] {
        self.paths.get(m).map(|p| p.as_slice()).unwrap_or(&[])
    }
    fn count(&self) -> usize {
        self.infos.len()
    }
}

impl CbcaRobot {
    /// Robot `me` among `n_robots` robots and `n_tasks` targets (the sizes of Z), knowing the
    /// targets in `known` at the start.
    pub fn new(
        me: Robot,
        n_robots: usize,
        n_tasks: usize,
        known: TaskBook,
        params: CbcaParams,
    ) -> Self {
        let mut infos = vec![None; n_robots];
        infos[me.id] = Some(RobotInfo {
            resources: me.resources,
            path: Vec::new(),
        });
        Self {
            winners: Winners::new(n_robots, n_tasks),
            stamps: vec![f64::NEG_INFINITY; n_robots],
            infos,
            book: known,
            plan: Plan::default(),
            detector: ConvergenceDetector::default(),
            iteration: 0,
            done: Default::default(),
            me,
            params,
        }
    }

    pub fn id(&self) -> RobotId {
        self.me.id
    }
    pub fn robot(&self) -> &Robot {
        &self.me
    }
    pub fn plan(&self) -> &Plan {
        &self.plan
    }
    pub fn winners(&self) -> &Winners {
        &self.winners
    }
    pub fn book(&self) -> &TaskBook {
        &self.book
    }
    pub fn stamps(&self) -> &[f64] {
        &self.stamps
    }
    pub fn iteration(&self) -> u64 {
        self.iteration
    }
    /// Robot m's path as robot i knows it.
    pub fn known_path(&self, m: RobotId) -> &[TaskId] {
        self.infos
            .get(m)
            .and_then(|i| i.as_ref())
            .map(|i| i.path.as_slice())
            .unwrap_or(&[])
    }
    /// The whole peer view (for the "why" reports of a driver).
    pub fn peers(&self) -> impl Peers + '_ {
        BelievedPeers::new(self.me.id, &self.infos, &self.winners, &self.doomed())
    }
    pub fn params(&self) -> &CbcaParams {
        &self.params
    }

    /// A target robot i detects itself (sec. 4.2.2).
    pub fn learn_task(&mut self, task: Task) -> bool {
        if self.book.contains_key(&task.id)
            || task.id >= self.winners.n_tasks()
            || self.done.contains(&task.id)
        {
            return false;
        }
        self.book.insert(task.id, task);
        true
    }

    /// Digest of the consensus content: Z/Y, the known paths, the known targets.
    pub fn digest(&self) -> u64 {
        let mut h = Fnv::new();
        for e in self.winners.entries() {
            h.u64(e.robot as u64);
            h.u64(e.task as u64);
            h.u64(e.bid.to_bits());
        }
        h.u64(u64::MAX);
        for (m, info) in self.infos.iter().enumerate() {
            if let Some(info) = info {
                h.u64(m as u64);
                for &j in &info.path {
                    h.u64(j as u64);
                }
                h.u64(u64::MAX - 1);
            }
        }
        for &j in self.book.keys() {
            h.u64(j as u64);
        }
        h.0
    }

    /// Drops b_i from position `from` on (CBCA's release), clearing i's entries.
    fn release_from(&mut self, from: usize) -> Vec<TaskId> {
        let dropped: Vec<TaskId> = self.plan.bundle.drain(from..).collect();
        for &j in &dropped {
            self.winners.clear(self.me.id, j);
            self.plan.path.retain(|&p| p != j);
            self.plan.committed.remove(&j);
        }
        dropped
    }

    fn sync_own_info(&mut self) {
        let id = self.me.id;
        self.infos[id] = Some(RobotInfo {
            resources: self.me.resources,
            path: self.plan.path.clone(),
        });
    }

    /// One iteration's Phase 1 at clock `now`: the deadlock repair (dag.rs: if the known paths
    /// form a cycle that this robot closes, it drops tasks from the end of its bundle until it
    /// no longer does), then Algorithm 1. Returns what Algorithm 1 added and what the repair
    /// dropped.
    pub fn iterate(&mut self, now: f64) -> (Vec<Added>, Vec<TaskId>) {
        self.iteration += 1;
        let mut dropped = Vec::new();
        loop {
            let mut paths =
                BelievedPeers::new(self.me.id, &self.infos, &self.winners, &self.doomed()).paths;
            paths[self.me.id] = self.plan.path.clone();
            if dag::cycle_closer(&paths) != Some(self.me.id) || self.plan.bundle.is_empty() {
                break;
            }
            let last = self.plan.bundle.len() - 1;
            dropped.extend(self.release_from(last));
        }
        dropped.extend(self.release_uncovered());
        let added = {
            let peers = BelievedPeers::new(self.me.id, &self.infos, &self.winners, &self.doomed());
            build_bundle(
                &self.me,
                &mut self.plan,
                &mut self.winners,
                &self.book,
                &peers,
                &self.params,
            )
        };
        self.sync_own_info();
        self.stamps[self.me.id] = now;
        let digest = self.digest();
        self.detector.note_state(self.iteration, digest);
        (added, dropped)
    }

    /// (2.6) after consensus: the tasks of b_i whose agreed coalition is full (N_j^sum = L_j)
    /// but whose members' carried resources E' do not cover E_j, and where robot i is the
    /// weakest member (4.16's min_k y_kj; ties: the larger id). Only when every member's
    /// resources are known (robot i judges only coalitions it can vouch for).
    pub fn uncovered_weakest(&self) -> Vec<TaskId> {
        let doomed = self.doomed();
        self.plan
            .bundle
            .iter()
            .copied()
            .filter(|&j| doomed.contains(&(self.me.id, j)))
            .collect()
    }

    /// Every (weakest member, task) of a full coalition robot i believes in whose members'
    /// carried resources (all known to i) do not cover E_j: who gives way by the (2.6) rule.
    pub fn doomed(&self) -> std::collections::BTreeSet<(RobotId, TaskId)> {
        let mut out = std::collections::BTreeSet::new();
        if !self.params.enforce_coverage {
            return out;
        }
        for (&j, task) in &self.book {
            let members = self.winners.winners_of(j);
            if members.len() < task.robots_needed {
                continue;
            }
            let res: Option<Vec<Resources>> =
                members.iter().map(|&(m, _)| self.resources_of(m)).collect();
            let Some(res) = res else { continue };
            let refs: Vec<&Resources> = res.iter().collect();
            if !super::model::covers(&refs, task) {
                if let Some((weak, _)) = self.winners.weakest(j) {
                    out.insert((weak, j));
                }
            }
        }
        out
    }

    /// The (2.6) rule of Algorithm 2 (our reading of sec. 4.2.3 and Fig. 4.4(d), spec 4.6):
    /// consensus compares bids only, so two robots that each complete a coalition with
    /// different partners, or rule (B) adding a relayed winner to a coalition with room, can
    /// leave a full coalition that does not cover E_j. Such a coalition cannot hunt (the thesis
    /// shelves T1 when "no coalition satisfies T1's resources"). Its weakest member gives way,
    /// as the loser of a full coalition does in the textual rule ("it loses winner status,
    /// resets this task's position in its bundle, and goes back to Phase 1"): it releases j and
    /// every task added after it; the place reopens for a robot whose resources complete the
    /// cover (Algorithm 1's completing bid is checked by `enforce_coverage`, so the same robot
    /// cannot take it back). Run at the start of each bundle pass. Returns the released tasks.
    fn release_uncovered(&mut self) -> Vec<TaskId> {
        let mut out = Vec::new();
        while let Some(&j) = self.uncovered_weakest().first() {
            let at = self
                .plan
                .bundle
                .iter()
                .position(|&t| t == j)
                .expect("in the bundle");
            out.extend(self.release_from(at));
        }
        if !out.is_empty() {
            self.sync_own_info();
        }
        out
    }

    /// The message to the neighbours at clock `now`.
    pub fn message(&self, now: f64) -> CbcaMessage {
        let mut stamps = self.stamps.clone();
        stamps[self.me.id] = now;
        CbcaMessage {
            sender: self.me.id,
            sent_at: now,
            winners: self.winners.entries(),
            stamps,
            infos: self.infos.clone(),
            tasks: self.book.values().cloned().collect(),
            digest: self.digest(),
        }
    }

    /// Algorithm 2 on one message (see the module doc for the rules).
    pub fn receive(&mut self, msg: &CbcaMessage) -> Received {
        let me = self.me.id;
        let k = msg.sender;
        let n_r = self.winners.n_robots();
        let n_e = self.winners.n_tasks();
        let mut out = Received::default();
        if k == me || k >= n_r || msg.stamps.len() != n_r {
            return out;
        }
        self.detector.note_heard(k, msg.digest, self.iteration);
        for t in &msg.tasks {
            if self.learn_task(t.clone()) {
                out.new_tasks.push(t.id);
            }
        }
        let mut sk = msg.stamps.clone();
        sk[k] = msg.sent_at;
        let newer = |m: RobotId, s: &[f64]| sk[m] > s[m];
        let theirs = Winners::from_entries(n_r, n_e, &msg.winners);
        // Robot facts travel with the same stamps (first, so rule B can use them).
        for m in 0..n_r {
            if m != me && newer(m, &self.stamps) {
                if let Some(Some(info)) = msg.infos.get(m) {
                    self.infos[m] = Some(info.clone());
                }
            }
        }
        let mut lost: Vec<TaskId> = Vec::new();
        for j in 0..n_e {
            let needed = self.book.get(&j).map(|t| t.robots_needed);
            // (A) update / reset what i believes of winners m != i.
            for (m, _) in self.winners.winners_of(j) {
                if m != me && newer(m, &self.stamps) {
                    let now = theirs.get(m, j);
                    if now != self.winners.get(m, j) {
                        self.winners.put(m, j, now);
                        out.changed_entries += 1;
                    }
                }
            }
            // (B) learn the winners k knows and i does not.
            for (m, bid) in theirs.winners_of(j) {
                if m == me || self.winners.is_winner(m, j) || !newer(m, &self.stamps) {
                    continue;
                }
                let Some(needed) = needed else { continue };
                if self.winners.count(j) < needed {
                    self.winners.set(m, j, bid);
                    out.changed_entries += 1;
                    continue;
                }
                let (weak, weak_bid) = self.winners.weakest(j).expect("full coalition");
                let substitutes = !self.params.substitution_check
                    || match (InfoPeers(&self.infos).resources(m), self.resources_of(weak)) {
                        (Some(a), Some(b)) => overlaps(&a, &b),
                        _ => true,
                    };
                if outbids((bid, m), (weak_bid, weak)) && substitutes {
                    self.winners.clear(weak, j);
                    self.winners.set(m, j, bid);
                    out.changed_entries += 2;
                    if weak == me {
                        lost.push(j);
                    }
                }
            }
        }
        for (m, (s, theirs)) in self.stamps.iter_mut().zip(&sk).enumerate() {
            if m != me {
                *s = s.max(*theirs);
            }
        }
        // Release the first lost task of the bundle and everything added after it.
        if let Some(first) = self.plan.bundle.iter().position(|j| lost.contains(j)) {
            out.released = self.release_from(first);
            self.sync_own_info();
        }
        out
    }

    /// E_m' as robot i knows it (its own, or what it heard).
    pub fn known_resources(&self, m: RobotId) -> Option<Resources> {
        self.resources_of(m)
    }

    fn resources_of(&self, m: RobotId) -> Option<Resources> {
        if m == self.me.id {
            Some(self.me.resources)
        } else {
            InfoPeers(&self.infos).resources(m)
        }
    }

    /// The robot's position from now on (t_o of the bids Algorithm 1 places next): the runtime
    /// moves it at a re-plan, so that new bids start where the robot is.
    pub fn set_position(&mut self, position: swarm::geometry::Vec2) {
        self.me.position = position;
    }

    /// A neighbour's state digest heard without its full state (a beacon).
    pub fn hear_digest(&mut self, from: RobotId, digest: u64) {
        if from != self.me.id {
            self.detector.note_heard(from, digest, self.iteration);
        }
    }

    /// The robot commits to its plan: its bids on the tasks of b_i are raised by `bonus` (once),
    /// so that a robot arriving later may join a coalition with room but cannot push a
    /// committed member out; the member leaves only by its own loyalty decision (4.22) or when
    /// a committed rival with a larger original bid claims the place (a merge of two groups
    /// that both took the task). Returns whether anything changed.
    pub fn pin(&mut self, bonus: f64) -> bool {
        let mut changed = false;
        self.plan.committed = self.plan.bundle.iter().copied().collect();
        for &j in &self.plan.bundle {
            if let Some(b) = self.winners.get(self.me.id, j) {
                if b < bonus {
                    self.winners.set(self.me.id, j, b + bonus);
                    changed = true;
                }
            }
        }
        changed
    }

    /// Starts from a decided plan (moving_rounds.rs, the consistency pass after the loyalty
    /// decisions of a merged group): b_i = p_i = `path`, every task committed (the head of the
    /// path), with robot i's bid on each raised to `bonus` + its `scores` entry (so a decided
    /// plan outranks any fresh bid and, between two decided plans claiming the last place of a
    /// coalition, the larger score keeps it). Replaces the current plan and i's own entries.
    pub fn seed_plan(&mut self, path: &[TaskId], scores: &[f64], bonus: f64) {
        self.release_all();
        for (&j, &s) in path.iter().zip(scores) {
            if !self.book.contains_key(&j) {
                continue;
            }
            self.plan.bundle.push(j);
            self.plan.path.push(j);
            self.plan.committed.insert(j);
            self.winners.set(self.me.id, j, bonus + s);
        }
        self.sync_own_info();
    }

    /// Drops every task of b_i (a switch after the loyalty test).
    pub fn release_all(&mut self) -> Vec<TaskId> {
        let r = self.release_from(0);
        self.sync_own_info();
        r
    }

    /// Target j is finished (captured and held): it leaves the book, Z and every plan, and a
    /// robot that executed it has one place fewer of its l_i (4.2).
    pub fn complete(&mut self, j: TaskId) -> bool {
        if j >= self.winners.n_tasks() || !self.done.insert(j) {
            return false;
        }
        if let Some(pos) = self.plan.bundle.iter().position(|&t| t == j) {
            self.plan.bundle.remove(pos);
            self.plan.path.retain(|&t| t != j);
            self.plan.committed.remove(&j);
            self.me.max_tasks = self.me.max_tasks.saturating_sub(1);
        }
        for m in 0..self.winners.n_robots() {
            self.winners.clear(m, j);
        }
        for info in self.infos.iter_mut().flatten() {
            info.path.retain(|&t| t != j);
        }
        self.book.remove(&j);
        self.sync_own_info();
        true
    }

    /// The finished targets.
    pub fn done(&self) -> &std::collections::BTreeSet<TaskId> {
        &self.done
    }

    /// S_i(p_i) (4.13) of the current path from the current position.
    pub fn path_score(&self) -> f64 {
        super::score::path_score(&self.me, &self.plan.path, &self.book, &self.params).total
    }

    /// The path Algorithm 1 would give this robot if it dropped its own plan now, with the
    /// others' bids as it believes them (p_i' of sec. 4.2.5), and S_i(p_i').
    pub fn proposal(&self) -> (Vec<TaskId>, f64) {
        let mut c = self.clone();
        c.release_all();
        let peers = BelievedPeers::new(c.me.id, &c.infos, &c.winners, &c.doomed());
        build_bundle(
            &c.me,
            &mut c.plan,
            &mut c.winners,
            &c.book,
            &peers,
            &c.params,
        );
        let s = super::score::path_score(&c.me, &c.plan.path, &c.book, &c.params).total;
        (c.plan.path.clone(), s)
    }

    /// Robot m is gone (its agent process died; the runtime's liveness check says so): clear its
    /// winner entries and its facts, and refuse any later news of it (s_im = +inf), so stale
    /// relays cannot bring it back. Its tasks reopen for Algorithm 1 at the next iteration.
    pub fn forget_robot(&mut self, m: RobotId) {
        if m == self.me.id || m >= self.stamps.len() {
            return;
        }
        for j in 0..self.winners.n_tasks() {
            self.winners.clear(m, j);
        }
        self.infos[m] = None;
        self.stamps[m] = f64::INFINITY;
    }

    /// Robot m, forgotten by [`CbcaRobot::forget_robot`], is alive after all (a revoked
    /// presumed loss, a restarted process; behaviours/cbca/liveness.rs): news of it that
    /// originated after `since` (the tick of its death record) is taken again, older relays
    /// stay refused.
    pub fn revive_robot(&mut self, m: RobotId, since: f64) {
        if m != self.me.id && m < self.stamps.len() && self.stamps[m] == f64::INFINITY {
            self.stamps[m] = since;
        }
    }

    /// The detector's verdict for the current neighbour set.
    pub fn converged(&self, neighbours: &[RobotId]) -> bool {
        self.detector
            .converged(self.iteration, self.params.quiet_iterations, neighbours)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cbca::model::tests::{robot, task};

    /// A pair R1 (index 0) and R2 (index 1) among three robots, one task T1 with L = 2 and a
    /// second T2 with L = 1; R3 (index 2) appears only in relayed news.
    fn pair() -> (CbcaRobot, CbcaRobot) {
        let book: TaskBook = [
            (0, task(0, [0.0, 0.0], [1.0; 6], 2)),
            (1, task(1, [1.0, 0.0], [1.0; 6], 1)),
        ]
        .into_iter()
        .collect();
        let p = CbcaParams::default();
        let a = CbcaRobot::new(
            robot(0, [0.0, 1.0], [5.0; 6]),
            3,
            2,
            book.clone(),
            p.clone(),
        );
        let b = CbcaRobot::new(robot(1, [0.0, 2.0], [5.0; 6]), 3, 2, book, p);
        (a, b)
    }

    /// A crafted message from `sender` with these entries and stamps.
    fn msg(
        sender: RobotId,
        sent_at: f64,
        winners: &[(RobotId, TaskId, f64)],
        stamps: [f64; 3],
    ) -> CbcaMessage {
        CbcaMessage {
            sender,
            sent_at,
            winners: winners
                .iter()
                .map(|&(robot, task, bid)| WinnerEntry { robot, task, bid })
                .collect(),
            stamps: stamps.to_vec(),
            infos: vec![None; 3],
            tasks: vec![],
            digest: 0,
        }
    }

    #[test]
    fn rule_a_update_of_the_senders_bid() {
        let (mut a, _) = pair();
        a.winners.set(1, 0, 5.0);
        a.stamps[1] = 1.0;
        // R2 (sender, sent at 2 > s_12 = 1) now bids 7 on T1: update.
        let r = a.receive(&msg(1, 2.0, &[(1, 0, 7.0)], [0.0, 0.0, 0.0]));
        assert_eq!(a.winners.get(1, 0), Some(7.0));
        assert_eq!(r.changed_entries, 1);
        assert_eq!(a.stamps[1], 2.0);
    }

    #[test]
    fn rule_a_reset_when_the_sender_left() {
        let (mut a, _) = pair();
        a.winners.set(1, 0, 5.0);
        a.stamps[1] = 1.0;
        // R2 no longer lists itself on T1: reset.
        a.receive(&msg(1, 2.0, &[], [0.0, 0.0, 0.0]));
        assert!(!a.winners.is_winner(1, 0));
    }

    #[test]
    fn rule_a_reset_of_a_third_robot_on_newer_news() {
        let (mut a, _) = pair();
        a.winners.set(2, 0, 4.0);
        a.stamps[2] = 1.0;
        // R2 heard from R3 at 3 (> s_13 = 1) and no longer counts R3 on T1: reset.
        a.receive(&msg(1, 4.0, &[], [0.0, 0.0, 3.0]));
        assert!(!a.winners.is_winner(2, 0));
        assert_eq!(a.stamps[2], 3.0);
        // Older news (R2's stamp on R3 0.5 < 3) changes nothing: leave.
        a.winners.set(2, 0, 4.0);
        a.receive(&msg(1, 5.0, &[], [0.0, 0.0, 0.5]));
        assert_eq!(a.winners.get(2, 0), Some(4.0));
        assert_eq!(a.stamps[2], 3.0);
    }

    #[test]
    fn rule_b_learns_a_winner_while_there_is_room() {
        let (mut a, _) = pair();
        // T1 (L = 2) holds R1 itself; R2 reports R3 on T1 with newer news: room, R3 joins.
        a.plan = Plan {
            committed: Default::default(),
            bundle: vec![0],
            path: vec![0],
        };
        a.winners.set(0, 0, 9.0);
        a.receive(&msg(1, 1.0, &[(2, 0, 3.0)], [0.0, 0.0, 0.5]));
        assert_eq!(a.winners.winners_of(0), vec![(0, 9.0), (2, 3.0)]);
    }

    #[test]
    fn rule_b_newcomer_outbids_the_weakest() {
        let book: TaskBook = [(0, task(0, [0.0, 0.0], [1.0; 6], 2))]
            .into_iter()
            .collect();
        let p = CbcaParams::default();
        let mut a = CbcaRobot::new(robot(0, [0.0, 1.0], [5.0; 6]), 4, 1, book, p);
        a.winners.set(1, 0, 6.0);
        a.winners.set(2, 0, 4.0);
        a.stamps = vec![0.0, 2.0, 2.0, 2.0];
        let m = |bid: f64, news_of_r4: f64| CbcaMessage {
            sender: 1,
            sent_at: 3.0,
            winners: vec![
                WinnerEntry {
                    robot: 1,
                    task: 0,
                    bid: 6.0,
                },
                WinnerEntry {
                    robot: 3,
                    task: 0,
                    bid,
                },
            ],
            stamps: vec![0.0, 0.0, 0.0, news_of_r4],
            infos: vec![None; 4],
            tasks: vec![],
            digest: 0,
        };
        // R1 believes T1 = {R2 6, R3 4}: full (L = 2). R2 relays R4 on T1 with news of R4
        // newer than R1's (2.5 > 2). R4 bids 3 < the weakest R3's 4: leave.
        a.receive(&m(3.0, 2.5));
        assert_eq!(a.winners.winners_of(0), vec![(1, 6.0), (2, 4.0)]);
        assert_eq!(a.stamps[3], 2.5);
        // Later news (3 > 2.5): R4 now bids 5 > 4, so R4 replaces R3 (update to y = -inf for R3).
        a.receive(&m(5.0, 3.0));
        assert_eq!(a.winners.winners_of(0), vec![(1, 6.0), (3, 5.0)]);
        assert!(a.winners.count(0) <= 2);
        // An equal bid: the smaller id wins; R4 (index 3) against R3 (index 2) at 4 would lose.
        assert!(!outbids((4.0, 3), (4.0, 2)));
    }

    #[test]
    fn rule_b_displaces_the_receiver_and_releases_later_tasks() {
        let (mut a, _) = pair();
        // R1's bundle: T1 (bid 3) then T2 (bid 2). T1 (L = 2) also has R2 (6).
        a.plan = Plan {
            committed: Default::default(),
            bundle: vec![0, 1],
            path: vec![0, 1],
        };
        a.winners.set(0, 0, 3.0);
        a.winners.set(0, 1, 2.0);
        a.winners.set(1, 0, 6.0);
        a.stamps = vec![0.0, 1.0, 1.0];
        // R2 relays R3 on T1 with 4 > R1's 3 (newer news of R3): R1 is the weakest, displaced;
        // it loses T1 and T2 (added after T1).
        let r = a.receive(&msg(1, 2.0, &[(1, 0, 6.0), (2, 0, 4.0)], [0.0, 0.0, 1.5]));
        assert_eq!(r.released, vec![0, 1]);
        assert!(a.plan.bundle.is_empty() && a.plan.path.is_empty());
        assert_eq!(a.winners.winners_of(0), vec![(1, 6.0), (2, 4.0)]);
        assert!(!a.winners.is_winner(0, 1));
        assert_eq!(a.known_path(0), &[] as &[TaskId]);
    }

    #[test]
    fn rule_b_needs_a_substitute_resource() {
        let book: TaskBook = [(0, task(0, [0.0, 0.0], [1.0; 6], 1))]
            .into_iter()
            .collect();
        let mut a = CbcaRobot::new(
            robot(0, [0.0, 1.0], [5.0; 6]),
            3,
            1,
            book,
            CbcaParams::default(),
        );
        a.winners.set(1, 0, 2.0);
        a.infos[1] = Some(RobotInfo {
            resources: [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            path: vec![0],
        });
        a.stamps = vec![0.0, 1.0, 1.0];
        let mut m = msg(1, 2.0, &[(1, 0, 2.0), (2, 0, 9.0)], [0.0, 0.0, 1.5]);
        // R3 outbids R2 (9 > 2) but carries only type 6, R2 only type 1: leave.
        m.infos[2] = Some(RobotInfo {
            resources: [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            path: vec![0],
        });
        a.receive(&m);
        assert_eq!(a.winners.winners_of(0), vec![(1, 2.0)]);
    }

    #[test]
    fn rule_2_6_the_weakest_of_a_full_uncovered_coalition_gives_way() {
        // T1 needs 4 of every type, L = 2. R1 (index 0) carries 1 a type and holds T1 at 5.
        // R2 (index 1) reports itself on T1 at 6: rule B, room, R2 joins. The pair {R1, R2}
        // is full but carries 1 + c < 4 of each type: R1, the weakest (5 < 6), releases T1 at
        // its next bundle pass and cannot bid it back (completing it would not cover either);
        // R2's entry stays. With R2 carrying 3 a type (1 + 3 = 4 covers) R1 keeps T1.
        let book: TaskBook = [(0, task(0, [0.0, 0.0], [4.0; 6], 2))]
            .into_iter()
            .collect();
        for (r2_carries, kept) in [(1.0, false), (3.0, true)] {
            let mut a = CbcaRobot::new(
                robot(0, [0.0, 1.0], [1.0; 6]),
                3,
                1,
                book.clone(),
                CbcaParams::default(),
            );
            a.plan = Plan {
                committed: Default::default(),
                bundle: vec![0],
                path: vec![0],
            };
            a.winners.set(0, 0, 5.0);
            let mut m = msg(1, 2.0, &[(1, 0, 6.0)], [0.0, 0.0, 0.0]);
            m.infos[1] = Some(RobotInfo {
                resources: [r2_carries; 6],
                path: vec![0],
            });
            a.receive(&m);
            assert_eq!(a.winners.winners_of(0), vec![(0, 5.0), (1, 6.0)]);
            assert_eq!(a.uncovered_weakest().is_empty(), kept);
            let (_, dropped) = a.iterate(3.0);
            assert_eq!(a.plan.bundle.contains(&0), kept, "R2 carries {r2_carries}");
            assert_eq!(dropped, if kept { vec![] } else { vec![0] });
            assert!(a.winners.is_winner(1, 0));
        }
        // Off: the uncovered pair stays.
        let mut a = CbcaRobot::new(
            robot(0, [0.0, 1.0], [1.0; 6]),
            3,
            1,
            book,
            CbcaParams {
                enforce_coverage: false,
                ..CbcaParams::default()
            },
        );
        a.plan = Plan {
            committed: Default::default(),
            bundle: vec![0],
            path: vec![0],
        };
        a.winners.set(0, 0, 5.0);
        a.receive(&msg(1, 2.0, &[(1, 0, 6.0)], [0.0, 0.0, 0.0]));
        a.iterate(3.0);
        assert_eq!(a.plan.bundle, vec![0]);
    }

    #[test]
    fn own_entries_are_never_overwritten() {
        let (mut a, _) = pair();
        a.plan = Plan {
            committed: Default::default(),
            bundle: vec![0],
            path: vec![0],
        };
        a.winners.set(0, 0, 3.0);
        // R2 claims R1 bids 8 on T2 and not on T1 with a huge stamp on R1: ignored.
        a.receive(&msg(1, 2.0, &[(0, 1, 8.0)], [100.0, 0.0, 0.0]));
        assert_eq!(a.winners.get(0, 0), Some(3.0));
        assert!(!a.winners.is_winner(0, 1));
        assert_eq!(a.stamps[0], f64::NEG_INFINITY);
    }

    #[test]
    fn a_late_message_is_older_news() {
        let (mut a, _) = pair();
        a.receive(&msg(1, 5.0, &[(1, 0, 7.0)], [0.0, 0.0, 0.0]));
        assert_eq!(a.winners.get(1, 0), Some(7.0));
        // A message R2 sent at 3, delivered after the one sent at 5: its news of R2 is older.
        a.receive(&msg(1, 3.0, &[], [0.0, 0.0, 0.0]));
        assert_eq!(a.winners.get(1, 0), Some(7.0));
        assert_eq!(a.stamps[1], 5.0);
    }

    #[test]
    fn tasks_and_robot_facts_are_shared() {
        let (mut a, mut b) = pair();
        a.book.remove(&1);
        b.iterate(1.0);
        let r = a.receive(&b.message(1.0));
        assert_eq!(r.new_tasks, vec![1]);
        assert_eq!(a.known_path(1), b.plan().path.as_slice());
        assert_eq!(a.infos[1].as_ref().unwrap().resources, [5.0; 6]);
    }

    #[test]
    fn the_detector_needs_quiet_and_agreeing_neighbours() {
        let mut d = ConvergenceDetector::default();
        d.note_state(0, 7);
        d.note_state(1, 9); // a change at iteration 1
        d.note_heard(5, 9, 1);
        assert!(!d.converged(3, 3, &[5])); // quiet only 2 iterations
        assert!(d.converged(4, 3, &[5]));
        assert!(!d.converged(4, 3, &[5, 6])); // never heard from 6
        d.note_heard(6, 8, 4); // 6 disagrees
        assert!(!d.converged(4, 3, &[5, 6]));
        d.note_state(5, 8); // the robot moves to 8: 6's old message predates the change
        d.note_heard(6, 8, 4);
        assert!(!d.converged(8, 3, &[6]));
        d.note_heard(6, 8, 6);
        assert!(d.converged(8, 3, &[6]));
    }
}
