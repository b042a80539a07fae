//! Robot bodies: discs of `robot.radius`. How far a disc is from obstacles and walls, whether a
//! place is clear for it, and the clearances and overlaps of a whole swarm at one tick.

use swarm::geometry::{point_in_polygon, polygon_distance, Vec2};
use swarm::recording::BodyFigures;
use swarm::scenario::Scenario;

/// The static things a disc can hit: the arena's walls and its obstacles (with bounding boxes,
/// so that far obstacles cost a box test).
pub struct Statics {
    width: f64,
    height: f64,
    obstacles: Vec<(Vec<[f64; 2]>, [f64; 4])>,
    /// Disc obstacles (`arena.discs`): exact circles.
    discs: Vec<swarm::scenario::DiscObstacle>,
}

/// (min x, min y, max x, max y) of a polygon.
pub fn bounding_box(points: &[[f64; 2]]) -> [f64; 4] {
    points.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        },
    )
}

/// Distance from `p` to the box `b` (0 inside).
fn box_distance(p: [f64; 2], b: &[f64; 4]) -> f64 {
    let dx = (b[0] - p[0]).max(p[0] - b[2]).max(0.0);
    let dy = (b[1] - p[1]).max(p[1] - b[3]).max(0.0);
    (dx * dx + dy * dy).sqrt()
}

/// The scenario's obstacles with their bounding boxes.
pub fn boxed_obstacles(sc: &Scenario) -> Vec<(Vec<[f64; 2]>, [f64; 4])> {
    sc.arena
        .obstacles
        .iter()
        .map(|o| (o.points.clone(), bounding_box(&o.points)))
        .collect()
}

impl Statics {
    pub fn new(sc: &Scenario) -> Statics {
        Statics {
            width: sc.arena.width,
            height: sc.arena.height,
            obstacles: boxed_obstacles(sc),
            discs: sc.arena.discs.clone(),
        }
    }

    /// Signed distance from point `p` to the nearest wall or obstacle boundary: positive in
    /// free space, negative inside an obstacle or outside the arena.
    pub fn clearance(&self, p: [f64; 2]) -> f64 {
        let walls = p[0]
            .min(p[1])
            .min(self.width - p[0])
            .min(self.height - p[1]);
        let mut best = walls;
        for d in &self.discs {
            best = best.min(d.distance(p));
        }
        for (poly, b) in &self.obstacles {
            if box_distance(p, b) >= best {
                continue;
            }
            let q = Vec2::new(p[0], p[1]);
            let d = polygon_distance(q, poly);
            let d = if point_in_polygon(q, poly) { -d } else { d };
            best = best.min(d);
        }
        best
    }

    /// A disc of radius `r` at `p` touches no obstacle and stays in the arena.
    pub fn disc_clear(&self, p: [f64; 2], r: f64) -> bool {
        self.clearance(p) >= r
    }
}

/// The smallest centre distance over all pairs of `points` (infinite for fewer than two) and
/// the number of pairs closer than `overlap` (a sweep along x: each point is compared only
/// with those within the best distance so far, or within `overlap`, in x).
pub fn closest_pairs(points: &[[f64; 2]], overlap: f64) -> (f64, u32) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_unstable_by(|&a, &b| points[a][0].total_cmp(&points[b][0]).then(a.cmp(&b)));
    let mut best = f64::INFINITY;
    let mut pairs = 0u32;
    for (k, &i) in order.iter().enumerate() {
        let p = points[i];
        for &j in &order[k + 1..] {
            let q = points[j];
            let dx = q[0] - p[0];
            if dx >= best && dx >= overlap {
                break;
            }
            let d = (dx * dx + (q[1] - p[1]).powi(2)).sqrt();
            best = best.min(d);
            if d < overlap {
                pairs += 1;
            }
        }
    }
    (best, pairs)
}

/// The body figures of robots of radius `r` at `poses` (every robot, dead ones included).
pub fn figures(statics: &Statics, poses: &[[f64; 3]], r: f64) -> BodyFigures {
    let points: Vec<[f64; 2]> = poses.iter().map(|p| [p[0], p[1]]).collect();
    let (closest, overlapping_pairs) = closest_pairs(&points, 2.0 * r);
    let mut min_obstacle_clearance = f64::INFINITY;
    let mut obstacle_overlaps = 0;
    for p in &points {
        let c = statics.clearance(*p) - r;
        min_obstacle_clearance = min_obstacle_clearance.min(c);
        obstacle_overlaps += (c < 0.0) as u32;
    }
    BodyFigures {
        min_robot_clearance: closest - 2.0 * r,
        min_obstacle_clearance,
        overlapping_pairs,
        obstacle_overlaps,
    }
}

/// The run's worst figures so far, for the summary.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct BodySummary {
    pub radius: f64,
    /// Smallest robot-robot clearance over the whole run (negative: an overlap happened).
    pub min_robot_clearance: f64,
    /// Smallest robot-obstacle clearance over the whole run.
    pub min_obstacle_clearance: f64,
    /// Most overlapping robot pairs at one tick.
    pub max_overlapping_pairs: u32,
    /// Ticks with at least one overlapping pair.
    pub ticks_with_overlap: u64,
    /// Most robots overlapping an obstacle or a wall at one tick.
    pub max_obstacle_overlaps: u32,
}

impl BodySummary {
    pub fn new(radius: f64) -> BodySummary {
        BodySummary {
            radius,
            min_robot_clearance: f64::INFINITY,
            min_obstacle_clearance: f64::INFINITY,
            max_overlapping_pairs: 0,
            ticks_with_overlap: 0,
            max_obstacle_overlaps: 0,
        }
    }
    pub fn add(&mut self, f: &BodyFigures) {
        self.min_robot_clearance = self.min_robot_clearance.min(f.min_robot_clearance);
        self.min_obstacle_clearance = self.min_obstacle_clearance.min(f.min_obstacle_clearance);
        self.max_overlapping_pairs = self.max_overlapping_pairs.max(f.overlapping_pairs);
        self.ticks_with_overlap += (f.overlapping_pairs > 0) as u64;
        self.max_obstacle_overlaps = self.max_obstacle_overlaps.max(f.obstacle_overlaps);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn disc_obstacles_are_exact_circles_in_the_clearance() {
        let mut sc = Scenario::roam();
        sc.arena.obstacles.clear();
        sc.arena.discs.push(swarm::scenario::DiscObstacle {
            name: "d".into(),
            centre: [50.0, 50.0],
            radius: 2.0,
        });
        let st = Statics::new(&sc);
        // 5 from the centre: 3 outside the circle; 1 from it: 1 inside.
        assert!((st.clearance([55.0, 50.0]) - 3.0).abs() < 1e-12);
        assert!((st.clearance([50.0, 51.0]) + 1.0).abs() < 1e-12);
        assert!(!st.disc_clear([53.5, 50.0], 2.0));
        assert!(st.disc_clear([54.0, 50.0], 2.0));
    }

    #[test]
    fn closest_pairs_matches_all_pairs() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [0, 1, 2, 3, 10, 60] {
            for _ in 0..20 {
                let pts: Vec<[f64; 2]> = (0..n)
                    .map(|_| [rng.gen_range(0.0..50.0), rng.gen_range(0.0..50.0)])
                    .collect();
                let overlap = rng.gen_range(0.0..8.0);
                let mut best = f64::INFINITY;
                let mut pairs = 0;
                for i in 0..n {
                    for j in i + 1..n {
                        let d = ((pts[i][0] - pts[j][0]).powi(2) + (pts[i][1] - pts[j][1]).powi(2))
                            .sqrt();
                        best = best.min(d);
                        pairs += (d < overlap) as u32;
                    }
                }
                let (b, p) = closest_pairs(&pts, overlap);
                assert_eq!(p, pairs, "n {n}");
                assert!(
                    b == best || (b - best).abs() < 1e-12,
                    "n {n}: {b} vs {best}"
                );
            }
        }
    }

    #[test]
    fn figures_of_two_touching_discs_and_a_wall() {
        let mut sc = Scenario::roam();
        sc.arena.obstacles.clear();
        let st = Statics::new(&sc);
        // Radius 1: centres 1.5 apart overlap by 0.5; the first disc is 0.5 from the wall x = 0.
        let f = figures(
            &st,
            &[[1.5, 50.0, 0.0], [3.0, 50.0, 0.0], [60.0, 60.0, 0.0]],
            1.0,
        );
        assert!((f.min_robot_clearance + 0.5).abs() < 1e-12, "{f:?}");
        assert_eq!(f.overlapping_pairs, 1);
        assert!((f.min_obstacle_clearance - 0.5).abs() < 1e-12, "{f:?}");
        assert_eq!(f.obstacle_overlaps, 0);
        let f = figures(&st, &[[0.5, 50.0, 0.0]], 1.0);
        assert_eq!(f.obstacle_overlaps, 1);
        assert!(f.min_robot_clearance.is_infinite());
    }

    #[test]
    fn clearance_is_negative_inside_an_obstacle() {
        let sc = Scenario::default();
        let st = Statics::new(&sc);
        let block = &sc.arena.obstacles[0].points;
        let b = bounding_box(block);
        let centre = [(b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0];
        assert!(point_in_polygon(Vec2::new(centre[0], centre[1]), block));
        assert!(st.clearance(centre) < 0.0);
        assert!(!st.disc_clear(centre, 0.0));
    }
}
