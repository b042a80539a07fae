use super::*;
use rand::{Rng, SeedableRng};
use swarm::frames::RadioHeader;

fn header(sender: u32, dest: u32, tick: u64, seq: u32, len: u32, pos: [f64; 3]) -> RadioHeader {
    RadioHeader {
        sender,
        dest,
        tick,
        seq,
        len,
        sender_pos: [pos[0], pos[1]],
    }
}

fn scenario(n: u32) -> Scenario {
    let mut sc = Scenario::roam();
    sc.run.robots = n;
    sc
}

/// Positions, liveness and messages of one tick.
type Traffic = (Vec<[f64; 3]>, Vec<bool>, Vec<(RadioHeader, Vec<u8>)>);

/// Random robots and traffic: every robot broadcasts once, some send a unicast too.
fn traffic(rng: &mut rand_chacha::ChaCha8Rng, n: usize, tick: u64) -> Traffic {
    let poses: Vec<[f64; 3]> = (0..n)
        .map(|_| [rng.gen_range(0.0..800.0), rng.gen_range(0.0..800.0), 0.0])
        .collect();
    let alive: Vec<bool> = (0..n).map(|_| rng.gen_bool(0.9)).collect();
    let mut msgs = Vec::new();
    for (s, &pos) in poses.iter().enumerate() {
        let len = rng.gen_range(1..40);
        msgs.push((
            header(s as u32, BROADCAST, tick, 1, len, pos),
            vec![s as u8; len as usize],
        ));
        if rng.gen_bool(0.3) {
            let d = rng.gen_range(0..n as u32 + 2);
            msgs.push((header(s as u32, d, tick, 2, 3, pos), vec![7; 3]));
        }
    }
    (poses, alive, msgs)
}

#[test]
fn the_medium_decides_as_the_receivers_did_and_its_counts_add_up() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut sc = scenario(60);
    sc.radio.loss = 0.3;
    let mut m = Medium::new(&sc, MediumParams::from_scenario(&sc));
    for tick in 0..20 {
        let (poses, alive, msgs) = traffic(&mut rng, 60, tick);
        let c = m.transmit(tick, msgs.iter().map(|(h, p)| (h, &p[..])), &poses, &alive);
        assert_eq!(
            c.offered,
            c.scheduled
                + c.dropped_range
                + c.dropped_loss
                + c.dropped_occluded
                + c.dropped_bandwidth
        );
        assert!(c.dropped_loss > 0 && c.scheduled > 0 && c.dropped_range > 0);
        let air = m.due(tick + 1).expect("due one tick later");
        assert_eq!(air.tick, tick);
        // Receiver by receiver: exactly the messages `decide` delivers, in (sender, seq) order.
        for r in 0..60u32 {
            let got: Vec<(u32, u32)> = air
                .deliveries(r)
                .iter()
                .map(|&i| {
                    let (h, p) = air.message(i).unwrap();
                    assert_eq!(p, &msgs.iter().find(|(g, _)| g == h).unwrap().1[..]);
                    (h.sender, h.seq)
                })
                .collect();
            let mut want: Vec<(u32, u32)> = msgs
                .iter()
                .filter(|(h, _)| {
                    let s = h.sender as usize;
                    alive[s]
                        && alive[r as usize]
                        && h.sender != r
                        && (h.dest == BROADCAST || h.dest == r)
                        && decide(
                            &sc.radio,
                            sc.run.seed,
                            tick,
                            h.sender,
                            h.sender_pos,
                            r,
                            [poses[r as usize][0], poses[r as usize][1]],
                            h.seq,
                        ) == Verdict::Deliver
                })
                .map(|(h, _)| (h.sender, h.seq))
                .collect();
            want.sort();
            assert_eq!(got, want, "receiver {r} tick {tick}");
        }
        assert_eq!(air.index.len() as u64, c.scheduled);
    }
}

#[test]
fn delay_holds_messages_and_in_flight_counts_what_is_not_due() {
    let mut sc = scenario(3);
    sc.radio.delay_ticks = 2;
    let mut m = Medium::new(&sc, MediumParams::from_scenario(&sc));
    let poses = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [20.0, 0.0, 0.0]];
    let alive = vec![true; 3];
    let h = header(0, BROADCAST, 5, 1, 2, poses[0]);
    m.transmit(5, [(&h, &[1u8, 2][..])], &poses, &alive);
    assert_eq!(m.in_flight(), 2);
    assert!(m.due(6).is_none() && m.due(7).is_none());
    let air = m.due(8).expect("sent at 5, delay 2: due at 8");
    assert_eq!(air.deliveries(1), &[0]);
    assert_eq!(air.deliveries(2), &[0]);
    assert!(air.deliveries(0).is_empty());
    assert_eq!(m.in_flight(), 0);
}

#[test]
fn the_bandwidth_cap_drops_a_senders_excess_in_send_order() {
    let sc = scenario(2);
    let mut p = MediumParams::from_scenario(&sc);
    // 40-byte header + 10 bytes: two messages fit in 100, the third does not.
    p.bandwidth_bytes_per_tick = 100;
    let mut m = Medium::new(&sc, p);
    let poses = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]];
    let msgs: Vec<RadioHeader> = (1..=3).map(|q| header(0, 1, 0, q, 10, poses[0])).collect();
    let payload = [0u8; 10];
    let c = m.transmit(
        0,
        msgs.iter().rev().map(|h| (h, &payload[..])),
        &poses,
        &[true, true],
    );
    assert_eq!((c.offered, c.scheduled, c.dropped_bandwidth), (3, 2, 1));
    let air = m.due(1).unwrap();
    let seqs: Vec<u32> = air
        .deliveries(1)
        .iter()
        .map(|&i| air.message(i).unwrap().0.seq)
        .collect();
    assert_eq!(seqs, vec![1, 2], "the first two sent go out");
}

#[test]
fn a_wall_between_two_robots_in_range_blocks_their_messages() {
    let mut sc = scenario(3);
    sc.arena.obstacles = vec![swarm::scenario::Obstacle {
        name: "wall".into(),
        points: vec![[100.0, 0.0], [102.0, 0.0], [102.0, 200.0], [100.0, 200.0]],
    }];
    let mut p = MediumParams::from_scenario(&sc);
    p.occlusion = true;
    let mut m = Medium::new(&sc, p);
    // Robot 1 behind the wall (in range: 100 apart), robot 2 on the same side.
    let poses = vec![[50.0, 100.0, 0.0], [150.0, 100.0, 0.0], [50.0, 150.0, 0.0]];
    let h = header(0, BROADCAST, 0, 1, 1, poses[0]);
    let c = m.transmit(0, [(&h, &[9u8][..])], &poses, &[true; 3]);
    assert_eq!((c.offered, c.scheduled, c.dropped_occluded), (2, 1, 1));
    let air = m.due(1).unwrap();
    assert!(air.deliveries(1).is_empty());
    assert_eq!(air.deliveries(2), &[0]);
}

#[test]
fn bursty_loss_on_the_medium_loses_at_the_chains_long_run_rate() {
    let sc = scenario(2);
    let mut p = MediumParams::from_scenario(&sc);
    let b = BurstParams {
        p_good_bad: 0.1,
        p_bad_good: 0.4,
        loss_good: 0.0,
        loss_bad: 1.0,
    };
    p.burst = Some(b);
    let mut m = Medium::new(&sc, p);
    let poses = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]];
    let (mut lost, n) = (0u64, 50_000u64);
    for t in 0..n {
        let h = header(0, 1, t, 1, 1, poses[0]);
        lost += m
            .transmit(t, [(&h, &[0u8][..])], &poses, &[true, true])
            .dropped_loss;
        m.due(t + 1);
    }
    let pi = b.long_run_loss();
    // lambda = 0.5: variance inflation (1.5 / 0.5) = 3.
    let sd = (pi * (1.0 - pi) / n as f64 * 3.0).sqrt();
    assert!(
        (lost as f64 / n as f64 - pi).abs() < 5.0 * sd,
        "{lost} of {n} vs {pi}"
    );
}
