use super::*;
use crate::section::SearchScenario;
use swarm::frames::Entity;

fn scenario(mode: &str) -> Scenario {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/search.toml");
    let mut sc = Scenario::load(&path).expect("configs/search.toml loads");
    sc.search_mut().mode = mode.into();
    sc
}

fn sense(pos: [f64; 2], signals: &[(u32, u32, f64)]) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.pos = pos;
    for (k, &(target, flags, intensity)) in signals.iter().enumerate() {
        s.entities[k] = Entity {
            id: target,
            kind: crate::section::ENTITY_SIGNAL,
            flags,
            reserved: 0,
            pos: [0.0; 2],
            value: intensity,
        };
    }
    s.n_entities = signals.len() as u32;
    s
}

fn status(pos: [f64; 2], detections: &[(u32, f32)], candidacy: Option<Candidacy>) -> Msg {
    Msg::Status(Status {
        pos: pack(pos),
        detections: detections.to_vec(),
        candidacy,
        found: TargetSet::default(),
    })
}

fn rx(from: u32, msg: Msg) -> Received<Msg> {
    Received {
        from,
        tick: 0,
        seq: 1,
        sender_pos: [0.0, 0.0],
        unicast: false,
        msg,
    }
}

fn speed(c: &Command) -> f64 {
    (c.cmd[0].powi(2) + c.cmd[1].powi(2)).sqrt()
}

fn signal_at(d: f64) -> f64 {
    1e4 / (d * d)
}

#[test]
fn type1_robot_picks_its_target_and_heads_for_the_estimate() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    let target = [500.0, 500.0];
    let me = [540.0, 500.0];
    let s = sense(me, &[(3, 0, signal_at(40.0))]);
    // Two other detectors of target 3, heard on the radio: with the own one, T_est exists.
    let inbox = vec![
        rx(
            1,
            status([500.0, 540.0], &[(3, signal_at(40.0) as f32)], None),
        ),
        rx(
            2,
            status([460.0, 500.0], &[(3, signal_at(40.0) as f32)], None),
        ),
    ];
    let c = r.step(&s, &inbox, &mut Outbox::new_for_tests(8));
    assert_eq!(c.events & 0xff, STATE_COOPERATIVE);
    match r.mode() {
        Mode::Cooperative {
            target: 3,
            role: Role::TypeI { .. },
        } => {}
        m => panic!("{m:?}"),
    }
    let est = r.last_estimate().expect("three detectors give T_est");
    assert!(
        (est - Vec2::new(target[0], target[1])).norm() < 3.0,
        "{est:?}"
    );
    let v = Vec2::new(c.cmd[0], c.cmd[1]);
    let to = Vec2::new(target[0] - me[0], target[1] - me[1]);
    assert!(
        v.norm() > 0.0 && v.dot(&to) / (v.norm() * to.norm()) > 0.99,
        "{v:?}"
    );
    assert!(speed(&c) <= sc.robot.v_max + 1e-12);
    // It announces itself as a Type I member of target 3 with its signal.
    let st = r.last_status().unwrap();
    let cand = st.candidacy.as_ref().unwrap();
    assert_eq!(cand.target, 3);
    assert!(cand.member);
    assert!(matches!(cand.role, WireRole::TypeI { .. }));
    assert_eq!(st.detections, vec![(3, signal_at(40.0) as f32)]);
}

#[test]
fn type1_keeps_its_previous_choice_among_several_targets() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 5);
    let sigs = [(1, 0, 5.0), (2, 0, 5.0), (4, 0, 5.0)];
    r.step(
        &sense([500.0, 500.0], &sigs),
        &[],
        &mut Outbox::new_for_tests(8),
    );
    let Mode::Cooperative { target: first, .. } = r.mode() else {
        panic!("{:?}", r.mode())
    };
    for _ in 0..20 {
        r.step(
            &sense([500.0, 500.0], &sigs),
            &[],
            &mut Outbox::new_for_tests(8),
        );
        let Mode::Cooperative { target, .. } = r.mode() else {
            panic!()
        };
        assert_eq!(target, first);
    }
    // Below I_min nothing is chosen.
    let mut q = Search::new(&sc, 6);
    q.step(
        &sense([500.0, 500.0], &[(1, 0, 0.9)]),
        &[],
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(q.mode(), Mode::Roaming);
}

fn type1_candidacy(target: u32, signal: f32) -> Option<Candidacy> {
    Some(Candidacy {
        target,
        role: WireRole::TypeI { signal },
        member: true,
        pb: None,
    })
}

fn type2_candidacy(target: u32, communicator: u32, distance: f32) -> Option<Candidacy> {
    Some(Candidacy {
        target,
        role: WireRole::TypeII {
            communicator,
            distance,
        },
        member: true,
        pb: None,
    })
}

#[test]
fn type2_robot_joins_the_nearest_type1_robot_heard() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    let me = [300.0, 300.0];
    let inbox = vec![
        // Robot 4: Type I of target 2, 200 away. Robot 9: Type I of target 7, 250 away.
        rx(
            4,
            status([500.0, 300.0], &[(2, 3.0)], type1_candidacy(2, 3.0)),
        ),
        rx(
            9,
            status([300.0, 550.0], &[(7, 3.0)], type1_candidacy(7, 3.0)),
        ),
        // Robot 11: Type I of target 5 but beyond R_cm.
        rx(
            11,
            status([300.0, 650.0], &[(5, 3.0)], type1_candidacy(5, 3.0)),
        ),
    ];
    let c = r.step(&sense(me, &[]), &inbox, &mut Outbox::new_for_tests(8));
    assert_eq!(c.events & 0xff, STATE_COOPERATIVE);
    match r.mode() {
        Mode::Cooperative {
            target: 2,
            role: Role::TypeII {
                distance_to_communicator,
            },
        } => assert!((distance_to_communicator - 200.0).abs() < 1e-3),
        m => panic!("{m:?}"),
    }
    let cand = r.last_status().unwrap().candidacy.clone().unwrap();
    assert!(matches!(
        cand.role,
        WireRole::TypeII {
            communicator: 4,
            ..
        }
    ));
    // Without any Type I robot heard it roams.
    let mut q = Search::new(&sc, 1);
    q.step(
        &sense(me, &[]),
        &[rx(3, status([310.0, 300.0], &[], None))],
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(q.mode(), Mode::Roaming);
}

#[test]
fn declaration_stops_the_robot_for_good() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 3);
    let c = r.step(
        &sense(
            [400.0, 400.0],
            &[(6, ENTITY_DONE_BY_YOU, 0.0), (1, 0, 50.0)],
        ),
        &[],
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(c.cmd, [0.0, 0.0]);
    assert_eq!(c.events & 0xff, STATE_DECLARED);
    assert_ne!(c.events & EVENT_TARGET_DECLARED, 0);
    assert_eq!(r.mode(), Mode::Declared { target: 6 });
    assert!(r.found_targets().contains(&6));
    // Later ticks: strong signals and Type I robots heard change nothing.
    for _ in 0..10 {
        let c = r.step(
            &sense([400.0, 400.0], &[(1, 0, 80.0)]),
            &[rx(
                2,
                status([420.0, 400.0], &[(1, 30.0)], type1_candidacy(1, 30.0)),
            )],
            &mut Outbox::new_for_tests(8),
        );
        assert_eq!(c.cmd, [0.0, 0.0]);
        assert_eq!(c.events, STATE_DECLARED);
    }
}

#[test]
fn members_of_a_found_target_return_to_roaming() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    let inbox = vec![rx(
        4,
        status([500.0, 300.0], &[(2, 3.0)], type1_candidacy(2, 3.0)),
    )];
    r.step(
        &sense([300.0, 300.0], &[]),
        &inbox,
        &mut Outbox::new_for_tests(8),
    );
    assert!(matches!(r.mode(), Mode::Cooperative { target: 2, .. }));
    // Robot 8 declares target 2; robot 4 still (one tick late) claims it.
    let inbox = vec![
        rx(
            4,
            status([500.0, 300.0], &[(2, 3.0)], type1_candidacy(2, 3.0)),
        ),
        rx(
            8,
            Msg::Found {
                target: 2,
                found: TargetSet::from_sorted([2]),
            },
        ),
    ];
    r.step(
        &sense([300.0, 300.0], &[]),
        &inbox,
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(r.mode(), Mode::Roaming);
    assert!(r.last_status().unwrap().found.contains(2));
}

#[test]
fn closed_loop_adjustment_drops_the_seventh_member() {
    let sc = scenario("BT");
    // One Type I robot (20) and five Type II robots (21..=25) of target 1, nearer to it than
    // robot 0 (the seventh) would be.
    let mut inbox = vec![rx(
        20,
        status([500.0, 500.0], &[(1, 2.0)], type1_candidacy(1, 2.0)),
    )];
    for k in 0..5u32 {
        let d = 100.0 + 10.0 * k as f32;
        inbox.push(rx(
            21 + k,
            status([500.0 - d as f64, 500.0], &[], type2_candidacy(1, 20, d)),
        ));
    }
    // Robot 0 at 250 from robot 20: ranked 7th of 7, dropped; it roams but stays a candidate.
    let mut r = Search::new(&sc, 0);
    let c = r.step(
        &sense([500.0, 250.0], &[]),
        &inbox,
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(r.mode(), Mode::Roaming);
    assert_eq!(c.events & 0xff, STATE_ROAMING);
    let cand = r.last_status().unwrap().candidacy.clone().unwrap();
    assert_eq!(cand.target, 1);
    assert!(!cand.member);
    // At 90 from robot 20 it outranks robot 25 (140 away) and stays.
    let mut q = Search::new(&sc, 0);
    q.step(
        &sense([500.0, 410.0], &[]),
        &inbox,
        &mut Outbox::new_for_tests(8),
    );
    assert!(matches!(q.mode(), Mode::Cooperative { target: 1, .. }));
    // Robot 25 (140 away), running the same rule on what it heard (robot 0 at 90), drops out.
    let mut inbox25: Vec<Received<Msg>> = inbox.iter().filter(|m| m.from != 25).cloned().collect();
    inbox25.insert(
        0,
        rx(0, status([500.0, 410.0], &[], type2_candidacy(1, 20, 90.0))),
    );
    let mut r25 = Search::new(&sc, 25);
    r25.step(
        &sense([360.0, 500.0], &[]),
        &inbox25,
        &mut Outbox::new_for_tests(8),
    );
    assert_eq!(r25.mode(), Mode::Roaming);
}

#[test]
fn roaming_is_repelled_by_the_two_nearest_robots_heard_and_keeps_heading_otherwise() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    let inbox = vec![
        rx(1, status([490.0, 500.0], &[], None)),
        rx(2, status([500.0, 490.0], &[], None)),
        rx(3, status([560.0, 560.0], &[], None)),
    ];
    let c = r.step(
        &sense([500.0, 500.0], &[]),
        &inbox,
        &mut Outbox::new_for_tests(8),
    );
    assert!((speed(&c) - 10.0).abs() < 1e-9);
    assert!(
        (c.cmd[0] - c.cmd[1]).abs() < 1e-9 && c.cmd[0] > 0.0,
        "{:?}",
        c.cmd
    );
    // Nothing heard: same heading.
    let c2 = r.step(
        &sense([507.0, 507.0], &[]),
        &[],
        &mut Outbox::new_for_tests(8),
    );
    assert!((c2.cmd[0] - c.cmd[0]).abs() < 1e-9 && (c2.cmd[1] - c.cmd[1]).abs() < 1e-9);
}

#[test]
fn obstacle_layer_applies_while_roaming() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    // Heading +x (pushed by a robot heard to the west) into a wall 30 ahead.
    let mut s = sense([500.0, 500.0], &[]);
    let wall: Vec<[f64; 2]> = (-40..=40)
        .map(|k| [530.0, 500.0 + 2.0 * k as f64])
        .collect();
    let mut sorted = wall.clone();
    sorted.sort_by(|a, b| {
        let da = (a[0] - 500.0).hypot(a[1] - 500.0);
        let db = (b[0] - 500.0).hypot(b[1] - 500.0);
        da.total_cmp(&db)
    });
    for (k, q) in sorted.iter().enumerate() {
        s.obstacle_points[k] = *q;
    }
    s.n_obstacle_points = sorted.len() as u32;
    let c = r.step(
        &s,
        &[rx(1, status([495.0, 500.0], &[], None))],
        &mut Outbox::new_for_tests(8),
    );
    assert!(c.cmd[1].abs() > 1.0, "deflected: {:?}", c.cmd);
    assert!(speed(&c) <= 10.0 + 1e-9);
}

#[test]
fn validation_accepts_every_mode_and_refuses_unknown_ones_and_keys() {
    for m in ["BT", "BE", "BA", "ST", "SE", "SA"] {
        validate_search(&scenario(m)).unwrap();
    }
    let e = validate_search(&scenario("XT")).unwrap_err();
    assert!(e.contains("B (BSOA) or S (SVF)"), "{e}");
    let e = validate_search(&scenario("BX")).unwrap_err();
    assert!(e.contains("T (TPEPSO), E (EPSO) or A (ARBA)"), "{e}");
    let mut sc = scenario("BA");
    sc.search_mut().kernels = "[arba]
loudness_decay = 1.5
"
    .parse()
    .unwrap();
    assert!(validate_search(&sc).unwrap_err().contains("loudness_decay"));
    let mut sc = scenario("BT");
    sc.search_mut().kernels = "[tpepso]\nomega = 0.4\n".parse().unwrap();
    assert!(validate_search(&sc).unwrap_err().contains("omega"));
    sc.search_mut().kernels = "declare_tickz = 2\n".parse().unwrap();
    assert!(validate_search(&sc).is_err());
    sc.search_mut().kernels = "declare_ticks = 5\n[subgroup]\ng_max = 4\n"
        .parse()
        .unwrap();
    validate_search(&sc).unwrap();
    let p = parse_params(&sc).unwrap();
    assert_eq!(
        (p.declare_ticks, p.subgroup.g_max, p.tpepso.c3),
        (5, 4, 1.2)
    );
    sc.search_mut().kernels = "[calibration]\nm = 0.2\n".parse().unwrap();
    assert!(validate_search(&sc).unwrap_err().contains("calibration.m"));
}

#[test]
fn same_seed_same_commands() {
    for mode in ["BT", "BA", "SA"] {
        let sc = scenario(mode);
        let run = |robot: u32| {
            let mut r = Search::new(&sc, robot);
            let mut v = Vec::new();
            for k in 0..30 {
                let s = sense(
                    [300.0 + k as f64, 300.0],
                    &[(1, 0, 3.0 + (k % 3) as f64), (2, 0, 2.5)],
                );
                v.push(r.step(&s, &[], &mut Outbox::new_for_tests(8)).cmd);
            }
            v
        };
        assert_eq!(run(7), run(7), "{mode}");
        assert_ne!(run(7), run(8), "{mode}: each robot has its own streams");
    }
}

#[test]
fn arba_robot_flies_to_the_subgroup_best_heard_on_the_radio() {
    for mode in ["BA", "SA"] {
        let sc = scenario(mode);
        let mut r = Search::new(&sc, 0);
        let me = [560.0, 500.0];
        let best = [505.0, 500.0];
        // A kept member of target 3's subgroup announces a pb much better than anything this
        // robot has measured: it becomes the robot's sgb = X* of the bat rule.
        let member = Candidacy {
            pb: Some((pack(best), signal_at(5.0) as f32)),
            ..type1_candidacy(3, signal_at(5.0) as f32).unwrap()
        };
        let inbox = vec![rx(
            1,
            status(best, &[(3, signal_at(5.0) as f32)], Some(member)),
        )];
        let c = r.step(
            &sense(me, &[(3, 0, signal_at(60.0))]),
            &inbox,
            &mut Outbox::new_for_tests(8),
        );
        assert_eq!(c.events & 0xff, STATE_COOPERATIVE, "{mode}");
        let (sgb, _) = r.subgroup_best().expect("sgb");
        assert!(
            (sgb - Vec2::new(best[0], best[1])).norm() < 1e-3,
            "{mode}: {sgb:?}"
        );
        // At rest, it either flies by frequency (f_i (X* − X_i)) or walks to within A_i V_max
        // of X*, 55 away: either way towards X*, at most V_max.
        let v = Vec2::new(c.cmd[0], c.cmd[1]);
        let to = Vec2::new(best[0] - me[0], best[1] - me[1]);
        assert!(
            speed(&c) > 0.0 && speed(&c) <= sc.robot.v_max + 1e-9,
            "{mode}: {v:?}"
        );
        assert!(v.dot(&to) / (v.norm() * to.norm()) > 0.95, "{mode}: {v:?}");
        // What it tells the others: its own pb, not the sgb it learnt.
        let pb = r.last_status().unwrap().candidacy.as_ref().unwrap().pb;
        assert_eq!(pb, Some((pack(me), signal_at(60.0) as f32)), "{mode}");
    }
}

/// Eq. (11)'s pb_i is "the best since the robot joined the subgroup" (paper 3.3): a Type II
/// robot that has measured nothing has none (no c1 term pulling it back to where it joined);
/// once it measures the target it has one; after a drop and a new join it starts empty again,
/// while the subgroup's sgb is kept (`keep_subgroup_best_across_gaps`).
#[test]
fn personal_best_is_the_best_since_joining() {
    let sc = scenario("BT");
    let mut r = Search::new(&sc, 0);
    let best = [500.0, 500.0];
    let member = Candidacy {
        pb: Some((pack(best), signal_at(20.0) as f32)),
        ..type1_candidacy(3, signal_at(20.0) as f32).unwrap()
    };
    let leader = || {
        vec![rx(
            4,
            status(best, &[(3, signal_at(20.0) as f32)], Some(member.clone())),
        )]
    };
    let mut out = Outbox::new_for_tests(8);
    // Tick 1: joins as Type II of robot 4 (200 away), senses nothing: no pb, sgb = 4's pb.
    r.step(&sense([700.0, 500.0], &[]), &leader(), &mut out);
    assert!(matches!(
        r.mode(),
        Mode::Cooperative {
            target: 3,
            role: Role::TypeII { .. }
        }
    ));
    assert_eq!(r.personal_best(), None);
    let (sgb, f) = r.subgroup_best().expect("sgb heard");
    assert!((sgb - Vec2::new(500.0, 500.0)).norm() < 1e-3 && f > 24.0);
    // With no pb the c1 term is absent: the status carries no pb either.
    assert_eq!(
        r.last_status().unwrap().candidacy.as_ref().unwrap().pb,
        None
    );
    // Tick 2: it measures the target below I_min (still Type II): that is its pb.
    r.step(&sense([690.0, 500.0], &[(3, 0, 0.5)]), &leader(), &mut out);
    let (pb, f) = r.personal_best().expect("measured");
    assert!((pb - Vec2::new(690.0, 500.0)).norm() < 1e-3 && (f - 0.5).abs() < 1e-12);
    // Tick 3: nobody heard, nothing sensed: it roams and forgets pb, keeps sgb.
    r.step(&sense([680.0, 500.0], &[]), &[], &mut out);
    assert_eq!(r.mode(), Mode::Roaming);
    // Tick 4: joins again: pb empty (since this join), sgb still the subgroup's.
    r.step(&sense([670.0, 500.0], &[]), &leader(), &mut out);
    assert!(matches!(r.mode(), Mode::Cooperative { target: 3, .. }));
    assert_eq!(r.personal_best(), None);
    assert!(r.subgroup_best().is_some());
}
