//! Bursty loss: the Gilbert-Elliott channel, one two-state Markov chain per directed link
//! (sender -> receiver), seeded, advanced per tick.
//!
//! The chain is Good or Bad; each tick it goes Good -> Bad with probability `p` and Bad ->
//! Good with probability `r`; a message is lost with probability `loss_good` in Good and
//! `loss_bad` in Bad. Long-run share of Bad ticks: pi_B = p / (p + r); mean burst (run of Bad
//! ticks) 1 / r; long-run loss pi_G loss_good + pi_B loss_bad.
//!
//! A link's state is sampled only at the ticks a message crosses it, from its last sampled
//! state: the n-step transition of the chain is exact in closed form,
//! P(Bad at t + n | Bad at t) = pi_B + (1 - pi_B) (1 - p - r)^n and
//! P(Bad at t + n | Good at t) = pi_B (1 - (1 - p - r)^n), so a link costs nothing on the ticks
//! nobody uses it and the draws depend only on (seed, link, tick): the same in both executors.

use std::collections::HashMap;
pub use swarm::radio::BurstParams;

/// Uniform draw in [0, 1) from (seed, a, b, c), SplitMix64-mixed.
fn draw(seed: u64, a: u64, b: u64, c: u64) -> f64 {
    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    let mut h = mix(seed ^ 0x4255_5253_5400_0000); // "BURST"
    h = mix(h ^ a);
    h = mix(h ^ b);
    h = mix(h ^ c);
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Every link's last sampled (tick, bad) state. Looked up, never iterated.
#[derive(Debug, Default)]
pub struct Links {
    state: HashMap<(u32, u32), (u64, bool)>,
}

impl Links {
    /// Whether link sender -> receiver is Bad at `tick` (ticks of one link must be asked in
    /// increasing order; asking the same tick again gives the same answer). A link first used
    /// at tick t starts from the chain's stationary distribution.
    pub fn bad_at(
        &mut self,
        p: &BurstParams,
        seed: u64,
        sender: u32,
        receiver: u32,
        tick: u64,
    ) -> bool {
        let link = (sender as u64) << 32 | receiver as u64;
        let u = draw(seed, link, tick, 0);
        let pi_b = p.bad_share();
        let bad = match self.state.get(&(sender, receiver)) {
            None => u < pi_b,
            Some(&(t0, b0)) if t0 == tick => b0,
            Some(&(t0, b0)) => {
                let n = tick.saturating_sub(t0);
                let lambda = 1.0 - p.p_good_bad - p.p_bad_good;
                let decay = if n > i32::MAX as u64 {
                    0.0
                } else {
                    lambda.powi(n as i32)
                };
                let p_bad = if b0 {
                    pi_b + (1.0 - pi_b) * decay
                } else {
                    pi_b * (1.0 - decay)
                };
                u < p_bad
            }
        };
        self.state.insert((sender, receiver), (tick, bad));
        bad
    }

    /// Whether a message on link sender -> receiver at `tick` is lost (state, then loss draw
    /// of the message's own `seq`).
    pub fn lost(
        &mut self,
        p: &BurstParams,
        seed: u64,
        sender: u32,
        receiver: u32,
        tick: u64,
        seq: u32,
    ) -> bool {
        let bad = self.bad_at(p, seed, sender, receiver, tick);
        let pl = if bad { p.loss_bad } else { p.loss_good };
        let link = (sender as u64) << 32 | receiver as u64;
        pl > 0.0 && draw(seed, link, tick, 1 + seq as u64) < pl
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: BurstParams = BurstParams {
        p_good_bad: 0.05,
        p_bad_good: 0.25,
        loss_good: 0.0,
        loss_bad: 1.0,
    };

    /// Loss rate and mean burst length of one link used every tick for `ticks` ticks.
    fn run(p: &BurstParams, ticks: u64, every: u64) -> (f64, f64, u64) {
        let mut l = Links::default();
        let (mut lost, mut n, mut bursts, mut in_burst, mut burst_ticks) =
            (0u64, 0u64, 0u64, false, 0u64);
        let mut t = 0;
        while t < ticks {
            let x = l.lost(p, 9, 3, 4, t, 0);
            lost += x as u64;
            n += 1;
            if x {
                burst_ticks += 1;
                if !in_burst {
                    bursts += 1;
                }
            }
            in_burst = x;
            t += every;
        }
        (
            lost as f64 / n as f64,
            burst_ticks as f64 / bursts.max(1) as f64,
            n,
        )
    }

    #[test]
    fn long_run_loss_and_burst_length_match_their_formulas() {
        // pi_B = 0.05 / 0.3 = 1/6, mean burst 1 / 0.25 = 4 ticks.
        let (loss, burst, n) = run(&P, 200_000, 1);
        let pi = P.long_run_loss();
        assert!((pi - 1.0 / 6.0).abs() < 1e-12);
        // The samples are correlated (a burst is ~4 ticks): the binomial standard deviation
        // times sqrt of the chain's variance inflation (1 + lambda) / (1 - lambda), lambda =
        // 1 - p - r = 0.7: x 5.67; 5 sigma.
        let sd = (pi * (1.0 - pi) / n as f64).sqrt() * ((1.0 + 0.7) / (1.0 - 0.7_f64)).sqrt();
        assert!(
            (loss - pi).abs() < 5.0 * sd,
            "loss {loss} vs {pi} (sd {sd})"
        );
        // Bursts: geometric with mean 4; ~5,600 of them, sd of the mean ~ sqrt(12)/sqrt(5600).
        assert!(
            (burst - 4.0).abs() < 5.0 * (12f64).sqrt() / (5600f64).sqrt(),
            "burst {burst}"
        );
        // Sampled every 7th tick (the lazy n-step transition), the loss rate is the same.
        let (loss7, _, n7) = run(&P, 1_400_000, 7);
        let sd7 = (pi * (1.0 - pi) / n7 as f64).sqrt() * 1.1;
        assert!((loss7 - pi).abs() < 5.0 * sd7, "every 7th: {loss7} vs {pi}");
    }

    #[test]
    fn without_bursts_it_is_bernoulli_and_draws_do_not_depend_on_query_order() {
        let p = BurstParams {
            p_good_bad: 0.0,
            p_bad_good: 1.0,
            loss_good: 0.3,
            loss_bad: 1.0,
        };
        let (loss, _, n) = run(&p, 100_000, 1);
        let sd = (0.3f64 * 0.7 / n as f64).sqrt();
        assert!((loss - 0.3).abs() < 5.0 * sd, "{loss}");
        // Two links asked in either order give the same answers.
        let (mut a, mut b) = (Links::default(), Links::default());
        for t in 0..50 {
            let x1 = a.lost(&P, 1, 0, 1, t, 0);
            let y1 = a.lost(&P, 1, 1, 0, t, 0);
            let y2 = b.lost(&P, 1, 1, 0, t, 0);
            let x2 = b.lost(&P, 1, 0, 1, t, 0);
            assert_eq!((x1, y1), (x2, y2));
        }
    }
}
