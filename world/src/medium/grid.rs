//! The receivers near a sender: a uniform bucket grid over the live robots' positions at the
//! send tick, rebuilt each tick (a counting sort, O(N + cells)), so a broadcast's range test
//! looks at the robots of the cells its circle can reach instead of every robot (O(N k) a
//! tick for k neighbours, not O(N^2)).
//!
//! The grid only culls: every robot it returns is still judged by `swarm::radio::decide`,
//! exactly as the scan over all robots judged it, and a robot it does not return is one that
//! `decide` would have put out of range (its cell lies beyond the radius by more than the
//! margin below). So the medium's verdicts, and therefore its deliveries, are the same.

/// How the medium finds the receivers a broadcast may reach (`radio.range_scan`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RangeScan {
    /// The cells within the sender's range (the default).
    #[default]
    Grid,
    /// Every live robot (the design before the grid; kept for the benchmark and the tests
    /// that check the grid gives the same deliveries).
    All,
}

/// Relative margin by which a cell must lie beyond a query's radius to be skipped: far more
/// than `decide`'s own tolerance (an in-range square is at most R^2 (1 + 1e-9), i.e. a
/// distance below R (1 + 5e-10)) and than the rounding of the coordinates' subtraction.
const CULL_MARGIN: f64 = 1e-6;
/// Most cells along one side: a grid over a spread far larger than the range (a station far
/// away) gets coarser cells instead of millions of empty ones.
const MAX_CELLS_PER_SIDE: usize = 1024;

/// The live robots by cell, row-major: the robots of cell c are `members[start[c]..start[c + 1]]`
/// in increasing id order.
#[derive(Debug, Default)]
pub struct RobotGrid {
    origin: [f64; 2],
    cell: f64,
    cols: usize,
    rows: usize,
    start: Vec<u32>,
    members: Vec<u32>,
    /// Each robot's cell (usize::MAX: not in the grid), and each cell's next free place:
    /// scratch of the build, kept for their allocations.
    cell_of: Vec<usize>,
    next: Vec<u32>,
}

impl RobotGrid {
    /// Rebuilds the grid over the robots with `alive[i]`, with cells of side about `cell`.
    pub fn rebuild(&mut self, poses: &[[f64; 3]], alive: &[bool], cell: f64) {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (p, _) in poses.iter().zip(alive).filter(|(_, a)| **a) {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if lo[0] > hi[0] {
            lo = [0.0; 2];
            hi = [0.0; 2];
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let cell = if cell.is_finite() && cell > 0.0 {
            cell.max(extent / MAX_CELLS_PER_SIDE as f64)
        } else {
            extent.max(1.0)
        };
        self.origin = lo;
        self.cell = cell.max(f64::MIN_POSITIVE);
        self.cols = ((hi[0] - lo[0]) / self.cell) as usize + 1;
        self.rows = ((hi[1] - lo[1]) / self.cell) as usize + 1;
        let cells = self.cols * self.rows;
        self.start.clear();
        self.start.resize(cells + 1, 0);
        self.cell_of.clear();
        for (p, &a) in poses.iter().zip(alive) {
            let c = if a {
                let (c, r) = (self.col(p[0]), self.row(p[1]));
                r * self.cols + c
            } else {
                usize::MAX
            };
            self.cell_of.push(c);
            if c != usize::MAX {
                self.start[c + 1] += 1;
            }
        }
        for c in 0..cells {
            self.start[c + 1] += self.start[c];
        }
        self.members.clear();
        self.members.resize(self.start[cells] as usize, 0);
        // Filled in id order, so each cell lists its robots by increasing id.
        self.next.clear();
        self.next.extend_from_slice(&self.start[..cells]);
        for (i, &c) in self.cell_of.iter().enumerate() {
            if c != usize::MAX {
                self.members[self.next[c] as usize] = i as u32;
                self.next[c] += 1;
            }
        }
    }

    /// The cell column of x (points beyond the grid fall in the outermost cells; the clamp is
    /// monotone, so a query's clamped range still holds every point it reaches).
    fn col(&self, x: f64) -> usize {
        (((x - self.origin[0]) / self.cell).floor().max(0.0) as usize).min(self.cols - 1)
    }

    fn row(&self, y: f64) -> usize {
        (((y - self.origin[1]) / self.cell).floor().max(0.0) as usize).min(self.rows - 1)
    }

    /// Calls `f` for every live robot whose cell lies within `radius` (plus the margin) of `q`
    /// on both axes: a superset of the robots within `radius`, row by row of cells.
    pub fn near(&self, q: [f64; 2], radius: f64, mut f: impl FnMut(u32)) {
        if self.members.is_empty() {
            return;
        }
        let reach = radius + CULL_MARGIN * (radius + q[0].abs().max(q[1].abs()));
        let (c0, c1) = (self.col(q[0] - reach), self.col(q[0] + reach));
        let (r0, r1) = (self.row(q[1] - reach), self.row(q[1] + reach));
        for r in r0..=r1 {
            let row = r * self.cols;
            let run =
                &self.members[self.start[row + c0] as usize..self.start[row + c1 + 1] as usize];
            for &j in run {
                f(j);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use swarm::radio::distance;

    #[test]
    fn near_returns_every_live_robot_within_the_radius() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut g = RobotGrid::default();
        for case in 0..200 {
            let n = rng.gen_range(0..150);
            let side = [10.0, 500.0, 5000.0][case % 3];
            let poses: Vec<[f64; 3]> = (0..n)
                .map(|_| {
                    // Some beyond the usual arena, some on top of each other.
                    if rng.gen_bool(0.1) {
                        [side * 0.5, side * 0.5, 0.0]
                    } else {
                        [
                            rng.gen_range(-0.2 * side..1.2 * side),
                            rng.gen_range(-0.2 * side..1.2 * side),
                            0.0,
                        ]
                    }
                })
                .collect();
            let alive: Vec<bool> = (0..n).map(|_| rng.gen_bool(0.8)).collect();
            let cell = [1.0, 50.0, 300.0, 1e-9][case % 4];
            g.rebuild(&poses, &alive, cell);
            for _ in 0..10 {
                let q = [
                    rng.gen_range(-0.5 * side..1.5 * side),
                    rng.gen_range(-0.5 * side..1.5 * side),
                ];
                let radius = rng.gen_range(0.0..side);
                let mut got = Vec::new();
                g.near(q, radius, |j| got.push(j));
                let mut sorted = got.clone();
                sorted.sort();
                sorted.dedup();
                assert_eq!(sorted.len(), got.len(), "each robot once");
                for (i, p) in poses.iter().enumerate() {
                    let within = distance(q, [p[0], p[1]]) <= radius * (1.0 + 1e-9);
                    if alive[i] && within {
                        assert!(got.contains(&(i as u32)), "case {case}: robot {i} missed");
                    }
                    if !alive[i] {
                        assert!(!got.contains(&(i as u32)), "case {case}: dead robot {i}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_far_query_visits_no_cell_and_an_empty_grid_nothing() {
        let mut g = RobotGrid::default();
        let poses = vec![[0.0, 0.0, 0.0], [1000.0, 1000.0, 0.0]];
        g.rebuild(&poses, &[true, true], 100.0);
        let mut got = Vec::new();
        g.near([0.0, 0.0], 50.0, |j| got.push(j));
        assert_eq!(got, vec![0]);
        g.rebuild(&poses, &[false, false], 100.0);
        got.clear();
        g.near([0.0, 0.0], 5000.0, |j| got.push(j));
        assert!(got.is_empty());
    }
}
