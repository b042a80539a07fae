//! A misbehaving robot, for fault-injection tests: roams like `roam`, but on a fixed schedule
//! sends a NaN, an infinite, a too-fast velocity and a frame for another robot id. The world
//! must reject and count each, and carry on.

use super::roam::{Beacon, Roam};
use swarm::scenario::Scenario;
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The registry's name of this behaviour.
pub const NAME: &str = "faulty";

/// Roam's section and checks.
pub use super::roam::{resolve, validate, SECTIONS};

/// Calls `v` with the faulty robot's constructor.
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Faulty::new(sc, i))
}

/// Every this many ticks the robot misbehaves once (cycling through the faults).
pub const FAULT_PERIOD: u64 = 10;

pub struct Faulty {
    inner: Roam,
}

impl Faulty {
    pub fn new(sc: &Scenario, robot: u32) -> Faulty {
        Faulty {
            inner: Roam::new(sc, robot),
        }
    }
}

/// What a faulty robot does at tick k (None: behaves).
pub fn fault_at(tick: u64) -> Option<u64> {
    (tick % FAULT_PERIOD == FAULT_PERIOD - 1).then_some((tick / FAULT_PERIOD) % 3)
}

impl Behaviour for Faulty {
    type Msg = Beacon;

    fn step_refs(
        &mut self,
        s: &Sense,
        inbox: &[&Received<Beacon>],
        out: &mut Outbox<Beacon>,
    ) -> Command {
        let mut c = self.inner.step_refs(s, inbox, out);
        match fault_at(s.tick) {
            Some(0) => c.cmd = [f64::NAN, 1.0],
            Some(1) => c.cmd = [f64::INFINITY, 0.0],
            Some(_) => c.cmd = [1e6, 1e6],
            None => {}
        }
        c
    }
}
