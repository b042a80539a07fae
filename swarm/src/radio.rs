//! The radio model of the transport layer: range, loss and the counters.
//!
//! A message sent by robot s at tick k reaches robot r only if |p_s(k) - p_r(k)| <= R_comm and
//! a loss draw passes. The draw is a hash of (seed, tick, sender, receiver, seq): the same in
//! both executors and independent of OS scheduling.

use crate::scenario::{LossModel, RadioParams};
use serde::{Deserialize, Serialize};

/// What happened to one (message, receiver) pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Deliver,
    OutOfRange,
    Lost,
}

/// SplitMix64 finaliser: a well-mixed 64-bit hash step.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Uniform draw in [0, 1) from (seed, tick, sender, receiver, seq).
#[inline]
pub fn loss_draw(seed: u64, tick: u64, sender: u32, receiver: u32, seq: u32) -> f64 {
    let mut h = mix(seed ^ 0x5241_4449_4f00_0000); // "RADIO"
    h = mix(h ^ tick);
    h = mix(h ^ ((sender as u64) << 32 | receiver as u64));
    h = mix(h ^ seq as u64);
    (h >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Loss probability at distance d.
#[inline]
pub fn loss_probability(p: &RadioParams, d: f64) -> f64 {
    loss_probability_within(p, p.comm_radius, d)
}

/// Loss probability at distance d from a sender of range `radius` (the distance model's
/// d / R_comm is d / radius).
#[inline]
pub fn loss_probability_within(p: &RadioParams, radius: f64, d: f64) -> f64 {
    match p.loss_model {
        LossModel::Bernoulli => p.loss,
        LossModel::Distance => {
            let x = (d / radius).clamp(0.0, 1.0);
            (p.loss + (p.loss_at_range - p.loss) * x.powf(p.loss_exponent)).clamp(0.0, 1.0)
        }
    }
}

/// Euclidean distance, computed the same way everywhere (so range decisions agree bit for bit).
#[inline]
pub fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    let dx = a[0] - b[0];
    let dy = a[1] - b[1];
    (dx * dx + dy * dy).sqrt()
}

/// The distance from q to p if it is at most `radius` (`distance(q, p) <= radius`, exactly as
/// that test decides). A square beyond radius^2 by far more than sqrt's rounding is out
/// without the sqrt (as in [`decide`]): most candidates of a radius query are.
#[inline]
pub fn within_radius(q: [f64; 2], p: [f64; 2], radius: f64) -> Option<f64> {
    let dx = q[0] - p[0];
    let dy = q[1] - p[1];
    let s = dx * dx + dy * dy;
    if s > radius * radius * (1.0 + 1e-9) {
        return None;
    }
    let d = s.sqrt();
    (d <= radius).then_some(d)
}

/// The decision for one (message, receiver) pair.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn decide(
    p: &RadioParams,
    seed: u64,
    tick: u64,
    sender: u32,
    sender_pos: [f64; 2],
    receiver: u32,
    receiver_pos: [f64; 2],
    seq: u32,
) -> Verdict {
    decide_within(
        p,
        p.comm_radius,
        seed,
        tick,
        sender,
        sender_pos,
        receiver,
        receiver_pos,
        seq,
    )
}

/// [`decide`] for a sender whose range is `radius` (`radio.sender_ranges`; `comm_radius` for
/// the others).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn decide_within(
    p: &RadioParams,
    radius: f64,
    seed: u64,
    tick: u64,
    sender: u32,
    sender_pos: [f64; 2],
    receiver: u32,
    receiver_pos: [f64; 2],
    seq: u32,
) -> Verdict {
    // d = sqrt(s) is needed only near the range (and by the distance loss model): a square
    // beyond (below) R^2 by far more than sqrt's rounding decides `d > R` without it. Half the
    // pairs are out of range, and the sqrt sat in front of that unpredictable branch.
    let dx = sender_pos[0] - receiver_pos[0];
    let dy = sender_pos[1] - receiver_pos[1];
    let s = dx * dx + dy * dy;
    let r2 = radius * radius;
    if s > r2 * (1.0 + 1e-9) {
        return Verdict::OutOfRange;
    }
    let pl = if s < r2 * (1.0 - 1e-9) && p.loss_model == LossModel::Bernoulli {
        p.loss
    } else {
        let d = s.sqrt();
        if d > radius {
            return Verdict::OutOfRange;
        }
        loss_probability_within(p, radius, d)
    };
    if pl > 0.0 && loss_draw(seed, tick, sender, receiver, seq) < pl {
        Verdict::Lost
    } else {
        Verdict::Deliver
    }
}

/// The scenario's `[radio.burst]`: the Gilbert-Elliott channel, one two-state Markov chain
/// per directed link (`world::medium::burst`). Mean burst length 1 / p_bad_good ticks;
/// long-run share of Bad ticks p_good_bad / (p_good_bad + p_bad_good).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BurstParams {
    /// p: probability per tick of Good -> Bad.
    pub p_good_bad: f64,
    /// r: probability per tick of Bad -> Good (mean burst length 1 / r ticks).
    pub p_bad_good: f64,
    /// Loss probability while Good.
    pub loss_good: f64,
    /// Loss probability while Bad.
    pub loss_bad: f64,
}

impl BurstParams {
    /// pi_B, the long-run share of Bad ticks.
    pub fn bad_share(&self) -> f64 {
        let s = self.p_good_bad + self.p_bad_good;
        if s > 0.0 {
            self.p_good_bad / s
        } else {
            0.0
        }
    }
    /// The long-run loss rate pi_G loss_good + pi_B loss_bad.
    pub fn long_run_loss(&self) -> f64 {
        let b = self.bad_share();
        (1.0 - b) * self.loss_good + b * self.loss_bad
    }
}

/// Message counters, per (message, intended receiver) pair: of one tick (a recording's tick
/// record) or of the run (the summary). They add up: offered = delivered + dropped_range +
/// dropped_occluded + dropped_bandwidth + dropped_loss + malformed + receiver_dead +
/// in_flight, over the ticks up to any tick with that tick's `in_flight`.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    Serialize,
    Deserialize,
    bincode::Encode,
    bincode::Decode,
)]
pub struct RadioCounters {
    /// Pairs offered at the send tick: a broadcast counts once per other live robot, a unicast
    /// once.
    pub offered: u64,
    /// Due at this tick and decoded by the receiver.
    pub delivered: u64,
    /// Receiver beyond comm_radius at the send tick (or a unicast to a dead or unknown robot).
    pub dropped_range: u64,
    /// In range, but an obstacle blocked the line of sight (`radio.occlusion`).
    pub dropped_occluded: u64,
    /// In range, but beyond the sender's `radio.bandwidth_bytes_per_tick`.
    pub dropped_bandwidth: u64,
    /// In range, dropped by the loss model (Bernoulli, distance or Gilbert-Elliott).
    pub dropped_loss: u64,
    /// Due at this tick, but the receiver could not decode the payload.
    pub malformed: u64,
    /// Due at this tick, but the receiver was dead (or sent no action: in real-time mode, a
    /// receiver that missed the tick's deadline, so its list of the tick went unread).
    pub receiver_dead: u64,
    /// Passed the medium and not due yet, after this tick (a snapshot, not a sum: the run's is
    /// that of its last tick).
    pub in_flight: u64,
}

impl RadioCounters {
    /// Every pair's outcome counter (each pair ends in exactly one of them), named once for
    /// [`RadioCounters::add`] and [`RadioCounters::accounted`].
    fn outcomes_mut(&mut self) -> [&mut u64; 7] {
        [
            &mut self.delivered,
            &mut self.dropped_range,
            &mut self.dropped_occluded,
            &mut self.dropped_bandwidth,
            &mut self.dropped_loss,
            &mut self.malformed,
            &mut self.receiver_dead,
        ]
    }

    /// Adds a tick's counts; `in_flight` becomes the tick's.
    pub fn add(&mut self, o: &RadioCounters) {
        let mut o = *o;
        self.offered += o.offered;
        for (a, b) in self.outcomes_mut().into_iter().zip(o.outcomes_mut()) {
            *a += *b;
        }
        self.in_flight = o.in_flight;
    }

    /// Every pair's outcome so far, in flight included: equals `offered` when the books balance.
    pub fn accounted(&self) -> u64 {
        let mut c = *self;
        c.outcomes_mut().into_iter().map(|v| *v).sum::<u64>() + self.in_flight
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::Scenario;

    /// Hand-made counters: `add` sums every outcome and takes the later `in_flight`;
    /// `accounted` is the seven outcomes plus `in_flight`.
    #[test]
    fn counters_add_field_by_field_and_account_for_every_outcome() {
        let a = RadioCounters {
            offered: 100,
            delivered: 1,
            dropped_range: 2,
            dropped_occluded: 3,
            dropped_bandwidth: 4,
            dropped_loss: 5,
            malformed: 6,
            receiver_dead: 7,
            in_flight: 8,
        };
        let b = RadioCounters {
            offered: 1000,
            delivered: 10,
            dropped_range: 20,
            dropped_occluded: 30,
            dropped_bandwidth: 40,
            dropped_loss: 50,
            malformed: 60,
            receiver_dead: 70,
            in_flight: 80,
        };
        assert_eq!(a.accounted(), 36);
        let mut s = a;
        s.add(&b);
        let want = RadioCounters {
            offered: 1100,
            delivered: 11,
            dropped_range: 22,
            dropped_occluded: 33,
            dropped_bandwidth: 44,
            dropped_loss: 55,
            malformed: 66,
            receiver_dead: 77,
            in_flight: 80,
        };
        assert_eq!(s, want);
        assert_eq!(s.accounted(), 11 + 22 + 33 + 44 + 55 + 66 + 77 + 80);
    }

    #[test]
    fn loss_draw_is_a_pure_function_of_its_inputs() {
        assert_eq!(loss_draw(1, 2, 3, 4, 5), loss_draw(1, 2, 3, 4, 5));
        assert_ne!(loss_draw(1, 2, 3, 4, 5), loss_draw(1, 2, 3, 4, 6));
        assert_ne!(loss_draw(1, 2, 3, 4, 5), loss_draw(1, 2, 4, 3, 5));
        assert_ne!(loss_draw(1, 2, 3, 4, 5), loss_draw(2, 2, 3, 4, 5));
    }

    #[test]
    fn loss_draw_is_uniform() {
        let n = 200_000;
        let mut bins = [0u32; 10];
        let mut below = 0;
        for i in 0..n {
            let u = loss_draw(7, i / 1000, (i % 50) as u32, 3, (i % 7) as u32);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 10.0) as usize] += 1;
            if u < 0.3 {
                below += 1;
            }
        }
        for b in bins {
            assert!((b as f64 - 20_000.0).abs() < 800.0, "bins {bins:?}");
        }
        assert!((below as f64 / n as f64 - 0.3).abs() < 0.005);
    }

    #[test]
    fn bernoulli_loss_rate_matches_p() {
        let mut p = Scenario::default().radio;
        p.loss = 0.25;
        let mut lost = 0;
        let n = 100_000;
        for i in 0..n {
            if decide(&p, 9, i, 1, [0.0, 0.0], 2, [10.0, 0.0], 0) == Verdict::Lost {
                lost += 1;
            }
        }
        assert!((lost as f64 / n as f64 - 0.25).abs() < 0.01, "{lost}");
    }

    #[test]
    fn range_is_checked_before_loss() {
        let p = Scenario::default().radio;
        assert_eq!(
            decide(&p, 0, 0, 1, [0.0, 0.0], 2, [300.0, 0.0], 0),
            Verdict::Deliver
        );
        assert_eq!(
            decide(&p, 0, 0, 1, [0.0, 0.0], 2, [300.001, 0.0], 0),
            Verdict::OutOfRange
        );
    }

    #[test]
    fn range_decisions_match_the_distance_at_the_edge() {
        let mut p = Scenario::default().radio;
        for (r, model) in [(300.0, LossModel::Bernoulli), (0.1, LossModel::Distance)] {
            p.comm_radius = r;
            p.loss_model = model;
            p.loss = 0.0;
            p.loss_at_range = 0.0;
            let mut x = r * (1.0 - 1e-8);
            while x < r * (1.0 + 1e-8) {
                for y in [0.0, 1e-3 * r, 0.3 * r] {
                    let b = [x, y];
                    let want = if distance([0.0, 0.0], b) > r {
                        Verdict::OutOfRange
                    } else {
                        Verdict::Deliver
                    };
                    assert_eq!(decide(&p, 0, 0, 1, [0.0, 0.0], 2, b, 0), want, "{b:?}");
                    assert_eq!(decide(&p, 0, 0, 1, b, 2, [0.0, 0.0], 0), want, "{b:?}");
                }
                x = f64::from_bits(x.to_bits() + 1_000_000);
            }
        }
    }

    #[test]
    fn distance_model_grows_with_distance() {
        let mut p = Scenario::default().radio;
        p.loss_model = LossModel::Distance;
        p.loss = 0.1;
        p.loss_at_range = 0.9;
        p.loss_exponent = 1.0;
        assert!((loss_probability(&p, 0.0) - 0.1).abs() < 1e-12);
        assert!((loss_probability(&p, 150.0) - 0.5).abs() < 1e-12);
        assert!((loss_probability(&p, 300.0) - 0.9).abs() < 1e-12);
        let count = |x: f64| {
            (0..20_000)
                .filter(|&i| decide(&p, 3, i, 1, [0.0, 0.0], 2, [x, 0.0], 0) == Verdict::Lost)
                .count()
        };
        let (near, far) = (count(10.0), count(290.0));
        assert!(near < 3_000 && far > 16_000, "near {near} far {far}");
    }
}
