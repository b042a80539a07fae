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
pub mod grid;
pub mod occlusion;

use burst::{BurstParams, Links};
use grid::RobotGrid;
use occlusion::Occluders;
use std::collections::VecDeque;
pub use swarm::air::TickAir;
use swarm::frames::{RadioHeader, BROADCAST};
use swarm::radio::{decide_within, Verdict};
use swarm::scenario::{RadioParams, RangeScan, Scenario};

/// Per-(message, intended receiver) counts of one tick of the medium, in pairs or in payload
/// bytes (each pair counts its message's payload length). They add up:
/// offered = scheduled + dropped_range + dropped_occluded + dropped_bandwidth + dropped_loss,
/// and at the due tick scheduled = delivered + malformed + receiver_dead.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    pub offered: u64,
    /// Passed every test at the send tick; delivered `delay_ticks` later.
    pub scheduled: u64,
    pub dropped_range: u64,
    pub dropped_occluded: u64,
    pub dropped_bandwidth: u64,
    pub dropped_loss: u64,
}

/// What became of one (message, receiver) pair at the send tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Scheduled,
    Range,
    Occluded,
    Bandwidth,
    Loss,
}

impl Tally {
    fn add(&mut self, o: Outcome, n: u64) {
        let slot = match o {
            Outcome::Scheduled => &mut self.scheduled,
            Outcome::Range => &mut self.dropped_range,
            Outcome::Occluded => &mut self.dropped_occluded,
            Outcome::Bandwidth => &mut self.dropped_bandwidth,
            Outcome::Loss => &mut self.dropped_loss,
        };
        *slot += n;
    }
}

/// A tick's counts: pairs, and the same in payload bytes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    pub pairs: Tally,
    pub bytes: Tally,
}

impl Counts {
    /// `n` pairs of a message of `len` payload bytes had outcome `o`.
    fn add(&mut self, o: Outcome, n: u64, len: u64) {
        self.pairs.add(o, n);
        self.bytes.add(o, n * len);
    }
    fn offer(&mut self, n: u64, len: u64) {
        self.pairs.offered += n;
        self.bytes.offered += n * len;
    }
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
    /// How receivers within range are found (`radio.range_scan`).
    pub scan: RangeScan,
}

impl MediumParams {
    pub fn from_scenario(sc: &Scenario) -> MediumParams {
        MediumParams {
            radio: sc.radio.clone(),
            bandwidth_bytes_per_tick: sc.radio.bandwidth_bytes_per_tick,
            burst: sc.radio.burst,
            occlusion: sc.radio.occlusion,
            scan: sc.radio.range_scan,
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
    /// Each agent's radio range (`radio.sender_ranges`, else `comm_radius`).
    ranges: Vec<f64>,
    occluders: Option<Occluders>,
    links: Links,
    /// Traffic sent and not yet due, oldest first.
    queue: VecDeque<TickAir>,
    /// Spent airs handed back ([`Medium::recycle`]), reused for their allocations.
    spare: Vec<TickAir>,
    /// Per-receiver lists of the tick being built (kept for their allocations).
    lists: Vec<Vec<u32>>,
    /// The tick's messages in (sender, seq, arrival) order (kept for its allocation).
    order: Vec<(u32, u32, u32)>,
    /// The live robots by cell at the send tick.
    grid: RobotGrid,
}

/// Each agent's radio range: `radio.sender_ranges`, else `radio.comm_radius`; a hunt's
/// auctioneer station with a `hunt.auctioneer.radio_range` and no entry of its own transmits
/// within min(comm_radius, radio_range) (the section's "on top of radio.comm_radius").
pub fn sender_ranges(sc: &Scenario, radio: &RadioParams) -> Vec<f64> {
    let n = sc.run.robots as usize;
    let mut ranges = radio.ranges(n);
    let station = sc.bodies() as usize;
    let own = radio
        .sender_ranges
        .iter()
        .any(|s| s.agent as usize == station);
    let r = sc.hunt().auctioneer.radio_range;
    if sc.run.stations > 0 && r > 0.0 && !own && station < n {
        ranges[station] = radio.comm_radius.min(r);
    }
    ranges
}

impl Medium {
    pub fn new(sc: &Scenario, p: MediumParams) -> Medium {
        let n = sc.run.robots as usize;
        Medium {
            occluders: p.occlusion.then(|| Occluders::new(sc)),
            ranges: sender_ranges(sc, &p.radio),
            p,
            seed: sc.run.seed,
            n,
            links: Links::default(),
            queue: VecDeque::new(),
            spare: Vec::new(),
            lists: vec![Vec::new(); n],
            order: Vec::new(),
            grid: RobotGrid::default(),
        }
    }

    /// The messages robots sent at `tick` (`sent`: header and the offset of its payload in
    /// `bytes`; any order: headers name sender and seq), with the positions (`poses`, at the
    /// send tick) and liveness the world holds: decides every (message, receiver) pair and
    /// holds what passes until it is due. A message whose payload lies outside `bytes` is
    /// not sent.
    pub fn transmit(
        &mut self,
        tick: u64,
        sent: &[(RadioHeader, usize)],
        bytes: &[u8],
        poses: &[[f64; 3]],
        alive: &[bool],
    ) -> Counts {
        self.transmit_into(tick, sent, bytes, poses, alive, false)
    }

    /// [`Medium::transmit`] without copying a payload: the air it queues is `lent`, its
    /// message ranges index `bytes`, and the caller writes it into the air sample straight
    /// from there (`swarm::air::write_air_from`), so a payload is copied once between the
    /// sender's buffer and the air instead of twice. The caller must publish the air due at
    /// `tick + 1` (the next [`Medium::due`]) from the same, unchanged `bytes`. With a delay
    /// (`radio.delay_ticks` > 0) the air outlives the tick's buffer, so the payloads are
    /// copied as by `transmit` (the air then holds them; `write_air_from` reads them there).
    /// Decisions and counts are those of `transmit`.
    pub fn transmit_lent(
        &mut self,
        tick: u64,
        sent: &[(RadioHeader, usize)],
        bytes: &[u8],
        poses: &[[f64; 3]],
        alive: &[bool],
    ) -> Counts {
        let lend = self.p.radio.delay_ticks == 0;
        self.transmit_into(tick, sent, bytes, poses, alive, lend)
    }

    fn transmit_into(
        &mut self,
        tick: u64,
        sent: &[(RadioHeader, usize)],
        bytes: &[u8],
        poses: &[[f64; 3]],
        alive: &[bool],
        lend: bool,
    ) -> Counts {
        let Medium {
            p,
            seed,
            n,
            ranges,
            occluders,
            links,
            queue,
            spare,
            lists,
            order,
            grid,
        } = self;
        let (n, seed) = (*n, *seed);
        order.clear();
        order.extend(
            sent.iter()
                .enumerate()
                .map(|(k, (h, _))| (h.sender, h.seq, k as u32)),
        );
        // The key is unique, so the unstable sort gives the stable sort's (sender, seq) order.
        order.sort_unstable();
        let mut counts = Counts::default();
        let mut air = spare.pop().unwrap_or_default();
        air.clear();
        air.tick = tick;
        air.lent = lend;
        air.bytes_to.resize(n, 0);
        for l in lists.iter_mut() {
            l.clear();
        }
        if p.scan == RangeScan::Grid {
            grid.rebuild(
                &poses[..n.min(poses.len())],
                &alive[..n.min(alive.len())],
                p.radio.comm_radius,
            );
        }
        let live = alive.iter().take(n).filter(|a| **a).count() as u64;
        let cap = p.bandwidth_bytes_per_tick as u64;
        let mut budget_of = (u32::MAX, 0u64);
        for &(_, _, k) in order.iter() {
            let (h, at) = &sent[k as usize];
            let s = h.sender as usize;
            let Some(payload) = bytes.get(*at..at.saturating_add(h.len as usize)) else {
                continue;
            };
            if s >= n || !alive[s] {
                continue;
            }
            let len = h.len as u64;
            let receivers = if h.dest == BROADCAST {
                live.saturating_sub(1)
            } else {
                1
            };
            counts.offer(receivers, len);
            // The sender's bandwidth, in send order.
            if budget_of.0 != h.sender {
                budget_of = (h.sender, 0);
            }
            budget_of.1 += air_bytes(h);
            if cap > 0 && budget_of.1 > cap {
                counts.add(Outcome::Bandwidth, receivers, len);
                continue;
            }
            let m = air.messages.len() as u32;
            let from = [poses[s][0], poses[s][1]];
            let range = ranges[s];
            let mut any = false;
            let mut judge = |j: usize, counts: &mut Counts| {
                let to = [poses[j][0], poses[j][1]];
                let verdict = decide_within(
                    &p.radio, range, seed, tick, h.sender, from, j as u32, to, h.seq,
                );
                let o = match verdict {
                    Verdict::OutOfRange => Outcome::Range,
                    _ if occluders.as_ref().is_some_and(|o| o.blocked(from, to)) => {
                        Outcome::Occluded
                    }
                    verdict => {
                        let lost = match &p.burst {
                            Some(b) => links.lost(b, seed, h.sender, j as u32, tick, h.seq),
                            None => verdict == Verdict::Lost,
                        };
                        if lost {
                            Outcome::Loss
                        } else {
                            lists[j].push(m);
                            air.bytes_to[j] += len;
                            any = true;
                            Outcome::Scheduled
                        }
                    }
                };
                counts.add(o, 1, len);
            };
            if h.dest == BROADCAST {
                match p.scan {
                    RangeScan::All => {
                        for (j, &up) in alive.iter().enumerate().take(n) {
                            if j != s && up {
                                judge(j, &mut counts);
                            }
                        }
                    }
                    RangeScan::Grid => {
                        // The grid returns a superset of the live robots in range; the rest
                        // are out of range without a test.
                        let mut judged = 0u64;
                        grid.near(from, range, |j| {
                            if j as usize != s {
                                judged += 1;
                                judge(j as usize, &mut counts);
                            }
                        });
                        counts.add(Outcome::Range, receivers - judged, len);
                    }
                }
            } else {
                let j = h.dest as usize;
                if j < n && j != s && alive[j] {
                    judge(j, &mut counts);
                } else {
                    counts.add(Outcome::Range, 1, len);
                }
            }
            if any && lend {
                air.messages.push((*h, *at..at + payload.len()));
            } else if any {
                let at = air.bytes.len();
                air.bytes.extend_from_slice(payload);
                air.messages.push((*h, at..at + payload.len()));
            }
        }
        air.start.reserve(n + 1);
        air.start.push(0);
        for l in lists.iter() {
            air.index.extend_from_slice(l);
            air.start.push(air.index.len() as u32);
        }
        queue.push_back(air);
        counts
    }

    /// The traffic due at `tick` (sent at tick - 1 - delay_ticks), if any was sent then.
    pub fn due(&mut self, tick: u64) -> Option<TickAir> {
        let delay = self.p.radio.delay_ticks as u64;
        while let Some(front) = self.queue.front() {
            if front.tick + 1 + delay < tick {
                let stale = self.queue.pop_front().expect("front");
                self.recycle(stale);
            } else {
                break;
            }
        }
        match self.queue.front() {
            Some(f) if f.tick + 1 + delay == tick => self.queue.pop_front(),
            _ => None,
        }
    }

    /// Hands a spent air back: the next tick's is built in its allocations.
    pub fn recycle(&mut self, air: TickAir) {
        if self.spare.len() < 2 {
            self.spare.push(air);
        }
    }

    /// (message, receiver) pairs scheduled and not yet due: in flight at the end of a run.
    pub fn in_flight(&self) -> u64 {
        self.queue.iter().map(|a| a.index.len() as u64).sum()
    }

    /// The payload bytes of [`Medium::in_flight`]'s pairs.
    pub fn in_flight_bytes(&self) -> u64 {
        self.queue
            .iter()
            .map(|a| a.bytes_to.iter().sum::<u64>())
            .sum()
    }
}

#[cfg(test)]
mod tests;
