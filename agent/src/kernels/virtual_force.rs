//! Simplified virtual-force model, eq. (5) of the search paper, and its roaming rule of paper
//! §3.1 / Fig. 2 (spec §2.3-2.4): a roaming robot is repelled by its two nearest robots and
//! moves at V_max along the net force. Shared: the search behaviour's roaming and subgroup
//! separation, BSOA's eq. (21) weights, and roam's repulsions use [`magnitude`].

use crate::kernels::nearest::TwoNearest;
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// Tunables of the virtual-force model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Virtual-force coefficient c = 3.9 (Table 4, eq. 5).
    pub c: f64,
    /// Enhanced obstacle-avoidance distance l_1 = 10 (Table 4, eq. 5).
    pub l1: f64,
    /// L_R; robots repel within d_0 = 2·L_R (eq. 5). The paper never gives
    /// L_R; by its text it is the radius of a robot's own disc in the family of
    /// L_T and L_B (both 100, Table 4): d_0 = 2·L_R for a robot (two discs) is
    /// set against d_0 = L_B for an obstacle (one disc), and "robots repel while
    /// ∃ R_dis < 2 L_R and spread evenly over the area" (paper §4) then means
    /// they repel while their sensing discs overlap. So L_R = L_T = 100,
    /// d_0 = 200 (issue 20 item 5; 50 before). [chosen] spec §5 item 4.
    pub l_r: f64,
    /// Obstacle force cut-off d_0 = L_B = 100 (eq. 5, Table 4).
    pub l_b: f64,
    /// Maximum speed V_max = 10 (Table 4, eq. 4).
    pub v_max: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            c: 3.9,
            l1: 10.0,
            l_r: 100.0,
            l_b: 100.0,
            v_max: 10.0,
        }
    }
}

impl Params {
    /// d_0 for robot–robot forces: 2·L_R (eq. 5).
    pub fn d0_robot(&self) -> f64 {
        2.0 * self.l_r
    }
    /// d_0 for obstacle / boundary-point forces: L_B (eq. 5).
    pub fn d0_obstacle(&self) -> f64 {
        self.l_b
    }
}

/// ‖f_vr‖ = c (l_1 / d)² for 0 ≤ d ≤ d_0, else 0 — eq. (5).
/// d = 0 gives +∞ (callers skip coincident points).
pub fn magnitude(d: f64, d0: f64, p: &Params) -> f64 {
    if (0.0..=d0).contains(&d) {
        p.c * (p.l1 / d).powi(2)
    } else {
        0.0
    }
}

/// Repulsive force of an object at `from` on a robot at `x` (points from
/// the object to the robot). Zero beyond `d0` or when the points coincide.
pub fn repulsion(x: &Vec2, from: &Vec2, d0: f64, p: &Params) -> Vec2 {
    let r = x - from;
    let d = r.norm();
    if d <= 1e-9 {
        return Vec2::zeros();
    }
    r / d * magnitude(d, d0, p)
}

/// Attractive force of an obstacle boundary point `to` on a robot at `x`
/// (paper §3.1: "obstacle boundaries attract the robot"), cut-off L_B.
pub fn attraction(x: &Vec2, to: &Vec2, p: &Params) -> Vec2 {
    -repulsion(x, to, p.d0_obstacle(), p)
}

/// Indices of the two robots of `others` nearest to `x` (ties: lower
/// index first; robots at exactly `x` are skipped).
pub fn two_nearest(x: &Vec2, others: &[Vec2]) -> Vec<usize> {
    nearest_two(x, others).into_iter().flatten().collect()
}

/// The two robots of `others` nearest to `x` in one pass ([`TwoNearest`]; coincident robots
/// and NaN distances are skipped, as the filter of a sort would).
fn nearest_two(x: &Vec2, others: &[Vec2]) -> [Option<usize>; 2] {
    let mut best = TwoNearest::default();
    for (i, o) in others.iter().enumerate() {
        let d = (o - x).norm();
        if d <= 1e-9 || d.is_nan() {
            continue;
        }
        best.offer(d, i);
    }
    [best.first(), best.second()].map(|b| b.map(|(_, i)| i))
}

/// f_i = f_vr1 + f_vr2: repulsion of the two nearest robots (Fig. 2).
pub fn roaming_force(x: &Vec2, others: &[Vec2], p: &Params) -> Vec2 {
    nearest_two(x, others)
        .into_iter()
        .flatten()
        .map(|i| repulsion(x, &others[i], p.d0_robot(), p))
        .sum()
}

/// Roaming desired velocity V_if(t+1) = V_max·(cos∠f_i, sin∠f_i)
/// (paper §3.1). When f_i = 0 (no robot within 2·L_R) the robot keeps the
/// heading of `previous_velocity` at V_max, or stands still if that is zero.
/// [chosen] spec §5 item 5.
pub fn roaming_velocity(x: &Vec2, others: &[Vec2], previous_velocity: &Vec2, p: &Params) -> Vec2 {
    let f = roaming_force(x, others, p);
    let dir = if f.norm() > 1e-12 {
        f
    } else {
        *previous_velocity
    };
    let n = dir.norm();
    if n > 1e-12 {
        dir * (p.v_max / n)
    } else {
        Vec2::zeros()
    }
}

/// The mirror images of a robot at `x` in the four walls of the arena [0, width] x [0, height]
/// (west, east, south, north): a wall seen as a robot standing as far beyond it as the robot
/// stands before it, so that eq. (5) pushes a robot off a wall it comes within L_R of, as it
/// pushes it off a robot within 2 L_R. Used by the search behaviour's wall rule.
pub fn wall_mirrors(x: &Vec2, width: f64, height: f64) -> [Vec2; 4] {
    [
        Vec2::new(-x.x, x.y),
        Vec2::new(2.0 * width - x.x, x.y),
        Vec2::new(x.x, -x.y),
        Vec2::new(x.x, 2.0 * height - x.y),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq5_values_and_cutoff() {
        let p = Params::default();
        assert!((magnitude(10.0, 100.0, &p) - 3.9).abs() < 1e-12);
        assert!((magnitude(5.0, 100.0, &p) - 15.6).abs() < 1e-12);
        assert!((magnitude(100.0, 100.0, &p) - 0.039).abs() < 1e-12);
        assert_eq!(magnitude(100.0001, 100.0, &p), 0.0);
    }

    #[test]
    fn repulsion_and_attraction_directions() {
        let p = Params::default();
        let f = repulsion(&Vec2::new(0.0, 0.0), &Vec2::new(10.0, 0.0), 100.0, &p);
        assert!(f.x < 0.0 && f.y.abs() < 1e-12);
        let a = attraction(&Vec2::new(0.0, 0.0), &Vec2::new(10.0, 0.0), &p);
        assert!(a.x > 0.0);
        assert_eq!(
            repulsion(&Vec2::new(1.0, 1.0), &Vec2::new(1.0, 1.0), 100.0, &p),
            Vec2::zeros()
        );
    }

    #[test]
    fn roaming_uses_only_two_nearest() {
        let p = Params::default();
        let x = Vec2::new(0.0, 0.0);
        // Two near robots to the east/north-east, a crowd far west ignored.
        let others = [
            Vec2::new(-90.0, 0.0),
            Vec2::new(10.0, 0.0),
            Vec2::new(-95.0, 1.0),
            Vec2::new(0.0, 20.0),
        ];
        assert_eq!(two_nearest(&x, &others), vec![1, 3]);
        let v = roaming_velocity(&x, &others, &Vec2::zeros(), &p);
        assert!((v.norm() - 10.0).abs() < 1e-9);
        assert!(v.x < 0.0 && v.y < 0.0, "{v:?}");
        // stronger (nearer) east robot dominates: mostly westward
        assert!(v.x.abs() > v.y.abs());
    }

    #[test]
    fn two_nearest_matches_sorting_all() {
        let x = Vec2::new(0.0, 0.0);
        let mut others: Vec<Vec2> = (0..40)
            .map(|i| Vec2::new(((i * 37) % 11) as f64 - 5.0, ((i * 53) % 7) as f64 - 3.0))
            .collect();
        others.push(Vec2::new(f64::NAN, 0.0));
        for n in 0..others.len() {
            let o = &others[..n];
            let mut idx: Vec<(f64, usize)> = o
                .iter()
                .enumerate()
                .map(|(i, q)| ((q - x).norm(), i))
                .filter(|(d, _)| *d > 1e-9)
                .collect();
            idx.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let want: Vec<usize> = idx.into_iter().take(2).map(|(_, i)| i).collect();
            assert_eq!(two_nearest(&x, o), want, "first {n}");
        }
    }

    #[test]
    fn roaming_without_neighbours_keeps_heading() {
        let p = Params::default();
        let others = [Vec2::new(500.0, 0.0)];
        let v = roaming_velocity(&Vec2::new(0.0, 0.0), &others, &Vec2::new(0.0, 3.0), &p);
        assert!((v - Vec2::new(0.0, 10.0)).norm() < 1e-12);
        let v0 = roaming_velocity(&Vec2::new(0.0, 0.0), &[], &Vec2::zeros(), &p);
        assert_eq!(v0, Vec2::zeros());
    }

    /// Hand-computed: a robot at (30, 500) of a 1000 x 1000 arena has its west mirror at
    /// (-30, 500), 60 away (inside d_0 = 100 for L_R = 50), the others 940+ away; with no
    /// robot near, the two nearest "robots" are the west and the south mirror (at (30, -500),
    /// 1000 away, beyond d_0): the force points east, magnitude c (l_1 / 60)^2.
    #[test]
    fn a_wall_mirror_pushes_a_robot_off_the_wall() {
        let p = Params {
            l_r: 50.0,
            ..Params::default()
        };
        let x = Vec2::new(30.0, 500.0);
        let m = wall_mirrors(&x, 1000.0, 1000.0);
        assert_eq!(m[0], Vec2::new(-30.0, 500.0));
        assert_eq!(m[1], Vec2::new(1970.0, 500.0));
        assert_eq!(m[2], Vec2::new(30.0, -500.0));
        assert_eq!(m[3], Vec2::new(30.0, 1500.0));
        let f = roaming_force(&x, &m, &p);
        assert!(
            (f.x - 3.9 * (10.0f64 / 60.0).powi(2)).abs() < 1e-12,
            "{f:?}"
        );
        assert!(f.y.abs() < 1e-12, "{f:?}");
    }
}
