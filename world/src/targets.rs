//! Targets of the search scenario (spec/search.md 1.1-1.4): placement, the signal of eq. (33)
//! each robot measures, and "found" (a robot closer than L_0; the target then stops emitting).

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use swarm::frames::{Sense, Signal, MAX_SIGNALS, SIGNAL_FOUND_BY_YOU};
use swarm::geometry::{point_in_polygon, polygon_distance, Vec2};
use swarm::radio::distance;
use swarm::scenario::Scenario;

pub struct Targets {
    pub pos: Vec<[f64; 2]>,
    /// Tick at which each target was found, and by whom.
    pub found: Vec<Option<(u64, u32)>>,
    /// Signal noise: one N(0, sigma^2) draw per (tick, robot, target in range), in that order.
    noise: ChaCha8Rng,
    /// Robot -> target it found at the last apply (reported once in its next Sense).
    just_found: Vec<(u32, u32)>,
}

/// Standard normal draw (Box-Muller), from the seeded stream only.
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
    let u2: f64 = rng.gen();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

impl Targets {
    pub fn new(sc: &Scenario) -> Result<Targets, String> {
        let mut rng = swarm::behaviour::robot_rng(sc.run.seed, u32::MAX, 3);
        let [x0, y0, x1, y1] = sc.search.target_region;
        let mut pos = Vec::new();
        for t in 0..sc.search.targets {
            let mut ok = false;
            for _ in 0..100_000 {
                let p = Vec2::new(rng.gen_range(x0..x1), rng.gen_range(y0..y1));
                let clear = sc.arena.obstacles.iter().all(|o| {
                    !point_in_polygon(p, &o.points)
                        && polygon_distance(p, &o.points) >= sc.search.target_clearance
                });
                if clear {
                    pos.push([p.x, p.y]);
                    ok = true;
                    break;
                }
            }
            if !ok {
                return Err(format!(
                    "search.target_region: no free position for target {t}"
                ));
            }
        }
        Ok(Targets {
            found: vec![None; pos.len()],
            pos,
            noise: swarm::behaviour::robot_rng(sc.run.seed, u32::MAX, 4),
            just_found: Vec::new(),
        })
    }

    pub fn found_count(&self) -> u32 {
        self.found.iter().filter(|f| f.is_some()).count() as u32
    }

    pub fn all_found(&self) -> bool {
        !self.pos.is_empty() && self.found.iter().all(|f| f.is_some())
    }

    /// Eq. (33): I = m Q / d^2 + eta for d <= L_T, else 0. Writes the robot's signal list
    /// (strongest first is left to the behaviour; listed in target order).
    pub fn sense(&mut self, sc: &Scenario, robot: u32, p: [f64; 2], out: &mut Sense) {
        let mut n = 0;
        for &(r, t) in &self.just_found {
            if r == robot && n < MAX_SIGNALS {
                out.signals[n] = Signal {
                    target: t,
                    flags: SIGNAL_FOUND_BY_YOU,
                    intensity: 0.0,
                };
                n += 1;
            }
        }
        let s = &sc.search;
        for (t, q) in self.pos.iter().enumerate() {
            if self.found[t].is_some() {
                continue;
            }
            let d = distance(p, *q);
            if d > s.l_t || n >= MAX_SIGNALS {
                continue;
            }
            let clean = s.signal_m * s.signal_q / (d * d).max(1e-9);
            let intensity = clean + s.noise_sigma * normal(&mut self.noise);
            out.signals[n] = Signal {
                target: t as u32,
                flags: 0,
                intensity,
            };
            n += 1;
        }
        out.n_signals = n as u32;
    }

    /// After the moves of tick k: targets with a robot closer than L_0 are found (lowest robot
    /// id first when several arrive together). Returns (target, robot) pairs found now.
    pub fn update(
        &mut self,
        sc: &Scenario,
        tick: u64,
        poses: &[[f64; 3]],
        alive: &[bool],
    ) -> Vec<(u32, u32)> {
        self.just_found.clear();
        for t in 0..self.pos.len() {
            if self.found[t].is_some() {
                continue;
            }
            let finder = poses
                .iter()
                .enumerate()
                .filter(|(i, _)| alive[*i])
                .find(|(_, p)| distance([p[0], p[1]], self.pos[t]) < sc.search.found_distance)
                .map(|(i, _)| i as u32);
            if let Some(r) = finder {
                self.found[t] = Some((tick, r));
                self.just_found.push((r, t as u32));
            }
        }
        self.just_found.clone()
    }
}
