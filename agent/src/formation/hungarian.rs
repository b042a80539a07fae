//! The minimum-cost assignment (the linear sum assignment problem of eqs. 1-3 and 15), by the
//! Hungarian method (Kuhn 1955, the paper's ref. \[20\]) in its O(n^3) shortest-augmenting-path
//! form with row and column potentials. Our own f64 implementation: `pathfinding`'s
//! kuhn_munkres needs integer (Ord) weights, and scaling real costs to integers would make the
//! branch-and-bound's bounds inexact; the tests check this one against it and against brute
//! force.
//!
//! The paper's cost (sec. 2.1, eq. 15) is k_ij = -p_i . q_j. We use it where the paper does
//! (the per-step reassignment, [`assign_targets`]); it gives the same assignment as the squared
//! distance c_ij = ||p_i - q_j||^2 of eq. (4), because sum_i ||p_i||^2 and sum_j ||q_j||^2 are the
//! same for every permutation (eq. 7) — a test shows the two agree.

use super::FormationError;
use swarm::geometry::Vec2;

/// A reusable Hungarian solver (its buffers are kept between calls).
#[derive(Debug, Default, Clone)]
pub struct Hungarian {
    u: Vec<f64>,
    v: Vec<f64>,
    p: Vec<usize>,
    way: Vec<usize>,
    minv: Vec<f64>,
    used: Vec<bool>,
    /// The cost matrix buffer of [`Hungarian::solve_with`].
    scratch: Vec<f64>,
    /// Solves made by this solver.
    solves: usize,
    /// Rows the last solve augmented.
    augmented: usize,
}

impl Hungarian {
    /// A solver with empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// Solves made by this solver.
    pub fn solves(&self) -> usize {
        self.solves
    }

    /// The column potential v_j of the last solve: the dual solution satisfies
    /// u_i + v_j <= cost(i, j) for all (i, j), with equality on the assignment.
    pub fn column_potential(&self, column: usize) -> f64 {
        self.v[column + 1]
    }

    /// Minimum-cost perfect assignment of an n x n cost given as a function of (row, column).
    /// Writes `assignment\[row\] = column` and returns the total cost. Costs must be finite
    /// (not checked here, for speed; [`solve`] checks). Ties go to the lowest column index.
    pub fn solve_with(
        &mut self,
        n: usize,
        cost: impl Fn(usize, usize) -> f64,
        assignment: &mut Vec<usize>,
    ) -> f64 {
        self.solve_fn(n, cost, None, assignment)
    }

    /// A cold or warm solve of a cost given as a function: its row-major matrix is computed
    /// once into the scratch buffer (the solver reads each entry O(n) times).
    fn solve_fn(
        &mut self,
        n: usize,
        cost: impl Fn(usize, usize) -> f64,
        warm: Option<(&[usize], &[f64])>,
        assignment: &mut Vec<usize>,
    ) -> f64 {
        let mut matrix = std::mem::take(&mut self.scratch);
        matrix.clear();
        matrix.extend((0..n * n).map(|k| cost(k / n, k % n)));
        let total = self.solve_matrix_from(n, &matrix, warm, assignment);
        self.scratch = matrix;
        total
    }

    /// [`Self::solve_with`] on a row-major n x n matrix.
    pub fn solve_matrix(&mut self, n: usize, cost: &[f64], assignment: &mut Vec<usize>) -> f64 {
        self.solve_matrix_from(n, cost, None, assignment)
    }

    /// [`Self::solve_with`], warm-started from a nearby problem's optimal assignment and column
    /// potentials (`warm = (assignment, potentials)`, e.g. the same instance at a nearby
    /// direction): with the columns' potentials kept, u_i = min_j (c_ij - v_j) is dual
    /// feasible, every row whose old column attains its minimum stays matched (tight), and
    /// only the others are augmented, O(k n^2) for k of them instead of O(n^3). The answer is
    /// an optimal assignment like a cold solve's (ties may break differently).
    pub fn solve_warm_with(
        &mut self,
        n: usize,
        cost: impl Fn(usize, usize) -> f64,
        warm: (&[usize], &[f64]),
        assignment: &mut Vec<usize>,
    ) -> f64 {
        self.solve_fn(n, cost, Some(warm), assignment)
    }

    /// The column potentials v_1..v_n of the last solve (to warm-start a later one).
    pub fn column_potentials(&self) -> &[f64] {
        &self.v[1..]
    }

    /// Rows the last solve augmented (n for a cold solve).
    pub fn augmented_rows(&self) -> usize {
        self.augmented
    }

    fn solve_matrix_from(
        &mut self,
        n: usize,
        cost: &[f64],
        warm: Option<(&[usize], &[f64])>,
        assignment: &mut Vec<usize>,
    ) -> f64 {
        assert_eq!(cost.len(), n * n, "the cost matrix must be n x n");
        assignment.clear();
        assignment.resize(n, 0);
        self.solves += 1;
        if n == 0 {
            return 0.0;
        }
        // 1-based: column 0 and row 0 are the virtual start of each augmenting path.
        self.u.clear();
        self.u.resize(n + 1, 0.0);
        self.v.clear();
        self.v.resize(n + 1, 0.0);
        self.p.clear();
        self.p.resize(n + 1, 0);
        self.way.clear();
        self.way.resize(n + 1, 0);
        let mut free = Vec::new();
        match warm {
            Some((sigma, v)) if sigma.len() == n && v.len() == n => {
                self.v[1..].copy_from_slice(v);
                for (i, &k) in sigma.iter().enumerate() {
                    let row = &cost[i * n..(i + 1) * n];
                    let least = row
                        .iter()
                        .zip(v)
                        .map(|(c, vj)| c - vj)
                        .fold(f64::INFINITY, f64::min);
                    let own = row[k] - v[k];
                    if own <= least && self.p[k + 1] == 0 {
                        self.u[i + 1] = own;
                        self.p[k + 1] = i + 1;
                    } else {
                        self.u[i + 1] = least;
                        free.push(i + 1);
                    }
                }
            }
            _ => free.extend(1..=n),
        }
        self.augmented = free.len();
        for row in free {
            self.p[0] = row;
            let mut j0 = 0;
            self.minv.clear();
            self.minv.resize(n + 1, f64::INFINITY);
            self.used.clear();
            self.used.resize(n + 1, false);
            loop {
                self.used[j0] = true;
                let i0 = self.p[j0];
                let ui0 = self.u[i0];
                let costs = &cost[(i0 - 1) * n..i0 * n];
                let mut delta = f64::INFINITY;
                let mut j1 = 0;
                // Columns 1..=n, zipped so that the hot loop has no bounds checks.
                let columns = self.used[1..]
                    .iter()
                    .zip(&mut self.minv[1..])
                    .zip(&self.v[1..])
                    .zip(&mut self.way[1..])
                    .zip(costs);
                for (j, ((((used, minv), v), way), c)) in columns.enumerate() {
                    if !*used {
                        let reduced = c - ui0 - v;
                        if reduced < *minv {
                            *minv = reduced;
                            *way = j0;
                        }
                        if *minv < delta {
                            delta = *minv;
                            j1 = j + 1;
                        }
                    }
                }
                for j in 0..=n {
                    if self.used[j] {
                        self.u[self.p[j]] += delta;
                        self.v[j] -= delta;
                    } else {
                        self.minv[j] -= delta;
                    }
                }
                j0 = j1;
                if self.p[j0] == 0 {
                    break;
                }
            }
            // Augment along the path back to the virtual column 0.
            loop {
                let j1 = self.way[j0];
                self.p[j0] = self.p[j1];
                j0 = j1;
                if j0 == 0 {
                    break;
                }
            }
        }
        for j in 1..=n {
            assignment[self.p[j] - 1] = j - 1;
        }
        assignment
            .iter()
            .enumerate()
            .map(|(i, &j)| cost[i * n + j])
            .sum()
    }
}

/// Minimum-cost assignment of a row-major n x n cost matrix: (assignment\[row\] = column, cost).
pub fn solve(cost: &[f64], n: usize) -> Result<(Vec<usize>, f64), FormationError> {
    if cost.len() != n * n {
        return Err(FormationError::SizeMismatch {
            template: cost.len(),
            robots: n * n,
        });
    }
    if cost.iter().any(|c| !c.is_finite()) {
        return Err(FormationError::NonFinite("assignment cost"));
    }
    let mut assignment = Vec::new();
    let total = Hungarian::new().solve_matrix(n, cost, &mut assignment);
    Ok((assignment, total))
}

/// The per-step reassignment of eq. (15): robot i -> target assignment\[i\], minimising
/// sum_i -p_i . q_sigma(i) over the current positions and the fixed targets G*.
pub fn assign_targets(
    positions: &[Vec2],
    targets: &[Vec2],
    solver: &mut Hungarian,
    assignment: &mut Vec<usize>,
) -> Result<(), FormationError> {
    if positions.len() != targets.len() {
        return Err(FormationError::SizeMismatch {
            template: targets.len(),
            robots: positions.len(),
        });
    }
    if positions
        .iter()
        .chain(targets)
        .any(|p| !p.x.is_finite() || !p.y.is_finite())
    {
        return Err(FormationError::NonFinite("positions or targets"));
    }
    solver.solve_with(
        positions.len(),
        |i, j| -positions[i].dot(&targets[j]),
        assignment,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use pathfinding::prelude::{kuhn_munkres_min, Matrix};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The minimum over all n! permutations.
    fn brute_force(cost: &[f64], n: usize) -> f64 {
        let mut best = f64::INFINITY;
        crate::formation::test_support::for_each_permutation(n, |p| {
            best = best.min((0..n).map(|i| cost[i * n + p[i]]).sum::<f64>());
        });
        best
    }

    fn is_permutation(a: &[usize]) -> bool {
        let mut seen = vec![false; a.len()];
        a.iter()
            .all(|&j| j < a.len() && !std::mem::replace(&mut seen[j], true))
    }

    #[test]
    fn hand_computed_three_by_three() {
        // Rows: [4 1 3; 2 0 5; 3 2 2]. Optimum 1 + 2 + 2 = 5 with rows -> columns (1, 0, 2).
        let cost = [4.0, 1.0, 3.0, 2.0, 0.0, 5.0, 3.0, 2.0, 2.0];
        let (a, total) = solve(&cost, 3).unwrap();
        assert_eq!(a, vec![1, 0, 2]);
        assert_eq!(total, 5.0);
    }

    #[test]
    fn matches_brute_force_for_n_up_to_7() {
        let mut rng = ChaCha8Rng::seed_from_u64(16);
        for n in 1..=7 {
            for _ in 0..60 {
                let cost: Vec<f64> = (0..n * n).map(|_| rng.gen_range(-10.0..10.0)).collect();
                let (a, total) = solve(&cost, n).unwrap();
                assert!(is_permutation(&a));
                let direct: f64 = (0..n).map(|i| cost[i * n + a[i]]).sum();
                assert!((direct - total).abs() < 1e-9);
                assert!((total - brute_force(&cost, n)).abs() < 1e-9, "n = {n}");
            }
        }
    }

    #[test]
    fn matches_pathfinding_kuhn_munkres_on_integer_costs() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        for n in [1, 2, 5, 9, 30, 100] {
            for _ in 0..5 {
                let ints: Vec<i64> = (0..n * n).map(|_| rng.gen_range(-1000..1000)).collect();
                let matrix = Matrix::from_vec(n, n, ints.clone()).unwrap();
                let (theirs, _) = kuhn_munkres_min(&matrix);
                let costs: Vec<f64> = ints.iter().map(|&c| c as f64).collect();
                let (a, total) = solve(&costs, n).unwrap();
                assert!(is_permutation(&a));
                assert_eq!(total as i64, theirs, "n = {n}");
            }
        }
    }

    #[test]
    fn dot_product_cost_gives_the_squared_distance_assignment() {
        let mut rng = ChaCha8Rng::seed_from_u64(18);
        let mut solver = Hungarian::new();
        let mut by_dot = Vec::new();
        for n in [3, 9, 40] {
            for _ in 0..20 {
                let pts = |rng: &mut ChaCha8Rng| -> Vec<Vec2> {
                    (0..n)
                        .map(|_| Vec2::new(rng.gen_range(0.0..24.0), rng.gen_range(0.0..24.0)))
                        .collect()
                };
                let p = pts(&mut rng);
                let q = pts(&mut rng);
                assign_targets(&p, &q, &mut solver, &mut by_dot).unwrap();
                let sq: Vec<f64> = (0..n * n)
                    .map(|k| (p[k / n] - q[k % n]).norm_squared())
                    .collect();
                let (by_sq, best) = solve(&sq, n).unwrap();
                let cost_of = |a: &[usize]| (0..n).map(|i| sq[i * n + a[i]]).sum::<f64>();
                // Same optimal value (and, barring exact ties, the same permutation).
                assert!((cost_of(&by_dot) - best).abs() < 1e-7);
                assert_eq!(by_dot, by_sq);
            }
        }
    }

    #[test]
    fn potentials_are_dual_feasible_and_tight() {
        let mut rng = ChaCha8Rng::seed_from_u64(19);
        let n = 8;
        let cost: Vec<f64> = (0..n * n).map(|_| rng.gen_range(-5.0..5.0)).collect();
        let mut h = Hungarian::new();
        let mut a = Vec::new();
        let total = h.solve_with(n, |i, j| cost[i * n + j], &mut a);
        // u_i = min_j (c_ij - v_j) is then dual feasible; the dual value must equal the cost.
        let dual: f64 = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| cost[i * n + j] - h.column_potential(j))
                    .fold(f64::INFINITY, f64::min)
            })
            .sum::<f64>()
            + (0..n).map(|j| h.column_potential(j)).sum::<f64>();
        assert!((dual - total).abs() < 1e-9, "{dual} vs {total}");
    }

    #[test]
    fn rejects_non_finite_costs() {
        assert_eq!(
            solve(&[f64::NAN], 1),
            Err(FormationError::NonFinite("assignment cost"))
        );
    }
}
