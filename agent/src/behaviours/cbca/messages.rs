//! What a CBCA robot says on the radio: one message type, sent with `Outbox::broadcast`.
//!
//! A message always carries the sender's state digest (what the convergence detector compares)
//! and the facts a group gossips (robots known dead, targets finished, the latest sighting of
//! each target, who is assembled at which target, compensation paid). While the robot's
//! consensus is not settled, or a neighbour's digest differs from its own, it also carries the
//! full consensus state (Z, Y, s) of Algorithm 2 ([`CbcaMessage`]); otherwise it is a beacon.

use serde::{Deserialize, Serialize};

use super::liveness::Obit;
use crate::cbca::consensus::CbcaMessage;

/// The last position a robot saw a target at, and when (tick).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sighting {
    pub task: u32,
    pub pos: [f64; 2],
    pub tick: u64,
}

/// Compensation paid by a robot that left a coalition (loyalty.rs) to one that stays.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Paid {
    pub from: u32,
    pub to: u32,
    pub task: u32,
    pub amount: f64,
}

/// One CBCA radio message.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CbcaRadio {
    /// The sender's consensus digest when it sent this.
    pub digest: u64,
    /// The full consensus state; None in a beacon.
    pub state: Option<CbcaMessage>,
    /// Death records, time-stamped (liveness.rs): a robot is forgotten while its latest death
    /// is later than the latest message known of it, and comes back when heard after it.
    pub gone: Vec<Obit>,
    /// Targets finished (captured and held): nobody bids on them again.
    pub done: Vec<u32>,
    /// The latest sighting of each target the sender knows of.
    pub sightings: Vec<Sighting>,
    /// (task, robot): robots assembled at the waiting ring of a target (joint arrival).
    pub ready: Vec<(u32, u32)>,
    /// Compensation payments, relayed until everyone has them.
    pub paid: Vec<Paid>,
}

/// The bincode size (the radio's encoding) of a message.
pub fn encoded_bytes(m: &CbcaRadio) -> usize {
    bincode::serde::encode_to_vec(m, bincode::config::standard())
        .expect("a CBCA message encodes")
        .len()
}

/// The largest message a run with `n_robots` robots and these targets can send: every
/// robot's facts with a full path, every coalition full, every target known, sighted and
/// finished, every robot with a death record and ready, and a switch's payments (at most L_j - 1 per
/// abandoned task, l_i tasks) — an upper bound the scenario's `radio.max_message_bytes` must
/// meet. Varints are taken at their widest.
pub fn worst_case_bytes(n_robots: usize, tasks: &[crate::cbca::Task], max_tasks: usize) -> usize {
    use crate::cbca::consensus::RobotInfo;
    use crate::cbca::winners::WinnerEntry;
    let big = u32::MAX as usize;
    let n_e = tasks.len();
    let winners: Vec<WinnerEntry> = tasks
        .iter()
        .flat_map(|t| {
            (0..t.robots_needed).map(move |_| WinnerEntry {
                robot: big,
                task: big,
                bid: f64::MAX,
            })
        })
        .collect();
    let mut widest = tasks.to_vec();
    for t in &mut widest {
        t.id = big;
        t.robots_needed = big;
    }
    let state = CbcaMessage {
        sender: big,
        sent_at: f64::MAX,
        winners,
        stamps: vec![f64::MAX; n_robots],
        infos: vec![
            Some(RobotInfo {
                resources: [f64::MAX; crate::cbca::RESOURCE_TYPES],
                path: vec![big; max_tasks],
            });
            n_robots
        ],
        tasks: widest,
        digest: u64::MAX,
    };
    let m = CbcaRadio {
        digest: u64::MAX,
        state: Some(state),
        gone: vec![
            Obit {
                robot: u32::MAX,
                dead_at: u64::MAX,
                alive_at: u64::MAX,
            };
            n_robots
        ],
        done: vec![u32::MAX; n_e],
        sightings: vec![
            Sighting {
                task: u32::MAX,
                pos: [f64::MAX; 2],
                tick: u64::MAX,
            };
            n_e
        ],
        ready: vec![(u32::MAX, u32::MAX); n_robots * max_tasks],
        paid: vec![
            Paid {
                from: u32::MAX,
                to: u32::MAX,
                task: u32::MAX,
                amount: f64::MAX,
            };
            paid_cap(tasks, max_tasks)
        ],
    };
    encoded_bytes(&m)
}

/// Most payments one message relays: one switch's worth (L_j - 1 members on each of l_i tasks).
pub fn paid_cap(tasks: &[crate::cbca::Task], max_tasks: usize) -> usize {
    let l_max = tasks.iter().map(|t| t.robots_needed).max().unwrap_or(1);
    max_tasks * l_max.saturating_sub(1)
}
