//! Where the relayed mode's re-plan puts the pattern for the robots left: the old transform's
//! template points clear of the wrecks, or the least translation of it that leaves enough
//! points clear (docs/formation.md 9, "The centralised mode relayed").
//!
//! Per-step reassignment (eq. 15) gives every robot its slot afresh, so the re-plan may take
//! any `n` of the template's points, not only the old plan's less the dead robots': a point a
//! wreck blocks is exchanged for a clear one the dead robots left (the letter keeps its
//! shape, less `n - template` points). With the translation delta the slots are the old ones
//! moved by delta (d of eq. 5 is additive), so the first ring with enough clear points is the
//! cheapest translation on that grid for robots standing near their old slots (no bound on
//! other placements: it is no certificate).

use swarm::geometry::Vec2;

/// Directions tried on each ring of translations.
const DIRECTIONS: usize = 16;

/// `all`: the slots of every template point under the old transform; `prefer`: the points to
/// keep first (the old plan's, less the dead robots'). Returns the translation (zero first,
/// then rings `step` apart up to `max_shift`) and the `n` chosen points, ascending: the
/// preferred clear points first, then the other clear points by index.
pub fn place(
    all: &[Vec2],
    prefer: &[u16],
    n: usize,
    clear: impl Fn(Vec2) -> bool,
    step: f64,
    max_shift: f64,
) -> Option<(Vec2, Vec<u16>)> {
    let rings = (max_shift / step).floor() as usize;
    let deltas = std::iter::once(Vec2::zeros()).chain((1..=rings).flat_map(|i| {
        (0..DIRECTIONS).map(move |j| {
            let a = std::f64::consts::TAU * j as f64 / DIRECTIONS as f64;
            Vec2::new(a.cos(), a.sin()) * (step * i as f64)
        })
    }));
    for delta in deltas {
        let ok: Vec<bool> = all.iter().map(|q| clear(q + delta)).collect();
        if ok.iter().filter(|c| **c).count() < n {
            continue;
        }
        let mut points: Vec<u16> = prefer.iter().copied().filter(|p| ok[*p as usize]).collect();
        points.truncate(n);
        for j in 0..all.len() as u16 {
            if points.len() >= n {
                break;
            }
            if ok[j as usize] && !points.contains(&j) {
                points.push(j);
            }
        }
        points.sort_unstable();
        return Some((delta, points));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blocked_point_is_exchanged_for_a_dead_robots_point_before_any_shift() {
        // Ten points on a line 2.2 apart; the robots of points 8 and 9 died; a wreck blocks
        // point 3. Eight robots left: points 8 and 9 are free, so point 3 is exchanged for
        // point 8 with no translation.
        let all: Vec<Vec2> = (0..10).map(|j| Vec2::new(2.2 * j as f64, 0.0)).collect();
        let wreck = all[3];
        let clear = |q: Vec2| (q - wreck).norm() >= 2.1;
        let prefer: Vec<u16> = (0..8).collect();
        let (delta, points) = place(&all, &prefer, 8, clear, 0.25, 6.0).expect("a placement");
        assert_eq!(delta, Vec2::zeros());
        assert_eq!(points, vec![0, 1, 2, 4, 5, 6, 7, 8]);
        // Ten robots left: no free point, the least ring that clears all ten is taken.
        let all_prefer: Vec<u16> = (0..10).collect();
        let (delta, points) = place(&all, &all_prefer, 10, clear, 0.25, 6.0).expect("a shift");
        assert!(delta.norm() > 0.0);
        assert_eq!(points.len(), 10);
        assert!(points.iter().all(|p| clear(all[*p as usize] + delta)));
        // Nothing clear at all: none.
        assert!(place(&all, &prefer, 8, |_| false, 0.25, 6.0).is_none());
    }
}
