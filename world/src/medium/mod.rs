//! The radio as one shared medium (issue "The radio as one shared medium"; DESIGN 5).
//!
//! A robot transmits once; the world, which holds ground truth, decides for every (message,
//! receiver) pair whether it arrives: the receiver alive and within `comm_radius` of the sender
//! at the send tick, the line of sight clear (`radio.occlusion`), the sender within its
//! bandwidth (`radio.bandwidth_bytes_per_tick`: its messages in send order until the budget is
//! spent), and the loss draw passing (Bernoulli / distance: the same hash of (seed, tick,
//! sender, receiver, seq) as [`swarm::radio::decide`]; or the Gilbert-Elliott chain of
//! [`burst`], per link). What passes is held `delay_ticks` and then handed out as one
//! [`TickAir`]: every message of the send tick once, behind its header, and per receiver the
//! indices of those that reach it, in (sender, seq) order.
//!
//! Both executors use it through [`crate::World`]: the world transmits each tick's messages in
//! `World::apply` and hands out the air due at the next tick (`World::air`); the multi-process
//! world publishes it as one `radio/air` sample (`swarm::air`), the in-process executor's
//! mailbox decodes it once. DESIGN-NOTES, "The radio as one medium", has the measurements.

pub mod burst;
pub mod occlusion;

use burst::{BurstParams, Links};
use occlusion::Occluders;
use std::collections::VecDeque;
pub use swarm::air::TickAir;
use swarm::frames::{RadioHeader, BROADCAST};
use swarm::radio::{decide, Verdict};
use swarm::scenario::{RadioParams, Scenario};

/// Per-(message, intended receiver) counts of one tick of the medium. They add up:
/// offered = scheduled + dropped_range + dropped_occluded + dropped_bandwidth + dropped_loss,
/// and at the due tick scheduled = delivered + malformed + receiver_dead.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    pub offered: u64,
    /// Passed every test at the send tick; delivered `delay_ticks` later.
    pub scheduled: u64,
    pub dropped_range: u64,
    pub dropped_occluded: u64,
    pub dropped_bandwidth: u64,
    pub dropped_loss: u64,
}

/// The medium's settings, from `[radio]`.
#[derive(Debug, Clone)]
pub struct MediumParams {
    pub radio: RadioParams,
    /// Bytes (headers included) a robot may put on the air per tick; 0: no cap.
    pub bandwidth_bytes_per_tick: u32,
    /// Gilbert-Elliott bursty loss instead of the loss model (None: the loss model).
    pub burst: Option<BurstParams>,
    /// Obstacles block the line of sight.
    pub occlusion: bool,
}

impl MediumParams {
    pub fn from_scenario(sc: &Scenario) -> MediumParams {
        MediumParams {
            radio: sc.radio.clone(),
            bandwidth_bytes_per_tick: sc.radio.bandwidth_bytes_per_tick,
            burst: sc.radio.burst,
            occlusion: sc.radio.occlusion,
        }
    }
}

/// Bytes a message takes on the air: its header and its payload.
pub fn air_bytes(h: &RadioHeader) -> u64 {
    std::mem::size_of::<RadioHeader>() as u64 + h.len as u64
}

pub struct Medium {
    p: MediumParams,
    seed: u64,
    n: usize,
    occluders: Option<Occluders>,
    links: Links,
    /// Traffic sent and not yet due, oldest first.
    queue: VecDeque<TickAir>,
    /// Per-receiver lists of the tick being built (kept for their allocations).
    lists: Vec<Vec<u32>>,
}

impl Medium {
    pub fn new(sc: &Scenario, p: MediumParams) -> Medium {
        let n = sc.run.robots as usize;
        Medium {
            occluders: p.occlusion.then(|| Occluders::new(sc)),
            p,
            seed: sc.run.seed,
            n,
            links: Links::default(),
            queue: VecDeque::new(),
            lists: vec![Vec::new(); n],
        }
    }

    /// The messages robots sent at `tick` (any order; headers name sender and seq), with the
    /// positions (`poses`, at the send tick) and liveness the world holds: decides every
    /// (message, receiver) pair and holds what passes until it is due.
    pub fn transmit<'a>(
        &mut self,
        tick: u64,
        sent: impl IntoIterator<Item = (&'a RadioHeader, &'a [u8])>,
        poses: &[[f64; 3]],
        alive: &[bool],
    ) -> Counts {
        let mut msgs: Vec<(&RadioHeader, &[u8])> = sent.into_iter().collect();
        msgs.sort_by_key(|(h, _)| (h.sender, h.seq));
        let mut counts = Counts::default();
        let mut air = TickAir {
            tick,
            ..Default::default()
        };
        for l in &mut self.lists {
            l.clear();
        }
        let live = alive.iter().filter(|a| **a).count() as u64;
        let mut budget_of = (u32::MAX, 0u64);
        for (h, payload) in msgs {
            let s = h.sender as usize;
            if s >= self.n || !alive[s] || payload.len() != h.len as usize {
                continue;
            }
            let receivers = if h.dest == BROADCAST {
                live.saturating_sub(1)
            } else {
                1
            };
            counts.offered += receivers;
            // The sender's bandwidth, in send order.
            if budget_of.0 != h.sender {
                budget_of = (h.sender, 0);
            }
            budget_of.1 += air_bytes(h);
            let cap = self.p.bandwidth_bytes_per_tick as u64;
            if cap > 0 && budget_of.1 > cap {
                counts.dropped_bandwidth += receivers;
                continue;
            }
            let m = air.messages.len() as u32;
            let from = [poses[s][0], poses[s][1]];
            let mut any = false;
            let mut judge = |j: usize, counts: &mut Counts, lists: &mut Vec<Vec<u32>>| {
                let to = [poses[j][0], poses[j][1]];
                match decide(
                    &self.p.radio,
                    self.seed,
                    tick,
                    h.sender,
                    from,
                    j as u32,
                    to,
                    h.seq,
                ) {
                    Verdict::OutOfRange => counts.dropped_range += 1,
                    verdict => {
                        if self.occluders.as_ref().is_some_and(|o| o.blocked(from, to)) {
                            counts.dropped_occluded += 1;
                            return;
                        }
                        let lost = match &self.p.burst {
                            Some(b) => self
                                .links
                                .lost(b, self.seed, h.sender, j as u32, tick, h.seq),
                            None => verdict == Verdict::Lost,
                        };
                        if lost {
                            counts.dropped_loss += 1;
                        } else {
                            counts.scheduled += 1;
                            lists[j].push(m);
                            any = true;
                        }
                    }
                }
            };
            if h.dest == BROADCAST {
                for (j, &up) in alive.iter().enumerate().take(self.n) {
                    if j != s && up {
                        judge(j, &mut counts, &mut self.lists);
                    }
                }
            } else {
                let j = h.dest as usize;
                if j < self.n && j != s && alive[j] {
                    judge(j, &mut counts, &mut self.lists);
                } else {
                    counts.dropped_range += 1;
                }
            }
            if any {
                let at = air.bytes.len();
                air.bytes.extend_from_slice(payload);
                air.messages.push((*h, at..at + payload.len()));
            }
        }
        air.start.reserve(self.n + 1);
        air.start.push(0);
        for l in &self.lists {
            air.index.extend_from_slice(l);
            air.start.push(air.index.len() as u32);
        }
        self.queue.push_back(air);
        counts
    }

    /// The traffic due at `tick` (sent at tick - 1 - delay_ticks), if any was sent then.
    pub fn due(&mut self, tick: u64) -> Option<TickAir> {
        let delay = self.p.radio.delay_ticks as u64;
        while let Some(front) = self.queue.front() {
            if front.tick + 1 + delay < tick {
                self.queue.pop_front();
            } else {
                break;
            }
        }
        match self.queue.front() {
            Some(f) if f.tick + 1 + delay == tick => self.queue.pop_front(),
            _ => None,
        }
    }

    /// (message, receiver) pairs scheduled and not yet due: in flight at the end of a run.
    pub fn in_flight(&self) -> u64 {
        self.queue.iter().map(|a| a.index.len() as u64).sum()
    }
}

#[cfg(test)]
mod tests;
