//! Behaviours, chosen by the scenario's `run.behaviour`.

pub mod faulty;
pub mod roam;

use swarm::scenario::Scenario;
use swarm::Behaviour;

/// Something to do with the scenario's behaviour type (run it in a process, or in-process).
pub trait BehaviourVisitor {
    type Out;
    fn visit<B: Behaviour + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out;
}

/// Calls `v` with the constructor of the scenario's behaviour (validated beforehand).
pub fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    match sc.run.behaviour.as_str() {
        "roam" => v.visit(&|i| roam::Roam::new(sc, i)),
        "faulty" => v.visit(&|i| faulty::Faulty::new(sc, i)),
        other => panic!("unknown behaviour {other:?} (the scenario was not validated)"),
    }
}
