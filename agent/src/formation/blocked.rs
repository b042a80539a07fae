//! Beyond the paper and beyond the pairwise rule of swaps.rs: the blocked-robot swap (ours;
//! docs/formation.md 9, "The slow tail of a packed pattern (swaps)").
//!
//! In a packed pattern a robot can arrive late at a slot that robots already in place enclose
//! (the gap between two of them under one diameter). ORCA lets it squeeze in only as fast as
//! the in-place robots yield their reciprocal half (their preferred velocity is zero): measured
//! 2200 ticks for one robot of 500. No pairwise swap helps, since every swap with an in-place
//! neighbour raises the summed squared distance (eq. 4) a little. The rule: a robot that made
//! less than `progress` towards its slot in the last `wait_ticks` ticks, while farther than
//! `min_distance` from it, proposes a swap to an in-place neighbour that stands in its way
//! (its disc meets the corridor from the robot to its slot), paying at most `max_price` in
//! summed squared distance. The in-place robot then steps into the vacant slot it is next to
//! (no one stands between them), and the blocked robot takes the slot it left. Both make and
//! accept no other swap for `hold_ticks` (hysteresis: right after the swap the pairwise rule
//! would gain exactly the price by swapping back). The handshake is the one of swaps.rs, so
//! slots stay unique under loss the same way.
//!
//! Making way (2026-12-04): once its blocked swap stands, the blocked robot backs away from
//! its partner at `make_way_speed` V_p until it is `make_way_steps` steps clear of ORCA's
//! contact with it, then holds still, until the partner is within `in_place` of the slot it took or `hold_ticks` pass
//! (swaps.rs `making_way`; the behaviour turns the preferred velocity). Without it a head-on
//! pair in a packed pattern (slots 2.15 apart, ORCA's contact 2.1) could not pass each other:
//! neither moved, and after `hold_ticks` a pairwise swap undid the blocked one (500 robots,
//! seed 4, docs/formation.md 9).
//!
//! An escaping robot (2026-12-06; behaviours/formation/escape.rs): its way to the slot runs
//! round wrecks, so the straight corridor and the straight price mislead. While it escapes
//! its own cost is its planned way's length squared (`SwapAgent::set_path_length`), it may ask
//! any in-place neighbour in range, and its proposal carries that cost (`from_cost`), which
//! the receiver prices by too. Measured: fourteen ids seed 2 at 100 robots, a robot boxed in by
//! three wrecks and two parked robots, one of them with its slot beside it, formed (K 450; it
//! stood for good before: the swap with that robot cost 26.4 at the straight price).
//!
//! A blocked robot is farther than `min_distance` from its slot and a receiver within
//! `in_place` of its own, and `min_distance >= in_place` (checked at load), so no robot is
//! both: blocked proposals never form a chain among themselves.

use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// The blocked-robot swap's numbers (`formation.kernels.swaps.blocked`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BlockedParams {
    /// The rule on or off. [chosen] true: on formation-100/500 it removed the slow tails it
    /// was built for and left the overlaps at 0 (docs/formation.md 9).
    pub enabled: bool,
    /// A robot is blocked after this many ticks without `progress` towards its slot.
    /// [chosen] 60 (15 s): a stall, not a detour in a crowd; the tails it removes were
    /// hundreds to thousands of ticks long (tried: 30 with `min_distance` 1.0, see there).
    pub wait_ticks: u64,
    /// The gain in distance to its slot that counts as progress. [chosen] 0.25: one step
    /// (V_p tau) of configs/formation-100/500.toml.
    pub progress: f64,
    /// A robot nearer than this to its slot is not blocked. [chosen] 2.0 = 2 r: its disc is
    /// then clear of its slot's (it stands outside the ring, not part-way in; the enclosed
    /// robot of the trace stood 2.5 from its slot). Tried 1.0 (with `wait_ticks` 30): the
    /// rule then fired on robots squeezing the last unit in (118 blocked swaps at 500 robots,
    /// seed 3, no kill) and K rose on 5 of 6 runs at 500 (512 -> 723 on seed 3).
    pub min_distance: f64,
    /// A neighbour within this of its slot is "in place" and may be asked. [chosen] 1.0 = r
    /// (in-place robots pushed by a squeezing one were measured 0.4-0.8 off their slots); it
    /// may not exceed `min_distance`.
    pub in_place: f64,
    /// Half-width of the corridor from the blocked robot to its slot: a neighbour whose centre
    /// lies within it (and between the two ends) stands in the way. [chosen] 2.0 = 2 r: its
    /// disc then meets the disc swept along the segment.
    pub corridor: f64,
    /// The most the pair's summed squared distance (eq. 4) may rise by the swap. [chosen]
    /// 10.0 squared units, about twice the square of the slots' spacing 2.2: the enclosed
    /// robot of the trace would have paid 3.2 (9.3 against 6.1).
    pub max_price: f64,
    /// After a blocked swap both robots make and accept no swap for this many ticks (the
    /// swap back would gain the price until they have moved). [chosen] 40: the in-place robot
    /// moves one spacing (2.2) in 9 ticks at V_p tau = 0.25, four times that for a crowd.
    pub hold_ticks: u64,
    /// A robot takes part in at most this many blocked swaps (either side) per plan, and
    /// never twice with the same partner in a row: each one raises the summed cost by up to
    /// `max_price`, so the rule ends, and two robots stalled near one jam cannot hand the
    /// blocked role back and forth (measured before this guard: 500 robots, seed 8, kill
    /// 150:37, robots 398 and 451 swapped four times in 280 ticks). [chosen] 4.
    pub max_swaps: u32,
    /// Making way: the blocked robot backs away from its partner at this fraction of V_p
    /// after its blocked swap stands. [chosen] 0.5: half a step a tick is enough to open the
    /// 0.05-0.1 a packed lattice lacks within a few ticks, and keeps it from running into the
    /// robots behind it. 0: no making way.
    pub make_way_speed: f64,
    /// ... until it is this many steps (V_p tau) clear of ORCA's contact 2 (r + orca_margin)
    /// with the partner, then it holds still. [chosen] 2.0: room for the partner's step in;
    /// backing away for the whole hold (up to 5 units) took a 100-robot run from K 534 to
    /// 1212 (docs/formation.md 9).
    pub make_way_steps: f64,
}

impl Default for BlockedParams {
    fn default() -> Self {
        Self {
            enabled: true,
            wait_ticks: 60,
            progress: 0.25,
            min_distance: 2.0,
            in_place: 1.0,
            corridor: 2.0,
            max_price: 10.0,
            hold_ticks: 40,
            max_swaps: 4,
            make_way_speed: 0.5,
            make_way_steps: 2.0,
        }
    }
}

/// Progress of a robot towards its slot: the slot watched, the distance at the last gain of
/// `progress`, and its tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Watch {
    target: usize,
    reference: f64,
    since: u64,
}

impl Watch {
    /// Starts (or restarts, after a new slot or a gain of `progress`) the watch, and returns
    /// whether the robot is blocked at tick `now`, `distance` from slot `target`.
    pub fn update(
        watch: &mut Option<Watch>,
        now: u64,
        target: usize,
        distance: f64,
        p: &BlockedParams,
    ) -> bool {
        match watch {
            Some(w) if w.target == target && distance > w.reference - p.progress => {}
            _ => {
                *watch = Some(Watch {
                    target,
                    reference: distance,
                    since: now,
                })
            }
        }
        let w = watch.expect("set above");
        distance > p.min_distance && now >= w.since + p.wait_ticks
    }
}

/// Whether a neighbour at `other` stands in the way from `from` to `slot`: its centre within
/// `corridor` of the segment, strictly between the two ends along it.
pub fn in_the_way(from: Vec2, slot: Vec2, other: Vec2, corridor: f64) -> bool {
    let d = slot - from;
    let len = d.norm();
    if len <= 0.0 {
        return false;
    }
    let u = d / len;
    let rel = other - from;
    let t = rel.dot(&u);
    let lateral = (rel - u * t).norm();
    t > 0.0 && t < len && lateral < corridor
}

/// Whether a robot at `position`, holding the slot at `mine`, accepts a blocked robot's
/// proposal at `price` (the pair's rise in summed squared distance): it is in place and the
/// price within bounds.
pub fn accepts(position: Vec2, mine: Vec2, price: f64, p: &BlockedParams) -> bool {
    p.enabled && (position - mine).norm() <= p.in_place && price <= p.max_price
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_corridor_holds_what_stands_between_and_nothing_behind_or_beside() {
        let (a, b) = (Vec2::zeros(), Vec2::new(4.0, 0.0));
        assert!(in_the_way(a, b, Vec2::new(2.0, 1.9), 2.0));
        assert!(!in_the_way(a, b, Vec2::new(2.0, 2.1), 2.0));
        assert!(!in_the_way(a, b, Vec2::new(-0.5, 0.0), 2.0));
        assert!(!in_the_way(a, b, Vec2::new(4.5, 0.0), 2.0));
        assert!(!in_the_way(a, a, Vec2::new(0.5, 0.0), 2.0));
    }

    #[test]
    fn a_robot_is_blocked_after_wait_ticks_without_a_steps_progress() {
        let p = BlockedParams::default();
        let w_ticks = p.wait_ticks;
        let mut w = None;
        // 0.2 in wait_ticks is less than a step (0.25): blocked at tick wait_ticks.
        for now in 0..w_ticks {
            let d = 3.0 - 0.2 * now as f64 / w_ticks as f64;
            assert!(!Watch::update(&mut w, now, 4, d, &p), "tick {now}");
        }
        assert!(Watch::update(&mut w, w_ticks, 4, 2.8, &p));
        // A step's gain restarts the watch.
        assert!(!Watch::update(&mut w, w_ticks + 1, 4, 2.5, &p));
        assert!(!Watch::update(&mut w, 2 * w_ticks, 4, 2.5, &p));
        assert!(Watch::update(&mut w, 2 * w_ticks + 1, 4, 2.5, &p));
        // So does another slot.
        assert!(!Watch::update(&mut w, 2 * w_ticks + 2, 5, 2.5, &p));
        // Within min_distance of its slot a robot is never blocked.
        let mut w = None;
        let near = p.min_distance - 0.1;
        assert!(!Watch::update(&mut w, 0, 4, near, &p));
        assert!(!Watch::update(&mut w, 100 * w_ticks, 4, near, &p));
    }
}
