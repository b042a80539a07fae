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
        found: TargetSet,
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
    pub found: TargetSet,
}

/// A set of target ids on the radio: ids below 64 as a bit mask, any others listed. Every
/// robot checks every status it hears against what it knows each tick; the mask is read from
/// the message itself, where a list would be one more heap block to fetch per message (that
/// fetch was ~15 % of an in-process search tick at N = 100).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TargetSet {
    pub low: u64,
    /// Ids of 64 and above, ascending.
    pub high: Vec<u32>,
}

impl TargetSet {
    /// The set of `ids` (ascending, as a BTreeSet iterates).
    pub fn from_sorted(ids: impl IntoIterator<Item = u32>) -> TargetSet {
        let mut s = TargetSet::default();
        for t in ids {
            if t < 64 {
                s.low |= 1 << t;
            } else {
                s.high.push(t);
            }
        }
        s
    }

    pub fn contains(&self, t: u32) -> bool {
        if t < 64 {
            self.low & (1 << t) != 0
        } else {
            self.high.binary_search(&t).is_ok()
        }
    }

    /// Every id, ascending.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        (0..64u32)
            .filter(|&t| self.low & (1 << t) != 0)
            .chain(self.high.iter().copied())
    }

    /// Whether every id of `self` is in `other`.
    pub fn is_subset(&self, other: &TargetSet) -> bool {
        self.low & !other.low == 0 && self.high.iter().all(|t| other.contains(*t))
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_sets_hold_any_id_and_compare_as_sets() {
        let a = TargetSet::from_sorted([0, 3, 63, 64, 900]);
        assert_eq!(a.iter().collect::<Vec<_>>(), vec![0, 3, 63, 64, 900]);
        assert!(a.contains(63) && a.contains(900) && !a.contains(4) && !a.contains(65));
        let b = TargetSet::from_sorted([3, 900]);
        assert!(b.is_subset(&a) && !a.is_subset(&b) && a.is_subset(&a));
        assert!(!TargetSet::from_sorted([65]).is_subset(&a));
        assert!(TargetSet::default().is_subset(&b));
        let cfg = bincode::config::standard();
        let bytes = bincode::serde::encode_to_vec(&a, cfg).unwrap();
        let (back, _): (TargetSet, _) = bincode::serde::decode_from_slice(&bytes, cfg).unwrap();
        assert_eq!(back, a);
    }
}
