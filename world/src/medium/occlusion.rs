//! Line-of-sight occlusion: an obstacle between sender and receiver blocks the message (as
//! ARGoS's range-and-bearing medium checks it).

use crate::body::boxed_obstacles;
use swarm::geometry::{polygon_hit, Vec2};
use swarm::scenario::Scenario;

/// The obstacles that can stand between two robots, with their boxes for a cheap first test.
pub struct Occluders {
    obstacles: Vec<(Vec<[f64; 2]>, [f64; 4])>,
}

impl Occluders {
    pub fn new(sc: &Scenario) -> Occluders {
        Occluders {
            obstacles: boxed_obstacles(sc),
        }
    }

    /// Whether the segment a -> b crosses or touches an obstacle.
    pub fn blocked(&self, a: [f64; 2], b: [f64; 2]) -> bool {
        let lo = [a[0].min(b[0]), a[1].min(b[1])];
        let hi = [a[0].max(b[0]), a[1].max(b[1])];
        let p = Vec2::new(a[0], a[1]);
        let d = Vec2::new(b[0] - a[0], b[1] - a[1]);
        self.obstacles.iter().any(|(poly, bb)| {
            let apart = bb[0] > hi[0] || bb[2] < lo[0] || bb[1] > hi[1] || bb[3] < lo[1];
            !apart && polygon_hit(p, d, poly).is_some()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wall_between_two_robots_blocks_the_line_of_sight() {
        let mut sc = Scenario::roam();
        sc.arena.obstacles = vec![swarm::scenario::Obstacle {
            name: "wall".into(),
            points: vec![[100.0, 0.0], [102.0, 0.0], [102.0, 200.0], [100.0, 200.0]],
        }];
        let o = Occluders::new(&sc);
        assert!(o.blocked([50.0, 100.0], [150.0, 100.0]));
        assert!(o.blocked([150.0, 100.0], [50.0, 100.0]));
        assert!(!o.blocked([50.0, 100.0], [60.0, 100.0]));
        // Over the wall's end: clear.
        assert!(!o.blocked([50.0, 250.0], [150.0, 210.0]));
    }
}
