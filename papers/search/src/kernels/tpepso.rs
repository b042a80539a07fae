//! TPEPSO cooperative-search update, eq. (11) (paper §3.3; spec §2.7), and
//! the EPSO baseline as its c3 = 0 variant (spec §5 item 28).
//!
//!   V_ip(t+1) = ω V_i(t) + c1 r1 (pb_i − X_i) + c2 r2 (sgb − X_i) + c3 r3 (T_est − X_i)
//!   V_if(t+1) = V_i(t) + α (V_ip(t+1) − V_i(t))
//!   X_if(t+1) = X_i(t) + V_i(t+1)                                            (11)

use rand::Rng;
use serde::{Deserialize, Serialize};
use swarm::geometry::{clamp_norm, Vec2};

/// Which cooperative-search rule to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Variant {
    /// Eq. (11) with the position-estimate term.
    Tpepso,
    /// Eq. (11) with c3 = 0 (spec §5 item 28).
    Epso,
}

/// Tunables of eq. (11).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Inertia weight ω = 0.5, constant (Table 4).
    pub w: f64,
    /// Cognitive coefficient c1 = 1 (Table 4).
    pub c1: f64,
    /// Social coefficient c2 = 1.2 (Table 4).
    pub c2: f64,
    /// Position-estimate coefficient c3 = 1.2 (Table 4).
    pub c3: f64,
    /// Motion-inertia factor α = 0.1 (Table 4).
    pub alpha: f64,
    /// Maximum speed V_max = 10 (Table 4); ‖V_if‖ is clamped to it by
    /// rescaling. [chosen] spec §5 item 12.
    pub v_max: f64,
    /// Draw r1, r2, r3 per dimension (true) or one scalar each per robot per
    /// step (false, default). [chosen] spec §5 item 11.
    pub per_dimension_random: bool,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            w: 0.5,
            c1: 1.0,
            c2: 1.2,
            c3: 1.2,
            alpha: 0.1,
            v_max: 10.0,
            per_dimension_random: false,
        }
    }
}

impl Params {
    /// C0 = 1 + αω − α of eq. (27).
    pub fn c0(&self) -> f64 {
        1.0 + self.alpha * self.w - self.alpha
    }

    /// Convergence region (32) of Theorem 1 for given r1..r3 (with the
    /// spec §2.10 sign fix α(ω−1) < 0, i.e. C0 < 1, and the Jury condition
    /// C0 > −1): 2C0 − ΣC + 2 > 0, ΣC > 0, −1 < C0 < 1, C_k = α c_k r_k.
    pub fn theorem1_holds(&self, r: [f64; 3], variant: Variant) -> bool {
        let c3 = if variant == Variant::Epso {
            0.0
        } else {
            self.c3
        };
        let sum_c = self.alpha * (self.c1 * r[0] + self.c2 * r[1] + c3 * r[2]);
        let c0 = self.c0();
        2.0 * c0 - sum_c + 2.0 > 0.0 && sum_c > 0.0 && c0 < 1.0 && c0 > -1.0
    }
}

/// What one subgroup member knows at step t.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// X_i(t).
    pub position: Vec2,
    /// V_i(t), the velocity actually flown last step.
    pub velocity: Vec2,
    /// pb_i: best position since joining the subgroup.
    pub personal_best: Vec2,
    /// sgb: best position of the subgroup.
    pub subgroup_best: Vec2,
    /// T_est (eq. 10), `None` with fewer than 3 detectors: the c3 term is
    /// then dropped. [chosen] spec §5 item 14.
    pub target_estimate: Option<Vec2>,
}

fn draw<R: Rng + ?Sized>(rng: &mut R, per_dim: bool) -> Vec2 {
    let a: f64 = rng.gen();
    let b = if per_dim { rng.gen() } else { a };
    Vec2::new(a, b)
}

/// V_if(t+1) of eq. (11), clamped to V_max. Draws r1, r2, r3 in that order
/// from `rng` (2 draws each when per-dimension) in *both* variants and
/// whether or not T_est exists, so TPEPSO and EPSO runs consume the same
/// random stream (common random numbers, spec §5 item 31).
pub fn desired_velocity<R: Rng + ?Sized>(
    s: &State,
    variant: Variant,
    p: &Params,
    rng: &mut R,
) -> Vec2 {
    let pd = p.per_dimension_random;
    let (r1, r2, r3) = (draw(rng, pd), draw(rng, pd), draw(rng, pd));
    let x = s.position;
    let mut v_ip = s.velocity * p.w
        + (s.personal_best - x).component_mul(&r1) * p.c1
        + (s.subgroup_best - x).component_mul(&r2) * p.c2;
    if let (Variant::Tpepso, Some(t)) = (variant, s.target_estimate) {
        v_ip += (t - x).component_mul(&r3) * p.c3;
    }
    let v_if = s.velocity + (v_ip - s.velocity) * p.alpha; // eq. (11), 2nd line
    clamp_norm(v_if, p.v_max)
}

/// Updates a (position, fitness) best record; larger fitness is better
/// (fitness = measured signal I_ij, spec §5 item 10). Ties keep the old best.
pub fn update_best(best: &mut Option<(Vec2, f64)>, position: Vec2, fitness: f64) -> bool {
    match best {
        Some((_, f)) if fitness <= *f => false,
        _ => {
            *best = Some((position, fitness));
            true
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Runs a 6-robot subgroup on a static target with noise-free fitness
    /// (the signal m·Q/d²) and T_est = `t_est`; returns the final distances
    /// and the first step at which some robot was within L_0 = 5.
    fn run(
        p: &Params,
        variant: Variant,
        t_est: Option<Vec2>,
        steps: usize,
        seed: u64,
    ) -> (Vec<f64>, Option<usize>) {
        let target = Vec2::new(600.0, 600.0);
        let fitness = |x: &Vec2| 1e4 / (x - target).norm_squared().max(1e-12);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut x: Vec<Vec2> = (0..6)
            .map(|k| {
                // a non-collinear blob ~100 from the target (with scalar r's a
                // collinear swarm at rest stays on its line under EPSO)
                let a = std::f64::consts::TAU * k as f64 / 6.0;
                target + Vec2::new(-80.0, -60.0) + Vec2::new(a.cos(), a.sin()) * 15.0
            })
            .collect();
        let mut v = [Vec2::zeros(); 6];
        let mut pb: Vec<Option<(Vec2, f64)>> = vec![None; 6];
        let mut sgb: Option<(Vec2, f64)> = None;
        let mut found = None;
        for t in 0..steps {
            for i in 0..6 {
                let f = fitness(&x[i]);
                update_best(&mut pb[i], x[i], f);
                update_best(&mut sgb, x[i], f);
            }
            for i in 0..6 {
                let s = State {
                    position: x[i],
                    velocity: v[i],
                    personal_best: pb[i].unwrap().0,
                    subgroup_best: sgb.unwrap().0,
                    target_estimate: t_est,
                };
                v[i] = desired_velocity(&s, variant, p, &mut rng);
                x[i] += v[i]; // no obstacles: V_i(t+1) = V_if(t+1)
                if found.is_none() && (x[i] - target).norm() < 5.0 {
                    found = Some(t);
                }
            }
        }
        (x.iter().map(|xi| (xi - target).norm()).collect(), found)
    }

    #[test]
    fn paper_parameters_satisfy_theorem1_for_all_r() {
        let p = Params::default();
        assert!((p.c0() - 0.95).abs() < 1e-12);
        for a in 0..=10 {
            for b in 0..=10 {
                for c in 0..=10 {
                    let r = [a as f64 / 10.0, b as f64 / 10.0, c as f64 / 10.0];
                    if r.iter().any(|&x| x > 0.0) {
                        assert!(p.theorem1_holds(r, Variant::Tpepso));
                    }
                }
            }
        }
        // ω > 1 gives C0 > 1: outside the region.
        let bad = Params {
            w: 3.0,
            ..Params::default()
        };
        assert!(!bad.theorem1_holds([0.5, 0.5, 0.5], Variant::Tpepso));
    }

    #[test]
    fn tpepso_converges_on_static_target() {
        for per_dimension_random in [false, true] {
            let p = Params {
                per_dimension_random,
                ..Params::default()
            };
            let (d, found) = run(&p, Variant::Tpepso, Some(Vec2::new(600.0, 600.0)), 400, 1);
            assert!(found.is_some_and(|t| t < 150), "found at {found:?}");
            for di in &d {
                assert!(*di < 1.0, "final distances {d:?}");
            }
        }
    }

    #[test]
    fn tpepso_always_converges_and_beats_epso_on_average() {
        // EPSO (c3 = 0) may stagnate around the best point found (premature
        // convergence of gbest PSO); a run that never gets within L_0 counts
        // as the full budget.
        let p = Params::default();
        let steps = 600;
        let (mut t_tp, mut t_ep) = (0usize, 0usize);
        for seed in 0..10 {
            let (d, a) = run(
                &p,
                Variant::Tpepso,
                Some(Vec2::new(600.0, 600.0)),
                steps,
                seed,
            );
            assert!(d.iter().all(|x| *x < 1.0), "seed {seed}: {d:?}");
            let (_, b) = run(
                &p,
                Variant::Epso,
                Some(Vec2::new(600.0, 600.0)),
                steps,
                seed,
            );
            t_tp += a.unwrap();
            t_ep += b.unwrap_or(steps);
        }
        eprintln!("steps to L_0 summed over 10 seeds: TPEPSO {t_tp}, EPSO {t_ep}");
        assert!(t_tp < t_ep, "TPEPSO {t_tp} vs EPSO {t_ep}");
    }

    #[test]
    fn outside_theorem1_region_it_does_not_converge() {
        // ω = 3 ⇒ C0 = 1.2 > 1: the swarm keeps moving at V_max.
        let p = Params {
            w: 3.0,
            ..Params::default()
        };
        let (d, _) = run(&p, Variant::Tpepso, Some(Vec2::new(600.0, 600.0)), 400, 1);
        assert!(d.iter().any(|x| *x > 5.0), "{d:?}");
    }

    #[test]
    fn speed_clamp_and_draw_count() {
        let p = Params::default();
        let s = State {
            position: Vec2::new(0.0, 0.0),
            velocity: Vec2::new(10.0, 0.0),
            personal_best: Vec2::new(1000.0, 0.0),
            subgroup_best: Vec2::new(1000.0, 1000.0),
            target_estimate: Some(Vec2::new(0.0, 1000.0)),
        };
        let mut a = ChaCha8Rng::seed_from_u64(5);
        let v = desired_velocity(&s, Variant::Tpepso, &p, &mut a);
        assert!((v.norm() - 10.0).abs() < 1e-9);
        // Both variants consume the same number of draws.
        let mut b = ChaCha8Rng::seed_from_u64(5);
        let _ = desired_velocity(&s, Variant::Epso, &p, &mut b);
        assert_eq!(a.gen::<u64>(), b.gen::<u64>());
    }

    #[test]
    fn eq11_by_hand() {
        // r drawn = (r1, r2, r3); check V_if against eq. (11) computed here.
        let p = Params::default();
        let s = State {
            position: Vec2::new(1.0, 2.0),
            velocity: Vec2::new(0.5, -0.5),
            personal_best: Vec2::new(3.0, 2.0),
            subgroup_best: Vec2::new(1.0, 6.0),
            target_estimate: Some(Vec2::new(-1.0, 2.0)),
        };
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mut copy = rng.clone();
        let (r1, r2, r3): (f64, f64, f64) = (copy.gen(), copy.gen(), copy.gen());
        let v = desired_velocity(&s, Variant::Tpepso, &p, &mut rng);
        let vip = s.velocity * 0.5
            + Vec2::new(2.0, 0.0) * (1.0 * r1)
            + Vec2::new(0.0, 4.0) * (1.2 * r2)
            + Vec2::new(-2.0, 0.0) * (1.2 * r3);
        let want = s.velocity + (vip - s.velocity) * 0.1;
        assert!((v - want).norm() < 1e-12);
    }

    #[test]
    fn best_tracking() {
        let mut b = None;
        assert!(update_best(&mut b, Vec2::new(0.0, 0.0), 1.0));
        assert!(!update_best(&mut b, Vec2::new(1.0, 0.0), 1.0));
        assert!(update_best(&mut b, Vec2::new(2.0, 0.0), 2.0));
        assert_eq!(b, Some((Vec2::new(2.0, 0.0), 2.0)));
    }
}
