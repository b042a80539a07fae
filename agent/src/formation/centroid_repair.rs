//! The nearest feasible centroid for one shape (ours; not in the paper, whose MILP solver finds
//! its own feasible points).
//!
//! With the scale and rotation fixed (A of eq. 5) and the assignment exact, eq. (14)'s cost is
//! g(A) + n |p_bar - c|^2 in the pattern's centroid c (optimise.rs, module comment), so the
//! best c is the one nearest p_bar among those that meet C1 and C2. C1 keeps c in a rectangle;
//! C2 keeps it out of one forbidden region per (target, obstacle) pair: the obstacle's square
//! (eq. 12) or disc (eq. 10) moved by -A s~_j. The nearest point of a rectangle less a union of
//! squares or discs is p_bar itself, or lies on the boundary of a forbidden region or of the
//! rectangle: a projection of p_bar onto one, or a corner where two of them meet. Every such
//! candidate is tried.
//!
//! Why: the branch-and-bound tries only a node's midpoint and p_bar clamped to the node as
//! incumbents. Where the unconstrained optimum lies in an obstacle, both stay infeasible in
//! every node near it, and the tight polygon bound (alignment.rs) keeps the search there:
//! configs/formation.toml seed 3, coordinator killed at tick 15, the re-plan for 8 robots split
//! 400 000 nodes without one feasible point and reported no placement (a grid finds 1 701).

use super::constraints::{PatternConstraints, SLACK};
use super::params::ObstacleConstraint;
use swarm::geometry::Vec2;

/// Above this many forbidden regions only the projections are tried (the corners where two
/// regions meet grow with the square of their number).
pub const MAX_PAIRWISE: usize = 64;

/// The centroid c nearest `p_bar` within `cbox` (\[x range, y range\]) for which every target
/// `offsets[j] + c` meets C1 and C2 of `cons`; None when no candidate does. `offsets` are
/// A s~_j, the targets relative to the centroid. Adds the work done (candidates tried times
/// the checks of each) to `work`: only the regions that meet `cbox` make candidates, so a
/// small box costs little.
pub fn nearest_feasible_centroid(
    offsets: &[Vec2],
    cons: &PatternConstraints,
    p_bar: Vec2,
    cbox: [[f64; 2]; 2],
    work: &mut f64,
) -> Option<Vec2> {
    // C1 exactly: every target in the box.
    let mut r = cbox;
    for o in offsets {
        r[0][0] = r[0][0].max(cons.x_range[0] - o.x);
        r[0][1] = r[0][1].min(cons.x_range[1] - o.x);
        r[1][0] = r[1][0].max(cons.y_range[0] - o.y);
        r[1][1] = r[1][1].min(cons.y_range[1] - o.y);
    }
    if r[0][0] > r[0][1] || r[1][0] > r[1][1] {
        return None;
    }
    let k = cons.keep_out;
    // Forbidden regions of c: centred at obstacle - offset, half-size (or radius) k.
    let centres: Vec<Vec2> = offsets
        .iter()
        .flat_map(|o| cons.obstacles.iter().map(move |ob| ob - o))
        .filter(|c| {
            c.x > r[0][0] - k && c.x < r[0][1] + k && c.y > r[1][0] - k && c.y < r[1][1] + k
        })
        .collect();
    let clamp = |q: Vec2| Vec2::new(q.x.clamp(r[0][0], r[0][1]), q.y.clamp(r[1][0], r[1][1]));
    let free = |c: Vec2| {
        offsets
            .iter()
            .all(|o| cons.in_box(o + c) && cons.clear_of_obstacles(o + c))
    };
    let mut candidates = vec![clamp(p_bar)];
    let square = cons.obstacle_form == ObstacleConstraint::Square;
    for c in &centres {
        if square {
            for sx in [-k, k] {
                candidates.push(Vec2::new(c.x + sx, p_bar.y.clamp(c.y - k, c.y + k)));
                candidates.push(Vec2::new(p_bar.x.clamp(c.x - k, c.x + k), c.y + sx));
                for sy in [-k, k] {
                    candidates.push(Vec2::new(c.x + sx, c.y + sy));
                }
                // Where the square's edges meet the rectangle's.
                candidates.push(Vec2::new(c.x + sx, r[1][0]));
                candidates.push(Vec2::new(c.x + sx, r[1][1]));
                candidates.push(Vec2::new(r[0][0], c.y + sx));
                candidates.push(Vec2::new(r[0][1], c.y + sx));
            }
        } else {
            let d = p_bar - c;
            let dir = if d.norm() > 0.0 {
                d / d.norm()
            } else {
                Vec2::new(1.0, 0.0)
            };
            candidates.push(c + dir * (k + SLACK));
            // Where the circle meets the rectangle's edges.
            for x in r[0] {
                let h = k * k - (x - c.x) * (x - c.x);
                if h >= 0.0 {
                    let h = h.sqrt() + SLACK;
                    candidates.extend([Vec2::new(x, c.y - h), Vec2::new(x, c.y + h)]);
                }
            }
            for y in r[1] {
                let h = k * k - (y - c.y) * (y - c.y);
                if h >= 0.0 {
                    let h = h.sqrt() + SLACK;
                    candidates.extend([Vec2::new(c.x - h, y), Vec2::new(c.x + h, y)]);
                }
            }
        }
    }
    if centres.len() <= MAX_PAIRWISE {
        for (i, a) in centres.iter().enumerate() {
            for b in &centres[i + 1..] {
                if square {
                    for s in [-k, k] {
                        for t in [-k, k] {
                            candidates.push(Vec2::new(a.x + s, b.y + t));
                            candidates.push(Vec2::new(b.x + s, a.y + t));
                        }
                    }
                } else {
                    candidates.extend(circle_crossings(*a, *b, k));
                }
            }
        }
    }
    *work += (candidates.len() * (offsets.len() * (1 + cons.obstacles.len()))) as f64;
    let mut best: Option<(f64, Vec2)> = None;
    for q in candidates {
        let q = clamp(q);
        let d = (q - p_bar).norm_squared();
        if best.is_some_and(|(bd, _)| bd <= d) {
            continue;
        }
        if free(q) {
            best = Some((d, q));
        }
    }
    best.map(|(_, q)| q)
}

/// The points where two circles of radius `k` round `a` and `b` cross, pushed out by SLACK
/// (so that they pass the tolerant test of C2).
fn circle_crossings(a: Vec2, b: Vec2, k: f64) -> Vec<Vec2> {
    let d = (b - a).norm();
    if d == 0.0 || d > 2.0 * k {
        return Vec::new();
    }
    let mid = (a + b) * 0.5;
    let h = (k * k - 0.25 * d * d).max(0.0).sqrt() + SLACK;
    let n = Vec2::new(a.y - b.y, b.x - a.x) / d;
    vec![mid + n * h, mid - n * h]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formation::params::FormationParams;

    fn cons(form: ObstacleConstraint, obstacles: Vec<[f64; 2]>) -> PatternConstraints {
        PatternConstraints::new(&FormationParams {
            obstacle_centres: obstacles,
            obstacle_margin: 0.0,
            obstacle_constraint: form,
            ..FormationParams::default()
        })
    }

    /// The nearest feasible centroid by brute force on a fine grid (for the test only).
    fn grid_nearest(offsets: &[Vec2], c: &PatternConstraints, p: Vec2, step: f64) -> f64 {
        let mut best = f64::INFINITY;
        for i in 0..=(24.0 / step) as usize {
            for j in 0..=(24.0 / step) as usize {
                let q = Vec2::new(i as f64 * step, j as f64 * step);
                if offsets
                    .iter()
                    .all(|o| c.in_box(o + q) && c.clear_of_obstacles(o + q))
                {
                    best = best.min((q - p).norm());
                }
            }
        }
        best
    }

    #[test]
    fn the_nearest_free_centroid_is_never_farther_than_a_fine_grid_finds() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let whole = [[-100.0, 100.0], [-100.0, 100.0]];
        for form in [ObstacleConstraint::Square, ObstacleConstraint::Circle] {
            for _ in 0..40 {
                let obstacles: Vec<[f64; 2]> = (0..rng.gen_range(1..4))
                    .map(|_| [rng.gen_range(4.0..20.0), rng.gen_range(4.0..20.0)])
                    .collect();
                let c = cons(form, obstacles);
                let offsets: Vec<Vec2> = (0..rng.gen_range(1..6))
                    .map(|_| Vec2::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0)))
                    .collect();
                let p = Vec2::new(rng.gen_range(2.0..22.0), rng.gen_range(2.0..22.0));
                let grid = grid_nearest(&offsets, &c, p, 0.05);
                match nearest_feasible_centroid(&offsets, &c, p, whole, &mut 0.0) {
                    Some(q) => {
                        assert!(offsets
                            .iter()
                            .all(|o| c.in_box(o + q) && c.clear_of_obstacles(o + q)));
                        // The grid's point is feasible, so ours is at most as far (grid cells
                        // are 0.05: the grid may be up to a diagonal farther than the truth).
                        assert!(
                            (q - p).norm() <= grid + 1e-9,
                            "{form:?}: {} vs grid {grid}",
                            (q - p).norm()
                        );
                    }
                    None => assert!(grid.is_infinite(), "{form:?}: grid found {grid}"),
                }
            }
        }
    }

    #[test]
    fn a_free_p_bar_is_its_own_answer_and_a_box_too_small_has_none() {
        let c = cons(ObstacleConstraint::Square, vec![[20.0, 20.0]]);
        let p = Vec2::new(5.0, 5.0);
        let whole = [[-100.0, 100.0], [-100.0, 100.0]];
        assert_eq!(
            nearest_feasible_centroid(&[Vec2::zeros()], &c, p, whole, &mut 0.0),
            Some(p)
        );
        // Targets 30 apart cannot both be in the 24 box.
        let wide = [Vec2::new(-15.0, 0.0), Vec2::new(15.0, 0.0)];
        assert_eq!(
            nearest_feasible_centroid(&wide, &c, p, whole, &mut 0.0),
            None
        );
    }
}
