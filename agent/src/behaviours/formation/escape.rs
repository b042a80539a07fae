//! Backing out of a notch of wrecks (not in the paper, which has no dead robots): a robot that
//! is still held still while it squeezes (squeeze.rs) for `escape.after_ticks` ticks steers by
//! a path planned round the wrecks at the true radii, until it reaches its slot.
//!
//! Why: eq. (16) points straight at the slot, and ORCA is local. A robot whose straight line to
//! its slot runs into a notch between wrecks too close to pass (100 robots, the fixed C, five
//! kills in one cluster, seed 2: wrecks 71 and 74 2.70 apart, the robot between them and its
//! slot beyond) stands in the notch for good: it would have to back out through the exit behind
//! it first, which no local rule does (docs/formation.md 9). The detour (detour.rs) plans with
//! ORCA's keep-out 2 (r + orca_margin) = 2.1 on a 0.5 grid and finds no way through the exits of
//! 4.14 between centres that the squeeze passes. This plan uses the true contact distance 2 r
//! less `cell_tolerance` for the grid's cells (a grid misses a neck narrower than a cell), on a
//! finer grid, inside the box; ORCA, squeezing (the wrecks' buffered cells at the true radii),
//! stays the safety layer: the plan only turns eq. (16)'s preferred velocity.
//!
//! Once on, it stays on until the robot is within epsilon of its slot: a robot that backed out
//! and went back to eq. (16)'s straight line would walk into the same notch. While the straight
//! line to the slot passes every wreck at 2 r or more, the aim is the slot itself. A run in
//! which no robot is held still while squeezing is unchanged.

use super::detour::{plan, segment_distance, steer, Bounds, Keepout, Neck};
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// `formation.kernels.escape`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EscapeParams {
    /// A squeezing robot held still this many ticks in a row plans its way out. [chosen] 10
    /// (2.5 s at tau = 0.25), as many as the squeeze itself waits: the squeezes that worked got
    /// going within a tick or two. 0: never.
    pub after_ticks: u32,
    /// The grid's cell side. [chosen] 0.25: one V_p tau step of configs/formation-100.toml, and
    /// under the width (0.34) that a neck of 4.14 between centres leaves the cells.
    pub cell: f64,
    /// The grid's half-width around the robot. [chosen] 8.0: room to back out of a notch two
    /// robots deep and go round the wrecks that made it (65 x 65 cells).
    pub window: f64,
    /// How far inside the true contact distance 2 r from a wreck a cell's centre may lie.
    /// [chosen] 0.1: a neck of 4.14 between centres leaves 0.14 of free line at 2 r, which a
    /// grid of 0.25 misses; at 1.9 it leaves 0.34. ORCA keeps the bodies apart.
    pub cell_tolerance: f64,
}

impl Default for EscapeParams {
    fn default() -> Self {
        EscapeParams {
            after_ticks: 10,
            cell: 0.25,
            window: 8.0,
            cell_tolerance: 0.1,
        }
    }
}

/// The escape state of one robot.
#[derive(Debug, Clone, Default)]
pub struct Escape {
    /// Consecutive ticks held still while squeezing, away from the slot.
    stuck: u32,
    /// Steering by the plan.
    on: bool,
}

impl Escape {
    /// Whether the robot steers by the plan this tick.
    pub fn on(&self) -> bool {
        self.on
    }

    /// After a tick's motion: `squeezing` (squeeze.rs), `held` (moving slower than the
    /// squeeze's held speed), `away` (farther than epsilon from its slot, or no slot).
    pub fn update(&mut self, squeezing: bool, held: bool, away: bool, after: u32) {
        if after == 0 {
            return;
        }
        if self.on {
            if !away {
                *self = Escape::default();
            }
            return;
        }
        if squeezing && held && away {
            self.stuck += 1;
            self.on = self.stuck >= after;
        } else {
            self.stuck = 0;
        }
    }
}

/// What the plan goes round: the wrecks, the arena's discs and the box.
pub struct Obstacles<'a> {
    pub wrecks: &'a [Vec2],
    /// The arena's discs grown by r (the true contact distance of a robot's centre).
    pub discs: &'a [Keepout],
    pub bounds: Bounds,
    /// The true radius r.
    pub robot_radius: f64,
}

/// Eq. (16)'s preferred velocity (V_p, K_a) for the slot at `slot`, turned at the plan's next
/// waypoint when a wreck or a disc stands within the true contact distance of the straight
/// line; eq. (16) itself when no path exists in the window. The cells keep `cell_tolerance`
/// less from every disc, wreck or arena's (ORCA, squeezing, holds both at the true radii).
#[cfg(test)]
pub fn preferred(me: Vec2, slot: Vec2, o: &Obstacles, max_speed: f64, k_a: f64, p: &EscapeParams) -> Vec2 {
    preferred_and_length(me, slot, o, max_speed, k_a, p).0
}

/// [`preferred`], with the length of the way to the slot: the straight distance when no wreck
/// or disc blocks it, the planned path's when one does, and the straight distance plus twice
/// the window when no path exists in the window (longer than any path the window holds).
pub fn preferred_and_length(
    me: Vec2,
    slot: Vec2,
    o: &Obstacles,
    max_speed: f64,
    k_a: f64,
    p: &EscapeParams,
) -> (Vec2, f64) {
    let contact = 2.0 * o.robot_radius;
    let near = |c: Vec2, radius: f64| (c - me).norm() <= p.window + radius;
    let blocked = o
        .wrecks
        .iter()
        .any(|w| near(*w, contact) && segment_distance(me, slot, *w) < contact)
        || o.discs
            .iter()
            .any(|k| near(k.centre, k.radius) && segment_distance(me, slot, k.centre) < k.radius);
    let straight = (slot - me).norm();
    let (aim, length) = if blocked {
        // Never below 0 (point robots, r = 0: no tolerance to take).
        let cells = (contact - p.cell_tolerance).max(0.0);
        let keepouts: Vec<Keepout> = o
            .wrecks
            .iter()
            .filter(|w| near(**w, cells))
            .map(|w| Keepout {
                centre: *w,
                radius: cells,
            })
            .chain(o.discs.iter().filter(|k| near(k.centre, k.radius)).map(|k| Keepout {
                centre: k.centre,
                radius: (k.radius - p.cell_tolerance).max(0.0),
            }))
            .collect();
        let necks = closed_necks(&keepouts, p.cell_tolerance, o.bounds);
        plan(me, slot, &keepouts, &necks, Some(o.bounds), p.cell, p.window)
            .unwrap_or((slot, straight + 2.0 * p.window))
    } else {
        (slot, straight)
    };
    (steer(me, slot, aim, max_speed, k_a), length)
}

/// The necks no robot passes among `keepouts` (each `tolerance` inside its true contact
/// distance): two whose true contact discs overlap (a robot's centre fits between them only
/// if their centres are at least the sum apart: two wrecks 4 r), and one whose true disc
/// reaches the box's edge (`bounds`, the box less r). Measured (100 robots, swaps, seed 65,
/// eight kills at 131-144, results/deaths-schedules.md t8): robot 20 stood in the notch between
/// wrecks 3.93 apart for 2,800 ticks, the plan steering it through the neck, whose cells at
/// 2 r - 0.1 are free.
pub fn closed_necks(keepouts: &[Keepout], tolerance: f64, bounds: Bounds) -> Vec<Neck> {
    let mut necks = Vec::new();
    for (i, a) in keepouts.iter().enumerate() {
        let ra = a.radius + tolerance;
        for b in &keepouts[i + 1..] {
            if (a.centre - b.centre).norm() < ra + b.radius + tolerance {
                necks.push((a.centre, b.centre));
            }
        }
        let (lo, hi) = bounds;
        let c = a.centre;
        for (gap, foot) in [
            (c.x - lo.x, Vec2::new(lo.x, c.y)),
            (hi.x - c.x, Vec2::new(hi.x, c.y)),
            (c.y - lo.y, Vec2::new(c.x, lo.y)),
            (hi.y - c.y, Vec2::new(c.x, hi.y)),
        ] {
            if gap < ra {
                necks.push((c, foot));
            }
        }
    }
    necks
}

impl super::Formation {
    /// Eq. (16) towards this robot's slot, turned by the escape plan round `wrecks` (the
    /// wrecks motion() puts into ORCA).
    /// Remembers the way's length for the blocked swap (swaps.rs `set_path_length`).
    pub(super) fn preferred_escaping(&self, me: Vec2, wrecks: &[Vec2]) -> Vec2 {
        let k = &self.p.kernels;
        let Some(slot) = self.slot.map(|s| self.targets[s]) else {
            return Vec2::zeros();
        };
        let r = k.robot_radius;
        let discs = self.disc_keepouts(r);
        let o = Obstacles {
            wrecks,
            discs: &discs,
            bounds: (
                Vec2::new(k.box_min[0] + r, k.box_min[1] + r),
                Vec2::new(k.box_max[0] - r, k.box_max[1] - r),
            ),
            robot_radius: r,
        };
        let (v, length) = preferred_and_length(me, slot, &o, k.max_speed, k.k_a, &self.p.escape);
        self.escape_length.set(Some(length));
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `wrecks` in a 60 x 60 box, no discs, r = 1.
    fn among(wrecks: &[Vec2]) -> Obstacles<'_> {
        Obstacles {
            wrecks,
            discs: &[],
            bounds: (Vec2::new(1.0, 1.0), Vec2::new(59.0, 59.0)),
            robot_radius: 1.0,
        }
    }

    #[test]
    fn held_while_squeezing_it_escapes_after_the_ticks_and_stops_in_its_slot() {
        let mut e = Escape::default();
        for _ in 0..9 {
            e.update(true, true, true, 10);
            assert!(!e.on());
        }
        // Moving resets the count; not squeezing too.
        e.update(true, false, true, 10);
        for _ in 0..9 {
            e.update(true, true, true, 10);
        }
        assert!(!e.on());
        e.update(true, true, true, 10);
        assert!(e.on());
        // It stays on while it moves, squeezes or not, until in its slot.
        e.update(false, false, true, 10);
        assert!(e.on());
        e.update(false, false, false, 10);
        assert!(!e.on());
        // 0: never.
        let mut never = Escape::default();
        for _ in 0..100 {
            never.update(true, true, true, 0);
        }
        assert!(!never.on());
    }

    /// The notch of the traced run: two wrecks 2.70 apart between the robot and its slot, a
    /// third behind it leaving exits of 4.14 between centres on both sides.
    fn notch() -> (Vec<Vec2>, Vec2, Vec2) {
        let a = Vec2::new(20.0, 20.0);
        let b = Vec2::new(20.0, 22.7);
        // The robot sits east of the pair, touching both (2 r = 2 from each centre).
        let mid = Vec2::new(20.0, 21.35);
        let me = mid + Vec2::new((4.0f64 - 1.35 * 1.35).sqrt() + 0.01, 0.0);
        // A wreck behind it, 4.14 from each of the pair's centres.
        let back = mid + Vec2::new((4.14f64 * 4.14 - 1.35 * 1.35).sqrt(), 0.0);
        (vec![a, b, back], me, Vec2::new(14.0, 21.35))
    }

    #[test]
    fn a_robot_in_a_notch_backs_out_through_the_exit_and_reaches_its_slot() {
        let (wrecks, start, slot) = notch();
        let p = EscapeParams::default();
        let o = among(&wrecks);
        // Straight at the slot it pushes into the notch (west); the plan first leads away.
        let first = preferred(start, slot, &o, 1.0, 1.0, &p);
        assert!(first.x > -0.5, "the first step is not straight west: {first:?}");
        // Driving at the aim (0.25 a step, no ORCA), re-planned every step, reaches the slot
        // and never comes within 2 r - cell_tolerance - (a step's cut) of a wreck centre.
        let (reached, least) = drive(start, slot, &wrecks);
        assert!(reached.is_some(), "not reached");
        assert!(least > 2.0 - p.cell_tolerance - 0.1, "came within {least} of a wreck");
        // Without the plan the same robot heads into the notch: eq. (16) points west.
        let straight = steer(start, slot, slot, 1.0, 1.0);
        assert!(straight.x < -0.9);
    }

    #[test]
    fn with_the_straight_line_clear_the_aim_is_the_slot() {
        let wrecks = [Vec2::new(5.0, 2.05)];
        let o = among(&wrecks);
        let (me, slot) = (Vec2::new(2.0, 0.0), Vec2::new(8.0, 0.0));
        let v = preferred(me, slot, &o, 1.0, 1.0, &EscapeParams::default());
        assert!((v - Vec2::new(1.0, 0.0)).norm() < 1e-12, "{v:?}");
    }

    #[test]
    fn the_plan_keeps_inside_the_box() {
        // A wreck against the south wall between the robot and its slot: the way round is north.
        let wrecks = [Vec2::new(10.0, 2.0)];
        let o = among(&wrecks);
        let (mut me, slot) = (Vec2::new(6.0, 1.0), Vec2::new(14.0, 1.0));
        let p = EscapeParams::default();
        for _ in 0..200 {
            me += preferred(me, slot, &o, 1.0, 1.0, &p) * 0.25;
            assert!(me.y >= 1.0 - 1e-9, "left the box: {me:?}");
            if (me - slot).norm() < 0.05 {
                return;
            }
        }
        panic!("not reached; at {me:?}");
    }

    /// Drives a point robot from `start` by the escape's preferred velocity (no ORCA, 0.25 a
    /// step): the step it reached `slot` at, or None within 400 steps; and the least distance
    /// to a wreck on the way.
    fn drive(start: Vec2, slot: Vec2, wrecks: &[Vec2]) -> (Option<usize>, f64) {
        let (o, p) = (among(wrecks), EscapeParams::default());
        let mut me = start;
        let mut least = f64::INFINITY;
        for step in 0..400 {
            me += preferred(me, slot, &o, 1.0, 1.0, &p) * 0.25;
            least = wrecks.iter().map(|w| (me - w).norm()).fold(least, f64::min);
            if (me - slot).norm() < 0.05 {
                return (Some(step), least);
            }
        }
        (None, least)
    }

    #[test]
    fn a_neck_narrower_than_a_robot_is_closed_and_a_wider_one_open() {
        // Two wrecks 3.93 apart (a robot needs 4.0 = 4 r between centres), the robot in the
        // notch above them, its slot below: the cells at 2 r - 0.1 leave the neck free, so
        // before the closed necks the plan aimed through it (100 robots, seed 65, t8).
        let (a, b) = (Vec2::new(20.0, 20.0), Vec2::new(23.93, 20.0));
        let me = Vec2::new(21.965, 20.45);
        let slot = Vec2::new(21.965, 15.0);
        let wrecks = [a, b];
        let keepouts: Vec<Keepout> = wrecks.iter().map(|w| Keepout { centre: *w, radius: 1.9 }).collect();
        let o = among(&wrecks);
        assert_eq!(closed_necks(&keepouts, 0.1, o.bounds), vec![(a, b)]);
        let v = preferred(me, slot, &o, 1.0, 1.0, &EscapeParams::default());
        assert!(v.y > 0.0 || v.x.abs() > 0.9, "it heads into the neck: {v:?}");
        let (reached, least) = drive(me, slot, &wrecks);
        assert!(reached.is_some(), "not reached");
        assert!(least >= 2.0 - 0.1 - 1e-9, "through the neck: {least}");
        // 4.14 apart the neck is open (no neck listed) and the robot goes straight through.
        let b = Vec2::new(24.14, 20.0);
        let wide = [a, b];
        let keepouts: Vec<Keepout> = wide.iter().map(|w| Keepout { centre: *w, radius: 1.9 }).collect();
        assert!(closed_necks(&keepouts, 0.1, o.bounds).is_empty());
        let me = Vec2::new(22.07, 20.45);
        let (reached, _) = drive(me, Vec2::new(22.07, 15.0), &wide);
        assert!(reached.is_some_and(|s| s < 30), "{reached:?}");
        // A wreck 2.9 from the box's edge line (the box less r) closes its side; 3.1 does not.
        let edge = |y: f64| closed_necks(&[Keepout { centre: Vec2::new(30.0, y), radius: 1.9 }], 0.1, o.bounds);
        assert_eq!(edge(1.0 + 1.9), vec![(Vec2::new(30.0, 2.9), Vec2::new(30.0, 1.0))]);
        assert!(edge(1.0 + 2.1).is_empty());
    }

    #[test]
    fn crossing_segments_are_told_from_parallel_and_apart_ones() {
        use super::super::detour::segments_cross;
        let (o, x, y) = (Vec2::zeros(), Vec2::new(2.0, 0.0), Vec2::new(1.0, 1.0));
        assert!(segments_cross(o, Vec2::new(2.0, 2.0), x, Vec2::new(0.0, 2.0)));
        assert!(!segments_cross(o, x, y, Vec2::new(2.0, 1.0)));
        assert!(!segments_cross(o, x, Vec2::new(3.0, -1.0), Vec2::new(3.0, 1.0)));
        // Touching at an end counts.
        assert!(segments_cross(o, x, Vec2::new(2.0, 0.0), Vec2::new(2.0, 3.0)));
    }
}
