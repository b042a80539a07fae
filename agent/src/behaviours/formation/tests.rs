use super::*;
use swarm::frames::Sense;

fn scenario() -> Scenario {
    Scenario::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/formation.toml"
    )))
    .unwrap()
}

fn sense(robot: u32, tick: u64, pos: [f64; 2], alive: u32) -> Box<Sense> {
    let mut s = Sense::zeroed();
    s.robot = robot;
    s.tick = tick;
    s.pos = pos;
    s.alive_robots = alive;
    s
}

fn status_from(from: u32, tick: u64, pos: [f64; 2]) -> Received<Msg> {
    Received {
        from,
        tick,
        seq: 0,
        sender_pos: pos,
        unicast: false,
        msg: Msg::Status(Status {
            pos,
            vel: [0.0, 0.0],
            slot: -1,
            epoch: 0,
        }),
    }
}

#[test]
fn the_lowest_id_heard_plans_once_it_heard_every_live_robot_and_the_others_follow() {
    let sc = scenario();
    let starts: Vec<[f64; 2]> = (0..9).map(|i| [2.0 + 2.5 * i as f64, 2.0]).collect();
    let mut robots: Vec<Formation> = (0..9).map(|i| Formation::new(&sc, i)).collect();
    // Tick 0: nobody heard anyone: no plan.
    let mut out = Outbox::new_for_tests(8);
    robots[0].step(&sense(0, 0, starts[0], 9), &[], &mut out);
    assert!(robots[0].plan().is_none());
    // Tick 1: robot 0 hears 1..8, robot 3 hears 0..8 but 3: 0 plans, 3 does not.
    let heard: Vec<Received<Msg>> = (1..9).map(|j| status_from(j, 0, starts[j as usize])).collect();
    let mut out = Outbox::new_for_tests(8);
    let c = robots[0].step(&sense(0, 1, starts[0], 9), &heard, &mut out);
    assert_eq!(c.report[2], REPORT_PLAN);
    let plan = robots[0].plan().unwrap().clone();
    assert_eq!((plan.epoch, plan.coordinator), (1, 0));
    assert_eq!(plan.members, (0..9).collect::<Vec<u32>>());
    // sigma is a permutation.
    let mut s = plan.slots.clone();
    s.sort_unstable();
    assert_eq!(s, (0..9).collect::<Vec<u16>>());
    let sent: Vec<&Msg> = out.queued().iter().map(|(_, m)| m).collect();
    assert!(sent.iter().any(|m| matches!(m, Msg::Plan(_))));
    let heard3: Vec<Received<Msg>> = (0..9)
        .filter(|j| *j != 3)
        .map(|j| status_from(j, 0, starts[j as usize]))
        .collect();
    let mut out3 = Outbox::new_for_tests(8);
    robots[3].step(&sense(3, 1, starts[3], 9), &heard3, &mut out3);
    assert!(robots[3].plan().is_none());
    // Tick 2: robot 3 hears the plan and takes sigma's slot; the slots are eq. (5)'s.
    let mut inbox = vec![Received {
        from: 0,
        tick: 1,
        seq: 1,
        sender_pos: starts[0],
        unicast: false,
        msg: Msg::Plan(plan.clone()),
    }];
    inbox.extend((0..9).filter(|j| *j != 3).map(|j| status_from(j, 1, starts[j as usize])));
    let mut out3 = Outbox::new_for_tests(8);
    let c3 = robots[3].step(&sense(3, 2, starts[3], 9), &inbox, &mut out3);
    assert_eq!(robots[3].slot(), Some(plan.slots[3] as usize));
    assert_eq!(robots[3].targets(), robots[0].targets());
    let q = robots[3].targets()[plan.slots[3] as usize];
    assert_eq!(c3.report, [q.x, q.y, plan.slots[3] as f64, 1.0]);
    // It moves towards its slot at no more than v_max per tick.
    let step = Vec2::new(c3.cmd[0], c3.cmd[1]);
    assert!(step.norm() <= sc.robot.v_max);
    assert!(step.dot(&(q - Vec2::new(starts[3][0], starts[3][1]))) > 0.0);
}

#[test]
fn a_silent_member_is_replanned_away_by_the_lowest_robot_left() {
    let sc = scenario();
    let starts: Vec<[f64; 2]> = (0..9).map(|i| [2.0 + 2.5 * i as f64, 2.0]).collect();
    let mut r1 = Formation::new(&sc, 1);
    // Robot 1 hears everyone at tick 0 and robot 0's plan... here robot 1 plans itself once
    // robot 0 is silent: first it hears all (0 included) and is not the coordinator.
    let all: Vec<Received<Msg>> = (0..9)
        .filter(|j| *j != 1)
        .map(|j| status_from(j, 0, starts[j as usize]))
        .collect();
    let mut out = Outbox::new_for_tests(8);
    r1.step(&sense(1, 1, starts[1], 9), &all, &mut out);
    assert!(r1.plan().is_none());
    // From tick 1 on robot 0 is silent; past lost_after_ticks robot 1 is the lowest heard.
    let lost = sc.formation().as_ref().unwrap().lost_after_ticks as u64;
    let mut planned_at = None;
    for k in 2..lost + 4 {
        let others: Vec<Received<Msg>> = (2..9)
            .map(|j| status_from(j, k - 1, starts[j as usize]))
            .collect();
        let mut out = Outbox::new_for_tests(8);
        let c = r1.step(&sense(1, k, starts[1], 8), &others, &mut out);
        if c.report[2] == REPORT_PLAN {
            planned_at.get_or_insert(k);
        }
    }
    assert_eq!(planned_at, Some(lost + 1));
    let plan = r1.plan().unwrap();
    assert_eq!(plan.members, (1..9).collect::<Vec<u32>>());
    assert_eq!(plan.points.len(), 8);
    assert_eq!(plan.coordinator, 1);
}

fn swaps_scenario() -> Scenario {
    Scenario::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/formation-swaps-16.toml"
    )))
    .unwrap()
}

fn slot_status(from: u32, tick: u64, pos: Vec2, slot: i32) -> Received<Msg> {
    Received {
        from,
        tick,
        seq: 0,
        sender_pos: [pos.x, pos.y],
        unicast: false,
        msg: Msg::Status(Status {
            pos: [pos.x, pos.y],
            vel: [0.0, 0.0],
            slot,
            epoch: 0,
        }),
    }
}

#[test]
fn under_swaps_a_death_makes_the_lowest_robot_heard_since_re_plan_around_the_wreck() {
    let sc = swaps_scenario();
    let mut robots: Vec<Formation> = (0..16).map(|i| Formation::new(&sc, i)).collect();
    // Tick 0: the fixed pattern, robot i on slot i; every robot sits on its slot.
    let mut at = Vec::new();
    for (i, r) in robots.iter_mut().enumerate() {
        let mut out = Outbox::new_for_tests(8);
        r.step(&sense(i as u32, 0, [1.0 + 1.5 * i as f64, 1.0], 16), &[], &mut out);
        assert_eq!(r.slot(), Some(i));
        at = r.targets().to_vec();
    }
    // Robot 5 died at tick 30 on its slot: robot 0 senses the wreck (an obstacle point off
    // every static boundary) and hears statuses sent at tick 30 from the 14 others only.
    let wreck = at[5];
    let heard: Vec<Received<Msg>> = (1..16)
        .filter(|j| *j != 5)
        .map(|j| slot_status(j, 30, at[j as usize], j as i32))
        .collect();
    // At the tick of the death (30) the statuses of tick 29, robot 5's among them, prove
    // nothing: no plan yet.
    let old: Vec<Received<Msg>> = (1..16).map(|j| slot_status(j, 29, at[j as usize], j as i32)).collect();
    let mut s = sense(0, 30, [at[0].x, at[0].y], 15);
    s.obstacle_points[0] = [wreck.x, wreck.y];
    s.n_obstacle_points = 1;
    let mut out = Outbox::new_for_tests(8);
    let c = robots[0].step(&s, &old, &mut out);
    assert_ne!(c.report[2], REPORT_PLAN);
    assert_eq!(robots[0].plan().unwrap().epoch, 0);
    // Robot 0 tells the others of the wreck its plan was not made around.
    assert!(out
        .queued()
        .iter()
        .any(|(_, m)| *m == Msg::Wrecks(vec![[wreck.x, wreck.y]])));
    let mut s = sense(0, 31, [at[0].x, at[0].y], 15);
    s.obstacle_points[0] = [wreck.x, wreck.y];
    s.n_obstacle_points = 1;
    let mut out = Outbox::new_for_tests(8);
    let c = robots[0].step(&s, &heard, &mut out);
    assert_eq!(c.report[2], REPORT_PLAN);
    let plan = robots[0].plan().unwrap().clone();
    assert_eq!((plan.epoch, plan.coordinator), (1, 0));
    let members: Vec<u32> = (0..16).filter(|j| *j != 5).collect();
    assert_eq!(plan.members, members);
    // The unheld slot 5 (the dead robot's) left the pattern; every other template point stays.
    let points: Vec<u16> = (0..16).filter(|j| *j != 5).collect();
    assert_eq!(plan.points, points);
    assert_eq!(plan.dead, vec![[wreck.x, wreck.y]]);
    let mut sigma = plan.slots.clone();
    sigma.sort_unstable();
    assert_eq!(sigma, (0..15).collect::<Vec<u16>>());
    // C2 with the wreck as one more obstacle centre: every new slot outside the square of
    // half-side r_o + r + margin = 2 + 1 + 0.1 around it.
    for q in robots[0].targets() {
        let d = (q - wreck).abs();
        assert!(d.x.max(d.y) >= 3.1 - 1e-9, "{q:?}");
    }
    assert!(out.queued().iter().any(|(_, m)| *m == Msg::Plan(plan.clone())));
    // Robot 1 heard robot 0 since the death: it does not plan, and adopts robot 0's plan.
    let mut heard1: Vec<Received<Msg>> = (0..16)
        .filter(|j| *j != 5 && *j != 1)
        .map(|j| slot_status(j, 30, at[j as usize], j as i32))
        .collect();
    let mut out = Outbox::new_for_tests(8);
    let c = robots[1].step(&sense(1, 31, [at[1].x, at[1].y], 15), &heard1, &mut out);
    assert_ne!(c.report[2], REPORT_PLAN);
    heard1.push(Received {
        from: 0,
        tick: 31,
        seq: 1,
        sender_pos: [at[0].x, at[0].y],
        unicast: false,
        msg: Msg::Plan(plan.clone()),
    });
    let mut out = Outbox::new_for_tests(8);
    let c = robots[1].step(&sense(1, 32, [at[1].x, at[1].y], 15), &heard1, &mut out);
    assert_eq!(robots[1].targets(), robots[0].targets());
    assert_eq!(robots[1].slot(), Some(plan.slots[1] as usize));
    assert_eq!(c.report[3], 1.0);
    // It repeats the plan for the others.
    assert!(out.queued().iter().any(|(_, m)| matches!(m, Msg::Plan(p) if p.epoch == 1)));
}

/// A coordinator mode whose plan cannot fit one message is refused at load, naming the key,
/// the sizes and the allowed values; swaps (the compact plan) are accepted.
#[test]
fn a_coordinator_plan_too_large_for_one_message_is_refused_and_swaps_accepted() {
    let mut sc = Scenario::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../configs/formation-500.toml"
    )))
    .unwrap();
    assert!(crate::behaviours::validate(&sc, "formation-500.toml").is_ok());
    sc.formation_mut().as_mut().unwrap().reassignment = Reassignment::PerStep;
    let e = crate::behaviours::validate(&sc, "formation-500.toml").unwrap_err();
    assert_eq!(e.key, "formation.reassignment");
    let need = compact::full_plan_len(500, 0);
    assert!(need > 512, "{need}");
    assert!(e.message.contains(&need.to_string()), "{}", e.message);
    assert!(e.message.contains("\"swaps\""), "{}", e.message);
    assert!(e.message.contains("[formation.kernels.relay]"), "{}", e.message);
    sc.radio.max_message_bytes = need as u32;
    assert!(crate::behaviours::validate(&sc, "formation-500.toml").is_ok());
}

/// The relayed mode at 500 robots is accepted at 512 bytes and 8 messages a tick; chunks too
/// large for a message, or too many for a tick, are refused naming the key to change.
#[test]
fn the_relayed_mode_is_checked_against_the_message_size_and_the_messages_per_tick() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../configs/formation-500-centralised.toml");
    let mut sc = Scenario::load(std::path::Path::new(path)).unwrap();
    let validate = |sc: &Scenario| crate::behaviours::validate(sc, "formation-500-centralised.toml");
    assert!(validate(&sc).is_ok(), "{:?}", validate(&sc).err());
    let set = |sc: &mut Scenario, key: &str, v: i64| {
        let f = sc.formation_mut().unwrap();
        let relay = f.kernels.get_mut("relay").and_then(|r| r.as_table_mut()).unwrap();
        relay.insert(key.into(), toml::Value::Integer(v));
    };
    set(&mut sc, "sigma_chunk", 400);
    let e = validate(&sc).unwrap_err();
    assert_eq!(e.key, "formation.kernels.relay.sigma_chunk", "{e:?}");
    assert!(e.message.contains("max_message_bytes = 512"), "{}", e.message);
    set(&mut sc, "sigma_chunk", 50);
    let e = validate(&sc).unwrap_err();
    assert_eq!(e.key, "formation.kernels.relay.sigma_chunk", "{e:?}");
    assert!(e.message.contains("max_messages_per_tick = 8"), "{}", e.message);
    set(&mut sc, "sigma_chunk", 150);
    set(&mut sc, "entries_per_message", 40);
    let e = validate(&sc).unwrap_err();
    assert_eq!(e.key, "formation.kernels.relay.entries_per_message", "{e:?}");
}

/// A remembered wreck on this robot or on a live neighbour is stale and dropped; one touching a
/// live robot (2 r apart, a real wreck can be that close) and one in free space are kept.
#[test]
fn stale_wrecks_on_live_robots_are_dropped_and_real_ones_kept() {
    let r = 1.0;
    let me = Vec2::new(0.0, 0.0);
    let live = [Disc {
        position: Vec2::new(10.0, 0.0),
        velocity: Vec2::zeros(),
        radius: r,
    }];
    let remembered = vec![
        Vec2::new(0.3, 0.0),  // on this robot: it was taken for lost
        Vec2::new(10.5, 0.5), // on the live neighbour
        Vec2::new(12.0, 0.0), // touching the neighbour: a wreck can lie there
        Vec2::new(5.0, 5.0),  // free space
    ];
    let kept = real_wrecks(remembered, me, &live, r);
    assert_eq!(kept, vec![Vec2::new(12.0, 0.0), Vec2::new(5.0, 5.0)]);
}
