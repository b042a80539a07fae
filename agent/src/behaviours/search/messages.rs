//! What search robots tell each other on the radio (bincode; f32 for positions and signals).
//!
//! Everything a robot knows about another robot comes from these messages: positions for the
//! roaming force, target announcements (Type I), subgroup candidacies and personal bests (for
//! the closed-loop adjustment and sgb), detections (for T_est) and found targets.

use serde::{Deserialize, Serialize};

/// One radio message.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Msg {
    /// Sent by every active robot once per tick.
    Status(Status),
    /// Sent by a robot that has just found a target (repeated `declare_ticks` times), after
    /// which it falls silent and stands still.
    Found {
        /// The target it found.
        target: u32,
        /// Every target the sender knows to be found (gossip).
        found: Vec<u32>,
    },
}

/// A robot's state as of the tick it was sent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Status {
    /// X_i(t).
    pub pos: [f32; 2],
    /// Own measurements I_ij > I_min, by target id (paper 2.9 b: "target id, signal,
    /// position"; also the detections of eqs. 7-10).
    pub detections: Vec<(u32, f32)>,
    /// The subgroup the robot is a candidate of this tick, if any.
    pub candidacy: Option<Candidacy>,
    /// Targets the sender knows to be found (gossip of the declarations).
    pub found: Vec<u32>,
}

/// A robot's claim on a subgroup (before the closed-loop adjustment).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidacy {
    /// The subgroup's target.
    pub target: u32,
    /// Type I (own signal) or Type II (attached to a communicating robot).
    pub role: WireRole,
    /// Whether the sender kept itself in the subgroup after its own closed-loop adjustment.
    pub member: bool,
    /// pb_i and its fitness (own I_ij), if any.
    pub pb: Option<([f32; 2], f32)>,
}

/// The Table 1 ranking data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum WireRole {
    /// Senses the target itself with this signal.
    TypeI { signal: f32 },
    /// Attached to `communicator` at distance `distance`.
    TypeII { communicator: u32, distance: f32 },
}

/// f64 position to wire form.
pub fn pack(p: [f64; 2]) -> [f32; 2] {
    [p[0] as f32, p[1] as f32]
}

/// Wire position to f64.
pub fn unpack(p: [f32; 2]) -> [f64; 2] {
    [p[0] as f64, p[1] as f64]
}
