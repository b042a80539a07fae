//! What formation robots say on the radio (bincode, one message per frame).

use super::gossip::{Bitmap, Need};
use super::relay::{Head, Sigma, Up};
use serde::{Deserialize, Serialize};

/// Every robot, every tick: where it is, how it moves, which slot it holds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub pos: [f64; 2],
    /// The velocity it commanded this tick (units per second).
    pub vel: [f64; 2],
    /// Its slot index in the plan of `epoch` (-1: none).
    pub slot: i32,
    pub epoch: u32,
}

/// The coordinator's pattern, repeated every tick so that a robot that missed it (loss, a late
/// start) gets it: every robot regenerates the slots from it (eq. 5 on the template points).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Higher wins; equal epochs: the lower coordinator id wins.
    pub epoch: u32,
    pub coordinator: u32,
    /// [alpha, d_1, d_2, theta] of eq. (5) (the kernels' reading).
    pub transform: [f64; 4],
    /// Template point of slot j (indices into formation.template).
    pub points: Vec<u16>,
    /// The robots of the pattern, ascending.
    pub members: Vec<u32>,
    /// sigma: slot of each member (the optimiser's assignment).
    pub slots: Vec<u16>,
    /// Last positions of robots lost so far: static discs of radius r for ORCA and, in the
    /// plan, obstacles for constraint C2.
    pub dead: Vec<[f64; 2]>,
}

/// A swaps re-plan for a swarm whose full [`Plan`] (members and sigma) exceeds
/// `radio.max_message_bytes` (compact.rs): no members, no sigma; each robot assigns itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompactPlan {
    /// Higher wins; equal epochs: the lower coordinator id wins (as [`Plan`]).
    pub epoch: u32,
    pub coordinator: u32,
    /// [alpha, d_1, d_2, theta] of eq. (5).
    pub transform: [f64; 4],
    /// The template points of the pattern (bits over formation.template): slot j is the j-th.
    pub kept: Bitmap,
    /// (dropped template point, kept template point): the robot that held the first takes
    /// the second (a kept point no live robot held).
    pub moves: Vec<(u16, u16)>,
    /// Wrecks planned around (as [`Plan::dead`]), the nearest the pattern first, capped.
    pub dead: Vec<[f64; 2]>,
}

/// The coordinator's per-step reassignment (eq. 15), for the plan of `epoch`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Assign {
    pub epoch: u32,
    /// The tick it was solved at: a robot keeps its slot until a newer one arrives.
    pub seq: u64,
    /// Slot of each member of the plan, in member order.
    pub slots: Vec<u16>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Msg {
    Status(Status),
    Plan(Plan),
    Assign(Assign),
    /// Decentralised swaps (agent/src/formation/swaps.rs): "swap with me".
    Propose {
        to: u32,
        seq: u64,
        from_target: u32,
        to_target: u32,
        from_position: [f64; 2],
        /// The proposer waits for the answer until this tick.
        deadline: u64,
        /// The plan the targets are slots of: a robot on another plan ignores it.
        epoch: u32,
        /// A blocked robot's proposal (agent/src/formation/blocked.rs).
        blocked: bool,
        /// An escaping proposer's squared path length to its target (swaps.rs).
        from_cost: Option<f64>,
    },
    /// The answer to proposal `seq` (of the plan of `epoch`).
    Reply {
        to: u32,
        seq: u64,
        accepted: bool,
        epoch: u32,
    },
    /// Swaps mode: dead robots' positions (the world's, from the sender's Sense frame or heard)
    /// that the sender's plan does not plan around yet: for the coordinator of the re-plan.
    Wrecks(Vec<[f64; 2]>),
    /// Swaps mode, large swarms: the multi-hop election and gathering of a re-plan (gossip.rs).
    Need(Need),
    /// Swaps mode, large swarms: the re-planned pattern (compact.rs).
    CompactPlan(CompactPlan),
    /// Relayed centralised mode (relay.rs): the beacon and a part of the position table.
    Up(Up),
    /// Relayed centralised mode: the root's pattern.
    Head(Head),
    /// Relayed centralised mode: a part of the assignment.
    Sigma(Sigma),
}
