//! Seeded random instances for the comparative sweeps of thesis 003 sec. 4.3 (Figs. 4.6, 4.7;
//! docs/hunting.md 8.3): n_r robots and n_e targets in the thesis's 10 km x 10 km square. The
//! thesis gives neither its generator nor its value ranges; [`InstanceParams`] takes each range
//! from the span of Tables 4.1-4.4 (stated per field), so a random instance looks like the
//! thesis's two examples.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use swarm::geometry::Vec2;

use super::model::{Resources, Robot, Task, RESOURCE_TYPES};
use super::params::CbcaParams;

/// The ranges a random instance is drawn from (uniformly; resources rounded to integers as in
/// the tables).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InstanceParams {
    /// Side of the square arena (km): 10, sec. 4.3.
    pub arena_km: f64,
    /// V_a: Tables 4.1 / 4.3 give 100-600.
    pub value: [f64; 2],
    /// E_j^p per type: the tables give 0-18; 5-15 keeps a target needing every type, as most
    /// of the tables' rows do.
    pub required: [f64; 2],
    /// beta_j: the tables give 0.45-0.71.
    pub beta: [f64; 2],
    /// L_j: 3 or 4, the tables' values (inclusive range).
    pub robots_needed: [usize; 2],
    /// gamma_i: the tables give 0.4-0.8.
    pub gamma: [f64; 2],
    /// E_i'^p per type: the tables give 1-18, mostly 2-10; 2-10.
    pub resources: [f64; 2],
}

impl Default for InstanceParams {
    fn default() -> Self {
        Self {
            arena_km: 10.0,
            value: [100.0, 600.0],
            required: [5.0, 15.0],
            beta: [0.45, 0.71],
            robots_needed: [3, 4],
            gamma: [0.4, 0.8],
            resources: [2.0, 10.0],
        }
    }
}

/// One instance: the targets (ids 0..n_e) and the robots (ids 0..n_r) at their start.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub tasks: Vec<Task>,
    pub robots: Vec<Robot>,
}

fn resources(rng: &mut ChaCha8Rng, range: [f64; 2]) -> Resources {
    let mut r = [0.0; RESOURCE_TYPES];
    for x in &mut r {
        *x = rng.gen_range(range[0]..=range[1]).round();
    }
    r
}

/// The instance of `seed`: targets first, then robots, from one ChaCha8 stream.
pub fn random_instance(
    n_r: usize,
    n_e: usize,
    seed: u64,
    ip: &InstanceParams,
    params: &CbcaParams,
) -> Instance {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let side = ip.arena_km;
    let tasks = (0..n_e)
        .map(|j| Task {
            id: j,
            position: [rng.gen_range(0.0..side), rng.gen_range(0.0..side)],
            value: rng.gen_range(ip.value[0]..=ip.value[1]),
            required: resources(&mut rng, ip.required),
            beta: rng.gen_range(ip.beta[0]..=ip.beta[1]),
            robots_needed: rng.gen_range(ip.robots_needed[0]..=ip.robots_needed[1]),
            hold_time: params.hold_time,
        })
        .collect();
    let robots = (0..n_r)
        .map(|i| Robot {
            id: i,
            position: Vec2::new(rng.gen_range(0.0..side), rng.gen_range(0.0..side)),
            gamma: rng.gen_range(ip.gamma[0]..=ip.gamma[1]),
            resources: resources(&mut rng, ip.resources),
            speed: params.robot_speed,
            max_tasks: params.max_tasks,
            mileage_budget: params.mileage_budget_km,
        })
        .collect();
    Instance { tasks, robots }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeded_within_ranges_and_distinct_per_seed() {
        let ip = InstanceParams::default();
        let p = CbcaParams::default();
        let a = random_instance(13, 30, 5, &ip, &p);
        assert_eq!(a, random_instance(13, 30, 5, &ip, &p));
        assert_ne!(a, random_instance(13, 30, 6, &ip, &p));
        assert_eq!((a.robots.len(), a.tasks.len()), (13, 30));
        for t in &a.tasks {
            assert!((100.0..=600.0).contains(&t.value));
            assert!((3..=4).contains(&t.robots_needed));
            assert!(t.required.iter().all(|&x| (5.0..=15.0).contains(&x)));
            assert!(t.position.iter().all(|&x| (0.0..10.0).contains(&x)));
        }
        for r in &a.robots {
            assert!((0.4..=0.8).contains(&r.gamma));
            assert!(r.resources.iter().all(|&x| (2.0..=10.0).contains(&x)));
        }
    }
}
