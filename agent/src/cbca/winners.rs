//! Z^i and Y^i of sec. 4.2.1 (spec 4.2) as one matrix: entry (m, j) holds m's winning bid on
//! task j when robot i believes m is a winner of j (z^i_mj = 1, y^i_mj = the bid), and nothing
//! otherwise (z = 0, y = -inf). A column may hold several winners: the coalition of task j.

use serde::{Deserialize, Serialize};

use super::model::{RobotId, TaskId};

/// One believed winner: z_mj = 1 with y_mj = bid. The radio carries these (the non-empty
/// entries), not the dense n_r x n_e matrices.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WinnerEntry {
    pub robot: RobotId,
    pub task: TaskId,
    pub bid: f64,
}

/// (bid a, robot a) beats (bid b, robot b): a higher bid, or an equal bid and a smaller id
/// (the tie rule under (4.16)).
pub fn outbids(a: (f64, RobotId), b: (f64, RobotId)) -> bool {
    a.0 > b.0 || (a.0 == b.0 && a.1 < b.1)
}

#[derive(Clone, Debug, PartialEq)]
pub struct Winners {
    n_robots: usize,
    n_tasks: usize,
    bids: Vec<Option<f64>>,
}

impl Winners {
    pub fn new(n_robots: usize, n_tasks: usize) -> Self {
        Self {
            n_robots,
            n_tasks,
            bids: vec![None; n_robots * n_tasks],
        }
    }

    pub fn n_robots(&self) -> usize {
        self.n_robots
    }

    pub fn n_tasks(&self) -> usize {
        self.n_tasks
    }

    fn at(&self, m: RobotId, j: TaskId) -> usize {
        assert!(
            m < self.n_robots && j < self.n_tasks,
            "({m}, {j}) outside Z"
        );
        m * self.n_tasks + j
    }

    /// z_mj.
    pub fn is_winner(&self, m: RobotId, j: TaskId) -> bool {
        self.bids[self.at(m, j)].is_some()
    }

    /// y_mj (-inf when m is no winner of j).
    pub fn bid(&self, m: RobotId, j: TaskId) -> f64 {
        self.bids[self.at(m, j)].unwrap_or(f64::NEG_INFINITY)
    }

    /// The raw entry (None: no winner).
    pub fn get(&self, m: RobotId, j: TaskId) -> Option<f64> {
        self.bids[self.at(m, j)]
    }

    /// z_mj = 1, y_mj = bid.
    pub fn set(&mut self, m: RobotId, j: TaskId, bid: f64) {
        let k = self.at(m, j);
        self.bids[k] = Some(bid);
    }

    /// Writes the raw entry.
    pub fn put(&mut self, m: RobotId, j: TaskId, entry: Option<f64>) {
        let k = self.at(m, j);
        self.bids[k] = entry;
    }

    /// z_mj = 0, y_mj = -inf.
    pub fn clear(&mut self, m: RobotId, j: TaskId) {
        let k = self.at(m, j);
        self.bids[k] = None;
    }

    /// The believed coalition of task j, as (robot, bid) in robot order.
    pub fn winners_of(&self, j: TaskId) -> Vec<(RobotId, f64)> {
        (0..self.n_robots)
            .filter_map(|m| self.get(m, j).map(|b| (m, b)))
            .collect()
    }

    /// N_j^sum = Σ_k z_kj (4.11).
    pub fn count(&self, j: TaskId) -> usize {
        (0..self.n_robots).filter(|&m| self.is_winner(m, j)).count()
    }

    /// The weakest winner of j, the one every other winner outbids (lowest bid; of equal bids,
    /// the larger id): min_k y_kj over the winners, the k of (4.16).
    pub fn weakest(&self, j: TaskId) -> Option<(RobotId, f64)> {
        self.winners_of(j).into_iter().reduce(|w, c| {
            if outbids((w.1, w.0), (c.1, c.0)) {
                c
            } else {
                w
            }
        })
    }

    /// The non-empty entries, in (robot, task) order.
    pub fn entries(&self) -> Vec<WinnerEntry> {
        let mut out = Vec::new();
        for m in 0..self.n_robots {
            for j in 0..self.n_tasks {
                if let Some(bid) = self.get(m, j) {
                    out.push(WinnerEntry {
                        robot: m,
                        task: j,
                        bid,
                    });
                }
            }
        }
        out
    }

    /// The matrix holding exactly these entries (entries outside it are ignored).
    pub fn from_entries(n_robots: usize, n_tasks: usize, entries: &[WinnerEntry]) -> Self {
        let mut w = Self::new(n_robots, n_tasks);
        for e in entries {
            if e.robot < n_robots && e.task < n_tasks {
                w.set(e.robot, e.task, e.bid);
            }
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weakest_is_the_lowest_bid_and_of_ties_the_larger_id() {
        let mut w = Winners::new(4, 2);
        w.set(0, 1, 5.0);
        w.set(2, 1, 3.0);
        w.set(3, 1, 3.0);
        assert_eq!(w.count(1), 3);
        assert_eq!(w.weakest(1), Some((3, 3.0)));
        assert!(outbids((3.0, 2), (3.0, 3)));
        assert!(!outbids((3.0, 3), (3.0, 2)));
        assert_eq!(w.weakest(0), None);
        assert_eq!(w.bid(1, 1), f64::NEG_INFINITY);
        let back = Winners::from_entries(4, 2, &w.entries());
        assert_eq!(back, w);
        w.clear(3, 1);
        assert_eq!(w.weakest(1), Some((2, 3.0)));
    }
}
