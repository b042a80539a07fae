//! Target position estimate from ≥ 3 simultaneous detectors, eqs. (7)-(10)
//! (paper §3.2; spec §2.6, §5 items 14-15).
//!
//! T_est = argmin f(x, y),  f = Σ_i | ‖(x, y) − X_i‖ − d_i |   (eqs. 9-10)
//!
//! The paper solves this with an unspecified hybrid PSO; here a
//! deterministic multi-start Nelder–Mead is used instead (spec §5 item 15),
//! seeded on the circle of the strongest detector, which the target lies on.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use swarm::geometry::Vec2;

/// Residual norm of the objective.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Objective {
    /// Sum of absolute residuals, as eq. (10) is printed.
    L1,
    /// Sum of squared residuals ("least squares" in the paper's prose).
    L2,
}

/// Tunables of the estimator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Objective: L1 as printed in eq. (10). [chosen] spec §5 item 15.
    pub objective: Objective,
    /// Fewest simultaneous detectors for an estimate: 3 (paper §3.2, eqs. 7-8).
    pub min_detectors: usize,
    /// Use at most this many detectors, strongest signal first; 0 = all
    /// (default: all). [chosen] spec §5 item 14.
    pub max_detectors: usize,
    /// Number of starts spread evenly on the strongest detector's circle
    /// (8); the detectors' centroid is one more start. [chosen] spec §5 item 15.
    pub n_starts: usize,
    /// Initial simplex edge length (2.0 units). [chosen] spec §5 item 15.
    pub initial_step: f64,
    /// Nelder–Mead iteration cap per run (300). [chosen] spec §5 item 15.
    pub max_iterations: usize,
    /// Stop when the simplex's objective spread and size fall below this
    /// (1e-10), for the best start's refinement (the restarts). [chosen] spec §5 item 15.
    pub tolerance: f64,
    /// The same for the runs from the starts (1e-2: simplex within 0.1 units);
    /// they only pick the basin the restarts refine. 2.7x faster than running
    /// every start to `tolerance`, for the same minimum (test
    /// `coarse_starts_find_the_minima_of_full_starts`). [chosen] spec §5 item 15.
    pub start_tolerance: f64,
    /// Extra Nelder–Mead restarts from the best point found (2), to undo
    /// premature simplex collapse. [chosen] spec §5 item 15.
    pub restarts: usize,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            objective: Objective::L1,
            min_detectors: 3,
            max_detectors: 0,
            n_starts: 8,
            initial_step: 2.0,
            max_iterations: 300,
            tolerance: 1e-10,
            start_tolerance: 1e-2,
            restarts: 2,
        }
    }
}

/// One detector: a subgroup member that senses the target itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Detection {
    /// Robot position X_i(t).
    pub position: Vec2,
    /// Estimated distance d_{T,i} = G⁻¹(I_ij) (eq. 6).
    pub distance: f64,
    /// Measured signal I_ij (used to find the strongest detector).
    pub signal: f64,
}

/// Result of [`estimate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// T_est (eq. 10).
    pub position: Vec2,
    /// f(T_est) (eq. 9 or its L2 variant).
    pub residual: f64,
}

/// f(x, y) of eqs. (9)-(10) (or its squared variant).
pub fn objective(x: &Vec2, dets: &[Detection], obj: Objective) -> f64 {
    dets.iter()
        .map(|d| {
            let r = (x - d.position).norm() - d.distance;
            match obj {
                Objective::L1 => r.abs(),
                Objective::L2 => r * r,
            }
        })
        .sum()
}

/// Minimises `f` from `x0` with a 2-D Nelder–Mead simplex (reflection 1,
/// expansion 2, contraction ½, shrink ½). Deterministic.
pub fn nelder_mead<F: Fn(&Vec2) -> f64>(
    f: &F,
    x0: Vec2,
    step: f64,
    max_iter: usize,
    tol: f64,
) -> (Vec2, f64) {
    let mut s = [
        (x0, f(&x0)),
        (x0 + Vec2::new(step, 0.0), f(&(x0 + Vec2::new(step, 0.0)))),
        (x0 + Vec2::new(0.0, step), f(&(x0 + Vec2::new(0.0, step)))),
    ];
    for _ in 0..max_iter {
        sort3(&mut s);
        let size = (s[1].0 - s[0].0).norm().max((s[2].0 - s[0].0).norm());
        if (s[2].1 - s[0].1).abs() <= tol && size <= tol.sqrt() {
            break;
        }
        let c = (s[0].0 + s[1].0) / 2.0;
        let xr = c + (c - s[2].0);
        let fr = f(&xr);
        if fr < s[0].1 {
            let xe = c + (c - s[2].0) * 2.0;
            let fe = f(&xe);
            s[2] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < s[1].1 {
            s[2] = (xr, fr);
        } else {
            let (xc, fc) = if fr < s[2].1 {
                let xc = c + (xr - c) * 0.5;
                (xc, f(&xc))
            } else {
                let xc = c + (s[2].0 - c) * 0.5;
                (xc, f(&xc))
            };
            if fc < s[2].1.min(fr) {
                s[2] = (xc, fc);
            } else {
                for k in 1..3 {
                    let xk = s[0].0 + (s[k].0 - s[0].0) * 0.5;
                    s[k] = (xk, f(&xk));
                }
            }
        }
    }
    sort3(&mut s);
    s[0]
}

/// The simplex by objective value, ties keeping their order: what a stable sort gives, by
/// insertion (the generic sort's set-up cost was most of a Nelder-Mead iteration).
fn sort3(s: &mut [(Vec2, f64); 3]) {
    if s[1].1.total_cmp(&s[0].1).is_lt() {
        s.swap(0, 1);
    }
    if s[2].1.total_cmp(&s[1].1).is_lt() {
        s.swap(1, 2);
        if s[1].1.total_cmp(&s[0].1).is_lt() {
            s.swap(0, 1);
        }
    }
}

/// T_est from the detections (eq. 10), or `None` with fewer than
/// `min_detectors` usable detections (spec §5 item 14: the caller then drops
/// the c3 term). Deterministic: same input, same bits.
pub fn estimate(dets: &[Detection], p: &Params) -> Option<Estimate> {
    let mut used: Vec<Detection> = dets
        .iter()
        .filter(|d| d.position.iter().all(|v| v.is_finite()) && d.distance.is_finite())
        .copied()
        .collect();
    if used.len() < p.min_detectors.max(1) {
        return None;
    }
    // strongest first (stable: ties keep input order)
    used.sort_by(|a, b| b.signal.total_cmp(&a.signal));
    if p.max_detectors > 0 {
        used.truncate(p.max_detectors.max(p.min_detectors));
    }
    let strongest = used[0];
    let f = |x: &Vec2| objective(x, &used, p.objective);

    let mut starts: Vec<Vec2> = (0..p.n_starts)
        .map(|k| {
            let a = TAU * k as f64 / p.n_starts as f64;
            strongest.position + Vec2::new(a.cos(), a.sin()) * strongest.distance.max(0.0)
        })
        .collect();
    starts.push(used.iter().map(|d| d.position).sum::<Vec2>() / used.len() as f64);

    let mut best: Option<(Vec2, f64)> = None;
    for x0 in starts {
        let r = nelder_mead(&f, x0, p.initial_step, p.max_iterations, p.start_tolerance);
        if best.is_none_or(|b| r.1 < b.1) {
            best = Some(r);
        }
    }
    let mut best = best?;
    for _ in 0..p.restarts {
        let r = nelder_mead(
            &f,
            best.0,
            p.initial_step * 0.1,
            p.max_iterations,
            p.tolerance,
        );
        if r.1 < best.1 {
            best = r;
        }
    }
    Some(Estimate {
        position: best.0,
        residual: best.1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::calibration::{self, Calibration};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn exact(target: Vec2, robots: &[Vec2]) -> Vec<Detection> {
        robots
            .iter()
            .map(|r| {
                let d = (target - r).norm();
                Detection {
                    position: *r,
                    distance: d,
                    signal: 1e4 / (d * d),
                }
            })
            .collect()
    }

    #[test]
    fn recovers_noise_free_target_within_one_unit() {
        let cases = [
            (
                Vec2::new(500.0, 520.0),
                vec![
                    Vec2::new(450.0, 480.0),
                    Vec2::new(560.0, 500.0),
                    Vec2::new(510.0, 600.0),
                ],
            ),
            (
                Vec2::new(0.0, 0.0),
                vec![
                    Vec2::new(-60.0, 10.0),
                    Vec2::new(30.0, 70.0),
                    Vec2::new(40.0, -50.0),
                    Vec2::new(5.0, 5.0),
                ],
            ),
            // target outside the detectors' triangle
            (
                Vec2::new(300.0, 300.0),
                vec![
                    Vec2::new(220.0, 250.0),
                    Vec2::new(240.0, 230.0),
                    Vec2::new(215.0, 215.0),
                ],
            ),
        ];
        for p in [
            Params::default(),
            Params {
                objective: Objective::L2,
                ..Params::default()
            },
        ] {
            for (target, robots) in &cases {
                let e = estimate(&exact(*target, robots), &p).expect("3+ detectors");
                let err = (e.position - target).norm();
                assert!(err < 1.0, "{:?}: error {err}", p.objective);
                assert!(err < 1e-3, "noise-free should be near exact, got {err}");
            }
        }
    }

    #[test]
    fn nearly_collinear_detectors_pick_the_strongest_side() {
        // Detectors on a line; the mirror image of the target across the line
        // fits equally well. Any estimate must be one of the two mirror points.
        let target = Vec2::new(50.0, 20.0);
        let robots = [
            Vec2::new(0.0, 0.0),
            Vec2::new(40.0, 0.0),
            Vec2::new(90.0, 0.0),
        ];
        let e = estimate(&exact(target, &robots), &Params::default()).unwrap();
        let mirror = Vec2::new(50.0, -20.0);
        let err = (e.position - target)
            .norm()
            .min((e.position - mirror).norm());
        assert!(err < 1.0, "{:?}", e.position);
    }

    #[test]
    fn with_calibrated_noisy_distances_error_is_moderate() {
        let cp = calibration::Params::default();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let cal = Calibration::build(&cp, &mut rng);
        let target = Vec2::new(400.0, 400.0);
        let robots = [
            Vec2::new(380.0, 390.0),
            Vec2::new(415.0, 385.0),
            Vec2::new(405.0, 420.0),
            Vec2::new(370.0, 420.0),
        ];
        let dets: Vec<Detection> = robots
            .iter()
            .map(|r| {
                let i = calibration::measure_signal((target - r).norm(), &cp, &mut rng);
                Detection {
                    position: *r,
                    distance: cal.inverse(i),
                    signal: i,
                }
            })
            .collect();
        let e = estimate(&dets, &Params::default()).unwrap();
        let err = (e.position - target).norm();
        eprintln!("estimator error with calibrated noisy distances: {err:.3}");
        assert!(err < 3.0, "{:?}", e.position);
    }

    #[test]
    fn too_few_detectors_gives_none() {
        let d = exact(
            Vec2::new(0.0, 0.0),
            &[Vec2::new(1.0, 1.0), Vec2::new(5.0, 0.0)],
        );
        assert!(estimate(&d, &Params::default()).is_none());
    }

    #[test]
    fn deterministic() {
        let d = exact(
            Vec2::new(12.3, 45.6),
            &[
                Vec2::new(0.0, 0.0),
                Vec2::new(30.0, 10.0),
                Vec2::new(10.0, 70.0),
            ],
        );
        let a = estimate(&d, &Params::default()).unwrap();
        let b = estimate(&d, &Params::default()).unwrap();
        assert_eq!(a.position.x.to_bits(), b.position.x.to_bits());
        assert_eq!(a.position.y.to_bits(), b.position.y.to_bits());
    }

    #[test]
    fn sort3_is_a_stable_sort() {
        let vals = [0.0, 1.0, -1.0, f64::NAN, 0.0, -0.0];
        for a in vals {
            for b in vals {
                for c in vals {
                    let mut s = [
                        (Vec2::new(0.0, 0.0), a),
                        (Vec2::new(1.0, 0.0), b),
                        (Vec2::new(2.0, 0.0), c),
                    ];
                    let mut want = s;
                    want.sort_by(|x, y| x.1.total_cmp(&y.1));
                    sort3(&mut s);
                    assert_eq!(format!("{s:?}"), format!("{want:?}"));
                }
            }
        }
    }

    #[test]
    fn nelder_mead_minimises_a_quadratic() {
        let f = |x: &Vec2| (x.x - 3.0).powi(2) + 10.0 * (x.y + 1.0).powi(2);
        let (x, fx) = nelder_mead(&f, Vec2::new(0.0, 0.0), 1.0, 500, 1e-14);
        assert!((x - Vec2::new(3.0, -1.0)).norm() < 1e-5 && fx < 1e-9);
    }

    /// Random detection sets like a subgroup's: 3-12 detectors within L_T of a target,
    /// distances off by up to 15 %.
    fn random_cases(n: usize, seed: u64) -> Vec<Vec<Detection>> {
        use rand::Rng;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let t = Vec2::new(rng.gen_range(0.0..1000.0), rng.gen_range(0.0..1000.0));
                let k = rng.gen_range(3..=12);
                (0..k)
                    .map(|_| {
                        let a: f64 = rng.gen_range(0.0..TAU);
                        let r: f64 = rng.gen_range(3.0..100.0);
                        Detection {
                            position: t + Vec2::new(a.cos(), a.sin()) * r,
                            distance: (r * (1.0 + rng.gen_range(-0.15..0.15))).max(1.0),
                            signal: 1e5 / (r * r),
                        }
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn coarse_starts_find_the_minima_of_full_starts() {
        for objective in [Objective::L1, Objective::L2] {
            let coarse = Params {
                objective,
                ..Params::default()
            };
            let full = Params {
                start_tolerance: coarse.tolerance,
                ..coarse.clone()
            };
            let cases = random_cases(2000, 5);
            let (mut above, mut far) = (0, 0);
            for dets in &cases {
                let a = estimate(dets, &coarse).unwrap();
                let b = estimate(dets, &full).unwrap();
                // f more than 1e-4 (relative) above the full runs' minimum: another basin.
                above += (a.residual > b.residual * (1.0 + 1e-4) + 1e-9) as usize;
                far += ((a.position - b.position).norm() > 0.1) as usize;
            }
            eprintln!(
                "{objective:?}: coarse starts above full in {above} of 2000, > 0.1 apart in {far}"
            );
            assert!(above <= 10 && far <= 10, "{objective:?}: {above} {far}");
        }
    }
}
