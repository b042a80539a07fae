//! The centralised modes (per-step, one-shot) relayed over many hops, for swarms whose radio
//! does not reach every robot from the coordinator or whose plan does not fit one message
//! (100 and 500 robots at comm radius 15, 512-byte messages; docs/formation.md 9, "The
//! centralised mode relayed").
//!
//! Three flows, each robot's share of them kept here ([`Relay`]), the behaviour's use of them
//! in relay_step.rs:
//! - **Election** (spec 5 option (a), "the lowest id a robot hears", made multi-hop): every
//!   robot forwards the freshest beacon (root, stamp, hops) of the lowest root it knows; the
//!   root stamps its own with the tick. A root whose stamp is older than `root_timeout`
//!   ticks is dead for this robot (it falls back to itself until a lower live root reaches
//!   it). `hops` (the beacon's distance) orders the robots into a gradient towards the root.
//! - **Gathering** (convergecast): every robot keeps a table of positions, its own refreshed
//!   every tick, and absorbs the entries of robots farther from the root (their `hops`
//!   larger) when newer. It sends its own entry and as many others as one message holds, the
//!   entries not yet sent since their last update first, then the least recently sent (a
//!   round robin: under loss every entry is repeated, and no entry starves).
//! - **Dissemination** (flooding): the root's plan head (transform, kept template points,
//!   members as bitmaps) and the assignment sigma in chunks, each with the plan's epoch and
//!   the assignment's sequence number; a robot repeats a head or chunk newer than it held for
//!   `repeat_ticks` ticks, then falls silent.

use super::compact::encoded_len;
use super::gossip::Bitmap;
use super::messages::Msg;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use swarm::geometry::Vec2;
use swarm::scenario::{Check, ConfigError, Scenario};

/// `formation.kernels.relay`: present for the relayed centralised mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RelayParams {
    /// Ticks a beacon may take per hop before its root is taken for dead. [chosen] 3: a hop
    /// is lost at loss 0.3 with 0.3 per tick and each robot forwards every tick, so three
    /// ticks fail with 0.027 on one link (a robot hears several).
    pub ticks_per_hop: u64,
    /// The hop count the timeouts allow is `hop_factor` times the box diagonal over the comm
    /// radius, plus one (a multi-hop path is longer than the straight line). [chosen] 1.5.
    pub hop_factor: f64,
    /// Entries of the position table in one gathering message. [chosen] 20 (22 bytes each:
    /// the message stays under 512 bytes).
    pub entries_per_message: usize,
    /// Wrecks in one gathering message (round robin over those the plan was not made
    /// around). [chosen] 2 (8 bytes each).
    pub wrecks_per_message: usize,
    /// Slots of sigma in one chunk. [chosen] 150 (at most 3 bytes each: 450 bytes).
    pub sigma_chunk: usize,
    /// A robot repeats a head or chunk newer than the one it held for this many ticks.
    /// [chosen] 3 (a neighbour misses three repeats with 0.3^3 = 0.027 at loss 0.3).
    pub repeat_ticks: u64,
    /// The root re-sends the current assignment at least this often, changed or not, for
    /// robots that missed it. [chosen] 10.
    pub refresh_ticks: u64,
    /// At most this many wrecks in a head, the nearest the pattern first. [chosen] 12.
    pub max_dead: usize,
    /// Per-step reassignment on relayed positions: the root changes many slots at once at
    /// most once every `reassign_ticks_per_hop` x hops ticks (`hops`: the network's diameter,
    /// as the timeouts count it), the time a new assignment takes to reach every robot.
    /// Sooner, the robots still follow the previous one when the root re-optimises on where
    /// they went, and it chases its own lag: at 500 robots with the certified pattern the root
    /// changed 40-100 slots a tick, each change lowering eq. (1) on the estimated positions by
    /// hundreds (225 of 500 in place at tick 400, against K = 193 one-shot). Tried and dropped
    /// (docs/formation.md 9, "The alignment polygon"): a least gain per changed robot, a lock
    /// per robot, the period for every change. [chosen] 0 (every step, the paper): with a
    /// pattern far from most robots (the fixed C) the period only slows the end game (500
    /// robots, three kills: K 299 -> 1103), and at 100 robots it changed nothing for the
    /// optimised pattern (33 kill runs, the same K and L sums); configs/formation-500-
    /// centralised.toml sets 2 (a hop at loss 0.3 takes 1 / 0.7 = 1.4 ticks on average: 40
    /// ticks at 500 robots).
    pub reassign_ticks_per_hop: u64,
    /// ... but a new assignment that changes at most this many slots (a local exchange, as
    /// the end game needs) is taken at once: with the period alone the fixed C at 100 robots
    /// (seed 1) formed at K = 381 instead of 147. [chosen] 4 (two pair swaps).
    pub reassign_small: usize,
}

impl Default for RelayParams {
    fn default() -> Self {
        RelayParams {
            ticks_per_hop: 3,
            hop_factor: 1.5,
            entries_per_message: 20,
            wrecks_per_message: 2,
            sigma_chunk: 150,
            repeat_ticks: 3,
            refresh_ticks: 10,
            max_dead: 12,
            reassign_ticks_per_hop: 0,
            reassign_small: 4,
        }
    }
}

impl RelayParams {
    /// The hops the timeouts allow in a box of this diagonal.
    pub fn hops(&self, diagonal: f64, comm_radius: f64) -> u64 {
        (self.hop_factor * diagonal / comm_radius.max(1e-9)).ceil() as u64 + 1
    }
    /// Ticks after which a root not heard of is dead (and a gathering gives up waiting).
    pub fn timeout(&self, diagonal: f64, comm_radius: f64) -> u64 {
        self.ticks_per_hop * self.hops(diagonal, comm_radius)
    }
}

/// Checks `formation.kernels.relay` against the radio: every message at its largest fits
/// `radio.max_message_bytes`, and a robot's messages of one tick (status, gathering, head,
/// every chunk) fit `radio.max_messages_per_tick`.
pub fn check(sc: &Scenario, c: &Check, p: &RelayParams) -> Result<(), ConfigError> {
    let key = |k: &str| format!("formation.kernels.relay.{k}");
    c.range_u(&key("ticks_per_hop"), p.ticks_per_hop, 1, 1_000_000)?;
    c.range_f(&key("hop_factor"), p.hop_factor, 1.0, 1e6, false)?;
    c.range_u(&key("entries_per_message"), p.entries_per_message as u64, 1, 10_000)?;
    c.range_u(&key("wrecks_per_message"), p.wrecks_per_message as u64, 0, 10_000)?;
    c.range_u(&key("sigma_chunk"), p.sigma_chunk as u64, 1, u16::MAX as u64)?;
    c.range_u(&key("repeat_ticks"), p.repeat_ticks, 1, 1_000_000)?;
    c.range_u(&key("refresh_ticks"), p.refresh_ticks, 1, 1_000_000)?;
    c.range_u(&key("max_dead"), p.max_dead as u64, 0, 1_000)?;
    c.range_u(&key("reassign_ticks_per_hop"), p.reassign_ticks_per_hop, 0, 1_000_000)?;
    c.range_u(&key("reassign_small"), p.reassign_small as u64, 0, u16::MAX as u64)?;
    let robots = sc.run.robots as usize;
    let top = robots.saturating_sub(1) as u32;
    let max = sc.radio.max_message_bytes as usize;
    let all = |n: usize| {
        let mut b = Bitmap::with_len(n);
        (0..n).for_each(|i| b.insert(i));
        b
    };
    let entry = Entry {
        id: top,
        tick: u32::MAX,
        pos: [0.0; 2],
        vel: [0.0; 2],
    };
    let sizes = [
        (
            "entries_per_message",
            encoded_len(&Msg::Up(Up {
                root: top,
                stamp: u32::MAX,
                hops: u16::MAX,
                entries: vec![entry; p.entries_per_message],
                wrecks: vec![[0.0; 2]; p.wrecks_per_message],
            })),
        ),
        (
            "sigma_chunk",
            encoded_len(&Msg::Sigma(Sigma {
                epoch: u32::MAX,
                coordinator: top,
                seq: u32::MAX,
                first: u16::MAX,
                slots: vec![top as u16; p.sigma_chunk.min(robots.max(1))],
            })),
        ),
        (
            "max_dead",
            encoded_len(&Msg::Head(Head {
                epoch: u32::MAX,
                coordinator: top,
                transform: [0.0; 4],
                kept: all(robots),
                members: all(robots),
                dead: vec![[0.0; 2]; p.max_dead],
            })),
        ),
    ];
    for (k, len) in sizes {
        if len > max {
            return Err(c.err(
                &key(k),
                format!(
                    "= the relayed mode's message for {robots} robots takes {len} bytes at its largest, \
                     more than radio.max_message_bytes = {max}: lower {} or raise radio.max_message_bytes",
                    key(k)
                ),
            ));
        }
    }
    let per_tick = 3 + robots.div_ceil(p.sigma_chunk.max(1));
    if per_tick > sc.radio.max_messages_per_tick as usize {
        return Err(c.err(
            &key("sigma_chunk"),
            format!(
                "= {}: a robot may send {per_tick} messages in a tick (status, gathering, head and \
                 {} chunks of sigma for {robots} robots), more than radio.max_messages_per_tick = {}: \
                 raise sigma_chunk or radio.max_messages_per_tick",
                p.sigma_chunk,
                per_tick - 3,
                sc.radio.max_messages_per_tick
            ),
        ));
    }
    Ok(())
}

/// One robot's position as the gathering carries it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    pub id: u32,
    /// The tick of the position.
    pub tick: u32,
    pub pos: [f32; 2],
    /// Units per second.
    pub vel: [f32; 2],
}

/// Every robot, every tick, in the relayed mode: its beacon and a part of its table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Up {
    pub root: u32,
    pub stamp: u32,
    pub hops: u16,
    pub entries: Vec<Entry>,
    /// Wrecks (dead robots' positions, the world's) the sender knows and its plan was not
    /// made around: relayed towards the root like the entries, for its re-plan.
    pub wrecks: Vec<[f32; 2]>,
}

/// The root's pattern, flooded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Head {
    pub epoch: u32,
    pub coordinator: u32,
    /// [alpha, d_1, d_2, theta] of eq. (5).
    pub transform: [f64; 4],
    /// Template points of the pattern (bits over formation.template): slot j is the j-th.
    pub kept: Bitmap,
    /// The robots of the pattern (bits by id): member i is the i-th.
    pub members: Bitmap,
    /// Wrecks planned around (static discs in ORCA, obstacles in C2).
    pub dead: Vec<[f32; 2]>,
}

/// A part of the assignment sigma: the slots of members `first ..` in member order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sigma {
    pub epoch: u32,
    pub coordinator: u32,
    /// The tick the assignment was solved at: newer replaces older.
    pub seq: u32,
    pub first: u16,
    pub slots: Vec<u16>,
}

/// A table row: the entry, and when this robot last sent it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Row {
    entry: Entry,
    /// Tick last sent, and the entry's tick then (None: never sent).
    sent: Option<(u64, u32)>,
}

/// One robot's view of the three flows.
#[derive(Debug, Clone, PartialEq)]
pub struct Relay {
    pub me: u32,
    /// The beacon held: root, its stamp, hops from it.
    pub root: u32,
    pub stamp: u64,
    pub hops: u16,
    /// The tick this robot last became root (or changed root).
    pub root_since: u64,
    table: BTreeMap<u32, Row>,
    timeout: u64,
}

impl Relay {
    pub fn new(me: u32, timeout: u64) -> Relay {
        Relay {
            me,
            root: me,
            stamp: 0,
            hops: 0,
            root_since: 0,
            table: BTreeMap::new(),
            timeout,
        }
    }

    pub fn is_root(&self) -> bool {
        self.root == self.me
    }

    /// The election for tick `k` from the beacons heard (root, stamp, hops of the sender).
    pub fn elect(&mut self, k: u64, heard: &[(u32, u64, u16)]) {
        let fresh = |stamp: u64| stamp + self.timeout >= k;
        // Candidates: myself (a root of my own, stamp k), the beacon held if still fresh, and
        // every beacon heard one hop farther.
        let mut best = (self.me, k, 0u16);
        let mut consider = |c: (u32, u64, u16)| {
            if !fresh(c.1) {
                return;
            }
            let better = c.0 < best.0
                || (c.0 == best.0 && (c.1 > best.1 || (c.1 == best.1 && c.2 < best.2)));
            if better {
                best = c;
            }
        };
        if self.root != self.me {
            consider((self.root, self.stamp, self.hops));
        }
        for (root, stamp, hops) in heard {
            consider((*root, *stamp, hops.saturating_add(1)));
        }
        if best.0 != self.root {
            self.root_since = k;
        }
        (self.root, self.stamp, self.hops) = best;
    }

    /// This robot's own entry for tick `k`.
    pub fn note_self(&mut self, k: u64, pos: Vec2, vel: Vec2) {
        let entry = Entry {
            id: self.me,
            tick: k as u32,
            pos: [pos.x as f32, pos.y as f32],
            vel: [vel.x as f32, vel.y as f32],
        };
        self.put(entry);
    }

    /// Absorbs a gathering message from a robot farther from the same root.
    pub fn absorb(&mut self, up: &Up) {
        if up.root != self.root || up.hops <= self.hops {
            return;
        }
        for e in &up.entries {
            if e.id != self.me {
                self.put(*e);
            }
        }
    }

    fn put(&mut self, entry: Entry) {
        match self.table.get_mut(&entry.id) {
            Some(row) if row.entry.tick >= entry.tick => {}
            Some(row) => row.entry = entry,
            None => {
                self.table.insert(entry.id, Row { entry, sent: None });
            }
        }
    }

    /// The gathering message of tick `k`: the beacon, this robot's entry and up to `n - 1`
    /// others, unsent updates first (oldest entry first), then the least recently sent.
    pub fn up(&mut self, k: u64, n: usize) -> Up {
        let mut order: Vec<(bool, u64, u32, u32)> = self
            .table
            .iter()
            .filter(|(id, _)| **id != self.me)
            .map(|(id, row)| {
                let unsent = row.sent.is_none_or(|(_, t)| t < row.entry.tick);
                let last = row.sent.map_or(0, |(at, _)| at);
                (!unsent, last, row.entry.tick, *id)
            })
            .collect();
        let mut entries = Vec::with_capacity(n);
        if let Some(row) = self.table.get(&self.me) {
            entries.push(row.entry);
        }
        // Only the first `take` in key order are sent: select them (linear), then order them,
        // rather than sort the whole table every tick (500 rows at 500 robots). The keys are
        // distinct (the id is in them), so the chosen set is the sort's.
        let take = n.saturating_sub(entries.len()).min(order.len());
        if take > 0 && take < order.len() {
            order.select_nth_unstable(take - 1);
        }
        order.truncate(take);
        order.sort_unstable();
        for (_, _, _, id) in order {
            let row = self.table.get_mut(&id).expect("listed above");
            row.sent = Some((k, row.entry.tick));
            entries.push(row.entry);
        }
        Up {
            root: self.root,
            stamp: self.stamp as u32,
            hops: self.hops,
            entries,
            wrecks: Vec::new(),
        }
    }

    /// The rows whose position is of tick `since` or later, by id.
    pub fn fresh_since(&self, since: u64) -> impl Iterator<Item = &Entry> + '_ {
        self.table
            .values()
            .map(|r| &r.entry)
            .filter(move |e| e.tick as u64 >= since)
    }

    /// The entry of robot `id`, if any.
    pub fn entry(&self, id: u32) -> Option<&Entry> {
        self.table.get(&id).map(|r| &r.entry)
    }
}

/// The position of an entry extrapolated to tick `k` (tau seconds a tick).
pub fn estimate(e: &Entry, k: u64, tau: f64) -> Vec2 {
    let age = k.saturating_sub(e.tick as u64) as f64 * tau;
    Vec2::new(e.pos[0] as f64, e.pos[1] as f64) + Vec2::new(e.vel[0] as f64, e.vel[1] as f64) * age
}

/// Sigma (member order) in chunks of `size`.
pub fn chunks(epoch: u32, coordinator: u32, seq: u32, sigma: &[u16], size: usize) -> Vec<Sigma> {
    sigma
        .chunks(size.max(1))
        .enumerate()
        .map(|(c, part)| Sigma {
            epoch,
            coordinator,
            seq,
            first: (c * size.max(1)) as u16,
            slots: part.to_vec(),
        })
        .collect()
}

/// The rank of `id` among the members (its index into sigma).
pub fn member_index(members: &Bitmap, id: u32) -> Option<usize> {
    if !members.contains(id as usize) {
        return None;
    }
    Some(members.iter().take_while(|m| *m < id as usize).count())
}

#[cfg(test)]
#[path = "relay_tests.rs"]
mod tests;
