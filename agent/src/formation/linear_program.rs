//! The velocity selection of eqs. (25)-(26): the velocity closest to V_pref inside the speed
//! disc ||v|| <= V_p and a set of half-planes, by the incremental 2-D linear program of
//! van den Berg et al. 2011 (the paper's ref. \[21\]), and its 3-D fallback when the half-planes
//! have no common point: the velocity that minimises the largest violation of the "soft"
//! half-planes while the "hard" ones stay satisfied.
//!
//! Constraints are processed in the order given (deterministic; no random permutation).
//! Algorithm (ours, after the reference's description): keep the optimum of the constraints
//! seen so far; when constraint i is violated by it, the new optimum lies on i's boundary line
//! (the objective is convex), so solve the 1-D problem on that line against the constraints
//! before i and the disc; if that interval is empty, the LP is infeasible at i.

use swarm::geometry::Vec2;

/// The half-plane { v : (v - point) . normal >= 0 } (the paper's eq. 22 form); `normal` is a
/// unit vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPlane {
    /// A point on the boundary line.
    pub point: Vec2,
    /// Unit normal pointing into the allowed side.
    pub normal: Vec2,
}

impl HalfPlane {
    /// How far v is outside the half-plane (negative inside).
    pub fn violation(&self, v: Vec2) -> f64 {
        -(v - self.point).dot(&self.normal)
    }
}

/// What the 2-D program optimises.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Objective {
    /// The point nearest to this one (eq. 26).
    Closest(Vec2),
    /// The point farthest along this direction (the 3-D fallback's inner problem).
    Farthest(Vec2),
}

/// How the selected velocity was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Selection {
    /// Every half-plane holds (eq. 25's set is non-empty).
    Feasible,
    /// The soft half-planes conflict: the largest violation of a soft one is minimised, the hard
    /// ones hold.
    SoftRelaxed,
    /// The hard ones conflict too: all were minimised together (only `keep` held).
    HardRelaxed,
}

/// The result of [`select_velocity`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Selected {
    /// The velocity.
    pub velocity: Vec2,
    /// How it was found.
    pub selection: Selection,
}

/// A violation this small counts as satisfied (rounding of the 1-D solves).
const EPS: f64 = 1e-10;

/// Eq. (26) over eq. (25)'s set with three priority levels: `keep` (always held: the
/// acceleration polygon), `hard` (held unless `keep` and `hard` conflict: obstacles) and `soft`
/// (other robots). `max_speed` is the radius of the speed disc.
pub fn select_velocity(
    keep: &[HalfPlane],
    hard: &[HalfPlane],
    soft: &[HalfPlane],
    max_speed: f64,
    preferred: Vec2,
) -> Selected {
    let mut all = Vec::with_capacity(keep.len() + hard.len() + soft.len());
    all.extend_from_slice(keep);
    all.extend_from_slice(hard);
    all.extend_from_slice(soft);
    let fixed = keep.len() + hard.len();
    match solve_2d(&all, max_speed, Objective::Closest(preferred)) {
        Ok(velocity) => Selected {
            velocity,
            selection: Selection::Feasible,
        },
        Err((failed, partial)) if failed >= fixed => Selected {
            velocity: solve_3d(
                &all[..fixed],
                &all[fixed..],
                failed - fixed,
                partial,
                max_speed,
            ),
            selection: Selection::SoftRelaxed,
        },
        Err(_) => {
            // keep + hard conflict: relax obstacles and robots together, hold only `keep`.
            let start = match solve_2d(keep, max_speed, Objective::Closest(preferred)) {
                Ok(v) => v,
                Err((_, v)) => v,
            };
            Selected {
                velocity: solve_3d(keep, &all[keep.len()..], 0, start, max_speed),
                selection: Selection::HardRelaxed,
            }
        }
    }
}

/// The 2-D program: Ok(optimum), or Err((index of the constraint that made it infeasible, the
/// optimum of the constraints before it)).
fn solve_2d(lines: &[HalfPlane], radius: f64, objective: Objective) -> Result<Vec2, (usize, Vec2)> {
    let mut v = match objective {
        Objective::Closest(p) if p.norm() > radius => p * (radius / p.norm()),
        Objective::Closest(p) => p,
        Objective::Farthest(d) => d * (radius / d.norm().max(f64::MIN_POSITIVE)),
    };
    for i in 0..lines.len() {
        if lines[i].violation(v) > EPS {
            match solve_1d(lines, i, radius, objective) {
                Some(next) => v = next,
                None => return Err((i, v)),
            }
        }
    }
    Ok(v)
}

/// The optimum on line i's boundary subject to lines\[..i\] and the disc, if any.
fn solve_1d(lines: &[HalfPlane], i: usize, radius: f64, objective: Objective) -> Option<Vec2> {
    let line = lines[i];
    // Points on the line: point + t dir.
    let dir = Vec2::new(-line.normal.y, line.normal.x);
    let along = line.point.dot(&dir);
    let disc = along * along - line.point.norm_squared() + radius * radius;
    if disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let (mut lo, mut hi) = (-along - root, -along + root);
    for other in &lines[..i] {
        let denom = dir.dot(&other.normal);
        let numer = (other.point - line.point).dot(&other.normal);
        if denom.abs() <= 1e-12 {
            // Parallel: the whole line is on one side of the other boundary.
            if numer > EPS {
                return None;
            }
            continue;
        }
        let t = numer / denom;
        if denom > 0.0 {
            lo = lo.max(t);
        } else {
            hi = hi.min(t);
        }
        if lo > hi + EPS {
            return None;
        }
    }
    let hi = hi.max(lo);
    let t = match objective {
        Objective::Closest(p) => (p - line.point).dot(&dir).clamp(lo, hi),
        Objective::Farthest(d) if d.dot(&dir) > 0.0 => hi,
        Objective::Farthest(d) if d.dot(&dir) < 0.0 => lo,
        Objective::Farthest(_) => 0.0f64.clamp(lo, hi),
    };
    Some(line.point + dir * t)
}

/// The 3-D fallback: minimise delta = the largest violation of a `soft` half-plane over
/// (v, delta), holding `fixed` and the disc. `v` is the optimum over fixed and soft\[..from\].
///
/// Incremental like the 2-D program: when soft line i is violated by more than the current
/// delta, the new optimum has line i tight, delta = -(v - p_i).n_i, and the earlier soft lines
/// j < i become (v - p_j).n_j >= (v - p_i).n_i, i.e. the half-plane v.(n_j - n_i) >=
/// p_j.n_j - p_i.n_i; maximising (v - p_i).n_i over those, the fixed lines and the disc is a
/// 2-D program with a linear objective.
fn solve_3d(
    fixed: &[HalfPlane],
    soft: &[HalfPlane],
    from: usize,
    mut v: Vec2,
    radius: f64,
) -> Vec2 {
    let mut delta: f64 = 0.0;
    for line in &soft[..from] {
        delta = delta.max(line.violation(v));
    }
    let mut lines = Vec::with_capacity(fixed.len() + soft.len());
    for i in from..soft.len() {
        if soft[i].violation(v) <= delta + EPS {
            continue;
        }
        lines.clear();
        lines.extend_from_slice(fixed);
        let ni = soft[i].normal;
        let offset_i = soft[i].point.dot(&ni);
        for earlier in &soft[..i] {
            let m = earlier.normal - ni;
            let len = m.norm();
            if len <= 1e-9 {
                // Same direction: the tighter of the two decides; line i is the violated one.
                continue;
            }
            let unit = m / len;
            let rhs = earlier.point.dot(&earlier.normal) - offset_i;
            lines.push(HalfPlane {
                point: unit * (rhs / len),
                normal: unit,
            });
        }
        if let Ok(next) = solve_2d(&lines, radius, Objective::Farthest(ni)) {
            v = next;
        }
        delta = delta.max(soft[i].violation(v));
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn hp(px: f64, py: f64, nx: f64, ny: f64) -> HalfPlane {
        let n = Vec2::new(nx, ny).normalize();
        HalfPlane {
            point: Vec2::new(px, py),
            normal: n,
        }
    }

    #[test]
    fn hand_computed_cases() {
        // Prefer (2, 0) within speed 1: (1, 0).
        let s = select_velocity(&[], &[], &[], 1.0, Vec2::new(2.0, 0.0));
        assert!((s.velocity - Vec2::new(1.0, 0.0)).norm() < 1e-12);
        // x <= 0.5 (normal -x through (0.5, 0)): (0.5, 0).
        let s = select_velocity(
            &[],
            &[],
            &[hp(0.5, 0.0, -1.0, 0.0)],
            1.0,
            Vec2::new(2.0, 0.0),
        );
        assert_eq!(s.selection, Selection::Feasible);
        assert!((s.velocity - Vec2::new(0.5, 0.0)).norm() < 1e-12);
        // x <= 0.5 and y >= 0.2 with preferred (2, -1): the corner (0.5, 0.2).
        let lines = [hp(0.5, 0.0, -1.0, 0.0), hp(0.0, 0.2, 0.0, 1.0)];
        let s = select_velocity(&[], &[], &lines, 1.0, Vec2::new(2.0, -1.0));
        assert!((s.velocity - Vec2::new(0.5, 0.2)).norm() < 1e-12, "{s:?}");
        // x >= 0.6 and x <= 0.2 conflict: the least largest violation is x = 0.4 (0.2 each).
        let lines = [hp(0.6, 0.0, 1.0, 0.0), hp(0.2, 0.0, -1.0, 0.0)];
        let s = select_velocity(&[], &[], &lines, 1.0, Vec2::new(0.0, 0.0));
        assert_eq!(s.selection, Selection::SoftRelaxed);
        assert!((s.velocity.x - 0.4).abs() < 1e-9, "{s:?}");
        // keep x >= 0.5 against hard x <= 0.2 and soft y >= 0.3: keep holds; the hard and soft
        // lines share the least largest violation: x = 0.5 (0.3 over), y anywhere >= 0.
        let keep = [hp(0.5, 0.0, 1.0, 0.0)];
        let hard = [hp(0.2, 0.0, -1.0, 0.0)];
        let soft = [hp(0.0, 0.3, 0.0, 1.0)];
        let s = select_velocity(&keep, &hard, &soft, 1.0, Vec2::new(0.0, 0.0));
        assert_eq!(s.selection, Selection::HardRelaxed);
        assert!(
            s.velocity.x >= 0.5 - 1e-9 && s.velocity.x < 0.5 + 1e-6,
            "{s:?}"
        );
        assert!(hard[0].violation(s.velocity) <= 0.3 + 1e-9);
        assert!(soft[0].violation(s.velocity) <= 0.3 + 1e-9);
        // The same conflict with x >= 0.6 hard: it holds exactly.
        let s = select_velocity(&[], &lines[..1], &lines[1..], 1.0, Vec2::new(0.0, 0.0));
        assert!((s.velocity.x - 0.6).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn feasible_answers_hold_every_half_plane_and_beat_sampled_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(25);
        let mut feasible = 0;
        for _ in 0..2000 {
            let k = rng.gen_range(1..8);
            let lines: Vec<HalfPlane> = (0..k)
                .map(|_| {
                    let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                    hp(
                        rng.gen_range(-1.0..1.0),
                        rng.gen_range(-1.0..1.0),
                        a.cos(),
                        a.sin(),
                    )
                })
                .collect();
            let pref = Vec2::new(rng.gen_range(-2.0..2.0), rng.gen_range(-2.0..2.0));
            let s = select_velocity(&[], &[], &lines, 1.0, pref);
            assert!(s.velocity.norm() <= 1.0 + 1e-9);
            if s.selection != Selection::Feasible {
                continue;
            }
            feasible += 1;
            for l in &lines {
                assert!(l.violation(s.velocity) < 1e-8);
            }
            // No sampled feasible point is closer to the preferred velocity.
            let best = (s.velocity - pref).norm();
            for _ in 0..200 {
                let q = Vec2::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
                if q.norm() <= 1.0 && lines.iter().all(|l| l.violation(q) <= 0.0) {
                    assert!((q - pref).norm() >= best - 1e-9);
                }
            }
        }
        assert!(feasible > 500, "{feasible}");
    }

    #[test]
    fn fallback_minimises_the_largest_violation() {
        // Sampled check: no point of the disc has a smaller largest violation.
        let mut rng = ChaCha8Rng::seed_from_u64(26);
        let mut relaxed = 0;
        for _ in 0..1000 {
            let lines: Vec<HalfPlane> = (0..5)
                .map(|_| {
                    let a: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                    let n = Vec2::new(a.cos(), a.sin());
                    // Each line excludes a large part of the disc, so conflicts are common.
                    HalfPlane {
                        point: n * rng.gen_range(0.0..0.9),
                        normal: n,
                    }
                })
                .collect();
            let s = select_velocity(&[], &[], &lines, 1.0, Vec2::zeros());
            if s.selection != Selection::SoftRelaxed {
                continue;
            }
            relaxed += 1;
            let worst = |v: Vec2| {
                lines
                    .iter()
                    .map(|l| l.violation(v))
                    .fold(f64::MIN, f64::max)
            };
            let got = worst(s.velocity);
            for _ in 0..300 {
                let q = Vec2::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
                if q.norm() <= 1.0 {
                    assert!(worst(q) >= got - 1e-7, "{} < {got}", worst(q));
                }
            }
        }
        assert!(relaxed > 50, "{relaxed}");
    }
}
