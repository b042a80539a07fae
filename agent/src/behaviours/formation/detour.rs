//! The wreck detour (swaps mode, `formation.kernels.detour`): a robot whose straight path to
//! its slot is blocked by known wrecks (dead robots, static discs) plans a grid path around
//! them and steers its preferred velocity at the path's next waypoint. ORCA stays the safety
//! layer: the detour only changes the preferred velocity of eq. (16).
//!
//! Why: ORCA is local. In front of a wall of wrecks (several deaths in one cluster) the
//! preferred velocity points into the wall and ORCA's closest feasible velocity stops the
//! robot there, a local minimum. The grid: square cells of side `cell` covering the window
//! of half-width `window` around the robot; a cell is free when its centre is at least the
//! blocked distance 2 (r + orca_margin) from every wreck (and the arena's discs by their
//! radius plus r + orca_margin). A* (the `pathfinding` crate) on the 8-connected grid, to
//! the slot's cell when the slot lies in the window, else to a free border cell, paying the
//! straight distance from it to the slot. The waypoint is the farthest cell of the path the
//! robot sees in a straight line clear of every disc (the slot itself when that is the
//! whole path); the speed stays eq. (16)'s for the slot's distance.

use pathfinding::prelude::astar;
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// `formation.kernels.detour`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DetourParams {
    /// Off: the preferred velocity points straight at the slot. [chosen] false: measured
    /// on the 18 several-deaths runs of docs/formation.md 9 ("Several deaths (swaps)"), all
    /// formed both ways, but K was lower without the detour in 8, higher in 5, equal in 5,
    /// and two runs took K = 1644 and 657 with it (260 and 245 without).
    pub enabled: bool,
    /// The grid's cell side. [chosen] 0.5: a quarter of a robot's diameter, two V_p tau
    /// steps of configs/formation-100.toml.
    pub cell: f64,
    /// The grid's half-width around the robot. [chosen] 6.0: room to go round a wall of
    /// three wrecks 2.2 apart (it keeps a robot's centre 2.2 + 2.1 = 4.3 from its middle
    /// one), on a grid of 25 x 25 cells.
    pub window: f64,
}

impl Default for DetourParams {
    fn default() -> Self {
        DetourParams {
            enabled: false,
            cell: 0.5,
            window: 6.0,
        }
    }
}

/// A disc the robot's centre must stay out of: a wreck (or an arena disc) grown by the
/// robot's own radius and the margins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keepout {
    pub centre: Vec2,
    pub radius: f64,
}

/// The distance from `w` to the segment a-b.
pub fn segment_distance(a: Vec2, b: Vec2, w: Vec2) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let t = if len2 > 0.0 {
        ((w - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - w).norm()
}

/// Whether the straight segment a-b stays out of every keep-out disc (a disc that already
/// holds `a`, the robot squeezing past it, does not count).
pub fn sees(a: Vec2, b: Vec2, keepouts: &[Keepout]) -> bool {
    keepouts
        .iter()
        .filter(|k| (a - k.centre).norm() >= k.radius)
        .all(|k| segment_distance(a, b, k.centre) >= k.radius)
}

/// A neck too narrow for a robot: the segment from one keep-out's centre to another's (or to
/// the foot of its perpendicular on the box's edge) where their true contact discs overlap.
/// A grid whose cells may lie inside the true contact distance (escape.rs `cell_tolerance`)
/// would otherwise pass through it.
pub type Neck = (Vec2, Vec2);

/// Whether the segments a-b and c-d cross (touching counts).
pub fn segments_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let cross = |o: Vec2, p: Vec2, q: Vec2| (p - o).perp(&(q - o));
    let (d1, d2) = (cross(c, d, a), cross(c, d, b));
    let (d3, d4) = (cross(a, b, c), cross(a, b, d));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && !(d1 == 0.0 && d2 == 0.0)
}

/// A node of the search: a cell (offsets from the robot's cell) or the goal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Node {
    Cell(i32, i32),
    Goal,
}

/// Path costs in integer millionths of a unit (A* needs an ordered cost).
fn cost(d: f64) -> u64 {
    (d * 1e6).round() as u64
}

/// The point a robot at `me` steers at for its slot `slot`: the slot, unless one of
/// `wrecks` (within the window) blocks the straight path, then the next waypoint of the grid
/// path around `wrecks` and `others` (the arena's discs; they do not trigger a detour), or
/// the slot when no path exists in the window.
pub fn aim(me: Vec2, slot: Vec2, wrecks: &[Keepout], others: &[Keepout], p: &DetourParams) -> Vec2 {
    let in_window = |k: &Keepout| (k.centre - me).norm() <= p.window + k.radius;
    let blocking = wrecks
        .iter()
        .any(|k| in_window(k) && segment_distance(me, slot, k.centre) < k.radius);
    if !p.enabled || !blocking {
        return slot;
    }
    let keepouts: Vec<Keepout> = wrecks.iter().chain(others).filter(|k| in_window(k)).copied().collect();
    plan(me, slot, &keepouts, &[], None, p.cell, p.window).map_or(slot, |(aim, _)| aim)
}

/// The rectangle a robot's centre must stay in (the box less the robot's radius): (min, max).
pub type Bounds = (Vec2, Vec2);

/// The next waypoint from `me` towards `slot` round `keepouts`: A* on the 8-connected grid of
/// side `cell` over the window of half-width `window` around `me` (cells whose centre lies in
/// a keep-out disc, within a cell's side of a closed neck, or outside `bounds`, are not
/// free), to the slot's cell when the slot lies in the window, else to a free border cell,
/// paying the straight distance from it to the slot; then the farthest point of the path `me`
/// sees in a straight line clear of every keep-out and crossing no neck (the slot itself when
/// that is the whole path), with the path's length (cells, then straight to the slot). None:
/// no path in the window.
pub fn plan(
    me: Vec2,
    slot: Vec2,
    keepouts: &[Keepout],
    necks: &[Neck],
    bounds: Option<Bounds>,
    cell: f64,
    window: f64,
) -> Option<(Vec2, f64)> {
    let half = (window / cell).round() as i32;
    let at = |i: i32, j: i32| me + Vec2::new(i as f64, j as f64) * cell;
    let inside = |q: Vec2| {
        bounds.is_none_or(|(lo, hi)| q.x >= lo.x && q.y >= lo.y && q.x <= hi.x && q.y <= hi.y)
    };
    let free = |i: i32, j: i32| {
        (i, j) == (0, 0)
            || (inside(at(i, j))
                && keepouts.iter().all(|k| (at(i, j) - k.centre).norm() >= k.radius)
                && necks.iter().all(|n| segment_distance(n.0, n.1, at(i, j)) >= cell))
    };
    let rel = (slot - me) / cell;
    let slot_cell = (rel.x.round() as i32, rel.y.round() as i32);
    let slot_inside = slot_cell.0.abs() <= half && slot_cell.1.abs() <= half;
    let to_goal = |i: i32, j: i32| {
        let reaches = if slot_inside {
            (i, j) == slot_cell
        } else {
            i.abs() == half || j.abs() == half
        };
        reaches.then(|| cost((at(i, j) - slot).norm()))
    };
    let successors = |n: &Node| -> Vec<(Node, u64)> {
        let Node::Cell(i, j) = *n else {
            return Vec::new();
        };
        let mut out = Vec::with_capacity(9);
        for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)] {
            let (a, b) = (i + di, j + dj);
            if a.abs() <= half && b.abs() <= half && free(a, b) {
                let step = cell * ((di * di + dj * dj) as f64).sqrt();
                out.push((Node::Cell(a, b), cost(step)));
            }
        }
        if let Some(c) = to_goal(i, j) {
            out.push((Node::Goal, c));
        }
        out
    };
    // The straight distance to the slot, rounded down: admissible.
    let heuristic = |n: &Node| match *n {
        Node::Cell(i, j) => ((at(i, j) - slot).norm() * 1e6).floor() as u64,
        Node::Goal => 0,
    };
    let (path, length) = astar(&Node::Cell(0, 0), successors, heuristic, |n| *n == Node::Goal)?;
    let points: Vec<Vec2> = path
        .iter()
        .map(|n| match *n {
            Node::Cell(i, j) => at(i, j),
            Node::Goal => slot,
        })
        .collect();
    // The farthest point of the path in sight (the slot when the goal is).
    let aim = points
        .iter()
        .skip(1)
        .rev()
        .find(|q| sees(me, **q, keepouts) && !necks.iter().any(|n| segments_cross(me, **q, n.0, n.1)))
        .copied()
        .unwrap_or(points.get(1).copied().unwrap_or(slot));
    Some((aim, length as f64 * 1e-6))
}

/// Eq. (16)'s preferred velocity for the slot at `slot`, turned towards `aim`: the speed of
/// the slot's distance (V_p min(1, d / K_a)), the direction of the waypoint.
pub fn steer(me: Vec2, slot: Vec2, aim: Vec2, max_speed: f64, k_a: f64) -> Vec2 {
    let to_aim = aim - me;
    let d = (slot - me).norm();
    if to_aim.norm() <= f64::EPSILON || d <= f64::EPSILON {
        return Vec2::zeros();
    }
    to_aim * (max_speed * (d / k_a).min(1.0) / to_aim.norm())
}

impl super::Formation {
    /// Eq. (16) towards this robot's slot, with the detour around `wrecks` (the real wrecks
    /// motion() puts into ORCA) when `formation.kernels.detour` is resolved (swaps mode).
    pub(super) fn preferred_with_detour(&self, me: Vec2, wrecks: &[Vec2]) -> Vec2 {
        let k = &self.p.kernels;
        let Some(slot) = self.slot.map(|s| self.targets[s]) else {
            return Vec2::zeros();
        };
        let Some(p) = self.p.detour.as_ref().filter(|p| p.enabled) else {
            return crate::formation::preferred::preferred_velocity(me, slot, k.max_speed, k.k_a);
        };
        let reach = k.robot_radius + self.p.orca_margin;
        let wrecks: Vec<Keepout> = wrecks
            .iter()
            .map(|w| Keepout {
                centre: *w,
                radius: 2.0 * reach,
            })
            .collect();
        let a = aim(me, slot, &wrecks, &self.disc_keepouts(reach), p);
        steer(me, slot, a, k.max_speed, k.k_a)
    }

    /// The arena's discs as keep-outs for a robot's centre: each grown by `grow`.
    pub(super) fn disc_keepouts(&self, grow: f64) -> Vec<Keepout> {
        self.discs
            .iter()
            .map(|d| Keepout {
                centre: d.position,
                radius: d.radius + grow,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall() -> Vec<Keepout> {
        // Three wrecks 2.2 apart across the robot's path: the gaps between them (0.2 between
        // bodies) pass no robot.
        [-2.2, 0.0, 2.2]
            .iter()
            .map(|y| Keepout {
                centre: Vec2::new(5.0, *y),
                radius: 2.1,
            })
            .collect()
    }

    #[test]
    fn the_detour_finds_a_path_around_a_wreck_wall_and_reaches_the_slot() {
        let p = DetourParams {
            enabled: true,
            ..DetourParams::default()
        };
        let walls = wall();
        let slot = Vec2::new(10.0, 0.3);
        // Straight at the slot the robot hits the wall: the first aim turns off the line.
        let mut me = Vec2::new(0.0, 0.0);
        let first = aim(me, slot, &walls, &[], &p);
        assert!(first != slot, "the wall blocks the straight path");
        assert!(sees(me, first, &walls));
        // Driving at the aim (0.25 a step, replanned every step, no ORCA) goes round the wall
        // and reaches the slot, its body never touching a wreck's: at least 2 r = 2.0 from
        // every centre (the keep-out radius 2.1 holds the margins; a step between two free
        // cells may cut up to a few hundredths into it).
        let touching = 0.1;
        let mut reached = None;
        for step in 0..400 {
            let a = aim(me, slot, &walls, &[], &p);
            let v = steer(me, slot, a, 0.25, 1.0);
            me += v;
            for k in &walls {
                assert!((me - k.centre).norm() >= k.radius - touching, "step {step}: touches at {me:?}");
            }
            if (me - slot).norm() < 0.05 {
                reached = Some(step);
                break;
            }
        }
        let steps = reached.expect("the slot is reached");
        // Round the wall's end (4.3 from its middle) and back: about 14 units, 56 steps.
        assert!(steps < 120, "{steps} steps");
        // The straight line: without the detour the first step goes into the wall's disc
        // within 3 units (the aim would be the slot).
        let off = DetourParams {
            enabled: false,
            ..p.clone()
        };
        assert_eq!(aim(Vec2::zeros(), slot, &walls, &[], &off), slot);
    }

    #[test]
    fn no_wreck_in_the_way_means_straight_at_the_slot() {
        let p = DetourParams {
            enabled: true,
            ..DetourParams::default()
        };
        let walls = wall();
        // The slot before the wall.
        let slot = Vec2::new(2.0, 0.0);
        assert_eq!(aim(Vec2::zeros(), slot, &walls, &[], &p), slot);
        // A wall beyond the window does not count yet.
        let far: Vec<Keepout> = walls
            .iter()
            .map(|k| Keepout {
                centre: k.centre + Vec2::new(20.0, 0.0),
                ..*k
            })
            .collect();
        assert_eq!(aim(Vec2::zeros(), Vec2::new(40.0, 0.0), &far, &[], &p), Vec2::new(40.0, 0.0));
    }
}
