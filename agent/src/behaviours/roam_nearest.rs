//! The nearest robots heard, for roam's repulsion (docs/search.md 2.3-2.4, eq. 5: the two
//! nearest robots): one pass over the inbox, no sort and no allocation.
//!
//! Roam used to collect every heard robot and sort them all by (distance, sender); at N = 500
//! that sort of ~466 beacons a tick was ~30 % of the agents' CPU (BENCHMARKS.md section 11).
//! This keeps the same `K` robots, in the same order, as that stable sort's first `K`: the
//! key is (distance by `f64::total_cmp`, sender id), and of equal keys the one offered first
//! stays ahead, as the stable sort kept them. Roam's recordings are byte-identical to the
//! sort's (checked against main's binary; BENCHMARKS.md section 11).

use std::cmp::Ordering;

/// A heard robot: its distance, its id and the position it sent.
pub type Heard = (f64, u32, [f64; 2]);

/// The `K` smallest of the robots offered by (distance, sender), ties by first offered.
#[derive(Debug, Clone, Copy)]
pub struct Nearest<const K: usize> {
    best: [Heard; K],
    len: usize,
}

impl<const K: usize> Default for Nearest<K> {
    fn default() -> Self {
        Nearest {
            best: [(0.0, 0, [0.0; 2]); K],
            len: 0,
        }
    }
}

/// The sort's order: distance (total order, so a NaN from a garbled beacon sorts where
/// `total_cmp` puts it), then sender id.
fn key_cmp(a: &Heard, b: &Heard) -> Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

impl<const K: usize> Nearest<K> {
    /// Offers one heard robot. O(K).
    pub fn offer(&mut self, h: Heard) {
        // Where it goes: after every kept one whose key is not greater (stability).
        let mut at = self.len;
        while at > 0 && key_cmp(&h, &self.best[at - 1]) == Ordering::Less {
            at -= 1;
        }
        if at >= K {
            return;
        }
        let end = self.len.min(K - 1);
        // Shift the kept ones from `at` one place down (the last falls off when full).
        let mut i = end;
        while i > at {
            self.best[i] = self.best[i - 1];
            i -= 1;
        }
        self.best[at] = h;
        self.len = (self.len + 1).min(K);
    }

    /// The kept robots, nearest first.
    pub fn as_slice(&self) -> &[Heard] {
        &self.best[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// What roam did before: collect, stable-sort by (distance, sender), take K.
    fn by_sorting(all: &[Heard], k: usize) -> Vec<Heard> {
        let mut v = all.to_vec();
        v.sort_by(key_cmp);
        v.truncate(k);
        v
    }

    fn kept<const K: usize>(all: &[Heard]) -> Vec<Heard> {
        let mut n = Nearest::<K>::default();
        for &h in all {
            n.offer(h);
        }
        n.as_slice().to_vec()
    }

    fn bits(v: &[Heard]) -> Vec<(u64, u32, u64, u64)> {
        v.iter()
            .map(|h| (h.0.to_bits(), h.1, h.2[0].to_bits(), h.2[1].to_bits()))
            .collect()
    }

    #[test]
    fn keeps_the_two_nearest_by_distance_then_sender_then_arrival() {
        // Hand-made: distances 5, 3, 3 (sender 7), 3 (sender 2), 1.
        let all = [
            (5.0, 1, [0.0, 0.0]),
            (3.0, 7, [1.0, 0.0]),
            (3.0, 7, [2.0, 0.0]),
            (3.0, 2, [3.0, 0.0]),
            (9.0, 0, [4.0, 0.0]),
        ];
        // Sender 2 beats sender 7 at the same distance; of the two equal keys of sender 7
        // the first offered stays.
        assert_eq!(
            kept::<2>(&all),
            vec![(3.0, 2, [3.0, 0.0]), (3.0, 7, [1.0, 0.0])]
        );
        assert_eq!(
            kept::<3>(&all),
            vec![(3.0, 2, [3.0, 0.0]), (3.0, 7, [1.0, 0.0]), (3.0, 7, [2.0, 0.0])]
        );
        assert_eq!(kept::<2>(&all[..1]), vec![(5.0, 1, [0.0, 0.0])]);
        assert!(kept::<2>(&[]).is_empty());
    }

    #[test]
    fn matches_the_stable_sort_on_seeded_inboxes_with_ties_and_nans() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(15);
        for case in 0..3000 {
            let n = rng.gen_range(0..40);
            let all: Vec<Heard> = (0..n)
                .map(|i| {
                    // Few distinct distances and senders: many ties; now and then a NaN
                    // (either sign) or an infinity.
                    let d = match rng.gen_range(0..20) {
                        0 => f64::NAN,
                        1 => -f64::NAN,
                        2 => f64::INFINITY,
                        _ => rng.gen_range(0..6) as f64 * 0.5,
                    };
                    (d, rng.gen_range(0..8), [i as f64, case as f64])
                })
                .collect();
            assert_eq!(bits(&kept::<1>(&all)), bits(&by_sorting(&all, 1)), "{case}");
            assert_eq!(bits(&kept::<2>(&all)), bits(&by_sorting(&all, 2)), "{case}");
            assert_eq!(bits(&kept::<5>(&all)), bits(&by_sorting(&all, 5)), "{case}");
        }
    }
}
