//! The multi-target search paper (docs/search.md) as a plug-in of the runtime: everything of
//! it in this folder, on the public API only (`swarm`'s SDK and plug-in traits, the world's
//! `Mission`, the agent crate's shared kernels).
//!
//! - [`section`]: the `[search]` scenario section (targets, signal, mode, kernels);
//! - [`kernels`]: the paper's algorithms, pure functions (BSOA, TPEPSO, SVF, EPSO, ARBA, the
//!   calibration and estimator, the subgroups), NOTES.md beside this crate for every choice
//!   made where the paper is silent;
//! - [`behaviour`]: the per-robot loop (spec 2.9);
//! - [`mission`]: the world side (targets, signals, finds, metrics).
//!
//! [`Search`] is the plug-in; a binary composes it with one line (bins/src/lib.rs).

pub mod behaviour;
pub mod kernels;
pub mod mission;
pub mod section;

pub use section::{SearchParams, SearchScenario, SEARCH_MODES};

use swarm::plugin::{BehaviourInfo, BehaviourVisitor, Plugin, SectionEntry};
use swarm::scenario::Scenario;

/// The search paper's plug-in: the `[search]` section, the `search` behaviour and mission.
pub struct Search;

impl Plugin for Search {
    fn sections() -> Vec<SectionEntry> {
        vec![SectionEntry::of::<SearchParams>()]
    }
    fn behaviours() -> Vec<BehaviourInfo> {
        vec![BehaviourInfo {
            name: behaviour::NAME,
            sections: behaviour::SECTIONS,
            validate: behaviour::validate,
            resolve: behaviour::resolve,
        }]
    }
    fn dispatch<V: BehaviourVisitor>(sc: &Scenario, v: V) -> Result<V::Out, V> {
        if sc.run.behaviour == behaviour::NAME {
            Ok(behaviour::dispatch(sc, v))
        } else {
            Err(v)
        }
    }
}

impl world::mission::Missions for Search {
    fn missions() -> Vec<world::mission::MissionEntry> {
        vec![mission::ENTRY]
    }
}
