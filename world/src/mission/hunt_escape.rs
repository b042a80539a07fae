//! The evader's escape strategy of the hunting thesis (003, eq. 2.17, Fig. 2.1; docs/hunting.md
//! section 1.8 and 12 items 1-2).
//!
//! A target stays silent (still) until it senses a pursuer within its sensing radius. Then it
//! flees along the bisector of the largest angle formed, at the target, by two bearing-adjacent
//! pursuers. Eq. (2.17) aims at the midpoint of the two robots' chord, which lies on that
//! bisector only when both are equally far and points the wrong way when the gap exceeds 180
//! degrees, so the bisector itself is used (spec 1.8 [INFERRED]). With one pursuer the gap is the
//! full circle and the target flees straight away from it.
//!
//! Choices where the thesis is silent:
//! - **Walls.** Within `wall_margin` of a wall, the wall counts as one more blocked bearing (the
//!   outward normal), so the largest gap never opens through it; the position is then kept inside
//!   the arena by clamping.
//! - **Capture stays possible with slower robots** (the thesis makes every robot slower than every
//!   target, sec. 2.1.3): the target's speed scales with its largest gap g as (g / 2 pi)^s,
//!   s = `encirclement_slowdown`. Chased from one side it runs at full speed; encircled by L
//!   robots evenly (g = 2 pi / L) it runs at v_j / L^s, so the robots close the ring. s = 0 is
//!   the thesis's literal strategy. Walls count here too: a cornered target is slowed.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use swarm::geometry::Vec2;

/// Tunables of the escape strategy. The defaults mirror the agent's `HuntParams`
/// (`evader_sensing_radius`, `encirclement_slowdown`); a test in the agent crate checks it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EscapeParams {
    /// The target reacts only to pursuers within this distance, km. [chosen] 1.5 km
    /// (spec 12 item 2: the thesis does not say which robots a target considers).
    pub sensing_radius: f64,
    /// A wall closer than this is a blocked bearing, km. [chosen] 0.5 km.
    pub wall_margin: f64,
    /// s in speed = v_j (g / 2 pi)^s: what keeps capture possible with robots slower than
    /// targets (spec 1.3, 12 item 1). [chosen] 1; 0 = the thesis as printed.
    pub encirclement_slowdown: f64,
}

impl Default for EscapeParams {
    fn default() -> Self {
        Self {
            sensing_radius: 1.5,
            wall_margin: 0.5,
            encirclement_slowdown: 1.0,
        }
    }
}

/// The arena [0, width] x [0, height], km.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArenaBox {
    pub width: f64,
    pub height: f64,
}

/// What a fleeing target does this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Escape {
    /// Heading phi, rad in (-pi, pi]: the bisector of the largest bearing gap (2.17).
    pub heading: f64,
    /// The largest bearing gap g, rad in (0, 2 pi].
    pub largest_gap: f64,
    /// Fraction of v_j the target runs at, (g / 2 pi)^s.
    pub speed_factor: f64,
}

/// The escape of a target at `evader` from the robots at `pursuers` (every robot: the target
/// filters by its sensing radius). `None` while it senses no pursuer: it stays silent.
pub fn escape(
    evader: &Vec2,
    pursuers: &[Vec2],
    arena: &ArenaBox,
    p: &EscapeParams,
) -> Option<Escape> {
    let mut bearings: Vec<f64> = pursuers
        .iter()
        .map(|q| q - evader)
        .filter(|r| r.norm() <= p.sensing_radius && r.norm() > 1e-12)
        .map(|r| r.y.atan2(r.x))
        .collect();
    if bearings.is_empty() {
        return None;
    }
    // Walls within the margin block the bearing of their outward normal.
    bearings.extend(wall_bearings(evader, arena, p.wall_margin));
    let (start, gap) = largest_gap(&mut bearings);
    Some(Escape {
        heading: wrap(start + gap / 2.0),
        largest_gap: gap,
        speed_factor: (gap / TAU).powf(p.encirclement_slowdown),
    })
}

/// The bearings (outward normals) of the arena's walls closer than `within` to `at`: each
/// blocks that direction like a pursuer would (the escape's walls, and the capture rule's
/// when hunting points are kept inside the arena).
pub fn wall_bearings(at: &Vec2, arena: &ArenaBox, within: f64) -> Vec<f64> {
    [
        (at.x, PI),                      // west wall, bearing 180 degrees
        (arena.width - at.x, 0.0),       // east
        (at.y, -PI / 2.0),               // south
        (arena.height - at.y, PI / 2.0), // north
    ]
    .iter()
    .filter(|(d, _)| *d < within)
    .map(|(_, b)| *b)
    .collect()
}

/// The largest angular gap between bearing-adjacent directions: (bearing it starts at, going
/// counter-clockwise, and its width). One direction gives the full circle. Ties: the first gap
/// in counter-clockwise order from -pi.
pub fn largest_gap(bearings: &mut [f64]) -> (f64, f64) {
    bearings.sort_by(|a, b| a.total_cmp(b));
    let n = bearings.len();
    let mut best = (bearings[0], -1.0);
    for k in 0..n {
        // Gap k runs from bearing k to bearing k+1; the last one wraps around through +-pi.
        let g = if k + 1 < n {
            bearings[k + 1] - bearings[k]
        } else {
            bearings[0] + TAU - bearings[k]
        };
        if g > best.1 + 1e-12 {
            best = (bearings[k], g);
        }
    }
    best
}

/// One step of a target at `evader` with top speed `speed` (km/min) over `dt` minutes: the
/// escape, then the position kept inside the arena. A silent target does not move.
pub fn flee_step(
    evader: &Vec2,
    pursuers: &[Vec2],
    arena: &ArenaBox,
    speed: f64,
    dt: f64,
    p: &EscapeParams,
) -> Vec2 {
    match escape(evader, pursuers, arena, p) {
        None => *evader,
        Some(e) => {
            let next =
                evader + speed * e.speed_factor * dt * Vec2::new(e.heading.cos(), e.heading.sin());
            Vec2::new(
                next.x.clamp(0.0, arena.width),
                next.y.clamp(0.0, arena.height),
            )
        }
    }
}

use crate::kinematics::wrap;

#[cfg(test)]
mod tests {
    use super::*;

    const ARENA: ArenaBox = ArenaBox {
        width: 10.0,
        height: 10.0,
    };

    fn at(x: f64, y: f64) -> Vec2 {
        Vec2::new(x, y)
    }

    fn angle_close(a: f64, b: f64) -> bool {
        wrap(a - b).abs() < 1e-9
    }

    #[test]
    fn silent_until_a_pursuer_is_sensed() {
        let p = EscapeParams::default();
        assert_eq!(escape(&at(5.0, 5.0), &[at(6.6, 5.0)], &ARENA, &p), None);
        assert_eq!(
            flee_step(&at(5.0, 5.0), &[at(6.6, 5.0)], &ARENA, 1.0, 0.1, &p),
            at(5.0, 5.0)
        );
        assert!(escape(&at(5.0, 5.0), &[at(6.4, 5.0)], &ARENA, &p).is_some());
    }

    #[test]
    fn one_pursuer_flee_straight_away_at_full_speed() {
        let e = escape(
            &at(5.0, 5.0),
            &[at(6.0, 5.0)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(angle_close(e.heading, PI), "{e:?}");
        assert!((e.largest_gap - TAU).abs() < 1e-12);
        assert!((e.speed_factor - 1.0).abs() < 1e-12);
        let e = escape(
            &at(5.0, 5.0),
            &[at(4.0, 4.0)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(angle_close(e.heading, PI / 4.0), "{e:?}");
    }

    #[test]
    fn symmetric_pair_flees_sideways_at_half_speed() {
        // North and south pursuers: both gaps are pi; the first from -pi counter-clockwise is
        // the one from -pi/2 (south) to pi/2 (north) through 0, so the target flees east.
        let e = escape(
            &at(5.0, 5.0),
            &[at(5.0, 6.0), at(5.0, 4.0)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(angle_close(e.heading, 0.0), "{e:?}");
        assert!((e.speed_factor - 0.5).abs() < 1e-12);
        // East-west pair at different distances: heading north or south, never toward either.
        let e = escape(
            &at(5.0, 5.0),
            &[at(6.0, 5.0), at(3.7, 5.0)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(e.heading.cos().abs() < 1e-9, "{e:?}");
    }

    #[test]
    fn three_pursuers_bisect_the_open_half() {
        // Pursuers east, north, west: the largest gap is the south half (pi), heading -pi/2.
        let e = escape(
            &at(5.0, 5.0),
            &[at(6.0, 5.0), at(5.0, 6.2), at(4.5, 5.0)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(angle_close(e.heading, -PI / 2.0), "{e:?}");
        assert!((e.largest_gap - PI).abs() < 1e-9);
    }

    #[test]
    fn gap_wider_than_pi_uses_the_bisector_not_the_chord_midpoint() {
        // Pursuers at bearings 10 and 80 degrees, at 1.0 and 0.4 km: the largest gap runs from
        // 80 to 370 degrees (290 wide), bisector 225 degrees. The chord midpoint of eq. (2.17)
        // would point at about 30 degrees, toward the pursuers.
        let b = |deg: f64, r: f64| {
            at(
                5.0 + r * deg.to_radians().cos(),
                5.0 + r * deg.to_radians().sin(),
            )
        };
        let e = escape(
            &at(5.0, 5.0),
            &[b(10.0, 1.0), b(80.0, 0.4)],
            &ARENA,
            &EscapeParams::default(),
        )
        .unwrap();
        assert!(
            angle_close(e.heading, 225f64.to_radians()),
            "heading {}",
            e.heading.to_degrees()
        );
        assert!((e.largest_gap - 290f64.to_radians()).abs() < 1e-9);
    }

    #[test]
    fn wall_blocks_the_bearing_through_it() {
        // Near the east wall, a pursuer to the west: without the wall it would run east into the
        // wall; with it the two blocked bearings (0 and pi) leave north/south gaps.
        let p = EscapeParams::default();
        let e = escape(&at(9.8, 5.0), &[at(9.0, 5.0)], &ARENA, &p).unwrap();
        assert!(e.heading.cos().abs() < 1e-9, "{e:?}");
        assert!((e.speed_factor - 0.5).abs() < 1e-12);
        // Far from the wall the same relative set flees east.
        let e = escape(&at(5.8, 5.0), &[at(5.0, 5.0)], &ARENA, &p).unwrap();
        assert!(angle_close(e.heading, 0.0));
    }

    #[test]
    fn cornered_target_stays_in_the_arena() {
        let p = EscapeParams::default();
        let mut x = at(9.9, 9.9);
        let pursuer = at(9.0, 9.0);
        for _ in 0..100 {
            x = flee_step(&x, &[pursuer], &ARENA, 1.2, 0.1, &p);
            assert!(
                (0.0..=10.0).contains(&x.x) && (0.0..=10.0).contains(&x.y),
                "{x:?}"
            );
        }
        // It got away from the corner pursuer along a wall, not through it.
        assert!((x - pursuer).norm() > 1.0, "{x:?}");
    }

    #[test]
    fn no_slowdown_when_the_parameter_is_zero() {
        let p = EscapeParams {
            encirclement_slowdown: 0.0,
            ..EscapeParams::default()
        };
        let ring: Vec<Vec2> = (0..4)
            .map(|k| {
                at(5.0, 5.0)
                    + 0.3 * Vec2::new((k as f64 * PI / 2.0).cos(), (k as f64 * PI / 2.0).sin())
            })
            .collect();
        assert_eq!(
            escape(&at(5.0, 5.0), &ring, &ARENA, &p)
                .unwrap()
                .speed_factor,
            1.0
        );
        let slowed = escape(&at(5.0, 5.0), &ring, &ARENA, &EscapeParams::default()).unwrap();
        assert!(
            (slowed.speed_factor - 0.25).abs() < 1e-12,
            "four robots evenly: (1/4)^1"
        );
    }
}
