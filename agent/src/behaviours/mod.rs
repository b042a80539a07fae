//! Behaviours, chosen by the scenario's `run.behaviour`.

pub mod faulty;
pub mod roam;
pub mod search;

use swarm::scenario::Scenario;
use swarm::Behaviour;

/// Something to do with the scenario's behaviour type (run it in a process, or in-process).
pub trait BehaviourVisitor {
    type Out;
    fn visit<B: Behaviour + Send + 'static>(self, make: &dyn Fn(u32) -> B) -> Self::Out
    where
        B::Msg: Send + Sync;
}

/// Checks the behaviour's own parameters (beyond what swarm::scenario validates).
pub fn validate(sc: &Scenario) -> Result<(), String> {
    match sc.run.behaviour.as_str() {
        "search" => search_validate(sc),
        _ => Ok(()),
    }
}

/// Writes every parameter of the behaviour into the scenario, defaults included, so the run's
/// resolved scenario.toml lists each value the algorithms use (the search kernels' defaults
/// live in code, with their sources, in behaviours/search/params.rs and search/*.rs).
pub fn resolve_defaults(sc: &mut Scenario) -> Result<(), String> {
    if sc.run.behaviour == "search" {
        let p = search::parse_params(sc)?;
        sc.search.kernels =
            toml::Table::try_from(&p).map_err(|e| format!("search.kernels: {e}"))?;
    }
    Ok(())
}

/// Calls `v` with the constructor of the scenario's behaviour (validated beforehand).
pub fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> V::Out {
    match sc.run.behaviour.as_str() {
        // Beacons with a bulk payload are their own type (received in place).
        "roam" if sc.roam.payload_bytes > 0 => {
            v.visit(&|i| roam::Roam::<roam::BulkBeacon>::new(sc, i))
        }
        "roam" => v.visit(&|i| roam::Roam::<roam::Beacon>::new(sc, i)),
        "faulty" => v.visit(&|i| faulty::Faulty::new(sc, i)),
        "search" => v.visit(&|i| search::Search::new(sc, i)),
        other => panic!("unknown behaviour {other:?} (the scenario was not validated)"),
    }
}

/// The search behaviour's parameters (`search.kernels`) and mode.
fn search_validate(sc: &Scenario) -> Result<(), String> {
    search::validate_search(sc)
}
