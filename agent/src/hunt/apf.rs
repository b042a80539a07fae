//! The artificial potential field of sec. 2.1.4 (eqs. 2.11-2.16) and its mapping to the unicycle
//! commands (v, w) of eqs. 2.8-2.10, with speed and turn-rate limits.
//!
//! Attraction pulls the robot to its goal: the target while pursuing, its hunting point once the
//! encirclement starts (2.16, used in the vector form -k_a (X_i - X_m), spec 1.7). Repulsion acts
//! between robots only, within d_o, and is scaled by d^n to the goal (the improved APF that keeps
//! the goal reachable). The thesis gives no constant and no force-to-(v, w) mapping (spec 12
//! item 4): see `HuntParams`.

use crate::hunt::params::HuntParams;
use std::f64::consts::{PI, TAU};
use swarm::geometry::Vec2;

/// A unicycle command: linear speed v (km/min) and angular speed w (rad/min), eqs. 2.8-2.10.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command {
    pub v: f64,
    pub w: f64,
}

/// A unicycle pose: position and heading phi.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub position: Vec2,
    pub heading: f64,
}

/// F_a = -grad U_a = -k_a (X_i - X_goal), eq. (2.12); with the hunting point as goal it is the
/// vector form of (2.16). Points from the robot to the goal.
pub fn attraction(x: &Vec2, goal: &Vec2, p: &HuntParams) -> Vec2 {
    -p.k_a * (x - goal)
}

/// U_r of eq. (2.13): 1/2 k_r (1/d - 1/d_o)^2 d_g^n within d_o of robot `other`, else 0.
pub fn repulsive_potential(x: &Vec2, other: &Vec2, goal: &Vec2, p: &HuntParams) -> f64 {
    let d = (x - other).norm();
    if d > p.d_o || d <= 0.0 {
        return 0.0;
    }
    let b = 1.0 / d - 1.0 / p.d_o;
    0.5 * p.k_r * b * b * (x - goal).norm().powf(p.n)
}

/// F_r1 + F_r2 of robot `other` on the robot at `x`, eqs. (2.14)-(2.15); zero beyond d_o.
///
/// F_r1 = -(n/2) k_r (1/d - 1/d_o)^2 d_g^(n-2) (X_i - X_goal)  points toward the goal (2.14).
/// F_r2 =  k_r (1/d - 1/d_o)^k d_g^n / d^3 (X_i - X_q)          points away from `other` (2.15),
/// with k = 1 (the exact gradient of 2.13, default) or k = 2 (as printed, `printed_fr2`).
pub fn repulsion(x: &Vec2, other: &Vec2, goal: &Vec2, p: &HuntParams) -> Vec2 {
    let away = x - other;
    let d = away.norm();
    if d > p.d_o || d <= 1e-12 {
        return Vec2::zeros();
    }
    let b = 1.0 / d - 1.0 / p.d_o;
    let to_goal = x - goal;
    let dg = to_goal.norm();
    // (2.14); d_g^(n-2) is singular at the goal when n < 2, where the term's limit is 0 for n > 1.
    let fr1 = if dg > 1e-12 {
        -(p.n / 2.0) * p.k_r * b * b * dg.powf(p.n - 2.0) * to_goal
    } else {
        Vec2::zeros()
    };
    // (2.15)
    let bk = if p.printed_fr2 { b * b } else { b };
    let fr2 = p.k_r * bk * dg.powf(p.n) / (d * d * d) * away;
    fr1 + fr2
}

/// The total force on a robot at `x` heading for `goal` among the other robots `others`:
/// F_a + sum_q (F_r1 + F_r2) over the robots within d_o (spec 1.7 [INFERRED summation]).
pub fn total_force(x: &Vec2, goal: &Vec2, others: &[Vec2], p: &HuntParams) -> Vec2 {
    others
        .iter()
        .fold(attraction(x, goal, p), |f, q| f + repulsion(x, q, goal, p))
}

/// Wrap an angle to (-pi, pi].
pub fn wrap(a: f64) -> f64 {
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

/// Map a force to unicycle commands [chosen, spec 1.6]: the desired heading is atan2(F_y, F_x);
/// w turns toward it, w = clamp(e / dt, -w_max, w_max) with e the heading error (so the robot
/// never overshoots the heading within one step); v = min(v_max, k_v |F|) max(0, cos e): full
/// speed when aligned and far, slower near the goal (|F| = k_a d there), and no motion while the
/// force points behind the robot.
pub fn to_command(
    force: &Vec2,
    heading: f64,
    v_max: f64,
    w_max: f64,
    dt: f64,
    p: &HuntParams,
) -> Command {
    let f = force.norm();
    if f <= 1e-12 {
        return Command { v: 0.0, w: 0.0 };
    }
    let e = wrap(force.y.atan2(force.x) - heading);
    let w = (e / dt).clamp(-w_max, w_max);
    let v = (p.speed_per_force * f).min(v_max) * e.cos().max(0.0);
    Command { v, w }
}

/// One step of the discrete unicycle, eqs. (2.8)-(2.10) (the world integrates these; kept here so
/// the kernels can be tested in closed loop).
pub fn unicycle_step(pose: &Pose, c: Command, dt: f64) -> Pose {
    Pose {
        position: pose.position + c.v * dt * Vec2::new(pose.heading.cos(), pose.heading.sin()), // (2.8), (2.9)
        heading: wrap(pose.heading + c.w * dt), // (2.10)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> HuntParams {
        HuntParams::default()
    }

    #[test]
    fn attraction_points_to_goal_with_magnitude_k_a_d() {
        let f = attraction(&Vec2::new(1.0, 1.0), &Vec2::new(4.0, 5.0), &p());
        // -k_a (X - X_goal) = -(1)(-3, -4) = (3, 4)
        assert!((f - Vec2::new(3.0, 4.0)).norm() < 1e-12);
    }

    #[test]
    fn repulsion_only_within_d_o() {
        let goal = Vec2::new(5.0, 0.0);
        let x = Vec2::zeros();
        assert_eq!(
            repulsion(&x, &Vec2::new(0.0, 0.21), &goal, &p()),
            Vec2::zeros()
        );
        assert!(repulsion(&x, &Vec2::new(0.0, 0.19), &goal, &p()).norm() > 0.0);
    }

    #[test]
    fn repulsion_hand_computed() {
        // Robot at the origin, other robot at (0, 0.1), goal at (1, 0); k_r = 0.002, d_o = 0.2,
        // n = 2. d = 0.1, b = 1/0.1 - 1/0.2 = 5, d_g = 1.
        // F_r1 = -(2/2)(0.002)(25)(1)(X - goal) = -0.05 (-1, 0) = (0.05, 0)   toward the goal
        // F_r2 = 0.002 (5)(1) / 0.001 (0, -0.1) = 10 (0, -0.1) = (0, -1)    away from the other
        let f = repulsion(
            &Vec2::zeros(),
            &Vec2::new(0.0, 0.1),
            &Vec2::new(1.0, 0.0),
            &p(),
        );
        assert!((f - Vec2::new(0.05, -1.0)).norm() < 1e-9, "{f:?}");
        // As printed (bracket squared): F_r2 is 5 times larger.
        let printed = HuntParams {
            printed_fr2: true,
            ..p()
        };
        let f = repulsion(
            &Vec2::zeros(),
            &Vec2::new(0.0, 0.1),
            &Vec2::new(1.0, 0.0),
            &printed,
        );
        assert!((f - Vec2::new(0.05, -5.0)).norm() < 1e-9, "{f:?}");
    }

    #[test]
    fn exact_repulsion_is_the_negative_gradient_of_2_13() {
        let params = HuntParams { n: 1.5, ..p() };
        let goal = Vec2::new(2.0, -1.0);
        let other = Vec2::new(0.3, 0.25);
        let x = Vec2::new(0.37, 0.16);
        let h = 1e-7;
        let u = |x: Vec2| repulsive_potential(&x, &other, &goal, &params);
        let grad = Vec2::new(
            (u(x + Vec2::new(h, 0.0)) - u(x - Vec2::new(h, 0.0))) / (2.0 * h),
            (u(x + Vec2::new(0.0, h)) - u(x - Vec2::new(0.0, h))) / (2.0 * h),
        );
        let f = repulsion(&x, &other, &goal, &params);
        assert!(
            (f + grad).norm() < 1e-5 * f.norm().max(1.0),
            "F {f:?} vs -grad {:?}",
            -grad
        );
    }

    #[test]
    fn repulsion_vanishes_at_the_goal_so_it_stays_reachable() {
        // A robot standing on its goal with another robot close by feels no repulsion (d_g^n = 0).
        let goal = Vec2::new(1.0, 1.0);
        assert!(repulsion(&goal, &Vec2::new(1.05, 1.0), &goal, &p()).norm() < 1e-12);
        assert!(total_force(&goal, &goal, &[Vec2::new(1.05, 1.0)], &p()).norm() < 1e-12);
    }

    #[test]
    fn command_straight_ahead_far_goal_runs_at_v_max() {
        let c = to_command(&Vec2::new(3.0, 0.0), 0.0, 0.8, 6.0, 0.1, &p());
        assert_eq!(c, Command { v: 0.8, w: 0.0 });
    }

    #[test]
    fn command_slows_near_the_goal() {
        // |F| = 0.05 -> k_v |F| = 0.5 < v_max.
        let c = to_command(&Vec2::new(0.05, 0.0), 0.0, 0.8, 6.0, 0.1, &p());
        assert!((c.v - 0.5).abs() < 1e-12 && c.w == 0.0);
    }

    #[test]
    fn command_turns_at_w_max_and_stands_while_force_behind() {
        // Force straight behind (heading 0, force along -x): e = pi, cos e < 0 -> v = 0,
        // w = clamp(pi / 0.1) = w_max.
        let c = to_command(&Vec2::new(-1.0, 0.0), 0.0, 0.8, 6.0, 0.1, &p());
        assert_eq!(c.v, 0.0);
        assert_eq!(c.w.abs(), 6.0);
        // Force 30 degrees to the left, large dt: w = e / dt is within the limit.
        let e = PI / 6.0;
        let c = to_command(&Vec2::new(e.cos(), e.sin()), 0.0, 0.8, 6.0, 1.0, &p());
        assert!((c.w - e).abs() < 1e-12);
        assert!((c.v - 0.8 * e.cos()).abs() < 1e-12);
        // No force: stand still.
        assert_eq!(
            to_command(&Vec2::zeros(), 0.3, 0.8, 6.0, 0.1, &p()),
            Command { v: 0.0, w: 0.0 }
        );
    }

    #[test]
    fn unicycle_step_2_8_to_2_10() {
        let pose = Pose {
            position: Vec2::new(1.0, 2.0),
            heading: PI / 2.0,
        };
        let next = unicycle_step(&pose, Command { v: 0.8, w: 2.0 }, 0.5);
        // x += 0.8*0.5*cos(pi/2) = 0, y += 0.4, phi += 1.0
        assert!((next.position - Vec2::new(1.0, 2.4)).norm() < 1e-12);
        assert!((next.heading - (PI / 2.0 + 1.0)).abs() < 1e-12);
    }

    #[test]
    fn closed_loop_reaches_goal_past_a_neighbour() {
        // A robot facing away from its goal 2 km off, a stationary robot near the straight path.
        let params = p();
        let goal = Vec2::new(2.0, 0.0);
        let other = Vec2::new(1.0, 0.05);
        let mut pose = Pose {
            position: Vec2::zeros(),
            heading: PI,
        };
        let dt = 0.05;
        let mut min_gap = f64::INFINITY;
        for _ in 0..400 {
            let f = total_force(&pose.position, &goal, &[other], &params);
            pose = unicycle_step(
                &pose,
                to_command(&f, pose.heading, 0.8, 6.0, dt, &params),
                dt,
            );
            min_gap = min_gap.min((pose.position - other).norm());
        }
        assert!(
            (pose.position - goal).norm() < 0.01,
            "ended at {:?}",
            pose.position
        );
        assert!(
            min_gap > 0.05,
            "came within {min_gap} km of the other robot"
        );
    }
}
