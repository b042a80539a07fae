//! `swarm._native`: the Rust side of the `swarm` Python package. It reads recordings with the
//! runtime's own reader ([`recording`]) and runs Python behaviours inside the runtime's own
//! agent loop ([`agent`], with the Sense frame of [`sense`]); the Python modules in
//! `python/swarm/` build the user's API on it.

use pyo3::prelude::*;

mod agent;
mod recording;
mod sense;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(recording::read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(agent::run_agent, m)?)?;
    m.add_class::<sense::PySense>()?;
    m.add_class::<agent::PyMessage>()?;
    m.add_class::<agent::PyOutbox>()?;
    m.add_class::<agent::PyCommand>()?;
    m.add_class::<agent::PyAgentInfo>()?;
    m.add("SENSE_LAYOUT", sense::layout(m.py())?)?;
    m.add("EXIT_BEHAVIOUR_FAULT", agent::EXIT_BEHAVIOUR_FAULT)?;
    Ok(())
}
