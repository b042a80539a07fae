//! Beyond the paper (its authors name large swarms as future work; spec 5 option (b)): a
//! decentralised reassignment by pairwise swaps between neighbours. Robots i and j holding
//! targets a and b swap when that lowers the pair's summed cost (the squared distances of
//! eq. 4) by more than `min_gain`, agreed by a two-message handshake. Each robot runs the same
//! pure state machine ([`SwapAgent::step`]): messages in, messages out, no clock, no I/O.
//!
//! Protocol (ours):
//! - Only a lower id proposes to a higher id (every pair is still considered, by its lower id),
//!   so proposals form chains of increasing id and never a cycle: the top of a chain is free
//!   and decides on the merits, so a round with proposals under lossless delivery commits a
//!   swap, and the search cannot livelock.
//! - The proposer sends `Propose` (its id, target, position, the target it believes the
//!   receiver holds, and a sequence number) and is then busy: it rejects proposals and keeps
//!   re-sending the same `Propose` every step until it hears the answer.
//! - A free receiver that still holds the believed target and finds the gain (from its own
//!   position and the proposer's) above `min_gain` takes the proposer's target at once and
//!   answers `Reply { accepted: true }`; otherwise it answers `false`. It records its answer per
//!   proposer and repeats it for a re-sent proposal (so a lost reply is recovered by the
//!   proposer's retry, and a duplicate never swaps twice).
//! - The proposer takes the receiver's old target when the acceptance arrives.
//!
//! Invariants: every committed swap exchanges exactly two targets and lowers the summed cost
//! by more than `min_gain` (for static positions); whenever no proposal is pending, the targets
//! are a permutation. Between the receiver's commit and the proposer's, both aim at the same
//! slot (message loss makes this window arbitrary long; ORCA keeps them apart meanwhile).
//! The fixed point is swap-stable (no neighbouring pair gains from swapping), which is not
//! always the optimal assignment that the centralised Hungarian finds.

use std::collections::BTreeMap;
use swarm::geometry::Vec2;

/// A handshake message (one radio frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message {
    /// "Swap with me: I hold `from_target` and am at `from_position`; you hold `to_target`."
    Propose {
        from: usize,
        to: usize,
        seq: u64,
        from_target: usize,
        to_target: usize,
        from_position: [f64; 2],
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
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Pending {
    to: usize,
    seq: u64,
    from_target: usize,
    to_target: usize,
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
    /// The last proposal answered per proposer: (seq, accepted).
    answered: BTreeMap<usize, (u64, bool)>,
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
            answered: BTreeMap::new(),
        }
    }

    /// Whether a proposal of this robot awaits its answer.
    pub fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// One step: handle the frames addressed to this robot (in the order given), then retry
    /// the pending proposal or make a new one to the best neighbour of higher id.
    pub fn step(
        &mut self,
        position: Vec2,
        targets: &[Vec2],
        neighbours: &[NeighbourView],
        inbox: &[Message],
        min_gain: f64,
    ) -> Vec<Message> {
        let mut out = Vec::new();
        for m in inbox.iter().filter(|m| m.to() == self.id) {
            match *m {
                Message::Reply {
                    from,
                    seq,
                    accepted,
                    ..
                } => {
                    if let Some(p) = self.pending.filter(|p| p.to == from && p.seq == seq) {
                        if accepted {
                            self.target = p.to_target;
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
                    ..
                } => {
                    let accepted = match self.answered.get(&from) {
                        Some(&(s, a)) if s == seq => a,
                        _ => {
                            let theirs = Vec2::new(from_position[0], from_position[1]);
                            let fits = self.pending.is_none()
                                && self.target == to_target
                                && from_target < targets.len()
                                && swap_gain(
                                    theirs,
                                    position,
                                    targets[from_target],
                                    targets[to_target],
                                ) > min_gain;
                            if fits {
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
        if self.pending.is_none() {
            let mine = targets[self.target];
            let mut best: Option<(f64, &NeighbourView)> = None;
            for n in neighbours
                .iter()
                .filter(|n| n.id > self.id && n.target < targets.len())
            {
                let gain = swap_gain(position, n.position, mine, targets[n.target]);
                if gain > min_gain
                    && best.is_none_or(|(g, b)| gain > g || (gain == g && n.id < b.id))
                {
                    best = Some((gain, n));
                }
            }
            if let Some((_, n)) = best {
                self.seq += 1;
                self.pending = Some(Pending {
                    to: n.id,
                    seq: self.seq,
                    from_target: self.target,
                    to_target: n.target,
                });
            }
        }
        if let Some(p) = self.pending {
            out.push(Message::Propose {
                from: self.id,
                to: p.to,
                seq: p.seq,
                from_target: p.from_target,
                to_target: p.to_target,
                from_position: [position.x, position.y],
            });
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::hungarian::{assign_targets, Hungarian};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

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
        for _round in 0..5000 {
            let views: Vec<NeighbourView> = agents
                .iter()
                .enumerate()
                .map(|(i, a)| NeighbourView {
                    id: i,
                    position: p[i],
                    target: a.target,
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
                sent.extend(agents[i].step(p[i], &q, &nb, &delivered, 1e-9));
            }
            in_flight = sent;
            if agents.iter().all(|a| !a.is_pending()) {
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
                agents.iter().all(|a| !a.is_pending()),
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

    #[test]
    fn a_duplicated_proposal_swaps_once() {
        let q = [Vec2::new(10.0, 0.0), Vec2::zeros()];
        let (pa, pb) = (Vec2::zeros(), Vec2::new(10.0, 0.0));
        let mut a = SwapAgent::new(0, 0);
        let mut b = SwapAgent::new(1, 1);
        let view_b = [NeighbourView {
            id: 1,
            position: pb,
            target: 1,
        }];
        let out = a.step(pa, &q, &view_b, &[], 0.0);
        assert_eq!(out.len(), 1);
        // b hears the proposal twice (a retry): it swaps once and answers both times.
        let replies = b.step(pb, &q, &[], &[out[0], out[0]], 0.0);
        assert_eq!(b.target, 0);
        assert_eq!(replies.len(), 2);
        let again = b.step(pb, &q, &[], &[out[0]], 0.0);
        assert_eq!(b.target, 0, "a re-sent proposal must not swap back");
        assert!(matches!(again[0], Message::Reply { accepted: true, .. }));
        a.step(pa, &q, &[], &replies[..1], 0.0);
        assert_eq!((a.target, a.is_pending()), (1, false));
    }
}
