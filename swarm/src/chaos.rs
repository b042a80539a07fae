//! The run's SIGKILL schedule: the scenario's explicit `faults.kill_at`, the random kills of
//! `faults.chaos_rate`, and the `faults.kill_fraction` of the robots killed once each, all drawn
//! from the run's seed. The world and the orchestrator both compute it
//! with this function, so the world treats each robot as dead from exactly its tick.

use crate::scenario::{FaultPolicy, Scenario};
use rand::Rng;

/// Sorted (tick, robot) pairs, no duplicates.
pub fn schedule(sc: &Scenario) -> Vec<[u64; 2]> {
    let mut out: Vec<[u64; 2]> = sc.faults.kill_at.clone();
    let p = sc.faults.chaos_rate / 100.0;
    if p > 0.0 {
        // Stations (bodiless agents, `run.stations`) are never killed at random.
        let n = sc.bodies() as u64;
        let mut rng =
            crate::streams::rng(sc.run.seed, crate::streams::WORLD, crate::streams::CHAOS);
        let drop = sc.faults.on_fault == FaultPolicy::Drop;
        let mut killed: Vec<bool> = vec![false; n as usize];
        for &[_, r] in &out {
            killed[r as usize] = true;
        }
        let mut tick = 0u64;
        loop {
            // Geometric gap to the next kill: each tick kills with probability p.
            let u: f64 = rng.gen_range(f64::MIN_POSITIVE..1.0);
            let gap = if p >= 1.0 {
                1
            } else {
                (u.ln() / (1.0 - p).ln()).floor() as u64 + 1
            };
            tick = tick.saturating_add(gap);
            if tick >= sc.run.max_ticks {
                break;
            }
            let candidates: Vec<u64> = (0..n).filter(|&r| !(drop && killed[r as usize])).collect();
            if candidates.is_empty() {
                break;
            }
            let r = candidates[rng.gen_range(0..candidates.len())];
            killed[r as usize] = true;
            out.push([tick, r]);
        }
    }
    let k = (sc.faults.kill_fraction * sc.bodies() as f64).round() as usize;
    if k > 0 {
        // Distinct robots, each at a uniform tick of the window (its own stream: adding a
        // fraction does not move the chaos_rate kills).
        let mut rng = crate::streams::rng(
            sc.run.seed,
            crate::streams::WORLD,
            crate::streams::KILL_FRACTION,
        );
        let [t0, t1] = sc.faults.kill_window;
        let mut robots: Vec<u64> = (0..sc.bodies() as u64).collect();
        for j in 0..k.min(robots.len()) {
            let pick = rng.gen_range(j..robots.len());
            robots.swap(j, pick);
            out.push([rng.gen_range(t0..=t1.max(t0)), robots[j]]);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_gives_about_the_expected_number_of_kills_reproducibly() {
        let mut sc = Scenario::default();
        sc.run.robots = 1000;
        sc.run.max_ticks = 20_000;
        sc.faults.chaos_rate = 0.5; // 0.5 per 100 ticks -> ~100 kills
        let a = schedule(&sc);
        assert_eq!(a, schedule(&sc));
        assert!((80..=120).contains(&a.len()), "{}", a.len());
        // Under drop no robot is killed twice.
        let mut robots: Vec<u64> = a.iter().map(|k| k[1]).collect();
        robots.sort_unstable();
        robots.dedup();
        assert_eq!(robots.len(), a.len());
        sc.run.seed = 2;
        assert_ne!(a, schedule(&sc));
    }

    #[test]
    fn a_fraction_kills_that_many_distinct_robots_within_the_window() {
        let mut sc = Scenario::default();
        sc.run.robots = 20;
        sc.faults.kill_fraction = 0.2;
        sc.faults.kill_window = [20, 200];
        let a = schedule(&sc);
        assert_eq!(a.len(), 4, "{a:?}");
        let mut robots: Vec<u64> = a.iter().map(|k| k[1]).collect();
        robots.sort_unstable();
        robots.dedup();
        assert_eq!(robots.len(), 4);
        assert!(a.iter().all(|k| (20..=200).contains(&k[0]) && k[1] < 20));
        assert_eq!(a, schedule(&sc));
        sc.run.seed = 9;
        assert_ne!(a, schedule(&sc));
    }

    #[test]
    fn explicit_kills_are_kept_and_sorted() {
        let mut sc = Scenario::default();
        sc.faults.kill_at = vec![[300, 12], [120, 7]];
        assert_eq!(schedule(&sc), vec![[120, 7], [300, 12]]);
    }
}
