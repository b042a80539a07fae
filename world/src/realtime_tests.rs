//! Real-time mode in `World::apply_with_late` (runtime.realtime_hz > 0): a robot with no
//! action of the tick keeps its last command and the miss is counted; a late action's
//! messages go out at the tick it is read, its command superseded.

use crate::world::World;
use swarm::frames::{Action, RadioHeader, BROADCAST};
use swarm::mailbox::Air;
use swarm::recording::Event;
use swarm::scenario::Scenario;
use swarm::wire::RadioTx;

/// Five roam robots in a row along y = 10, 100 apart (all within comm_radius 300 of robot 0
/// but robot 4); `realtime_hz` 0 is lock-step.
fn world(realtime_hz: f64) -> World {
    let mut sc = Scenario::roam();
    sc.run.robots = 5;
    sc.runtime.realtime_hz = realtime_hz;
    let mut w = World::new(&sc).unwrap();
    for i in 0..5 {
        w.poses[i] = [10.0 + i as f64 * 100.0, 10.0, 0.0];
    }
    w
}

fn moving(tick: u64, robot: u32, cmd: [f64; 2]) -> Option<Action> {
    let mut a = Action::idle(tick, robot);
    a.cmd = cmd;
    Some(a)
}

/// One broadcast of `len` bytes by `sender`, written into `air`; `a` says it sent it.
fn broadcast(air: &mut Air, a: &mut Action, len: u32) {
    let slot = a.n_sent as usize;
    a.sent_to[slot] = BROADCAST;
    a.n_sent += 1;
    let h = RadioHeader {
        sender: a.robot,
        len,
        seq: a.tick as u32 * 10 + slot as u32,
        ..Default::default()
    };
    air.transmit(&h, &mut |b| b.fill(7));
}

#[test]
fn a_robot_that_misses_its_deadline_keeps_its_last_command_and_the_miss_is_counted() {
    for (hz, second_x) in [(100.0, 12.0), (0.0, 11.0)] {
        let mut w = world(hz);
        let acts: Vec<_> = (0..5).map(|i| moving(0, i, [1.0, 0.0])).collect();
        w.begin_tick();
        w.apply_with_late(&acts, &[], &Air::default());
        assert_eq!(w.poses[0][0], 11.0);
        // Tick 1: robot 0 sent nothing in time.
        let mut acts: Vec<_> = (0..5).map(|i| moving(1, i, [1.0, 0.0])).collect();
        acts[0] = None;
        w.begin_tick();
        let rec = w.apply_with_late(&acts, &[], &Air::default());
        // Real-time: it moved on by its last command (x 11 -> 12); lock-step: it stood still.
        assert_eq!(w.poses[0][0], second_x, "realtime_hz {hz}");
        assert_eq!(w.poses[1][0], 112.0);
        let missed = rec
            .events
            .iter()
            .filter(|e| matches!(e, Event::DeadlineMissed { .. }))
            .count();
        if hz > 0.0 {
            assert_eq!(w.misses, vec![1, 0, 0, 0, 0]);
            assert_eq!(rec.events, vec![Event::DeadlineMissed { robot: 0 }]);
            assert_eq!(w.robot_ticks, 10);
        } else {
            assert_eq!((w.total_misses(), missed), (0, 0));
            assert_eq!(w.vel[0], [0.0, 0.0]);
        }
    }
}

#[test]
fn after_a_rejected_action_a_late_robot_stands_still() {
    let mut w = world(50.0);
    let mut acts: Vec<_> = (0..5).map(|i| moving(0, i, [1.0, 0.0])).collect();
    acts[0].as_mut().unwrap().cmd = [f64::NAN, 0.0];
    w.begin_tick();
    w.apply_with_late(&acts, &[], &Air::default());
    acts = (0..5).map(|i| moving(1, i, [1.0, 0.0])).collect();
    acts[0] = None;
    w.begin_tick();
    w.apply_with_late(&acts, &[], &Air::default());
    // Its last command was refused: it has none to keep.
    assert_eq!(w.poses[0][0], 10.0);
    assert_eq!(w.misses[0], 1);
}

#[test]
fn a_late_actions_messages_go_out_at_the_tick_it_is_read_and_its_command_is_superseded() {
    let mut w = world(100.0);
    // Tick 0: robot 0 misses; its action of tick 0 (one broadcast, a turn to +y) is read at
    // tick 1, beside its action of tick 1 (one broadcast, +x).
    let mut acts: Vec<_> = (0..5).map(|i| moving(0, i, [0.0, 0.0])).collect();
    acts[0] = None;
    w.begin_tick();
    let rec = w.apply_with_late(&acts, &[], &Air::default());
    assert_eq!(rec.radio.offered, 0);
    let mut air = Air::default();
    let mut late = moving(0, 0, [0.0, 1.0]).unwrap();
    broadcast(&mut air, &mut late, 5);
    let mut acts: Vec<_> = (0..5).map(|i| moving(1, i, [0.0, 0.0])).collect();
    let a0 = acts[0].as_mut().unwrap();
    a0.cmd = [1.0, 0.0];
    broadcast(&mut air, a0, 5);
    let mut lates = vec![None; 5];
    lates[0] = Some(late);
    w.begin_tick();
    let rec = w.apply_with_late(&acts, &lates, &air);
    // Both broadcasts are sent at tick 1: 2 x 4 other robots offered, robot 4 (400 away)
    // out of range each time.
    assert_eq!(rec.radio.offered, 8);
    assert_eq!(rec.radio.dropped_range, 2);
    assert_eq!(rec.radio.in_flight, 6);
    assert_eq!(w.late_actions, 1);
    assert_eq!(
        w.poses[0],
        [11.0, 10.0, 0.0],
        "the action of tick 1 moves it"
    );
    // At tick 2 robot 1's list holds both, in send order.
    w.begin_tick();
    let due = w.air().expect("due at tick 2");
    assert_eq!(due.deliveries(1).len(), 2);
    let acts: Vec<_> = (0..5).map(|i| moving(2, i, [0.0, 0.0])).collect();
    let rec = w.apply_with_late(&acts, &[], &Air::default());
    assert_eq!(rec.radio.delivered, 6);
    assert_eq!(w.radio.offered, w.radio.accounted());
}

#[test]
fn a_late_report_that_disagrees_with_its_messages_refuses_the_robots_radio() {
    let mut w = world(100.0);
    let mut air = Air::default();
    let mut late = moving(0, 0, [0.0, 0.0]).unwrap();
    broadcast(&mut air, &mut late, 5);
    late.n_sent = 2; // says two, sent one
    w.begin_tick();
    w.apply_with_late(&[None, None, None, None, None], &[], &Air::default());
    let mut lates = vec![None; 5];
    lates[0] = Some(late);
    let acts: Vec<_> = (0..5).map(|i| moving(1, i, [0.0, 0.0])).collect();
    w.begin_tick();
    let rec = w.apply_with_late(&acts, &lates, &air);
    assert_eq!(rec.radio.offered, 0);
    assert_eq!(w.rejected[4], 1, "bad_radio_report");
    assert_eq!(w.misses, vec![1; 5]);
}
