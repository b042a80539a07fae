//! Metrics every run has, whatever its mission: how well the swarm spread.

use serde::Serialize;
use swarm::radio::distance;

/// Side of the square cells used for area coverage.
pub const COVERAGE_CELL: f64 = 20.0;

/// Which cells of the arena any robot has been in.
pub struct Coverage {
    cols: usize,
    rows: usize,
    seen: Vec<bool>,
    count: usize,
}

impl Coverage {
    pub fn new(width: f64, height: f64) -> Coverage {
        let cols = (width / COVERAGE_CELL).ceil().max(1.0) as usize;
        let rows = (height / COVERAGE_CELL).ceil().max(1.0) as usize;
        Coverage {
            cols,
            rows,
            seen: vec![false; cols * rows],
            count: 0,
        }
    }
    pub fn visit(&mut self, p: [f64; 2]) {
        let c = ((p[0] / COVERAGE_CELL) as usize).min(self.cols - 1);
        let r = ((p[1] / COVERAGE_CELL) as usize).min(self.rows - 1);
        let k = r * self.cols + c;
        if !self.seen[k] {
            self.seen[k] = true;
            self.count += 1;
        }
    }
    pub fn fraction(&self) -> f64 {
        self.count as f64 / self.seen.len() as f64
    }
}

/// The `mission` section of summary.json: the mission's own metrics under its name, the
/// body figures when robots have a body, and how the swarm spread (every run).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MissionMetrics {
    /// The mission's metrics, keyed by its name (search: `search`); none for roam.
    #[serde(flatten)]
    pub own: serde_json::Map<String, serde_json::Value>,
    /// Fraction of 20 x 20 cells any robot visited.
    pub coverage: f64,
    /// Mean distance of live robots to their centroid at the end.
    pub spread: f64,
    /// Mean distance from each live robot to its nearest live robot at the end.
    pub mean_nearest_neighbour: f64,
}

pub fn spread(coverage: &Coverage, poses: &[[f64; 3]], alive: &[bool]) -> MissionMetrics {
    let live: Vec<[f64; 2]> = poses
        .iter()
        .zip(alive)
        .filter(|(_, a)| **a)
        .map(|(p, _)| [p[0], p[1]])
        .collect();
    let n = live.len().max(1) as f64;
    let cx = live.iter().map(|p| p[0]).sum::<f64>() / n;
    let cy = live.iter().map(|p| p[1]).sum::<f64>() / n;
    let spread = live.iter().map(|p| distance(*p, [cx, cy])).sum::<f64>() / n;
    let nn = if live.len() < 2 {
        0.0
    } else {
        live.iter()
            .enumerate()
            .map(|(i, p)| {
                live.iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, q)| distance(*p, *q))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            / n
    };
    MissionMetrics {
        own: serde_json::Map::new(),
        coverage: coverage.fraction(),
        spread,
        mean_nearest_neighbour: nn,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_counts_cells_once() {
        let mut c = Coverage::new(100.0, 100.0);
        c.visit([1.0, 1.0]);
        c.visit([2.0, 2.0]);
        c.visit([99.9, 99.9]);
        assert!((c.fraction() - 2.0 / 25.0).abs() < 1e-12);
    }

    #[test]
    fn spread_and_nearest_neighbour() {
        let c = Coverage::new(100.0, 100.0);
        let m = spread(
            &c,
            &[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [500.0, 0.0, 0.0]],
            &[true, true, false],
        );
        assert!((m.spread - 5.0).abs() < 1e-12);
        assert!((m.mean_nearest_neighbour - 10.0).abs() < 1e-12);
    }
}
