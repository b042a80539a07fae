//! A scenario made ready to run: every section checked by its owner (the run's own sections by
//! swarm, the world core's limits and the robots' placement and the mission's section by the
//! world crate, then the behaviour's by the agent crate's registry), then
//! the behaviour's defaults written in, so the resolved scenario lists every value.

use swarm::scenario::{Check, ConfigError, Scenario};

/// Validates `sc` (errors name the key and `key_source(key)`, where its value came from) and
/// resolves the behaviour's defaults into it.
pub fn prepare(sc: &mut Scenario, key_source: &dyn Fn(&str) -> String) -> Result<(), ConfigError> {
    sc.validate(key_source)?;
    let c = Check { key_source };
    world::limits::validate(sc, &c)?;
    // The mission first: its range checks name the key the user wrote (`search.signal_m =
    // nan`) before the behaviour compares its own copies with them.
    world::mission::validate_with(sc, &c)?;
    agent::behaviours::validate_with(sc, &c)?;
    agent::behaviours::resolve_defaults(sc)
}

/// [`prepare`] with every key from one `source` (a file, a bench).
pub fn prepare_from(sc: &mut Scenario, source: &str) -> Result<(), ConfigError> {
    prepare(sc, &|_| source.to_string())
}
