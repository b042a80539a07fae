//! The constraints a generated pattern must meet (paper section 1.3): C1 inside the area
//! (eq. 9), C2 no target in an obstacle (eq. 10 exact, or eqs. 11-12's square), C3 targets at
//! least 2r apart (eq. 13), each with the margins of [`FormationParams`].
//!
//! The printed eqs. (11)-(12) have two typos (spec 2.2): the 4th line of (12) must use y_{o_i},
//! and i runs over obstacles, j over targets. The square form here is the fixed one:
//! |x_q - x_o| >= R or |y_q - y_o| >= R, which the paper's big-M binaries linearise.

use super::params::{FormationParams, ObstacleConstraint};
use swarm::geometry::Vec2;

/// The constraint geometry, precomputed from the parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PatternConstraints {
    /// Allowed target x range \[X_min + r, X_max - r\] (eq. 9).
    pub x_range: [f64; 2],
    /// Allowed target y range \[Y_min + r, Y_max - r\] (eq. 9).
    pub y_range: [f64; 2],
    /// Obstacle centres.
    pub obstacles: Vec<Vec2>,
    /// Keep-out distance R = r_o + r + obstacle margin (eq. 10).
    pub keep_out: f64,
    /// Square (eq. 12) or circle (eq. 10).
    pub obstacle_form: ObstacleConstraint,
    /// Least target spacing 2r + separation margin (eq. 13).
    pub min_separation: f64,
}

/// Tolerance for a constraint met with equality up to rounding.
pub const SLACK: f64 = 1e-9;

impl PatternConstraints {
    /// The constraints of a scenario.
    pub fn new(params: &FormationParams) -> Self {
        let r = params.robot_radius;
        Self {
            x_range: [params.box_min[0] + r, params.box_max[0] - r],
            y_range: [params.box_min[1] + r, params.box_max[1] - r],
            obstacles: params
                .obstacle_centres
                .iter()
                .map(|c| Vec2::new(c[0], c[1]))
                .collect(),
            keep_out: params.obstacle_radius + r + params.obstacle_margin,
            obstacle_form: params.obstacle_constraint,
            min_separation: 2.0 * r + params.separation_margin,
        }
    }

    /// C1, eq. (9).
    pub fn in_box(&self, q: Vec2) -> bool {
        q.x >= self.x_range[0] - SLACK
            && q.x <= self.x_range[1] + SLACK
            && q.y >= self.y_range[0] - SLACK
            && q.y <= self.y_range[1] + SLACK
    }

    /// C2 for one target and one obstacle: eq. (10) or the square of eq. (12).
    pub fn clear_of(&self, q: Vec2, obstacle: Vec2) -> bool {
        let rel = q - obstacle;
        match self.obstacle_form {
            ObstacleConstraint::Square => {
                rel.x.abs() >= self.keep_out - SLACK || rel.y.abs() >= self.keep_out - SLACK
            }
            ObstacleConstraint::Circle => rel.norm() >= self.keep_out - SLACK,
        }
    }

    /// C2 for one target and every obstacle.
    pub fn clear_of_obstacles(&self, q: Vec2) -> bool {
        self.obstacles.iter().all(|&o| self.clear_of(q, o))
    }

    /// Whether an axis-aligned box \[x\] x \[y\] lies wholly in one obstacle's forbidden region,
    /// so that no target inside it can meet C2 (used to prune branch-and-bound nodes).
    pub fn box_inside_an_obstacle(&self, x: [f64; 2], y: [f64; 2]) -> bool {
        let r = self.keep_out - SLACK;
        self.obstacles.iter().any(|o| match self.obstacle_form {
            ObstacleConstraint::Square => {
                x[0] > o.x - r && x[1] < o.x + r && y[0] > o.y - r && y[1] < o.y + r
            }
            ObstacleConstraint::Circle => {
                // The disc is convex: the box is inside it when its farthest corner is.
                let dx = (x[0] - o.x).abs().max((x[1] - o.x).abs());
                let dy = (y[0] - o.y).abs().max((y[1] - o.y).abs());
                dx * dx + dy * dy < r * r
            }
        })
    }

    /// Whether an axis-aligned box misses the allowed area of eq. (9) entirely.
    pub fn box_outside_area(&self, x: [f64; 2], y: [f64; 2]) -> bool {
        x[1] < self.x_range[0] - SLACK
            || x[0] > self.x_range[1] + SLACK
            || y[1] < self.y_range[0] - SLACK
            || y[0] > self.y_range[1] + SLACK
    }

    /// C3, eq. (13), over a whole pattern (O(n^2)).
    pub fn separated(&self, targets: &[Vec2]) -> bool {
        (0..targets.len()).all(|i| {
            (i + 1..targets.len())
                .all(|j| (targets[i] - targets[j]).norm() >= self.min_separation - SLACK)
        })
    }

    /// All of C1-C3 for a pattern.
    pub fn satisfied(&self, targets: &[Vec2]) -> bool {
        targets
            .iter()
            .all(|&q| self.in_box(q) && self.clear_of_obstacles(q))
            && self.separated(targets)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constraints(form: ObstacleConstraint) -> PatternConstraints {
        let params = FormationParams {
            obstacle_centres: vec![[10.0, 10.0]],
            obstacle_margin: 0.0,
            obstacle_constraint: form,
            ..FormationParams::default()
        };
        PatternConstraints::new(&params)
    }

    #[test]
    fn square_is_conservative_and_circle_exact() {
        // R = 2 + 1 = 3. (12, 12) is 2.83 from the centre: inside the circle and the square.
        // (12.5, 12.5) is 3.54 away: outside the circle but inside the square.
        let sq = constraints(ObstacleConstraint::Square);
        let ci = constraints(ObstacleConstraint::Circle);
        let o = Vec2::new(10.0, 10.0);
        assert!(!sq.clear_of(Vec2::new(12.0, 12.0), o) && !ci.clear_of(Vec2::new(12.0, 12.0), o));
        assert!(!sq.clear_of(Vec2::new(12.5, 12.5), o) && ci.clear_of(Vec2::new(12.5, 12.5), o));
        assert!(sq.clear_of(Vec2::new(13.0, 10.0), o) && ci.clear_of(Vec2::new(13.0, 10.0), o));
        assert!(sq.box_inside_an_obstacle([9.0, 11.0], [9.0, 11.0]));
        assert!(!ci.box_inside_an_obstacle([9.0, 12.2], [9.0, 12.2]));
        assert!(sq.box_inside_an_obstacle([9.0, 12.2], [9.0, 12.2]));
    }

    #[test]
    fn box_and_separation() {
        let c = constraints(ObstacleConstraint::Square);
        assert!(c.in_box(Vec2::new(1.0, 23.0)) && !c.in_box(Vec2::new(0.5, 5.0)));
        assert!(c.box_outside_area([-3.0, 0.9], [4.0, 5.0]));
        assert!(!c.box_outside_area([-3.0, 1.1], [4.0, 5.0]));
        let pts = [Vec2::new(2.0, 2.0), Vec2::new(4.2, 2.0)];
        assert!(c.separated(&pts));
        assert!(!c.separated(&[Vec2::new(2.0, 2.0), Vec2::new(4.1, 2.0)]));
    }
}
