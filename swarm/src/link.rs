//! Which robots an agent's transport is linked to (subscribed to the radio service of).
//!
//! The world's Sense frame lists the robots within comm_radius + link_margin (by id,
//! at most radio.max_links). The agent links to those, keeps a link for `linger` ticks after a
//! robot drops off the list (links cost ~1 ms to make on this VM, so churn is avoided), and
//! never holds more than max_links + radio.lingering_links. Both executors run this same code, so the set of messages a
//! receiver can see is the same in both.
//!
//! Why no in-range message is missed: a link made while handling Sense_k exists before any
//! robot sends at tick k+1. If d_{k+1}(r, s) <= R then d_k <= R + 2 v_max <= R + margin, so s was
//! listed at k. A link dropped while handling Sense_k belongs to a robot beyond R + margin at
//! k, whose tick-k messages are out of range anyway.

#[derive(Debug, Clone)]
pub struct LinkSet {
    /// Longest list the world sends.
    max_links: usize,
    /// Most links held: max_links plus the lingering slack.
    cap: usize,
    linger: u64,
    /// (robot, last tick it was listed, tick whose Sense created the link), sorted by robot id.
    links: Vec<(u32, u64, u64)>,
    /// Scratch of the merge in `update` (the next `links`).
    merged: Vec<(u32, u64, u64)>,
    added: Vec<u32>,
    removed: Vec<u32>,
    /// Scratch of `update`: one bit per robot id, all clear between calls.
    marks: Vec<u64>,
    /// The tick of the last `update` and whether its list was full (then robots within reach
    /// may be off it, on lingering links).
    last_update: Option<(u64, bool)>,
}

impl LinkSet {
    pub fn new(max_links: usize, lingering: usize, linger_ticks: u64) -> LinkSet {
        LinkSet {
            max_links,
            cap: max_links + lingering,
            linger: linger_ticks,
            links: Vec::new(),
            merged: Vec::new(),
            added: Vec::new(),
            removed: Vec::new(),
            marks: Vec::new(),
            last_update: None,
        }
    }

    /// Marks robot r; false (and no mark) for an id beyond any run's robots, which a corrupt
    /// frame could hold: the bitmap stays small.
    fn mark(&mut self, r: u32) -> bool {
        if r >= crate::scenario::MAX_ROBOTS {
            return false;
        }
        let w = r as usize / 64;
        if w >= self.marks.len() {
            self.marks.resize(w + 1, 0);
        }
        self.marks[w] |= 1 << (r % 64);
        true
    }

    /// Clears robot r's mark; whether it was set.
    fn unmark(marks: &mut [u64], r: u32) -> bool {
        match marks.get_mut(r as usize / 64) {
            Some(w) => {
                let bit = 1 << (r % 64);
                let was = *w & bit != 0;
                *w &= !bit;
                was
            }
            None => false,
        }
    }

    /// Applies Sense_k's neighbour list. Returns (added, removed), both sorted by robot id.
    pub fn update(&mut self, tick: u64, listed: &[u32], own: u32) -> (&[u32], &[u32]) {
        self.last_update = Some((tick, listed.len() >= self.max_links));
        self.added.clear();
        self.removed.clear();
        if listed.windows(2).all(|w| w[0] < w[1]) {
            // The world lists by robot id, as the links are kept: one merge of the two.
            self.merge(tick, listed, own);
        } else {
            self.mark_and_insert(tick, listed, own);
        }
        self.expire(tick)
    }

    /// `update` for a list sorted by robot id: links listed are refreshed, new ones made.
    fn merge(&mut self, tick: u64, listed: &[u32], own: u32) {
        if self.refresh_in_place(tick, listed, own) {
            return;
        }
        let mut merged = std::mem::take(&mut self.merged);
        merged.clear();
        let mut i = 0;
        for &r in listed {
            if r == own {
                continue;
            }
            while i < self.links.len() && self.links[i].0 < r {
                merged.push(self.links[i]);
                i += 1;
            }
            if i < self.links.len() && self.links[i].0 == r {
                merged.push((r, tick, self.links[i].2));
                i += 1;
            } else {
                merged.push((r, tick, tick));
                self.added.push(r);
            }
        }
        merged.extend_from_slice(&self.links[i..]);
        self.merged = std::mem::replace(&mut self.links, merged);
    }

    /// The usual tick of `merge`: every robot listed already has a link, so the links are
    /// only refreshed, in place. False (with the links listed so far refreshed, as the merge
    /// would) when a listed robot has none.
    fn refresh_in_place(&mut self, tick: u64, listed: &[u32], own: u32) -> bool {
        let mut i = 0;
        for &r in listed {
            if r == own {
                continue;
            }
            while i < self.links.len() && self.links[i].0 < r {
                i += 1;
            }
            match self.links.get_mut(i) {
                Some(l) if l.0 == r => {
                    l.1 = tick;
                    i += 1;
                }
                _ => return false,
            }
        }
        true
    }

    /// `update` for a list in any order (duplicates, own id and ids beyond any run allowed).
    fn mark_and_insert(&mut self, tick: u64, listed: &[u32], own: u32) {
        // Mark the listed robots; refresh the links to marked ones (unmarking them); what is
        // still marked is new. Linear in listed + links: every robot does this every tick, and
        // a search per listed robot cost more.
        for &r in listed {
            if r != own && !self.mark(r) {
                // Unmarkable: looked up instead.
                match self.links.binary_search_by_key(&r, |l| l.0) {
                    Ok(i) => self.links[i].1 = tick,
                    Err(i) => {
                        self.links.insert(i, (r, tick, tick));
                        self.added.push(r);
                    }
                }
            }
        }
        for l in self.links.iter_mut() {
            if Self::unmark(&mut self.marks, l.0) {
                l.1 = tick;
            }
        }
        for &r in listed {
            if r != own && Self::unmark(&mut self.marks, r) {
                self.added.push(r);
            }
        }
        for &r in &self.added {
            if let Err(i) = self.links.binary_search_by_key(&r, |l| l.0) {
                self.links.insert(i, (r, tick, tick));
            }
        }
    }

    /// The rest of `update`: drops links that lingered too long or exceed the cap.
    fn expire(&mut self, tick: u64) -> (&[u32], &[u32]) {
        let linger = self.linger;
        let removed = &mut self.removed;
        self.links.retain(|&(r, last, _)| {
            let keep = tick.saturating_sub(last) <= linger;
            if !keep {
                removed.push(r);
            }
            keep
        });
        while self.links.len() > self.cap {
            // Evict the link listed longest ago (ties: highest id). Listed ones have last == tick
            // and the world lists at most max_links <= cap, so only lingering links go.
            let (i, _) = self
                .links
                .iter()
                .enumerate()
                .min_by_key(|(_, &(r, last, _))| (last, std::cmp::Reverse(r)))
                .expect("non-empty");
            let (r, _, _) = self.links.remove(i);
            self.removed.push(r);
        }
        self.added.sort_unstable();
        self.removed.sort_unstable();
        // A robot can be added and evicted in one update only if the list exceeds max_links.
        let removed = &self.removed;
        self.added.retain(|r| removed.binary_search(r).is_err());
        (&self.added, &self.removed)
    }

    /// Whether a message sent by `sender` at tick `msg_tick` counts as received on this link.
    /// A link made while handling Sense_j carries only messages sent after tick j: whether
    /// one sent at j itself was seen depends on scheduling, so it never counts (the world
    /// counts it as unlinked). This keeps both executors identical even when max_links binds.
    #[inline]
    pub fn accepts(&self, sender: u32, msg_tick: u64) -> bool {
        match self.links.binary_search_by_key(&sender, |l| l.0) {
            Ok(i) => self.links[i].2 < msg_tick,
            Err(_) => false,
        }
    }

    /// The robot of the `i`-th link (in robot-id order) if that link carries messages sent at
    /// `msg_tick` (as [`LinkSet::accepts`]): lets a receiver walk its links instead of looking
    /// up each message's sender.
    #[inline]
    pub fn carrier(&self, i: usize, msg_tick: u64) -> Option<u32> {
        let &(r, _, created) = self.links.get(i)?;
        (created < msg_tick).then_some(r)
    }

    /// Whether link `i` may hold a message sent at `msg_tick` that is in range: it carries that
    /// tick's messages ([`LinkSet::carrier`]) and, unless that tick's list was full, its robot
    /// was on it. A linked robot off a list that was not full was beyond comm_radius +
    /// link_margin at `msg_tick`, so every message it sent then is out of range: the receiver
    /// need not even take it off its link. When the last list is not that tick's, or was
    /// full, the answer is "yes" (the messages are judged as usual).
    #[inline]
    pub fn reaching(&self, i: usize, msg_tick: u64) -> Option<u32> {
        let r = self.carrier(i, msg_tick)?;
        let last = self.links[i].1;
        match self.last_update {
            Some((t, false)) if t == msg_tick && last < msg_tick => None,
            _ => Some(r),
        }
    }

    /// [`LinkSet::reaching`] by robot id.
    pub fn reaches(&self, robot: u32, msg_tick: u64) -> bool {
        match self.links.binary_search_by_key(&robot, |l| l.0) {
            Ok(i) => self.reaching(i, msg_tick).is_some(),
            Err(_) => false,
        }
    }

    pub fn contains(&self, robot: u32) -> bool {
        self.links.binary_search_by_key(&robot, |l| l.0).is_ok()
    }

    pub fn robots(&self) -> impl Iterator<Item = u32> + '_ {
        self.links.iter().map(|l| l.0)
    }

    pub fn len(&self) -> usize {
        self.links.len()
    }

    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// Forgets a robot (its process died): the transport drops the link at once.
    pub fn forget(&mut self, robot: u32) -> bool {
        match self.links.binary_search_by_key(&robot, |l| l.0) {
            Ok(i) => {
                self.links.remove(i);
                true
            }
            Err(_) => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_follow_the_list_and_linger() {
        let mut l = LinkSet::new(8, 0, 2);
        let (a, r) = l.update(0, &[3, 1, 0], 0);
        assert_eq!((a.to_vec(), r.to_vec()), (vec![1, 3], vec![]));
        let (a, r) = l.update(1, &[1], 0);
        assert!(a.is_empty() && r.is_empty());
        assert!(l.contains(3)); // lingering
        l.update(2, &[1], 0);
        let (_, r) = l.update(3, &[1], 0);
        assert_eq!(r.to_vec(), vec![3]);
        assert!(!l.contains(3));
        assert!(l.accepts(1, 1) && !l.accepts(1, 0) && !l.accepts(3, 5));
        assert_eq!(
            (l.carrier(0, 1), l.carrier(0, 0), l.carrier(1, 1)),
            (Some(1), None, None)
        );
    }

    #[test]
    fn duplicates_and_own_id_in_the_list_are_harmless() {
        let mut l = LinkSet::new(8, 0, 2);
        let (a, _) = l.update(0, &[70, 3, 70, 5, 3], 5);
        assert_eq!(a.to_vec(), vec![3, 70]);
        let (a, r) = l.update(1, &[3, 200, 3, u32::MAX - 1, u32::MAX - 1], 5);
        assert_eq!((a.to_vec(), r.to_vec()), (vec![200, u32::MAX - 1], vec![]));
        assert_eq!(
            l.robots().collect::<Vec<_>>(),
            vec![3, 70, 200, u32::MAX - 1]
        );
        assert!(l.marks.iter().all(|w| *w == 0) && l.marks.len() <= 4);
        let (a, r) = l.update(2, &[u32::MAX - 1], 5);
        assert!(a.is_empty() && r.is_empty());
    }

    /// One tick's list applied to `a` by marking and to `b` by `update`: the same links and the
    /// same (added, removed).
    fn update_both(a: &mut LinkSet, b: &mut LinkSet, tick: u64, list: &[u32], own: u32) {
        a.last_update = Some((tick, list.len() >= a.max_links));
        a.added.clear();
        a.removed.clear();
        a.mark_and_insert(tick, list, own);
        let (aa, ar) = a.expire(tick);
        let (aa, ar) = (aa.to_vec(), ar.to_vec());
        let (ba, br) = b.update(tick, list, own);
        assert_eq!((aa, ar), (ba.to_vec(), br.to_vec()), "tick {tick}");
        assert_eq!(a.links, b.links, "tick {tick}");
    }

    #[test]
    fn the_merge_of_a_sorted_list_keeps_the_same_links_as_marking() {
        let (mut a, mut b) = (LinkSet::new(6, 3, 4), LinkSet::new(6, 3, 4));
        let mut x: u64 = 12345;
        for tick in 0..400u64 {
            let mut list: Vec<u32> = Vec::new();
            for r in 0..20u32 {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                if (x >> 33).is_multiple_of(3) && list.len() < 6 {
                    list.push(r);
                }
            }
            let own = (tick % 20) as u32;
            update_both(&mut a, &mut b, tick, &list, own);
        }
    }

    #[test]
    fn refreshing_in_place_keeps_the_same_links_as_marking() {
        // Lists that change slowly (one robot in or out every few ticks), so most updates
        // refresh in place and some insert.
        let (mut a, mut b) = (LinkSet::new(8, 3, 5), LinkSet::new(8, 3, 5));
        let mut x: u64 = 777;
        let mut on = [false; 16];
        let (mut same, mut changed) = (0, 0);
        for tick in 0..600u64 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if (x >> 33).is_multiple_of(3) {
                let r = ((x >> 40) % 16) as usize;
                on[r] = !on[r];
                changed += 1;
            } else {
                same += 1;
            }
            let list: Vec<u32> = (0..16u32).filter(|&r| on[r as usize]).take(8).collect();
            let own = 15;
            update_both(&mut a, &mut b, tick, &list, own);
        }
        assert!(same > 300 && changed > 100);
    }

    #[test]
    fn a_lingering_link_off_the_last_list_does_not_reach() {
        let mut l = LinkSet::new(3, 1, 100);
        l.update(0, &[1, 2], 0);
        l.update(1, &[1], 0);
        // Tick 1's list was not full: 2 was beyond reach at tick 1.
        assert_eq!((l.reaching(0, 1), l.reaching(1, 1)), (Some(1), None));
        assert!(l.reaches(1, 1) && !l.reaches(2, 1) && !l.reaches(9, 1));
        // Messages of another tick than the last list's: no claim.
        assert_eq!(l.reaching(1, 2), Some(2));
        // A full list may have left robots in reach off it: their links may carry.
        l.update(2, &[1, 3, 4], 0);
        assert_eq!(l.robots().collect::<Vec<_>>(), vec![1, 2, 3, 4]);
        assert_eq!(l.reaching(1, 2), Some(2));
        // Made while handling tick 2's list: carries nothing of tick 2.
        assert_eq!(
            l.reaching(l.robots().position(|r| r == 3).unwrap(), 2),
            None
        );
    }

    #[test]
    fn never_more_than_the_cap_lingering_evicted_first() {
        let mut l = LinkSet::new(3, 0, 100);
        l.update(0, &[1, 2, 3], 0);
        let (a, r) = l.update(1, &[4, 5, 1], 0);
        assert_eq!(a.to_vec(), vec![4, 5]);
        assert_eq!(r.to_vec(), vec![2, 3]);
        assert_eq!(l.robots().collect::<Vec<_>>(), vec![1, 4, 5]);
        // With slack, robots that fall off a full list stay linked up to the cap.
        let mut l = LinkSet::new(3, 2, 100);
        l.update(0, &[1, 2, 3], 0);
        let (a, r) = l.update(1, &[4, 1, 2], 0);
        assert_eq!((a.to_vec(), r.to_vec()), (vec![4], vec![]));
        let (a, r) = l.update(2, &[5, 6, 1], 0);
        assert_eq!((a.to_vec(), r.to_vec()), (vec![5, 6], vec![3]));
        assert_eq!(l.robots().collect::<Vec<_>>(), vec![1, 2, 4, 5, 6]);
    }
}
