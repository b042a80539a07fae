//! The plug-ins this orchestrator was composed with (bins/src/lib.rs): their behaviours by
//! name (validation, defaults, the sections they read) and the in-process executor's dispatch
//! to their behaviour types. Set once by [`crate::main`]; until then (this crate's own tests)
//! the agent crate's built-in behaviours.

use crate::inprocess::InProcess;
use std::sync::{LazyLock, RwLock};
use swarm::plugin::{BehaviourInfo, Plugin};
use swarm::scenario::{Check, ConfigError, Scenario};

/// Runs the scenario's behaviour in-process (a plug-in's dispatch with the in-process
/// visitor), or gives the visitor back when no plug-in has the behaviour.
type InProcessDispatch =
    for<'a> fn(&'a Scenario, InProcess<'a>) -> Result<std::io::Result<world::Summary>, ()>;

struct Registry {
    behaviours: Vec<BehaviourInfo>,
    inprocess: InProcessDispatch,
}

fn inprocess_of<P: Plugin>(
    sc: &Scenario,
    v: InProcess<'_>,
) -> Result<std::io::Result<world::Summary>, ()> {
    P::dispatch(sc, v).map_err(|_| ())
}

/// Until [`register`]: the built-in plug-ins (this crate's own tests), registered in swarm
/// and the world too as this registry is first read.
type Defaults = (search::Search, agent::behaviours::Builtin);

static REGISTRY: LazyLock<RwLock<Registry>> = LazyLock::new(|| {
    swarm::plugin::register_plugin::<Defaults>();
    world::mission::register::<Defaults>();
    RwLock::new(Registry {
        behaviours: Defaults::behaviours(),
        inprocess: inprocess_of::<Defaults>,
    })
});

/// Registers plug-in `P` everywhere: its sections (swarm), missions (world), behaviours and
/// the in-process dispatch to them (here).
pub fn register<P: Plugin + world::mission::Missions>() {
    swarm::plugin::register_plugin::<P>();
    world::mission::register::<P>();
    let mut r = REGISTRY.write().unwrap_or_else(|e| e.into_inner());
    // (The defaults' registration above ran first if the registry was read before.)
    r.behaviours = P::behaviours();
    r.inprocess = inprocess_of::<P>;
}

/// Every behaviour's name.
pub fn behaviour_names() -> Vec<&'static str> {
    let r = REGISTRY.read().unwrap_or_else(|e| e.into_inner());
    r.behaviours.iter().map(|b| b.name).collect()
}

/// The behaviour `name`.
pub fn behaviour(name: &str) -> Option<BehaviourInfo> {
    let r = REGISTRY.read().unwrap_or_else(|e| e.into_inner());
    r.behaviours.iter().find(|b| b.name == name).copied()
}

/// Checks that `run.behaviour` names a behaviour and that its sections are valid.
pub fn validate_behaviour(sc: &Scenario, c: &Check) -> Result<(), ConfigError> {
    match behaviour(&sc.run.behaviour) {
        Some(b) => (b.validate)(sc, c),
        None => Err(c.err(
            "run.behaviour",
            format!(
                "= {:?} is unknown: allowed {:?}",
                sc.run.behaviour,
                behaviour_names()
            ),
        )),
    }
}

/// Writes every parameter of the scenario's behaviour into it, defaults included.
pub fn resolve_behaviour(sc: &mut Scenario) -> Result<(), ConfigError> {
    match behaviour(&sc.run.behaviour) {
        Some(b) => (b.resolve)(sc),
        None => Ok(()),
    }
}

/// Runs the scenario's behaviour in-process with `v` (the scenario validated).
pub fn run_inprocess<'a>(sc: &'a Scenario, v: InProcess<'a>) -> std::io::Result<world::Summary> {
    let f = REGISTRY.read().unwrap_or_else(|e| e.into_inner()).inprocess;
    f(sc, v).unwrap_or_else(|()| {
        Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "run.behaviour = {:?} is none of this program's",
                sc.run.behaviour
            ),
        ))
    })
}
