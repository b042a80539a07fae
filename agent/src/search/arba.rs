//! ARBA, the adaptive robotic bat algorithm baseline (search layer "A", modes BA and SA;
//! spec/search.md 2.8 and 5 item 29).
//!
//! The paper cites ARBA (Tang et al., "A multirobot target searching method based on bat
//! algorithm in unknown environments", Expert Systems with Applications 2020, 141: 112945) and
//! says only that it is "an adaptive robot bat algorithm that considers obstacle avoidance and a
//! mechanism for escaping local optima". Its text is not available here, so this is the bat
//! algorithm (Yang 2010) mapped onto robots the way that paper describes it, with every
//! assumption a named parameter below marked [assumed]:
//!
//!   f_i   = f_min + (f_max − f_min) β,                 β ~ U(0, 1)           (frequency)
//!   V_i   = w_i V_i + f_i (X* − X_i)                                         (velocity)
//!   if rand > r_i:  V_i = (X* + ε A_i V_max u) − X_i,  u ~ U(−1, 1)²          (local walk)
//!   on improvement of the robot's own best, with probability A_i:
//!         A_i ← α_A A_i,   r_i ← r_0 (1 − exp(−γ t))                        (adaptation)
//!   w_i = w_min + (w_max − w_min) A_i / A_0                                  (adaptive inertia)
//!   no improvement for `stall_ticks`: a random heading for `escape_ticks`, A_i ← A_0
//!                                                                            (escape)
//!
//! X* is the best position the robot's subgroup knows (sgb, learnt over the radio as in
//! TPEPSO), the fitness the robot's own signal I_ij. Obstacle avoidance is the mode's obstacle
//! layer (BSOA or SVF) applied afterwards, as for every search layer (Table 3).

use crate::search::geometry::{clamp_norm, v2, Vec2};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// Tunables of the bat rule. None is given in the search paper.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// Lowest pulse frequency f_min. [assumed] 0 (Yang 2010).
    pub f_min: f64,
    /// Highest pulse frequency f_max: the pull towards X* per tick as a share of the distance.
    /// [assumed] 1, so that a robot can reach X* within a step or two, as eq. (11)'s c2 α does.
    pub f_max: f64,
    /// Initial loudness A_0. [assumed] 1 (Yang 2010).
    pub loudness_initial: f64,
    /// Loudness decay α_A per accepted improvement. [assumed] 0.9 (Yang 2010).
    pub loudness_decay: f64,
    /// Asymptotic pulse rate r_0. [assumed] 0.5 (Yang 2010).
    pub pulse_rate_initial: f64,
    /// Pulse-rate growth γ. [assumed] 0.9 (Yang 2010).
    pub pulse_rate_growth: f64,
    /// Inertia while loud (exploring). [assumed] 0.9.
    pub w_max: f64,
    /// Inertia once quiet (exploiting). [assumed] 0.4.
    pub w_min: f64,
    /// Local random walk radius around X*, in units of A_i V_max. [assumed] 1.
    pub local_walk: f64,
    /// Ticks without improving the robot's own best before it escapes. [assumed] 20.
    pub stall_ticks: u32,
    /// Ticks of the escape move (a random heading at V_max). [assumed] 5.
    pub escape_ticks: u32,
    /// Maximum speed V_max = 10 (Table 4).
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
    /// Ranges the rule needs; the message names the key.
    pub fn check(&self) -> Result<(), String> {
        let ok = self.f_min >= 0.0
            && self.f_max >= self.f_min
            && self.loudness_initial > 0.0
            && (0.0..=1.0).contains(&self.loudness_decay)
            && (0.0..=1.0).contains(&self.pulse_rate_initial)
            && self.pulse_rate_growth >= 0.0
            && self.w_min >= 0.0
            && self.w_max >= self.w_min
            && self.local_walk >= 0.0
            && self.v_max > 0.0;
        if ok {
            Ok(())
        } else {
            Err(
                "arba: need 0 <= f_min <= f_max, loudness_initial > 0, loudness_decay and \
                 pulse_rate_initial in [0, 1], pulse_rate_growth >= 0, 0 <= w_min <= w_max, \
                 local_walk >= 0, v_max > 0"
                    .into(),
            )
        }
    }
}

/// One robot's bat: its loudness, pulse rate and escape state (reset when it joins a subgroup).
#[derive(Clone, Debug, PartialEq)]
pub struct Bat {
    pub loudness: f64,
    pub pulse_rate: f64,
    /// Cooperative ticks so far (the t of the pulse-rate law).
    pub t: u32,
    best: f64,
    stall: u32,
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
            escape_dir: v2(0.0, 0.0),
        }
    }
}

/// The desired velocity of a cooperative robot at `position` moving with `velocity`, whose
/// subgroup's best known position is `best` and whose own measured fitness now is `fitness`.
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
    // Adaptation on improvement of the robot's own best.
    if fitness > bat.best {
        bat.best = fitness;
        bat.stall = 0;
        if rng.gen::<f64>() < bat.loudness {
            bat.loudness *= p.loudness_decay;
            bat.pulse_rate =
                p.pulse_rate_initial * (1.0 - (-p.pulse_rate_growth * bat.t as f64).exp());
        }
    } else {
        bat.stall += 1;
    }
    // Escape from a local optimum: a random heading for a few ticks, loud again afterwards.
    if bat.escape_left == 0 && p.stall_ticks > 0 && bat.stall >= p.stall_ticks {
        let a = rng.gen_range(-std::f64::consts::PI..std::f64::consts::PI);
        bat.escape_dir = v2(a.cos(), a.sin());
        bat.escape_left = p.escape_ticks;
        bat.stall = 0;
        bat.loudness = p.loudness_initial;
    }
    if bat.escape_left > 0 {
        bat.escape_left -= 1;
        return bat.escape_dir * p.v_max;
    }
    let beta: f64 = rng.gen();
    let f = p.f_min + (p.f_max - p.f_min) * beta;
    let w = p.w_min + (p.w_max - p.w_min) * (bat.loudness / p.loudness_initial).min(1.0);
    let mut v = velocity * w + (best - position) * f;
    if rng.gen::<f64>() > bat.pulse_rate {
        let r = p.local_walk * bat.loudness * p.v_max;
        let u = v2(rng.gen_range(-1.0..=1.0), rng.gen_range(-1.0..=1.0));
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
        let target = v2(300.0, 200.0);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut xs: Vec<Vec2> = (0..5).map(|i| v2(200.0 + 10.0 * i as f64, 120.0)).collect();
        let mut vs = [v2(0.0, 0.0); 5];
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
            let x = v2(k as f64, 0.0);
            desired_velocity(
                &mut bat,
                x,
                v2(0.0, 0.0),
                v2(100.0, 0.0),
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
        let x = v2(0.0, 0.0);
        let mut speeds = Vec::new();
        for _ in 0..=p.stall_ticks + 1 {
            let v = desired_velocity(&mut bat, x, v2(0.0, 0.0), x, 1.0, &p, &mut rng);
            speeds.push(v.norm());
        }
        // Tick 0 improves (from -inf); then stall_ticks ticks without improvement.
        assert!(
            (speeds[p.stall_ticks as usize] - p.v_max).abs() < 1e-9,
            "{speeds:?}"
        );
        assert_eq!(bat.loudness, p.loudness_initial);
    }
}
