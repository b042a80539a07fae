//! SVF baseline: obstacle following with a simplified virtual-force model
//! (refs [20], [21] of the paper; spec §2.11 and §5 item 27).
//!
//! The paper only says: follow the obstacle left or right "along the
//! direction formed by the two nearest obstacle points", obstacle boundaries
//! attract the robot, and the method gives longer detours than BSOA. This is
//! a reconstruction [chosen, spec §5 item 27]:
//! * engage when an obstacle point lies in the desired direction within
//!   `engage_distance`; pick the sense of ±(Q1 − Q2) closer to V_if and
//!   remember which side the wall is on;
//! * while following, move along ±(Q1 − Q2) keeping the wall on that side,
//!   bent toward the wall when farther than `follow_distance` (the boundary
//!   attraction) and away from it when nearer, by at most `max_correction`;
//! * release when nothing lies in the desired direction within L_B.
//!
//! Against the published description (docs/search.md 5 item 27): the direction
//! ±(Q1 − Q2) is the description's; the kept wall side (`keep_side`), the
//! look-ahead at concave corners and the stand-off bend (in place of eq. 5's
//! 1/d² boundary attraction) are ours.

use crate::kernels::bsoa::obstacle_ahead;
use agent::kernels::obstacles::blocked_at;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use swarm::geometry::{angle_between, cross, rotate, Vec2};

/// Wall-following state carried between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Follow {
    /// Not following.
    #[default]
    None,
    /// Following with the obstacle on the robot's left (turning clockwise).
    WallOnLeft,
    /// Following with the obstacle on the robot's right.
    WallOnRight,
}

/// SVF result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Output {
    /// V_i(t+1).
    pub velocity: Vec2,
    /// State for the next step.
    pub follow: Follow,
}

/// Tunables of SVF.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Maximum speed V_max = 10; following flies at V_max (Table 4).
    pub v_max: f64,
    /// Obstacle sensing radius L_B = 100 (Table 4).
    pub l_b: f64,
    /// Start following when a blocking obstacle point is nearer than this
    /// (20 = two steps). [chosen] spec §5 item 27.
    pub engage_distance: f64,
    /// Stand-off kept from the nearest obstacle point while following; set to
    /// l_1 = 10, the "enhanced obstacle-avoidance distance" of eq. (5).
    /// [chosen] spec §5 item 27.
    pub follow_distance: f64,
    /// Largest bend (rad) toward / away from the wall (π/4). [chosen] spec §5 item 27.
    pub max_correction: f64,
    /// Heading cone of the "obstacle in the desired direction" test, 0.1 rad
    /// as in BSOA (Table 2 line 1). [chosen] spec §5 item 21.
    pub heading_tolerance: f64,
    /// Corridor half-width of that test and of the look-ahead (2.0, the
    /// sample spacing). [chosen] spec §5 items 21-22.
    pub corridor_half_width: f64,
    /// Keep the wall side chosen when following began until release (true), or choose the
    /// sense of ±(Q1 − Q2) nearer V_if again at every step (false: the published description
    /// read literally, "left or right along the line through the two nearest obstacle
    /// points", with no memory). The description also says SVF copes with non-convex
    /// obstacles, which a robot that may change sense at every step does not do reliably (it
    /// turns back and forth at the bottom of a U). [chosen] spec §5 item 27.
    pub keep_side: bool,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            v_max: 10.0,
            l_b: 100.0,
            engage_distance: 20.0,
            follow_distance: 10.0,
            max_correction: PI / 4.0,
            heading_tolerance: 0.1,
            corridor_half_width: 2.0,
            keep_side: true,
        }
    }
}

/// One SVF step.
pub fn avoid(x: &Vec2, v_if: &Vec2, obstacle_points: &[Vec2], state: Follow, p: &Params) -> Output {
    let free = Output {
        velocity: *v_if,
        follow: Follow::None,
    };
    let mut near: Vec<(f64, Vec2)> = obstacle_points
        .iter()
        .map(|b| ((b - x).norm(), *b))
        .filter(|(d, _)| *d < p.l_b && *d > 1e-9)
        .collect();
    if near.is_empty() || v_if.norm() <= 1e-12 {
        return free;
    }
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    let pts: Vec<Vec2> = near.iter().map(|(_, b)| *b).collect();
    let ahead = |range: f64| {
        let k = near.partition_point(|(d, _)| *d < range);
        obstacle_ahead(
            x,
            v_if,
            &pts[..k],
            p.heading_tolerance,
            p.corridor_half_width,
        )
    };
    let side = match state {
        Follow::None if !ahead(p.engage_distance) => return free,
        Follow::None => None,
        _ if !ahead(p.l_b) => return free, // release: desired direction clear
        s if p.keep_side => Some(s),
        _ => None,
    };

    let (d1, q1) = near[0];
    let to_q1 = (q1 - x) / d1;
    let line = match pts.get(1) {
        Some(q2) if (q1 - q2).norm() > 1e-9 => (q1 - q2).normalize(),
        _ => Vec2::new(-to_q1.y, to_q1.x),
    };
    let wall_side = |t: &Vec2| {
        if cross(*t, to_q1) > 0.0 {
            Follow::WallOnLeft
        } else {
            Follow::WallOnRight
        }
    };
    let follow = side.unwrap_or_else(|| {
        // engage: the sense of ±(Q1 − Q2) closer to V_if
        let t = if angle_between(&line, v_if).abs() <= angle_between(&-line, v_if).abs() {
            line
        } else {
            -line
        };
        wall_side(&t)
    });
    let t = if wall_side(&line) == follow {
        line
    } else {
        -line
    };
    // bend toward the wall (attraction) beyond the stand-off, away inside it
    let k = ((d1 - p.follow_distance) / p.follow_distance).clamp(-1.0, 1.0);
    let toward = if follow == Follow::WallOnLeft {
        1.0
    } else {
        -1.0
    };
    let mut dir = rotate(&t, toward * k * p.max_correction);
    // look-ahead: turn away from the wall while the step is blocked
    let reach = p.v_max + p.corridor_half_width;
    let mut best = (dir, 0.0);
    for step in 0..5 {
        let u = rotate(&dir, -toward * step as f64 * PI / 4.0);
        match blocked_at(x, &u, &pts, p.corridor_half_width, reach) {
            None => {
                best = (u, f64::INFINITY);
                break;
            }
            Some(d) if d > best.1 => best = (u, d),
            Some(_) => {}
        }
    }
    dir = best.0;
    Output {
        velocity: dir * p.v_max,
        follow,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::bsoa;
    use crate::kernels::testkit::{rect, run_to_goal, u_shape};
    use swarm::geometry::sample_boundary;

    fn svf_runner(p: Params) -> impl FnMut(&Vec2, &Vec2, &[Vec2]) -> Vec2 {
        let mut st = Follow::None;
        move |x, v_if, pts| {
            let o = avoid(x, v_if, pts, st, &p);
            st = o.follow;
            o.velocity
        }
    }

    fn path_len(path: &[Vec2]) -> f64 {
        path.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
    }

    #[test]
    fn engages_only_when_close_and_blocked() {
        let p = Params::default();
        let wall = sample_boundary(&rect(50.0, -40.0, 54.0, 40.0), 2.0);
        let o = avoid(
            &Vec2::new(0.0, 0.0),
            &Vec2::new(10.0, 0.0),
            &wall,
            Follow::None,
            &p,
        );
        assert_eq!((o.follow, o.velocity), (Follow::None, Vec2::new(10.0, 0.0)));
        let o = avoid(
            &Vec2::new(35.0, 5.0),
            &Vec2::new(10.0, 0.0),
            &wall,
            Follow::None,
            &p,
        );
        assert_ne!(o.follow, Follow::None);
        assert!((o.velocity.norm() - 10.0).abs() < 1e-9);
        // heading parallel to the wall: not engaged
        let o = avoid(
            &Vec2::new(40.0, 0.0),
            &Vec2::new(0.0, 10.0),
            &wall,
            Follow::None,
            &p,
        );
        assert_eq!(o.follow, Follow::None);
    }

    #[test]
    fn follows_a_long_wall_at_the_stand_off_and_keeps_its_side() {
        let p = Params::default();
        let polys = [rect(-500.0, 0.0, 500.0, 4.0)];
        let pts: Vec<Vec2> = polys.iter().flat_map(|q| sample_boundary(q, 2.0)).collect();
        // goal on the far side of the wall, slightly to the right
        let goal = Vec2::new(40.0, 300.0);
        let mut x = Vec2::new(0.0, -15.0);
        let mut st = Follow::None;
        for _ in 0..30 {
            let v_if = (goal - x).normalize() * 10.0;
            let sensed: Vec<Vec2> = pts
                .iter()
                .filter(|q| (*q - x).norm() < 100.0)
                .copied()
                .collect();
            let o = avoid(&x, &v_if, &sensed, st, &p);
            if st != Follow::None {
                assert_eq!(o.follow, st, "side changed");
            }
            st = o.follow;
            x += o.velocity;
            assert!(x.y < 0.0, "crossed the wall at {x:?}");
        }
        assert_eq!(st, Follow::WallOnLeft); // moving +x with the wall above
        assert!(x.x > 200.0 && x.y > -16.0 && x.y < -4.0, "{x:?}");
    }

    #[test]
    fn goes_around_a_convex_box() {
        let boxes = vec![rect(470.0, 450.0, 530.0, 480.0)];
        let tr = run_to_goal(
            Vec2::new(500.0, 350.0),
            Vec2::new(500.0, 600.0),
            &boxes,
            100,
            100.0,
            svf_runner(Params::default()),
        );
        assert_eq!(tr.crossed, None);
        assert!(tr.reached.unwrap() < 45, "{:?}", tr.reached);
    }

    #[test]
    fn gets_out_of_a_u_trap_but_with_a_longer_path_than_bsoa() {
        let u = vec![u_shape(440.0, 450.0, 120.0, 85.0, 15.0)];
        let (start, goal) = (Vec2::new(500.0, 330.0), Vec2::new(500.0, 700.0));
        let tr = run_to_goal(start, goal, &u, 300, 100.0, svf_runner(Params::default()));
        assert_eq!(tr.crossed, None);
        assert!(tr.reached.is_some(), "stuck at {:?}", tr.path.last());
        let mut sf = bsoa::Sense::None;
        let bp = bsoa::Params::default();
        let tb = run_to_goal(start, goal, &u, 300, 100.0, |x, v, pts| {
            let o = bsoa::avoid(x, v, pts, sf, &bp);
            sf = o.sense;
            o.velocity
        });
        eprintln!(
            "U trap: SVF {} steps / {:.1} units, BSOA {:?} steps / {:.1} units, SVF entered cavity: {}",
            tr.path.len() - 1,
            path_len(&tr.path),
            tb.reached,
            path_len(&tb.path),
            tr.path.iter().any(|x| crate::kernels::testkit::in_box(x, 455.0, 450.0, 545.0, 520.0))
        );
        assert!(
            path_len(&tr.path) > path_len(&tb.path),
            "SVF {} vs BSOA {}",
            path_len(&tr.path),
            path_len(&tb.path)
        );
    }
}
