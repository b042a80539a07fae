//! A scenario made ready to run: every section checked by its owner (the run's own sections by
//! swarm, the behaviour's by the agent crate's registry, the mission's by the world's), then
//! the behaviour's defaults written in, so the resolved scenario lists every value.

use swarm::scenario::{Check, ConfigError, Scenario};

/// Validates `sc` (errors name the key and `key_source(key)`, where its value came from) and
/// resolves the behaviour's defaults into it.
pub fn prepare(sc: &mut Scenario, key_source: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
    sc.validate(key_source)?;
    let c = Check { key_source };
    agent::behaviours::validate_with(sc, &c)?;
    world::mission::validate_with(sc, &c)?;
    agent::behaviours::resolve_defaults(sc)
}

/// [`prepare`] with every key from one `source` (a file, a bench).
pub fn prepare_from(sc: &mut Scenario, source: &str) -> Result<(), ConfigError> {
    prepare(sc, &|_| source.to_string())
}
