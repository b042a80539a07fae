//! The hunting behaviour of thesis 003 chapters 2-3 (docs/hunting.md; kernels in
//! `crate::hunt`): one agent per robot (`robot.rs`: the Bidder over the radio, the APF pursuit
//! on a unicycle, hunting points, re-planning as the auctioneer sends it) and the auctioneer
//! as an agent of its own (`auctioneer.rs`: the station, the last agent of the run, with no
//! body). Both speak `messages::HuntMsg` through the behaviour API only.

pub mod auctioneer;
pub mod messages;
pub mod robot;

pub use messages::HuntMsg;

use swarm::scenario::{Check, ConfigError, Scenario};
use swarm::{Behaviour, Command, Outbox, Received, Sense};

/// The registry's name of this behaviour.
pub const NAME: &str = "hunt";

/// Nothing of its own to check: the behaviour reads only the `[hunt]` section, which the
/// world's hunt mission (implied by this behaviour) validates: rows, agent count, kinematics,
/// limits.
pub fn validate(_sc: &Scenario, _c: &Check) -> Result<(), ConfigError> {
    Ok(())
}

/// Nothing to resolve: `[hunt.params]` is written in full by the scenario itself.
pub fn resolve(_sc: &mut Scenario) -> Result<(), ConfigError> {
    Ok(())
}

/// Calls `v` with the constructor: robots for agents 0..bodies, the auctioneer for the station.
pub fn dispatch<V: crate::BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    v.visit(&|i| Hunt::new(sc, i))
}

/// A hunting agent: a robot or the auctioneer.
#[allow(clippy::large_enum_variant)]
pub enum Hunt {
    Robot(robot::HuntRobot),
    Auctioneer(auctioneer::Station),
}

impl Hunt {
    pub fn new(sc: &Scenario, i: u32) -> Hunt {
        if sc.is_station(i) {
            Hunt::Auctioneer(auctioneer::Station::new(sc))
        } else {
            Hunt::Robot(robot::HuntRobot::new(sc, i))
        }
    }
}

impl Behaviour for Hunt {
    type Msg = HuntMsg;
    fn step_refs(
        &mut self,
        sense: &Sense,
        inbox: &[&Received<HuntMsg>],
        out: &mut Outbox<HuntMsg>,
    ) -> Command {
        match self {
            Hunt::Robot(r) => r.step(sense, inbox, out),
            Hunt::Auctioneer(a) => a.step(sense, inbox, out),
        }
    }
}
