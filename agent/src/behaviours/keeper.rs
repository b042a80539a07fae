//! A robot that keeps what it heard: roams like `roam` with bulk beacons (a `Blob` payload,
//! received zero-copy), and keeps the beacons of its last tick alive until the next one, as a
//! robot keeping the latest camera frames of its neighbours would, and looks at them again
//! then (reads every byte of them, at the start of its next step). Its agent therefore holds
//! an air (through the beacons' views) between ticks, which is what the air's SIGKILL-safety
//! test needs to kill (tests/tests/air_held.rs), and reads it outside the agent's guarded
//! reads, which is what the test of a truncated air under held views needs
//! (tests/tests/tamper.rs). What it reads does not steer it.

use super::roam::{BulkBeacon, Roam};
use swarm::scenario::Scenario;
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The registry's name of this behaviour.
pub const NAME: &str = "keeper";

/// Roam's section and checks (`roam.payload_bytes` > 0 makes the views worth keeping).
pub use super::roam::{resolve, validate, SECTIONS};

/// Calls `v` with the keeper's constructor.
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Keeper::new(sc, i))
}

pub struct Keeper {
    inner: Roam<BulkBeacon>,
    /// The beacons heard last tick (views into its air while the hold limit allows).
    kept: Vec<BulkBeacon>,
}

impl Keeper {
    pub fn new(sc: &Scenario, robot: u32) -> Keeper {
        Keeper {
            inner: Roam::new(sc, robot),
            kept: Vec::new(),
        }
    }

    /// How many of the kept beacons are views (not copies).
    pub fn views(&self) -> usize {
        self.kept.iter().filter(|b| b.payload.is_view()).count()
    }
}

impl Behaviour for Keeper {
    type Msg = BulkBeacon;

    fn zero_copy(&self) -> bool {
        true
    }

    fn step_refs(
        &mut self,
        s: &Sense,
        inbox: &[&Received<BulkBeacon>],
        out: &mut Outbox<BulkBeacon>,
    ) -> Command {
        // The last tick's looked at once more (every byte: a view of an air whose segment
        // was truncated since reads zeros there, through the shrink guard), then they go
        // (their air with them) and this tick's stay.
        let sum = self
            .kept
            .iter()
            .flat_map(|b| b.payload.iter())
            .fold(0u64, |a, &x| a.wrapping_add(x as u64));
        std::hint::black_box(sum);
        self.kept.clear();
        self.kept.extend(inbox.iter().map(|r| r.msg.clone()));
        self.inner.step_refs(s, inbox, out)
    }
}
