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
//! - `held`: the template points their robots held while in the need (a bit per template
//!   point, OR-merged): a point no live robot held is the dead robot's, vacant.
//!
//! The coordinator solves once `known` counts `alive` robots and `held` leaves the deficit of
//! points vacant, or at the timeout (replan.rs).

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
    /// Template points held by robots in the need (bits by template point).
    pub held: Bitmap,
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
            },
        }
    }

    pub fn is_for(&self, epoch: u32, alive: u32) -> bool {
        self.need.epoch == epoch && self.need.alive == alive
    }

    /// This robot's share: its id, and the template point it holds now (if any).
    pub fn note(&mut self, robot: u32, point: Option<usize>) {
        self.need.candidate = self.need.candidate.min(robot);
        self.need.known.insert(robot as usize);
        if let Some(p) = point {
            self.need.held.insert(p);
        }
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
                g.note(*id, Some(*id as usize + 2));
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
        fresh.note(4, None);
        assert!(!fresh.merge(&other));
        assert_eq!((fresh.need.candidate, fresh.need.known.count()), (4, 1));
    }
}
