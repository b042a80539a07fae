//! The relayed mode's flows on a line of robots, each hearing only its two neighbours (a
//! multi-hop swarm), with seeded loss.

use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Robots with ids `ids` on a line; one round of every robot's `Up` to its neighbours (each
/// message lost with `loss`), then the election, the absorption and its own entry.
fn round(relays: &mut [Relay], k: u64, loss: f64, rng: &mut ChaCha8Rng, dead: &[usize]) {
    let sent: Vec<Option<Up>> = relays
        .iter_mut()
        .enumerate()
        .map(|(i, r)| (!dead.contains(&i)).then(|| r.up(k, 4)))
        .collect();
    for (i, r) in relays.iter_mut().enumerate() {
        if dead.contains(&i) {
            continue;
        }
        let heard: Vec<&Up> = [i.wrapping_sub(1), i + 1]
            .iter()
            .filter_map(|j| sent.get(*j).and_then(|u| u.as_ref()))
            .filter(|_| rng.gen::<f64>() >= loss)
            .collect();
        let beacons: Vec<(u32, u64, u16)> = heard.iter().map(|u| (u.root, u.stamp as u64, u.hops)).collect();
        r.elect(k + 1, &beacons);
        for u in heard {
            r.absorb(u);
        }
        r.note_self(k + 1, Vec2::new(i as f64, 0.0), Vec2::zeros());
    }
}

const IDS: [u32; 12] = [5, 3, 8, 10, 9, 2, 7, 11, 1, 6, 4, 0];

fn line(timeout: u64) -> Vec<Relay> {
    IDS.iter()
        .enumerate()
        .map(|(i, id)| {
            let mut r = Relay::new(*id, timeout);
            r.note_self(0, Vec2::new(i as f64, 0.0), Vec2::zeros());
            r
        })
        .collect()
}

/// The ticks until robot `root` holds a position newer than `since` of every live robot.
fn gathered(relays: &[Relay], root: usize, since: u64, live: usize) -> bool {
    relays[root].fresh_since(since).count() >= live
}

#[test]
fn on_a_lossless_line_the_lowest_id_is_elected_and_gathers_every_position() {
    let mut relays = line(30);
    let root = IDS.iter().position(|i| *i == 0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut k = 0;
    while !gathered(&relays, root, 1, IDS.len()) {
        round(&mut relays, k, 0.0, &mut rng, &[]);
        k += 1;
        assert!(k < 40, "not gathered in 40 rounds");
    }
    assert!(relays.iter().all(|r| r.root == 0), "every robot holds root 0");
    // Hops are the line distance to the root (it stands at the end).
    for (i, r) in relays.iter().enumerate() {
        assert_eq!(r.hops as usize, root - i, "robot {i}");
    }
    // 11 hops: the farthest entry needs at least 11 rounds; with 4 entries a message and
    // the round robin it may take a few more, not many.
    assert!((11..=20).contains(&k), "gathered in {k} rounds");
}

#[test]
fn on_a_lossy_line_every_entry_arrives_and_a_dead_root_is_replaced_by_the_next_lowest() {
    let timeout = 12 * 3;
    let mut relays = line(timeout);
    let root = IDS.iter().position(|i| *i == 0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut k = 0;
    while !gathered(&relays, root, 1, IDS.len()) {
        round(&mut relays, k, 0.3, &mut rng, &[]);
        k += 1;
        assert!(k < 120, "not gathered in 120 rounds at loss 0.3");
    }
    // Root 0 dies: after the timeout every robot falls back, and robot 1 (the next lowest,
    // at index 8) is elected and gathers the 11 left.
    let dead = [root];
    let died = k;
    let next = IDS.iter().position(|i| *i == 1).unwrap();
    while !(relays.iter().enumerate().all(|(i, r)| i == root || r.root == 1)
        && gathered(&relays, next, died + 1, IDS.len() - 1))
    {
        round(&mut relays, k, 0.3, &mut rng, &dead);
        k += 1;
        assert!(k < died + timeout + 120, "no new root gathered by tick {k}");
    }
    assert!(k > died + timeout / 2, "a dead root's stamp is trusted for the timeout");
    assert!(relays[next].fresh_since(died + 1).all(|e| e.id != 0), "the dead root's entry is not fresh");
}

#[test]
fn sigma_chunks_cover_the_members_and_the_rank_in_the_bitmap_indexes_them() {
    let mut members = Bitmap::with_len(500);
    let ids: Vec<u32> = (0..500).filter(|i| i % 7 != 3).collect();
    for i in &ids {
        members.insert(*i as usize);
    }
    let sigma: Vec<u16> = (0..ids.len() as u16).rev().collect();
    let parts = chunks(2, 0, 40, &sigma, 150);
    assert_eq!(parts.len(), ids.len().div_ceil(150));
    for (n, id) in ids.iter().enumerate() {
        let i = member_index(&members, *id).expect("a member");
        assert_eq!(i, n);
        let c = parts.iter().find(|c| (c.first as usize..c.first as usize + c.slots.len()).contains(&i)).unwrap();
        assert_eq!(c.slots[i - c.first as usize], sigma[n]);
    }
    assert_eq!(member_index(&members, 3), None);
    // Every part of 500 robots fits 512 bytes.
    for c in &parts {
        assert!(encoded_len(&Msg::Sigma(c.clone())) <= 512);
    }
}
