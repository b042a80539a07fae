//! Dynamic division of labour (paper §2.2; spec §2.2): Type I roulette
//! target choice (eqs. 2-3), Type II attachment, and the closed-loop
//! adjustment that caps a subgroup at g_max with Table 1's priority.

use rand::Rng;
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use swarm::geometry::Vec2;

/// Target identifier (targets are told apart by frequency, paper §2.1).
pub type TargetId = usize;
/// Robot identifier.
pub type RobotId = usize;

/// Tunables of the division of labour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Target response threshold I_min = 1; only I_ij > I_min counts (Table 4).
    pub i_min: f64,
    /// Largest subgroup g_max = G_max = 6 (Table 4).
    pub g_max: usize,
    /// Communication radius R_cm = 300 (Table 4).
    pub r_cm: f64,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            i_min: 1.0,
            g_max: 6,
            r_cm: 300.0,
        }
    }
}

/// Candidate targets {T_j : I_ij > I_min}, sorted by target id so the
/// roulette does not depend on the caller's order.
pub fn candidates(signals: &[(TargetId, f64)], p: &Params) -> Vec<(TargetId, f64)> {
    let mut c: Vec<(TargetId, f64)> = signals
        .iter()
        .copied()
        .filter(|(_, i)| *i > p.i_min)
        .collect();
    c.sort_by_key(|(t, _)| *t);
    c
}

/// p_ij = I_ij / Σ_ρ I_iρ over the candidates (eq. 2).
pub fn roulette_probabilities(cands: &[(TargetId, f64)]) -> Vec<f64> {
    let total: f64 = cands.iter().map(|(_, i)| i).sum();
    cands.iter().map(|(_, i)| i / total).collect()
}

/// Target choice of a Type I robot (paper §2.2): keep `previous` if it is
/// still a candidate (no random draw); otherwise draw r_a ~ U[0,1) from `rng`
/// (exactly one draw, even with a single candidate) and pick T_j with
/// P(i, j−1) ≤ r_a < P(i, j), P(i, j) = Σ_{ρ≤j} p_iρ (eq. 3). `None` when no
/// signal exceeds I_min (the robot is then not Type I, spec §5 item 25).
pub fn choose_target<R: Rng + ?Sized>(
    signals: &[(TargetId, f64)],
    previous: Option<TargetId>,
    p: &Params,
    rng: &mut R,
) -> Option<TargetId> {
    let cands = candidates(signals, p);
    if cands.is_empty() {
        return None;
    }
    if let Some(prev) = previous {
        if cands.iter().any(|(t, _)| *t == prev) {
            return Some(prev);
        }
    }
    let r_a: f64 = rng.gen();
    let mut cum = 0.0; // P(i, j), eq. (3)
    for ((t, _), pj) in cands.iter().zip(roulette_probabilities(&cands)) {
        cum += pj;
        if r_a < cum {
            return Some(*t);
        }
    }
    cands.last().map(|(t, _)| *t) // rounding: P(i, k) may fall just below 1
}

/// The nearest Type I robot within R_cm of a Type II robot at `position`
/// (its "communicating robot", paper §2.2), with the distance. Ties: lower
/// robot id.
pub fn communicating_robot(
    position: &Vec2,
    type_i: &[(RobotId, Vec2)],
    p: &Params,
) -> Option<(RobotId, f64)> {
    type_i
        .iter()
        .map(|(id, x)| (*id, (x - position).norm()))
        .filter(|(_, d)| *d <= p.r_cm)
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
}

/// How a member knows the subgroup's target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Role {
    /// Senses the target itself, with signal strength I_ij.
    TypeI { signal: f64 },
    /// Told by its communicating robot, at this distance from it.
    TypeII { distance_to_communicator: f64 },
}

/// One subgroup member.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Member {
    /// Robot id.
    pub robot: RobotId,
    /// Type I or Type II.
    pub role: Role,
}

/// Table 1 priority: Type I before Type II; Type I by stronger signal;
/// Type II by shorter distance to the communicating robot (whichever Type I
/// robot that is); remaining ties by lower robot id.
pub fn priority(a: &Member, b: &Member) -> Ordering {
    let key = match (a.role, b.role) {
        (Role::TypeI { .. }, Role::TypeII { .. }) => Ordering::Less,
        (Role::TypeII { .. }, Role::TypeI { .. }) => Ordering::Greater,
        (Role::TypeI { signal: sa }, Role::TypeI { signal: sb }) => sb.total_cmp(&sa),
        (
            Role::TypeII {
                distance_to_communicator: da,
            },
            Role::TypeII {
                distance_to_communicator: db,
            },
        ) => da.total_cmp(&db),
    };
    key.then(a.robot.cmp(&b.robot))
}

/// Result of the closed-loop adjustment, both lists in rank order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Adjustment {
    /// The best g_max members, who stay.
    pub kept: Vec<RobotId>,
    /// The others, who leave the subgroup and roam.
    pub dropped: Vec<RobotId>,
}

/// Closed-loop adjustment (paper §2.2, after ref [29]): rank the members by
/// [`priority`] and keep the first g_max.
pub fn closed_loop_adjust(members: &[Member], p: &Params) -> Adjustment {
    let mut ranked = members.to_vec();
    ranked.sort_by(priority);
    let ids: Vec<RobotId> = ranked.iter().map(|m| m.robot).collect();
    let cut = p.g_max.min(ids.len());
    Adjustment {
        kept: ids[..cut].to_vec(),
        dropped: ids[cut..].to_vec(),
    }
}

/// Whether `members[i]` is among those [`closed_loop_adjust`] keeps (robot ids distinct):
/// fewer than g_max members rank before it. One pass, where the full ranking sorts them all
/// (every candidate asks this every tick, of everyone it heard).
pub fn is_kept(members: &[Member], i: usize, p: &Params) -> bool {
    let me = &members[i];
    let before = members
        .iter()
        .filter(|m| priority(m, me) == Ordering::Less)
        .count();
    before < p.g_max
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn t1(robot: RobotId, signal: f64) -> Member {
        Member {
            robot,
            role: Role::TypeI { signal },
        }
    }
    fn t2(robot: RobotId, d: f64) -> Member {
        Member {
            robot,
            role: Role::TypeII {
                distance_to_communicator: d,
            },
        }
    }

    /// Table 1 of the paper, rows in the printed order.
    fn table1() -> Vec<Member> {
        vec![
            t1(8, 2.1703),
            t2(15, 125.0506),
            t2(59, 110.3372),
            t2(61, 126.5248),
            t1(79, 2.8835),
            t2(81, 98.6029),
            t2(92, 123.8633),
            t2(96, 136.2546),
        ]
    }

    #[test]
    fn closed_loop_adjustment_reproduces_table1() {
        let a = closed_loop_adjust(&table1(), &Params::default());
        assert_eq!(a.kept, vec![79, 8, 81, 59, 92, 15]);
        assert_eq!(a.dropped, vec![61, 96]);
        // independent of input order
        let mut rev = table1();
        rev.reverse();
        assert_eq!(closed_loop_adjust(&rev, &Params::default()), a);
    }

    #[test]
    fn small_subgroup_keeps_everyone() {
        let a = closed_loop_adjust(&table1()[..4], &Params::default());
        assert_eq!(a.kept, vec![8, 59, 15, 61]);
        assert!(a.dropped.is_empty());
    }

    #[test]
    fn roulette_probabilities_eq2() {
        let c = candidates(
            &[(3, 6.0), (1, 2.0), (2, 0.5), (7, 2.0)],
            &Params::default(),
        );
        assert_eq!(c, vec![(1, 2.0), (3, 6.0), (7, 2.0)]);
        assert_eq!(roulette_probabilities(&c), vec![0.2, 0.6, 0.2]);
    }

    #[test]
    fn roulette_frequencies_match_eq3() {
        let p = Params::default();
        let sig = [(4, 30.0), (9, 10.0), (2, 60.0), (5, 0.9)];
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut counts = [0usize; 10];
        let n = 20000;
        for _ in 0..n {
            counts[choose_target(&sig, None, &p, &mut rng).unwrap()] += 1;
        }
        assert_eq!(counts[5], 0); // below I_min
        for (t, want) in [(2, 0.6), (4, 0.3), (9, 0.1)] {
            let f = counts[t] as f64 / n as f64;
            assert!((f - want).abs() < 0.015, "T{t}: {f} vs {want}");
        }
    }

    #[test]
    fn previous_target_is_kept_without_drawing() {
        let p = Params::default();
        let sig = [(4, 30.0), (9, 10.0)];
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let before = rng.clone();
        assert_eq!(choose_target(&sig, Some(9), &p, &mut rng), Some(9));
        assert_eq!(rng, before);
        // previous no longer above threshold: roulette, one draw
        let sig = [(4, 30.0), (9, 0.5)];
        assert_eq!(choose_target(&sig, Some(9), &p, &mut rng), Some(4));
        assert_ne!(rng, before);
        assert_eq!(
            choose_target(&[(1, 1.0), (2, -3.0)], None, &p, &mut rng),
            None
        );
    }

    #[test]
    fn type_ii_attaches_to_nearest_type_i_within_range() {
        let p = Params::default();
        let ti = [
            (8, Vec2::new(0.0, 0.0)),
            (79, Vec2::new(100.0, 0.0)),
            (3, Vec2::new(1000.0, 0.0)),
        ];
        assert_eq!(
            communicating_robot(&Vec2::new(60.0, 0.0), &ti, &p),
            Some((79, 40.0))
        );
        assert_eq!(
            communicating_robot(&Vec2::new(50.0, 0.0), &ti, &p),
            Some((8, 50.0))
        );
        assert_eq!(communicating_robot(&Vec2::new(-400.0, 0.0), &ti, &p), None);
    }

    #[test]
    fn is_kept_agrees_with_the_ranking() {
        use rand::Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let p = Params::default();
        let (mut kept, mut dropped) = (0, 0);
        for _ in 0..500 {
            let n = rng.gen_range(1..20);
            let mut ids: Vec<RobotId> = (0..40).collect();
            let members: Vec<Member> = (0..n)
                .map(|_| {
                    let robot = ids.swap_remove(rng.gen_range(0..ids.len()));
                    // Coarse values, so that equal signals and distances (ties by id) occur.
                    if rng.gen_bool(0.4) {
                        t1(robot, rng.gen_range(0..5) as f64)
                    } else {
                        t2(robot, rng.gen_range(0..5) as f64 * 10.0)
                    }
                })
                .collect();
            let adj = closed_loop_adjust(&members, &p);
            for (i, m) in members.iter().enumerate() {
                let want = adj.kept.contains(&m.robot);
                assert_eq!(is_kept(&members, i, &p), want, "{members:?} {i}");
                if want {
                    kept += 1;
                } else {
                    dropped += 1;
                }
            }
        }
        assert!(kept > 100 && dropped > 100, "{kept} {dropped}");
    }
}
