//! The round radio for CBCA (the thesis runs CBCA as rounds): every round each robot iterates, broadcasts its message to its
//! neighbours, and messages are dropped with probability `loss` and delayed by 0..=max_delay
//! rounds (a seeded rand_chacha stream); the run ends when every robot's convergence detector
//! says so (or at a safety cap, reported as not converged).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::consensus::{CbcaMessage, CbcaRobot};
use super::model::RobotId;

#[derive(Clone, Debug)]
pub struct Radio {
    pub loss: f64,
    pub max_delay: u64,
    pub seed: u64,
}

impl Radio {
    pub fn perfect() -> Self {
        Self {
            loss: 0.0,
            max_delay: 0,
            seed: 0,
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunStats {
    /// Consensus rounds until every detector declared convergence.
    pub rounds: u64,
    pub converged: bool,
    /// Broadcasts (one per robot per round).
    pub broadcasts: u64,
    /// Bytes broadcast (bincode, standard config, of each message).
    pub bytes: u64,
    /// Copies that reached a neighbour.
    pub delivered: u64,
    /// Copies the radio dropped.
    pub dropped: u64,
}

/// The bincode size of a message (what the radio would carry).
pub fn message_bytes(m: &CbcaMessage) -> usize {
    bincode::serde::encode_to_vec(m, bincode::config::standard())
        .expect("a CBCA message encodes")
        .len()
}

impl RunStats {
    /// Adds a later phase's counts (the conflict merges of compare.rs run consensus again):
    /// rounds, broadcasts, bytes and copies add up; converged only if both converged.
    pub fn add(&mut self, later: &RunStats) {
        self.rounds += later.rounds;
        self.converged = self.converged && later.converged;
        self.broadcasts += later.broadcasts;
        self.bytes += later.bytes;
        self.delivered += later.delivered;
        self.dropped += later.dropped;
    }
}

/// Runs consensus on `robots` over the graph `neighbours` (indices into `robots`) until every
/// robot's detector converges, for at most `max_rounds` rounds.
pub fn run(
    robots: &mut [CbcaRobot],
    neighbours: &[Vec<RobotId>],
    radio: &Radio,
    max_rounds: u64,
) -> RunStats {
    run_from(robots, neighbours, radio, 0, max_rounds)
}

/// [`run`] continuing after `rounds_before` earlier rounds (the time stamps go on from there,
/// so a later phase's messages are newer than everything the robots hold); `stats.rounds`
/// counts this call's rounds only.
pub fn run_from(
    robots: &mut [CbcaRobot],
    neighbours: &[Vec<RobotId>],
    radio: &Radio,
    rounds_before: u64,
    max_rounds: u64,
) -> RunStats {
    let mut rng = ChaCha8Rng::seed_from_u64(radio.seed.wrapping_add(rounds_before));
    let mut stats = RunStats::default();
    let mut queue: Vec<(u64, RobotId, std::rc::Rc<CbcaMessage>)> = Vec::new();
    for round in rounds_before + 1..=rounds_before + max_rounds {
        let now = round as f64;
        for r in robots.iter_mut() {
            r.iterate(now);
        }
        stats.rounds = round - rounds_before;
        let ids =
            |i: usize| -> Vec<RobotId> { neighbours[i].iter().map(|&n| robots[n].id()).collect() };
        if robots.iter().enumerate().all(|(i, r)| r.converged(&ids(i))) {
            stats.converged = true;
            return stats;
        }
        for (i, r) in robots.iter().enumerate() {
            let m = std::rc::Rc::new(r.message(now));
            stats.broadcasts += 1;
            stats.bytes += message_bytes(&m) as u64;
            for &n in &neighbours[i] {
                if radio.loss > 0.0 && rng.gen::<f64>() < radio.loss {
                    stats.dropped += 1;
                    continue;
                }
                let delay = if radio.max_delay > 0 {
                    rng.gen_range(0..=radio.max_delay)
                } else {
                    0
                };
                queue.push((round + delay, n, m.clone()));
            }
        }
        let (due, later): (Vec<_>, Vec<_>) = queue.drain(..).partition(|(t, _, _)| *t <= round);
        queue = later;
        for (_, to, m) in due {
            robots[to].receive(&m);
            stats.delivered += 1;
        }
    }
    stats
}
