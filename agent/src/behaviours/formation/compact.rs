//! The compact re-plan of the swaps mode for swarms whose full [`Plan`] (members and sigma)
//! exceeds `radio.max_message_bytes` (100 and 500 robots at 512 bytes): the transform, the
//! kept template points as a bitmap, a few moves, the wrecks. No robot lists the others: each
//! assigns itself ([`own_slot`]):
//! - it keeps its template point when the point is kept;
//! - the robot whose point was dropped (a wreck blocks it) takes the kept point its move
//!   names: a point no live robot held (the dead robot's), matched nearest first;
//! - a robot with neither (no slot, or more drops than a message carries) takes the nearest slot in
//!   `adopt_for_swaps` (it may then share it: the limit docs/formation.md 9 reports).
//!
//! Since the kept points held by live robots stay theirs and every move goes to a point no
//! live robot held, the slots are distinct whenever the coordinator's `held` set is exact.

use super::gossip::Bitmap;
use super::messages::{CompactPlan, Msg, Plan};
use swarm::geometry::Vec2;

/// The bincode configuration of the radio (swarm's wire format: standard, varints).
pub(super) fn encoded_len(msg: &Msg) -> usize {
    bincode::serde::encode_to_vec(msg, bincode::config::standard()).map_or(usize::MAX, |b| b.len())
}

/// Whether the full plan for `robots` robots, with `max_dead` wrecks, fits one message of
/// `max_message_bytes` (its worst case: every id and slot at its largest).
pub fn full_plan_fits(robots: usize, max_dead: usize, max_message_bytes: u32) -> bool {
    full_plan_len(robots, max_dead) <= max_message_bytes as usize
}

/// The encoded size of the full plan for `robots` robots with `max_dead` wrecks, at its worst
/// case (every id and slot at its largest).
pub fn full_plan_len(robots: usize, max_dead: usize) -> usize {
    let top = robots.saturating_sub(1);
    let plan = Plan {
        epoch: u32::MAX,
        coordinator: top as u32,
        transform: [0.0; 4],
        points: vec![top as u16; robots],
        members: vec![top as u32; robots],
        slots: vec![top as u16; robots],
        dead: vec![[0.0; 2]; max_dead],
    };
    encoded_len(&Msg::Plan(plan))
}

/// The encoded size of a compact plan message.
pub fn compact_len(c: &CompactPlan) -> usize {
    encoded_len(&Msg::CompactPlan(c.clone()))
}

/// How many moves a compact plan for `robots` robots can carry within `max_message_bytes`,
/// at its worst case: every template and spare point kept (the bitmap at its longest), `max_dead`
/// wrecks, every id and point index at its largest. 0 when not even the plan without moves fits.
pub fn moves_that_fit(robots: usize, max_dead: usize, max_message_bytes: u32) -> usize {
    let plan = |moves: usize| worst_case_plan(robots, moves, max_dead);
    let bytes = max_message_bytes as usize;
    let empty = compact_len(&plan(0));
    if empty > bytes {
        return 0;
    }
    let per = compact_len(&plan(1)) - empty;
    // Linear in the moves but for the length's varint (one byte more past 250): step back.
    let mut k = (bytes - empty) / per.max(1);
    while k > 0 && compact_len(&plan(k)) > bytes {
        k -= 1;
    }
    k
}

/// The largest compact plan for `robots` robots with `moves` moves and `dead` wrecks: every
/// template and spare point kept, every id and point index at its largest (an f64 always
/// takes 8 bytes, so the transform's and wrecks' values do not matter).
fn worst_case_plan(robots: usize, moves: usize, dead: usize) -> CompactPlan {
    let points = robots + super::shift_drop::MAX_SPARE;
    let top = (points.saturating_sub(1)).min(u16::MAX as usize) as u16;
    let mut kept = Bitmap::with_len(points);
    for p in 0..points {
        kept.insert(p);
    }
    CompactPlan {
        epoch: u32::MAX,
        coordinator: robots.saturating_sub(1) as u32,
        transform: [0.0; 4],
        kept,
        moves: vec![(top, top); moves],
        dead: vec![[0.0; 2]; dead],
    }
}

/// The pattern a compact plan describes, as the behaviour holds it (no members, no sigma).
pub fn plan_of(c: &CompactPlan) -> Plan {
    Plan {
        epoch: c.epoch,
        coordinator: c.coordinator,
        transform: c.transform,
        points: c.kept.iter().map(|p| p as u16).collect(),
        members: Vec::new(),
        slots: Vec::new(),
        dead: c.dead.clone(),
    }
}

/// This robot's slot in `c` when it held template point `point` (None: take the nearest).
pub fn own_slot(c: &CompactPlan, point: Option<u16>) -> Option<usize> {
    let point = point?;
    let target = if c.kept.contains(point as usize) {
        point
    } else {
        c.moves.iter().find(|(from, _)| *from == point)?.1
    };
    c.kept.iter().position(|p| p == target as usize)
}

/// The coordinator's choice for `n` robots on the old pattern (`points`, its slots
/// `targets`): which template points stay and which robots move. Dropped first: the points a
/// wreck blocks (within `blocked_within`), then the points no live robot held (`held`), then
/// the nearest a wreck, then by index. Each dropped point a live robot held moves to a kept
/// point none held, the nearest pair first, at most `max_moves`.
pub fn choose(
    points: &[u16],
    targets: &[Vec2],
    held: &Bitmap,
    wrecks: &[Vec2],
    blocked_within: f64,
    n: usize,
    max_moves: usize,
) -> (Bitmap, Vec<(u16, u16)>) {
    let wreck_distance = |j: usize| nearest_wreck(targets[j], wrecks);
    let blocked = |j: usize| wreck_distance(j) < blocked_within;
    choose_by(points, targets, held, &blocked, &wreck_distance, n, max_moves)
}

/// The distance from `q` to the nearest of `wrecks` (infinite when none).
pub fn nearest_wreck(q: Vec2, wrecks: &[Vec2]) -> f64 {
    wrecks.iter().map(|w| (q - w).norm()).fold(f64::INFINITY, f64::min)
}

/// [`choose`] with the test of a blocked point (`blocked`, by index into `points`) and the
/// order among the rest (`wreck_distance`, nearest dropped first) given: shift_drop.rs calls
/// it for a translated placement.
pub fn choose_by(
    points: &[u16],
    targets: &[Vec2],
    held: &Bitmap,
    blocked: &dyn Fn(usize) -> bool,
    wreck_distance: &dyn Fn(usize) -> f64,
    n: usize,
    max_moves: usize,
) -> (Bitmap, Vec<(u16, u16)>) {
    let is_held = |j: usize| held.contains(points[j] as usize);
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|a, b| {
        blocked(*b)
            .cmp(&blocked(*a))
            .then(is_held(*a).cmp(&is_held(*b)))
            .then(wreck_distance(*a).total_cmp(&wreck_distance(*b)))
            .then(a.cmp(b))
    });
    let drop = points.len().saturating_sub(n);
    let (dropped, kept) = order.split_at(drop);
    let mut from: Vec<usize> = dropped.iter().copied().filter(|j| is_held(*j)).collect();
    let mut to: Vec<usize> = kept.iter().copied().filter(|j| !is_held(*j)).collect();
    from.sort_unstable();
    to.sort_unstable();
    let mut moves = Vec::new();
    while moves.len() < max_moves && !from.is_empty() && !to.is_empty() {
        let mut best = (f64::INFINITY, 0, 0);
        for (a, f) in from.iter().enumerate() {
            for (b, t) in to.iter().enumerate() {
                let d = (targets[*f] - targets[*t]).norm();
                if d < best.0 {
                    best = (d, a, b);
                }
            }
        }
        moves.push((points[from.remove(best.1)], points[to.remove(best.2)]));
    }
    let mut bits = Bitmap::default();
    for j in kept {
        bits.insert(points[*j] as usize);
    }
    (bits, moves)
}

/// The wrecks a compact plan carries: the old plan's and the known ones, the nearest a slot
/// of `targets` first, at most `max_dead` (the rest stay static discs in the ORCA of the
/// robots that sense them or hear of them).
pub fn dead_list(old: &[[f64; 2]], wrecks: &[Vec2], targets: &[Vec2], max_dead: usize) -> Vec<[f64; 2]> {
    let mut dead: Vec<[f64; 2]> = old.to_vec();
    for w in wrecks {
        if !dead.iter().any(|d| d[0] == w.x && d[1] == w.y) {
            dead.push([w.x, w.y]);
        }
    }
    let near = |d: &[f64; 2]| {
        targets
            .iter()
            .map(|t| (t - Vec2::new(d[0], d[1])).norm())
            .fold(f64::INFINITY, f64::min)
    };
    dead.sort_by(|a, b| near(a).total_cmp(&near(b)).then(a[0].total_cmp(&b[0])).then(a[1].total_cmp(&b[1])));
    dead.truncate(max_dead);
    dead
}

/// The smallest translation delta of the slots `slots` (on rings `step` apart, 16 directions
/// each, up to `max_shift`) that leaves every slot in the box and clear (`clear`) of the
/// wrecks: with the old slots as positions and each robot keeping its point, the cost of
/// eq. (14) is n |delta|^2, so the first clear shift is the cheapest translation of the old
/// placement on that grid (no bound on other placements: it is no certificate).
pub fn nearest_clear_shift(
    slots: &[Vec2],
    clear: impl Fn(Vec2) -> bool,
    step: f64,
    max_shift: f64,
) -> Option<Vec2> {
    const DIRECTIONS: usize = 16;
    let rings = (max_shift / step).floor() as usize;
    (1..=rings).find_map(|i| {
        (0..DIRECTIONS).find_map(|j| {
            let a = std::f64::consts::TAU * j as f64 / DIRECTIONS as f64;
            let delta = Vec2::new(a.cos(), a.sin()) * (step * i as f64);
            slots.iter().all(|q| clear(q + delta)).then_some(delta)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_nearest_clear_shift_moves_a_line_of_slots_off_a_wreck_by_the_least_ring() {
        // Slots on the x axis 2.2 apart, a wreck at (1.1, 0.5) between two of them, clearance
        // 2.1: no sideways shift clears both neighbours (it needs |dx| >= 2.04 on each side
        // of a 2.2 gap); down by delta clears when 1.1^2 + (0.5 + delta)^2 >= 2.1^2, delta
        // >= 1.29, so ring 6 (1.5) is the least and ring 5 (1.25) is clear in no direction.
        let slots: Vec<Vec2> = (0..5).map(|j| Vec2::new(2.2 * j as f64, 0.0)).collect();
        let wreck = Vec2::new(1.1, 0.5);
        let clear = |q: Vec2| (q - wreck).norm() >= 2.1;
        let d = nearest_clear_shift(&slots, clear, 0.25, 6.0).expect("a clear shift");
        assert!(slots.iter().all(|q| clear(q + d)));
        assert!((d.norm() - 1.5).abs() < 1e-12, "{d:?}");
        // No shift of a smaller ring is clear (checked densely: 360 directions).
        let r = d.norm();
        for i in 1..((r / 0.25).round() as usize) {
            for a in 0..360 {
                let a = (a as f64).to_radians();
                let e = Vec2::new(a.cos(), a.sin()) * (0.25 * i as f64);
                assert!(!slots.iter().all(|q| clear(q + e)), "ring {i} clear at {a}");
            }
        }
        assert!(nearest_clear_shift(&slots, |_| false, 0.25, 6.0).is_none());
    }

    #[test]
    fn the_moves_that_fit_are_the_most_a_worst_case_plan_carries_within_the_message() {
        for (robots, dead, bytes) in [(500, 12, 512), (100, 12, 512), (500, 0, 512), (100, 3, 300)] {
            let k = moves_that_fit(robots, dead, bytes);
            assert!(k > 12, "{robots} robots, {dead} wrecks, {bytes} bytes: {k}");
            // Other values in the f64 fields: the same length.
            let plan = |moves: usize| CompactPlan {
                transform: [1.05, 65.0, 65.0, -3.1],
                dead: vec![[129.0, 129.0]; dead],
                ..worst_case_plan(robots, moves, dead)
            };
            assert!(compact_len(&plan(k)) <= bytes as usize);
            assert!(compact_len(&plan(k + 1)) > bytes as usize);
        }
        // A message too small for the plan without moves carries none.
        assert_eq!(moves_that_fit(500, 12, 200), 0);
    }

    #[test]
    fn the_full_plan_fits_512_bytes_at_16_robots_and_not_at_100() {
        assert!(full_plan_fits(16, 12, 512));
        assert!(!full_plan_fits(100, 12, 512));
        assert!(!full_plan_fits(500, 12, 512));
    }

    #[test]
    fn a_worst_case_compact_plan_and_need_of_500_robots_fit_512_bytes() {
        let params = super::super::params::ReplanParams::default();
        // Every template point and every spare point (shift_drop.rs) kept.
        let points = 500 + super::super::shift_drop::MAX_SPARE;
        let mut kept = Bitmap::with_len(points);
        for p in 0..points {
            kept.insert(p);
        }
        let c = CompactPlan {
            epoch: u32::MAX,
            coordinator: 499,
            transform: [1.05, 65.0, 65.0, -3.1],
            kept: kept.clone(),
            moves: vec![(499, 498); params.max_moves],
            dead: vec![[129.0, 129.0]; params.max_dead],
        };
        let len = compact_len(&c);
        assert!(len <= 512, "compact plan {len} bytes");
        let need = Msg::Need(super::super::gossip::Need {
            epoch: u32::MAX,
            alive: 500,
            candidate: 499,
            known: kept.clone(),
            held: kept.clone(),
            settled: kept,
        });
        let len = encoded_len(&need);
        assert!(len <= 512, "need {len} bytes");
    }

    /// 500 robots on a line of slots, robot i on template point perm(i); three die; a wreck
    /// blocks the point of a live robot.
    #[test]
    fn self_assignment_from_a_compact_plan_gives_every_live_robot_a_distinct_slot() {
        let n = 500;
        let points: Vec<u16> = (0..n as u16).collect();
        let targets: Vec<Vec2> = (0..n).map(|j| Vec2::new(2.2 * j as f64, 0.0)).collect();
        // A seeded-free permutation: i -> (7 i + 3) mod 500 (7 is prime to 500).
        let point_of = |i: usize| ((7 * i + 3) % n) as u16;
        let dead = [11usize, 200, 377];
        let mut held = Bitmap::with_len(n);
        for i in (0..n).filter(|i| !dead.contains(i)) {
            held.insert(point_of(i) as usize);
        }
        // Robot 40's point is blocked by a wreck at its slot (the wreck of another, earlier
        // death whose point is vacant too: dead robots 11, 200, 377 leave 3 points).
        let blocked = point_of(40) as usize;
        let wrecks = [targets[blocked]];
        let (kept, moves) = choose(&points, &targets, &held, &wrecks, 2.1, n - 3, 12);
        assert_eq!(kept.count(), n - 3);
        assert!(!kept.contains(blocked));
        assert_eq!(moves.len(), 1);
        assert_eq!(moves[0].0 as usize, blocked);
        let c = CompactPlan {
            epoch: 1,
            coordinator: 0,
            transform: [1.0, 0.0, 0.0, 0.0],
            kept,
            moves,
            dead: Vec::new(),
        };
        let mut slots: Vec<usize> = (0..n)
            .filter(|i| !dead.contains(i))
            .map(|i| own_slot(&c, Some(point_of(i))).expect("every live robot gets a slot"))
            .collect();
        slots.sort_unstable();
        slots.dedup();
        assert_eq!(slots.len(), n - 3, "slots are distinct");
        assert!(slots.iter().all(|s| *s < n - 3));
    }
}
