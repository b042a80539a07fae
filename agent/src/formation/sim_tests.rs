//! A test-only, in-memory run of the paper's whole pipeline (spec 2.4's loop): optimise the
//! pattern once, then every iteration reassign (eq. 15, Hungarian), preferred velocity
//! (eq. 16), ORCA (eqs. 17-26) for every robot from the same state (synchronous, as in a MATLAB
//! loop), p += v tau (eq. 27), until every robot is within epsilon of its assigned target.
//! It previews Table 1: the proposed model against the no-rotation baseline of ref. \[10\].

use super::hungarian::{assign_targets, Hungarian};
use super::optimise::{optimise, optimise_without_rotation};
use super::orca::{orca_velocity, Disc};
use super::params::FormationParams;
use super::preferred::preferred_velocity;
use super::template::Template;
use super::test_support::random_starts;
use swarm::geometry::Vec2;

/// What one run measured.
#[derive(Debug, Clone)]
struct RunReport {
    /// K: iterations to completion (or the cap).
    iterations: usize,
    completed: bool,
    /// L: the sum over robots of their path lengths.
    path_length: f64,
    /// Times some robot's assigned target changed.
    reassignments: usize,
    /// Least centre distance minus 2r over all pairs and steps.
    min_robot_clearance: f64,
    /// Least centre distance minus (r + r_o) over robots, obstacles and steps.
    min_obstacle_clearance: f64,
    /// Robot pairs overlapping (clearance < -1e-9), summed over steps.
    overlapping_pairs: usize,
    /// Robot-obstacle overlaps, summed over steps.
    obstacle_overlaps: usize,
}

fn run(starts: &[Vec2], targets: &[Vec2], params: &FormationParams, per_step: bool) -> RunReport {
    let n = starts.len();
    let r = params.robot_radius;
    let tau = params.time_step;
    let obstacles: Vec<Disc> = params
        .obstacle_centres
        .iter()
        .map(|c| Disc {
            position: Vec2::new(c[0], c[1]),
            velocity: Vec2::zeros(),
            radius: params.obstacle_radius,
        })
        .collect();
    let mut robots: Vec<Disc> = starts
        .iter()
        .map(|&p| Disc {
            position: p,
            velocity: Vec2::zeros(),
            radius: r,
        })
        .collect();
    let mut solver = Hungarian::new();
    let mut assignment = Vec::new();
    let mut next_assignment = Vec::new();
    assign_targets(starts, targets, &mut solver, &mut assignment).unwrap();
    let mut report = RunReport {
        iterations: params.max_iterations,
        completed: false,
        path_length: 0.0,
        reassignments: 0,
        min_robot_clearance: f64::INFINITY,
        min_obstacle_clearance: f64::INFINITY,
        overlapping_pairs: 0,
        obstacle_overlaps: 0,
    };
    let mut positions: Vec<Vec2> = starts.to_vec();
    let mut others = Vec::with_capacity(n);
    for k in 1..=params.max_iterations {
        if per_step {
            assign_targets(&positions, targets, &mut solver, &mut next_assignment).unwrap();
            report.reassignments += assignment
                .iter()
                .zip(&next_assignment)
                .filter(|(a, b)| a != b)
                .count();
            std::mem::swap(&mut assignment, &mut next_assignment);
        }
        let velocities: Vec<Vec2> = (0..n)
            .map(|i| {
                let pref = preferred_velocity(
                    robots[i].position,
                    targets[assignment[i]],
                    params.max_speed,
                    params.k_a,
                );
                others.clear();
                others.extend((0..n).filter(|&j| j != i).map(|j| robots[j]));
                orca_velocity(&robots[i], pref, &others, &obstacles, params).velocity
            })
            .collect();
        for (robot, v) in robots.iter_mut().zip(&velocities) {
            robot.velocity = *v;
            robot.position += v * tau;
            report.path_length += v.norm() * tau;
        }
        for i in 0..n {
            positions[i] = robots[i].position;
            for j in i + 1..n {
                let c = (robots[i].position - robots[j].position).norm() - 2.0 * r;
                report.min_robot_clearance = report.min_robot_clearance.min(c);
                report.overlapping_pairs += usize::from(c < -1e-9);
            }
            for o in &obstacles {
                let c = (robots[i].position - o.position).norm() - r - o.radius;
                report.min_obstacle_clearance = report.min_obstacle_clearance.min(c);
                report.obstacle_overlaps += usize::from(c < -1e-9);
            }
        }
        let done = (0..n).all(|i| (positions[i] - targets[assignment[i]]).norm() <= params.epsilon);
        if done {
            report.iterations = k;
            report.completed = true;
            break;
        }
    }
    report
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

#[test]
fn nine_robots_form_the_c_without_a_collision_for_20_seeds() {
    let params = FormationParams::default();
    let template = Template::letter_c();
    let (mut ks, mut ls, mut base_ks, mut base_ls) = (vec![], vec![], vec![], vec![]);
    let mut min_clear: f64 = f64::INFINITY;
    let mut min_obst: f64 = f64::INFINITY;
    eprintln!("seed | with rotation: K, L, cost, reassign | without rotation: K, L, cost");
    for seed in 0..20 {
        let starts = random_starts(1000 + seed, 9, &params, 0.1);
        let ours = optimise(&starts, &template, &params).unwrap();
        let base = optimise_without_rotation(&starts, &template, &params).unwrap();
        let a = run(&starts, &ours.targets, &params, true);
        let b = run(&starts, &base.targets, &params, true);
        for (name, rep) in [("rotation", &a), ("baseline", &b)] {
            assert!(rep.completed, "seed {seed} {name}: {rep:?}");
            assert_eq!(rep.overlapping_pairs, 0, "seed {seed} {name}: {rep:?}");
            assert_eq!(rep.obstacle_overlaps, 0, "seed {seed} {name}: {rep:?}");
            min_clear = min_clear.min(rep.min_robot_clearance);
            min_obst = min_obst.min(rep.min_obstacle_clearance);
        }
        eprintln!(
            "{seed:4} | {:4} {:7.2} {:8.2} {:3} | {:4} {:7.2} {:8.2}",
            a.iterations,
            a.path_length,
            ours.cost,
            a.reassignments,
            b.iterations,
            b.path_length,
            base.cost
        );
        ks.push(a.iterations as f64);
        ls.push(a.path_length);
        base_ks.push(b.iterations as f64);
        base_ls.push(b.path_length);
    }
    let pct = |x: f64, y: f64| 100.0 * (y - x) / y;
    eprintln!(
        "mean K {:.1} vs {:.1} ({:.1} % fewer), mean L {:.2} vs {:.2} ({:.1} % shorter); \
         least clearance robot-robot {min_clear:.4}, robot-obstacle {min_obst:.4}",
        mean(&ks),
        mean(&base_ks),
        pct(mean(&ks), mean(&base_ks)),
        mean(&ls),
        mean(&base_ls),
        pct(mean(&ls), mean(&base_ls))
    );
}

#[test]
fn per_step_reassignment_against_one_shot() {
    // Section 3.2: the same optimised pattern, assignment once vs every iteration.
    let params = FormationParams::default();
    let template = Template::letter_c();
    let (mut per, mut once) = (vec![], vec![]);
    for seed in 0..5 {
        let starts = random_starts(2000 + seed, 9, &params, 0.1);
        let sol = optimise(&starts, &template, &params).unwrap();
        let a = run(&starts, &sol.targets, &params, true);
        let b = run(&starts, &sol.targets, &params, false);
        for rep in [&a, &b] {
            assert!(rep.completed && rep.overlapping_pairs == 0 && rep.obstacle_overlaps == 0);
        }
        assert_eq!(b.reassignments, 0);
        eprintln!(
            "seed {seed}: per-step K {} L {:.2} ({} reassignments); one-shot K {} L {:.2}",
            a.iterations, a.path_length, a.reassignments, b.iterations, b.path_length
        );
        per.push(a.path_length);
        once.push(b.path_length);
    }
    eprintln!(
        "mean L per-step {:.2}, one-shot {:.2}",
        mean(&per),
        mean(&once)
    );
}
