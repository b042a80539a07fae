//! A closed-loop check of the kernels together, before the world mission exists: one coalition
//! chases one evader with the APF (2.11-2.16) on unicycles (2.8-2.10), switches to hunting points
//! (3.17-3.20) once its first member enters r_e, and the evader flees by (2.17) with the
//! encirclement slowdown. It shows that capture is possible with robots slower than the evader
//! when the slowdown is on (spec 1.3, 12 item 1).

use crate::hunt::apf::{to_command, total_force, unicycle_step, Pose};
use crate::hunt::hunting_points::{assign, encircled, hunting_points, HuntingPhase};
use crate::hunt::model::RobotId;
use crate::hunt::params::HuntParams;
use swarm::geometry::Vec2;
use world::mission::hunt_escape::{flee_step, ArenaBox, EscapeParams};

struct Run {
    captured_at: Option<f64>,
    closest: f64,
}

/// Robots at `starts` (speed `v`, w_max 6 rad/min) against an evader at (5, 5) with speed 1.0;
/// `dt` = 0.01 min, for at most `t_max` minutes.
fn chase(starts: &[Vec2], v: f64, slowdown: f64, t_max: f64) -> Run {
    let p = HuntParams::default();
    let esc = EscapeParams {
        encirclement_slowdown: slowdown,
        ..EscapeParams::default()
    };
    let arena = ArenaBox {
        width: 10.0,
        height: 10.0,
    };
    let dt = 0.01;
    let mut evader = Vec2::new(5.0, 5.0);
    let mut poses: Vec<Pose> = starts
        .iter()
        .map(|s| Pose {
            position: *s,
            heading: (evader - s).y.atan2((evader - s).x),
        })
        .collect();
    let ids: Vec<RobotId> = (1..=starts.len() as RobotId).collect();
    let r_e = p.effective_range(starts.len());
    let mut phase = HuntingPhase::default();
    let mut closest = f64::INFINITY;
    let mut t = 0.0;
    while t < t_max {
        let members: Vec<(RobotId, Vec2)> = ids
            .iter()
            .zip(&poses)
            .map(|(i, q)| (*i, q.position))
            .collect();
        // Goals: the evader until a leader is in r_e, then the hunting points (recomputed each
        // cycle, sec. 3.2.4 step 5).
        let goals: Vec<Vec2> = match phase.update(&members, &evader, r_e) {
            None => vec![evader; poses.len()],
            Some(_) => {
                let pts =
                    hunting_points(&evader, poses.len(), p.r_s, phase.anchor_angle().unwrap());
                let a = assign(&members, &pts, p.contested_point_to_farthest);
                if encircled(&members, &pts, &a, p.capture_tolerance) {
                    return Run {
                        captured_at: Some(t),
                        closest,
                    };
                }
                ids.iter().map(|i| pts[a[i]]).collect()
            }
        };
        let positions: Vec<Vec2> = poses.iter().map(|q| q.position).collect();
        for (k, pose) in poses.iter_mut().enumerate() {
            let others: Vec<Vec2> = positions
                .iter()
                .enumerate()
                .filter(|(m, _)| *m != k)
                .map(|(_, x)| *x)
                .collect();
            let f = total_force(&pose.position, &goals[k], &others, &p);
            *pose = unicycle_step(pose, to_command(&f, pose.heading, v, 6.0, dt, &p), dt);
        }
        evader = flee_step(&evader, &positions, &arena, 1.0, dt, &esc);
        closest = positions
            .iter()
            .map(|x| (x - evader).norm())
            .fold(closest, f64::min);
        t += dt;
    }
    Run {
        captured_at: None,
        closest,
    }
}

fn ring(n: usize, r: f64) -> Vec<Vec2> {
    (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64 + 0.3;
            Vec2::new(5.0 + r * a.cos(), 5.0 + r * a.sin())
        })
        .collect()
}

#[test]
fn slower_robots_capture_with_the_encirclement_slowdown() {
    for n in [3, 4, 5] {
        let run = chase(&ring(n, 3.0), 0.8, 1.0, 60.0);
        println!(
            "{n} robots at 0.8 vs evader 1.0, slowdown 1: captured at {:?} min",
            run.captured_at
        );
        assert!(
            run.captured_at.is_some(),
            "{n} robots: no capture in 60 min"
        );
    }
}

#[test]
fn without_the_slowdown_slower_robots_only_trail() {
    // The thesis as printed (s = 0): the faster evader breaks out; report how close they got.
    let run = chase(&ring(3, 3.0), 0.8, 0.0, 60.0);
    println!(
        "3 robots at 0.8 vs evader 1.0, slowdown 0: captured at {:?}, closest {:.3} km",
        run.captured_at, run.closest
    );
    assert!(run.captured_at.is_none());
}
