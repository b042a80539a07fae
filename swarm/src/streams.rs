//! Every seeded random stream of a run, by name.
//!
//! A stream is a ChaCha8 generator keyed by (run seed, owner, stream number): the owner is a
//! robot id, or [`WORLD`] for the world's and the orchestrator's own draws. Each purpose has its
//! own number, so adding draws to one never shifts another. The numbers are part of what makes
//! a recording reproducible: never renumber one.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The owner id of streams that belong to no robot (world, orchestrator).
pub const WORLD: u32 = u32::MAX;

/// World: start positions of the robots.
pub const PLACEMENT: u64 = 1;
/// Roam behaviour: each robot's initial heading.
pub const ROAM_HEADING: u64 = 2;
/// Search mission: target positions.
pub const TARGET_PLACEMENT: u64 = 3;
/// Search mission: signal noise, one draw per (tick, robot, target in range).
pub const SIGNAL_NOISE: u64 = 4;
/// Orchestrator: the `faults.chaos_rate` kill schedule.
pub const CHAOS: u64 = 7;
/// Orchestrator: the `faults.kill_fraction` kills.
pub const KILL_FRACTION: u64 = 8;
/// Search behaviour: initial heading.
pub const SEARCH_HEADING: u64 = 20;
/// Search behaviour: the offline calibration's measurements (paper 3.2).
pub const SEARCH_CALIBRATION: u64 = 21;
/// Search behaviour: the roulette of eqs. (2)-(3).
pub const SEARCH_ROULETTE: u64 = 22;
/// Search behaviour: PSO draws (r1, r2, r3 of eq. 11).
pub const SEARCH_PSO: u64 = 23;
/// Search behaviour: ARBA's bat draws.
pub const SEARCH_BAT: u64 = 24;

/// The seeded stream `stream` of `owner` in the run with seed `seed`.
pub fn rng(seed: u64, owner: u32, stream: u64) -> ChaCha8Rng {
    let mut r =
        ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15u64.wrapping_mul(owner as u64 + 1));
    r.set_stream(stream);
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_distinct_and_reproducible() {
        use rand::Rng;
        let a: u64 = rng(1, 0, PLACEMENT).gen();
        assert_eq!(a, rng(1, 0, PLACEMENT).gen::<u64>());
        assert_ne!(a, rng(1, 0, ROAM_HEADING).gen::<u64>());
        assert_ne!(a, rng(1, 1, PLACEMENT).gen::<u64>());
        assert_ne!(a, rng(2, 0, PLACEMENT).gen::<u64>());
    }
}
