//! Hunting points by a wall (sec. 3.2.4 is silent on walls; docs/hunting.md section 13).
//!
//! The thesis's ring (3.18)-(3.20) spaces the n_j points evenly on the circle of radius r_s
//! around the target. A target pinned to the arena's edge has part of that circle outside
//! the arena: no robot can stand on those points, so the coalition never captures it
//! (measured: Example 3-A's replacement run, T4 on the top wall for 140 min). With
//! `hunting_points_inside_arena`, when any printed point lies closer than
//! `hunting_point_wall_clearance` to the edge (or beyond it), the points are spread evenly
//! instead over the longest arc of the circle that keeps that clearance, its two ends
//! included; the wall closes the rest of the ring (the world's capture rule counts a wall
//! closer than r_s as a blocked bearing, as the escape does).

use super::hunting_points::hunting_points;
use std::f64::consts::TAU;
use swarm::geometry::Vec2;

/// Angular samples of the circle used to find the arc inside the arena. [chosen] 720: half a
/// degree, 2.6 m of arc at r_s = 0.3 km, well under the capture tolerance.
const ARC_SAMPLES: usize = 720;

/// The arena [0, width] x [0, height] and how far inside it a point must lie, km.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walls {
    pub width: f64,
    pub height: f64,
    pub clearance: f64,
}

impl Walls {
    fn keeps(&self, q: &Vec2) -> bool {
        let c = self.clearance;
        q.x >= c && q.x <= self.width - c && q.y >= c && q.y <= self.height - c
    }
}

/// The n hunting points around `target`: the printed ring ([`hunting_points`], s_1 at bearing
/// `first_angle`) when all of it keeps the clearance (or `walls` is None), else n points
/// evenly over the longest arc of the r_s circle that does, from its clockwise end to its
/// counter-clockwise end (one point: the arc's middle). When no point of the circle keeps the
/// clearance (a target in a corner with r_s below the clearance), the printed ring.
pub fn ring_points(
    target: &Vec2,
    n: usize,
    r_s: f64,
    first_angle: f64,
    walls: Option<&Walls>,
) -> Vec<Vec2> {
    let ring = hunting_points(target, n, r_s, first_angle);
    let Some(w) = walls else {
        return ring;
    };
    if n == 0 || ring.iter().all(|q| w.keeps(q)) {
        return ring;
    }
    let at = |a: f64| target + r_s * Vec2::new(a.cos(), a.sin());
    let step = TAU / ARC_SAMPLES as f64;
    let inside: Vec<bool> = (0..ARC_SAMPLES)
        .map(|k| w.keeps(&at(k as f64 * step)))
        .collect();
    let Some(outside) = inside.iter().position(|x| !x) else {
        return ring; // every sample inside: only a printed point was out, between samples
    };
    // The longest circular run of inside samples, scanning from an outside sample.
    let (mut best, mut run) = ((0usize, 0usize), (0usize, 0usize));
    for j in 1..=ARC_SAMPLES {
        let k = (outside + j) % ARC_SAMPLES;
        if inside[k] {
            if run.1 == 0 {
                run.0 = k;
            }
            run.1 += 1;
            if run.1 > best.1 {
                best = run;
            }
        } else {
            run.1 = 0;
        }
    }
    let (start, len) = best;
    if len == 0 {
        return ring;
    }
    let a0 = start as f64 * step;
    let span = (len - 1) as f64 * step;
    if n == 1 {
        return vec![at(a0 + span / 2.0)];
    }
    (0..n)
        .map(|i| at(a0 + span * i as f64 / (n - 1) as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    const W: Walls = Walls {
        width: 10.0,
        height: 10.0,
        clearance: 0.1,
    };

    #[test]
    fn away_from_the_walls_the_ring_is_the_printed_one() {
        let t = Vec2::new(5.0, 5.0);
        assert_eq!(
            ring_points(&t, 5, 0.3, 0.7, Some(&W)),
            hunting_points(&t, 5, 0.3, 0.7)
        );
    }

    #[test]
    fn on_the_top_wall_the_points_span_the_arc_below_it_by_hand() {
        // Target on the north wall (y = 10): a point keeps the clearance when
        // 10 + 0.3 sin(a) <= 9.9, i.e. sin(a) <= -1/3: a in [-pi + asin(1/3), -asin(1/3)],
        // 141.06 degrees wide, centred due south. Five points: 35.26 degrees apart.
        let t = Vec2::new(5.0, 10.0);
        let pts = ring_points(&t, 5, 0.3, PI / 2.0, Some(&W));
        assert_eq!(pts.len(), 5);
        let half = (1.0f64 / 3.0).asin();
        let mut bearings: Vec<f64> = pts
            .iter()
            .map(|q| {
                assert!(((q - t).norm() - 0.3).abs() < 1e-12, "on the r_s circle");
                assert!(q.y <= 9.9 + 1e-12, "{q:?} keeps the clearance");
                (q.y - t.y).atan2(q.x - t.x)
            })
            .collect();
        bearings.sort_by(f64::total_cmp);
        let sample = TAU / ARC_SAMPLES as f64;
        // The arc's ends within one sample of -pi + asin(1/3) and -asin(1/3).
        assert!((bearings[0] - (-PI + half)).abs() <= sample, "{bearings:?}");
        assert!((bearings[4] - (-half)).abs() <= sample, "{bearings:?}");
        for k in 0..4 {
            let gap = bearings[k + 1] - bearings[k];
            assert!(
                (gap - (PI - 2.0 * half) / 4.0).abs() <= sample,
                "{bearings:?}"
            );
        }
    }

    #[test]
    fn in_a_corner_the_points_keep_clear_of_both_walls() {
        let t = Vec2::new(0.0, 0.0);
        let pts = ring_points(&t, 3, 0.3, 0.0, Some(&W));
        for q in &pts {
            assert!(q.x >= 0.1 - 1e-12 && q.y >= 0.1 - 1e-12, "{q:?}");
            assert!(((q - t).norm() - 0.3).abs() < 1e-12);
        }
        // One point: the middle of the arc, due north-east.
        let one = ring_points(&t, 1, 0.3, 0.0, Some(&W))[0];
        assert!(
            (one.x - one.y).abs() <= 0.3 * TAU / ARC_SAMPLES as f64,
            "{one:?}"
        );
    }

    #[test]
    fn without_walls_or_with_no_room_the_printed_ring() {
        let t = Vec2::new(0.05, 10.0);
        assert_eq!(
            ring_points(&t, 4, 0.3, 0.0, None),
            hunting_points(&t, 4, 0.3, 0.0)
        );
        // r_s 0.05 in a corner: no point of the circle is 0.1 inside both walls.
        let c = Vec2::new(0.0, 0.0);
        assert_eq!(
            ring_points(&c, 4, 0.05, 0.0, Some(&W)),
            hunting_points(&c, 4, 0.05, 0.0)
        );
    }
}
