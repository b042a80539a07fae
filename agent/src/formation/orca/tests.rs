use super::*;
use crate::formation::linear_program::{select_velocity, Selection};
use crate::formation::preferred::preferred_velocity;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::borrow::Cow;

/// The kernels' defaults without the box's walls: these scenes sit around the origin, a corner
/// of the default box, and test ORCA itself (walls.rs tests the walls).
fn open_plane() -> FormationParams {
    FormationParams {
        wall_half_planes: false,
        ..FormationParams::default()
    }
}

fn disc(x: f64, y: f64, vx: f64, vy: f64, radius: f64) -> Disc {
    Disc {
        position: Vec2::new(x, y),
        velocity: Vec2::new(vx, vy),
        radius,
    }
}

#[test]
fn head_on_pair_gives_the_hand_computed_leg_half_plane() {
    // p_rel = (4, 0), v_rel = (2, 0), R = 2, T = 2: w = 0, so the nearest boundary is a leg,
    // the tangent at -30 degrees: dir = (cos 30, -sin 30), u = 1.732 dir - (2, 0) =
    // (-0.5, -0.866), n = (-0.5, -0.866); point = v_i + u / 2 = (0.75, -0.433).
    let me = disc(0.0, 0.0, 1.0, 0.0, 1.0);
    let other = disc(4.0, 0.0, -1.0, 0.0, 1.0);
    let h = orca_half_plane(&me, &other, 0.5, 2.0, 0.25);
    let s3 = 3f64.sqrt() / 2.0;
    assert!((h.normal - Vec2::new(-0.5, -s3)).norm() < 1e-12, "{h:?}");
    assert!(
        (h.point - Vec2::new(0.75, -s3 / 2.0)).norm() < 1e-12,
        "{h:?}"
    );
}

#[test]
fn slow_approach_gives_the_hand_computed_cut_off_half_plane() {
    // p_rel = (10, 0), v_rel = (1, 0), R = 2, T = 5: cut-off disc centre (2, 0), radius 0.4,
    // nearest boundary point (1.6, 0), u = (0.6, 0), n = (-1, 0); with c = 1/2 the half-plane is
    // v_x <= 0.3.
    let me = disc(0.0, 0.0, 0.0, 0.0, 1.0);
    let other = disc(10.0, 0.0, -1.0, 0.0, 1.0);
    let h = orca_half_plane(&me, &other, 0.5, 5.0, 0.25);
    assert!((h.normal - Vec2::new(-1.0, 0.0)).norm() < 1e-12, "{h:?}");
    assert!((h.point - Vec2::new(0.3, 0.0)).norm() < 1e-12, "{h:?}");
    // An obstacle (c = 1) takes the whole change: v_x <= 0.6 against a static disc.
    let wall = disc(10.0, 0.0, 0.0, 0.0, 1.0);
    let me = disc(0.0, 0.0, 1.0, 0.0, 1.0);
    let h = orca_half_plane(&me, &wall, 1.0, 5.0, 0.25);
    assert!(
        (h.point.x - 1.6).abs() < 1e-12 && (h.normal.x + 1.0).abs() < 1e-12,
        "{h:?}"
    );
}

#[test]
fn overlapping_pair_asks_to_separate_within_one_step() {
    // Overlap by 0.5 along x, both still: w = -(1.5, 0) / 0.25 = (-6, 0), n = (-1, 0),
    // u = (2 / 0.25 - 6) n = (-2, 0); c = 1/2: v_x <= -1.
    let me = disc(0.0, 0.0, 0.0, 0.0, 1.0);
    let other = disc(1.5, 0.0, 0.0, 0.0, 1.0);
    let h = orca_half_plane(&me, &other, 0.5, 2.0, 0.25);
    assert!((h.point - Vec2::new(-1.0, 0.0)).norm() < 1e-12 && (h.normal.x + 1.0).abs() < 1e-12);
}

fn random_scene(rng: &mut ChaCha8Rng, neighbours: usize) -> (Disc, Vec<Disc>, Vec2) {
    random_scene_in(rng, neighbours, 7.0)
}

/// `neighbours` robots at least 2.05 apart within \[-spread, spread\]^2 around `me` at 0.
fn random_scene_in(
    rng: &mut ChaCha8Rng,
    neighbours: usize,
    spread: f64,
) -> (Disc, Vec<Disc>, Vec2) {
    let mut v = || Vec2::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)) * 0.7;
    let me = Disc {
        position: Vec2::zeros(),
        velocity: v(),
        radius: 1.0,
    };
    let mut others: Vec<Disc> = Vec::new();
    while others.len() < neighbours {
        let p = Vec2::new(
            rng.gen_range(-spread..spread),
            rng.gen_range(-spread..spread),
        );
        if p.norm() > 2.05 && others.iter().all(|o| (o.position - p).norm() > 2.05) {
            let vel = Vec2::new(rng.gen_range(-0.7..0.7), rng.gen_range(-0.7..0.7));
            others.push(Disc {
                position: p,
                velocity: vel,
                radius: 1.0,
            });
        }
    }
    let pref = Vec2::new(rng.gen_range(-1.5..1.5), rng.gen_range(-1.5..1.5));
    (me, others, pref)
}

#[test]
fn new_velocity_satisfies_every_half_plane_when_feasible() {
    let params = open_plane();
    let mut rng = ChaCha8Rng::seed_from_u64(40);
    let mut feasible = 0;
    for case in 0..1000 {
        let (me, robots, pref) = random_scene(&mut rng, 1 + case % 9);
        let obstacles = vec![disc(4.0, -4.5, 0.0, 0.0, 2.0)];
        if (obstacles[0].position - me.position).norm() <= 3.0 {
            continue;
        }
        let s = orca_velocity(&me, pref, &robots, &obstacles, &params);
        assert!(s.velocity.norm() <= params.max_speed + 1e-9);
        // Always inside the acceleration polygon (it is never relaxed).
        for h in acceleration_polygon(
            me.velocity,
            4.0 * params.time_step,
            params.accel_polygon_sides,
        ) {
            assert!(h.violation(s.velocity) < 1e-8);
        }
        if s.selection != Selection::Feasible {
            continue;
        }
        feasible += 1;
        let tau = params.time_step;
        for o in &robots {
            let h = orca_half_plane(&me, o, 0.5, params.time_horizon, tau);
            assert!(h.violation(s.velocity) < 1e-8, "case {case}");
        }
        let h = orca_half_plane(&me, &obstacles[0], 1.0, params.obstacle_time_horizon, tau);
        assert!(h.violation(s.velocity) < 1e-8, "case {case}");
    }
    assert!(feasible > 700, "{feasible}");
}

#[test]
fn two_robots_head_on_never_overlap_and_both_arrive() {
    let params = open_plane();
    let tau = params.time_step;
    let targets = [Vec2::new(16.0, 12.05), Vec2::new(8.0, 12.0)];
    // Exactly symmetric head-on starts deadlock ORCA (a known property: every half-plane is
    // then perpendicular to the line of centres; spec 6 item 12); 0.05 off the line breaks it.
    let mut robots = [
        disc(8.0, 12.0, 0.0, 0.0, 1.0),
        disc(16.0, 12.05, 0.0, 0.0, 1.0),
    ];
    let mut closest = f64::INFINITY;
    for _ in 0..400 {
        let next: Vec<Vec2> = (0..2)
            .map(|i| {
                let pref = preferred_velocity(
                    robots[i].position,
                    targets[i],
                    params.max_speed,
                    params.k_a,
                );
                orca_velocity(&robots[i], pref, &[robots[1 - i]], &[], &params).velocity
            })
            .collect();
        for i in 0..2 {
            robots[i].velocity = next[i];
            robots[i].position += next[i] * tau;
        }
        let d = (robots[0].position - robots[1].position).norm();
        closest = closest.min(d);
        assert!(d >= 2.0 - 1e-9, "overlap: {d}");
    }
    for i in 0..2 {
        assert!(
            (robots[i].position - targets[i]).norm() < params.epsilon,
            "{robots:?}"
        );
    }
    // They passed each other (so the test exercised avoidance), touching at most.
    assert!(closest < 2.5, "{closest}");
}

fn to_dodgy(d: &Disc, responsibility: f32) -> dodgy_2d::Agent {
    dodgy_2d::Agent {
        position: dodgy_2d::Vec2::new(d.position.x as f32, d.position.y as f32),
        velocity: dodgy_2d::Vec2::new(d.velocity.x as f32, d.velocity.y as f32),
        radius: d.radius as f32,
        avoidance_responsibility: responsibility,
    }
}

/// dodgy_2d's conventions, mapped: its responsibility is the ratio r_i / (r_i + r_j), so 1 and
/// 1 give c = 1/2, and an obstacle disc passed as an agent of responsibility 1e-6 gives c ~ 1.
/// Unlike RVO2 and the paper, it applies that ratio only when the relative velocity is inside
/// the velocity obstacle; outside it takes c = 1 (the full room up to the obstacle's boundary).
/// So the comparison builds our half-planes (`orca_half_plane`) with c chosen the same way
/// (inside iff u points along the outward normal) and solves them with our
/// `select_velocity`, robots soft and obstacles hard as `orca_velocity` does. dodgy_2d has one
/// horizon for agents, so our obstacle horizon equals it; it has no acceleration limit; it
/// computes in f32, hence the tolerance; its polygon obstacles are not used (ours are discs).
#[test]
fn agrees_with_dodgy_2d_on_random_cases() {
    let horizon = 2.0;
    let (tau, max_speed) = (0.25, 1.0);
    let options = dodgy_2d::AvoidanceOptions {
        obstacle_margin: 0.0,
        time_horizon: horizon as f32,
        obstacle_time_horizon: horizon as f32,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let (mut compared, mut agreed, mut relaxed_compared, mut relaxed_agreed) = (0, 0, 0, 0);
    let mut worst: f64 = 0.0;
    for case in 0..900 {
        // Every third case is crowded (neighbours within 3.6), where the 2-D program is often
        // infeasible and the 3-D fallback decides.
        let crowded = case % 3 == 2;
        let (me, robots, pref) = if crowded {
            random_scene_in(&mut rng, 5 + case % 4, 3.6)
        } else {
            random_scene(&mut rng, 1 + case % 7)
        };
        let with_obstacle = !crowded && case % 2 == 1;
        let obstacles: Vec<Disc> = if with_obstacle {
            let o = disc(
                rng.gen_range(-6.0..6.0),
                rng.gen_range(-6.0..6.0),
                0.0,
                0.0,
                2.0,
            );
            let clear = (o.position - me.position).norm() > 3.05
                && robots
                    .iter()
                    .all(|r| (r.position - o.position).norm() > 3.05);
            if !clear {
                continue;
            }
            vec![o]
        } else {
            vec![]
        };
        let line = |o: &Disc, ratio: f64| {
            let full = orca_half_plane(&me, o, 1.0, horizon, tau);
            let inside = (full.point - me.velocity).dot(&full.normal) > 0.0;
            if inside {
                orca_half_plane(&me, o, ratio, horizon, tau)
            } else {
                full
            }
        };
        let soft: Vec<HalfPlane> = robots.iter().map(|r| line(r, 0.5)).collect();
        let hard: Vec<HalfPlane> = obstacles
            .iter()
            .map(|o| line(o, 1.0 / (1.0 + 1e-6)))
            .collect();
        let ours = select_velocity(&[], &hard, &soft, max_speed, pref);
        let neighbours: Vec<Cow<dodgy_2d::Agent>> = robots
            .iter()
            .map(|r| Cow::Owned(to_dodgy(r, 1.0)))
            .chain(obstacles.iter().map(|o| Cow::Owned(to_dodgy(o, 1e-6))))
            .collect();
        let theirs = to_dodgy(&me, 1.0).compute_avoiding_velocity(
            &neighbours,
            &[],
            dodgy_2d::Vec2::new(pref.x as f32, pref.y as f32),
            max_speed as f32,
            tau as f32,
            &options,
        );
        let diff = (ours.velocity - Vec2::new(theirs.x as f64, theirs.y as f64)).norm();
        let feasible = ours.selection == Selection::Feasible;
        // With an obstacle our fallback holds it hard while dodgy_2d relaxes it with the
        // robots: only feasible cases are comparable there.
        if !feasible && with_obstacle {
            continue;
        }
        if feasible {
            compared += 1;
            worst = worst.max(diff);
            agreed += usize::from(diff < 2e-3);
        } else {
            relaxed_compared += 1;
            relaxed_agreed += usize::from(diff < 2e-3);
        }
    }
    eprintln!(
        "dodgy_2d: feasible {agreed}/{compared} agree (worst {worst:.2e}), \
         3-D fallback {relaxed_agreed}/{relaxed_compared}"
    );
    assert!(compared > 300, "{compared}");
    assert_eq!(agreed, compared, "worst difference {worst}");
    assert!(relaxed_compared > 10, "{relaxed_compared}");
    assert_eq!(relaxed_agreed, relaxed_compared);
}

#[test]
fn a_squeezed_robot_finds_a_one_step_safe_velocity_by_shrinking_the_horizon() {
    // Four neighbours 2.5 away (R = 2) close in on a robot at rest at speed 1 from the four
    // sides. Against a 2 s horizon each pair's half-plane asks the robot to move away from
    // that neighbour (opposite sides conflict: infeasible). At one step (0.25 s) the
    // truncated cone starts |p| / T - R / T = 2 away, beyond the closing speed 1: feasible.
    let me = disc(0.0, 0.0, 0.0, 0.0, 1.0);
    let others = [
        disc(2.5, 0.0, -1.0, 0.0, 1.0),
        disc(-2.5, 0.0, 1.0, 0.0, 1.0),
        disc(0.0, 2.5, 0.0, -1.0, 1.0),
        disc(0.0, -2.5, 0.0, 1.0, 1.0),
    ];
    let mut params = open_plane();
    let plain = orca_velocity(&me, Vec2::new(1.0, 0.0), &others, &[], &params);
    assert_ne!(plain.selection, Selection::Feasible);
    params.shrink_horizon_when_infeasible = true;
    let shrunk = orca_velocity(&me, Vec2::new(1.0, 0.0), &others, &[], &params);
    assert_eq!(shrunk.selection, Selection::Feasible);
    for o in &others {
        let h = orca_half_plane(&me, o, 0.5, params.time_step, params.time_step);
        assert!(h.violation(shrunk.velocity) <= 1e-9, "{o:?}: {shrunk:?}");
    }
    // Feasible scenes are not touched: one neighbour far away.
    let far = [disc(8.0, 0.0, 0.0, 0.0, 1.0)];
    assert_eq!(
        orca_velocity(&me, Vec2::new(1.0, 0.0), &far, &[], &params),
        orca_velocity(&me, Vec2::new(1.0, 0.0), &far, &[], &open_plane())
    );
}

#[test]
fn buffered_cells_give_the_hand_computed_half_gap_bound() {
    // A neighbour 2.2 to the right (true radii 1, ORCA radii 1.05): gap 0.2, this robot may
    // close half of it in one 0.25 s step: v_x <= (0.2 - 1e-6) / 2 / 0.25 = 0.399998. A disc
    // obstacle (radius 2) 3.1 above: gap 0.1, all of it: v_y <= (0.1 - 1e-6) / 0.25.
    let params = open_plane();
    let me = disc(0.0, 0.0, 0.0, 0.0, 1.05);
    let robots = [
        disc(2.2, 0.0, 0.0, 0.0, 1.05),
        disc(9.0, 0.0, 0.0, 0.0, 1.05),
    ];
    let obstacles = [disc(0.0, 3.1, 0.0, 0.0, 2.05)];
    let cells = buffered_cell_half_planes(&me, &robots, &obstacles, 0.05, &params);
    // The far robot (gap 7) cannot be reached in one step: no half-plane.
    assert_eq!(cells.len(), 2, "{cells:?}");
    assert!((cells[0].normal - Vec2::new(-1.0, 0.0)).norm() < 1e-12);
    assert!((cells[0].violation(Vec2::new(0.399998, 0.0))).abs() < 1e-9);
    assert!((cells[1].normal - Vec2::new(0.0, -1.0)).norm() < 1e-12);
    assert!((cells[1].violation(Vec2::new(0.0, 0.399996))).abs() < 1e-9);
    // Touching (gap below the slack): the step may not shrink it at all.
    let touching = [disc(2.0 + 1e-7, 0.0, 0.0, 0.0, 1.05)];
    let cells = buffered_cell_half_planes(&me, &touching, &[], 0.05, &params);
    assert!(cells[0].violation(Vec2::zeros()).abs() < 1e-12);
    assert!(cells[0].violation(Vec2::new(1e-6, 0.0)) > 0.0);
}

#[test]
fn in_a_crowd_with_buffered_cells_no_step_makes_an_overlap_even_when_orca_is_infeasible() {
    // Random packed crowds of 20, every robot crossing through the centre to the far side at
    // full speed, 40 steps: ORCA is often infeasible; with the buffered cells no pair is ever
    // closer than 2r after a step. Without them (ORCA and its 3-D fallback alone) some pairs
    // are, so the test can fail.
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let (mut infeasible, mut overlaps_without) = (0, 0);
    for _ in 0..30 {
        let mut start: Vec<Vec2> = Vec::new();
        while start.len() < 20 {
            let p = Vec2::new(rng.gen_range(0.0..13.0), rng.gen_range(0.0..13.0));
            if start.iter().all(|q| (p - q).norm() >= 2.0) {
                start.push(p);
            }
        }
        let centre = Vec2::new(6.5, 6.5);
        let goals: Vec<Vec2> = start.iter().map(|p| centre * 2.0 - p).collect();
        for cells in [true, false] {
            let params = FormationParams {
                buffered_cells: cells,
                ..open_plane()
            };
            let mut pos = start.clone();
            let mut vel = vec![Vec2::zeros(); pos.len()];
            for _ in 0..40 {
                let discs: Vec<Disc> = (0..pos.len())
                    .map(|i| Disc {
                        position: pos[i],
                        velocity: vel[i],
                        radius: 1.05,
                    })
                    .collect();
                for i in 0..pos.len() {
                    let others: Vec<Disc> = (0..pos.len())
                        .filter(|j| *j != i)
                        .map(|j| discs[j])
                        .collect();
                    let pref = preferred_velocity(pos[i], goals[i], 1.0, 1.0);
                    let s = orca_velocity(&discs[i], pref, &others, &[], &params);
                    if cells && s.selection != Selection::Feasible {
                        infeasible += 1;
                    }
                    assert!(s.velocity.norm() <= 1.0 + 1e-9);
                    vel[i] = s.velocity;
                }
                for i in 0..pos.len() {
                    pos[i] += vel[i] * params.time_step;
                }
                for i in 0..pos.len() {
                    for j in i + 1..pos.len() {
                        let d = (pos[i] - pos[j]).norm();
                        if cells {
                            assert!(d >= 2.0, "{i} {j}: {d}");
                        } else if d < 2.0 {
                            overlaps_without += 1;
                        }
                    }
                }
            }
        }
    }
    assert!(infeasible > 50, "{infeasible}");
    assert!(overlaps_without > 0, "{overlaps_without}");
}
