//! The blackboard act transport (`runtime.acts = "blackboard"`) against real iceoryx2, world
//! and agent sides in one process: attach, a lock-step action with its messages (in the head
//! and across chunks), a late action in real-time mode, and a dead agent's board
//! made anew for its replacement.

use swarm::air::ActTx;
use swarm::cleanup;
use swarm::frames::{Action, RadioHeader, BROADCAST};
use swarm::mailbox::Air;
use swarm::scenario::{ActsKind, Scenario};
use swarm::transport::{self, ActSink, ActSource};
use swarm::wire::RadioTx;

/// Removes the test's files however it ends.
struct Cleanup(String);
impl Drop for Cleanup {
    fn drop(&mut self) {
        cleanup::remove_run(&self.0);
    }
}

fn scenario(robots: u32, messages: u32, bytes: u32) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = robots;
    sc.radio.max_messages_per_tick = messages;
    sc.radio.max_message_bytes = bytes;
    sc.runtime.acts = ActsKind::Blackboard;
    sc
}

/// An action of tick `tick` with `n` messages of `len` bytes, each filled with
/// its index.
fn send(sink: &mut ActSink, tick: u64, n: u32, len: u32) {
    sink.send(|area| {
        let mut tx = ActTx::new(area);
        for m in 0..n {
            let h = RadioHeader {
                dest: BROADCAST,
                // A sender the world must not believe.
                sender: 99,
                len,
                seq: m,
                ..RadioHeader::default()
            };
            tx.transmit(&h, &mut |b| b.fill(m as u8 + 1));
        }
        Action {
            n_sent: n,
            radio_bytes: tx.used as u32,
            // A robot the world must not believe.
            ..Action::idle(tick, 1234)
        }
    })
    .unwrap();
}

fn senders_and_lens(air: &Air) -> Vec<(u32, usize, u8)> {
    air.messages()
        .map(|(h, p)| (h.sender, p.len(), p.first().copied().unwrap_or(0)))
        .collect()
}

#[test]
fn a_board_carries_attach_actions_and_messages() {
    transport::quiet_logs();
    let prefix = format!("swab{}_", std::process::id());
    let _cleanup = Cleanup(prefix.clone());
    // 3 messages of 3,000 bytes: 9,120 bytes of area, the head's 2,048 and two chunks.
    let sc = scenario(3, 3, 3000);
    assert_eq!(transport::act_board_chunks(&sc), 2);
    let config = transport::run_config(&prefix).unwrap();
    let world = transport::node(&config, "world").unwrap();
    let agent = transport::node(&config, "agent-1").unwrap();
    let mut src = ActSource::create(&world, &sc).unwrap();
    assert!(matches!(src, ActSource::Board(_)));
    assert_eq!(src.attached(&world, 1), 0);
    let mut sink = ActSink::open(&agent, &sc, 1, &|| true).unwrap();
    sink.attach(7).unwrap();
    assert_eq!(src.attached(&world, 1), 7);

    // Tick 0: nothing yet, then the action with three messages across head and chunks.
    assert!(!src.arrived(1, 0));
    send(&mut sink, 0, 3, 3000);
    assert!(src.arrived(1, 0));
    let mut sent = Air::default();
    let a = src.take(1, 0, &mut sent).unwrap();
    assert_eq!((a.robot, a.tick, a.n_sent), (1, 0, 3));
    // Every message stamped with the board's robot, whole.
    assert_eq!(
        senders_and_lens(&sent),
        vec![(1, 3000, 1), (1, 3000, 2), (1, 3000, 3)]
    );
    // Taken: not again.
    sent.clear();
    assert!(src.take(1, 0, &mut sent).is_none());
    // Another robot's board holds nothing.
    assert!(!src.arrived(2, 0));

    // Tick 1 (slot 1), a small action in the head alone.
    send(&mut sink, 1, 1, 100);
    let a = src.take(1, 1, &mut sent).unwrap();
    assert_eq!(a.tick, 1);
    assert_eq!(senders_and_lens(&sent), vec![(1, 100, 1)]);

    // Real-time: tick 2 written after its deadline, taken at tick 3's as late (its messages
    // after tick 3's); not taken twice.
    sent.clear();
    send(&mut sink, 2, 1, 10);
    send(&mut sink, 3, 2, 20);
    assert!(src.poll_realtime(1, 3, 0));
    assert!(src.holds(1, 3));
    let (cur, late) = src.take_realtime(1, 3, 0, &mut sent);
    assert_eq!(cur.map(|a| a.tick), Some(3));
    assert_eq!(late.map(|a| a.tick), Some(2));
    assert_eq!(
        senders_and_lens(&sent),
        vec![(1, 20, 1), (1, 20, 2), (1, 10, 1)]
    );
    sent.clear();
    assert!(!src.poll_realtime(1, 4, 0));
    assert_eq!(src.take_realtime(1, 4, 0, &mut sent), (None, None));
}

#[test]
fn a_dead_agents_board_is_made_anew_for_its_replacement() {
    transport::quiet_logs();
    let prefix = format!("swar{}_", std::process::id());
    let _cleanup = Cleanup(prefix.clone());
    let sc = scenario(2, 4, 256);
    let config = transport::run_config(&prefix).unwrap();
    let world = transport::node(&config, "world").unwrap();
    let mut src = ActSource::create(&world, &sc).unwrap();
    {
        let first = transport::node(&config, "agent-1").unwrap();
        let mut sink = ActSink::open(&first, &sc, 1, &|| true).unwrap();
        sink.attach(1).unwrap();
        assert_eq!(src.attached(&world, 1), 1);
        send(&mut sink, 0, 1, 8);
        assert!(src.arrived(1, 0));
        // The agent goes (its node and ports dropped, as the orchestrator's cleanup of a
        // dead node removes them); the world retires the board at the robot's death.
    }
    src.retire(1);
    // Made anew at the next look; the attach number seen so far stays.
    assert_eq!(src.attached(&world, 1), 1);
    let second = transport::node(&config, "agent-1").unwrap();
    let mut sink = ActSink::open(&second, &sc, 1, &|| true).unwrap();
    sink.attach(2).unwrap();
    assert_eq!(src.attached(&world, 1), 2);
    send(&mut sink, 5, 1, 8);
    let mut sent = Air::default();
    assert_eq!(src.take(1, 5, &mut sent).map(|a| a.tick), Some(5));
}
