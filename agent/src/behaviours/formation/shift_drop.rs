//! Shift-and-drop placement for the compact re-plan (replan_multihop.rs), when several
//! robots died: tried after the old placement and the least clear translation of the old
//! placement's kept slots (compact.rs `nearest_clear_shift`) both failed, before the budgeted
//! branch-and-bound (useless at 100 and 500 robots, docs/formation.md 9).
//!
//! Several wrecks (a cluster of deaths) can block more kept slots than any translation of
//! the kept set clears. But the old pattern has one point per robot that ever lived: the dead
//! robots' points are vacant, so a translation only needs `n` clear points of the old
//! pattern, not the kept set's. For every translation delta (0, then rings `shift_step`
//! apart, 16 directions each, up to `max_shift`) the points the translated pattern leaves
//! blocked (out of the box, on an arena disc, within 2 (r + orca_margin) of a wreck) are
//! dropped first ([`choose_by`]), then the vacant ones; each dropped point a live robot holds
//! moves to a kept vacant point (at most `max_moves`, else the delta is refused). Of the
//! admissible deltas the one of least cost wins: eq. (14)'s sum of squared distances with
//! every robot on its old slot, n_kept |delta|^2 plus each moved robot's squared distance
//! from its old slot to its new one. The plan reports the gap [`SHIFTED_AND_DROPPED`].

use super::compact::{choose_by, nearest_wreck};
use super::gossip::Bitmap;
use swarm::geometry::Vec2;

/// The gap a re-plan reports for a shift-and-drop placement (a sentinel: a report must be
/// finite and this is no bound). The others: replan.rs `NO_PLACEMENT` = -1 (no placement
/// found, the old transform kept), replan_multihop.rs `SHIFTED` = -2 (the kept slots
/// translated, nothing dropped beyond the vacant points).
pub const SHIFTED_AND_DROPPED: f64 = -3.0;

/// How much farther than 2 (r + orca_margin) from every wreck a slot of a shift-and-drop
/// placement must lie. [chosen] 0.4: measured (100 robots, seeds 2 and 3, kills 60:37,
/// 62:38, 64:39): slots 2.11 and 2.17 from a wreck (just clear of 2.1) left their robots
/// 0.24 and 0.07 short for 2,900 ticks (ORCA against the wreck and the neighbours), so the
/// runs never formed; the robots stood 2.24-2.31 from the wreck. replan_multihop.rs tries
/// the search without it when it finds nothing with it.
pub const CLEARANCE_SLACK: f64 = 0.4;

/// Directions on each ring of translations (as compact.rs `nearest_clear_shift`).
const DIRECTIONS: usize = 16;

/// Spare points (beyond the template's one per robot) lie this far from every template
/// point and from each other. [chosen] 2.2: the thick letters' arc spacing (their chords are
/// at least 2.148), so a pattern with spares keeps the letters' separation (C3).
pub const SPARE_SPACING: f64 = 2.2;

/// Directions tried around each template point for a spare point (every 30 degrees).
const SPARE_DIRECTIONS: usize = 12;

/// At most this many spare points (a compact plan's kept bitmap grows by one bit each).
/// [chosen] 256: the rim of the 500-robot C; a 756-bit bitmap keeps the worst-case compact
/// plan and need under 512 bytes.
pub const MAX_SPARE: usize = 256;

/// The rim of `template`: points `SPARE_SPACING` from a template point (12 directions, in
/// template order) and at least that far from every template point and every earlier spare,
/// at most [`MAX_SPARE`]. Every robot computes the same list from the template alone. At 500
/// robots three wrecks inside the thick C block more slots than the dead robots' points can
/// replace at any translation (docs/formation.md 9): the spares are the vacancies of the last
/// shift-and-drop search.
pub fn spare_points(template: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let at = |p: &[f64; 2]| Vec2::new(p[0], p[1]);
    let mut spares: Vec<Vec2> = Vec::new();
    let clear = |q: Vec2, spares: &[Vec2]| {
        let far = |o: Vec2| (q - o).norm() >= SPARE_SPACING - 1e-9;
        template.iter().all(|p| far(at(p))) && spares.iter().all(|o| far(*o))
    };
    'outer: for p in template {
        for d in 0..SPARE_DIRECTIONS {
            let a = std::f64::consts::TAU * d as f64 / SPARE_DIRECTIONS as f64;
            let q = at(p) + Vec2::new(a.cos(), a.sin()) * SPARE_SPACING;
            if clear(q, &spares) {
                spares.push(q);
                if spares.len() >= MAX_SPARE {
                    break 'outer;
                }
            }
        }
    }
    spares.into_iter().map(|q| [q.x, q.y]).collect()
}

/// A shift-and-drop placement: the translation, the kept points, the moves, its cost.
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftDrop {
    pub delta: Vec2,
    pub kept: Bitmap,
    pub moves: Vec<(u16, u16)>,
    pub cost: f64,
}

/// The search's inputs: the old pattern (`points`, its slots `targets`), the points live
/// robots hold (`held`, exact: gossip.rs), the wrecks (for the order of drops), how many
/// points to keep (`n`), and the limits.
pub struct Search<'a> {
    pub points: &'a [u16],
    pub targets: &'a [Vec2],
    pub held: &'a Bitmap,
    pub wrecks: &'a [Vec2],
    pub n: usize,
    pub max_moves: usize,
    pub step: f64,
    pub max_shift: f64,
    /// Among the vacant points keep those nearest the robots that must move (with spare
    /// points: many vacancies), else those farthest from a wreck (the first search's order).
    pub keep_near_moves: bool,
}

impl Search<'_> {
    /// The candidate translations in order: 0, then ring by ring.
    fn deltas(&self) -> Vec<Vec2> {
        let rings = if self.step > 0.0 {
            (self.max_shift / self.step).floor() as usize
        } else {
            0
        };
        let mut out = vec![Vec2::zeros()];
        for i in 1..=rings {
            for j in 0..DIRECTIONS {
                let a = std::f64::consts::TAU * j as f64 / DIRECTIONS as f64;
                out.push(Vec2::new(a.cos(), a.sin()) * (self.step * i as f64));
            }
        }
        out
    }

    /// The placement at `delta`, if every kept slot is clear and every robot whose point is
    /// dropped has a move.
    fn at(&self, delta: Vec2, clear: &dyn Fn(Vec2) -> bool) -> Option<ShiftDrop> {
        let shifted: Vec<Vec2> = self.targets.iter().map(|t| t + delta).collect();
        let ok: Vec<bool> = shifted.iter().map(|q| clear(*q)).collect();
        if ok.iter().filter(|c| **c).count() < self.n {
            return None;
        }
        let blocked = |j: usize| !ok[j];
        // The robots that must move stand on the blocked held slots (their old slots).
        let movers: Vec<Vec2> = (0..self.points.len())
            .filter(|j| !ok[*j] && self.held.contains(self.points[*j] as usize))
            .map(|j| self.targets[j])
            .collect();
        let distance = |j: usize| {
            if self.keep_near_moves && !self.held.contains(self.points[j] as usize) {
                -nearest_wreck(shifted[j], &movers)
            } else {
                nearest_wreck(shifted[j], self.wrecks)
            }
        };
        let (kept, moves) = choose_by(
            self.points,
            self.targets,
            self.held,
            &blocked,
            &distance,
            self.n,
            self.max_moves,
        );
        let index = |p: u16| self.points.iter().position(|q| *q == p);
        let all_clear = (0..self.points.len())
            .filter(|j| kept.contains(self.points[*j] as usize))
            .all(|j| ok[j]);
        let dropped_held = (0..self.points.len())
            .filter(|j| {
                let p = self.points[*j] as usize;
                !kept.contains(p) && self.held.contains(p)
            })
            .count();
        if !all_clear || dropped_held > moves.len() {
            return None;
        }
        let moved: f64 = moves
            .iter()
            .filter_map(|(f, t)| Some((self.targets[index(*f)?] - shifted[index(*t)?]).norm_squared()))
            .sum();
        let stay = (0..self.points.len())
            .filter(|j| {
                let p = self.points[*j] as usize;
                kept.contains(p) && self.held.contains(p)
            })
            .count();
        let cost = stay as f64 * delta.norm_squared() + moved;
        Some(ShiftDrop {
            delta,
            kept,
            moves,
            cost,
        })
    }

    /// The admissible placement of least cost (the first in [`Search::deltas`]'s order on a
    /// tie), or None.
    pub fn best(&self, clear: &dyn Fn(Vec2) -> bool) -> Option<ShiftDrop> {
        let mut best: Option<ShiftDrop> = None;
        for delta in self.deltas() {
            if let Some(s) = self.at(delta, clear) {
                if best.as_ref().is_none_or(|b| s.cost < b.cost) {
                    best = Some(s);
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::super::compact::choose;
    use super::*;

    /// Twelve slots in a row 2.2 apart; two robots died, their points (10, 11, at the row's
    /// end) vacant, their wrecks between slots 1 and 2 and between 3 and 4, each blocking
    /// both neighbours (within 2.1): 4 held points blocked, 2 vacancies, so the old
    /// placement keeps a blocked slot whatever it drops. A sideways shift by half a spacing
    /// puts two slots on the wrecks and leaves the other ten clear: drop those two, move
    /// their robots to the vacancies.
    #[test]
    fn shift_and_drop_places_the_pattern_where_the_old_placement_keeps_a_blocked_slot() {
        let targets: Vec<Vec2> = (0..12).map(|i| Vec2::new(2.2 * i as f64, 0.0)).collect();
        let points: Vec<u16> = (0..12).collect();
        let wrecks = [Vec2::new(3.3, 0.0), Vec2::new(7.7, 0.0)];
        let mut held = Bitmap::with_len(12);
        for p in 0..10 {
            held.insert(p);
        }
        let within = 2.1;
        let clear = |q: Vec2| nearest_wreck(q, &wrecks) >= within;
        let (step, max_shift) = (0.55, 1.65);
        let (kept0, _) = choose(&points, &targets, &held, &wrecks, within, 10, 12);
        assert!(!kept0.iter().all(|p| clear(targets[p])), "the old placement is blocked");
        let search = Search {
            points: &points,
            targets: &targets,
            held: &held,
            wrecks: &wrecks,
            n: 10,
            max_moves: 12,
            step,
            max_shift,
            keep_near_moves: false,
        };
        let s = search.best(&clear).expect("a shift-and-drop placement");
        assert!(s.delta.norm() > 0.0);
        assert_eq!(s.kept.count(), 10);
        for p in s.kept.iter() {
            assert!(clear(targets[p] + s.delta), "kept point {p} blocked");
        }
        // Every live robot keeps its point or moves to a vacant kept one: distinct slots.
        let mut slots: Vec<u16> = held
            .iter()
            .map(|p| {
                let p = p as u16;
                if s.kept.contains(p as usize) {
                    p
                } else {
                    s.moves.iter().find(|(f, _)| *f == p).expect("a move").1
                }
            })
            .collect();
        slots.sort_unstable();
        slots.dedup();
        assert_eq!(slots.len(), 10, "slots are distinct");
        assert_eq!(s.moves.len(), 2);
        // Least cost: no admissible delta is cheaper.
        for d in search.deltas() {
            if let Some(o) = search.at(d, &clear) {
                assert!(o.cost >= s.cost);
            }
        }
        // Three wrecks leave fewer than ten clear points at every delta: none.
        let more = [wrecks[0], wrecks[1], Vec2::new(12.1, 0.0)];
        let clear3 = |q: Vec2| nearest_wreck(q, &more) >= within;
        let s3 = Search {
            wrecks: &more,
            ..search
        };
        assert!(s3.best(&clear3).is_none());
    }

    #[test]
    fn spare_points_ring_a_template_at_the_letter_spacing() {
        let c = swarm::sections::formation::builtin_template("C", 100).unwrap();
        let spares = spare_points(&c);
        assert!(!spares.is_empty() && spares.len() <= MAX_SPARE);
        let d = |a: &[f64; 2], b: &[f64; 2]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        for (i, q) in spares.iter().enumerate() {
            let nearest = c.iter().map(|p| d(p, q)).fold(f64::INFINITY, f64::min);
            assert!((nearest - SPARE_SPACING).abs() < 1e-6, "spare {i} {nearest}");
            assert!(spares[..i].iter().all(|o| d(o, q) >= SPARE_SPACING - 1e-6));
        }
        assert_eq!(spare_points(&c), spares, "deterministic");
    }
}
