//! Random hunting instances for the chapter 3 sweeps (Figs. 3.7-3.10: n_e = 12 with n_r = 20..30,
//! n_r = 30 with n_e = 10..25) and the bench. The thesis only says "random initial conditions"
//! (spec 7.2 [MISSING]); every range below is [chosen] to span Tables 3.1-3.2.

use crate::hunt::model::{Resources, Robot, Task, N_RESOURCES};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

/// Ranges of a random instance.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InstanceParams {
    /// Square arena side, km (the thesis's 10 km).
    pub arena: f64,
    /// L_j uniform in this inclusive range (Table 3.1: 3-5).
    pub required_robots: [usize; 2],
    /// z_jmax uniform in this range (Table 3.1: 520-1350).
    pub reward_cap: [f64; 2],
    /// E_j^p uniform integer in this inclusive range (Table 3.1: 5-18).
    pub task_resources: [u32; 2],
    /// E_i'^p uniform integer in this inclusive range (Table 3.2: 1-18).
    pub robot_resources: [u32; 2],
    /// v_j = base + step (L_j - 3): faster targets need more robots (sec. 3.3), km/min.
    pub task_speed_base: f64,
    pub task_speed_step: f64,
    /// v_i uniform in this range, km/min (below every target's speed, sec. 2.1.3).
    pub robot_speed: [f64; 2],
    /// w_max of every robot, rad/min.
    pub turn_rate: f64,
}

impl Default for InstanceParams {
    fn default() -> Self {
        Self {
            arena: 10.0,
            required_robots: [3, 5],
            reward_cap: [500.0, 1400.0],
            task_resources: [5, 18],
            robot_resources: [1, 18],
            task_speed_base: 1.0,
            task_speed_step: 0.1,
            robot_speed: [0.65, 0.9],
            turn_rate: 6.0,
        }
    }
}

fn resources(rng: &mut ChaCha8Rng, r: [u32; 2]) -> Resources {
    let mut out = [0.0; N_RESOURCES];
    for x in &mut out {
        *x = rng.gen_range(r[0]..=r[1]) as f64;
    }
    out
}

/// `n_e` tasks and `n_r` robots, uniform in the arena, from the seeded stream `seed`. Each
/// robot's matching coefficients are uniform then normalised to sum 1 (sec. 3.1.2).
pub fn random_instance(
    n_e: usize,
    n_r: usize,
    seed: u64,
    p: &InstanceParams,
) -> (Vec<Task>, Vec<Robot>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let tasks = (1..=n_e as u32)
        .map(|id| {
            let l = rng.gen_range(p.required_robots[0]..=p.required_robots[1]);
            Task {
                id,
                position: Vec2::new(rng.gen_range(0.0..p.arena), rng.gen_range(0.0..p.arena)),
                resources: resources(&mut rng, p.task_resources),
                required_robots: l,
                reward_cap: rng.gen_range(p.reward_cap[0]..p.reward_cap[1]).round(),
                speed: p.task_speed_base + p.task_speed_step * (l as f64 - 3.0),
                min_robot_speed: 0.0,
            }
        })
        .collect();
    let robots = (1..=n_r as u32)
        .map(|id| {
            let raw: Vec<f64> = (0..n_e).map(|_| rng.gen_range(0.0..1.0)).collect();
            let sum: f64 = raw.iter().sum::<f64>().max(1e-12);
            Robot {
                id,
                position: Vec2::new(rng.gen_range(0.0..p.arena), rng.gen_range(0.0..p.arena)),
                heading: rng.gen_range(-std::f64::consts::PI..std::f64::consts::PI),
                resources: resources(&mut rng, p.robot_resources),
                matching: raw.iter().map(|g| g / sum).collect(),
                speed: rng.gen_range(p.robot_speed[0]..p.robot_speed[1]),
                turn_rate: p.turn_rate,
                max_mileage: f64::INFINITY,
                travelled: 0.0,
            }
        })
        .collect();
    (tasks, robots)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hunt::auction::run_auction;
    use crate::hunt::parallel_auction::run_parallel_auction;
    use crate::hunt::HuntParams;

    #[test]
    fn seeded_and_in_range() {
        let p = InstanceParams::default();
        let (t, r) = random_instance(12, 30, 7, &p);
        assert_eq!(random_instance(12, 30, 7, &p), (t.clone(), r.clone()));
        assert_ne!(random_instance(12, 30, 8, &p).0, t);
        assert!(t
            .iter()
            .all(|t| (3..=5).contains(&t.required_robots) && t.position.x < 10.0));
        for robot in &r {
            assert!((robot.matching.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            assert!(t.iter().all(|t| robot.speed < t.speed));
        }
    }

    #[test]
    fn both_auctions_give_valid_disjoint_coalitions_on_random_instances() {
        let hp = HuntParams::default();
        for seed in 0..10 {
            let (tasks, robots) = random_instance(12, 30, seed, &InstanceParams::default());
            let out = run_auction(&tasks, &robots, &hp);
            let mut seen = std::collections::BTreeSet::new();
            for c in out.coalitions.values() {
                let t = tasks.iter().find(|t| t.id == c.award.task).unwrap();
                assert_eq!(c.award.members.len(), t.required_robots);
                assert!(c.award.reward < t.reward_cap);
                for i in &c.award.members {
                    assert!(seen.insert(*i), "seed {seed}: R{i} twice");
                }
            }
            let par = run_parallel_auction(&tasks, &robots, &hp);
            for c in par.coalitions.values() {
                let t = tasks.iter().find(|t| t.id == c.award.task).unwrap();
                assert_eq!(c.award.members.len(), t.required_robots);
                assert_eq!(
                    c.award.reward,
                    hp.parallel_reward_fraction * t.reward_cap,
                    "fixed reward"
                );
            }
        }
    }
}
