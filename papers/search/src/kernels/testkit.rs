//! Test fixtures shared by the obstacle-avoidance tests: obstacle polygons,
//! their sampled boundary points, and a goal-seeking stepping loop.

use swarm::geometry::{sample_boundary, segment_hits_polygon, Vec2};

/// A U-shaped (non-convex) obstacle with its mouth facing down (-y).
/// Outer box [x0, x0+w] × [y0, y0+h], walls `t` thick; the cavity is
/// [x0+t, x0+w−t] × [y0, y0+h−t].
pub fn u_shape(x0: f64, y0: f64, w: f64, h: f64, t: f64) -> Vec<Vec2> {
    vec![
        Vec2::new(x0, y0),
        Vec2::new(x0 + t, y0),
        Vec2::new(x0 + t, y0 + h - t),
        Vec2::new(x0 + w - t, y0 + h - t),
        Vec2::new(x0 + w - t, y0),
        Vec2::new(x0 + w, y0),
        Vec2::new(x0 + w, y0 + h),
        Vec2::new(x0, y0 + h),
    ]
}

/// Axis-aligned rectangle.
pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Vec2> {
    vec![
        Vec2::new(x0, y0),
        Vec2::new(x1, y0),
        Vec2::new(x1, y1),
        Vec2::new(x0, y1),
    ]
}

/// Outcome of [`run_to_goal`].
pub struct Trace {
    /// Positions X(0), X(1), ...
    pub path: Vec<Vec2>,
    /// Step at which the robot came within V_max of the goal.
    pub reached: Option<usize>,
    /// First step whose segment touched or entered a polygon.
    pub crossed: Option<usize>,
}

/// Steps a robot from `start` toward `goal` with V_if = V_max·unit(goal − X);
/// `avoid(x, v_if, sensed_points)` returns V_i(t+1). Sensing: all sampled
/// boundary points (spacing 2) within `sense_range`.
pub fn run_to_goal<F: FnMut(&Vec2, &Vec2, &[Vec2]) -> Vec2>(
    start: Vec2,
    goal: Vec2,
    polys: &[Vec<Vec2>],
    max_steps: usize,
    sense_range: f64,
    mut avoid: F,
) -> Trace {
    let pts: Vec<Vec2> = polys.iter().flat_map(|p| sample_boundary(p, 2.0)).collect();
    let mut x = start;
    let mut tr = Trace {
        path: vec![x],
        reached: None,
        crossed: None,
    };
    for t in 0..max_steps {
        if (goal - x).norm() <= 10.0 {
            tr.reached = Some(t);
            break;
        }
        let v_if = (goal - x).normalize() * 10.0;
        let sensed: Vec<Vec2> = pts
            .iter()
            .filter(|p| (*p - x).norm() <= sense_range)
            .copied()
            .collect();
        let v = avoid(&x, &v_if, &sensed);
        assert!(v.norm() <= 10.0 + 1e-9, "speed {} > V_max", v.norm());
        let nx = x + v;
        if tr.crossed.is_none() && polys.iter().any(|p| segment_hits_polygon(x, nx, p)) {
            tr.crossed = Some(t);
        }
        x = nx;
        tr.path.push(x);
    }
    tr
}

/// True if `p` is strictly inside the open box (x0, x1) × (y0, y1).
pub fn in_box(p: &Vec2, x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
    p.x > x0 && p.x < x1 && p.y > y0 && p.y < y1
}
