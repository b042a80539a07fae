//! Multi-hop election and gathering for the swaps re-plan (issue 16 at 100 and 500 robots:
//! comm radius 15 in a 60 x 60 or 130 x 130 box, no robot hears everyone).
//!
//! A need is named by its key (the plan's epoch, Sense `alive_robots` when it began): every
//! robot sees the world's live count change on the same tick, so all agree on the key, and a
//! dead robot, silent since its death, never sent a message with the key of the need its
//! death opened. Each robot in a need broadcasts a [`Need`] every tick and merges the ones it
//! hears of the same key:
//! - `candidate`: the lowest id it knows in the need (min-id flooding); after about the
//!   network's diameter in hops every robot holds the global minimum, the coordinator;
//! - `known`: the robots known alive in the need (a bit per robot id, OR-merged);
//! - `held`: the template points the robots of `settled` hold (a bit per template point,
//!   OR-merged): a point no live robot holds is a dead robot's, vacant;
//! - `settled`: the robots whose point is in `held` (a bit per robot id, OR-merged).
//!
//! `held` is exact, not the union over the gathering: a robot adds its point once, when the
//! point is final for the need, i.e. when it is in no handshake ([`Gathering::note`] with
//! `final_point`); while gathering it makes, accepts and takes no new swap or vacancy
//! (mod.rs, replan_multihop.rs), so that point stays its point until the plan comes. (The
//! union, the first version, counted both points of a robot that took a vacancy during the
//! gathering, so `held` left fewer points vacant than the deficit and the coordinator waited
//! for the timeout.) A robot in a handshake at the need's start adds its point when the
//! handshake has settled; until then it is in `known` but not in `settled`.
//!
//! The coordinator solves once `settled` counts `alive` robots (so `held` is every live
//! robot's point), or at the timeout (replan_multihop.rs).

use serde::{Deserialize, Serialize};

/// A set of small indices (robot ids, template points) as bits, for the radio: 500 robots in
/// 63 bytes.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Bitmap(pub Vec<u8>);

impl Bitmap {
    /// The empty set of indices below `n`.
    pub fn with_len(n: usize) -> Bitmap {
        Bitmap(vec![0; n.div_ceil(8)])
    }
    pub fn insert(&mut self, i: usize) {
        let byte = i / 8;
        if byte >= self.0.len() {
            self.0.resize(byte + 1, 0);
        }
        self.0[byte] |= 1 << (i % 8);
    }
    pub fn contains(&self, i: usize) -> bool {
        self.0.get(i / 8).is_some_and(|b| b & (1 << (i % 8)) != 0)
    }
    pub fn count(&self) -> usize {
        self.0.iter().map(|b| b.count_ones() as usize).sum()
    }
    /// Set union (OR), in place.
    pub fn merge(&mut self, other: &Bitmap) {
        if other.0.len() > self.0.len() {
            self.0.resize(other.0.len(), 0);
        }
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a |= *b;
        }
    }
    /// The members, ascending.
    pub fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.0.len() * 8).filter(|i| self.contains(*i))
    }
}

/// The gossip of one need (a radio message).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Need {
    /// The key: the epoch of the plan to re-make and the live count.
    pub epoch: u32,
    pub alive: u32,
    /// The lowest robot id known in the need.
    pub candidate: u32,
    /// Robots known alive in the need (bits by id).
    pub known: Bitmap,
    /// Template points held by the robots of `settled` (bits by template point).
    pub held: Bitmap,
    /// Robots whose final point is in `held` (bits by id).
    pub settled: Bitmap,
}

/// One robot's gathering for a need.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Gathering {
    /// The tick this robot entered the need.
    pub since: u64,
    pub need: Need,
}

impl Gathering {
    /// Entering the need (epoch, alive) at tick `k`, for `robots` ids and `points` template
    /// points.
    pub fn start(k: u64, epoch: u32, alive: u32, robots: usize, points: usize) -> Gathering {
        Gathering {
            since: k,
            need: Need {
                epoch,
                alive,
                candidate: u32::MAX,
                known: Bitmap::with_len(robots),
                held: Bitmap::with_len(points),
                settled: Bitmap::with_len(robots),
            },
        }
    }

    pub fn is_for(&self, epoch: u32, alive: u32) -> bool {
        self.need.epoch == epoch && self.need.alive == alive
    }

    /// This robot's share: its id, and the template point it holds now (if any) when that
    /// point is final for the need (`final_point`: the robot is in no handshake). The first
    /// final point counts; a robot already settled adds nothing (its point cannot change
    /// while gathering).
    pub fn note(&mut self, robot: u32, point: Option<usize>, final_point: bool) {
        self.need.candidate = self.need.candidate.min(robot);
        self.need.known.insert(robot as usize);
        if final_point && !self.need.settled.contains(robot as usize) {
            self.need.settled.insert(robot as usize);
            if let Some(p) = point {
                self.need.held.insert(p);
            }
        }
    }

    /// Whether every live robot's final point is known: `held` is then exact.
    pub fn complete(&self) -> bool {
        self.need.settled.count() >= self.need.alive as usize
    }

    /// The points of `points` no settled robot holds.
    pub fn vacant(&self, points: &[u16]) -> usize {
        points
            .iter()
            .filter(|p| !self.need.held.contains(**p as usize))
            .count()
    }

    /// Merges a neighbour's gossip of the same key (another key is ignored: it may count a
    /// robot that died since). Returns whether it was merged.
    pub fn merge(&mut self, other: &Need) -> bool {
        if !self.is_for(other.epoch, other.alive) {
            return false;
        }
        self.need.candidate = self.need.candidate.min(other.candidate);
        self.need.known.merge(&other.known);
        self.need.held.merge(&other.held);
        self.need.settled.merge(&other.settled);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bitmap_of_500_ids_takes_63_bytes_and_counts_its_members() {
        let mut b = Bitmap::with_len(500);
        assert_eq!(b.0.len(), 63);
        for i in [0, 7, 8, 255, 499] {
            b.insert(i);
        }
        b.insert(7);
        assert_eq!(b.count(), 5);
        assert!(b.contains(499) && !b.contains(498) && !b.contains(10_000));
        assert_eq!(b.iter().collect::<Vec<_>>(), vec![0, 7, 8, 255, 499]);
    }

    #[test]
    fn gossip_on_a_line_floods_the_lowest_id_and_every_robot_to_both_ends() {
        // Robots 0..9 on a line, id order shuffled, each hearing only its two neighbours: a
        // multi-hop swarm. After at most 9 rounds every robot holds candidate 0 and all ids.
        let ids: [u32; 10] = [5, 3, 8, 0, 9, 2, 7, 1, 6, 4];
        let mut g: Vec<Gathering> = ids
            .iter()
            .map(|id| {
                let mut g = Gathering::start(3, 1, 10, 10, 12);
                g.note(*id, Some(*id as usize + 2), true);
                g
            })
            .collect();
        let mut rounds = 0;
        while g.iter().any(|x| x.need.candidate != 0 || x.need.known.count() < 10) {
            let sent: Vec<Need> = g.iter().map(|x| x.need.clone()).collect();
            for (i, x) in g.iter_mut().enumerate() {
                for j in [i.wrapping_sub(1), i + 1] {
                    if let Some(n) = sent.get(j) {
                        assert!(x.merge(n));
                    }
                }
            }
            rounds += 1;
            assert!(rounds <= 9, "not flooded in the line's diameter");
        }
        // The ends' ids cross the whole line: its diameter, 9 hops.
        assert_eq!(rounds, 9);
        for x in &g {
            assert_eq!(x.need.held.iter().collect::<Vec<_>>(), (2..12).collect::<Vec<_>>());
        }
        // Another key (a further death: alive 9) is not merged.
        let mut other = g[0].need.clone();
        other.alive = 9;
        other.candidate = 0;
        let mut fresh = Gathering::start(9, 1, 10, 10, 12);
        fresh.note(4, None, true);
        assert!(!fresh.merge(&other));
        assert_eq!((fresh.need.candidate, fresh.need.known.count()), (4, 1));
    }

    /// Five robots on template points 0..5 of six (point 5 the dead robot's, deficit 1).
    /// Robot 2 stands next to a wreck on point 2 and moves to the vacancy, point 5, during the
    /// gathering, as a `take_vacancy` does: it is not final before it moved (here: it was in a
    /// handshake; mod.rs freezes `take_vacancy` itself while gathering, so a final point stays
    /// put). Robot 4 is in a handshake until round 2. Each round every robot notes its current
    /// point and hears every other.
    #[test]
    fn held_is_exact_when_a_robot_takes_a_vacancy_during_the_gathering() {
        let points: Vec<u16> = (0..6).collect();
        // (robot, point per round, busy per round), rounds 0..3.
        let rounds: [[(u32, usize, bool); 5]; 3] = [
            [(0, 0, false), (1, 1, false), (2, 2, true), (3, 3, false), (4, 4, true)],
            [(0, 0, false), (1, 1, false), (2, 5, false), (3, 3, false), (4, 4, true)],
            [(0, 0, false), (1, 1, false), (2, 5, false), (3, 3, false), (4, 4, false)],
        ];
        let mut g: Vec<Gathering> = (0..5).map(|_| Gathering::start(10, 0, 5, 5, 6)).collect();
        // The first version's rule: every point noted, OR-merged.
        let mut union = Bitmap::with_len(6);
        for (r, round) in rounds.iter().enumerate() {
            for (i, (robot, point, busy)) in round.iter().enumerate() {
                g[i].note(*robot, Some(*point), !busy);
                union.insert(*point);
            }
            let sent: Vec<Need> = g.iter().map(|x| x.need.clone()).collect();
            for x in &mut g {
                for n in &sent {
                    assert!(x.merge(n));
                }
            }
            // Robot 4 is still in its handshake after rounds 0 and 1: not complete.
            assert_eq!(g[0].complete(), r == 2, "round {r}");
        }
        for x in &g {
            assert_eq!(x.need.held.iter().collect::<Vec<_>>(), vec![0, 1, 3, 4, 5]);
            // Exactly the deficit vacant: the blocked point 2 the robot left.
            assert_eq!(x.vacant(&points), 1);
        }
        // The union counted point 2 as held too: no point vacant, the gathering never
        // complete (the coordinator waited for the timeout).
        let vacant_union = points.iter().filter(|p| !union.contains(**p as usize)).count();
        assert_eq!(vacant_union, 0);
    }
}
