//! What each robot senses: obstacle / wall boundary points within the sensing radius (a set,
//! in a fixed order) and the robots within radio link range (by id).

use swarm::frames::{Nearby, Sense, MAX_NEARBY, MAX_OBSTACLE_POINTS};
use swarm::geometry::sample_boundary;
use swarm::radio::within_radius;
use swarm::scenario::Scenario;

/// A uniform bucket grid over fixed points, for radius queries.
///
/// Cells are a quarter of the query radius the world uses, and a query skips the cells wholly
/// beyond its radius: it looks at ~1.4 times the points in the circle instead of ~3 times with
/// radius-sized cells. The points of a row of cells lie together (compressed rows), so a query
/// reads one contiguous run per row.
pub struct PointGrid {
    cell: f64,
    cols: usize,
    rows: usize,
    /// The points of cell c are `in_cell[start[c]..start[c + 1]]`: (coordinates, index).
    start: Vec<u32>,
    in_cell: Vec<([f64; 2], u32)>,
    pub points: Vec<[f64; 2]>,
}

impl PointGrid {
    pub fn new(points: Vec<[f64; 2]>, width: f64, height: f64, cell: f64) -> PointGrid {
        let cell = cell.max(1.0);
        let cols = (width / cell).ceil() as usize + 1;
        let rows = (height / cell).ceil() as usize + 1;
        let cell_index = |p: [f64; 2]| {
            let (c, r) = Self::cell_of(cell, cols, rows, p);
            r * cols + c
        };
        let mut start = vec![0u32; cols * rows + 1];
        for p in &points {
            start[cell_index(*p) + 1] += 1;
        }
        for c in 0..cols * rows {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut in_cell = vec![([0.0; 2], 0); points.len()];
        for (i, p) in points.iter().enumerate() {
            let c = cell_index(*p);
            in_cell[next[c] as usize] = (*p, i as u32);
            next[c] += 1;
        }
        PointGrid {
            cell,
            cols,
            rows,
            start,
            in_cell,
            points,
        }
    }

    fn cell_of(cell: f64, cols: usize, rows: usize, p: [f64; 2]) -> (usize, usize) {
        let c = ((p[0] / cell).floor().max(0.0) as usize).min(cols - 1);
        let r = ((p[1] / cell).floor().max(0.0) as usize).min(rows - 1);
        (c, r)
    }

    /// How far `x` is from band `k` of cells ([k cell, (k + 1) cell); the outermost bands
    /// also hold the points beyond the grid, so they reach to infinity).
    fn gap(&self, x: f64, k: usize, last: usize) -> f64 {
        let lo = if k == 0 {
            f64::NEG_INFINITY
        } else {
            k as f64 * self.cell
        };
        let hi = if k == last {
            f64::INFINITY
        } else {
            (k + 1) as f64 * self.cell
        };
        (lo - x).max(x - hi).max(0.0)
    }

    /// Indices of points within `radius` of q, with their distances, in the grid's order (row
    /// by row of cells, then by cell, then by index).
    ///
    /// The cells of one row lie together in `in_cell`, so each row of cells that the circle
    /// reaches is one contiguous run of points, from the first to the last cell of the row
    /// within reach: no per-cell overhead, and an empty row costs two lookups.
    pub fn within(&self, q: [f64; 2], radius: f64, out: &mut Vec<(f64, u32)>) {
        let span = (radius / self.cell).ceil() as isize;
        let (_, r0) = Self::cell_of(self.cell, self.cols, self.rows, q);
        // A cell is skipped only if it lies beyond the radius by far more than the rounding of
        // a point's cell (floor(x / cell)) could misplace it.
        let reach = radius + self.cell * 1e-6;
        let reach2 = reach * reach;
        let last_col = self.cols - 1;
        for dr in -span..=span {
            let r = r0 as isize + dr;
            if r < 0 || r >= self.rows as isize {
                continue;
            }
            let gy = self.gap(q[1], r as usize, self.rows - 1);
            if gy * gy > reach2 {
                continue;
            }
            // Columns whose band comes within `w` of q[0]: those the circle reaches in this
            // row (the outermost bands reach to infinity, which the clamp gives them).
            let w = (reach2 - gy * gy).sqrt();
            let band = |x: f64| ((x / self.cell).floor().max(0.0) as usize).min(last_col);
            let (lo, hi) = (band(q[0] - w), band(q[0] + w));
            let row = r as usize * self.cols;
            let run =
                &self.in_cell[self.start[row + lo] as usize..self.start[row + hi + 1] as usize];
            for &(p, i) in run {
                if let Some(d) = within_radius(q, p, radius) {
                    out.push((d, i));
                }
            }
        }
    }
}

/// Keeps the `cap` nearest of (distance, index) pairs, ties by index, in no particular order
/// (but the same for the same input). The distances are never negative or NaN (those failed
/// `d <= radius`), so their bit patterns order as the numbers do.
fn keep_nearest(near: &mut Vec<(f64, u32)>, cap: usize) {
    debug_assert!(near.iter().all(|(d, _)| *d >= 0.0));
    if near.len() > cap {
        if cap > 0 {
            near.select_nth_unstable_by_key(cap - 1, |&(d, i)| (d.to_bits(), i));
        }
        near.truncate(cap);
    }
}

/// Cell size of the world's sensing grid of static points: a quarter of the sensing radius,
/// at least 2.5 units (so the grid stays a few cells per sensing disc).
pub fn grid_cell(sc: &Scenario) -> f64 {
    (sc.robot.sensing_radius / 4.0).max(2.5)
}

/// The static boundary points the robots can sense: obstacles, and the arena walls if sensed.
pub fn static_points(sc: &Scenario) -> Vec<[f64; 2]> {
    let mut pts = Vec::new();
    for o in &sc.arena.obstacles {
        pts.extend(sample_boundary(&o.points, sc.arena.boundary_spacing));
    }
    for d in &sc.arena.discs {
        pts.extend(d.boundary(sc.arena.boundary_spacing));
    }
    if sc.arena.walls_sensed {
        let (w, h) = (sc.arena.width, sc.arena.height);
        pts.extend(sample_boundary(
            &[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]],
            sc.arena.boundary_spacing,
        ));
    }
    pts
}

/// Scratch buffers reused across ticks (no allocation on the tick path once warm).
#[derive(Default)]
pub struct SenseScratch {
    near: Vec<(f64, u32)>,
}

/// Fills the obstacle-point list of `out`: static points and dead robots within the sensing
/// radius, at most MAX_OBSTACLE_POINTS (the nearest, ties by index, when more are in range).
///
/// The list is in no particular order, but in the same order for the same positions: its
/// users need it as a set (BSOA's angular scan sorts by angle, its forced case takes the two
/// nearest). Sorting it nearest first was ~11 % of an in-process search tick.
pub fn fill_obstacles(
    grid: &PointGrid,
    dead: &[[f64; 2]],
    q: [f64; 2],
    radius: f64,
    scratch: &mut SenseScratch,
    out: &mut Sense,
) {
    scratch.near.clear();
    grid.within(q, radius, &mut scratch.near);
    let base = grid.points.len() as u32;
    for (j, p) in dead.iter().enumerate() {
        if let Some(d) = within_radius(q, *p, radius) {
            scratch.near.push((d, base + j as u32));
        }
    }
    keep_nearest(&mut scratch.near, MAX_OBSTACLE_POINTS);
    let n = scratch.near.len();
    for (k, &(_, i)) in scratch.near.iter().enumerate() {
        out.obstacle_points[k] = if i < base {
            grid.points[i as usize]
        } else {
            dead[(i - base) as usize]
        };
    }
    out.n_obstacle_points = n as u32;
}

/// Fills the `nearby` list of robot `me`: live robots within `range` as its own sensors see
/// them (position and velocity), by robot id; the nearest MAX_NEARBY (ties by id) when more
/// are in range.
pub fn fill_nearby(
    me: usize,
    pos: &[[f64; 3]],
    vel: &[[f64; 2]],
    alive: &[bool],
    range: f64,
    scratch: &mut SenseScratch,
    out: &mut Sense,
) {
    scratch.near.clear();
    let q = [pos[me][0], pos[me][1]];
    for (j, p) in pos.iter().enumerate() {
        if j == me || !alive[j] {
            continue;
        }
        if let Some(d) = within_radius(q, [p[0], p[1]], range) {
            scratch.near.push((d, j as u32));
        }
    }
    keep_nearest(&mut scratch.near, MAX_NEARBY);
    scratch.near.sort_unstable_by_key(|&(_, j)| j);
    for (k, &(_, j)) in scratch.near.iter().enumerate() {
        let p = pos[j as usize];
        out.nearby[k] = Nearby {
            robot: j,
            reserved: 0,
            pos: [p[0], p[1]],
            vel: vel[j as usize],
        };
    }
    out.n_nearby = scratch.near.len() as u32;
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarm::radio::distance;

    #[test]
    fn grid_query_matches_brute_force() {
        let pts: Vec<[f64; 2]> = (0..2000)
            .map(|i| [((i * 37) % 1000) as f64, ((i * 91) % 1000) as f64])
            .collect();
        let mut pts = pts;
        // Points on cell borders and beyond the grid.
        pts.extend([
            [25.0, 50.0],
            [-30.0, 20.0],
            [1040.0, 990.0],
            [500.0, 1100.0],
        ]);
        for cell in [100.0, 25.0, 7.0] {
            let g = PointGrid::new(pts.clone(), 1000.0, 1000.0, cell);
            for q in [
                [0.0, 0.0],
                [500.0, 500.0],
                [999.0, 3.0],
                [250.5, 730.2],
                [-20.0, 10.0],
                [1030.0, 1000.0],
                [125.0, 25.0],
            ] {
                let mut got = vec![];
                g.within(q, 100.0, &mut got);
                let mut got: Vec<u32> = got.into_iter().map(|x| x.1).collect();
                got.sort();
                let want: Vec<u32> = (0..pts.len() as u32)
                    .filter(|&i| distance(q, pts[i as usize]) <= 100.0)
                    .collect();
                assert_eq!(got, want, "cell {cell} q {q:?}");
            }
        }
    }

    #[test]
    fn keep_nearest_keeps_the_nearest_set_ties_by_index() {
        // Distances 5, 1, 3, 1, 4, 2, 3 at indices 0..7.
        let all: Vec<(f64, u32)> = [5.0, 1.0, 3.0, 1.0, 4.0, 2.0, 3.0]
            .iter()
            .enumerate()
            .map(|(i, d)| (*d, i as u32))
            .collect();
        let kept = |cap: usize| {
            let mut v = all.clone();
            keep_nearest(&mut v, cap);
            let mut ids: Vec<u32> = v.iter().map(|x| x.1).collect();
            ids.sort();
            ids
        };
        assert_eq!(kept(3), vec![1, 3, 5]);
        // The tie at distance 3 goes to the lower index.
        assert_eq!(kept(4), vec![1, 2, 3, 5]);
        assert_eq!(kept(0), Vec::<u32>::new());
        // Not over the cap: everything, in the order given.
        let mut v = all.clone();
        keep_nearest(&mut v, 7);
        assert_eq!(v, all);
    }
}
