//! Beyond the paper (its authors name large swarms as future work; spec 5 option (b)): a
//! decentralised reassignment by pairwise swaps between neighbours. Robots i and j holding
//! targets a and b swap when that lowers the pair's summed cost (the squared distances of
//! eq. 4) by more than `min_gain`, agreed by a two-message handshake. Each robot runs the same
//! pure state machine ([`SwapAgent::step`]): the tick and messages in, messages out, no I/O.
//!
//! Protocol (ours; measured on 500 robots, docs/formation.md 9, where the first version, which
//! waited for an answer without end, left 72 robots busy for good and one slot doubled):
//! - Only a lower id proposes to a higher id (every pair is still considered, by its lower id),
//!   so proposals form chains of increasing id and never a cycle: the top of a chain is free
//!   and decides on the merits, so a round with proposals under lossless delivery commits a
//!   swap, and the search cannot livelock.
//! - A robot proposes only to a neighbour heard within `SwapParams::range` (well inside the
//!   radio's reach, so that the two keep hearing each other while they move).
//! - The proposer sends `Propose` (its id, target, position, the target it believes the
//!   receiver holds, a sequence number and a deadline `timeout_ticks` ahead) and is then busy:
//!   it rejects proposals and re-sends the same `Propose` every step until it hears the answer
//!   or the deadline comes. It commits (takes the receiver's old target) only on an
//!   acceptance heard before the deadline; at the deadline it gives up, keeps its target and
//!   makes no swap for `settle_ticks` (so that its receiver hears it still holding it).
//! - A free receiver that still holds the believed target, before the deadline, and finds the
//!   gain (from its own position and the proposer's) above `min_gain` takes the proposer's
//!   target at once and answers `Reply { accepted: true }`; otherwise it answers `false`. It
//!   records its answer per proposer and repeats it for a re-sent proposal (a lost reply is
//!   recovered by the proposer's retry, a duplicate never swaps twice).
//! - An acceptance is "granted" until the receiver learns the proposer's side from its status
//!   frames (which carry the target each robot holds): the proposer holding the receiver's
//!   old target confirms it; the proposer still holding its own target in a status sent at or
//!   after the deadline, and before the settle time ran out, means it gave up, and the receiver
//!   takes its old target back. Meanwhile the receiver makes and accepts no other swap. Heard
//!   nothing of the proposer by the end of the settle time: the swap stands.
//!
//! Invariants: every committed swap exchanges exactly two targets and lowers the summed cost
//! by more than `min_gain` (for static positions); whenever no robot is busy (pending or
//! granted), the targets are a permutation, unless a receiver missed every status its
//! proposer sent in the `settle_ticks` after the deadline (loss^settle_ticks when in range).
//! Between the receiver's commit and the proposer's (or the receiver's revert), both aim at
//! the same slot (at most `timeout_ticks` + `settle_ticks` ticks; ORCA keeps them apart).
//! The fixed point is swap-stable (no neighbouring pair within range gains from swapping),
//! which is not always the optimal assignment that the centralised Hungarian finds.
//!
//! The blocked-robot swap (blocked.rs, `SwapParams::blocked`) is the one exception to the
//! gain and id rules: a robot stalled short of an enclosed slot proposes to an in-place
//! neighbour in its way, of any id, at a bounded price (`Propose { blocked: true, .. }`),
//! through the same handshake; both then hold still in the protocol for `hold_ticks`. The
//! summed cost then rises by at most `max_price` per such swap.

use super::blocked::{self, BlockedParams, Watch};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use swarm::geometry::Vec2;

/// The handshake's numbers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SwapParams {
    /// Least gain (squared units) for a swap, against chattering. [chosen] 0.5.
    pub min_gain: f64,
    /// Proposals go only to neighbours at most this far (their last status, extrapolated).
    /// [chosen] 7.5: half the 100- and 500-robot scenarios' comm radius of 15, so that the
    /// pair stays in reach for the handshake's few ticks even when moving apart at 2 V_p.
    pub range: f64,
    /// Ticks the proposer waits for its answer before it gives up. [chosen] 6: with loss 0.3 a
    /// round trip fails with probability 0.51 per try, six tries all fail with 0.018.
    pub timeout_ticks: u64,
    /// Ticks after its deadline in which a proposer that gave up makes no swap and its
    /// receiver decides from its status frames. [chosen] 10: the receiver misses all ten
    /// statuses with probability 0.3^10 = 6e-6 at loss 0.3.
    pub settle_ticks: u64,
    /// The blocked-robot swap (blocked.rs). None: off. Left out of the resolved scenario
    /// when None, so the scenarios without swaps keep their recordings; the behaviour's
    /// `parse_params` fills in the default for `reassignment = "swaps"`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub blocked: Option<BlockedParams>,
}

impl Default for SwapParams {
    fn default() -> Self {
        SwapParams {
            min_gain: 0.5,
            range: 7.5,
            timeout_ticks: 6,
            settle_ticks: 10,
            blocked: None,
        }
    }
}

/// A handshake message (one radio frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// "Swap with me: I hold `from_target` and am at `from_position`; you hold `to_target`;
    /// I wait for your answer until tick `deadline`."
    Propose {
        from: usize,
        to: usize,
        seq: u64,
        from_target: usize,
        to_target: usize,
        from_position: [f64; 2],
        deadline: u64,
        /// A blocked robot's proposal (blocked.rs): judged by price, not gain.
        blocked: bool,
        /// An escaping proposer's cost to its own target (its planned path's length,
        /// squared) in place of the straight distance's square, for the price.
        from_cost: Option<f64>,
    },
    /// The receiver's answer to proposal `seq`.
    Reply {
        from: usize,
        to: usize,
        seq: u64,
        accepted: bool,
    },
}

impl Message {
    /// The addressee.
    pub fn to(&self) -> usize {
        match *self {
            Message::Propose { to, .. } | Message::Reply { to, .. } => to,
        }
    }
}

/// What a robot knows of a neighbour (from its last status frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NeighbourView {
    /// The neighbour's id.
    pub id: usize,
    /// Its position.
    pub position: Vec2,
    /// The target it holds.
    pub target: usize,
    /// The tick its status was sent at.
    pub tick: u64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Pending {
    to: usize,
    seq: u64,
    from_target: usize,
    to_target: usize,
    deadline: u64,
    blocked: bool,
    from_cost: Option<f64>,
}

/// An acceptance whose proposer's side is not known yet.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Granted {
    proposer: usize,
    /// The target this robot gave up (the proposer's, if it committed).
    gave: usize,
    /// The target it took (the proposer's old one).
    took: usize,
    deadline: u64,
    /// A blocked robot's proposal (blocked.rs): the hold starts when the swap stands.
    blocked: bool,
}

/// One robot's side of the swap protocol.
#[derive(Debug, Clone, PartialEq)]
pub struct SwapAgent {
    /// This robot's id.
    pub id: usize,
    /// The target it holds.
    pub target: usize,
    seq: u64,
    pending: Option<Pending>,
    granted: Option<Granted>,
    /// No swap before this tick (a proposer that gave up).
    quiet_until: u64,
    /// The last proposal answered per proposer: (seq, accepted).
    answered: BTreeMap<usize, (u64, bool)>,
    /// Progress towards the target, for the blocked-robot swap.
    watch: Option<Watch>,
    /// Blocked swaps taken part in (either side, a reverted one included), and the partner
    /// of the last one.
    blocked_swaps: u32,
    blocked_partner: Option<usize>,
    /// After its blocked swap stands, the blocked robot makes way for the partner stepping
    /// into its vacated slot: (partner, the slot the partner took, until this tick).
    make_way: Option<(usize, usize, u64)>,
    /// While this robot escapes (escape.rs): its planned path's length to its target,
    /// squared, the cost its blocked swap is priced by.
    path_cost: Option<f64>,
}

/// How much robots i, j at `pi`, `pj` holding `a`, `b` gain by swapping (eq. 4 costs).
pub fn swap_gain(pi: Vec2, pj: Vec2, a: Vec2, b: Vec2) -> f64 {
    (pi - a).norm_squared() + (pj - b).norm_squared()
        - (pi - b).norm_squared()
        - (pj - a).norm_squared()
}

impl SwapAgent {
    /// A robot holding `target`.
    pub fn new(id: usize, target: usize) -> Self {
        Self {
            id,
            target,
            seq: 0,
            pending: None,
            granted: None,
            quiet_until: 0,
            answered: BTreeMap::new(),
            watch: None,
            blocked_swaps: 0,
            blocked_partner: None,
            make_way: None,
            path_cost: None,
        }
    }

    /// Sets (Some, while the robot escapes) or clears its planned path's length to its
    /// target: its blocked swap then asks any in-place neighbour in range, not only those
    /// in the straight corridor, priced with the path's length in place of the straight
    /// distance (the way round wrecks is longer than the line through them).
    pub fn set_path_length(&mut self, length: Option<f64>) {
        self.path_cost = length.map(|l| l * l);
    }

    /// Whether a proposal of this robot awaits its answer.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Whether the robot is in a handshake: its proposal pending, or an acceptance whose
    /// proposer's side it does not know yet.
    pub fn is_busy(&self) -> bool {
        self.pending.is_some() || self.granted.is_some()
    }

    /// A robot killed mid-run (issue 16: "the pattern re-plans for the robots left"), for the
    /// swaps mode, which has no coordinator to re-plan: `wrecks` are the dead robots this one
    /// knows of, each with where it lies and the target it last held (its last status).
    /// Every other target of the pattern stays; the dead robot's target is vacant. If a wreck
    /// lies within `blocked_within` of this robot's own target (the wreck's disc leaves no room
    /// for it there), this robot takes the dead robot's vacant target instead, so the wreck's
    /// neighbourhood loses one slot, not the dead robot's: only when the robot is not in a
    /// handshake, the vacant target is not blocked by a wreck itself, no live neighbour
    /// (`neighbours`) holds it, and no live neighbour of lower id has a target blocked by the
    /// same wreck (that one takes it). Returns whether it took a vacancy. A dead robot's pending
    /// handshake needs nothing more: a proposal to it passes its deadline, an acceptance it
    /// granted stands after the settle time ([`SwapAgent::step`]).
    pub fn take_vacancy(
        &mut self,
        targets: &[Vec2],
        wrecks: &[(Vec2, usize)],
        neighbours: &[NeighbourView],
        blocked_within: f64,
    ) -> bool {
        if self.is_busy() || self.target >= targets.len() {
            return false;
        }
        let blocked = |t: usize| {
            targets
                .get(t)
                .is_some_and(|q| wrecks.iter().any(|(w, _)| (q - w).norm() < blocked_within))
        };
        let Some(&(wreck, vacant)) = wrecks
            .iter()
            .find(|(w, _)| (targets[self.target] - w).norm() < blocked_within)
        else {
            return false;
        };
        let free = vacant < targets.len()
            && vacant != self.target
            && !blocked(vacant)
            && neighbours.iter().all(|n| n.target != vacant);
        let first = neighbours.iter().all(|n| {
            n.id > self.id
                || targets
                    .get(n.target)
                    .is_none_or(|q| (q - wreck).norm() >= blocked_within)
        });
        if free && first {
            self.target = vacant;
        }
        free && first
    }

    /// One step at tick `now`: handle the frames addressed to this robot (in the order given),
    /// settle a granted acceptance from the proposer's status, give up a proposal past its
    /// deadline, then retry the pending proposal or make a new one to the best neighbour of
    /// higher id within range, or, if none and this robot is blocked (blocked.rs), to the
    /// in-place neighbour in its way at the least price.
    pub fn step(
        &mut self,
        now: u64,
        position: Vec2,
        targets: &[Vec2],
        neighbours: &[NeighbourView],
        inbox: &[Message],
        p: &SwapParams,
    ) -> Vec<Message> {
        let mut out = Vec::new();
        let me = self.id;
        for m in inbox.iter().filter(|m| m.to() == me) {
            match *m {
                Message::Reply {
                    from,
                    seq,
                    accepted,
                    ..
                } => {
                    if let Some(pd) = self
                        .pending
                        .filter(|pd| pd.to == from && pd.seq == seq && now < pd.deadline)
                    {
                        if accepted {
                            self.target = pd.to_target;
                            if let Some(b) = p.blocked.as_ref().filter(|_| pd.blocked) {
                                self.blocked_swap_stands(now, pd.to, b);
                                self.make_way = Some((pd.to, pd.from_target, now + b.hold_ticks));
                            }
                        }
                        self.pending = None;
                    }
                }
                Message::Propose {
                    from,
                    seq,
                    from_target,
                    to_target,
                    from_position,
                    deadline,
                    blocked,
                    from_cost,
                    ..
                } => {
                    let accepted = match self.answered.get(&from) {
                        Some(&(s, a)) if s == seq => a,
                        _ => {
                            let theirs = Vec2::new(from_position[0], from_position[1]);
                            let free = !self.is_busy()
                                && now >= self.quiet_until
                                && now < deadline
                                && self.target == to_target
                                && from_target < targets.len();
                            let gain = || {
                                let straight = swap_gain(
                                    theirs,
                                    position,
                                    targets[from_target],
                                    targets[to_target],
                                );
                                // The proposer's own cost by its path, not the line.
                                from_cost.map_or(straight, |c| {
                                    straight - (theirs - targets[from_target]).norm_squared() + c
                                })
                            };
                            let fits = free
                                && if blocked {
                                    p.blocked.as_ref().is_some_and(|b| {
                                        self.blocked_swaps < b.max_swaps
                                            && self.blocked_partner != Some(from)
                                            && blocked::accepts(
                                                position,
                                                targets[to_target],
                                                -gain(),
                                                b,
                                            )
                                    })
                                } else {
                                    gain() > p.min_gain
                                };
                            if fits {
                                self.granted = Some(Granted {
                                    proposer: from,
                                    gave: self.target,
                                    took: from_target,
                                    deadline,
                                    blocked,
                                });
                                self.target = from_target;
                            }
                            self.answered.insert(from, (seq, fits));
                            fits
                        }
                    };
                    out.push(Message::Reply {
                        from: self.id,
                        to: from,
                        seq,
                        accepted,
                    });
                }
            }
        }
        if let Some(g) = self.granted {
            let seen = neighbours.iter().find(|n| n.id == g.proposer);
            let stands = |me: &mut Self| {
                // A blocked swap that stands: the receiver's hold and count (a reverted one
                // leaves neither, so the blocked robot's retry is heard).
                if let Some(b) = p.blocked.as_ref().filter(|_| g.blocked) {
                    me.blocked_swap_stands(now, g.proposer, b);
                }
                me.granted = None;
            };
            if seen.is_some_and(|n| n.target == g.gave) {
                // The proposer committed.
                stands(self);
            } else if seen.is_some_and(|n| {
                n.target == g.took && n.tick >= g.deadline && n.tick < g.deadline + p.settle_ticks
            }) {
                // It still held its own target after its deadline: it gave up.
                if self.target == g.took {
                    self.target = g.gave;
                }
                self.granted = None;
            } else if now >= g.deadline + p.settle_ticks {
                stands(self);
            }
        }
        if let Some(pd) = self.pending {
            if now >= pd.deadline {
                self.pending = None;
                self.quiet_until = pd.deadline + p.settle_ticks;
            }
        }
        let stalled = p.blocked.as_ref().filter(|b| b.enabled).is_some_and(|b| {
            let d = (position - targets[self.target]).norm();
            Watch::update(&mut self.watch, now, self.target, d, b)
        });
        if !self.is_busy() && now >= self.quiet_until {
            let mine = targets[self.target];
            let mut best: Option<(f64, &NeighbourView)> = None;
            for n in neighbours.iter().filter(|n| {
                n.id > self.id
                    && n.target < targets.len()
                    && (n.position - position).norm() <= p.range
            }) {
                let gain = swap_gain(position, n.position, mine, targets[n.target]);
                if gain > p.min_gain
                    && best.is_none_or(|(g, b)| gain > g || (gain == g && n.id < b.id))
                {
                    best = Some((gain, n));
                }
            }
            let mut blocked = false;
            if best.is_none() && stalled {
                best = self.in_the_way(position, targets, neighbours, p);
                blocked = best.is_some();
            }
            if let Some((_, n)) = best {
                self.seq += 1;
                self.pending = Some(Pending {
                    to: n.id,
                    seq: self.seq,
                    from_target: self.target,
                    to_target: n.target,
                    deadline: now + p.timeout_ticks,
                    blocked,
                    from_cost: self.path_cost.filter(|_| blocked),
                });
            }
        }
        if let Some(pd) = self.pending {
            out.push(Message::Propose {
                from: self.id,
                to: pd.to,
                seq: pd.seq,
                from_target: pd.from_target,
                to_target: pd.to_target,
                from_position: [position.x, position.y],
                deadline: pd.deadline,
                blocked: pd.blocked,
                from_cost: pd.from_cost,
            });
        }
        out
    }

    /// Where the partner of this robot's blocked swap stands while this robot makes way for
    /// it (blocked.rs): within `hold_ticks` of the swap, until the partner is in place in the
    /// slot this robot left (`in_place` of it). None: no way to make.
    pub fn making_way(
        &self,
        now: u64,
        targets: &[Vec2],
        neighbours: &[NeighbourView],
        p: &SwapParams,
    ) -> Option<Vec2> {
        let (partner, slot, until) = self.make_way?;
        let b = p.blocked.as_ref().filter(|b| b.make_way_speed > 0.0)?;
        let n = neighbours.iter().find(|n| n.id == partner)?;
        let q = targets.get(slot)?;
        (now < until && (n.position - q).norm() > b.in_place).then_some(n.position)
    }

    /// A blocked swap with `partner` stands (either side): hold still for `hold_ticks`,
    /// count it, and remember the partner (no second one in a row with it).
    fn blocked_swap_stands(&mut self, now: u64, partner: usize, b: &BlockedParams) {
        self.quiet_until = self.quiet_until.max(now + b.hold_ticks);
        self.blocked_swaps += 1;
        self.blocked_partner = Some(partner);
    }

    /// For a blocked robot: the in-place neighbour in its way (blocked.rs) within range whose
    /// swap costs the least (ties: the lower id), if that is at most `max_price`; with the
    /// gain (minus the price) as the first member.
    fn in_the_way<'a>(
        &self,
        position: Vec2,
        targets: &[Vec2],
        neighbours: &'a [NeighbourView],
        p: &SwapParams,
    ) -> Option<(f64, &'a NeighbourView)> {
        let b = p
            .blocked
            .as_ref()
            .filter(|b| self.blocked_swaps < b.max_swaps)?;
        let mine = targets[self.target];
        let mut best: Option<(f64, &NeighbourView)> = None;
        for n in neighbours.iter().filter(|n| {
            n.target < targets.len()
                && n.target != self.target
                && Some(n.id) != self.blocked_partner
                && (n.position - position).norm() <= p.range
                && (n.position - targets[n.target]).norm() <= b.in_place
                && (self.path_cost.is_some()
                    || blocked::in_the_way(position, mine, n.position, b.corridor))
        }) {
            let straight = swap_gain(position, n.position, mine, targets[n.target]);
            let gain = self.path_cost.map_or(straight, |c| {
                straight - (position - mine).norm_squared() + c
            });
            if -gain <= b.max_price
                && best.is_none_or(|(g, o)| gain > g || (gain == g && n.id < o.id))
            {
                best = Some((gain, n));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::hungarian::{assign_targets, Hungarian};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_blocked_robot_makes_way_until_its_partner_is_in_place_or_the_hold_ends() {
        let p = SwapParams {
            blocked: Some(BlockedParams::default()),
            ..SwapParams::default()
        };
        let hold = p.blocked.as_ref().unwrap().hold_ticks;
        // Robot 0 gave slot 0 (at the origin) to robot 1 in a blocked swap at tick 100.
        let targets = [Vec2::zeros(), Vec2::new(2.2, 0.0)];
        let mut a = SwapAgent::new(0, 1);
        a.make_way = Some((1, 0, 100 + hold));
        let at = |x: f64| NeighbourView {
            id: 1,
            position: Vec2::new(x, 0.0),
            target: 0,
            tick: 100,
        };
        // Partner 1.55 from the slot: make way (its position given).
        assert_eq!(
            a.making_way(101, &targets, &[at(1.55)], &p),
            Some(Vec2::new(1.55, 0.0))
        );
        // In place (within in_place of the slot): done.
        assert_eq!(a.making_way(102, &targets, &[at(0.5)], &p), None);
        // Not heard: nothing to make way for.
        assert_eq!(a.making_way(102, &targets, &[], &p), None);
        // The hold over: done.
        assert_eq!(a.making_way(100 + hold, &targets, &[at(1.55)], &p), None);
        // No blocked swap: never.
        let b = SwapAgent::new(0, 1);
        assert_eq!(b.making_way(101, &targets, &[at(1.55)], &p), None);
    }

    #[test]
    fn hand_computed_gain() {
        // Robots at 0 and 10 on the x axis holding each other's nearest targets (10 and 0):
        // 100 + 100 now, 0 after the swap: gain 200.
        let (o, t) = (Vec2::zeros(), Vec2::new(10.0, 0.0));
        assert_eq!(swap_gain(o, t, t, o), 200.0);
        assert_eq!(swap_gain(o, t, o, t), -200.0);
    }

    fn total_cost(p: &[Vec2], q: &[Vec2], agents: &[SwapAgent]) -> f64 {
        agents
            .iter()
            .enumerate()
            .map(|(i, a)| (p[i] - q[a.target]).norm_squared())
            .sum()
    }

    /// Runs the protocol in synchronous rounds over the disc graph of `radius`; each frame is
    /// lost with probability `loss`. Returns the agents and the costs at quiescent rounds.
    fn simulate(
        seed: u64,
        n: usize,
        radius: f64,
        loss: f64,
    ) -> (Vec<Vec2>, Vec<Vec2>, Vec<SwapAgent>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let side = 3.0 * (n as f64).sqrt();
        let pt =
            |rng: &mut ChaCha8Rng| Vec2::new(rng.gen_range(0.0..side), rng.gen_range(0.0..side));
        let p: Vec<Vec2> = (0..n).map(|_| pt(&mut rng)).collect();
        let q: Vec<Vec2> = (0..n).map(|_| pt(&mut rng)).collect();
        let mut agents: Vec<SwapAgent> =
            (0..n).map(|i| SwapAgent::new(i, (i * 7 + 3) % n)).collect();
        let mut in_flight: Vec<Message> = Vec::new();
        let mut costs = vec![total_cost(&p, &q, &agents)];
        let params = SwapParams {
            min_gain: 1e-9,
            range: radius,
            ..SwapParams::default()
        };
        for round in 0..5000u64 {
            // Status frames (not lost here): what each robot held after the last round.
            let views: Vec<NeighbourView> = agents
                .iter()
                .enumerate()
                .map(|(i, a)| NeighbourView {
                    id: i,
                    position: p[i],
                    target: a.target,
                    tick: round.saturating_sub(1),
                })
                .collect();
            let delivered: Vec<Message> = in_flight
                .drain(..)
                .filter(|_| rng.gen::<f64>() >= loss)
                .collect();
            let mut sent = Vec::new();
            for i in 0..n {
                let nb: Vec<NeighbourView> = views
                    .iter()
                    .filter(|v| v.id != i && (v.position - p[i]).norm() <= radius)
                    .copied()
                    .collect();
                sent.extend(agents[i].step(round, p[i], &q, &nb, &delivered, &params));
            }
            in_flight = sent;
            if agents.iter().all(|a| !a.is_busy()) {
                costs.push(total_cost(&p, &q, &agents));
                if in_flight.is_empty() {
                    break;
                }
            }
        }
        (p, q, agents, costs)
    }

    fn is_permutation(agents: &[SwapAgent]) -> bool {
        let mut seen = vec![false; agents.len()];
        agents
            .iter()
            .all(|a| !std::mem::replace(&mut seen[a.target], true))
    }

    #[test]
    fn never_increases_cost_and_converges_to_swap_stable_on_a_connected_graph() {
        for (seed, loss) in [(1, 0.0), (2, 0.0), (3, 0.3), (4, 0.3)] {
            let n = 30;
            // Radius 6 in a 16.4-unit square of 30 points: connected for these seeds (checked).
            let (p, q, agents, costs) = simulate(seed, n, 6.0, loss);
            assert!(connected(&p, 6.0), "seed {seed}");
            assert!(
                agents.iter().all(|a| !a.is_busy()),
                "seed {seed}: did not settle"
            );
            assert!(is_permutation(&agents), "seed {seed}");
            for w in costs.windows(2) {
                assert!(
                    w[1] <= w[0] + 1e-9,
                    "seed {seed}: cost rose {} -> {}",
                    w[0],
                    w[1]
                );
            }
            // Swap-stable: no neighbouring pair gains.
            for i in 0..n {
                for j in 0..n {
                    if i != j && (p[i] - p[j]).norm() <= 6.0 {
                        let g = swap_gain(p[i], p[j], q[agents[i].target], q[agents[j].target]);
                        assert!(g <= 1e-9, "seed {seed}: {i}-{j} still gain {g}");
                    }
                }
            }
            let mut h = Hungarian::new();
            let mut best = Vec::new();
            assign_targets(&p, &q, &mut h, &mut best).unwrap();
            let opt: f64 = (0..n).map(|i| (p[i] - q[best[i]]).norm_squared()).sum();
            let last = *costs.last().unwrap();
            assert!(last >= opt - 1e-9 && last < costs[0]);
            eprintln!(
                "seed {seed} loss {loss}: cost {:.1} -> {last:.1} (Hungarian {opt:.1})",
                costs[0]
            );
        }
    }

    fn connected(p: &[Vec2], radius: f64) -> bool {
        let mut seen = vec![false; p.len()];
        let mut stack = vec![0];
        seen[0] = true;
        while let Some(i) = stack.pop() {
            for j in 0..p.len() {
                if !seen[j] && (p[i] - p[j]).norm() <= radius {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        seen.iter().all(|&s| s)
    }

    fn view(id: usize, position: Vec2, target: usize, tick: u64) -> NeighbourView {
        NeighbourView {
            id,
            position,
            target,
            tick,
        }
    }

    fn no_gain_limit() -> SwapParams {
        SwapParams {
            min_gain: 0.0,
            range: 20.0,
            ..SwapParams::default()
        }
    }

    #[test]
    fn a_duplicated_proposal_swaps_once() {
        let p = no_gain_limit();
        let q = [Vec2::new(10.0, 0.0), Vec2::zeros()];
        let (pa, pb) = (Vec2::zeros(), Vec2::new(10.0, 0.0));
        let mut a = SwapAgent::new(0, 0);
        let mut b = SwapAgent::new(1, 1);
        let out = a.step(0, pa, &q, &[view(1, pb, 1, 0)], &[], &p);
        assert_eq!(out.len(), 1);
        // b hears the proposal twice (a retry): it swaps once and answers both times.
        let replies = b.step(1, pb, &q, &[], &[out[0], out[0]], &p);
        assert_eq!(b.target, 0);
        assert_eq!(replies.len(), 2);
        let again = b.step(2, pb, &q, &[], &[out[0]], &p);
        assert_eq!(b.target, 0, "a re-sent proposal must not swap back");
        assert!(matches!(again[0], Message::Reply { accepted: true, .. }));
        a.step(2, pa, &q, &[], &replies[..1], &p);
        assert_eq!((a.target, a.is_pending()), (1, false));
        // b is granted until it hears a holding b's old target.
        assert!(b.is_busy());
        b.step(3, pb, &q, &[view(0, pa, 1, 2)], &[], &p);
        assert!(!b.is_busy());
        assert_eq!((a.target, b.target), (1, 0));
    }

    #[test]
    fn a_proposer_killed_after_the_acceptance_leaves_the_receiver_settled_on_its_new_target() {
        // a proposes at tick 0 and dies: b accepted at tick 1, hears nothing more of a, and at
        // deadline + settle_ticks = 16 is free again, on a's old target 0 (the swap stands; a's
        // side is vacant). A proposal to a dead robot is given up at its deadline the same way
        // (a_lost_answer_is_given_up_and_the_receiver_takes_its_target_back).
        let p = no_gain_limit();
        let q = [Vec2::new(10.0, 0.0), Vec2::zeros()];
        let (pa, pb) = (Vec2::zeros(), Vec2::new(10.0, 0.0));
        let mut a = SwapAgent::new(0, 0);
        let mut b = SwapAgent::new(1, 1);
        let out = a.step(0, pa, &q, &[view(1, pb, 1, 0)], &[], &p);
        b.step(1, pb, &q, &[view(0, pa, 0, 0)], &out, &p);
        for now in 2..16 {
            b.step(now, pb, &q, &[], &[], &p);
            assert!(b.is_busy(), "tick {now}");
        }
        b.step(16, pb, &q, &[], &[], &p);
        assert_eq!((b.target, b.is_busy()), (0, false));
    }

    #[test]
    fn a_robot_whose_target_a_wreck_blocks_takes_the_dead_robots_vacant_target() {
        // Targets on a line 2.2 apart; "blocked" is within 2.1 of a wreck. Robot 3 (holding
        // target 3) died at (6.0, 0.5): target 2 at (4.4, 0) is 1.68 from it, target 3 at
        // (6.6, 0) 0.78.
        let q: Vec<Vec2> = (0..6).map(|i| Vec2::new(2.2 * i as f64, 0.0)).collect();
        let wreck = (Vec2::new(6.0, 0.5), 3);
        let near = |id, target| view(id, q[target], target, 0);
        // Robot 2's target is blocked, but so is the vacancy: nobody moves.
        let mut r2 = SwapAgent::new(2, 2);
        assert!(!r2.take_vacancy(&q, &[wreck], &[near(4, 4)], 2.1));
        assert_eq!(r2.target, 2);
        // The wreck at (5.0, 1.2): target 2 at 1.34, target 3 at 2.00 (blocked), target 1 at
        // 3.05 (free). With the dead robot's last target 1 (it had swapped), robot 2 takes 1.
        let wreck = (Vec2::new(5.0, 1.2), 1);
        assert!((q[3] - wreck.0).norm() < 2.1 && (q[1] - wreck.0).norm() > 2.1);
        let mut r2 = SwapAgent::new(2, 2);
        assert!(r2.take_vacancy(&q, &[wreck], &[near(4, 4), near(6, 3)], 2.1));
        assert_eq!(r2.target, 1);
        // Robot 6 (target 3, also blocked) defers to robot 2, the lower id.
        let mut r6 = SwapAgent::new(6, 3);
        assert!(!r6.take_vacancy(&q, &[wreck], &[near(2, 2)], 2.1));
        assert_eq!(r6.target, 3);
        // Not while a live robot still holds the vacancy (the dead one still heard, or a
        // partner of its last handshake): here robot 7 on target 1.
        let mut r2 = SwapAgent::new(2, 2);
        assert!(!r2.take_vacancy(&q, &[wreck], &[near(7, 1)], 2.1));
        // Not in a handshake.
        let mut r2 = SwapAgent::new(2, 2);
        r2.step(0, q[0], &q, &[view(9, q[2], 0, 0)], &[], &no_gain_limit());
        assert!(r2.is_busy());
        assert!(!r2.take_vacancy(&q, &[wreck], &[], 2.1));
        // A robot whose target no wreck blocks keeps it.
        let mut r0 = SwapAgent::new(0, 0);
        assert!(!r0.take_vacancy(&q, &[wreck], &[], 2.1));
        assert_eq!(r0.target, 0);
    }

    #[test]
    fn a_lost_answer_is_given_up_and_the_receiver_takes_its_target_back() {
        // Every reply is lost: a gives up at its deadline (tick 0 + 6), b accepted at tick 1
        // and, hearing a still on target 0 in a status sent at tick 6, returns to target 1.
        let p = no_gain_limit();
        let q = [Vec2::new(10.0, 0.0), Vec2::zeros()];
        let (pa, pb) = (Vec2::zeros(), Vec2::new(10.0, 0.0));
        let mut a = SwapAgent::new(0, 0);
        let mut b = SwapAgent::new(1, 1);
        let out = a.step(0, pa, &q, &[view(1, pb, 1, 0)], &[], &p);
        assert!(matches!(out[0], Message::Propose { deadline: 6, .. }));
        b.step(1, pb, &q, &[view(0, pa, 0, 0)], &out, &p);
        assert_eq!(b.target, 0);
        for now in 1..6 {
            let retry = a.step(now, pa, &q, &[view(1, pb, 0, now - 1)], &[], &p);
            assert_eq!(retry.len(), 1, "tick {now}: a retries");
            // a's statuses before its deadline decide nothing.
            b.step(now + 1, pb, &q, &[view(0, pa, 0, now)], &[], &p);
            assert!(b.is_busy());
        }
        let quiet = a.step(6, pa, &q, &[view(1, pb, 0, 5)], &[], &p);
        assert!(quiet.is_empty() && !a.is_busy() && a.target == 0);
        b.step(7, pb, &q, &[view(0, pa, 0, 6)], &[], &p);
        assert_eq!((a.target, b.target, b.is_busy()), (0, 1, false));
        // a stays quiet for settle_ticks after its deadline, then proposes again.
        assert!(a
            .step(15, pa, &q, &[view(1, pb, 1, 14)], &[], &p)
            .is_empty());
        assert_eq!(a.step(16, pa, &q, &[view(1, pb, 1, 15)], &[], &p).len(), 1);
    }

    #[test]
    fn proposes_only_within_range() {
        let p = SwapParams {
            min_gain: 0.0,
            range: 9.0,
            ..SwapParams::default()
        };
        let q = [Vec2::new(10.0, 0.0), Vec2::zeros()];
        let mut a = SwapAgent::new(0, 0);
        // Gain 200, but b is 10 away.
        assert!(a
            .step(
                0,
                Vec2::zeros(),
                &q,
                &[view(1, Vec2::new(10.0, 0.0), 1, 0)],
                &[],
                &p
            )
            .is_empty());
        assert_eq!(
            a.step(
                1,
                Vec2::zeros(),
                &q,
                &[view(1, Vec2::new(9.0, 0.0), 1, 0)],
                &[],
                &p
            )
            .len(),
            1
        );
    }
}
