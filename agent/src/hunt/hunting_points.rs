//! Hunting-point assignment (thesis sec. 3.2.4, Fig. 3.2, eqs. 3.17-3.20; spec 3.7).
//!
//! When the first coalition member enters the target's effective hunting range r_e (3.17), it
//! becomes the local leader. The leader places n_j points on the formation circle of radius r_s
//! around the target (3.18)-(3.20), the first on the line leader-target, and assigns them by the
//! distance-balance principle: every robot claims its nearest free point; a point claimed once is
//! matched; a point claimed by several goes to the farthest claimant (as written, so the nearer
//! ones, which can reach another point sooner, renegotiate); repeat with what is left. The
//! assignment is recomputed each cycle while the target moves (step 5), by the caller.

use crate::hunt::model::RobotId;
use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use swarm::geometry::Vec2;

/// (3.17): the robot at `x` is inside the effective hunting range G of the target at `target`.
pub fn in_effective_range(x: &Vec2, target: &Vec2, r_e: f64) -> bool {
    (x - target).norm() <= r_e
}

/// Who leads a coalition's encirclement: the first member to enter r_e, kept afterwards, and the
/// bearing (from the target) at which it entered, which orients the ring of points from then on.
/// [chosen] The ring translates with the target but does not turn with the leader: re-anchoring
/// s_1 on the leader's bearing every cycle makes the ring turn whenever the leader moves to a
/// point other than s_1, so that robot chases a point that keeps moving away and never gets there.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HuntingPhase {
    leader: Option<RobotId>,
    anchor: f64,
}

impl HuntingPhase {
    pub fn leader(&self) -> Option<RobotId> {
        self.leader
    }

    /// The bearing of s_1 (the leader's bearing from the target when it entered r_e).
    pub fn anchor_angle(&self) -> Option<f64> {
        self.leader.map(|_| self.anchor)
    }

    /// Update with the members' current positions; returns the leader once there is one. If
    /// several enter in the same cycle, the nearest leads (ties: lower id). A leader that left the
    /// coalition (died, was swapped) is replaced the same way.
    pub fn update(
        &mut self,
        members: &[(RobotId, Vec2)],
        target: &Vec2,
        r_e: f64,
    ) -> Option<RobotId> {
        if let Some(l) = self.leader {
            if members.iter().any(|(id, _)| *id == l) {
                return self.leader;
            }
            self.leader = None;
        }
        self.leader = members
            .iter()
            .filter(|(_, x)| in_effective_range(x, target, r_e))
            .min_by(|a, b| {
                (a.1 - target)
                    .norm()
                    .total_cmp(&(b.1 - target).norm())
                    .then(a.0.cmp(&b.0))
            })
            .map(|(id, _)| *id);
        self.leader
    }
}

/// The n hunting points (3.18)-(3.20) around `target` on radius r_s, the first at bearing
/// `first_angle`, then clockwise: angle_i = first_angle - a_i, a_i = 2 pi (i - 1) / n. The thesis
/// prints first_angle = pi (x_js = x_j + r_s cos(pi - a_i)), which puts s_1 due west whatever the
/// leader; its text puts s_1 on the leader-target line: use [`leader_angle`] (spec 3.7).
pub fn hunting_points(target: &Vec2, n: usize, r_s: f64, first_angle: f64) -> Vec<Vec2> {
    (0..n)
        .map(|i| {
            let a = TAU * i as f64 / n as f64; // (3.20)
            let ang = first_angle - a;
            target + r_s * Vec2::new(ang.cos(), ang.sin()) // (3.18), (3.19)
        })
        .collect()
}

/// The bearing of the leader from the target: s_1 is "the intersection of the line
/// leader-target with the encirclement circle".
pub fn leader_angle(target: &Vec2, leader: &Vec2) -> f64 {
    let d = leader - target;
    if d.norm() <= 1e-12 {
        PI // the printed (3.18) when the leader stands on the target
    } else {
        d.y.atan2(d.x)
    }
}

/// Distance-balance assignment with negotiation (sec. 3.2.4 steps 2-5): robot id -> point index.
/// Every robot gets exactly one point while points remain, and no point gets two robots.
/// `farthest` = the thesis's rule for a contested point; false gives it to the nearest claimant.
pub fn assign(
    robots: &[(RobotId, Vec2)],
    points: &[Vec2],
    farthest: bool,
) -> BTreeMap<RobotId, usize> {
    let mut free_robots: Vec<(RobotId, Vec2)> = robots.to_vec();
    free_robots.sort_by_key(|r| r.0);
    let mut free_points: Vec<usize> = (0..points.len()).collect();
    let mut out = BTreeMap::new();
    while !free_robots.is_empty() && !free_points.is_empty() {
        // Step 2-3: every remaining robot claims its nearest remaining point (ties: lower index).
        let mut claims: BTreeMap<usize, Vec<(RobotId, f64)>> = BTreeMap::new();
        for (id, x) in &free_robots {
            let (m, d) = free_points
                .iter()
                .map(|&m| (m, (points[m] - x).norm())) // D_im
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .expect("a free point");
            claims.entry(m).or_default().push((*id, d));
        }
        // Step 4: S_m = 1 -> matched; S_m > 1 -> the farthest (or nearest) claimant.
        for (m, claimants) in claims {
            let winner = if farthest {
                claimants
                    .iter()
                    .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            } else {
                claimants
                    .iter()
                    .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
            }
            .expect("a claimant")
            .0;
            out.insert(winner, m);
            free_robots.retain(|r| r.0 != winner);
            free_points.retain(|&k| k != m);
        }
    }
    out
}

/// Capture (sec. 1.4): every member stands within `tolerance` of its assigned point and every
/// point is taken.
pub fn encircled(
    robots: &[(RobotId, Vec2)],
    points: &[Vec2],
    assignment: &BTreeMap<RobotId, usize>,
    tolerance: f64,
) -> bool {
    assignment.len() == points.len()
        && robots.iter().all(|(id, x)| {
            assignment
                .get(id)
                .is_some_and(|&m| (points[m] - x).norm() <= tolerance)
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::BTreeSet;

    #[test]
    fn points_evenly_spaced_on_r_s_first_toward_the_leader() {
        let target = Vec2::new(5.0, 5.0);
        let leader = Vec2::new(5.0, 8.0); // due north
        let pts = hunting_points(&target, 5, 0.3, leader_angle(&target, &leader));
        assert_eq!(pts.len(), 5);
        assert!(
            (pts[0] - Vec2::new(5.0, 5.3)).norm() < 1e-12,
            "s_1 on the leader-target line"
        );
        for (k, q) in pts.iter().enumerate() {
            assert!(((q - target).norm() - 0.3).abs() < 1e-12);
            let next = pts[(k + 1) % 5];
            // Chord between neighbours: 2 r_s sin(pi / n).
            assert!(((next - q).norm() - 0.6 * (PI / 5.0).sin()).abs() < 1e-12);
        }
    }

    #[test]
    fn printed_3_18_puts_the_first_point_west() {
        let pts = hunting_points(&Vec2::new(1.0, 1.0), 4, 0.5, PI);
        // angles pi, pi/2, 0, -pi/2 (cos(pi - a_i), a_i = 0, pi/2, pi, 3pi/2)
        let expect = [(0.5, 1.0), (1.0, 1.5), (1.5, 1.0), (1.0, 0.5)];
        for (q, (x, y)) in pts.iter().zip(expect) {
            assert!((q - Vec2::new(x, y)).norm() < 1e-12, "{q:?}");
        }
    }

    #[test]
    fn contested_point_goes_to_the_farthest_claimant() {
        // Points east (1,0) and west (-1,0) of a target at the origin; robots A at (2,0) and
        // B at (3,0) both claim east. Farthest rule: B takes east, A renegotiates to west.
        let pts = hunting_points(&Vec2::zeros(), 2, 1.0, 0.0);
        let robots = [(1, Vec2::new(2.0, 0.0)), (2, Vec2::new(3.0, 0.0))];
        let a = assign(&robots, &pts, true);
        assert_eq!(a[&2], 0);
        assert_eq!(a[&1], 1);
        let a = assign(&robots, &pts, false);
        assert_eq!(a[&1], 0);
        assert_eq!(a[&2], 1);
    }

    #[test]
    fn every_robot_assigned_exactly_once() {
        let mut rng = ChaCha8Rng::seed_from_u64(17);
        for trial in 0..500 {
            let n = rng.gen_range(1..=8);
            let target = Vec2::new(rng.gen_range(0.0..10.0), rng.gen_range(0.0..10.0));
            let robots: Vec<(RobotId, Vec2)> = (0..n)
                .map(|i| {
                    // Often clustered on one side, where greedy nearest-point assignment collides.
                    let c = if trial % 2 == 0 { 0.5 } else { 3.0 };
                    (
                        i as RobotId + 1,
                        target + Vec2::new(rng.gen_range(0.2..c + 0.2), rng.gen_range(-c..c)),
                    )
                })
                .collect();
            let pts = hunting_points(&target, n, 0.3, leader_angle(&target, &robots[0].1));
            for farthest in [true, false] {
                let a = assign(&robots, &pts, farthest);
                assert_eq!(a.len(), n, "trial {trial}: every robot gets a point");
                let used: BTreeSet<usize> = a.values().copied().collect();
                assert_eq!(used.len(), n, "trial {trial}: no point twice");
            }
        }
    }

    #[test]
    fn more_robots_than_points_leaves_the_extra_unassigned() {
        let pts = hunting_points(&Vec2::zeros(), 2, 1.0, 0.0);
        let robots = [
            (1, Vec2::new(2.0, 0.0)),
            (2, Vec2::new(-2.0, 0.0)),
            (3, Vec2::new(0.0, 5.0)),
        ];
        let a = assign(&robots, &pts, true);
        assert_eq!(a.len(), 2);
    }

    #[test]
    fn leader_is_the_first_to_enter_and_stays() {
        let target = Vec2::new(0.0, 0.0);
        let mut ph = HuntingPhase::default();
        assert_eq!(
            ph.update(
                &[(1, Vec2::new(2.0, 0.0)), (2, Vec2::new(0.0, 3.0))],
                &target,
                1.0
            ),
            None
        );
        assert_eq!(
            ph.update(
                &[(1, Vec2::new(0.9, 0.0)), (2, Vec2::new(0.0, 1.5))],
                &target,
                1.0
            ),
            Some(1)
        );
        // R2 is now nearer, but R1 entered first.
        assert_eq!(
            ph.update(
                &[(1, Vec2::new(0.8, 0.0)), (2, Vec2::new(0.0, 0.3))],
                &target,
                1.0
            ),
            Some(1)
        );
        // R1 dies: R2, inside, takes over.
        assert_eq!(
            ph.update(&[(2, Vec2::new(0.0, 0.3))], &target, 1.0),
            Some(2)
        );
    }

    #[test]
    fn encircled_needs_every_point_within_tolerance() {
        let pts = hunting_points(&Vec2::zeros(), 3, 0.3, 0.0);
        let robots: Vec<(RobotId, Vec2)> = pts
            .iter()
            .enumerate()
            .map(|(k, q)| (k as RobotId + 1, q + Vec2::new(0.04, 0.0)))
            .collect();
        let a = assign(&robots, &pts, true);
        assert!(encircled(&robots, &pts, &a, 0.05));
        assert!(!encircled(&robots, &pts, &a, 0.03));
        assert!(!encircled(
            &robots[..2],
            &pts,
            &assign(&robots[..2], &pts, true),
            0.05
        ));
    }
}
