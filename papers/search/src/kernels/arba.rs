//! ARBA, the adaptive robotic bat algorithm baseline (search layer "A", modes BA and SA;
//! docs/search.md 2.11, 4.1 Table 3 and 5 item 29).
//!
//! The search paper cites ARBA (Tang H., Sun W., Yu H. et al., "A multirobot target searching
//! method based on bat algorithm in unknown environments", Expert Systems with Applications
//! 2020, 141: 112945) and says only that it is "an adaptive robot bat algorithm that considers
//! obstacle avoidance and a mechanism for escaping local optima". Neither that paper nor its
//! parameters are available here, so this is the bat algorithm (Yang 2010) mapped onto robots
//! the way the cited paper describes it in outline (each robot is a bat; the best is the best
//! position its group knows from the target signal; speeds limited to V_max; adaptive inertia;
//! obstacle avoidance; an escape from local optima). Per cooperative tick of robot i:
//!
//! ```text
//!   f_i = f_min + (f_max − f_min) β,   β ~ U(0, 1)                           (frequency)
//!   V_i = w_i V_i(t) + f_i (X* − X_i)                                        (velocity)
//!   if rand > r_i:  V_i = (X* + ε A_i V_max local_walk) − X_i,  ε ~ U(−1, 1)² (local walk)
//!   V_i = V_i clamped to ‖V_i‖ ≤ V_max                                        (V_max)
//!   on improvement of the robot's own best fitness, with probability A_i (rand < A_i):
//!         A_i ← α_A A_i,   r_i ← r_0 (1 − exp(−γ t))                         (adaptation)
//!   w_i = w_min + (w_max − w_min) A_i / A_0                                  (adaptive inertia)
//!   no improvement for `stall_ticks`: a random heading at V_max for `escape_ticks`, A_i ← A_0
//!                                                                            (escape)
//! ```
//!
//! Assumptions, each marked [assumed] (the values are the fields of [`Params`]):
//! 1. **Sign of the frequency term.** Yang writes v ← v + (x_i − x*) f_i; here robots are
//!    pulled towards X*, (X* − X_i), as in the robotic and most later bat variants (with Yang's
//!    sign and no candidate evaluation a robot would be pushed away from the best).
//! 2. **The best X\*** is the subgroup best sgb: the best personal best (pb, fitness = own
//!    measured I_ij of the subgroup's target) announced by the members heard over the radio,
//!    exactly the sgb of TPEPSO (the caller keeps it; the existing `Status` message carries pb).
//! 3. **No candidate evaluation.** A robot cannot test a candidate position without going there,
//!    so the bat's "new solution" is the position it moves to; it is "accepted" when the fitness
//!    measured there beats the robot's own best so far, and then, with probability A_i (Yang's
//!    rand < A_i), loudness and pulse rate adapt.
//! 4. **Own loudness** A_i scales the local walk, not the swarm's mean loudness ⟨A⟩ (which a
//!    robot does not know without extra radio fields).
//! 5. **t of the pulse-rate law** is the number of cooperative ticks since the bat was created
//!    (the robot joined the subgroup of a new target); r_i starts at r_0 (1 − e^0) = 0, so a
//!    fresh bat walks around X* until its first accepted improvement (with A_0 = 1 that is its
//!    first tick, whose measurement always beats the empty best: r_i = r_0 (1 − e^{−γ})).
//! 6. **Adaptive inertia** w_i falls from w_max to w_min with the loudness (loud = exploring,
//!    quiet = exploiting); ARBA's published adaptation rule is not available.
//! 7. **Escape from local optima:** `stall_ticks` ticks without improving the own best start
//!    `escape_ticks` ticks of flight at V_max in a random heading, after which the bat is loud
//!    again (A_i = A_0), so it explores before it settles.
//! 8. **Obstacle avoidance** is not a term of this rule: Table 3 pairs ARBA with the mode's
//!    obstacle layer (BSOA in BA, SVF in SA), applied to the returned velocity as for every
//!    search layer. Robot-robot separation inside a subgroup is the behaviour's
//!    `subgroup_separation`, also common to every search layer.
//! 9. Roaming, target choice (roulette), Type II attachment and the closed-loop adjustment are
//!    those of the other modes (Table 3 swaps only the search method); ARBA runs inside a
//!    subgroup where TPEPSO / EPSO would.
//!
//! Draws per call, from the caller's stream (a dedicated one in the behaviour): one for the
//! acceptance if the fitness improved, one heading when an escape starts, then (unless
//! escaping) β, the walk decision and, if walking, two for ε.

use rand::Rng;
use serde::{Deserialize, Serialize};
use swarm::geometry::{clamp_norm, Vec2};

/// Tunables of the bat rule. The search paper gives none of them and ARBA's own values are not
/// available here: every one is an assumption (the scenario file lists them under
/// `[search.kernels.arba]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Lowest pulse frequency f_min. [assumed] 0, Yang 2010's f_min.
    pub f_min: f64,
    /// Highest pulse frequency f_max: the pull towards X* per tick as a share of the distance.
    /// [assumed] 1 (Yang 2010 uses f ∈ [0, 1] or [0, 2]); with 1 the mean pull 0.5 (X* − X_i)
    /// lets a robot reach X* in a few ticks, like eq. (11)'s social term.
    pub f_max: f64,
    /// Initial loudness A_0 (also the loudness after an escape). [assumed] 1, Yang 2010's A_0
    /// range [1, 2] at its lower end, so that A_i is a probability (acceptance rand < A_i).
    pub loudness_initial: f64,
    /// Loudness factor α (A_i ← α A_i on each accepted improvement). [assumed] 0.9, Yang 2010.
    pub loudness_decay: f64,
    /// Pulse rate r_0 (r_i ← r_0 (1 − exp(−γ t)) on each accepted improvement): the limit of the
    /// probability of flying by frequency instead of walking around X*. [assumed] 0.5, the
    /// r_0 of Yang's demo code.
    pub pulse_rate_initial: f64,
    /// Pulse-rate growth γ of r_i = r_0 (1 − exp(−γ t)). [assumed] 0.9, Yang 2010.
    pub pulse_rate_growth: f64,
    /// Inertia w_i while the bat is loud (A_i = A_0: exploring). [assumed] 0.9, the usual upper
    /// inertia of linearly adapted PSO weights (the adaptive inertia of the robotic PSO line of
    /// work ARBA follows; its exact rule is not available).
    pub w_max: f64,
    /// Inertia w_i as the loudness goes to 0 (exploiting). [assumed] 0.4, the usual lower PSO
    /// inertia; w_i = w_min + (w_max − w_min) A_i / A_0.
    pub w_min: f64,
    /// Half-width of the local random walk box around X*, in units of A_i V_max (Yang's
    /// x_new = x* + ε ⟨A⟩ with ε ∈ [−1, 1], scaled to the robot's reach per tick).
    /// [assumed] 1: a fresh bat aims within ±V_max of X* per coordinate.
    pub local_walk: f64,
    /// Ticks without improving the robot's own best fitness before it escapes (the local-optimum
    /// test); 0 turns the escape off. [assumed] 20 = 2 L_T / V_max, the ticks to cross the signal disc of a target.
    pub stall_ticks: u32,
    /// Ticks of the escape flight (a random heading at V_max, about escape_ticks V_max = 50
    /// units away, half of L_T). [assumed] 5.
    pub escape_ticks: u32,
    /// Maximum speed V_max = 10 (Table 4); must equal robot.v_max.
    pub v_max: f64,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            f_min: 0.0,
            f_max: 1.0,
            loudness_initial: 1.0,
            loudness_decay: 0.9,
            pulse_rate_initial: 0.5,
            pulse_rate_growth: 0.9,
            w_max: 0.9,
            w_min: 0.4,
            local_walk: 1.0,
            stall_ticks: 20,
            escape_ticks: 5,
            v_max: 10.0,
        }
    }
}

impl Params {
    /// Ranges the rule needs; the message names the first key out of range.
    pub fn check(&self) -> Result<(), String> {
        let checks: [(&str, bool, &str); 8] = [
            ("f_min", self.f_min >= 0.0, ">= 0"),
            ("f_max", self.f_max >= self.f_min, ">= f_min"),
            ("loudness_initial", self.loudness_initial > 0.0, "> 0"),
            (
                "loudness_decay",
                (0.0..=1.0).contains(&self.loudness_decay),
                "in [0, 1]",
            ),
            (
                "pulse_rate_initial",
                (0.0..=1.0).contains(&self.pulse_rate_initial),
                "in [0, 1]",
            ),
            ("pulse_rate_growth", self.pulse_rate_growth >= 0.0, ">= 0"),
            (
                "w_min, w_max",
                self.w_min >= 0.0 && self.w_max >= self.w_min,
                "0 <= w_min <= w_max",
            ),
            (
                "local_walk, v_max",
                self.local_walk >= 0.0 && self.v_max > 0.0,
                "local_walk >= 0 and v_max > 0",
            ),
        ];
        match checks.iter().find(|(_, ok, _)| !ok) {
            None => Ok(()),
            Some((key, _, need)) => Err(format!("arba.{key}: need {need}")),
        }
    }

    /// The pulse-rate law r(t) = r_0 (1 − exp(−γ t)).
    pub fn pulse_rate_at(&self, t: u32) -> f64 {
        self.pulse_rate_initial * (1.0 - (-self.pulse_rate_growth * t as f64).exp())
    }
}

/// One robot's bat: its loudness, pulse rate and escape state. The behaviour makes a fresh one
/// whenever the robot starts a fresh subgroup memory (a new target).
#[derive(Clone, Debug, PartialEq)]
pub struct Bat {
    /// A_i: the acceptance probability of an improvement and the local walk's scale.
    pub loudness: f64,
    /// r_i: the probability of flying by frequency rather than walking around X*.
    pub pulse_rate: f64,
    /// Cooperative ticks so far (the t of the pulse-rate law).
    pub t: u32,
    /// The robot's own best fitness so far (the acceptance test).
    best: f64,
    /// Ticks since the own best last improved (the local-optimum test).
    stall: u32,
    /// Ticks of escape flight left, and its heading.
    escape_left: u32,
    escape_dir: Vec2,
}

impl Bat {
    pub fn new(p: &Params) -> Bat {
        Bat {
            loudness: p.loudness_initial,
            // r_0 (1 − e^{−γ·0}) = 0: a fresh bat walks locally around X* at first.
            pulse_rate: 0.0,
            t: 0,
            best: f64::NEG_INFINITY,
            stall: 0,
            escape_left: 0,
            escape_dir: Vec2::new(0.0, 0.0),
        }
    }
}

/// The desired velocity V_if of a cooperative robot at `position` moving with `velocity`, whose
/// subgroup's best known position is `best` (X* = sgb, learnt over the radio) and whose own
/// measured fitness now is `fitness` (I_ij; larger is better). ‖V_if‖ ≤ V_max. The obstacle
/// layer is applied by the caller.
pub fn desired_velocity(
    bat: &mut Bat,
    position: Vec2,
    velocity: Vec2,
    best: Vec2,
    fitness: f64,
    p: &Params,
    rng: &mut impl Rng,
) -> Vec2 {
    bat.t += 1;
    // Acceptance (assumption 3): the fitness measured where the last move led beats the own
    // best; then, with probability A_i, the bat grows quieter and pulses more often.
    if fitness > bat.best {
        bat.best = fitness;
        bat.stall = 0;
        if rng.gen::<f64>() < bat.loudness {
            bat.loudness *= p.loudness_decay;
            bat.pulse_rate = p.pulse_rate_at(bat.t);
        }
    } else {
        bat.stall += 1;
    }
    // Escape from a local optimum: a random heading for a few ticks, loud again afterwards.
    if bat.escape_left == 0 && p.stall_ticks > 0 && bat.stall >= p.stall_ticks {
        let a = rng.gen_range(-std::f64::consts::PI..std::f64::consts::PI);
        bat.escape_dir = Vec2::new(a.cos(), a.sin());
        bat.escape_left = p.escape_ticks;
        bat.stall = 0;
        bat.loudness = p.loudness_initial;
    }
    if bat.escape_left > 0 {
        bat.escape_left -= 1;
        return bat.escape_dir * p.v_max;
    }
    // Frequency, inertia from loudness (assumption 6) and the pull towards X* (assumption 1).
    let beta: f64 = rng.gen();
    let f = p.f_min + (p.f_max - p.f_min) * beta;
    let w = p.w_min + (p.w_max - p.w_min) * (bat.loudness / p.loudness_initial).min(1.0);
    let mut v = velocity * w + (best - position) * f;
    // Local random walk around X* (assumption 4) when rand > r_i.
    if rng.gen::<f64>() > bat.pulse_rate {
        let r = p.local_walk * bat.loudness * p.v_max;
        let u = Vec2::new(rng.gen_range(-1.0..=1.0), rng.gen_range(-1.0..=1.0));
        v = best + u * r - position;
    }
    clamp_norm(v, p.v_max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Signal-like fitness of a static target at `t` (higher nearer).
    fn fitness(x: Vec2, t: Vec2) -> f64 {
        -(x - t).norm()
    }

    /// A small swarm of bats sharing their best (as sgb over the radio) closes on a static
    /// target in an empty field.
    fn run(seed: u64, ticks: usize) -> (Vec<Vec2>, Vec2) {
        let p = Params::default();
        let target = Vec2::new(300.0, 200.0);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut xs: Vec<Vec2> = (0..5)
            .map(|i| Vec2::new(200.0 + 10.0 * i as f64, 120.0))
            .collect();
        let mut vs = [Vec2::new(0.0, 0.0); 5];
        let mut bats: Vec<Bat> = (0..5).map(|_| Bat::new(&p)).collect();
        let mut best = xs[0];
        for _ in 0..ticks {
            for x in &xs {
                if fitness(*x, target) > fitness(best, target) {
                    best = *x;
                }
            }
            for i in 0..5 {
                let v = desired_velocity(
                    &mut bats[i],
                    xs[i],
                    vs[i],
                    best,
                    fitness(xs[i], target),
                    &p,
                    &mut rng,
                );
                assert!(v.norm() <= p.v_max + 1e-9, "V_max respected");
                vs[i] = v;
                xs[i] += v;
            }
        }
        (xs, target)
    }

    #[test]
    fn bats_sharing_their_best_converge_on_a_static_target() {
        let (xs, target) = run(1, 300);
        let nearest = xs
            .iter()
            .map(|x| (x - target).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 5.0, "nearest bat {nearest} from the target");
    }

    #[test]
    fn deterministic_for_a_seed() {
        assert_eq!(run(7, 50), run(7, 50));
        assert_ne!(run(7, 50).0, run(8, 50).0);
    }

    #[test]
    fn loudness_falls_and_pulse_rate_rises_with_improvement() {
        let p = Params::default();
        let mut bat = Bat::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for k in 0..30 {
            let x = Vec2::new(k as f64, 0.0);
            desired_velocity(
                &mut bat,
                x,
                Vec2::new(0.0, 0.0),
                Vec2::new(100.0, 0.0),
                k as f64,
                &p,
                &mut rng,
            );
        }
        assert!(bat.loudness < p.loudness_initial * 0.5, "{}", bat.loudness);
        assert!(bat.pulse_rate > 0.4 && bat.pulse_rate <= p.pulse_rate_initial);
    }

    #[test]
    fn a_stalled_bat_escapes_at_full_speed_and_is_loud_again() {
        let p = Params::default();
        let mut bat = Bat::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let x = Vec2::new(0.0, 0.0);
        let mut speeds = Vec::new();
        for _ in 0..=p.stall_ticks + 1 {
            let v = desired_velocity(&mut bat, x, Vec2::new(0.0, 0.0), x, 1.0, &p, &mut rng);
            speeds.push(v.norm());
        }
        // Tick 0 improves (from -inf); then stall_ticks ticks without improvement.
        assert!(
            (speeds[p.stall_ticks as usize] - p.v_max).abs() < 1e-9,
            "{speeds:?}"
        );
        assert_eq!(bat.loudness, p.loudness_initial);
    }

    /// Ticks until one of a subgroup of g_max = 6 bats comes within L_0 = 5 of a static target
    /// in an empty field, from starts 70-95 away (inside L_T), with the noisy eq. (33) signal as
    /// fitness, pb per bat and sgb = the best pb (what the radio gives the behaviour).
    fn ticks_to_l0(seed: u64, p: &Params) -> Option<usize> {
        use crate::kernels::calibration::{self, measure_signal};
        let sig = calibration::Params::default();
        let target = Vec2::new(500.0, 500.0);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut noise = ChaCha8Rng::seed_from_u64(seed + 1000);
        let mut xs: Vec<Vec2> = (0..6)
            .map(|_| {
                let a: f64 = rng.gen_range(-0.6..0.6);
                let d: f64 = rng.gen_range(70.0..95.0);
                target + Vec2::new(a.cos(), a.sin()) * d
            })
            .collect();
        let mut vs = [Vec2::new(0.0, 0.0); 6];
        let mut bats: Vec<Bat> = (0..6).map(|_| Bat::new(p)).collect();
        let mut pbs: Vec<(Vec2, f64)> = vec![(Vec2::new(0.0, 0.0), f64::NEG_INFINITY); 6];
        for tick in 0..400 {
            if xs.iter().any(|x| (x - target).norm() < 5.0) {
                return Some(tick);
            }
            let fit: Vec<f64> = xs
                .iter()
                .map(|x| measure_signal((x - target).norm(), &sig, &mut noise))
                .collect();
            for i in 0..6 {
                if fit[i] > pbs[i].1 {
                    pbs[i] = (xs[i], fit[i]);
                }
            }
            let sgb = pbs
                .iter()
                .fold(pbs[0], |b, q| if q.1 > b.1 { *q } else { b });
            for i in 0..6 {
                let v = desired_velocity(&mut bats[i], xs[i], vs[i], sgb.0, fit[i], p, &mut rng);
                assert!(v.norm() <= p.v_max + 1e-9);
                vs[i] = v;
                xs[i] += v;
            }
        }
        None
    }

    #[test]
    fn a_subgroup_on_the_noisy_signal_reaches_l0_for_every_seed() {
        let p = Params::default();
        let ticks: Vec<Option<usize>> = (0..10).map(|s| ticks_to_l0(s, &p)).collect();
        eprintln!("ARBA ticks to L_0 over 10 seeds: {ticks:?}");
        assert!(
            ticks.iter().all(|t| t.is_some_and(|t| t < 150)),
            "{ticks:?}"
        );
    }

    #[test]
    fn adaptation_follows_the_bat_laws() {
        // Every change of A_i is one factor α, made only on an improvement, and sets r_i to
        // r_0 (1 − e^{−γ t}) at that tick; without improvement nothing changes (no escape here).
        let p = Params {
            stall_ticks: 0,
            ..Params::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut bat = Bat::new(&p);
        assert_eq!((bat.loudness, bat.pulse_rate), (p.loudness_initial, 0.0));
        let mut accepted = 0;
        for k in 0..200u32 {
            // Improves on even ticks only.
            let fitness = (k / 2) as f64 + if k % 2 == 0 { 0.5 } else { 0.0 };
            let (a, r) = (bat.loudness, bat.pulse_rate);
            desired_velocity(
                &mut bat,
                Vec2::new(0.0, 0.0),
                Vec2::new(0.0, 0.0),
                Vec2::new(50.0, 0.0),
                fitness,
                &p,
                &mut rng,
            );
            assert_eq!(bat.t, k + 1);
            if bat.loudness != a {
                assert!(k % 2 == 0, "adapted without an improvement at tick {k}");
                assert!((bat.loudness - a * p.loudness_decay).abs() < 1e-15);
                assert!((bat.pulse_rate - p.pulse_rate_at(bat.t)).abs() < 1e-15);
                accepted += 1;
            } else {
                assert_eq!(bat.pulse_rate, r, "r_i changed without A_i at tick {k}");
            }
        }
        // Acceptance with probability A_i: frequent while loud, rarer as A_i falls.
        assert!(accepted >= 10, "{accepted}");
        assert!(accepted < 100, "{accepted}");
        assert!((bat.loudness - p.loudness_decay.powi(accepted)).abs() < 1e-12);
        assert!(bat.pulse_rate > 0.49 && bat.pulse_rate <= p.pulse_rate_initial);
        assert!((p.pulse_rate_at(1) - 0.5 * (1.0 - (-0.9f64).exp())).abs() < 1e-15);
    }

    #[test]
    fn the_speed_never_exceeds_v_max() {
        let p = Params::default();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut bat = Bat::new(&p);
        for k in 0..2000 {
            let x = Vec2::new(rng.gen_range(-1e3..1e3), rng.gen_range(-1e3..1e3));
            let v = Vec2::new(rng.gen_range(-1e2..1e2), rng.gen_range(-1e2..1e2));
            let best = Vec2::new(rng.gen_range(-1e3..1e3), rng.gen_range(-1e3..1e3));
            let out = desired_velocity(&mut bat, x, v, best, (k % 7) as f64, &p, &mut rng);
            assert!(out.norm() <= p.v_max + 1e-9, "{out:?}");
        }
    }

    #[test]
    fn a_fresh_bat_walks_inside_the_loudness_box_around_the_best() {
        // r_i = 0 before any accepted improvement: every move aims at X* + ε A_i V_max
        // local_walk, whatever the inertia.
        let p = Params {
            local_walk: 0.2,
            ..Params::default()
        };
        let best = Vec2::new(100.0, 100.0);
        let x = Vec2::new(103.0, 100.0);
        for seed in 0..50 {
            let mut bat = Bat::new(&p);
            bat.best = 10.0; // no improvement: A_i and r_i stay as they are
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let v = desired_velocity(&mut bat, x, Vec2::new(9.0, 9.0), best, 1.0, &p, &mut rng);
            let aim = x + v - best;
            let half = p.local_walk * p.loudness_initial * p.v_max;
            assert!(
                aim.x.abs() <= half + 1e-9 && aim.y.abs() <= half + 1e-9,
                "{aim:?}"
            );
        }
    }

    #[test]
    fn check_names_the_key_out_of_range() {
        assert_eq!(Params::default().check(), Ok(()));
        let bad = Params {
            pulse_rate_initial: 1.5,
            ..Params::default()
        };
        assert!(bad.check().unwrap_err().contains("arba.pulse_rate_initial"));
        let bad = Params {
            w_min: 0.95,
            ..Params::default()
        };
        assert!(bad.check().unwrap_err().contains("w_max"));
    }
}
