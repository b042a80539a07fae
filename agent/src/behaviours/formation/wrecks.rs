//! Dead robots ("wrecks") as a robot's own sensors see them (issue 16, a robot killed mid-run).
//!
//! The world lists in Sense `obstacle_points` the static boundary points (obstacle polygons,
//! the arena's discs, the walls when sensed) and the centre of every dead robot within the
//! sensing radius, from its ground truth. The static points lie on a known boundary (the
//! scenario's), a wreck's centre never does: the world keeps a disc robot of radius r > 0 at
//! least r clear of every obstacle and wall. So a sensed point farther than `on_boundary`
//! from every static boundary is a wreck, at exactly the position the world holds. This
//! replaces guessing from robots that vanished from `nearby` (only robots that saw the death
//! knew of the body).

use swarm::geometry::Vec2;
use swarm::scenario::Scenario;
use swarm::Sense;

/// A sensed point this close to a static boundary is a boundary point. [chosen] 1e-6: the
/// world's samples lie on the boundary up to rounding (~1e-14), a wreck's centre is at least
/// the robot radius away.
pub const ON_BOUNDARY: f64 = 1e-6;

/// The boundaries the world samples into static obstacle points.
#[derive(Debug, Clone, Default)]
pub struct StaticBoundaries {
    /// (centre, radius) of the arena's discs.
    discs: Vec<(Vec2, f64)>,
    /// Polygon edges (and the walls when `arena.walls_sensed`).
    edges: Vec<(Vec2, Vec2)>,
}

impl StaticBoundaries {
    pub fn of(sc: &Scenario) -> Self {
        let mut edges = Vec::new();
        let mut polygon = |pts: &[[f64; 2]]| {
            for i in 0..pts.len() {
                let a = pts[i];
                let b = pts[(i + 1) % pts.len()];
                edges.push((Vec2::new(a[0], a[1]), Vec2::new(b[0], b[1])));
            }
        };
        for o in &sc.arena.obstacles {
            polygon(&o.points);
        }
        if sc.arena.walls_sensed {
            let (w, h) = (sc.arena.width, sc.arena.height);
            polygon(&[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]);
        }
        StaticBoundaries {
            discs: sc
                .arena
                .discs
                .iter()
                .map(|d| (Vec2::new(d.centre[0], d.centre[1]), d.radius))
                .collect(),
            edges,
        }
    }

    /// Whether `p` lies on one of the static boundaries.
    pub fn on_boundary(&self, p: Vec2) -> bool {
        self.discs
            .iter()
            .any(|(c, r)| ((p - c).norm() - r).abs() <= ON_BOUNDARY)
            || self
                .edges
                .iter()
                .any(|(a, b)| segment_distance(p, *a, *b) <= ON_BOUNDARY)
    }

    /// The wrecks among the Sense frame's obstacle points, in the frame's order.
    pub fn wrecks_in(&self, sense: &Sense) -> Vec<Vec2> {
        sense
            .obstacle_points()
            .iter()
            .map(|q| Vec2::new(q[0], q[1]))
            .filter(|p| !self.on_boundary(*p))
            .collect()
    }
}

fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

/// Adds `w` to `known` unless it is there already (positions are the world's, exact).
pub fn remember(known: &mut Vec<Vec2>, w: Vec2) -> bool {
    if known.contains(&w) {
        return false;
    }
    known.push(w);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario() -> Scenario {
        Scenario::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../configs/formation-swaps-16.toml"
        )))
        .unwrap()
    }

    #[test]
    fn the_world_s_static_points_are_boundary_points_and_a_dead_robot_s_centre_is_a_wreck() {
        let sc = scenario();
        let b = StaticBoundaries::of(&sc);
        // Every point the world samples (discs and walls, as world/src/sensing.rs does).
        let mut statics = Vec::new();
        for d in &sc.arena.discs {
            statics.extend(d.boundary(sc.arena.boundary_spacing));
        }
        let (w, h) = (sc.arena.width, sc.arena.height);
        statics.extend(swarm::geometry::sample_boundary(
            &[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]],
            sc.arena.boundary_spacing,
        ));
        assert!(statics.len() > 200);
        let mut s = Sense::zeroed();
        for (k, q) in statics.iter().enumerate().take(100) {
            s.obstacle_points[k] = *q;
        }
        // Two dead robots: one touching the disc OB1 (centre 24, 15, radius 2; robot radius
        // 1: its centre 3 from the disc's), one touching the left wall.
        s.obstacle_points[100] = [21.0, 15.0];
        s.obstacle_points[101] = [1.0, 7.5];
        s.n_obstacle_points = 102;
        assert_eq!(
            b.wrecks_in(&s),
            vec![Vec2::new(21.0, 15.0), Vec2::new(1.0, 7.5)]
        );
        // The full sampled boundary holds no wreck.
        assert!(statics
            .iter()
            .all(|q| b.on_boundary(Vec2::new(q[0], q[1]))));
    }

    #[test]
    fn remembering_a_wreck_twice_keeps_one() {
        let mut known = Vec::new();
        assert!(remember(&mut known, Vec2::new(1.0, 2.0)));
        assert!(!remember(&mut known, Vec2::new(1.0, 2.0)));
        assert!(remember(&mut known, Vec2::new(1.0, 2.0 + 1e-12)));
        assert_eq!(known.len(), 2);
    }
}
