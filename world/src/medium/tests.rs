use super::*;
use rand::{Rng, SeedableRng};
use swarm::frames::RadioHeader;
use swarm::radio::decide;

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

/// Hands `msgs` to the medium as the world does: headers, and payloads back to back.
fn send(
    m: &mut Medium,
    tick: u64,
    msgs: &[(RadioHeader, Vec<u8>)],
    poses: &[[f64; 3]],
    alive: &[bool],
) -> Counts {
    let mut sent = Vec::new();
    let mut bytes = Vec::new();
    for (h, p) in msgs {
        sent.push((*h, bytes.len()));
        bytes.extend_from_slice(p);
    }
    m.transmit(tick, &sent, &bytes, poses, alive)
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
        let c = send(&mut m, tick, &msgs, &poses, &alive);
        for t in [c.pairs, c.bytes] {
            assert_eq!(
                t.offered,
                t.scheduled
                    + t.dropped_range
                    + t.dropped_loss
                    + t.dropped_occluded
                    + t.dropped_bandwidth
            );
        }
        let c = c.pairs;
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
    send(&mut m, 5, &[(h, vec![1u8, 2])], &poses, &alive);
    assert_eq!(m.in_flight(), 2);
    assert_eq!(m.in_flight_bytes(), 4);
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
    let msgs: Vec<(RadioHeader, Vec<u8>)> = (1..=3)
        .rev()
        .map(|q| (header(0, 1, 0, q, 10, poses[0]), vec![0u8; 10]))
        .collect();
    let c = send(&mut m, 0, &msgs, &poses, &[true, true]);
    let p = c.pairs;
    assert_eq!((p.offered, p.scheduled, p.dropped_bandwidth), (3, 2, 1));
    let b = c.bytes;
    assert_eq!((b.offered, b.scheduled, b.dropped_bandwidth), (30, 20, 10));
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
    let c = send(&mut m, 0, &[(h, vec![9u8])], &poses, &[true; 3]).pairs;
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
        lost += send(&mut m, t, &[(h, vec![0u8])], &poses, &[true, true])
            .pairs
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

/// Every receiver's list of `air` (message headers' (sender, seq)), for comparing two airs.
fn lists(air: &TickAir, n: u32) -> Vec<Vec<(u32, u32)>> {
    (0..n)
        .map(|r| {
            air.deliveries(r)
                .iter()
                .map(|&i| {
                    let h = air.message(i).unwrap().0;
                    (h.sender, h.seq)
                })
                .collect()
        })
        .collect()
}

#[test]
fn the_grid_gives_the_deliveries_and_counts_of_the_scan_over_every_robot() {
    // Random layouts from dense (every robot in range) to sparse, with loss, bursts,
    // occlusion, per-sender ranges and a delay: the two scans agree message for message.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    for case in 0..40u64 {
        let n = rng.gen_range(2..90);
        let mut sc = scenario(n as u32);
        sc.radio.comm_radius = [300.0, 120.0, 40.0, 5.0][case as usize % 4];
        sc.radio.loss = 0.2;
        sc.radio.occlusion = case % 3 == 0;
        if case % 5 == 1 {
            sc.radio.burst = Some(BurstParams {
                p_good_bad: 0.2,
                p_bad_good: 0.3,
                loss_good: 0.05,
                loss_bad: 0.9,
            });
        }
        if case % 2 == 0 {
            sc.radio.loss_model = swarm::scenario::LossModel::Distance;
        }
        sc.radio.sender_ranges = vec![swarm::scenario::SenderRange {
            agent: (case as u32) % n as u32,
            comm_radius: 700.0,
        }];
        sc.radio.delay_ticks = (case % 2) as u32;
        let mut all = sc.clone();
        all.radio.range_scan = swarm::scenario::RangeScan::All;
        let mut g = Medium::new(&sc, MediumParams::from_scenario(&sc));
        let mut a = Medium::new(&all, MediumParams::from_scenario(&all));
        let delay = sc.radio.delay_ticks as u64;
        for tick in 0..6 {
            let (poses, alive, msgs) = traffic(&mut rng, n, tick);
            let cg = send(&mut g, tick, &msgs, &poses, &alive);
            let ca = send(&mut a, tick, &msgs, &poses, &alive);
            assert_eq!(cg, ca, "case {case} tick {tick}");
            match (g.due(tick + 1 + delay), a.due(tick + 1 + delay)) {
                (Some(x), Some(y)) => {
                    assert_eq!(lists(&x, n as u32), lists(&y, n as u32), "case {case}");
                    assert_eq!(x, y, "case {case} tick {tick}: the whole air");
                    g.recycle(x);
                    a.recycle(y);
                }
                (None, None) => {}
                _ => panic!("case {case}: one scan has an air, the other not"),
            }
        }
    }
}

#[test]
fn a_sender_with_its_own_range_reaches_only_within_it() {
    let mut sc = scenario(4);
    sc.radio.comm_radius = 100.0;
    // Robot 3 (a station, say) reaches 500; robot 0 only 20.
    sc.radio.sender_ranges = vec![
        swarm::scenario::SenderRange {
            agent: 3,
            comm_radius: 500.0,
        },
        swarm::scenario::SenderRange {
            agent: 0,
            comm_radius: 20.0,
        },
    ];
    let mut m = Medium::new(&sc, MediumParams::from_scenario(&sc));
    let poses = vec![
        [0.0, 0.0, 0.0],
        [50.0, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        [400.0, 0.0, 0.0],
    ];
    let alive = [true; 4];
    let msgs = vec![
        (header(0, BROADCAST, 0, 1, 5, poses[0]), vec![0; 5]),
        (header(1, BROADCAST, 0, 1, 7, poses[1]), vec![1; 7]),
        (header(3, BROADCAST, 0, 1, 11, poses[3]), vec![3; 11]),
    ];
    let c = send(&mut m, 0, &msgs, &poses, &alive);
    // 0 (range 20) reaches 2 (10 away), not 1 (50) or 3 (400). 1 (range 100) reaches 0 and 2,
    // not 3 (350). 3 (range 500) reaches all three (400, 350, 390 away).
    let air = m.due(1).unwrap();
    assert_eq!(
        lists(&air, 4),
        vec![
            vec![(1, 1), (3, 1)],
            vec![(3, 1)],
            vec![(0, 1), (1, 1), (3, 1)],
            vec![],
        ]
    );
    assert_eq!(
        (c.pairs.offered, c.pairs.scheduled, c.pairs.dropped_range),
        (9, 6, 3)
    );
    // Bytes: 0's 5 to one and out of range to two; 1's 7 to two, one out; 3's 11 to three.
    assert_eq!(c.bytes.offered, 3 * 5 + 3 * 7 + 3 * 11);
    assert_eq!(c.bytes.scheduled, 5 + 2 * 7 + 3 * 11);
    assert_eq!(c.bytes.dropped_range, 2 * 5 + 7);
    assert_eq!(
        (0..4).map(|r| air.bytes_to(r)).collect::<Vec<_>>(),
        vec![7 + 11, 11, 5 + 7 + 11, 0]
    );
}

#[test]
fn a_hunt_auctioneer_with_a_radio_range_transmits_within_it() {
    let sc = Scenario::parse(
        include_str!("../../../configs/hunt-example-3a.toml"),
        "hunt-example-3a.toml",
    )
    .unwrap();
    let station = sc.bodies() as usize;
    assert!(sender_ranges(&sc, &sc.radio)
        .iter()
        .all(|&r| r == sc.radio.comm_radius));
    let mut sc2 = sc.clone();
    sc2.hunt_mut().auctioneer.radio_range = 2.0;
    let r = sender_ranges(&sc2, &sc2.radio);
    assert_eq!(r[station], sc.radio.comm_radius.min(2.0));
    assert!(r[..station].iter().all(|&x| x == sc.radio.comm_radius));
    // An entry of its own wins.
    sc2.radio.sender_ranges = vec![swarm::scenario::SenderRange {
        agent: station as u32,
        comm_radius: 7.0,
    }];
    assert_eq!(sender_ranges(&sc2, &sc2.radio)[station], 7.0);
}

/// `transmit_lent` decides and counts as `transmit`, and the air written from the sender's
/// buffer is byte for byte the air of the copying medium; with a delay it copies.
#[test]
fn a_lent_air_is_the_copied_air_written_from_the_senders_buffer() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    for delay in [0, 2] {
        let mut sc = scenario(40);
        sc.radio.loss = 0.3;
        sc.radio.delay_ticks = delay;
        let mut copied = Medium::new(&sc, MediumParams::from_scenario(&sc));
        let mut lent = Medium::new(&sc, MediumParams::from_scenario(&sc));
        for tick in 0..12 {
            let (poses, alive, msgs) = traffic(&mut rng, 40, tick);
            let mut sent = Vec::new();
            let mut bytes = Vec::new();
            for (h, p) in &msgs {
                sent.push((*h, bytes.len()));
                bytes.extend_from_slice(p);
            }
            let a = copied.transmit(tick, &sent, &bytes, &poses, &alive);
            let b = lent.transmit_lent(tick, &sent, &bytes, &poses, &alive);
            assert_eq!(a, b);
            let (x, y) = (copied.due(tick + 1), lent.due(tick + 1));
            assert_eq!(x.is_some(), y.is_some(), "tick {tick} delay {delay}");
            if let (Some(x), Some(y)) = (x, y) {
                assert_eq!(y.lent, delay == 0);
                let len = swarm::air::air_len(Some(&x), 40);
                assert_eq!(len, swarm::air::air_len(Some(&y), 40));
                let (mut ox, mut oy) = (vec![0u8; len], vec![1u8; len]);
                let hx = swarm::air::write_air(Some(&x), 40, tick + 1, &mut ox);
                let hy = swarm::air::write_air_from(Some(&y), &bytes, 40, tick + 1, &mut oy);
                assert_eq!((hx, &ox), (hy, &oy), "tick {tick} delay {delay}");
                assert!(x.pairs() > 0);
                copied.recycle(x);
                lent.recycle(y);
            }
        }
    }
}
