//! Who is alive, time-stamped (issue 18: a revocable presumed loss).
//!
//! A robot's death is a record, not a verdict: `dead_at`, the tick someone took it for dead
//! (its proximity sensor saw it vanish, or `presume_lost_ticks` of silence at the capture
//! ring), beside `alive_at`, the latest tick anyone knows it sent a message at. Both travel in
//! every message ([`Obit`]) and merge by the maximum, so the group converges on the latest
//! news whatever the order it arrives in: robot m is gone while `dead_at > alive_at`, and comes
//! back as soon as a message it sent after its death record is heard, directly or as a relayed
//! `alive_at`. A real death (its process died) stays final only while the robot stays dead: a
//! dead process sends nothing, so no later `alive_at` can exist; a restarted one sends again
//! and is back. Ties go to "alive": a death is declared at the tick of the silence that
//! showed it, after every message the robot sent before dying (send ticks are earlier than the
//! tick the sensor misses it).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One robot's death record as gossiped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Obit {
    pub robot: u32,
    /// The latest tick it was taken for dead at.
    pub dead_at: u64,
    /// The latest send tick of a message of it known to the sender (0: none).
    pub alive_at: u64,
}

impl Obit {
    pub fn gone(&self) -> bool {
        self.dead_at > self.alive_at
    }
}

/// What a call changed for robot m.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// m was alive and is now gone.
    Died,
    /// m was gone and is now alive again.
    Revived { dead_at: u64 },
}

/// Robot i's view of who is alive.
#[derive(Clone, Debug, Default)]
pub struct Liveness {
    /// The latest send tick heard of each robot (directly, or relayed in an [`Obit`]).
    alive_at: BTreeMap<u32, u64>,
    /// The death records: robot -> the latest tick it was taken for dead at.
    dead_at: BTreeMap<u32, u64>,
}

impl Liveness {
    pub fn is_gone(&self, m: u32) -> bool {
        self.dead_at
            .get(&m)
            .is_some_and(|&d| d > self.alive_at(m).unwrap_or(0))
    }

    /// The latest send tick known of m.
    pub fn alive_at(&self, m: u32) -> Option<u64> {
        self.alive_at.get(&m).copied()
    }

    fn status(&self, m: u32, was_gone: bool) -> Option<Change> {
        match (was_gone, self.is_gone(m)) {
            (false, true) => Some(Change::Died),
            (true, false) => Some(Change::Revived {
                dead_at: self.dead_at[&m],
            }),
            _ => None,
        }
    }

    /// m sent a message at tick `sent` (heard directly, or relayed).
    pub fn alive(&mut self, m: u32, sent: u64) -> Option<Change> {
        let was = self.is_gone(m);
        let a = self.alive_at.entry(m).or_insert(sent);
        *a = (*a).max(sent);
        self.status(m, was)
    }

    /// m is taken for dead at tick `at`.
    pub fn dead(&mut self, m: u32, at: u64) -> Option<Change> {
        let was = self.is_gone(m);
        let d = self.dead_at.entry(m).or_insert(at);
        *d = (*d).max(at);
        self.status(m, was)
    }

    /// A neighbour's record of one robot: both stamps merge by the maximum.
    pub fn merge(&mut self, o: &Obit) -> Option<Change> {
        let was = self.is_gone(o.robot);
        if o.alive_at > 0 {
            let a = self.alive_at.entry(o.robot).or_insert(o.alive_at);
            *a = (*a).max(o.alive_at);
        }
        let d = self.dead_at.entry(o.robot).or_insert(o.dead_at);
        *d = (*d).max(o.dead_at);
        self.status(o.robot, was)
    }

    /// Every death record, gone or revoked, with the latest alive stamp (robot order).
    pub fn obits(&self) -> Vec<Obit> {
        self.dead_at
            .iter()
            .map(|(&robot, &dead_at)| Obit {
                robot,
                dead_at,
                alive_at: self.alive_at(robot).unwrap_or(0),
            })
            .collect()
    }

    /// The robots gone now (robot order).
    pub fn gone(&self) -> impl Iterator<Item = u32> + '_ {
        self.dead_at.keys().copied().filter(|&m| self.is_gone(m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_later_alive_beats_an_earlier_death_and_not_the_reverse() {
        let mut l = Liveness::default();
        assert_eq!(l.alive(2, 50), None);
        assert_eq!(l.dead(2, 150), Some(Change::Died));
        assert!(l.is_gone(2));
        // News sent before the death record changes nothing.
        assert_eq!(l.alive(2, 120), None);
        assert_eq!(l.merge(&Obit { robot: 2, dead_at: 100, alive_at: 149 }), None);
        assert!(l.is_gone(2));
        // A message sent after it: back.
        assert_eq!(l.alive(2, 151), Some(Change::Revived { dead_at: 150 }));
        assert!(!l.is_gone(2));
        // An older death gossiped later does not kill it again; a newer one does.
        assert_eq!(l.merge(&Obit { robot: 2, dead_at: 140, alive_at: 0 }), None);
        assert_eq!(l.merge(&Obit { robot: 2, dead_at: 200, alive_at: 90 }), Some(Change::Died));
        // A relayed alive stamp later than every death revives it (gossip, not hearing).
        assert_eq!(
            l.merge(&Obit { robot: 2, dead_at: 200, alive_at: 201 }),
            Some(Change::Revived { dead_at: 200 })
        );
        assert_eq!(l.obits(), vec![Obit { robot: 2, dead_at: 200, alive_at: 201 }]);
    }

    #[test]
    fn a_tie_is_alive_and_a_dead_process_stays_dead() {
        let mut l = Liveness::default();
        l.alive(4, 30);
        assert_eq!(l.dead(4, 30), None, "a death at the tick of its last message is no death");
        assert_eq!(l.dead(4, 31), Some(Change::Died));
        // Relays of what it sent before dying never bring it back.
        for sent in [0, 10, 30] {
            assert_eq!(l.merge(&Obit { robot: 4, dead_at: 31, alive_at: sent }), None);
        }
        assert_eq!(l.gone().collect::<Vec<_>>(), vec![4]);
        // Restarted, it sends again: back.
        assert_eq!(l.alive(4, 500), Some(Change::Revived { dead_at: 31 }));
    }
}
