//! Shared helpers of the formation tests: seeded random starts, every permutation.

use super::params::FormationParams;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use swarm::geometry::Vec2;

/// `n` start positions, uniform in the box (kept a radius from its walls), pairwise at least
/// 2r + `gap` apart and at least r_o + r + `gap` from every obstacle, from a seeded stream.
pub fn random_starts(seed: u64, n: usize, params: &FormationParams, gap: f64) -> Vec<Vec2> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let r = params.robot_radius;
    let obstacles: Vec<Vec2> = params
        .obstacle_centres
        .iter()
        .map(|c| Vec2::new(c[0], c[1]))
        .collect();
    let mut starts: Vec<Vec2> = Vec::with_capacity(n);
    while starts.len() < n {
        let p = Vec2::new(
            rng.gen_range(params.box_min[0] + r..params.box_max[0] - r),
            rng.gen_range(params.box_min[1] + r..params.box_max[1] - r),
        );
        let clear_of_robots = starts.iter().all(|q| (p - q).norm() >= 2.0 * r + gap);
        let clear_of_obstacles = obstacles
            .iter()
            .all(|o| (p - o).norm() >= params.obstacle_radius + r + gap);
        if clear_of_robots && clear_of_obstacles {
            starts.push(p);
        }
    }
    starts
}

/// Calls `f` on each of the n! permutations of 0..n (Heap's algorithm).
pub fn for_each_permutation(n: usize, mut f: impl FnMut(&[usize])) {
    let mut perm: Vec<usize> = (0..n).collect();
    f(&perm);
    let mut c = vec![0usize; n];
    let mut i = 0;
    while i < n {
        if c[i] < i {
            if i % 2 == 0 {
                perm.swap(0, i);
            } else {
                perm.swap(c[i], i);
            }
            f(&perm);
            c[i] += 1;
            i = 0;
        } else {
            c[i] = 0;
            i += 1;
        }
    }
}
