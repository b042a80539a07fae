//! Obstacle points ahead of a robot: the corridor test BSOA's forced slide (spec 5 item 22)
//! and SVF's wall following use to see whether a direction is blocked.

use swarm::geometry::{cross, Vec2};

/// Distance along unit vector `u` to the first of `pts` lying in the
/// corridor of half-width `hw` ahead of `x` (0 < along < `reach`), if any.
pub fn blocked_at(x: &Vec2, u: &Vec2, pts: &[Vec2], hw: f64, reach: f64) -> Option<f64> {
    pts.iter()
        .map(|b| b - x)
        .filter(|r| {
            let along = r.dot(u);
            along > 0.0 && along < reach && cross(*u, *r).abs() < hw
        })
        .map(|r| r.dot(u))
        .min_by(f64::total_cmp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_point_in_the_corridor_ahead() {
        let pts = [
            Vec2::new(5.0, 1.5),
            Vec2::new(3.0, -3.0),
            Vec2::new(-2.0, 0.0),
            Vec2::new(20.0, 0.0),
        ];
        let u = Vec2::new(1.0, 0.0);
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 2.0, 12.0), Some(5.0));
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 1.0, 12.0), None);
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 2.0, 21.0), Some(5.0));
        assert_eq!(blocked_at(&Vec2::zeros(), &u, &pts, 4.0, 12.0), Some(3.0));
    }
}
